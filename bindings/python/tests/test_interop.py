"""Arrays of other libraries, read in place: DLPack and the CUDA array interface (minkq._interop).

Without a GPU the protocol code runs on host memory: Warp CPU arrays and DLPack-only wrappers
of numpy arrays go through the same capsule parsing, checks and raw descriptors as device
arrays do; the CUDA paths (stream synchronisation, device ordinals) run against a stand-in of
the CUDA driver; device arrays given to the CPU backend must raise, never be copied. The tests
marked ``gpu`` need a GPU and skip, with the reason, where there is none."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import minkq
from minkq import _interop
from oracle import rolled_sheet


class DLPackOnly:
    """A host array visible only through DLPack (as a PyTorch CPU tensor is)."""

    def __init__(self, array: np.ndarray) -> None:
        self.array = array

    def __dlpack__(self, stream=None):
        assert stream is None, "a host array is asked for without a stream"
        return self.array.__dlpack__()

    def __dlpack_device__(self):
        return self.array.__dlpack_device__()


class FakeCudaDLPack:
    """Claims CUDA memory through DLPack; records the stream it is asked for."""

    def __init__(self, array: np.ndarray, ordinal: int = 0) -> None:
        self.array, self.ordinal, self.streams = array, ordinal, []

    def __dlpack_device__(self):
        return (_interop.DL_CUDA, self.ordinal)

    def __dlpack__(self, stream=None):
        self.streams.append(stream)
        return self.array.__dlpack__()


class FakeCudaArrayInterface:
    """A CUDA array interface over host memory (never read by the CPU backend)."""

    def __init__(self, array: np.ndarray, version: int = 3, stream=1, readonly=False) -> None:
        self.array = array
        interface = {
            "data": (array.ctypes.data, readonly),
            "shape": array.shape,
            "strides": None if array.flags.c_contiguous else array.strides,
            "typestr": array.dtype.str,
            "version": version,
        }
        if version >= 3:
            interface["stream"] = stream
        self.__cuda_array_interface__ = interface


class FakeCudaDevice:
    """What minkq._interop reads of a minkq.Device, for a CUDA device that is not here."""

    backend = "cuda"
    name = "cuda:0 (stand-in)"

    def __init__(self, ordinal: int = 0) -> None:
        self.ordinal = ordinal


class FakeDriver:
    """libcuda's calls as _interop uses them: records host synchronisations and stream waits;
    streams in ``capturing`` report a capture in progress."""

    def __init__(self, ordinal: int = 0) -> None:
        self.ordinal, self.synchronised, self.waits, self.capturing = ordinal, [], [], set()

    def pointer_device(self, address: int) -> int:
        return self.ordinal

    def stream_synchronize(self, stream: int) -> None:
        self.synchronised.append(stream)

    def stream_is_capturing(self, stream: int) -> bool:
        return stream in self.capturing

    def stream_wait(self, consumer: int, producer: int) -> None:
        self.waits.append((consumer, producer))


@pytest.fixture
def mesh():
    return rolled_sheet(12, 3)


def test_dlpack_host_arrays_are_read_in_place(device, mesh):
    xyz, tris = mesh
    reference = minkq.Scene(xyz, tris, device=device)
    before = sys.getrefcount(xyz)
    wrapped = DLPackOnly(xyz)
    view = _interop.view(wrapped, "vertices", device)
    assert view.address == xyz.ctypes.data and view.cuda is None and view.strides == (12, 4)
    del view
    scene = minkq.Scene(wrapped, DLPackOnly(tris), device=device)
    for kind, mode in (("vt", "sphere"), ("ee", "capsule_exact")):
        pairs, digest = scene.query_digest(kind, 0.04, mode=mode, leaf_exact=True)
        expected = reference.query_digest(kind, 0.04, mode=mode, leaf_exact=True)
        assert isinstance(pairs, np.ndarray) and np.array_equal(pairs, expected[0]) and digest == expected[1]
    # Every capsule was released after its call (the producer's deleter ran).
    del wrapped
    assert sys.getrefcount(xyz) == before


def test_strided_rows_are_read_in_place_and_inner_strides_rejected(device, mesh):
    xyz, tris = mesh
    padded = np.zeros((len(xyz), 4), np.float32)
    padded[:, :3] = xyz
    padded[:, 3] = np.nan  # never read
    rows = DLPackOnly(padded[:, :3])
    assert _interop.view(rows, "vertices", device).strides == (16, 4)
    scene = minkq.Scene(rows, tris, device=device)
    expected = minkq.Scene(xyz, tris, device=device).query_digest("ee", 0.03)[1]
    assert scene.query_digest("ee", 0.03)[1] == expected
    table = np.full((len(scene.edges()), 4), -1, np.int32)
    table[:, 2:] = scene.edges()
    explicit = minkq.Scene(xyz, tris, DLPackOnly(table[:, 2:]), device=device)
    assert explicit.query_digest("ee", 0.03)[1] == expected
    with pytest.raises(ValueError, match=r"vertices: expected rows of 12 contiguous bytes.*does not copy"):
        minkq.Scene(DLPackOnly(np.zeros((5, 6), np.float32)[:, ::2]), tris, device=device)
    with pytest.raises(ValueError, match="out: expected C-contiguous"):
        scene.query("vt", 0.03, out=DLPackOnly(np.zeros((10, 4), np.int32)[:, :2]))


def test_wrong_dtype_or_shape_names_the_argument(device, mesh):
    xyz, tris = mesh
    with pytest.raises(TypeError, match="vertices: expected a float32 or float64 array, got float16"):
        minkq.Scene(DLPackOnly(xyz.astype(np.float16)), tris, device=device)
    # Foreign int64 indices are converted as numpy's are (test_dtypes.py checks the range).
    assert minkq.Scene(xyz, DLPackOnly(tris.astype(np.int64)), device=device).triangle_count == len(tris)
    with pytest.raises(ValueError, match=r"edges: expected shape \(n, 2\), got \(4, 3\)"):
        minkq.Scene(xyz, tris, DLPackOnly(np.zeros((4, 3), np.int32)), device=device)
    scene = minkq.Scene(xyz, tris, device=device)
    with pytest.raises(TypeError, match="out: expected a int32 array, got float32"):
        scene.query("vt", 0.1, out=DLPackOnly(np.zeros((4, 2), np.float32)))
    with pytest.raises(TypeError, match="out: expected a numpy array or an array with __dlpack__"):
        scene.query("vt", 0.1, out=[[0, 0]])


def test_cuda_arrays_on_the_cpu_backend_raise_and_are_never_read(device, mesh):
    xyz, tris = mesh
    fake = FakeCudaDLPack(xyz)
    with pytest.raises(minkq.InvalidArgumentError, match=r"vertices: .* on cuda:0 \(DLPack\) cannot be read by the minkq device 'cpu.*does not copy"):
        minkq.Scene(fake, tris, device=device)
    assert fake.streams == [], "the producer was asked for its tensor"
    with pytest.raises(minkq.InvalidArgumentError, match=r"vertices: .*__cuda_array_interface__.*does not copy"):
        minkq.Scene(FakeCudaArrayInterface(xyz), tris, device=device)
    scene = minkq.Scene(xyz, tris, device=device)
    with pytest.raises(minkq.InvalidArgumentError, match="^vertices: "):
        scene.refit(FakeCudaArrayInterface(xyz))
    with pytest.raises(minkq.InvalidArgumentError, match="^out: "):
        scene.query("vt", 0.1, out=FakeCudaArrayInterface(np.zeros((8, 2), np.int32)))
    with pytest.raises(minkq.InvalidArgumentError, match="^like: "):
        scene.query("vt", 0.1, like=FakeCudaDLPack(np.zeros((1, 2), np.int32)))
    bvh = minkq.BVH(np.zeros((1, 2, 3), np.float32), device=device)
    with pytest.raises(minkq.InvalidArgumentError, match="^centres: "):
        bvh.query("sphere", FakeCudaArrayInterface(xyz), 0.1)
    with pytest.raises(minkq.InvalidArgumentError, match="^boxes: "):
        minkq.BVH(FakeCudaDLPack(np.zeros((1, 6), np.float32)), device=device)


def test_cuda_array_interface_stream_and_device_checks(monkeypatch, mesh):
    """The CUDA path of the protocol code, with a stand-in driver: version 3 streams are
    synchronised before minkq reads, other GPUs refused, read-only outputs refused."""
    xyz, _ = mesh
    driver = FakeDriver(ordinal=0)
    monkeypatch.setattr(_interop, "_driver", driver)
    gpu = FakeCudaDevice(0)
    view = _interop.view(FakeCudaArrayInterface(xyz, stream=7), "vertices", gpu)
    assert (view.address, view.cuda, view.shape, view.strides) == (xyz.ctypes.data, 0, xyz.shape, (12, 4))
    assert view.descriptor() == (xyz.ctypes.data, 12, len(xyz), True)
    assert driver.synchronised == [7]
    _interop.view(FakeCudaArrayInterface(xyz, stream=None), "vertices", gpu)
    _interop.view(FakeCudaArrayInterface(xyz, version=2), "vertices", gpu)
    assert driver.synchronised == [7], "no stream: the producer promises the data are ready"
    with pytest.raises(minkq.InvalidArgumentError, match=r"vertices: the array is on cuda:0 but the minkq device is 'cuda:0 \(stand-in\)'"):
        _interop.view(FakeCudaArrayInterface(xyz), "vertices", FakeCudaDevice(1))
    readonly = _interop.view(FakeCudaArrayInterface(np.zeros((4, 2), np.int32), readonly=True), "out", gpu)
    with pytest.raises(ValueError, match="out: the array is read-only"):
        _interop.checked(readonly, "out", np.int32, (2,), writable=True, packed=True)
    masked = FakeCudaArrayInterface(xyz)
    masked.__cuda_array_interface__["mask"] = object()
    with pytest.raises(TypeError, match="vertices: masked CUDA arrays are not supported"):
        _interop.view(masked, "vertices", gpu)


def test_dlpack_cuda_producers_are_asked_for_minkqs_stream():
    """DLPack: the consumer passes its stream; minkq works on the per-thread default stream,
    which is ordered after the legacy default stream (DLPack's 1) that the producer is asked
    for, so the producer orders its work before minkq's."""
    fake = FakeCudaDLPack(np.zeros((3, 3), np.float32), ordinal=0)
    _interop.view(fake, "vertices", FakeCudaDevice(0))
    assert fake.streams == [_interop.BLOCKING_STREAM] == [1]
    other = FakeCudaDLPack(np.zeros((3, 3), np.float32), ordinal=1)
    with pytest.raises(minkq.InvalidArgumentError, match="on cuda:1 but the minkq device"):
        _interop.view(other, "vertices", FakeCudaDevice(0))
    assert other.streams == []


def test_unknown_libraries_get_numpy_results_on_the_host(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(DLPackOnly(xyz), tris, device=device)
    assert isinstance(scene.query("vt", 0.03), np.ndarray)
    with pytest.raises(TypeError, match="pass a \\(capacity, 2\\) int32 array of your own to query_into"):
        _interop.allocate_pairs(_interop.Like("mylib", 0, None, "mylib.Array"), 4)


# ---- Warp (host here; device where a GPU is) ------------------------------------------------------


def test_warp_arrays_in_and_out(wp, device, mesh):
    xyz, tris = mesh
    positions = wp.array(xyz, dtype=wp.vec3, device="cpu")
    triangles = wp.array(tris, dtype=wp.int32, device="cpu")
    assert _interop.view(positions, "vertices", device).address == positions.ptr  # in place
    scene = minkq.Scene(positions, triangles, device=device)
    reference = minkq.Scene(xyz, tris, device=device)
    pairs = scene.query("ee", 0.04, mode="capsule_exact", leaf_exact=True, canonical=True)
    assert isinstance(pairs, wp.array) and pairs.device == positions.device and pairs.dtype == wp.int32
    assert np.array_equal(pairs.numpy(), reference.query("ee", 0.04, mode="capsule_exact", leaf_exact=True, canonical=True))
    assert isinstance(reference.query("vt", 0.04, like=positions), wp.array)
    # A first query that finds nothing (its array was allocated empty) gives an empty array.
    nothing = scene.query("vt", 0.0, leaf_exact=True)
    assert isinstance(nothing, wp.array) and nothing.shape == (0, 2)
    out = wp.full((4096, 2), -7, dtype=wp.int32, device="cpu")
    got, digest = scene.query_digest("vt", 0.04, mode="sphere", out=out)
    assert digest == reference.query_digest("vt", 0.04, mode="sphere")[1]
    assert (out.numpy()[len(got) :] == -7).all()
    with pytest.raises(minkq.CapacityError) as e:
        scene.query("vt", 0.04, mode="sphere", out=wp.zeros((1, 2), dtype=wp.int32, device="cpu"))
    assert e.value.needed == len(got)
    # Refit from a Warp array: the scene follows it.
    moved = wp.array(xyz * np.float32(0.8), dtype=wp.vec3, device="cpu")
    scene.refit(moved)
    reference.refit(xyz * np.float32(0.8))
    assert scene.query_digest("ee", 0.04)[1] == reference.query_digest("ee", 0.04)[1]


def test_warp_arrays_with_a_bvh(wp, device):
    rng = np.random.default_rng(5)
    lo = rng.random((50, 3)).astype(np.float32)
    boxes = np.concatenate([lo, lo + 0.1], axis=1)
    centres = rng.random((40, 3)).astype(np.float32)
    segments = rng.random((30, 2, 3)).astype(np.float32)
    bvh = minkq.BVH(wp.array(boxes, dtype=wp.float32, device="cpu"), device=device)
    reference = minkq.BVH(boxes, device=device)
    spheres = bvh.query("sphere", wp.array(centres, dtype=wp.vec3, device="cpu"), 0.05, canonical=True)
    assert isinstance(spheres, wp.array)
    assert np.array_equal(spheres.numpy(), reference.query("sphere", centres, 0.05, canonical=True))
    capsules = bvh.query_digest("capsule", wp.array(segments, dtype=wp.float32, device="cpu"), 0.02)
    assert capsules[1] == reference.query_digest("capsule", segments, 0.02)[1]
    bvh.refit(wp.array(boxes + np.float32(1), dtype=wp.float32, device="cpu"))
    reference.refit(boxes + np.float32(1))
    assert bvh.query_digest("box", boxes)[1] == reference.query_digest("box", boxes)[1]


@pytest.mark.gpu
def test_warp_cuda_arrays_are_read_and_written_on_the_gpu(wp, mesh):
    if minkq.cuda_device_count() == 0 or not wp.is_cuda_available():
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")
    xyz, tris = mesh
    gpu = minkq.Device("cuda:0")
    reference = minkq.Scene(xyz, tris)
    stream = wp.Stream("cuda:0")
    with wp.ScopedStream(stream):  # produced on a non-default stream: DLPack orders it before minkq's
        positions = wp.array(xyz, dtype=wp.vec3, device="cuda:0")
        scene = minkq.Scene(positions, wp.array(tris, dtype=wp.int32, device="cuda:0"))  # on the arrays' GPU
        pairs = scene.query("ee", 0.04, mode="capsule_exact", leaf_exact=True, canonical=True)
    assert isinstance(pairs, wp.array) and pairs.device.is_cuda
    assert (scene.device.backend, scene.device.ordinal) == (gpu.backend, gpu.ordinal)
    assert np.array_equal(pairs.numpy(), reference.query("ee", 0.04, mode="capsule_exact", leaf_exact=True, canonical=True))
    out = wp.empty((4096, 2), dtype=wp.int32, device="cuda:0")
    _, digest = scene.query_digest("vt", 0.04, mode="sphere", out=out)
    assert digest == reference.query_digest("vt", 0.04, mode="sphere")[1]
    with pytest.raises(minkq.InvalidArgumentError, match="does not copy device arrays"):
        reference.refit(positions)


@pytest.mark.gpu
def test_torch_cuda_tensors(mesh):
    torch = pytest.importorskip("torch")
    if minkq.cuda_device_count() == 0 or not torch.cuda.is_available():
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")
    xyz, tris = mesh
    scene = minkq.Scene(torch.from_numpy(xyz).cuda(), torch.from_numpy(tris).cuda(), device=minkq.Device("cuda:0"))
    pairs = scene.query("vt", 0.04, mode="sphere", canonical=True)
    assert isinstance(pairs, torch.Tensor) and pairs.is_cuda
    reference = minkq.Scene(xyz, tris).query("vt", 0.04, mode="sphere", canonical=True)
    assert np.array_equal(pairs.cpu().numpy(), reference)
    if torch.cuda.device_count() > 1:
        with pytest.raises(minkq.InvalidArgumentError, match="on cuda:1 but the minkq device"):
            scene.refit(torch.from_numpy(xyz).to("cuda:1"))
