"""Validation at the package's boundary (geodex/_arrays.py) and the error
classes (geodex/errors.py): no server needed."""

from types import SimpleNamespace

import numpy as np
import pytest

import geodex
from geodex._arrays import as_mesh, as_points, as_positions


def test_points_are_normalised_to_int32_and_float64():
    p = as_points(([1, 2], [[1, 0, 0], [0.25, 0.25, 0.5]]), "a")
    assert p.faces.dtype == np.int32 and p.faces.flags.c_contiguous
    assert p.weights.dtype == np.float64 and p.weights.shape == (2, 3)
    again = as_points(p, "a")  # SurfacePoints are points too
    assert np.array_equal(again.faces, p.faces) and np.array_equal(again.weights, p.weights)


def test_points_accept_objects_with_faces_and_weights_and_one_point():
    located = geodex.Located(np.array([3]), np.array([[0.0, 1.0, 0.0]]), np.array([0.5]))
    assert as_points(located, "a").faces.tolist() == [3]
    one = as_points((7, (0.2, 0.3, 0.5)), "centre")
    assert one.faces.tolist() == [7] and one.weights.shape == (1, 3)


def test_take_picks_points():
    p = as_points((np.arange(5), np.full((5, 3), 1 / 3)), "a")
    q = p.take(slice(1, 3))
    assert q.faces.tolist() == [1, 2] and q.weights.shape == (2, 3)
    assert p.take(np.array([4, 0])).faces.tolist() == [4, 0]


def test_empty_points():
    p = as_points(([], np.zeros((0, 3))), "a")
    assert p.faces.shape == (0,) and p.weights.shape == (0, 3)


@pytest.mark.parametrize(
    "faces, weights, error, words",
    [
        ([0, -4], [[1, 0, 0]] * 2, geodex.InvalidArgument, "a.faces[1] is -4"),
        ([0, 1, 2], [[1, 0, 0]] * 2, geodex.InvalidArgument,
         "a.weights has shape (2, 3), want (3, 3)"),
        ([[0, 1]], [[1, 0, 0]] * 2, geodex.InvalidArgument, "a.faces has shape (1, 2)"),
        ([0, 1], [[1, 0]] * 2, geodex.InvalidArgument, "want (2, 3)"),
        ([0.0, 1.5], [[1, 0, 0]] * 2, geodex.InvalidArgument,
         "a.faces[1] is 1.5: ids must be whole numbers"),
        ([0.0, np.nan], [[1, 0, 0]] * 2, geodex.InvalidArgument, "a.faces[1] is nan"),
        ([True, False], [[1, 0, 0]] * 2, geodex.InvalidArgument, "integer array, not bool"),
        ([0.0, -3.0], [[1, 0, 0]] * 2, geodex.InvalidArgument, "a.faces[1] is -3"),
        ([0.0, 1e30], [[1, 0, 0]] * 2, geodex.OutOfRange, "a.faces[1]"),
        ([0, 1, 2], [[1, 0, 0], [0, 1, 0], [np.nan, 0, 1]], geodex.InvalidArgument, "a.weights[2]"),
        ([0, 1], [[np.inf, 0, 0], [0, 1, 0]], geodex.InvalidArgument, "a.weights[0]"),
        ([0, 2**31], [[1, 0, 0]] * 2, geodex.OutOfRange, "a.faces[1]"),
        ([0], [["x", 0, 0]], geodex.InvalidArgument, "a.weights: not a float array"),
    ],
)
def test_bad_points_name_the_array_and_the_element(faces, weights, error, words):
    with pytest.raises(error) as e:
        as_points((np.asarray(faces), weights), "a")
    assert words in str(e.value)
    assert isinstance(e.value, geodex.Error)


def test_whole_float_ids_are_ids():
    # What np.loadtxt reads from a table of ids: float64 of whole numbers.
    p = as_points((np.array([3.0, 0.0, 17.0]), np.full((3, 3), 1 / 3)), "a")
    assert p.faces.dtype == np.int32 and p.faces.tolist() == [3, 0, 17]
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    faces = np.loadtxt(["0 1 2", "1 3 2"])
    assert faces.dtype == np.float64
    assert as_mesh(v, faces)[1].tolist() == [[0, 1, 2], [1, 3, 2]]
    with pytest.raises(geodex.InvalidArgument, match=r"faces\[1, 2\] is 2.5: ids must be whole"):
        as_mesh(v, [[0.0, 1.0, 2.0], [1.0, 3.0, 2.5]])


def test_points_of_another_kind_are_refused():
    with pytest.raises(geodex.InvalidArgument, match="want \\(faces, weights\\)"):
        as_points(np.zeros((3, 4)), "b")


def test_positions():
    assert as_positions([1, 2, 3], "xyz").shape == (1, 3)
    with pytest.raises(geodex.InvalidArgument, match=r"xyz\[1\] is \[nan"):
        as_positions([[0, 0, 0], [np.nan, 0, 0]], "xyz")
    with pytest.raises(geodex.InvalidArgument, match=r"shape \(2, 2\)"):
        as_positions(np.zeros((2, 2)), "xyz")


def test_meshes_from_arrays_and_objects():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], dtype=float)
    f = np.array([[0, 1, 2], [1, 3, 2]])
    vertices, faces = as_mesh(v, f)
    assert faces.dtype == np.int32 and np.array_equal(faces, f)
    trimesh_like = SimpleNamespace(vertices=v, faces=f)
    assert np.array_equal(as_mesh(trimesh_like)[1], f)
    pyvista_like = SimpleNamespace(points=v, faces=np.array([3, 0, 1, 2, 3, 1, 3, 2]))
    assert np.array_equal(as_mesh(pyvista_like)[1], f)
    with pytest.raises(geodex.InvalidArgument, match=r"faces\[1\] is \[1, 4, 2\]"):
        as_mesh(v, [[0, 1, 2], [1, 4, 2]])
    with pytest.raises(geodex.InvalidArgument, match="triangles only"):
        as_mesh(SimpleNamespace(points=v, faces=np.array([4, 0, 1, 3, 2])))
    with pytest.raises(geodex.InvalidArgument, match=".vertices"):
        as_mesh(object())


def test_error_classes_are_the_builtin_exceptions_of_their_mistakes():
    # A caller's bad argument is a ValueError, an unknown name a
    # LookupError, as Python code expects; each stays a geodex.Error.
    for code, builtin in ((3, ValueError), (11, ValueError), (5, LookupError)):
        e = geodex.errors.error_for_code(code, "m")
        assert isinstance(e, builtin) and isinstance(e, geodex.Error), type(e)
    with pytest.raises(ValueError, match=r"a.faces\[0\] is -1"):
        as_points(([-1], [[1, 0, 0]]), "a")
    for code in (5, 9, 13, 14, 15):  # not a caller's argument
        assert not isinstance(geodex.errors.error_for_code(code, "m"), ValueError)
    assert not isinstance(geodex.errors.error_for_code(3, "m"), LookupError)
    assert str(geodex.errors.error_for_code(3, "m")) == "INVALID_ARGUMENT: m"


def test_error_classes_carry_code_and_message():
    e = geodex.errors.error_for_code(5, "unknown model 'x'")
    assert isinstance(e, geodex.NotFound) and isinstance(e, geodex.Error)
    assert e.code == 5 and e.code_name == "NOT_FOUND" and e.message == "unknown model 'x'"
    assert str(e) == "NOT_FOUND: unknown model 'x'"
    assert type(geodex.errors.error_for_code(11, "")) is geodex.OutOfRange
    assert type(geodex.errors.error_for_code(99, "odd")) is geodex.Unknown
    # Every code of google.rpc.Code but OK has its class.
    assert {geodex.errors.error_for_code(c, "").code for c in range(1, 17)} == set(range(1, 17))
