#!/usr/bin/env bash
# Power of `diagnose` under specimen scatter on the sets of the power table: for every
# catalogued effect, generate N specimen-world sets from FIRST_SEED on and compute both
# oracles (examples/oracle_study.rs: λ with each specimen's factor known, and with the factors
# unknown, as `battery` now bins them), then diagnose the sets detectable with the factors
# unknown (λ_s ≥ 25), one effect after the other in turn, at most K per effect, each set's
# line appended to OUT/diagnosed.txt as it finishes (its verdict, both oracles, and the set's
# likelihood ratio at the truth's error model and scatter, with the error model estimated,
# and in `diagnose`). Rerun with the same arguments to resume (sets already in
# OUT/diagnosed.txt are skipped). Each effect's sets are in OUT/sets/EFFECT/.
#
#   scripts/power_scatter.sh OUT FIRST_SEED N K
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1 first=$2 n=$3 k=$4
cargo build --release --quiet --example oracle_study
bin=target/release/examples/oracle_study
mkdir -p "$out"
effects="constant_load loading_strain dislocation_damage stress_ductility strain_softening rupture_damage"
for e in $effects; do
  if [ ! -s "$out/$e.txt" ]; then
    "$bin" "$out/sets/$e" "$e" "$first" "$n" > "$out/$e.txt.tmp"
    mv "$out/$e.txt.tmp" "$out/$e.txt"
  fi
  tail -1 "$out/$e.txt" | sed "s/^/$e: /"
done
touch "$out/diagnosed.txt"
for round in $(seq 1 "$k"); do
  for e in $effects; do
    seed=$(awk -v r="$round" '$1 ~ /^[0-9]+$/ && $6 >= 25 { if (++c == r) print $1 }' "$out/$e.txt")
    [ -n "$seed" ] || continue
    grep -q "^diagnosed $seed $e:" "$out/diagnosed.txt" && continue
    "$bin" "$out/sets/$e" "$e" "$seed" 1 1 | grep '^diagnosed' >> "$out/diagnosed.txt"
    tail -1 "$out/diagnosed.txt"
  done
done
awk '{ split($3, s, ":"); e=$3; sub(":", "", e); n[e]++; if ($4 == "extension:" e) k[e]++ }
     END { for (e in n) printf "%s: named %d of %d\n", e, k[e], n[e] }' "$out/diagnosed.txt"
