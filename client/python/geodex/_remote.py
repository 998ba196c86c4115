"""The queries of :class:`geodex.Client`: each public method beside its
back half, the request over gRPC and the answer decoded (the front half,
shared with the in-process index, is geodex/_front.py).

Requests carrying arrays are serialised by _wire (bytes in), and the
numeric answers decoded by it too (bytes out): protobuf's Python objects
would copy every number through a Python float.
"""

from __future__ import annotations

from typing import Any, Dict, Iterator, List, Optional, Sequence, Tuple, Union, cast

import grpc
import numpy as np

from . import _wire
from ._arrays import Located, Path, Points, VertexPoints
from ._arrays import count as count_points
from ._front import QueryFront
from ._messages import _in_pairs, _model_ref, _path_of, _rpc_error
from .errors import DataLoss, error_for_code
from .v1 import geodex_pb2 as pb

__all__ = ["At", "RemoteQueries", "raw_calls"]

# gRPC's multicallable for each kind of call: (client streams, server streams).
_KINDS = {
    (False, False): "unary_unary",
    (False, True): "unary_stream",
    (True, False): "stream_unary",
    (True, True): "stream_stream",
}


def raw_calls(channel: grpc.Channel) -> Dict[str, Any]:
    """Every call of geodex.v1.Geodex, as the proto's descriptor lists them,
    by name: a raw callable on the channel taking and returning serialised
    bytes (the numeric arrays are encoded and decoded by _wire)."""
    service = pb.DESCRIPTOR.services_by_name["Geodex"]
    return {
        m.name: getattr(channel, _KINDS[m.client_streaming, m.server_streaming])(
            f"/{service.full_name}/{m.name}"
        )
        for m in service.methods
    }


def _points(points: Points) -> bytes:
    """The geodex.v1.SurfacePoints message of `points`: faces and weights,
    or vertex ids, which the server reads."""
    if isinstance(points, VertexPoints):
        return _wire.vertex_points(points.vertices)
    return _wire.surface_points(points.faces, points.weights)


class At:
    """Where a client's query is answered: the model, and its version (0:
    the newest until an answer names the version, which then answers the
    rest of the query, so that positions located first and the query on
    their points meet the same index)."""

    __slots__ = ("model", "version")

    def __init__(self, model: str, version: int) -> None:
        self.model = model
        self.version = int(version)

    def ref(self) -> pb.ModelRef:
        return _model_ref(self.model, self.version)

    def pin(self, version: int) -> None:
        if self.version == 0:
            self.version = version


class RemoteQueries(QueryFront[At]):
    """The seven queries over a channel: the public methods of
    :class:`geodex.Client`, and their back halves (``_run_*`` of
    QueryFront)."""

    _timeout: Optional[float]
    _metadata: Optional[Tuple[Tuple[str, str], ...]]
    _batch_size: int

    def _open_methods(self, channel: grpc.Channel) -> None:
        calls = raw_calls(channel)
        self._distance_call = calls["Distance"]
        self._stream_distances = calls["StreamDistances"]
        self._matrix_call = calls["Matrix"]
        self._path_call = calls["Path"]
        self._field_call = calls["DistanceField"]
        self._expmap_call = calls["ExpMap"]
        self._locate_call = calls["Locate"]
        self._mesh_call = calls["GetMesh"]

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

    def _run_distance(
        self, at: At, a: Points, b: Points, near_pairs: int, tolerance: float,
        bounds: bool, refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        n = count_points(a)
        ref = at.ref()
        if n > self._batch_size:
            return self._stream(ref, a, b, bounds, tolerance, near_pairs, refine_below)
        head = pb.DistanceRequest(
            model=ref, near_pairs=near_pairs, tolerance=tolerance, error_bounds=bounds,
            refine_below=refine_below,
        ).SerializeToString()
        request = (
            head
            + _wire.length_delimited(2, _points(a))
            + _wire.length_delimited(3, _points(b))
        )
        try:
            data = self._distance_call(request, timeout=self._timeout, metadata=self._metadata)
        except grpc.RpcError as e:
            raise _rpc_error(e) from None
        fields = _wire.read_fields(data)
        d = self._sized(_wire.packed_doubles(fields, 1), n, "distances").copy()
        if not bounds:
            return d, None
        return d, self._sized(_wire.packed_doubles(fields, 3), n, "bounds").copy()

    def _stream(
        self,
        ref: pb.ModelRef,
        a: Points,
        b: Points,
        bounds: bool,
        tolerance: float,
        near_pairs: int,
        refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        """Distances through one StreamDistances call, batch_size pairs a
        batch. gRPC's sending thread encodes a batch when the previous one
        has gone out, and the server reads a few batches ahead of its
        answers, so only a few batches are ever in memory at once."""
        n = count_points(a)
        size = self._batch_size
        num_batches = (n + size - 1) // size
        out = np.empty(n, dtype=np.float64)
        out_bounds = np.empty(n, dtype=np.float64) if bounds else None

        def batches() -> Iterator[bytes]:
            for k in range(num_batches):
                lo, hi = k * size, min(n, (k + 1) * size)
                head = pb.DistanceBatch(
                    batch_id=k, near_pairs=near_pairs, tolerance=tolerance, error_bounds=bounds,
                    refine_below=refine_below,
                )
                if k == 0:  # later batches reuse the stream's model
                    head.model.CopyFrom(ref)
                yield (
                    head.SerializeToString()
                    + _wire.length_delimited(
                        3, _points(a.take(slice(lo, hi)))
                    )
                    + _wire.length_delimited(
                        4, _points(b.take(slice(lo, hi)))
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
        return out, out_bounds

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

    def _run_matrix(
        self, at: At, sources: Points, targets: Points, near_pairs: int,
        tolerance: float, bounds: bool, refine_below: float,
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        src, tgt = sources, targets
        s, t = count_points(src), count_points(tgt)
        out = np.empty((s, t), dtype=np.float64)
        out_bounds = np.empty((s, t), dtype=np.float64) if bounds else None
        targets_bytes = _wire.length_delimited(3, _points(tgt))
        rows_per_call = max(1, (1 << 24) // max(t, 1))
        start = 0
        while True:
            stop = min(s, start + rows_per_call)
            head = pb.MatrixRequest(
                model=at.ref(), near_pairs=near_pairs, tolerance=tolerance, error_bounds=bounds,
                refine_below=refine_below,
            ).SerializeToString()
            request = (
                head
                + _wire.length_delimited(
                    2, _points(src.take(slice(start, stop)))
                )
                + targets_bytes
            )
            rows = 0
            try:
                for data in self._matrix_call(request, metadata=self._metadata):
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
                    at.pin(_wire.scalar(fields, 5))  # the rest from the version that answered
            except grpc.RpcError as e:
                raise _rpc_error(e) from None
            if rows != stop - start:
                raise DataLoss(f"the matrix stream sent {rows} of {stop - start} rows")
            start = stop
            if start >= s:
                break
        return out, out_bounds

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

    def _run_path(
        self, at: At, a: Points, b: Points, exact_corridor: int, batch_size: int
    ) -> List[Path]:
        pa, pb_, n = a, b, count_points(a)
        paths: List[Path] = []
        for lo in range(0, max(n, 1), batch_size):
            hi = min(n, lo + batch_size)
            request = (
                pb.PathRequest(model=at.ref(), exact_corridor=exact_corridor).SerializeToString()
                + _wire.length_delimited(
                    2, _points(pa.take(slice(lo, hi)))
                )
                + _wire.length_delimited(
                    3, _points(pb_.take(slice(lo, hi)))
                )
            )
            try:
                data = self._path_call(request, timeout=self._timeout, metadata=self._metadata)
            except grpc.RpcError as e:
                raise _in_pairs(_rpc_error(e), lo, hi) from None
            fields = _wire.read_fields(data)
            # Wire type 2: a length-delimited field, read as a memoryview.
            polylines = [cast(memoryview, v) for w, v in fields.get(1, ()) if w == 2]
            if len(polylines) != hi - lo:
                raise DataLoss(f"the server sent {len(polylines)} paths for {hi - lo} pairs")
            paths.extend(_path_of(p) for p in polylines)
            at.pin(_wire.scalar(fields, 2))
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
        return self._field(At(model, version), sources, radius, nearest, xyz)

    def _field_request(self, at: At, sources: Points, radius: float, nearest: bool) -> bytes:
        return (
            pb.DistanceFieldRequest(
                model=at.ref(), with_nearest_source=nearest, radius=radius
            ).SerializeToString()
            + _wire.length_delimited(2, _points(sources))
        )

    def _run_field(
        self, at: At, sources: Points, nearest: bool
    ) -> Tuple[np.ndarray, Optional[np.ndarray]]:
        request = self._field_request(at, sources, 0.0, nearest)
        out: Optional[np.ndarray] = None
        near: Optional[np.ndarray] = None
        filled = 0
        try:
            for data in self._field_call(request, metadata=self._metadata):
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
        return out, near

    def _run_field_within(
        self, at: At, sources: Points, radius: float, nearest: bool
    ) -> Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]:
        """The sparse chunks of a field within a radius, assembled."""
        request = self._field_request(at, sources, radius, nearest)
        vertices: List[np.ndarray] = []
        distances: List[np.ndarray] = []
        chunk_sources: List[np.ndarray] = []
        total: Optional[int] = None
        filled = 0
        try:
            for data in self._field_call(request, metadata=self._metadata):
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
                    chunk_sources.append(
                        self._sized(_wire.packed_varints(fields, 3), d.shape[0], "nearest sources")
                    )
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
            return ids, out, None
        near = (
            np.concatenate(chunk_sources).astype(np.int32)
            if chunk_sources
            else np.zeros(0, np.int32)
        )
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
        at = At(model, version)
        return self._expmap(at, centre, radius, direction, polar, near_pairs, tolerance, xyz)

    def _run_expmap(
        self, at: At, centre: Points, radius: float, direction: Optional[np.ndarray],
        polar: bool, near_pairs: int, tolerance: float,
    ) -> Tuple[np.ndarray, np.ndarray]:
        c = centre
        request = pb.ExpMapRequest(
            model=at.ref(), radius=radius, near_pairs=near_pairs, tolerance=tolerance
        )
        if direction is not None:
            request.reference_direction.xyz.extend(direction.ravel().tolist())
        data = request.SerializeToString() + _wire.length_delimited(
            2, _points(c)
        )
        vertices: List[np.ndarray] = []
        first: List[np.ndarray] = []
        second: List[np.ndarray] = []
        try:
            for chunk in self._expmap_call(data, metadata=self._metadata):
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

    def locate(self, model: str, xyz: Any, *, version: int = 0, batch_size: int = 65536) -> Located:
        """The closest surface point of each (N, 3) position.

        Returns
        -------
        Located
            faces (N,) int32, weights (N, 3) float64 (usable as points) and
            distances (N,) float64 from each position to its point.
        """
        return self._locate(At(model, version), xyz, max(1, int(batch_size)))

    def _run_locate(self, at: At, xyz: np.ndarray, batch_size: int) -> Located:
        n = xyz.shape[0]
        faces = np.empty(n, dtype=np.int32)
        weights = np.empty((n, 3), dtype=np.float64)
        distances = np.empty(n, dtype=np.float64)
        size = max(1, int(batch_size))
        for lo in range(0, max(n, 1), size):
            hi = min(n, lo + size)
            request = pb.LocateRequest(model=at.ref()).SerializeToString()
            request += _wire.length_delimited(2, _wire.positions(xyz[lo:hi]))
            try:
                data = self._locate_call(request, timeout=self._timeout, metadata=self._metadata)
            except grpc.RpcError as e:
                raise _rpc_error(e) from None
            fields = _wire.read_fields(data)
            points = _wire.read_fields(_wire.message(fields, 1))
            faces[lo:hi] = self._sized(_wire.packed_varints(points, 1), hi - lo, "located faces")
            weights[lo:hi] = self._sized(
                _wire.packed_doubles(points, 2), 3 * (hi - lo), "located weights"
            ).reshape(-1, 3)
            distances[lo:hi] = self._sized(_wire.packed_doubles(fields, 2), hi - lo, "distances")
            at.pin(_wire.scalar(fields, 3))
        return Located(faces, weights, distances)

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

    def _run_mesh(self, at: At) -> Tuple[np.ndarray, np.ndarray]:
        request = pb.GetMeshRequest(model=at.ref()).SerializeToString()
        vertices: Optional[np.ndarray] = None
        faces: Optional[np.ndarray] = None
        nv = nf = 0
        try:
            for data in self._mesh_call(request, metadata=self._metadata):
                fields = _wire.read_fields(data)
                if vertices is None or faces is None:
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

    @staticmethod
    def _sized(values: np.ndarray, n: int, what: str) -> np.ndarray:
        if values.shape[0] != n:
            raise DataLoss(f"the server sent {values.shape[0]} {what} for {n}")
        return values
