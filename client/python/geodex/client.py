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
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import grpc
import numpy as np

from ._arrays import Located, Path, SurfacePoints
from ._messages import _model_of, _model_ref, _rpc_error
from ._remote import At, RemoteQueries
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
    return Client(channel, token=token, timeout=timeout, batch_size=int(batch_size))


class Client(RemoteQueries):
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
        self._open_methods(channel)  # the queries' calls (geodex/_remote.py)

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
    # --- queries (geodex/_front.py checks the arguments and shapes answers;
    # geodex/_remote.py asks the server) --------------------------------------

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
        refine_below: float = 0.0,
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
        refine_below : float
            Also refine every pair that may be closer than this many L1000
            (the spacing of 1,000 samples on the surface; 8: the
            every-distance mode). 0: the model's threshold.

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
        return self._distance(
            At(model, version), a, b, bounds, tolerance, near_pairs, xyz, refine_below
        )

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
        refine_below: float = 0.0,
    ) -> Union[np.ndarray, Tuple[np.ndarray, np.ndarray]]:
        """All sources x targets distances: ``m[s, t] = d(sources[s],
        targets[t])``.

        Parameters are those of :meth:`distance`. Returns an (S, T) float64
        array, and with ``bounds`` the (S, T) bounds too. Sources are sent
        in groups of at most 2**24 cells (the server streams each group's
        rows back in blocks); beyond the server's max_matrix_cells a group
        fails ResourceExhausted.
        """
        at = At(model, version)
        return self._matrix(
            at, sources, targets, bounds, tolerance, near_pairs, xyz, refine_below
        )

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
        return self._path(At(model, version), a, b, exact_corridor, xyz, batch_size)

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
        return self._field(At(model, version), sources, radius, nearest, xyz)

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
        at = At(model, version)
        return self._expmap(at, centre, radius, direction, polar, near_pairs, tolerance, xyz)

    def locate(self, model: str, xyz: Any, *, version: int = 0, batch_size: int = 65536) -> Located:
        """The closest surface point of each (N, 3) position.

        Returns
        -------
        Located
            faces (N,) int32, weights (N, 3) float64 (usable as points) and
            distances (N,) float64 from each position to its point.
        """
        return self._locate(At(model, version), xyz, max(1, int(batch_size)))

    def mesh(self, model: str, *, version: int = 0) -> Tuple[np.ndarray, np.ndarray]:
        """The model's triangle mesh, in the mesh file's ids.

        Returns
        -------
        (numpy.ndarray, numpy.ndarray)
            (V, 3) float64 vertex positions and (F, 3) int32 vertex ids of
            each face (polygons fan-triangulated; unreferenced vertices
            kept).
        """
        return self._mesh(At(model, version))

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
