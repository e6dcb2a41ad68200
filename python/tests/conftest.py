"""Shared fixtures: the repository, the command-line binary, the bundled 560 °C data."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "configs" / "560C.toml"


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `creepfit` binary of this checkout (CREEPFIT_BIN, else cargo's release build,
    built if missing)."""
    given = os.environ.get("CREEPFIT_BIN")
    if given:
        return Path(given)
    exe = ROOT / "target" / "release" / "creepfit"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "--bin", "creepfit"], cwd=ROOT, check=True)
    return exe


@pytest.fixture(scope="session")
def run_cli(cli):
    """Run the binary from the repository root; the completed process (checked)."""

    def run(*args: str) -> subprocess.CompletedProcess:
        p = subprocess.run([str(cli), *map(str, args)], cwd=ROOT, capture_output=True, text=True)
        assert p.returncode == 0, f"creepfit {' '.join(map(str, args))}: {p.stderr}"
        return p

    return run


@pytest.fixture(scope="session")
def curves() -> pd.DataFrame:
    """data/creep_560C.csv as a user loads it: pandas' default reader."""
    return pd.read_csv(ROOT / "data" / "creep_560C.csv")


@pytest.fixture(scope="session")
def ruptures() -> pd.DataFrame:
    return pd.read_csv(ROOT / "data" / "lifetimes.csv")
