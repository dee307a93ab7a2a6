#!/usr/bin/env python3
"""The markdown report of bench/peers/ccd_peers.py: its rows (one per frame pair, radius and contestant)
and ground-truth rows rendered as bench/results/ccd_peers.md or ccd_newton.md.

write() gives the header (machine, versions, load, the command line), the data and definitions
paragraphs, the headline (geomean time over the fastest ipctk broad phase), the pair sets against
the exact D(r), the ground-truth section (gt_section; none for Newton runs) and a table per scene
or frame pair (per_scene). Imported by ccd_peers.py after it has pinned the process's threads
(ipctk and minkq are imported here only for their versions and minkq's CPU device name).
"""
from __future__ import annotations

import datetime
import os
import platform
import sys

import numpy as np

import ipctk
import minkq
from ccd_sources import NEWTON_SCENES


def fmt_ms(row):
    return f"{row['ms']:.2f} ({row['lo']:.2f}-{row['hi']:.2f})"


def geomean(xs):
    xs = [x for x in xs if x > 0]
    return float(np.exp(np.mean(np.log(xs)))) if xs else float("nan")


def write(rows, gt_rows, notes, src, load0, load1=None, written=None, source="scalable-ccd", runs_meta=(), *,
          args, threads):
    """Writes the markdown report to args.out (args: ccd_peers.py's options; threads: the CPUs both
    libraries ran on)."""
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load1 = os.getloadavg()[0] if load1 is None else load1
    written = written or f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"
    newton = source == "newton"
    o = ["# Swept queries beside ipctk's CCD broad phases (" + ("Newton cloth runs" if newton else "Scalable CCD sample data")
         + ")", ""]
    o.append(f"Machine: {cpu}, {os.cpu_count()} CPUs, {threads} used by both libraries (process pinned to them; "
             f"ipctk.set_num_threads({threads}), minkq's CPU device: {minkq.Device('cpu').name}); Python "
             f"{platform.python_version()}, numpy {np.__version__}, ipctk {getattr(ipctk, '__version__', '?')} (PyPI wheel), "
             f"minkq {'.'.join(map(str, minkq.version()))}. Load average (1 min) at start {load0:.2f}, at write {load1:.2f}. "
             f"Written {written} UTC by `bench/peers/ccd_peers.py`"
             f"{' --newton' if newton else ''} --repeats {args.repeats}"
             f"{' --newton-scenes ' + args.newton_scenes + ' --newton-pairs ' + str(args.newton_pairs) if newton else ''}"
             f"{' --radii ' + args.radii if args.radii != ('0,0.01,contact' if newton else '0,0.01') else ''}.")
    o.append("")
    if newton:
        o.append("Data: Newton cloth runs, simulated by this script on Warp's CPU device (newton "
                 f"{runs_meta[0]['newton'] if runs_meta else '?'}, warp-lang {runs_meta[0]['warp'] if runs_meta else '?'}); "
                 f"per run, {args.newton_pairs} consecutive frame pairs at the end (x0 = the particle positions after frame "
                 "f, x1 = after frame f + 1: one frame of motion, 10 solver substeps; Warp's float32 positions as float64, "
                 "exactly) with the cloth's triangles (`model.tri_indices`). **No ground truth**: a Newton run has no list "
                 "of colliding queries, so only the exact swept-box set D(r) below is checked (no 'missing colliding "
                 "queries' column). Runs:")
        o.append("")
        for m in runs_meta:
            o.append(f"- `{m['name']}`, {m['frames']} frames ({m['sim_s']:.0f} s to simulate): "
                     + NEWTON_SCENES[m["name"]][1].format(cells=m.get("cells"))
                     + f"; {m['particles']} particles; the solver's self-contact margin {m['margin']:.4g}, its detection "
                     f"radius (margin + gap) {m['query']:.4g}.")
        o.append("")
        o.append("Radii: multiples of the frame's mean edge length, and 'contact' = the run's self-contact detection radius "
                 "(`SolverVBD`'s margin + gap, the radius its detector queries with each step; the multiple it makes is "
                 "in the per-pair tables).")
        o += ["", ""]  # the next paragraph is written into the last
    else:
        o.append("Data: the Scalable CCD sample data (Belgrod et al. 2023, public repository "
                 f"Continuous-Collision-Detection/Sample-Scalable-CCD-Data{', commit ' + src.commit[:10] if src.commit else ''}): "
                 "per scene two consecutive frames (x0, x1, read as doubles) and the step's ground-truth queries. ")
    o[-1] += ("Every contestant gets the same doubles and mesh (edges: minkq's `scene.edges()`, handed to ipctk's "
             "`CollisionMesh(V0, E, F)`, so EE ids agree). ipctk: `Candidates().build(mesh, V0, V1, r / 2, broad_phase)` "
             "(its candidates: fv and ee lists; the time includes its box building and its candidate vectors, not their "
             "conversion to Python). minkq: a float64 `Scene` (incident pairs dropped), `rebuild_swept(x0, x1)` or "
             "`refit_swept(x0, x1)` of a scene built at x0, then `query(\"vt\", mode, r)` and `query(\"ee\", \"box\", r)` "
             "(numpy pair arrays). Round-robin: one warm-up round, then the rounds; ms = median (range). "
             "'/ fastest ipctk' = ms over the fastest ipctk broad phase's ms for that scene and r (< 1: faster).")
    o.append("")
    o.append("Definitions: ipctk grows each vertex's box of x0, x1 by the inflation radius (bounds nudged one ulp "
             "outward), unions them into edge and face boxes, and keeps the face-vertex and edge-edge pairs whose boxes "
             "meet (closed intervals) and that share no vertex; at inflation r / 2 that is the pairs whose swept boxes' "
             "per-axis gap is at most r: exactly minkq's swept VT box and EE box definition, with the same incident pairs "
             "dropped. Both report supersets of that exact set D(r): ipctk by its nudges (its LBVH stores float boxes "
             "rounded outward), minkq by its float trees (the float64 scene widens r by twice its rounding). "
             "|D(r)| is decided exactly (the double gap and its rounding error, TwoSum) over every pair any box contestant "
             "reported; 'excess' = pairs outside D(r), 'miss' = pairs of D(r) not reported (must be 0). VT capsule_exact "
             "has no ipctk counterpart (the capsule of radius r around the vertex path against the triangle's swept box): "
             "its count, and whether it lies within minkq's box set.")
    o.append("")
    # headline
    o.append("## Headline")
    o.append("")
    o.append(f"Geomean over the {'frame pairs' if newton else 'scenes'} of each contestant's time over the fastest ipctk "
             f"broad phase (per {'pair' if newton else 'scene'}, per r):")
    o.append("")
    radii = sorted(set(rkey(r) for r in rows), key=lambda k: (isinstance(k, str), 0.0 if isinstance(k, str) else k, str(k)))
    whos = list(dict.fromkeys(r["who"] for r in rows))
    o.append("| contestant | " + " | ".join(f"r = {x:g} x mean edge" if not isinstance(x, str) else
                                            "r = the solver's contact radius" for x in radii) + " |")
    o.append("|---|" + "---|" * len(radii))
    for w in whos:
        cells = []
        for x in radii:
            rs = [r["ratio"] for r in rows if r["who"] == w and rkey(r) == x]
            scenes = len(rs)
            cells.append(f"{geomean(rs):.3g}x ({scenes} {'pairs' if newton else 'scenes'})" if rs else "-")
        o.append(f"| {w} | " + " | ".join(cells) + " |")
    o.append("")
    fastest = {}
    for r in rows:
        if r["who"].startswith("ipctk"):
            k = (r["scene"], rtext(r))
            if k not in fastest or r["ms"] < fastest[k][1]:
                fastest[k] = (r["who"], r["ms"])
    o.append("Fastest ipctk broad phase per scene and r: " + "; ".join(
        f"{s} r={x}: {w[6:]} {ms:.1f} ms" for (s, x), (w, ms) in sorted(fastest.items())) + ".")
    o.append("")
    o.append(f"Pair sets against the exact swept-box set D(r), over every {'frame pair' if newton else 'scene'} and r "
             "(VT = FV)" + (" — no ground truth for Newton runs, so no colliding-query check:" if newton else ":"))
    o.append("")
    gtcol = " colliding ground-truth queries missed |" if newton else ""
    o.append("| contestant | runs equal to D(r) | largest VT excess / D | largest EE excess / D | pairs of D(r) missed |" + gtcol)
    o.append("|---|---|---|---|---|" + ("---|" if newton else ""))
    gtcell = " n/a (no ground truth: Newton run) |" if newton else ""
    for w in whos:
        rs = [r for r in rows if r["who"] == w]
        if "capsule" in w:
            ratio = [r["vt"] / max(r["D_vt"], 1) for r in rs]
            o.append(f"| {w} | (VT: no ipctk counterpart; {min(ratio):.3g}-{max(ratio):.3g}x the VT pairs of D(r), "
                     f"within the box set: {sum(bool(r['capsule_in_box']) for r in rs)}/{len(rs)}) | - | "
                     f"{max(r['ee_excess'] / max(r['D_ee'], 1) for r in rs):.2g} | EE {sum(r['ee_miss'] for r in rs)} |" + gtcell)
            continue
        eq = sum(1 for r in rs if r["vt_excess"] == 0 and r["ee_excess"] == 0 and r["vt_miss"] == 0 and r["ee_miss"] == 0)
        o.append(f"| {w} | {eq}/{len(rs)} | {max(r['vt_excess'] / max(r['D_vt'], 1) for r in rs):.2g} | "
                 f"{max(r['ee_excess'] / max(r['D_ee'], 1) for r in rs):.2g} | "
                 f"{sum(r['vt_miss'] + r['ee_miss'] for r in rs)} |" + gtcell)
    o.append("")
    ipc = [w for w in whos if w.startswith("ipctk")]
    ran = {p: {(r["scene"], rtext(r)) for r in rows if r["who"] == p} for p in ipc}
    same = []
    for w in whos:
        if w.startswith("minkq") and "capsule" not in w:
            rs = [r for r in rows if r["who"] == w]
            same.append(f"{w}: " + ", ".join(
                f"{p[6:]} {sum(1 for r in rs if p in r.get('same_as', []))}/{sum(1 for r in rs if (r['scene'], rtext(r)) in ran[p])}"
                for p in ipc))
    o.append("Runs where a minkq box set (VT and EE) is identical to an ipctk broad phase's (the definitions agree; "
             "each side may add its own rounding excess over D(r)): " + "; ".join(same) + ".")
    o.append("")
    if newton:
        o.append("## Ground truth")
        o.append("")
        o.append("None: a Newton run records no colliding queries (no exact narrow phase was run on these steps), so "
                 "every set is checked against the exact swept-box set D(r) only.")
        o.append("")
    else:
        gt_section(o, gt_rows)
    o.append("## Per scene" if not newton else "## Per frame pair")
    o.append("")
    for s in dict.fromkeys(r["scene"] for r in rows):
        per_scene(o, [r for r in rows if r["scene"] == s])
    if notes:
        o.append("## Notes")
        o.append("")
        for n in notes:
            o.append(f"- {n}")
        o.append("")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w") as f:
        f.write("\n".join(o))
    print(f"ccd_peers: wrote {args.out}", file=sys.stderr)


def gt_section(o, gt_rows):
    o.append("## Ground truth")
    o.append("")
    o.append("Each scene's listed queries (boxes/*.json: ids of Scalable CCD's combined box array, vertices, then "
             "igl::edges(F) edges, then faces, mapped to vertex / triangle and minkq edge ids) and those of them that "
             "collide (mma_bool/*.json, Mathematica, exact). 'coords' = queries whose coordinates in queries/*.csv "
             "(rationals) equal the frames' doubles at the mapped ids (absent: the csv is not in the data copy). "
             "'incident' = listed queries whose elements share a vertex. 'missing' = colliding queries not in the "
             "contestant's set (must be 0); 'found' = listed queries in it.")
    o.append("")
    whos_gt = list(dict.fromkeys(g["who"] for g in gt_rows))
    o.append("Missing colliding queries per contestant at r = 0 (every radius run is checked: D(0) lies within D(r)):")
    o.append("")
    o.append("| scene | kind | listed | colliding | incident | coords | " + " | ".join(whos_gt) + " |")
    o.append("|---|---|---|---|---|---|" + "---|" * len(whos_gt))
    for key in dict.fromkeys((g["scene"], g["kind"]) for g in gt_rows):
        gs = [g for g in gt_rows if (g["scene"], g["kind"]) == key and g["r_rel"] == 0] or \
             [g for g in gt_rows if (g["scene"], g["kind"]) == key]
        g0 = gs[0]
        cells = []
        for w in whos_gt:
            gw = [g for g in gs if g["who"] == w]
            cells.append("-" if not gw else f"**{gw[0]['missing']}**" + (f" {gw[0]['missing_pairs']}" if gw[0]["missing"] else ""))
        o.append(f"| {key[0]} | {key[1].upper()} | {g0['listed']} | {g0['colliding']} | {g0['incident']} | {g0['checked']} | "
                 + " | ".join(cells) + " |")
    o.append("")
    other = [g for g in gt_rows if g["r_rel"] != 0]
    if other:
        miss = sum(g["missing"] for g in other)
        radii_other = ", ".join(sorted({f"{g['r_rel']:g}" for g in other}))
        o.append(f"At the other radii ({radii_other} x mean edge): "
                 f"{miss} colliding queries missing over every contestant and scene; listed queries found: "
                 + ", ".join(f"{w} {sum(g['found_listed'] for g in other if g['who'] == w)}/{sum(g['listed'] for g in other if g['who'] == w)}"
                             for w in whos_gt) + ".")
        o.append("")
    zero = [g for g in gt_rows if g["r_rel"] == 0]
    if zero:
        o.append("Listed queries (colliding or not) found at r = 0: " + ", ".join(
                     f"{w} {sum(g['found_listed'] for g in zero if g['who'] == w)}/{sum(g['listed'] for g in zero if g['who'] == w)}"
                     for w in whos_gt) + ".")
        o.append("")


def rkey(row):
    """A row's radius, for grouping: the named radius (e.g. 'contact') or r / mean edge."""
    return row.get("r_tag") or row["r_rel"]


def rtext(row):
    return f"{row['r_rel']:g}" if not row.get("r_tag") else f"{row['r_tag']} ({row['r_rel']:.3g})"


def per_scene(o, srows):
    r0 = srows[0]
    o.append(f"### {r0['scene']}")
    o.append("")
    if "run" in r0:
        o.append(f"Newton run `{r0['run']}`, frames {r0['frame0']} -> {r0['frame0'] + 1} of {r0['frames']}; "
                 f"contact radius {r0['query']:.4g} = {r0['query'] / r0['mean_edge']:.3g} x mean edge "
                 f"(mean edge {r0['mean_edge']:.4g}). No ground truth.")
        o.append("")
    o.append(f"{r0['nV']} vertices, {r0['nF']} triangles, {r0['nE']} edges; vertex motion over the step: max "
             f"{r0['motion_max']:.3g}, mean {r0['motion_mean']:.3g} x mean edge.")
    o.append("")
    o.append("| r / mean edge | contestant | ms | / fastest ipctk | VT (FV) pairs | VT excess / miss | EE pairs | "
             "EE excess / miss | exact D(r): VT, EE |")
    o.append("|---|---|---|---|---|---|---|---|---|")
    for r in srows:
        vtx = (f"{r['vt_excess']} / {r['vt_miss']}" if r["vt_excess"] is not None
               else ("within box set" if r["capsule_in_box"] else "**not within box set**"))
        o.append(f"| {rtext(r)} | {r['who']} | {fmt_ms(r)} | {r['ratio']:.3g}x | {r['vt']} | {vtx} | {r['ee']} | "
                 f"{r['ee_excess']} / {r['ee_miss']} | {r['D_vt']}, {r['D_ee']} |")
    o.append("")
    for x in dict.fromkeys(rtext(r) for r in srows):
        p = next(r["parts"] for r in srows if rtext(r) == x)
        o.append(f"minkq's parts at r = {x} x mean edge (median ms): " + ", ".join(f"{k} {v:.2f}" for k, v in p.items())
                 + ".")
        o.append("")
