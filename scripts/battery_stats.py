#!/usr/bin/env python3
"""Pooled numbers of one or more batteries' `results.jsonl` files (one line per diagnosed set,
as `creepfit battery` writes them and docs/measurements/ keeps them), so that the figures the
docs quote can be recomputed from the repository.

Per file and pooled (sets counted once by seed; a seed in two files is an error):
- null sets (scenario `none`): false alarms (verdict other than `adequate`) with the Wilson 95 %
  interval, and each alarm's seed, verdict and cause;
- sets with a catalogued effect that the oracle calls detectable: named correctly (verdict
  `extension` with the set's own scenario as cause), with the Wilson interval;
- the specimen scatter's 95 % interval against its truth (worlds with scatter), per kind (rate,
  ductility, coarsening where the sets have it), counted as the battery's `summary.json` does:
  coverage where the truth has the scatter, and where it has none how often the interval
  excludes zero;
- the median wall time of a set.

    scripts/battery_stats.py docs/measurements/null-battery-180001.jsonl [more.jsonl ...]
"""
import json
import math
import sys


def wilson(k, n, z=1.959964):
    """The Wilson score interval of k successes in n trials (fractions)."""
    if n == 0:
        return (float("nan"), float("nan"))
    p = k / n
    d = 1 + z * z / n
    c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return (max(0.0, c - h), min(1.0, c + h))


def rate(k, n):
    if n == 0:
        return f"{k} of {n}"
    lo, hi = wilson(k, n)
    return f"{k} of {n} ({100 * k / n:.1f} %, Wilson 95 % {100 * lo:.1f}–{100 * hi:.1f} %)"


def load(path):
    rows = []
    with open(path) as f:
        for i, line in enumerate(f, 1):
            line = line.strip()
            if not line:
                continue
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError as e:
                sys.exit(f"error: {path}:{i}: not a JSON line ({e.msg})")
    return rows


KINDS = ["rate", "ductility", "coarsening"]


def covers(lo, hi, truth):
    return lo is not None and hi is not None and lo <= truth <= hi


def summary(rows):
    out = []
    done = [r for r in rows if r.get("error") is None]
    failed = len(rows) - len(done)
    null = [r for r in done if r["scenario"] == "none"]
    alarms = [r for r in null if r["verdict"] != "adequate"]
    out.append(f"sets {len(rows)} ({failed} failed to run)")
    if null:
        out.append("false alarms " + rate(len(alarms), len(null)))
        for r in alarms:
            why = r.get("cause") or r.get("closest") or "-"
            out.append(f"  {r['seed']}: {r['verdict']} {why}")
    eff = [r for r in done if r["scenario"] != "none" and r.get("detectable")]
    if eff:
        named = {
            r["seed"] for r in eff if r["verdict"] == "extension" and r.get("cause") == r["scenario"]
        }
        out.append("detectable effects named " + rate(len(named), len(eff)))
        by = {}
        for r in eff:
            k, n = by.get(r["scenario"], (0, 0))
            by[r["scenario"]] = (k + (r["seed"] in named), n + 1)
        for s, (k, n) in sorted(by.items()):
            out.append(f"  {s}: {k} of {n}")
    # As the battery's own `summary.json` counts them (`coverage_of` in
    # src/experiments/battery.rs): per kind, a set whose truth has the scatter is covered when
    # the interval holds it (a kind the fit dropped, with no interval, is not); a set whose
    # truth has none counts when the interval excludes zero.
    for k, kind in enumerate(KINDS):
        rows_k = [r for r in done if len(r.get("scatter_true") or []) > k]
        if not rows_k:
            continue
        true = [r for r in rows_k if r["scatter_true"][k] > 0]
        cov = {
            r["seed"]
            for r in true
            if covers(r["scatter_lo95"][k], r["scatter_hi95"][k], r["scatter_true"][k])
        }
        out.append(f"{kind} scatter covered " + rate(len(cov), len(true)))
        for r in true:
            if r["seed"] not in cov:
                lo, hi = r["scatter_lo95"][k], r["scatter_hi95"][k]
                where = "dropped" if lo is None else f"interval {lo:.3f}–{hi:.3f}"
                out.append(
                    f"  miss {r['seed']} ({r['sampling']}): truth {r['scatter_true'][k]:.3f}, {where}"
                )
        absent = [r for r in rows_k if r["scatter_true"][k] == 0]
        spurious = [r for r in absent if (r["scatter_lo95"][k] or 0) > 0]
        out.append(f"no {kind} scatter, interval excludes zero: {len(spurious)} of {len(absent)}")
    walls = sorted(r["wall_s"] for r in done if r.get("wall_s") is not None)
    if walls:
        out.append(f"median wall {walls[len(walls) // 2]:.0f} s a set")
    return out


def main(paths):
    if not paths:
        sys.exit(__doc__.strip().splitlines()[-1].strip())
    pooled, seen = [], {}
    for p in paths:
        rows = load(p)
        for r in rows:
            if r["seed"] in seen:
                sys.exit(f"error: {p}: seed {r['seed']} is in {seen[r['seed']]} too")
            seen[r["seed"]] = p
        pooled.extend(rows)
        print(f"# {p}")
        print("\n".join(summary(rows)))
    if len(paths) > 1:
        print("# pooled")
        print("\n".join(summary(pooled)))


if __name__ == "__main__":
    main(sys.argv[1:])
