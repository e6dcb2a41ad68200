#!/usr/bin/env bash
# The project's one test command (README "Tests"; .ci/run calls it): the module layers
# (scripts/layers.py: no import circle, at most two upward imports), the Rust suite
# (`cargo test --release --workspace`, in two invocations that leave out the examples' release
# build), then the Python package (scripts/test_python.sh: the wheel built
# into a virtualenv, its pytest suite against the binary the Rust suite built).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== $(date +%T) module layers (scripts/layers.py)"
python3 scripts/layers.py
# The library's, binaries' and integration tests, then the doc tests: everything `cargo test
# --release` runs, without building the examples again in release (clippy --all-targets
# checks that they compile; building them here took about half a minute of CI). Over the
# workspace: the Python bindings have no Rust tests, but their features then resolve with the
# library's, so the wheel below reuses this build of the library (python/Cargo.toml).
echo "== $(date +%T) cargo test --release --workspace --tests"
cargo test --release --workspace --tests
echo "== $(date +%T) cargo test --release --workspace --doc"
cargo test --release --workspace --doc
echo "== $(date +%T) Python package (scripts/test_python.sh)"
scripts/test_python.sh
