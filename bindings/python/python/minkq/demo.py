"""The cloth broad phase of `minkq demo`, from Python.

Builds the default scene of `minkq demo` (a twisted sheet of 388 x 388 vertices, 3 turns,
radius 0.25 x the mean edge length), runs the VT and EE queries in every mode and prints the
same table: candidates, true contacts, false-positive ratio, false negatives, query time
(median of 3, after one untimed run that sizes the output array) and speedup over the box mode.

The true contacts here are the leaf_exact pairs (the primitive distance test at the leaves)
rather than `minkq demo`'s independent double-precision oracle; on the default scene the two
are equal, 62694 VT and 192090 EE contacts, and the demo checks that it finds those numbers.

    minkq-demo [--backend cpu|cuda|auto] [--size N] [--radius-factor F] [--repeat K]
    python3 -m minkq ...                      (the same; examples/python/demo.py calls it too)
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import List, Optional, Tuple

import numpy as np

import minkq  # the package itself: this module is minkq.demo

# What `minkq demo` prints for the default scene (the reference oracle's contacts).
DEFAULT_SIZE, DEFAULT_FACTOR = 388, 0.25
REFERENCE_CONTACTS = {"vt": 62694, "ee": 192090}


def grid_sheet(n: int) -> Tuple[np.ndarray, np.ndarray]:
    """n x n vertices on [0,1]^2 at z = 0, vertex (i, j) at index j * n + i; cell (i, j) gives
    triangles (v00, v10, v11) and (v00, v11, v01). As oracle/'s grid_sheet."""
    if n < 2:
        raise ValueError("n must be >= 2")
    coords = (np.arange(n, dtype=np.float64) / (n - 1)).astype(np.float32)
    xyz = np.zeros((n * n, 3), dtype=np.float32)
    xyz[:, 0] = np.tile(coords, n)
    xyz[:, 1] = np.repeat(coords, n)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (j * n + i).ravel().astype(np.int32)
    v10, v01 = v00 + 1, v00 + n
    v11 = v01 + 1
    tris = np.empty((2 * len(v00), 3), dtype=np.int32)
    tris[0::2] = np.stack([v00, v10, v11], axis=1)
    tris[1::2] = np.stack([v00, v11, v01], axis=1)
    return xyz, tris


def twisted_sheet(n: int, turns: float = 3.0) -> Tuple[np.ndarray, np.ndarray]:
    """grid_sheet(n) twisted about the x axis: (u, v) -> (u, (v - 1/2) cos t, (v - 1/2) sin t),
    t = turns * 2 pi * u, bit for bit as oracle/'s twisted_sheet (double arithmetic,
    the C library's cos and sin through math, rounded to float)."""
    xyz, tris = grid_sheet(n)
    u = xyz[:, 0].astype(np.float64)
    v = xyz[:, 1].astype(np.float64) - 0.5
    # t depends on the column only: n calls of math.cos/sin (the C library's, as in C++).
    columns = xyz[:n, 0].astype(np.float64)
    angle = turns * 2 * math.pi * columns
    cos = np.array([math.cos(t) for t in angle])
    sin = np.array([math.sin(t) for t in angle])
    column = np.searchsorted(columns, u)
    xyz[:, 1] = (v * cos[column]).astype(np.float32)
    xyz[:, 2] = (v * sin[column]).astype(np.float32)
    return xyz, tris


def derive_edges(tris: np.ndarray) -> np.ndarray:
    """Every distinct undirected triangle edge as (min, max), sorted lexicographically: the
    numbering of the C API."""
    e = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    e = np.sort(e, axis=1).astype(np.int64)
    keys = np.unique(e[:, 0] << 32 | e[:, 1])
    return np.stack([keys >> 32, keys & 0xFFFFFFFF], axis=1).astype(np.int32)


def mean_edge_length(xyz: np.ndarray, edges: np.ndarray) -> float:
    """The mean edge length, summed in edge order in double as the reference does."""
    d = xyz[edges[:, 0]].astype(np.float64) - xyz[edges[:, 1]].astype(np.float64)
    lengths = np.sqrt((d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1]) + d[:, 2] * d[:, 2])
    return float(np.add.accumulate(lengths)[-1] / len(edges)) if len(edges) else 0.0


def keys(pairs: np.ndarray) -> np.ndarray:
    return pairs[:, 0].astype(np.int64) << 32 | pairs[:, 1].astype(np.int64)


MODES = [
    ("vt", "box", "box", False),
    ("vt", "sphere", "sphere", False),
    ("vt", "sphere+leaf_exact", "sphere", True),
    ("ee", "box", "box", False),
    ("ee", "capsule_ray", "capsule_ray", False),
    ("ee", "capsule_exact", "capsule_exact", False),
    ("ee", "capsule_exact+leaf_exact", "capsule_exact", True),
]


def run(backend: str = "auto", size: int = DEFAULT_SIZE, factor: float = DEFAULT_FACTOR, repeat: int = 3) -> int:
    """Prints the demo table; returns the exit status (1: false negatives, or the default scene's
    contacts differ from the reference's)."""
    xyz, tris = twisted_sheet(size, 3.0)
    edges = derive_edges(tris)
    h = mean_edge_length(xyz, edges)
    r = float(np.float32(factor * h))  # the library takes a float radius
    device = minkq.Device(backend)
    print(f"minkq demo (Python): twisted sheet {size}x{size}, 3 turns: {len(xyz)} vertices, {len(tris)} triangles, {len(edges)} edges")
    print(f"radius {r:.6g} = {factor:g} x mean edge length {h:.6g}; device {device.name}")
    t0 = time.perf_counter()
    scene = minkq.Scene(xyz, tris, vt=True, ee=True, drop_incident=True, device=device)
    print(f"scene build {1e3 * (time.perf_counter() - t0):.1f} ms")
    if not np.array_equal(scene.edges(), edges):
        raise RuntimeError("the library's edge numbering differs from derive_edges")

    truth = {kind: keys(scene.query(kind, r, mode=mode, leaf_exact=True)) for kind, mode in (("vt", "sphere"), ("ee", "capsule_exact"))}
    print(f"true contacts: the leaf_exact pairs, {len(truth['vt'])} VT and {len(truth['ee'])} EE\n")

    print(f"{'kind':<4} {'mode':<26} {'candidates':>12} {'true':>12} {'fp ratio':>9} {'false neg':>10} {'query ms':>10} {'speedup':>8}")
    false_negatives = 0
    box_ms = 0.0
    for kind, name, mode, leaf_exact in MODES:
        scene.query(kind, r, mode=mode, leaf_exact=leaf_exact)  # sizes the output: the timed runs run once
        times: List[float] = []
        for _ in range(repeat):
            start = time.perf_counter()
            pairs = scene.query(kind, r, mode=mode, leaf_exact=leaf_exact)
            times.append(1e3 * (time.perf_counter() - start))
        ms = sorted(times)[len(times) // 2]
        if mode == "box":
            box_ms = ms
        true = truth[kind]
        missing = int(np.count_nonzero(~np.isin(true, keys(pairs))))
        false_negatives += missing
        fp = (len(pairs) - len(true)) / len(true) if len(true) else 0.0
        speedup = box_ms / ms if ms > 0 else 0.0
        print(f"{kind.upper():<4} {name:<26} {len(pairs):>12} {len(true):>12} {fp:>9.3f} {missing:>10} {ms:>10.2f} {speedup:>7.2f}x")

    status = 0
    if false_negatives:
        print(f"\nFAIL: {false_negatives} true contacts missing from the candidates")
        status = 1
    else:
        print("\nno false negatives")
    if size == DEFAULT_SIZE and factor == DEFAULT_FACTOR:
        found = {kind: len(truth[kind]) for kind in truth}
        if found == REFERENCE_CONTACTS:
            print(f"true contacts equal `minkq demo`'s reference oracle: {found['vt']} VT, {found['ee']} EE")
        else:
            print(f"FAIL: true contacts {found} differ from `minkq demo`'s reference oracle {REFERENCE_CONTACTS}")
            status = 1
    return status


def main(argv: Optional[List[str]] = None) -> int:
    """The command line of ``minkq-demo`` and ``python -m minkq`` (``argv``: sys.argv[1:] by
    default); returns the exit status."""
    parser = argparse.ArgumentParser(prog="minkq-demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--backend", default="auto", help="cpu, cuda, cuda:N or auto (default)")
    parser.add_argument("--size", type=int, default=DEFAULT_SIZE, help="vertices per side (default 388)")
    parser.add_argument("--radius-factor", type=float, default=DEFAULT_FACTOR, help="radius / mean edge length (default 0.25)")
    parser.add_argument("--repeat", type=int, default=3, help="runs per query; the median is shown (default 3)")
    args = parser.parse_args(argv)
    if not 2 <= args.size <= 20000:
        parser.error("--size: an integer from 2 to 20000")
    if args.radius_factor < 0:
        parser.error("--radius-factor: must be >= 0")
    if args.repeat < 1:
        parser.error("--repeat: must be >= 1")
    try:
        return run(args.backend, args.size, args.radius_factor, args.repeat)
    except minkq.MinkqError as e:
        print(f"minkq: {e.status_name}: {e}", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
