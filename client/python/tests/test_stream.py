"""A million area-uniform pairs through client.distance: streamed in
batches, in order, with the client's memory bounded by the batches in
flight rather than by the number of pairs."""

import time
import tracemalloc

import numpy as np
import pytest

import geodex
from support import area_uniform_points, query_distances

MODEL = "torus"
N = 1_000_000
BATCH = 16384


@pytest.fixture(scope="module")
def pairs(torus_mesh):
    vertices, faces = torus_mesh
    return area_uniform_points(vertices, faces, N, 31), area_uniform_points(vertices, faces, N, 32)


def test_a_million_pairs_stream_in_bounded_memory(server, client, pairs, torus_index, tmp_path):
    a, b = pairs
    with geodex.connect(server.address, batch_size=BATCH) as streaming:
        tracemalloc.start()
        try:
            before, _ = tracemalloc.get_traced_memory()
            start = time.perf_counter()
            d = streaming.distance(MODEL, a, b)
            seconds = time.perf_counter() - start
            _, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
    print(f"{N} pairs in {seconds:.2f} s: {N / seconds:,.0f} pairs/s (under tracemalloc)")
    assert d.shape == (N,) and np.isfinite(d).all() and (d >= 0).all()
    # Besides the answer itself, a few encoded batches (~52 bytes a pair) at
    # a time: all of them at once would be 52 MB and more.
    encoded_batch = BATCH * 52
    assert peak - before - d.nbytes < 16 * encoded_batch, (peak - before, d.nbytes)
    # In order, and the same answers as one call and as geodex-query.
    head = 50_000
    one_call = client.distance(MODEL, a.take(slice(head)), b.take(slice(head)))
    assert np.array_equal(d[:head], one_call)
    sample = np.random.default_rng(33).choice(N, 2000, replace=False)
    reference = query_distances(torus_index, tmp_path, a.take(sample), b.take(sample))
    np.testing.assert_allclose(d[sample], reference, rtol=1e-12, atol=0)
