"""Tutorial: a scene of many geometries. A static floor shared by every world, and in each of
two worlds a cloth with a thickness per vertex, the two cloths at the same place: each cloth
touches the floor, never the other world's cloth.

Run as a script (docs/build.sh --check runs every tutorial): exits non-zero if a check fails.
"""
import numpy as np

from _distances import point_triangle, vt_within

# ---- tutorial
import minkq
from minkq.demo import grid_sheet

floor_v, floor_t = grid_sheet(10)                          # z = 0
cloth_v, cloth_t = grid_sheet(8)
cloth_v = cloth_v * np.float32(0.5) + np.float32([0.2, 0.2, 0.015])
thickness = np.linspace(0.0, 0.02, len(cloth_v), dtype=np.float32)  # one per cloth vertex

floor = minkq.Geometry(floor_v, floor_t, static=True, self_pairs=False, world=-1)  # every world
cloths = [minkq.Geometry(cloth_v, cloth_t, thickness=thickness, world=w) for w in (0, 1)]
scene = minkq.Scene.from_geometries([floor] + cloths)

r = 0.005
vt = scene.query("vt", r, leaf_exact=True, canonical=True)  # one global numbering
geometry, local = scene.geometry_of_pairs("vt", vt)               # back to (geometry, local id)
for g in (1, 2):
    mine = geometry[:, 0] == g
    print(f"cloth {g}: {mine.sum()} contacts of its vertices with floor triangles, "
          f"{((geometry[:, 0] == 0) & (geometry[:, 1] == g)).sum()} of floor vertices with its triangles")
# Moving the cloths: Scene.refit takes the moving geometries' vertices, concatenated.
scene.refit(np.concatenate([cloth_v, cloth_v + np.float32([0, 0, 1])]))  # world 1's cloth lifts
lifted = scene.query("vt", r, leaf_exact=True)
print(f"after world 1's cloth lifted: {len(lifted)} contacts")
# ---- end

# Checks. No pair joins the two worlds' cloths, and each cloth has the same floor contacts:
# its vertices within r + thickness of a floor triangle (the floor has no thickness).
assert not (np.sort(geometry, axis=1) == [1, 2]).all(axis=1).any(), "a pair across worlds"
assert (geometry.min(axis=1) == 0).all(), "the cloths touch only the floor"
pairs = {g: {tuple(p) for p in local[(geometry == [g, 0]).all(axis=1)].tolist()} for g in (1, 2)}
floor_on = {g: {tuple(p) for p in local[(geometry == [0, g]).all(axis=1)].tolist()} for g in (1, 2)}
assert floor_on[1] == floor_on[2], "the worlds differ"
both = np.concatenate([cloth_v, floor_v])
reach = vt_within(both, floor_t + len(cloth_v), r + float(thickness.max()), drop_incident=False)
reach = reach[reach[:, 0] < len(cloth_v)]
tri = both[floor_t[reach[:, 1]] + len(cloth_v)].astype(np.float64)
d = point_triangle(both[reach[:, 0]].astype(np.float64), tri[:, 0], tri[:, 1], tri[:, 2])
truth = {(v, t) for (v, t), dist in zip(reach.tolist(), d) if dist <= r + thickness[v]}
loose = {(v, t) for (v, t), dist in zip(reach.tolist(), d) if dist <= (r + thickness[v]) * (1 + 1e-5)}
assert truth and truth <= pairs[1] <= loose, "the contacts differ from the distances"
assert pairs[1] == pairs[2], "the worlds differ"
assert set(scene.geometry_of_pairs("vt", lifted)[0].ravel().tolist()) == {0, 1}, "world 1 lifted off"
print(f"checked: {len(truth)} contacts a world, as the distances say, none across worlds")
