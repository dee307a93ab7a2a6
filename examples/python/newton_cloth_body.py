#!/usr/bin/env python3
"""Cloth against a body mesh in Newton's own scene: minkq.newton.ClothBodyContacts beside
Newton's soft contacts.

Newton's ``vbd_soft_rigid_contact`` example (newton 1.8) drops rigid shapes into cloth bags
and lifts the bags; its first bag holds a mesh, Newton's bear asset (bear.usd). This script
runs that example with the bear's bag alone (``--all-bags``: the six of them) on Warp's device,
Newton's ``SolverVBD`` and ``CollisionPipeline`` doing the simulation as in the example, and
every ``--every`` frames reports, for the bear:

- Newton's soft contacts (``CollisionPipeline.collide``): one per particle near the mesh, its
  closest point (vertex-triangle only);
- minkq's contacts (:class:`minkq.newton.ClothBodyContacts`, radius Newton's
  ``soft_contact_gap`` plus each particle's radius and the shape's margin, as Newton's band):
  cloth vertices near bear triangles, bear vertices near cloth triangles, cloth edges near
  bear edges.

    python3 examples/python/newton_cloth_body.py [--frames 60] [--every 10] [--device cpu]

bench/peers/newton_body.py measures the same scene against a double-precision oracle.
"""

from __future__ import annotations

import argparse
import sys
from types import SimpleNamespace
from typing import Any


def bear_bag_example(all_bags: bool = False, device: str = "cpu") -> Any:
    """Newton's ``vbd_soft_rigid_contact`` Example (no viewer) with the bear's bag only, or all
    six bags, on ``device``."""
    import warp as wp

    wp.config.quiet = True
    import newton.viewer
    from newton.examples.vbd import example_vbd_soft_rigid_contact as soft_rigid

    if not all_bags:  # the Example reads the module's PARAMS
        soft_rigid.PARAMS = dict(soft_rigid.PARAMS, shape_names=["mesh"])
    with wp.ScopedDevice(device):
        return soft_rigid.Example(newton.viewer.ViewerNull(), SimpleNamespace(seed=42))


def soft_contacts(example: Any, shapes: Any, pipeline: Any = None) -> set:
    """Newton's soft contacts at the example's current state, as (particle, shape) pairs of
    ``shapes``: a collision pipeline (the example's, or ``(pipeline, contacts)``) run once more
    on ``state_0``."""
    pipeline, c = (example.pipeline, example.contacts) if pipeline is None else pipeline
    pipeline.collide(example.state_0, c)
    count = min(int(c.soft_contact_count.numpy()[0]), c.soft_contact_max)
    particle, shape = c.soft_contact_particle.numpy()[:count], c.soft_contact_shape.numpy()[:count]
    return {(int(p), int(s)) for p, s in zip(particle, shape) if int(s) in shapes}


def main(argv: Any = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=60, help="frames to simulate (60 per second)")
    parser.add_argument("--every", type=int, default=10, help="report every this many frames")
    parser.add_argument("--device", default="cpu", help="Warp's device for Newton (minkq queries on the CPU)")
    parser.add_argument("--all-bags", action="store_true", help="all six bags of Newton's example, not the bear's alone")
    args = parser.parse_args(argv)

    from minkq.newton import ClothBodyContacts

    example = bear_bag_example(args.all_bags, args.device)
    gap = example.params["soft_contact_gap"]
    contacts = ClothBodyContacts(example.model, state=example.state_0)
    print(f"cloth: {example.model.particle_count} particles, {example.model.tri_count} triangles; mesh shapes "
          f"{contacts.shapes}; soft_contact_gap {gap}")
    print("frame  newton soft contacts  minkq: cloth vertex-body triangle (particles)  body vertex-cloth triangle  edge-edge")
    for frame in range(args.frames + 1):
        if frame % args.every == 0:
            newton_pairs = soft_contacts(example, set(contacts.shapes))
            contacts.update(example.state_0)
            pairs = contacts.detect(gap)
            particles = len({(int(p), int(s)) for p, s, _ in pairs.vertex_triangle})
            print(f"{frame:5d}  {len(newton_pairs):20d}  {len(pairs.vertex_triangle):34d} ({particles:4d})"
                  f"  {len(pairs.triangle_vertex):26d}  {len(pairs.edge_edge):9d}")
        if frame < args.frames:
            example.step()
    return 0


if __name__ == "__main__":
    sys.exit(main())
