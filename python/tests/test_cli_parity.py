"""The package's results equal the command line's on the same data, to the last digit.

Each test runs the `creepfit` binary on configs/560C.toml (its files) and the package on the
same configuration with the data loaded by pandas from data/creep_560C.csv and
data/lifetimes.csv, then compares every table cell and every JSON value but wall times. The
CLI's CSV files are read with the package's own reader, so equal DataFrames mean equal
numbers (the files hold shortest round-trip forms; the reader parses them exactly).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

import creepfit
from creepfit import _frame

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - the CI's Python is 3.11
    tomllib = None

from conftest import CONFIG

# Wall times and thread counts differ between two runs of the same computation.
TIMINGS = {"wall_s", "fit_wall_s", "phase_s", "threads"}


def read_table(path: Path) -> pd.DataFrame:
    return _frame(path.read_text())


def without_timings(v):
    if isinstance(v, dict):
        return {k: without_timings(x) for k, x in v.items() if k not in TIMINGS}
    if isinstance(v, list):
        return [without_timings(x) for x in v]
    return v


def assert_same_table(cli: pd.DataFrame, py: pd.DataFrame, what: str) -> None:
    assert list(py.columns) == list(cli.columns), what
    assert len(py) == len(cli) > 0, what
    pd.testing.assert_frame_equal(py, cli, check_exact=True, obj=what)


@pytest.fixture(scope="module")
def cli_fit(run_cli, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("fit")
    run_cli("fit", CONFIG, "--out", out)
    return out


def check_fit(res: creepfit.FitResult, out: Path) -> None:
    for name in ("constants", "errors", "curves"):
        assert_same_table(read_table(out / f"{name}.csv"), getattr(res, name), f"{name}.csv")
    cli_summary = json.loads((out / "summary.json").read_text())
    assert without_timings(res.summary) == without_timings(cli_summary)


def test_fit_with_dataframes_equals_cli(cli_fit, curves, ruptures):
    res = creepfit.fit(CONFIG, curves, ruptures)
    check_fit(res, cli_fit)
    # The comparison can fail: the six constants are the paper's, found by a real fit.
    assert res.constants["name"].tolist() == ["A", "B", "Hstar", "h", "Kc", "C"]
    assert 0.1 < res.params["B"] < 0.2


def test_fit_with_the_configs_files_equals_cli(cli_fit):
    check_fit(creepfit.fit(str(CONFIG)), cli_fit)


@pytest.mark.skipif(tomllib is None, reason="tomllib is Python 3.11+")
def test_fit_with_a_config_dict_equals_cli(cli_fit, curves, ruptures):
    """The TOML file as a dict (its data keys dropped, the DataFrames given): the dict is
    written as TOML by the package, every number exactly (omega_f = 0.3333333333333333)."""
    cfg = tomllib.loads(CONFIG.read_text())
    del cfg["curves"], cfg["ruptures"]
    res = creepfit.fit(cfg, curves, ruptures)
    check_fit(res, cli_fit)


def test_fit_with_toml_text_equals_cli(cli_fit, curves, ruptures):
    text = "\n".join(
        line for line in CONFIG.read_text().splitlines()
        if not line.startswith(("curves", "ruptures"))
    ) + "\n"
    check_fit(creepfit.fit(text, curves, ruptures), cli_fit)


def test_fit_with_w_and_start_equals_cli(run_cli, tmp_path, curves, ruptures):
    run_cli("fit", CONFIG, "--out", tmp_path, "--w", "0.5", "--start", "guess")
    check_fit(creepfit.fit(CONFIG, curves, ruptures, w=0.5, start="guess"), tmp_path)


def test_sweep_equals_cli(run_cli, tmp_path, curves, ruptures):
    run_cli("sweep", CONFIG, "--starts", "8", "--seed", "3", "--threads", "2", "--out", tmp_path)
    res = creepfit.sweep(CONFIG, curves, ruptures, starts=8, seed=3, threads=2, progress=False)
    assert_same_table(read_table(tmp_path / "ranked.csv"), res.ranked, "ranked.csv")
    assert_same_table(read_table(tmp_path / "minima.csv"), res.minima, "minima.csv")
    cli_summary = json.loads((tmp_path / "summary.json").read_text())
    # run_id hashes the resolved configuration, the data bit for bit and the starts.
    assert res.summary["run_id"] == cli_summary["run_id"]
    assert without_timings(res.summary) == without_timings(cli_summary)
    assert res.summary["complete"] is True
    assert len(res.ranked) == 9 * 10  # 8 Latin-hypercube starts + the config's, × 10 w


@pytest.mark.parametrize("intervals", [False, True])
def test_predict_equals_cli(run_cli, cli_fit, tmp_path, curves, ruptures, intervals):
    args = ["predict", CONFIG, "--constants", cli_fit / "constants.csv",
            "--at", "560:100,560:70", "--out", tmp_path]
    if intervals:
        args.append("--intervals")
    run_cli(*args)
    constants = read_table(cli_fit / "constants.csv")
    with pytest.warns(creepfit.CreepfitWarning, match="70 MPa: extrapolation"):
        res = creepfit.predict(CONFIG, constants, curves, ruptures,
                               at=[(560, 100), (560, 70)], intervals=intervals)
    assert_same_table(read_table(tmp_path / "predictions.csv"), res, "predictions.csv")
    cli_summary = json.loads((tmp_path / "summary.json").read_text())
    assert res.attrs["summary"] == cli_summary
    assert res["extrapolation"].tolist() == ["none", "stress"]
    assert ("rupture_time_lo95_h" in res.columns) == intervals


def test_predict_tests_equals_cli(run_cli, cli_fit, tmp_path, curves, ruptures):
    # Another campaign's lives (a replicate pair and one more test) as a DataFrame and as the
    # file the command line reads: the same tests.csv, predictions and summary.
    tests = pd.DataFrame({
        "temperature_C": [560.0, 560.0, 560.0],
        "stress_MPa": [100.0, 90.0, 100.0],
        "rupture_time_h": [1500.0, 9000.0, 2500.0],
        "specimen": ["N-1", "N-2", "N-3"],
    })
    path = tmp_path / "campaign.csv"
    tests.to_csv(path, index=False)
    out = tmp_path / "cli"
    run_cli("predict", CONFIG, "--constants", cli_fit / "constants.csv",
            "--tests", path, "--out", out)
    constants = read_table(cli_fit / "constants.csv")
    res = creepfit.predict(CONFIG, constants, curves, ruptures, tests=tests)
    assert_same_table(read_table(out / "predictions.csv"), res, "predictions.csv")
    assert_same_table(read_table(out / "tests.csv"), res.attrs["tests"], "tests.csv")
    cli_summary = json.loads((out / "summary.json").read_text())
    summary = res.attrs["summary"]
    assert summary["tests"]["tests"] == 3 and summary["tests"]["conditions"] == 2
    # The file's name differs (a DataFrame has none); every number is the same.
    summary["tests"]["file"] = cli_summary["tests"]["file"]
    assert summary == cli_summary
    errs = res.attrs["tests"]["model_log10_err"].abs().mean()
    assert errs == pytest.approx(summary["tests"]["model_mean_abs_log10_err"], rel=1e-12)
    # From the path, the file's name is the command line's.
    res = creepfit.predict(CONFIG, constants, curves, ruptures, tests=path)
    assert res.attrs["summary"]["tests"]["file"] == cli_summary["tests"]["file"]
    with pytest.raises(creepfit.CreepfitError, match="not both"):
        creepfit.predict(CONFIG, constants, curves, ruptures, tests=tests, at=[(560, 100)])
    # The file named in the configuration ([predict] tests, relative to it): the same tests.
    keyed = tmp_path / "keyed.toml"
    data = CONFIG.parent.parent / "data"
    keyed.write_text(CONFIG.read_text().replace("../data/", f"{data.as_posix()}/")
                     + '\n[predict]\ntests = "campaign.csv"\n')
    res = creepfit.predict(keyed, constants, curves, ruptures)
    assert_same_table(read_table(out / "tests.csv"), res.attrs["tests"], "tests.csv")
    assert_same_table(read_table(out / "predictions.csv"), res, "predictions.csv")


def test_predict_from_a_fit_result_and_a_dict(cli_fit, curves, ruptures):
    fitted = creepfit.fit(CONFIG, curves, ruptures)
    a = creepfit.predict(CONFIG, fitted, curves, ruptures, at=[(560, 100)])
    b = creepfit.predict(CONFIG, fitted.params, curves, ruptures, at=[(560, 100)])
    c = creepfit.predict(CONFIG, cli_fit / "constants.csv", at=[(560, 100)])
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    pd.testing.assert_frame_equal(a, c, check_exact=True)


def test_diagnose_equals_cli(run_cli, tmp_path, curves, ruptures):
    # Few starts and replicates (alpha 0.4 lets 19 replicates reject over 8 tests): the
    # comparison, not the verdict's power, is what is tested here.
    opts = {"starts": 4, "seed": 5, "bootstrap": 19, "alpha": 0.4, "threads": 2}
    args = ["diagnose", CONFIG, "--out", tmp_path]
    for k, v in opts.items():
        args += [f"--{k}", str(v)]
    run_cli(*args)
    cli_d = json.loads((tmp_path / "diagnosis.json").read_text())
    calls = []
    d = creepfit.diagnose(CONFIG, curves, ruptures, progress=lambda *a: calls.append(a), **opts)
    # The hook is called with the phases' counts (the diagnosis itself is the command's).
    assert calls and all(done <= total for done, total in calls if total)
    assert any(total == 19 for _, total in calls), "the bootstrap's 19 replicates not counted"
    assert d["verdict"] == cli_d["verdict"]
    assert d["cause"] == cli_d["cause"]
    assert d["candidates"] == cli_d["candidates"]
    assert d["base"] == cli_d["base"]
    assert without_timings(dict(d)) == without_timings(cli_d)
    table = d.table()
    assert table.index.tolist() == ["base"] + [c["name"] for c in cli_d["candidates"]]
    assert table.loc["base", "aic"] == cli_d["base"]["aic"]
    for c in cli_d["candidates"]:
        assert table.loc[c["name"], "objective"] == c["objective"]
        assert table.loc[c["name"], "significant"] == c["significant"]


@pytest.fixture(scope="module")
def campaigns(tmp_path_factory, root):
    """The seed's 560 and 590 °C data (configs/cmv-joint.toml: Arrhenius laws) with a
    specimen column: the highest stress at each temperature is campaign Q, the others P.
    (folder with h.toml, c.csv, r.csv; the curves and ruptures as DataFrames)."""
    d = tmp_path_factory.mktemp("campaigns")
    curves = pd.read_csv(root / "data" / "creep_cmv.csv")
    ruptures = pd.read_csv(root / "data" / "lifetimes.csv")
    top = ruptures.groupby("temperature_C")["stress_MPa"].transform("max")
    label = {(t, s): ("Q-1" if s == m else f"P-{s:g}")
             for t, s, m in zip(ruptures["temperature_C"], ruptures["stress_MPa"], top)}
    for df in (curves, ruptures):
        df["specimen"] = [label[(t, s)] for t, s in zip(df["temperature_C"], df["stress_MPa"])]
    curves.to_csv(d / "c.csv", index=False)
    ruptures.to_csv(d / "r.csv", index=False)
    text = (root / "configs" / "cmv-joint.toml").read_text()
    (d / "h.toml").write_text(text.replace('"../data/creep_cmv.csv"', '"c.csv"')
                              .replace('"../data/lifetimes.csv"', '"r.csv"'))
    return d, curves, ruptures


def test_holdout_equals_cli(run_cli, tmp_path, campaigns):
    d, curves, ruptures = campaigns
    run_cli("holdout", d / "h.toml", "--campaign", "Q", "--starts", "1", "--out", tmp_path)
    calls = []
    res = creepfit.holdout(d / "h.toml", curves, ruptures, campaign="Q", starts=1,
                           progress=lambda *a: calls.append(a))
    assert calls
    assert_same_table(read_table(tmp_path / "holdout.csv"), res.tests, "holdout.csv")
    assert_same_table(read_table(tmp_path / "constants.csv"), res.constants, "constants.csv")
    cli_summary = json.loads((tmp_path / "summary.json").read_text())
    assert res.summary == cli_summary
    # One test of campaign Q at each temperature, every classical baseline fitted to the
    # other four lives at both temperatures (Wilshire needs tensile strengths).
    assert res.tests["temperature_C"].tolist() == [560.0, 590.0]
    assert res.tests["specimen"].tolist() == ["Q-1", "Q-1"]
    assert res.summary["held_out"] == {"kind": "campaign", "campaign": "Q"}
    assert res.summary["one_to_beat"]["name"] in ("Larson–Miller", "Orr–Sherby–Dorn",
                                                  "Manson–Haferd")
    err = res.tests["model_log10_err"].abs().mean()
    assert err == pytest.approx(res.summary["model_mean_abs_log10_err"], rel=1e-12)
    # The configuration's own files give the same.
    again = creepfit.holdout(d / "h.toml", campaign="Q", starts=1, progress=False)
    pd.testing.assert_frame_equal(again.tests, res.tests, check_exact=True)


def test_holdout_intervals_and_errors(run_cli, tmp_path, campaigns):
    d, curves, ruptures = campaigns
    run_cli("holdout", d / "h.toml", "--campaign", "Q", "--starts", "1", "--intervals",
            "--out", tmp_path)
    res = creepfit.holdout(d / "h.toml", curves, ruptures, campaign="Q", starts=1,
                           intervals=True, progress=False)
    assert_same_table(read_table(tmp_path / "holdout.csv"), res.tests, "holdout.csv")
    assert "rupture_time_lo95_h" in res.tests.columns
    assert res.summary == json.loads((tmp_path / "summary.json").read_text())
    with pytest.raises(creepfit.CreepfitError, match="one of them"):
        creepfit.holdout(d / "h.toml", curves, ruptures, progress=False)
    with pytest.raises(creepfit.CreepfitError, match="one of them"):
        creepfit.holdout(d / "h.toml", curves, ruptures, temperature=560, campaign="Q",
                         progress=False)
    # The library's own refusal, as the command line words it.
    refused = "--campaign R: no test.s specimen is of that campaign"
    with pytest.raises(creepfit.CreepfitError, match=refused):
        creepfit.holdout(d / "h.toml", curves, ruptures, campaign="R", progress=False)


def test_profile_equals_cli(run_cli, cli_fit, tmp_path, curves, ruptures):
    """`profile` from the fit's constants: every interval, every profile point, the summary
    and the report equal the binary's; the constants as a FitResult give the same."""
    run_cli("profile", CONFIG, "--constants", cli_fit / "constants.csv", "--out", tmp_path)
    calls = []
    res = creepfit.profile(CONFIG, curves, ruptures, constants=cli_fit / "constants.csv",
                           progress=lambda *a: calls.append(a))
    # The phases' counts (calibration replicates, profile sides): never above their total.
    assert calls and all(done <= total for done, total in calls if total)
    assert_same_table(read_table(tmp_path / "intervals.csv"), res.intervals, "intervals.csv")
    assert_same_table(read_table(tmp_path / "profiles.csv"), res.profiles, "profiles.csv")
    assert res.summary == json.loads((tmp_path / "summary.json").read_text())
    assert res.report == (tmp_path / "report.md").read_text()
    # Each constant's maximum-likelihood value lies inside its 95 % interval, and is the
    # value of its profile's optimum row.
    iv = res.intervals.set_index("name")
    assert list(iv.index) == ["A", "B", "Hstar", "h", "Kc", "C"]
    assert ((iv["lo95"] <= iv["value"]) & (iv["value"] <= iv["hi95"])).all()
    opt = res.profiles[res.profiles["side"] == "optimum"].set_index("name")
    assert (opt["value"] == iv["value"]).all()
    assert (iv["value_source"] == "ml_refit").all()
    # The constants as the package's own fit result: the same computation.
    fitted = creepfit.fit(CONFIG, curves, ruptures)
    again = creepfit.profile(CONFIG, curves, ruptures, constants=fitted, progress=False)
    pd.testing.assert_frame_equal(again.intervals, res.intervals, check_exact=True)
    # A constants table that names no KHD constant is refused, the table named.
    with pytest.raises(creepfit.CreepfitError, match="<constants>"):
        creepfit.profile(CONFIG, curves, ruptures, constants={"X": 1.0}, progress=False)


def test_simulate_equals_cli(run_cli, cli_fit, tmp_path, curves, ruptures):
    """`simulate` at the fit's constants with a lifetime weight: the dense curves, the
    ruptures and the objective equal the binary's; the simulated lives are the fit's."""
    run_cli("simulate", CONFIG, "--constants", cli_fit / "constants.csv", "--w", "0.5",
            "--out", tmp_path)
    fitted = creepfit.fit(CONFIG, curves, ruptures)
    res = creepfit.simulate(CONFIG, fitted, curves, ruptures, w=0.5)
    assert_same_table(read_table(tmp_path / "curves.csv"), res.curves, "curves.csv")
    assert_same_table(read_table(tmp_path / "ruptures.csv"), res.ruptures, "ruptures.csv")
    assert res.objective == json.loads((tmp_path / "objective.json").read_text())
    assert res.objective["w"] == 0.5
    # One row per test, in the data's order, each ruptured at the life errors.csv predicts.
    assert (res.ruptures["outcome"] == "ruptured").all()
    pd.testing.assert_series_equal(
        res.ruptures["rupture_time_h"].reset_index(drop=True),
        fitted.errors["rupture_time_pred_h"].reset_index(drop=True),
        check_names=False, rtol=1e-9,
    )
    # Without w no objective; from a path the same curves.
    plain = creepfit.simulate(CONFIG, cli_fit / "constants.csv")
    assert plain.objective is None
    pd.testing.assert_frame_equal(plain.curves, res.curves, check_exact=True)
    with pytest.raises(creepfit.CreepfitError, match=r"w: must be a weight in \[0, 1\]"):
        creepfit.simulate(CONFIG, fitted, w=2.0)


@pytest.mark.parametrize("world", ["identical", "specimens"])
def test_synth_equals_cli(run_cli, tmp_path, world):
    """A generated set from Python is, file for file, the one `creepfit synth` writes; its
    config text with its tables fits as the written folder's config file does."""
    run_cli("synth", tmp_path / "cli", "--sets", "1", "--seed", "7", "--scenario",
            "constant_load", "--world", world)
    s = creepfit.synth(7, "constant_load", world)
    path = s.write(tmp_path / "py")
    for f in ("curves.csv", "ruptures.csv", "config.toml", "truth.json"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / "set-7" / f).read_bytes(), f
    assert s.truth["effect"]["kind"] == "constant_load"
    assert len(s.ruptures) == len(s.truth["stresses"])
    # Specimens carry their labels and true factors only where the world has them.
    assert ("specimen" in s.curves.columns) == (world != "identical")
    assert ("specimens" in s.truth) == (world != "identical")
    in_memory = creepfit.fit(s.config, s.curves, s.ruptures, start="guess", w=0.5)
    from_files = creepfit.fit(path, start="guess", w=0.5)
    pd.testing.assert_frame_equal(in_memory.constants, from_files.constants, check_exact=True)


def test_synth_refuses_an_unknown_scenario_or_world():
    with pytest.raises(creepfit.CreepfitError, match="scenario: unknown scenario 'creep' "
                       r"\(known: none, constant_load"):
        creepfit.synth(1, "creep")
    with pytest.raises(creepfit.CreepfitError, match="world: unknown world 'lab' "
                       r"\(known: identical, specimens, shapes, campaigns\)"):
        creepfit.synth(1, "none", "lab")
    # Another name is the run's name, and nothing else changes.
    a, b = creepfit.synth(3), creepfit.synth(3, name="trial")
    assert 'name = "trial"' in b.config and a.config.replace("set-3", "trial") == b.config
    pd.testing.assert_frame_equal(a.curves, b.curves, check_exact=True)


def test_battery_and_the_command_share_a_folder(run_cli, tmp_path):
    """A battery of one null set from Python (set 1001: `adequate`, as tests/diagnose.rs
    has it), then the command into the same folder: it resumes the set, and its reports are
    the ones Python returned; Python again resumes without computing."""
    calls = []
    res = creepfit.battery(tmp_path, sets=1, seed=1001, scenario="none", threads=2,
                           progress=lambda *a: calls.append(a))
    assert len(res.results) == 1
    row = res.results.iloc[0]
    assert (row["seed"], row["scenario"], row["outcome"]) == (1001, "none", "adequate")
    assert res.summary["null_sets"] == 1 and res.summary["false_alarms"] == 0
    assert calls[-1] == (1, 1), calls[-3:]
    assert (tmp_path / "sets" / "set-1001" / "diagnosis.json").exists()
    out = run_cli("battery", tmp_path, "--sets", "1", "--seed", "1001", "--scenario", "none",
                  "--quiet")
    assert "false alarms 0 of 1" in out.stdout
    assert_same_table(read_table(tmp_path / "results.csv"), res.results, "results.csv")
    t0 = time.perf_counter()
    again = creepfit.battery(tmp_path, sets=1, seed=1001, scenario="none", progress=False)
    assert time.perf_counter() - t0 < 5, "the finished set was computed again"
    pd.testing.assert_frame_equal(again.results, res.results, check_exact=True)
    with pytest.raises(creepfit.CreepfitError, match="world: unknown world 'lab'"):
        creepfit.battery(tmp_path / "other", sets=1, world="lab")
