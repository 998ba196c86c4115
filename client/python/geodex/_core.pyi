# Types of geodex._core, the compiled bindings of core (core/python/*.cc).
# Users call them through geodex.Index and geodex.build (_inprocess.py),
# which validate the arrays first; these are the shapes and dtypes the
# bindings take (anything numpy converts, as C-contiguous int32 faces and
# float64 weights and positions) and return.

from typing import Callable, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

_Faces = npt.ArrayLike  # (N,) int32
_Weights = npt.ArrayLike  # (N, 3) float64
_F64 = npt.NDArray[np.float64]
_I32 = npt.NDArray[np.int32]

class Index:
    """An index file answering queries in the mesh file's ids."""

    def __init__(self, path: str, threads: int = 0) -> None: ...
    @property
    def num_vertices(self) -> int: ...
    @property
    def num_faces(self) -> int: ...
    @property
    def num_samples(self) -> int: ...
    @property
    def has_error_bounds(self) -> bool: ...
    @property
    def report(self) -> str: ...
    @property
    def report_json(self) -> str: ...
    def distance(
        self, a_faces: _Faces, a_weights: _Weights, b_faces: _Faces, b_weights: _Weights,
        near_pairs: int, tolerance: float, bounds: bool, refine_below: float, /,
    ) -> Tuple[_F64, Optional[_F64]]:
        """(N,) float64 distances and, with bounds, (N,) float64 bounds."""
    def matrix(
        self, s_faces: _Faces, s_weights: _Weights, t_faces: _Faces, t_weights: _Weights,
        near_pairs: int, tolerance: float, bounds: bool, refine_below: float, /,
    ) -> Tuple[_F64, Optional[_F64]]:
        """(S, T) float64 distances and, with bounds, (S, T) float64 bounds."""
    def path(
        self, a_faces: _Faces, a_weights: _Weights, b_faces: _Faces, b_weights: _Weights,
        exact_corridor: int, /,
    ) -> List[Tuple[_F64, _I32, _F64, float]]:
        """Per pair: (K, 3) float64 positions, (K,) int32 faces, (K, 3)
        float64 weights, length."""
    def field(self, faces: _Faces, weights: _Weights, /) -> Tuple[_F64, _I32]:
        """(n,) float64 distances and (n,) int32 nearest sources per vertex."""
    def field_within(
        self, faces: _Faces, weights: _Weights, radius: float, /
    ) -> Tuple[_I32, _F64, _I32]:
        """(k,) int32 vertices, (k,) float64 distances, (k,) int32 nearest
        sources."""
    def expmap(
        self, face: int, weights: _Weights, radius: float, direction: Optional[_Weights],
        near_pairs: int, tolerance: float, /,
    ) -> Tuple[_I32, _F64, _F64, _F64, _F64]:
        """(k,) int32 vertices and (k,) float64 r, theta, u, v."""
    def locate(self, xyz: _Weights, /) -> Tuple[_I32, _F64, _F64]:
        """(N,) int32 faces, (N, 3) float64 weights, (N,) float64 distances."""
    def vertex_points(self, ids: _Faces, name: str, /) -> Tuple[_I32, _F64]:
        """(N,) int32 faces and (N, 3) float64 weights of (N,) vertex ids:
        weight 1 on each vertex in the lowest face that holds it."""
    def mesh(self) -> Tuple[_F64, _I32]:
        """(V, 3) float64 vertices and (F, 3) int32 faces."""

def build(
    mesh_path: str,
    out: str,
    samples: int,
    target_error: float,
    max_samples: int,
    seed: int,
    threads: int,
    strict: bool,
    split: bool,
    calibrate: bool,
    progress: Optional[Callable[[str, int, int], None]],
    log: Optional[Callable[[str], None]],
) -> str:
    """Builds the index of mesh_path (a mesh file or builtin:NAME) into out;
    returns the build report. samples 0: none asked, so to the error target
    (target_error, 0: the default) as geodex-build without --samples."""
