#!/usr/bin/env python3
"""Two arborx_bench result files side by side (issue 27): per scene and target row, minkq's and
ArborX's medians in each run and the speed-up (ArborX ms / minkq ms) before and after, beside the
target. Each run's ratios come from its own rounds; the two runs' absolute times need not match
(the machine may have been busier in one), which is why the ratios are what is compared.

usage: bench/arborx/before_after.py BEFORE.md AFTER.md [--out FILE]
       (default: print to stdout)
"""
import argparse
import re
import sys

# The targets' rows and the ArborX contestant each is measured against (arborx_report.cpp).
TARGETS = [
    ("build triangle tree", "boxes + BVH", 1.5),
    ("build edge tree", "boxes + BVH", 1.5),
    ("rebuild triangle tree, scratch kept", "boxes + BVH", 1.5),
    ("rebuild edge tree, scratch kept", "boxes + BVH", 1.5),
    ("VT box (count)", "intersects(Box(v +- r))", 1.5),
    ("VT sphere (count)", "intersects(Sphere(v, r))", 1.5),
    ("EE box, each pair once (count)", "HalfTraversal (internal, as DBSCAN)", 1.5),
    ("EE pairs stored", "CSR query, buffer hint = max per query", 2.0),
]


def parse(path):
    """{scene: {(row, library, variant): median ms}} and the file's 'Written by' line."""
    scenes, scene, written = {}, None, ""
    with open(path, encoding="utf-8") as f:
        for line in f:
            if line.startswith("Written by"):
                written = line.strip()
            m = re.search(r"source ([0-9a-f]{7,40})", line)
            if m and line.startswith("Versions"):
                written = f"minkq {m.group(1)[:7]}; " + written
            m = re.match(r"### (\S+) \(", line)
            if m:
                scene = m.group(1)
                scenes[scene] = {}
                continue
            if scene is None or not line.startswith("| ") or line.startswith("| row"):
                continue
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) < 4:
                continue
            ms = re.match(r"([0-9.e+-]+)", cells[3])
            if ms:
                scenes[scene][(cells[0], cells[1], cells[2])] = float(ms.group(1))
    return scenes, written


def minkq_ms(rows, row):
    for (r, lib, _), ms in rows.items():
        if r == row and lib == "minkq":
            return ms
    return None


def fmt(x, unit=""):
    return "—" if x is None else f"{x:.3g}{unit}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--out")
    a = ap.parse_args()
    before, written_before = parse(a.before)
    after, written_after = parse(a.after)
    out = ["# ArborX beside minkq, before and after (issue 27)", "",
           f"Written by `bench/arborx/before_after.py {a.before} {a.after}`.", "",
           f"- before: {written_before}", f"- after: {written_after}", "",
           "ms = median of each run's timed rounds; speed-up = ArborX ms / minkq ms in the same run (> 1: minkq "
           "faster). A row the earlier minkq did not have (rebuilds with the scratch kept) shows —.", ""]
    summary = []
    for row, variant, target in TARGETS:
        met_b = met_a = n_b = n_a = 0
        for scene in after:
            for runs, is_after in ((before, False), (after, True)):
                rows = runs.get(scene, {})
                mk, ax = minkq_ms(rows, row), rows.get((row, "ArborX", variant))
                if mk is None or ax is None:
                    continue
                if is_after:
                    n_a += 1
                    met_a += ax / mk >= target
                else:
                    n_b += 1
                    met_b += ax / mk >= target
        summary.append(f"| {row} | >= {target:g}x | {met_b} of {n_b} | {met_a} of {n_a} |")
    out += ["## Scenes meeting each target", "", "| row | target | before | after |", "|---|---|---|---|"]
    out += summary + [""]
    out += ["## Every scene", "",
            "| scene | row | minkq ms before → after | ArborX ms before → after | speed-up before → after | target |",
            "|---|---|---|---|---|---|"]
    for scene in after:
        for row, variant, target in TARGETS:
            cells = []
            ratio = []
            for runs in (before, after):
                rows = runs.get(scene, {})
                mk, ax = minkq_ms(rows, row), rows.get((row, "ArborX", variant))
                cells.append((mk, ax))
                ratio.append(None if mk is None or ax is None else ax / mk)
            if ratio[1] is None:
                continue
            verdict = "met" if ratio[1] >= target else "missed"
            out.append(f"| {scene} | {row} | {fmt(cells[0][0])} → {fmt(cells[1][0])} | {fmt(cells[0][1])} → "
                       f"{fmt(cells[1][1])} | {fmt(ratio[0], 'x')} → {fmt(ratio[1], 'x')} | >= {target:g}x: {verdict} |")
    text = "\n".join(out) + "\n"
    if a.out:
        with open(a.out, "w", encoding="utf-8") as f:
            f.write(text)
        print(f"wrote {a.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
