"""Exceptions raised by minkq, one per C error code (``minkq_status``).

Each subclasses :class:`MinkqError`, and the built-in exception closest to its meaning, so
that ``except ValueError`` also catches bad input.
"""

from __future__ import annotations

from typing import Dict, Optional, Type

__all__ = [
    "MinkqError",
    "InvalidArgumentError",
    "NonFiniteError",
    "IndexOutOfRangeError",
    "SizeOverflowError",
    "CapacityError",
    "UnsupportedError",
    "OutOfMemoryError",
    "DeviceError",
    "InternalError",
]


class MinkqError(Exception):
    """A minkq call failed.

    ``status`` is the C status code, ``status_name`` its C name and ``message`` the library's
    message, which names the offending element (``"vertex 12 has a non-finite coordinate"``).
    """

    status: int = -1
    status_name: str = "unknown minkq_status"

    def __init__(self, message: str, status: Optional[int] = None) -> None:
        super().__init__(message)
        self.message = message
        if status is not None:
            self.status = status

    def __str__(self) -> str:
        return self.message


class InvalidArgumentError(MinkqError, ValueError):
    """MINKQ_ERROR_INVALID_ARGUMENT: a bad enum, stride, flag combination, count or spec."""

    status = 1
    status_name = "MINKQ_ERROR_INVALID_ARGUMENT"


class NonFiniteError(MinkqError, ValueError):
    """MINKQ_ERROR_NON_FINITE: NaN or infinity in a coordinate or the radius."""

    status = 2
    status_name = "MINKQ_ERROR_NON_FINITE"


class IndexOutOfRangeError(MinkqError, ValueError):
    """MINKQ_ERROR_INDEX_OUT_OF_RANGE: a negative or too large vertex index."""

    status = 3
    status_name = "MINKQ_ERROR_INDEX_OUT_OF_RANGE"


class SizeOverflowError(MinkqError, OverflowError):
    """MINKQ_ERROR_SIZE_OVERFLOW: a count over 2**31 - 2, or one whose byte size overflows."""

    status = 4
    status_name = "MINKQ_ERROR_SIZE_OVERFLOW"


class CapacityError(MinkqError):
    """MINKQ_ERROR_CAPACITY: the output array holds fewer pairs than the query found.

    ``needed`` is the exact number of pairs; nothing was written past the array.
    """

    status = 5
    status_name = "MINKQ_ERROR_CAPACITY"

    def __init__(self, message: str, needed: int = 0) -> None:
        super().__init__(message)
        self.needed = needed


class UnsupportedError(MinkqError):
    """MINKQ_ERROR_UNSUPPORTED: e.g. CUDA asked for where there is none."""

    status = 6
    status_name = "MINKQ_ERROR_UNSUPPORTED"


class OutOfMemoryError(MinkqError, MemoryError):
    """MINKQ_ERROR_OUT_OF_MEMORY."""

    status = 7
    status_name = "MINKQ_ERROR_OUT_OF_MEMORY"


class DeviceError(MinkqError, RuntimeError):
    """MINKQ_ERROR_DEVICE: a CUDA runtime call failed."""

    status = 8
    status_name = "MINKQ_ERROR_DEVICE"


class InternalError(MinkqError, RuntimeError):
    """MINKQ_ERROR_INTERNAL."""

    status = 9
    status_name = "MINKQ_ERROR_INTERNAL"


_BY_STATUS: Dict[int, Type[MinkqError]] = {
    cls.status: cls
    for cls in (
        InvalidArgumentError,
        NonFiniteError,
        IndexOutOfRangeError,
        SizeOverflowError,
        CapacityError,
        UnsupportedError,
        OutOfMemoryError,
        DeviceError,
        InternalError,
    )
}


def _from_status(status: int, message: str, needed: Optional[int] = None) -> MinkqError:
    """The exception for a C status (called by minkq._native)."""
    cls = _BY_STATUS.get(status)
    if cls is None:
        return MinkqError(message, status)
    if cls is CapacityError:
        return CapacityError(message, needed or 0)
    return cls(message)
