"""Indexes in this process: :class:`Index` and :func:`build`, over the
compiled bindings of geodex's core (``geodex._core``, core/python/).

This is the only module of the package that imports ``geodex._core``; the
rest of the package (the gRPC client) works without it. An Index takes the
same arguments as the Client's methods, without the model name, and gives
the same answers to the bit: the server answers with the same engine, in the
same ids (the mesh file's, also when the builder repaired the mesh).
"""

from __future__ import annotations

import json
import logging
import os
import sys
import tempfile
import time
import warnings
from typing import Any, Callable, Dict, List, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from ._arrays import Located, Path, Points, SurfacePoints, VertexPoints, as_mesh, is_pathlike
from ._front import QueryFront
from .errors import InvalidArgument

try:
    from . import _core
except ImportError as e:  # the package was installed without its compiled part
    _core = None
    _core_error: Optional[ImportError] = e
else:
    _core_error = None

__all__ = ["Index", "build", "BuildProgress", "has_in_process"]

# The builder's messages about the rounds of a target-error build.
_log = logging.getLogger("geodex")


def _read(points: Points) -> SurfacePoints:
    """Points as the compiled module takes them: the front has read vertex
    ids as surface points already (Index._run_vertices)."""
    assert isinstance(points, SurfacePoints), "vertex ids reach the index as surface points"
    return points


def has_in_process() -> bool:
    """True when the compiled module (geodex._core) is installed, so that
    :class:`Index` and :func:`build` work."""
    return _core is not None


def _require_core() -> Any:
    if _core is None:
        raise ImportError(
            "geodex.Index and geodex.build need the compiled module geodex._core, which "
            f"this installation lacks ({_core_error}); the client (geodex.connect) works "
            "without it"
        )
    return _core


class BuildProgress(NamedTuple):
    """How far :func:`build` has come: ``done`` of ``total`` steps of
    ``phase`` ("sampling", "repair", "rows", "merge", "calibration", ...)."""

    phase: str
    done: int
    total: int


class Index(QueryFront[None]):
    """An index file, mapped read-only, answering queries in this process.

    Parameters
    ----------
    path : str or os.PathLike
        A .gdx file (geodex-build, or :func:`build`); kept as ``filename``.
    threads : int
        Threads for large batches (``distance``, ``matrix``); 0: one per
        core. The answers do not depend on it.

    Raises
    ------
    NotFound
        No such file.
    DataLoss, FailedPrecondition, InvalidArgument
        A corrupt file, another format version, or not an index.

    Notes
    -----
    Thread safety: an Index is immutable; its methods may be called from
    several threads at once (they release the GIL while they compute).
    """

    def __init__(self, path: Union[str, "os.PathLike[str]"], *, threads: int = 0) -> None:
        core = _require_core()
        if int(threads) < 0:
            raise InvalidArgument(f"threads must be >= 0, not {threads}")
        self.filename = os.fspath(path)
        self._index = core.Index(self.filename, int(threads))

    def __repr__(self) -> str:
        return (
            f"geodex.Index({self.filename!r}: {self.num_vertices} vertices, "
            f"{self.num_faces} faces, {self.num_samples} samples)"
        )

    # --- what the index holds -----------------------------------------------

    @property
    def num_vertices(self) -> int:
        """Vertices of the mesh file (what vertex ids are checked against)."""
        return self._index.num_vertices

    @property
    def num_faces(self) -> int:
        """Faces of the mesh file (what face ids are checked against)."""
        return self._index.num_faces

    @property
    def num_samples(self) -> int:
        """m, the samples of the geodesic triangulation."""
        return self._index.num_samples

    @property
    def has_error_bounds(self) -> bool:
        """True when the index carries its accuracy calibration (``bounds``
        and ``tolerance`` need it)."""
        return self._index.has_error_bounds

    @property
    def report(self) -> Dict[str, str]:
        """The builder's report ("key" -> "value"), as Client.model gives it."""
        out: Dict[str, str] = {}
        for line in self._index.report.splitlines():
            key, eq, value = line.partition("=")
            if eq and key.strip():
                out[key.strip()] = value.strip()
        return out

    def info(self) -> Dict[str, Any]:
        """The build report as a dict: mesh, repairs, samples, size by
        section, the error target (met, or why not) and the relative error by
        distance (keys in core/index/README.md, "The build report"); relative
        errors are fractions. Equal to ``Client.info`` of a server serving
        this file."""
        return json.loads(self._index.report_json)

    # --- queries (geodex/_front.py checks the arguments and shapes answers) --

    def distance(
        self,
        a: Any,
        b: Any,
        bounds: bool = False,
        tolerance: float = 0.0,
        *,
        near_pairs: Optional[str] = None,
        xyz: bool = False,
        refine_below: float = 0.0,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """Geodesic distances of pairs, ``d[i] = d(a[i], b[i])``, as
        :meth:`geodex.Client.distance` (without the model).

        Parameters
        ----------
        a, b : points
            N points each: ``(faces, weights)``, (N,) integer face ids and
            (N, 3) float barycentric weights (stored as int32 and float64),
            or (N, 3) float positions with ``xyz=True``.
        bounds : bool
            Also return each distance's absolute error bound.
        tolerance : float
            Relative error tolerance (e.g. 0.005); 0: the index's.
        near_pairs : {None, "path", "unfold", "exact"}
            How near pairs are answered; None: the index's configuration.
        xyz : bool
            ``a`` and ``b`` are (N, 3) positions, located first.
        refine_below : float
            Also refine every pair that may be closer than this many L1000
            (the spacing of 1,000 samples on the surface); 8: the
            every-distance mode. 0: the index's threshold.

        Returns
        -------
        numpy.ndarray or (numpy.ndarray, numpy.ndarray)
            (N,) float64 distances (``inf`` between components); with
            ``bounds``, also (N,) float64 absolute error bounds.

        Raises
        ------
        InvalidArgument, OutOfRange
            Bad points (naming the first: "a[17]: ...").
        FailedPrecondition
            ``bounds`` or ``tolerance`` of an index without calibration.
        """
        return self._distance(None, a, b, bounds, tolerance, near_pairs, xyz, refine_below)

    def matrix(
        self,
        sources: Any,
        targets: Any,
        bounds: bool = False,
        tolerance: float = 0.0,
        *,
        near_pairs: Optional[str] = None,
        xyz: bool = False,
        refine_below: float = 0.0,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """All sources x targets distances, ``m[s, t] = d(sources[s],
        targets[t])``, as :meth:`geodex.Client.matrix`.

        Parameters are those of :meth:`distance`: ``sources`` are S points
        ((S,) int faces, (S, 3) float weights), ``targets`` T points.

        Returns
        -------
        numpy.ndarray or (numpy.ndarray, numpy.ndarray)
            (S, T) float64 distances; with ``bounds``, also (S, T) float64
            bounds.
        """
        return self._matrix(
            None, sources, targets, bounds, tolerance, near_pairs, xyz, refine_below
        )

    def path(self, a: Any, b: Any, *, exact_corridor: int = 0, xyz: bool = False) -> List[Path]:
        """Geodesic paths from a[i] to b[i], as :meth:`geodex.Client.path`.

        Parameters
        ----------
        a, b : points
            N points each: (N,) int faces and (N, 3) float weights, or (N, 3)
            float positions with ``xyz=True``.
        exact_corridor : int
            In [0, 64]: when > 0, each path is also solved exactly within
            this many edge steps of the traced one, and the shorter kept.

        Returns
        -------
        list of Path
            One per pair: (K, 3) float64 positions, (K,) int32 faces, (K, 3)
            float64 weights and the float length; K = 0 and length ``inf``
            between components.
        """
        return self._path(None, a, b, exact_corridor, xyz, 1)

    def field(
        self, sources: Any, *, radius: float = 0.0, nearest: bool = False, xyz: bool = False
    ) -> Union[np.ndarray, Tuple[np.ndarray, ...]]:
        """The distance from the nearest source to every vertex of the mesh
        file, or to the vertices within ``radius``, as
        :meth:`geodex.Client.field`.

        Parameters
        ----------
        sources : points
            (S,) int faces and (S, 3) float weights, or (S, 3) float
            positions with ``xyz=True``.
        radius : float
            0: every vertex. > 0 and finite: only the vertices within it,
            with exact distances. Negative, NaN or infinite:
            InvalidArgument.
        nearest : bool
            Also return each vertex's nearest source.

        Returns
        -------
        numpy.ndarray or tuple of numpy.ndarray
            Without a radius: (n,) float64 per vertex (and (n,) int32 the
            nearest source, -1 if none, with ``nearest``). With a radius:
            (k,) int32 vertices, ascending, and (k,) float64 distances (and
            (k,) int32 nearest sources with ``nearest``).
        """
        return self._field(None, sources, radius, nearest, xyz)

    def expmap(
        self,
        centre: Any,
        radius: float,
        *,
        direction: Optional[Sequence[float]] = None,
        polar: bool = False,
        near_pairs: Optional[str] = None,
        tolerance: float = 0.0,
        xyz: bool = False,
    ) -> Tuple[np.ndarray, np.ndarray]:
        """The exponential map round one point, as
        :meth:`geodex.Client.expmap`.

        Parameters
        ----------
        centre : point
            One point: ``(face, (w0, w1, w2))``, or a (3,) position with
            ``xyz=True``.
        radius : float
            Vertices farther than this from the centre are left out.
        direction : (3,) float, optional
            theta = 0 along it, projected into the centre's face.
        polar : bool
            Return (r, theta) instead of (u, v).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            (k,) int32 vertex ids, ascending, and (k, 2) float64 (u, v), or
            (r, theta) with ``polar``.
        """
        return self._expmap(None, centre, radius, direction, polar, near_pairs, tolerance, xyz)

    def locate(self, xyz: Any) -> Located:
        """The closest surface point of each position.

        Parameters
        ----------
        xyz : (N, 3) float
            Positions.

        Returns
        -------
        Located
            faces (N,) int32, weights (N, 3) float64 (usable as points) and
            distances (N,) float64 from each position to its point.
        """
        return self._locate(None, xyz, 0)

    def mesh(self) -> Tuple[np.ndarray, np.ndarray]:
        """The mesh file's (V, 3) float64 vertices and (F, 3) int32 faces
        (polygons fan-triangulated), as :meth:`geodex.Client.mesh`."""
        return self._mesh(None)

    # --- the back half: geodex._core ----------------------------------------

    def _run_vertices(self, at: None, points: VertexPoints, name: str) -> Points:
        faces, weights = self._index.vertex_points(points.vertices, name)
        return SurfacePoints(faces, weights)

    def _run_distance(
        self, at: None, a: Points, b: Points, near_pairs: int, tolerance: float,
        bounds: bool, refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        a, b = _read(a), _read(b)
        d, bnd = self._index.distance(
            a.faces, a.weights, b.faces, b.weights, near_pairs, tolerance, bounds, refine_below
        )
        return d, (bnd if bounds else None)

    def _run_matrix(
        self, at: None, sources: Points, targets: Points, near_pairs: int,
        tolerance: float, bounds: bool, refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        sources, targets = _read(sources), _read(targets)
        m, bnd = self._index.matrix(
            sources.faces, sources.weights, targets.faces, targets.weights,
            near_pairs, tolerance, bounds, refine_below,
        )
        return m, (bnd if bounds else None)

    def _run_path(
        self, at: None, a: Points, b: Points, exact_corridor: int, batch_size: int
    ) -> List[Path]:
        a, b = _read(a), _read(b)
        raw = self._index.path(a.faces, a.weights, b.faces, b.weights, exact_corridor)
        return [Path(*path) for path in raw]  # (positions, faces, weights, length)

    def _run_field(
        self, at: None, sources: Points, nearest: bool
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        sources = _read(sources)
        d, near = self._index.field(sources.faces, sources.weights)
        return d, (near if nearest else None)

    def _run_field_within(
        self, at: None, sources: Points, radius: float, nearest: bool
    ) -> Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]:
        sources = _read(sources)
        ids, d, near = self._index.field_within(sources.faces, sources.weights, radius)
        return ids, d, (near if nearest else None)

    def _run_expmap(
        self, at: None, centre: Points, radius: float, direction: Optional[np.ndarray],
        polar: bool, near_pairs: int, tolerance: float,
    ) -> Tuple[np.ndarray, np.ndarray]:
        centre = _read(centre)
        ref = None if direction is None else direction[0]
        vertices, r, theta, u, v = self._index.expmap(
            int(centre.faces[0]), centre.weights[0], radius, ref, near_pairs, tolerance
        )
        coords = np.stack([r, theta] if polar else [u, v], axis=1).reshape(-1, 2)
        return vertices, coords

    def _run_locate(self, at: None, xyz: np.ndarray, batch_size: int) -> Located:
        faces, weights, distances = self._index.locate(xyz)
        return Located(faces, weights, distances)

    def _run_mesh(self, at: None) -> Tuple[np.ndarray, np.ndarray]:
        vertices, faces = self._index.mesh()
        return vertices, faces


class _ProgressBar:
    """A one-line progress bar on stderr (a log line every 10 s when stderr
    is not a terminal)."""

    def __init__(self) -> None:
        self._tty = sys.stderr.isatty()
        self._last = 0.0

    def __call__(self, p: BuildProgress) -> None:
        fraction = p.done / p.total if p.total > 0 else 1.0
        line = f"[{p.phase}] {p.done}/{p.total} ({100 * fraction:.1f}%)"
        now = time.monotonic()
        if self._tty:
            bar = "#" * int(30 * fraction)
            sys.stderr.write(f"\r\033[K{line} [{bar:<30}]" + ("\n" if p.done >= p.total else ""))
            sys.stderr.flush()
        elif p.done >= p.total or now - self._last >= 10:
            sys.stderr.write(line + "\n")
            self._last = now


def build(
    mesh: Any,
    faces: Any = None,
    path: Union[None, str, "os.PathLike[str]"] = None,
    *,
    samples: Optional[int] = None,
    target_error: Optional[float] = None,
    max_samples: Optional[int] = None,
    seed: int = 1,
    threads: int = 0,
    strict: bool = False,
    split: bool = True,
    calibrate: bool = True,
    progress: Union[None, bool, Callable[[BuildProgress], Any]] = None,
    refine: Optional[bool] = None,
) -> Index:
    """Builds an index, writes it to ``path`` and opens it.

    Parameters
    ----------
    mesh : str, os.PathLike, array or object
        A mesh file (.obj, .ply, .off; ids in answers are the file's), or
        the vertices as a (V, 3) float array with ``faces``, or anything
        with ``.vertices`` (or ``.points``) and ``.faces`` (trimesh,
        pyvista-like).
    faces : array, optional
        (F, 3) integer vertex ids when ``mesh`` is the vertices. With a file
        or a mesh object, the output path may be given here instead.
    path : str or os.PathLike
        Where to write the index (.gdx); written atomically.
    samples : int, optional
        m, the number of samples: exactly m without ``target_error``, the
        first round's with it. Default: none, and the index is built to the
        error target (``target_error``, 0.005 unless given) from a predicted
        first round, as ``geodex-build`` without ``--samples`` builds it.
    target_error : float, optional
        The error target (default 0.005 when ``samples`` is not given):
        relative RMS over area-uniform pairs at most E and p99 at most 4E
        for pairs at least 8 L1000 apart, by 95% upper limits on held-out
        sources; m grows round by round up to ``max_samples``. Each round is
        logged to the "geodex" logger (logging.INFO); a build that stops
        short of its target warns (``UserWarning``) with the report's
        verdict.
    max_samples : int, optional
        With a target: the cap on m (default 8000; with ``split=False``,
        at most half the mesh's vertices).
    seed : int
        The sampling seed: the same mesh and options give the same bytes.
    threads : int
        Worker threads (0: one per core).
    strict : bool
        Refuse a mesh that needs repair (duplicate faces, non-manifold
        edges or vertices, inconsistent orientation) instead of repairing it;
        a repaired mesh keeps its ids in every answer.
    split : bool
        Split edges longer than half the sample spacing flat first (the
        surface is unchanged; ``geodex-build --no-split`` is ``False``).
    calibrate : bool
        Measure the index against held-out exact propagations and store its
        error bounds (``bounds`` and ``tolerance`` need them).
    progress : None, True or callable
        True: a progress bar on stderr. A callable gets a
        :class:`BuildProgress` now and then (from the building thread, with
        the GIL held; an exception it raises is raised by ``build`` once the
        build is over).
    refine : bool, deprecated
        The old name of ``split`` (a DeprecationWarning); "refine" names
        the near pairs' refinement (``refine_below``).

    Returns
    -------
    Index
        The new index, opened.

    Raises
    ------
    InvalidArgument
        Bad arrays or options, or a mesh that cannot be built from (with
        ``strict``: one that needs repair), naming the reason.
    NotFound
        No such mesh file.
    FailedPrecondition
        No valid geodesic triangulation within the builder's limits.
    """
    core = _require_core()
    if refine is not None:
        warnings.warn("geodex.build: refine= is deprecated; it is split= (the long-edge split)",
                      DeprecationWarning, stacklevel=2)
        split = refine
    if path is None and faces is not None and is_pathlike(faces):
        faces, path = None, faces
    if path is None:
        raise InvalidArgument("build: the output path (.gdx) is required")
    if samples is not None and int(samples) < 1:
        raise InvalidArgument(f"samples must be >= 1, not {samples}")
    if target_error is not None and not (float(target_error) > 0):
        raise InvalidArgument(f"target_error must be > 0, not {target_error}")
    if max_samples is not None and int(max_samples) < 1:
        raise InvalidArgument(f"max_samples must be >= 1, not {max_samples}")
    if int(threads) < 0:
        raise InvalidArgument(f"threads must be >= 0, not {threads}")
    if progress is True:
        callback: Optional[Callable[[BuildProgress], Any]] = _ProgressBar()
    elif progress is None or progress is False:
        callback = None
    elif callable(progress):
        callback = progress
    else:
        raise InvalidArgument(f"progress must be None, True or a callable, not {progress!r}")

    def report(phase: str, done: int, total: int) -> None:
        assert callback is not None
        callback(BuildProgress(phase, done, total))

    def run(mesh_path: str) -> None:
        core.build(
            mesh_path,
            os.fsdecode(path),
            0 if samples is None else int(samples),
            0.0 if target_error is None else float(target_error),
            0 if max_samples is None else int(max_samples),
            int(seed),
            int(threads),
            bool(strict),
            bool(split),
            bool(calibrate),
            None if callback is None else report,
            _log.info,
        )

    if faces is None and is_pathlike(mesh):
        run(os.fsdecode(mesh))
    else:
        # Arrays go to the builder as the file it reads (the same repair as
        # for any mesh file): a binary PLY of doubles keeps every coordinate
        # and the order of vertices and faces, so the ids are the arrays'.
        vertices, face_array = as_mesh(mesh, faces)
        with tempfile.TemporaryDirectory(prefix="geodex-build-") as tmp:
            ply = os.path.join(tmp, "mesh.ply")
            _write_ply(ply, vertices, face_array)
            run(ply)
    index = Index(path, threads=threads)
    _warn_if_target_missed(index)
    return index


def _warn_if_target_missed(index: "Index") -> None:
    """Warns with the report's verdict when a build stopped short of its
    error target (the index is written all the same)."""
    target = index.info().get("target") or {}
    if target.get("asked") and target.get("met") is False:
        warnings.warn(f"geodex.build: error target {target.get('verdict')}", stacklevel=3)


def _write_ply(path: str, vertices: np.ndarray, faces: np.ndarray) -> None:
    """A binary little-endian PLY: double x, y, z; faces as uchar-counted int lists."""
    header = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {vertices.shape[0]}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"element face {faces.shape[0]}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    records = np.empty(faces.shape[0], dtype=[("n", "u1"), ("v", "<i4", (3,))])
    records["n"] = 3
    records["v"] = faces
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
        f.write(records.tobytes())
