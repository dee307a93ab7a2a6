"""Every bad input raises its exception: TypeError / ValueError naming the argument for a wrong
dtype or shape, and the exception named after the C error code, with the library's message,
for what the library rejects."""

import pickle

import numpy as np
import pytest

import minkq
from minkq import _native
from oracle import rolled_sheet


@pytest.fixture
def mesh():
    return rolled_sheet(5, 0)


@pytest.fixture
def scene(device, mesh):
    return minkq.Scene(*mesh, device=device)


@pytest.mark.parametrize(
    "change, error, match",
    [
        (lambda v, t: (v, t.astype(np.float32)), TypeError, r"triangles: expected int32 values, got float32 \(floats are not rounded"),
        (lambda v, t: (v.astype(np.complex64), t), TypeError, r"vertices: expected float32 values, got complex64"),
        (lambda v, t: (v, t.astype(bool)), TypeError, r"triangles: expected int32 values, got bool"),
        (lambda v, t: (v[:, :2].copy(), t), ValueError, r"vertices: expected shape \(n, 3\), got \(25, 2\)"),
        (lambda v, t: (v.ravel(), t), ValueError, r"vertices: expected shape \(n, 3\), got \(75,\)"),
        (lambda v, t: (v, t[:, :2].copy()), ValueError, r"triangles: expected shape \(n, 3\), got \(32, 2\)"),
        (lambda v, t: ("vertices", t), TypeError, r"vertices: expected an \(n, 3\) array, got 'vertices'"),
        (lambda v, t: ([[0.5, 1.0, 2.0]], [[0.0, 1.0, 2.0]]), TypeError, r"triangles: expected int32 values, got float64"),
    ],
)
def test_wrong_dtype_or_shape_names_the_argument(device, mesh, change, error, match):
    with pytest.raises(error, match=match):
        minkq.Scene(*change(*mesh), device=device)


def test_wrong_edges_device_and_out_arguments(device, mesh):
    with pytest.raises(ValueError, match=r"edges: expected shape \(n, 2\), got \(4, 3\)"):
        minkq.Scene(*mesh, edges=np.zeros((4, 3), np.int32), device=device)
    with pytest.raises(TypeError, match="device: expected 'cpu', 'cuda:N', a minkq.Device, a torch.device or a Warp device, got int"):
        minkq.Scene(*mesh, device=42)
    with pytest.raises(TypeError, match="spec: expected a str"):
        minkq.Device(0)
    scene = minkq.Scene(*mesh, device=device)
    with pytest.raises(TypeError, match="out: expected an int32 array, got int64"):
        scene.query("vt", 0.1, out=np.zeros((4, 2), np.int64))
    with pytest.raises(ValueError, match=r"out: expected shape \(capacity, 2\), got \(4, 3\)"):
        scene.query("vt", 0.1, out=np.zeros((4, 3), np.int32))
    with pytest.raises(ValueError, match="out: expected a C-contiguous array"):
        scene.query("vt", 0.1, out=np.zeros((4, 4), np.int32)[:, :2])
    readonly = np.zeros((4, 2), np.int32)
    readonly.flags.writeable = False
    with pytest.raises(ValueError, match="out: the array is read-only"):
        scene.query("vt", 0.1, out=readonly)
    with pytest.raises(TypeError, match="out: expected a numpy array"):
        scene.query("vt", 0.1, out=[[0, 0]])


def test_wrong_kind_mode_and_radius_name_the_argument(scene):
    with pytest.raises(ValueError, match="kind: expected one of 'vt', 'ee', 'vv', 'ev', got 'tv'"):
        scene.query("tv", 0.1)
    with pytest.raises(ValueError, match="mode: expected one of 'box', 'sphere', 'capsule_ray', 'capsule_exact', got 'exact'"):
        scene.query("vt", 0.1, mode="exact")
    with pytest.raises(TypeError, match="radius: expected a number, got str"):
        scene.query("vt", "0.1")
    # The native layer checks on its own too.
    with pytest.raises(ValueError, match="mode: expected"):
        scene._native.query_into(np.zeros((1, 2), np.int32), "vt", "exact", 0.1, False, False, False)
    with pytest.raises(TypeError, match="out: expected a i32 array"):
        scene._native.query_into(np.zeros((1, 2), np.int64), "vt", "box", 0.1, False, False, False)
    # A byte-swapped array (pyo3 0.17 alone would read it as native): refused, not read swapped.
    swapped = np.zeros((1, 2), np.dtype(np.int32).newbyteorder())
    with pytest.raises(TypeError, match="out: expected native byte order"):
        scene._native.query_into(swapped, "vt", "box", 0.1, False, False, False)


def test_byte_swapped_vertices_are_refused_by_the_native_layer(device, mesh):
    xyz, tris = mesh
    swapped = xyz.astype(xyz.dtype.newbyteorder())
    assert np.array_equal(swapped, xyz)  # the same values, the other byte order
    with pytest.raises(TypeError, match="vertices: expected native byte order"):
        _native.Scene(device._native, swapped, tris, None, True, True, False, False, True, False)
    with pytest.raises(TypeError, match="vertices: expected native byte order"):
        _native.Scene(device._native, swapped.astype(">f8"), tris, None, True, True, False, False, True, True)
    # The package converts it (one copy in native order) before the native layer sees it.
    scene = minkq.Scene(swapped, tris, device=device)
    assert np.array_equal(scene.query("vt", 0.1, canonical=True), minkq.Scene(xyz, tris, device=device).query("vt", 0.1, canonical=True))


def test_non_finite_vertex(device, mesh):
    xyz, tris = mesh
    xyz = xyz.copy()
    xyz[3, 1] = np.nan
    with pytest.raises(minkq.NonFiniteError, match=r"^vertex 3 has a non-finite coordinate") as e:
        minkq.Scene(xyz, tris, device=device)
    assert isinstance(e.value, minkq.MinkqError) and isinstance(e.value, ValueError)
    assert e.value.status == 2 and e.value.status_name == "MINKQ_ERROR_NON_FINITE"


def test_index_out_of_range(device, mesh):
    xyz, tris = mesh
    bad = tris.copy()
    bad[4, 2] = 25
    with pytest.raises(minkq.IndexOutOfRangeError, match="triangle 4 references vertex 25 but the scene has 25 vertices"):
        minkq.Scene(xyz, bad, device=device)
    bad[4, 2] = -1
    with pytest.raises(minkq.IndexOutOfRangeError):
        minkq.Scene(xyz, bad, device=device)
    with pytest.raises(minkq.IndexOutOfRangeError, match="edge 0 references vertex 99"):
        minkq.Scene(xyz, tris, edges=np.array([[0, 99]], np.int32), device=device)
    with pytest.raises(minkq.IndexOutOfRangeError, match=r"triangles\[0, 2\] = 1099511627776 does not fit in int32"):
        minkq.Scene(xyz, [[0, 1, 2**40]], device=device)


def test_invalid_arguments(device, mesh, scene):
    with pytest.raises(minkq.InvalidArgumentError, match="asks for no query"):
        minkq.Scene(*mesh, vt=False, ee=False, device=device)
    with pytest.raises(minkq.InvalidArgumentError, match="radius -0.5 is negative"):
        scene.query("vt", -0.5, mode="sphere")
    with pytest.raises(minkq.InvalidArgumentError, match="sphere mode needs point queries"):
        scene.query("ee", 0.1, mode="sphere")
    with pytest.raises(minkq.InvalidArgumentError, match="unknown device spec"):
        minkq.Device("tpu")
    with pytest.raises(minkq.InvalidArgumentError, match="refit with 24 vertices but the scene has 25"):
        scene.refit(mesh[0][:-1])
    with pytest.raises(minkq.InvalidArgumentError, match="^rebuild with 24 vertices but the scene has 25$"):
        scene.rebuild(mesh[0][:-1])
    with pytest.raises(ValueError, match=r"vertices: expected shape \(n, 3\), got \(25, 2\)"):
        scene.rebuild(mesh[0][:, :2].copy())
    with pytest.raises(TypeError, match="vertices: expected float32 values, got complex128"):
        scene.rebuild(mesh[0].astype(np.complex128))


def test_non_finite_radius(scene):
    with pytest.raises(minkq.NonFiniteError, match="radius inf is not finite"):
        scene.query("vt", float("inf"), mode="sphere")
    with pytest.raises(minkq.NonFiniteError):
        scene.query("ee", 1e39, mode="capsule_exact")  # rounds to an infinite float


def test_failed_refit_keeps_the_previous_positions(device, mesh, scene):
    before = scene.query_digest("ee", 0.2, mode="capsule_exact")
    moved = mesh[0] * 2
    moved[7, 0] = np.inf
    with pytest.raises(minkq.NonFiniteError, match="vertex 7"):
        scene.refit(moved)
    after = scene.query_digest("ee", 0.2, mode="capsule_exact")
    assert before[1] == after[1]


def test_failed_rebuild_keeps_the_previous_positions_and_trees(device, mesh, scene):
    scene.refit(mesh[0] * np.array([3, 1, 0.5], np.float32))  # stretched: the trees have grown
    before = scene.query_digest("ee", 0.2, mode="capsule_exact")
    growth = scene.tree_growth()
    assert growth != 1.0
    moved = mesh[0] * 2
    moved[7, 0] = np.nan
    with pytest.raises(minkq.NonFiniteError, match=r"^vertex 7 has a non-finite coordinate"):
        scene.rebuild(moved)
    with pytest.raises(minkq.InvalidArgumentError, match="rebuild with 26 vertices"):
        scene.rebuild(np.concatenate([mesh[0], mesh[0][:1]]))
    assert scene.query_digest("ee", 0.2, mode="capsule_exact")[1] == before[1]
    assert scene.tree_growth() == growth


def test_unsupported_cuda():
    if minkq.cuda_device_count() > 0:
        pytest.skip("a CUDA device is present")
    with pytest.raises(minkq.UnsupportedError):
        minkq.Device("cuda")


def test_bvh_bad_input(device):
    with pytest.raises(minkq.InvalidArgumentError, match="box 1 has lo > hi"):
        minkq.BVH(np.array([[0, 0, 0, 1, 1, 1], [0, 0, 0, 1, -1, 1]], np.float32), device=device)
    with pytest.raises(minkq.NonFiniteError, match="box 0 has a non-finite coordinate"):
        minkq.BVH(np.array([[[0, 0, np.nan], [1, 1, 1]]], np.float32), device=device)
    with pytest.raises(ValueError, match=r"boxes: expected shape \(n, 2, 3\)"):
        minkq.BVH(np.zeros((3, 3, 3), np.float32), device=device)
    bvh = minkq.BVH(np.array([[[0, 0, 0], [1, 1, 1]]], np.float32), device=device)
    segments = np.zeros((1, 2, 3), np.float32)
    with pytest.raises(minkq.InvalidArgumentError, match="sphere mode needs point queries"):
        bvh.query("capsule", segments, 0.1, mode="sphere")
    with pytest.raises(minkq.InvalidArgumentError, match="box queries support only MINKQ_MODE_BOX"):
        bvh.query("box", np.zeros((1, 2, 3), np.float32), mode="sphere")
    with pytest.raises(ValueError, match=r"centres: expected shape \(n, 3\)"):
        bvh.query("sphere", segments, 0.1)
    with pytest.raises(ValueError, match="shape: expected one of 'sphere', 'capsule', 'box', got 'cone'"):
        bvh.query("cone", segments, 0.1)
    with pytest.raises(minkq.NonFiniteError, match="query point 0"):
        bvh.query("sphere", np.array([[np.inf, 0, 0]], np.float32), 0.1)
    with pytest.raises(minkq.InvalidArgumentError, match="refit with 2 boxes but the bvh has 1"):
        bvh.refit(np.zeros((2, 6), np.float32))
    with pytest.raises(minkq.InvalidArgumentError, match="^rebuild with 2 boxes but the bvh has 1$"):
        bvh.rebuild(np.zeros((2, 6), np.float32))
    with pytest.raises(minkq.InvalidArgumentError, match="box 0 has lo > hi"):
        bvh.rebuild(np.array([[[0, 0, 0], [1, -1, 1]]], np.float32))
    with pytest.raises(minkq.NonFiniteError, match="box 0 has a non-finite coordinate"):
        bvh.rebuild(np.array([[[0, 0, 0], [1, np.inf, 1]]], np.float32))
    with pytest.raises(ValueError, match=r"boxes: expected shape \(n, 2, 3\)"):
        bvh.rebuild(np.zeros((1, 3, 3), np.float32))
    # The failed rebuilds kept the box and its tree.
    assert bvh.query("sphere", np.array([[0.5, 0.5, 0.5]], np.float32)).tolist() == [[0, 0]]
    assert bvh.tree_growth() == 1.0


@pytest.mark.parametrize(
    "status, cls, base",
    [
        (1, minkq.InvalidArgumentError, ValueError),
        (2, minkq.NonFiniteError, ValueError),
        (3, minkq.IndexOutOfRangeError, ValueError),
        (4, minkq.SizeOverflowError, OverflowError),
        (5, minkq.CapacityError, minkq.MinkqError),
        (6, minkq.UnsupportedError, minkq.MinkqError),
        (7, minkq.OutOfMemoryError, MemoryError),
        (8, minkq.DeviceError, RuntimeError),
        (9, minkq.InternalError, RuntimeError),
        (42, minkq.MinkqError, Exception),
    ],
)
def test_each_c_status_raises_its_exception(status, cls, base):
    # The mapping the extension applies to every failed call (minkq::Error -> exception).
    with pytest.raises(cls, match="^the message$") as e:
        _native._raise_status(status, "the message")
    assert type(e.value) is cls and isinstance(e.value, minkq.MinkqError) and isinstance(e.value, base)
    assert e.value.status == status and e.value.message == "the message"


def test_the_exceptions_are_the_extensions_and_pickle():
    # Defined once, by the extension that raises them; the package re-exports the same classes.
    for name in minkq._errors.__all__:
        cls = getattr(minkq, name)
        assert cls is getattr(_native, name) and cls.__module__ == "minkq" and cls.__doc__, name
    e = pickle.loads(pickle.dumps(minkq.CapacityError("the message", 12)))
    assert type(e) is minkq.CapacityError and str(e) == "the message" and e.needed == 12 and e.status == 5
