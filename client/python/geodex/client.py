"""The geodex service from Python: numpy in, numpy out, over gRPC.

    import geodex
    with geodex.connect("localhost:8980") as client:
        d = client.distance("bunny", (faces_a, weights_a), (faces_b, weights_b))

Ids and units are those of the service (geodex/v1/geodex.proto): a surface
point is a face id of the mesh file the model was built from and the
barycentric weights of that face's three vertices; distances are in the
mesh's units, ``inf`` between different connected components.

Large inputs are split into batches: ``distance`` streams them through
StreamDistances (memory bounded by the batch size, not by the number of
pairs), ``path``, ``locate`` and ``matrix`` make several calls. A call that
fails raises the :class:`geodex.Error` subclass of its status code with the
server's message; arrays no index could accept are refused before anything
is sent (geodex/_arrays.py).

Thread safety: a Client may be used from several threads at once (gRPC
channels are thread-safe and a Client keeps no per-call state).
"""

from __future__ import annotations

import json
import math
from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import grpc
import numpy as np

from . import _wire
from ._arrays import (
    Located,
    Path,
    SurfacePoints,
    as_near_pairs,
    as_points,
    as_positions,
    check_tolerance,
)
from ._messages import (
    Model,
    Tls,
    Triangulation,
    _in_pairs,
    _model_of,
    _model_ref,
    _path_of,
    _rpc_error,
)
from .errors import DataLoss, FailedPrecondition, InvalidArgument, error_for_code
from .v1 import geodex_pb2 as pb
from .v1 import geodex_pb2_grpc as pb_grpc

__all__ = ["connect", "Client", "Model", "Tls", "Triangulation"]

_METHOD = "/geodex.v1.Geodex/"
_NEAR_PAIRS = {None: 0, "path": 1, "unfold": 2, "exact": 3}


def connect(
    address: str,
    token: Optional[str] = None,
    tls: Union[None, bool, Tls] = None,
    *,
    timeout: Optional[float] = 60.0,
    batch_size: int = 32768,
    max_attempts: int = 4,
) -> "Client":
    """Opens a channel to a geodex server.

    Parameters
    ----------
    address : str
        "host:port" (any gRPC target, e.g. "dns:///geodex.internal:8980").
    token : str, optional
        Sent as "authorization: Bearer <token>" with every call.
    tls : None, True or Tls
        None or False: plaintext. True: TLS verified against the system's
        roots. A :class:`Tls`: TLS with those files.
    timeout : float, optional
        Seconds each unary call may take (None: no deadline). Streams
        (distances in batches, matrices, fields, maps, meshes) have none.
    batch_size : int
        Pairs per StreamDistances batch: ``distance`` on more pairs than
        this streams, holding a few batches in flight at a time.
    max_attempts : int
        Tries of a call that fails UNAVAILABLE (a model still loading, no
        connection yet), with exponential backoff from 50 ms to 2 s; 1: none.

    Returns
    -------
    Client
        Connecting is lazy: a server that is down shows as
        :class:`geodex.Unavailable` on the first call.

    Raises
    ------
    InvalidArgument
        A bad option (batch_size < 1, unreadable TLS files).
    """
    if int(batch_size) < 1:
        raise InvalidArgument(f"batch_size must be >= 1, not {batch_size}")
    options: List[Tuple[str, Any]] = [
        ("grpc.max_receive_message_length", 1 << 30),
        ("grpc.primary_user_agent", "geodex-python/0.1"),
        ("grpc.enable_retries", 1),
    ]
    if max_attempts > 1:
        policy = {
            "maxAttempts": min(int(max_attempts), 5),  # gRPC's cap
            "initialBackoff": "0.05s",
            "maxBackoff": "2s",
            "backoffMultiplier": 2,
            "retryableStatusCodes": ["UNAVAILABLE"],
        }
        config = {
            "methodConfig": [{"name": [{"service": "geodex.v1.Geodex"}], "retryPolicy": policy}]
        }
        options.append(("grpc.service_config", json.dumps(config)))
    if tls is None or tls is False:
        channel = grpc.insecure_channel(address, options=options)
    else:
        settings = tls if isinstance(tls, Tls) else Tls()

        def read(path: Optional[str]) -> Optional[bytes]:
            if path is None:
                return None
            try:
                with open(path, "rb") as f:
                    return f.read()
            except OSError as e:
                raise InvalidArgument(f"tls: cannot read {path}: {e}") from None

        credentials = grpc.ssl_channel_credentials(
            root_certificates=read(settings.ca_file),
            private_key=read(settings.key_file),
            certificate_chain=read(settings.cert_file),
        )
        if settings.server_name:
            options.append(("grpc.ssl_target_name_override", settings.server_name))
        channel = grpc.secure_channel(address, credentials, options=options)
    return Client(channel, token=token, timeout=timeout, batch_size=int(batch_size))


class Client:
    """A connection to a geodex server; see :func:`connect`.

    Every method takes the model's name first and answers from its newest
    version, or from ``version`` when given. Points are ``(faces, weights)``
    arrays, (N,) int and (N, 3) float, in the mesh file's ids; with
    ``xyz=True`` they are (N, 3) positions instead, located first (the
    answer then comes from the version that located them).
    """

    def __init__(
        self,
        channel: grpc.Channel,
        token: Optional[str] = None,
        timeout: Optional[float] = 60.0,
        batch_size: int = 32768,
    ) -> None:
        self._channel = channel
        self._metadata = (("authorization", f"Bearer {token}"),) if token else None
        self._timeout = timeout
        self._batch_size = batch_size
        self._stub = pb_grpc.GeodexStub(channel)
        # Requests carrying arrays are serialised by _wire (bytes in); the
        # numeric answers are decoded by it too (bytes out).
        raw = lambda kind, name: getattr(channel, kind)(_METHOD + name)  # noqa: E731
        self._distance = raw("unary_unary", "Distance")
        self._stream_distances = raw("stream_stream", "StreamDistances")
        self._matrix = raw("unary_stream", "Matrix")
        self._path = raw("unary_unary", "Path")
        self._field = raw("unary_stream", "DistanceField")
        self._expmap = raw("unary_stream", "ExpMap")
        self._locate = raw("unary_unary", "Locate")
        self._mesh = raw("unary_stream", "GetMesh")

    # --- lifetime ----------------------------------------------------------

    def close(self) -> None:
        """Closes the channel; calls in flight are cancelled."""
        self._channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    # --- models ------------------------------------------------------------

    def models(self) -> List[Model]:
        """Every model of the server's repository, with its state."""
        try:
            response = self._stub.ListModels(
                pb.ListModelsRequest(), timeout=self._timeout, metadata=self._metadata
            )
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        return [_model_of(m) for m in response.models]

    def model(self, name: str, version: int = 0) -> Model:
        """One model (its newest version, or ``version``), with its build
        report. Raises NotFound for an unknown model or version."""
        try:
            info = self._stub.GetModel(
                pb.GetModelRequest(model=_model_ref(name, version)),
                timeout=self._timeout,
                metadata=self._metadata,
            )
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        return _model_of(info)

    def info(self, name: str, version: int = 0) -> Dict[str, Any]:
        """The build report of a model (its newest version, or ``version``)
        as a dict: mesh, repairs, samples, size by section, the error target
        (met, or why not) and the relative error by distance (keys in
        core/README.md, "The build report"); relative errors are fractions.
        Equal to ``geodex.Index(path).info()`` of the file served.

        Raises NotFound for an unknown model or version, FailedPrecondition
        when the model is not serving or the server sends no report (a
        server older than ModelInfo.report_json)."""
        model = self.model(name, version)
        if not model.report:
            raise FailedPrecondition(
                f"model {name} version {model.version} has no build report "
                f"(state {model.state}{': ' + model.reason if model.reason else ''})"
            )
        return model.report

    # --- distances ---------------------------------------------------------

    def distance(
        self,
        model: str,
        a: Any,
        b: Any,
        bounds: bool = False,
        tolerance: float = 0.0,
        *,
        near_pairs: Optional[str] = None,
        xyz: bool = False,
        version: int = 0,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """Geodesic distances of pairs: ``d[i] = d(a[i], b[i])``.

        Parameters
        ----------
        model : str
            The model's name.
        a, b : points
            N points each: ``(faces (N,), weights (N, 3))``, or (N, 3)
            positions with ``xyz=True``.
        bounds : bool
            Also return each distance's absolute error bound (needs a model
            built with its accuracy calibration: FailedPrecondition
            otherwise).
        tolerance : float
            Relative error tolerance (e.g. 0.005): pairs whose bound exceeds
            tolerance x distance are refined further. 0: the model's.
        near_pairs : {None, "path", "unfold", "exact"}
            How near pairs are answered (geodex.v1.NearPairs); None: the
            model's configuration.
        xyz : bool
            ``a`` and ``b`` are positions, located first.
        version : int
            The model version (0: the newest).

        Returns
        -------
        numpy.ndarray or (numpy.ndarray, numpy.ndarray)
            (N,) float64 distances (``inf`` between components); with
            ``bounds``, also (N,) float64 bounds.

        Raises
        ------
        InvalidArgument
            Bad arrays or options (before anything is sent), or points the
            server refuses (weights that do not sum to 1).
        OutOfRange
            A face id past the model's face count.
        NotFound
            An unknown model or version.
        """
        check_tolerance(tolerance)
        as_near_pairs(near_pairs)
        pa, pb_, version = self._points_pair(model, a, b, xyz, version)
        n = pa.faces.shape[0]
        if pb_.faces.shape[0] != n:
            raise InvalidArgument(
                f"a has {n} points but b has {pb_.faces.shape[0]}; they must pair up"
            )
        ref = _model_ref(model, version)
        if n <= self._batch_size:
            head = pb.DistanceRequest(
                model=ref,
                near_pairs=_NEAR_PAIRS[near_pairs],
                tolerance=float(tolerance),
                error_bounds=bool(bounds),
            ).SerializeToString()
            request = (
                head
                + _wire.length_delimited(2, _wire.surface_points(pa.faces, pa.weights))
                + _wire.length_delimited(3, _wire.surface_points(pb_.faces, pb_.weights))
            )
            try:
                data = self._distance(request, timeout=self._timeout, metadata=self._metadata)
            except grpc.RpcError as e:
                raise _rpc_error(e) from None
            fields = _wire.read_fields(data)
            d = self._sized(_wire.packed_doubles(fields, 1), n, "distances").copy()
            if not bounds:
                return d
            return d, self._sized(_wire.packed_doubles(fields, 3), n, "bounds").copy()
        return self._stream(ref, pa, pb_, bool(bounds), float(tolerance), _NEAR_PAIRS[near_pairs])

    def _stream(
        self,
        ref: pb.ModelRef,
        a: SurfacePoints,
        b: SurfacePoints,
        bounds: bool,
        tolerance: float,
        near_pairs: int,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """Distances through one StreamDistances call, batch_size pairs a
        batch. gRPC's sending thread encodes a batch when the previous one
        has gone out, and the server reads a few batches ahead of its
        answers, so only a few batches are ever in memory at once."""
        n = a.faces.shape[0]
        size = self._batch_size
        num_batches = (n + size - 1) // size
        out = np.empty(n, dtype=np.float64)
        out_bounds = np.empty(n, dtype=np.float64) if bounds else None

        def batches() -> Iterator[bytes]:
            for k in range(num_batches):
                lo, hi = k * size, min(n, (k + 1) * size)
                head = pb.DistanceBatch(
                    batch_id=k, near_pairs=near_pairs, tolerance=tolerance, error_bounds=bounds
                )
                if k == 0:  # later batches reuse the stream's model
                    head.model.CopyFrom(ref)
                yield (
                    head.SerializeToString()
                    + _wire.length_delimited(
                        3, _wire.surface_points(a.faces[lo:hi], a.weights[lo:hi])
                    )
                    + _wire.length_delimited(
                        4, _wire.surface_points(b.faces[lo:hi], b.weights[lo:hi])
                    )
                )

        call = self._stream_distances(batches(), metadata=self._metadata)
        k = 0
        try:
            for data in call:
                if k >= num_batches:
                    raise DataLoss(f"the server answered {k + 1} batches for {num_batches}")
                lo, hi = k * size, min(n, (k + 1) * size)
                fields = _wire.read_fields(data)
                if _wire.scalar(fields, 1) != k:
                    raise DataLoss(
                        f"the server answered batch {_wire.scalar(fields, 1)} "
                        f"when batch {k} was due"
                    )
                code = _wire.scalar(fields, 3)
                if code != 0:
                    raise _in_pairs(error_for_code(code, _wire.string(fields, 4)), lo, hi)
                out[lo:hi] = self._sized(_wire.packed_doubles(fields, 2), hi - lo, "distances")
                if out_bounds is not None:
                    out_bounds[lo:hi] = self._sized(
                        _wire.packed_doubles(fields, 6), hi - lo, "bounds"
                    )
                k += 1
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        finally:
            call.cancel()  # a no-op once the call has ended; stops the sender otherwise
        if k != num_batches:
            raise DataLoss(f"the distance stream ended after {k} of {num_batches} batches")
        return out if out_bounds is None else (out, out_bounds)

    def matrix(
        self,
        model: str,
        sources: Any,
        targets: Any,
        bounds: bool = False,
        tolerance: float = 0.0,
        *,
        near_pairs: Optional[str] = None,
        xyz: bool = False,
        version: int = 0,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """All sources x targets distances: ``m[s, t] = d(sources[s],
        targets[t])``.

        Parameters are those of :meth:`distance`. Returns an (S, T) float64
        array, and with ``bounds`` the (S, T) bounds too. Sources are sent
        in groups of at most 2**24 cells (the server streams each group's
        rows back in blocks); beyond the server's max_matrix_cells a group
        fails ResourceExhausted.
        """
        check_tolerance(tolerance)
        as_near_pairs(near_pairs)
        src, tgt, version = self._points_pair(
            model, sources, targets, xyz, version, ("sources", "targets")
        )
        s, t = src.faces.shape[0], tgt.faces.shape[0]
        out = np.empty((s, t), dtype=np.float64)
        out_bounds = np.empty((s, t), dtype=np.float64) if bounds else None
        targets_bytes = _wire.length_delimited(3, _wire.surface_points(tgt.faces, tgt.weights))
        rows_per_call = max(1, (1 << 24) // max(t, 1))
        start = 0
        while True:
            stop = min(s, start + rows_per_call)
            head = pb.MatrixRequest(
                model=_model_ref(model, version),
                near_pairs=_NEAR_PAIRS[near_pairs],
                tolerance=float(tolerance),
                error_bounds=bool(bounds),
            ).SerializeToString()
            request = (
                head
                + _wire.length_delimited(
                    2, _wire.surface_points(src.faces[start:stop], src.weights[start:stop])
                )
                + targets_bytes
            )
            rows = 0
            try:
                for data in self._matrix(request, metadata=self._metadata):
                    fields = _wire.read_fields(data)
                    offset, count = _wire.scalar(fields, 1), _wire.scalar(fields, 2)
                    if _wire.scalar(fields, 3) != t or offset < 0 or offset + count > stop - start:
                        raise DataLoss(
                            f"matrix block of rows [{offset}, {offset + count}) x "
                            f"{_wire.scalar(fields, 3)} for {stop - start} x {t}"
                        )
                    block = self._sized(_wire.packed_doubles(fields, 4), count * t, "matrix values")
                    out[start + offset : start + offset + count] = block.reshape(count, t)
                    if out_bounds is not None:
                        block = self._sized(
                            _wire.packed_doubles(fields, 6), count * t, "matrix bounds"
                        )
                        rows_at = slice(start + offset, start + offset + count)
                        out_bounds[rows_at] = block.reshape(count, t)
                    rows += count
                    if version == 0:  # the rest from the version that answered
                        version = _wire.scalar(fields, 5)
            except grpc.RpcError as e:
                raise _rpc_error(e) from None
            if rows != stop - start:
                raise DataLoss(f"the matrix stream sent {rows} of {stop - start} rows")
            start = stop
            if start >= s:
                break
        return out if out_bounds is None else (out, out_bounds)

    # --- paths, fields, maps -----------------------------------------------

    def path(
        self,
        model: str,
        a: Any,
        b: Any,
        *,
        exact_corridor: int = 0,
        xyz: bool = False,
        version: int = 0,
        batch_size: int = 256,
    ) -> List[Path]:
        """Geodesic paths from a[i] to b[i].

        Parameters
        ----------
        exact_corridor : int
            When > 0 (at most 64), each path is also solved exactly within
            this many edge steps of the traced one, and the shorter kept.
            0: the model's default.
        batch_size : int
            Pairs per Path call (the server allows 10000 by default).

        Returns
        -------
        list of Path
            One per pair: (K, 3) positions with the (K,) faces and (K, 3)
            weights of the points, and the length; K = 0 and length ``inf``
            between components.
        """
        if not 0 <= int(exact_corridor) <= 64:
            raise InvalidArgument(f"exact_corridor must be in [0, 64], not {exact_corridor}")
        pa, pb_, version = self._points_pair(model, a, b, xyz, version)
        n = pa.faces.shape[0]
        if pb_.faces.shape[0] != n:
            raise InvalidArgument(
                f"a has {n} points but b has {pb_.faces.shape[0]}; they must pair up"
            )
        paths: List[Path] = []
        for lo in range(0, max(n, 1), max(1, int(batch_size))):
            hi = min(n, lo + max(1, int(batch_size)))
            request = (
                pb.PathRequest(
                    model=_model_ref(model, version), exact_corridor=int(exact_corridor)
                ).SerializeToString()
                + _wire.length_delimited(
                    2, _wire.surface_points(pa.faces[lo:hi], pa.weights[lo:hi])
                )
                + _wire.length_delimited(
                    3, _wire.surface_points(pb_.faces[lo:hi], pb_.weights[lo:hi])
                )
            )
            try:
                data = self._path(request, timeout=self._timeout, metadata=self._metadata)
            except grpc.RpcError as e:
                raise _in_pairs(_rpc_error(e), lo, hi) from None
            fields = _wire.read_fields(data)
            polylines = [v for w, v in fields.get(1, ()) if w == 2]
            if len(polylines) != hi - lo:
                raise DataLoss(f"the server sent {len(polylines)} paths for {hi - lo} pairs")
            paths.extend(_path_of(p) for p in polylines)
            if version == 0:
                version = _wire.scalar(fields, 2)
        return paths

    def field(
        self,
        model: str,
        sources: Any,
        *,
        radius: float = 0.0,
        nearest: bool = False,
        xyz: bool = False,
        version: int = 0,
    ) -> Union[np.ndarray, Tuple[np.ndarray, ...]]:
        """The distance from the nearest of ``sources`` to every vertex, or
        to the vertices within ``radius``.

        Parameters
        ----------
        radius : float
            0 (the default): every vertex, O(1) per vertex per source.
            > 0 and finite: only the vertices within this geodesic distance
            of the sources, with exact distances (one exact propagation on
            the server, whose cost follows the vertices it reaches: for many
            targets round a few sources).

        Returns
        -------
        numpy.ndarray or tuple of numpy.ndarray
            Without a radius: (n,) float64 per vertex of the mesh file
            (``inf`` for vertices no face uses or on other components); with
            ``nearest``, also (n,) int32 the index of each vertex's nearest
            source (-1 if none). With a radius: (k,) int32 the vertices
            within it, ascending, and (k,) float64 their distances; with
            ``nearest``, also (k,) int32 their nearest sources.

        Raises
        ------
        InvalidArgument
            For a radius that is negative, NaN or infinite.
        ResourceExhausted
            When the field within the radius reaches more vertices than the
            server allows (max_field_vertices).
        """
        radius = float(radius)
        if radius != 0 and not (math.isfinite(radius) and radius > 0):
            raise InvalidArgument(f"the radius must be finite and > 0, got {radius:g}")
        (src,), version = self._points_list(model, [sources], ("sources",), xyz, version)
        request = (
            pb.DistanceFieldRequest(
                model=_model_ref(model, version), with_nearest_source=bool(nearest), radius=radius
            ).SerializeToString()
            + _wire.length_delimited(2, _wire.surface_points(src.faces, src.weights))
        )
        if radius > 0:
            return self._field_within(request, nearest)
        out: Optional[np.ndarray] = None
        near: Optional[np.ndarray] = None
        filled = 0
        try:
            for data in self._field(request, metadata=self._metadata):
                fields = _wire.read_fields(data)
                total = _wire.scalar(fields, 4)
                if out is None:
                    out = np.empty(total, dtype=np.float64)
                    near = np.empty(total, dtype=np.int32) if nearest else None
                offset = _wire.scalar(fields, 1)
                values = _wire.packed_doubles(fields, 2)
                if total != out.shape[0] or offset != filled or offset + values.shape[0] > total:
                    raise DataLoss(
                        f"field chunk at {offset} ({values.shape[0]} of {total}) after {filled}"
                    )
                out[offset : offset + values.shape[0]] = values
                if near is not None:
                    near[offset : offset + values.shape[0]] = self._sized(
                        _wire.packed_varints(fields, 3), values.shape[0], "nearest sources"
                    )
                filled += values.shape[0]
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        if out is None:
            raise DataLoss("the field stream sent no chunk")
        if filled != out.shape[0]:
            raise DataLoss(f"the field stream sent {filled} of {out.shape[0]} vertices")
        return out if not nearest else (out, near)

    def _field_within(self, request: bytes, nearest: bool) -> Tuple[np.ndarray, ...]:
        """The sparse chunks of a field within a radius, assembled."""
        vertices: List[np.ndarray] = []
        distances: List[np.ndarray] = []
        sources: List[np.ndarray] = []
        total: Optional[int] = None
        filled = 0
        try:
            for data in self._field(request, metadata=self._metadata):
                fields = _wire.read_fields(data)
                n, offset = _wire.scalar(fields, 4), _wire.scalar(fields, 1)
                d = _wire.packed_doubles(fields, 2)
                v = _wire.packed_varints(fields, 6)
                if v.shape[0] != d.shape[0]:
                    raise DataLoss(
                        f"field chunk of {d.shape[0]} distances for {v.shape[0]} vertices"
                        + (" (a whole-mesh field: the server predates radius fields)"
                           if v.shape[0] == 0 else "")
                    )
                total = n if total is None else total
                if n != total or offset != filled or offset + d.shape[0] > total:
                    raise DataLoss(f"field chunk at {offset} ({d.shape[0]} of {n}) after {filled}")
                vertices.append(v)
                distances.append(np.array(d))
                if nearest:
                    sources.append(self._sized(_wire.packed_varints(fields, 3), d.shape[0],
                                               "nearest sources"))
                filled += d.shape[0]
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        if total is None:
            raise DataLoss("the field stream sent no chunk")
        if filled != total:
            raise DataLoss(f"the field stream sent {filled} of {total} vertices within the radius")
        ids = np.concatenate(vertices).astype(np.int32) if vertices else np.zeros(0, np.int32)
        if ids.shape[0] > 1 and not (np.diff(ids) > 0).all():
            raise DataLoss("the server sent the field's vertices out of order")
        out = np.concatenate(distances) if distances else np.zeros(0)
        if not nearest:
            return ids, out
        near = np.concatenate(sources).astype(np.int32) if sources else np.zeros(0, np.int32)
        return ids, out, near

    def expmap(
        self,
        model: str,
        centre: Any,
        radius: float,
        *,
        direction: Optional[Sequence[float]] = None,
        polar: bool = False,
        near_pairs: Optional[str] = None,
        tolerance: float = 0.0,
        xyz: bool = False,
        version: int = 0,
    ) -> Tuple[np.ndarray, np.ndarray]:
        """The exponential map (geodesic polar coordinates) round one point.

        Parameters
        ----------
        centre : point
            One point: ``(face, (w0, w1, w2))``, or a position with xyz=True.
        radius : float
            Vertices farther than this from the centre are left out.
        direction : (3,) float, optional
            theta = 0 along it, projected into the centre's face; default
            along that face's first edge.
        polar : bool
            Return (r, theta) instead of (u, v).

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            (k,) int32 vertex ids, ascending, and (k, 2) float64 coordinates:
            (u, v) = r (cos theta, sin theta), or (r, theta) with ``polar``.
        """
        check_tolerance(tolerance)
        as_near_pairs(near_pairs)
        (c,), version = self._points_list(model, [centre], ("centre",), xyz, version)
        if c.faces.shape[0] != 1:
            raise InvalidArgument(f"centre must be one point, not {c.faces.shape[0]}")
        request = pb.ExpMapRequest(
            model=_model_ref(model, version),
            radius=float(radius),
            near_pairs=_NEAR_PAIRS[near_pairs],
            tolerance=float(tolerance),
        )
        if direction is not None:
            xyz = as_positions(direction, "direction").ravel()
            request.reference_direction.xyz.extend(xyz.tolist())
        data = request.SerializeToString() + _wire.length_delimited(
            2, _wire.surface_points(c.faces, c.weights)
        )
        vertices, first, second = [], [], []
        try:
            for chunk in self._expmap(data, metadata=self._metadata):
                fields = _wire.read_fields(chunk)
                vertices.append(_wire.packed_varints(fields, 1))
                first.append(np.array(_wire.packed_doubles(fields, 2 if polar else 4)))
                second.append(np.array(_wire.packed_doubles(fields, 3 if polar else 5)))
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        ids = np.concatenate(vertices).astype(np.int32) if vertices else np.zeros(0, np.int32)
        coords = np.empty((ids.shape[0], 2))
        if vertices:
            coords[:, 0] = np.concatenate(first)
            coords[:, 1] = np.concatenate(second)
        if coords.shape[0] != ids.shape[0]:
            raise DataLoss("the exponential map's arrays differ in length")
        return ids, coords

    # --- location and the mesh ---------------------------------------------

    def locate(self, model: str, xyz: Any, *, version: int = 0, batch_size: int = 65536) -> Located:
        """The closest surface point of each (N, 3) position.

        Returns
        -------
        Located
            faces (N,) int32, weights (N, 3) float64 (usable as points) and
            distances (N,) float64 from each position to its point.
        """
        located, _ = self._locate_pinned(model, as_positions(xyz, "xyz"), int(version), batch_size)
        return located

    def _locate_pinned(
        self, model: str, xyz: np.ndarray, version: int, batch_size: int = 65536
    ) -> Tuple[Located, int]:
        n = xyz.shape[0]
        faces = np.empty(n, dtype=np.int32)
        weights = np.empty((n, 3), dtype=np.float64)
        distances = np.empty(n, dtype=np.float64)
        size = max(1, int(batch_size))
        for lo in range(0, max(n, 1), size):
            hi = min(n, lo + size)
            request = pb.LocateRequest(model=_model_ref(model, version)).SerializeToString()
            request += _wire.length_delimited(2, _wire.positions(xyz[lo:hi]))
            try:
                data = self._locate(request, timeout=self._timeout, metadata=self._metadata)
            except grpc.RpcError as e:
                raise _rpc_error(e) from None
            fields = _wire.read_fields(data)
            points = _wire.read_fields(_wire.message(fields, 1))
            faces[lo:hi] = self._sized(_wire.packed_varints(points, 1), hi - lo, "located faces")
            weights[lo:hi] = self._sized(
                _wire.packed_doubles(points, 2), 3 * (hi - lo), "located weights"
            ).reshape(-1, 3)
            distances[lo:hi] = self._sized(_wire.packed_doubles(fields, 2), hi - lo, "distances")
            if version == 0:
                version = _wire.scalar(fields, 3)
        return Located(faces, weights, distances), version

    def mesh(self, model: str, *, version: int = 0) -> Tuple[np.ndarray, np.ndarray]:
        """The model's triangle mesh, in the mesh file's ids.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            (V, 3) float64 vertex positions and (F, 3) int32 vertex ids of
            each face (polygons fan-triangulated; unreferenced vertices
            kept).
        """
        request = pb.GetMeshRequest(model=_model_ref(model, version)).SerializeToString()
        vertices: Optional[np.ndarray] = None
        faces: Optional[np.ndarray] = None
        nv = nf = 0
        try:
            for data in self._mesh(request, metadata=self._metadata):
                fields = _wire.read_fields(data)
                if vertices is None:
                    vertices = np.empty((_wire.scalar(fields, 1), 3))
                    faces = np.empty((_wire.scalar(fields, 2), 3), dtype=np.int32)
                positions = _wire.packed_doubles(fields, 5).reshape(-1, 3)
                ids = _wire.packed_varints(fields, 7).reshape(-1, 3)
                vo, fo = _wire.scalar(fields, 4), _wire.scalar(fields, 6)
                if vo != nv or fo != nf or vo + positions.shape[0] > vertices.shape[0] or (
                    fo + ids.shape[0] > faces.shape[0]
                ):
                    raise DataLoss(f"mesh chunk at vertex {vo}, face {fo} after {nv}, {nf}")
                vertices[vo : vo + positions.shape[0]] = positions
                faces[fo : fo + ids.shape[0]] = ids
                nv, nf = vo + positions.shape[0], fo + ids.shape[0]
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        if vertices is None or faces is None or nv != vertices.shape[0] or nf != faces.shape[0]:
            raise DataLoss("the mesh stream ended early")
        return vertices, faces

    def triangulation(self, model: str, *, version: int = 0) -> Triangulation:
        """The geodesic triangulation of the model's index (its samples, its
        geodesic triangles and the triangle of every vertex)."""
        try:
            r = self._stub.GetTriangulation(
                pb.GetTriangulationRequest(model=_model_ref(model, version)),
                timeout=self._timeout,
                metadata=self._metadata,
            )
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        m = len(r.sample_vertices)
        return Triangulation(
            sample_vertices=np.array(r.sample_vertices, dtype=np.int32),
            sample_positions=np.array(r.sample_positions.xyz, dtype=np.float64).reshape(m, 3),
            sample_points=SurfacePoints(
                np.array(r.sample_points.faces, dtype=np.int32),
                np.array(r.sample_points.weights, dtype=np.float64).reshape(-1, 3),
            ),
            triangle_corners=np.array(r.triangle_corners, dtype=np.int32).reshape(-1, 3),
            triangle_neighbors=np.array(r.triangle_neighbors, dtype=np.int32).reshape(-1, 3),
            vertex_triangles=np.array(r.vertex_triangles, dtype=np.int32),
            version=r.version,
        )

    # --- helpers -----------------------------------------------------------

    def _points_list(
        self, model: str, points: Sequence[Any], names: Sequence[str], xyz: bool, version: int
    ) -> Tuple[List[SurfacePoints], int]:
        """Validated points; with xyz, the positions located first (in one
        version, which the caller's next call then pins)."""
        version = int(version)
        if not xyz:
            return [as_points(p, name) for p, name in zip(points, names)], version
        positions = [as_positions(p, name) for p, name in zip(points, names)]
        out = []
        for p in positions:
            located, version = self._locate_pinned(model, p, version)
            out.append(SurfacePoints(located.faces, located.weights))
        return out, version

    def _points_pair(
        self,
        model: str,
        a: Any,
        b: Any,
        xyz: bool,
        version: int,
        names: Tuple[str, str] = ("a", "b"),
    ) -> Tuple[SurfacePoints, SurfacePoints, int]:
        (pa, pb_), version = self._points_list(model, [a, b], names, xyz, version)
        return pa, pb_, version

    @staticmethod
    def _sized(values: np.ndarray, n: int, what: str) -> np.ndarray:
        if values.shape[0] != n:
            raise DataLoss(f"the server sent {values.shape[0]} {what} for {n}")
        return values
