"""The streams minkq._interop asks producers for and orders (issue 30, items 4 and 5), without a
GPU: stand-in producers and a stand-in of libcuda behind the real driver wrapper.

- The blocking path asks a CUDA DLPack producer for the legacy default stream (1), never the
  per-thread default stream (2), which PyTorch refuses.
- A stream-ordered call whose stream is being captured into a CUDA graph issues no event
  record or wait for a CUDA array interface stream outside it (CUDA's capture rules forbid the
  wait); a stream that is not capturing is ordered after the producer's as before."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

import minkq
from minkq import _interop
from test_interop import FakeCudaArrayInterface, FakeCudaDevice, FakeDriver

PRODUCER, CONSUMER, EVENT = 7, 9, 0xE7


class TorchLikeDLPack:
    """A CUDA DLPack producer that refuses the per-thread default stream as
    ``torch.Tensor.__dlpack__`` does; records the streams it is asked for."""

    def __init__(self, array: np.ndarray) -> None:
        self.array, self.streams = array, []

    def __dlpack_device__(self):
        return (_interop.DL_CUDA, 0)

    def __dlpack__(self, stream=None):
        self.streams.append(stream)
        if stream == 2:
            raise BufferError("per-thread default stream is not supported.")
        return self.array.__dlpack__()


def test_the_blocking_path_asks_dlpack_producers_for_the_legacy_default_stream():
    xyz = np.zeros((3, 3), np.float32)
    fake = TorchLikeDLPack(xyz)
    view = _interop.view(fake, "vertices", FakeCudaDevice(0))
    assert fake.streams == [1]
    assert (view.address, view.shape) == (xyz.ctypes.data, (3, 3))  # the stand-in hands over host memory
    # The stream-ordered calls still pass their own stream (1 for CUDA's NULL stream).
    for handle, asked in ((0, 1), (0x1234, 0x1234)):
        fake = TorchLikeDLPack(xyz)
        _interop.view(fake, "vertices", FakeCudaDevice(0), handle)
        assert fake.streams == [asked]


def test_a_capturing_stream_waits_on_no_event_from_outside_the_capture(monkeypatch):
    driver = FakeDriver()
    monkeypatch.setattr(_interop, "_driver", driver)
    gpu = FakeCudaDevice(0)
    array = np.zeros((3, 3), np.float32)
    driver.capturing = {CONSUMER}
    _interop.view(FakeCudaArrayInterface(array, stream=PRODUCER), "vertices", gpu, CONSUMER)
    assert driver.waits == [] and driver.synchronised == []
    driver.capturing = set()
    _interop.view(FakeCudaArrayInterface(array, stream=PRODUCER), "vertices", gpu, CONSUMER)
    assert driver.waits == [(CONSUMER, PRODUCER)] and driver.synchronised == []


class FakeLibcuda:
    """The libcuda.so.1 entry points _interop._Driver calls, recording them; streams in
    ``capturing`` report CU_STREAM_CAPTURE_STATUS_ACTIVE."""

    def __init__(self, capturing=(), capture_status_result: int = 0) -> None:
        self.capturing, self.capture_status_result, self.calls = set(capturing), capture_status_result, []

    @staticmethod
    def _handle(pointer: ctypes.c_void_p) -> int:
        return pointer.value or 0

    def cuPointerGetAttribute(self, out, attribute, address):
        out._obj.value = 0
        return 0

    def cuStreamIsCapturing(self, stream, status):
        self.calls.append(("cuStreamIsCapturing", self._handle(stream)))
        status._obj.value = 1 if self._handle(stream) in self.capturing else 0
        return self.capture_status_result

    def cuEventCreate(self, event, flags):
        event._obj.value = EVENT
        self.calls.append(("cuEventCreate",))
        return 0

    def cuEventRecord(self, event, stream):
        self.calls.append(("cuEventRecord", self._handle(event), self._handle(stream)))
        return 0

    def cuStreamWaitEvent(self, stream, event, flags):
        self.calls.append(("cuStreamWaitEvent", self._handle(stream), self._handle(event)))
        return 0

    def cuEventDestroy_v2(self, event):
        self.calls.append(("cuEventDestroy_v2", self._handle(event)))
        return 0


def driver_over(monkeypatch, lib: FakeLibcuda) -> _interop._Driver:
    """The real driver wrapper over ``lib`` (its constructor loads libcuda and calls cuInit)."""
    driver = _interop._Driver.__new__(_interop._Driver)
    driver._lib = lib
    monkeypatch.setattr(_interop, "_driver", driver)
    return driver


def test_the_driver_records_and_waits_only_outside_a_capture(monkeypatch):
    gpu = FakeCudaDevice(0)
    array = np.zeros((3, 3), np.float32)
    lib = FakeLibcuda(capturing={CONSUMER})
    driver_over(monkeypatch, lib)
    _interop.view(FakeCudaArrayInterface(array, stream=PRODUCER), "vertices", gpu, CONSUMER)
    assert lib.calls == [("cuStreamIsCapturing", CONSUMER)], "an event was recorded or waited for inside a capture"

    lib = FakeLibcuda()
    driver_over(monkeypatch, lib)
    _interop.view(FakeCudaArrayInterface(array, stream=PRODUCER), "vertices", gpu, CONSUMER)
    assert lib.calls == [
        ("cuStreamIsCapturing", CONSUMER),
        ("cuEventCreate",),
        ("cuEventRecord", EVENT, PRODUCER),
        ("cuStreamWaitEvent", CONSUMER, EVENT),
        ("cuEventDestroy_v2", EVENT),
    ]
    # The producer's own stream needs no ordering, capturing or not.
    lib.calls.clear()
    _interop.view(FakeCudaArrayInterface(array, stream=PRODUCER), "vertices", gpu, PRODUCER)
    assert lib.calls == []


def test_a_failed_capture_query_raises_a_device_error(monkeypatch):
    lib = FakeLibcuda(capture_status_result=201)  # CUDA_ERROR_INVALID_CONTEXT
    driver_over(monkeypatch, lib)
    with pytest.raises(minkq.DeviceError, match="cuStreamIsCapturing failed with CUresult 201"):
        array = FakeCudaArrayInterface(np.zeros((3, 3), np.float32), stream=PRODUCER)
        _interop.view(array, "vertices", FakeCudaDevice(0), CONSUMER)
    assert [c[0] for c in lib.calls] == ["cuStreamIsCapturing"]
