"""Cloth against a body mesh in Newton's own scene: what Newton's soft contact pass finds,
what minkq.newton.ClothBodyContacts finds, and a double-precision oracle's contacts.

The scene is Newton 1.8's ``vbd_soft_rigid_contact`` example with the bear's bag alone
(examples/python/newton_cloth_body.py: a cloth bag, Newton's bear mesh dropped into it, the bag
lifted after 120 frames), simulated by Newton (``SolverVBD``, ``CollisionPipeline``) on Warp's
CPU device. Every ``--every`` frames, at the same positions, for the example's soft contact gap
(0.01) and each of ``--gaps`` (a Newton pipeline made with that gap, for the measurement only):

- Newton: its soft contacts for the bear (``CollisionPipeline.collide``: per particle, the
  closest point of the mesh within ``soft_contact_gap + particle_radius + shape_margin``, by
  signed distance); counted as distinct particles;
- minkq: ``ClothBodyContacts(model).detect(gap)``: cloth vertex - bear triangle
  (VT c->b), bear vertex - cloth triangle (VT b->c), cloth edge - bear edge (EE), every pair
  within the same band (unsigned distance);
- oracle: every such pair by brute force in double (bindings/python/tests/newton_body_oracle.py).

"Newton misses" counts the oracle's particles within the band of the bear that Newton reports
no contact for (active particles; pinned ones Newton skips by design are counted apart), and
"uncovered" the oracle's VT b->c and EE contacts none of whose cloth vertices has a Newton
contact: contacts that Newton's per-particle pass has no trace of (a bear corner or edge
between the particles). "Newton only": particles Newton reports outside the oracle's band
(inside the bear, by its signed distance).

    python bench/peers/newton_body.py [--frames 180] [--every 30] [--gaps 0] [--out table.md]

Exits 1 when minkq misses a contact of the oracle or reports a pair farther than 1 + 1e-5 times
the band.

Needs warp-lang 1.19, newton 1.8 and usd-core (bindings/test.sh's venv) and minkq importable.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples", "python"))
sys.path.insert(0, os.path.join(ROOT, "bindings", "python", "tests"))
import newton_body_oracle as bo  # noqa: E402
from newton_cloth_body import bear_bag_example, soft_contacts  # noqa: E402

COLUMNS = (
    "frame", "gap", "Newton: particles", "oracle VT c->b: pairs (particles)", "minkq VT c->b: pairs (particles)",
    "Newton misses: particles (+ pinned)", "Newton only: particles", "oracle VT b->c", "minkq VT b->c",
    "uncovered by Newton", "oracle EE", "minkq EE", "uncovered by Newton", "minkq missed", "minkq beyond 1e-5",
)


def measure(example, contacts, gap: float, pipeline) -> list:
    model, state = example.model, example.state_0
    newton_particles = {p for p, _ in soft_contacts(example, set(contacts.shapes), pipeline)}
    contacts.update(state)
    pairs = contacts.detect(gap)
    cloth = bo.side(state.particle_q.numpy(), contacts.tri_indices, contacts.edge_indices, model.particle_radius.numpy())
    margins = model.shape_margin.numpy()
    bodies = [(s, bo.side(contacts.shape_world_vertices(s, state), model.shape_source[s].indices,
                          contacts.shape_edges(s), margins[s])) for s in contacts.shapes]
    near = bo.truth(cloth, bodies, gap)  # the pairs within 1 + 1e-5 times the band
    truth = {kind: t.within() for kind, t in near.items()}
    missed = sum(len(bo.as_keys(truth[k]) - bo.as_keys(getattr(pairs, k))) for k in bo.KINDS)
    beyond = sum(len(bo.as_keys(getattr(pairs, k)) - bo.as_keys(near[k].rows)) for k in bo.KINDS)

    active = (model.particle_flags.numpy() & 1).astype(bool)  # ParticleFlags.ACTIVE
    oracle_particles = set(truth["vertex_triangle"][:, 0].tolist())
    minkq_particles = set(pairs.vertex_triangle[:, 0].tolist())
    lost = oracle_particles - newton_particles
    lost_active = sum(1 for p in lost if active[p])
    covered = np.zeros(model.particle_count, bool)
    covered[list(newton_particles)] = True
    uncovered_vt = int((~covered[contacts.tri_indices[truth["triangle_vertex"][:, 0]]].any(axis=1)).sum())
    uncovered_ee = int((~covered[contacts.edge_indices[truth["edge_edge"][:, 0]]].any(axis=1)).sum())
    return [
        len(newton_particles),
        f"{len(truth['vertex_triangle'])} ({len(oracle_particles)})",
        f"{len(pairs.vertex_triangle)} ({len(minkq_particles)})",
        f"{lost_active} (+ {len(lost) - lost_active})",
        len(newton_particles - oracle_particles),
        len(truth["triangle_vertex"]), len(pairs.triangle_vertex), uncovered_vt,
        len(truth["edge_edge"]), len(pairs.edge_edge), uncovered_ee,
        missed, beyond,
    ]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=180)
    parser.add_argument("--every", type=int, default=30)
    parser.add_argument("--gaps", default="0",
                        help="soft contact gaps measured besides the example's (comma-separated; Newton's pipeline "
                             "made again for each, for the measurement only)")
    parser.add_argument("--out", help="write the markdown table here")
    args = parser.parse_args()

    import newton
    import warp as wp

    import minkq
    from minkq.newton import ClothBodyContacts

    example = bear_bag_example()
    gap = example.params["soft_contact_gap"]
    pipelines = {gap: (example.pipeline, example.contacts)}
    for g in (float(g) for g in args.gaps.split(",") if g.strip()):
        pipeline = newton.CollisionPipeline(example.model, broad_phase="nxn", soft_contact_gap=g)
        pipelines.setdefault(g, (pipeline, pipeline.contacts()))
    contacts = ClothBodyContacts(example.model, state=example.state_0)
    rows = []
    for frame in range(args.frames + 1):
        if frame % args.every == 0:
            for g, pipeline in pipelines.items():
                rows.append([frame, g, *measure(example, contacts, g, pipeline)])
                print(" | ".join(map(str, rows[-1])), flush=True)
        if frame < args.frames:
            example.step()

    try:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = "?"
    model = example.model
    bear = contacts.shapes[0]
    lines = [
        "# Cloth against a body mesh: Newton's soft contacts, minkq's three kinds, an oracle",
        "",
        f"`bench/peers/newton_body.py --frames {args.frames} --every {args.every} --gaps {args.gaps}` ({datetime.date.today()}, minkq "
        f"{minkq.__version__} {commit}, warp-lang {wp.__version__}, newton {newton.__version__}), Warp's `cpu` device "
        f"({platform.processor() or platform.machine()}). Counts only: they do not depend on timing.",
        "",
        f"Newton's `vbd_soft_rigid_contact` example, the bear's bag alone: a cloth bag of {model.particle_count} "
        f"particles, {model.tri_count} triangles, {model.edge_count} edges (particle radius "
        f"{float(model.particle_radius.numpy()[0]):.4g}), Newton's bear mesh ({len(model.shape_source[bear].vertices)} "
        f"vertices, {len(model.shape_source[bear].indices) // 3} triangles, shape margin "
        f"{float(model.shape_margin.numpy()[bear]):.4g}) on a free body dropped into it; the bag is lifted from frame 120. "
        f"Band: gap + particle radius + shape margin, the gap Newton's `soft_contact_gap` (the example's {gap}, "
        f"and {args.gaps} with a Newton pipeline made for the measurement). Newton: its soft contacts for the bear "
        "(one per particle: the closest point, signed distance), as distinct particles. minkq: "
        "`ClothBodyContacts.detect(gap)`. Oracle: every pair within the band, brute force in double. "
        "\"Newton misses\": oracle particles with no Newton contact (active; + pinned ones, which Newton skips). "
        "\"Uncovered\": oracle VT b->c / EE contacts none of whose cloth vertices has a Newton contact. "
        "\"Newton only\": Newton particles outside the oracle's band (inside the bear). \"minkq missed\": oracle "
        "contacts of the three kinds minkq does not report; \"minkq beyond 1e-5\": pairs it reports "
        "farther than 1 + 1e-5 times the band (its leaf-exact bound allows 2**-19).",
        "",
        "| " + " | ".join(COLUMNS) + " |",
        "|" + "---|" * len(COLUMNS),
        *("| " + " | ".join(map(str, row)) + " |" for row in rows),
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text)
    return 1 if any(row[-2] or row[-1] for row in rows) else 0  # minkq missed a contact, or went beyond


if __name__ == "__main__":
    sys.exit(main())
