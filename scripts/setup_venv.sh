#!/usr/bin/env bash
# Create scripts/.venv with numpy and scipy for scripts/compare_scipy.py.
# Installs nothing outside scripts/.venv. Re-running is harmless (pip skips what is there).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
venv="$here/.venv"
python="${PYTHON:-python3}"
if [ ! -x "$venv/bin/python" ]; then
    "$python" -m venv "$venv"
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check numpy scipy
"$venv/bin/python" -c 'import sys, numpy, scipy; print(f"venv {sys.prefix}: python {sys.version.split()[0]}, numpy {numpy.__version__}, scipy {scipy.__version__}")'
