"""Host arrays of other dtypes than minkq's (int64 / uint32 indices, as trimesh and most mesh
loaders give; float16 or byte-swapped vertices) are converted once into a copy; float32 / int32
C-contiguous numpy arrays are read in place; an index that does not fit in int32 is refused
naming the element; arrays of other libraries (DLPack, CUDA array interface) are never
converted. float64 vertices make a float64 scene (test_float64.py), which gives a float32
scene's pairs for values that are floats already."""

import numpy as np
import pytest

import minkq
from minkq import _args
from oracle import rolled_sheet

R = 0.05


@pytest.fixture
def mesh():
    return rolled_sheet(9, 3)


def _pairs(scene):
    return {
        (kind, mode): scene.query(kind, R, mode=mode, canonical=True)
        for kind, mode in (("vt", "box"), ("vt", "sphere"), ("ee", "box"), ("ee", "capsule_exact"))
    }


def _same(a, b):
    assert a.keys() == b.keys()
    for key in a:
        assert np.array_equal(a[key], b[key]), key
    assert sum(len(p) for p in a.values()) > 0


@pytest.mark.parametrize("vdtype", [np.float64, np.float16, ">f4"])
@pytest.mark.parametrize("tdtype", [np.int64, np.uint32, np.int16, ">i4"])
def test_other_dtypes_give_the_pairs_of_float32_int32(device, mesh, vdtype, tdtype):
    xyz, tris = mesh
    if np.dtype(vdtype) == np.float16:
        xyz = xyz.astype(np.float16).astype(np.float32)  # exactly representable in both
    if np.dtype(tdtype) == np.int16 and tris.max() > np.iinfo(np.int16).max:
        pytest.skip("mesh too large for int16 indices")
    exact = _pairs(minkq.Scene(xyz, tris, device=device))
    other = minkq.Scene(xyz.astype(vdtype), tris.astype(tdtype), device=device)
    _same(exact, _pairs(other))


def test_float64_refit_rebuild_edges_and_bvh_queries(device, mesh):
    xyz, tris = mesh
    moved = xyz * np.float32(1.01)
    exact = minkq.Scene(xyz, tris, device=device)
    other = minkq.Scene(xyz.astype(np.float64), tris.astype(np.int64), edges=exact.edges().astype(np.int64), device=device)
    exact.refit(moved)
    other.refit(moved.astype(np.float64))
    _same(_pairs(exact), _pairs(other))
    exact.rebuild(moved)
    other.rebuild(moved.astype(np.float64))
    _same(_pairs(exact), _pairs(other))

    boxes = np.concatenate([xyz[tris].min(1), xyz[tris].max(1)], axis=1)
    bvh32, bvh64 = minkq.BVH(boxes, device=device), minkq.BVH(boxes.astype(np.float64), device=device)
    for shape, queries, r in (("sphere", xyz, R), ("capsule", xyz[exact.edges()], R), ("box", boxes, 0.0)):
        a = bvh32.query(shape, queries, r, canonical=True)
        b = bvh64.query(shape, queries.astype(np.float64), r, canonical=True)
        assert len(a) and np.array_equal(a, b), shape


def test_conversion_copies_and_exact_dtypes_are_read_in_place(mesh):
    xyz, tris = mesh
    # Exact dtypes, C-contiguous: the caller's arrays themselves go to the extension.
    assert _args._rows(xyz, "vertices", np.float32, (3,)) is xyz
    assert _args._rows(tris, "triangles", np.int32, (3,)) is tris
    # Other dtypes: one copy in minkq's dtype; the caller's array is left as it was.
    xyz64, tris64 = xyz.astype(np.float64), tris.astype(np.int64)
    before = tris64.copy()
    v = _args._rows(xyz64, "vertices", np.float32, (3,))
    t = _args._rows(tris64, "triangles", np.int32, (3,))
    assert v.dtype == np.float32 and v.flags.c_contiguous and not np.shares_memory(v, xyz64)
    assert t.dtype == np.int32 and t.flags.c_contiguous and not np.shares_memory(t, tris64)
    assert np.array_equal(v, xyz) and np.array_equal(t, tris) and np.array_equal(tris64, before)
    # A strided int64 array is converted once (astype gives a contiguous array), not twice.
    strided = np.zeros((8, 6), np.int64)[:, ::2]
    assert _args._rows(strided, "triangles", np.int32, (3,)).flags.c_contiguous


@pytest.mark.parametrize("value, where", [(2**31, "[4, 1]"), (2**40, "[4, 1]"), (-(2**31) - 1, "[4, 1]")])
def test_index_that_does_not_fit_in_int32_is_refused_naming_the_element(device, mesh, value, where):
    xyz, tris = mesh
    bad = tris.astype(np.int64)
    bad[4, 1] = value
    with pytest.raises(minkq.IndexOutOfRangeError, match=rf"triangles\{where[:-1]}\] = {value} does not fit in int32"):
        minkq.Scene(xyz, bad, device=device)
    with pytest.raises(minkq.IndexOutOfRangeError, match=r"edges\[0, 0\] = 4294967296"):
        minkq.Scene(xyz, tris, edges=np.array([[2**32, 1]], np.uint64), device=device)
    # Never wrapped around: 2**32 + 1 as int32 would be the valid index 1.
    wrapped = tris.astype(np.int64)
    wrapped[0, 0] = 2**32 + 1
    with pytest.raises(minkq.IndexOutOfRangeError, match="does not fit in int32"):
        minkq.Scene(xyz, wrapped, device=device)


def test_index_in_int32_but_past_the_vertices_is_the_library_s_error(device, mesh):
    xyz, tris = mesh
    bad = tris.astype(np.int64)
    bad[2, 0] = len(xyz)
    with pytest.raises(minkq.IndexOutOfRangeError) as info:
        minkq.Scene(xyz, bad, device=device)
    assert "does not fit" not in str(info.value)  # the C library's own index check


class _Foreign:
    """A host array of another library: DLPack only (as a Warp CPU array, a torch tensor)."""

    def __init__(self, array):
        self._array = array

    def __dlpack__(self, stream=None):
        return self._array.__dlpack__()

    def __dlpack_device__(self):
        return self._array.__dlpack_device__()


def test_arrays_of_other_libraries_stay_strict(device, mesh):
    xyz, tris = mesh
    minkq.Scene(_Foreign(xyz), _Foreign(tris), device=device)  # exact dtypes: read in place
    assert minkq.Scene(_Foreign(xyz.astype(np.float64)), tris, device=device).dtype == np.float64  # read in place
    with pytest.raises(TypeError, match=r"vertices: expected a float32 or float64 array, got float16"):
        minkq.Scene(_Foreign(xyz.astype(np.float16)), tris, device=device)
    # Foreign integer indices (PyTorch's int64 faces) are converted as numpy's are, range checked.
    want = minkq.Scene(xyz, tris, device=device).query("vt", 0.05, canonical=True)
    got = minkq.Scene(xyz, _Foreign(tris.astype(np.int64)), device=device).query("vt", 0.05, canonical=True)
    assert np.array_equal(got, want)
    far = tris.astype(np.int64)
    far[1, 2] = 2**32 + int(far[1, 2])  # would wrap around to a valid index in int32
    with pytest.raises(minkq.IndexOutOfRangeError, match=r"triangles\[1, 2\] = 4294967\d+ does not fit in int32"):
        minkq.Scene(xyz, _Foreign(far), device=device)
    with pytest.raises(TypeError, match=r"triangles: expected a int32 array, got float32"):
        minkq.Scene(xyz, _Foreign(tris.astype(np.float32)), device=device)
