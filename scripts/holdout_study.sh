#!/usr/bin/env bash
# Leave-one-out study: for every configuration given, `creepfit holdout` at each temperature
# of HOLDOUT_TEMPS (default "850 900") and for each campaign of HOLDOUT_CAMPAIGNS (default
# none; e.g. "KAERI2 INL2" for data/alloy617), and one table of the mean |log10 error| of the
# held-out rupture times, creepfit beside the Larson–Miller baseline fitted to the same
# training data and the best classical baseline (summary.json "one_to_beat") with creepfit's
# difference from it and its 95 % interval ("creepfit_difference").
#
#   scripts/holdout_study.sh [--starts N] CONFIG...
#   HOLDOUT_CAMPAIGNS="KAERI2 INL2" scripts/holdout_study.sh configs/alloy617.toml
#
# Outputs: results/holdout-study/<config stem>/<T>C/ and .../campaign-<NAME>/ (holdout.csv,
# summary.json, plots).
set -euo pipefail
cd "$(dirname "$0")/.."
starts=()
if [[ "${1:-}" == "--starts" ]]; then starts=(--starts "$2"); shift 2; fi
temps=${HOLDOUT_TEMPS:-"850 900"}
campaigns=${HOLDOUT_CAMPAIGNS:-}
cargo build --release --quiet
bin=target/release/creepfit
printf "%-28s %10s %6s %12s %12s %-24s %-26s %10s %8s\n" config held_out tests creepfit LMP one_to_beat "creepfit-it (95 %)" curve_rms wall_s
for cfg in "$@"; do
  stem=$(basename "$cfg" .toml)
  for t in $temps ${campaigns:+$(printf 'campaign:%s ' $campaigns)}; do
    case $t in
      campaign:*) name=${t#campaign:}; out=results/holdout-study/$stem/campaign-$name; what=(--campaign "$name"); t=$name ;;
      *) out=results/holdout-study/$stem/${t}C; what=(--temperature "$t") ;;
    esac
    mkdir -p "$out"
    "$bin" holdout "$cfg" "${what[@]}" "${starts[@]}" --out "$out" >"$out/run.log" 2>&1 \
      || { echo "$stem $t: failed, see $out/run.log"; continue; }
    python3 - "$out/summary.json" "$stem" "$t" "$out/timings.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s["wall_s"] = json.load(open(sys.argv[4]))["wall_s"]  # this run's (a rerun resumes the fits)
b = s.get("one_to_beat")
best = f"{b['name']} {b['mean_abs_log10_err']:.3f}" if b else "none"
d = (b or {}).get("creepfit_difference")
f = lambda v: "-" if v is None else f"{v:+.3f}"
diff = f"{f(d['mean'])} ({f(d['lo95'])}..{f(d['hi95'])})" if d else "-"
print(f"{sys.argv[2]:<28} {sys.argv[3]:>10} {s['tests']:>6} {s['model_mean_abs_log10_err']:>12.3f} "
      f"{s['lmp_mean_abs_log10_err']:>12.3f} {best:<24} {diff:<26} {s['mean_curve_rms_pct']:>10.2f} {s['wall_s']:>8.1f}")
PY
  done
done
