"""The seven queries of :class:`geodex.Index` and :class:`geodex.Client`,
written once: distance, matrix, path, field, expmap, locate and mesh.

A query's front half is the same in process and over the network: the
arguments are checked, points are validated (and positions located first,
with ``xyz``), pairs must pair up, and the answer is shaped (bounds or not,
nearest sources or not, (u, v) or (r, theta)). Only the back half differs:
the in-process index calls geodex._core, the client sends requests. A
subclass supplies that half as the ``_run_*`` methods, each taking the
query's ``At`` (where it is answered: nothing for an index; the model and
its version for a client) and arguments already checked.

Errors raised here are the same for both, which is what keeps their
exceptions identical (tests/test_index.py compares them).
"""

from __future__ import annotations

import math
from typing import Any, Generic, List, Optional, Sequence, Tuple, TypeVar, Union

import numpy as np

from ._arrays import Located, Path, Points, SurfacePoints, VertexPoints, as_near_pairs, as_points
from ._arrays import as_positions, count
from ._arrays import check_nonnegative, check_tolerance
from .errors import InvalidArgument

__all__ = ["QueryFront", "NEAR_PAIRS"]

# geodex.v1.NearPairs, also what geodex._core takes.
NEAR_PAIRS = {None: 0, "path": 1, "unfold": 2, "exact": 3}

# Where a query is answered (the backend's business: an index ignores it; a
# client's carries the model and the version its positions were located in).
At = TypeVar("At")

Distances = Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]


class QueryFront(Generic[At]):
    """The front half of the seven queries; subclasses answer them in
    ``_run_*``. Holds no state: thread safety is the subclass's."""

    # --- the back half, one method a query ---------------------------------

    def _run_distance(
        self, at: At, a: Points, b: Points, near_pairs: int, tolerance: float,
        bounds: bool, refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """(N,) float64 distances, and (N,) bounds when ``bounds``."""
        raise NotImplementedError

    def _run_matrix(
        self, at: At, sources: Points, targets: Points, near_pairs: int,
        tolerance: float, bounds: bool, refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """(S, T) float64 distances, and (S, T) bounds when ``bounds``."""
        raise NotImplementedError

    def _run_path(
        self, at: At, a: Points, b: Points, exact_corridor: int, batch_size: int
    ) -> List[Path]:
        raise NotImplementedError

    def _run_field(
        self, at: At, sources: Points, nearest: bool
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """(n,) float64 per vertex, and (n,) int32 nearest sources when
        ``nearest``."""
        raise NotImplementedError

    def _run_field_within(
        self, at: At, sources: Points, radius: float, nearest: bool
    ) -> Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]:
        """(k,) int32 vertices, (k,) float64 distances, and (k,) int32
        nearest sources when ``nearest``."""
        raise NotImplementedError

    def _run_expmap(
        self, at: At, centre: Points, radius: float, direction: Optional[np.ndarray],
        polar: bool, near_pairs: int, tolerance: float,
    ) -> Tuple[np.ndarray, np.ndarray]:
        """(k,) int32 vertices and (k, 2) float64 coordinates; ``direction``
        is as the caller gave it, as (M, 3) float64 positions (one
        expected)."""
        raise NotImplementedError

    def _run_locate(self, at: At, xyz: np.ndarray, batch_size: int) -> Located:
        """The points of (N, 3) float64 positions; a client pins ``at`` to
        the version that answered."""
        raise NotImplementedError

    def _run_mesh(self, at: At) -> Tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def _run_vertices(self, at: At, points: VertexPoints, name: str) -> Points:
        """Vertex ids as the backend answers them: an index reads them as
        surface points here; a client sends the ids as they are."""
        return points

    # --- the front half ----------------------------------------------------

    def _points(
        self, at: At, points: Sequence[Any], names: Sequence[str], xyz: bool
    ) -> List[Points]:
        """Validated points; with xyz, every array is validated before the
        first is located (nothing is sent for input no index accepts)."""
        if not xyz:
            checked = [as_points(p, name) for p, name in zip(points, names)]
            return [
                self._run_vertices(at, p, name) if isinstance(p, VertexPoints) else p
                for p, name in zip(checked, names)
            ]
        positions = [as_positions(p, name) for p, name in zip(points, names)]
        located = [self._run_locate(at, p, 65536) for p in positions]
        return [SurfacePoints(x.faces, x.weights) for x in located]

    @staticmethod
    def _pair_up(a: Points, b: Points) -> None:
        if count(a) != count(b):
            raise InvalidArgument(
                f"a has {count(a)} points but b has {count(b)}; they must pair up"
            )

    def _distance(
        self, at: At, a: Any, b: Any, bounds: bool, tolerance: float, near_pairs: Optional[str],
        xyz: bool, refine_below: float,
    ) -> Distances:
        check_tolerance(tolerance)
        below = check_nonnegative("refine_below", refine_below)
        as_near_pairs(near_pairs)
        pa, pb = self._points(at, [a, b], ("a", "b"), xyz)
        self._pair_up(pa, pb)
        d, bnd = self._run_distance(
            at, pa, pb, NEAR_PAIRS[near_pairs], float(tolerance), bool(bounds), below
        )
        return (d, bnd) if bnd is not None else d

    def _matrix(
        self, at: At, sources: Any, targets: Any, bounds: bool, tolerance: float,
        near_pairs: Optional[str], xyz: bool, refine_below: float,
    ) -> Distances:
        check_tolerance(tolerance)
        below = check_nonnegative("refine_below", refine_below)
        as_near_pairs(near_pairs)
        src, tgt = self._points(at, [sources, targets], ("sources", "targets"), xyz)
        m, bnd = self._run_matrix(
            at, src, tgt, NEAR_PAIRS[near_pairs], float(tolerance), bool(bounds), below
        )
        return (m, bnd) if bnd is not None else m

    def _path(
        self, at: At, a: Any, b: Any, exact_corridor: int, xyz: bool, batch_size: int
    ) -> List[Path]:
        if not 0 <= int(exact_corridor) <= 64:
            raise InvalidArgument(f"exact_corridor must be in [0, 64], not {exact_corridor}")
        pa, pb = self._points(at, [a, b], ("a", "b"), xyz)
        self._pair_up(pa, pb)
        return self._run_path(at, pa, pb, int(exact_corridor), max(1, int(batch_size)))

    def _field(
        self, at: At, sources: Any, radius: float, nearest: bool, xyz: bool
    ) -> Union[np.ndarray, Tuple[np.ndarray, ...]]:
        radius = float(radius)
        if radius != 0 and not (math.isfinite(radius) and radius > 0):
            raise InvalidArgument(f"the radius must be finite and > 0, got {radius:g}")
        (src,) = self._points(at, [sources], ("sources",), xyz)
        if radius > 0:
            ids, d, near = self._run_field_within(at, src, radius, bool(nearest))
            return (ids, d, near) if near is not None else (ids, d)
        values, nearest_sources = self._run_field(at, src, bool(nearest))
        return (values, nearest_sources) if nearest_sources is not None else values

    def _expmap(
        self, at: At, centre: Any, radius: float, direction: Optional[Sequence[float]],
        polar: bool, near_pairs: Optional[str], tolerance: float, xyz: bool,
    ) -> Tuple[np.ndarray, np.ndarray]:
        check_tolerance(tolerance)
        as_near_pairs(near_pairs)
        (c,) = self._points(at, [centre], ("centre",), xyz)
        if count(c) != 1:
            raise InvalidArgument(f"centre must be one point, not {count(c)}")
        ref = None if direction is None else as_positions(direction, "direction")
        return self._run_expmap(
            at, c, float(radius), ref, bool(polar), NEAR_PAIRS[near_pairs], float(tolerance)
        )

    def _locate(self, at: At, xyz: Any, batch_size: int) -> Located:
        return self._run_locate(at, as_positions(xyz, "xyz"), batch_size)

    def _mesh(self, at: At) -> Tuple[np.ndarray, np.ndarray]:
        return self._run_mesh(at)
