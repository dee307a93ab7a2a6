"""Exceptions raised by minkq, one per C error code (``minkq_status``).

Each subclasses :class:`MinkqError`, and the built-in exception closest to its meaning, so
that ``except ValueError`` also catches bad input. The extension module defines them, where it
raises them (bindings/python/src/errors.rs); the package's Python code raises the same classes
for what it checks before calling the library.
"""

from __future__ import annotations

from ._native import (
    CapacityError,
    DeviceError,
    IndexOutOfRangeError,
    InternalError,
    InvalidArgumentError,
    MinkqError,
    NonFiniteError,
    OutOfMemoryError,
    SizeOverflowError,
    UnsupportedError,
)
from ._native import _exception as _from_status

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
