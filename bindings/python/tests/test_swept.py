"""Swept positions (Scene.refit_swept, rebuild_swept, is_swept, refit_swept_async,
rebuild_swept_async, reserve(swept=True)): every vertex moves linearly from x0 to x1 over a
step and the queries report every pair whose elements come within r at some time of it. At zero
motion the static pairs; a vertex or an edge flying through another element is found by the
swept queries and by no static query at either end; every static contact at a time of the step
is among the swept pairs; float64 scenes keep their guarantee over the step; leaf-exact and the
EE segment modes are refused; a plain refit or rebuild ends the swept state. The stream-ordered
calls run on the CPU (numpy and Warp CPU arrays) and equal the blocking ones; a NaN leaves the
scene at rest, reported by async_status. The CUDA path of both arrays' streams runs against
stand-ins; the test marked ``gpu`` captures a swept step into a CUDA graph and skips, with the
reason, where there is no GPU."""

from __future__ import annotations

import numpy as np
import pytest

import minkq
from minkq import _interop
from oracle import rolled_sheet
from test_async import moved
from test_float64 import CASES, CROSSED, NO_TRIANGLES, TRIANGLE, crossed_edges, vertex_over_triangle
from test_float64 import R as R64
from test_interop import FakeCudaArrayInterface, FakeCudaDevice, FakeCudaDLPack, FakeDriver

R = 0.04
VT_MODES = ("box", "sphere", "capsule_ray", "capsule_exact")
STATIC_MODE = {"box": "box", "sphere": "sphere", "capsule_ray": "capsule_ray", "capsule_exact": "sphere"}
"""The static VT mode whose pairs a swept one gives at zero motion (a path that is a point)."""


@pytest.fixture
def mesh():
    return rolled_sheet(12, 3)


def flying_vertex(start: float = -1.0, end: float = 1.0):
    """Triangle 0 in the plane x = 0, still; vertex 3 moving along x from ``start`` to ``end``."""
    x0 = np.array([[0, -1, -1], [0, 2, -1], [0, -1, 2], [start, 0.1, 0.1]], np.float32)
    x1 = x0.copy()
    x1[3, 0] = end
    return x0, x1


def flying_edge():
    """Edge 0 along x at z = 0, still; edge 1 along y moving from z = 1 to z = -1 (crossing edge
    0 at t = 1/2); edge 2 along y at x = 5 moving alike, never near the others."""
    x0 = np.array([[-1, 0, 0], [1, 0, 0], [0, -1, 1], [0, 1, 1], [5, -1, 1], [5, 1, 1]], np.float32)
    x1 = x0.copy()
    x1[2:, 2] = -1
    return x0, x1, np.array([[0, 1], [2, 3], [4, 5]], np.int32)


def swept_pairs(scene: minkq.Scene) -> dict:
    """Every swept query the scene answers, canonical."""
    pairs = {("vt", mode): scene.query("vt", R, mode=mode, canonical=True) for mode in VT_MODES}
    pairs["ee", "box"] = scene.query("ee", R, canonical=True)
    return pairs


def same(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)


def test_zero_motion_gives_the_static_pairs(device, mesh):
    xyz, tris = mesh
    static = minkq.Scene(xyz, tris, device=device)
    for call in ("refit_swept", "rebuild_swept"):
        scene = minkq.Scene(xyz, tris, device=device)
        assert not scene.is_swept
        getattr(scene, call)(xyz, xyz)
        assert scene.is_swept
        sphere = static.query("vt", R, mode="sphere", canonical=True)
        assert len(sphere) > 100
        # The vertex's path is a point: capsule_exact (and sphere, the same) is the static sphere.
        assert np.array_equal(scene.query("vt", R, mode="capsule_exact", canonical=True), sphere), call
        for mode in VT_MODES:
            expected = static.query("vt", R, mode=STATIC_MODE[mode], canonical=True)
            assert np.array_equal(scene.query("vt", R, mode=mode, canonical=True), expected), (call, mode)
        ee = scene.query("ee", R, canonical=True)
        assert len(ee) > 100 and np.array_equal(ee, static.query("ee", R, canonical=True)), call
        vt, ee_both = scene.query_vt_ee(R, vt_mode="capsule_exact", canonical=True)
        assert np.array_equal(vt, sphere) and np.array_equal(ee_both, ee)


def test_a_vertex_flying_through_a_triangle_is_found_only_by_the_swept_queries(device):
    x0, x1 = flying_vertex()
    scene = minkq.Scene(x0, TRIANGLE, device=device)
    for x in (x0, x1):
        scene.refit(x)
        for mode in VT_MODES:
            assert len(scene.query("vt", R, mode=mode)) == 0, mode
            assert len(scene.query("vt", R, mode=mode, leaf_exact=True)) == 0, mode
    for call in ("refit_swept", "rebuild_swept"):
        getattr(scene, call)(x0, x1)
        for mode in VT_MODES:
            assert scene.query("vt", R, mode=mode).tolist() == [[3, 0]], (call, mode)
    # A path past the triangle's lower edge (crossing x = 0 at y = -1.2, at least 0.1 from the
    # triangle): its box reaches the triangle's (box mode), its capsule does not.
    start, end = x0.copy(), x0.copy()
    start[3], end[3] = (-0.2, -0.9, 0.1), (0.2, -1.5, 0.1)
    scene.refit_swept(start, end)
    assert scene.query("vt", R).tolist() == [[3, 0]]
    assert len(scene.query("vt", R, mode="capsule_exact")) == 0
    assert len(scene.query("vt", R, mode="sphere")) == 0


def test_an_edge_flying_through_an_edge_is_found_only_by_the_swept_query(device):
    x0, x1, edges = flying_edge()
    triangles = np.array([[0, 1, 2]], np.int32)  # the EE queries take the given edges
    scene = minkq.Scene(x0, triangles, edges, vt=False, device=device)
    for x in (x0, x1):
        scene.refit(x)
        assert len(scene.query("ee", R)) == 0
    scene.refit_swept(x0, x1)
    assert scene.query("ee", R).tolist() == [[0, 1]]
    scene.rebuild_swept(x1, x0)  # backwards: the same crossing
    assert scene.query("ee", R).tolist() == [[0, 1]]


def test_every_static_contact_during_the_step_is_a_swept_pair(device, mesh):
    """At sampled times t, the true contacts within 0.9 r at x(t) (the oracle of the static
    leaf-exact queries) are among the swept pairs within r."""
    xyz, tris = mesh
    x0, x1 = moved(xyz, 1), moved(xyz, 4)
    scene = minkq.Scene(x0, tris, device=device)
    scene.refit_swept(x0, x1)
    swept = {mode: {tuple(p) for p in scene.query("vt", R, mode=mode)} for mode in VT_MODES}
    swept_ee = {tuple(p) for p in scene.query("ee", R)}
    at_t = minkq.Scene(x0, tris, device=device)
    found_vt, found_ee = set(), set()
    for t in np.linspace(0, 1, 9):
        at_t.refit((x0 + t * (x1.astype(np.float64) - x0)).astype(np.float32))
        found_vt |= {tuple(p) for p in at_t.query("vt", 0.9 * R, leaf_exact=True)}
        found_ee |= {tuple(p) for p in at_t.query("ee", 0.9 * R, leaf_exact=True)}
    assert len(found_vt) > 100 and len(found_ee) > 100
    for mode in VT_MODES:
        assert found_vt <= swept[mode], mode
    assert found_ee <= swept_ee
    assert swept["capsule_exact"] <= swept["box"] and swept["sphere"] == swept["capsule_exact"]


@pytest.mark.parametrize("plane, point", CASES[:3])
def test_float64_swept_steps_find_the_pairs_rounding_pulls_apart(device, plane, point):
    """Within r in double only mid-step (the vertex passes over the triangle, the edge over the
    edge, from far to one side to far to the other); beyond r once rounded to float."""
    x0 = vertex_over_triangle(plane, point)
    x0[3, 1], x1 = -50.0, x0.copy()
    x1[3, 1] = 50.0
    scene = minkq.Scene(x0, TRIANGLE, ee=False, device=device)
    assert scene.dtype == np.float64 and len(scene.query("vt", R64, mode="capsule_exact")) == 0
    for call in ("refit_swept", "rebuild_swept"):
        getattr(scene, call)(x0, x1)
        for mode in VT_MODES:
            assert scene.query("vt", R64, mode=mode).tolist() == [[3, 0]], (call, mode)
    e0 = crossed_edges(plane, point)
    e0[2:, 1] -= 50.0
    e1 = e0.copy()
    e1[2:, 1] += 100.0
    edges = minkq.Scene(e0, NO_TRIANGLES, CROSSED, vt=False, device=device)
    edges.refit_swept(e0, e1)
    assert edges.query("ee", R64).tolist() == [[0, 1]]
    # The same steps rounded to float32 (float32 scenes) lose the pairs in every mode.
    rounded = minkq.Scene(x0.astype(np.float32), TRIANGLE, ee=False, device=device)
    rounded.refit_swept(x0.astype(np.float32), x1.astype(np.float32))
    assert all(len(rounded.query("vt", R64, mode=mode)) == 0 for mode in VT_MODES)
    rounded = minkq.Scene(e0.astype(np.float32), NO_TRIANGLES, CROSSED, vt=False, device=device)
    rounded.refit_swept(e0.astype(np.float32), e1.astype(np.float32))
    assert len(rounded.query("ee", R64)) == 0


def test_precision_and_shapes_are_checked_per_array(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    with pytest.raises(TypeError, match="^x1: got float64 values for a scene created from float32 vertices"):
        scene.refit_swept(xyz, xyz.astype(np.float64))
    with pytest.raises(ValueError, match=r"^x0: expected shape \(n, 3\)"):
        scene.rebuild_swept(xyz[:, :2], xyz)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.refit_swept(xyz, xyz[:-1])
    scene64 = minkq.Scene(xyz.astype(np.float64), tris, device=device)
    scene64.reserve(refit=True, swept=True)
    with pytest.raises(TypeError, match="^x0: expected float64 values, the dtype of the scene's vertices, got float32"):
        scene64.refit_swept_async(xyz, xyz.astype(np.float64))
    scene64.refit_swept_async(xyz.astype(np.float64), moved(xyz, 1).astype(np.float64))
    scene64.async_status()
    reference = minkq.Scene(xyz.astype(np.float64), tris, device=device)
    reference.refit_swept(xyz, moved(xyz, 1))  # converted exactly
    assert same(swept_pairs(scene64), swept_pairs(reference))


def test_leaf_exact_and_ee_segment_modes_are_refused_on_swept_positions(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    assert len(scene.query("ee", R, mode="capsule_exact", leaf_exact=True)) > 0  # static: fine
    scene.refit_swept(xyz, moved(xyz, 1))
    for kind, mode in (("vt", "box"), ("vt", "capsule_exact"), ("ee", "box")):
        with pytest.raises(minkq.UnsupportedError, match="MINKQ_QUERY_LEAF_EXACT on swept positions"):
            scene.query(kind, R, mode=mode, leaf_exact=True)
    for mode in ("capsule_ray", "capsule_exact"):
        with pytest.raises(minkq.UnsupportedError, match="swept EE queries run box mode only"):
            scene.query("ee", R, mode=mode)
    with pytest.raises(minkq.UnsupportedError, match="^ee_query: swept EE queries run box mode only"):
        scene.query_vt_ee(R, ee_mode="capsule_exact")
    with pytest.raises(minkq.UnsupportedError, match="^vt_query->flags asks for MINKQ_QUERY_LEAF_EXACT"):
        scene.query_vt_ee(R, leaf_exact=True)
    pairs, count = np.zeros((64, 2), np.int32), np.zeros(1, np.uint64)
    with pytest.raises(minkq.UnsupportedError):
        scene.query_async(pairs, count, "vt", R, leaf_exact=True)
    with pytest.raises(minkq.UnsupportedError):
        scene.query_async(pairs, count, "ee", R, mode="capsule_ray")


def test_a_plain_refit_or_rebuild_ends_the_swept_state(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    scene.reserve(refit=True, rebuild=True, swept=True)
    x1 = moved(xyz, 2)
    static = minkq.Scene(x1, tris, device=device)
    for plain in (scene.refit, scene.rebuild, scene.refit_async, scene.rebuild_async):
        scene.refit_swept(xyz, x1)
        assert scene.is_swept
        plain(x1)
        assert not scene.is_swept, plain.__name__
        assert np.array_equal(scene.query("ee", R, mode="capsule_exact", leaf_exact=True, canonical=True),
                              static.query("ee", R, mode="capsule_exact", leaf_exact=True, canonical=True))
    # An error keeps the swept state and positions.
    scene.rebuild_swept(xyz, x1)
    before = swept_pairs(scene)
    bad = x1.copy()
    bad[7, 2] = np.nan
    with pytest.raises(minkq.NonFiniteError, match="vertex 7 "):
        scene.refit_swept(xyz, bad)
    with pytest.raises(minkq.NonFiniteError):
        scene.refit(bad)
    assert scene.is_swept and same(swept_pairs(scene), before)


def test_async_swept_steps_on_the_cpu_equal_the_blocking_ones(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    reference = minkq.Scene(xyz, tris, device=device)
    scene.reserve(refit=True, rebuild=True, swept=True, canonical_capacity=4096)
    pairs, count = np.zeros((4096, 2), np.int32), np.zeros(1, np.uint64)
    vt_pairs, ee_pairs = np.zeros((4096, 2), np.int32), np.zeros((4096, 2), np.int32)
    vt_count, ee_count = np.zeros(1, np.uint64), np.zeros(1, np.uint64)
    for step in range(4):
        x0, x1 = moved(xyz, step), moved(xyz, step + 1)
        rebuild = step == 2
        (scene.rebuild_swept_async if rebuild else scene.refit_swept_async)(x0, x1, stream=7)  # ignored on the CPU
        (reference.rebuild_swept if rebuild else reference.refit_swept)(x0, x1)
        scene.async_status()
        assert scene.is_swept and same(swept_pairs(scene), swept_pairs(reference)), step
        scene.query_async(pairs, count, "vt", R, mode="capsule_exact", canonical=True)
        expected = reference.query("vt", R, mode="capsule_exact", canonical=True)
        assert int(count[0]) == len(expected) and np.array_equal(pairs[: len(expected)], expected), step
        scene.query_vt_ee_async(vt_pairs, vt_count, ee_pairs, ee_count, R, vt_mode="sphere", canonical=True)
        vt, ee = reference.query_vt_ee(R, vt_mode="sphere", canonical=True)
        assert np.array_equal(vt_pairs[: int(vt_count[0])], vt) and np.array_equal(ee_pairs[: int(ee_count[0])], ee)
        assert scene.tree_growth() == reference.tree_growth(), step


def test_a_nan_leaves_the_scene_at_rest_and_async_status_reports_it(device):
    near, far = flying_vertex(-0.5 * R)[0], flying_vertex()[0]  # vertex 3 within r, and 1 away
    scene = minkq.Scene(far, TRIANGLE, device=device)
    scene.reserve(refit=True, rebuild=True, swept=True)
    for call, end in (("refit", 1), ("rebuild", 0)):
        bad = (near.copy(), near.copy())
        bad[end][3, 1] = np.nan if end else np.inf
        getattr(scene, f"{call}_swept_async")(*bad)  # accepted at once
        # At rest at the positions the scene kept (far), not at this call's x0 (near).
        assert scene.is_swept and all(len(scene.query("vt", R, mode=mode)) == 0 for mode in VT_MODES), call
        with pytest.raises(minkq.NonFiniteError, match=f"^minkq_scene_{call}_swept_async: vertex 3 .*at rest"):
            scene.async_status()
        scene.async_status()  # cleared
        scene.refit(far)
    # After an accepted step near -> far, the start of that step is kept: the static pairs at near.
    scene.refit_swept_async(near, far)
    bad = far.copy()
    bad[0, 0] = np.nan
    scene.refit_swept_async(far, bad)
    static_near = minkq.Scene(near, TRIANGLE, device=device)
    for mode in VT_MODES:
        assert np.array_equal(scene.query("vt", R, mode=mode), static_near.query("vt", R, mode=STATIC_MODE[mode])), mode
    assert scene.query("vt", R, mode="sphere").tolist() == [[3, 0]]
    with pytest.raises(minkq.NonFiniteError, match="vertex 0 "):
        scene.async_status()


def test_missing_reservations_are_refused_at_once(device, mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)
    x1 = moved(xyz, 1)
    before = scene.query("ee", R, canonical=True)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.refit_swept_async(xyz, x1)
    scene.reserve(refit=True, rebuild=True)  # a plain step's reservation does not cover swept ones
    with pytest.raises(minkq.InvalidArgumentError, match="MINKQ_RESERVE_SWEPT"):
        scene.refit_swept_async(xyz, x1)
    with pytest.raises(minkq.InvalidArgumentError, match="MINKQ_RESERVE_SWEPT"):
        scene.rebuild_swept_async(xyz, x1)
    assert not scene.is_swept and np.array_equal(scene.query("ee", R, canonical=True), before)
    other = minkq.Scene(xyz, tris, device=device)
    other.reserve(refit=True, swept=True)  # covers refits only
    other.refit_swept_async(xyz, x1)
    with pytest.raises(minkq.InvalidArgumentError):
        other.rebuild_swept_async(xyz, x1)
    other.async_status()
    with pytest.raises(TypeError, match="stream: expected None, an int"):
        other.refit_swept_async(xyz, x1, stream="cuda:0")
    with pytest.raises(ValueError, match=r"^x1: expected shape \(n, 3\)"):
        other.refit_swept_async(xyz, x1[:, :2])


def test_both_arrays_streams_are_taken_and_ordered_as_a_refits(monkeypatch, device, mesh):
    """On a stand-in CUDA device and driver, with a stand-in for the extension: stream=None is
    the first array's stream; each array's stream is ordered before the call's (a CUDA array
    interface stream waited for on the device, a DLPack producer asked for the call's stream)."""
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris, device=device)

    class Native:
        """The extension's swept calls, recording their arguments."""

        def __init__(self) -> None:
            self.calls: list = []

        def __getattr__(self, name: str):
            return lambda *args: self.calls.append((name,) + args)

    native, driver = Native(), FakeDriver()
    monkeypatch.setattr(_interop, "_driver", driver)
    monkeypatch.setattr(scene, "device", FakeCudaDevice(0))
    monkeypatch.setattr(scene, "_native", native)
    x1 = moved(xyz, 1)
    scene.refit_swept_async(FakeCudaArrayInterface(xyz, stream=7), FakeCudaArrayInterface(x1, stream=5))
    assert native.calls == [
        ("refit_swept_async", (xyz.ctypes.data, 12, len(xyz), True), (x1.ctypes.data, 12, len(x1), True), 7)
    ]
    assert driver.waits == [(7, 5)] and driver.synchronised == []
    dlpack = FakeCudaDLPack(x1)
    scene.rebuild_swept_async(FakeCudaArrayInterface(xyz, stream=7), dlpack, stream=9)
    assert native.calls[-1][0] == "rebuild_swept_async" and native.calls[-1][3] == 9
    assert driver.waits[-1] == (9, 7) and dlpack.streams == [9]
    # The blocking swept calls synchronise a CUDA array interface stream before reading, as refit does.
    scene.refit_swept(FakeCudaArrayInterface(xyz, stream=3), x1)
    assert native.calls[-1][0] == "refit_swept" and native.calls[-1][2] is x1 and driver.synchronised == [3]


# ---- Warp (host arrays here; a captured swept step where a GPU is) ---------------------------------


def test_warp_cpu_arrays(wp, device, mesh):
    xyz, tris = mesh
    p0 = wp.array(xyz, dtype=wp.vec3, device="cpu")
    p1 = wp.array(moved(xyz, 2), dtype=wp.vec3, device="cpu")
    scene = minkq.Scene(p0, wp.array(tris, dtype=wp.int32, device="cpu"), device=device)
    reference = minkq.Scene(xyz, tris, device=device)
    reference.refit_swept(xyz, moved(xyz, 2))
    scene.refit_swept(p0, p1)
    pairs = scene.query("vt", R, mode="capsule_exact", canonical=True)
    assert isinstance(pairs, wp.array)  # results like the positions
    assert same(swept_pairs(scene), swept_pairs(reference))
    scene.reserve(refit=True, rebuild=True, swept=True)
    scene.rebuild_swept_async(p0, p1)
    scene.async_status()
    assert same(swept_pairs(scene), swept_pairs(reference))
    bad = moved(xyz, 2)
    bad[5] = np.nan
    scene.refit_swept_async(p0, wp.array(bad, dtype=wp.vec3, device="cpu"))
    with pytest.raises(minkq.NonFiniteError, match="vertex 5 "):
        scene.async_status()
    # Float64: wp.vec3d for a float64 scene, read in place; float32 Warp arrays refused.
    scene64 = minkq.Scene(wp.array(xyz.astype(np.float64), dtype=wp.vec3d, device="cpu"), tris, device=device)
    scene64.refit_swept(wp.array(xyz.astype(np.float64), dtype=wp.vec3d, device="cpu"),
                        wp.array(moved(xyz, 2).astype(np.float64), dtype=wp.vec3d, device="cpu"))
    assert same(swept_pairs(scene64), swept_pairs(reference))
    with pytest.raises(TypeError, match=r"^x1: expected float64 values.*got float32 \(warp, host memory\)"):
        scene64.refit_swept(xyz, p1)


@pytest.mark.gpu
def test_warp_graph_capture_replays_swept_steps(wp, mesh):
    if minkq.cuda_device_count() == 0 or not wp.is_cuda_available():
        pytest.skip("needs a CUDA GPU and a libminkq built with CUDA (none here)")
    xyz, tris = mesh
    gpu = minkq.Device("cuda:0")
    p0 = wp.array(xyz, dtype=wp.vec3, device="cuda:0")
    p1 = wp.array(xyz, dtype=wp.vec3, device="cuda:0")
    scene = minkq.Scene(p0, wp.array(tris, dtype=wp.int32, device="cuda:0"), device=gpu)
    capacity = 8192
    scene.reserve(refit=True, swept=True, canonical_capacity=capacity)
    vt_pairs = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    ee_pairs = wp.zeros((capacity, 2), dtype=wp.int32, device="cuda:0")
    vt_count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    ee_count = wp.zeros(1, dtype=wp.uint64, device="cuda:0")
    with wp.ScopedCapture(device="cuda:0") as capture:
        scene.refit_swept_async(p0, p1)  # on Warp's capture stream (stream=None)
        scene.query_vt_ee_async(vt_pairs, vt_count, ee_pairs, ee_count, R, vt_mode="capsule_exact", canonical=True)
    reference = minkq.Scene(xyz, tris)
    stream = wp.get_stream("cuda:0")
    for step in range(3):
        x0, x1 = moved(xyz, step), moved(xyz, step + 1)
        p0.assign(x0)
        p1.assign(x1)
        wp.capture_launch(capture.graph)
        scene.async_status(stream)
        assert scene.is_swept
        reference.refit_swept(x0, x1)
        vt, ee = reference.query_vt_ee(R, vt_mode="capsule_exact", canonical=True)
        assert int(vt_count.numpy()[0]) == len(vt) and np.array_equal(vt_pairs.numpy()[: len(vt)], vt), step
        assert int(ee_count.numpy()[0]) == len(ee) and np.array_equal(ee_pairs.numpy()[: len(ee)], ee), step
    bad = moved(xyz, 3)
    bad[12, 1] = np.nan
    p1.assign(bad)
    wp.capture_launch(capture.graph)
    with pytest.raises(minkq.NonFiniteError, match="minkq_scene_refit_swept_async: vertex 12 "):
        scene.async_status(stream)
