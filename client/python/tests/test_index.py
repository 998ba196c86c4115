"""The in-process index (geodex.Index, geodex.build) against the server on
the same index file: the same engine in the same ids, so the same answers to
the bit, and the same exceptions with the same messages."""

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import geodex
from support import build_index, query_distances, random_points, require_in_process, shared_mesh

MODEL = "torus"


@pytest.fixture(scope="module")
def index(torus_index) -> "geodex.Index":
    require_in_process()
    return geodex.Index(torus_index)


@pytest.fixture(scope="module")
def num_faces(index) -> int:
    return index.num_faces


def test_what_the_index_holds(index, client):
    model = client.model(MODEL)
    assert (index.num_vertices, index.num_faces, index.num_samples) == (
        model.num_vertices, model.num_faces, model.num_samples)
    assert index.has_error_bounds
    assert index.report == model.build_report
    assert "torus" in repr(index) or "index.gdx" in repr(index)


def test_the_build_report_is_the_servers(index, client):
    report = index.info()
    assert report == client.info(MODEL) == client.model(MODEL).report
    assert report["mesh"]["faces"] == index.num_faces
    assert report["samples"]["final"] == index.num_samples
    assert report["error_bounds"] is True
    # The bins of the calibration, in order, with the stored figures.
    assert [b["key"] for b in report["accuracy"]["bins"]] == ["below_L", "L_3L", "3L_10L", "beyond_10L"]
    assert float(index.report["accuracy_p99_3L_10L"]) == pytest.approx(
        report["accuracy"]["bins"][2]["p99"], rel=1e-5)
    assert sum(s["bytes"] for s in report["size"]["sections"]) == report["size"]["bytes"]


@pytest.mark.parametrize("options", [{}, {"bounds": True}, {"near_pairs": "unfold"},
                                     {"near_pairs": "exact"}, {"tolerance": 0.005},
                                     {"refine_below": 8}])
def test_distances_equal_the_servers_to_the_bit(index, client, num_faces, options):
    # Under a tolerance, far pairs are refined exactly (milliseconds each);
    # the exact mode propagates for every near pair, the every-distance mode
    # refines pairs up to 8 L1000 apart.
    slow = "tolerance" in options or "refine_below" in options
    n = 200 if slow else 2000 if options.get("near_pairs") == "exact" else 20000
    a, b = random_points(num_faces, n, 41), random_points(num_faces, n, 42)
    b.faces[::2] = a.faces[::2]  # near pairs too
    ours, theirs = index.distance(a, b, **options), client.distance(MODEL, a, b, **options)
    if options.get("bounds"):
        assert np.array_equal(ours[0], theirs[0]) and np.array_equal(ours[1], theirs[1])
    else:
        assert np.array_equal(ours, theirs)


def test_threads_do_not_change_the_answers(torus_index, num_faces):
    a, b = random_points(num_faces, 50000, 43), random_points(num_faces, 50000, 44)
    one = geodex.Index(torus_index, threads=1).distance(a, b)
    assert np.array_equal(one, geodex.Index(torus_index, threads=3).distance(a, b))


def test_every_other_method_equals_the_server(index, client, num_faces, torus_mesh):
    s, t = random_points(num_faces, 6, 45), random_points(num_faces, 200, 46)
    ours_m, theirs_m = index.matrix(s, t, bounds=True), client.matrix(MODEL, s, t, bounds=True)
    for ours, theirs in zip(ours_m, theirs_m):
        assert np.array_equal(ours, theirs)
    t6 = t.take(slice(6))
    for ours, theirs in zip(index.path(s, t6), client.path(MODEL, s, t6)):
        assert np.array_equal(ours.positions, theirs.positions)
        assert np.array_equal(ours.faces, theirs.faces)
        assert np.array_equal(ours.weights, theirs.weights)
        assert ours.length == theirs.length
    for ours, theirs in zip(index.field(s, nearest=True), client.field(MODEL, s, nearest=True)):
        assert np.array_equal(ours, theirs)
    for ours, theirs in zip(index.field(s, radius=0.8, nearest=True),
                            client.field(MODEL, s, radius=0.8, nearest=True)):
        assert np.array_equal(ours, theirs) and ours.dtype == theirs.dtype
    for radius in (-1.0, np.nan, np.inf):
        with pytest.raises(geodex.InvalidArgument, match="radius must be finite and > 0") as ours:
            index.field(s, radius=radius)
        with pytest.raises(geodex.InvalidArgument) as theirs:
            client.field(MODEL, s, radius=radius)
        assert str(ours.value).endswith(str(theirs.value).split("got ")[-1])
    for ours, theirs in zip(index.expmap((5, (0.1, 0.1, 0.8)), 1.2, direction=(1, 2, 3)),
                            client.expmap(MODEL, (5, (0.1, 0.1, 0.8)), 1.2, direction=(1, 2, 3))):
        assert np.array_equal(ours, theirs)
    xyz = np.random.default_rng(47).uniform(-3, 3, (300, 3))
    for ours, theirs in zip(index.locate(xyz), client.locate(MODEL, xyz)):
        assert np.array_equal(ours, theirs)
    assert np.array_equal(index.distance(xyz[:10], xyz[10:20], xyz=True),
                          client.distance(MODEL, xyz[:10], xyz[10:20], xyz=True))
    for ours, theirs in zip(index.mesh(), torus_mesh):
        assert np.array_equal(ours, theirs) and ours.dtype == theirs.dtype


def test_vertex_ids_are_points_in_process_and_on_the_server(index, client, num_faces, torus_mesh):
    vertices, faces = torus_mesh
    ids = np.arange(0, vertices.shape[0], 7)
    a, b = geodex.vertices(ids), geodex.vertices(ids[::-1])
    # The vertex in the lowest face holding it, weight 1 on it.
    lowest = np.array([np.flatnonzero((faces == v).any(axis=1))[0] for v in ids])
    corner = (faces[lowest] == ids[:, None]).argmax(axis=1)
    explicit = (lowest, np.eye(3)[corner])
    ours = index.distance(a, b)
    assert np.array_equal(ours, client.distance(MODEL, a, b))
    assert np.array_equal(ours, index.distance(explicit, b))
    # Vertex ids mix with face points across the two sides of a pair.
    g = random_points(num_faces, ids.shape[0], 49)
    assert np.array_equal(index.distance(a, g), client.distance(MODEL, a, g))
    for ours_p, theirs_p in zip(index.path(a.take(slice(3)), b.take(slice(3))),
                                client.path(MODEL, a.take(slice(3)), b.take(slice(3)))):
        assert np.array_equal(ours_p.positions, theirs_p.positions)
        assert np.array_equal(ours_p.faces, theirs_p.faces)
    first = index.path(a.take(slice(1)), b.take(slice(1)))[0]
    assert np.allclose(first.positions[0], vertices[ids[0]], rtol=0, atol=1e-12)
    assert first.faces[0] == lowest[0]
    assert np.array_equal(index.field(a), client.field(MODEL, a))
    # Whole floats are ids; the rest is refused before anything is sent.
    assert np.array_equal(geodex.vertices(ids.astype(float)).vertices, ids)
    with pytest.raises(geodex.InvalidArgument, match="vertices\\[1\\] is -2"):
        geodex.vertices([0, -2])
    with pytest.raises(geodex.InvalidArgument, match="vertices\\[0\\] is 1.5"):
        geodex.vertices([1.5])
    past = geodex.vertices([0, vertices.shape[0]])
    with pytest.raises(geodex.OutOfRange) as ours_e:
        index.distance(past, past)
    with pytest.raises(geodex.OutOfRange) as theirs_e:
        client.distance(MODEL, past, past)
    assert ours_e.value.message == theirs_e.value.message
    assert "a[1]: vertex id" in ours_e.value.message


def test_the_same_exceptions_as_the_server(index, client, num_faces):
    g = random_points(num_faces, 10, 48)
    cases = [
        ((np.array([0, num_faces], np.int32), np.eye(3)[:2]), geodex.OutOfRange),
        ((g.faces[:2], np.array([[1, 0, 0], [0.5, 0.2, 0.2]])), geodex.InvalidArgument),
    ]
    for a, error in cases:
        with pytest.raises(error) as ours:
            index.distance(a, (g.faces[:2], g.weights[:2]))
        with pytest.raises(error) as theirs:
            client.distance(MODEL, a, (g.faces[:2], g.weights[:2]))
        assert ours.value.message == theirs.value.message
    with pytest.raises(geodex.InvalidArgument, match="a.faces\\[1\\] is -1"):
        index.distance((np.array([0, -1]), np.eye(3)[:2]), (g.faces[:2], g.weights[:2]))
    with pytest.raises(geodex.NotFound):
        geodex.Index("/nonexistent/index.gdx")


def test_an_uncalibrated_index_refuses_bounds(models_dir):
    require_in_process()
    cube = geodex.Index(models_dir / "cube" / "1" / "index.gdx")
    p = random_points(cube.num_faces, 3, 49)
    with pytest.raises(geodex.FailedPrecondition):
        cube.distance(p, p, bounds=True)


def test_build_from_arrays_gives_the_servers_index(torus_mesh, client, tmp_path, num_faces):
    """The torus's arrays, built as geodex-build built builtin:torus: the
    same mesh and options, so the same index and the same answers."""
    vertices, faces = torus_mesh
    seen = []
    built = geodex.build(vertices, faces, tmp_path / "torus.gdx", samples=200,
                         progress=lambda p: seen.append(p))
    assert isinstance(built, geodex.Index) and Path(built.filename).is_file()
    phases = {p.phase for p in seen}
    assert {"sampling", "rows"} <= phases, phases
    assert all(0 <= p.done <= p.total for p in seen if p.total > 0)
    a, b = random_points(num_faces, 5000, 50), random_points(num_faces, 5000, 51)
    assert np.array_equal(built.distance(a, b), client.distance(MODEL, a, b))


def test_build_from_objects_and_files(tmp_path):
    require_in_process()
    # A flat 2 x 1 strip of four triangles: distances are Euclidean.
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], float)
    f = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    trimesh_like = SimpleNamespace(vertices=v, faces=f)
    strip = geodex.build(trimesh_like, tmp_path / "strip.gdx", samples=4, calibrate=False)
    d = strip.distance(([0], [[1, 0, 0]]), ([2], [[0, 1, 0]]))  # (0,0,0) to (2,0,0)
    assert d == pytest.approx([2.0], rel=1e-9)
    obj = tmp_path / "strip.obj"
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in v)
                   + "".join(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in f))
    from_file = geodex.build(obj, tmp_path / "strip_file.gdx", samples=4, calibrate=False)
    assert np.array_equal(from_file.mesh()[1], f)
    d = from_file.distance(([0], [[1, 0, 0]]), ([2], [[0, 1, 0]]))
    assert d == pytest.approx([2.0], rel=1e-9)


def test_split_is_the_long_edge_split_and_refine_its_deprecated_name(tmp_path):
    require_in_process()
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0]], float)
    f = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]])
    geodex.build(v, f, tmp_path / "split.gdx", samples=20, calibrate=False)
    geodex.build(v, f, tmp_path / "whole.gdx", samples=5, split=False, calibrate=False)
    with pytest.warns(DeprecationWarning, match="split="):
        geodex.build(v, f, tmp_path / "old.gdx", samples=5, refine=False, calibrate=False)
    assert (tmp_path / "old.gdx").read_bytes() == (tmp_path / "whole.gdx").read_bytes()
    # Six vertices hold at most three samples unsplit; split, the strip takes 20.
    assert geodex.Index(tmp_path / "split.gdx").num_samples == 20
    assert geodex.Index(tmp_path / "whole.gdx").num_samples <= 6


def test_build_refuses_bad_input(tmp_path):
    require_in_process()
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    with pytest.raises(geodex.InvalidArgument, match=r"faces\[0\]"):
        geodex.build(v, [[0, 1, 3]], tmp_path / "x.gdx")
    with pytest.raises(geodex.InvalidArgument, match="output path"):
        geodex.build(v, [[0, 1, 2]])
    with pytest.raises(geodex.InvalidArgument, match="samples"):
        geodex.build(v, [[0, 1, 2]], tmp_path / "x.gdx", samples=0)
    with pytest.raises(geodex.NotFound):
        geodex.build(tmp_path / "missing.obj", tmp_path / "x.gdx")
    # Two triangles sharing an edge the same way round: inconsistent
    # orientation, which strict refuses and the default repairs.
    v4 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    flipped = np.array([[0, 1, 2], [1, 2, 3]])
    with pytest.raises(geodex.InvalidArgument):
        geodex.build(v4, flipped, tmp_path / "strict.gdx", samples=3, strict=True, calibrate=False)
    assert not (tmp_path / "strict.gdx").exists()


def test_a_failing_progress_callback_is_raised_after_the_build(tmp_path):
    require_in_process()
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)

    def progress(p):
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        geodex.build(v, [[0, 1, 2], [1, 3, 2]], tmp_path / "p.gdx", samples=3, calibrate=False,
                     progress=progress)


def test_a_repaired_shared_mesh_answers_in_the_files_ids(tmp_path):
    """cow_nonmanifold_3k needs repair (non-manifold): the index answers in
    the file's ids, in process as with geodex-query."""
    require_in_process()
    mesh = shared_mesh("cow_nonmanifold_3k.obj")
    path = build_index(str(mesh), tmp_path / "cow.gdx", "--samples", "200", "--no-calibration")
    cow = geodex.Index(path)
    a, b = random_points(cow.num_faces, 2000, 52), random_points(cow.num_faces, 2000, 53)
    reference = query_distances(path, tmp_path, a, b)
    d = cow.distance(a, b)
    same = (d == reference) | (np.isinf(d) & np.isinf(reference))
    assert np.all(same | (np.abs(d - reference) <= 1e-12 * np.abs(reference)))


def _write_hill(path: Path, n: int = 16) -> Path:
    """A bumpy 1 x 1 height field of 2 (n - 1)^2 triangles, as an OBJ file."""
    x, y = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    z = 0.15 * np.sin(3 * x) * np.cos(2 * y)
    corners = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    faces = np.concatenate([
        np.c_[corners, corners + 1, corners + n + 1],
        np.c_[corners, corners + n + 1, corners + n],
    ])
    path.write_text("".join(f"v {a!r} {b!r} {c!r}\n" for a, b, c in zip(x.flat, y.flat, z.flat))
                    + "".join(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in faces))
    return path


def test_build_without_samples_is_geodex_builds_default_target_build(tmp_path):
    """No samples=: to the default error target from a predicted first
    round, as geodex-build without --samples: the same file, byte for byte."""
    require_in_process()
    hill = _write_hill(tmp_path / "hill.obj")
    cli = build_index(str(hill), tmp_path / "cli.gdx", "--threads", "1")
    built = geodex.build(hill, tmp_path / "python.gdx", threads=1)
    target = built.info()["target"]
    assert target["asked"] and target["error"] == 0.005 and target["met"], target
    assert target["rounds"] and target["rounds"][0] != 1000  # predicted, not the old fixed m
    assert (tmp_path / "python.gdx").read_bytes() == cli.read_bytes()


def test_build_messages_speak_pythons_keywords_and_a_missed_target_warns(tmp_path):
    require_in_process()
    hill = _write_hill(tmp_path / "hill.obj", n=8)
    fixed = geodex.build(hill, tmp_path / "fixed.gdx", samples=20, threads=1)
    verdict = fixed.info()["target"]["verdict"]
    assert verdict.startswith("none asked (a fixed m, 20 requested)"), verdict
    assert "--" not in verdict
    with pytest.warns(UserWarning, match=r"error target 0\.0100% NOT met: m stopped at the cap"):
        short = geodex.build(hill, tmp_path / "short.gdx", target_error=0.0001, max_samples=30,
                             threads=1)
    assert short.info()["target"]["met"] is False
