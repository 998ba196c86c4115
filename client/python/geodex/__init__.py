"""geodex: geodesic distances, paths and fields on triangle meshes, from
precomputed indexes (Xin, Ying & He 2012), with numpy arrays in and out.

Two ways in, with the same methods and the same answers:

- :func:`connect` opens a :class:`Client` of a geodex server (gRPC);
- :class:`Index` maps an index file and answers in this process, and
  :func:`build` makes one from a mesh (both need the compiled module
  ``geodex._core``, installed with the package).

A surface point is a face id of the mesh file the index was built from and
the barycentric weights of that face's three vertices: points are
``(faces, weights)`` arrays of shapes (N,) and (N, 3). Errors are
:class:`Error` subclasses named after their status code
(:class:`InvalidArgument`, :class:`NotFound`, ...).
"""

from .errors import (
    Aborted,
    AlreadyExists,
    Cancelled,
    DataLoss,
    DeadlineExceeded,
    Error,
    FailedPrecondition,
    Internal,
    InvalidArgument,
    NotFound,
    OutOfRange,
    PermissionDenied,
    ResourceExhausted,
    Unauthenticated,
    Unavailable,
    Unimplemented,
    Unknown,
)
from . import errors as _errors
from ._arrays import Located, Path, SurfacePoints
from .client import Client, Model, Tls, Triangulation, connect
from ._inprocess import BuildProgress, Index, build, has_in_process

__version__ = "0.1.0"

__all__ = [
    "connect",
    "Client",
    "Model",
    "Tls",
    "Triangulation",
    "Index",
    "build",
    "BuildProgress",
    "has_in_process",
    "SurfacePoints",
    "Located",
    "Path",
    # the exception classes, one per status code
    *(name for name in _errors.__all__ if name != "error_for_code"),
]
