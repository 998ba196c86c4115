"""The client against the fake server, whose answers are closed forms
(client/fake_geodex_service_testing.h): how batches, streams and chunks
are split and put back together, and how failures come back."""

from pathlib import Path
from typing import Iterator

import numpy as np
import pytest

import geodex
from support import Server, random_points

NUM_FACES, NUM_VERTICES = 100, 60


@pytest.fixture(scope="module")
def fake(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(Path("."), tmp_path_factory.mktemp("fake") / "fake.log",
               binary_path="client/geodex-fake-server")
    yield s
    s.stop()


def fake_distance(a: geodex.SurfacePoints, b: geodex.SurfacePoints) -> np.ndarray:
    return np.abs(a.faces - b.faces) + np.abs(a.weights - b.weights).sum(axis=1)


@pytest.mark.parametrize("batch_size", [1, 7, 1000, 32768])
def test_distances_in_order_whatever_the_batches(fake, batch_size):
    a, b = random_points(NUM_FACES, 2500, 1), random_points(NUM_FACES, 2500, 2)
    with geodex.connect(fake.address, batch_size=batch_size) as client:
        d = client.distance("fake", a, b)
    np.testing.assert_allclose(d, fake_distance(a, b), rtol=0, atol=1e-12)


def test_a_bad_pair_in_a_later_batch_is_named_by_its_place_in_the_input(fake):
    a, b = random_points(NUM_FACES, 50, 3), random_points(NUM_FACES, 50, 4)
    b.faces[37] = 100  # the fake's face count: past the end
    with geodex.connect(fake.address, batch_size=16) as client:
        with pytest.raises(geodex.OutOfRange, match=r"^OUT_OF_RANGE: b\[37\]"):
            client.distance("fake", a, b)
        with pytest.raises(geodex.OutOfRange, match=r"b\[37\]"):  # one unary call
            geodex.connect(fake.address).distance("fake", a, b)
        assert client.distance("fake", a, a).max() == 0.0


def test_mesh_chunks_are_put_together(fake):
    with geodex.connect(fake.address) as client:
        vertices, faces = client.mesh("fake")
    v = np.arange(NUM_VERTICES)
    assert np.array_equal(vertices, np.stack([v, v % 2, 0 * v], axis=1))
    f = np.arange(NUM_FACES)
    assert np.array_equal(faces, np.stack([f % 60, (f + 1) % 60, (f + 2) % 60], axis=1))
    assert faces.dtype == np.int32


def test_field_matrix_path_locate(fake):
    sources = geodex.SurfacePoints(np.array([10, 40], np.int32), np.eye(3)[:2])
    with geodex.connect(fake.address) as client:
        d, nearest = client.field("fake", sources, nearest=True)
        v = np.arange(NUM_VERTICES)
        expected = np.minimum(np.abs(v - 10), np.abs(v - 40))
        assert np.array_equal(d, expected)
        assert nearest.dtype == np.int32 and nearest.shape == (NUM_VERTICES,)
        # Within a radius: the vertices of the closed form within it (30, in
        # chunks of 7), ascending, with their distances and nearest sources.
        ids, dr, near = client.field("fake", sources, radius=7, nearest=True)
        within = v[expected <= 7]
        assert ids.dtype == np.int32 and ids.tolist() == within.tolist() and len(within) == 30
        assert np.array_equal(dr, expected[within]) and dr.dtype == np.float64
        assert np.array_equal(near, (within > 25).astype(np.int32))
        ids, dr = client.field("fake", sources, radius=0.5)
        assert ids.tolist() == [10, 40] and dr.tolist() == [0.0, 0.0]
        a, b = random_points(NUM_FACES, 5, 5), random_points(NUM_FACES, 7, 6)
        m = client.matrix("fake", a, b)
        rows = np.stack([fake_distance(geodex.SurfacePoints(np.repeat(a.faces[i], 7),
                                                            np.repeat(a.weights[i:i + 1], 7, 0)), b)
                         for i in range(5)])
        np.testing.assert_allclose(m, rows, atol=1e-12)
        paths = client.path("fake", a, a, batch_size=2)
        assert len(paths) == 5 and all(p.length == 0 and p.positions.shape == (2, 3) for p in paths)
        located = client.locate("fake", [[3.7, -2.0, 1.0], [250.0, 0.5, 0.0]])
        assert located.faces.tolist() == [3, 99] and located.distances.tolist() == [2.0, 0.5]


def test_failures_are_exceptions_of_their_code(fake):
    with geodex.connect(fake.address, max_attempts=2) as client:
        with pytest.raises(geodex.NotFound):
            client.model("nope")
        with pytest.raises(geodex.Unavailable):  # "loading" is always UNAVAILABLE
            p = random_points(NUM_FACES, 3, 1)
            client.distance("loading", p, p)
        assert client.model("fake").state == "SERVING"


def test_no_server_is_unavailable():
    with geodex.connect("127.0.0.1:1", max_attempts=1, timeout=5) as client:
        with pytest.raises(geodex.Unavailable):
            client.models()
