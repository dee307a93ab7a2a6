#!/usr/bin/env python3
"""Newton's TriMeshCollisionDetector and minkq's drop-in, side by side, on a twisted sheet.

Switching a Newton script to minkq is one import:

    # from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector
    from minkq.newton import TriMeshCollisionDetector

(or ``minkq.newton.install()`` before creating a ``SolverVBD`` / ``CollisionPipeline``). This
script builds an N x N grid on the unit square twisted three turns as a Newton model, runs both
detectors with the same arguments on the model's device, and prints the vertex-triangle and
edge-edge contacts each stores in its rows. For N = 500 (edges across the sheet 2e-3 long, under
the 3.2e-3 that Newton's edge_edge_parallel_epsilon = 1e-5 treats as points) Newton loses about
half of the edge-edge contacts; minkq's rows hold all of them.

    python3 examples/python/newton_detector.py [--size N] [--device cpu|cuda:0] [--radius-factor F]
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
import warp as wp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from demo import derive_edges, mean_edge_length, twisted_sheet  # noqa: E402


def stored_pairs(buffer, offsets, counts) -> int:
    """The number of pairs the rows hold (counts clamped to each row's capacity)."""
    capacity = np.diff(offsets.numpy())
    return int(np.minimum(counts.numpy(), capacity).sum())


def run(size: int, device: str, factor: float) -> int:
    import newton
    from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector as NewtonDetector

    import minkq.newton

    xyz, tris = twisted_sheet(size, 3.0)
    r = float(np.float32(factor * mean_edge_length(xyz, derive_edges(tris))))
    builder = newton.ModelBuilder()
    builder.add_cloth_mesh(
        pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
        vertices=xyz, indices=tris.reshape(-1), density=1.0,
    )
    model = builder.finalize(device=device)
    print(f"twisted sheet {size}x{size}, 3 turns: {model.particle_count} vertices, {model.tri_count} triangles, "
          f"{model.edge_count} edges; r = {r:.4g} ({factor:g} x mean edge); device {model.device}")
    print(f"{'detector':<38} {'VT pairs':>10} {'EE pairs':>10} {'resize flags':>14} {'refit+VT+EE ms':>15}")
    found = {}
    for name, cls in (("newton TriMeshCollisionDetector", NewtonDetector), ("minkq.newton TriMeshCollisionDetector", minkq.newton.TriMeshCollisionDetector)):
        detector = cls(model, init_collision_info=True)
        for _ in range(2):  # the first run compiles kernels and sizes buffers
            wp.synchronize_device(model.device)
            start = time.perf_counter()
            detector.refit(model.particle_q)
            detector.vertex_triangle_collision_detection(r)
            detector.edge_edge_collision_detection(r)
            wp.synchronize_device(model.device)
            ms = 1e3 * (time.perf_counter() - start)
        vt = stored_pairs(detector.vertex_colliding_triangles, detector.vertex_colliding_triangles_offsets, detector.vertex_colliding_triangles_count)
        ee = stored_pairs(detector.edge_colliding_edges, detector.edge_colliding_edges_offsets, detector.edge_colliding_edges_count) // 2
        found[name] = (vt, ee)
        print(f"{name:<38} {vt:>10} {ee:>10} {str(detector.resize_flags.numpy().tolist()):>14} {ms:>15.1f}")
    (n_vt, n_ee), (m_vt, m_ee) = found.values()
    print(f"minkq finds {m_ee - n_ee} more edge-edge contacts ({100 * (m_ee - n_ee) / max(m_ee, 1):.1f}% of them), "
          f"{m_vt - n_vt} more vertex-triangle contacts")
    return 0 if m_ee >= n_ee and m_vt >= n_vt else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=500, help="vertices per side (default 500)")
    parser.add_argument("--device", default="cpu", help="Warp device of the Newton model (default cpu)")
    parser.add_argument("--radius-factor", type=float, default=0.25, help="r as a multiple of the mean edge (0.25)")
    args = parser.parse_args()
    wp.config.quiet = True
    return run(args.size, args.device, args.radius_factor)


if __name__ == "__main__":
    sys.exit(main())
