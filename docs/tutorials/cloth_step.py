"""Tutorial: a cloth self-contact step loop. A sheet folds onto itself over 12 steps; each
step moves the vertices (refit, or rebuild when the trees have grown), asks for the VT and EE
contacts in one pass, and hands them to the solver.

Run as a script (docs/build.sh --check runs every tutorial): exits non-zero if a check fails.
"""
import math

import numpy as np

from _distances import vt_within

# ---- tutorial
import minkq
from minkq.demo import derive_edges, grid_sheet, mean_edge_length


def folded(rest: np.ndarray, angle: float) -> np.ndarray:
    """The sheet with its half x > 0.5 turned by `angle` about the line x = 0.5, z = 0."""
    x = rest.copy()
    right = rest[:, 0] > 0.5
    s = rest[right, 0] - 0.5
    x[right, 0] = 0.5 + s * math.cos(angle)
    x[right, 2] = s * math.sin(angle)
    return x


rest, triangles = grid_sheet(16)  # 256 vertices, 450 triangles
r = 0.5 * mean_edge_length(rest, derive_edges(triangles))  # contact distance of the solver
scene = minkq.Scene(rest, triangles)  # VT and EE trees, incident pairs dropped
steps = 12
for step in range(1, steps + 1):
    x = folded(rest, math.pi * 0.97 * step / steps)
    scene.refit(x)                      # cheap: same tree, new boxes
    if scene.tree_growth() > 1.5:       # boxes grew far past a fresh build's: rebuild
        scene.rebuild(x)
    vt, ee = scene.query_vt_ee(r, leaf_exact=True)  # the contacts: (vertex, triangle), (e, f)
    # ... the solver applies its contact forces to vt and ee here ...
    print(f"step {step:2}: {len(vt):4} VT, {len(ee):4} EE contacts, tree growth {scene.tree_growth():.2f}")
    # ---- end
    # Checks: a scene built afresh at these positions reports the same contacts (refit or
    # rebuild never changes the pairs), and the VT contacts are those within r, in double.
    fresh = minkq.Scene(x, triangles)
    for kind, pairs in (("vt", vt), ("ee", ee)):
        again = fresh.query(kind, r, leaf_exact=True, canonical=True)
        assert np.array_equal(np.unique(pairs, axis=0).reshape(-1, 2), again), f"step {step}: {kind} differs"
    truth = {tuple(p) for p in vt_within(x, triangles, r).tolist()}
    loose = {tuple(p) for p in vt_within(x, triangles, r * (1 + 1e-5)).tolist()}
    assert truth <= {tuple(p) for p in vt.tolist()} <= loose, f"step {step}: VT contacts differ from the distances"
assert len(vt) > 0 and len(ee) > 0, "the folded sheet touches itself"
print("every step checked against a fresh scene and brute-force distances")
