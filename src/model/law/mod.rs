//! Temperature laws of the constants (DESIGN.md §8): a constant c may depend on the test
//! temperature T through a law with its own parameter, fitted with the other constants:
//!
//! | law | c(T) | parameter |
//! |---|---|---|
//! | `constant` (default) | c_ref | — |
//! | `arrhenius` | c_ref · exp(−(Q/R)(1/T − 1/T_ref)) | `Q`, kJ/mol |
//! | `linear` | c_ref + s·(T − T_ref) | `slope`, the constant's unit per K |
//!
//! c_ref is the value at the reference temperature T_ref (a configuration value; by default
//! the mean test temperature, so that c_ref and the law's parameter are not collinear), and
//! the bounds of the constant apply to c_ref. The law's parameter is a constant of its own,
//! named `<constant>.<parameter>` (e.g. `A.Q`), following the model's constants.
//!
//! A law is one file here (its formula, its parameter and the regression that turns
//! per-temperature values into c_ref and the parameter, for the initial guess) and its line
//! in [`LawKind`]'s methods. [`WithLaws`] applies the laws of a configuration to any model:
//! before every simulation it computes the constants at the test's temperature
//! ([`crate::model::Load::temperature_k`]) and integrates the model with them, in `f64` or in
//! dual numbers alike, so the sensitivities include ∂/∂Q.

pub mod arrhenius;
pub mod constant;
pub mod linear;

use std::collections::HashSet;
use std::sync::Mutex;

use serde::{Deserialize, Serialize};

use super::{ConstantSpec, Load, Model, Scale, ZERO_CELSIUS_K};
use crate::data::Curve;
use crate::dual::{Dual, Scalar, SENS, SENS_WIDE};
use crate::model::guess::Guess;
use crate::model::objective::{ParamSpace, SimScalar, MAX_PARAMS};
use crate::ode::{OdeOptions, SimResult};

/// The temperature law of one constant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LawKind {
    /// No temperature dependence.
    #[default]
    Constant,
    /// c_ref · exp(−(Q/R)(1/T − 1/T_ref)).
    Arrhenius,
    /// c_ref + s·(T − T_ref).
    Linear,
}

/// Names of the laws, as in configurations.
pub const LAW_NAMES: &[&str] = &[constant::NAME, arrhenius::NAME, linear::NAME];

impl LawKind {
    /// Every law.
    pub const ALL: [LawKind; 3] = [LawKind::Constant, LawKind::Arrhenius, LawKind::Linear];

    /// Registry name.
    pub fn name(self) -> &'static str {
        match self {
            LawKind::Constant => constant::NAME,
            LawKind::Arrhenius => arrhenius::NAME,
            LawKind::Linear => linear::NAME,
        }
    }

    /// The law of a name.
    pub fn from_name(name: &str) -> Option<LawKind> {
        Self::ALL.into_iter().find(|l| l.name() == name)
    }

    /// Name of the law's parameter (`None` for `constant`).
    pub fn param(self) -> Option<&'static str> {
        match self {
            LawKind::Constant => None,
            LawKind::Arrhenius => Some(arrhenius::PARAM),
            LawKind::Linear => Some(linear::PARAM),
        }
    }

    /// Unit of the parameter for a constant in `unit`.
    pub fn param_unit(self, unit: &str) -> String {
        match self {
            LawKind::Constant => String::new(),
            LawKind::Arrhenius => arrhenius::UNIT.to_string(),
            LawKind::Linear if unit == "-" => "1/K".to_string(),
            LawKind::Linear => format!("{unit}/K"),
        }
    }

    /// Default bounds of the parameter for a constant boxed in [lb, ub].
    pub fn default_bounds(self, lb: f64, ub: f64) -> (f64, f64) {
        match self {
            LawKind::Constant => (0.0, 0.0),
            LawKind::Arrhenius => arrhenius::DEFAULT_BOUNDS,
            LawKind::Linear => linear::default_bounds(lb, ub),
        }
    }

    /// c(T) from c_ref and the parameter `p` (ignored by `constant`), T and T_ref in K.
    #[inline(always)]
    pub fn eval<S: Scalar>(self, c_ref: S, p: S, t_k: f64, t_ref_k: f64) -> S {
        if t_k == t_ref_k {
            // Exactly the reference value, whatever the parameter.
            return c_ref;
        }
        match self {
            LawKind::Constant => constant::eval(c_ref),
            LawKind::Arrhenius => arrhenius::eval(c_ref, p, t_k, t_ref_k),
            LawKind::Linear => linear::eval(c_ref, p, t_k, t_ref_k),
        }
    }

    /// The range of c(T) at `t_k` over c_ref in `c` = (lb, ub) and the parameter in `p`.
    pub fn range_at(self, c: (f64, f64), p: (f64, f64), t_k: f64, t_ref_k: f64) -> (f64, f64) {
        let corners = [
            self.eval(c.0, p.0, t_k, t_ref_k),
            self.eval(c.0, p.1, t_k, t_ref_k),
            self.eval(c.1, p.0, t_k, t_ref_k),
            self.eval(c.1, p.1, t_k, t_ref_k),
        ];
        let lo = corners.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = corners.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    }

    /// (c_ref, parameter) from values of the constant at the temperatures `t_k`: the law's
    /// regression (with `held` the parameter is known and only c_ref is fitted; `log` says
    /// the constant is on a log scale, for `constant`'s mean). `None` when the law cannot be
    /// fitted to these values (one temperature and a free parameter, non-positive values of
    /// an Arrhenius constant).
    pub fn fit(
        self,
        t_k: &[f64],
        values: &[f64],
        t_ref_k: f64,
        held: Option<f64>,
        log: bool,
    ) -> Option<(f64, f64)> {
        if values.len() == 1 {
            // One value: c_ref from the known (or given) parameter, exactly the value at T_ref.
            let p = held?;
            let (t, v) = (t_k[0], values[0]);
            return match self {
                LawKind::Constant => Some((v, 0.0)),
                LawKind::Arrhenius => Some((v / arrhenius::factor(p, t, t_ref_k), p)),
                LawKind::Linear => Some((v - p * (t - t_ref_k), p)),
            };
        }
        match self {
            LawKind::Constant => Some((constant::fit(values, log), 0.0)),
            LawKind::Arrhenius => arrhenius::fit(t_k, values, t_ref_k, held),
            LawKind::Linear => linear::fit(t_k, values, t_ref_k, held),
        }
    }
}

/// A `&'static str` for a name made at run time (`A.Q`, `1/MPa/K`): each distinct string is
/// leaked once, so the set stays as small as the set of names used.
pub fn intern(s: &str) -> &'static str {
    static NAMES: Mutex<Option<HashSet<&'static str>>> = Mutex::new(None);
    let mut guard = NAMES.lock().expect("intern lock");
    let set = guard.get_or_insert_with(HashSet::new);
    if let Some(&k) = set.get(s) {
        return k;
    }
    let k: &'static str = Box::leak(s.to_string().into_boxed_str());
    set.insert(k);
    k
}

/// Name of the law parameter of constant `constant`, e.g. `A.Q`.
pub fn param_name(constant: &str, law: LawKind) -> Option<String> {
    law.param().map(|p| format!("{constant}.{p}"))
}

/// The constants of a model with laws: the model's own (`inner`), then, for each of them
/// whose law has a parameter (in the model's order), that parameter with its default
/// bounds.
pub fn constants_with_laws(inner: &[ConstantSpec], laws: &[LawKind]) -> Vec<ConstantSpec> {
    let mut out = inner.to_vec();
    for (c, &law) in inner.iter().zip(laws) {
        if let Some(name) = param_name(c.name, law) {
            let (lb, ub) = law.default_bounds(c.lb, c.ub);
            out.push(ConstantSpec {
                name: intern(&name),
                unit: intern(&law.param_unit(c.unit)),
                lb,
                ub,
                default: 0.0f64.clamp(lb, ub),
                scale: Scale::Linear,
                role: super::Role::Other,
                doc: match law {
                    LawKind::Arrhenius => "activation energy of the constant's Arrhenius law",
                    _ => "slope of the constant's linear temperature law",
                },
            });
        }
    }
    out
}

/// Where the laws sit in a parameter vector.
#[derive(Debug, Clone, PartialEq)]
pub struct Laws {
    /// Law of each of the model's own constants (model order).
    pub kinds: Vec<LawKind>,
    /// Index of each constant's law parameter in the parameter vector (`None` for
    /// `constant`).
    pub param: Vec<Option<usize>>,
    /// Reference temperature, K.
    pub t_ref_k: f64,
}

impl Laws {
    /// The laws `kinds` of a model's constants, parameters in the order of
    /// [`constants_with_laws`], with reference temperature `t_ref_c` (°C).
    pub fn new(kinds: Vec<LawKind>, t_ref_c: f64) -> Laws {
        let mut next = kinds.len();
        let param = kinds
            .iter()
            .map(|l| {
                l.param().map(|_| {
                    next += 1;
                    next - 1
                })
            })
            .collect();
        Laws {
            kinds,
            param,
            t_ref_k: t_ref_c + ZERO_CELSIUS_K,
        }
    }

    /// Number of the model's own constants.
    pub fn n_inner(&self) -> usize {
        self.kinds.len()
    }

    /// The model's constants at temperature `t_k` (K) from the full parameter vector.
    #[inline]
    pub fn at<S: Scalar>(&self, params: &[S], t_k: f64, out: &mut [S]) {
        for j in 0..self.kinds.len() {
            out[j] = match self.param[j] {
                Some(p) => self.kinds[j].eval(params[j], params[p], t_k, self.t_ref_k),
                None => params[j],
            };
        }
    }
}

/// A model whose constants follow temperature laws: the constants of the inner model are
/// computed at each test's temperature before it is integrated.
pub struct WithLaws {
    name: String,
    inner: Box<dyn Model>,
    constants: Vec<ConstantSpec>,
    laws: Laws,
}

/// `inner` with the laws `kinds` (one per constant of `inner`) about `t_ref_c` (°C); `inner`
/// itself when every law is `constant` (nothing changes, bit for bit).
pub fn with_laws(inner: Box<dyn Model>, kinds: &[LawKind], t_ref_c: f64) -> Box<dyn Model> {
    assert_eq!(kinds.len(), inner.constants().len(), "one law per constant");
    if kinds.iter().all(|k| *k == LawKind::Constant) {
        return inner;
    }
    let constants = constants_with_laws(inner.constants(), kinds);
    let which: Vec<String> = inner
        .constants()
        .iter()
        .zip(kinds)
        .filter(|(_, k)| **k != LawKind::Constant)
        .map(|(c, k)| format!("{} {}", c.name, k.name()))
        .collect();
    Box::new(WithLaws {
        name: format!(
            "{} [{}; T_ref {} °C]",
            inner.name(),
            which.join(", "),
            t_ref_c
        ),
        inner,
        constants,
        laws: Laws::new(kinds.to_vec(), t_ref_c),
    })
}

impl WithLaws {
    fn run<S: SimScalar>(
        &self,
        params: &[S],
        load: &Load,
        times: &[f64],
        strain_out: &mut [S],
        opts: &OdeOptions,
    ) -> SimResult<S> {
        let n = self.laws.n_inner();
        let mut at = [S::cst(0.0); MAX_PARAMS];
        self.laws.at(params, load.temperature_k, &mut at[..n]);
        S::simulate(self.inner.as_ref(), &at[..n], load, times, strain_out, opts)
    }

    /// The laws.
    pub fn laws(&self) -> &Laws {
        &self.laws
    }
}

impl Model for WithLaws {
    fn name(&self) -> &str {
        &self.name
    }
    fn constants(&self) -> &[ConstantSpec] {
        &self.constants
    }
    fn simulate(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        strain_out: &mut [f64],
        opts: &OdeOptions,
    ) -> SimResult {
        self.run(params, load, times, strain_out, opts)
    }
    fn simulate_sens(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>> {
        self.run(params, load, times, strain_out, opts)
    }
    fn simulate_sens_wide(
        &self,
        params: &[Dual<SENS_WIDE>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS_WIDE>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS_WIDE>> {
        self.run(params, load, times, strain_out, opts)
    }
    fn simulate_sens_each(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        each: &mut dyn FnMut(usize, &[Dual<SENS>]),
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>> {
        let n = self.laws.n_inner();
        let mut at = [Dual::cst(0.0); MAX_PARAMS];
        self.laws.at(params, load.temperature_k, &mut at[..n]);
        self.inner
            .simulate_sens_each(&at[..n], load, times, each, opts)
    }
    fn trajectory(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        opts: &OdeOptions,
    ) -> (SimResult, Vec<(f64, f64, Vec<f64>)>) {
        let n = self.laws.n_inner();
        let mut at = [0.0; MAX_PARAMS];
        self.laws.at(params, load.temperature_k, &mut at[..n]);
        self.inner.trajectory(&at[..n], load, times, opts)
    }
    fn output_names(&self) -> Vec<&'static str> {
        self.inner.output_names()
    }
    fn guess_procedure(&self) -> Option<crate::model::guess::GuessFn> {
        None
    }
    fn initial_guess(
        &self,
        curves: &[Curve],
        space: &ParamSpace,
        omega_f: f64,
        ode: &OdeOptions,
    ) -> Guess {
        crate::model::guess::per_temperature(
            self.inner.as_ref(),
            &self.laws,
            curves,
            space,
            omega_f,
            ode,
        )
    }
    fn constants_at(&self, params: &[f64], temperature_c: f64) -> Vec<f64> {
        let n = self.laws.n_inner();
        let mut at = vec![0.0; n];
        self.laws
            .at(params, temperature_c + ZERO_CELSIUS_K, &mut at);
        at
    }
    fn inner_constants(&self) -> &[ConstantSpec] {
        self.inner.constants()
    }
    fn as_dyn(&self) -> &dyn Model {
        self
    }
}
