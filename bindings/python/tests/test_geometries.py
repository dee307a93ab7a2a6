"""Scenes of many geometries (minkq.Geometry, Scene.from_geometries): a rolled cloth over a
static body. Its cross pairs equal the cross pairs of the one-mesh scene of both meshes
concatenated, in every kind, mode and with leaf_exact; self flags add each geometry's own pairs;
groups and masks, and worlds (with a world -1 ground), filter whole geometry pairs; a uniform
thickness t gives the pairs of r + 2t, a varied one contains the double oracle's contacts under
r + t(a) + t(b); float64 geometries find pairs that rounding to float pulls apart; one
geometry's refit, rebuild and swept forms equal a fresh scene; static geometries are refused;
geometry_range and geometry_of number the pairs; bad input raises the package's exceptions with
the library's messages naming the geometry."""

from __future__ import annotations

import numpy as np
import pytest

import minkq
from minkq._geometry import _thickness
from oracle import as_set, derive_edges, ee_distances, rolled_sheet, vt_distances
from test_float64 import CASES
from test_interop import DLPackOnly

MODES = minkq.MODES
EE_MODES = ("box", "capsule_ray", "capsule_exact")
R = 0.04
SLACK = 1e-5
"""Above the leaf test's 2^-19 S on these unit-sized meshes."""


def body_mesh(n: int = 10, seed: int = 0):
    """A bumpy sheet under the rolled cloth (rolled_sheet), near its lowest layer."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(-0.35, 0.35, n), np.linspace(-0.05, 1.05, n))
    z = -0.245 + 0.015 * np.sin(9 * x) * np.cos(7 * y) + 0.004 * rng.random(x.shape)
    xyz = np.stack([x.ravel(), y.ravel(), z.ravel()], 1).astype(np.float32)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (j * n + i).ravel()
    tris = np.concatenate([np.stack([v00, v00 + 1, v00 + n + 1], 1), np.stack([v00, v00 + n + 1, v00 + n], 1)])
    return xyz, tris.astype(np.int32)


BODY = body_mesh()
CLOTH = rolled_sheet(9, 3)


def concatenated(meshes):
    """The meshes as one: vertices, triangles and (derived) edges in the global numbering."""
    xyz = np.concatenate([m[0] for m in meshes])
    offsets = np.cumsum([0] + [len(m[0]) for m in meshes])
    tris = np.concatenate([m[1] + o for m, o in zip(meshes, offsets)]).astype(np.int32)
    edges = np.concatenate([derive_edges(m[1]) + o for m, o in zip(meshes, offsets)]).astype(np.int32)
    return xyz, tris, edges


def owner(scene: minkq.Scene, kind: str, pairs) -> np.ndarray:
    """Each pair's two geometries, (k, 2)."""
    return scene.geometry_of_pairs(kind, np.asarray(pairs, np.int32).reshape(-1, 2))[0]


def split(scene: minkq.Scene, kind: str, pairs) -> dict:
    """The pairs by their geometries: {(ga, gb): set of pairs}."""
    pairs = np.asarray(pairs, np.int32).reshape(-1, 2)
    out: dict = {}
    for pair, g in zip(pairs.tolist(), owner(scene, kind, pairs).tolist()):
        out.setdefault(tuple(g), set()).add(tuple(pair))
    return out


ALL_KINDS = ("vt", "ee", "vv", "ev")
RADII = {"vt": R, "ee": R, "vv": 0.1, "ev": 0.06}
"""Radii that give each kind cross and self pairs on the body and the cloth."""


@pytest.fixture(scope="module")
def pair_scenes(device):
    """The body (static, no self pairs) and the cloth (self pairs) as two geometries, every kind,
    and the one-mesh scene of both concatenated (the reference)."""
    body = minkq.Geometry(*BODY, kinds=ALL_KINDS, self_pairs=False, static=True)
    cloth = minkq.Geometry(*CLOTH, kinds=ALL_KINDS)
    scene = minkq.Scene.from_geometries([body, cloth], device=device)
    xyz, tris, edges = concatenated([BODY, CLOTH])
    one = minkq.Scene(xyz, tris, edges, vv=True, ev=True, device=device)
    return scene, one


def test_numbering_is_the_concatenated_meshes(pair_scenes):
    scene, one = pair_scenes
    nb, tb, eb = len(BODY[0]), len(BODY[1]), len(derive_edges(BODY[1]))
    assert scene.geometry_count == 2 and one.geometry_count == 1
    assert [scene.geometry_range(0, e) for e in ("vertex", "triangle", "edge")] == [(0, nb), (0, tb), (0, eb)]
    assert scene.geometry_range(1, "vertex") == (nb, len(CLOTH[0]))
    assert scene.geometry_range(1, "triangle") == (tb, len(CLOTH[1]))
    assert (scene.vertex_count, scene.triangle_count, scene.edge_count) == (
        one.vertex_count,
        one.triangle_count,
        one.edge_count,
    )
    assert np.array_equal(scene.edges(), one.edges())
    assert scene.dtype == np.float32
    assert repr(scene).endswith(", 2 geometries)")
    ids = np.array([[0, nb - 1], [nb, nb + 5]])
    g, local = scene.geometry_of("vertex", ids)
    assert g.tolist() == [[0, 0], [1, 1]] and local.tolist() == [[0, nb - 1], [0, 5]]
    assert g.dtype == local.dtype == np.int32
    assert [a.tolist() for a in scene.geometry_of("edge", [])] == [[], []]


def test_geometry_of_pairs_follows_the_ranges(device):
    """Every id maps to the geometry whose range holds it, also past a geometry without such
    elements (particles: no triangles or edges) and with local ids from its first."""
    particles = minkq.Geometry(CLOTH[0][::7] + np.float32([0, 0, 0.01]), kinds=("vt", "vv", "ev"))
    cloth = minkq.Geometry(*CLOTH, kinds=ALL_KINDS)
    scene = minkq.Scene.from_geometries([cloth, particles, cloth], device=device)
    assert scene.geometry_range(1, "triangle") == (len(CLOTH[1]), 0)
    for kind in ALL_KINDS:
        pairs = scene.query(kind, RADII[kind])
        geometries, local = scene.geometry_of_pairs(kind, pairs)
        assert geometries.shape == local.shape == pairs.shape and len(pairs) > 10, kind
        elements = {"vt": ("vertex", "triangle"), "ee": ("edge",) * 2, "vv": ("vertex",) * 2, "ev": ("vertex", "edge")}
        for column, element in enumerate(elements[kind]):
            ranges = [scene.geometry_range(g, element) for g in range(3)]
            for pair, g, lid in zip(pairs.tolist(), geometries[:, column].tolist(), local[:, column].tolist()):
                first, count = ranges[g]
                assert first <= pair[column] < first + count and lid == pair[column] - first, (kind, pair)
        assert {0, 1, 2} <= set(geometries.ravel().tolist()) or kind == "ee", kind
    with pytest.raises(ValueError, match=r"pairs: expected shape \(k, 2\), got \(3,\)"):
        scene.geometry_of_pairs("vt", [1, 2, 3])
    with pytest.raises(ValueError, match="kind: expected one of"):
        scene.geometry_of_pairs("tv", [[1, 2]])


@pytest.mark.parametrize("kind", ALL_KINDS)
@pytest.mark.parametrize("leaf_exact", [False, True])
def test_cross_and_self_pairs_are_the_concatenated_meshes_pairs(pair_scenes, kind, leaf_exact):
    scene, one = pair_scenes
    for mode in EE_MODES if kind == "ee" else MODES:
        got = split(scene, kind, scene.query(kind, RADII[kind], mode=mode, leaf_exact=leaf_exact))
        want = split(scene, kind, one.query(kind, RADII[kind], mode=mode, leaf_exact=leaf_exact))
        cross = {p for g, ps in want.items() if g[0] != g[1] for p in ps}
        assert len(cross) > 10, f"{kind} {mode}: the scene needs cross pairs"
        assert {p for g, ps in got.items() if g[0] != g[1] for p in ps} == cross, (kind, mode, leaf_exact)
        assert got.get((1, 1), set()) == want.get((1, 1), set()), f"{kind} {mode}: the cloth's own pairs"
        assert (0, 0) not in got, f"{kind} {mode}: the body has no self pairs"
        if kind == "vt":
            assert got[(0, 1)] and got[(1, 0)], "VT runs both ways"


@pytest.mark.parametrize("kind", ALL_KINDS)
def test_self_flags_choose_each_geometrys_own_pairs(device, pair_scenes, kind):
    """The body with self pairs and the cloth without: the body's own pairs are the
    concatenated scene's, the cloth has none; drop_incident=False adds the incident ones."""
    _, one = pair_scenes
    r = 0.1
    for drop in (True, False):
        body = minkq.Geometry(*BODY, kinds=ALL_KINDS, drop_incident=drop)
        scene = minkq.Scene.from_geometries([body, minkq.Geometry(*CLOTH, kinds=ALL_KINDS, self_pairs=False)], device=device)
        got = split(scene, kind, scene.query(kind, r, leaf_exact=True))
        assert (1, 1) not in got, kind
        if drop:
            want = split(scene, kind, one.query(kind, r, leaf_exact=True))
            assert got[(0, 0)] == want[(0, 0)], kind
            dropped = got[(0, 0)]
        elif kind != "vv":  # VV pairs are never incident
            assert got[(0, 0)] > dropped, kind


def test_the_cross_pairs_contain_the_double_oracle(pair_scenes):
    scene, _ = pair_scenes
    xyz, tris, edges = concatenated([BODY, CLOTH])
    nb, tb, eb = len(BODY[0]), len(BODY[1]), len(derive_edges(BODY[1]))
    vt, ee = vt_distances(xyz, tris), ee_distances(xyz, edges)
    vg, tg, eg = (np.arange(len(a)) >= n for a, n in ((xyz, nb), (tris, tb), (edges, eb)))
    truth = {
        "vt": (vt <= R) & (vg[:, None] != tg[None, :]),
        "ee": (ee <= R) & (eg[:, None] != eg[None, :]) & np.triu(np.ones(ee.shape, bool), 1),
    }
    loose = {"vt": (vt <= R + SLACK), "ee": (ee <= R + SLACK)}
    for kind, close in truth.items():
        want = set(zip(*map(np.ndarray.tolist, np.nonzero(close))))
        assert len(want) > 10
        for mode in EE_MODES if kind == "ee" else MODES:
            got = split(scene, kind, scene.query(kind, R, mode=mode))
            cross = got.get((0, 1), set()) | got.get((1, 0), set())
            assert want <= cross, f"{kind} {mode} lost {sorted(want - cross)[:5]}"
        leaf = split(scene, kind, scene.query(kind, R, leaf_exact=True))
        cross = leaf.get((0, 1), set()) | leaf.get((1, 0), set())
        assert want <= cross and all(loose[kind][p] for p in cross), kind


def test_groups_and_masks_filter_geometry_pairs(device):
    """Two cloths (group 2, mask 1: they ignore each other) over a body (group 1, mask 2)."""
    body = minkq.Geometry(*BODY, self_pairs=False, static=True, group=1, mask=2)
    cloths = [minkq.Geometry(*CLOTH, self_pairs=False, group=2, mask=1) for _ in range(2)]
    scene = minkq.Scene.from_geometries([body] + cloths, device=device)
    two = minkq.Scene.from_geometries([body, cloths[0]], device=device)
    for kind in ("vt", "ee"):
        got = split(scene, kind, scene.query(kind, R, leaf_exact=True))
        assert set(got) <= {(0, 1), (1, 0), (0, 2), (2, 0), (1, 0)}, f"{kind}: the cloths must not pair: {set(got)}"
        ref = two.query(kind, R, leaf_exact=True)
        for g in (1, 2):  # each cloth meets the body as the one cloth alone does
            assert local(scene, kind, got, g) == local(two, kind, split(two, kind, ref), 1), (kind, g)
    # A mask bit the other's group lacks, either way round, drops the pair.
    for b_group, b_mask in ((2, 2), (4, 1)):
        lone = minkq.Geometry(*CLOTH, self_pairs=False, group=b_group, mask=b_mask)
        assert len(minkq.Scene.from_geometries([body, lone], device=device).query("vt", R)) == 0
    # The same cloths in each other's masks meet (they coincide: every element pairs).
    open_cloths = [minkq.Geometry(*CLOTH, kinds="vt", self_pairs=False, group=2, mask=3) for _ in range(2)]
    both = minkq.Scene.from_geometries(open_cloths, device=device)
    assert set(split(both, "vt", both.query("vt", R))) == {(0, 1), (1, 0)}


def local(scene: minkq.Scene, kind: str, by_geometry: dict, cloth: int) -> set:
    """The pairs between the body (geometry 0) and geometry ``cloth`` with local ids, as
    (body element, cloth element, which way)."""
    elements = {"vt": ("vertex", "triangle"), "ee": ("edge", "edge")}[kind]
    out = set()
    for (ga, gb), ps in by_geometry.items():
        if {ga, gb} != {0, cloth}:
            continue
        pairs = np.array(sorted(ps), np.int32)
        la = scene.geometry_of(elements[0], pairs[:, 0])[1]
        lb = scene.geometry_of(elements[1], pairs[:, 1])[1]
        # (body element, cloth element, whether the cloth's element comes first); EE pairs are
        # unordered: which way is not a property of the pair.
        way = ga != 0 and kind != "ee"
        out |= {(b, a, way) if ga != 0 else (a, b, way) for a, b in zip(la.tolist(), lb.tolist())}
    return out


def test_worlds_never_pair_and_world_minus_one_joins_every_world(device):
    """The same cloth in worlds 0 and 1 (coinciding: across worlds every element would pair)
    over one body in world -1: each world's pairs are those of a one-world scene."""
    body = minkq.Geometry(*BODY, self_pairs=False, static=True, world=-1)
    worlds = [minkq.Geometry(*CLOTH, world=w) for w in (0, 1)]
    scene = minkq.Scene.from_geometries([body] + worlds, device=device)
    alone = minkq.Scene.from_geometries([body, worlds[0]], device=device)
    nc, tc = len(CLOTH[0]), len(CLOTH[1])
    for kind in ("vt", "ee"):
        got = split(scene, kind, scene.query(kind, R, leaf_exact=True))
        assert not {(1, 2), (2, 1)} & set(got), f"{kind}: a pair across worlds"
        ref = split(alone, kind, alone.query(kind, R, leaf_exact=True))
        assert got[(1, 1)] and got[(2, 2)] and (got.get((0, 1)) or got.get((1, 0)))
        assert local(scene, kind, got, 1) == local(scene, kind, got, 2) == local(alone, kind, ref, 1), kind
        assert len(got[(1, 1)]) == len(got[(2, 2)]) == len(ref[(1, 1)])
    # World 1 of the scene, shifted to world 0's ids, is world 0.
    vt = split(scene, "vt", scene.query("vt", R, leaf_exact=True))
    assert {(v - nc, t - tc) for v, t in vt[(2, 2)]} == vt[(1, 1)]


@pytest.mark.parametrize("t", [0.0, 0.01, 0.03])
def test_uniform_thickness_is_a_larger_radius(device, t):
    with_t = minkq.Scene.from_geometries(
        [
            minkq.Geometry(*BODY, self_pairs=False, static=True, thickness=t),
            minkq.Geometry(*CLOTH, thickness=np.full(len(CLOTH[0]), t, np.float32)),
        ], device=device
    )
    without = minkq.Scene.from_geometries(
        [minkq.Geometry(*BODY, self_pairs=False, static=True), minkq.Geometry(*CLOTH)], device=device
    )
    r = 0.02
    for kind in ("vt", "ee"):
        for leaf_exact in (False, True):
            a = as_set(with_t.query(kind, r, leaf_exact=leaf_exact))
            b = as_set(without.query(kind, r + 2 * t, leaf_exact=leaf_exact))
            assert a == b, (kind, leaf_exact, len(a ^ b))


def test_varied_thickness_reaches_r_plus_both_thicknesses(device):
    rng = np.random.default_rng(5)
    tb = (0.02 * rng.random(len(BODY[0]))).astype(np.float32)
    tc = (0.02 * rng.random(len(CLOTH[0]))).astype(np.float32)
    body = minkq.Geometry(*BODY, self_pairs=False, static=True, thickness=tb)
    scene = minkq.Scene.from_geometries([body, minkq.Geometry(*CLOTH, thickness=tc)], device=device)
    xyz, tris, edges = concatenated([BODY, CLOTH])
    t = np.concatenate([tb, tc]).astype(np.float64)
    r = 0.015
    for kind, d, a, b in (
        ("vt", vt_distances(xyz, tris), t, t[tris].max(1)),
        ("ee", ee_distances(xyz, edges), t[edges].max(1), t[edges].max(1)),
    ):
        reach = r + a[:, None] + b[None, :]
        got = split(scene, kind, scene.query(kind, r, leaf_exact=True))
        pairs = set().union(*got.values())
        truth = {
            p for p in zip(*map(np.ndarray.tolist, np.nonzero(d <= reach))) if p in pairs or owner_ok(scene, kind, p)
        }
        assert len(truth) > 10
        assert truth <= pairs, f"{kind} lost {sorted(truth - pairs)[:5]}"
        assert all(d[p] <= reach[p] + SLACK for p in pairs), kind
        for mode in EE_MODES if kind == "ee" else MODES:
            assert truth <= as_set(scene.query(kind, r, mode=mode)), (kind, mode)


def owner_ok(scene: minkq.Scene, kind: str, pair) -> bool:
    """Whether the scene looks for ``pair`` (the oracle's, before its geometry rules): a cross
    pair, or a cloth self pair that is not incident (the body has no self pairs)."""
    ga, gb = owner(scene, kind, [pair])[0].tolist()
    if ga != gb:
        return kind == "vt" or pair[0] < pair[1]
    if ga == 0:
        return False
    xyz, tris, edges = concatenated([BODY, CLOTH])
    if kind == "vt":
        return pair[0] not in tris[pair[1]]
    return pair[0] < pair[1] and not set(edges[pair[0]].tolist()) & set(edges[pair[1]].tolist())


@pytest.mark.parametrize("plane, point", CASES[:3])
def test_float64_geometries_find_pairs_that_rounding_pulls_apart(device, plane, point):
    """A float64 triangle and a float64 particle, 0.9 r to 0.999 r apart in double, farther in
    float: found in every mode; the scene's refits take float64."""
    r = 1e-3
    tri = np.array([[plane, -1, -1], [plane, 2, -1], [plane, -1, 2]], np.float64)
    particle = np.array([[point, 0, 0]], np.float64)
    scene = minkq.Scene.from_geometries(
        [minkq.Geometry(tri, [[0, 1, 2]], kinds="vt", static=True), minkq.Geometry(particle, kinds="vt")], device=device
    )
    assert scene.dtype == np.float64
    for mode in MODES:
        for leaf_exact in (False, True):
            assert scene.query("vt", r, mode=mode, leaf_exact=leaf_exact).tolist() == [[3, 0]], (mode, leaf_exact)
    scene.refit(particle + [1, 0, 0])
    assert len(scene.query("vt", r)) == 0
    scene.refit_geometry(1, particle.astype(np.float32))  # taken: converted to float64 exactly
    scene.refit_geometry(1, particle)
    assert scene.query("vt", r).tolist() == [[3, 0]]


def test_mixed_precision_moves_each_geometry_alone(device):
    a = minkq.Geometry(BODY[0].astype(np.float64), BODY[1], self_pairs=False)
    scene = minkq.Scene.from_geometries([a, minkq.Geometry(*CLOTH)], device=device)
    before = as_set(scene.query("vt", R))
    with pytest.raises(minkq.InvalidArgumentError, match="mix float32 and float64"):
        scene.refit(np.concatenate([BODY[0], CLOTH[0]]))
    scene.refit_geometry(0, BODY[0].astype(np.float64))
    scene.refit_geometry(1, CLOTH[0])
    assert as_set(scene.query("vt", R)) == before
    with pytest.raises(TypeError, match="float32"):
        scene.refit_geometry(1, CLOTH[0].astype(np.float64))


def test_refit_of_one_geometry_is_a_fresh_scene(device):
    body = minkq.Geometry(*BODY, self_pairs=False, static=True)
    scene = minkq.Scene.from_geometries([body, minkq.Geometry(*CLOTH)], device=device)
    moved = CLOTH[0] + np.float32([0.02, -0.01, -0.012])
    fresh = minkq.Scene.from_geometries([body, minkq.Geometry(moved, CLOTH[1])], device=device)
    for move in (
        scene.refit_geometry,
        scene.rebuild_geometry,
        lambda g, v: scene.refit(v),
        lambda g, v: scene.rebuild(v),
    ):
        scene.refit_geometry(1, CLOTH[0])
        move(1, moved)
        for kind in ("vt", "ee"):
            for mode in ("box", "capsule_exact"):
                got, want = scene.query_digest(kind, R, mode=mode), fresh.query_digest(kind, R, mode=mode)
                assert got[1] == want[1] and np.array_equal(got[0], want[0]), (kind, mode)
    assert scene.tree_growth() == 1.0  # the last move was a rebuild


@pytest.mark.parametrize("rebuild", [False, True])
def test_swept_geometry_is_the_concatenated_swept_scene(device, rebuild):
    body = minkq.Geometry(*BODY, self_pairs=False, static=True)
    scene = minkq.Scene.from_geometries([body, minkq.Geometry(*CLOTH)], device=device)
    xyz, tris, edges = concatenated([BODY, CLOTH])
    one = minkq.Scene(xyz, tris, edges, device=device)
    x1 = CLOTH[0] + np.float32([0.0, 0.0, -0.03])
    (scene.rebuild_geometry_swept if rebuild else scene.refit_geometry_swept)(1, CLOTH[0], x1)
    one.refit_swept(xyz, np.concatenate([BODY[0], x1]))
    assert scene.is_swept
    for kind, modes in (("vt", MODES), ("ee", ("box",))):
        for mode in modes:
            got = split(scene, kind, scene.query(kind, R, mode=mode))
            want = split(scene, kind, one.query(kind, R, mode=mode))
            for g in ((0, 1), (1, 0), (1, 1)):
                assert got.get(g, set()) == want.get(g, set()), (kind, mode, g)
    scene.refit_geometry(1, x1)
    assert not scene.is_swept


def test_static_geometries_are_refused_and_skipped(device):
    body = minkq.Geometry(*BODY, self_pairs=False, static=True)
    scene = minkq.Scene.from_geometries([body, minkq.Geometry(*CLOTH)], device=device)
    with pytest.raises(minkq.InvalidArgumentError, match=r"^geometry 0 is static \(MINKQ_GEOMETRY_STATIC\)"):
        scene.refit_geometry(0, BODY[0])
    with pytest.raises(minkq.InvalidArgumentError, match="geometry 0 is static"):
        scene.rebuild_geometry_swept(0, BODY[0], BODY[0])
    both = np.concatenate([BODY[0], CLOTH[0]])
    with pytest.raises(minkq.InvalidArgumentError, match=f"moving geometries have {len(CLOTH[0])}"):
        scene.refit(both)
    with pytest.raises(minkq.InvalidArgumentError, match="geometry 2 is out of range: the scene has 2 geometries"):
        scene.refit_geometry(2, CLOTH[0])
    with pytest.raises(minkq.InvalidArgumentError, match="geometry 1 with 80 vertices but the geometry has 81"):
        scene.refit_geometry(1, CLOTH[0][:80])
    bad = CLOTH[0].copy()
    bad[4, 1] = np.nan
    with pytest.raises(minkq.NonFiniteError, match="^geometry 1: vertex 4 "):
        scene.refit_geometry(1, bad)


def test_stream_ordered_calls_serve_scenes_of_many_geometries(device):
    """The stream-ordered calls take scenes of several geometries: a whole-scene refit moves the
    moving ones (the body is static), its queries give the blocking scene's pairs, and a bad
    vertex is reported naming its geometry; the constructor's scene is one geometry and keeps
    them too."""
    def make():
        return minkq.Scene.from_geometries([minkq.Geometry(*BODY, static=True), minkq.Geometry(*CLOTH)], device=device)

    scene, twin = make(), make()
    scene.reserve(refit=True, canonical_capacity=1 << 14)
    moved = CLOTH[0] + np.float32(0.01) * np.sin(np.arange(CLOTH[0].size, dtype=np.float32)).reshape(-1, 3)
    scene.refit_async(moved)
    twin.refit(moved)
    scene.async_status()
    for kind in ("vt", "ee"):
        expected = twin.query(kind, R, leaf_exact=True)
        pairs = np.zeros((len(expected) + 4, 2), np.int32)
        count = np.zeros(1, np.uint64)
        scene.query_async(pairs, count, kind, R, leaf_exact=True, canonical=True)
        assert int(count[0]) == len(expected) > 0
        expected = expected[np.lexsort((expected[:, 1], expected[:, 0]))]
        assert np.array_equal(pairs[: len(expected)], expected), kind
    bad = moved.copy()
    bad[4, 1] = np.nan
    scene.refit_async(bad)
    with pytest.raises(minkq.NonFiniteError, match=r"vertex 4 .*geometry 1 \(its vertex 4\) kept its positions"):
        scene.async_status()
    one = minkq.Scene(*CLOTH, device=device)
    assert one.geometry_count == 1 and one.geometry_range(0, "triangle") == (0, len(CLOTH[1]))
    one.reserve(refit=True)
    one.refit_async(CLOTH[0])
    one.refit_geometry(0, CLOTH[0])
    one.async_status()


def test_bad_geometries_raise_with_the_geometry_named(device):
    tri = np.zeros((3, 3), np.float32)
    good = minkq.Geometry(tri, [[0, 1, 2]])

    def make(*geometries):
        return minkq.Scene.from_geometries(list(geometries), device=device)

    with pytest.raises(minkq.IndexOutOfRangeError, match="^geometry 1: triangle 0 references vertex 3"):
        make(good, minkq.Geometry(tri, [[0, 1, 3]]))
    with pytest.raises(minkq.IndexOutOfRangeError, match=r"geometries\[1\]\.triangles\[0, 2\] = 4294967296"):
        make(good, minkq.Geometry(tri, np.array([[0, 1, 2**32]], np.int64)))
    with pytest.raises(minkq.InvalidArgumentError, match="^geometry 1: thickness.count 2 is not the vertex count 3"):
        make(good, minkq.Geometry(tri, [[0, 1, 2]], thickness=[0.1, 0.2]))
    with pytest.raises(minkq.InvalidArgumentError, match="thickness of vertex 1 is -0.5, negative"):
        make(minkq.Geometry(tri, [[0, 1, 2]], thickness=[0.1, -0.5, 0]))
    with pytest.raises(minkq.NonFiniteError, match="thickness of vertex 2 is"):
        make(minkq.Geometry(tri, [[0, 1, 2]], thickness=[0.1, 0, np.inf]))
    with pytest.raises(minkq.InvalidArgumentError):
        make()
    with pytest.raises(ValueError, match=r"geometries\[0\]\.vertices: expected shape \(n, 3\)"):
        make(minkq.Geometry(np.zeros((3, 2), np.float32)))
    with pytest.raises(TypeError, match=r"geometries\[1\]: expected a minkq.Geometry, got tuple"):
        make(good, (tri, [[0, 1, 2]]))
    with pytest.raises(TypeError, match="expected a list of minkq.Geometry"):
        minkq.Scene.from_geometries(good, device=device)
    with pytest.raises(ValueError, match="kinds: expected names among"):
        minkq.Geometry(tri, kinds=("vt", "xx"))
    with pytest.raises(ValueError, match="kinds: expected at least one"):
        minkq.Geometry(tri, kinds=())
    with pytest.raises(ValueError, match="world: expected a world id >= 0, or -1"):
        minkq.Geometry(tri, world=-2)
    with pytest.raises(ValueError, match="mask: expected a uint32 bit set"):
        minkq.Geometry(tri, mask=2**32)
    with pytest.raises(TypeError, match="group: expected an int"):
        minkq.Geometry(tri, group=1.0)
    scene = make(good, good)
    with pytest.raises(ValueError, match="element: expected one of"):
        scene.geometry_range(0, "face")
    with pytest.raises(minkq.InvalidArgumentError, match="geometry 5 is out of range"):
        scene.geometry_range(5, "vertex")
    with pytest.raises(IndexError, match="vertex id 6 is outside the scene's 0 to 5"):
        scene.geometry_of("vertex", [0, 6])
    with pytest.raises(TypeError, match="ids: expected integers"):
        scene.geometry_of("vertex", [0.5])


def test_thickness_is_rounded_up_to_float32(device):
    """float64 and integer thickness becomes float32 rounded up, never down (no pair within
    r + t(a) + t(b) in double may fall outside the float reach); float32 is used as it is."""
    below = float(np.float32(0.1)) + 1e-9  # nearest float32: 0.1f, below it
    args = minkq._args._Args(device)
    t = _thickness(args, np.array([below, 0.25, 3.0]), "thickness", np.zeros((3, 3), np.float32))
    assert t.dtype == np.float32 and t.tolist() == [float(np.nextafter(np.float32(0.1), np.float32(1))), 0.25, 3.0]
    assert _thickness(args, np.array([2, 0], np.int64), "thickness", np.zeros((2, 3), np.float32)).tolist() == [
        2.0,
        0.0,
    ]
    assert _thickness(args, below, "thickness", np.zeros((2, 3), np.float32)).tolist() == [t[0]] * 2
    exact = np.array([0.1, 0.2], np.float32)
    assert _thickness(args, exact, "thickness", np.zeros((2, 3), np.float32)) is exact
    with pytest.raises(TypeError, match="thickness: expected float32 values"):
        _thickness(args, np.array([True]), "thickness", np.zeros((1, 3), np.float32))


def test_a_particle_set_and_rods_against_a_mesh(device):
    """Vertex and edge sets as geometries: EV and VV cross pairs of a rod set beside the cloth
    equal the concatenated scene's."""
    rng = np.random.default_rng(2)
    rod = np.cumsum(0.05 * (rng.random((30, 3)) - 0.5), 0).astype(np.float32) + np.float32([0, 0.5, -0.2])
    rod_edges = np.stack([np.arange(29), np.arange(1, 30)], 1).astype(np.int32)
    cloth = minkq.Geometry(*CLOTH, kinds=("vv", "ev"), self_pairs=False)
    rods = minkq.Geometry(rod, None, rod_edges, kinds=("vv", "ev"), self_pairs=False)
    scene = minkq.Scene.from_geometries([cloth, rods], device=device)
    xyz = np.concatenate([CLOTH[0], rod])
    edges = np.concatenate([derive_edges(CLOTH[1]), rod_edges + len(CLOTH[0])]).astype(np.int32)
    one = minkq.Scene(xyz, None, edges, vt=False, ee=False, vv=True, ev=True, device=device)
    for kind in ("vv", "ev"):
        got = split(scene, kind, scene.query(kind, 0.05, mode="sphere", leaf_exact=True))
        want = split(scene, kind, one.query(kind, 0.05, mode="sphere", leaf_exact=True))
        cross = {p for g, ps in want.items() if g[0] != g[1] for p in ps}
        assert cross and set().union(*got.values()) == cross, kind


def test_arrays_of_other_libraries_are_read_in_place(device):
    """DLPack host arrays (as PyTorch CPU tensors are) for every array of a geometry and its
    moves: the pairs of numpy arrays; never converted (a float64 thickness is refused)."""
    tb = np.full(len(BODY[0]), 0.005, np.float32)
    reference = minkq.Scene.from_geometries(
        [
            minkq.Geometry(*BODY, self_pairs=False, static=True, thickness=tb),
            minkq.Geometry(BODY[0].astype(np.float64) + 0.02, BODY[1]),
        ], device=device
    )
    body = minkq.Geometry(
        DLPackOnly(BODY[0]), DLPackOnly(BODY[1]), self_pairs=False, static=True, thickness=DLPackOnly(tb)
    )
    moving = minkq.Geometry(DLPackOnly(BODY[0].astype(np.float64) + 0.02), DLPackOnly(BODY[1]))
    scene = minkq.Scene.from_geometries([body, moving], device=device)
    assert scene.dtype == np.float64
    for kind in ("vt", "ee"):
        assert scene.query_digest(kind, R)[1] == reference.query_digest(kind, R)[1], kind
    moved = BODY[0].astype(np.float64) + [0.01, 0.0, 0.03]
    scene.refit_geometry(1, DLPackOnly(moved))
    reference.refit_geometry(1, moved)
    assert scene.query_digest("vt", R)[1] == reference.query_digest("vt", R)[1]
    with pytest.raises(TypeError, match=r"geometries\[0\]\.thickness: expected a float32 array, got float64"):
        minkq.Scene.from_geometries([minkq.Geometry(*BODY, thickness=DLPackOnly(tb.astype(np.float64)))], device=device)
    with pytest.raises(TypeError, match="expected float64 values"):
        scene.refit_geometry(1, DLPackOnly(moved.astype(np.float32)))


def test_warp_arrays_in_and_out(wp, device):
    """Warp CPU arrays as geometries: results are Warp arrays, equal to numpy's."""
    positions = wp.array(CLOTH[0], dtype=wp.vec3, device="cpu")
    body = minkq.Geometry(*BODY, self_pairs=False, static=True)
    cloth = minkq.Geometry(
        positions,
        wp.array(CLOTH[1], dtype=wp.int32, device="cpu"),
        thickness=wp.full(len(CLOTH[0]), 0.01, dtype=wp.float32, device="cpu"),
    )
    scene = minkq.Scene.from_geometries([body, cloth], device=device)
    reference = minkq.Scene.from_geometries([body, minkq.Geometry(*CLOTH, thickness=0.01)], device=device)
    pairs = scene.query("vt", R, leaf_exact=True, canonical=True)
    assert isinstance(pairs, wp.array) and pairs.dtype == wp.int32
    assert np.array_equal(pairs.numpy(), reference.query("vt", R, leaf_exact=True, canonical=True))
    moved = CLOTH[0] + np.float32([0, 0, -0.02])
    scene.refit_geometry(1, wp.array(moved, dtype=wp.vec3, device="cpu"))
    reference.refit_geometry(1, moved)
    assert scene.query_digest("ee", R)[1] == reference.query_digest("ee", R)[1]
    g, local = scene.geometry_of("vertex", pairs.numpy()[:, 0])
    assert set(g.tolist()) == {0, 1} and (local >= 0).all()
