#!/usr/bin/env python3
"""The campaign test of `fit` (summary.json `specimens.campaign_levels`) on generated null sets:
each set of the specimens world (scenario `none`: specimens with their own creep rate and, in
half the sets, ductility; replicates; no campaign effect) is generated with `creepfit synth`,
its specimens are given campaigns `A` and `B` at random (both present; a fixed stream per
seed), and `creepfit fit` with the likelihood objective fits their factors (`auto`, the scatter
beyond the stress trend). The labels carry no effect, so the test's p-values should be uniform:
rejections at 5 % and 1 % near those rates. Appends one line per set to OUT/results.jsonl.

    scripts/campaign_null.py CREEPFIT_BINARY OUT FIRST_SEED SETS
"""
import csv
import json
import os
import random
import subprocess
import sys

binary, out, first, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
os.makedirs(out, exist_ok=True)
results = open(os.path.join(out, "results.jsonl"), "a")
for seed in range(first, first + n):
    sets = os.path.join(out, "sets")
    sd = os.path.join(sets, f"set-{seed}")
    if not os.path.exists(sd):
        subprocess.run([binary, "synth", sets, "--sets", "1", "--seed", str(seed), "--world",
                        "specimens", "--scenario", "none"], check=True, capture_output=True)
    rows = list(csv.DictReader(open(os.path.join(sd, "curves.csv"))))
    labels = sorted({r["specimen"] for r in rows})
    rng = random.Random(seed)
    while True:
        campaign = {label: rng.choice("AB") for label in labels}
        if len(set(campaign.values())) == 2:
            break
    new, count = {}, {"A": 0, "B": 0}
    for label in labels:
        c = campaign[label]
        count[c] += 1
        new[label] = f"{c}-{count[c]}"
    for name in ["curves.csv", "ruptures.csv"]:
        rr = list(csv.DictReader(open(os.path.join(sd, name))))
        with open(os.path.join(sd, f"camp-{name}"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rr[0].keys()))
            w.writeheader()
            for r in rr:
                r["specimen"] = new[r["specimen"]]
                w.writerow(r)
    cfg = open(os.path.join(sd, "config.toml")).read()
    cfg = cfg.replace('curves = "curves.csv"', 'curves = "camp-curves.csv"')
    cfg = cfg.replace('ruptures = "ruptures.csv"', 'ruptures = "camp-ruptures.csv"')
    cfg += '\n[objective]\nkind = "likelihood"\n'
    with open(os.path.join(sd, "camp.toml"), "w") as f:
        f.write(cfg)
    o = subprocess.run([binary, "fit", os.path.join(sd, "camp.toml"), "--out",
                        os.path.join(sd, "fit")], capture_output=True, text=True)
    if o.returncode != 0:
        results.write(json.dumps({"seed": seed, "error": o.stderr[-300:]}) + "\n")
        results.flush()
        continue
    s = json.load(open(os.path.join(sd, "fit", "summary.json")))
    levels = s["specimens"].get("campaign_levels", {})
    results.write(json.dumps({
        "seed": seed,
        "levels": {k: {"p": v["p_value"], "df": v["df"], "f": v["f"]} for k, v in levels.items()},
        "scatter": {k: v["sd_ln"] for k, v in s["specimens"]["scatter"].items()},
    }) + "\n")
    results.flush()
