#!/usr/bin/env python3
"""minkq's swept (CCD broad phase) queries beside ipctk's broad phases, on the Scalable CCD sample data or Newton cloth runs.

Two frame sources, the same contestants and checks:
  - --source scalable-ccd (the default): per scene of the Scalable CCD sample data (Belgrod et
    al. 2023: two consecutive frames, the step's ground-truth queries and which of them
    collide), x0 / x1 = the two frames' vertices in double; writes bench/results/ccd_peers.md;
  - --source newton (or --newton): Newton cloth runs simulated here on Warp's CPU device (see
    "Newton runs" below); per run, --newton-pairs consecutive frame pairs at its end, x0 / x1 =
    the particle positions after frames f and f + 1 (Warp's float32, as float64: exact), with
    the cloth's triangles; no ground truth (a simulation lists no colliding queries), so only
    the exact D(r) checks below apply; writes bench/results/ccd_newton.md.
Per frame pair:
  - ipctk (IPC Toolkit, PyPI): ``Candidates().build(CollisionMesh(V0, E, F), V0, V1,
    inflation_radius = r / 2, broad_phase)`` with each of its CPU broad phases (BruteForce only
    where its all-pairs work fits --brute-force-max); its face-vertex (fv) and edge-edge (ee)
    candidates;
  - minkq: a float64 ``minkq.Scene`` (VT + EE, incident pairs dropped) and its swept queries:
    VT box (the vertex path's box grown by r against each triangle's swept box), VT capsule_exact
    (the capsule of radius r around the path) and EE box (swept edge boxes, per-axis gap <= r),
    after ``rebuild_swept(x0, x1)`` (trees built afresh, as ipctk does every call) and after
    ``refit_swept(x0, x1)`` of a scene built at x0 (a simulator's steps);
on the same threads (--threads N pins the process to N CPUs before either library starts TBB,
and ipctk.set_num_threads(N); default: every CPU), round-robin: one warm-up round, then
--repeats rounds, medians.

Definitions (ipctk's source, src/ipc/broad_phase/aabb.cpp and broad_phase.cpp): a vertex box is
the box of x0 and x1 grown by the inflation radius (each bound nudged one double ulp outward),
edge and face boxes are the unions of their vertices' boxes, boxes overlap when every axis'
closed intervals meet, and pairs sharing a vertex are dropped (can_edges_collide,
can_face_vertex_collide). Two such boxes meet when the uninflated swept boxes' per-axis gap is
at most twice the inflation: ipctk at r / 2 and minkq's box modes at r test the same exact set
D(r) = {pairs whose swept boxes have every per-axis gap <= r}. Both are conservative supersets
of it (ipctk's nudges; its LBVH stores float boxes rounded outward, its SweepAndPrune may run
scalable_ccd in float; minkq's float trees widen r by the float64 scene's rounding), so the
table gives |D(r)|, decided exactly for every pair either side reports, each set's excess over
it and its misses (must be 0).

Ground truth: boxes/<step>{vf,ee}.json lists the step's queries as ids of Scalable CCD's
combined box array (vertices, then igl::edges(F) edges, then faces; tests/test_broad_phase.cpp
there adds these offsets), mma_bool/ says which of them collide (Mathematica, exact). Every
colliding query must be in minkq's sets at r = 0 (VT box, VT capsule_exact, EE box): 'missing'
must be 0 (exit 1 otherwise). Where queries/<step>{vf,ee}.csv is present, the id mapping is
checked against the query's rational coordinates.

Newton runs (--newton-scenes NAME[:FRAMES],..., default vbd_twist,cloth_twist,cloth_hanging):
  - vbd_twist (90 frames): bench/peers/newton_vbd.py's twisted sheet (its TwistScene: --newton-cells
    cells a side, default 40, columns pinned and turned, SolverVBD with self-contact);
  - cloth_twist (100 frames), cloth_hanging (60 frames): Newton's own examples, unmodified
    (newton.examples.cloth.*: Example(ViewerNull, its default arguments), graph capture as the
    example does it on the CPU), stepped frame by frame.
  Radii (default 0,0.01,contact): 'contact' = the run's self-contact detection radius
  (SolverVBD's margin + gap). --newton-cache NPZ keeps the simulated frames (read back when a
  scene's frames, pairs and cells match; the simulation is most of the run time). Needs
  warp-lang 1.19 and newton 1.8 (bindings/test.sh's venv) beside ipctk.

usage: ccd_peers.py [--source scalable-ccd|newton] [--newton] [--data DIR] [--out FILE] [--repeats N]
                    [--threads N] [--only SCENE,...] [--radii R,...] [--brute-force-max N]
                    [--newton-scenes NAME[:FRAMES],...] [--newton-pairs K] [--newton-cells N]
                    [--newton-cache NPZ] [--save JSON] [--render JSON]
  --data: the sample data: a checkout of the public Sample-Scalable-CCD-Data repository, or a
          bare git clone of it (read with git cat-file); default: $MINKQ_CCD_DATA, else the first
          of ../shared/data/Sample-Scalable-CCD-Data, ../shared/data/scalable-ccd-sample,
          build-bench/Sample-Scalable-CCD-Data that exists. A scene whose frames are absent
          (large blobs a clone may lack) is skipped by name on stderr.
  --radii: r as multiples of the scene's mean edge length (default 0,0.01: r = 0 for the
           ground truth, and a contact-margin-like radius), or 'contact' (Newton runs).
  --only: substrings of the scene names (Newton: "RUN F-F+1", e.g. "cloth_twist 148-149").
This file: the options, the contestants and their comparison (compare), the runs; the frame sources
(Scalable CCD data reading, id mapping, ground truth; the Newton runs and their cache) are in
ccd_sources.py, the markdown tables in ccd_report.py (sibling modules, found from any cwd).
Needs numpy, ipctk and minkq importable (PYTHONPATH=bindings/python/python with libminkq.so on
LD_LIBRARY_PATH, or the wheel).
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import statistics
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench", "peers"))  # the sibling modules, from any cwd
from ccd_sources import (NEWTON_SCENES, Source, default_data, find_scenes, ground_truth_of,  # noqa: E402
                         newton_runs, pair_keys, scene_frames)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data")
    p.add_argument("--source", choices=["scalable-ccd", "newton"], default="scalable-ccd")
    p.add_argument("--newton", dest="source", action="store_const", const="newton", help="--source newton")
    p.add_argument("--out")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--only", default="")
    p.add_argument("--radii")
    p.add_argument("--newton-scenes", default="vbd_twist,cloth_twist,cloth_hanging")
    p.add_argument("--newton-pairs", type=int, default=3)
    p.add_argument("--newton-cells", type=int, default=40)
    p.add_argument("--newton-cache")
    p.add_argument("--brute-force-max", type=float, default=6e8)
    p.add_argument("--save", help="also write the measured rows to this JSON file")
    p.add_argument("--render", help="write the tables from a --save file, measuring nothing")
    a = p.parse_args()
    newton = a.source == "newton"
    if a.out is None:
        a.out = os.path.join(ROOT, "bench", "results", "ccd_newton.md" if newton else "ccd_peers.md")
    if a.radii is None:
        a.radii = "0,0.01,contact" if newton else "0,0.01"
    return a


ARGS = parse_args()
if ARGS.threads > 0:  # before TBB starts in either library: both size their pools from the mask
    cpus = sorted(os.sched_getaffinity(0))[: ARGS.threads]
    os.sched_setaffinity(0, cpus)
THREADS = len(os.sched_getaffinity(0))

import ipctk  # noqa: E402
import minkq  # noqa: E402

ipctk.set_num_threads(THREADS)

from ccd_report import write  # noqa: E402


# ---- pair sets ------------------------------------------------------------------------------


def uniq(a):
    """Sorted distinct values (np.unique's hash path is slow on millions of int64 here)."""
    a = np.sort(np.asarray(a, np.int64))
    return a[np.r_[True, a[1:] != a[:-1]]] if len(a) else a


def member(a, b):
    """For each value of a, whether it is in b (sorted, distinct)."""
    if len(b) == 0:
        return np.zeros(len(a), bool)
    i = np.minimum(np.searchsorted(b, a), len(b) - 1)
    return b[i] == a


def count_not_in(a, b):
    return int((~member(a, b)).sum())


# ---- exact box test ------------------------------------------------------------------------


def exact_in_box_set(lo_a, hi_a, lo_b, hi_b, r):
    """For rows of boxes (exact doubles), whether every axis' gap is <= r, decided exactly: the
    gap x - y is s + e exactly (s = fl(x - y), e its rounding error, Knuth's TwoSum), so
    x - y <= r iff s < r, or s == r and e <= 0."""
    def le(x, y):
        s = x - y
        bv = s - x
        e = (x - (s - bv)) + (-y - bv)
        return (s < r) | ((s == r) & (e <= 0))
    return (le(lo_b, hi_a) & le(lo_a, hi_b)).all(axis=1)


# ---- one scene ---------------------------------------------------------------------------------


def median_ms(ts):
    return 1e3 * statistics.median(ts)


def run_scene(src, name, step, frames, device, rows, gt_rows, notes):
    fr = scene_frames(src, name, frames, notes)
    if fr is None:
        return
    V0, V1, F = fr
    compare(name, V0, V1, F, device, rows, gt_rows, notes, ARGS.radii.split(","),
            ground_truth=ground_truth_of(src, name, step, notes))


def compare(name, V0, V1, F, device, rows, gt_rows, notes, radii, named_radii=None, ground_truth=None, info=None):
    """The contestants on one frame pair (x0, x1 in double, triangles F): timings, pair sets against
    the exact D(r) and, where ground_truth gives one, the step's colliding queries. radii: tokens,
    each a multiple of the mean edge length or a name of named_radii (an absolute radius)."""
    V0 = np.ascontiguousarray(V0, np.float64)
    V1 = np.ascontiguousarray(V1, np.float64)
    F = np.ascontiguousarray(F, np.int32)
    assert V0.shape == V1.shape
    nV, nF = len(V0), len(F)
    t0 = time.perf_counter()
    scene = minkq.Scene(V0, F, device=device)  # float64: the guarantee in double
    scene0 = minkq.Scene(V0, F, device=device)  # built at x0, refit_swept each round
    E = np.ascontiguousarray(scene.edges(), np.int32)
    nE = len(E)
    mean_edge = float(np.mean(np.linalg.norm(V0[E[:, 0]] - V0[E[:, 1]], axis=1)))
    motion = np.linalg.norm(V1 - V0, axis=1)
    print(f"ccd_peers: {name}: {nV} vertices, {nF} triangles, {nE} edges, mean edge {mean_edge:.3g}", file=sys.stderr)
    gt = ground_truth(V0, V1, F, E) if ground_truth else None

    def vt_key(p):
        return pair_keys(p[:, 0], p[:, 1], nF)

    def ee_key(p):
        return pair_keys(p[:, 0], p[:, 1], nE)

    # Swept boxes in double, for the exact D(r) test.
    lo_v, hi_v = np.minimum(V0, V1), np.maximum(V0, V1)
    lo_f, hi_f = lo_v[F].min(axis=1), hi_v[F].max(axis=1)
    lo_e, hi_e = lo_v[E].min(axis=1), hi_v[E].max(axis=1)

    mesh = ipctk.CollisionMesh(V0, E, F)
    V0f, V1f = np.asfortranarray(V0), np.asfortranarray(V1)
    phases = [("LBVH", ipctk.LBVH), ("HashGrid", ipctk.HashGrid), ("SweepAndPrune", ipctk.SweepAndPrune)]
    brute_work = float(nV) * nF + float(nE) * nE / 2
    if brute_work <= ARGS.brute_force_max:
        phases.append(("BruteForce", ipctk.BruteForce))
    else:
        notes.append(f"{name}: ipctk BruteForce not run ({brute_work:.2g} box pairs > --brute-force-max {ARGS.brute_force_max:.2g})")

    for tok in radii:
        if tok in (named_radii or {}):
            tag, r = tok, float(named_radii[tok])
            rel = r / mean_edge
        else:
            tag, rel = None, float(tok)
            r = rel * mean_edge
        cands = {}
        contestants = []
        for pname, cls in phases:
            bp = cls()
            c = ipctk.Candidates()

            def run_ipc(bp=bp, c=c):
                c.build(mesh, V0f, V1f, r / 2, bp)
                return c
            contestants.append((f"ipctk {pname}", run_ipc))

        def mk_rebuild():
            scene.rebuild_swept(V0, V1)
            return scene.query("vt", r), scene.query("ee", r)

        def mk_refit():
            scene0.refit_swept(V0, V1)
            return scene0.query("vt", r), scene0.query("ee", r)

        def mk_refit_capsule():
            scene0.refit_swept(V0, V1)
            return scene0.query("vt", r, mode="capsule_exact"), scene0.query("ee", r)
        contestants += [("minkq rebuild_swept, VT box + EE box", mk_rebuild),
                        ("minkq refit_swept, VT box + EE box", mk_refit),
                        ("minkq refit_swept, VT capsule_exact + EE box", mk_refit_capsule)]
        # Split timings of minkq's parts (same rounds).
        parts = {"refit_swept": lambda: scene0.refit_swept(V0, V1), "rebuild_swept": lambda: scene.rebuild_swept(V0, V1)}
        times = {n: [] for n, _ in contestants}
        ptimes = {n: [] for n in list(parts) + ["query VT box", "query VT capsule_exact", "query EE box"]}
        out = {}
        for rnd in range(ARGS.repeats + 1):
            for n, fn in contestants:
                t = time.perf_counter()
                res = fn()
                dt = time.perf_counter() - t
                if rnd:
                    times[n].append(dt)
                else:
                    out[n] = res
            for n, fn in parts.items():
                t = time.perf_counter()
                fn()
                dt = time.perf_counter() - t
                if rnd:
                    ptimes[n].append(dt)
            scene0.refit_swept(V0, V1)
            for n, (k, mode) in {"query VT box": ("vt", "box"), "query VT capsule_exact": ("vt", "capsule_exact"),
                                 "query EE box": ("ee", "box")}.items():
                t = time.perf_counter()
                scene0.query(k, r, mode=mode)
                dt = time.perf_counter() - t
                if rnd:
                    ptimes[n].append(dt)

        print(f"ccd_peers: {name} r={rel:g}x: timed ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
        # Pair sets.
        sets = {}
        for n, res in out.items():
            if n.startswith("ipctk"):
                fvl, eel = res.fv_candidates, res.ee_candidates
                v = np.fromiter((x.vertex_id for x in fvl), np.int64, len(fvl))
                f = np.fromiter((x.face_id for x in fvl), np.int64, len(fvl))
                a = np.fromiter((x.edge0_id for x in eel), np.int64, len(eel))
                b = np.fromiter((x.edge1_id for x in eel), np.int64, len(eel))
                sets[n] = (v * nF + f, np.minimum(a, b) * nE + np.maximum(a, b))
            else:
                vt, ee = res
                sets[n] = (vt_key(np.asarray(vt)), ee_key(np.asarray(ee)))
        for n in sets:
            vt, ee = sets[n]
            uvt, uee = uniq(vt), uniq(ee)
            if len(uvt) != len(vt) or len(uee) != len(ee):
                notes.append(f"{name} r={rel:g}: {n} reports duplicate pairs (counted once below)")
            sets[n] = (uvt, uee)
        # Exact D(r) over the union of every box set (each a superset of D(r)).
        box_names = [n for n in sets if "capsule" not in n]
        union_vt = uniq(np.concatenate([sets[n][0] for n in box_names]))
        union_ee = uniq(np.concatenate([sets[n][1] for n in box_names]))
        uv, uf = union_vt // nF, union_vt % nF
        in_vt = exact_in_box_set(lo_v[uv], hi_v[uv], lo_f[uf], hi_f[uf], r)
        ua, ub = union_ee // nE, union_ee % nE
        in_ee = exact_in_box_set(lo_e[ua], hi_e[ua], lo_e[ub], hi_e[ub], r)
        # incident pairs are not in D(r) as both define it
        fv_inc = (F[uf] == uv[:, None]).any(axis=1)
        ee_inc = (E[ua][:, :, None] == E[ub][:, None, :]).any(axis=(1, 2))
        D_vt, D_ee = union_vt[in_vt & ~fv_inc], union_ee[in_ee & ~ee_inc]

        print(f"ccd_peers: {name} r={rel:g}x: sets compared ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
        fastest_ipc = min(median_ms(times[n]) for n in times if n.startswith("ipctk"))
        same_as = {n: [m for m in box_names if m.startswith("ipctk") and np.array_equal(sets[n][0], sets[m][0])
                       and np.array_equal(sets[n][1], sets[m][1])]
                   for n in box_names if n.startswith("minkq")}
        for n in times:
            vt, ee = sets[n]
            exact = "capsule" not in n
            rows.append(dict(
                scene=name, r_rel=rel, r=r, who=n, ms=median_ms(times[n]), lo=1e3 * min(times[n]), hi=1e3 * max(times[n]),
                ratio=median_ms(times[n]) / fastest_ipc, vt=len(vt), ee=len(ee),
                vt_excess=count_not_in(vt, D_vt) if exact else None,
                ee_excess=count_not_in(ee, D_ee),
                vt_miss=count_not_in(D_vt, vt) if exact else None, ee_miss=count_not_in(D_ee, ee),
                capsule_in_box=not count_not_in(vt, sets["minkq refit_swept, VT box + EE box"][0]) if not exact else None,
                D_vt=len(D_vt), D_ee=len(D_ee), nV=nV, nF=nF, nE=nE,
                parts={k: median_ms(v) for k, v in ptimes.items()},
                motion_max=float(motion.max()) / mean_edge, motion_mean=float(motion.mean()) / mean_edge,
                mean_edge=mean_edge, r_tag=tag, same_as=same_as.get(n, []), **(info or {})))
        # Ground truth against every set, at every radius (r >= 0: D(0) is within D(r)).
        for n in (sets if gt else ()):
            vt, ee = sets[n]
            for kind, have, key in (("vf", vt, vt_key), ("ee", ee, ee_key)):
                g = gt[kind]
                k = key(g["ids"])
                found = member(k, have)
                miss_coll = np.flatnonzero(g["coll"] & ~found)
                gt_rows.append(dict(scene=name, r_rel=rel, who=n, kind=kind, listed=len(k), colliding=int(g["coll"].sum()),
                                    found_listed=int(found.sum()), missing=len(miss_coll),
                                    missing_pairs=g["ids"][miss_coll[:10]].tolist(), checked=g["checked"],
                                    incident=g["incident"]))
                if len(miss_coll):
                    print(f"ccd_peers: {name} r={rel:g} {n}: {len(miss_coll)} colliding {kind} ground-truth pairs missing, "
                          f"first {g['ids'][miss_coll[:10]].tolist()}", file=sys.stderr)
        print(f"ccd_peers: {name} r={rel:g}x: " + ", ".join(f"{n} {median_ms(t):.1f} ms" for n, t in times.items()),
              file=sys.stderr)
    print(f"ccd_peers: {name}: {time.perf_counter() - t0:.0f} s", file=sys.stderr)


def run_newton(device, rows, gt_rows, notes):
    only = [s for s in ARGS.only.split(",") if s]
    runs_meta = []
    for name, F, X, meta in newton_runs(notes, ARGS.newton_scenes, ARGS.newton_pairs, ARGS.newton_cells,
                                        ARGS.newton_cache):
        runs_meta.append(meta)
        desc = NEWTON_SCENES[name][1].format(cells=meta.get("cells"))
        first = meta["frames"] - meta["pairs"]
        for k in range(len(X) - 1):
            f = first + k
            if only and not any(o in f"{name} {f}-{f + 1}" for o in only):
                continue
            info = dict(run=name, desc=desc, frame0=f, frames=meta["frames"], margin=meta["margin"],
                        query=meta["query"], particles=meta["particles"])
            compare(f"{name} {f}-{f + 1}", X[k], X[k + 1], F, device, rows, gt_rows, notes, ARGS.radii.split(","),
                    named_radii={"contact": meta["query"]}, info=info)
    return runs_meta


def main():
    if ARGS.render:
        with open(ARGS.render) as f:
            d = json.load(f)
        src = Source.__new__(Source)
        src.path, src.commit = d["data"], d["commit"]
        write(d["rows"], d["gt_rows"], d["notes"], src, d["load0"], d["load1"], d["written"],
              d.get("source", "scalable-ccd"), d.get("runs_meta", ()), args=ARGS, threads=THREADS)
        return 0
    if ARGS.source == "newton":
        return main_newton()
    data = ARGS.data or default_data()
    if not data or not os.path.exists(data):
        print("ccd_peers: skipped (no Scalable CCD sample data: --data DIR or MINKQ_CCD_DATA)", file=sys.stderr)
        return 0
    load0 = os.getloadavg()[0]
    src = Source(data)
    device = minkq.Device("cpu")
    only = [s for s in ARGS.only.split(",") if s]
    rows, gt_rows, notes = [], [], []
    for name, step, frames in find_scenes(src):
        if only and not any(o in name for o in only):
            continue
        run_scene(src, name, step, frames, device, rows, gt_rows, notes)
    write(rows, gt_rows, notes, src, load0, args=ARGS, threads=THREADS)
    if ARGS.save:
        with open(ARGS.save, "w") as f:
            json.dump(dict(rows=rows, gt_rows=gt_rows, notes=notes, data=src.path, commit=src.commit, load0=load0,
                           load1=os.getloadavg()[0], written=f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"), f,
                      default=lambda x: x.item() if hasattr(x, "item") else str(x))
    return exit_status(rows, gt_rows)


def exit_status(rows, gt_rows):
    bad = [g for g in gt_rows if g["missing"] and g["who"].startswith("minkq")]
    bad += [r for r in rows if r["who"].startswith("minkq") and ((r["vt_miss"] or 0) or r["ee_miss"])]
    return 1 if bad else 0


def main_newton():
    load0 = os.getloadavg()[0]
    device = minkq.Device("cpu")
    rows, gt_rows, notes = [], [], []
    runs_meta = run_newton(device, rows, gt_rows, notes)
    src = Source.__new__(Source)
    src.path, src.commit = "", ""
    write(rows, gt_rows, notes, src, load0, source="newton", runs_meta=runs_meta, args=ARGS, threads=THREADS)
    if ARGS.save:
        with open(ARGS.save, "w") as f:
            json.dump(dict(rows=rows, gt_rows=gt_rows, notes=notes, data="", commit="", load0=load0, source="newton",
                           runs_meta=runs_meta, load1=os.getloadavg()[0],
                           written=f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"), f,
                      default=lambda x: x.item() if hasattr(x, "item") else str(x))
    return exit_status(rows, gt_rows)


if __name__ == "__main__":
    sys.exit(main())
