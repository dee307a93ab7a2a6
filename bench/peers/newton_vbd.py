"""Newton VBD cloth with self-contact on a fine mesh: Newton's detector against minkq's.

A square sheet of side ``--side`` metres on a ``--cells`` x ``--cells`` grid (edges of
side / cells: below 3 mm by default), its left and right columns pinned and turned in opposite
directions about the sheet's axis (as Newton's ``cloth_twist`` example does), simulated with
``newton.solvers.SolverVBD`` and self-contact on, three ways:

- ``newton``: Newton 1.8's ``TriMeshCollisionDetector`` and solver at their defaults;
- ``newton eps=0``: the same with the solver's ``particle_edge_parallel_epsilon`` at 0;
- ``minkq``: after ``minkq.newton.install()`` (minkq's detector, and whatever install() does to
  the solver's edge-edge evaluation).

After every frame it reads the detector's edge-edge rows and counts, among the distinct
reported pairs whose distance (float64, this script's own segment distance) is below the
solver's interaction distance (``particle_self_contact_margin``), those the solver applies a
force to: the test of Newton's VBD force kernel, ``0 < d < margin`` with ``d`` from
``wp.closest_point_edge_edge(..., epsilon)`` and the solver's epsilon. At the end it counts
self-intersecting triangle pairs with Newton's own triangle-triangle test (a fresh Newton
detector on the final positions, the same for every run), and the time per substep (wall
clock, after one warm-up frame that compiles the kernels).

    python bench/peers/newton_vbd.py [--frames 90] [--cells 40] [--side 0.1] [--out table.md]

Needs warp-lang 1.19 and newton 1.8 (bindings/test.sh's venv) and minkq importable.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import warp as wp
import newton
from newton import ParticleFlags
from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector as NewtonDetector


@wp.kernel
def _turn_pinned(ids: wp.array(dtype=wp.int32), rest: wp.array(dtype=wp.vec3), signs: wp.array(dtype=float),
                 centre: wp.vec3, angle: float, q0: wp.array(dtype=wp.vec3), q1: wp.array(dtype=wp.vec3)):
    # Pinned vertex i turned by sign * angle about the x axis through the sheet's centre.
    i = wp.tid()
    v = ids[i]
    p = rest[v] - centre
    a = signs[i] * angle
    c = wp.cos(a)
    s = wp.sin(a)
    turned = centre + wp.vec3(p[0], c * p[1] - s * p[2], s * p[1] + c * p[2])
    q0[v] = turned
    q1[v] = turned


@wp.kernel
def _solver_applies_force(pairs: wp.array2d(dtype=wp.int32), pos: wp.array(dtype=wp.vec3),
                          edges: wp.array2d(dtype=wp.int32), epsilon: float, margin: float,
                          out: wp.array(dtype=wp.int32)):
    # Newton's VBD edge-edge force test for pair i (particle_vbd_kernels.py).
    i = wp.tid()
    e = pairs[i, 0]
    f = pairs[i, 1]
    st = wp.closest_point_edge_edge(pos[edges[e, 2]], pos[edges[e, 3]], pos[edges[f, 2]], pos[edges[f, 3]], epsilon)
    d = st[2]
    out[i] = wp.where(d > 0.0 and d < margin, 1, 0)


def _segment_distances(p0, p1, q0, q1):
    """Distances between segments p0p1 and q0q1 (rows, float64): the endpoint-segment distances
    and the clamped closest points of the lines (Ericson), the least of them."""

    def point_segment(p, a, b):
        d = b - a
        dd = np.einsum("ij,ij->i", d, d)
        t = np.where(dd > 0, np.clip(np.einsum("ij,ij->i", p - a, d) / np.where(dd > 0, dd, 1), 0, 1), 0)
        w = p - (a + t[:, None] * d)
        return np.einsum("ij,ij->i", w, w)

    best = np.minimum.reduce([point_segment(p0, q0, q1), point_segment(p1, q0, q1), point_segment(q0, p0, p1),
                              point_segment(q1, p0, p1)])
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e = np.einsum("ij,ij->i", d1, d1), np.einsum("ij,ij->i", d2, d2)
    b, c, f = np.einsum("ij,ij->i", d1, d2), np.einsum("ij,ij->i", d1, r), np.einsum("ij,ij->i", d2, r)
    ok = (a > 0) & (e > 0)
    denom = a * e - b * b
    s = np.where(ok & (denom > 0), np.clip((b * f - c * e) / np.where(denom > 0, denom, 1), 0, 1), 0)
    t = np.clip((b * s + f) / np.where(e > 0, e, 1), 0, 1)
    s = np.clip((b * t - c) / np.where(a > 0, a, 1), 0, 1)
    w = (p0 + s[:, None] * d1) - (q0 + t[:, None] * d2)
    best = np.where(ok, np.minimum(best, np.einsum("ij,ij->i", w, w)), best)
    return np.sqrt(best)


def _reported_ee_pairs(info) -> np.ndarray:
    """Distinct (e, f), e < f, of the detector's edge-edge rows (within each row's capacity)."""
    offsets = info.edge_colliding_edges_offsets.numpy()
    counts = info.edge_colliding_edges_count.numpy()
    rows = info.edge_colliding_edges.numpy().reshape(-1, 2)
    keep = []
    for e in np.nonzero(counts)[0]:
        n = min(int(counts[e]), int(offsets[e + 1] - offsets[e]))
        keep.append(rows[offsets[e]: offsets[e] + n])
    if not keep:
        return np.zeros((0, 2), np.int32)
    pairs = np.concatenate(keep)
    pairs = np.sort(pairs, axis=1)
    return np.unique(pairs[pairs[:, 0] != pairs[:, 1]], axis=0).astype(np.int32)


def _intersecting_pairs(model, positions) -> int:
    """Self-intersecting triangle pairs at `positions`: Newton's own triangle-triangle test (a
    fresh Newton detector, the same for every run; each pair is in both triangles' rows)."""
    detector = NewtonDetector(model, vertex_positions=positions)
    detector.triangle_triangle_intersection_detection()
    return int(detector.triangle_intersecting_triangles_count.numpy().sum()) // 2


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _model(cells: int, side: float):
    builder = newton.ModelBuilder(gravity=(0.0, 0.0, 0.0))
    h = side / cells
    builder.add_cloth_grid(pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), vel=wp.vec3(0.0, 0.0, 0.0),
                           dim_x=cells, dim_y=cells, cell_x=h, cell_y=h, mass=0.2 * h * h, tri_ke=1.0e3,
                           tri_ka=1.0e3, tri_kd=2.0e-4, edge_ke=1e-5, edge_kd=1e-3)
    builder.color()
    model = builder.finalize()
    model.soft_contact_ke = 1.0e3
    model.soft_contact_kd = 1.0e-1
    model.soft_contact_mu = 0.2
    return model, h


class TwistScene:
    """The twisted sheet: model, solver (self-contact on) and the pinned columns' turning; frame()
    advances one frame (the detector's BVH rebuilt, then 10 substeps). Also a frame source for
    ccd_peers.py --source newton."""

    substeps, frame_dt = 10, 1.0 / 60.0

    def __init__(self, args, solver_kwargs=None):
        self.model, h = _model(args.cells, args.side)
        model = self.model
        n = args.cells + 1
        left = [j * n for j in range(n)]
        right = [j * n + args.cells for j in range(n)]
        flags = model.particle_flags.numpy()
        for v in left + right:
            flags[v] &= ~ParticleFlags.ACTIVE
        model.particle_flags = wp.array(flags, dtype=model.particle_flags.dtype)
        self.h = h
        self.margin, self.gap = 0.4 * h, 0.3 * h  # interaction distance and extra detection distance, to the mesh
        self.solver = newton.solvers.SolverVBD(model, iterations=4, particle_enable_self_contact=True,
                                               particle_self_contact_margin=self.margin,
                                               particle_self_contact_gap=self.gap,
                                               particle_vertex_contact_buffer_size=64,
                                               particle_edge_contact_buffer_size=128, **(solver_kwargs or {}))
        self.state_0, self.state_1, self.control = model.state(), model.state(), model.control()
        self.pinned = wp.array(left + right, dtype=wp.int32)
        self.signs = wp.array([1.0] * n + [-1.0] * n, dtype=float)
        self.rest = wp.clone(model.particle_q)
        self.centre = wp.vec3(*model.particle_q.numpy().mean(axis=0))
        self.omega = args.omega
        self.t = 0.0

    def frame(self):
        dt = self.frame_dt / self.substeps
        self.solver.rebuild_bvh(self.state_0)
        for _ in range(self.substeps):
            self.t += dt
            wp.launch(_turn_pinned, dim=self.pinned.shape[0],
                      inputs=[self.pinned, self.rest, self.signs, self.centre, self.omega * self.t,
                              self.state_0.particle_q, self.state_1.particle_q])
            self.state_0.clear_forces()
            self.solver.step(self.state_0, self.state_1, self.control, None, dt)
            self.state_0, self.state_1 = self.state_1, self.state_0


def run(label: str, args, solver_kwargs=None) -> dict:
    scene = TwistScene(args, solver_kwargs)
    model, solver, h, margin = scene.model, scene.solver, scene.h, scene.margin
    substeps = scene.substeps
    detector = solver.trimesh_collision_detector
    epsilon = float(solver._self_contact_edge_edge_parallel_epsilon)
    edges = model.edge_indices
    within = forced = reported = crossing = boundary = 0
    first_intersection = None  # the first frame (of every 10th) with a self-intersection
    seconds = 0.0
    for frame in range(args.frames + 1):
        start = time.perf_counter()
        scene.frame()
        wp.synchronize()
        if frame > 0:  # frame 0 compiles the kernels
            seconds += time.perf_counter() - start
        if frame % 10 == 0 and first_intersection is None and _intersecting_pairs(model, scene.state_0.particle_q):
            first_intersection = frame
        pairs = _reported_ee_pairs(detector.collision_info)
        reported += len(pairs)
        if len(pairs) == 0:
            continue
        q = detector.vertex_positions.numpy().astype(np.float64)
        e = edges.numpy()
        d = _segment_distances(q[e[pairs[:, 0], 2]], q[e[pairs[:, 0], 3]], q[e[pairs[:, 1], 2]], q[e[pairs[:, 1], 3]])
        inside = pairs[d < margin]
        within += len(inside)
        if len(inside):
            out = wp.zeros(len(inside), dtype=wp.int32)
            wp.launch(_solver_applies_force, dim=len(inside),
                      inputs=[wp.array(inside, dtype=wp.int32), detector.vertex_positions, edges, epsilon, margin, out])
            got = out.numpy().astype(bool)
            forced += int(got.sum())
            # Misses the epsilon cannot explain: crossing edges (the kernel needs 0 < d) and
            # distances within float rounding of the margin (float32 d >= margin).
            missed = d[d < margin][~got]
            crossing += int((missed <= 1e-7 * margin).sum())
            boundary += int((missed >= margin * (1 - 1e-5)).sum())
    intersecting = _intersecting_pairs(model, scene.state_0.particle_q)
    return {"label": label, "epsilon": epsilon, "reported": reported, "within": within, "forced": forced,
            "other_misses": within - forced - crossing - boundary, "crossing": crossing, "boundary": boundary,
            "intersecting": intersecting, "first_intersection": first_intersection, "ms_per_substep": 1e3 * seconds / (args.frames * substeps),
            "edge": h, "margin": margin, "detector": type(detector).__module__ + "." + type(detector).__name__}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=90)
    parser.add_argument("--cells", type=int, default=40)
    parser.add_argument("--side", type=float, default=0.1)
    parser.add_argument("--omega", type=float, default=np.pi, help="turn rate of each pinned side [rad/s]")
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--out", help="also write the table here (markdown)")
    args = parser.parse_args()
    wp.config.quiet = True
    wp.init()
    wp.set_device(args.device)
    import minkq.newton

    rows = [run("newton", args), run("newton eps=0", args, {"particle_edge_parallel_epsilon": 0.0})]
    minkq.newton.install()
    try:
        rows.append(run("minkq", args))
    finally:
        minkq.newton.uninstall()
    base = rows[0]["ms_per_substep"]
    device = wp.get_device(args.device)
    where = f"{device} ({_cpu_model()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f})" if device.is_cpu \
        else f"{device} ({device.name})"
    lines = [
        f"Newton VBD, twisted {args.side} m sheet, {args.cells}x{args.cells} cells (edges {rows[0]['edge'] * 1e3:.2f} mm), "
        f"margin {rows[0]['margin'] * 1e3:.2f} mm, {args.frames} frames x 10 substeps, on {where}",
        "",
        "| run | solver EE epsilon | EE pairs reported (sum over frames) | of them within the margin | "
        "receiving force | fraction | missed: crossing / at the margin / other | "
        "self-intersecting triangle pairs at the end | first frame with one (of every 10th) | ms / substep | vs newton |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        fraction = r["forced"] / r["within"] if r["within"] else float("nan")
        lines.append(f"| {r['label']} | {r['epsilon']:g} | {r['reported']} | {r['within']} | {r['forced']} | "
                     f"{fraction:.4f} | {r['crossing']} / {r['boundary']} / {r['other_misses']} | "
                     f"{r['intersecting']} | {r['first_intersection'] if r['first_intersection'] is not None else 'none'} | "
                     f"{r['ms_per_substep']:.2f} | "
                     f"{r['ms_per_substep'] / base:.2f}x |")
    table = "\n".join(lines)
    print(table)
    if args.out:
        with open(args.out, "w") as f:
            f.write(table + "\n")


if __name__ == "__main__":
    main()
