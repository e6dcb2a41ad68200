//! Constitutive models: the [`CreepModel`] trait that the integrator is monomorphised over,
//! the object-safe [`Model`] that the fit and the commands use, and the registry by name.
//!
//! A model exposes its constants ([`ConstantSpec`]: name, unit, default bounds, scale), a
//! per-simulation preparation of derived constants, the right-hand side, the rupture event
//! and the strain read-out. Adding an extension means one file that implements
//! [`CreepModel`] plus one line in [`registry`].

pub mod ext;
pub mod guess;
mod khd;
pub mod khd_guess;
pub mod kr;
pub mod law;
pub mod objective;

pub use ext::KhdExtended;
pub use khd::{Khd, KhdReduced};
pub use law::{with_laws, LawKind, WithLaws};

use crate::data::Curve;
use crate::dual::{Dual, Scalar, SENS, SENS_WIDE};
use crate::error::{Error, Result};
use crate::model::guess::{Guess, GuessFn};
use crate::model::objective::ParamSpace;
use crate::ode::{self, OdeOptions, SimResult};

/// How a constant is mapped to the optimiser's unit box.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Scale {
    /// u = (x − lb)/(ub − lb)
    #[default]
    Linear,
    /// u = (ln x − ln lb)/(ln ub − ln lb); for constants that span decades (needs lb > 0).
    Log,
}

/// Description of one material constant of a model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantSpec {
    /// Name as used in configurations and output files (e.g. `Hstar`).
    pub name: &'static str,
    /// Physical unit (`1/h`, `1/MPa`, `MPa`, `-`).
    pub unit: &'static str,
    /// Default lower bound (used when a configuration does not give one).
    pub lb: f64,
    /// Default upper bound.
    pub ub: f64,
    /// Default value (start when nothing else is known).
    pub default: f64,
    /// Default scale in the optimiser.
    pub scale: Scale,
    /// One line on what the constant does.
    pub doc: &'static str,
    /// What a specimen's own value of it means ([`Role`]): where specimen-to-specimen
    /// scatter of the creep rate and of the ductility enters the model.
    pub role: Role,
}

/// The part a constant plays for specimen effects (random effects in the error model): a
/// specimen's own creep rate is the population's rate constant times a factor, its own
/// ductility the population's inverse-ductility constant divided by one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Role {
    /// No specimen effect acts through it.
    #[default]
    Other,
    /// Multiplying it by f multiplies the creep rate by f (KHD: A).
    Rate,
    /// Dividing it by g multiplies the rupture strain by g (KHD: C, ε_r = ω_f/C).
    InverseDuctility,
    /// The rate of the softening that brings on the tertiary stage (KHD: Kc).
    Softening,
}

pub use crate::data::ZERO_CELSIUS_K;

/// The conditions of one test: nominal stress, temperature and the damage at rupture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Load {
    /// Nominal (initial) stress, MPa.
    pub stress_mpa: f64,
    /// Test temperature, K (the temperature laws of the constants read it; a model without
    /// laws ignores it).
    pub temperature_k: f64,
    /// Damage at rupture ω_f (the paper: 1/3).
    pub omega_f: f64,
}

impl Load {
    /// The load at `stress_mpa` (MPa) and `temperature_c` (°C, as in the files).
    pub fn new(stress_mpa: f64, temperature_c: f64, omega_f: f64) -> Load {
        Load {
            stress_mpa,
            temperature_k: temperature_c + ZERO_CELSIUS_K,
            omega_f,
        }
    }

    /// The load of a measured curve: its stress and temperature.
    pub fn of_curve(c: &crate::data::Curve, omega_f: f64) -> Load {
        Load::new(c.stress_mpa, c.temperature_c, omega_f)
    }

    /// The temperature in °C.
    pub fn temperature_c(&self) -> f64 {
        self.temperature_k - ZERO_CELSIUS_K
    }
}

/// A constitutive model with an `N`-component state, integrated by [`crate::ode`].
///
/// Generic over the number type [`Scalar`]: `f64` for plain simulation, [`Dual`] to carry the
/// derivatives with respect to the constants (forward sensitivities) through the same code.
/// Domain checks look at value parts only. All methods are called in the integrator's hot
/// loop: they must not allocate.
pub trait CreepModel<const N: usize>: Send + Sync {
    /// Constants derived once per simulation from the material constants and the load.
    type Prepared<S: Scalar>: Copy;
    /// Derive the per-simulation constants; `params` follow [`Model::constants`].
    fn prepare<S: Scalar>(&self, params: &[S], load: &Load) -> Self::Prepared<S>;
    /// State at t = 0.
    fn init<S: Scalar>(&self, p: &Self::Prepared<S>) -> [S; N];
    /// Right-hand side dy/dt at (t, y), t in h. Returns `false` when the state is outside the
    /// model's domain or the rate is non-finite or absurd (a trial step past rupture): the
    /// integrator then rejects the step and shrinks it.
    fn rhs<S: Scalar>(&self, p: &Self::Prepared<S>, t: S, y: &[S; N], dy: &mut [S; N]) -> bool;
    /// The part of the right-hand side that depends on time alone (the coarsening factor
    /// (1 + Kc·t)^(1/3) = 1/(1 − Φ) of the one-state models); zero for models without one.
    /// The integrator evaluates it for all stages of a step before the stages, off their
    /// chain of dependencies: a cube root inside the chain cost a third of the step.
    #[inline(always)]
    fn time_part<S: Scalar>(&self, _p: &Self::Prepared<S>, _t: S) -> S {
        S::cst(0.0)
    }
    /// [`CreepModel::rhs`] given `tp` = [`CreepModel::time_part`] at `t`.
    #[inline(always)]
    fn rhs_tp<S: Scalar>(
        &self,
        p: &Self::Prepared<S>,
        t: S,
        _tp: S,
        y: &[S; N],
        dy: &mut [S; N],
    ) -> bool {
        self.rhs(p, t, y, dy)
    }
    /// Rupture event function: negative before rupture, zero at rupture (ω − ω_f).
    fn event<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N]) -> S;
    /// Time derivative of [`CreepModel::event`] along the solution, given dy/dt (used to carry
    /// the rupture time's sensitivity: dt_r = −g/ġ).
    fn event_rate<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N], dy: &[S; N]) -> S;
    /// Total strain (fraction) read from the state.
    fn strain<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N]) -> S;
    /// Strain rate (1/h) from the state and its derivative.
    fn strain_rate<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N], dy: &[S; N]) -> S;
    /// Names of the state components.
    fn state_names(&self) -> [&'static str; N];
    /// Names of the quantities the model reports beside the strain (its output columns in
    /// `simulate`'s and `predict`'s `curves.csv`, e.g. H, Φ, ω for KHD); none by default.
    fn output_names(&self) -> &'static [&'static str] {
        &[]
    }
    /// The values of [`CreepModel::output_names`] at time `t` (h) and state `y`, appended to
    /// `out`.
    fn outputs(&self, _p: &Self::Prepared<f64>, _t: f64, _y: &[f64; N], _out: &mut Vec<f64>) {}
}

/// Every constitutive model is what the integrator integrates (the methods forward, inlined:
/// the integrator is monomorphised over the model as before).
impl<const N: usize, M: CreepModel<N>> ode::OdeSystem<N> for M {
    type Prepared<S: Scalar> = <M as CreepModel<N>>::Prepared<S>;
    #[inline(always)]
    fn init<S: Scalar>(&self, p: &Self::Prepared<S>) -> [S; N] {
        CreepModel::init(self, p)
    }
    #[inline(always)]
    fn rhs<S: Scalar>(&self, p: &Self::Prepared<S>, t: S, y: &[S; N], dy: &mut [S; N]) -> bool {
        CreepModel::rhs(self, p, t, y, dy)
    }
    #[inline(always)]
    fn time_part<S: Scalar>(&self, p: &Self::Prepared<S>, t: S) -> S {
        CreepModel::time_part(self, p, t)
    }
    #[inline(always)]
    fn rhs_tp<S: Scalar>(
        &self,
        p: &Self::Prepared<S>,
        t: S,
        tp: S,
        y: &[S; N],
        dy: &mut [S; N],
    ) -> bool {
        CreepModel::rhs_tp(self, p, t, tp, y, dy)
    }
    #[inline(always)]
    fn event<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N]) -> S {
        CreepModel::event(self, p, y)
    }
    #[inline(always)]
    fn event_rate<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N], dy: &[S; N]) -> S {
        CreepModel::event_rate(self, p, y, dy)
    }
    #[inline(always)]
    fn strain<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N]) -> S {
        CreepModel::strain(self, p, y)
    }
    #[inline(always)]
    fn strain_rate<S: Scalar>(&self, p: &Self::Prepared<S>, y: &[S; N], dy: &[S; N]) -> S {
        CreepModel::strain_rate(self, p, y, dy)
    }
}

/// Object-safe face of a model: what fits, reports and commands need.
pub trait Model: Send + Sync {
    /// Registry name, e.g. `khd`.
    fn name(&self) -> &str;
    /// The constants, in the order parameter vectors use.
    fn constants(&self) -> &[ConstantSpec];
    /// Integrate one test to rupture. `times` (h) must be sorted ascending; the predicted
    /// strain (fraction) at each time up to the rupture is written to `strain_out` (which has
    /// the length of `times`); entries after rupture are left untouched
    /// ([`SimResult::n_out`] says how many were written).
    fn simulate(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        strain_out: &mut [f64],
        opts: &OdeOptions,
    ) -> SimResult;
    /// [`Model::simulate`] in dual numbers: the predicted strains, rupture time, rupture strain
    /// and rate carry their derivatives with respect to the seeded constants (forward
    /// sensitivities, integrated with the same steps as the value).
    fn simulate_sens(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>>;
    /// [`Model::simulate_sens`] with the wide dual numbers, for more than [`SENS`] free
    /// constants.
    fn simulate_sens_wide(
        &self,
        params: &[Dual<SENS_WIDE>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS_WIDE>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS_WIDE>>;
    /// [`Model::simulate_sens`] handing the predicted strains to `each(k0, strains)` in
    /// order, in chunks (strains k0, k0 + 1, …), as the integrator produces them instead of
    /// storing them all, so that a streaming consumer (the normal equations of a fit to a
    /// logged curve of a million points) needs no dual-number buffer as long as the curve.
    /// The default goes through such a buffer.
    fn simulate_sens_each(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        each: &mut dyn FnMut(usize, &[Dual<SENS>]),
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>> {
        let mut buf = vec![Dual::cst(0.0); times.len()];
        let res = self.simulate_sens(params, load, times, &mut buf, opts);
        each(0, &buf[..res.n_out]);
        res
    }
    /// Integrate and return, at each of `times` up to rupture, the time, the strain and the
    /// model's outputs ([`Model::output_names`]), for reports.
    fn trajectory(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        opts: &OdeOptions,
    ) -> (SimResult, Vec<(f64, f64, Vec<f64>)>);
    /// Names of the quantities [`Model::trajectory`] reports beside the strain: the model's
    /// output columns (H, Phi, omega for KHD).
    fn output_names(&self) -> Vec<&'static str>;
    /// The model's own initial-guess procedure (from its registry entry), if it has one.
    fn guess_procedure(&self) -> Option<GuessFn>;
    /// Start constants for `curves` within `space`: the model's procedure, else the centre
    /// of the box (a model with temperature laws makes the guess per temperature).
    fn initial_guess(
        &self,
        curves: &[Curve],
        space: &ParamSpace,
        omega_f: f64,
        ode: &OdeOptions,
    ) -> Guess {
        match self.guess_procedure() {
            Some(g) => g(self.as_dyn(), curves, space, omega_f, ode),
            None => crate::model::guess::box_centre(space),
        }
    }
    /// The constants of the underlying model at `temperature_c` (°C) from a parameter
    /// vector: the parameters themselves for a model without temperature laws.
    fn constants_at(&self, params: &[f64], _temperature_c: f64) -> Vec<f64> {
        params.to_vec()
    }
    /// The constants of the underlying model (without the laws' parameters).
    fn inner_constants(&self) -> &[ConstantSpec] {
        self.constants()
    }
    /// This model as a trait object.
    fn as_dyn(&self) -> &dyn Model;
}

/// Adapts any [`CreepModel`] to the object-safe [`Model`]; the integration stays
/// monomorphised.
pub struct Integrated<M, const N: usize> {
    name: String,
    model: M,
    constants: Vec<ConstantSpec>,
    guess: Option<GuessFn>,
}

impl<M, const N: usize> Integrated<M, N> {
    /// Wrap `model` under a registry `name` with its `constants` (no guess procedure).
    pub fn new(name: impl Into<String>, model: M, constants: Vec<ConstantSpec>) -> Self {
        Integrated {
            name: name.into(),
            model,
            constants,
            guess: None,
        }
    }

    /// The same with the initial-guess procedure `guess`.
    pub fn with_guess(mut self, guess: Option<GuessFn>) -> Self {
        self.guess = guess;
        self
    }
}

impl<M: CreepModel<N>, const N: usize> Integrated<M, N> {
    /// Integrate in any number type, writing the strain at `times` into `strain_out`.
    fn run<S: Scalar>(
        &self,
        params: &[S],
        load: &Load,
        times: &[f64],
        strain_out: &mut [S],
        opts: &OdeOptions,
    ) -> SimResult<S> {
        let p = self.model.prepare(params, load);
        ode::integrate(&self.model, &p, times, opts, |k, _t, y| {
            strain_out[k] = self.model.strain(&p, y)
        })
    }
}

impl<M: CreepModel<N>, const N: usize> Model for Integrated<M, N> {
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
        // Chunks on the stack: the consumer's loop runs over a chunk, not one call a point.
        const CHUNK: usize = 256;
        let p = self.model.prepare(params, load);
        let mut buf = [Dual::cst(0.0); CHUNK];
        let (mut start, mut len) = (0, 0);
        let res = ode::integrate(&self.model, &p, times, opts, |k, _t, y| {
            if len == CHUNK {
                each(start, &buf);
                (start, len) = (k, 0);
            }
            buf[len] = self.model.strain(&p, y);
            len += 1;
        });
        each(start, &buf[..len]);
        res
    }
    fn trajectory(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        opts: &OdeOptions,
    ) -> (SimResult, Vec<(f64, f64, Vec<f64>)>) {
        let p = self.model.prepare(params, load);
        let mut out = Vec::with_capacity(times.len());
        let res = ode::integrate(&self.model, &p, times, opts, |_k, t, y| {
            let mut v = Vec::with_capacity(self.model.output_names().len());
            self.model.outputs(&p, t, y, &mut v);
            out.push((t, self.model.strain(&p, y), v))
        });
        (res, out)
    }
    fn output_names(&self) -> Vec<&'static str> {
        self.model.output_names().to_vec()
    }
    fn guess_procedure(&self) -> Option<GuessFn> {
        self.guess
    }
    fn as_dyn(&self) -> &dyn Model {
        self
    }
}

/// A model simulated through a cheaper exact reduction (the fast path) and reported through
/// its full form: fits and sweeps use `fast`; trajectories (H, Φ, ω for output) use `full`.
pub struct FastPath {
    name: &'static str,
    fast: Box<dyn Model>,
    full: Box<dyn Model>,
}

impl Model for FastPath {
    fn name(&self) -> &str {
        self.name
    }
    fn constants(&self) -> &[ConstantSpec] {
        self.full.constants()
    }
    fn simulate(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        strain_out: &mut [f64],
        opts: &OdeOptions,
    ) -> SimResult {
        self.fast.simulate(params, load, times, strain_out, opts)
    }
    fn simulate_sens(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>> {
        self.fast
            .simulate_sens(params, load, times, strain_out, opts)
    }
    fn simulate_sens_wide(
        &self,
        params: &[Dual<SENS_WIDE>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS_WIDE>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS_WIDE>> {
        self.fast
            .simulate_sens_wide(params, load, times, strain_out, opts)
    }
    fn simulate_sens_each(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        each: &mut dyn FnMut(usize, &[Dual<SENS>]),
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>> {
        self.fast
            .simulate_sens_each(params, load, times, each, opts)
    }
    fn trajectory(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        opts: &OdeOptions,
    ) -> (SimResult, Vec<(f64, f64, Vec<f64>)>) {
        self.full.trajectory(params, load, times, opts)
    }
    fn output_names(&self) -> Vec<&'static str> {
        self.full.output_names()
    }
    fn guess_procedure(&self) -> Option<GuessFn> {
        self.fast.guess_procedure()
    }
    fn as_dyn(&self) -> &dyn Model {
        self
    }
}

/// How a registry entry builds its model with the given extensions.
pub type BuildFn = fn(&ModelEntry, &[String]) -> Result<Box<dyn Model>>;

/// One entry of the model registry: everything that is particular to a model — how it is
/// built (with the catalogued extensions, where they apply) and its initial-guess procedure.
/// Its output columns come with the model itself ([`Model::output_names`]). Adding a model
/// is its files plus one entry in [`REGISTRY`].
pub struct ModelEntry {
    /// Registry name, as in configurations.
    pub name: &'static str,
    /// One line on what it is.
    pub doc: &'static str,
    /// The model with the given extensions (an error if it takes none and some are given).
    pub build: BuildFn,
    /// Its initial-guess procedure, if it has one (else fits start from the configuration or
    /// the centre of the box).
    pub guess: Option<GuessFn>,
    /// The catalogued extensions it composes with (DESIGN.md §6): what `diagnose` tests
    /// by default. Empty for a family that takes none.
    pub extensions: &'static [&'static str],
}

/// The registered models.
///
/// `khd` is the paper's model (eqs. 1–4), simulated through its exact one-state reduction
/// (DESIGN.md §1) and reported with its four states; `khd4` integrates the four states
/// (eqs. 1–4 as written); `khd1` is the one-state reduction alone. All three give the same
/// predictions (tested to 1e-9): the reduction is faster and, unlike the four-state form,
/// its sensitivity equations are not stiff (H relaxing to its saturation H* makes the
/// four-state sensitivities stiff when h/σ is large). Extensions (DESIGN.md §6) compose with
/// `khd` and `khd1` as the one-state reduction with the extensions' terms
/// ([`ext::KhdExtended`]), named e.g. `khd+constant_load`.
pub const REGISTRY: &[ModelEntry] = &[
    ModelEntry {
        name: "khd",
        doc: "the paper's KHD model, fitted through its exact one-state reduction",
        build: build_khd,
        guess: Some(khd_guess::initial_guess),
        extensions: ext::CATALOGUE,
    },
    ModelEntry {
        name: "khd4",
        doc: "the KHD model integrated in its four states",
        build: build_khd4,
        guess: Some(khd_guess::initial_guess),
        extensions: &[],
    },
    ModelEntry {
        name: "khd1",
        doc: "the KHD model's one-state reduction alone",
        build: build_khd,
        guess: Some(khd_guess::initial_guess),
        extensions: ext::CATALOGUE,
    },
    ModelEntry {
        name: "kr",
        doc: "the Kachanov–Rabotnov model: Norton creep with a damage of its own stress exponent",
        build: |e, x| {
            no_extensions(e, x)?;
            Ok(Box::new(
                Integrated::new("kr", kr::Kr, kr::constants()).with_guess(e.guess),
            ))
        },
        guess: Some(kr::initial_guess),
        extensions: &[],
    },
];

/// Names of the registered models, in registry order.
pub fn model_names() -> Vec<&'static str> {
    REGISTRY.iter().map(|e| e.name).collect()
}

fn no_extensions(e: &ModelEntry, extensions: &[String]) -> Result<()> {
    if extensions.is_empty() {
        Ok(())
    } else {
        let takes: Vec<&str> = REGISTRY
            .iter()
            .filter(|m| !m.extensions.is_empty())
            .map(|m| m.name)
            .collect();
        Err(Error::UnknownModel(
            format!("{} with extensions", e.name),
            format!("{} (the models that take extensions)", takes.join(", ")),
        ))
    }
}

fn build_khd4(e: &ModelEntry, extensions: &[String]) -> Result<Box<dyn Model>> {
    no_extensions(e, extensions)?;
    Ok(Box::new(
        Integrated::new("khd4", Khd, khd::constants()).with_guess(e.guess),
    ))
}

fn build_khd(e: &ModelEntry, extensions: &[String]) -> Result<Box<dyn Model>> {
    let khd1 = || Integrated::new("khd1", KhdReduced, khd::constants()).with_guess(e.guess);
    if extensions.is_empty() {
        return Ok(match e.name {
            "khd" => Box::new(FastPath {
                name: "khd",
                fast: Box::new(khd1()),
                full: Box::new(Integrated::new("khd4", Khd, khd::constants()).with_guess(e.guess)),
            }),
            _ => Box::new(khd1()),
        });
    }
    let (m, constants) = KhdExtended::new(extensions)
        .map_err(|bad| Error::UnknownModel(format!("extension {bad}"), ext::ALL.join(", ")))?;
    let full = format!("khd+{}", extensions.join("+"));
    Ok(Box::new(
        Integrated::new(full, m, constants).with_guess(e.guess),
    ))
}

/// The registry entry of model `name`.
pub fn entry(name: &str) -> Result<&'static ModelEntry> {
    REGISTRY
        .iter()
        .find(|e| e.name == name)
        .ok_or_else(|| Error::UnknownModel(name.to_string(), model_names().join(", ")))
}

/// Pick a model by its registry name (without extensions).
pub fn registry(name: &str) -> Result<Box<dyn Model>> {
    build(name, &[])
}

/// The model of a configuration: `name` from the registry, plus the catalogued `extensions`
/// (DESIGN.md §6) composed with it.
pub fn build(name: &str, extensions: &[String]) -> Result<Box<dyn Model>> {
    let e = entry(name)?;
    (e.build)(e, extensions)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_names_and_entries_agree() {
        assert_eq!(model_names(), ["khd", "khd4", "khd1", "kr"]);
        for e in REGISTRY {
            let m = build(e.name, &[]).unwrap();
            assert_eq!(m.name(), e.name);
            assert!(m.guess_procedure().is_some());
            let outputs: &[&str] = if e.name == "kr" {
                &["omega"]
            } else {
                &["H", "Phi", "omega"]
            };
            assert_eq!(m.output_names(), outputs);
            // Every catalogued extension of an entry builds with it.
            for x in e.extensions {
                assert!(build(e.name, &[x.to_string()]).is_ok(), "{} + {x}", e.name);
            }
        }
        assert!(build("kr", &["stress_ductility".to_string()]).is_err());
        let m = build("khd", &["stress_ductility".to_string()]).unwrap();
        assert_eq!(m.output_names(), ["H", "Phi", "omega"]);
        assert!(build("khd4", &["stress_ductility".to_string()]).is_err());
        assert!(build("nope", &[]).is_err());
    }
}
