"""The stream-ordered scene calls (Scene.reserve, refit_async, rebuild_async, query_async,
query_vt_ee_async, async_status). On the CPU they run to completion on host memory (numpy and
Warp CPU arrays) and follow the rules they follow on CUDA: the blocking calls' pairs, exact
counts with nothing written past a short array, arrays reused across steps, missing
reservations refused at once, a non-finite vertex reported by async_status (the scene keeps its
positions). The stream arguments and the CUDA paths of the array protocols run against
stand-ins; the tests marked ``gpu`` capture the calls into a CUDA graph and skip, with the
reason, where there is no GPU."""

from __future__ import annotations

import numpy as np
import pytest

import minkq
from minkq import _interop
from oracle import rolled_sheet
from test_interop import FakeCudaArrayInterface, FakeCudaDevice, FakeCudaDLPack, FakeDriver

R = 0.04
QUERIES = [("vt", "sphere", False), ("vt", "box", True), ("ee", "capsule_exact", False), ("ee", "box", True)]
GUARD = -7


@pytest.fixture
def mesh():
    return rolled_sheet(12, 3)


def moved(xyz: np.ndarray, step: int) -> np.ndarray:
    """The sheet turned a little about y and shrunk: every vertex moves, the pairs change."""
    a = 0.05 * step
    c, s = np.cos(a), np.sin(a)
    rot = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return ((xyz @ rot.T) * (1 - 0.02 * step)).astype(np.float32)


def blocking(scene: minkq.Scene, kind: str, mode: str, leaf_exact: bool) -> np.ndarray:
    return scene.query(kind, R, mode=mode, leaf_exact=leaf_exact, canonical=True)


def guarded(capacity: int, extra: int = 16) -> np.ndarray:
    return np.full((capacity + extra, 2), GUARD, np.int32)


def test_async_queries_give_the_blocking_pairs_and_exact_counts(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    scene.reserve(canonical_capacity=4096)
    count = np.zeros(1, np.uint64)
    for kind, mode, leaf_exact in QUERIES:
        expected = blocking(scene, kind, mode, leaf_exact)
        assert len(expected) > 10, (kind, mode)
        for capacity in (4096, len(expected)):
            storage = guarded(capacity)
            scene.query_async(storage[:capacity], count, kind, R, mode=mode, leaf_exact=leaf_exact, canonical=True)
            assert int(count[0]) == len(expected)
            assert np.array_equal(storage[: len(expected)], expected), (kind, mode, capacity)
            assert (storage[capacity:] == GUARD).all(), "wrote past the array"
        for capacity in (0, 1, len(expected) - 1):
            storage = guarded(capacity)
            scene.query_async(storage[:capacity], count, kind, R, mode=mode, leaf_exact=leaf_exact, canonical=True)
            assert int(count[0]) == len(expected), (kind, mode, capacity)
            assert (storage[capacity:] == GUARD).all(), "wrote past the array"
            written = {tuple(p) for p in storage[:capacity]}  # `capacity` of the pairs, any order
            assert len(written) == capacity and written <= {tuple(p) for p in expected}, (kind, mode, capacity)
        # Not canonical: the same set; an int64 count works alike.
        storage, signed = guarded(len(expected), 0), np.full(1, -1, np.int64)
        scene.query_async(storage, signed, kind, R, mode=mode, leaf_exact=leaf_exact)
        assert signed[0] == len(expected)
        assert np.array_equal(storage[np.lexsort((storage[:, 1], storage[:, 0]))], expected)


def test_async_steps_reuse_arrays_and_match_fresh_scenes(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    scene.reserve(refit=True, rebuild=True, canonical_capacity=4096)
    scene.reserve(refit=True, canonical_capacity=8)  # reservations only grow
    vt_pairs, ee_pairs = guarded(4096), guarded(4096)
    vt_count, ee_count = np.zeros(1, np.uint64), np.zeros(1, np.uint64)
    for step in range(1, 6):
        vertices = moved(xyz, step)
        (scene.rebuild_async if step % 2 == 0 else scene.refit_async)(vertices)
        scene.query_vt_ee_async(
            vt_pairs[:4096], vt_count, ee_pairs[:4096], ee_count, R, ee_mode="capsule_exact", leaf_exact=True, canonical=True
        )
        scene.async_status()
        reference = minkq.Scene(vertices, tris, device=device)
        vt, ee = reference.query_vt_ee(R, ee_mode="capsule_exact", leaf_exact=True, canonical=True)
        assert np.array_equal(vt_pairs[: int(vt_count[0])], vt), step
        assert np.array_equal(ee_pairs[: int(ee_count[0])], ee), step
        assert (vt_pairs[4096:] == GUARD).all() and (ee_pairs[4096:] == GUARD).all()
        assert np.array_equal(scene.query("ee", R, canonical=True), reference.query("ee", R, canonical=True))
        if step % 2 == 0:
            assert scene.tree_growth() == 1.0
    # A short EE array: both counts exact, VT written in full, EE as far as it holds.
    vt, ee = scene.query_vt_ee(R, canonical=True)
    short = guarded(len(ee) - 1)
    scene.query_vt_ee_async(vt_pairs[:4096], vt_count, short[: len(ee) - 1], ee_count, R, canonical=True)
    assert (int(vt_count[0]), int(ee_count[0])) == (len(vt), len(ee))
    assert np.array_equal(vt_pairs[: len(vt)], vt) and (short[len(ee) - 1:] == GUARD).all()
    assert {tuple(p) for p in short[: len(ee) - 1]} <= {tuple(p) for p in ee}


def test_missing_reservations_and_bad_arguments_are_refused_at_once(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    before = blocking(scene, "ee", "box", False)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.refit_async(moved(xyz, 1))
    with pytest.raises(minkq.InvalidArgumentError):
        scene.rebuild_async(moved(xyz, 1))
    assert np.array_equal(blocking(scene, "ee", "box", False), before)
    pairs, count = np.zeros((64, 2), np.int32), np.zeros(1, np.uint64)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.query_async(pairs, count, "ee", R, canonical=True)  # no canonical capacity
    scene.query_async(pairs, count, "ee", R)  # a plain query needs none
    assert int(count[0]) == len(before)
    scene.reserve(refit=True, canonical_capacity=32)
    scene.refit_async(moved(xyz, 1))
    with pytest.raises(minkq.InvalidArgumentError):
        scene.rebuild_async(moved(xyz, 1))  # refit does not cover rebuilds
    with pytest.raises(minkq.InvalidArgumentError):
        scene.query_async(pairs, count, "ee", R, canonical=True)  # 64 over 32 reserved
    scene.query_async(pairs[:32], count, "ee", R, canonical=True)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.refit_async(xyz[:10])
    with pytest.raises(minkq.InvalidArgumentError):
        scene.query_async(pairs, count, "ee", R, mode="sphere")
    with pytest.raises(minkq.NonFiniteError):
        scene.query_async(pairs, count, "ee", float("nan"))
    with pytest.raises(minkq.InvalidArgumentError):
        scene.query_vt_ee_async(pairs, count, pairs.copy(), count, R)  # one count for both
    # Python-side checks, naming the argument.
    with pytest.raises(TypeError, match="out_count: expected a uint64 or int64 array, got float64"):
        scene.query_async(pairs, np.zeros(1), "vt", R)
    with pytest.raises(ValueError, match=r"out_count: expected shape \(1,\), got \(2,\)"):
        scene.query_async(pairs, np.zeros(2, np.uint64), "vt", R)
    with pytest.raises(ValueError, match="out_count: the array is read-only"):
        scene.query_async(pairs, _readonly(), "vt", R)
    with pytest.raises(TypeError, match="out_count: expected a \\(1,\\) uint64 numpy array"):
        scene.query_async(pairs, [0], "vt", R)
    with pytest.raises(ValueError, match=r"out_pairs: expected shape \(capacity, 2\)"):
        scene.query_async(np.zeros((4, 3), np.int32), count, "vt", R)
    with pytest.raises(ValueError, match=r"ee_pairs: expected shape \(capacity, 2\)"):
        scene.query_vt_ee_async(pairs, count, np.zeros(4, np.int32), np.zeros(1, np.uint64), R)
    with pytest.raises(TypeError, match="canonical_capacity: expected an int"):
        scene.reserve(canonical_capacity=1.5)
    with pytest.raises(ValueError, match="canonical_capacity: expected a count >= 0"):
        scene.reserve(canonical_capacity=-1)


def _readonly() -> np.ndarray:
    count = np.zeros(1, np.uint64)
    count.setflags(write=False)
    return count


def test_a_non_finite_vertex_is_raised_by_async_status_and_the_scene_keeps_its_positions(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    scene.reserve(refit=True, rebuild=True, canonical_capacity=4096)
    before = [blocking(scene, *q) for q in QUERIES]
    pairs, count = np.zeros((4096, 2), np.int32), np.zeros(1, np.uint64)
    for call, value in (("refit", np.nan), ("rebuild", np.inf), ("refit", -np.inf)):
        bad = moved(xyz, 3)
        bad[12, 1] = value
        getattr(scene, f"{call}_async")(bad)  # accepted at once
        for q, expected in zip(QUERIES, before):
            assert np.array_equal(blocking(scene, *q), expected), (call, q)
            scene.query_async(pairs, count, q[0], R, mode=q[1], leaf_exact=q[2], canonical=True)
            assert np.array_equal(pairs[: int(count[0])], expected), (call, q)
        with pytest.raises(minkq.NonFiniteError, match=f"minkq_scene_{call}_async: vertex 12 "):
            scene.async_status()
        scene.async_status()  # cleared
    # The first refused call is the one reported; a later good refit still applies.
    bad = xyz.copy()
    bad[3, 0] = np.nan
    scene.refit_async(bad)
    scene.refit_async(moved(xyz, 2))
    with pytest.raises(minkq.NonFiniteError, match="vertex 3 "):
        scene.async_status()
    reference = minkq.Scene(moved(xyz, 2), tris, device=device)
    assert np.array_equal(blocking(scene, "ee", "box", False), blocking(reference, "ee", "box", False))


def test_streams_are_checked_and_ignored_on_the_cpu(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    scene.reserve()

    class WarpLikeStream:
        cuda_stream = 0x1234

    class CupyLikeStream:
        ptr = 0x5678

    for stream in (None, 0, 7, np.uint64(9), WarpLikeStream(), CupyLikeStream()):
        scene.refit_async(xyz, stream=stream)
        scene.async_status(stream=stream)
    with pytest.raises(TypeError, match="stream: expected None, an int"):
        scene.refit_async(xyz, stream="cuda:0")
    with pytest.raises(TypeError, match="stream: expected None, an int"):
        scene.async_status(stream=True)
    with pytest.raises(ValueError, match="stream: expected a cudaStream_t"):
        scene.query_async(np.zeros((4, 2), np.int32), np.zeros(1, np.uint64), "vt", R, stream=-1)
    assert _interop.stream_handle(WarpLikeStream(), device) == 0x1234
    assert _interop.stream_handle(None, device, (xyz,)) == 0


def test_the_current_stream_of_a_cuda_array_and_its_ordering(monkeypatch):
    """With stand-ins for a CUDA device and driver: stream=None takes the array's stream, a
    DLPack producer is asked for its tensor on the call's stream (1 for CUDA's NULL stream), and
    a CUDA array interface stream other than the call's is ordered before it on the device,
    never synchronised on the host."""
    gpu = FakeCudaDevice(0)
    array = np.zeros((3, 3), np.float32)
    assert _interop.stream_handle(None, gpu, (array, FakeCudaArrayInterface(array, stream=7))) == 7
    assert _interop.stream_handle(None, gpu, (FakeCudaArrayInterface(array, stream=1),)) == 0
    assert _interop.stream_handle(None, gpu, (FakeCudaArrayInterface(array, version=2),)) == 0
    assert _interop.stream_handle(None, FakeCudaDevice(0), ()) == 0
    for handle, asked in ((0x1234, 0x1234), (0, 1), (2, 2)):
        fake = FakeCudaDLPack(array)
        _interop.view(fake, "vertices", gpu, handle)
        assert fake.streams == [asked]

    driver = FakeDriver()
    monkeypatch.setattr(_interop, "_driver", driver)
    _interop.view(FakeCudaArrayInterface(array, stream=7), "vertices", gpu, 7)
    _interop.view(FakeCudaArrayInterface(array, stream=1), "vertices", gpu, 0)
    assert driver.waits == [] and driver.synchronised == []
    _interop.view(FakeCudaArrayInterface(array, stream=7), "vertices", gpu, 9)
    assert driver.waits == [(9, 7)] and driver.synchronised == []
    count = _interop.checked_count(_interop.view(FakeCudaArrayInterface(np.zeros(1, np.uint64)), "c", gpu, 7), "c")
    assert count.descriptor()[1:] == (8, 1, True)
    with pytest.raises(TypeError, match="c: expected a uint64 or int64 array, got int32"):
        _interop.checked_count(_interop.view(FakeCudaArrayInterface(np.zeros(1, np.int32)), "c", gpu, 7), "c")


def test_device_arrays_on_the_cpu_backend_are_refused_and_never_read(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    scene.reserve()
    fake = FakeCudaDLPack(xyz)
    with pytest.raises(minkq.InvalidArgumentError, match="^vertices: .*does not copy"):
        scene.refit_async(fake, stream=5)
    assert fake.streams == []
    with pytest.raises(minkq.InvalidArgumentError, match="^out_count: "):
        scene.query_async(np.zeros((4, 2), np.int32), FakeCudaArrayInterface(np.zeros(1, np.uint64)), "vt", R)


# ---- Warp (host arrays here; device arrays and graph capture where a GPU is) ----------------------


def test_warp_cpu_arrays(wp, device, mesh):
    xyz, tris = mesh
    positions = wp.array(xyz, dtype=wp.vec3, device="cpu")
    scene = minkq.Scene(positions, wp.array(tris, dtype=wp.int32, device="cpu"), device=device)
    reference = minkq.Scene(xyz, tris, device=device)
    scene.reserve(refit=True, rebuild=True, canonical_capacity=4096)
    pairs = wp.full((4096 + 16, 2), GUARD, dtype=wp.int32, device="cpu")
    count = wp.zeros(1, dtype=wp.uint64, device="cpu")
    for step in range(1, 4):
        vertices = moved(xyz, step)
        positions.assign(vertices)
        (scene.rebuild_async if step == 2 else scene.refit_async)(positions)
        reference.refit(vertices)
        scene.query_async(pairs[:4096], count, "ee", R, mode="capsule_exact", canonical=True)
        scene.async_status()
        n = int(count.numpy()[0])
        assert np.array_equal(pairs.numpy()[:n], reference.query("ee", R, mode="capsule_exact", canonical=True))
        assert (pairs.numpy()[4096:] == GUARD).all()
    expected = reference.query("vt", R, mode="sphere", canonical=True)
    short = wp.full((len(expected) - 1, 2), GUARD, dtype=wp.int32, device="cpu")
    signed = wp.zeros(1, dtype=wp.int64, device="cpu")
    scene.query_async(short, signed, "vt", R, mode="sphere", canonical=True)
    assert int(signed.numpy()[0]) == len(expected)  # and all but one of the pairs, in any order
    assert {tuple(p) for p in short.numpy()} <= {tuple(p) for p in expected} and not (short.numpy() == GUARD).any()
    with pytest.raises(TypeError, match="out_count: expected a uint64 or int64 array, got int32"):
        scene.query_async(short, wp.zeros(1, dtype=wp.int32, device="cpu"), "vt", R, mode="sphere")
    with pytest.raises(ValueError, match=r"out_count: expected shape \(1,\), got \(2,\)"):
        scene.query_async(short, wp.zeros(2, dtype=wp.uint64, device="cpu"), "vt", R, mode="sphere")
    bad = moved(xyz, 1)
    bad[5] = np.nan
    scene.refit_async(wp.array(bad, dtype=wp.vec3, device="cpu"))
    with pytest.raises(minkq.NonFiniteError, match="vertex 5 "):
        scene.async_status()


def _needs_cuda(wp) -> None:
    if minkq.cuda_device_count() == 0 or not wp.is_cuda_available():
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")


@pytest.mark.gpu
def test_warp_graph_capture_replays_refit_and_queries_over_moved_vertices(wp, mesh):
    _needs_cuda(wp)
    xyz, tris = mesh
    gpu = minkq.Device("cuda:0")
    positions = wp.array(xyz, dtype=wp.vec3, device="cuda:0")
    scene = minkq.Scene(positions, wp.array(tris, dtype=wp.int32, device="cuda:0"), device=gpu)
    capacity = 8192
    scene.reserve(refit=True, canonical_capacity=capacity)
    vt_pairs = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    ee_pairs = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    vt_count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    ee_count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    vt_both = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    ee_both = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    vt_both_count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    ee_both_count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    with wp.ScopedCapture(device="cuda:0") as capture:
        scene.refit_async(positions)  # on Warp's capture stream (stream=None)
        scene.query_async(vt_pairs, vt_count, "vt", R, leaf_exact=True, canonical=True)
        scene.query_async(ee_pairs, ee_count, "ee", R, mode="capsule_exact", canonical=True)
        scene.query_vt_ee_async(vt_both, vt_both_count, ee_both, ee_both_count, R, leaf_exact=True, canonical=True)
    reference = minkq.Scene(xyz, tris)
    stream = wp.get_stream("cuda:0")
    for step in range(1, 5):
        vertices = moved(xyz, step)
        positions.assign(vertices)  # on the same stream, before the replay
        wp.capture_launch(capture.graph)
        scene.async_status(stream)
        reference.refit(vertices)
        vt = reference.query("vt", R, leaf_exact=True, canonical=True)
        ee = reference.query("ee", R, mode="capsule_exact", canonical=True)
        assert int(vt_count.numpy()[0]) == len(vt) and np.array_equal(vt_pairs.numpy()[: len(vt)], vt), step
        assert int(ee_count.numpy()[0]) == len(ee) and np.array_equal(ee_pairs.numpy()[: len(ee)], ee), step
        vt_b, ee_b = reference.query_vt_ee(R, leaf_exact=True, canonical=True)
        assert np.array_equal(vt_both.numpy()[: int(vt_both_count.numpy()[0])], vt_b), step
        assert np.array_equal(ee_both.numpy()[: int(ee_both_count.numpy()[0])], ee_b), step
        # The blocking query of the GPU scene sees the replay's positions.
        blocking_vt = scene.query("vt", R, leaf_exact=True, canonical=True)
        assert np.array_equal(blocking_vt.numpy(), vt), step
    # A NaN during a replay: the scene keeps its positions, async_status names the vertex.
    bad = moved(xyz, 4)
    bad[12, 1] = np.nan
    positions.assign(bad)
    wp.capture_launch(capture.graph)
    with pytest.raises(minkq.NonFiniteError, match="minkq_scene_refit_async: vertex 12 "):
        scene.async_status(stream)
    assert np.array_equal(vt_pairs.numpy()[: int(vt_count.numpy()[0])], vt)


class _ProducedOn:
    """A Warp CUDA array behind a version-3 CUDA array interface that names another stream as
    its producer's, as CuPy and Numba arrays do."""

    def __init__(self, array, stream: int):
        self._array = array  # keeps the memory alive
        self.__cuda_array_interface__ = dict(array.__cuda_array_interface__, version=3, stream=stream)


@pytest.mark.gpu
def test_warp_capture_of_an_array_produced_on_a_stream_outside_the_capture(wp, mesh):
    # Issue 30, item 4: waiting on an event recorded on the producer's stream, outside the
    # capture, would invalidate the capture (ScopedCapture's end would raise); the caller has
    # finished the producer's work before capture began, as the module's docstring asks.
    _needs_cuda(wp)
    xyz, tris = mesh
    positions = wp.array(xyz, dtype=wp.vec3, device="cuda:0")
    scene = minkq.Scene(positions, wp.array(tris, dtype=wp.int32, device="cuda:0"), device=minkq.Device("cuda:0"))
    capacity = 8192
    scene.reserve(refit=True, canonical_capacity=capacity)
    producer = wp.Stream("cuda:0")
    assert int(producer.cuda_stream) != int(wp.get_stream("cuda:0").cuda_stream)
    pairs = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    wp.synchronize_device("cuda:0")
    with wp.ScopedCapture(device="cuda:0") as capture:
        scene.refit_async(_ProducedOn(positions, int(producer.cuda_stream)))
        scene.query_async(pairs, count, "vt", R, leaf_exact=True, canonical=True)
    reference = minkq.Scene(xyz, tris)
    for step in range(1, 4):
        vertices = moved(xyz, step)
        positions.assign(vertices)
        wp.capture_launch(capture.graph)
        scene.async_status(wp.get_stream("cuda:0"))
        reference.refit(vertices)
        expected = reference.query("vt", R, leaf_exact=True, canonical=True)
        assert int(count.numpy()[0]) == len(expected), step
        assert np.array_equal(pairs.numpy()[: len(expected)], expected), step
    # Outside a capture the same array is ordered after its producer's stream by an event.
    scene.refit_async(_ProducedOn(positions, int(producer.cuda_stream)))
    scene.async_status(wp.get_stream("cuda:0"))
    assert np.array_equal(scene.query("vt", R, leaf_exact=True, canonical=True).numpy(), expected)


@pytest.mark.gpu
def test_warp_cuda_arrays_on_an_explicit_stream_and_short_capacity(wp, mesh):
    _needs_cuda(wp)
    xyz, tris = mesh
    gpu = minkq.Device("cuda:0")
    scene = minkq.Scene(wp.array(xyz, dtype=wp.vec3, device="cuda:0"), wp.array(tris, dtype=wp.int32, device="cuda:0"), device=gpu)
    scene.reserve(refit=True, rebuild=True, canonical_capacity=4096)
    expected = minkq.Scene(xyz, tris).query("ee", R, canonical=True)
    stream = wp.Stream("cuda:0")
    positions = wp.array(xyz, dtype=wp.vec3, device="cuda:0")
    short = wp.zeros((len(expected) - 1, 2), dtype=wp.int32, device="cuda:0")
    count = wp.zeros(1, dtype=wp.int64, device="cuda:0")
    scene.rebuild_async(positions, stream=stream)
    scene.query_async(short, count, "ee", R, stream=stream)
    scene.async_status(stream)
    assert int(count.numpy()[0]) == len(expected)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.refit_async(xyz)  # host vertices on a CUDA device


@pytest.mark.gpu
def test_torch_cuda_graph_capture(mesh):
    torch = pytest.importorskip("torch")
    if minkq.cuda_device_count() == 0 or not torch.cuda.is_available():
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")
    xyz, tris = mesh
    positions = torch.from_numpy(xyz).cuda()
    scene = minkq.Scene(positions, torch.from_numpy(tris).cuda(), device=minkq.Device("cuda:0"))
    scene.reserve(refit=True, canonical_capacity=4096)
    pairs = torch.zeros((4096, 2), dtype=torch.int32, device="cuda:0")
    count = torch.zeros(1, dtype=torch.int64, device="cuda:0")
    graph = torch.cuda.CUDAGraph()
    torch.cuda.synchronize()
    with torch.cuda.graph(graph):  # torch's capture stream is its current stream
        scene.refit_async(positions)
        scene.query_async(pairs, count, "vt", R, mode="sphere", canonical=True)
    reference = minkq.Scene(xyz, tris)
    for step in range(1, 4):
        vertices = moved(xyz, step)
        positions.copy_(torch.from_numpy(vertices))
        graph.replay()
        torch.cuda.synchronize()
        reference.refit(vertices)
        expected = reference.query("vt", R, mode="sphere", canonical=True)
        assert int(count.item()) == len(expected)
        assert np.array_equal(pairs[: len(expected)].cpu().numpy(), expected), step
