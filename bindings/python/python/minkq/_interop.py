"""Arrays of other libraries, read in place: DLPack (``__dlpack__``, ``__dlpack_device__``) and
the CUDA array interface (``__cuda_array_interface__``): Warp arrays, PyTorch and CuPy tensors,
Numba device arrays. Host or CUDA device memory; never copied.

Streams. minkq's C API has no stream argument: on a CUDA device it works on the calling
thread's per-thread default stream (``cudaStreamPerThread``) and synchronises that stream before
each call returns. So

- a DLPack producer is asked for its tensor with ``stream=1`` (DLPack's number for the legacy
  default stream): the producer orders its pending work on the array before that stream, as
  the DLPack protocol requires of it, and work on the legacy default stream is ordered before
  later work on every blocking stream, the per-thread default stream included (PyTorch refuses
  ``stream=2``, the per-thread default stream, so minkq does not ask for it);
- a CUDA array interface with a ``stream`` entry (version 3) is synchronised on the host
  (``cuStreamSynchronize``) before minkq reads it, as that protocol requires of a consumer;
  one without (versions 0-2, or ``None``) promises the data are ready;
- results written by minkq are complete when the call returns, so any stream may read them.

The stream-ordered calls (``Scene.refit_async``, ``query_async``, ...) are enqueued on a stream
of the caller's instead (:func:`stream_handle`: by default the current stream of the arrays'
library), and read the arrays through the same code with that stream: a DLPack producer is
asked for its tensor on it, and a CUDA array interface stream other than it is ordered before
it with an event (``cuStreamWaitEvent``), never synchronised on the host, so that the calls can
be captured into a CUDA graph. While that stream is being captured (``wp.ScopedCapture``,
``torch.cuda.graph``) no event is waited for: CUDA's capture rules forbid a captured stream to
wait on an event recorded outside the capture, which would invalidate it. Inside a capture the
caller orders the producer's work into it: the producer's stream must be part of the capture
(the capture stream itself, or a stream forked from it and joined back before the call), or
the data ready before capture began.

A CUDA array given to a CPU device, or one on another GPU than the minkq device, raises
:class:`~minkq.InvalidArgumentError` naming the argument; nothing is copied to make it fit.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from typing import Any, Optional, Tuple

import numpy as np

from ._errors import DeviceError, InvalidArgumentError

# DLPack device types (dlpack.h).
DL_CPU, DL_CUDA, DL_CUDA_HOST, DL_CUDA_MANAGED = 1, 2, 3, 13
# The stream a CUDA DLPack producer is asked for on the blocking path: DLPack's number for the
# legacy default stream. minkq works on the per-thread default stream (DLPack's 2), which is
# ordered after work on the legacy default stream, so the producer's work stays before minkq's.
# PyTorch raises BufferError for 2 ("per-thread default stream is not supported") and takes 1 as
# its default stream; Warp and CuPy take 1 as the legacy default stream too.
BLOCKING_STREAM = 1
# DLDataTypeCode -> numpy kind.
_DL_KINDS = {0: "i", 1: "u", 2: "f"}


class _DLDevice(ctypes.Structure):
    _fields_ = [("device_type", ctypes.c_int32), ("device_id", ctypes.c_int32)]


class _DLDataType(ctypes.Structure):
    _fields_ = [("code", ctypes.c_uint8), ("bits", ctypes.c_uint8), ("lanes", ctypes.c_uint16)]


class _DLTensor(ctypes.Structure):
    _fields_ = [
        ("data", ctypes.c_void_p),
        ("device", _DLDevice),
        ("ndim", ctypes.c_int32),
        ("dtype", _DLDataType),
        ("shape", ctypes.POINTER(ctypes.c_int64)),
        ("strides", ctypes.POINTER(ctypes.c_int64)),
        ("byte_offset", ctypes.c_uint64),
    ]


class _DLManagedTensor(ctypes.Structure):
    _fields_ = [("dl_tensor", _DLTensor), ("manager_ctx", ctypes.c_void_p), ("deleter", ctypes.c_void_p)]


_capsule_is_valid = ctypes.pythonapi.PyCapsule_IsValid
_capsule_is_valid.restype = ctypes.c_int
_capsule_is_valid.argtypes = [ctypes.py_object, ctypes.c_char_p]
_capsule_pointer = ctypes.pythonapi.PyCapsule_GetPointer
_capsule_pointer.restype = ctypes.c_void_p
_capsule_pointer.argtypes = [ctypes.py_object, ctypes.c_char_p]


@dataclass(frozen=True)
class Foreign:
    """An array of another library, viewed in place."""

    obj: Any
    """The caller's object (kept alive with the view)."""
    address: int
    """The address of element 0."""
    shape: Tuple[int, ...]
    strides: Tuple[int, ...]
    """In bytes."""
    dtype: np.dtype
    cuda: Optional[int]
    """The CUDA ordinal of device memory; None for host memory."""
    readonly: bool
    protocol: str
    """``"dlpack"`` or ``"cuda_array_interface"``."""
    keepalive: Any = None
    """The DLPack capsule: its destructor releases the producer's tensor (the capsule is not
    consumed, so the DLPack deleter runs when it is freed)."""

    @property
    def kind(self) -> str:
        """The library the array comes from: ``"warp"``, ``"torch"``, ``"cupy"``, ..."""
        return type(self.obj).__module__.split(".")[0]

    @property
    def where(self) -> str:
        return "host memory" if self.cuda is None else f"cuda:{self.cuda}"

    def descriptor(self) -> Tuple[int, int, int, bool]:
        """(address, byte stride of the first axis, rows, device memory) for minkq._native."""
        rows = self.shape[0]
        row_bytes = self.dtype.itemsize * int(np.prod(self.shape[1:], dtype=np.int64))
        stride = self.strides[0] if rows > 1 else row_bytes
        return (self.address if rows else 0, stride, rows, self.cuda is not None)


def has_protocol(value: Any) -> bool:
    """Whether ``value`` is read through DLPack or the CUDA array interface (numpy arrays are
    read through the buffer protocol instead)."""
    if isinstance(value, np.ndarray):
        return False
    return (hasattr(value, "__dlpack__") and hasattr(value, "__dlpack_device__")) or hasattr(
        value, "__cuda_array_interface__"
    )


def host_copy(value: Any) -> np.ndarray:
    """The values of an array of another library as a numpy array: read in place from host
    memory (DLPack), copied from device memory by the array's own library (PyTorch ``.cpu()``,
    Warp ``.numpy()``, CuPy ``.get()``)."""
    if hasattr(value, "__dlpack_device__") and int(value.__dlpack_device__()[0]) in (DL_CPU, DL_CUDA_HOST):
        if hasattr(np, "from_dlpack"):
            return np.from_dlpack(value)
        return np.asarray(value)
    for method in ("cpu", "numpy", "get"):
        if callable(getattr(value, method, None)):
            value = getattr(value, method)()
            if isinstance(value, np.ndarray):
                return value
    return np.asarray(value)


def view(value: Any, name: str, device: Any, stream: Optional[int] = None) -> Foreign:
    """``value`` viewed in place, checked against the minkq ``device`` (a minkq.Device): a CUDA
    array needs a CUDA device of the same ordinal. ``stream``: None for the blocking calls
    (minkq's per-thread default stream, data ready on the host); for a stream-ordered call the
    cudaStream_t it is enqueued on (0: CUDA's default stream), which the array's pending work
    is ordered before."""
    if hasattr(value, "__dlpack__") and hasattr(value, "__dlpack_device__"):
        device_type, device_id = (int(x) for x in value.__dlpack_device__())
        if device_type in (DL_CUDA, DL_CUDA_MANAGED):
            _require_cuda(name, device, device_id, type(value), "DLPack")
            capsule = value.__dlpack__(stream=BLOCKING_STREAM if stream is None else _dlpack_stream(stream))
        elif device_type in (DL_CPU, DL_CUDA_HOST):
            capsule = value.__dlpack__()
        else:
            raise TypeError(
                f"{name}: a {_type_name(value)} in DLPack device type {device_type} memory: minkq reads host "
                "or CUDA memory"
            )
        return _from_capsule(value, capsule, name)
    if hasattr(value, "__cuda_array_interface__"):
        return _from_cuda_array_interface(value, name, device, stream)
    raise TypeError(f"{name}: {_type_name(value)} has neither __dlpack__ nor __cuda_array_interface__")


def _type_name(value: Any) -> str:
    t = type(value)
    return f"{t.__module__}.{t.__qualname__}"


def _require_cuda(name: str, device: Any, ordinal: Optional[int], cls: type, protocol: str) -> None:
    where = "a CUDA device" if ordinal is None else f"cuda:{ordinal}"
    if device.backend != "cuda":
        raise InvalidArgumentError(
            f"{name}: a {cls.__module__}.{cls.__qualname__} on {where} ({protocol}) cannot be read by the minkq "
            f"device {device.name!r}; minkq does not copy device arrays to the host: pass host arrays, or "
            "create the scene on minkq.Device('cuda')"
        )
    if ordinal is not None and ordinal != device.ordinal:
        raise InvalidArgumentError(
            f"{name}: the array is on cuda:{ordinal} but the minkq device is {device.name!r}; minkq does not copy "
            f"between GPUs: use minkq.Device('cuda:{ordinal}')"
        )


def _from_capsule(value: Any, capsule: Any, name: str) -> Foreign:
    if not _capsule_is_valid(capsule, b"dltensor"):
        raise TypeError(f"{name}: __dlpack__ of {_type_name(value)} did not return an unconsumed 'dltensor' capsule")
    managed = _DLManagedTensor.from_address(_capsule_pointer(capsule, b"dltensor"))
    tensor = managed.dl_tensor
    dt = tensor.dtype
    if dt.code not in _DL_KINDS or dt.lanes != 1 or dt.bits % 8:
        raise TypeError(f"{name}: DLPack dtype (code {dt.code}, {dt.bits} bits, {dt.lanes} lanes) is not a plain int or float")
    dtype = np.dtype(f"<{_DL_KINDS[dt.code]}{dt.bits // 8}")
    ndim = int(tensor.ndim)
    shape = tuple(int(tensor.shape[k]) for k in range(ndim))
    if tensor.strides:
        strides = tuple(int(tensor.strides[k]) * dtype.itemsize for k in range(ndim))
    else:
        strides = _c_strides(shape, dtype.itemsize)
    device_type = int(tensor.device.device_type)
    cuda = int(tensor.device.device_id) if device_type in (DL_CUDA, DL_CUDA_MANAGED) else None
    address = (tensor.data or 0) + int(tensor.byte_offset)
    return Foreign(value, address, shape, strides, dtype, cuda, False, "dlpack", capsule)


def _dlpack_stream(handle: int) -> int:
    """DLPack's number for a cudaStream_t: 1 for the legacy default stream (NULL, which DLPack
    does not allow), the handle itself otherwise (2 is the per-thread default stream)."""
    return 1 if handle == 0 else handle


def _from_cuda_array_interface(value: Any, name: str, device: Any, consumer: Optional[int] = None) -> Foreign:
    cai = value.__cuda_array_interface__
    if cai.get("mask") is not None:
        raise TypeError(f"{name}: masked CUDA arrays are not supported")
    _require_cuda(name, device, None, type(value), "__cuda_array_interface__")
    address, readonly = cai["data"]
    address = int(address or 0)
    shape = tuple(int(d) for d in cai["shape"])
    dtype = np.dtype(cai["typestr"])
    strides = cai.get("strides")
    strides = _c_strides(shape, dtype.itemsize) if strides is None else tuple(int(s) for s in strides)
    ordinal = cuda_driver().pointer_device(address) if address else device.ordinal
    _require_cuda(name, device, ordinal, type(value), "__cuda_array_interface__")
    stream = cai.get("stream")
    if stream is not None:
        if consumer is None:
            cuda_driver().stream_synchronize(int(stream))
        elif _dlpack_stream(int(stream)) != _dlpack_stream(consumer):
            # The CUDA array interface's stream numbers are DLPack's (1 legacy, 2 per-thread).
            # A capturing stream must not wait on an event recorded outside its capture (that
            # invalidates the capture): there the caller has ordered the producer's work into
            # the capture, or finished it before capture began (the module's docstring).
            driver = cuda_driver()
            if not driver.stream_is_capturing(consumer):
                driver.stream_wait(consumer, int(stream))
    return Foreign(value, address, shape, strides, dtype, ordinal, bool(readonly), "cuda_array_interface")


def _c_strides(shape: Tuple[int, ...], itemsize: int) -> Tuple[int, ...]:
    strides = []
    step = itemsize
    for d in reversed(shape):
        strides.append(step)
        step *= max(d, 1)
    return tuple(reversed(strides))


def checked(array: Foreign, name: str, dtype: Any, trailing: Tuple[int, ...], *, writable: bool = False, packed: bool = False) -> Foreign:
    """``array`` if it holds rows of ``trailing`` ``dtype`` values, each row contiguous (rows
    themselves at any byte stride, unless ``packed``); TypeError / ValueError naming the
    argument otherwise. Nothing is converted or copied."""
    dtype = np.dtype(dtype)
    if array.dtype != dtype:
        raise TypeError(f"{name}: expected a {dtype.name} array, got {array.dtype.name} ({array.kind}, {array.where})")
    if len(array.shape) != 1 + len(trailing) or array.shape[1:] != trailing:
        wanted = ", ".join(["n"] + [str(d) for d in trailing])
        raise ValueError(f"{name}: expected shape ({wanted}), got {array.shape}")
    inner = _c_strides(trailing, dtype.itemsize)
    row_bytes = dtype.itemsize * int(np.prod(trailing, dtype=np.int64))
    inner_ok = all(s == want for s, want, d in zip(array.strides[1:], inner, trailing) if d > 1)
    rows = array.shape[0]
    row_ok = rows <= 1 or (array.strides[0] == row_bytes if packed else array.strides[0] >= row_bytes)
    if not (inner_ok and row_ok):
        need = "C-contiguous" if packed else f"rows of {row_bytes} contiguous bytes at a positive stride of at least {row_bytes}"
        raise ValueError(
            f"{name}: expected {need}, got byte strides {array.strides} ({array.kind}, {array.where}); minkq reads "
            "such arrays in place and does not copy them: pass a contiguous array"
        )
    if writable and array.readonly:
        raise ValueError(f"{name}: the array is read-only")
    # DLPack before 1.0 cannot mark a tensor read-only: refuse the library whose arrays are
    # immutable rather than write into one.
    if writable and array.kind in ("jax", "jaxlib"):
        raise ValueError(f"{name}: JAX arrays are immutable; pass a numpy, Warp, PyTorch or CuPy array to write into")
    if rows and array.address % dtype.itemsize:
        raise ValueError(f"{name}: the data address is not {dtype.itemsize}-byte aligned")
    return array


def checked_count(array: Foreign, name: str) -> Foreign:
    """``array`` if it is a writable one-element uint64 or int64 array (a stream-ordered query's
    exact count), 8-byte aligned; TypeError / ValueError naming the argument otherwise."""
    if array.dtype not in (np.dtype("<u8"), np.dtype("<i8")):
        raise TypeError(f"{name}: expected a uint64 or int64 array, got {array.dtype.name} ({array.kind}, {array.where})")
    checked(array, name, array.dtype, (), writable=True, packed=True)
    if array.shape != (1,):
        raise ValueError(f"{name}: expected shape (1,), got {array.shape}")
    return array


# ---- Streams of the stream-ordered calls ----------------------------------------------------------


def stream_handle(stream: Any, device: Any, arrays: Tuple[Any, ...] = ()) -> int:
    """The cudaStream_t (as an int; 0 is CUDA's default stream) that a stream-ordered call on the
    minkq ``device`` is enqueued on. ``stream``: an int (a cudaStream_t), an object with
    ``.cuda_stream`` (Warp, PyTorch streams) or ``.ptr`` (CuPy streams), or None: on a CUDA
    device, the current stream of the library of the first array of ``arrays`` that has one
    (Warp: ``wp.get_stream(array.device)``, which inside ``wp.ScopedCapture`` is the capture
    stream; PyTorch: ``torch.cuda.current_stream(array.device)``; CuPy:
    ``cupy.cuda.get_current_stream()``; another library's CUDA array interface stream), else
    CUDA's default stream. A CPU device ignores the stream (it is still checked)."""
    if stream is not None:
        return _explicit_stream(stream)
    if getattr(device, "backend", None) != "cuda":
        return 0
    for value in arrays:
        if value is None or isinstance(value, np.ndarray) or not has_protocol(value):
            continue
        kind = type(value).__module__.split(".")[0]
        if kind == "warp":
            import warp as wp

            return int(wp.get_stream(value.device).cuda_stream)
        if kind == "torch":
            import torch

            return int(torch.cuda.current_stream(value.device).cuda_stream)
        if kind == "cupy":
            import cupy

            return int(cupy.cuda.get_current_stream().ptr)
        cai = getattr(value, "__cuda_array_interface__", None)
        if isinstance(cai, dict) and cai.get("stream") is not None:
            handle = int(cai["stream"])
            return 0 if handle == 1 else handle
    return 0


def _explicit_stream(stream: Any) -> int:
    if isinstance(stream, bool):
        raise TypeError("stream: expected None, an int (a cudaStream_t) or a stream object, got bool")
    if isinstance(stream, (int, np.integer)):
        handle = int(stream)
    elif hasattr(stream, "cuda_stream"):
        handle = int(stream.cuda_stream)
    elif hasattr(stream, "ptr"):
        handle = int(stream.ptr)
    else:
        raise TypeError(
            f"stream: expected None, an int (a cudaStream_t) or a stream with .cuda_stream (Warp, PyTorch) or .ptr "
            f"(CuPy), got {_type_name(stream)}"
        )
    if handle < 0:
        raise ValueError(f"stream: expected a cudaStream_t (an address >= 0), got {handle}")
    return handle


# ---- Results of the caller's kind ---------------------------------------------------------------


@dataclass(frozen=True)
class Like:
    """What results need of an array to be made like it (without keeping the array alive)."""

    kind: str
    """Its library: ``"warp"``, ``"torch"``, ``"cupy"``, ..."""
    cuda: Optional[int]
    """The CUDA ordinal of device memory; None for host memory."""
    device: Any
    """The library's own device object (``array.device``), if it has one."""
    type_name: str


def like(array: Foreign) -> Like:
    return Like(array.kind, array.cuda, getattr(array.obj, "device", None), _type_name(array.obj))


def allocate_pairs(like: Optional[Like], count: int) -> Any:
    """An empty (count, 2) int32 array of ``like``'s library on ``like``'s device (numpy for
    None, and for host arrays of libraries other than Warp, PyTorch and CuPy)."""
    if like is None:
        return np.empty((count, 2), dtype=np.int32)
    kind = like.kind
    if kind == "warp":
        import warp as wp

        return wp.empty(shape=(count, 2), dtype=wp.int32, device=like.device)
    if kind == "torch":
        import torch

        return torch.empty((count, 2), dtype=torch.int32, device=like.device)
    if kind == "cupy":
        import cupy

        with cupy.cuda.Device(like.cuda if like.cuda is not None else 0):
            return cupy.empty((count, 2), dtype=cupy.int32)
    if like.cuda is None:
        return np.empty((count, 2), dtype=np.int32)
    raise TypeError(
        f"cannot allocate result pairs like a {like.type_name} (minkq allocates numpy, Warp, PyTorch and CuPy "
        "arrays): pass a (capacity, 2) int32 array of your own to query_into"
    )


def head(pairs: Any, count: int, compact: bool) -> Any:
    """The first ``count`` rows of an array from :func:`allocate_pairs`; a copy when
    ``compact`` (so that a much larger array is not kept alive behind a small result). All the
    rows are the array itself: Warp cannot slice an empty array (a first query that finds
    nothing allocated none)."""
    rows = pairs if count == len(pairs) else pairs[:count]
    if not compact:
        return rows
    if isinstance(rows, np.ndarray):
        return rows.copy()
    if type(rows).__module__.split(".")[0] == "warp":
        import warp as wp

        return wp.clone(rows)
    if hasattr(rows, "clone"):  # torch
        return rows.clone()
    return rows.copy()  # cupy


# ---- The CUDA driver, for the CUDA array interface ----------------------------------------------


class _Driver:
    """The few CUDA driver calls the CUDA array interface needs, through libcuda.so.1 (present
    wherever a GPU is usable): the device of a pointer, stream synchronisation, and the ordering
    of one stream after another (stream-ordered calls), and whether a stream is being captured."""

    CU_POINTER_ATTRIBUTE_DEVICE_ORDINAL = 9
    CU_EVENT_DISABLE_TIMING = 2
    CU_STREAM_CAPTURE_STATUS_NONE = 0  # ACTIVE is 1, INVALIDATED 2

    def __init__(self) -> None:
        try:
            self._lib = ctypes.CDLL("libcuda.so.1")
        except OSError as e:
            raise DeviceError(f"the CUDA driver (libcuda.so.1) cannot be loaded: {e}") from None
        self._check(self._lib.cuInit(0), "cuInit")

    def _check(self, status: int, call: str) -> None:
        if status != 0:
            raise DeviceError(f"{call} failed with CUresult {status}")

    def pointer_device(self, address: int) -> int:
        ordinal = ctypes.c_int(-1)
        status = self._lib.cuPointerGetAttribute(
            ctypes.byref(ordinal), ctypes.c_int(self.CU_POINTER_ATTRIBUTE_DEVICE_ORDINAL), ctypes.c_uint64(address)
        )
        self._check(status, "cuPointerGetAttribute(DEVICE_ORDINAL)")
        return ordinal.value

    def stream_synchronize(self, stream: int) -> None:
        self._check(self._lib.cuStreamSynchronize(ctypes.c_void_p(stream)), "cuStreamSynchronize")

    def stream_is_capturing(self, stream: int) -> bool:
        """Whether ``stream`` is in a CUDA graph capture: active, or already invalidated (a wait
        from outside is no more legal there; the capture reports its failure when it ends)."""
        status = ctypes.c_int(self.CU_STREAM_CAPTURE_STATUS_NONE)
        call = self._lib.cuStreamIsCapturing(ctypes.c_void_p(stream), ctypes.byref(status))
        self._check(call, "cuStreamIsCapturing")
        return status.value != self.CU_STREAM_CAPTURE_STATUS_NONE

    def stream_wait(self, consumer: int, producer: int) -> None:
        """Orders ``consumer`` after the work enqueued on ``producer`` so far, on the device (an
        event recorded on one and waited for by the other), without blocking the host."""
        event = ctypes.c_void_p()
        flags = ctypes.c_uint(self.CU_EVENT_DISABLE_TIMING)
        self._check(self._lib.cuEventCreate(ctypes.byref(event), flags), "cuEventCreate")
        try:
            self._check(self._lib.cuEventRecord(event, ctypes.c_void_p(producer)), "cuEventRecord")
            wait = self._lib.cuStreamWaitEvent(ctypes.c_void_p(consumer), event, ctypes.c_uint(0))
            self._check(wait, "cuStreamWaitEvent")
        finally:
            self._lib.cuEventDestroy_v2(event)


_driver: Optional[_Driver] = None


def cuda_driver() -> _Driver:
    global _driver
    if _driver is None:
        _driver = _Driver()
    return _driver
