#!/usr/bin/env python3
"""Before/after table of two builds' study files (build.md of minkq_build_study, traversal.md
of minkq_traversal_study), for a change that must leave the trees and the work unchanged.

  bench/compare_studies.py build|traversal --before A.md[,B.md...] --after C.md[,D.md...] [--title T]

Each side may hold several runs (run the two binaries alternately, in both orders: on a small
shared machine a run's order alone moves its times by several per cent); a side's time for a
row is the best of its runs' medians. Prints a markdown table: the times per row, speed-up =
before / after, the geometric mean per tree (build) or per kind and mode (traversal), and
whether the rows' structure columns (node count and area cost; pairs and work per query) are
the same on both sides, which the comparison presumes. Exits 1 when a row differs or is missing.
"""
import argparse
import math
import sys

BUILD = {"key": ("scene", "tree"), "same": ("elements", "nodes", "area cost"),
         "times": ("library ms", "kept ms", "boxes", "sort", "nodes + boxes", "refit"),
         "group": ("tree",)}
TRAVERSAL = {"key": ("scene", "kind", "mode"),
             "same": ("queries", "pairs", "nodes / query, walk → grouped",
                      "node tests / query, top-down → half → grouped"),
             "times": ("half ms",), "group": ("kind", "mode")}


def read_table(path):
    """The rows of the first table in a study file, as dicts by header name."""
    header, rows = None, []
    for line in open(path, encoding="utf-8"):
        if not line.startswith("|"):
            if header and rows:
                break
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cells
        elif not set(cells[0]) <= set("-: "):
            rows.append(dict(zip(header, cells)))
    return rows


def number(cell):
    return float(cell.split()[0])


def geomean(values):
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", choices=("build", "traversal"))
    parser.add_argument("--before", required=True)
    parser.add_argument("--after", required=True)
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    spec = BUILD if args.study == "build" else TRAVERSAL
    sides = []
    for files in (args.before, args.after):
        runs = []
        for path in files.split(","):
            runs.append({tuple(r[k] for k in spec["key"]): r for r in read_table(path)})
        sides.append(runs)
    ok = True
    keys = list(sides[0][0])
    for runs in sides:
        for run in runs:
            if set(run) != set(keys):
                print(f"compare_studies: the runs hold different rows ({len(run)} vs {len(keys)})", file=sys.stderr)
                ok = False
    if not ok:
        return 1
    head = list(spec["key"]) + [f"{t} {side}" for t in spec["times"] for side in ("before", "after", "speed-up")]
    if args.title:
        print(f"### {args.title}\n")
    print("| " + " | ".join(head + ["same"]) + " |")
    print("|" + "---|" * (len(head) + 1))
    groups = {}
    for key in keys:
        cells = list(key)
        for t in spec["times"]:
            before = min(number(run[key][t]) for run in sides[0])
            after = min(number(run[key][t]) for run in sides[1])
            cells += [f"{before:.3g}", f"{after:.3g}", f"{before / after:.2f}x"]
            groups.setdefault(tuple(sides[0][0][key][g] for g in spec["group"]), {}).setdefault(t, []).append(
                before / after)
        same = all(run[key][c] == sides[0][0][key][c] for runs in sides for run in runs for c in spec["same"])
        ok &= same
        print("| " + " | ".join(cells + ["yes" if same else "**no**"]) + " |")
    print("\nGeometric mean of the speed-ups:\n")
    print("| " + " | ".join(list(spec["group"]) + list(spec["times"]) + ["rows"]) + " |")
    print("|" + "---|" * (len(spec["group"]) + len(spec["times"]) + 1))
    for group, by_time in groups.items():
        rows = len(next(iter(by_time.values())))
        print("| " + " | ".join(list(group) + [f"{geomean(by_time[t]):.3f}x" for t in spec["times"]] + [str(rows)]) + " |")
    if not ok:
        print("compare_studies: a row's structure differs between the sides", file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
