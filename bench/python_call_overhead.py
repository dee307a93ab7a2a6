#!/usr/bin/env python3
"""Per-call cost of handing numpy arrays to minkq._native as raw descriptors (address, row
stride, rows, device memory), as a stable-ABI (abi3) extension would have to, instead of the
buffer protocol the extension uses today (not in the limited API before 3.11), on the calls a
simulation step makes: a refit from (n, 3) float32 vertices and a query into an (capacity, 2)
int32 output.

Both routes enter the same native functions (the descriptor route is the one arrays of other
libraries take already); the descriptor route adds the checks the buffer protocol does
natively (dtype, shape, contiguity, writability), done in Python as the package would. The
rounds alternate the two routes and the report is the median ratio, so that load shared with
other work moves both alike. Small scenes show the per-call overhead most.

    PYTHONPATH=bindings/python/python python3 bench/python_call_overhead.py [--size 16] [--rounds 15]
"""

import argparse
import statistics
import sys
import time

import numpy as np

import minkq


def sheet(n):
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    xyz = np.stack([u.ravel(), v.ravel(), 0.05 * np.sin(7 * u.ravel())], 1).astype(np.float32)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1))
    v00 = (j * n + i).ravel()
    tris = np.concatenate([np.stack([v00, v00 + 1, v00 + n + 1], 1), np.stack([v00, v00 + n + 1, v00 + n], 1)])
    return xyz, tris.astype(np.int32)


def descriptor(array, dtype, width, writable=False):
    """What an abi3 extension would be handed for a numpy array: checked here, in Python."""
    if array.dtype != dtype or array.ndim != 2 or array.shape[1] != width:
        raise TypeError("wrong dtype or shape")
    if not array.flags.c_contiguous or (writable and not array.flags.writeable):
        raise ValueError("not contiguous or not writable")
    return (array.__array_interface__["data"][0], array.strides[0], array.shape[0], False)


def timed(call, calls):
    start = time.perf_counter()
    for _ in range(calls):
        call()
    return (time.perf_counter() - start) / calls


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=16, help="sheet of size x size vertices (default 16)")
    parser.add_argument("--rounds", type=int, default=15, help="alternating rounds (default 15)")
    parser.add_argument("--calls", type=int, default=2000, help="calls per round (default 2000)")
    args = parser.parse_args()
    xyz, tris = sheet(args.size)
    scene = minkq.Scene(xyz, tris, device="cpu")
    native = scene._native
    r = 0.5 / args.size
    out = np.empty((scene.count("vt", r) + 64, 2), np.int32)
    f32, i32 = np.dtype(np.float32), np.dtype(np.int32)
    routes = {
        "refit": (lambda: native.refit(xyz), lambda: native.refit(descriptor(xyz, f32, 3))),
        "query": (
            lambda: native.query_into(out, "vt", "box", r, False, False, False),
            lambda: native.query_into(descriptor(out, i32, 2, True), "vt", "box", r, False, False, False),
        ),
    }
    assert native.query_into(out, "vt", "box", r, False, False, False) == native.query_into(
        descriptor(out, i32, 2, True), "vt", "box", r, False, False, False
    )
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, {len(xyz)} vertices, {len(tris)} triangles, "
          f"{args.rounds} rounds of {args.calls} calls")
    print("| call | buffer protocol (us) | descriptors (us) | descriptors / buffer protocol |")
    print("|---|---|---|---|")
    for name, (buffer, described) in routes.items():
        ratios, times_b, times_d = [], [], []
        for _ in range(args.rounds):
            b = timed(buffer, args.calls)
            d = timed(described, args.calls)
            times_b.append(b)
            times_d.append(d)
            ratios.append(d / b)
        print(f"| {name} | {statistics.median(times_b) * 1e6:.2f} | {statistics.median(times_d) * 1e6:.2f} | "
              f"{statistics.median(ratios):.3f} (min {min(ratios):.3f}, max {max(ratios):.3f}) |")
    alone = statistics.median(timed(lambda: descriptor(out, i32, 2, True), args.calls) for _ in range(args.rounds))
    print(f"\nbuilding one descriptor alone: {alone * 1e6:.2f} us per array")


if __name__ == "__main__":
    main()
