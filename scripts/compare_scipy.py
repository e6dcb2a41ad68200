#!/usr/bin/env python3
"""The same local fit done "the SciPy way" and by creepfit, side by side.

SciPy side: the paper's four-state model (eqs. 1-4) integrated with solve_ivp (RK45,
rtol 1e-10, atol 1e-13, terminal rupture event omega = omega_f, dense output at the measured
times), the eq. 8 residual exactly as creepfit defines it (normalised strain residuals, the
linear continuation at the rupture rate after a predicted rupture, the "late" lifetime term),
least_squares (trf, 2-point finite differences) in the same unit box (log scale for A, h, Kc)
from the configuration's start values, one w for all curves.

creepfit side: `creepfit fit CONFIG --start config --w W`.

Then each side's objective is evaluated at the other side's constants (creepfit through
`creepfit simulate --constants --w`), which checks that both implement the same problem: the
script exits non-zero if those agree worse than 1e-6 relative.

Usage: compare_scipy.py CONFIG --w W [--creepfit BIN] [--out DIR] [--scipy-tol TOL]
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
import tomllib

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

NAMES = ["A", "B", "Hstar", "h", "Kc", "C"]
RTOL, ATOL = 1e-10, 1e-13
HORIZON_FACTOR = 1000.0  # creepfit's objective::HORIZON_FACTOR
SAME_PROBLEM_TOL = 1e-6


def load_config(path):
    with open(path, "rb") as f:
        cfg = tomllib.load(f)
    base = os.path.dirname(os.path.abspath(path))
    consts = cfg["constants"]
    lb = np.array([float(consts[n]["lb"]) for n in NAMES])
    ub = np.array([float(consts[n]["ub"]) for n in NAMES])
    start = np.array([float(consts[n]["start"]) for n in NAMES])
    log = np.array([consts[n].get("scale", "linear") == "log" for n in NAMES])
    obj = cfg.get("objective", {})
    if obj.get("lifetime_term", "late") != "late":
        sys.exit("compare_scipy.py implements the 'late' lifetime term only")
    return dict(
        curves=os.path.join(base, cfg["curves"]),
        ruptures=os.path.join(base, cfg["ruptures"]),
        temperature=cfg.get("temperature_C"),
        lb=lb, ub=ub, start=start, log=log,
        omega_f=float(obj.get("omega_f", 1.0 / 3.0)),
    )


def load_curves(cfg):
    """Curves as creepfit reads them: grouped by stress, sorted by time, exact duplicate
    points dropped, strains as fractions, rupture strain = last measured strain."""
    pts = {}
    with open(cfg["curves"]) as f:
        for row in csv.DictReader(f):
            T = float(row["temperature_C"])
            if cfg["temperature"] is not None and T != float(cfg["temperature"]):
                continue
            key = float(row["stress_MPa"])
            pts.setdefault(key, []).append((float(row["time_h"]), float(row["strain_pct"]) / 100))
    rupt = {}
    with open(cfg["ruptures"]) as f:
        for row in csv.DictReader(f):
            T = float(row["temperature_C"])
            if cfg["temperature"] is not None and T != float(cfg["temperature"]):
                continue
            rupt[float(row["stress_MPa"])] = float(row["rupture_time_h"])
    curves = []
    for s in sorted(pts):
        p = []
        for q in sorted(pts[s], key=lambda x: x[0]):  # stable: equal times keep file order
            if p and q == p[-1]:
                continue
            p.append(q)
        t = np.array([q[0] for q in p])
        e = np.array([q[1] for q in p])
        last_t = t[-1]
        eps_f = max(e[t == last_t])
        curves.append(dict(stress=s, t=t, e=e, t_f=rupt[s], eps_f=eps_f))
    return curves


class Counter:
    rhs = 0


def rhs(t, y, p, sigma):
    Counter.rhs += 1
    A, B, Hs, h, Kc, C = p
    eps, H, phi, om = y
    denom = (1 - phi) * (1 - om)
    arg = B * sigma * (1 - H) / denom if denom > 0 else math.inf
    # past rupture a trial stage can overflow: let the step control see an absurd rate
    rate = A * math.sinh(min(arg, 700.0))
    return [rate, h / sigma * rate * (1 - H / Hs), Kc / 3 * (1 - phi) ** 4, C * rate]


def simulate(p, c, omega_f):
    sigma = c["stress"]

    def event(t, y, *_):
        return y[3] - omega_f

    event.terminal = True
    event.direction = 1
    t_end = HORIZON_FACTOR * max(c["t_f"], c["t"][-1])
    sol = solve_ivp(rhs, (0, t_end), [0.0, 0.0, 0.0, 0.0], method="RK45", rtol=RTOL, atol=ATOL,
                    dense_output=True, events=event, args=(p, sigma))
    if sol.status != 1 or len(sol.t_events[0]) == 0:
        raise RuntimeError(f"{sigma} MPa: no rupture ({sol.message})")
    t_r = sol.t_events[0][0]
    y_r = sol.y_events[0][0]
    rate_r = rhs(t_r, y_r, p, sigma)[0]
    pred = np.empty_like(c["t"])
    before = c["t"] <= t_r
    pred[before] = sol.sol(c["t"][before])[0]
    pred[~before] = y_r[0] + rate_r * (c["t"][~before] - t_r)
    return pred, t_r


def residuals_phys(p, curves, w, omega_f):
    r = []
    for c in curves:
        pred, t_r = simulate(p, c, omega_f)
        r.extend((pred - c["e"]) / c["eps_f"])
        r.append(math.sqrt(w) * max(0.0, (t_r - c["t_f"]) / c["t_f"]))
    return np.array(r)


def from_unit(u, cfg):
    lb, ub, log = cfg["lb"], cfg["ub"], cfg["log"]
    x = np.where(log, np.exp(np.log(lb) + u * (np.log(ub) - np.log(lb))), lb + u * (ub - lb))
    return np.clip(x, lb, ub)


def to_unit(x, cfg):
    lb, ub, log = cfg["lb"], cfg["ub"], cfg["log"]
    return np.where(log, (np.log(x) - np.log(lb)) / (np.log(ub) - np.log(lb)), (x - lb) / (ub - lb))


def read_constants(path):
    with open(path) as f:
        rows = {r["name"]: float(r["value"]) for r in csv.DictReader(f)}
    return np.array([rows[n] for n in NAMES])


def write_constants(path, x, cfg):
    units = ["1/h", "1/MPa", "-", "MPa", "1/h", "-"]
    with open(path, "w") as f:
        f.write("name,value,unit,lb,ub\n")
        for n, v, u, lo, hi in zip(NAMES, x, units, cfg["lb"], cfg["ub"]):
            f.write(f"{n},{float(v)!r},{u},{float(lo)!r},{float(hi)!r}\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("config")
    ap.add_argument("--w", type=float, required=True)
    ap.add_argument("--creepfit", default="target/release/creepfit")
    ap.add_argument("--out", default="results/compare_scipy")
    ap.add_argument("--scipy-tol", type=float, default=1e-10,
                    help="ftol = xtol = gtol of least_squares (1e-15: run to its own end)")
    a = ap.parse_args()
    cfg = load_config(a.config)
    curves = load_curves(cfg)
    omega_f = cfg["omega_f"]
    os.makedirs(a.out, exist_ok=True)

    # creepfit
    cf_dir = os.path.join(a.out, "creepfit")
    t0 = time.perf_counter()
    subprocess.run([a.creepfit, "fit", a.config, "--start", "config", "--w", str(a.w),
                    "--out", cf_dir], check=True, stdout=subprocess.DEVNULL)
    cf_wall = time.perf_counter() - t0
    cf_summary = json.load(open(os.path.join(cf_dir, "summary.json")))
    cf_x = read_constants(os.path.join(cf_dir, "constants.csv"))
    cf_obj = cf_summary["objective"]
    cf_fit_s = cf_summary.get("fit_wall_s", cf_wall)

    # SciPy
    Counter.rhs = 0
    u0 = to_unit(cfg["start"], cfg)
    t0 = time.perf_counter()
    ls = least_squares(lambda u: residuals_phys(from_unit(u, cfg), curves, a.w, omega_f), u0,
                       bounds=(0.0, 1.0), method="trf", diff_step=1e-6,
                       ftol=a.scipy_tol, xtol=a.scipy_tol, gtol=a.scipy_tol, max_nfev=3000)
    sp_wall = time.perf_counter() - t0
    sp_rhs = Counter.rhs
    sp_x = from_unit(ls.x, cfg)
    sp_obj = float(np.sum(ls.fun ** 2))

    # Cross-evaluation: the same constants in both implementations.
    sp_csv = os.path.join(a.out, "scipy_constants.csv")
    write_constants(sp_csv, sp_x, cfg)
    sim_dir = os.path.join(a.out, "creepfit_at_scipy")
    subprocess.run([a.creepfit, "simulate", a.config, "--constants", sp_csv, "--w", str(a.w),
                    "--out", sim_dir], check=True, stdout=subprocess.DEVNULL)
    cf_at_sp = json.load(open(os.path.join(sim_dir, "objective.json")))["objective"]
    sp_at_cf = float(np.sum(residuals_phys(cf_x, curves, a.w, omega_f) ** 2))
    d1 = abs(cf_at_sp - sp_obj) / sp_obj
    d2 = abs(sp_at_cf - cf_obj) / cf_obj

    print(f"config {a.config}, w = {a.w}, start = the configuration's start values")
    print(f"{'':8} {'creepfit':>14} {'SciPy':>14}")
    for n, x1, x2 in zip(NAMES, cf_x, sp_x):
        print(f"{n:8} {x1:14.6e} {x2:14.6e}")
    print(f"{'F':8} {cf_obj:14.9f} {sp_obj:14.9f}")
    print(f"creepfit: {cf_summary['termination']}, {cf_summary['iterations']} iterations, "
          f"{cf_fit_s:.3f} s fit ({cf_wall:.3f} s for the whole command)")
    print(f"SciPy tolerances ftol = xtol = gtol = {a.scipy_tol:g}")
    print(f"SciPy:    status {ls.status} ({ls.message}), {ls.nfev} residual evaluations, "
          f"{sp_rhs} RHS evaluations, {sp_wall:.1f} s")
    print(f"time ratio SciPy / creepfit (fit): {sp_wall / cf_fit_s:.0f}x "
          f"(whole creepfit command: {sp_wall / cf_wall:.0f}x)")
    rel = (cf_obj - sp_obj) / sp_obj
    print(f"final objectives differ by {rel:+.2e} relative "
          f"({'creepfit' if cf_obj <= sp_obj else 'SciPy'} lower)")
    print(f"same constants, both implementations: creepfit(SciPy's x) vs SciPy {d1:.2e}, "
          f"SciPy(creepfit's x) vs creepfit {d2:.2e} (must be <= {SAME_PROBLEM_TOL:g})")
    result = dict(config=a.config, w=a.w, creepfit=dict(constants=dict(zip(NAMES, cf_x.tolist())),
                  objective=cf_obj, fit_s=cf_fit_s, command_s=cf_wall,
                  termination=cf_summary["termination"], iterations=cf_summary["iterations"]),
                  scipy=dict(constants=dict(zip(NAMES, sp_x.tolist())), objective=sp_obj,
                  wall_s=sp_wall, nfev=int(ls.nfev), rhs_evals=sp_rhs, status=int(ls.status),
                  message=ls.message),
                  time_ratio_fit=sp_wall / cf_fit_s, objective_rel_diff=rel,
                  cross_eval_rel_diff=[d1, d2])
    with open(os.path.join(a.out, "comparison.json"), "w") as f:
        json.dump(result, f, indent=2)
    if max(d1, d2) > SAME_PROBLEM_TOL:
        print("FAIL: the two implementations disagree on the same constants")
        sys.exit(1)


if __name__ == "__main__":
    main()
