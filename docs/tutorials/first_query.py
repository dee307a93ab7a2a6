"""Getting started: two parallel sheets, h apart, and the vertex-triangle contacts between them.

Run as a script (docs/build.sh --check runs every tutorial): exits non-zero if a check fails.
"""
import numpy as np

from _distances import vt_within

# ---- tutorial
import minkq
from minkq.demo import grid_sheet

lower, tris = grid_sheet(12)                  # (144, 3) float32 on z = 0, (242, 3) int32
upper = lower + np.float32([0, 0, 0.05])      # the same sheet 0.05 above
vertices = np.concatenate([lower, upper])
triangles = np.concatenate([tris, tris + len(lower)])

scene = minkq.Scene(vertices, triangles)      # numpy arrays: the CPU; device="auto" for GPU 0
r = 0.06
contacts = scene.query("vt", r, leaf_exact=True, canonical=True)         # (k, 2): (vertex, triangle)
candidates = scene.query("vt", r)                                        # a superset, cheaper
print(f"{len(contacts)} VT contacts within r = {r}, {len(candidates)} box candidates")

# Every upper vertex touches the triangles below it, and every lower one those above.
assert set(np.unique(contacts[:, 0])) == set(range(len(vertices)))
# Below the gap there is nothing to report.
assert len(scene.query("vt", 0.04, leaf_exact=True)) == 0
# ---- end

# The guarantee, checked in double precision: every pair within r is reported, and the contacts
# are no more than the pairs within r (plus the leaf test's slack, far below 1e-5 r here).
truth = vt_within(vertices, triangles, r)
loose = vt_within(vertices, triangles, r * (1 + 1e-5))
as_set = lambda pairs: set(map(tuple, pairs.tolist()))  # noqa: E731
assert as_set(truth) <= as_set(contacts) <= as_set(loose), "contacts differ from the distances"
assert as_set(contacts) <= as_set(candidates)
print("checked against brute-force distances: equal")
