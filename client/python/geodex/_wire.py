"""The protobuf wire format of geodex.v1's numeric arrays, with numpy.

The generated message classes copy a repeated field element by element
(about 0.8 us a pair to fill a DistanceBatch from numpy arrays: the whole
budget of a streamed distance). The packed arrays of geodex.v1 are simple on
the wire, so the client encodes them here in a few vectorised passes and
decodes the numeric answers (distances, matrix blocks) the same way; the rest
of every message (model, options) still goes through the generated classes,
and both parts are concatenated, which protobuf defines as merging them.

Wire format (https://protobuf.dev/programming-guides/encoding/): a field is
a varint key (field_number << 3 | wire_type) and a value; repeated scalars
are packed into one length-delimited value: varints for int32 and uint32,
8-byte little-endian for double.
"""

from __future__ import annotations

from typing import Dict, List, Tuple, Union

import numpy as np

__all__ = [
    "encode_varints",
    "decode_varints",
    "surface_points",
    "vertex_points",
    "positions",
    "length_delimited",
    "read_fields",
    "packed_doubles",
    "packed_varints",
    "scalar",
]

_VARINT, _I64, _LEN, _I32 = 0, 1, 2, 5


def _varint(value: int) -> bytes:
    """One non-negative integer as a varint."""
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def encode_varints(values: np.ndarray) -> bytes:
    """Non-negative integers (< 2**35) as consecutive varints, vectorised.

    Each value takes 1 + (bit length - 1) // 7 bytes: the low 7 bits first,
    the high bit of every byte but the last set.
    """
    v = np.ascontiguousarray(values, dtype=np.uint64)
    if v.size == 0:
        return b""
    if int(v.max()) < 0x80:  # one byte each (small meshes)
        return v.astype(np.uint8).tobytes()
    lengths = np.ones(v.shape, dtype=np.int64)
    for k in range(1, 5):
        lengths += v >= (1 << (7 * k))
    ends = np.cumsum(lengths)
    starts = ends - lengths
    out = np.empty(int(ends[-1]), dtype=np.uint8)
    for k in range(int(lengths.max())):
        sel = lengths > k
        byte = ((v[sel] >> np.uint64(7 * k)) & np.uint64(0x7F)).astype(np.uint8)
        byte |= (lengths[sel] > k + 1).astype(np.uint8) << np.uint8(7)
        out[starts[sel] + k] = byte
    return out.tobytes()


def decode_varints(data: Union[bytes, memoryview]) -> np.ndarray:
    """Consecutive varints as uint64, vectorised (the inverse of
    encode_varints, for values of up to 10 bytes)."""
    b = np.frombuffer(data, dtype=np.uint8)
    if b.size == 0:
        return np.zeros(0, dtype=np.uint64)
    ends = np.flatnonzero(b < 0x80)
    if ends.size == 0 or ends[-1] != b.size - 1:
        raise ValueError("truncated varint")
    starts = np.empty_like(ends)
    starts[0] = 0
    starts[1:] = ends[:-1] + 1
    lengths = ends - starts + 1
    out = (b[starts] & 0x7F).astype(np.uint64)
    for k in range(1, int(lengths.max())):
        sel = lengths > k
        out[sel] |= (b[starts[sel] + k] & 0x7F).astype(np.uint64) << np.uint64(7 * k)
    return out


def length_delimited(field: int, payload: bytes) -> bytes:
    """Field `field` holding `payload` (a message, a packed array, a string)."""
    return _varint(field << 3 | _LEN) + _varint(len(payload)) + payload


def surface_points(faces: np.ndarray, weights: np.ndarray) -> bytes:
    """A geodex.v1.SurfacePoints message: faces (N,) non-negative int32 as
    field 1 (packed varints), weights (N, 3) float64 as field 2 (packed
    doubles). Empty arrays are left out, as proto3 does."""
    if faces.shape[0] == 0:
        return b""
    return length_delimited(1, encode_varints(faces)) + length_delimited(
        2, np.ascontiguousarray(weights, dtype="<f8").tobytes()
    )


def vertex_points(vertices: np.ndarray) -> bytes:
    """A geodex.v1.SurfacePoints message of points given as vertex ids:
    vertices (N,) non-negative int32 as field 3 (packed varints), no faces
    and no weights."""
    if vertices.shape[0] == 0:
        return b""
    return length_delimited(3, encode_varints(vertices))


def positions(xyz: np.ndarray) -> bytes:
    """A geodex.v1.Positions message: xyz (N, 3) float64 as field 1."""
    if xyz.shape[0] == 0:
        return b""
    return length_delimited(1, np.ascontiguousarray(xyz, dtype="<f8").tobytes())


Field = Tuple[int, Union[int, memoryview]]


def read_fields(data: Union[bytes, memoryview]) -> Dict[int, List[Field]]:
    """Splits a message into its fields: number -> [(wire type, value)], in
    order; a value is an int for varints and fixed-size scalars (their raw
    bits), a memoryview of the bytes for length-delimited ones.

    Raises ValueError on a malformed message.
    """
    view = memoryview(data)
    n = len(view)
    fields: Dict[int, List[Field]] = {}
    pos = 0
    while pos < n:
        key, pos = _read_varint(view, pos)
        number, wire = key >> 3, key & 7
        if wire == _VARINT:
            value, pos = _read_varint(view, pos)
        elif wire == _I64:
            if pos + 8 > n:
                raise ValueError("truncated fixed64")
            value = int.from_bytes(view[pos : pos + 8], "little")
            pos += 8
        elif wire == _LEN:
            size, pos = _read_varint(view, pos)
            if pos + size > n:
                raise ValueError("truncated length-delimited field")
            value = view[pos : pos + size]
            pos += size
        elif wire == _I32:
            if pos + 4 > n:
                raise ValueError("truncated fixed32")
            value = int.from_bytes(view[pos : pos + 4], "little")
            pos += 4
        else:
            raise ValueError(f"unsupported wire type {wire}")
        fields.setdefault(number, []).append((wire, value))
    return fields


def _read_varint(view: memoryview, pos: int) -> Tuple[int, int]:
    value = 0
    shift = 0
    while True:
        if pos >= len(view) or shift > 63:
            raise ValueError("truncated varint")
        byte = view[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if byte < 0x80:
            return value, pos
        shift += 7


def packed_doubles(fields: Dict[int, List[Field]], number: int) -> np.ndarray:
    """Repeated double field `number` as float64: packed runs (any number of
    them) and unpacked elements, in order. The result may be a read-only view
    of the message's bytes: copy it to keep it."""
    parts = []
    for wire, value in fields.get(number, ()):
        if wire == _LEN:
            if len(value) % 8:
                raise ValueError(f"field {number}: packed doubles of {len(value)} bytes")
            parts.append(np.frombuffer(value, dtype="<f8"))
        elif wire == _I64:
            parts.append(np.array([value], dtype=np.uint64).view("<f8"))
        else:
            raise ValueError(f"field {number}: wire type {wire} for a double")
    if not parts:
        return np.zeros(0, dtype=np.float64)
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def packed_varints(fields: Dict[int, List[Field]], number: int) -> np.ndarray:
    """Repeated int32/uint32/int64 field `number` as int64 (negative int32
    values, which are sign-extended to 64 bits on the wire, come back
    negative)."""
    parts = []
    for wire, value in fields.get(number, ()):
        if wire == _LEN:
            parts.append(decode_varints(value))
        elif wire == _VARINT:
            parts.append(np.array([value], dtype=np.uint64))
        else:
            raise ValueError(f"field {number}: wire type {wire} for an integer")
    if not parts:
        return np.zeros(0, dtype=np.int64)
    return np.concatenate(parts).view(np.int64)


def scalar(fields: Dict[int, List[Field]], number: int, default: int = 0) -> int:
    """The last value of a singular varint field (proto3: absent is 0), as a
    signed 64-bit integer."""
    values = fields.get(number)
    if not values:
        return default
    wire, value = values[-1]
    if wire != _VARINT:
        raise ValueError(f"field {number}: wire type {wire} for an integer")
    return value - (1 << 64) if value >= 1 << 63 else value


def double(fields: Dict[int, List[Field]], number: int) -> float:
    """The last value of a singular double field (proto3: absent is 0)."""
    values = [value for wire, value in fields.get(number, ()) if wire == _I64]
    if not values:
        return 0.0
    return float(np.array([values[-1]], dtype=np.uint64).view("<f8")[0])


def message(fields: Dict[int, List[Field]], number: int) -> bytes:
    """A singular message field (its parts merged, as protobuf does), or b""."""
    parts = [bytes(value) for wire, value in fields.get(number, ()) if wire == _LEN]
    return b"".join(parts)


def string(fields: Dict[int, List[Field]], number: int) -> str:
    """A singular string field (the last one), or ""."""
    values = [value for wire, value in fields.get(number, ()) if wire == _LEN]
    return bytes(values[-1]).decode("utf-8", errors="replace") if values else ""
