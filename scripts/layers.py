#!/usr/bin/env python3
"""Import circles between the crate's top-level modules (issue 21).

Reads every src/**/*.rs, maps it to its top-level module (src/fit.rs -> fit,
src/diagnose/gof.rs -> diagnose), collects references to `crate::<module>` (in `use` lines
and in paths), and prints the strongly connected components of that graph with more than
one module, each with the edges that close it. Exit status 1 when there is one.

    scripts/layers.py            # the circles
    scripts/layers.py --edges    # every edge, module -> module (files that make it)
"""
import re
import sys
from collections import defaultdict
from pathlib import Path

src = Path(__file__).resolve().parent.parent / "src"
mods = {p.stem for p in src.glob("*.rs")} | {p.name for p in src.iterdir() if p.is_dir()}
mods -= {"lib", "main"}
edges = defaultdict(set)
for f in src.rglob("*.rs"):
    rel = f.relative_to(src)
    me = rel.parts[0] if len(rel.parts) > 1 else rel.stem
    if me in ("lib", "main"):
        continue
    text = f.read_text()
    # Test modules do not count: they may reach anywhere.
    text = re.split(r"#\[cfg\(test\)\]\s*mod tests", text)[0]
    for m in re.findall(r"crate::([a-z_0-9]+)", text):
        if m in mods and m != me:
            edges[(me, m)].add(str(rel))
    for m in re.findall(r"use crate::\{([^}]*)\}", text):
        for part in re.findall(r"([a-z_0-9]+)(?:::|\s*,|\s*$)", m):
            if part in mods and part != me:
                edges[(me, part)].add(str(rel))
graph = defaultdict(set)
for a, b in edges:
    graph[a].add(b)

# Tarjan's strongly connected components.
index, low, stack, on, sccs, n = {}, {}, [], set(), [], [0]
def visit(v):
    index[v] = low[v] = n[0]; n[0] += 1; stack.append(v); on.add(v)
    for w in graph[v]:
        if w not in index:
            visit(w); low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        c = []
        while True:
            w = stack.pop(); on.discard(w); c.append(w)
            if w == v:
                break
        sccs.append(sorted(c))
sys.setrecursionlimit(10000)
for v in sorted(mods):
    if v not in index:
        visit(v)
if "--edges" in sys.argv:
    for (a, b), files in sorted(edges.items()):
        print(f"{a} -> {b}: {', '.join(sorted(files))}")
circles = [c for c in sccs if len(c) > 1]
for c in circles:
    inside = sorted((a, b) for (a, b) in edges if a in c and b in c)
    print(f"circle of {len(c)} modules: {' '.join(c)} ({len(inside)} edges inside)")
print(f"{len(mods)} modules, {len(edges)} edges, {len(circles)} circle(s)")
sys.exit(1 if circles else 0)
