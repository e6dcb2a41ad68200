#!/usr/bin/env bash
# Wall time and peak memory of `creepfit diagnose` on 2 threads: the seed's 560 °C and 590 °C
# data (3 curves each), a generated 5-curve data set with a hidden effect (the full bootstrap
# runs there), and every temperature of the Alloy 617 data (5–13 dense logged curves).
# Usage: scripts/bench_diagnose.sh [OUT]   (default /tmp/creepfit-bench-diagnose)
# Needs /usr/bin/time (Debian package `time`). Run it on an otherwise idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-/tmp/creepfit-bench-diagnose}"
rm -rf "$out"; mkdir -p "$out"
cargo build --release --quiet
bin=target/release/creepfit
[ -x /usr/bin/time ] || { echo "error: /usr/bin/time missing (apt-get install time)" >&2; exit 1; }
echo "# $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"
# A 5-curve set with a catalogued effect (the bootstrap cannot stop early).
"$bin" synth "$out/sets" --sets 1 --seed 7 --scenario dislocation_damage > /dev/null
printf '%-28s %8s %8s %10s %8s %10s %8s %10s  %s\n' data wall_s user_s max_rss_MB lm_runs lm_iters at_limit lm_evals verdict
for cfg in configs/560C.toml configs/590C.toml "$out/sets/set-7/config.toml" \
           configs/alloy617-750C.toml configs/alloy617-850C.toml \
           configs/alloy617-900C.toml configs/alloy617-950C.toml; do
    name=$(basename "$(dirname "$cfg")")/$(basename "$cfg" .toml)
    tag=$(echo "$name" | tr '/' '_')
    /usr/bin/time -f '%e %U %M' -o "$out/$tag.time" \
        "$bin" diagnose "$cfg" --threads 2 --out "$out/$tag" > "$out/$tag.log" 2>&1
    read -r wall user rss < "$out/$tag.time"
    verdict=$(python3 -c "import json,sys; d=json.load(open('$out/$tag/diagnosis.json')); print(d['verdict'], d['cause'] or '', d['bootstrap']['replicates'], 'replicates')")
    # The Levenberg–Marquardt work (timings.json `phase_lm`): runs, iterations, runs at the
    # limit, evaluations (an iteration's cost: rejected trials and probes count too).
    lm=$(python3 -c "import json; t=json.load(open('$out/$tag/timings.json'))['phase_lm']['total']; print(t['runs'], t['iterations'], t['runs_at_limit'], t['evaluations'])")
    read -r runs iters limit evals <<< "$lm"
    printf '%-28s %8s %8s %10.0f %8s %10s %8s %10s  %s\n' "$name" "$wall" "$user" "$(echo "$rss/1024" | bc -l)" "$runs" "$iters" "$limit" "$evals" "$verdict"
done
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
