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
from typing import Any, Dict, List, Optional, Tuple, Union

import grpc
import numpy as np

from ._arrays import SurfacePoints
from ._messages import _model_of, _model_ref, _rpc_error
from ._remote import RemoteQueries
from ._values import Model, Tls, Triangulation
from .errors import FailedPrecondition, InvalidArgument
from .v1 import geodex_pb2 as pb
from .v1 import geodex_pb2_grpc as pb_grpc

__all__ = ["connect", "Client", "Model", "Tls", "Triangulation"]


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
    return Client(
        channel,
        token=token,
        timeout=timeout,
        batch_size=int(batch_size),
        address=address,
        tls=not (tls is None or tls is False),
    )


class Client(RemoteQueries):
    """A connection to a geodex server; see :func:`connect`.

    Every method takes the model's name first and answers from its newest
    version, or from ``version`` when given. Points are ``(faces, weights)``
    arrays, (N,) int and (N, 3) float, in the mesh file's ids; with
    ``xyz=True`` they are (N, 3) positions instead, located first (the
    answer then comes from the version that located them).

    The seven queries are RemoteQueries' (geodex/_remote.py), each written
    beside the request it sends; this class opens the channel and answers
    for the models and their triangulations.

    ``address`` is the address :func:`connect` was given (None for a
    Client made on a channel of the caller's); the repr shows it.
    """

    def __init__(
        self,
        channel: grpc.Channel,
        token: Optional[str] = None,
        timeout: Optional[float] = 60.0,
        batch_size: int = 32768,
        *,
        address: Optional[str] = None,
        tls: bool = False,
    ) -> None:
        self.address = address
        self._tls = tls
        self._token = token is not None
        self._channel = channel
        self._metadata = (("authorization", f"Bearer {token}"),) if token else None
        self._timeout = timeout
        self._batch_size = batch_size
        self._stub = pb_grpc.GeodexStub(channel)
        self._open_methods(channel)  # the queries' calls (geodex/_remote.py)

    def __repr__(self) -> str:
        # The token is a secret: only whether one is sent.
        where = repr(self.address) if self.address is not None else "a given channel"
        return (
            f"geodex.Client({where}, {'TLS' if self._tls else 'plaintext'}"
            f"{', token' if self._token else ''}, timeout={self._timeout}, "
            f"batch_size={self._batch_size})"
        )

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
        """Every model of the server's repository, with its state.

        Each prints as one line (name, version, state, counts, size and
        the error target's verdict); its whole build report is
        ``model.report``, or ``info(name)``."""
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
        core/index/README.md, "The build report"); relative errors are fractions.
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
