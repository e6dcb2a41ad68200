#!/usr/bin/env bash
# The calibration of `diagnose` beyond CI's reduced check (tests/diagnose.rs runs 6 sets):
# the full battery on evaluation seeds never used while developing, in both worlds
# (identical specimens; specimens with scatter and replicates), null sets with scatter alone,
# then the Alloy 617
# logging-density check at every temperature and the hidden effect under scatter of
# tests/specimen.rs (both ignored in CI for their time). Resumable: rerun to continue a battery.
#
#   scripts/bench_battery.sh [SETS] [OUT]      (default: 200 sets per world, results/battery)
#
# Each battery writes confusion.csv, power.csv, summary.md and summary.json (false-alarm
# rate, power, scatter coverage) into OUT/<world>-<seed>/, then a battery of null sets alone with specimen
# scatter (OUT/specimens-none-98001/: the false-alarm rate on SETS null sets). Takes hours on
# 2 cores (measured: 20–100 s per set).
set -euo pipefail
cd "$(dirname "$0")/.."
sets="${1:-200}"
out="${2:-results/battery}"
cargo build --release --quiet
bin=target/release/creepfit
echo "== CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) threads"
for world in identical specimens; do
    seed=$([ "$world" = identical ] && echo 80001 || echo 97001)
    dir="$out/$world-$seed"
    echo "== battery: $sets sets, world $world, seeds from $seed -> $dir"
    time "$bin" battery "$dir" --sets "$sets" --seed "$seed" --world "$world"
done
# The false-alarm rate under specimen scatter on as many null sets (a quarter of the mixed
# battery above is null data; this one is all null data, its own seeds).
dir="$out/specimens-none-98001"
echo "== battery: $sets null sets, world specimens, seeds from 98001 -> $dir"
time "$bin" battery "$dir" --sets "$sets" --seed 98001 --world specimens --scenario none
echo "== Alloy 617: the same verdict on every 10th point, every temperature"
cargo test --release --test diagnose -- --ignored
echo "== a loading strain hidden under specimen scatter, named (seed 95102)"
cargo test --release --test specimen -- --ignored an_effect_under_specimen_scatter_is_named
