#!/usr/bin/env bash
# The measurement session behind README.md's numbers, in sequence on an otherwise idle machine:
# fit and 200-start sweeps at 560 and 590 °C, the 1,001 × 10 sweep on 2 threads, sweep
# throughput on 1 and 2 threads, the criterion benchmarks and the SciPy comparison.
# Usage: scripts/measure_all.sh [OUT]   (default results/measurements; about 10 minutes)
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/measurements}
mkdir -p "$out"
cargo build --release -q
bin=./target/release/creepfit
{ date; nproc; lscpu | grep "Model name"; } > "$out/when.txt"
( time $bin fit configs/560C.toml ) > "$out/fit560.log" 2>&1
( time $bin fit configs/590C.toml ) > "$out/fit590.log" 2>&1
$bin sweep configs/560C.toml --starts 200 --threads 2 --out "$out/sweep560" > "$out/sweep560.log" 2>&1
$bin sweep configs/590C.toml --starts 200 --threads 2 --out "$out/sweep590" > "$out/sweep590.log" 2>&1
$bin sweep configs/560C.toml --starts 1000 --threads 2 --out "$out/bench1000" > "$out/bench1000.log" 2>&1
scripts/bench_sweep.sh configs/560C.toml 24 > "$out/bench_sweep.log" 2>&1
cargo bench --bench core > "$out/criterion.log" 2>&1
scripts/compare_scipy.sh --with-590 > "$out/compare_scipy.log" 2>&1
grep -h "fits computed now" "$out"/*.log
echo "outputs in $out"
