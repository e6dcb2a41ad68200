#!/usr/bin/env bash
# The project's one test command (README "Tests"; .ci/run calls it): the module layers
# (scripts/layers.py: no import circle, at most two upward imports), the Rust suite
# (`cargo test --release`), then the Python package (scripts/test_python.sh: the wheel built
# into a virtualenv, its pytest suite against the binary the Rust suite built).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== $(date +%T) module layers (scripts/layers.py)"
python3 scripts/layers.py
echo "== $(date +%T) cargo test --release"
cargo test --release
echo "== $(date +%T) Python package (scripts/test_python.sh)"
scripts/test_python.sh
