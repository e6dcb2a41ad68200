"""Type stubs of the native module creepfit._native (python/src/lib.rs).

Every function takes the configuration as ``(config, kind)``: ``kind`` is ``"path"`` (a TOML
file), ``"toml"`` (TOML text) or ``"json"`` (the JSON of a dict with the TOML keys); the data
tables, when given, as CSV text. Each returns the output files' texts by name and the
library's warnings.
"""

from typing import Callable, Dict, List, Optional, Tuple

_Outputs = Tuple[Dict[str, str], List[str]]
_Progress = Optional[Callable[[int, int, str], object]]  # (done, total, phase)

class CreepfitError(ValueError):
    path: Optional[str]
    line: Optional[int]

def fit(
    config: str,
    kind: str,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    start: Optional[str] = None,
    w: Optional[float] = None,
) -> _Outputs: ...
def sweep(
    config: str,
    kind: str,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    starts: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> _Outputs: ...
def diagnose(
    config: str,
    kind: str,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    starts: Optional[int] = None,
    seed: Optional[int] = None,
    bootstrap: Optional[int] = None,
    bootstrap_extended: Optional[int] = None,
    alpha: Optional[float] = None,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> _Outputs: ...
def predict(
    config: str,
    kind: str,
    constants: str,
    constants_name: Optional[str] = None,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    at: Optional[str] = None,
    intervals: Optional[bool] = None,
    tests: Optional[str] = None,
    tests_name: Optional[str] = None,
) -> _Outputs: ...
def holdout(
    config: str,
    kind: str,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    temperature: Optional[float] = None,
    campaign: Optional[str] = None,
    starts: Optional[int] = None,
    seed: Optional[int] = None,
    intervals: Optional[bool] = None,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> _Outputs: ...
def profile(
    config: str,
    kind: str,
    constants: Optional[str] = None,
    constants_name: Optional[str] = None,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> _Outputs: ...
def simulate(
    config: str,
    kind: str,
    constants: Optional[str] = None,
    constants_name: Optional[str] = None,
    curves: Optional[str] = None,
    ruptures: Optional[str] = None,
    w: Optional[float] = None,
) -> _Outputs: ...
def synth(seed: int, scenario: str, world: str, name: str) -> Dict[str, str]: ...
def battery(
    folder: str,
    sets: int,
    seed: int,
    world: str,
    scenario: Optional[str] = None,
    threads: Optional[int] = None,
    progress: _Progress = None,
) -> Dict[str, str]: ...
