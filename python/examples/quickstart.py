# %% [markdown]
# # creepfit quickstart: the seed paper's 560 °C curves
#
# Cells are marked `# %%` (VS Code, PyCharm, Jupytext open this file as a notebook; `python
# quickstart.py` runs it whole). Install first: `pip install ./python` from the repository
# root. Units: time h, stress MPa, temperature °C, strain %.

# %%
from pathlib import Path

import pandas as pd

import creepfit

# The repository root (this file is python/examples/quickstart.py; in a notebook without
# __file__, start it from the root).
ROOT = Path(__file__).resolve().parents[2] if "__file__" in globals() else Path.cwd()
curves = pd.read_csv(ROOT / "data" / "creep_560C.csv")
ruptures = pd.read_csv(ROOT / "data" / "lifetimes.csv")
curves.groupby("stress_MPa")["time_h"].agg(["count", "max"])

# %% [markdown]
# The configuration: the TOML file's keys as a dict (or a path to configs/560C.toml). The
# DataFrames replace its `curves` and `ruptures` files.

# %%
config = {
    "name": "cmv-560C",
    "temperature_C": 560,
    "constants": {
        "A": {"lb": 1e-10, "ub": 1e-9, "start": 1e-9, "scale": "log"},
        "B": {"lb": 0.1, "ub": 0.2, "start": 0.11},
        "Hstar": {"lb": 0.4, "ub": 0.8, "start": 0.426},
        "h": {"lb": 1e4, "ub": 2e5, "start": 5.05e4, "scale": "log"},
        "Kc": {"lb": 1e-6, "ub": 3e-5, "start": 6.86e-6, "scale": "log"},
        "C": {"lb": 3, "ub": 10, "start": 4.311},
    },
    "objective": {
        "w_grid": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0],
        "lifetime_term": "late",
        "omega_f": 1 / 3,
    },
}

# %% Fit: the paper's procedure (initial guess, a bounded fit per lifetime weight w).
fitted = creepfit.fit(config, curves, ruptures)
print(fitted.constants)
print(fitted.errors[["stress_MPa", "rupture_time_exp_h", "rupture_time_pred_h", "lifetime_err_pct"]])

# %% Diagnose: what the calibrated model misses, and whether an extension explains it.
diagnosis = creepfit.diagnose(config, curves, ruptures, threads=2)
print("verdict:", diagnosis["verdict"], "cause:", diagnosis["cause"])
print(diagnosis.table()[["k", "objective", "aic", "lr", "p_holm", "significant"]])

# %% Predict: a stress inside the tested range and one below it (marked as an extrapolation).
predictions = creepfit.predict(config, fitted, curves, ruptures, at=[(560, 95), (560, 70)])
print(predictions[["stress_MPa", "rupture_time_h", "rupture_strain_pct", "min_rate_pct_per_h", "extrapolation"]])

# %% How sure: each constant's profile-likelihood intervals and whether the data determine it.
sure = creepfit.profile(config, curves, ruptures, constants=fitted, threads=2)
print(sure.intervals[["name", "value", "lo95", "hi95", "class"]].to_string())

# %% Simulate: the model's curves at the fitted constants (state variables included), e.g. to plot.
sim = creepfit.simulate(config, fitted, curves, ruptures)
print(sim.ruptures[["stress_MPa", "rupture_time_h", "rupture_strain_pct", "outcome"]].to_string())
print(sim.curves.groupby("stress_MPa")["strain_pct"].max())

# %% [markdown]
# Specimens are not identical. A generated set with a known truth (`synth`, the world with
# specimen scatter: each specimen its own creep rate, replicates, a reading error growing with
# strain), fitted by the likelihood, which estimates how much the specimens differ (the sd of
# the ln rate factor) and each specimen's factor. `creepfit.battery(folder, sets=…,
# world="specimens")` runs many such sets through `diagnose` and counts how often it is right
# (about a minute a set).

# %%
gen = creepfit.synth(seed=7, world="specimens")
likelihood = gen.config + '\n[objective]\nkind = "likelihood"\n'
hier = creepfit.fit(likelihood, gen.curves, gen.ruptures)
rate = hier.summary["specimens"]["scatter"]["rate"]
print(f"creep-rate scatter between specimens: sd of ln factor {rate['sd_ln']:.3f} "
      f"(95 % {rate['sd_ln_lo95']:.3f}-{rate['sd_ln_hi95']:.3f}), "
      f"true {gen.truth['specimens']['rate_sd']:.3f}")
