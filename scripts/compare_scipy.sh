#!/usr/bin/env bash
# creepfit against SciPy (solve_ivp RK45 + least_squares) on the same fit of the bundled data.
# Sets up scripts/.venv (numpy, scipy from PyPI; nothing installed outside it), builds
# creepfit, and runs scripts/compare_scipy.py. Usage: scripts/compare_scipy.sh [CONFIG] [W]
# (default configs/560C.toml, w = 1); further arguments go to compare_scipy.py (e.g.
# --scipy-tol 1e-15 to let least_squares run to its own end). One SciPy fit takes minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
config=${1:-configs/560C.toml}
w=${2:-1}
shift $(( $# < 2 ? $# : 2 ))
if [ ! -x scripts/.venv/bin/python ]; then
  python3 -m venv scripts/.venv
  scripts/.venv/bin/pip install --quiet numpy scipy
fi
cargo build --release --quiet
name=$(basename "$config" .toml)
scripts/.venv/bin/python scripts/compare_scipy.py "$config" --w "$w" --out "results/compare_scipy/$name" "$@"
