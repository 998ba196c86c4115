"""Every method of geodex.Client against a real geodex-server, with
geodex-query on the same index file as the reference: the same engine, so
the answers agree to the last bit (asserted: relative difference <= 1e-12)."""

import json

import numpy as np
import pytest

import geodex
from support import (
    area_uniform_points,
    query_distances,
    query_points_lines,
    random_points,
    run_query,
)

MODEL = "torus"


def max_relative_difference(x: np.ndarray, y: np.ndarray) -> float:
    assert x.shape == y.shape
    same = (x == y) | (np.isinf(x) & np.isinf(y))
    scale = np.maximum(np.abs(y), 1e-300)
    return float(np.max(np.where(same, 0.0, np.abs(x - y) / scale), initial=0.0))


@pytest.fixture(scope="module")
def num_faces(client) -> int:
    return client.model(MODEL).num_faces


def pair_lines(a: geodex.SurfacePoints, b: geodex.SurfacePoints):
    """geodex-query's pair lines "fa a0 a1 a2 fb b0 b1 b2"."""
    return [f"{x} {y}" for x, y in zip(query_points_lines(a), query_points_lines(b))]


def near_pairs(num_faces: int, n: int, seed: int):
    """Pairs of points in one face or in faces a few ids apart (neighbours,
    on a generated grid): the pairs each near-pair mode answers its own way."""
    a = random_points(num_faces, n, seed)
    b = random_points(num_faces, n, seed + 1)
    b.faces[:] = (a.faces + np.arange(n) % 3) % num_faces
    return a, b


def test_models_and_their_build_reports(client, torus_mesh):
    models = {m.name: m for m in client.models()}
    assert models["torus"].state == "SERVING" and models["cube"].state == "SERVING"
    torus = client.model(MODEL)
    vertices, faces = torus_mesh
    assert (torus.num_vertices, torus.num_faces) == (vertices.shape[0], faces.shape[0])
    assert torus.version == 1 and torus.available_versions == (1,)
    assert torus.num_samples >= 200 and torus.num_triangles > 0
    assert isinstance(torus.build_report, dict) and torus.build_report
    assert client.model(MODEL, version=1).version == 1


def test_distances_equal_geodex_query(client, server, torus_index, tmp_path, num_faces):
    a, b = random_points(num_faces, 3000, 1), random_points(num_faces, 3000, 2)
    reference = query_distances(torus_index, tmp_path, a, b)
    d = client.distance(MODEL, a, b)
    assert d.dtype == np.float64 and d.shape == (3000,)
    assert max_relative_difference(d, reference) <= 1e-12
    # The same pairs streamed in batches.
    with geodex.connect(server.address, batch_size=256) as streaming:
        assert np.array_equal(streaming.distance(MODEL, a, b), d)


@pytest.mark.parametrize("mode", ["path", "unfold", "exact"])
def test_near_pair_modes_equal_geodex_query(client, torus_index, tmp_path, num_faces, mode):
    a, b = near_pairs(num_faces, 400, 3)
    reference = query_distances(torus_index, tmp_path, a, b, "--near-pairs", mode)
    d = client.distance(MODEL, a, b, near_pairs=mode)
    assert max_relative_difference(d, reference) <= 1e-12


def test_bounds_and_tolerance_equal_geodex_query(client, torus_index, tmp_path, num_faces):
    a, b = near_pairs(num_faces, 300, 5)
    lines = run_query(torus_index, tmp_path, "--error-bounds",
                      stdin_lines=pair_lines(a, b), file_flag="--pairs")
    reference = np.array([[float(v) for v in line.split()] for line in lines.splitlines()])
    d, bounds = client.distance(MODEL, a, b, bounds=True)
    assert max_relative_difference(d, reference[:, 0]) <= 1e-12
    assert max_relative_difference(bounds, reference[:, 1]) <= 1e-12
    assert (bounds >= 0).all()
    refined = query_distances(torus_index, tmp_path, a, b, "--tolerance", "0.005")
    assert max_relative_difference(client.distance(MODEL, a, b, tolerance=0.005), refined) <= 1e-12
    every = query_distances(torus_index, tmp_path, a, b, "--refine-below", "8")
    assert max_relative_difference(client.distance(MODEL, a, b, refine_below=8), every) <= 1e-12


def test_matrix_rows_are_distances(client, num_faces):
    sources, targets = random_points(num_faces, 7, 11), random_points(num_faces, 300, 12)
    m, bounds = client.matrix(MODEL, sources, targets, bounds=True)
    assert m.shape == (7, 300) and bounds.shape == (7, 300)
    for s in range(7):
        row = geodex.SurfacePoints(np.repeat(sources.faces[s], 300),
                                   np.repeat(sources.weights[s:s + 1], 300, axis=0))
        d, b = client.distance(MODEL, row, targets, bounds=True)
        assert np.array_equal(m[s], d) and np.array_equal(bounds[s], b)
    no_sources = geodex.SurfacePoints(np.zeros(0, np.int32), np.zeros((0, 3)))
    empty = client.matrix(MODEL, no_sources, targets)
    assert empty.shape == (0, 300)


def test_paths_equal_geodex_query(client, torus_index, tmp_path, num_faces, torus_mesh):
    a, b = random_points(num_faces, 20, 13), random_points(num_faces, 20, 14)
    out = run_query(torus_index, tmp_path, "--format", "json",
                    stdin_lines=pair_lines(a, b), file_flag="--paths")
    reference = json.loads(out)
    paths = client.path(MODEL, a, b, batch_size=6)
    assert len(paths) == 20
    vertices, faces = torus_mesh
    for path, ref_path in zip(paths, reference):
        assert path.length == ref_path["length"]
        ref = ref_path["points"]
        assert path.faces.tolist() == [p["face"] for p in ref]
        assert np.array_equal(path.weights, np.array([p["w"] for p in ref]).reshape(-1, 3))
        assert np.array_equal(path.positions, np.array([p["xyz"] for p in ref]).reshape(-1, 3))
        segments = np.linalg.norm(np.diff(path.positions, axis=0), axis=1).sum()
        assert path.length == pytest.approx(segments, rel=1e-12)
        # The points' faces and weights are where the positions are.
        on_mesh = np.einsum("kc,kcd->kd", path.weights, vertices[faces[path.faces]])
        np.testing.assert_allclose(on_mesh, path.positions, atol=1e-9)
    # Each path runs from a[i] to b[i].
    starts = np.einsum("nc,ncd->nd", a.weights, vertices[faces[a.faces]])
    ends = np.einsum("nc,ncd->nd", b.weights, vertices[faces[b.faces]])
    np.testing.assert_allclose([p.positions[0] for p in paths], starts, atol=1e-9)
    np.testing.assert_allclose([p.positions[-1] for p in paths], ends, atol=1e-9)


def test_field_within_a_radius_is_exact(client, num_faces, torus_mesh):
    # The reference: each vertex's distance as an exact near pair (a local
    # exact propagation), for vertices near enough to be refined.
    vertices, faces = torus_mesh
    model = client.model(MODEL)
    area = 0.5 * np.linalg.norm(np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]],
                                         vertices[faces[:, 2]] - vertices[faces[:, 0]]), axis=1).sum()
    scale = np.sqrt(2 * area / (np.sqrt(3) * model.num_samples))  # L
    sources = random_points(num_faces, 2, 16)
    radius = 1.5 * scale
    ids, d, nearest = client.field(MODEL, sources, radius=radius, nearest=True)
    assert ids.dtype == np.int32 and d.dtype == np.float64 and nearest.dtype == np.int32
    assert (np.diff(ids) > 0).all() and (d <= radius).all() and set(nearest.tolist()) <= {0, 1}
    assert 0 < ids.shape[0] < vertices.shape[0] // 4
    # Every vertex: its face and the corner it is in that face.
    face_of = np.zeros(vertices.shape[0], np.int32)
    corner_of = np.zeros(vertices.shape[0], np.int64)
    for k in range(3):
        face_of[faces[:, k]] = np.arange(faces.shape[0])
        corner_of[faces[:, k]] = k
    at = geodex.SurfacePoints(face_of, np.eye(3)[corner_of])
    exact = np.full(vertices.shape[0], np.inf)
    for s in range(2):
        source = sources.take(slice(s, s + 1))
        repeated = geodex.SurfacePoints(np.repeat(source.faces, vertices.shape[0]),
                                        np.repeat(source.weights, vertices.shape[0], axis=0))
        exact = np.minimum(exact, client.distance(MODEL, repeated, at, near_pairs="exact"))
    assert max_relative_difference(d, exact[ids]) <= 1e-9
    off = np.abs(exact - radius) > 1e-9 * radius  # vertices on the circle may go either way
    assert np.array_equal(np.isin(np.arange(vertices.shape[0]), ids)[off], (exact <= radius)[off])
    # Without nearest sources: the same vertices and distances.
    ids2, d2 = client.field(MODEL, sources, radius=radius)
    assert np.array_equal(ids2, ids) and np.array_equal(d2, d)


def test_field_equals_geodex_query(client, torus_index, tmp_path, num_faces):
    sources = random_points(num_faces, 5, 15)
    out = run_query(torus_index, tmp_path, "--nearest", stdin_lines=query_points_lines(sources),
                    file_flag="--field")
    reference = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    d, nearest = client.field(MODEL, sources, nearest=True)
    assert max_relative_difference(d, reference[:, 0]) <= 1e-12
    assert np.array_equal(nearest, reference[:, 1].astype(np.int32))
    assert np.array_equal(client.field(MODEL, sources), d)


def test_expmap_equals_geodex_query(client, torus_index, tmp_path):
    centre = (17, (0.2, 0.3, 0.5))
    out = run_query(torus_index, tmp_path, "--expmap", "17 0.2 0.3 0.5", "--radius", "1.5")
    reference = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    vertices, uv = client.expmap(MODEL, centre, 1.5)
    assert np.array_equal(vertices, reference[:, 0].astype(np.int32))
    assert max_relative_difference(uv, reference[:, 1:]) <= 1e-12
    _, polar = client.expmap(MODEL, centre, 1.5, polar=True)
    np.testing.assert_allclose(polar[:, 0] * np.cos(polar[:, 1]), uv[:, 0], atol=1e-12)
    assert (polar[:, 0] <= 1.5).all()
    turned_ids, _ = client.expmap(MODEL, centre, 1.5, direction=(0.0, 0.0, 1.0))
    assert np.array_equal(turned_ids, vertices)


def test_expmap_refuses_a_bad_centre_or_radius(client, num_faces):
    past = (np.array([num_faces], np.int32), np.array([[1.0, 0.0, 0.0]]))
    with pytest.raises(geodex.OutOfRange, match=r"center\[0\]"):
        client.expmap(MODEL, past, 1.0)
    with pytest.raises(geodex.InvalidArgument, match="radius"):
        client.expmap(MODEL, (3, (1.0, 0.0, 0.0)), -1.0)
    two = random_points(num_faces, 2, 21)
    with pytest.raises(geodex.InvalidArgument, match="one point"):
        client.expmap(MODEL, two, 1.0)
    assert len(client.expmap(MODEL, (3, (1.0, 0.0, 0.0)), 0.5)[0]) > 0


def test_locate_equals_geodex_query(client, torus_index, tmp_path, torus_mesh):
    rng = np.random.default_rng(16)
    xyz = rng.uniform(-3, 3, (200, 3))
    out = run_query(torus_index, tmp_path, stdin_lines=[f"{x!r} {y!r} {z!r}" for x, y, z in xyz],
                    file_flag="--locate")
    reference = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
    located = client.locate(MODEL, xyz, batch_size=64)
    assert np.array_equal(located.faces, reference[:, 0].astype(np.int32))
    assert max_relative_difference(located.weights, reference[:, 1:4]) <= 1e-12
    assert max_relative_difference(located.distances, reference[:, 4]) <= 1e-12


def test_positions_are_located_first(client, torus_mesh):
    vertices, faces = torus_mesh
    a = area_uniform_points(vertices, faces, 500, 17)
    b = area_uniform_points(vertices, faces, 500, 18)
    xa = np.einsum("nc,ncd->nd", a.weights, vertices[faces[a.faces]])
    xb = np.einsum("nc,ncd->nd", b.weights, vertices[faces[b.faces]])
    d = client.distance(MODEL, xa, xb, xyz=True)
    expected = client.distance(MODEL, client.locate(MODEL, xa), client.locate(MODEL, xb))
    assert np.array_equal(d, expected)
    np.testing.assert_allclose(d, client.distance(MODEL, a, b), rtol=1e-6, atol=1e-9)


def test_mesh_and_triangulation(client, torus_mesh):
    vertices, faces = torus_mesh
    model = client.model(MODEL)
    assert vertices.shape == (model.num_vertices, 3) and faces.shape == (model.num_faces, 3)
    assert faces.min() >= 0 and faces.max() < vertices.shape[0]
    assert np.all(vertices.min(axis=0) >= np.array(model.bbox_min) - 1e-12)
    t = client.triangulation(MODEL)
    assert t.sample_positions.shape == (model.num_samples, 3)
    assert t.triangle_corners.shape == (model.num_triangles, 3)
    assert t.vertex_triangles.shape == (model.num_vertices,)
    np.testing.assert_array_equal(t.sample_positions, vertices[t.sample_vertices])


def test_distances_between_identical_points_are_zero(client, num_faces):
    a = random_points(num_faces, 100, 19)
    assert np.array_equal(client.distance(MODEL, a, a), np.zeros(100))
    empty = geodex.SurfacePoints(np.zeros(0, np.int32), np.zeros((0, 3)))
    assert client.distance(MODEL, empty, empty).shape == (0,)
