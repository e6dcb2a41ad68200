#!/usr/bin/env bash
# The false-alarm rate and power of `fit`'s check of the specimen factors against stress
# (docs/DIAGNOSE.md, "Do the factors follow stress?"): generate sets with specimen scatter,
# fit each by maximum likelihood with specimen effects (`auto`), and count the sets whose
# `summary.json` → `specimens.stress_trend` has p < 0.05 and p < 0.01, per kind.
#
#   scripts/stress_trend_study.sh OUT SEED SETS [SCENARIO]    (SCENARIO: none by default)
#
# OUT/results.tsv has a line per set and kind: seed, kind, slope, se, df, p. Uses the release
# binary (cargo build --release first).
set -euo pipefail
out=$1; seed=$2; sets=$3; scenario=${4:-none}
bin="$(cd "$(dirname "$0")/.." && pwd)/target/release/creepfit"
mkdir -p "$out"
"$bin" synth "$out/sets" --sets "$sets" --seed "$seed" --scenario "$scenario" --world specimens > "$out/synth.log"
: > "$out/results.tsv"
for d in "$out"/sets/set-*; do
    grep -q '^\[objective\]' "$d/config.toml" || printf '\n[objective]\nkind = "likelihood"\n' >> "$d/config.toml"
    if ! "$bin" fit "$d/config.toml" -q --out "$d/fit" > "$d/fit.log" 2>&1; then
        echo "${d##*-} FAILED" >> "$out/results.tsv"
        continue
    fi
    python3 - "$d" >> "$out/results.tsv" <<'PY'
import json, sys
d = sys.argv[1]
trend = json.load(open(d + "/fit/summary.json")).get("specimens", {}).get("stress_trend", {})
if not trend:
    print(d.rsplit("-", 1)[-1], "none")
for kind, t in trend.items():
    print(d.rsplit("-", 1)[-1], kind, t["slope_per_ln_stress"], t["se"], t["df"], t["p_value"])
PY
done
python3 - "$out/results.tsv" <<'PY'
import sys
rows = [l.split() for l in open(sys.argv[1])]
for kind in ("rate", "ductility"):
    ps = [float(r[5]) for r in rows if len(r) > 5 and r[1] == kind and r[5] not in ("None", "null", "NaN")]
    print(f"{kind}: {len(ps)} sets with the factors; p < 0.05 in {sum(p < 0.05 for p in ps)}, p < 0.01 in {sum(p < 0.01 for p in ps)}")
print(f"sets without specimen effects: {sum(1 for r in rows if r[1] == 'none')}; failed fits: {sum(1 for r in rows if r[1] == 'FAILED')}")
PY
