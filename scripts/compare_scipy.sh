#!/usr/bin/env bash
# creepfit against the SciPy way on the same eq. 8 calibration (issue 5, part 1).
#
#   scripts/compare_scipy.sh            # 560 °C, w = 0.4 (about 2 minutes, mostly SciPy)
#   scripts/compare_scipy.sh --with-590 # and 590 °C, w = 0.4
#
# Sets up scripts/.venv (numpy, scipy) if missing, builds creepfit in release mode, runs
# scripts/compare_scipy.py and prints its summary. Outputs: results/scipy-comparison/<T>-w<W>/
# (comparison.json, both constant sets, creepfit's fit and simulate outputs, logs).
# Exit status: 0 if every run's same-constants objectives agree within 1e-6 (relative),
# 2 if one does not (the two implementations would not be the same problem), else the error.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

with_590=0
for a in "$@"; do
    case "$a" in
        --with-590) with_590=1 ;;
        *) echo "usage: $0 [--with-590]" >&2; exit 64 ;;
    esac
done

py="$root/scripts/.venv/bin/python"
if [ ! -x "$py" ] || ! "$py" -c 'import numpy, scipy' 2>/dev/null; then
    "$root/scripts/setup_venv.sh" || exit 1
fi
cargo build --release --quiet || exit 1

out="${OUT:-$root/results/scipy-comparison}"
w=0.4
runs=("560C")
[ "$with_590" = 1 ] && runs+=("590C")

status=0
for t in "${runs[@]}"; do
    echo "================ $t, w = $w ================"
    "$py" "$root/scripts/compare_scipy.py" "configs/$t.toml" --w "$w" \
        --creepfit "$root/target/release/creepfit" --creepfit-max-iterations 5000 \
        --out "$out/$t-w$w"
    rc=$?
    if [ "$rc" -ne 0 ]; then
        echo "compare_scipy.py on $t exited with status $rc" >&2
        [ "$status" -eq 0 ] && status=$rc
    fi
    echo
done

echo "================ summary ================"
for t in "${runs[@]}"; do
    f="$out/$t-w$w/comparison.json"
    [ -f "$f" ] || { echo "$t: no comparison.json"; continue; }
    "$py" - "$f" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
s, c, x = d["scipy"], d["creepfit"], d["creepfit_more_iterations"]
print(f"{d['name']} w={d['w']}: SciPy F {s['objective']:.6f} ({'converged' if s['converged'] else 'NOT converged'}, status {s['status']}) "
      f"in {s['wall_s']:.1f} s, {s['rhs_evaluations']:,} RHS evals; creepfit F {c['objective']:.6f} ({c['termination']}) in {c['fit_wall_s']:.3f} s; "
      f"wall ratio {d['wall_ratio_scipy_over_creepfit']:.0f}x, per residual vector {d['per_residual_vector_ratio_scipy_over_creepfit']:.0f}x")
if x:
    print(f"  creepfit with max_iterations {x['max_iterations']}: F {x['objective']:.6f} ({x['termination']}, {x['iterations']} it.) in {x['fit_wall_s']:.3f} s")
print("  same constants, relative differences: " + ", ".join(f"{e['at']} {e['rel_diff']:.1e}" for e in d["cross_evaluation"])
      + ("  -> same problem" if d["same_problem"] else "  -> NOT THE SAME PROBLEM"))
PY
done
exit "$status"
