"""Bad input raises CreepfitError (a ValueError) with the library's one-line message, naming
the table, line and field; warnings arrive as CreepfitWarning."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import creepfit
from creepfit import _csv, _frame, CURVE_COLUMNS

from conftest import CONFIG


def test_a_bad_cell_names_the_row_as_a_line(curves, ruptures):
    bad = curves.copy()
    bad.loc[4, "time_h"] = -1
    with pytest.raises(creepfit.CreepfitError) as e:
        creepfit.fit(CONFIG, bad, ruptures)
    assert isinstance(e.value, ValueError)
    msg = str(e.value)
    # Row at position 4 is line 6 (the header is line 1).
    assert msg == "<curves DataFrame>:6: column 'time_h': must not be negative (got -1)"
    assert "\n" not in msg
    assert e.value.path == "<curves DataFrame>"
    assert e.value.line == 6


def test_missing_column_and_empty_cell(curves, ruptures):
    with pytest.raises(creepfit.CreepfitError, match="missing required column 'strain_pct'"):
        creepfit.fit(CONFIG, curves.drop(columns="strain_pct"), ruptures)
    bad = ruptures.copy()
    bad["rupture_time_h"] = bad["rupture_time_h"].astype(float)
    bad.loc[0, "rupture_time_h"] = np.nan
    with pytest.raises(creepfit.CreepfitError, match=r"^<ruptures DataFrame>:2: column 'rupture_time_h': empty cell"):
        creepfit.fit(CONFIG, curves, bad)


def test_non_finite_values_are_refused(curves, ruptures):
    bad = curves.copy()
    bad.loc[3, "strain_pct"] = np.inf
    with pytest.raises(creepfit.CreepfitError, match=r"<curves DataFrame>:5: column 'strain_pct': 'inf' is not a finite number"):
        creepfit.fit(CONFIG, bad, ruptures)


def test_one_table_alone_is_refused(curves):
    with pytest.raises(creepfit.CreepfitError, match="give both"):
        creepfit.fit(CONFIG, curves, None)


def test_config_dict_errors_name_the_field_without_a_line(curves, ruptures):
    cfg = {
        "temperature_C": 560,
        "constants": {
            "A": {"lb": 1e-10, "ub": 1e-9, "scale": "log"},
            "B": {"lb": 0.3, "ub": 0.2},
            "Hstar": {"lb": 0.4, "ub": 0.8},
            "h": {"lb": 1e4, "ub": 2e5, "scale": "log"},
            "Kc": {"lb": 1e-6, "ub": 3e-5, "scale": "log"},
            "C": {"lb": 3, "ub": 10},
        },
    }
    with pytest.raises(creepfit.CreepfitError) as e:
        creepfit.fit(cfg, curves, ruptures)
    assert str(e.value).startswith("<config>: constants.B: ")
    assert e.value.line is None
    cfg["objective"] = {"omega_f": None}
    with pytest.raises(creepfit.CreepfitError, match=r"<config>: objective.omega_f: None has no TOML form"):
        creepfit.fit(cfg, curves, ruptures)
    cfg["objective"] = {"omega_f": float("nan")}
    with pytest.raises(creepfit.CreepfitError, match="^<config>: "):
        creepfit.fit(cfg, curves, ruptures)


def test_toml_text_errors_name_the_line_of_the_text(curves, ruptures):
    """The package puts placeholder data keys in front of TOML text that names no files:
    the error's line is still the line of the text as given."""
    lines = [
        line for line in CONFIG.read_text().splitlines()
        if not line.startswith(("curves", "ruptures"))
    ]
    k = next(i for i, line in enumerate(lines) if line.startswith("B "))
    lines[k] = "B     = { lb = 0.3,   ub = 0.2 }"
    text = "\n".join(lines) + "\n"
    with pytest.raises(creepfit.CreepfitError) as e:
        creepfit.fit(text, curves, ruptures)
    assert e.value.line == k + 1, str(e.value)
    assert str(e.value).startswith(f"<config>:{k + 1}: constants.B: ")


def test_bad_constants_and_conditions(curves, ruptures):
    fitted = creepfit.fit(CONFIG, curves, ruptures)
    far = dict(fitted.params, B=5.0)
    with pytest.raises(creepfit.CreepfitError, match=r"^<constants>:3: column 'value': B = 5 is outside the configuration's bounds"):
        creepfit.predict(CONFIG, far, curves, ruptures, at=[(560, 100)])
    with pytest.raises(creepfit.CreepfitError, match="not a tested temperature"):
        creepfit.predict(CONFIG, fitted, curves, ruptures, at=[(600, 100)])
    with pytest.raises(creepfit.CreepfitError, match="stress must be positive"):
        creepfit.predict(CONFIG, fitted, curves, ruptures, at=[(560, -5)])


def test_warnings_are_creepfit_warnings(curves, ruptures):
    # Row 5 twice, one after the other: an exact duplicate point, dropped with a warning.
    dup = pd.concat([curves.iloc[:6], curves.iloc[5:]]).reset_index(drop=True)
    with pytest.warns(creepfit.CreepfitWarning, match=r"<curves DataFrame>:\d+: duplicate point"):
        res = creepfit.fit(CONFIG, dup, ruptures)
    assert any("duplicate point" in w for w in res.warnings)


def test_dataframe_cells_reach_the_library_exactly():
    """Floats of every magnitude survive the DataFrame's CSV text bit for bit (shortest
    round-trip form), NaN as an empty cell, extra columns left out."""
    rng = np.random.default_rng(7)
    n = 5000
    x = rng.standard_normal(n) * 10.0 ** rng.integers(-300, 300, n)
    df = pd.DataFrame({"temperature_C": x, "stress_MPa": -x, "time_h": x / 3,
                       "strain_pct": np.nan, "other": "z"})
    text = _csv(df, CURVE_COLUMNS, "curves")
    rows = text.splitlines()
    assert rows[0] == "temperature_C,stress_MPa,time_h,strain_pct"
    cells = [r.split(",") for r in rows[1:]]
    assert [float(c[0]) for c in cells] == x.tolist()
    assert [float(c[2]) for c in cells] == (x / 3).tolist()
    assert all(c[3] == "" for c in cells)


def test_output_tables_are_read_exactly():
    """The outputs' CSV text (shortest round-trip numbers, empty cells for NaN) becomes a
    DataFrame with the same numbers bit for bit."""
    rng = np.random.default_rng(11)
    n = 5000
    x = rng.standard_normal(n) * 10.0 ** rng.integers(-300, 300, n)
    text = "name,value,lb\n" + "".join(f"c{i},{float(v)!r},\n" for i, v in enumerate(x))
    df = _frame(text)
    assert df["value"].tolist() == x.tolist()
    assert df["lb"].isna().all()
    assert df["name"].iloc[3] == "c3"
