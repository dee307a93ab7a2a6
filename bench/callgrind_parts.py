#!/usr/bin/env python3
# Self instructions of a callgrind profile's query loop (functions matching a regex), by source
# line, sorted into the parts of bench/README.md's floor section; the line ranges below are the
# headers' at the commit that section names. Usage: callgrind_parts.py OUT REGEX [--lines]
import collections, re, sys

PARTS = [("node visits", "predicates.h", 48, 51), ("node visits", "shapes.h", 104, 105), ("setup", "shapes.h", 103, 103),
         ("leaf scans", "shapes.h", 110, 118), ("leaf scans", "simd.h", 18, 22), ("leaf filter", "simd.h", 23, 27), ("leaf scans", "simd.h", 28, 34),
         ("leaf scans", "traversal.h", 81, 92), ("node visits", "traversal.h", 96, 192), ("pair writes", "leaf_filter.h", 79, 80),
         ("leaf filter", "leaf_filter.h", 63, 78), ("setup", "leaf_filter.h", 87, 93), ("leaf filter", "leaf_groups.h", 0, 99),
         ("leaf filter", "query_sources.h", 134, 157), ("pair writes", "query_sources.h", 158, 158), ("setup", "query_sources.h", 0, 133),
         ("leaf filter", "hd.h", 85, 100), ("setup", "hd.h", 0, 140), ("pair writes", "passes.h", 39, 42), ("setup", "passes.h", 0, 99),
         ("pair writes", "stl_vector.h", 0, 1 << 30), ("pair writes", "new_allocator.h", 0, 1 << 30), ("pair writes", "alloc_traits.h", 0, 1 << 30)]
names, cost, path, fl, fn, last, skip = {}, collections.Counter(), None, None, "", 0, False
def name(kind, value):  # "(id) name" defines id, "(id)" refers to it
    m = re.match(r"\((\d+)\)\s*(.*)", value)
    if not m: return value
    if m.group(2): names[kind, m.group(1)] = m.group(2)
    return names.get((kind, m.group(1)), "?")
for row in open(sys.argv[1]):
    key, _, value = row.rstrip("\n").partition("=")
    if key == "fl": path = fl = name("file", value)
    elif key in ("fi", "fe"): path = name("file", value)
    elif key == "fn": fn, path = name("fn", value), fl
    elif key in ("cfi", "cfl"): name("file", value)
    elif key == "cfn": name("fn", value)
    elif key == "calls": skip = True
    elif row[:1] in "+-*0123456789" and row.strip():
        pos, ir = (row.split() + ["0"])[:2]
        last = last if pos == "*" else last + int(pos) if pos[0] in "+-" else int(pos)
        if not skip and re.search(sys.argv[2], fn): cost[path.split("/")[-1], last] += int(ir)
        skip = False
parts = collections.Counter()
for (f, line), ir in cost.items():
    parts[next((p for p, pf, lo, hi in PARTS if pf == f and lo <= line <= hi), "other")] += ir
for part, ir in parts.most_common() + [("total", sum(cost.values()))]: print(f"{part:12} {ir:>12}")
if "--lines" in sys.argv: print(*(f"{ir:>12} {f}:{line}" for (f, line), ir in cost.most_common(40)), sep="\n")
