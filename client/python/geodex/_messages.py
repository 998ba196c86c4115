"""The service's messages as Python values: models, TLS settings, the
triangulation, paths, and gRPC failures as the package's exceptions.
Internal to geodex.client."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any, Dict, NamedTuple, Optional, Tuple

import grpc
import numpy as np

from . import _wire
from ._arrays import Path, SurfacePoints
from .errors import DataLoss, Error, InvalidArgument, error_for_code
from .v1 import geodex_pb2 as pb

_STATES = {0: "UNSPECIFIED", 1: "LOADING", 2: "SERVING", 3: "FAILED"}


@dataclass(frozen=True)
class Tls:
    """TLS settings of :func:`connect`.

    Attributes
    ----------
    ca_file : str, optional
        PEM roots that verify the server's certificate; None: the system's.
    cert_file, key_file : str, optional
        The client's PEM certificate chain and private key (mutual TLS).
    server_name : str, optional
        The name checked against the server's certificate, when it is not
        the address's host (tests with self-signed certificates).
    """

    ca_file: Optional[str] = None
    cert_file: Optional[str] = None
    key_file: Optional[str] = None
    server_name: Optional[str] = None


@dataclass(frozen=True)
class Model:
    """A model as the server describes it (GetModel, ListModels).

    ``state`` is "LOADING", "SERVING" or "FAILED" (then ``reason`` says
    why); vertex and face counts are those of the mesh file;
    ``build_report`` holds the builder's validation and accuracy figures
    ("key" -> "value"); ``report`` the same report as a structured dict
    (``Client.info``), empty when the server sends none.
    """

    name: str
    version: int
    available_versions: Tuple[int, ...]
    state: str
    reason: str
    num_vertices: int
    num_faces: int
    num_samples: int
    num_triangles: int
    bbox_min: Tuple[float, ...]
    bbox_max: Tuple[float, ...]
    requested_samples: int
    seed: int
    samples_added_by_repair: int
    builder_version: str
    build_report: Dict[str, str] = field(default_factory=dict)
    mapped_bytes: int = 0
    mesh_hash: int = 0
    report: Dict[str, Any] = field(default_factory=dict)


class Triangulation(NamedTuple):
    """The geodesic triangulation of a model's index (GetTriangulation).

    Attributes
    ----------
    sample_vertices : numpy.ndarray
        (m,) int32 the mesh vertex of each sample (-1 for a sample on the
        midpoint of a long edge, which is no vertex of the mesh).
    sample_positions : numpy.ndarray
        (m, 3) float64.
    sample_points : SurfacePoints
        The samples as surface points.
    triangle_corners : numpy.ndarray
        (t, 3) int32 sample ids of each geodesic triangle's corners.
    triangle_neighbors : numpy.ndarray
        (t, 3) int32: across side (k, k+1 mod 3) of triangle t lies
        ``triangle_neighbors[t, k]`` (-1: none).
    vertex_triangles : numpy.ndarray
        (n,) int32 the geodesic triangle holding each mesh vertex (-1 for
        vertices no face uses).
    version : int
        The model version.
    """

    sample_vertices: np.ndarray
    sample_positions: np.ndarray
    sample_points: SurfacePoints
    triangle_corners: np.ndarray
    triangle_neighbors: np.ndarray
    vertex_triangles: np.ndarray
    version: int


def _rpc_error(e: grpc.RpcError) -> Error:
    """A gRPC failure as the package's exception of its code."""
    code = e.code() if hasattr(e, "code") else grpc.StatusCode.UNKNOWN
    details = e.details() if hasattr(e, "details") else str(e)
    return error_for_code(code.value[0], details or code.name)


def _model_ref(name: str, version: int) -> pb.ModelRef:
    if not isinstance(name, str):
        raise InvalidArgument(f"model must be a model name (str), not {type(name).__name__}")
    if int(version) < 0:
        raise InvalidArgument(f"version must be >= 0 (0: the newest), not {version}")
    return pb.ModelRef(name=name, version=int(version))


def _model_of(info: pb.ModelInfo) -> Model:
    return Model(
        name=info.name,
        version=info.version,
        available_versions=tuple(info.available_versions),
        state=_STATES.get(info.state, str(info.state)),
        reason=info.reason,
        num_vertices=info.num_vertices,
        num_faces=info.num_faces,
        num_samples=info.num_samples,
        num_triangles=info.num_triangles,
        bbox_min=tuple(info.bbox_min),
        bbox_max=tuple(info.bbox_max),
        requested_samples=info.requested_samples,
        seed=info.seed,
        samples_added_by_repair=info.samples_added_by_repair,
        builder_version=info.builder_version,
        build_report=dict(info.build_report),
        mapped_bytes=info.mapped_bytes,
        mesh_hash=info.mesh_hash,
        report=json.loads(info.report_json) if info.report_json else {},
    )


def _in_pairs(error: Error, begin: int, end: int) -> Error:
    """A batch's error with its pairs' place in the whole input: the
    server's "a[17]: ..." (17 within the batch) becomes "a[65553]: ..."."""
    message = error.message
    for name in ("a", "b"):
        prefix = f"{name}["
        if message.startswith(prefix) and "]" in message:
            index = message[len(prefix) : message.index("]")]
            if index.isdigit():
                rest = message[message.index("]") + 1 :]
                return type(error)(f"{name}[{begin + int(index)}]{rest}")
    return type(error)(f"pairs [{begin}, {end}): {message}")


def _path_of(polyline: memoryview) -> Path:
    fields = _wire.read_fields(polyline)
    points = _wire.read_fields(_wire.message(fields, 1))
    faces = _wire.packed_varints(points, 1).astype(np.int32)
    weights = np.array(_wire.packed_doubles(points, 2)).reshape(-1, 3)
    positions = np.array(_wire.packed_doubles(_wire.read_fields(_wire.message(fields, 2)), 1))
    length = _wire.double(fields, 3)
    positions = positions.reshape(-1, 3)
    if positions.shape[0] != faces.shape[0] or weights.shape[0] != faces.shape[0]:
        raise DataLoss("a path's points and positions differ in length")
    return Path(positions, faces, weights, length)
