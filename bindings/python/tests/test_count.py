"""Scene.count and BVH.count (MINKQ_QUERY_COUNT): the exact number of pairs of every kind, mode
and leaf-exact setting, equal to the length of the stored query, on float32 and float64 scenes
and user-box BVHs; bad arguments raise as for query."""

from __future__ import annotations

import numpy as np
import pytest

import minkq
from oracle import rods_and_particles


def soup(seed: int, n: int = 300) -> tuple:
    rng = np.random.default_rng(seed)
    centres = rng.uniform(0, 1, (n, 1, 3))
    xyz = (centres + rng.normal(0, 0.03, (n, 3, 3))).reshape(-1, 3).astype(np.float32)
    return xyz, np.arange(3 * n, dtype=np.int32).reshape(n, 3)


@pytest.mark.parametrize("float64", [False, True])
def test_scene_count_equals_the_stored_query_in_every_kind_and_mode(float64):
    xyz, tris = soup(11)
    rods, edges = rods_and_particles(5, 12, 20, 80)
    device = minkq.Device("cpu")
    dtype = np.float64 if float64 else np.float32
    mesh = minkq.Scene(xyz.astype(dtype), tris, drop_incident=True, device=device)
    codim = minkq.Scene(rods.astype(dtype), None, edges=edges, vt=False, ee=False, vv=True, ev=True, device=device)
    counted = 0
    for scene, kinds, r in ((mesh, ("vt", "ee"), 0.02), (codim, ("vv", "ev"), 0.05)):
        for kind in kinds:
            for mode in minkq.MODES:
                if kind == "ee" and mode == "sphere":
                    continue
                for leaf in (False, True):
                    n = scene.count(kind, r, mode=mode, leaf_exact=leaf)
                    assert isinstance(n, int)
                    assert n == len(scene.query(kind, r, mode=mode, leaf_exact=leaf)), (kind, mode, leaf)
                    counted += n
    assert counted > 1000


def test_count_refuses_what_query_refuses():
    xyz, tris = soup(3, 20)
    scene = minkq.Scene(xyz, tris)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.count("ee", 0.1, mode="sphere")
    with pytest.raises(ValueError):
        scene.count("vt", -1.0)
    with pytest.raises(minkq.InvalidArgumentError):
        scene.count("vv", 0.1)  # a kind the scene was made without


def test_bvh_count_equals_the_stored_query_for_every_shape():
    rng = np.random.default_rng(7)
    lo = rng.uniform(0, 10, (400, 3)).astype(np.float32)
    boxes = np.stack([lo, lo + rng.uniform(0, 0.5, (400, 3)).astype(np.float32)], 1)
    bvh = minkq.BVH(boxes)
    centres = rng.uniform(0, 10, (200, 3)).astype(np.float32)
    segments = np.stack([centres, centres + rng.uniform(-1, 1, (200, 3)).astype(np.float32)], 1)
    cases = [("sphere", centres, 0.3, m) for m in ("box", "sphere")]
    cases += [("capsule", segments, 0.2, m) for m in ("box", "capsule_ray", "capsule_exact")]
    cases += [("box", boxes[:100], 0.0, "box")]
    for shape, queries, r, mode in cases:
        n = bvh.count(shape, queries, r, mode=mode)
        assert n == len(bvh.query(shape, queries, r, mode=mode)) > 0, (shape, mode)
