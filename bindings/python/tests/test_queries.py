"""Every mode against the brute-force oracle: zero false negatives, the containment chain
true <= leaf_exact <= capsule_exact <= capsule_ray <= box (EE) and
true <= leaf_exact <= sphere <= box (VT), refit after moving vertices, rebuild (the pairs of
refit) and the tree growth, BVH queries."""

import numpy as np
import pytest

import minkq
from oracle import as_set, degenerate_soup, derive_edges, ee_contacts, point_segment_sq, rolled_sheet, vt_contacts

SCENES = [
    pytest.param(lambda: rolled_sheet(12, 1), 0.04, id="rolled-12"),
    pytest.param(lambda: rolled_sheet(16, 2), 0.02, id="rolled-16"),
    pytest.param(lambda: rolled_sheet(9, 3), 0.1, id="rolled-9-wide"),
    pytest.param(lambda: degenerate_soup(90, 4), 0.03, id="degenerate-soup"),
]


def check_modes(scene: minkq.Scene, xyz: np.ndarray, tris: np.ndarray, r: float) -> None:
    edges = scene.edges()
    true_vt = vt_contacts(xyz, tris, r)
    true_ee = ee_contacts(xyz, edges, r)
    assert len(true_vt) > 5 and len(true_ee) > 5, "the scene must have contacts"
    loose = r + 1e-5  # leaf_exact pairs lie within r + 2**-19 S

    vt = {mode: as_set(scene.query("vt", r, mode=mode)) for mode in minkq.MODES}
    vt_leaf = as_set(scene.query("vt", r, mode="sphere", leaf_exact=True))
    assert true_vt <= vt_leaf, "VT false negatives"
    assert vt_leaf <= vt_contacts(xyz, tris, loose)
    assert vt_leaf <= vt["sphere"] <= vt["box"]
    # Points are zero-length capsules: capsule_ray is the box test, capsule_exact the sphere.
    assert vt["capsule_ray"] == vt["box"] and vt["capsule_exact"] == vt["sphere"]

    ee = {mode: as_set(scene.query("ee", r, mode=mode)) for mode in ("box", "capsule_ray", "capsule_exact")}
    ee_leaf = as_set(scene.query("ee", r, mode="capsule_exact", leaf_exact=True))
    assert true_ee <= ee_leaf, "EE false negatives"
    assert ee_leaf <= ee_contacts(xyz, edges, loose)
    assert ee_leaf <= ee["capsule_exact"] <= ee["capsule_ray"] <= ee["box"]
    assert all(e < f for e, f in ee["box"])


@pytest.mark.parametrize("make, r", SCENES)
def test_every_mode_contains_the_true_contacts_and_the_chain_holds(device, make, r):
    xyz, tris = make()
    scene = minkq.Scene(xyz, tris, device=device)
    assert np.array_equal(scene.edges(), derive_edges(tris))
    check_modes(scene, xyz, tris, r)


def test_refit_after_moving_vertices(device):
    xyz, tris = rolled_sheet(12, 7)
    scene = minkq.Scene(xyz, tris, device=device)
    rng = np.random.default_rng(0)
    for _ in range(3):
        xyz = xyz.copy()
        xyz[:, [0, 2]] *= 0.9  # squash the roll: contacts change from step to step
        xyz[:, 2] += (0.01 * (rng.random(len(xyz)) - 0.5)).astype(np.float32)
        scene.refit(xyz)
        check_modes(scene, xyz, tris, 0.03)
        fresh = minkq.Scene(xyz, tris, device=device)
        for kind, mode in [("vt", "box"), ("vt", "sphere"), ("ee", "box"), ("ee", "capsule_ray"), ("ee", "capsule_exact")]:
            for leaf in (False, True):
                a = scene.query_digest(kind, 0.03, mode=mode, leaf_exact=leaf)
                b = fresh.query_digest(kind, 0.03, mode=mode, leaf_exact=leaf)
                assert np.array_equal(a[0], b[0]) and a[1] == b[1], (kind, mode, leaf)


def flat_grid(n: int):
    """A flat n x n grid over the unit square (z = 0), triangulated as rolled_sheet."""
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    xyz = np.stack([u.ravel(), v.ravel(), np.zeros(n * n)], axis=1).astype(np.float32)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (j * n + i).ravel()
    tris = np.concatenate([np.stack([v00, v00 + 1, v00 + n + 1], 1), np.stack([v00, v00 + n + 1, v00 + n], 1)])
    return xyz, tris.astype(np.int32)


def rolled_and_twisted(flat: np.ndarray, twist: float) -> np.ndarray:
    """The flat grid rolled up as rolled_sheet rolls it (layers ~0.035 apart, no jitter), each
    row then turned about the y axis by ``twist * v`` radians."""
    u, v = flat[:, 0].astype(np.float64), flat[:, 1].astype(np.float64)
    angle, radius = 9.0 * u, 0.2 + 0.05 * u
    x, z = radius * np.cos(angle), radius * np.sin(angle)
    c, s = np.cos(twist * v), np.sin(twist * v)
    return np.stack([c * x - s * z, v, s * x + c * z], axis=1).astype(np.float32)


QUERIES = [(kind, mode) for kind in ("vt", "ee") for mode in minkq.MODES if (kind, mode) != ("ee", "sphere")]


def test_rebuild_gives_the_pairs_of_refit_and_resets_the_tree_growth(device):
    flat, tris = flat_grid(16)
    r = 0.04
    refitted, rebuilt = minkq.Scene(flat, tris, device=device), minkq.Scene(flat, tris, device=device)
    assert refitted.tree_growth() == 1.0  # right after the constructor
    growths = []
    for twist in (0.0, 2.0):
        # Built flat, moved to a rolled sheet whose layers come within r of each other.
        moved = rolled_and_twisted(flat, twist)
        refitted.refit(moved)
        rebuilt.rebuild(moved)
        assert rebuilt.tree_growth() == 1.0
        growth = refitted.tree_growth()
        assert growth > 1.2, f"rolling a flat sheet up should degrade the refitted trees: {growth}"
        growths.append(growth)
        check_modes(rebuilt, moved, tris, r)
        for kind, mode in QUERIES:
            for leaf in (False, True):
                a = refitted.query_digest(kind, r, mode=mode, leaf_exact=leaf)
                b = rebuilt.query_digest(kind, r, mode=mode, leaf_exact=leaf)
                assert len(a[0]) > 0 and np.array_equal(a[0], b[0]) and a[1] == b[1], (twist, kind, mode, leaf)
    # Scale-free: the same meshes scaled by 1024 (exact in float32) grow alike.
    large = minkq.Scene(flat * np.float32(1024), tris, device=device)
    for twist, growth in zip((0.0, 2.0), growths):
        large.refit(rolled_and_twisted(flat, twist) * np.float32(1024))
        assert large.tree_growth() == pytest.approx(growth, rel=1e-12)
    # Back to the positions of its build, the refitted scene's trees are those of a build.
    refitted.refit(flat)
    assert refitted.tree_growth() == 1.0


def test_bvh_rebuild_gives_the_pairs_of_refit_and_resets_the_tree_growth(device):
    flat, tris = flat_grid(16)

    def boxes_of(xyz):
        corners = xyz[tris]  # (m, 3 vertices, 3)
        return np.stack([corners.min(axis=1), corners.max(axis=1)], axis=1)

    refitted, rebuilt = minkq.BVH(boxes_of(flat), device=device), minkq.BVH(boxes_of(flat), device=device)
    assert refitted.tree_growth() == 1.0
    moved = rolled_and_twisted(flat, 2.0)
    refitted.refit(boxes_of(moved))
    rebuilt.rebuild(boxes_of(moved).reshape(-1, 6))  # (n, 6) boxes are accepted too
    assert rebuilt.tree_growth() == 1.0
    growth = refitted.tree_growth()
    assert growth > 1.2, growth
    large = minkq.BVH(boxes_of(flat * np.float32(1024)), device=device)
    large.refit(boxes_of(moved * np.float32(1024)))
    assert large.tree_growth() == pytest.approx(growth, rel=1e-12)
    segments = np.stack([moved[::7], moved[::7] + [0.05, 0, 0]], axis=1).astype(np.float32)
    for shape, queries, mode in [
        ("sphere", moved, "sphere"),
        ("sphere", moved, "box"),
        ("capsule", segments, "capsule_exact"),
        ("capsule", segments, "capsule_ray"),
        ("box", boxes_of(moved), "box"),
    ]:
        radius = 0.0 if shape == "box" else 0.03
        a = refitted.query_digest(shape, queries, radius, mode=mode)
        b = rebuilt.query_digest(shape, queries, radius, mode=mode)
        assert len(a[0]) > 0 and np.array_equal(a[0], b[0]) and a[1] == b[1], (shape, mode)


def test_without_drop_incident_every_vertex_touches_its_triangles(device):
    xyz, tris = rolled_sheet(6, 5)
    scene = minkq.Scene(xyz, tris, drop_incident=False, device=device)
    pairs = as_set(scene.query("vt", 0.0, mode="sphere", leaf_exact=True))
    assert {(int(v), t) for t, tri in enumerate(tris) for v in tri} <= pairs
    assert vt_contacts(xyz, tris, 0.02, drop_incident=False) <= as_set(scene.query("vt", 0.02, mode="sphere"))


def test_explicit_edges_and_single_query_kind(device):
    xyz, tris = rolled_sheet(10, 8)
    edges = derive_edges(tris)[::2].copy()  # any edge list works, not only the derived one
    scene = minkq.Scene(xyz, tris, edges, vt=False, device=device)
    assert scene.edge_count == len(edges)
    assert np.array_equal(scene.edges(), edges)
    assert ee_contacts(xyz, edges, 0.04) <= as_set(scene.query("ee", 0.04, mode="capsule_exact", leaf_exact=True))
    with pytest.raises(minkq.InvalidArgumentError, match="VT query on a scene created without MINKQ_SCENE_VT"):
        scene.query("vt", 0.04, mode="sphere")


def test_canonical_query_into_and_capacity(device):
    xyz, tris = rolled_sheet(12, 9)
    scene = minkq.Scene(xyz, tris, device=device)
    pairs = scene.query("ee", 0.04, canonical=True)
    assert pairs.dtype == np.int32 and pairs.shape == (len(pairs), 2) and pairs.flags.c_contiguous
    keys = pairs[:, 0].astype(np.int64) << 32 | pairs[:, 1]
    assert np.all(np.diff(keys) > 0), "canonical: sorted, no duplicates"
    out = np.full((len(pairs) + 5, 2), -1, np.int32)
    with pytest.warns(DeprecationWarning, match="query_into"):  # the old spelling, for one more release
        info = scene.query_into(out, "ee", "box", 0.04, canonical=True, digest=True)
    assert info.count == len(pairs) and info.digest is not None
    assert np.array_equal(out[: info.count], pairs) and np.all(out[info.count :] == -1)
    small = np.full((len(pairs) - 1, 2), -7, np.int32)
    with pytest.raises(minkq.CapacityError) as e:
        scene.query("ee", 0.04, out=small)
    assert e.value.needed == len(pairs)
    # Nothing is written past the buffer; pairs (e < f) never hold -7.
    assert np.all(small == -7)


@pytest.mark.parametrize("vt_mode, ee_mode", [("box", "box"), ("sphere", "capsule_exact"), ("capsule_ray", "capsule_ray")])
def test_vt_ee_in_one_pass_gives_what_each_query_gives(device, vt_mode, ee_mode):
    xyz, tris = rolled_sheet(12, 11)
    scene = minkq.Scene(xyz, tris, device=device)
    for r, leaf_exact in ((0.04, True), (0.02, False), (0.04, False)):  # sizes regrow, then shrink
        vt, ee = scene.query_vt_ee(r, vt_mode=vt_mode, ee_mode=ee_mode, leaf_exact=leaf_exact, canonical=True)
        assert np.array_equal(vt, scene.query("vt", r, mode=vt_mode, leaf_exact=leaf_exact, canonical=True))
        assert np.array_equal(ee, scene.query("ee", r, mode=ee_mode, leaf_exact=leaf_exact, canonical=True))
        assert len(vt) > 0 and len(ee) > 0
    with pytest.raises(minkq.InvalidArgumentError, match="sphere mode needs point queries"):
        scene.query_vt_ee(0.04, ee_mode="sphere")
    with pytest.raises(ValueError, match="vt_mode"):
        scene.query_vt_ee(0.04, vt_mode="ball")


def test_vt_ee_needs_both_trees(device):
    xyz, tris = rolled_sheet(8, 12)
    scene = minkq.Scene(xyz, tris, ee=False, device=device)
    with pytest.raises(minkq.InvalidArgumentError, match="without MINKQ_SCENE_EE"):
        scene.query_vt_ee(0.04)


def test_repeated_queries_reuse_their_size_and_return_fresh_arrays(device):
    xyz, tris = rolled_sheet(10, 10)
    scene = minkq.Scene(xyz, tris, device=device)
    first = scene.query("vt", 0.05, canonical=True)
    second = scene.query("vt", 0.05, canonical=True)
    assert np.array_equal(first, second) and not np.shares_memory(first, second)
    smaller = scene.query("vt", 0.01, canonical=True)
    assert set(map(tuple, smaller.tolist())) <= set(map(tuple, first.tolist()))


def test_bvh_sphere_capsule_and_box_queries(device):
    rng = np.random.default_rng(21)
    centres = rng.random((200, 3)).astype(np.float32)
    boxes = np.stack([centres - [0.02, 0.03, 0.01], centres + [0.02, 0.01, 0.04]], axis=1).astype(np.float32)
    bvh = minkq.BVH(boxes, device=device)
    assert len(bvh) == 200
    queries = rng.random((100, 3)).astype(np.float32)
    r = 0.05

    def box_distance_sq(p):  # (q, 3) -> (q, boxes)
        lo, hi = boxes[None, :, 0, :].astype(np.float64), boxes[None, :, 1, :].astype(np.float64)
        d = np.maximum(np.maximum(lo - p[:, None, :], 0), p[:, None, :] - hi)
        return (d * d).sum(-1)

    brute = set(zip(*map(np.ndarray.tolist, np.nonzero(box_distance_sq(queries.astype(np.float64)) <= r * r))))
    sphere = as_set(bvh.query("sphere", queries, r, mode="sphere"))
    padded = as_set(bvh.query("sphere", queries, r, mode="box"))
    assert brute <= sphere <= padded

    segments = np.stack([queries, queries + [0.1, 0.0, 0.05]], axis=1).astype(np.float32)
    exact = as_set(bvh.query("capsule", segments, r, mode="capsule_exact"))
    ray = as_set(bvh.query("capsule", segments, r, mode="capsule_ray"))
    padded = as_set(bvh.query("capsule", segments, r, mode="box"))
    assert exact <= ray <= padded
    # Points sampled on each segment: every box within r of one of them is reported.
    for t in np.linspace(0, 1, 21):
        p = segments[:, 0].astype(np.float64) * (1 - t) + segments[:, 1].astype(np.float64) * t
        near = set(zip(*map(np.ndarray.tolist, np.nonzero(box_distance_sq(p) <= 0.999 * r * r))))
        assert near <= exact

    # Box queries after a refit that shifts every box; (n, 6) boxes are accepted too.
    shifted = boxes + np.array([1.0, 0, 0], np.float32)
    bvh.refit(shifted.reshape(-1, 6))
    query_boxes = np.stack([queries + [1, 0, 0], queries + [1.05, 0.05, 0.05]], axis=1).astype(np.float32)
    got, digest = bvh.query_digest("box", query_boxes)
    lo_ok = query_boxes[:, None, 0, :] <= shifted[None, :, 1, :]
    hi_ok = shifted[None, :, 0, :] <= query_boxes[:, None, 1, :]
    expected = np.argwhere(np.all(lo_ok & hi_ok, axis=-1)).astype(np.int32)
    assert np.array_equal(got, expected)
    out = np.empty((len(expected), 2), np.int32)
    with pytest.warns(DeprecationWarning, match="query_into"):  # the old spelling, for one more release
        info = bvh.query_into(out, "box", query_boxes, canonical=True, digest=True)
    assert (info.count, info.digest) == (len(expected), digest)


def test_strided_and_list_inputs_give_the_same_pairs(device):
    xyz, tris = rolled_sheet(8, 12)
    base = minkq.Scene(xyz, tris, device=device).query_digest("ee", 0.05, mode="capsule_exact")
    wide = np.zeros((len(xyz), 5), np.float32)
    wide[:, 1:4] = xyz
    strided = wide[:, 1:4]  # not contiguous: copied once
    assert not strided.flags.c_contiguous
    from_strided = minkq.Scene(strided, np.asfortranarray(tris), device=device).query_digest("ee", 0.05, mode="capsule_exact")
    from_lists = minkq.Scene(xyz.tolist(), tris.tolist(), device=device).query_digest("ee", 0.05, mode="capsule_exact")
    assert base[1] == from_strided[1] == from_lists[1]
    assert point_segment_sq(np.zeros(3), np.ones(3), np.ones(3)) == 3.0  # the oracle's own sanity


def test_work_counts_match_the_pairs_and_shrink_with_finer_modes(device):
    xyz, tris = rolled_sheet(16, 2)
    scene = minkq.Scene(xyz, tris, device=device)
    r = 0.02
    for kind, coarse, fine in (("vt", "box", "sphere"), ("ee", "box", "capsule_exact")):
        a, b = scene.work(kind, r, mode=coarse), scene.work(kind, r, mode=fine)
        assert a.candidates == len(scene.query(kind, r, mode=coarse))
        assert b.candidates == len(scene.query(kind, r, mode=fine))
        assert a.nodes_visited > 0 and a.node_tests >= a.nodes_visited
        # Finer node tests pass a subset of the coarser one's nodes and leaves.
        assert (b.nodes_visited, b.node_tests, b.primitive_tests) <= (a.nodes_visited, a.node_tests, a.primitive_tests)
        assert b.nodes_visited <= a.nodes_visited and b.primitive_tests <= a.primitive_tests
    leaf = scene.work("ee", r, mode="capsule_exact", leaf_exact=True)
    assert leaf.candidates == len(scene.query("ee", r, mode="capsule_exact", leaf_exact=True))
    with pytest.raises(ValueError, match="mode"):
        scene.work("ee", r, mode="cube")
