#!/usr/bin/env python3
# A callgrind profile's query loop (functions matching REGEX): self instructions by part of bench/README.md's
# floor section, from the inlined headers' lines (ranges of the commit it names); --lines: the costliest
# lines; --at FILE:LINE: with --dump-instr=yes, each instruction of that line and how often it ran.
# Usage: callgrind_parts.py CALLGRIND_OUT REGEX [--lines] [--at FILE:LINE]
import collections, re, sys
PARTS = {  # part: header:first-last line ranges (a header alone: all of it)
    "node visits": "predicates:48-51 shapes:104-105 traversal:96-192",
    "leaf scans": "shapes:110-118 simd:18-22 simd:28-34 traversal:81-92",
    "leaf filter": "simd:23-27 leaf_filter:63-78 leaf_groups query_sources:134-157 query_sources:187-214 hd:85-100",
    "pair writes": "leaf_filter:79-80 query_sources:158 query_sources:215 passes:39-42 stl_vector new_allocator alloc_traits",
    "setup": "shapes:103 leaf_filter:87-93 query_sources:0-133 query_sources:166-186 hd:0-84 hd:101-140 passes:0-38 passes:43-99"}
def part(f, line):
    return next((p for p, spec in PARTS.items() for h, _, r in (t.partition(":") for t in spec.split())
                 if f == h + ".h" and (not r or int(r.split("-")[0]) <= line <= int(r.split("-")[-1]))), "other")
names, cost, pos, path, fl, fn, skip = {}, collections.Counter(), [0], None, None, "", False
def name(kind, value):  # "(id) name" defines id, "(id)" refers to it
    m = re.match(r"\((\d+)\)\s*(.*)", value)
    if m and m.group(2): names[kind, m.group(1)] = m.group(2)
    return names.get((kind, m.group(1)), "?") if m else value
for row in open(sys.argv[1]):
    key, _, value = row.rstrip("\n").partition("=")
    if row.startswith("positions:"): pos = [0] * len(row.split()[1:])  # "line" or "instr line"
    elif key in ("fl", "fi", "fe"): path, fl = (p := name("file", value)), (p if key == "fl" else fl)
    elif key in ("cfi", "cfl", "cfn"): name("fn" if key == "cfn" else "file", value)
    elif key == "fn": fn, path = name("fn", value), fl
    elif key == "calls": skip = True
    elif row[:1] in "+-*0123456789" and row.strip():
        t = row.split() + ["0"]
        pos = [old if x == "*" else old + int(x) if x[0] in "+-" else int(x, 0) for old, x in zip(pos, t)]
        if not skip and re.search(sys.argv[2], fn):
            cost[(path.split("/")[-1], pos[-1]) + tuple(pos[:-1])] += int(t[len(pos)])
        skip = False
parts, lines = collections.Counter(), collections.Counter()
for (f, line, *_), ir in cost.items():
    lines[f, line] += ir
    parts[part(f, line)] += ir
for part, ir in parts.most_common() + [("total", sum(cost.values()))]: print(f"{part:12} {ir:>12}")
if "--lines" in sys.argv: print(*(f"{ir:>12} {f}:{line}" for (f, line), ir in lines.most_common(40)), sep="\n")
at = sys.argv[sys.argv.index("--at") + 1] if "--at" in sys.argv else None
print(*(f"{ir:>12} {hex(k[2])} {k[0]}:{k[1]}" for k, ir in sorted(cost.items()) if len(k) > 2 and f"{k[0]}:{k[1]}" == at),
      sep="\n")
