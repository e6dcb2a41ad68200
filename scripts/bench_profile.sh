#!/usr/bin/env bash
# Speed of `creepfit profile` on the seed's 560 °C data (README, "How sure"): the whole
# command on 2 threads, RUNS times, with the phases it reports in summary.json (the profiles
# of the six constants, their calibration, the intervals of the predictions at 70 MPa and
# the band). Prints the CPU and the load before and after, since the machine is shared.
#   scripts/bench_profile.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-3}
cargo build --release --quiet
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores"
echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sed "s#\.\./data/#$PWD/data/#" configs/560C.toml > "$tmp/560.toml"
printf '\n[profile]\npredict_stress_MPa = [70]\n' >> "$tmp/560.toml"
# A phase's seconds, read inside "timings_s" of timings.json.
field() { sed -n '/"timings_s"/,/}/p' "$tmp/out/timings.json" | grep -o "\"$1\": [0-9.e-]*" | head -1 | awk '{printf "%.2f", $2}'; }
for i in $(seq "$runs"); do
    rm -rf "$tmp/out"  # else the run resumes from the previous one's journal
    start=$(date +%s.%N)
    ./target/release/creepfit profile "$tmp/560.toml" --threads 2 --out "$tmp/out" > /dev/null
    end=$(date +%s.%N)
    printf 'run %d: command %.2f s | fit %s, calibration %s, profiles of 6 constants %s, prediction intervals %s, band %s, combinations %s s\n' \
        "$i" "$(awk -v a="$start" -v b="$end" 'BEGIN{print b-a}')" "$(field fit)" "$(field calibration)" "$(field profiles)" \
        "$(field prediction_intervals)" "$(field bands)" "$(field combinations)"
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
