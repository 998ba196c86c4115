"""The numpy wire codec (geodex/_wire.py) against the generated protobuf
classes: the bytes it writes are protobuf's, and it reads what protobuf
writes, including the encodings a server could legally choose otherwise."""

import numpy as np
import pytest

from geodex import _wire
from geodex.v1 import geodex_pb2 as pb


@pytest.mark.parametrize("largest", [1, 127, 128, 16383, 16384, 2**21, 2**28, 2**31 - 1])
def test_surface_points_are_protobufs_bytes(largest):
    rng = np.random.default_rng(largest)
    faces = rng.integers(0, largest + 1, 1000).astype(np.int32)
    faces[:2] = [0, largest]
    weights = rng.random((1000, 3))
    ours = _wire.surface_points(faces, weights)
    theirs = pb.SurfacePoints(faces=faces.tolist(), weights=weights.ravel().tolist())
    assert ours == theirs.SerializeToString()
    assert np.array_equal(_wire.decode_varints(_wire.encode_varints(faces)), faces)


def test_vertex_ids_are_protobufs_bytes():
    vertices = np.array([0, 5, 127, 128, 2**31 - 1], np.int32)
    ours = _wire.vertex_points(vertices)
    assert ours == pb.SurfacePoints(vertices=vertices.tolist()).SerializeToString()
    assert _wire.vertex_points(np.zeros(0, np.int32)) == b""


def test_the_clients_calls_are_the_protos():
    """The client opens every call of the service as the descriptor lists
    it, with gRPC's kind for its streaming (a call added to geodex.proto is
    there; one renamed fails the client's table)."""
    import grpc

    from geodex._remote import raw_calls

    service = pb.DESCRIPTOR.services_by_name["Geodex"]
    with grpc.insecure_channel("127.0.0.1:1") as channel:
        calls = raw_calls(channel)
    assert sorted(calls) == sorted(m.name for m in service.methods)
    kinds = {"StreamDistances": grpc.StreamStreamMultiCallable,
             "Matrix": grpc.UnaryStreamMultiCallable, "Distance": grpc.UnaryUnaryMultiCallable}
    for name, kind in kinds.items():
        assert isinstance(calls[name], kind), name


def test_empty_arrays_are_left_out():
    assert _wire.surface_points(np.zeros(0, np.int32), np.zeros((0, 3))) == b""
    assert _wire.positions(np.zeros((0, 3))) == b""


def test_positions_are_protobufs_bytes():
    xyz = np.random.default_rng(1).normal(size=(50, 3))
    assert _wire.positions(xyz) == pb.Positions(xyz=xyz.ravel().tolist()).SerializeToString()


def test_a_request_is_its_head_and_its_arrays_merged():
    faces = np.array([4, 300], np.int32)
    weights = np.array([[1.0, 0, 0], [0.2, 0.3, 0.5]])
    head = pb.DistanceRequest(model=pb.ModelRef(name="m", version=3), tolerance=0.01)
    data = (head.SerializeToString()
            + _wire.length_delimited(2, _wire.surface_points(faces, weights))
            + _wire.length_delimited(3, _wire.surface_points(faces[::-1].copy(), weights[::-1])))
    parsed = pb.DistanceRequest.FromString(data)
    assert parsed.model.name == "m" and parsed.model.version == 3 and parsed.tolerance == 0.01
    assert list(parsed.a.faces) == [4, 300] and list(parsed.b.faces) == [300, 4]
    assert list(parsed.b.weights) == weights[::-1].ravel().tolist()


def test_results_are_read_as_protobuf_wrote_them():
    message = pb.DistanceResult(batch_id=2**40, distances=[1.5, float("inf"), 0.0],
                                error_code=3, error_message="a[1]: bad", version=7,
                                bounds=[0.25, 0.0, 1e-300])
    fields = _wire.read_fields(message.SerializeToString())
    assert _wire.scalar(fields, 1) == 2**40
    assert _wire.packed_doubles(fields, 2).tolist() == [1.5, float("inf"), 0.0]
    assert _wire.scalar(fields, 3) == 3 and _wire.string(fields, 4) == "a[1]: bad"
    assert _wire.scalar(fields, 5) == 7
    assert _wire.packed_doubles(fields, 6).tolist() == [0.25, 0.0, 1e-300]
    assert _wire.packed_doubles(fields, 9).shape == (0,)  # absent: empty
    assert _wire.scalar(fields, 9) == 0


def test_negative_int32_and_unpacked_and_split_fields():
    chunk = pb.DistanceFieldChunk(nearest_source=[-1, 5, 2**31 - 1], vertex_offset=-3)
    fields = _wire.read_fields(chunk.SerializeToString())
    assert _wire.packed_varints(fields, 3).tolist() == [-1, 5, 2**31 - 1]
    assert _wire.scalar(fields, 1) == -3
    # The same repeated double sent as two packed runs and one unpacked
    # element (legal protobuf), and a path's length (a singular double).
    data = (_wire.length_delimited(2, np.array([1.0, 2.0]).tobytes())
            + bytes([2 << 3 | 1]) + np.array([3.0]).tobytes()
            + _wire.length_delimited(2, np.array([4.0]).tobytes()))
    assert _wire.packed_doubles(_wire.read_fields(data), 2).tolist() == [1.0, 2.0, 3.0, 4.0]
    polyline = pb.Polyline(length=2.5).SerializeToString()
    assert _wire.double(_wire.read_fields(polyline), 3) == 2.5


def test_malformed_messages_are_refused():
    with pytest.raises(ValueError):
        _wire.read_fields(bytes([2 << 3 | 2, 10, 1, 2]))  # shorter than its length
    with pytest.raises(ValueError):
        _wire.read_fields(bytes([1 << 3 | 0, 0x80]))  # a varint that never ends
    with pytest.raises(ValueError):
        _wire.decode_varints(bytes([0x81]))
