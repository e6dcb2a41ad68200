#!/usr/bin/env bash
# Build the Python package (python/, PyO3 + maturin) into the virtualenv python/.venv and run
# its pytest suite (python/tests). Needs only Rust and Python >= 3.9 with pip and venv, and
# the package registry for pandas, tqdm, pytest and maturin (the build backend). The wheel
# build reuses the library compiled in target/ by `cargo test --release --workspace` (one
# workspace, one target folder; python/Cargo.toml says how the features agree) and compiles
# only PyO3 and the bindings. Re-running is harmless.
# PYTHON: the interpreter of the virtualenv (default python3). Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=python/.venv
python="${PYTHON:-python3}"
pip_q=(--quiet --disable-pip-version-check)
if [ ! -x "$venv/bin/python" ]; then
    if ! "$python" -m venv "$venv"; then
        # An interpreter without venv/ensurepip (Debian's python3 without python3-venv):
        # as root (CI), install Debian's python3-venv and use Debian's python3; else say how.
        rm -rf "$venv"
        if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null; then
            echo "python package: $python has no venv; installing Debian's python3-venv"
            apt-get update -qq
            DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv python3-pip >/dev/null
            python=/usr/bin/python3
            "$python" -m venv "$venv"
        else
            echo "error: $python -m venv failed: install python3-venv (Debian) or set PYTHON" >&2
            exit 1
        fi
    fi
fi
t0=$(date +%s)
"$venv/bin/python" -m pip install "${pip_q[@]}" pandas tqdm pytest
# --force-reinstall --no-deps: the package is rebuilt from this checkout every time.
"$venv/bin/python" -m pip install "${pip_q[@]}" --force-reinstall --no-deps ./python
t1=$(date +%s)
echo "python package: dependencies and wheel installed in $((t1 - t0)) s"
# From the repository root, with pytest's own launcher: `python -m pytest` in python/ would
# import the source folder python/creepfit (which has no native module) before the install.
"$venv/bin/pytest" python/tests "$@"
