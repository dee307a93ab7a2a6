#!/usr/bin/env python3
"""Warp 1.19 and Newton 1.8 baselines, on the scenes minkq_bench exported (--export).

For each exported scene (its last frame, the same float coordinates and radius minkq used) it
runs, on Warp's CPU device (or --device cuda:0, beside minkq's cuda rows), with every tree built at the scene's first frame and refit to the
last (as minkq_bench treats minkq and Embree: a simulator's refit-only steps):
  - VT: per vertex bvh_query_aabb (r-padded box) and bvh_query_sphere over a wp.Bvh of
        triangle boxes; incident triangles dropped; candidates counted and a float
        point-triangle distance test (Newton's triangle_closest_point) counts contacts;
  - EE: per edge bvh_query_aabb and bvh_query_capsule (dir = e1 - e0, max_dist 1) over a wp.Bvh
        of edge boxes; pairs (e, f) with f > e not sharing a vertex (each pair once, as minkq);
        contacts by wp.closest_point_edge_edge with epsilon 0 (no absolute epsilon);
  - Newton's TriMeshCollisionDetector (defaults: edge_edge_parallel_epsilon = 1e-5): refit,
        vertex_triangle_collision_detection(r), edge_edge_collision_detection(r); contacts are the
        sums of its per-element counts (EE halved: each pair is reported by both edges).
Times are medians over repeats after a warm-up launch (kernel compilation excluded), with
wp.synchronize() around each launch. Warp's CPU kernels run on one thread, so minkq is shown
beside it from a --threads 1 run of minkq_bench (its rows.csv), along with the oracle's counts.

usage: warp_baseline.py EXPORT_DIR MINKQ_ROWS_CSV OUT_MD [--repeats N] [--only SUBSTR,...] [--minkq-threads N]
                        [--device cpu|cuda:0]
  --device: Warp's device for every array, launch and Newton model (default cpu); minkq's rows
            are then taken from the rows.csv backend of the same kind (cpu or cuda).
"""
import csv
import glob
import os
import statistics
import struct
import sys
import time
import traceback

import numpy as np


def load_mkqb(path):
    with open(path, "rb") as f:
        data = f.read()
    assert data[:4] == b"MKQB", path
    version, nv, nt, ne, nf = struct.unpack_from("<5I", data, 4)
    (r,) = struct.unpack_from("<f", data, 24)
    off = 28
    frames = []
    for _ in range(nf):
        frames.append(np.frombuffer(data, dtype="<f4", count=3 * nv, offset=off).reshape(nv, 3).copy())
        off += 12 * nv
    tris = np.frombuffer(data, dtype="<i4", count=3 * nt, offset=off).reshape(nt, 3).copy()
    off += 12 * nt
    edges = np.frombuffer(data, dtype="<i4", count=2 * ne, offset=off).reshape(ne, 2).copy()
    return frames, tris, edges, np.float32(r)


def timed(fn, repeats, wp):
    fn()
    wp.synchronize()
    ts = []
    for _ in range(repeats):
        wp.synchronize()
        t0 = time.perf_counter()
        fn()
        wp.synchronize()
        ts.append(1000 * (time.perf_counter() - t0))
    return statistics.median(ts), min(ts), max(ts)


def take(args, name, default):
    """The value after option `name` in args (both removed), else default."""
    if name not in args:
        return default
    i = args.index(name)
    value = args[i + 1]
    del args[i : i + 2]
    return value


def main():
    args = sys.argv[1:]
    repeats = int(take(args, "--repeats", 3))
    minkq_threads = take(args, "--minkq-threads", "1")
    only = take(args, "--only", "").split(",") if "--only" in args else []
    device = take(args, "--device", "cpu")
    backend = "cpu" if device == "cpu" else "cuda"
    if len(args) != 3:
        print(__doc__)
        return 2
    export_dir, rows_csv, out_md = args

    lines = []
    minkq = {}
    if os.path.exists(rows_csv):
        with open(rows_csv) as f:
            for row in csv.DictReader(f):
                if row.get("backend", "cpu") != backend:
                    continue
                minkq[(row["suite"] + "__" + row["scene"], row["kind"], row["mode"], int(row["frame"]))] = row
    try:
        import warp as wp

        wp.config.quiet = True
        wp.init()
        wp.get_device(device)  # an unknown device (no GPU) fails here, reported below
        from newton._src.geometry.kernels import triangle_closest_point
    except Exception:
        with open(out_md, "w") as f:
            f.write("# Warp / Newton baselines\n\nWarp could not be initialised (device " + device + "):\n\n```\n" + traceback.format_exc() + "```\n")
        print("warp init failed; wrote", out_md)
        return 1

    @wp.func
    def vt_dist(a: wp.vec3, b: wp.vec3, c: wp.vec3, p: wp.vec3):
        res = triangle_closest_point(a, b, c, p)
        return wp.length(res[0] - p)

    @wp.func
    def vt_pair(v: int, t: int, p: wp.vec3, pos: wp.array(dtype=wp.vec3), tris: wp.array2d(dtype=wp.int32), r: float):
        # 0: not a candidate (an incident triangle), 1: candidate, 2: candidate within r
        a = tris[t, 0]
        b = tris[t, 1]
        c = tris[t, 2]
        if a == v or b == v or c == v:
            return 0
        if vt_dist(pos[a], pos[b], pos[c], p) <= r:
            return 2
        return 1

    @wp.kernel
    def vt_query(bvh: wp.uint64, pos: wp.array(dtype=wp.vec3), tris: wp.array2d(dtype=wp.int32), r: float,
                 sphere: int, counts: wp.array(dtype=wp.int32)):
        # sphere 0: bvh_query_aabb of the r-padded box, 1: bvh_query_sphere
        v = wp.tid()
        p = pos[v]
        cand = int(0)
        cont = int(0)
        t = int(0)
        if sphere == 0:
            q = wp.bvh_query_aabb(bvh, p - wp.vec3(r), p + wp.vec3(r))
        else:
            q = wp.bvh_query_sphere(bvh, p, r)
        while wp.bvh_query_next(q, t):
            k = vt_pair(v, t, p, pos, tris, r)
            cand += wp.where(k > 0, 1, 0)
            cont += wp.where(k > 1, 1, 0)
        wp.atomic_add(counts, 0, cand)
        wp.atomic_add(counts, 1, cont)

    @wp.func
    def ee_pair(e: int, f: int, i0: int, i1: int, p0: wp.vec3, p1: wp.vec3, pos: wp.array(dtype=wp.vec3),
                edges: wp.array2d(dtype=wp.int32), r: float):
        # 0: not a candidate (f <= e or shares a vertex), 1: candidate, 2: candidate within r
        j0 = edges[f, 0]
        j1 = edges[f, 1]
        if f <= e or j0 == i0 or j0 == i1 or j1 == i0 or j1 == i1:
            return 0
        st = wp.closest_point_edge_edge(p0, p1, pos[j0], pos[j1], 0.0)
        if st[2] <= r:
            return 2
        return 1

    @wp.kernel
    def ee_query(bvh: wp.uint64, pos: wp.array(dtype=wp.vec3), edges: wp.array2d(dtype=wp.int32), r: float,
                 capsule: int, counts: wp.array(dtype=wp.int32)):
        # capsule 0: bvh_query_aabb of the edge's r-padded box, 1: bvh_query_capsule (dir = e1 - e0,
        # max_dist 1), or for a zero-length edge, which it does not support (its docs), bvh_query_sphere
        e = wp.tid()
        i0 = edges[e, 0]
        i1 = edges[e, 1]
        p0 = pos[i0]
        p1 = pos[i1]
        cand = int(0)
        cont = int(0)
        f = int(0)
        if capsule != 0 and wp.length(p1 - p0) > 0.0:
            q = wp.bvh_query_capsule(bvh, p0, p1 - p0, r)
            while wp.bvh_query_next(q, f, 1.0):
                k = ee_pair(e, f, i0, i1, p0, p1, pos, edges, r)
                cand += wp.where(k > 0, 1, 0)
                cont += wp.where(k > 1, 1, 0)
        else:
            if capsule == 0:
                q2 = wp.bvh_query_aabb(bvh, wp.min(p0, p1) - wp.vec3(r), wp.max(p0, p1) + wp.vec3(r))
            else:
                q2 = wp.bvh_query_sphere(bvh, p0, r)
            while wp.bvh_query_next(q2, f):
                k2 = ee_pair(e, f, i0, i1, p0, p1, pos, edges, r)
                cand += wp.where(k2 > 0, 1, 0)
                cont += wp.where(k2 > 1, 1, 0)
        wp.atomic_add(counts, 0, cand)
        wp.atomic_add(counts, 1, cont)

    @wp.kernel
    def boxes_kernel(pos: wp.array(dtype=wp.vec3), idx: wp.array2d(dtype=wp.int32), k: int,
                     lo: wp.array(dtype=wp.vec3), hi: wp.array(dtype=wp.vec3)):
        i = wp.tid()
        a = pos[idx[i, 0]]
        l = a
        h = a
        for j in range(1, k):
            b = pos[idx[i, j]]
            l = wp.min(l, b)
            h = wp.max(h, b)
        lo[i] = l
        hi[i] = h

    dev = device
    results = []
    paths = sorted(glob.glob(os.path.join(export_dir, "*.mkqb")))
    if only:
        paths = [p for p in paths if any(s in os.path.basename(p) for s in only)]
    for path in paths:
        tag = os.path.basename(path)[:-5]
        frames, tris, edges, r = load_mkqb(path)
        k = len(frames) - 1
        x = frames[k]
        x0 = frames[0]  # the trees are built here and refit to x
        row = {"scene": tag.split("__", 1)[1], "tag": tag, "frame": k, "V": len(x), "T": len(tris), "E": len(edges), "r": float(r)}
        print(f"[warp] {tag}: {len(x)} V, {len(tris)} T, {len(edges)} E, r = {float(r):.6g}", flush=True)
        try:
            pos0 = wp.array(x0, dtype=wp.vec3, device=dev)
            pos = wp.array(x, dtype=wp.vec3, device=dev)
            wt = wp.array(tris, dtype=wp.int32, device=dev)
            we = wp.array(edges, dtype=wp.int32, device=dev)
            tlo = wp.zeros(len(tris), dtype=wp.vec3, device=dev)
            thi = wp.zeros(len(tris), dtype=wp.vec3, device=dev)
            elo = wp.zeros(len(edges), dtype=wp.vec3, device=dev)
            ehi = wp.zeros(len(edges), dtype=wp.vec3, device=dev)
            wp.launch(boxes_kernel, dim=len(tris), inputs=[pos0, wt, 3, tlo, thi], device=dev)
            wp.launch(boxes_kernel, dim=len(edges), inputs=[pos0, we, 2, elo, ehi], device=dev)
            t0 = time.perf_counter()
            bvh_t = wp.Bvh(tlo, thi)
            bvh_e = wp.Bvh(elo, ehi)
            row["warp_build_ms"] = 1000 * (time.perf_counter() - t0)
            # The last frame's boxes into the arrays the trees were built from, then refit.
            wp.launch(boxes_kernel, dim=len(tris), inputs=[pos, wt, 3, tlo, thi], device=dev)
            wp.launch(boxes_kernel, dim=len(edges), inputs=[pos, we, 2, elo, ehi], device=dev)
            row["warp_refit_ms"] = timed(lambda: (bvh_t.refit(), bvh_e.refit()), repeats, wp)[0]
            counts = wp.zeros(2, dtype=wp.int32, device=dev)
            for name, kern, bvh, n, idx, mode in [("vt_aabb", vt_query, bvh_t, len(x), wt, 0),
                                                  ("vt_sphere", vt_query, bvh_t, len(x), wt, 1),
                                                  ("ee_aabb", ee_query, bvh_e, len(edges), we, 0),
                                                  ("ee_capsule", ee_query, bvh_e, len(edges), we, 1)]:

                def go(kern=kern, bvh=bvh, n=n, idx=idx, mode=mode):
                    counts.zero_()
                    wp.launch(kern, dim=n, inputs=[bvh.id, pos, idx, float(r), mode, counts], device=dev)

                row[name + "_ms"] = timed(go, repeats, wp)[0]
                c = counts.numpy()
                row[name + "_cand"], row[name + "_true"] = int(c[0]), int(c[1])
        except Exception:
            row["warp_error"] = traceback.format_exc().strip().splitlines()[-1]
            print("warp failed:", row["warp_error"])
        try:
            import newton
            from newton._src.geometry.tri_mesh_collision import TriMeshCollisionDetector

            builder = newton.ModelBuilder()
            builder.add_cloth_mesh(pos=wp.vec3(0.0, 0.0, 0.0), rot=wp.quat_identity(), scale=1.0, vel=wp.vec3(0.0, 0.0, 0.0),
                                   vertices=[wp.vec3(*p) for p in x0.tolist()], indices=tris.reshape(-1).tolist(), density=1.0)
            model = builder.finalize(device=dev)
            det = TriMeshCollisionDetector(model, init_collision_info=True)  # its trees built at the first frame
            row["newton_T"], row["newton_E"] = int(model.tri_count), int(model.edge_count)
            q_last = wp.array(x, dtype=wp.vec3, device=dev)
            row["newton_refit_ms"] = timed(lambda: det.refit(q_last), repeats, wp)[0]
            row["newton_vt_ms"] = timed(lambda: det.vertex_triangle_collision_detection(float(r)), repeats, wp)[0]
            row["newton_ee_ms"] = timed(lambda: det.edge_edge_collision_detection(float(r)), repeats, wp)[0]
            row["newton_vt_true"] = int(det.vertex_colliding_triangles_count.numpy().sum())
            row["newton_ee_true"] = int(det.edge_colliding_edges_count.numpy().sum()) // 2
            row["newton_resize"] = int(np.asarray(det.resize_flags.numpy()).any())
        except Exception:
            row["newton_error"] = traceback.format_exc().strip().splitlines()[-1]
            print("newton failed:", row["newton_error"])
        results.append(row)

    def g(row, key, fmtstr="{:.3g}"):
        v = row.get(key)
        return "–" if v is None else (fmtstr.format(v) if isinstance(v, float) else str(v))

    def mk(row, kind, mode, field):
        m = minkq.get((row["tag"], kind, mode, row["frame"]))
        return m[field] if m else "–"

    def mkms(row, kind, mode):
        m = minkq.get((row["tag"], kind, mode, row["frame"]))
        return float(m["ms_median"]) if m else None

    def ratio(a, b):
        return "–" if a is None or b is None or b == 0 else f"{a / b:.3g}x"

    import platform

    cpu = "unknown CPU"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = open("/proc/loadavg").read().split()[0] if os.path.exists("/proc/loadavg") else "?"
    where = "the CPU" if dev == "cpu" else f"the GPU ({wp.get_device(dev).name})"
    o = [f"# Warp 1.19 / Newton 1.8 baselines on {where}\n"]
    o.append(f"Machine: {cpu}, {os.cpu_count()} CPUs, Python {platform.python_version()}, Warp {wp.config.version}, "
             f"Newton {getattr(__import__('newton'), '__version__', '?')}; load average at write {load}. "
             + (f"Warp's CPU kernels run on one thread; minkq's columns come from a `minkq_bench` run on {minkq_threads} thread(s)"
                if dev == "cpu" else f"Warp on {dev}; minkq's columns are its cuda rows (output copied to host memory)")
             + " on the same exported scenes. Last frame of "
             f"each scene, every tree (minkq's, Warp's, Newton's) built at its first frame and refit; medians of {repeats} repeats after a warm-up launch; times in ms.\n")
    o.append("Warp kernels count candidates (incident pairs dropped, EE pairs once with f > e) and contacts with a float "
             "distance test (Newton's `triangle_closest_point`, `wp.closest_point_edge_edge` with epsilon 0); minkq's "
             "\"true\" column is the long-double oracle. Newton's detector uses its defaults "
             "(edge_edge_parallel_epsilon = 1e-5, buffers 16/32 grown to at most 256) and its own edge list.\n")
    o.append("## VT\n\n| scene | T | r | oracle true | Warp aabb cand / true / ms | Warp sphere cand / true / ms | minkq box cand / ms | minkq sphere cand / ms | minkq leaf_exact ms | Newton VT true / ms | Newton VT lost | minkq box vs Warp aabb | minkq sphere vs Warp sphere | minkq leaf vs Newton |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    def lost(row, kind, key):
        true = mk(row, kind, "box", "true_contacts")
        if true == "–" or row.get(key) is None or int(true) == 0:
            return "–"
        return f"{100 * (1 - row[key] / int(true)):.1f}%"

    for row in results:
        o.append(f"| {row['scene']} | {row['T']} | {row['r']:.4g} | {mk(row, 'VT', 'box', 'true_contacts')} | "
                 f"{g(row, 'vt_aabb_cand')} / {g(row, 'vt_aabb_true')} / {g(row, 'vt_aabb_ms')} | "
                 f"{g(row, 'vt_sphere_cand')} / {g(row, 'vt_sphere_true')} / {g(row, 'vt_sphere_ms')} | "
                 f"{mk(row, 'VT', 'box', 'candidates')} / {mk(row, 'VT', 'box', 'ms_median')} | "
                 f"{mk(row, 'VT', 'sphere', 'candidates')} / {mk(row, 'VT', 'sphere', 'ms_median')} | {mk(row, 'VT', 'leaf_exact', 'ms_median')} | "
                 f"{g(row, 'newton_vt_true')} / {g(row, 'newton_vt_ms')} | {lost(row, 'VT', 'newton_vt_true')} | {ratio(row.get('vt_aabb_ms'), mkms(row, 'VT', 'box'))} | "
                 f"{ratio(row.get('vt_sphere_ms'), mkms(row, 'VT', 'sphere'))} | {ratio(row.get('newton_vt_ms'), mkms(row, 'VT', 'leaf_exact'))} |\n")
    o.append("\n## EE\n\n| scene | E | oracle true | Warp aabb cand / true / ms | Warp capsule cand / true / ms | minkq box cand / ms | minkq capsule_ray cand / ms | minkq capsule_exact cand / ms | minkq leaf_exact ms | Newton EE true / ms | Newton EE lost | minkq box vs Warp aabb | minkq ray vs Warp capsule | minkq leaf vs Newton |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    for row in results:
        o.append(f"| {row['scene']} | {row['E']} | {mk(row, 'EE', 'box', 'true_contacts')} | {g(row, 'ee_aabb_cand')} / {g(row, 'ee_aabb_true')} / {g(row, 'ee_aabb_ms')} | "
                 f"{g(row, 'ee_capsule_cand')} / {g(row, 'ee_capsule_true')} / {g(row, 'ee_capsule_ms')} | "
                 f"{mk(row, 'EE', 'box', 'candidates')} / {mk(row, 'EE', 'box', 'ms_median')} | "
                 f"{mk(row, 'EE', 'capsule_ray', 'candidates')} / {mk(row, 'EE', 'capsule_ray', 'ms_median')} | "
                 f"{mk(row, 'EE', 'capsule_exact', 'candidates')} / {mk(row, 'EE', 'capsule_exact', 'ms_median')} | {mk(row, 'EE', 'leaf_exact', 'ms_median')} | "
                 f"{g(row, 'newton_ee_true')} / {g(row, 'newton_ee_ms')} | {lost(row, 'EE', 'newton_ee_true')} | {ratio(row.get('ee_aabb_ms'), mkms(row, 'EE', 'box'))} | "
                 f"{ratio(row.get('ee_capsule_ms'), mkms(row, 'EE', 'capsule_ray'))} | {ratio(row.get('newton_ee_ms'), mkms(row, 'EE', 'leaf_exact'))} |\n")
    o.append("\n## Build and refit\n\n| scene | Warp build both trees (LBVH default) | Warp refit both | Newton refit | Newton T / E (vs minkq) | Newton resize flag | errors |\n|---|---|---|---|---|---|---|\n")
    for row in results:
        errs = "; ".join(row[k] for k in ("warp_error", "newton_error") if k in row) or "–"
        o.append(f"| {row['scene']} | {g(row, 'warp_build_ms')} | {g(row, 'warp_refit_ms')} | {g(row, 'newton_refit_ms')} | "
                 f"{g(row, 'newton_T')} / {g(row, 'newton_E')} ({row['T']} / {row['E']}) | {g(row, 'newton_resize')} | {errs} |\n")
    o.append(f"\n\"x\" ratios are Warp or Newton time over minkq time (> 1: minkq faster); Warp/Newton on one thread, minkq on {minkq_threads}. "
             "\"Newton VT/EE lost\" = 1 - Newton's contacts / the oracle's (its counts are the per-element counters summed; "
             "the resize flag says whether a per-element buffer overflowed its allocation).\n")
    with open(out_md, "w") as f:
        f.write("".join(o))
    print("wrote", out_md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
