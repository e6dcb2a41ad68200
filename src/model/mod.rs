//! Constitutive models: the [`CreepModel`] trait that the integrator is monomorphised over,
//! the object-safe [`Model`] that the fit and the commands use, and the registry by name.
//!
//! A model exposes its constants ([`ConstantSpec`]: name, unit, default bounds, scale), a
//! per-simulation preparation of derived constants, the right-hand side, the rupture event
//! and the strain read-out. Adding an extension means one file that implements
//! [`CreepModel`] plus one line in [`registry`].

pub mod ext;
mod khd;

pub use ext::KhdExtended;
pub use khd::{Khd, KhdReduced};

use crate::dual::{Dual, Scalar, SENS};
use crate::error::{Error, Result};
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
}

/// The loading of one test: nominal stress and the damage at rupture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Load {
    /// Nominal (initial) stress, MPa.
    pub stress_mpa: f64,
    /// Damage at rupture ω_f (the paper: 1/3).
    pub omega_f: f64,
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
    /// Names of the state components, for trajectory output.
    fn state_names(&self) -> [&'static str; N];
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
    /// Integrate and return the full state at each of `times` up to rupture (for reports).
    fn trajectory(
        &self,
        params: &[f64],
        load: &Load,
        times: &[f64],
        opts: &OdeOptions,
    ) -> (SimResult, Vec<(f64, f64, Vec<f64>)>);
    /// Names of the state components reported by [`Model::trajectory`].
    fn state_names(&self) -> Vec<&'static str>;
}

/// Adapts any [`CreepModel`] to the object-safe [`Model`]; the integration stays
/// monomorphised.
pub struct Integrated<M, const N: usize> {
    name: String,
    model: M,
    constants: Vec<ConstantSpec>,
}

impl<M, const N: usize> Integrated<M, N> {
    /// Wrap `model` under a registry `name` with its `constants`.
    pub fn new(name: impl Into<String>, model: M, constants: Vec<ConstantSpec>) -> Self {
        Integrated {
            name: name.into(),
            model,
            constants,
        }
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
        let p = self.model.prepare(params, load);
        ode::integrate(&self.model, &p, times, opts, |k, _t, y| {
            strain_out[k] = self.model.strain(&p, y)
        })
    }
    fn simulate_sens(
        &self,
        params: &[Dual<SENS>],
        load: &Load,
        times: &[f64],
        strain_out: &mut [Dual<SENS>],
        opts: &OdeOptions,
    ) -> SimResult<Dual<SENS>> {
        let p = self.model.prepare(params, load);
        ode::integrate(&self.model, &p, times, opts, |k, _t, y| {
            strain_out[k] = self.model.strain(&p, y)
        })
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
            out.push((t, self.model.strain(&p, y), y.to_vec()))
        });
        (res, out)
    }
    fn state_names(&self) -> Vec<&'static str> {
        self.model.state_names().to_vec()
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
    fn state_names(&self) -> Vec<&'static str> {
        self.full.state_names()
    }
}

/// Names of the registered models.
pub const MODEL_NAMES: &[&str] = &["khd", "khd4", "khd1"];

/// Pick a model by its registry name.
///
/// `khd` is the paper's model (eqs. 1–4), simulated through its exact one-state reduction
/// (DESIGN.md §1) and reported with its four states; `khd4` integrates the four states
/// (eqs. 1–4 as written); `khd1` is the one-state reduction alone. All three give the same
/// predictions (tested to 1e-9): the reduction is faster and, unlike the four-state form,
/// its sensitivity equations are not stiff (H relaxing to its saturation H* makes the
/// four-state sensitivities stiff when h/σ is large).
pub fn registry(name: &str) -> Result<Box<dyn Model>> {
    let khd4 = || Box::new(Integrated::new("khd4", Khd, khd::constants()));
    let khd1 = || Box::new(Integrated::new("khd1", KhdReduced, khd::constants()));
    match name {
        "khd" => Ok(Box::new(FastPath {
            name: "khd",
            fast: khd1(),
            full: khd4(),
        })),
        "khd4" => Ok(khd4()),
        "khd1" => Ok(khd1()),
        _ => Err(Error::UnknownModel(
            name.to_string(),
            MODEL_NAMES.join(", "),
        )),
    }
}

/// The model of a configuration: `name` from the registry, plus the catalogued `extensions`
/// (DESIGN.md §6) composed with it. Extensions apply to the KHD model (`khd`, `khd1`): the
/// composition is the one-state reduction with the extensions' terms
/// ([`ext::KhdExtended`]), named e.g. `khd+constant_load`.
pub fn build(name: &str, extensions: &[String]) -> Result<Box<dyn Model>> {
    if extensions.is_empty() {
        return registry(name);
    }
    if !matches!(name, "khd" | "khd1") {
        return Err(Error::UnknownModel(
            format!("{name} with extensions"),
            "khd, khd1 (extensions apply to the KHD model)".into(),
        ));
    }
    let (m, constants) = KhdExtended::new(extensions).map_err(|bad| {
        Error::UnknownModel(format!("extension {bad}"), ext::CATALOGUE.join(", "))
    })?;
    let full = format!("khd+{}", extensions.join("+"));
    Ok(Box::new(Integrated::new(full, m, constants)))
}
