#!/usr/bin/env bash
# Sweep throughput (local fits per second) on 1 and 2 threads, same sweep, fresh folders.
# Usage: scripts/bench_sweep.sh [CONFIG] [STARTS]   (default configs/560C.toml, 24 starts × its w grid)
# Run it on an otherwise idle machine: the speed-up is only meaningful then.
set -euo pipefail
cd "$(dirname "$0")/.."
config=${1:-configs/560C.toml}
starts=${2:-24}
cargo build --release --quiet
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
declare -A rate
for t in 1 2; do
  line=$(./target/release/creepfit sweep "$config" --starts "$starts" --threads "$t" --out "$tmp/t$t" | grep "fits computed now")
  echo "threads $t: $line"
  rate[$t]=$(echo "$line" | sed -E 's/.*\(([0-9.]+) fits\/s\).*/\1/')
done
cmp -s "$tmp/t1/ranked.csv" "$tmp/t2/ranked.csv" && echo "ranked.csv identical for 1 and 2 threads" || { echo "ranked.csv DIFFERS"; exit 1; }
python3 - "${rate[1]}" "${rate[2]}" <<'PY'
import sys
r1, r2 = float(sys.argv[1]), float(sys.argv[2])
print(f"throughput: {r1:.2f} fits/s on 1 thread, {r2:.2f} fits/s on 2 threads; speed-up {r2/r1:.2f}x")
PY
