#!/usr/bin/env python3
"""The frame sources of bench/peers/ccd_peers.py: where its frame pairs (x0, x1, triangles) come from.

  - The Scalable CCD sample data (Belgrod et al. 2023): reading it from a checkout or a bare git
    clone (Source: a folder, or git ls-tree / cat-file of HEAD), its PLY / OBJ frames, the scenes
    and steps it lists, and the step's ground truth: boxes/<step>{vf,ee}.json (ids of Scalable
    CCD's combined box array: vertices, then igl::edges(F) edges, then faces) mapped to minkq's
    vertex / triangle and edge ids, mma_bool/ (which queries collide), checked against
    queries/<step>{vf,ee}.csv's rational coordinates where present.
  - Newton cloth runs (NEWTON_SCENES): simulated on Warp's CPU device (bench/peers/newton_vbd.py's
    twisted sheet, Newton's own cloth examples, unmodified), the positions of the last frames
    and the solver's self-contact radii, kept in a --newton-cache .npz.
The contestants, their comparison and the tables are ccd_peers.py's; see its docstring for the
options. Needs numpy (warp-lang and newton for the Newton runs, imported when simulating).
"""
from __future__ import annotations

import argparse
import io
import json
import os
import re
import subprocess
import sys
import time
from fractions import Fraction

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


# ---- Scalable CCD sample data -----------------------------------------------------------------


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


def default_data():
    cands = [os.environ.get("MINKQ_CCD_DATA", "")]
    cands += [os.path.join(ROOT, "..", "shared", "data", d) for d in ("Sample-Scalable-CCD-Data", "scalable-ccd-sample")]
    cands.append(os.path.join(ROOT, "build-bench", "Sample-Scalable-CCD-Data"))
    for c in cands:
        if c and os.path.exists(c):
            return c
    return None


def scene_frames(src, name, frames, notes):
    """A scene's first two frames as (V0, V1, F), or None where they are missing (said on stderr
    and, for frames absent from the data copy, in notes)."""
    if len(frames) < 2:
        print(f"ccd_peers: {name}: skipped (fewer than two frames listed)", file=sys.stderr)
        return None
    m0, m1 = read_mesh(src, frames[0]), read_mesh(src, frames[1])
    if m0 is None or m1 is None:
        print(f"ccd_peers: {name}: skipped (frames {frames[0]}, {frames[1]} absent from {src.path})", file=sys.stderr)
        notes.append(f"{name}: skipped, its frames are absent from the data copy")
        return None
    (V0, F), (V1, F1) = m0, m1
    assert (F == F1).all() and V0.shape == V1.shape
    return V0, V1, F


def ground_truth_of(src, name, step, notes):
    """compare()'s ground_truth for one Scalable CCD scene and step."""
    def ground_truth(V0, V1, F, E):
        """The step's listed queries as (vertex, triangle) and (edge, edge) ids of minkq's scene."""
        nV, nF, nE = len(V0), len(F), len(E)
        E_igl = igl_edges(F)
        assert len(E_igl) == nE
        # minkq's edges are (min, max) lexicographic; map igl's order onto them.
        ekey = pair_keys(E[:, 0], E[:, 1], nV)
        igl_to_minkq = np.searchsorted(ekey, pair_keys(E_igl[:, 0], E_igl[:, 1], nV))
        assert (ekey[igl_to_minkq] == pair_keys(E_igl[:, 0], E_igl[:, 1], nV)).all()
        return scalable_ccd_ground_truth(src, name, step, V0, V1, F, nE, E_igl, igl_to_minkq, notes)
    return ground_truth


def scalable_ccd_ground_truth(src, name, step, V0, V1, F, nE, E_igl, igl_to_minkq, notes):
    """Ground truth: ids of the combined box array; checked against the queries' coordinates where present."""
    nV, nF = len(V0), len(F)
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
    return gt


# ---- Newton cloth runs ------------------------------------------------------------------------

# name: (default frame count, what it is)
NEWTON_SCENES = {
    "vbd_twist": (90, "bench/peers/newton_vbd.py's twisted sheet (`TwistScene`): a 0.1 m square of {cells} x {cells} cells, its "
                      "left and right columns pinned and turned at pi rad/s in opposite directions about the sheet's "
                      "axis, no gravity, `SolverVBD` (4 iterations, 10 substeps a frame at 60 fps) with self-contact "
                      "(margin 0.4, gap 0.3 x the cell)"),
    "cloth_twist": (100, "Newton's example cloth_twist, unmodified (`newton.examples.cloth.example_cloth_twist`: "
                         "Newton's square_cloth asset, 50 x 50 vertices, two opposite sides turned at pi/3 rad/s "
                         "in opposite directions, no gravity, `SolverVBD`, 4 iterations, 10 substeps a frame at 60 fps, "
                         "self-contact on)"),
    "cloth_hanging": (60, "Newton's example cloth_hanging, unmodified (`newton.examples.cloth.example_cloth_hanging`, "
                          "its defaults: a 64 x 32 cell grid fixed on one side, falling under gravity and onto the "
                          "ground, `SolverVBD`, 10 substeps a frame at 60 fps, self-contact on)"),
}


def newton_scene_list(spec):
    out = []
    for item in [x for x in spec.split(",") if x]:
        name, _, frames = item.partition(":")
        if name not in NEWTON_SCENES:
            sys.exit(f"ccd_peers: unknown Newton scene {name!r} (known: {', '.join(NEWTON_SCENES)})")
        out.append((name, int(frames) if frames else NEWTON_SCENES[name][0]))
    return out


def newton_simulate(name, frames, pairs, cells):
    """Runs one Newton cloth scene on Warp's CPU device for `frames` frames and returns its
    triangles, the positions after frames frames - pairs ... frames (float32 from Warp, as
    float64: exact) and its solver's self-contact radii."""
    import warp as wp
    wp.config.quiet = True
    wp.init()
    wp.set_device("cpu")
    import newton  # noqa: F401
    t = time.perf_counter()
    if name == "vbd_twist":
        sys.path.insert(0, os.path.join(ROOT, "bench", "peers"))
        import newton_vbd
        sim = newton_vbd.TwistScene(argparse.Namespace(cells=cells, side=0.1, omega=np.pi))
        model, solver, step = sim.model, sim.solver, sim.frame
        positions = lambda: sim.state_0.particle_q  # noqa: E731
    else:
        import importlib
        import newton.examples
        import newton.viewer
        mod = importlib.import_module(newton.examples.get_examples()[name])
        parser = mod.Example.create_parser() if hasattr(mod.Example, "create_parser") else newton.examples.create_parser()
        args = parser.parse_args(["--viewer", "null", "--device", "cpu", "--num-frames", str(frames)])
        ex = mod.Example(newton.viewer.ViewerNull(num_frames=frames), args)
        model, solver, step = ex.model, ex.solver, ex.step
        positions = lambda: ex.state_0.particle_q  # noqa: E731
    X = []
    for f in range(frames + 1):
        if f >= frames - pairs:
            X.append(positions().numpy().astype(np.float64))
        if f < frames:
            step()
            if f % 10 == 0:
                print(f"ccd_peers: newton {name}: frame {f + 1}/{frames} ({time.perf_counter() - t:.0f} s)", file=sys.stderr)
    wp.synchronize()
    margin = float(solver.particle_self_contact_margin)
    query = float(getattr(solver, "_self_contact_query_radius", margin + float(solver.particle_self_contact_gap)))
    meta = dict(name=name, frames=frames, pairs=pairs, cells=cells if name == "vbd_twist" else None,
                margin=margin, query=query, sim_s=time.perf_counter() - t, particles=int(model.particle_count),
                newton=getattr(newton, "__version__", "?"), warp=wp.__version__)
    return np.ascontiguousarray(model.tri_indices.numpy(), np.int32), np.stack(X), meta


def newton_runs(notes, scenes, pairs, cells, cache_path):
    """(name, F, X, meta) per Newton scene, simulated or read from cache_path (--newton-cache: an .npz the
    script writes after simulating; a scene is re-simulated when its frames, pairs or cells differ).
    scenes, pairs, cells: --newton-scenes (NAME[:FRAMES],...), --newton-pairs, --newton-cells."""
    cache = {}
    if cache_path and os.path.exists(cache_path):
        with np.load(cache_path, allow_pickle=False) as z:
            cache = {k: z[k] for k in z.files}
    runs, dirty = [], False
    for name, frames in newton_scene_list(scenes):
        want = dict(frames=frames, pairs=pairs, cells=cells if name == "vbd_twist" else None)
        meta = json.loads(str(cache[name + "/meta"])) if name + "/meta" in cache else None
        if meta and all(meta.get(k) == v for k, v in want.items()):
            F, X = cache[name + "/F"], cache[name + "/X"]
            print(f"ccd_peers: newton {name}: {frames} frames read from {cache_path}", file=sys.stderr)
            notes.append(f"{name}: frames from {os.path.relpath(cache_path, ROOT)} (simulated by this script "
                         f"earlier, {meta['sim_s']:.0f} s)")
        else:
            F, X, meta = newton_simulate(name, frames, pairs)
            print(f"ccd_peers: newton {name}: {frames} frames simulated in {meta['sim_s']:.0f} s", file=sys.stderr)
            cache.update({name + "/F": F, name + "/X": X, name + "/meta": np.array(json.dumps(meta))})
            dirty = True
        runs.append((name, F, X, meta))
    if cache_path and dirty:
        os.makedirs(os.path.dirname(os.path.abspath(cache_path)), exist_ok=True)
        np.savez(cache_path, **cache)
    return runs
