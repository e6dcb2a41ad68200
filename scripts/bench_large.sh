#!/usr/bin/env bash
# A large logged curve end to end: writes a data set with one 560 °C test logged at N points
# (default 1,000,000; examples/gen_large.rs: the 560 °C fit's constants plus 0.002 % noise)
# and two tests of 1,000 points, then measures wall time and peak memory (/usr/bin/time -v,
# Debian package `time`) of `creepfit simulate` (load + simulate every test at the measured
# times) and `creepfit fit` (load + initial guess + every local fit + outputs + plot), the fit
# RUNS times (default 3; the machine is shared, so say how loaded it was: the script prints
# the CPU and the load average before each run).
# Usage: scripts/bench_large.sh [N] [OUT_DIR]   (keeps OUT_DIR when given, else a temp dir)
# Environment: RUNS=k repeats the fit k times; ALSO="sweep diagnose" measures those commands
# on the same file too (sweep with --starts 4, i.e. 5 starts x 10 w).
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-1000000}
runs=${RUNS:-3}
if [ -n "${2:-}" ]; then out=$2; mkdir -p "$out"; else out=$(mktemp -d); trap 'rm -rf "$out"' EXIT; fi
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (apt-get install -y time)"; exit 1; }
cargo build --release --quiet --bin creepfit --example gen_large
./target/release/examples/gen_large "$out" "$n"
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; curves.csv $(du -h "$out/curves.csv" | cut -f1)"
printf 'name,value\nA,1e-10\nB,0.1749367\nHstar,0.5630134\nh,5.903132e4\nKc,2.212783e-5\nC,4.031361\n' > "$out/true_constants.csv"
measure() { # label, command...
  local label=$1; shift
  echo "== $label (load average: $(cut -d' ' -f1-3 /proc/loadavg))"
  /usr/bin/time -v "$@" > "$out/$label.out" 2> "$out/$label.time" || { cat "$out/$label.time"; exit 1; }
  grep -E "local fits|best:|fits computed|verdict" "$out/$label.out" || true
  awk -F': ' '/Elapsed \(wall clock\)/ {print "  wall " $2} /Maximum resident set size/ {printf "  peak memory %.0f MB\n", $2/1024} /User time/ {print "  user " $2 " s"} /System time/ {print "  system " $2 " s"}' "$out/$label.time"
}
measure simulate ./target/release/creepfit simulate "$out/run.toml" --constants "$out/true_constants.csv" --out "$out/simulate"
for i in $(seq 1 "$runs"); do
  measure "fit-$i" ./target/release/creepfit fit "$out/run.toml" --out "$out/fit"
done
for cmd in ${ALSO:-}; do
  case $cmd in
    sweep) measure sweep ./target/release/creepfit sweep "$out/run.toml" --starts 4 --out "$out/sweep" ;;
    diagnose) measure diagnose ./target/release/creepfit diagnose "$out/run.toml" --out "$out/diagnose" ;;
    *) echo "unknown command in ALSO: $cmd"; exit 1 ;;
  esac
done
