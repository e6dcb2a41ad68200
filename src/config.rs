//! Run configuration (TOML, DESIGN.md §4): serde structures, defaults and validation.
//!
//! Unknown keys are errors everywhere. Paths are resolved relative to the configuration
//! file's directory. Constants come out in the model's order, with the ones the file does
//! not mention filled from the model's defaults (bounds and scale; no start).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::data::{self, Dataset, LoadOptions};
use crate::error::{Error, Result};
use crate::model::{self, Scale};
use crate::objective::JacobianMethod;

/// Names of the extension catalogue (DESIGN.md §6).
pub const EXTENSION_NAMES: &[&str] = model::ext::CATALOGUE;

/// Which side of the lifetime error enters the objective (eq. 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LifetimeTerm {
    /// Only when the prediction ruptures later than measured (the paper).
    #[default]
    Late,
    /// Always.
    Both,
}

/// One constant as the run uses it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstantConfig {
    /// Name, as in the model's [`model::ConstantSpec`].
    pub name: String,
    /// Physical unit, from the model.
    pub unit: &'static str,
    /// Lower bound.
    pub lb: f64,
    /// Upper bound.
    pub ub: f64,
    /// Start value, if the configuration gives one.
    pub start: Option<f64>,
    /// Scale in the optimiser.
    pub scale: Scale,
}

/// `[objective]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ObjectiveConfig {
    /// Weights applied to every curve alike; each gives one fit. Default 0.1, 0.2, …, 1.0.
    pub w_grid: Vec<f64>,
    /// Explicit per-curve weight vectors (ascending-stress order); each gives one fit, in
    /// addition to `w_grid`. Default empty.
    pub w_sets: Vec<Vec<f64>>,
    /// Lifetime term side. Default `late`.
    pub lifetime_term: LifetimeTerm,
    /// Damage at rupture ω_f. Default 1/3.
    pub omega_f: f64,
}

impl Default for ObjectiveConfig {
    fn default() -> Self {
        ObjectiveConfig {
            w_grid: (1..=10).map(|k| k as f64 / 10.0).collect(),
            w_sets: Vec::new(),
            lifetime_term: LifetimeTerm::Late,
            omega_f: 1.0 / 3.0,
        }
    }
}

impl ObjectiveConfig {
    /// All per-curve weight vectors of the run: first each `w_grid` value repeated for every
    /// curve, then the `w_sets`. A `w_sets` entry whose length is not `n_curves` is an error
    /// (reported against `path`, the configuration file).
    pub fn weight_vectors(&self, n_curves: usize, path: &Path) -> Result<Vec<Vec<f64>>> {
        let mut out: Vec<Vec<f64>> = self.w_grid.iter().map(|&w| vec![w; n_curves]).collect();
        for (k, set) in self.w_sets.iter().enumerate() {
            if set.len() != n_curves {
                return Err(Error::config(
                    path,
                    format!(
                        "objective.w_sets[{k}] has {} weights but the data have {n_curves} curves",
                        set.len()
                    ),
                ));
            }
            out.push(set.clone());
        }
        Ok(out)
    }
}

/// `[sweep]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SweepConfig {
    /// Number of Latin hypercube starts. Default 256.
    pub starts: usize,
    /// Seed of the start sequence. Default 1.
    pub seed: u64,
    /// Also start from the configured start / initial guess. Default true.
    pub include_guess: bool,
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            starts: 256,
            seed: 1,
            include_guess: true,
        }
    }
}

/// `[solver]`: the ODE integration and the local least-squares iteration limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SolverConfig {
    /// Relative tolerance of the integrator. Default 1e-8, from the accuracy study in README.md
    /// (`scripts/tolerance_study.sh`): the objective is then within 1e-7 relative of its
    /// tight-tolerance value and the fit reaches the same minimum to 1e-7, 1.7× faster than
    /// at 1e-10.
    pub rtol: f64,
    /// Absolute tolerance of the integrator. Default 1e-13.
    pub atol: f64,
    /// Iteration limit of a local fit. Default 200.
    pub max_iterations: usize,
    /// Relative objective change at which a local fit has converged. Default 1e-8: the
    /// objective itself is accurate to about 1e-7 at the default `rtol`, and smaller changes
    /// only chase integration error (README.md, "Speed").
    pub ftol: f64,
    /// Geodesic acceleration of the Levenberg–Marquardt steps (Transtrum & Sethna 2012):
    /// follows the curved, nearly flat valleys of this objective in a third of the
    /// iterations. Default true.
    pub geodesic: bool,
    /// Jacobian of the local fits: "sensitivity" (default) or "finite_difference".
    pub jacobian: JacobianMethod,
}

impl Default for SolverConfig {
    fn default() -> Self {
        SolverConfig {
            rtol: 1e-8,
            atol: 1e-13,
            max_iterations: 200,
            ftol: 1e-8,
            geodesic: true,
            jacobian: JacobianMethod::default(),
        }
    }
}

/// A validated run configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct RunConfig {
    /// The configuration file itself.
    pub path: PathBuf,
    /// Run name (outputs go to `results/<name>/`). Default: the file's stem.
    pub name: String,
    /// Curves CSV, resolved against the configuration's directory.
    pub curves: PathBuf,
    /// Ruptures CSV, resolved against the configuration's directory.
    pub ruptures: PathBuf,
    /// Keep only curves at this temperature (°C).
    pub temperature_c: Option<f64>,
    /// Model registry name. Default `khd`.
    pub model: String,
    /// Extension names (none implemented yet).
    pub extensions: Vec<String>,
    /// Stresses (MPa) of tests declared interrupted.
    pub interrupted: Vec<f64>,
    /// Constants in the model's order.
    pub constants: Vec<ConstantConfig>,
    /// `[objective]`.
    pub objective: ObjectiveConfig,
    /// `[sweep]`.
    pub sweep: SweepConfig,
    /// `[solver]`.
    pub solver: SolverConfig,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConfig {
    name: Option<String>,
    curves: PathBuf,
    ruptures: PathBuf,
    #[serde(rename = "temperature_C")]
    temperature_c: Option<f64>,
    #[serde(default = "default_model")]
    model: String,
    #[serde(default)]
    extensions: Vec<String>,
    #[serde(default)]
    interrupted: Vec<f64>,
    #[serde(default)]
    constants: BTreeMap<String, RawConstant>,
    #[serde(default)]
    objective: ObjectiveConfig,
    #[serde(default)]
    sweep: SweepConfig,
    #[serde(default)]
    solver: SolverConfig,
}

fn default_model() -> String {
    "khd".to_string()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConstant {
    lb: f64,
    ub: f64,
    start: Option<f64>,
    scale: Option<Scale>,
}

impl RunConfig {
    /// Read and validate a configuration file.
    pub fn load(path: &Path) -> Result<RunConfig> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_str(&text, path)
    }

    /// Parse and validate configuration `text`; `path` locates relative data paths and names
    /// the file in errors.
    pub fn from_str(text: &str, path: &Path) -> Result<RunConfig> {
        let raw: RawConfig = toml::from_str(text).map_err(|e| toml_error(text, path, &e))?;
        let err = |msg: String| Error::config(path, msg);

        model::registry(&raw.model).map_err(|e| err(format!("model: {e}")))?;
        for (i, ext) in raw.extensions.iter().enumerate() {
            if !EXTENSION_NAMES.contains(&ext.as_str()) {
                return Err(err(format!(
                    "extensions: unknown extension '{ext}' (known: {})",
                    EXTENSION_NAMES.join(", ")
                )));
            }
            if raw.extensions[..i].contains(ext) {
                return Err(err(format!("extensions: '{ext}' is listed twice")));
            }
        }
        let m = model::build(&raw.model, &raw.extensions)
            .map_err(|e| err(format!("extensions: {e}")))?;

        let specs = m.constants();
        for name in raw.constants.keys() {
            if !specs.iter().any(|s| s.name == name) {
                return Err(err(format!(
                    "constants: unknown constant '{name}' for model '{}' (known: {})",
                    raw.model,
                    specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
                )));
            }
        }
        let mut constants = Vec::with_capacity(specs.len());
        for s in specs {
            let c = match raw.constants.get(s.name) {
                Some(r) => ConstantConfig {
                    name: s.name.to_string(),
                    unit: s.unit,
                    lb: r.lb,
                    ub: r.ub,
                    start: r.start,
                    scale: r.scale.unwrap_or(s.scale),
                },
                None => ConstantConfig {
                    name: s.name.to_string(),
                    unit: s.unit,
                    lb: s.lb,
                    ub: s.ub,
                    start: None,
                    scale: s.scale,
                },
            };
            validate_constant(&c).map_err(|m| err(format!("constants.{}: {m}", c.name)))?;
            constants.push(c);
        }

        if let Some(t) = raw.temperature_c {
            if !t.is_finite() {
                return Err(err(format!("temperature_C: must be finite (got {t})")));
            }
        }
        for &s in &raw.interrupted {
            if !(s.is_finite() && s > 0.0) {
                return Err(err(format!(
                    "interrupted: stresses must be positive and finite (got {s})"
                )));
            }
        }
        validate_objective(&raw.objective).map_err(|m| err(format!("objective.{m}")))?;
        if raw.sweep.starts == 0 {
            return Err(err("sweep.starts: must be at least 1".into()));
        }
        let sv = &raw.solver;
        for (k, v) in [("rtol", sv.rtol), ("atol", sv.atol)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(err(format!("solver.{k}: must be positive (got {v})")));
            }
        }
        if !(sv.ftol > 0.0 && sv.ftol < 1.0) {
            return Err(err(format!(
                "solver.ftol: must be in (0, 1) (got {})",
                sv.ftol
            )));
        }
        if sv.max_iterations == 0 {
            return Err(err("solver.max_iterations: must be at least 1".into()));
        }

        let dir = path.parent().unwrap_or(Path::new(""));
        let name = match raw.name {
            Some(n) if n.trim().is_empty() => return Err(err("name: must not be empty".into())),
            Some(n) => n,
            None => path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "run".into()),
        };
        Ok(RunConfig {
            path: path.to_path_buf(),
            name,
            curves: dir.join(&raw.curves),
            ruptures: dir.join(&raw.ruptures),
            temperature_c: raw.temperature_c,
            model: raw.model,
            extensions: raw.extensions,
            interrupted: raw.interrupted,
            constants,
            objective: raw.objective,
            sweep: raw.sweep,
            solver: raw.solver,
        })
    }

    /// Options for [`data::load`]: the temperature filter and the interrupted tests.
    pub fn load_options(&self) -> LoadOptions {
        LoadOptions {
            temperature_c: self.temperature_c,
            interrupted: self.interrupted.clone(),
            ..LoadOptions::default()
        }
    }

    /// Load the run's data ([`data::load`] with [`RunConfig::load_options`]).
    pub fn load_data(&self) -> Result<Dataset> {
        data::load(&self.curves, &self.ruptures, &self.load_options())
    }

    /// The start vector (model order) if every constant has a start, else `None`.
    pub fn starts_all_given(&self) -> Option<Vec<f64>> {
        self.constants.iter().map(|c| c.start).collect()
    }

    /// Lower bounds, model order.
    pub fn lower(&self) -> Vec<f64> {
        self.constants.iter().map(|c| c.lb).collect()
    }

    /// Upper bounds, model order.
    pub fn upper(&self) -> Vec<f64> {
        self.constants.iter().map(|c| c.ub).collect()
    }

    /// Scales, model order.
    pub fn scales(&self) -> Vec<Scale> {
        self.constants.iter().map(|c| c.scale).collect()
    }

    /// Constant names, model order.
    pub fn constant_names(&self) -> Vec<&str> {
        self.constants.iter().map(|c| c.name.as_str()).collect()
    }
}

fn validate_constant(c: &ConstantConfig) -> std::result::Result<(), String> {
    if !c.lb.is_finite() || !c.ub.is_finite() {
        return Err(format!(
            "bounds must be finite (lb = {}, ub = {})",
            c.lb, c.ub
        ));
    }
    if c.lb >= c.ub {
        return Err(format!("lb ({}) must be below ub ({})", c.lb, c.ub));
    }
    if c.scale == Scale::Log && c.lb <= 0.0 {
        return Err(format!("scale \"log\" needs lb > 0 (lb = {})", c.lb));
    }
    if let Some(s) = c.start {
        if !(s >= c.lb && s <= c.ub) {
            return Err(format!(
                "start ({s}) is outside the bounds [{}, {}]",
                c.lb, c.ub
            ));
        }
    }
    Ok(())
}

fn validate_objective(o: &ObjectiveConfig) -> std::result::Result<(), String> {
    if o.w_grid.is_empty() && o.w_sets.is_empty() {
        return Err("w_grid: w_grid and w_sets are both empty; give at least one weight".into());
    }
    for &w in &o.w_grid {
        if !(w.is_finite() && w >= 0.0) {
            return Err(format!(
                "w_grid: weights must be finite and non-negative (got {w})"
            ));
        }
    }
    for (k, set) in o.w_sets.iter().enumerate() {
        if set.is_empty() {
            return Err(format!("w_sets[{k}]: empty weight set"));
        }
        for &w in set {
            if !(w.is_finite() && w >= 0.0) {
                return Err(format!(
                    "w_sets[{k}]: weights must be finite and non-negative (got {w})"
                ));
            }
        }
    }
    if !(o.omega_f > 0.0 && o.omega_f < 1.0) {
        return Err(format!("omega_f: must be in (0, 1) (got {})", o.omega_f));
    }
    Ok(())
}

/// toml's error as one line: `line N: message`.
fn toml_error(text: &str, path: &Path, e: &toml::de::Error) -> Error {
    let msg = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let line = text[..span.start.min(text.len())].matches('\n').count() + 1;
            Error::config(path, format!("line {line}: {msg}"))
        }
        None => Error::config(path, msg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FULL: &str = r#"
name = "t"
curves = "../data/c.csv"
ruptures = "r.csv"
temperature_C = 560
model = "khd"
extensions = []
interrupted = [70]

[constants]
A     = { lb = 1e-10, ub = 1e-9, start = 1e-9,   scale = "log" }
B     = { lb = 0.1,   ub = 0.2,  start = 0.11 }
C     = { lb = 3,     ub = 10,   start = 4.311 }

[objective]
w_grid = [0.5, 1.0]
w_sets = [[0.12, 0.12, 1.0]]
lifetime_term = "both"
omega_f = 0.3

[sweep]
starts = 10
seed = 7

[solver]
rtol = 1e-8
"#;

    fn parse(text: &str) -> Result<RunConfig> {
        RunConfig::from_str(text, Path::new("cfg/run.toml"))
    }

    #[test]
    fn full_config() {
        let c = parse(FULL).unwrap();
        assert_eq!(c.name, "t");
        assert_eq!(c.curves, Path::new("cfg/../data/c.csv"));
        assert_eq!(c.ruptures, Path::new("cfg/r.csv"));
        assert_eq!(c.temperature_c, Some(560.0));
        assert_eq!(c.interrupted, vec![70.0]);
        assert_eq!(c.constant_names(), ["A", "B", "Hstar", "h", "Kc", "C"]);
        assert_eq!(c.constants[0].scale, Scale::Log);
        assert_eq!(c.constants[1].scale, Scale::Linear);
        assert_eq!(c.constants[5].lb, 3.0);
        assert_eq!(c.constants[5].start, Some(4.311));
        // Hstar not given: spec defaults, no start
        assert_eq!(c.constants[2].start, None);
        assert_eq!(c.constants[2].lb, 0.4);
        assert_eq!(c.constants[3].scale, Scale::Log);
        assert_eq!(c.starts_all_given(), None);
        assert_eq!(c.objective.lifetime_term, LifetimeTerm::Both);
        assert_eq!(c.objective.omega_f, 0.3);
        assert_eq!(c.sweep.starts, 10);
        assert_eq!(c.sweep.seed, 7);
        assert!(c.sweep.include_guess);
        assert_eq!(c.solver.rtol, 1e-8);
        assert_eq!(c.solver.atol, 1e-13);
        let w = c.objective.weight_vectors(3, &c.path).unwrap();
        assert_eq!(w.len(), 3);
        assert_eq!(w[0], vec![0.5; 3]);
        assert_eq!(w[2], vec![0.12, 0.12, 1.0]);
        assert!(c.objective.weight_vectors(2, &c.path).is_err());
        assert_eq!(c.load_options().interrupted, vec![70.0]);
    }

    #[test]
    fn defaults() {
        let c = parse("curves = \"a.csv\"\nruptures = \"b.csv\"\n").unwrap();
        assert_eq!(c.name, "run");
        assert_eq!(c.model, "khd");
        assert_eq!(c.objective.w_grid.len(), 10);
        assert_eq!(c.objective.w_grid[2], 0.3);
        assert_eq!(c.objective.w_grid[9], 1.0);
        assert!(c.objective.w_sets.is_empty());
        assert_eq!(c.objective.lifetime_term, LifetimeTerm::Late);
        assert_eq!(c.objective.omega_f, 1.0 / 3.0);
        assert_eq!(c.sweep.starts, 256);
        assert_eq!(c.sweep.seed, 1);
        assert_eq!(c.solver.max_iterations, 200);
        assert_eq!(c.solver.ftol, 1e-8);
        assert!(c.solver.geodesic);
        assert_eq!(c.constants.len(), 6);
    }

    fn err_of(text: &str) -> String {
        let e = parse(text).unwrap_err().to_string();
        assert!(!e.contains('\n'), "multi-line error: {e}");
        assert!(e.starts_with("cfg/run.toml: "), "{e}");
        e
    }

    #[test]
    fn errors() {
        let base = "curves = \"a.csv\"\nruptures = \"b.csv\"\n";
        let cases: &[(&str, &str)] = &[
            ("bogus = 1\n", "line 3: unknown field `bogus`"),
            ("model = \"nope\"\n", "unknown model 'nope'"),
            (
                "extensions = [\"constant_load\", \"constant_load\"]\n",
                "'constant_load' is listed twice",
            ),
            (
                "extensions = [\"loading_strain\"]\n[constants]\nEL = { lb = 2, ub = 1 }\n",
                "constants.EL",
            ),
            ("extensions = [\"foo\"]\n", "unknown extension 'foo'"),
            (
                "[constants]\nX = { lb = 1, ub = 2 }\n",
                "unknown constant 'X'",
            ),
            (
                "[constants]\nB = { lb = 1, ub = 2, foo = 3 }\n",
                "unknown field `foo`",
            ),
            (
                "[constants]\nB = { lb = 2, ub = 1 }\n",
                "constants.B: lb (2) must be below ub (1)",
            ),
            (
                "[constants]\nB = { lb = 1, ub = inf }\n",
                "constants.B: bounds must be finite",
            ),
            (
                "[constants]\nB = { lb = 0, ub = 1, scale = \"log\" }\n",
                "constants.B: scale \"log\" needs lb > 0",
            ),
            (
                "[constants]\nB = { lb = 0, ub = 1, start = 2 }\n",
                "constants.B: start (2) is outside",
            ),
            (
                "[constants]\nB = { lb = 0, ub = 1, scale = \"ln\" }\n",
                "unknown variant `ln`",
            ),
            (
                "[objective]\nw_grid = []\n",
                "objective.w_grid: w_grid and w_sets are both empty",
            ),
            (
                "[objective]\nw_grid = [-0.1]\n",
                "objective.w_grid: weights must be finite and non-negative",
            ),
            ("[objective]\nw_sets = [[1, -1]]\n", "objective.w_sets[0]"),
            (
                "[objective]\nomega_f = 1.0\n",
                "objective.omega_f: must be in (0, 1)",
            ),
            (
                "[objective]\nlifetime_term = \"early\"\n",
                "unknown variant `early`",
            ),
            ("[solver]\nrtol = 0\n", "solver.rtol: must be positive"),
            ("[solver]\nftol = 1\n", "solver.ftol: must be in (0, 1)"),
            ("[solver]\natol = -1e-3\n", "solver.atol: must be positive"),
            ("[sweep]\nstarts = 0\n", "sweep.starts: must be at least 1"),
            ("[sweep]\nthreads = 2\n", "unknown field `threads`"),
        ];
        for (extra, want) in cases {
            let e = err_of(&format!("{base}{extra}"));
            assert!(e.contains(want), "for {extra:?}: got {e}, want {want}");
        }
        let e = err_of("ruptures = \"b.csv\"\n");
        assert!(e.contains("missing field `curves`"), "{e}");
    }
}
