"""Compute devices and what the loaded library says of itself."""

from __future__ import annotations

from typing import Optional, Tuple

from . import _native


class Device:
    """A compute device: ``"cpu"``, ``"cuda"`` (GPU 0), ``"cuda:N"`` or ``"auto"`` (CUDA when a GPU
    is usable, else the CPU). Scenes and BVHs are built on a device and keep it alive.

    >>> import minkq
    >>> minkq.Device("cpu").backend
    'cpu'

    Raises :class:`InvalidArgumentError` for an unknown spec and :class:`UnsupportedError` for CUDA
    where there is none.
    """

    def __init__(self, spec: str = "auto") -> None:
        if not isinstance(spec, str):
            raise TypeError(f"spec: expected a str, got {type(spec).__name__}")
        self._native = _native.Device(spec)

    @property
    def name(self) -> str:
        """A description such as ``"cpu (8 threads, avx2)"`` or ``"cuda:0 (NVIDIA H100 80GB HBM3)"``."""
        return self._native.name

    @property
    def backend(self) -> str:
        """``"cpu"`` or ``"cuda"``."""
        return self._native.backend

    @property
    def ordinal(self) -> Optional[int]:
        """The CUDA device number (``cuda:N``) of a CUDA device; None for the CPU."""
        if self.backend != "cuda":
            return None
        return int(self.name.split()[0].split(":")[1])

    def __repr__(self) -> str:
        return f"minkq.Device({self.name!r})"


def cuda_device_count() -> int:
    """The number of usable CUDA devices (0 where minkq was built without CUDA or has no GPU)."""
    return _native.cuda_device_count()


def version() -> Tuple[int, int, int]:
    """The library's run-time version (major, minor, patch)."""
    return _native.version()


def abi_version() -> int:
    """The library's run-time ABI version (``minkq.ABI_VERSION`` is the one the bindings were
    generated against)."""
    return _native.abi_version()
