"""Arrays at the package's boundary: the point, position and mesh types, and
their validation.

Everything a caller passes is checked here, before anything is sent or
computed, with vectorised numpy (no per-element Python loop). What only the
index can judge (a face id past the model's face count, weights that do not
sum to 1 within the engine's tolerance) is left to it; what no index could
accept (a wrong shape, NaN, a negative face id) is refused here with
:class:`geodex.InvalidArgument`, naming the array and the index of the first
bad element.
"""

from __future__ import annotations

import os
from typing import Any, NamedTuple, Optional, Tuple, Union

import numpy as np

from .errors import InvalidArgument, OutOfRange

__all__ = [
    "SurfacePoints",
    "VertexPoints",
    "Points",
    "vertices",
    "count",
    "Located",
    "Path",
    "as_points",
    "as_positions",
    "as_mesh",
    "as_near_pairs",
    "is_pathlike",
]

_INT32_MAX = 2**31 - 1


class SurfacePoints(NamedTuple):
    """Points on a mesh: point i lies in face ``faces[i]`` with barycentric
    weights ``weights[i]`` of that face's three vertices (in the mesh file's
    order; polygons fan-triangulated in order).

    Attributes
    ----------
    faces : numpy.ndarray
        (N,) int32 face ids, as in the mesh file the index was built from.
    weights : numpy.ndarray
        (N, 3) float64 barycentric weights, each row >= 0 and summing to 1.
    """

    faces: np.ndarray
    weights: np.ndarray

    def take(self, index: Any) -> "SurfacePoints":
        """The points at ``index`` (a slice, an integer array or a mask):
        ``points.take(slice(0, 10))``. (Indexing the tuple itself picks its
        fields, as for any tuple.)"""
        return SurfacePoints(self.faces[index], self.weights[index])


class VertexPoints(NamedTuple):
    """Points given as vertex ids of the mesh file the index was built from
    (made by :func:`geodex.vertices`): point i is vertex ``vertices[i]``,
    read as weight 1 on it in the lowest-numbered face that holds it. Every
    query takes them where it takes :class:`SurfacePoints`; a path or a field
    from a vertex starts at it, and a path's first point names that face.

    Attributes
    ----------
    vertices : numpy.ndarray
        (N,) int32 vertex ids.
    """

    vertices: np.ndarray

    def take(self, index: Any) -> "VertexPoints":
        """The points at ``index`` (a slice, an integer array or a mask)."""
        return VertexPoints(self.vertices[index])


# What the queries take once the front has checked them.
Points = Union[SurfacePoints, VertexPoints]


def count(points: Points) -> int:
    """The number of points."""
    if isinstance(points, VertexPoints):
        return int(points.vertices.shape[0])
    return int(points.faces.shape[0])


def vertices(ids: Any) -> VertexPoints:
    """Vertices of the mesh file as points, for any query that takes points:
    ``index.distance(geodex.vertices([0, 5]), geodex.vertices([17, 2]))``.

    Parameters
    ----------
    ids : array_like
        (N,) vertex ids (integers, or floats that are whole numbers), or one
        id.

    Raises
    ------
    InvalidArgument
        Not a 1-D array of whole numbers, or a negative id (naming the first).
    OutOfRange
        An id beyond int32. An id past the model's vertex count is refused
        by the query (OutOfRange, naming the point).
    """
    array = np.asarray(ids)
    if array.ndim == 0:
        array = array.reshape(1)
    if array.ndim != 1:
        raise InvalidArgument(f"vertices has shape {array.shape}, want (N,)")
    if array.shape[0] > 0:
        array = as_ids(array, "vertices")
        negative = array < 0
        if negative.any():
            i = _first(negative)
            raise InvalidArgument(f"vertices[{i}] is {int(array[i])}: vertex ids are >= 0")
        large = array > _INT32_MAX
        if large.any():
            i = _first(large)
            raise OutOfRange(f"vertices[{i}] is {int(array[i])}, past any vertex id (int32)")
    return VertexPoints(np.ascontiguousarray(array, dtype=np.int32))


class Located(NamedTuple):
    """The closest surface points of 3D positions (``locate``): usable
    wherever points are (its ``faces`` and ``weights``).

    Attributes
    ----------
    faces : numpy.ndarray
        (N,) int32 face ids.
    weights : numpy.ndarray
        (N, 3) float64 barycentric weights.
    distances : numpy.ndarray
        (N,) float64 Euclidean distance from each position to its point.
    """

    faces: np.ndarray
    weights: np.ndarray
    distances: np.ndarray


class Path(NamedTuple):
    """A geodesic path between two surface points.

    Attributes
    ----------
    positions : numpy.ndarray
        (K, 3) float64 positions along the path, the start first and the end
        last; consecutive points share a mesh face.
    faces : numpy.ndarray
        (K,) int32 the face of each point (the mesh file's ids).
    weights : numpy.ndarray
        (K, 3) float64 the barycentric weights of each point in its face.
    length : float
        The sum of the path's 3D segments; ``inf`` (and K = 0) when the two
        points lie on different connected components.
    """

    positions: np.ndarray
    faces: np.ndarray
    weights: np.ndarray
    length: float


PointsLike = Union[SurfacePoints, Located, Tuple[Any, Any], Any]


def _first(mask: np.ndarray) -> int:
    """The index of the first True of a 1-D mask (which has one)."""
    return int(np.argmax(mask))


def as_ids(ids: np.ndarray, name: str) -> np.ndarray:
    """Ids as an integer array: integers as they are, floats that are whole
    numbers (a table read with ``np.loadtxt``) as int64.

    Raises
    ------
    InvalidArgument
        Neither integers nor floats (booleans, strings, objects), or a float
        that is no whole number, naming the first such element (``name[i]``,
        or ``name[i, j]`` for a 2-D array).
    """
    if np.issubdtype(ids.dtype, np.integer) and ids.dtype != np.bool_:
        return ids
    if not np.issubdtype(ids.dtype, np.floating):
        raise InvalidArgument(f"{name} must be an integer array, not {ids.dtype}")
    fractional = (ids != np.floor(ids)) | ~np.isfinite(ids)
    if fractional.any():
        at = np.unravel_index(_first(fractional.ravel()), ids.shape)
        where = ", ".join(str(int(i)) for i in at)
        raise InvalidArgument(
            f"{name}[{where}] is {ids[at]!r}: ids must be whole numbers "
            f"(a {ids.dtype} array is accepted when every element is one)"
        )
    # Clipped so that a whole float past int64 (1e30) does not wrap into a
    # valid id: it stays past every id, and the range checks name it.
    return np.clip(ids, -(2.0**62), 2.0**62).astype(np.int64)


def as_points(points: PointsLike, name: str) -> Points:
    """Validates surface points and returns them as C-contiguous arrays.

    Parameters
    ----------
    points : tuple or object
        ``(faces, weights)``: faces an integer array of shape (N,) (or a
        float array of whole numbers) and weights
        a float array of shape (N, 3); or anything with ``.faces`` and
        ``.weights`` (a :class:`SurfacePoints`, a :class:`Located`). A single
        point may be given as ``(face, (w0, w1, w2))``. Vertex ids
        (:class:`VertexPoints`, from :func:`geodex.vertices`) pass as they
        are.
    name : str
        How error messages name the points ("a", "sources", ...).

    Returns
    -------
    SurfacePoints or VertexPoints
        faces (N,) int32 and weights (N, 3) float64; or the vertex ids.

    Raises
    ------
    InvalidArgument
        A wrong shape or type, a negative face id, a weight that is NaN or
        infinite; the message names the array and the first bad index.
    OutOfRange
        A face id beyond int32 (no mesh has that many faces).
    """
    if isinstance(points, VertexPoints):
        return points  # checked by geodex.vertices
    if hasattr(points, "faces") and hasattr(points, "weights"):
        faces, weights = points.faces, points.weights
    elif isinstance(points, (tuple, list)) and len(points) == 2:
        faces, weights = points
    else:
        raise InvalidArgument(
            f"{name}: want (faces, weights) arrays or an object with .faces and .weights, "
            f"got {type(points).__name__}"
        )
    faces = np.asarray(faces)
    try:
        weights = np.asarray(weights, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InvalidArgument(f"{name}.weights: not a float array ({e})") from None
    if faces.ndim == 0 and weights.shape == (3,):  # one point
        faces, weights = faces.reshape(1), weights.reshape(1, 3)
    if faces.ndim != 1:
        raise InvalidArgument(f"{name}.faces has shape {faces.shape}, want (N,)")
    n = faces.shape[0]
    if n > 0:
        faces = as_ids(faces, f"{name}.faces")
    if weights.shape != (n, 3):
        raise InvalidArgument(f"{name}.weights has shape {weights.shape}, want ({n}, 3)")
    # Each check is one pass over the array (min, max, a whole-array
    # reduction); the offending index is looked for only once one fails.
    if n > 0:
        if faces.min() < 0:
            i = _first(faces < 0)
            raise InvalidArgument(f"{name}.faces[{i}] is {int(faces[i])}: face ids are >= 0")
        if np.iinfo(faces.dtype).max > _INT32_MAX and faces.max() > _INT32_MAX:
            i = _first(faces > _INT32_MAX)
            raise OutOfRange(f"{name}.faces[{i}] is {int(faces[i])}, past any face id (int32)")
        if not np.isfinite(weights).all():
            i = _first(~np.isfinite(weights).all(axis=1))
            raise InvalidArgument(
                f"{name}.weights[{i}] is {weights[i].tolist()}: weights must be finite"
            )
    return SurfacePoints(
        np.ascontiguousarray(faces, dtype=np.int32), np.ascontiguousarray(weights)
    )


def as_positions(xyz: Any, name: str) -> np.ndarray:
    """Validates 3D positions: an (N, 3) array of finite floats.

    Returns
    -------
    numpy.ndarray
        (N, 3) float64, C-contiguous. A single position (3,) becomes (1, 3).

    Raises
    ------
    InvalidArgument
        Not a float array of shape (N, 3), or a coordinate that is not
        finite (naming the first such row).
    """
    try:
        xyz = np.asarray(xyz, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise InvalidArgument(f"{name}: not a float array ({e})") from None
    if xyz.shape == (3,):
        xyz = xyz.reshape(1, 3)
    if xyz.ndim != 2 or xyz.shape[1] != 3:
        raise InvalidArgument(f"{name} has shape {xyz.shape}, want (N, 3)")
    bad = ~np.isfinite(xyz).all(axis=1)
    if bad.any():
        i = _first(bad)
        raise InvalidArgument(f"{name}[{i}] is {xyz[i].tolist()}: coordinates must be finite")
    return np.ascontiguousarray(xyz)


def _triangles_from_flat(faces: np.ndarray, name: str) -> np.ndarray:
    """pyvista's flat face array [3, a, b, c, 3, ...] as (M, 3)."""
    if faces.size % 4 != 0 or not (faces.reshape(-1, 4)[:, 0] == 3).all():
        raise InvalidArgument(
            f"{name}: a flat face array must be [3, a, b, c, 3, ...] (triangles only)"
        )
    return faces.reshape(-1, 4)[:, 1:]


def as_mesh(mesh: Any, faces: Any = None) -> Tuple[np.ndarray, np.ndarray]:
    """A triangle mesh as (vertices (V, 3) float64, faces (F, 3) int32).

    Parameters
    ----------
    mesh : array or object
        The vertices, an (V, 3) float array (then ``faces`` is required), or
        anything with ``.vertices`` (or ``.points``) and ``.faces``: a trimesh
        Trimesh, a pyvista PolyData of triangles (flat face array), ...
    faces : array, optional
        (F, 3) integer vertex ids, 0-based (floats that are whole numbers are
        accepted, as ``np.loadtxt`` reads them).

    Raises
    ------
    InvalidArgument
        Wrong shapes or types, non-finite coordinates, vertex ids out of
        [0, V) (naming the first bad face).
    """
    if faces is None:
        vertices = getattr(mesh, "vertices", None)
        if vertices is None:
            vertices = getattr(mesh, "points", None)
        faces = getattr(mesh, "faces", None)
        if vertices is None or faces is None:
            raise InvalidArgument(
                "mesh: want vertices and faces arrays, or an object with .vertices (or "
                f".points) and .faces, got {type(mesh).__name__}"
            )
    else:
        vertices = mesh
    vertices = as_positions(vertices, "vertices")
    faces = np.asarray(faces)
    if faces.ndim == 1:
        faces = _triangles_from_flat(faces, "faces")
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise InvalidArgument(f"faces has shape {faces.shape}, want (F, 3)")
    if faces.shape[0] > 0:
        faces = as_ids(faces, "faces")
    bad = ((faces < 0) | (faces >= vertices.shape[0])).any(axis=1)
    if bad.any():
        i = _first(bad)
        raise InvalidArgument(
            f"faces[{i}] is {faces[i].tolist()}: vertex ids must be in [0, {vertices.shape[0]})"
        )
    return vertices, np.ascontiguousarray(faces, dtype=np.int32)


_NEAR_PAIRS = ("path", "unfold", "exact")


def as_near_pairs(near_pairs: Optional[str]) -> Optional[str]:
    """Validates a near-pair mode: None (the default), "path", "unfold" or
    "exact" (see geodex.v1.NearPairs)."""
    if near_pairs is not None and near_pairs not in _NEAR_PAIRS:
        raise InvalidArgument(
            f"near_pairs must be one of {', '.join(_NEAR_PAIRS)} or None, not {near_pairs!r}"
        )
    return near_pairs


def check_nonnegative(name: str, value: float) -> float:
    """``value`` as a float, finite and >= 0; InvalidArgument naming
    ``name`` otherwise."""
    try:
        t = float(value)
    except (TypeError, ValueError):
        raise InvalidArgument(f"{name} must be a number, not {value!r}") from None
    if not (np.isfinite(t) and t >= 0):
        raise InvalidArgument(f"{name} must be finite and >= 0, not {t}")
    return t


def check_tolerance(tolerance: float) -> float:
    """A relative error tolerance: finite and >= 0 (0: none)."""
    return check_nonnegative("tolerance", tolerance)


def is_pathlike(x: Any) -> bool:
    """True for a str, bytes or os.PathLike (a file name)."""
    return isinstance(x, (str, bytes, os.PathLike))
