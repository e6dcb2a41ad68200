#!/usr/bin/env python3
"""The campaign test of `fit` (summary.json `specimens.campaign_levels`) and the specimen
scatter's interval on generated sets of the campaigns world (`creepfit synth --world
campaigns --scenario none`: the specimens world's sets, their specimens from two campaigns `A`
and `B` alternating in stress order, each campaign with its own log-normal creep-rate factor of
sd 10–40 %). Each set is fitted by `creepfit fit` with the likelihood objective (`auto`
specimen effects, the configuration's own scatter estimate). Appends one line per set to
OUT/results.jsonl: the truth (specimen and campaign sd, the campaigns' true ln-rate
contrast), the rate test's F, df and p, the rate scatter's estimate and 95 % interval, and
the sd of a new specimen from a new campaign with its interval (`new_campaign_sd_ln`).
Read with `--summary OUT`: the test's rejection rate at 1 % by the true contrast in units of
the specimen sd, and how often each interval covers the within-campaign sd and the sd of a
new specimen from a new campaign.

    scripts/campaign_power.py CREEPFIT_BINARY OUT FIRST_SEED SETS
    scripts/campaign_power.py --summary OUT   (or a results file, e.g. docs/measurements/campaign-power-213001.jsonl)
"""
import json
import os
import subprocess
import sys


def summary(out):
    path = out if os.path.isfile(out) else os.path.join(out, "results.jsonl")
    rows = [json.loads(l) for l in open(path)]
    ok = [r for r in rows if r.get("error") is None]
    print(f"sets {len(rows)}, fitted {len(ok)}")
    tested = [r for r in ok if r["p"] is not None]
    print(f"campaign test made on {len(tested)} (the others: scatter at its floor or no dof)")
    bands = [(0, 1), (1, 2), (2, 4), (4, 1e9)]
    print("|true contrast| / specimen sd | sets | called at 1 % | at 5 % | median dof |")
    for lo, hi in bands:
        b = [r for r in tested if lo <= abs(r["contrast"]) / r["rate_sd"] < hi]
        if not b:
            continue
        c1 = sum(r["p"] < 0.01 for r in b)
        c5 = sum(r["p"] < 0.05 for r in b)
        d2 = sorted(r["df"][1] for r in b)[len(b) // 2]
        print(f"| {lo}–{hi if hi < 1e9 else '∞'} | {len(b)} | {c1} ({100*c1/len(b):.0f} %) | "
              f"{c5} ({100*c5/len(b):.0f} %) | (1, {d2}) |")
    det = [r for r in tested if r.get("detectable") is not None]
    if det:
        big = [r for r in det if abs(r["contrast"]) >= r["detectable"]]
        small = [r for r in det if abs(r["contrast"]) < r["detectable"]]
        print(f"true contrast at least the stated detectable difference: called in "
              f"{sum(r['p'] < 0.01 for r in big)} of {len(big)}; below it: "
              f"{sum(r['p'] < 0.01 for r in small)} of {len(small)}")
    sign = [r for r in tested if r["p"] < 0.01]
    right = sum((r["est_contrast"] > 0) == (r["contrast"] > 0) for r in sign)
    print(f"called with the true sign: {right} of {len(sign)}")
    sc = [r for r in ok if r["sd_lo"] is not None and r["sd_hi"] is not None]
    within = sum(r["sd_lo"] <= r["rate_sd"] <= r["sd_hi"] for r in sc)
    marginal = sum(r["sd_lo"] <= r["marginal_sd"] <= r["sd_hi"] for r in sc)
    print(f"rate scatter's 95 % interval covers the within-campaign sd in {within} of {len(sc)}, "
          f"the sd of a new specimen from a new campaign in {marginal} of {len(sc)}")
    nc = [r for r in ok if r.get("new_lo") is not None]
    if nc:
        cov = sum(r["new_lo"] <= r["marginal_sd"] <= r["new_hi"] for r in nc)
        low = sum(r["new_hi"] < r["marginal_sd"] for r in nc)
        both = [r for r in nc if r in sc]
        old_cov = sum(r["sd_lo"] <= r["marginal_sd"] <= r["sd_hi"] for r in both)
        big = [r for r in nc if r["campaign_sd"] >= r["rate_sd"]]
        print(f"new-campaign sd's 95 % interval (campaign_levels.rate.new_campaign_sd_ln) covers "
              f"the sd of a new specimen from a new campaign in {cov} of {len(nc)} (too low in "
              f"{low}); the rate scatter's interval on the same sets {old_cov} of {len(both)}; "
              f"where the campaign sd is at least the specimen sd: "
              f"{sum(r['new_lo'] <= r['marginal_sd'] <= r['new_hi'] for r in big)} against "
              f"{sum(r['sd_lo'] <= r['marginal_sd'] <= r['sd_hi'] for r in big if r in sc)} of {len(big)}")
        w = sorted(r["new_hi"] / r["new_lo"] for r in nc if r["new_lo"] > 0)
        if w:
            print(f"its upper/lower end ratio: median {w[len(w)//2]:.1f}")


def main():
    if sys.argv[1] == "--summary":
        summary(sys.argv[2])
        return
    binary, out, first, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    os.makedirs(out, exist_ok=True)
    results = open(os.path.join(out, "results.jsonl"), "a")
    sets = os.path.join(out, "sets")
    for seed in range(first, first + n):
        sd = os.path.join(sets, f"set-{seed}")
        if not os.path.exists(sd):
            subprocess.run([binary, "synth", sets, "--sets", "1", "--seed", str(seed), "--world",
                            "campaigns", "--scenario", "none"], check=True, capture_output=True)
        truth = json.load(open(os.path.join(sd, "truth.json")))["specimens"]
        labels, camp = truth["labels"], truth["campaign_effects"]
        level = {l.split("-")[0]: c for l, c in zip(labels, camp)}
        cfg = open(os.path.join(sd, "config.toml")).read()
        if "kind = \"likelihood\"" not in cfg:
            with open(os.path.join(sd, "config.toml"), "a") as f:
                f.write('\n[objective]\nkind = "likelihood"\n')
        o = subprocess.run([binary, "fit", os.path.join(sd, "config.toml"), "--out",
                            os.path.join(sd, "fit")], capture_output=True, text=True)
        row = {"seed": seed, "curves": len(labels), "rate_sd": truth["rate_sd"],
               "campaign_sd": truth["campaign_sd"],
               "marginal_sd": (truth["rate_sd"] ** 2 + truth["campaign_sd"] ** 2) ** 0.5,
               "contrast": level["A"] - level["B"], "error": None}
        if o.returncode != 0:
            row["error"] = o.stderr[-300:]
        else:
            s = json.load(open(os.path.join(sd, "fit", "summary.json")))["specimens"]
            lv = s.get("campaign_levels", {}).get("rate")
            sc = s["scatter"].get("rate", {})
            means = {g["campaign"]: g["mean_ln"] for g in lv["mean_ln_by_campaign"]} if lv else {}
            row.update({
                "p": lv["p_value"] if lv else None,
                "f": lv["f"] if lv else None,
                "df": lv["df"] if lv else None,
                "est_contrast": means.get("A", 0.0) - means.get("B", 0.0) if lv else None,
                "detectable": lv.get("detectable_difference_ln") if lv else None,
                "sd": sc.get("sd_ln"), "sd_lo": sc.get("sd_ln_lo95"), "sd_hi": sc.get("sd_ln_hi95"),
            })
            nc = lv.get("new_campaign_sd_ln") if lv else None
            if nc is not None:
                row.update({"new_sd": nc["estimate"], "new_lo": nc["lo95"], "new_hi": nc["hi95"]})
        results.write(json.dumps(row) + "\n")
        results.flush()


main()
