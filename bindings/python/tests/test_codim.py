"""Codimensional elements: Scene(..., vv=True, ev=True) with triangles=None, and the "vv" and
"ev" query kinds. Rods and loose particles against the brute-force numpy oracle at three
scales: every mode contains the true contacts, leaf-exact pairs are the true contacts within the
float slack, the modes nest (points: capsule_ray == box, capsule_exact == sphere); VV pairs once
as (v, w), v < w; EV drops a vertex's own edges with drop_incident and keeps them without;
refit and rebuild give a fresh scene's pairs; float64 scenes find what rounding to float pulls
apart and keep the double truth; swept steps contain the contacts sampled at 17 times in every
mode (float32 and float64), refuse leaf-exact, and give the static pairs at rest; VV and EV
beside triangles equal a triangle-less scene; every entry point (query, query_digest,
query_into, work, query_async, refit_async) takes the new kinds and query_vt_ee stays VT + EE;
kinds a scene was made without raise InvalidArgumentError with the library's message; Warp CPU
arrays in and out."""

from __future__ import annotations

import numpy as np
import pytest

import minkq
from oracle import as_set, ev_contacts, rods_and_particles, vv_contacts
from test_float64 import pulled_apart

MODES = minkq.MODES
CODIM = dict(vt=False, ee=False, vv=True, ev=True)
"""A scene of rods and particles: VV and EV only (drop_incident by default)."""


def rods(seed: int, scale: float = 1.0, offset: float = 0.0, float64: bool = False, n: tuple = (12, 20, 80)):
    """Rods and particles (see oracle.rods_and_particles) as float32, or float64, vertices."""
    xyz, edges = rods_and_particles(seed, *n, scale=scale, offset=offset)
    return (xyz if float64 else xyz.astype(np.float32)), edges


def pairs(scene: minkq.Scene, kind: str, mode: str, r: float, leaf_exact: bool = False) -> set:
    return as_set(scene.query(kind, r, mode=mode, leaf_exact=leaf_exact))


def check_codim(scene: minkq.Scene, xyz: np.ndarray, edges: np.ndarray, r: float, slack: float, what: str):
    """Zero false negatives in every mode, leaf-exact pairs between truth(r) and truth(r +
    slack), the modes' chain, VV ordered, no incident EV pair; the truth on ``xyz``, the
    positions the scene reads (float32 or float64)."""
    truths = {
        "vv": (vv_contacts(xyz, r), vv_contacts(xyz, r + slack)),
        "ev": (ev_contacts(xyz, edges, r), ev_contacts(xyz, edges, r + slack)),
    }
    for kind, (truth, loose) in truths.items():
        assert len(truth) > 20, f"{what}: {kind}: the scene needs contacts"
        got = {}
        for mode in MODES:
            got[mode] = pairs(scene, kind, mode, r)
            assert truth <= got[mode], f"{what}: {kind} {mode} lost {sorted(truth - got[mode])[:5]}"
            leaf = pairs(scene, kind, mode, r, leaf_exact=True)
            assert truth <= leaf <= loose, f"{what}: {kind} {mode} leaf_exact"
            assert leaf <= got[mode], f"{what}: {kind} {mode}"
            if kind == "vv":
                assert all(v < w for v, w in got[mode]), f"{what}: VV order"
            else:
                assert not any(v in edges[e] for v, e in got[mode]), f"{what}: incident EV pair"
        assert got["sphere"] <= got["box"] and len(got["sphere"]) < len(got["box"]), f"{what}: {kind}"
        assert got["capsule_ray"] == got["box"], f"{what}: {kind}: capsule_ray is box for points"
        assert got["capsule_exact"] == got["sphere"], f"{what}: {kind}: capsule_exact is sphere for points"


@pytest.mark.parametrize("seed, scale", [(1, 1e-3), (2, 1.0), (3, 1e3)])
def test_rods_and_particles_lose_no_pair_in_any_mode_at_any_scale(device, seed, scale):
    xyz, edges = rods(seed, scale, 0.25 * scale)
    scene = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    assert (scene.vertex_count, scene.triangle_count, scene.edge_count) == (320, 0, 228)
    assert np.array_equal(scene.edges(), edges)
    assert repr(scene) == "minkq.Scene(320 vertices, 0 triangles, 228 edges)"
    check_codim(scene, xyz, edges, 0.05 * scale, 1e-5 * scale, f"scale {scale}")


def test_no_triangles_may_be_none_an_empty_array_or_an_empty_list(device):
    xyz, edges = rods(4)
    want = None
    for triangles in (None, np.zeros((0, 3), np.int32), [], np.zeros((0, 3), np.int64)):
        scene = minkq.Scene(xyz, triangles, edges, **CODIM, device=device)
        got = (scene.query_digest("vv", 0.04), scene.query_digest("ev", 0.04))
        if want is None:
            want = got
        assert scene.triangle_count == 0
        assert all(np.array_equal(a[0], b[0]) and a[1] == b[1] for a, b in zip(got, want)), type(triangles)


def test_vv_pairs_once_in_order_and_ev_drops_incident_edges_only_when_asked(device):
    xyz, edges = rods(4, n=(6, 30, 20))
    keep = minkq.Scene(xyz, None, edges, **CODIM, drop_incident=False, device=device)
    drop = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    edge_set = set(map(tuple, edges.tolist()))
    incident = {(v, e) for e, (a, b) in enumerate(edges.tolist()) for v in (a, b)}
    r = 0.04
    for mode in MODES:
        for leaf in (False, True):
            raw = drop.query("vv", r, mode=mode, leaf_exact=leaf)
            assert len(as_set(raw)) == len(raw), f"{mode}: VV pairs reported twice"
            assert (raw[:, 0] < raw[:, 1]).all(), f"{mode}: VV order"
            assert as_set(raw) == pairs(keep, "vv", mode, r, leaf), f"{mode}: drop_incident drops no VV pair"
            assert len(as_set(raw) & edge_set) > 10, f"{mode}: rod neighbours within r pair too"
            kept, dropped = pairs(keep, "ev", mode, r, leaf), pairs(drop, "ev", mode, r, leaf)
            assert incident <= kept, f"{mode}: every vertex with its own edges (distance 0)"
            assert dropped == kept - incident, f"{mode}: drop_incident drops exactly those"
            if leaf:
                assert ev_contacts(xyz, edges, r, drop_incident=False) <= kept
                assert ev_contacts(xyz, edges, r) <= dropped


def test_refit_and_rebuild_give_a_fresh_scenes_pairs(device):
    before, edges = rods(5, n=(10, 20, 60))
    after, same_edges = rods(6, n=(10, 20, 60))  # the same topology, other positions
    assert np.array_equal(edges, same_edges)
    fresh = minkq.Scene(after, None, edges, **CODIM, device=device)
    for call in ("refit", "rebuild"):
        scene = minkq.Scene(before, None, edges, **CODIM, device=device)
        getattr(scene, call)(after)
        if call == "rebuild":
            assert scene.tree_growth() == 1.0
        for kind in ("vv", "ev"):
            for mode in MODES:
                for leaf in (False, True):
                    got = scene.query_digest(kind, 0.05, mode=mode, leaf_exact=leaf)
                    want = fresh.query_digest(kind, 0.05, mode=mode, leaf_exact=leaf)
                    assert len(got[0]) > 0 and np.array_equal(got[0], want[0]) and got[1] == want[1], (call, kind, mode)


def test_float64_scenes_find_pairs_that_rounding_pulls_apart(device):
    # Near 2e4 floats lie 2^-9 apart: points 0.9r..0.999r apart in double round beyond r = 1e-3.
    r = 1e-3
    for plane, point in pulled_apart(2e4, r, 4):
        # Particles 0 and 1 (VV); particle 4 facing edge 0, from vertex 2 to 3 along y (EV).
        xyz = np.array([[plane, 0, 0], [point, 0, 0], [plane, -1, 5], [plane, 1, 5], [point, 0, 5]], np.float64)
        edges = np.array([[2, 3]], np.int32)
        scene = minkq.Scene(xyz, None, edges, **CODIM, device=device)
        rounded = minkq.Scene(xyz.astype(np.float32), None, edges, **CODIM, device=device)
        assert scene.dtype == np.float64 and rounded.dtype == np.float32
        for mode in MODES:
            for leaf in (False, True):
                assert scene.query("vv", r, mode=mode, leaf_exact=leaf).tolist() == [[0, 1]], (mode, leaf)
                assert scene.query("ev", r, mode=mode, leaf_exact=leaf).tolist() == [[4, 0]], (mode, leaf)
            assert len(rounded.query("vv", r, mode=mode, leaf_exact=True)) == 0, mode
            assert len(rounded.query("ev", r, mode=mode, leaf_exact=True)) == 0, mode
        with pytest.raises(TypeError, match="vertices: got float64 values for a scene created from float32"):
            rounded.refit(xyz)  # never rounded quietly


def test_float64_rods_keep_the_double_truth(device):
    # Coordinates off the floats near 1000 + [0, 1]: the truth in double; leaf-exact extras
    # within r + 2 rho (rho <= sqrt(3)/2 ulp) plus the float slack.
    xyz, edges = rods(7, 1.0, 1000.0, float64=True)
    rng = np.random.default_rng(11)
    xyz = xyz + np.spacing(xyz.astype(np.float32)).astype(np.float64) * (rng.random(xyz.shape) - 0.5)
    scene = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    assert scene.dtype == np.float64
    slack = np.sqrt(3) * float(np.spacing(np.float32(1001))) + 1e-5
    check_codim(scene, xyz, edges, 0.05, slack, "float64")
    scene.rebuild(xyz)
    check_codim(scene, xyz, edges, 0.05, slack, "float64 rebuilt")


def sampled(x0: np.ndarray, x1: np.ndarray, edges: np.ndarray, r: float, steps: int = 16):
    """The VV and EV contacts at steps + 1 times of the step x0 -> x1, in double."""
    a, b = x0.astype(np.float64), x1.astype(np.float64)
    vv, ev = set(), set()
    for k in range(steps + 1):
        at = a + (b - a) * (k / steps)
        vv |= vv_contacts(at, r)
        ev |= ev_contacts(at, edges, r)
    return vv, ev


@pytest.mark.parametrize("float64", [False, True])
def test_swept_steps_contain_every_sampled_contact_in_every_mode(device, float64):
    r = 0.03
    x0, edges = rods(8, offset=300.0 if float64 else 0.0, float64=float64, n=(8, 16, 40))
    v, k = np.meshgrid(np.arange(len(x0)), np.arange(3), indexing="ij")
    x1 = (x0 + 0.1 * np.sin(0.7 * v + 2.1 * k)).astype(x0.dtype)
    vv, ev = sampled(x0, x1, edges, r)
    assert len(vv) > len(vv_contacts(x0, r)) + 5, "the step must add VV contacts"
    for call in ("refit_swept", "rebuild_swept"):
        scene = minkq.Scene(x0, None, edges, **CODIM, device=device)
        getattr(scene, call)(x0, x1)
        assert scene.is_swept
        got = {(kind, mode): pairs(scene, kind, mode, r) for kind in ("vv", "ev") for mode in MODES}
        for mode in MODES:
            assert vv <= got["vv", mode], f"{call} {mode}: lost {sorted(vv - got['vv', mode])[:5]}"
            assert ev <= got["ev", mode], f"{call} {mode}: lost {sorted(ev - got['ev', mode])[:5]}"
        for kind in ("vv", "ev"):
            # The sphere swept along the path is the capsule around it; the modes nest.
            assert got[kind, "sphere"] == got[kind, "capsule_exact"], (call, kind)
            assert got[kind, "capsule_exact"] <= got[kind, "capsule_ray"] <= got[kind, "box"], (call, kind)
            with pytest.raises(minkq.UnsupportedError, match="MINKQ_QUERY_LEAF_EXACT on swept positions"):
                scene.query(kind, r, leaf_exact=True)
        assert all(a < b for a, b in got["vv", "box"])
        assert not any(p in edges[e] for p, e in got["ev", "box"])
        scene.refit(x0)  # static again: leaf-exact runs
        assert not scene.is_swept
        assert pairs(scene, "vv", "box", r, leaf_exact=True) >= vv_contacts(x0, r)


def test_swept_steps_at_rest_give_the_static_pairs(device):
    xyz, edges = rods(9, n=(8, 16, 40))
    fixed = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    still = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    still.rebuild_swept(xyz, xyz)
    static_mode = {"box": "box", "capsule_ray": "box", "sphere": "sphere", "capsule_exact": "sphere"}
    for kind in ("vv", "ev"):
        for mode in MODES:
            want = fixed.query_digest(kind, 0.04, mode=static_mode[mode])
            got = still.query_digest(kind, 0.04, mode=mode)
            assert len(want[0]) > 0 and np.array_equal(got[0], want[0]) and got[1] == want[1], (kind, mode)


def test_vv_and_ev_beside_triangles_equal_a_scene_without_them(device):
    n = 10
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    xyz = np.stack([u.ravel(), v.ravel(), 0.1 * np.sin(9 * u.ravel()) * np.cos(7 * v.ravel())], 1).astype(np.float32)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (j * n + i).ravel()
    tris = np.concatenate([np.stack([v00, v00 + 1, v00 + n + 1], 1), np.stack([v00, v00 + n + 1, v00 + n], 1)])
    tris = tris.astype(np.int32)
    every = minkq.Scene(xyz, tris, vv=True, ev=True, device=device)
    mesh_only = minkq.Scene(xyz, tris, device=device)
    edges = every.edges()
    assert np.array_equal(edges, mesh_only.edges())
    codim = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    ev_only = minkq.Scene(xyz, tris, vt=False, ee=False, ev=True, device=device)  # edges derived, as for EE
    assert np.array_equal(ev_only.edges(), edges)
    r = 0.13  # beyond the grid spacing: neighbours pair
    for mode in MODES:
        for leaf in (False, True):
            want_vv, want_ev = pairs(codim, "vv", mode, r, leaf), pairs(codim, "ev", mode, r, leaf)
            assert want_vv and want_ev
            assert pairs(every, "vv", mode, r, leaf) == want_vv, (mode, leaf)
            assert pairs(every, "ev", mode, r, leaf) == want_ev, (mode, leaf)
            assert pairs(ev_only, "ev", mode, r, leaf) == want_ev, (mode, leaf)
            assert pairs(every, "vt", mode, r, leaf) == pairs(mesh_only, "vt", mode, r, leaf), (mode, leaf)
            if mode != "sphere":
                assert pairs(every, "ee", mode, r, leaf) == pairs(mesh_only, "ee", mode, r, leaf), (mode, leaf)
    # The fused VT + EE call is unchanged by the extra trees.
    vt, ee = every.query_vt_ee(r, leaf_exact=True, canonical=True)
    assert as_set(vt) == pairs(mesh_only, "vt", "box", r, True) and as_set(ee) == pairs(mesh_only, "ee", "box", r, True)


def test_every_entry_point_takes_vv_and_ev(device):
    assert minkq.KINDS == ("vt", "ee", "vv", "ev")
    xyz, edges = rods(10, n=(8, 16, 40))
    scene = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    scene.reserve(refit=True, canonical_capacity=4096)
    for kind in ("vv", "ev"):
        want = scene.query(kind, 0.05, leaf_exact=True, canonical=True)
        n = len(want)
        assert n > 10, kind
        pairs_, digest = scene.query_digest(kind, 0.05, leaf_exact=True)
        assert np.array_equal(pairs_, want)
        with pytest.raises(minkq.CapacityError) as e:
            scene.query(kind, 0.05, leaf_exact=True, out=np.zeros((n - 1, 2), np.int32))
        assert e.value.needed == n
        out = np.full((n + 4, 2), -1, np.int32)
        got, got_digest = scene.query_digest(kind, 0.05, leaf_exact=True, out=out)
        assert len(got) == n and got_digest == digest and np.array_equal(out[:n], want) and (out[n:] == -1).all()
        assert scene.work(kind, 0.05, leaf_exact=True).candidates == n
        # Stream-ordered (on the CPU: run to completion).
        out, count = np.zeros((4096, 2), np.int32), np.zeros(1, np.uint64)
        scene.query_async(out, count, kind, 0.05, leaf_exact=True, canonical=True)
        scene.async_status()
        assert int(count[0]) == n and np.array_equal(out[:n], want), kind
    moved = (xyz + np.float32(0.01)).astype(np.float32)
    scene.refit_async(moved)
    scene.async_status()
    fresh = minkq.Scene(moved, None, edges, **CODIM, device=device)
    assert pairs(scene, "ev", "sphere", 0.05) == pairs(fresh, "ev", "sphere", 0.05)
    # The fused call stays VT + EE: a scene without them refuses it.
    with pytest.raises(minkq.InvalidArgumentError, match="VT query on a scene created without MINKQ_SCENE_VT"):
        scene.query_vt_ee(0.05)


def test_kinds_a_scene_was_made_without_are_refused(device):
    xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.05, 0.05, 0]], np.float32)

    def refused(scene, kind):
        name = kind.upper()
        message = f"^{name} query on a scene created without MINKQ_SCENE_{name}$"
        with pytest.raises(minkq.InvalidArgumentError, match=message):
            scene.query(kind, 0.1)

    mesh = minkq.Scene(xyz[:3], np.array([[0, 1, 2]], np.int32), device=device)
    for kind in ("vv", "ev"):
        refused(mesh, kind)
        with pytest.raises(minkq.InvalidArgumentError):
            mesh.work(kind, 0.1)
        with pytest.raises(minkq.InvalidArgumentError):
            mesh.query(kind, 0.1, out=np.zeros((4, 2), np.int32))
    # Loose particles: vertices only, VV alone.
    particles = minkq.Scene(xyz, None, vt=False, ee=False, vv=True, device=device)
    assert particles.edge_count == 0
    assert particles.query("vv", 0.1, mode="sphere", leaf_exact=True).tolist() == [[0, 3]]
    for kind in ("vt", "ee", "ev"):
        refused(particles, kind)
    rod = minkq.Scene(xyz, None, np.array([[0, 1]], np.int32), vt=False, ee=False, ev=True, drop_incident=False, device=device)
    assert rod.query("ev", 0.1, leaf_exact=True, canonical=True).tolist() == [[0, 0], [1, 0], [3, 0]]
    refused(rod, "vv")
    # Creation: no kind at all, an edge past the vertices, a NaN; sphere mode stays EE's refusal.
    with pytest.raises(minkq.InvalidArgumentError, match="MINKQ_SCENE_VV"):
        minkq.Scene(xyz, None, vt=False, ee=False, device=device)
    with pytest.raises(minkq.IndexOutOfRangeError):
        minkq.Scene(xyz, None, np.array([[0, 4]], np.int32), **CODIM, device=device)
    with pytest.raises(minkq.NonFiniteError, match="vertex 1 "):
        minkq.Scene(np.array([[0, 0, 0], [np.nan, 0, 0]], np.float32), None, np.array([[0, 1]]), **CODIM, device=device)
    both = minkq.Scene(xyz, None, np.array([[0, 1]], np.int32), vt=False, vv=True, ev=True, device=device)
    with pytest.raises(minkq.InvalidArgumentError, match="sphere mode"):
        both.query("ee", 0.1, mode="sphere")
    assert both.query("ev", 0.1, mode="sphere").tolist() == [[3, 0]]
    with pytest.raises(ValueError, match="kind: expected one of 'vt', 'ee', 'vv', 'ev', got 've'"):
        both.query("ve", 0.1)


def test_warp_cpu_arrays_in_and_out(wp, device):
    xyz, edges = rods(12, n=(8, 16, 40))
    positions = wp.array(xyz, dtype=wp.vec3, device="cpu")
    scene = minkq.Scene(positions, None, wp.array(edges, dtype=wp.int32, device="cpu"), **CODIM, device=device)
    reference = minkq.Scene(xyz, None, edges, **CODIM, device=device)
    for kind in ("vv", "ev"):
        got = scene.query(kind, 0.05, leaf_exact=True, canonical=True)
        assert isinstance(got, wp.array) and got.dtype == wp.int32
        want = reference.query(kind, 0.05, leaf_exact=True, canonical=True)
        assert len(want) > 10 and np.array_equal(got.numpy(), want), kind
        out = wp.full((4096, 2), -7, dtype=wp.int32, device="cpu")
        got = scene.query(kind, 0.05, mode="sphere", canonical=True, out=out)
        assert len(got) == len(reference.query(kind, 0.05, mode="sphere"))
    moved = (xyz * np.float32(0.9)).astype(np.float32)
    scene.refit(wp.array(moved, dtype=wp.vec3, device="cpu"))
    reference.refit(moved)
    assert as_set(scene.query("ev", 0.05, mode="sphere").numpy()) == pairs(reference, "ev", "sphere", 0.05)
