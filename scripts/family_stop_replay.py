#!/usr/bin/env python3
"""Replay the null bootstrap of finished diagnoses under the family stop.

For each diagnosis.json given (or found under the folders given), the null statistics it
stored (`bootstrap.null_statistics`, replicate order) are read again batch by batch (10
replicates) and the first batch end is found where Holm's procedure over the family could
reject none of the tests any more: every test's (g + 1)/(first + 1) above α/m (and above α/2
too where tests may go on past `max`, `bootstrap.most` > `max`), g its replicates at or above its observed statistic (a failed refit counts as at or above),
m the family's size (every extension with an observed ratio, and the goodness-of-fit
shapes that decide: the two beyond specimen shapes with specimen effects, the other two
without). Prints, per diagnosis, the replicates the run drew and those it would draw with
the stop, then the totals. Usage: scripts/family_stop_replay.py PATH [PATH ...]
"""
import glob
import json
import os
import sys


def family(d):
    effects = d["base"].get("specimen") is not None
    out = []
    for t in d["bootstrap"]["null_statistics"]:
        if t["test"].startswith("base") and (("beyond" in t["test"]) != effects):
            continue
        if t["observed"] is None:
            continue
        out.append(t)
    return out


def replay(d):
    first = d["bootstrap"]["max"]
    alpha = d["alpha"]
    fam = family(d)
    drawn = d["bootstrap"]["replicates"]
    if not fam:
        return drawn, drawn
    bound = alpha / len(fam)
    if d["bootstrap"]["most"] > first:
        bound = max(bound, alpha / 2.0)
    for n in range(10, min(drawn, first) + 1, 10):
        settled = True
        for t in fam:
            g = sum(1 for x in t["values"][:n] if x is None or x >= t["observed"])
            if not (g + 1) / (first + 1) > bound:
                settled = False
                break
        if settled:
            return drawn, n
    return drawn, drawn


def main(paths):
    files = []
    for p in paths:
        if os.path.isdir(p):
            files += sorted(glob.glob(os.path.join(p, "**", "diagnosis.json"), recursive=True))
        else:
            files.append(p)
    tot = [0, 0]
    earlier = 0
    for f in files:
        d = json.load(open(f))
        drawn, stop = replay(d)
        tot[0] += drawn
        tot[1] += stop
        earlier += stop < drawn
        print(f"{os.path.basename(os.path.dirname(f))}\t{d['verdict']}\t{drawn}\t{stop}")
    print(f"# {len(files)} diagnoses, {earlier} stop earlier: replicates {tot[0]} -> {tot[1]}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
