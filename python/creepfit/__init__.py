"""creepfit from Python: calibrate continuum-damage creep equations on pandas DataFrames.

The functions call the Rust library the ``creepfit`` command line calls, with the same
configuration (a TOML file's path, TOML text, or a dict with the TOML file's keys, see
docs/FORMATS.md) and the same data rules, and return the command's output files as
DataFrames (their columns and numbers, to the last digit) and dicts (their JSON).

Units: time in h, stress in MPa, temperature in °C, strain in percent (as in the files).

Data: ``curves`` has the columns ``temperature_C, stress_MPa, time_h, strain_pct[, specimen]``,
``ruptures`` ``temperature_C, stress_MPa, rupture_time_h[, rupture_strain_pct]
[, min_rate_pct_per_h][, specimen]``; other columns and the index are ignored, an empty cell
(NaN) is an empty cell of the file. Without them the configuration's files are read, as the
command line does. Errors name a DataFrame's row as a file's line: the header is line 1, so
the row at position k (``df.iloc[k]``) is line k + 2.

Bad input raises :class:`CreepfitError` (a ``ValueError``) with the library's one-line
message; the library's warnings are issued as :class:`CreepfitWarning`.
"""

from __future__ import annotations

import csv
import io
import json
import os
import warnings
from typing import Any, Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import pandas as pd

from . import _native
from ._native import CreepfitError

__all__ = [
    "BatteryResult",
    "CreepfitError",
    "CreepfitWarning",
    "Diagnosis",
    "FitResult",
    "HoldoutResult",
    "ProfileResult",
    "SimulateResult",
    "SweepResult",
    "SynthSet",
    "diagnose",
    "fit",
    "holdout",
    "predict",
    "profile",
    "simulate",
    "battery",
    "sweep",
    "synth",
]

__version__ = "0.1.0"

Config = Union[str, "os.PathLike[str]", Mapping[str, Any]]
"""A TOML file's path, TOML text (a str with a line break), or a dict of the TOML keys."""

Progress = Union[bool, Callable[[int, int], Any], None]
"""True: a tqdm bar (notebook or terminal), one per phase of the work; a callable: called with
(done, total) about every 0.1 s, the count of the current phase (it restarts at 0 when a phase
begins; total 0 where the library does not know the phase's steps); False or None: nothing."""

CURVE_COLUMNS = ("temperature_C", "stress_MPa", "time_h", "strain_pct", "specimen")
RUPTURE_COLUMNS = (
    "temperature_C",
    "stress_MPa",
    "rupture_time_h",
    "rupture_strain_pct",
    "min_rate_pct_per_h",
    "specimen",
)
# Text columns of the outputs (everything else is read as numbers where it parses).
_TEXT_COLUMNS = ("name", "unit", "specimen", "status", "w", "extrapolation", "outcome",
                 "constants", "given_outcome")


class CreepfitWarning(UserWarning):
    """A non-fatal finding of the library (dropped duplicate points, an unused rupture
    record, an extrapolation, …), one line each, as the command line prints them."""


def _config(config: Config) -> Tuple[str, str]:
    """(text, kind) of a configuration for the native module."""
    if isinstance(config, Mapping):
        try:
            text = json.dumps(config, default=_json_default, allow_nan=False)
        except (TypeError, ValueError) as e:
            raise CreepfitError(f"<config>: {e}") from None
        return text, "json"
    if isinstance(config, os.PathLike):
        return os.fspath(config), "path"
    if isinstance(config, str):
        if "\n" in config or ("=" in config and not os.path.exists(config)):
            return config, "toml"
        return config, "path"
    raise TypeError(f"config: expected a path, TOML text or a dict, not {type(config).__name__}")


def _json_default(v: Any) -> Any:
    """numpy scalars and arrays, paths and tuples in a config dict as JSON values."""
    if hasattr(v, "tolist"):
        return v.tolist()
    if isinstance(v, os.PathLike):
        return os.fspath(v)
    raise TypeError(f"{v!r} ({type(v).__name__}) has no TOML form")


def _csv(df: Any, columns: Sequence[str], what: str) -> str:
    """The CSV text of a table's known columns (floats in their shortest round-trip form, an
    empty cell for NaN): what the library reads from a file."""
    if not isinstance(df, pd.DataFrame):
        try:
            df = pd.DataFrame(df)
        except Exception as e:  # noqa: BLE001 - any construction failure is bad input
            raise CreepfitError(f"<{what} DataFrame>: not a table: {e}") from None
    keep = [c for c in df.columns if c in columns]
    return df.loc[:, keep].to_csv(index=False, lineterminator="\n")


def _tables(curves: Any, ruptures: Any) -> Tuple[Optional[str], Optional[str]]:
    if curves is None and ruptures is None:
        return None, None
    if curves is None or ruptures is None:
        raise CreepfitError(
            "give both the curves and the ruptures DataFrames, or neither (the configuration's files)"
        )
    return _csv(curves, CURVE_COLUMNS, "curves"), _csv(ruptures, RUPTURE_COLUMNS, "ruptures")


# pandas before 3.0 parses floats exactly only when asked; 3.0 does by default and deprecates
# the option.
_EXACT: Dict[str, Any] = (
    {} if int(pd.__version__.split(".")[0]) >= 3 else {"float_precision": "round_trip"}
)


def _frame(text: str) -> pd.DataFrame:
    """An output table's CSV text as a DataFrame: numbers exactly as written (round-trip
    parsing), only empty cells missing, text columns as text."""
    header = next(csv.reader(io.StringIO(text)), [])
    dtype = {c: str for c in header if c in _TEXT_COLUMNS}
    return pd.read_csv(
        io.StringIO(text),
        keep_default_na=False,
        na_values=[""],
        dtype=dtype,
        **_EXACT,
    )


def _warn(lines: Iterable[str]) -> List[str]:
    lines = list(lines)
    for w in lines:
        warnings.warn(w, CreepfitWarning, stacklevel=3)
    return lines


def _progress(
    progress: Progress, what: str, unit: str
) -> Tuple[Optional[Callable[[int, int, str], Any]], Callable[[], None]]:
    """(callback for the native module, closer) of a `progress` argument. The native module
    calls it with (done, total, phase): `phase` the library's phase ("" where the command has
    one), whose count starts at 0 (total 0 where the library does not know its steps)."""
    if progress is None or progress is False:
        return None, lambda: None
    if callable(progress):
        user = progress
        return (lambda done, total, phase: user(done, total)), lambda: None
    try:
        from tqdm.auto import tqdm
    except ImportError:  # tqdm is a dependency, but a bar is never worth a failure
        return None, lambda: None
    state: Dict[str, Any] = {"bar": None, "phase": None}

    def update(done: int, total: int, phase: str) -> None:
        bar = state["bar"]
        desc = f"{what}: {phase}" if phase else what
        if bar is None:
            bar = tqdm(total=total or None, desc=desc, unit=unit, leave=False)
            state["bar"], state["phase"] = bar, phase
        elif phase != state["phase"]:
            # A new phase: its own count and total (None: tqdm shows the count and time).
            state["phase"] = phase
            bar.set_description(desc, refresh=False)
            bar.reset(total=total or None)
        elif total and bar.total != total:
            bar.total = total
        bar.n = done
        bar.refresh()

    def close() -> None:
        if state["bar"] is not None:
            state["bar"].close()

    return update, close


class FitResult:
    """What ``creepfit fit`` writes: the best fit of the paper's procedure.

    Attributes:
        constants: constants.csv (name, value, unit, lb, ub; a last ``T_ref`` row with
            temperature laws).
        errors: errors.csv (per curve: rupture time, minimum rate and rupture strain,
            measured and predicted, and the errors in %).
        curves: curves.csv (measured and predicted strain, %, at every measured time).
        summary: summary.json.
        warnings: the library's warnings, one line each.
    """

    def __init__(self, out: Mapping[str, str], warnings: List[str]):
        self.constants: pd.DataFrame = _frame(out["constants"])
        self.errors: pd.DataFrame = _frame(out["errors"])
        self.curves: pd.DataFrame = _frame(out["curves"])
        self.summary: Dict[str, Any] = json.loads(out["summary"])
        self.warnings: List[str] = warnings

    @property
    def params(self) -> Dict[str, float]:
        """The fitted constants by name (the ``T_ref`` row left out)."""
        c = self.constants[self.constants["name"] != "T_ref"]
        return dict(zip(c["name"], c["value"].astype(float)))

    def __repr__(self) -> str:
        return f"FitResult({self.summary.get('name')!r}, constants={self.params})"


class SweepResult:
    """What ``creepfit sweep`` writes: ranked.csv (every fit, best first), minima.csv (the
    distinct minima) and summary.json."""

    def __init__(self, out: Mapping[str, str], warnings: List[str]):
        self.ranked: pd.DataFrame = _frame(out["ranked"])
        self.minima: pd.DataFrame = _frame(out["minima"])
        self.summary: Dict[str, Any] = json.loads(out["summary"])
        self.warnings: List[str] = warnings

    def __repr__(self) -> str:
        s = self.summary
        return (f"SweepResult({s.get('name')!r}, fits={s.get('fits')}, "
                f"distinct_minima={s.get('distinct_minima')})")


class HoldoutResult:
    """What ``creepfit holdout`` writes (the plots apart): how well a calibration predicts the
    tests it has not seen, beside the classical time–temperature parameters.

    Attributes:
        tests: holdout.csv (one row per held-out test: measured and predicted rupture time,
            creepfit's and every baseline's log10 error, the curve's error up to the predicted
            rupture; the 95 % interval columns with ``intervals=True``).
        constants: constants.csv of the training fit.
        summary: summary.json (each method's mean |log10 error|, ``one_to_beat``, creepfit
            against each baseline with its 95 % interval over the test conditions, …).
        warnings: the library's warnings, one line each.
    """

    def __init__(self, out: Mapping[str, str], warnings: List[str]):
        self.tests: pd.DataFrame = _frame(out["holdout"])
        self.constants: pd.DataFrame = _frame(out["constants"])
        self.summary: Dict[str, Any] = json.loads(out["summary"])
        self.warnings: List[str] = warnings

    def __repr__(self) -> str:
        s = self.summary
        best = (s.get("one_to_beat") or {}).get("name")
        return (f"HoldoutResult(tests={s.get('tests')}, creepfit="
                f"{s.get('model_mean_abs_log10_err')}, one_to_beat={best!r})")


class ProfileResult:
    """What ``creepfit profile`` writes (the plots apart): how sure the constants and the
    predictions are.

    Attributes:
        intervals: intervals.csv (per constant: the maximum-likelihood value, its 68 % and
            95 % profile intervals, the identifiability class, the given value and whether the
            95 % interval holds it, the calibrated thresholds).
        profiles: profiles.csv (every profile point: the constant's value, Δ(−2 ln L), status,
            and the other constants refitted there).
        summary: summary.json (reference fit, calibration of the thresholds, well-determined
            combinations, prediction intervals).
        report: report.md's text.
        warnings: the library's warnings, one line each.
    """

    def __init__(self, out: Mapping[str, str], warnings: List[str]):
        self.intervals: pd.DataFrame = _frame(out["intervals"])
        self.profiles: pd.DataFrame = _frame(out["profiles"])
        self.summary: Dict[str, Any] = json.loads(out["summary"])
        self.report: str = out["report"]
        self.warnings: List[str] = warnings

    def __repr__(self) -> str:
        classes = dict(zip(self.intervals["name"], self.intervals["class"]))
        return f"ProfileResult({self.summary.get('name')!r}, {classes})"


class SimulateResult:
    """What ``creepfit simulate`` writes (the plot apart): the configured tests simulated at
    given constants.

    Attributes:
        curves: curves.csv (every test's trajectory on a dense grid and the measured times up
            to its end: time h, strain %, the model's state variables).
        ruptures: ruptures.csv (per test: rupture time h and strain % where it ruptured, the
            minimum rate %/h, how the simulation ended).
        objective: objective.json with ``w`` (the eq. 8 objective at that lifetime weight, its
            normalised residual and the lifetime errors, %), else None.
        warnings: the library's warnings, one line each.
    """

    def __init__(self, out: Mapping[str, str], warnings: List[str]):
        self.curves: pd.DataFrame = _frame(out["curves"])
        self.ruptures: pd.DataFrame = _frame(out["ruptures"])
        self.objective: Optional[Dict[str, Any]] = (
            json.loads(out["objective"]) if "objective" in out else None
        )
        self.warnings: List[str] = warnings

    def __repr__(self) -> str:
        return f"SimulateResult(tests={len(self.ruptures)}, points={len(self.curves)})"


class SynthSet:
    """A generated data set (``creepfit synth``): data with a known truth, to try a
    configuration or a procedure on before trusting it with measurements.

    Attributes:
        curves: the curves table (temperature_C, stress_MPa, time_h, strain_pct[, specimen]).
        ruptures: the ruptures table (temperature_C, stress_MPa, rupture_time_h,
            rupture_strain_pct[, specimen]).
        config: config.toml's text (its data files named ``curves.csv``, ``ruptures.csv``):
            pass it with ``curves`` and ``ruptures`` to any function, or :meth:`write` the set
            and give the file's path.
        truth: truth.json as a dict (family, the true constants, the hidden effect and its
            size, the sampling, and in a world with specimens their true factors and scatter).
    """

    def __init__(self, out: Mapping[str, str]):
        self._texts = dict(out)
        self.curves: pd.DataFrame = _frame(out["curves"])
        self.ruptures: pd.DataFrame = _frame(out["ruptures"])
        self.config: str = out["config"]
        self.truth: Dict[str, Any] = json.loads(out["truth"])

    def write(self, folder: Union[str, "os.PathLike[str]"]) -> str:
        """Write curves.csv, ruptures.csv, config.toml and truth.json into ``folder``
        (created), byte for byte those ``creepfit synth`` writes; returns config.toml's
        path."""
        os.makedirs(folder, exist_ok=True)
        files = {"curves.csv": "curves", "ruptures.csv": "ruptures",
                 "config.toml": "config", "truth.json": "truth"}
        for file, key in files.items():
            with open(os.path.join(folder, file), "w", encoding="utf-8", newline="") as f:
                f.write(self._texts[key])
        return os.path.join(folder, "config.toml")

    def __repr__(self) -> str:
        effect = self.truth.get("effect", {}).get("kind")
        return (f"SynthSet({self.truth.get('name')!r}, family={self.truth.get('family')!r}, "
                f"effect={effect!r}, curves={len(self.ruptures)})")


def synth(
    seed: int = 1,
    scenario: str = "none",
    world: str = "identical",
    *,
    name: Optional[str] = None,
) -> SynthSet:
    """``creepfit synth``'s set of ``seed``: a generated data set with a known hidden effect.

    Args:
        seed: the set's seed (the command line's set ``set-SEED``).
        scenario: the hidden effect: ``"none"`` (null data) or a catalogued one, as
            ``--scenario`` (constant_load, loading_strain, dislocation_damage,
            stress_ductility, primary_transient, mid_life_step, strain_softening,
            rupture_damage); its size is drawn from the seed.
        world: the laboratory, as ``--world``: ``"identical"`` specimens, ``"specimens"``
            (each its own creep rate and ductility, replicates, reading error growing with
            strain), ``"shapes"`` (each its own onset of tertiary creep too) or
            ``"campaigns"`` (specimens from two campaigns).
        name: the run name in config.toml (default ``set-SEED``, the command line's).
    """
    name = f"set-{int(seed)}" if name is None else name
    return SynthSet(_native.synth(int(seed), scenario, world, name))


class BatteryResult:
    """What ``creepfit battery`` writes (the plot apart): generated sets diagnosed, and how
    often the diagnosis was right.

    Attributes:
        folder: the battery's folder (every set's data, configuration, truth and diagnosis
            under ``sets/``; ``results.jsonl``, from which a rerun resumes).
        results: results.csv (one row per set: its seed, scenario, sampling, the oracle's λ,
            whether the effect is detectable, the outcome, the p-values, the wall time s).
        confusion, confusion_detectable: confusion.csv and confusion_detectable.csv (true
            scenario against outcome; the second over the detectable sets only).
        power: power.csv (the share named per effect and λ bin).
        summary: summary.json (false alarms, named, the scatter's coverage, with Wilson
            intervals) as a dict; report: summary.md's text.
    """

    def __init__(self, folder: str, out: Mapping[str, str]):
        self.folder = folder
        self.results: pd.DataFrame = _frame(out["results"])
        self.confusion: pd.DataFrame = _frame(out["confusion"])
        self.confusion_detectable: pd.DataFrame = _frame(out["confusion_detectable"])
        self.power: pd.DataFrame = _frame(out["power"])
        self.summary: Dict[str, Any] = json.loads(out["summary"])
        self.report: str = out["report"]

    def __repr__(self) -> str:
        return f"BatteryResult({self.folder!r}, sets={len(self.results)})"


def battery(
    folder: Union[str, "os.PathLike[str]"],
    sets: int = 8,
    seed: int = 1,
    world: str = "identical",
    scenario: Optional[str] = None,
    *,
    threads: Optional[int] = None,
    progress: Progress = True,
) -> BatteryResult:
    """``creepfit battery``: ``sets`` generated sets (seeds ``seed``, ``seed + 1``, …; see
    :func:`synth`) each diagnosed with its own configuration, into ``folder``, and the
    rates: false alarms on the sets without an effect, catalogued effects named where
    detectable, the specimens' scatter covered. Minutes a set: a rerun into the same folder
    resumes with the sets it finished; Ctrl-C (KeyboardInterrupt) starts no new set, the
    running ones finish and are kept.

    Args:
        world: ``"identical"``, ``"specimens"``, ``"shapes"`` or ``"campaigns"``
            (``--world``).
        scenario: one hidden effect for every set (``--scenario``; ``"none"``: the
            false-alarm rate alone); default: the battery's cycle of scenarios.
        threads: worker threads (default: all cores; the sets run in parallel).
        progress: a bar (True) of the sets, a callback ``(done, total)``, or nothing.
    """
    folder = os.fspath(folder)
    cb, close = _progress(progress, "battery", "set")
    try:
        out = _native.battery(folder, int(sets), int(seed), world, scenario, threads, cb)
    finally:
        close()
    return BatteryResult(folder, out)


class Diagnosis(dict):
    """diagnosis.json as a dict (verdict, cause, base, candidates, …), with the candidates
    as a table."""

    warnings: List[str]

    def table(self) -> pd.DataFrame:
        """One row per model (the base model first, then every extension tried), indexed by
        name, with each candidate's scalar fields (model, status, k, objective = −2 ln L,
        aic, lr, p_value, p_holm, significant, delta_bic, loo_rmse, gain_pct, …)."""
        rows = [self["base"], *self["candidates"]]
        scalar = (str, int, float, bool, type(None))
        table = pd.DataFrame(
            [{k: v for k, v in r.items() if isinstance(v, scalar)} for r in rows]
        )
        return table.set_index("name")


def fit(
    config: Config,
    curves: Any = None,
    ruptures: Any = None,
    *,
    start: str = "both",
    w: Optional[float] = None,
) -> FitResult:
    """``creepfit fit``: the initial guess, a local bounded fit for every lifetime weight w,
    the best one.

    Args:
        config: a TOML file's path, TOML text, or a dict with the TOML file's keys.
        curves, ruptures: the data as DataFrames (default: the configuration's files).
        start: the start points: ``"config"``, ``"guess"`` or ``"both"`` (``--start``).
        w: one lifetime weight for every curve instead of the configured grid (``--w``).
    """
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    out, warns = _native.fit(text, kind, c, r, start, None if w is None else float(w))
    return FitResult(out, _warn(warns))


def sweep(
    config: Config,
    curves: Any = None,
    ruptures: Any = None,
    *,
    starts: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    progress: Progress = True,
) -> SweepResult:
    """``creepfit sweep``: Latin-hypercube starts × w candidates, a local fit from each, in
    parallel; ranked, with the Pareto set and the distinct minima. In memory: no journal,
    no output folder. Ctrl-C (KeyboardInterrupt) stops it: no new fit starts, the running
    ones finish, and KeyboardInterrupt is raised.

    Args:
        starts, seed: the Latin-hypercube starts and their seed (default: ``[sweep]``'s).
        threads: worker threads (default: all cores).
        progress: a bar (True), a callback ``(done, total)``, or nothing.
    """
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    cb, close = _progress(progress, "sweep", "fit")
    try:
        out, warns = _native.sweep(text, kind, c, r, starts, seed, threads, cb)
    finally:
        close()
    return SweepResult(out, _warn(warns))


def diagnose(
    config: Config,
    curves: Any = None,
    ruptures: Any = None,
    *,
    starts: Optional[int] = None,
    seed: Optional[int] = None,
    bootstrap: Optional[int] = None,
    bootstrap_extended: Optional[int] = None,
    alpha: Optional[float] = None,
    threads: Optional[int] = None,
    progress: Progress = True,
) -> Diagnosis:
    """``creepfit diagnose``: what the calibrated model misses, the named cause, and what an
    extension gains; diagnosis.json as a :class:`Diagnosis` (a dict with ``.table()``).
    Ctrl-C (KeyboardInterrupt) stops it at the library's next check (the end of a fit or of
    a replicate); ``fit`` and ``predict`` raise it only once their work ends.

    Args:
        starts, seed, bootstrap, bootstrap_extended, alpha: ``[diagnose]``'s settings
            (default: the file's; ``bootstrap_extended``: the most replicates of a test whose
            p-value after ``bootstrap`` is at most alpha/2).
        threads: worker threads (default: all cores).
        progress: a bar (True: the phase, e.g. "null bootstrap", and its count), a callback
            ``(done, total)`` (the count restarts at each phase; total 0 where the library
            does not know it), or nothing.
    """
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    cb, close = _progress(progress, "diagnose", "step")
    try:
        out, warns = _native.diagnose(
            text, kind, c, r, starts, seed, bootstrap, bootstrap_extended,
            None if alpha is None else float(alpha), threads, cb,
        )
    finally:
        close()
    d = Diagnosis(json.loads(out["diagnosis"]))
    d.warnings = _warn(warns)
    return d


def holdout(
    config: Config,
    curves: Any = None,
    ruptures: Any = None,
    *,
    temperature: Optional[float] = None,
    campaign: Optional[str] = None,
    starts: Optional[int] = None,
    seed: Optional[int] = None,
    intervals: Optional[bool] = None,
    threads: Optional[int] = None,
    progress: Progress = True,
) -> HoldoutResult:
    """``creepfit holdout``: fit on every test but those left out, predict those, and compare
    with Larson–Miller, Orr–Sherby–Dorn, Manson–Haferd (and Wilshire where tensile strengths
    are given) fitted to the same training rupture times. In memory: no journal, no output
    folder, no plots.

    Args:
        temperature: leave out every test at this temperature, °C (``--temperature``).
        campaign: or every test of this campaign: specimen labels ``NAME`` or ``NAME-…``
            (``--campaign``). Exactly one of the two.
        starts, seed: the training fit's Latin-hypercube starts and their seed (default:
            ``[sweep]``'s).
        intervals: add each held-out life's 95 % intervals (``--intervals``; default:
            ``[predict]``'s).
        threads: worker threads (default: all cores).
        progress: a bar (True: the phase and its count), a callback ``(done, total)`` (the
            count restarts at each phase; total 0 where unknown), or nothing. Ctrl-C
            (KeyboardInterrupt) stops it at the library's next check.
    """
    if (temperature is None) == (campaign is None):
        raise CreepfitError("give the temperature or the campaign to leave out (one of them)")
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    cb, close = _progress(progress, "holdout", "step")
    try:
        out, warns = _native.holdout(
            text, kind, c, r, None if temperature is None else float(temperature),
            None if campaign is None else str(campaign), starts, seed,
            None if intervals is None else bool(intervals), threads, cb,
        )
    finally:
        close()
    return HoldoutResult(out, _warn(warns))


def _constants(constants: Any) -> Tuple[str, Optional[str]]:
    """(CSV text, name in errors) of constants given as a FitResult, a DataFrame with name
    and value columns, a dict name -> value, or a constants.csv path."""
    if isinstance(constants, FitResult):
        constants = constants.constants
    if isinstance(constants, (str, os.PathLike)):
        path = os.fspath(constants)
        try:
            with open(path, encoding="utf-8", newline="") as f:
                return f.read(), path
        except OSError as e:
            raise CreepfitError(f"{path}: {e.strerror}") from None
    if isinstance(constants, Mapping):
        constants = pd.DataFrame({"name": list(constants), "value": list(constants.values())})
    if isinstance(constants, pd.DataFrame):
        return constants.to_csv(index=False, lineterminator="\n"), None
    raise TypeError(
        "constants: expected a FitResult, a DataFrame (name, value), a dict or a path, "
        f"not {type(constants).__name__}"
    )


def profile(
    config: Config,
    curves: Any = None,
    ruptures: Any = None,
    *,
    constants: Any = None,
    threads: Optional[int] = None,
    progress: Progress = True,
) -> ProfileResult:
    """``creepfit profile``: the profile likelihood of every constant, its 68 % and 95 %
    intervals with thresholds calibrated by a parametric bootstrap, the identifiability of
    each, the well-determined combinations and the prediction intervals. In memory: no
    journal, no output folder, no plots.

    Args:
        constants: where the maximum-likelihood fit starts (``--constants``): a
            :class:`FitResult`, a DataFrame (name, value), a dict or a constants.csv path;
            default: a multistart.
        threads: worker threads (default: all cores).
        progress: a bar (True: the phase and its count), a callback ``(done, total)`` (the
            count restarts at each phase; total 0 where unknown), or nothing. Ctrl-C
            (KeyboardInterrupt) stops it at the library's next check.
    """
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    ctext, cname = (None, None) if constants is None else _constants(constants)
    cb, close = _progress(progress, "profile", "step")
    try:
        out, warns = _native.profile(text, kind, ctext, cname, c, r, threads, cb)
    finally:
        close()
    return ProfileResult(out, _warn(warns))


def simulate(
    config: Config,
    constants: Any = None,
    curves: Any = None,
    ruptures: Any = None,
    *,
    w: Optional[float] = None,
) -> SimulateResult:
    """``creepfit simulate``: every configured test simulated at the constants, to its rupture
    or the integration horizon.

    Args:
        constants: a :class:`FitResult`, a DataFrame (name, value), a dict or a
            constants.csv path; default: the configuration's start values.
        w: also the eq. 8 objective with this lifetime weight on every curve (``--w``).
    """
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    ctext, cname = (None, None) if constants is None else _constants(constants)
    out, warns = _native.simulate(text, kind, ctext, cname, c, r,
                                  None if w is None else float(w))
    return SimulateResult(out, _warn(warns))


def predict(
    config: Config,
    constants: Any,
    curves: Any = None,
    ruptures: Any = None,
    *,
    at: Optional[Iterable[Tuple[float, float]]] = None,
    intervals: Optional[bool] = None,
    tests: Any = None,
) -> pd.DataFrame:
    """``creepfit predict``: rupture time, rupture strain and minimum creep rate at untested
    conditions; predictions.csv as a DataFrame, summary.json in ``.attrs["summary"]``.

    Args:
        constants: a :class:`FitResult`, a DataFrame (name, value), a dict or a
            constants.csv path.
        at: conditions ``[(T °C, stress MPa), ...]`` (default: ``[predict] at``).
        intervals: add the 95 % intervals (``--intervals``; default: ``[predict]``'s).
        tests: measured tests to predict and score (``--tests FILE``): a DataFrame or a path
            of rupture times (temperature_C, stress_MPa, rupture_time_h[, specimen]), e.g.
            another campaign's, instead of ``at``; tests.csv in ``.attrs["tests"]``, their
            mean |log10 error| against the classical baselines in the summary's ``tests``.
    """
    text, kind = _config(config)
    c, r = _tables(curves, ruptures)
    ctext, cname = _constants(constants)
    ttext, tname = None, None
    if tests is not None:
        if at is not None:
            raise CreepfitError("give `at` or `tests`, not both")
        if isinstance(tests, (str, os.PathLike)):
            tname = os.fspath(tests)
            try:
                with open(tname, encoding="utf-8", newline="") as f:
                    ttext = f.read()
            except OSError as e:
                raise CreepfitError(f"{tname}: {e.strerror}") from None
        else:
            ttext = _csv(tests, RUPTURE_COLUMNS, "tests")
    at_text = None
    if at is not None:
        pairs = []
        for cond in at:
            t, s = cond
            pairs.append(f"{float(t)!r}:{float(s)!r}")
        at_text = ",".join(pairs)
    out, warns = _native.predict(
        text, kind, ctext, cname, c, r, at_text, None if intervals is None else bool(intervals),
        ttext, tname,
    )
    _warn(warns)
    df = _frame(out["predictions"])
    df.attrs["summary"] = json.loads(out["summary"])
    if "tests" in out:
        df.attrs["tests"] = _frame(out["tests"])
    return df

