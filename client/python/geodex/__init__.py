"""geodex: geodesic distances, paths and fields on triangle meshes, from
precomputed indexes (Xin, Ying & He 2012), with numpy arrays in and out.

Two ways in, with the same methods and the same answers:

- :func:`connect` opens a :class:`Client` of a geodex server (gRPC; it
  needs grpcio and protobuf: ``pip install 'geodex[client]'``);
- :class:`Index` maps an index file and answers in this process, and
  :func:`build` makes one from a mesh (both need the compiled module
  ``geodex._core``, installed with the package, and numpy only).

A surface point is a face id of the mesh file the index was built from and
the barycentric weights of that face's three vertices: points are
``(faces, weights)`` arrays of shapes (N,) and (N, 3), or vertex ids of
the mesh file, ``geodex.vertices(ids)``. Errors are
:class:`Error` subclasses named after their status code
(:class:`InvalidArgument`, :class:`NotFound`, ...).
"""

import typing as _typing

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
from ._arrays import Located, Path, SurfacePoints, VertexPoints, vertices
from ._inprocess import BuildProgress, Index, build, has_in_process
from ._values import Model, Tls, Triangulation

try:
    from .client import Client, connect
except ImportError as _error:
    # The client's dependencies (grpcio, protobuf) are the extra "client";
    # without them the rest of the package works, and connect (or Client)
    # names what is missing. Type checkers see the client as installed.
    if _typing.TYPE_CHECKING or not (_error.name or "").startswith(("grpc", "google")):
        raise  # a broken installation, not a missing extra
    _MISSING = (
        f"geodex.connect needs {'grpcio' if _error.name.startswith('grpc') else 'protobuf'} "
        f"(module {_error.name} is not installed): pip install 'geodex[client]', or "
        "install grpcio and protobuf"
    )

    def connect(*args: object, **kwargs: object) -> _typing.NoReturn:
        """Raises ImportError: the client's dependencies are not installed."""
        raise ImportError(_MISSING, name="grpc")

    def __getattr__(name: str) -> object:
        if name == "Client":
            raise ImportError(_MISSING, name="grpc")
        raise AttributeError(f"module 'geodex' has no attribute {name!r}")


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
    "VertexPoints",
    "vertices",
    "Located",
    "Path",
    # the exception classes, one per status code
    *(name for name in _errors.__all__ if name != "error_for_code"),
]


def __dir__() -> _typing.List[str]:
    # The public names, not the helpers and submodules the package imports.
    return sorted([*__all__, "__version__", "errors"])
