"""The exceptions of the geodex package: one class per status code.

Every failure the package reports is a :class:`geodex.Error` whose subclass
names the status code (``geodex.NotFound``, ``geodex.InvalidArgument``, ...)
and whose message is the one the server, or the in-process engine, gave.
The classes of a caller's mistakes are also the built-in exceptions Python
code expects for them: ``InvalidArgument`` and ``OutOfRange`` are also
``ValueError``, ``NotFound`` is also a ``LookupError``; an ``except
geodex.Error`` still catches every one.
The codes are gRPC's (google.rpc.Code), which are also Abseil's: the client
and the in-process index raise the same class for the same mistake.

This module imports nothing but the standard library, so that both the gRPC
client and the in-process bindings can raise its classes.
"""

from __future__ import annotations

from typing import Dict, Type

__all__ = [
    "Error",
    "Cancelled",
    "Unknown",
    "InvalidArgument",
    "DeadlineExceeded",
    "NotFound",
    "AlreadyExists",
    "PermissionDenied",
    "ResourceExhausted",
    "FailedPrecondition",
    "Aborted",
    "OutOfRange",
    "Unimplemented",
    "Internal",
    "Unavailable",
    "DataLoss",
    "Unauthenticated",
    "error_for_code",
]


class Error(Exception):
    """A failed geodex call.

    Attributes
    ----------
    code : int
        The status code (google.rpc.Code: 3 is INVALID_ARGUMENT, ...).
    code_name : str
        Its name, e.g. ``"INVALID_ARGUMENT"``.
    message : str
        What went wrong, as the server or the engine said it (e.g.
        ``"a[17]: face id 99999 out of range [0, 5000)"``).
    """

    code: int = 2
    code_name: str = "UNKNOWN"

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:
        return f"{self.code_name}: {self.message}"


class Cancelled(Error):
    """The call was cancelled (CANCELLED)."""

    code, code_name = 1, "CANCELLED"


class Unknown(Error):
    """An error without a better code (UNKNOWN)."""

    code, code_name = 2, "UNKNOWN"


class InvalidArgument(Error, ValueError):
    """Malformed input: a bad array, point, option or mesh (INVALID_ARGUMENT);
    a ``ValueError``."""

    code, code_name = 3, "INVALID_ARGUMENT"


class DeadlineExceeded(Error):
    """The call ran out of time (DEADLINE_EXCEEDED)."""

    code, code_name = 4, "DEADLINE_EXCEEDED"


class NotFound(Error, LookupError):
    """An unknown model or version, or a missing file (NOT_FOUND); a
    ``LookupError``."""

    code, code_name = 5, "NOT_FOUND"


class AlreadyExists(Error):
    """ALREADY_EXISTS."""

    code, code_name = 6, "ALREADY_EXISTS"


class PermissionDenied(Error):
    """PERMISSION_DENIED."""

    code, code_name = 7, "PERMISSION_DENIED"


class ResourceExhausted(Error):
    """A server limit was exceeded, or the server is busy (RESOURCE_EXHAUSTED)."""

    code, code_name = 8, "RESOURCE_EXHAUSTED"


class FailedPrecondition(Error):
    """E.g. error bounds asked of an index without calibration, or an index
    of another format version (FAILED_PRECONDITION)."""

    code, code_name = 9, "FAILED_PRECONDITION"


class Aborted(Error):
    """ABORTED."""

    code, code_name = 10, "ABORTED"


class OutOfRange(Error, ValueError):
    """A face or vertex id past the end (OUT_OF_RANGE); a ``ValueError``."""

    code, code_name = 11, "OUT_OF_RANGE"


class Unimplemented(Error):
    """UNIMPLEMENTED."""

    code, code_name = 12, "UNIMPLEMENTED"


class Internal(Error):
    """INTERNAL."""

    code, code_name = 13, "INTERNAL"


class Unavailable(Error):
    """No server answers, a model is still loading, or the server is
    shutting down (UNAVAILABLE)."""

    code, code_name = 14, "UNAVAILABLE"


class DataLoss(Error):
    """A corrupt index file or an inconsistent answer (DATA_LOSS)."""

    code, code_name = 15, "DATA_LOSS"


class Unauthenticated(Error):
    """A missing or wrong bearer token (UNAUTHENTICATED)."""

    code, code_name = 16, "UNAUTHENTICATED"


_BY_CODE: Dict[int, Type[Error]] = {
    cls.code: cls
    for cls in (
        Cancelled,
        Unknown,
        InvalidArgument,
        DeadlineExceeded,
        NotFound,
        AlreadyExists,
        PermissionDenied,
        ResourceExhausted,
        FailedPrecondition,
        Aborted,
        OutOfRange,
        Unimplemented,
        Internal,
        Unavailable,
        DataLoss,
        Unauthenticated,
    )
}


def error_for_code(code: int, message: str) -> Error:
    """The exception for status ``code`` (google.rpc.Code) with ``message``.

    Codes without a class of their own (none today; 0 is not an error)
    become :class:`Unknown`, with the code kept in the message.
    """
    cls = _BY_CODE.get(int(code))
    if cls is None:
        return Unknown(f"status code {int(code)}: {message}")
    return cls(message)
