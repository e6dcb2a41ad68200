//! Output files of `fit` and `simulate` (DESIGN.md §5) and the printed error table.

use std::fmt::Write as _;
use std::fs;
use std::path::Path;

use serde_json::{json, Value};

use crate::config::{LocalFits, RunConfig};
use crate::data::Curve;
use crate::error::{Error, Result};
use crate::fit::{FitRun, LocalFit};
use crate::model::objective::ParamSpace;
use crate::model::Model;
use crate::output;

/// Create `dir` (and parents).
pub fn ensure_dir(dir: &Path) -> Result<()> {
    fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
}

/// Write `text` to `path` atomically ([`output::write_atomic`]: the old file or the new one,
/// never a truncated one).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    output::write_atomic(path, |w| w.write_all(text.as_bytes()))
}

/// Write a CSV file atomically from a header and rows of already formatted cells.
pub fn write_csv(path: &Path, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
    write_csv_rows(path, header, rows.iter())
}

/// [`write_csv`] from rows made one at a time: a million-point curve's rows are formatted
/// as they are written, never held all at once. Atomic like [`write_csv`].
pub fn write_csv_rows<R, I>(path: &Path, header: &[&str], rows: I) -> Result<()>
where
    R: AsRef<[String]>,
    I: Iterator<Item = R>,
{
    output::write_atomic(path, |w| {
        let mut c = csv::Writer::from_writer(w);
        c.write_record(header).map_err(csv_io)?;
        for r in rows {
            c.write_record(r.as_ref()).map_err(csv_io)?;
        }
        c.flush()
    })
}

/// The text of the CSV file that [`write_csv_rows`] writes, kept in memory: for callers that
/// hand the tables on instead of writing them (the Python package's DataFrames).
pub fn csv_text<R, I>(header: &[&str], rows: I) -> String
where
    R: AsRef<[String]>,
    I: Iterator<Item = R>,
{
    let mut c = csv::Writer::from_writer(Vec::new());
    c.write_record(header).expect("CSV into memory");
    for r in rows {
        c.write_record(r.as_ref()).expect("CSV into memory");
    }
    String::from_utf8(c.into_inner().expect("CSV into memory")).expect("UTF-8 cells")
}

fn csv_io(e: csv::Error) -> std::io::Error {
    match e.into_kind() {
        csv::ErrorKind::Io(e) => e,
        k => std::io::Error::other(format!("{k:?}")),
    }
}

/// A number as CSV text: shortest round-trip form, empty for NaN.
pub fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        String::new()
    }
}

/// JSON number or null.
pub fn jnum(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// Name of the row of `constants.csv` that holds the reference temperature of the
/// temperature laws (°C): constants about one reference temperature mean other values about
/// another, so `predict` and `simulate` check it against the configuration's.
pub const T_REF_ROW: &str = "T_ref";

/// `constants.csv`: name,value,unit,lb,ub; with temperature laws a last row `T_ref` (°C,
/// lb = ub = value), the reference temperature the constants are about.
pub fn write_constants(
    path: &Path,
    model: &dyn Model,
    space: &ParamSpace,
    params: &[f64],
    t_ref_c: Option<f64>,
) -> Result<()> {
    let rows = constants_rows(model, space, params, t_ref_c);
    write_csv(path, &CONSTANTS_COLUMNS, &rows)
}

/// `constants.csv`'s columns.
pub const CONSTANTS_COLUMNS: [&str; 5] = ["name", "value", "unit", "lb", "ub"];

/// The rows of `constants.csv` ([`write_constants`]).
pub fn constants_rows(
    model: &dyn Model,
    space: &ParamSpace,
    params: &[f64],
    t_ref_c: Option<f64>,
) -> Vec<Vec<String>> {
    let mut rows: Vec<Vec<String>> = model
        .constants()
        .iter()
        .enumerate()
        .map(|(j, c)| {
            vec![
                c.name.to_string(),
                num(params[j]),
                c.unit.to_string(),
                num(space.lb[j]),
                num(space.ub[j]),
            ]
        })
        .collect();
    if let Some(t) = t_ref_c {
        rows.push(vec![
            T_REF_ROW.to_string(),
            num(t),
            "°C".to_string(),
            num(t),
            num(t),
        ]);
    }
    rows
}

/// Read a `constants.csv` (columns `name,value`, any order, extra columns ignored) into the
/// model's order. Every model constant must appear exactly once with a finite value; an
/// unknown name, a repeated one (a `T_ref` row included) or a missing one is an error naming
/// the file, the line and the field. A `T_ref` row is skipped here
/// ([`check_t_ref`] checks it); [`read_constants_for`] also checks the
/// configuration's bounds.
pub fn read_constants(path: &Path, model: &dyn Model) -> Result<Vec<f64>> {
    read_constants_lines(path, model).map(|(v, _)| v)
}

/// [`read_constants`] for a run of `cfg`: also the reference temperature of the constants
/// (`T_ref` row, [`check_t_ref`]) and every value inside the configuration's
/// bounds `[lb, ub]` (a held law parameter: equal to its value), each an error naming the
/// file, the line and the constant.
pub fn read_constants_for(path: &Path, cfg: &RunConfig, model: &dyn Model) -> Result<Vec<f64>> {
    check_t_ref(path, cfg)?;
    let (values, lines) = read_constants_lines(path, model)?;
    within_bounds(path, values, &lines, cfg)
}

/// [`read_constants_for`] of a constants table's CSV text in memory, named `path` in errors
/// (the Python package's constants).
pub fn read_constants_bytes(
    path: &Path,
    csv: &[u8],
    cfg: &RunConfig,
    model: &dyn Model,
) -> Result<Vec<f64>> {
    let text = std::str::from_utf8(csv)
        .map_err(|e| Error::data(path, 0, format!("not UTF-8 text: {e}")))?;
    check_t_ref_text(path, text, cfg)?;
    let (values, lines) = constants_lines(path, csv, None, model)?;
    within_bounds(path, values, &lines, cfg)
}

/// `values` (read from `lines` of `path`) if each is inside the configuration's bounds.
fn within_bounds(
    path: &Path,
    values: Vec<f64>,
    lines: &[usize],
    cfg: &RunConfig,
) -> Result<Vec<f64>> {
    for ((v, line), c) in values.iter().zip(lines).zip(&cfg.constants) {
        if !(c.lb <= *v && *v <= c.ub) {
            return Err(Error::data(
                path,
                *line,
                format!(
                    "column 'value': {} = {v} is outside the configuration's bounds [{}, {}] (constants.{} in {}); constants from another box or model do not belong to this configuration",
                    c.name,
                    c.lb,
                    c.ub,
                    c.name,
                    cfg.path.display()
                ),
            ));
        }
    }
    Ok(values)
}

/// The values of [`read_constants`] and the line each was read from.
fn read_constants_lines(path: &Path, model: &dyn Model) -> Result<(Vec<f64>, Vec<usize>)> {
    let (bytes, progress) = crate::data::read_file(path)?;
    constants_lines(path, &bytes, progress, model)
}

/// [`read_constants_lines`] of the file's bytes.
fn constants_lines(
    path: &Path,
    bytes: &[u8],
    progress: Option<indicatif::ProgressBar>,
    model: &dyn Model,
) -> Result<(Vec<f64>, Vec<usize>)> {
    let mut table = crate::data::Table::open(path, bytes, &["name", "value"], progress)?;
    let (ci, cv) = (table.col("name").unwrap(), table.col("value").unwrap());
    let specs = model.constants();
    let mut values = vec![f64::NAN; specs.len()];
    let mut lines = vec![0usize; specs.len()];
    let mut t_ref_line = 0usize;
    let mut rec = csv::StringRecord::new();
    while let Some(line) = table.next_row(&mut rec)? {
        let name = rec.get(ci).unwrap_or("").trim();
        let text = rec.get(cv).unwrap_or("").trim();
        if name == T_REF_ROW && !specs.iter().any(|c| c.name == T_REF_ROW) {
            if t_ref_line > 0 {
                return Err(Error::data(
                    path,
                    line,
                    format!("column 'name': '{name}' appears again (first on line {t_ref_line})"),
                ));
            }
            t_ref_line = line;
            continue;
        }
        let Some(j) = specs.iter().position(|s| s.name == name) else {
            return Err(Error::data(
                path,
                line,
                format!(
                    "column 'name': '{name}' is not a constant of model {} (its constants: {})",
                    model.name(),
                    specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
                ),
            ));
        };
        if lines[j] > 0 {
            return Err(Error::data(
                path,
                line,
                format!(
                    "column 'name': '{name}' appears again (first on line {}); give each constant once",
                    lines[j]
                ),
            ));
        }
        let v: f64 = text.parse().map_err(|_| {
            Error::data(
                path,
                line,
                format!("column 'value': {name}: cannot parse '{text}' as a number"),
            )
        })?;
        if !v.is_finite() {
            return Err(Error::data(
                path,
                line,
                format!("column 'value': {name} = '{text}' is not finite"),
            ));
        }
        values[j] = v;
        lines[j] = line;
    }
    let missing: Vec<&str> = specs
        .iter()
        .zip(&lines)
        .filter(|(_, l)| **l == 0)
        .map(|(s, _)| s.name)
        .collect();
    if !missing.is_empty() {
        return Err(Error::data(
            path,
            0,
            format!(
                "column 'name': constant(s) {} missing (model {} needs {})",
                missing.join(", "),
                model.name(),
                specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
            ),
        ));
    }
    Ok((values, lines))
}

/// Per-curve error rows of a fit (the columns of `errors.csv`), as numbers.
pub struct ErrorRow {
    pub temperature_c: f64,
    pub stress_mpa: f64,
    pub rupture_time_exp_h: f64,
    pub rupture_time_pred_h: f64,
    pub lifetime_err_pct: f64,
    pub min_rate_exp_pct_per_h: f64,
    pub min_rate_pred_pct_per_h: f64,
    pub min_rate_err_pct: f64,
    pub rupture_strain_exp_pct: f64,
    pub rupture_strain_pred_pct: f64,
    /// Specimen label of the curve, if the data have one.
    pub specimen: Option<String>,
}

/// The error rows of a local fit.
pub fn error_rows(fit: &LocalFit, curves: &[Curve]) -> Vec<ErrorRow> {
    curves
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let p = &fit.eval.curves[i];
            ErrorRow {
                temperature_c: c.temperature_c,
                stress_mpa: c.stress_mpa,
                rupture_time_exp_h: c.rupture_time_h.unwrap_or(f64::NAN),
                rupture_time_pred_h: p.rupture_time_h,
                lifetime_err_pct: fit.lifetime_err_pct[i],
                min_rate_exp_pct_per_h: 100.0 * c.min_rate_measured.unwrap_or(c.min_rate_estimated),
                min_rate_pred_pct_per_h: 100.0 * p.min_rate,
                min_rate_err_pct: fit.min_rate_err_pct[i],
                rupture_strain_exp_pct: 100.0 * c.rupture_strain,
                rupture_strain_pred_pct: 100.0 * p.rupture_strain,
                specimen: c.specimen.clone(),
            }
        })
        .collect()
}

/// Whether a `specimen` column goes into per-curve outputs: when some curve has one. It is
/// appended after the contract's columns, so readers by column name keep working.
pub fn has_specimens(curves: &[Curve]) -> bool {
    curves.iter().any(|c| c.specimen.is_some())
}

/// `header` plus `specimen` if `specimens`.
pub fn with_specimen<'a>(header: &[&'a str], specimens: bool) -> Vec<&'a str> {
    let mut h = header.to_vec();
    if specimens {
        h.push("specimen");
    }
    h
}

/// `errors.csv` (plus a last `specimen` column when some row has one).
pub fn write_errors(path: &Path, rows: &[ErrorRow]) -> Result<()> {
    let (header, rows) = errors_table(rows);
    write_csv(path, &header, &rows)
}

/// The header and rows of `errors.csv` ([`write_errors`]).
pub fn errors_table(rows: &[ErrorRow]) -> (Vec<&'static str>, Vec<Vec<String>>) {
    let specimens = rows.iter().any(|r| r.specimen.is_some());
    let header = [
        "temperature_C",
        "stress_MPa",
        "rupture_time_exp_h",
        "rupture_time_pred_h",
        "lifetime_err_pct",
        "min_rate_exp_pct_per_h",
        "min_rate_pred_pct_per_h",
        "min_rate_err_pct",
        "rupture_strain_exp_pct",
        "rupture_strain_pred_pct",
    ];
    let rows: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            [
                r.temperature_c,
                r.stress_mpa,
                r.rupture_time_exp_h,
                r.rupture_time_pred_h,
                r.lifetime_err_pct,
                r.min_rate_exp_pct_per_h,
                r.min_rate_pred_pct_per_h,
                r.min_rate_err_pct,
                r.rupture_strain_exp_pct,
                r.rupture_strain_pred_pct,
            ]
            .iter()
            .map(|v| num(*v))
            .chain(specimens.then(|| r.specimen.clone().unwrap_or_default()))
            .collect()
        })
        .collect();
    (with_specimen(&header, specimens), rows)
}

/// `curves.csv` of a fit: measured and predicted strain at every measured time, whether the
/// time is past the predicted rupture (plus a last `specimen` column when some curve has one).
pub fn write_fit_curves(path: &Path, fit: &LocalFit, curves: &[Curve]) -> Result<()> {
    let (header, rows) = fit_curves_table(fit, curves);
    write_csv_rows(path, &header, rows)
}

/// The header and rows (made one at a time) of a fit's `curves.csv` ([`write_fit_curves`]).
pub fn fit_curves_table<'a>(
    fit: &'a LocalFit,
    curves: &'a [Curve],
) -> (Vec<&'static str>, impl Iterator<Item = Vec<String>> + 'a) {
    let specimens = has_specimens(curves);
    let rows = curves.iter().enumerate().flat_map(move |(i, c)| {
        c.times_h.iter().enumerate().map(move |(k, &t)| {
            let mut row = vec![
                num(c.temperature_c),
                num(c.stress_mpa),
                num(t),
                num(100.0 * c.strains[k]),
                num(100.0 * fit.eval.curves[i].strain[k]),
                past_rupture(&fit.eval.curves[i], t).to_string(),
            ];
            if specimens {
                row.push(c.specimen.clone().unwrap_or_default());
            }
            row
        })
    });
    let header = [
        "temperature_C",
        "stress_MPa",
        "time_h",
        "strain_exp_pct",
        "strain_pred_pct",
        "past_predicted_rupture",
    ];
    (with_specimen(&header, specimens), rows)
}

/// Whether measured time `t` (h) lies after the predicted rupture of `p`: its
/// `strain_pred_pct` is then eq. 8's linear continuation at the rupture rate (what the
/// objective compares with the measurement), not a strain of the specimen, which has broken
/// (`curves.csv` column `past_predicted_rupture`, 1 or 0).
pub fn past_rupture(p: &crate::model::objective::CurvePrediction, t: f64) -> u8 {
    u8::from(p.outcome == crate::ode::Outcome::Ruptured && t > p.rupture_time_h)
}

/// At most about `max` of `points`, evenly spaced in index, first and last kept: what a plot
/// draws of a logged curve (a million markers cost seconds and show nothing more).
pub fn thin<T: Copy>(points: Vec<T>, max: usize) -> Vec<T> {
    let n = points.len();
    if n <= max.max(2) {
        return points;
    }
    let stride = n.div_ceil(max.max(2) - 1);
    let mut out: Vec<T> = points.iter().step_by(stride).copied().collect();
    if !(n - 1).is_multiple_of(stride) {
        out.push(points[n - 1]);
    }
    out
}

/// The paper-style table (Tables 6/7): lifetime and minimum-rate errors per stress.
pub fn error_table(rows: &[ErrorRow], min_rate_measured: bool) -> String {
    let mut s = String::new();
    let rate_note = if min_rate_measured {
        "measured"
    } else {
        "estimated from the curve"
    };
    let specimens = rows.iter().any(|r| r.specimen.is_some());
    let _ = write!(
        s,
        "{:>6} {:>7} | {:>10} {:>10} {:>8} | {:>11} {:>11} {:>8} | {:>7} {:>7}",
        "T(C)",
        "MPa",
        "t_f exp h",
        "t_f pred h",
        "err %",
        "rate exp",
        "rate pred",
        "err %",
        "e_f exp",
        "e_f pred"
    );
    let _ = writeln!(s, "{}", if specimens { " | specimen" } else { "" });
    for r in rows {
        let _ = write!(
            s,
            "{:>6} {:>7} | {:>10.0} {:>10.0} {:>8.2} | {:>11.4e} {:>11.4e} {:>8.2} | {:>7.3} {:>7.3}",
            r.temperature_c,
            r.stress_mpa,
            r.rupture_time_exp_h,
            r.rupture_time_pred_h,
            r.lifetime_err_pct,
            r.min_rate_exp_pct_per_h,
            r.min_rate_pred_pct_per_h,
            r.min_rate_err_pct,
            r.rupture_strain_exp_pct,
            r.rupture_strain_pred_pct
        );
        let _ = match (&r.specimen, specimens) {
            (Some(sp), _) => writeln!(s, " | {sp}"),
            (None, true) => writeln!(s, " |"),
            (None, false) => writeln!(s),
        };
    }
    let mean = |f: &dyn Fn(&ErrorRow) -> f64| {
        let v: Vec<f64> = rows
            .iter()
            .map(f)
            .filter(|x| x.is_finite())
            .map(f64::abs)
            .collect();
        v.iter().sum::<f64>() / v.len().max(1) as f64
    };
    let _ = writeln!(
        s,
        "{:>14} | {:>21} {:>8.2} | {:>23} {:>8.2} |   (rates in %/h, {rate_note}; strains in %)",
        "mean |err|",
        "",
        mean(&|r| r.lifetime_err_pct),
        "",
        mean(&|r| r.min_rate_err_pct)
    );
    s
}

/// The error model of creep data ([`crate::errmodel`]) estimated from the residuals of `fit`'s
/// chosen constants: per curve the marginal sd (% strain) and AR(1) correlation of the
/// residuals — reading error plus whatever misfit the model leaves (φ near 1: mostly misfit) —, the scatter of rupture times (% on the log scale), and −2 ln L. `null` if the
/// chosen constants cannot be evaluated.
pub fn error_model_json(cfg: &RunConfig, run: &FitRun, curves: &[Curve]) -> Value {
    let best = &run.fits[run.best];
    // With specimen effects, each curve at its own specimen's factors: the residuals the
    // likelihood saw (the population's prediction misses each specimen by its factor, up to
    // hundreds of % strain on Alloy 617 at 950 °C).
    let factors = run
        .specimens
        .fit
        .as_ref()
        .and_then(|sp| sp.curve_factors(run.model.as_ref()));
    let at_factors = factors.is_some();
    let obj = crate::likelihood::raw_objective(run.model.as_ref(), curves, &run.settings)
        .with_factors(factors);
    let mut r = vec![0.0; obj.n_residuals()];
    if obj.residuals(&best.params, &mut r).is_err() {
        return Value::Null;
    }
    let res = crate::likelihood::split_residuals(curves, &r);
    let m = crate::errmodel::ErrorModel::estimate(&res, cfg.diagnose.lifetime_sd_floor);
    json!({
        "at_specimen_factors": at_factors,
        "curves": curves.iter().zip(&m.strain).zip(&res.strain).map(|((c, p), e)| json!({
            "temperature_C": c.temperature_c,
            "stress_MPa": c.stress_mpa,
            "specimen": c.specimen,
            "points": e.len(),
            "residual_sd_pct": jnum(100.0 * p.marginal_sd()),
            "ar1_phi": jnum(p.phi),
            "largest_strain_pct": jnum(100.0 * c.largest_strain()),
            "written_off": crate::errmodel::writes_off(p.marginal_sd(), c.largest_strain()),
        })).collect::<Vec<_>>(),
        "lifetime_sd_pct": jnum(100.0 * m.lifetime_sd),
        "lifetime_sd_floor_pct": jnum(100.0 * cfg.diagnose.lifetime_sd_floor),
        "neg2_log_likelihood": jnum(m.neg2ll(&res)),
        "effective_observations": jnum(m.effective_n(&res)),
    })
}

/// `summary.json` of a fit of the configuration `cfg`.
pub fn fit_summary(cfg: &RunConfig, run: &FitRun, curves: &[Curve]) -> Value {
    let best = &run.fits[run.best];
    let names: Vec<&str> = run.model.constants().iter().map(|c| c.name).collect();
    let consts = |p: &[f64]| -> Value {
        let mut m = serde_json::Map::new();
        for (n, v) in names.iter().zip(p) {
            m.insert(n.to_string(), jnum(*v));
        }
        Value::Object(m)
    };
    let pinned: Vec<Value> = (0..run.space.len())
        .filter_map(|j| {
            run.space
                .at_bound(j, best.params[j], 1e-6)
                .map(|side| json!({"name": names[j], "bound": side, "value": best.params[j]}))
        })
        .collect();
    let candidates: Vec<Value> = run
        .fits
        .iter()
        .map(|f| {
            json!({
                "start": f.start_label,
                "w": f.w,
                "objective": jnum(f.eval.objective),
                "norm_residual": jnum(f.eval.norm_residual),
                "mean_lifetime_err_pct": jnum(f.mean_lifetime_err()),
                "mean_min_rate_err_pct": jnum(f.mean_min_rate_err()),
                "lifetime_err_pct": f.lifetime_err_pct.iter().map(|v| jnum(*v)).collect::<Vec<_>>(),
                "termination": f.lm.termination.as_str(),
                "iterations": f.lm.iterations,
                "evaluations": f.lm.evaluations,
                "wall_s": f.wall_s,
                "constants": consts(&f.params),
            })
        })
        .collect();
    let error_model = error_model_json(cfg, run, curves);
    // Every caution that applies, in one sentence each.
    let labels: Vec<String> = curves.iter().map(Curve::label).collect();
    let mut cautions: Vec<String> = crate::fit::lives_caution(&labels, &best.lifetime_err_pct)
        .into_iter()
        .collect();
    if cfg.objective.kind == crate::model::objective::ObjectiveKind::Likelihood {
        let per_curve = |key: &str| -> Vec<f64> {
            error_model["curves"]
                .as_array()
                .map(|v| {
                    v.iter()
                        .map(|c| c[key].as_f64().unwrap_or(f64::NAN))
                        .collect()
                })
                .unwrap_or_default()
        };
        cautions.extend(crate::fit::absorbed_noise_caution(
            &per_curve("ar1_phi"),
            &per_curve("residual_sd_pct"),
        ));
        cautions.extend(crate::fit::written_off_caution(
            &labels,
            &per_curve("residual_sd_pct"),
            &per_curve("largest_strain_pct"),
        ));
    }
    let caution = (!cautions.is_empty()).then(|| cautions.join("; "));
    let mut summary = json!({
        "model": run.model.name(),
        "extensions": cfg.extensions,
        "error_model": error_model,
        "run_id": crate::identity::hash_value(&crate::config::identity(cfg)),
        "data_hash": cfg.data_hash,
        "objective": jnum(best.eval.objective),
        "norm_residual": jnum(best.eval.norm_residual),
        "w": best.w,
        "start": best.start_label,
        "iterations": best.lm.iterations,
        "evaluations": best.lm.evaluations,
        "wall_s": run.wall_s,
        "fit_wall_s": best.wall_s,
        "termination": best.lm.termination.as_str(),
        "caution": caution,
        "constants": consts(&best.params),
        "pinned_at_bounds": pinned,
        "mean_lifetime_err_pct": jnum(best.mean_lifetime_err()),
        "mean_min_rate_err_pct": jnum(best.mean_min_rate_err()),
        "lifetime_err_pct": best.lifetime_err_pct.iter().map(|v| jnum(*v)).collect::<Vec<_>>(),
        "min_rate_err_pct": best.min_rate_err_pct.iter().map(|v| jnum(*v)).collect::<Vec<_>>(),
        "stresses_MPa": curves.iter().map(|c| c.stress_mpa).collect::<Vec<_>>(),
        "min_rate_source": if run.used_min_rate { "measured" } else { "estimated_from_curve" },
        "best_w_rule": "sum of norm_residual, mean |lifetime error| and (if measured) mean |min-rate error|, each normalised over the converged fits with a floor of 0.1 % resp. 0.1 pp on its range; scores within 0.05 of the best are ties, won by the largest w",
        "initial_guess": {
            "constants": consts(&run.guess.params),
            "min_rates_pct_per_h": run.guess.min_rates.iter().map(|r| 100.0 * r).collect::<Vec<_>>(),
            "clamped_to_bounds": run.guess.clamped,
        },
        "ode": {"rtol": run.settings.ode.rtol, "atol": run.settings.ode.atol},
        "candidates": candidates,
    });
    // What the objective is, and the configured specimen effects it leaves out (eq. 8 has
    // none): a user comparing with `diagnose` or a likelihood fit is told.
    let left_out = cfg.objective.effects_left_out(curves, LocalFits::Fit);
    summary["objective_kind"] = json!(cfg.objective.kind);
    summary["objective_note"] = json!(crate::config::objective_note(cfg.objective.kind, &left_out));
    summary["specimen_effects_not_fitted"] = json!(left_out);
    // A joint calibration across temperatures (or the likelihood objective) says so, with
    // the errors and the model's constants at each temperature.
    if cfg.has_laws() || cfg.objective.kind != crate::model::objective::ObjectiveKind::Eq8 {
        let inner: Vec<&str> = run.model.inner_constants().iter().map(|c| c.name).collect();
        let at = |t: f64| -> Value {
            let v = run.model.constants_at(&best.params, t);
            Value::Object(
                inner
                    .iter()
                    .zip(v)
                    .map(|(n, x)| (n.to_string(), jnum(x)))
                    .collect(),
            )
        };
        let per_t: Vec<Value> = crate::fit::errors_per_temperature(best, curves)
            .into_iter()
            .map(|e| {
                let mut v = json!(e);
                v["constants"] = at(e.temperature_c);
                v
            })
            .collect();
        summary["T_ref_C"] = json!(cfg.t_ref);
        summary["per_temperature"] = json!(per_t);
        summary["initial_guess"]["procedure"] = json!(run.guess.procedure);
        summary["initial_guess"]["per_temperature"] = json!(run
            .guess
            .per_temperature
            .iter()
            .map(|(t, p)| json!({"temperature_C": t, "constants": inner.iter().zip(p).map(|(n, x)| (n.to_string(), jnum(*x))).collect::<serde_json::Map<_, _>>()}))
            .collect::<Vec<_>>());
    }
    if cfg.has_laws() {
        let a = crate::activation::for_fit(
            run.model.as_ref(),
            &best.params,
            curves,
            run.settings.omega_f,
            &run.settings.ode,
        );
        summary["activation_energy"] = serde_json::to_value(a).expect("plain values");
    }
    if run.settings.kind == crate::model::objective::ObjectiveKind::Likelihood {
        summary["specimens"] = specimens_json(&run.specimens);
    }
    summary
}

/// Coefficient of variation (%) of a log-normal factor whose ln has sd `s`: what "the creep
/// rate varies 23 % between specimens" means.
pub fn lognormal_cv_pct(s: f64) -> f64 {
    100.0 * (s * s).exp_m1().sqrt()
}

/// Below this many degrees of freedom ([`crate::specimen::Lmm::effect_dof`]) the data hardly
/// separate a scatter from the constants: fewer than two specimens' worth beyond them.
pub const FEW_SCATTER_DOF: f64 = 2.0;

/// What a scatter's interval rests on, for a printed line after its ends: ", from 4.2
/// degrees of freedom", and where they are fewer than [`FEW_SCATTER_DOF`] that the data hardly
/// separate the scatter from the constants; empty when unknown (an interval computed before
/// they were counted, or none).
///
/// The count is printed to one decimal, or where rounding would put it on the other side of
/// [`FEW_SCATTER_DOF`] than the words, cut (not rounded) to two (1.96 reads "1.96", 1.999
/// "1.99", never "2.0 … hardly separate").
pub fn scatter_dof_note(dof: Option<f64>) -> String {
    let Some(d) = dof.filter(|d| d.is_finite()) else {
        return String::new();
    };
    let few = d < FEW_SCATTER_DOF;
    let one = format!("{d:.1}");
    let crosses = one
        .parse::<f64>()
        .is_ok_and(|r| (r < FEW_SCATTER_DOF) != few);
    let text = if crosses {
        format!("{:.2}", (d * 100.0).floor() / 100.0)
    } else {
        one
    };
    if few {
        format!(", from {text} degrees of freedom: the data hardly separate it from the constants")
    } else {
        format!(", from {text} degrees of freedom")
    }
}

/// A p-value for a printed line: three decimals, or two significant digits below 0.001.
pub fn p_text(p: f64) -> String {
    if p.is_finite() && p < 1e-3 {
        format!("{p:.1e}")
    } else {
        format!("{p:.3}")
    }
}

/// The clause on the difference of two groups' levels a test calls with 80 % probability
/// ([`crate::likelihood::GroupLevels::detectable_ln`]); empty where there is none.
fn detectable_text(d: f64) -> String {
    if !d.is_finite() {
        return String::new();
    }
    format!(
        "; it calls a difference of {d:.2} between the two levels (a factor {:.2}) with {:.0} % probability",
        d.exp(),
        100.0 * crate::likelihood::DETECT_POWER
    )
}

/// One line on how a kind's ln factors differ between temperatures
/// ([`crate::likelihood::TemperatureLevels`]), without a leading dash: the means per
/// temperature, the F-test and, where it is called, what that means.
pub fn temperature_levels_text(t: &crate::likelihood::TemperatureLevels) -> String {
    let means: Vec<String> = t
        .mean_ln
        .iter()
        .map(|(temp, m)| format!("{m:+.2} at {temp} °C"))
        .collect();
    let test = if t.f.is_finite() {
        format!(
            "F-test of equal levels beside a common slope on ln stress: p {}, {} and {} degrees of freedom; called at p < {}",
            p_text(t.p_value),
            t.df.0,
            t.df.1,
            crate::likelihood::STRESS_TREND_ALPHA
        ) + &detectable_text(t.detectable_ln)
    } else if t.df.1 == 0 {
        "no test: too few specimens beside the levels and the slope".to_string()
    } else {
        "no test: the scatter is at its floor, the factors are zero".to_string()
    };
    let flag = if t.differ() {
        ": **they follow temperature**, a temperature dependence the constants' laws miss and the factors take up, which goodness-of-fit tests cannot see"
    } else {
        ""
    };
    format!(
        "The ln {} factors between temperatures: mean {} ({test}){flag}",
        t.kind.name(),
        means.join(", ")
    )
}

/// One line on how a kind's ln factors differ between test campaigns
/// ([`crate::likelihood::CampaignLevels`]), without a leading dash: the means per campaign,
/// the F-test beyond the temperatures' levels and the stress slope and, where it is called,
/// what that means.
pub fn campaign_levels_text(c: &crate::likelihood::CampaignLevels) -> String {
    let means: Vec<String> = c
        .mean_ln
        .iter()
        .map(|(name, m)| format!("{m:+.2} for {name}"))
        .collect();
    let test = if c.f.is_finite() {
        format!(
            "F-test of equal campaign levels beside a level per temperature and a common slope on ln stress: p {}, {} and {} degrees of freedom; called at p < {}",
            p_text(c.p_value),
            c.df.0,
            c.df.1,
            crate::likelihood::STRESS_TREND_ALPHA
        ) + &detectable_text(c.detectable_ln)
    } else if c.df.0 == 0 {
        "no test: the campaigns share no temperature, so their levels are the temperatures'"
            .to_string()
    } else if c.df.1 == 0 {
        "no test: too few specimens beside the levels and the slope".to_string()
    } else {
        "no test: the scatter is at its floor, the factors are zero".to_string()
    };
    let flag = if c.differ() {
        ": **the campaigns differ**, a heat or laboratory effect that the scatter between specimens mixes in; `predict` draws a new specimen from one population of specimens, so for a specimen of a new campaign its interval leaves this difference out"
    } else {
        ""
    };
    format!(
        "The ln {} factors between campaigns: mean {} ({test}){flag}{}",
        c.kind.name(),
        means.join(", "),
        new_campaign_text(c.new_group_sd)
    )
}

/// The campaign line's clause on a new specimen from a new campaign
/// ([`crate::likelihood::GroupLevels::new_group_sd`]); empty without the estimate.
fn new_campaign_text(sd: Option<(f64, f64, f64)>) -> String {
    sd.map_or_else(String::new, |(est, lo, hi)| {
        format!(
            "; a new specimen from a new campaign: sd {est:.2} in the ln factor (95 % {lo:.2}–{hi:.2}, the campaigns' degrees of freedom included)"
        )
    })
}

/// The kinds of specimen effect, in the order of `specimens.csv` and `summary.json`.
const EFFECT_KINDS: [(crate::likelihood::EffectKind, &str); 3] = [
    (crate::likelihood::EffectKind::Rate, "rate"),
    (crate::likelihood::EffectKind::Ductility, "ductility"),
    (crate::likelihood::EffectKind::Coarsening, "coarsening"),
];

/// `summary.json`'s `specimens`: the scatter between specimens the likelihood fit found (per
/// kind: sd of the ln factor, its 95 % interval, the coefficient of variation), or why there
/// is none.
pub fn specimens_json(sp: &crate::fit::FitSpecimens) -> Value {
    let scatter: serde_json::Map<String, Value> = sp
        .fit
        .iter()
        .flat_map(|f| {
            f.kinds.iter().enumerate().map(move |(j, k)| {
                let name = EFFECT_KINDS.iter().find(|e| e.0 == *k).map_or("?", |e| e.1);
                (
                    name.to_string(),
                    json!({
                        "sd_ln": jnum(f.scatter[j]),
                        "sd_ln_lo95": jnum(f.scatter_lo95[j]),
                        "sd_ln_hi95": jnum(f.scatter_hi95[j]),
                        "sd_ln_dof": jnum(f.scatter_dof.get(j).copied().unwrap_or(f64::NAN)),
                        "cv_pct": jnum(lognormal_cv_pct(f.scatter[j])),
                        "at_bound": crate::likelihood::scatter_at_bound(f.scatter[j]),
                    }),
                )
            })
        })
        .collect();
    json!({
        "fitted": sp.fit.is_some(),
        "scatter": scatter,
        "dropped": sp.fit.as_ref().map(|f| f.dropped.clone()).unwrap_or_default(),
        "scatter_method": sp.fit.as_ref().map(|f| f.scatter_method),
        "neg2ll_without_effects": jnum(sp.plain_neg2ll),
        "replicate_curves": sp.replicate_curves,
        "replicate_sd_ln_rupture_time": sp.replicate_sd_ln_life.map(jnum),
        "note": sp.note,
        "by_temperature": factor_groups_json(sp, &sp.by_temperature),
        "by_campaign": factor_groups_json(sp, &sp.by_campaign),
        "stress_trend": sp
            .stress_trend
            .iter()
            .map(|t| (
                t.kind.name().to_string(),
                json!({
                    "slope_per_ln_stress": jnum(t.slope),
                    "se": jnum(t.se),
                    "df": t.df,
                    "p_value": jnum(t.p_value),
                    "follows_stress": t.follows_stress(),
                    "specimens": t.specimens,
                    "temperatures": t.temperatures,
                })
            ))
            .collect::<serde_json::Map<String, Value>>(),
        "temperature_levels": group_levels_json(
            &sp.temperature_levels,
            ("mean_ln_by_temperature", "temperature_C"),
            "follows_temperature"
        ),
        "campaign_levels": group_levels_json(
            &sp.campaign_levels,
            ("mean_ln_by_campaign", "campaign"),
            "differ"
        ),
    })
}

/// `specimens.temperature_levels` / `campaign_levels`: per kind the mean ln factor of each
/// group (in the list `means.0`, the group under the key `means.1`), the F-test and whether
/// the groups differ (under the key `called`).
fn group_levels_json<G: serde::Serialize>(
    levels: &[crate::likelihood::GroupLevels<G>],
    means: (&str, &str),
    called: &str,
) -> Value {
    levels
        .iter()
        .map(|t| {
            let by_group: Vec<Value> = t
                .mean_ln
                .iter()
                .map(|(g, m)| json!({ means.1: g, "mean_ln": jnum(*m) }))
                .collect();
            (
                t.kind.name().to_string(),
                json!({
                    means.0: by_group,
                    "f": jnum(t.f),
                    "df": [t.df.0, t.df.1],
                    "p_value": jnum(t.p_value),
                    "detectable_difference_ln": jnum(t.detectable_ln),
                    "new_campaign_sd_ln": t.new_group_sd.map(|(e, lo, hi)| {
                        json!({"estimate": jnum(e), "lo95": jnum(lo), "hi95": jnum(hi)})
                    }),
                    called: t.differ(),
                }),
            )
        })
        .collect::<serde_json::Map<String, Value>>()
        .into()
}

/// `specimens.by_temperature` / `by_campaign`: per group its name, specimens, and per kind
/// the mean ln factor and its standard error.
fn factor_groups_json(
    sp: &crate::fit::FitSpecimens,
    groups: &[crate::likelihood::FactorGroup],
) -> Value {
    let kinds = sp.fit.as_ref().map(|f| f.kinds.clone()).unwrap_or_default();
    groups
        .iter()
        .map(|g| {
            let mut o = json!({"group": g.group, "specimens": g.specimens});
            for (j, k) in kinds.iter().enumerate() {
                o[format!("mean_ln_{}", k.name())] = jnum(g.mean_ln[j]);
                o[format!("se_ln_{}", k.name())] = jnum(g.se[j]);
            }
            o
        })
        .collect()
}

/// `specimens.csv`: each curve's specimen factors (the conditional mode e^η of the factor
/// on the creep rate, and on the rupture strain, with e^(η ± 1.96 sd)), empty for a kind the
/// fit does not carry.
pub fn write_specimens(
    path: &Path,
    fit: &crate::likelihood::SpecimenFit,
    curves: &[Curve],
) -> Result<()> {
    let rows: Vec<Vec<String>> = curves
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let mut row = vec![
                (i + 1).to_string(),
                num(c.temperature_c),
                num(c.stress_mpa),
                c.specimen.clone().unwrap_or_default(),
            ];
            for (kind, _) in EFFECT_KINDS {
                match fit.kinds.iter().position(|k| *k == kind) {
                    Some(j) => {
                        let (e, sd) = (fit.effects[j][i], fit.effects_sd[j][i]);
                        row.push(num(e.exp()));
                        row.push(num((e - 1.96 * sd).exp()));
                        row.push(num((e + 1.96 * sd).exp()));
                    }
                    None => row.extend([String::new(), String::new(), String::new()]),
                }
            }
            row
        })
        .collect();
    write_csv(
        path,
        &[
            "curve",
            "temperature_C",
            "stress_MPa",
            "specimen",
            "rate_factor",
            "rate_factor_lo95",
            "rate_factor_hi95",
            "ductility_factor",
            "ductility_factor_lo95",
            "ductility_factor_hi95",
            "coarsening_factor",
            "coarsening_factor_lo95",
            "coarsening_factor_hi95",
        ],
        &rows,
    )
}

/// The constants' reference temperature written with them (`T_ref` row of constants.csv),
/// if the file has one.
pub fn constants_t_ref(path: &Path) -> Result<Option<(f64, usize)>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    constants_t_ref_text(path, &text)
}

/// [`constants_t_ref`] of a constants table's text in memory, named `path` in errors.
pub fn constants_t_ref_text(path: &Path, text: &str) -> Result<Option<(f64, usize)>> {
    for (i, line) in text.lines().enumerate() {
        let mut f = line.split(',');
        if f.next().map(str::trim) == Some(T_REF_ROW) {
            let v = f.next().unwrap_or("").trim();
            let t: f64 = v.parse().map_err(|_| {
                Error::data(
                    path,
                    i + 1,
                    format!("column 'value': cannot parse '{v}' as a number"),
                )
            })?;
            return Ok(Some((t, i + 1)));
        }
    }
    Ok(None)
}

/// Constants fitted about another reference temperature than the configuration's mean
/// different constants: an error naming both.
pub fn check_t_ref(path: &Path, cfg: &RunConfig) -> Result<()> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    check_t_ref_text(path, &text, cfg)
}

/// [`check_t_ref`] of a constants table's text in memory, named `path` in errors.
pub fn check_t_ref_text(path: &Path, text: &str, cfg: &RunConfig) -> Result<()> {
    if let Some((t, line)) = constants_t_ref_text(path, text)? {
        match cfg.t_ref {
            Some(c) if c == t => {}
            other => {
                return Err(Error::data(
                    path,
                    line,
                    format!(
                        "T_ref: these constants are about T_ref = {t} °C, the configuration resolves T_ref = {}; set T_ref = {t} in {}",
                        other.map_or("none (no temperature laws)".to_string(), |c| format!("{c} °C")),
                        cfg.path.display()
                    ),
                ))
            }
        }
    }
    Ok(())
}

/// Write `timings.json` into `out`: how long this run took, what it resumed. Timings are kept
/// out of the result files, which are then the same for an interrupted and resumed run as for
/// an uninterrupted one.
pub fn write_timings(
    out: &Path,
    command: &str,
    journal: Option<&crate::journal::Journal>,
    timings: serde_json::Value,
) -> Result<()> {
    let mut t = serde_json::json!({ "command": command });
    if let Some(j) = journal {
        t["journal_records_resumed"] = j.found().into();
        t["journal_records_written"] = j.written().into();
    }
    if let (Some(m), serde_json::Value::Object(more)) = (t.as_object_mut(), timings) {
        m.extend(more);
    }
    write_text(
        &out.join(TIMINGS_FILE),
        &serde_json::to_string_pretty(&t).expect("JSON of plain values"),
    )
}

/// The file of a run's wall times (not a result: it differs between runs of one computation).
pub const TIMINGS_FILE: &str = "timings.json";

#[cfg(test)]
mod tests {
    use super::*;

    /// The campaign line's words for each case of the test, as a table: called, not called,
    /// campaigns confounded with temperatures, too few specimens, the scatter at its floor;
    /// the difference the test can detect wherever there is a test.
    #[test]
    fn campaign_levels_text_says_why_there_is_no_test() {
        use crate::likelihood::{CampaignLevels, EffectKind};
        let line = |f: f64, df: (usize, usize), p: f64| {
            // The difference the test can detect exists only where there is a test.
            let detectable_ln = if f.is_finite() { 0.5 } else { f64::NAN };
            campaign_levels_text(&CampaignLevels {
                kind: EffectKind::Rate,
                mean_ln: vec![("INL2".into(), 0.21), ("KAERI2".into(), -0.25)],
                f,
                df,
                p_value: p,
                detectable_ln,
                new_group_sd: None,
            })
        };
        // F, its degrees of freedom, p, words the line holds, whether it is called.
        type Case<'a> = (f64, (usize, usize), f64, &'a str, bool);
        let cases: [Case; 5] = [
            (
                9.1,
                (1, 28),
                0.005,
                "p 0.005, 1 and 28 degrees of freedom",
                true,
            ),
            (
                7.4,
                (1, 28),
                0.011,
                "p 0.011, 1 and 28 degrees of freedom",
                false,
            ),
            (
                f64::NAN,
                (0, 29),
                f64::NAN,
                "the campaigns share no temperature",
                false,
            ),
            (f64::NAN, (1, 0), f64::NAN, "too few specimens", false),
            (
                f64::NAN,
                (1, 28),
                f64::NAN,
                "the scatter is at its floor",
                false,
            ),
        ];
        for (f, df, p, words, called) in cases {
            let s = line(f, df, p);
            assert!(s.starts_with("The ln rate factors between campaigns: mean +0.21 for INL2, -0.25 for KAERI2 ("), "{s}");
            assert!(s.contains(words), "{s}");
            assert_eq!(s.contains("**the campaigns differ**"), called, "{s}");
            assert_eq!(
                s.contains("it calls a difference of 0.50 between the two levels (a factor 1.65) with 80 % probability"),
                f.is_finite(),
                "{s}"
            );
        }
        // The sd of a new campaign's specimen closes the line where there is one.
        assert_eq!(new_campaign_text(None), "");
        assert_eq!(
            new_campaign_text(Some((0.655, 0.505, 13.794))),
            "; a new specimen from a new campaign: sd 0.66 in the ln factor (95 % 0.51–13.79, the campaigns' degrees of freedom included)"
        );
    }

    #[test]
    fn csv_text_is_the_file_text() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let header = ["name", "value", "note"];
        let rows = vec![
            vec!["A".to_string(), num(1e-10), "a, quoted".to_string()],
            vec!["B".to_string(), num(f64::NAN), String::new()],
            vec!["C".to_string(), num(0.1 + 0.2), "line\nbreak".to_string()],
        ];
        write_csv(&path, &header, &rows).unwrap();
        let file = std::fs::read_to_string(&path).unwrap();
        assert_eq!(csv_text(&header, rows.iter()), file);
        assert!(file.starts_with("name,value,note\nA,0.0000000001,\"a, quoted\"\nB,,\n"));
    }

    #[test]
    fn a_scatter_from_few_degrees_of_freedom_says_so() {
        for (dof, want) in [
            (None, ""),
            (Some(f64::NAN), ""),
            (Some(4.23), ", from 4.2 degrees of freedom"),
            (Some(2.0), ", from 2.0 degrees of freedom"),
            (
                Some(1.96),
                ", from 1.96 degrees of freedom: the data hardly separate it from the constants",
            ),
            (
                Some(1.999),
                ", from 1.99 degrees of freedom: the data hardly separate it from the constants",
            ),
            (
                Some(1.94),
                ", from 1.9 degrees of freedom: the data hardly separate it from the constants",
            ),
            (
                Some(0.4),
                ", from 0.4 degrees of freedom: the data hardly separate it from the constants",
            ),
        ] {
            assert_eq!(scatter_dof_note(dof), want, "{dof:?}");
        }
    }
}
