"""The conventions of numpy, Warp and PyTorch (issue 54): the device taken from the arrays or
given as device= in any spelling, mode="box" by default, out= into an array or a growing
PairBuffer, close() and with, foreign int64 indices converted with numpy's range check, and
the old spellings working with a DeprecationWarning."""

import types

import numpy as np
import pytest

import minkq
from oracle import rolled_sheet
from test_dtypes import _Foreign  # a host array of another library (DLPack only)

R = 0.04


@pytest.fixture(scope="module")
def mesh():
    return rolled_sheet(12, 9)


class _OnGpu(_Foreign):
    """An array that says it lives on cuda:1 (DLPack device type 2)."""

    def __dlpack_device__(self):
        return (2, 1)


def test_the_device_comes_from_the_arrays_or_device_in_any_spelling(mesh):
    xyz, tris = mesh
    want = minkq.Scene(xyz, tris, device=minkq.Device("cpu")).query("vt", R, canonical=True)
    torch_like = types.SimpleNamespace(type="cpu", index=None)  # what minkq reads of a torch.device
    warp_like = types.SimpleNamespace(alias="cpu", is_cuda=False, ordinal=-1)  # ... of a Warp device
    for device in (None, "cpu", minkq.Device("cpu"), torch_like, warp_like):
        scene = minkq.Scene(xyz, tris, device=device)
        assert scene.device.backend == "cpu", device
        assert np.array_equal(scene.query("vt", R, canonical=True), want), device
    # An array in CUDA memory picks its GPU: here, with no such GPU, creating it fails there.
    if minkq.cuda_device_count() < 2:
        with pytest.raises((minkq.UnsupportedError, minkq.DeviceError, minkq.InvalidArgumentError), match="(?i)cuda"):
            minkq.Scene(_OnGpu(xyz), tris)
    with pytest.raises(TypeError, match=r"vertices: expected an \(n, 3\) array, got 'cpu': the device is a keyword"):
        minkq.Scene("cpu", xyz, tris)
    with pytest.raises(TypeError, match="device: expected 'cpu', 'cuda:N', a minkq.Device, a torch.device or a Warp device, got int"):
        minkq.Scene(xyz, tris, device=0)
    with pytest.raises(ValueError, match=r"device: minkq runs on 'cpu' and 'cuda' devices, got torch.device\('mps'\)"):
        minkq.Scene(xyz, tris, device=types.SimpleNamespace(type="mps", index=None))
    boxes = np.stack([xyz - 0.01, xyz + 0.01], axis=1).astype(np.float32)
    assert minkq.BVH(boxes).device.backend == minkq.BVH(boxes, device="cpu").device.backend == "cpu"


def test_warp_devices_and_arrays_choose_the_cpu(mesh, wp):
    xyz, tris = mesh
    scene = minkq.Scene(wp.array(xyz, dtype=wp.vec3, device="cpu"), tris, device=wp.get_device("cpu"))
    assert scene.device.backend == "cpu"
    assert minkq.Scene(wp.array(xyz, dtype=wp.vec3, device="cpu"), tris).device.backend == "cpu"


def test_mode_is_box_by_default_everywhere(mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris)
    tighter = 0
    for kind, tight in (("vt", "sphere"), ("ee", "capsule_exact")):
        box = scene.query(kind, R, mode="box", canonical=True)
        assert np.array_equal(scene.query(kind, R, canonical=True), box)
        assert scene.count(kind, R) == len(box) == scene.work(kind, R).candidates
        assert scene.query_digest(kind, R)[1] == scene.query_digest(kind, R, mode="box")[1]
        # A tighter mode gives a subset, here a smaller one: the default really is box.
        tighter += len(scene.query(kind, R, mode=tight)) < len(box)
    assert tighter > 0
    bvh = minkq.BVH(np.array([[[0, 0, 0], [1, 1, 1]], [[2, 2, 2], [3, 3, 3]]], np.float32))
    centres = np.array([[1.5, 1.5, 1.5], [0.5, 0.5, 0.5]], np.float32)
    default = bvh.query("sphere", centres, 0.5, canonical=True)
    assert np.array_equal(default, bvh.query("sphere", centres, 0.5, mode="box", canonical=True))
    assert bvh.count("sphere", centres, 0.5) == len(default) == 3
    assert bvh.query("sphere", centres, 0.5, mode="sphere").tolist() == [[1, 0]]


def test_out_writes_into_an_array_or_a_growing_pair_buffer(mesh):
    xyz, tris = mesh
    scene = minkq.Scene(xyz, tris)
    want = scene.query("ee", R, canonical=True)
    out = np.full((len(want) + 3, 2), -1, np.int32)
    got = scene.query("ee", R, canonical=True, out=out)
    assert np.shares_memory(got, out) and np.array_equal(got, want) and (out[len(want) :] == -1).all()
    with pytest.raises(minkq.CapacityError) as e:
        scene.query("ee", R, out=np.zeros((len(want) - 1, 2), np.int32))
    assert e.value.needed == len(want)
    # A PairBuffer grows once, then is reused.
    buffer = minkq.PairBuffer()
    assert buffer.capacity == 0
    got = scene.query("ee", R, canonical=True, out=buffer)
    first = buffer.array
    assert np.array_equal(got, want) and np.shares_memory(got, first) and buffer.capacity >= len(want)
    got = scene.query("vt", R, canonical=True, out=buffer)
    assert np.array_equal(got, scene.query("vt", R, canonical=True))
    assert buffer.array is first or len(scene.query("vt", R)) > len(first)
    small = minkq.PairBuffer(np.zeros((1, 2), np.int32))
    assert np.array_equal(scene.query("ee", R, canonical=True, out=small), want) and small.capacity > len(want)
    # query_vt_ee: two outputs, VT's first.
    vt_buffer, ee_out = minkq.PairBuffer(), np.zeros((len(want), 2), np.int32)
    vt, ee = scene.query_vt_ee(R, canonical=True, out=(vt_buffer, ee_out))
    assert np.shares_memory(vt, vt_buffer.array) and np.shares_memory(ee, ee_out)
    assert np.array_equal(vt, scene.query("vt", R, canonical=True)) and np.array_equal(ee, want)
    with pytest.raises(minkq.CapacityError):
        scene.query_vt_ee(R, out=(vt_buffer, ee_out[:1]))
    with pytest.raises(TypeError, match=r"out: expected \(vt_out, ee_out\)"):
        scene.query_vt_ee(R, out=ee_out)
    # BVH queries too.
    bvh = minkq.BVH(np.stack([xyz - 0.01, xyz + 0.01], axis=1).astype(np.float32))
    bvh_buffer = minkq.PairBuffer()
    assert np.array_equal(bvh.query("sphere", xyz, R, canonical=True, out=bvh_buffer), bvh.query("sphere", xyz, R, canonical=True))


def test_out_takes_warp_arrays_and_pair_buffers_of_them(mesh, wp):
    xyz, tris = mesh
    scene = minkq.Scene(wp.array(xyz, dtype=wp.vec3, device="cpu"), tris)
    want = minkq.Scene(xyz, tris).query("vt", R, canonical=True)
    buffer = minkq.PairBuffer(wp.zeros((1, 2), dtype=wp.int32, device="cpu"))
    got = scene.query("vt", R, canonical=True, out=buffer)
    assert isinstance(got, wp.array) and isinstance(buffer.array, wp.array) and np.array_equal(got.numpy(), want)


def test_close_and_with_release_scenes_and_bvhs(mesh):
    xyz, tris = mesh
    with minkq.Scene(xyz, tris) as scene:
        assert not scene.closed and len(scene.query("vt", R)) > 0
    assert scene.closed and repr(scene) == "minkq.Scene(closed)"
    for call in (lambda: scene.query("vt", R), lambda: scene.refit(xyz), lambda: scene.vertex_count):
        with pytest.raises(ValueError, match="this minkq.Scene is closed"):
            call()
    scene.close()  # twice: harmless
    bvh = minkq.BVH(np.stack([xyz - 0.01, xyz + 0.01], axis=1).astype(np.float32))
    bvh.close()
    with pytest.raises(ValueError, match="this minkq.BVH is closed"):
        bvh.query("sphere", xyz, R)


def test_foreign_int64_indices_are_converted_like_numpys(mesh, wp):
    xyz, tris = mesh
    want = minkq.Scene(xyz, tris).query("ee", R, canonical=True)
    for triangles in (wp.array(tris.astype(np.int64), dtype=wp.int64, device="cpu"), _Foreign(tris.astype(np.int64)),
                      tris.astype(np.int64)):
        assert np.array_equal(minkq.Scene(xyz, triangles).query("ee", R, canonical=True), want)
    far = tris.astype(np.int64)
    far[3, 1] = -(2**40)
    for triangles in (far, _Foreign(far), wp.array(far, dtype=wp.int64, device="cpu")):
        with pytest.raises(minkq.IndexOutOfRangeError, match=r"triangles\[3, 1\] = -1099511627776 does not fit in int32"):
            minkq.Scene(xyz, triangles)
    edges = minkq.Scene(xyz, tris).edges()
    with pytest.raises(minkq.IndexOutOfRangeError, match=r"edges\[0, 0\] = 2147483648 does not fit in int32"):
        minkq.Scene(xyz, None, _Foreign(np.vstack([[2**31, 0], edges]).astype(np.int64)), vt=False, ee=False, ev=True)


def test_old_spellings_work_with_a_deprecation_warning(mesh):
    xyz, tris = mesh
    device = minkq.Device("cpu")
    scene = minkq.Scene(xyz, tris)
    want = scene.query("vt", R, mode="sphere", canonical=True)
    with pytest.warns(DeprecationWarning, match=r"Scene\(device, \.\.\.\) is deprecated .* use Scene\(\.\.\., device=device\)"):
        old = minkq.Scene(device, xyz, tris)
    assert old.device is device
    with pytest.warns(DeprecationWarning, match=r"query\(kind, mode, radius\) with a positional mode is deprecated"):
        assert np.array_equal(old.query("vt", "sphere", R, canonical=True), want)
    with pytest.warns(DeprecationWarning, match="count"):
        assert old.count("vt", "sphere", R) == len(want)
    with pytest.warns(DeprecationWarning, match="work"):
        assert old.work("vt", "sphere", R).candidates == len(want)
    with pytest.warns(DeprecationWarning, match="query_digest"):
        assert old.query_digest("vt", "sphere", R)[1] == scene.query_digest("vt", R, mode="sphere")[1]
    out = np.zeros((len(want), 2), np.int32)
    with pytest.warns(DeprecationWarning, match=r"query_into\(out, kind, mode, radius\) is deprecated"):
        assert old.query_into(out, "vt", "sphere", R, canonical=True).count == len(want)
    assert np.array_equal(out, want)
    count = np.zeros(1, np.uint64)
    with pytest.warns(DeprecationWarning, match="query_async"):
        old.query_async(out, count, "vt", "sphere", R, canonical=False)
    assert int(count[0]) == len(want)
    # Old scenes of vertices and edges, with the edges fourth.
    edges = scene.edges()
    with pytest.warns(DeprecationWarning):
        rods = minkq.Scene(device, xyz, None, edges, vt=False, ee=False, vv=True)
    assert rods.edge_count == len(edges)
    with pytest.warns(DeprecationWarning, match=r"Scene.from_geometries\(device, \.\.\.\)"):
        minkq.Scene.from_geometries(device, [minkq.Geometry(xyz, tris)])
    with pytest.warns(DeprecationWarning, match=r"BVH\(device, \.\.\.\)"):
        minkq.BVH(device, np.stack([xyz - 0.01, xyz + 0.01], axis=1).astype(np.float32))
    # Mixed spellings are refused rather than guessed.
    with pytest.raises(TypeError, match="got a mode positionally and mode= as well"):
        scene.query("vt", "sphere", R, mode="capsule_exact")
    with pytest.raises(TypeError, match="got a minkq.Device first and device= as well"):
        minkq.Scene(device, xyz, tris, device="cpu")


def test_deprecation_warnings_name_the_callers_line(mesh):
    """Python shows a DeprecationWarning by default where it is attributed to __main__: each
    must name the line of the old spelling, not a line inside minkq."""
    xyz, tris = mesh
    device = minkq.Device("cpu")
    scene = minkq.Scene(xyz, tris)
    boxes = np.stack([xyz - 0.01, xyz + 0.01], axis=1).astype(np.float32)
    old_spellings = {
        "Scene": lambda: minkq.Scene(device, xyz, tris),
        "from_geometries": lambda: minkq.Scene.from_geometries(device, [minkq.Geometry(xyz, tris)]),
        "BVH": lambda: minkq.BVH(device, boxes),
        "query": lambda: scene.query("vt", "sphere", R),
        "query_async": lambda: scene.query_async(np.zeros((1, 2), np.int32), np.zeros(1, np.uint64), "vt", "box", R),
        "query_into": lambda: scene.query_into(np.zeros((4096, 2), np.int32), "vt", "box", R),
        "BVH.query_into": lambda: minkq.BVH(boxes).query_into(np.zeros((4096, 2), np.int32), "box", boxes),
    }
    for name, call in old_spellings.items():
        with pytest.warns(DeprecationWarning) as record:
            call()
        assert [w.filename for w in record] == [__file__], name
