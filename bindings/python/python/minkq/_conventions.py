"""The conventions the Python API shares with numpy, Warp and PyTorch: the device taken from
the arrays or given as ``device=`` in any of their spellings, the node test as ``mode=`` with
``"box"`` by default, growable output buffers (:class:`PairBuffer`), and the deprecation of
the spellings these replaced (``Scene(device, vertices, triangles)``, positional modes,
``query_into(out, ...)``), which keep working for one release with a DeprecationWarning."""

from __future__ import annotations

import threading
import warnings
from typing import Any, Dict, Iterable, Optional, Tuple

from ._device import Device
from ._interop import DL_CUDA, DL_CUDA_MANAGED, cuda_driver, has_protocol

_DEVICES: Dict[str, Device] = {}
"""One minkq.Device per spec: scenes made from arrays share their device (and its threads)."""
_DEVICES_LOCK = threading.Lock()


def deprecated(old: str, new: str, depth: int = 1) -> None:
    """Warns that the spelling ``old`` is deprecated in favour of ``new``, naming the user's line:
    the caller of the ``depth`` minkq functions that called this one (1: its caller's caller)."""
    message = f"{old} is deprecated and will be removed in the next release: use {new}"
    warnings.warn(message, DeprecationWarning, stacklevel=depth + 2)


def _device(spec: str) -> Device:
    with _DEVICES_LOCK:
        if spec not in _DEVICES:
            _DEVICES[spec] = Device(spec)
        return _DEVICES[spec]


def device_spec(device: Any, name: str = "device") -> str:
    """minkq's spec (``"cpu"``, ``"cuda:N"``, ``"cuda"``, ``"auto"``) of a device given as a
    string, a :class:`minkq.Device`, a ``torch.device`` or a Warp device; TypeError naming the
    argument for anything else."""
    if isinstance(device, str):
        return device
    if isinstance(device, Device):
        return "cpu" if device.backend == "cpu" else f"cuda:{device.ordinal}"
    kind = getattr(device, "type", None)  # torch.device: type "cpu" / "cuda", index None or N
    if isinstance(kind, str) and hasattr(device, "index"):
        if kind == "cuda" and device.index is None:
            import torch

            return f"cuda:{torch.cuda.current_device()}"
        if kind in ("cpu", "cuda"):
            return kind if device.index is None else f"{kind}:{device.index}"
        raise ValueError(f"{name}: minkq runs on 'cpu' and 'cuda' devices, got torch.device({kind!r})")
    alias = getattr(device, "alias", None)  # warp.context.Device: alias "cpu" / "cuda:N"
    if isinstance(alias, str) and hasattr(device, "is_cuda"):
        return f"cuda:{device.ordinal}" if device.is_cuda else "cpu"
    raise TypeError(
        f"{name}: expected 'cpu', 'cuda:N', a minkq.Device, a torch.device or a Warp device, got {type(device).__name__}"
    )


def array_device(value: Any) -> Optional[str]:
    """``"cuda:N"`` for an array in CUDA memory (DLPack or the CUDA array interface), ``"cpu"``
    for an array of another library in host memory, None for numpy arrays and sequences."""
    if value is None or not has_protocol(value):
        return None
    if hasattr(value, "__dlpack_device__"):
        device_type, device_id = (int(x) for x in value.__dlpack_device__())
        return f"cuda:{device_id}" if device_type in (DL_CUDA, DL_CUDA_MANAGED) else "cpu"
    address = int(value.__cuda_array_interface__["data"][0] or 0)
    return f"cuda:{cuda_driver().pointer_device(address) if address else 0}"


def resolve_device(device: Any, arrays: Iterable[Any]) -> Device:
    """The minkq.Device of ``device=`` (see :func:`device_spec`), or, for None, that of the first
    array of another library among ``arrays`` in CUDA memory (numpy arrays, sequences and host
    arrays: the CPU)."""
    if device is not None:
        return device if isinstance(device, Device) else _device(device_spec(device))
    for value in arrays:
        where = array_device(value)
        if where is not None and where != "cpu":
            return _device(where)
    return _device("cpu")


def old_device_form(what: str, args: Tuple[Any, ...], device: Any, depth: int = 1) -> Tuple[Tuple[Any, ...], Any]:
    """``(args, device)`` of a call whose positional ``args`` may start with a minkq.Device (the
    old ``what(device, ...)``): that device, with a DeprecationWarning; else ``args`` as given.
    ``depth``: the minkq functions between this one and the user's call."""
    if args and isinstance(args[0], Device):
        if device is not None:
            raise TypeError(f"{what}: got a minkq.Device first and device= as well")
        deprecated(f"{what}(device, ...)", f"{what}(..., device=device) (or no device: it is taken from the arrays)", depth + 1)
        return args[1:], args[0]
    return args, device


def old_mode_form(what: str, radius: Any, old: Tuple[Any, ...], mode: Any) -> Tuple[Any, Any]:
    """``(mode, radius)`` of ``what(kind, radius, *, mode=...)``, also in the old spelling
    ``what(kind, mode, radius)`` (a string where the radius goes), with a DeprecationWarning."""
    if isinstance(radius, str) and old:
        if len(old) != 1:
            raise TypeError(f"{what}: expected {what}(kind, radius, *, mode='box', ...), got {2 + len(old)} positional arguments")
        if mode != "box":
            raise TypeError(f"{what}: got a mode positionally and mode= as well")
        deprecated(f"{what}(kind, mode, radius) with a positional mode", f"{what}(kind, radius, mode=...)", 2)
        return radius, old[0]
    if old:
        raise TypeError(f"{what}: takes kind and radius positionally, the rest as keywords; got {2 + len(old)} positional arguments")
    return mode, radius


class _Closed:
    """What a closed object's ``_native`` is: every use raises ValueError naming the object."""

    def __init__(self, what: str) -> None:
        self._what = what

    def __getattr__(self, name: str) -> Any:
        raise ValueError(f"{self._what} is closed")


class Closable:
    """``close()`` and ``with`` for objects over a native handle (``self._native``): closing
    releases the handle (its memory, on the device too) now rather than when the object is
    collected; any later call raises ValueError. Closing twice is harmless. Calls running in
    other threads finish first: they hold the handle until they return."""

    _native: Any

    def close(self) -> None:
        """Releases the native object now; later calls raise ValueError."""
        if not isinstance(getattr(self, "_native", None), _Closed):
            self._native = _Closed(f"this minkq.{type(self).__name__}")

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return isinstance(getattr(self, "_native", None), _Closed)

    def __enter__(self: Any) -> Any:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


class PairBuffer:
    """A reusable, growing output buffer for ``out=``: a (capacity, 2) int32 array that queries
    write their pairs into and that is replaced by a larger one (with an eighth more room, in
    the same library and on the same device) when a query finds more pairs than it holds.
    Queries given ``out=buffer`` return ``buffer.array[:count]``, a view that the next query
    into the same buffer overwrites: copy it to keep it.

    ``array``: the first array (numpy, or another library's, on the scene's device), or None
    to let the first query allocate one like its results (numpy, or the arrays' library).

    >>> import numpy as np, minkq
    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, .1], [1, 0, .1], [0, 1, .1]], np.float32)
    >>> scene = minkq.Scene(v, np.array([[0, 1, 2], [3, 4, 5]], np.int32))
    >>> buffer = minkq.PairBuffer()
    >>> for step in range(3):  # no allocation once the buffer is large enough
    ...     vt = scene.query("vt", 0.2, leaf_exact=True, out=buffer)
    >>> len(vt), buffer.capacity >= len(vt)
    (6, True)
    """

    def __init__(self, array: Any = None) -> None:
        self.array = array

    @property
    def capacity(self) -> int:
        """The rows the buffer holds now (0 before its first query)."""
        return 0 if self.array is None else len(self.array)

    def __repr__(self) -> str:
        return f"minkq.PairBuffer(capacity={self.capacity})"
