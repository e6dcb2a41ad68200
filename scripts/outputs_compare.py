#!/usr/bin/env python3
"""Compare two output trees of creepfit byte for byte (scripts/outputs_identical.sh).

    scripts/outputs_compare.py OLD_DIR NEW_DIR

Left out: timings.json (wall times only) and .creepfit.lock (the PID of the run that held the
folder). A file that differs is compared again without what differs between two runs of one
computation, and then counts as identical "but for run facts": a JSON file without its
wall-time keys (manifest.json's started/written_unix_s, summary.json's wall_s, ...); a
journal.jsonl (a resume log) without its header's `build` (the binary's own size and mtime)
and with its records as a set (parallel fits are journaled in the order they finish);
stdout.txt with the numbers of its timing lines masked. Prints each differing file and a
summary; exit 1 if any file differs or is in one tree only.
"""
import json
import re
import sys
from pathlib import Path

old, new = Path(sys.argv[1]), Path(sys.argv[2])
SKIP = {"timings.json", ".creepfit.lock"}
TIME_KEYS = {"wall_s", "fit_wall_s", "phase_s", "timings_s", "training_fit_s",
             "started_unix_s", "written_unix_s"}
TIMING_LINE = re.compile(r"( in [0-9.]+ s\b| fits/s\)|^Wall time )")


def files(d):
    return {p.relative_to(d) for p in d.rglob("*") if p.is_file() and p.name not in SKIP}


def untimed(v):
    if isinstance(v, dict):
        return {k: untimed(x) for k, x in v.items() if k not in TIME_KEYS}
    if isinstance(v, list):
        return [untimed(x) for x in v]
    return v


def journal(text):
    lines = [json.loads(l) for l in text.splitlines() if l.strip()]
    for l in lines:
        if isinstance(l, dict) and isinstance(l.get("header"), dict):
            l["header"].pop("build", None)
    return sorted(json.dumps(untimed(l), sort_keys=True) for l in lines)


def stdout(text):
    return [re.sub(r"[0-9]+(\.[0-9]+)?", "N", l) if TIMING_LINE.search(l) else l
            for l in text.splitlines()]


def run_facts_only(f, x, y):
    """The bytes x and y of file f are the same but for wall times, PID, build, order."""
    try:
        x, y = x.decode(), y.decode()
        if f.name == "journal.jsonl":
            return journal(x) == journal(y)
        if f.suffix == ".json":
            return untimed(json.loads(x)) == untimed(json.loads(y))
        if f.name == "stdout.txt":
            return stdout(x) == stdout(y)
    except ValueError:
        pass
    return False


a, b = files(old), files(new)
bad = [f"{f}: only in {'old' if f in a else 'new'}" for f in sorted(a ^ b)]
same, facts = 0, []
for f in sorted(a & b):
    x, y = (old / f).read_bytes(), (new / f).read_bytes()
    if x == y:
        same += 1
    elif run_facts_only(f, x, y):
        facts.append(str(f))
    else:
        bad.append(f"{f}: differs")
for line in bad:
    print("DIFFERS", line)
print(f"identical but for run facts (wall times, build stamp, journal order): {', '.join(facts)}")
print(f"{len(a | b)} files compared: {same} byte-identical, {len(facts)} identical but for run "
      f"facts, {len(bad)} differing (timings.json and .creepfit.lock left out)")
sys.exit(1 if bad else 0)
