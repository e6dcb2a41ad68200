#!/usr/bin/env python3
"""The crate's layers: import circles and upward imports between top-level modules (issue 21).

Reads every src/**/*.rs, maps it to its top-level module (src/calibration/fit.rs -> fit,
src/analysis/diagnose/gof.rs -> diagnose; each layer is a folder of src/), collects references to `crate::<module>` in code (`use`
lines and paths; comment lines, and so doc links, do not count: they are no dependency; test
modules do not count either: they may reach anywhere), and checks that graph against the
LAYER table below: a module may import only from its own layer or a lower one.

Prints every circle (strongly connected component of more than one module) with its edge
count, every upward edge (an import from a higher layer), and a one-line summary. Exit status
1 when there is a circle, when more than MAX_UPWARD edges go upward, when a module is
missing from the table, or when a module's file is not in its layer's folder.

    scripts/layers.py            # the check
    scripts/layers.py --edges    # also every edge, module -> module (files that make it)
"""
import re
import sys
from collections import defaultdict
from pathlib import Path

# Lowest first. Each top-level module of src/ is in exactly one layer.
LAYERS = [
    # Infrastructure every layer may use: the error enum, atomic output files, hashing of
    # JSON values (run identities), the journal of finished work and progress reporting
    # (the calibration layer's sweep keeps a journal and reports progress, so they are low).
    ("infra", ["error", "output", "identity", "journal", "progress"]),
    # Numerics: forward-mode duals, the least-squares solver, the integrator (generic over
    # its `OdeSystem`, knows no model), start-point sampling, one-dimensional minimisation.
    ("numerics", ["dual", "lsq", "ode", "sampling", "scalar_min"]),
    # Measured data: curves, ruptures, test conditions, specimens.
    ("data", ["data", "specimen"]),
    # The constitutive models, their parameter space, the eq. 8 objective over simulated
    # curves and the models' initial guesses (the KHD guess fits eq. 8 sub-problems, and the
    # registry names each family's guess: one module).
    ("model", ["model"]),
    # Statistical models of the data around a model: the error model, the likelihood,
    # activation energies, Larson–Miller, the empirical baselines, synthetic data sets.
    ("statistics", ["errmodel", "likelihood", "activation", "lmp", "baseline", "synth"]),
    # The run's resolved settings (the TOML schema): every command of the library takes it.
    ("settings", ["config"]),
    # Calibration: the fit, its tables and plots, the multistart sweep (which reports
    # through `report`).
    ("calibration", ["fit", "report", "sweep"]),
    # Analysis commands on calibrated models.
    ("analysis", ["predict", "simulate", "diagnose", "uncertainty", "holdout", "scores"]),
    # Experiments over many synthetic worlds.
    ("experiments", ["battery"]),
    # Exporters: each command's result written to its files and the console.
    ("io", ["export"]),
    # The command line parsed, resolved and dispatched to the commands (src/main.rs is only
    # its entry point).
    ("app", ["cli", "commands"]),
]
MAX_UPWARD = 2

LAYER = {m: i for i, (_, ms) in enumerate(LAYERS) for m in ms}
src = Path(__file__).resolve().parent.parent / "src"
# Each layer is a folder of src/ holding its modules (src/numerics/ode/, src/calibration/fit.rs);
# `data` and `model` are themselves the data and model layers' folders (src/data/specimen.rs is
# the data layer's second module). The crate root re-exports every module under its own name.
FOLDERS = {name for name, _ in LAYERS} - {"data", "model"}


def module_of(rel):
    """The top-level module a file of src/ belongs to (None: lib.rs, main.rs, a layer's mod.rs)."""
    p = rel.parts
    if p[0] in FOLDERS:
        return None if len(p) == 1 or p[1] == "mod.rs" else Path(p[1]).stem
    if p[0] == "data" and len(p) > 1 and Path(p[1]).stem == "specimen":
        return "specimen"
    if len(p) == 1 and rel.stem in ("lib", "main"):
        return None
    return p[0] if len(p) > 1 else rel.stem


def layer_folder(rel):
    """The layer a file's folder says it is in."""
    return "data" if rel.parts[0] in ("data", "data.rs") else rel.parts[0].removesuffix(".rs")


def referenced(m, n):
    """The module a path `crate::m::n` reaches (through a layer folder or directly)."""
    if m in FOLDERS:
        return n
    if m == "data" and n == "specimen":
        return "specimen"
    return m


def code_of(text):
    """The text without its test module and without comment lines (`//`, `///`, `//!`)."""
    text = re.split(r"#\[cfg\(test\)\]\s*mod tests", text)[0]
    return "\n".join(l for l in text.splitlines() if not l.lstrip().startswith("//"))


files = {f.relative_to(src): module_of(f.relative_to(src)) for f in src.rglob("*.rs")}
mods = {m for m in files.values() if m}
misplaced = sorted({(m, str(rel)) for rel, m in files.items()
                    if m in LAYER and layer_folder(rel) != LAYERS[LAYER[m]][0]})
edges = defaultdict(set)
for rel, me in files.items():
    if me is None:
        continue
    text = code_of((src / rel).read_text())
    for m, n in re.findall(r"crate::([a-z_0-9]+)(?:::([a-z_0-9]+))?", text):
        m = referenced(m, n)
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
unplaced = sorted(mods - LAYER.keys())
for m in unplaced:
    print(f"not in the LAYER table: {m}")
for m in sorted(LAYER.keys() - mods):
    print(f"in the LAYER table but not in src/: {m}")
upward = sorted((a, b) for (a, b) in edges if a in LAYER and b in LAYER and LAYER[b] > LAYER[a])
for a, b in upward:
    print(f"upward: {a} ({LAYERS[LAYER[a]][0]}) -> {b} ({LAYERS[LAYER[b]][0]}): "
          f"{', '.join(sorted(edges[(a, b)]))}")
for m, f in misplaced:
    print(f"{f}: module {m} is in layer {LAYERS[LAYER[m]][0]}, not in this folder")
ok = not circles and not unplaced and not misplaced and len(upward) <= MAX_UPWARD
print(f"{len(mods)} modules in {len(LAYERS)} layers, {len(edges)} edges, {len(circles)} circle(s), "
      f"{len(upward)} upward edge(s) (at most {MAX_UPWARD}): {'ok' if ok else 'FAILED'}")
sys.exit(0 if ok else 1)
