#!/usr/bin/env python3
"""minkq's swept (CCD broad phase) queries beside ipctk's broad phases, on the Scalable CCD sample data.

Per scene of the Scalable CCD sample data (Belgrod et al. 2023: two consecutive frames, the
step's ground-truth queries and which of them collide), with x0 / x1 = the two frames' vertices
in double:
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

usage: ccd_peers.py [--data DIR] [--out FILE] [--repeats N] [--threads N] [--only SCENE,...]
                    [--radii R,...] [--brute-force-max N] [--save JSON] [--render JSON]
  --data: the sample data: a checkout of the public Sample-Scalable-CCD-Data repository, or a
          bare git clone of it (read with git cat-file); default: $MINKQ_CCD_DATA, else the first
          of ../shared/data/Sample-Scalable-CCD-Data, ../shared/data/scalable-ccd-sample,
          build-bench/Sample-Scalable-CCD-Data that exists. A scene whose frames are absent
          (large blobs a clone may lack) is skipped by name on stderr.
  --radii: r as multiples of the scene's mean edge length (default 0,0.01: r = 0 for the
           ground truth, and a contact-margin-like radius).
Needs numpy, ipctk and minkq importable (PYTHONPATH=bindings/python/python with libminkq.so on
LD_LIBRARY_PATH, or the wheel).
"""
from __future__ import annotations

import argparse
import datetime
import io
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import time
from fractions import Fraction

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--data")
    p.add_argument("--out", default=os.path.join(ROOT, "bench", "results", "ccd_peers.md"))
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--only", default="")
    p.add_argument("--radii", default="0,0.01")
    p.add_argument("--brute-force-max", type=float, default=6e8)
    p.add_argument("--save", help="also write the measured rows to this JSON file")
    p.add_argument("--render", help="write the tables from a --save file, measuring nothing")
    return p.parse_args()


ARGS = parse_args()
if ARGS.threads > 0:  # before TBB starts in either library: both size their pools from the mask
    cpus = sorted(os.sched_getaffinity(0))[: ARGS.threads]
    os.sched_setaffinity(0, cpus)
THREADS = len(os.sched_getaffinity(0))

import ipctk  # noqa: E402
import minkq  # noqa: E402

ipctk.set_num_threads(THREADS)


# ---- data ------------------------------------------------------------------------------------


class Source:
    """Files of the sample data: a folder, or a bare git clone (HEAD's tree)."""

    def __init__(self, path):
        self.path = path
        self.git = not os.path.isdir(os.path.join(path, "armadillo-rollers")) and os.path.exists(os.path.join(path, "HEAD"))
        if self.git:
            out = subprocess.run(["git", "--git-dir", path, "ls-tree", "-r", "--name-only", "HEAD"],
                                 capture_output=True, text=True, check=True).stdout
            self.files = out.split()
            self.commit = subprocess.run(["git", "--git-dir", path, "rev-parse", "HEAD"], capture_output=True,
                                         text=True).stdout.strip()
        else:
            self.files = []
            for d, _, fs in os.walk(path):
                for f in fs:
                    self.files.append(os.path.relpath(os.path.join(d, f), path))
            self.commit = ""

    def read(self, rel):
        if self.git:
            r = subprocess.run(["git", "--git-dir", self.path, "cat-file", "blob", "HEAD:" + rel], capture_output=True)
            return r.stdout if r.returncode == 0 else None
        try:
            with open(os.path.join(self.path, rel), "rb") as f:
                return f.read()
        except OSError:
            return None


def read_ply(data):
    head_end = data.index(b"end_header") + len(b"end_header")
    head_end = data.index(b"\n", head_end) + 1
    lines = data[:head_end].decode("ascii").splitlines()
    fmt = None
    elements = []
    for ln in lines:
        t = ln.split()
        if not t:
            continue
        if t[0] == "format":
            fmt = t[1]
        elif t[0] == "element":
            elements.append([t[1], int(t[2]), []])
        elif t[0] == "property":
            elements[-1][2].append(t[1:])
    types = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2", "ushort": "u2",
             "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4",
             "double": "f8", "float64": "f8"}
    body = data[head_end:]
    if fmt == "ascii":
        vals = body.split()
        pos, V, F = 0, None, None
        for name, n, props in elements:
            if name == "vertex":
                k = len(props)
                a = np.array(vals[pos:pos + n * k], dtype=np.float64).reshape(n, k)
                names = [p[-1] for p in props]
                V = a[:, [names.index(c) for c in "xyz"]]
                pos += n * k
            elif name == "face":
                F = np.empty((n, 3), np.int32)
                for i in range(n):
                    c = int(vals[pos])
                    assert c == 3, "non-triangle face"
                    F[i] = [int(x) for x in vals[pos + 1:pos + 4]]
                    pos += 1 + c
        return V, F
    end = "<" if fmt == "binary_little_endian" else ">"
    pos, V, F = 0, None, None
    for name, n, props in elements:
        if props and props[0][0] == "list":
            assert name == "face" and len(props) == 1
            ct, it = types[props[0][1]], types[props[0][2]]
            dt = np.dtype([("c", end + ct), ("i", end + it, (3,))])
            a = np.frombuffer(body, dt, n, pos)
            assert (a["c"] == 3).all(), "non-triangle face"
            F = a["i"].astype(np.int32)
            pos += n * dt.itemsize
        else:
            dt = np.dtype([(p[1], end + types[p[0]]) for p in props])
            a = np.frombuffer(body, dt, n, pos)
            pos += n * dt.itemsize
            if name == "vertex":
                V = np.stack([a[c].astype(np.float64) for c in "xyz"], axis=1)
    return V, F


def read_obj(data):
    vs, fs = [], []
    for ln in data.decode().splitlines():
        t = ln.split()
        if not t:
            continue
        if t[0] == "v":
            vs.append([float(x) for x in t[1:4]])
        elif t[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in t[1:]]
            for k in range(1, len(idx) - 1):
                fs.append([idx[0], idx[k], idx[k + 1]])
    return np.array(vs, np.float64), np.array(fs, np.int32)


def read_mesh(src, rel):
    data = src.read(rel)
    if data is None:
        return None
    return read_ply(data) if rel.endswith(".ply") else read_obj(data)


def igl_edges(F):
    """igl::edges(F): the undirected edges, (min, max), in the order of the adjacency matrix's
    column-major nonzeros: sorted by (max, min)."""
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e = np.sort(e, axis=1)
    e = np.unique(e, axis=0)
    return e[np.lexsort((e[:, 0], e[:, 1]))]


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


def pair_keys(a, b, n):
    return a.astype(np.int64) * n + b.astype(np.int64)


def find_scenes(src):
    scenes = {}
    for f in src.files:
        m = re.match(r"([^/]+)/boxes/(\d+)vf\.json$", f)
        if m:
            scenes[m.group(1)] = m.group(2)
    out = []
    for name in sorted(scenes):
        frames = [f for f in src.files if f.startswith(name + "/frames/") and f.endswith((".ply", ".obj"))]
        frames.sort(key=lambda f: int(re.findall(r"\d+", os.path.basename(f))[-1]))
        out.append((name, scenes[name], frames))
    return out


def rationals(csv):
    rows = np.loadtxt(io.BytesIO(csv), delimiter=",", dtype=object)
    if rows.ndim == 1:
        rows = rows[None]
    return np.array([[float(Fraction(int(r[2 * k]), int(r[2 * k + 1]))) for k in range(3)] for r in rows])


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
    if len(frames) < 2:
        print(f"ccd_peers: {name}: skipped (fewer than two frames listed)", file=sys.stderr)
        return
    m0, m1 = read_mesh(src, frames[0]), read_mesh(src, frames[1])
    if m0 is None or m1 is None:
        print(f"ccd_peers: {name}: skipped (frames {frames[0]}, {frames[1]} absent from {src.path})", file=sys.stderr)
        notes.append(f"{name}: skipped, its frames are absent from the data copy")
        return
    (V0, F), (V1, F1) = m0, m1
    assert (F == F1).all() and V0.shape == V1.shape
    V0 = np.ascontiguousarray(V0)
    V1 = np.ascontiguousarray(V1)
    F = np.ascontiguousarray(F, np.int32)
    nV, nF = len(V0), len(F)
    E_igl = igl_edges(F)
    nE = len(E_igl)
    t0 = time.perf_counter()
    scene = minkq.Scene(device, V0, F)           # float64: the guarantee in double
    scene0 = minkq.Scene(device, V0, F)          # built at x0, refit_swept each round
    E = np.ascontiguousarray(scene.edges(), np.int32)
    assert len(E) == nE
    # minkq's edges are (min, max) lexicographic; map igl's order onto them.
    ekey = pair_keys(E[:, 0], E[:, 1], nV)
    igl_to_minkq = np.searchsorted(ekey, pair_keys(E_igl[:, 0], E_igl[:, 1], nV))
    assert (ekey[igl_to_minkq] == pair_keys(E_igl[:, 0], E_igl[:, 1], nV)).all()
    mean_edge = float(np.mean(np.linalg.norm(V0[E[:, 0]] - V0[E[:, 1]], axis=1)))
    motion = np.linalg.norm(V1 - V0, axis=1)
    print(f"ccd_peers: {name}: {nV} vertices, {nF} triangles, {nE} edges, mean edge {mean_edge:.3g}", file=sys.stderr)

    # Ground truth: ids of the combined box array; checked against the queries' coordinates where present.
    gt = {}
    for kind in ("vf", "ee"):
        boxes = json.loads(src.read(f"{name}/boxes/{step}{kind}.json"))
        coll = json.loads(src.read(f"{name}/mma_bool/{step}{kind}_mma_bool.json"))
        b = np.array(boxes, np.int64).reshape(-1, 2)
        coll = np.array(coll, bool)
        assert len(coll) == len(b)
        if kind == "vf":
            v, f = b[:, 0], b[:, 1] - nV - nE
            assert ((v >= 0) & (v < nV) & (f >= 0) & (f < nF)).all()
            ids = np.stack([v, f], 1)
            verts = np.concatenate([v[:, None], F[f]], axis=1)
        else:
            ea, eb = b[:, 0] - nV, b[:, 1] - nV
            assert ((ea >= 0) & (ea < nE) & (eb >= 0) & (eb < nE)).all()
            ma, mb = igl_to_minkq[ea], igl_to_minkq[eb]
            ids = np.stack([np.minimum(ma, mb), np.maximum(ma, mb)], 1)
            verts = np.concatenate([E_igl[ea], E_igl[eb]], axis=1)
        csv = src.read(f"{name}/queries/{step}{kind}.csv")
        checked = "absent"
        if csv is not None:
            q = rationals(csv).reshape(-1, 8, 3)
            assert len(q) == len(b), (len(q), len(b))
            ok = (q[:, :4] == V0[verts]).all(axis=(1, 2)) & (q[:, 4:] == V1[verts]).all(axis=(1, 2))
            checked = f"{int(ok.sum())}/{len(ok)} match"
            if not ok.all():
                notes.append(f"{name} {kind}: {int((~ok).sum())} queries' coordinates differ from the frames at their ids")
        incident = np.array([len(set(r)) < len(r) for r in verts.tolist()])
        gt[kind] = dict(ids=ids, coll=coll, checked=checked, incident=int(incident.sum()))

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

    for rel in [float(x) for x in ARGS.radii.split(",")]:
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
            return scene.query("vt", "box", r), scene.query("ee", "box", r)

        def mk_refit():
            scene0.refit_swept(V0, V1)
            return scene0.query("vt", "box", r), scene0.query("ee", "box", r)

        def mk_refit_capsule():
            scene0.refit_swept(V0, V1)
            return scene0.query("vt", "capsule_exact", r), scene0.query("ee", "box", r)
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
                scene0.query(k, mode, r)
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
                motion_max=float(motion.max()) / mean_edge, motion_mean=float(motion.mean()) / mean_edge))
        # Ground truth against every set, at every radius (r >= 0: D(0) is within D(r)).
        for n in sets:
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


# ---- report ------------------------------------------------------------------------------------


def fmt_ms(row):
    return f"{row['ms']:.2f} ({row['lo']:.2f}-{row['hi']:.2f})"


def geomean(xs):
    xs = [x for x in xs if x > 0]
    return float(np.exp(np.mean(np.log(xs)))) if xs else float("nan")


def write(rows, gt_rows, notes, src, load0, load1=None, written=None):
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load1 = os.getloadavg()[0] if load1 is None else load1
    written = written or f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"
    o = ["# Swept queries beside ipctk's CCD broad phases (Scalable CCD sample data)", ""]
    o.append(f"Machine: {cpu}, {os.cpu_count()} CPUs, {THREADS} used by both libraries (process pinned to them; "
             f"ipctk.set_num_threads({THREADS}), minkq's CPU device: {minkq.Device('cpu').name}); Python "
             f"{platform.python_version()}, numpy {np.__version__}, ipctk {getattr(ipctk, '__version__', '?')} (PyPI wheel), "
             f"minkq {'.'.join(map(str, minkq.version()))}. Load average (1 min) at start {load0:.2f}, at write {load1:.2f}. "
             f"Written {written} UTC by `bench/ccd_peers.py`"
             f" --repeats {ARGS.repeats}.")
    o.append("")
    o.append("Data: the Scalable CCD sample data (Belgrod et al. 2023, public repository "
             f"Continuous-Collision-Detection/Sample-Scalable-CCD-Data{', commit ' + src.commit[:10] if src.commit else ''}): "
             "per scene two consecutive frames (x0, x1, read as doubles) and the step's ground-truth queries. "
             "Every contestant gets the same doubles and mesh (edges: minkq's `scene.edges()`, handed to ipctk's "
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
    o.append("Geomean over the scenes of each contestant's time over the fastest ipctk broad phase (per scene, per r):")
    o.append("")
    radii = sorted(set(r["r_rel"] for r in rows))
    whos = list(dict.fromkeys(r["who"] for r in rows))
    o.append("| contestant | " + " | ".join(f"r = {x:g} x mean edge" for x in radii) + " |")
    o.append("|---|" + "---|" * len(radii))
    for w in whos:
        cells = []
        for x in radii:
            rs = [r["ratio"] for r in rows if r["who"] == w and r["r_rel"] == x]
            scenes = len(rs)
            cells.append(f"{geomean(rs):.3g}x ({scenes} scenes)" if rs else "-")
        o.append(f"| {w} | " + " | ".join(cells) + " |")
    o.append("")
    fastest = {}
    for r in rows:
        if r["who"].startswith("ipctk"):
            k = (r["scene"], r["r_rel"])
            if k not in fastest or r["ms"] < fastest[k][1]:
                fastest[k] = (r["who"], r["ms"])
    o.append("Fastest ipctk broad phase per scene and r: " + "; ".join(
        f"{s} r={x:g}: {w[6:]} {ms:.1f} ms" for (s, x), (w, ms) in sorted(fastest.items())) + ".")
    o.append("")
    o.append("Pair sets against the exact swept-box set D(r), over every scene and r (VT = FV):")
    o.append("")
    o.append("| contestant | runs equal to D(r) | largest VT excess / D | largest EE excess / D | pairs of D(r) missed |")
    o.append("|---|---|---|---|---|")
    for w in whos:
        rs = [r for r in rows if r["who"] == w]
        if "capsule" in w:
            ratio = [r["vt"] / max(r["D_vt"], 1) for r in rs]
            o.append(f"| {w} | (VT: no ipctk counterpart; {min(ratio):.3g}-{max(ratio):.3g}x the VT pairs of D(r), "
                     f"within the box set: {sum(bool(r['capsule_in_box']) for r in rs)}/{len(rs)}) | - | "
                     f"{max(r['ee_excess'] / max(r['D_ee'], 1) for r in rs):.2g} | EE {sum(r['ee_miss'] for r in rs)} |")
            continue
        eq = sum(1 for r in rs if r["vt_excess"] == 0 and r["ee_excess"] == 0 and r["vt_miss"] == 0 and r["ee_miss"] == 0)
        o.append(f"| {w} | {eq}/{len(rs)} | {max(r['vt_excess'] / max(r['D_vt'], 1) for r in rs):.2g} | "
                 f"{max(r['ee_excess'] / max(r['D_ee'], 1) for r in rs):.2g} | "
                 f"{sum(r['vt_miss'] + r['ee_miss'] for r in rs)} |")
    o.append("")
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
    o.append("## Per scene")
    o.append("")
    for s in dict.fromkeys(r["scene"] for r in rows):
        srows = [r for r in rows if r["scene"] == s]
        r0 = srows[0]
        o.append(f"### {s}")
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
            o.append(f"| {r['r_rel']:g} | {r['who']} | {fmt_ms(r)} | {r['ratio']:.3g}x | {r['vt']} | {vtx} | {r['ee']} | "
                     f"{r['ee_excess']} / {r['ee_miss']} | {r['D_vt']}, {r['D_ee']} |")
        o.append("")
        for x in sorted(set(r["r_rel"] for r in srows)):
            p = next(r["parts"] for r in srows if r["r_rel"] == x)
            o.append(f"minkq's parts at r = {x:g} x mean edge (median ms): " + ", ".join(f"{k} {v:.2f}" for k, v in p.items())
                     + ".")
            o.append("")
    if notes:
        o.append("## Notes")
        o.append("")
        for n in notes:
            o.append(f"- {n}")
        o.append("")
    os.makedirs(os.path.dirname(os.path.abspath(ARGS.out)), exist_ok=True)
    with open(ARGS.out, "w") as f:
        f.write("\n".join(o))
    print(f"ccd_peers: wrote {ARGS.out}", file=sys.stderr)


def default_data():
    cands = [os.environ.get("MINKQ_CCD_DATA", "")]
    cands += [os.path.join(ROOT, "..", "shared", "data", d) for d in ("Sample-Scalable-CCD-Data", "scalable-ccd-sample")]
    cands.append(os.path.join(ROOT, "build-bench", "Sample-Scalable-CCD-Data"))
    for c in cands:
        if c and os.path.exists(c):
            return c
    return None


def main():
    if ARGS.render:
        with open(ARGS.render) as f:
            d = json.load(f)
        src = Source.__new__(Source)
        src.path, src.commit = d["data"], d["commit"]
        write(d["rows"], d["gt_rows"], d["notes"], src, d["load0"], d["load1"], d["written"])
        return 0
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
    write(rows, gt_rows, notes, src, load0)
    if ARGS.save:
        with open(ARGS.save, "w") as f:
            json.dump(dict(rows=rows, gt_rows=gt_rows, notes=notes, data=src.path, commit=src.commit, load0=load0,
                           load1=os.getloadavg()[0], written=f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M}"), f,
                      default=lambda x: x.item() if hasattr(x, "item") else str(x))
    bad = [g for g in gt_rows if g["missing"] and g["who"].startswith("minkq")]
    bad += [r for r in rows if r["who"].startswith("minkq") and ((r["vt_miss"] or 0) or r["ee_miss"])]
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
