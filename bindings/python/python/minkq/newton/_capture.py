"""minkq.newton inside Warp graph captures: the host calls a CPU graph records and replays
(:class:`ReplayError`, :func:`capture_launch`), pausing a capture, and the pass buffers a graph
keeps (see the package's documentation)."""

from __future__ import annotations

import contextlib
import ctypes
from typing import Any, Optional

import warp as wp

from . import _compat


# ---- Graph capture on the CPU: host calls recorded as kernel launches ----------------------
#
# Warp's CPU graphs (APIC) record kernel launches, memsets and copies and replay them in C++;
# a Python call made during the capture runs once, at record time, and never again. What a
# replay does repeat is a kernel, and a CPU kernel may call a host function pointer: each
# detector method called inside a CPU capture records one launch of _host_call_kernel
# (dim 1) whose token names the method's body with its arguments, and the replay calls back
# into Python to run that body eagerly (no capture is active then) on the current data.


class ReplayError(RuntimeError):
    """A detector method recorded into a Warp CPU graph failed while the graph was replayed
    (``wp.capture_launch``); raised by the detector's next call or :meth:`check_replays`, or by
    :func:`capture_launch`, with the original exception as ``__cause__``."""


_HostCall = ctypes.CFUNCTYPE(None, ctypes.c_uint64)
# token -> (detector weakref, method name, body, arguments, vertex_positions at record time); an
# entry lives as long as the graph that recorded it.
_recorded: dict = {}
_next_token = [1]


def _dispatch(token: int) -> None:
    # Called from a Warp CPU kernel during capture_launch. Nothing may escape into C: a failure
    # is kept on the detector (and printed) for the next call to raise.
    entry = _recorded.get(token)
    if entry is None:
        return
    ref, what, body, args, positions = entry
    detector = ref()
    if detector is None:
        return
    try:
        if wp.get_device("cpu").is_capturing:
            raise RuntimeError("a graph holding minkq's detection was replayed inside another CPU graph capture")
        detector.vertex_positions = positions  # as a graph bakes its pointers
        body(detector, *args)
        detector.replayed_calls += 1
    except BaseException as error:  # noqa: BLE001 - reported, never swallowed
        detector._replay_failed(what, error)


_dispatch_pointer_keepalive = _HostCall(_dispatch)
_DISPATCH = ctypes.cast(_dispatch_pointer_keepalive, ctypes.c_void_p).value


@wp.func_native(
    """
    #if !defined(__CUDA_ARCH__)  // host code only: the module is compiled for CUDA devices too
    typedef void (*minkq_host_call)(unsigned long long);
    ((minkq_host_call)fn)(token);
    #endif
    """
)
def _call_host(fn: wp.uint64, token: wp.uint64): ...


@wp.kernel
def _host_call_kernel(fn: wp.uint64, token: wp.uint64):
    _call_host(fn, token)


def _graph_being_captured() -> Any:
    # The Graph object a CPU capture is recording into.
    return _compat.cpu_graph_being_captured()


def capture_launch(graph: Any) -> None:
    """``wp.capture_launch(graph)``, then raises :class:`ReplayError` if a minkq detector
    method recorded into a CPU graph failed during a replay (``wp.capture_launch`` itself
    cannot: the failure happens inside a kernel). Use it in place of ``wp.capture_launch``
    where a failure must stop the loop at once."""
    wp.capture_launch(graph)
    for ref, _, _, _, _ in list(_recorded.values()):
        detector = ref()
        if detector is not None:
            detector.check_replays()


# ---- Pausing a capture; the buffers a graph keeps ------------------------------------------


@contextlib.contextmanager
def _capture_paused(device: Any):
    """Runs the block outside a Warp graph capture in progress on ``device`` (Warp's
    ``capture_pause`` / ``capture_resume``), or as it is when none is."""
    if not getattr(device, "is_capturing", False):
        yield
        return
    graph = _compat.capture_pause(device)
    try:
        yield
    finally:
        _compat.capture_resume(graph, device)


class _Scratch:
    """Device arrays of one pass kept between calls, grown geometrically. While ``pinned`` is a
    list (inside a CUDA graph capture) every array handed out is also kept there: a graph bakes
    their addresses, so they must outlive any later growth. An array first needed inside a
    capture is allocated with the capture paused: a graph allocation would be freed with its
    graph, and is not memory minkq's device-pointer check accepts."""

    def __init__(self, device: Any) -> None:
        self.device = device
        self.arrays: dict = {}
        self.pinned: Optional[list] = None

    def get(self, name: str, dtype: Any, size: int, shape_tail: tuple = ()) -> wp.array:
        array = self.arrays.get(name)
        if array is None or array.shape[0] < size:
            capacity = max(size, 2 * (array.shape[0] if array is not None else 0), 16)
            with _capture_paused(self.device):
                array = wp.empty(shape=(capacity,) + shape_tail, dtype=dtype, device=self.device)
            self.arrays[name] = array
        if self.pinned is not None:
            self.pinned.append(array)
        return array
