"""The installed package: typed (py.typed, the native module's stubs matching what it
exports), and the public functions' signatures as documented."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import creepfit
from creepfit import _native

PKG = Path(creepfit.__file__).parent


def stub_functions() -> dict:
    tree = ast.parse((PKG / "_native.pyi").read_text())
    return {
        f.name: [a.arg for a in f.args.args]
        for f in tree.body
        if isinstance(f, ast.FunctionDef)
    }


def test_typed_package():
    assert (PKG / "py.typed").exists()
    assert (PKG / "_native.pyi").exists()


def test_native_stubs_match_the_module():
    stubs = stub_functions()
    exported = {n for n in dir(_native) if not n.startswith("_") and callable(getattr(_native, n))}
    assert set(stubs) | {"CreepfitError"} == exported
    for name, params in stubs.items():
        sig = inspect.signature(getattr(_native, name))
        assert list(sig.parameters) == params, name


def test_error_type():
    assert issubclass(creepfit.CreepfitError, ValueError)
    assert creepfit.CreepfitError is _native.CreepfitError


def test_public_signatures():
    assert list(inspect.signature(creepfit.sweep).parameters)[:3] == ["config", "curves", "ruptures"]
    for name in ("starts", "seed", "threads", "progress"):
        assert name in inspect.signature(creepfit.sweep).parameters
    p = inspect.signature(creepfit.predict).parameters
    assert "at" in p and "intervals" in p and "constants" in p


# Runs the quickstart with its `diagnose` call given few starts and replicates (alpha 0.4, as
# in test_cli_parity.py, lets 19 replicates reject over 8 tests): the test is
# that the example runs whole against the installed package, not the diagnosis's power
# (tests/test_cli_parity.py and the Rust suite test that). The full diagnosis took 52 s of
# the suite's 89 s (2026-11-28, 2 cores).
QUICK_RUN = """
import os, runpy, sys
sys.path[0] = os.path.dirname(sys.argv[1])  # as `python quickstart.py`: not the source folder
import creepfit
full = creepfit.diagnose
creepfit.diagnose = lambda *a, **k: full(*a, **{**k, "starts": 4, "bootstrap": 19, "alpha": 0.4})
runpy.run_path(sys.argv[1], run_name="__main__")
"""


def test_quickstart_example_runs(root):
    """python/examples/quickstart.py runs whole and prints its six results."""
    import subprocess
    import sys

    p = subprocess.run(
        [sys.executable, "-c", QUICK_RUN, str(root / "python" / "examples" / "quickstart.py")],
        capture_output=True, text=True, cwd=root / "python",
    )
    assert p.returncode == 0, p.stderr
    assert "lifetime_err_pct" in p.stdout
    assert "verdict: " in p.stdout
    assert "extrapolation" in p.stdout and "stress" in p.stdout
    assert "identifiable" in p.stdout and "lo95" in p.stdout
    assert "ruptured" in p.stdout and "outcome" in p.stdout
    assert "creep-rate scatter between specimens" in p.stdout and "true 0.125" in p.stdout
