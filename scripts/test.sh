#!/usr/bin/env bash
# The project's one test command (README "Tests"; .ci/run calls it): the module layers
# (scripts/layers.py: no import circle, at most two upward imports), the Rust suite
# (`cargo nextest run --release --workspace --tests`, or `cargo test` without nextest, then the
# doc tests: two invocations that leave out the examples' release build), then the Python
# package (scripts/test_python.sh: the wheel built into a virtualenv, its pytest suite against
# the binary the Rust suite built).
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== $(date +%T) module layers (scripts/layers.py)"
python3 scripts/layers.py
# The library's, binaries' and integration tests, then the doc tests: everything `cargo test
# --release` runs, without building the examples again in release (clippy --all-targets
# checks that they compile; building them here took about half a minute of CI). Over the
# workspace: the Python bindings have no Rust tests, but their features then resolve with the
# library's, so the wheel below reuses this build of the library (python/Cargo.toml).
#
# With cargo-nextest (on this project's machines; `cargo install cargo-nextest` elsewhere) the
# tests of every binary share the two cores: `cargo test` runs one test binary after another,
# and a binary whose last test is long (tests/diagnose.rs' battery, 340 s) leaves a core idle
# while the others wait. Measured on CI's kind of machine (Intel Xeon 2.5 GHz, 2 cores,
# 2026-11-29, the suite of faf42ef): `cargo test` 14 min 53 s, nextest 11 min 13 s, the same
# 355 tests passing. Without nextest, `cargo test` runs the same tests.
if cargo nextest --version >/dev/null 2>&1; then
    echo "== $(date +%T) cargo nextest run --release --workspace --tests"
    cargo nextest run --release --workspace --tests
else
    echo "== $(date +%T) cargo test --release --workspace --tests (cargo-nextest not found)"
    cargo test --release --workspace --tests
fi
echo "== $(date +%T) cargo test --release --workspace --doc"
cargo test --release --workspace --doc
echo "== $(date +%T) Python package (scripts/test_python.sh)"
scripts/test_python.sh
