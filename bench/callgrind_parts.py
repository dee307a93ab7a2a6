#!/usr/bin/env python3
# A callgrind profile's query loop (the functions matching REGEX): self instructions sorted into
# the parts of bench/README.md's floor section by the inlined headers' lines (the ranges below are
# those of the commit the section names); --lines: the costliest lines; --at FILE:LINE: with
# --dump-instr=yes, each instruction of that line and how often it ran.
# Usage: callgrind_parts.py CALLGRIND_OUT REGEX [--lines] [--at FILE:LINE]
import collections, re, sys
A = 1 << 30
PARTS = [("node visits", "predicates.h", 48, 51), ("node visits", "shapes.h", 104, 105), ("setup", "shapes.h", 103, 103),
         ("leaf scans", "shapes.h", 110, 118), ("leaf scans", "simd.h", 18, 22), ("leaf filter", "simd.h", 23, 27),
         ("leaf scans", "simd.h", 28, 34), ("leaf scans", "traversal.h", 81, 92), ("node visits", "traversal.h", 96, 192),
         ("pair writes", "leaf_filter.h", 79, 80), ("leaf filter", "leaf_filter.h", 63, 78), ("setup", "leaf_filter.h", 87, 93),
         ("leaf filter", "leaf_groups.h", 0, 99), ("leaf filter", "query_sources.h", 134, 157), ("setup", "query_sources.h", 0, 133),
         ("pair writes", "query_sources.h", 158, 158), ("setup", "query_sources.h", 166, 186), ("pair writes", "query_sources.h", 215, 215),
         ("leaf filter", "query_sources.h", 187, 214), ("leaf filter", "hd.h", 85, 100), ("setup", "hd.h", 0, 140),
         ("pair writes", "passes.h", 39, 42), ("setup", "passes.h", 0, 99), ("pair writes", "stl_vector.h", 0, A),
         ("pair writes", "new_allocator.h", 0, A), ("pair writes", "alloc_traits.h", 0, A)]
names, cost, pos, path, fl, fn, skip = {}, collections.Counter(), [0], None, None, "", False
def name(kind, value):  # "(id) name" defines id, "(id)" refers to it
    m = re.match(r"\((\d+)\)\s*(.*)", value)
    if m and m.group(2): names[kind, m.group(1)] = m.group(2)
    return names.get((kind, m.group(1)), "?") if m else value
for row in open(sys.argv[1]):
    key, _, value = row.rstrip("\n").partition("=")
    if row.startswith("positions:"): pos = [0] * len(row.split()[1:])  # "line" or "instr line"
    elif key == "fl": path = fl = name("file", value)
    elif key in ("fi", "fe"): path = name("file", value)
    elif key in ("cfi", "cfl"): name("file", value)
    elif key == "fn": fn, path = name("fn", value), fl
    elif key == "cfn": name("fn", value)
    elif key == "calls": skip = True
    elif row[:1] in "+-*0123456789" and row.strip():
        t = row.split() + ["0"]
        pos = [old if x == "*" else old + int(x) if x[0] in "+-" else int(x, 0) for old, x in zip(pos, t)]
        if not skip and re.search(sys.argv[2], fn): cost[(path.split("/")[-1], pos[-1]) + tuple(pos[:-1])] += int(t[len(pos)])
        skip = False
parts, lines = collections.Counter(), collections.Counter()
for (f, line, *_), ir in cost.items():
    lines[f, line] += ir
    parts[next((p for p, pf, lo, hi in PARTS if pf == f and lo <= line <= hi), "other")] += ir
for part, ir in parts.most_common() + [("total", sum(cost.values()))]: print(f"{part:12} {ir:>12}")
if "--lines" in sys.argv: print(*(f"{ir:>12} {f}:{line}" for (f, line), ir in lines.most_common(40)), sep="\n")
at = sys.argv[sys.argv.index("--at") + 1] if "--at" in sys.argv else None
print(*(f"{ir:>12} {hex(k[2])} {k[0]}:{k[1]}" for k, ir in sorted(cost.items()) if at and len(k) > 2 and f"{k[0]}:{k[1]}" == at), sep="\n")
