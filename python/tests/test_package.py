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


def test_quickstart_example_runs(root):
    """python/examples/quickstart.py runs whole and prints its three results."""
    import subprocess
    import sys

    p = subprocess.run(
        [sys.executable, str(root / "python" / "examples" / "quickstart.py")],
        capture_output=True, text=True, cwd=root / "python",
    )
    assert p.returncode == 0, p.stderr
    assert "lifetime_err_pct" in p.stdout
    assert "verdict: " in p.stdout
    assert "extrapolation" in p.stdout and "stress" in p.stdout
