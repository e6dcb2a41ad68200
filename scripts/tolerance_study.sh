#!/usr/bin/env bash
# Accuracy study behind the integrator's default tolerance: for each rtol, run `fit` on the
# bundled data, then re-evaluate the fitted constants' eq. 8 objective at rtol = 1e-12 and
# print fit time, the normalised strain residual the fit saw (eq. 8's strain term, independent
# of w), the reference value and their relative difference.
# Usage: scripts/tolerance_study.sh [CONFIG...]   (default: configs/560C.toml configs/590C.toml)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
bin=target/release/creepfit
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
configs=("$@")
[ ${#configs[@]} -eq 0 ] && configs=(configs/560C.toml configs/590C.toml)
printf '%-18s %7s %8s %18s %18s %10s\n' config rtol fit_s residual_fit residual_ref rel_diff
for cfg in "${configs[@]}"; do
  for rtol in 1e-6 1e-7 1e-8 1e-9 1e-10 1e-11; do
    c="$tmp/c.toml"; ref="$tmp/ref.toml"
    # Absolute data paths so the copies work from $tmp.
    sed "s#\"\.\./data#\"$PWD/data#g" "$cfg" | grep -v '^\[solver\]' > "$c"
    cp "$c" "$ref"
    printf '\n[solver]\nrtol = %s\n' "$rtol" >> "$c"
    printf '\n[solver]\nrtol = 1e-12\natol = 1e-15\n' >> "$ref"
    start=$(date +%s.%N)
    "$bin" fit "$c" --out "$tmp/fit" > /dev/null
    end=$(date +%s.%N)
    fobj=$(python3 -c "import json;print(json.load(open('$tmp/fit/summary.json'))['norm_residual'])")
    # Reference: the same constants at tight tolerance.
    "$bin" simulate "$ref" --constants "$tmp/fit/constants.csv" --w 1 --out "$tmp/sim" > /dev/null
    robj=$(python3 -c "import json;print(json.load(open('$tmp/sim/objective.json'))['norm_residual'])")
    python3 - "$cfg" "$rtol" "$start" "$end" "$fobj" "$robj" <<'PY'
import sys
cfg, rtol, s, e, f, r = sys.argv[1:]
f, r = float(f), float(r)
print(f"{cfg:<18} {rtol:>7} {float(e)-float(s):8.2f} {f:18.12f} {r:18.12f} {abs(f-r)/r:10.2e}")
PY
  done
done
