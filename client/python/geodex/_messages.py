"""The service's messages as Python values: models, TLS settings, the
triangulation, paths, and gRPC failures as the package's exceptions
(the values themselves are in _values.py). Internal to geodex.client."""

from __future__ import annotations

import json

import grpc
import numpy as np

from . import _wire
from ._arrays import Path
from ._values import Model
from .errors import DataLoss, Error, InvalidArgument, error_for_code
from .v1 import geodex_pb2 as pb

_STATES = {0: "UNSPECIFIED", 1: "LOADING", 2: "SERVING", 3: "FAILED"}


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
