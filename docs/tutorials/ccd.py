"""Tutorial: swept candidates handed to a CCD narrow phase. A small sheet falls through a large
one within one step (the tunnelling a static query at the step's ends would miss); the swept
query gives every pair that may come within r during the step, and a narrow phase finds each
one's time of impact.

Run as a script (docs/build.sh --check runs every tutorial): exits non-zero if a check fails.
"""
import numpy as np

from _distances import point_triangle

# ---- tutorial
import minkq
from minkq.demo import grid_sheet

floor, floor_tris = grid_sheet(8)                         # the unit square, z = 0: static
patch, patch_tris = grid_sheet(6)
patch = patch * np.float32(0.3) + np.float32([0.3, 0.3, 0.2])  # a smaller sheet above it
triangles = np.concatenate([floor_tris, patch_tris + len(floor)])
x0 = np.concatenate([floor, patch])
x1 = x0.copy()
x1[len(floor):] += np.float32([0.1, 0.05, -0.4])           # the patch ends 0.2 below the floor

scene = minkq.Scene(x0, triangles)
scene.refit_swept(x0, x1)                                  # x(t) = x0 + t (x1 - x0), t in [0, 1]
r = 0.01
vt = scene.query("vt", r)   # (vertex, triangle) whose paths come within r: CCD candidates
ee = scene.query("ee", r)   # (e, f), each edge's swept box
print(f"swept candidates: {len(vt)} VT, {len(ee)} EE")


def vt_time_of_impact(v, t, iterations=60):
    """Narrow phase: for candidates (v, t), the first time in [0, 1] at which the vertex comes
    within r of the triangle, or inf. Here each body translates, so the vertex's motion relative
    to the triangle is linear and its distance convex in time: a ternary search finds the
    closest time, bisection the first within r. (A general narrow phase, such as ipctk's
    point-triangle CCD, decides any linear motion of the four points.)"""
    p0, p1 = x0[v].astype(np.float64), x1[v].astype(np.float64)
    a0, a1 = x0[triangles[t]].astype(np.float64), x1[triangles[t]].astype(np.float64)

    def distance(s):
        s = s[:, None]
        tri = a0 + s[:, None] * (a1 - a0)
        return point_triangle(p0 + s * (p1 - p0), tri[:, 0], tri[:, 1], tri[:, 2])

    lo, hi = np.zeros(len(v)), np.ones(len(v))
    for _ in range(iterations):                            # ternary search: the closest time
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        closer = distance(m1) <= distance(m2)
        hi, lo = np.where(closer, m2, hi), np.where(closer, lo, m1)
    closest = (lo + hi) / 2
    first, late = np.zeros(len(v)), closest.copy()
    for _ in range(iterations):                            # bisection: the first time within r
        mid = (first + late) / 2
        within = distance(mid) <= r
        late, first = np.where(within, mid, late), np.where(within, first, mid)
    toi = np.where(distance(np.zeros(len(v))) <= r, 0.0, late)
    return np.where(distance(closest) <= r, toi, np.inf)


toi = vt_time_of_impact(vt[:, 0], vt[:, 1])
hits = np.isfinite(toi)
print(f"narrow phase: {hits.sum()} of {len(vt)} VT candidates touch, first at t = {toi.min():.4f}")
# A simulator now limits the step to the first impact (or adds contact forces for these pairs).
# ---- end

# Checks. The patch crosses the floor: some pair touches, no sooner than the patch's 0.2 - r
# drop over its 0.4 (t = 0.475), and no static query at either end of the step sees it.
assert hits.any() and abs(toi.min() - (0.2 - r) / 0.4) < 1e-6, toi.min()
for ends in (x0, x1):
    static = minkq.Scene(ends, triangles)
    static_vt = {tuple(p) for p in static.query("vt", r).tolist()}
    assert not static_vt & {tuple(p) for p in vt[hits].tolist()}, "a static query saw an impact"
# The guarantee: every (vertex, triangle) pair that touches during the step is a candidate.
everything = np.array([(v, t) for v in range(len(x0)) for t in range(len(triangles))
                       if v not in triangles[t]])
touching = everything[np.isfinite(vt_time_of_impact(everything[:, 0], everything[:, 1]))]
missed = {tuple(p) for p in touching.tolist()} - {tuple(p) for p in vt.tolist()}
assert not missed, f"{len(missed)} touching pairs are not candidates"
print(f"checked: all {len(touching)} touching pairs of {len(everything)} are candidates")
