"""Float64 vertices (a MINKQ_SCENE_FLOAT64 scene): read as doubles, in place, never rounded by
the package; every pair within r in double is reported in every mode, also pairs that rounding
to float carries past r (a float32 scene of the rounded positions loses them). float32 input is
converted exactly on the blocking host calls of a float64 scene; float64 input for a float32
scene, and other dtypes where nothing is converted (arrays of other libraries, the
stream-ordered calls), raise TypeError naming the argument and both dtypes."""

import numpy as np
import pytest

import minkq
from minkq import _args, _interop
from oracle import rolled_sheet
from test_interop import DLPackOnly

R = 1e-3
VT_MODES = ("box", "sphere", "capsule_ray", "capsule_exact")
EE_MODES = ("box", "capsule_ray", "capsule_exact")


def pulled_apart(base: float, r: float, wanted: int):
    """(plane, point) pairs, point - plane = f r for f in 0.90..0.999, that rounding to nearest
    float puts more than r apart (tests/test_float64.cpp's pulled_apart): float distances near
    `base` are multiples of its spacing u, which must exceed r (2^-9 at 2e4 against r = 1e-3)."""
    u = float(np.spacing(np.float32(base)))
    found = []
    for fraction in (0.90, 0.93, 0.95, 0.97, 0.99, 0.999):
        for k in range(64):
            if len(found) == wanted:
                return found
            plane = base + (k / 64 - 0.5) * u
            point = plane + fraction * r
            if float(np.float32(point)) - float(np.float32(plane)) > r:
                found.append((plane, point))
                break
    return found


CASES = pulled_apart(2e4, R, 6)
TRIANGLE = np.array([[0, 1, 2]], np.int32)
NO_TRIANGLES = np.zeros((0, 3), np.int32)
CROSSED = np.array([[0, 1], [2, 3]], np.int32)


def vertex_over_triangle(plane: float, point: float) -> np.ndarray:
    """A triangle in the plane x = plane and vertex 3 at x = point (distance point - plane)."""
    return np.array([[plane, -1, -1], [plane, 2, -1], [plane, -1, 2], [point, 0, 0]], np.float64)


def crossed_edges(plane: float, point: float) -> np.ndarray:
    """Edge 0 along y at x = plane, edge 1 along z at x = point (distance point - plane)."""
    return np.array([[plane, -1, 0], [plane, 1, 0], [point, 0, -1], [point, 0, 1]], np.float64)


def test_the_cases_are_within_r_in_double_and_beyond_r_in_float():
    assert len(CASES) == 6
    for plane, point in CASES:
        assert 0.89 * R < point - plane < R
        assert float(np.float32(point)) - float(np.float32(plane)) > R


@pytest.mark.parametrize("plane, point", CASES)
def test_pairs_that_rounding_pulls_apart_are_found_in_every_mode(device, plane, point):
    vt64 = minkq.Scene(vertex_over_triangle(plane, point), TRIANGLE, ee=False, device=device)
    ee64 = minkq.Scene(crossed_edges(plane, point), NO_TRIANGLES, CROSSED, vt=False, device=device)
    assert vt64.dtype == ee64.dtype == np.float64
    assert repr(vt64) == "minkq.Scene(4 vertices, 1 triangles, 0 edges, float64)"
    for leaf_exact in (False, True):
        for mode in VT_MODES:
            assert vt64.query("vt", R, mode=mode, leaf_exact=leaf_exact).tolist() == [[3, 0]], (mode, leaf_exact)
        for mode in EE_MODES:
            assert ee64.query("ee", R, mode=mode, leaf_exact=leaf_exact).tolist() == [[0, 1]], (mode, leaf_exact)
    # The rounded positions as a float32 scene (what float64 input used to become): the leaf
    # test rightly finds them beyond r.
    vt32 = minkq.Scene(vertex_over_triangle(plane, point).astype(np.float32), TRIANGLE, ee=False, device=device)
    ee32 = minkq.Scene(crossed_edges(plane, point).astype(np.float32), NO_TRIANGLES, CROSSED, vt=False, device=device)
    assert vt32.dtype == ee32.dtype == np.float32
    assert len(vt32.query("vt", R, leaf_exact=True)) == 0
    assert len(ee32.query("ee", R, leaf_exact=True)) == 0


def test_float64_refit_and_rebuild_find_the_pairs_rounding_pulls_apart(device):
    (plane, point), (plane2, point2) = CASES[0], CASES[-1]
    far = vertex_over_triangle(plane, point)
    far[3, 0] += 1.0  # the vertex a whole unit away: no pair
    scene = minkq.Scene(far, TRIANGLE, ee=False, device=device)
    assert len(scene.query("vt", R)) == 0
    scene.refit(vertex_over_triangle(plane, point))
    assert scene.query("vt", R, leaf_exact=True).tolist() == [[3, 0]]
    scene.rebuild(far)
    assert len(scene.query("vt", R)) == 0
    scene.rebuild(vertex_over_triangle(plane2, point2))
    assert scene.query("vt", R, mode="sphere", leaf_exact=True).tolist() == [[3, 0]]


def test_float64_numpy_vertices_are_read_in_place_and_other_layouts_copied_once_in_float64():
    xyz = rolled_sheet(5, 0)[0].astype(np.float64)
    args = _args._Args(minkq.Device("cpu"))
    native, dtype = args.vertices(xyz, "vertices", None)
    assert native is xyz and dtype == np.float64
    for other in (xyz[::-1], np.asfortranarray(xyz), xyz.astype(">f8"), xyz.tolist()):
        native, dtype = args.vertices(other, "vertices", None)
        assert dtype == np.float64 and native.dtype == np.float64 and native.flags.c_contiguous
        assert np.array_equal(native, np.asarray(other, np.float64))
    # float32 (and integer) host vertices make a float32 scene, as they always did.
    native, dtype = args.vertices(xyz.astype(np.float32), "vertices", None)
    assert dtype == np.float32 and native.dtype == np.float32
    assert args.vertices([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "vertices", None)[1] == np.float32
    assert args.vertices(np.zeros((3, 3), np.float16), "vertices", None)[1] == np.float32


def test_lists_of_python_floats_make_a_float64_scene(device):
    scene = minkq.Scene([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, 0.1]], [[0, 1, 2]], device=device)
    assert scene.dtype == np.float64
    assert scene.query("vt", 0.2, mode="sphere", leaf_exact=True).tolist() == [[3, 0]]
    ints = minkq.Scene([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], device=device)
    assert ints.dtype == np.float32


def test_float32_input_is_converted_exactly_on_a_float64_scene(device):
    xyz, tris = rolled_sheet(9, 3)
    moved = xyz * np.float32(1.01)
    exact = minkq.Scene(xyz, tris, device=device)
    wide = minkq.Scene(xyz.astype(np.float64), tris, device=device)
    assert (exact.dtype, wide.dtype) == (np.float32, np.float64)
    for call in ("refit", "rebuild"):
        getattr(exact, call)(moved)
        getattr(wide, call)(moved)  # float32 values are doubles exactly: no rounding, rho 0
        for kind, mode in (("vt", "sphere"), ("ee", "capsule_exact")):
            a, b = exact.query_digest(kind, 0.05, mode=mode), wide.query_digest(kind, 0.05, mode=mode)
            assert len(a[0]) and a[1] == b[1], (call, kind, mode)


def test_float64_input_is_refused_on_a_float32_scene(device):
    xyz, tris = rolled_sheet(5, 0)
    scene = minkq.Scene(xyz, tris, device=device)
    message = r"vertices: got float64 values for a scene created from float32 vertices.*create the scene from float64"
    for call in (scene.refit, scene.rebuild):
        with pytest.raises(TypeError, match=message):
            call(xyz.astype(np.float64))
        with pytest.raises(TypeError, match=message):
            call(xyz.tolist())  # Python floats are doubles
    scene.reserve(refit=True, rebuild=True)
    for call in (scene.refit_async, scene.rebuild_async):
        with pytest.raises(TypeError, match=message):
            call(xyz.astype(np.float64))
    with pytest.raises(TypeError, match=r"vertices: got float64 values \(test_interop, host memory\) for a scene "
                                        r"created from float32 vertices"):
        scene.refit(DLPackOnly(xyz.astype(np.float64)))
    scene.refit(xyz.astype(np.float16).astype(np.float32))  # float32 and narrower still work


def test_non_float64_arrays_are_refused_where_nothing_is_converted(device):
    xyz, tris = rolled_sheet(5, 0)
    scene = minkq.Scene(xyz.astype(np.float64), tris, device=device)
    with pytest.raises(TypeError, match=r"vertices: expected float64 values, the dtype of the scene's vertices, got "
                                        r"float32 \(test_interop, host memory\).*never converted"):
        scene.refit(DLPackOnly(xyz))
    scene.reserve(refit=True, rebuild=True)
    for call in (scene.refit_async, scene.rebuild_async):
        with pytest.raises(TypeError, match=r"vertices: expected float64 values, the dtype of the scene's vertices, "
                                            r"got float32.*stream-ordered calls"):
            call(xyz)
    with pytest.raises(TypeError, match=r"vertices: expected a float32 or float64 array, got int32"):
        minkq.Scene(DLPackOnly(xyz.astype(np.int32)), tris, device=device)
    with pytest.raises(TypeError, match=r"vertices: expected float32 or float64 values, got float128"):
        minkq.Scene(xyz.astype(np.longdouble), tris, device=device)


def test_a_double_beyond_the_float_range_is_non_finite_naming_the_vertex(device):
    xyz = rolled_sheet(5, 0)[0].astype(np.float64)
    tris = rolled_sheet(5, 0)[1]
    bad = xyz.copy()
    bad[7, 1] = 1e39
    with pytest.raises(minkq.NonFiniteError, match="vertex 7 "):
        minkq.Scene(bad, tris, device=device)
    scene = minkq.Scene(xyz, tris, device=device)
    expected = scene.query_digest("ee", 0.05)[1]
    for call in (scene.refit, scene.rebuild):
        with pytest.raises(minkq.NonFiniteError, match="vertex 7 "):
            call(bad)
    assert scene.query_digest("ee", 0.05)[1] == expected  # the positions were kept


def test_stream_ordered_calls_take_float64_on_the_cpu(device):
    (plane, point) = CASES[1]
    far = vertex_over_triangle(plane, point)
    far[3, 0] += 1.0
    scene = minkq.Scene(far, TRIANGLE, ee=False, device=device)
    scene.reserve(refit=True, rebuild=True, canonical_capacity=8)
    pairs, count = np.zeros((8, 2), np.int32), np.zeros(1, np.uint64)
    near = vertex_over_triangle(plane, point)
    scene.refit_async(near)
    scene.query_async(pairs, count, "vt", R, leaf_exact=True, canonical=True)
    scene.async_status()
    assert pairs[: int(count[0])].tolist() == [[3, 0]]
    scene.rebuild_async(far)
    scene.query_async(pairs, count, "vt", R)
    scene.async_status()
    assert int(count[0]) == 0
    bad = near.copy()
    bad[2, 0] = 1e39
    scene.refit_async(bad)
    with pytest.raises(minkq.NonFiniteError, match="vertex 2 "):
        scene.async_status()


def test_warp_float64_arrays_are_read_in_place(wp, device):
    plane, point = CASES[2]
    near = vertex_over_triangle(plane, point)
    rows = wp.array(near, dtype=wp.vec3d, device="cpu")
    assert _interop.view(rows, "vertices", device).address == rows.ptr  # in place
    scene = minkq.Scene(rows, TRIANGLE, ee=False, device=device)
    assert scene.dtype == np.float64
    pairs = scene.query("vt", R, leaf_exact=True)
    assert isinstance(pairs, wp.array) and pairs.numpy().tolist() == [[3, 0]]
    far = near.copy()
    far[3, 0] += 1.0
    scene.refit(wp.array(far, dtype=wp.float64, device="cpu"))  # (n, 3) float64
    assert len(scene.query("vt", R)) == 0
    scene.reserve(refit=True)
    scene.refit_async(rows)
    assert scene.query("vt", R, leaf_exact=True).numpy().tolist() == [[3, 0]]
    with pytest.raises(TypeError, match=r"vertices: expected float64 values.*got float32 \(warp, host memory\)"):
        scene.refit(wp.array(far.astype(np.float32), dtype=wp.vec3, device="cpu"))
    # Warp float32 vec3 arrays keep making float32 scenes (minkq.newton passes them).
    assert minkq.Scene(wp.array(far.astype(np.float32), dtype=wp.vec3, device="cpu"), TRIANGLE, device=device).dtype == np.float32

