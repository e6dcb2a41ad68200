//! The Kowalewski–Hayhurst–Dyson creep-damage model of the seed paper (eqs. 1–4), in its
//! four-state form and in its exact one-state reduction.

use super::{ConstantSpec, CreepModel, Load, Role, Scale};
use crate::dual::Scalar;

/// Largest sinh argument accepted as physical: beyond it the rate is absurd (A·e^200) and
/// the state can only come from a trial step past rupture.
pub const MAX_SINH_ARG: f64 = 200.0;

/// The six constants b = [A, B, H*, h, Kc, C], with the seed paper's 560 °C Table 1 bounds
/// and Table 4 start as defaults.
pub fn constants() -> Vec<ConstantSpec> {
    vec![
        ConstantSpec {
            name: "A",
            unit: "1/h",
            lb: 1e-10,
            ub: 1e-9,
            default: 1e-9,
            scale: Scale::Log,
            role: Role::Rate,
            doc: "creep rate coefficient",
        },
        ConstantSpec {
            name: "B",
            unit: "1/MPa",
            lb: 0.1,
            ub: 0.2,
            default: 0.11,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "stress sensitivity of the creep rate",
        },
        ConstantSpec {
            name: "Hstar",
            unit: "-",
            lb: 0.4,
            ub: 0.8,
            default: 0.426,
            scale: Scale::Linear,
            role: Role::Other,
            doc: "saturation value of the hardening variable H",
        },
        ConstantSpec {
            name: "h",
            unit: "MPa",
            lb: 1e4,
            ub: 2e5,
            default: 5.05e4,
            scale: Scale::Log,
            role: Role::Other,
            doc: "hardening modulus (primary creep)",
        },
        ConstantSpec {
            name: "Kc",
            unit: "1/h",
            lb: 1e-6,
            ub: 3e-5,
            default: 6.86e-6,
            scale: Scale::Log,
            role: Role::Softening,
            doc: "carbide coarsening rate",
        },
        ConstantSpec {
            name: "C",
            unit: "-",
            lb: 3.0,
            ub: 10.0,
            default: 4.311,
            scale: Scale::Linear,
            role: Role::InverseDuctility,
            doc: "cavitation damage per unit strain (omega = C eps)",
        },
    ]
}

/// Per-simulation constants of the KHD model (in the number type `S` of the simulation).
#[derive(Debug, Clone, Copy)]
pub struct KhdPrepared<S> {
    /// A, 1/h
    pub a: S,
    /// B·σ, dimensionless
    pub b_sigma: S,
    /// 1/H*
    pub inv_hstar: S,
    /// H*
    pub hstar: S,
    /// h/σ
    pub h_over_sigma: S,
    /// Kc/3, 1/h
    pub kc3: S,
    /// Kc, 1/h
    pub kc: S,
    /// C
    pub c: S,
    /// ω_f
    pub omega_f: f64,
}

/// Derive the per-simulation constants from b = [A, B, H*, h, Kc, C] and the load.
pub fn prepare<S: Scalar>(params: &[S], load: &Load) -> KhdPrepared<S> {
    let (a, b, hstar, h, kc, c) = (
        params[0], params[1], params[2], params[3], params[4], params[5],
    );
    KhdPrepared {
        a,
        b_sigma: b * load.stress_mpa,
        inv_hstar: S::cst(1.0) / hstar,
        hstar,
        h_over_sigma: h / load.stress_mpa,
        kc3: kc / 3.0,
        kc,
        c,
        omega_f: load.omega_f,
    }
}

/// Strain rate A·sinh(Bσ(1−H)/((1−Φ)(1−ω))), or `None` outside the model's domain.
#[inline(always)]
pub fn khd_rate<S: Scalar>(
    p: &KhdPrepared<S>,
    hard: S,
    one_minus_phi: S,
    one_minus_omega: S,
) -> Option<S> {
    let denom = one_minus_phi * one_minus_omega;
    if !(denom.re() > 0.0) {
        return None;
    }
    let arg = p.b_sigma * (S::cst(1.0) - hard) / denom;
    if !(arg.re().abs() <= MAX_SINH_ARG) {
        return None;
    }
    Some(p.a * arg.sinh())
}

/// 1/(1 − Φ(t)) = (1 + Kc·t)^(1/3): the closed-form coarsening of the one-state models.
#[inline(always)]
pub fn coarsening_factor<S: Scalar>(p: &KhdPrepared<S>, t: S) -> S {
    (p.kc * t + 1.0).cbrt()
}

/// [`khd_rate`] with the coarsening given as `coarsening` = 1/(1 − Φ) (one division less).
#[inline(always)]
pub fn khd_rate_coarsened<S: Scalar>(
    p: &KhdPrepared<S>,
    hard: S,
    coarsening: S,
    one_minus_omega: S,
) -> Option<S> {
    if !(one_minus_omega.re() > 0.0 && coarsening.re() > 0.0) {
        return None;
    }
    let arg = p.b_sigma * (S::cst(1.0) - hard) * coarsening / one_minus_omega;
    if !(arg.re().abs() <= MAX_SINH_ARG) {
        return None;
    }
    Some(p.a * arg.sinh())
}

/// The KHD model's output columns: the hardening variable H, the coarsening damage Φ and
/// the cavitation damage ω.
pub const OUTPUTS: [&str; 3] = ["H", "Phi", "omega"];

/// H, Φ, ω of the one-state forms at time `t` (h) and creep strain `eps`: H from the
/// hardening strain `g` (ε, or ln(1+ε) at constant load), Φ = 1 − (1 + Kc t)^(−1/3),
/// ω = `c_eff`·ε.
pub fn outputs(p: &KhdPrepared<f64>, t: f64, eps: f64, g: f64, c_eff: f64, out: &mut Vec<f64>) {
    out.push(p.hstar * (1.0 - (-(p.h_over_sigma * g * p.inv_hstar)).exp()));
    out.push(1.0 - 1.0 / coarsening_factor(p, t));
    out.push(c_eff * eps);
}

/// The paper's four-state model, state y = [ε, H, Φ, ω].
#[derive(Debug, Clone, Copy, Default)]
pub struct Khd;

impl CreepModel<4> for Khd {
    type Prepared<S: Scalar> = KhdPrepared<S>;
    fn prepare<S: Scalar>(&self, params: &[S], load: &Load) -> KhdPrepared<S> {
        prepare(params, load)
    }
    fn init<S: Scalar>(&self, _p: &KhdPrepared<S>) -> [S; 4] {
        [S::cst(0.0); 4]
    }
    #[inline(always)]
    fn rhs<S: Scalar>(&self, p: &KhdPrepared<S>, _t: S, y: &[S; 4], dy: &mut [S; 4]) -> bool {
        let [_, hard, phi, omega] = *y;
        let one_minus_phi = S::cst(1.0) - phi;
        let Some(rate) = khd_rate(p, hard, one_minus_phi, S::cst(1.0) - omega) else {
            return false;
        };
        let sq = one_minus_phi * one_minus_phi;
        dy[0] = rate;
        dy[1] = p.h_over_sigma * rate * (S::cst(1.0) - hard * p.inv_hstar);
        dy[2] = p.kc3 * sq * sq;
        dy[3] = p.c * rate;
        true
    }
    #[inline(always)]
    fn event<S: Scalar>(&self, p: &KhdPrepared<S>, y: &[S; 4]) -> S {
        y[3] - p.omega_f
    }
    #[inline(always)]
    fn event_rate<S: Scalar>(&self, _p: &KhdPrepared<S>, _y: &[S; 4], dy: &[S; 4]) -> S {
        dy[3]
    }
    #[inline(always)]
    fn strain<S: Scalar>(&self, _p: &KhdPrepared<S>, y: &[S; 4]) -> S {
        y[0]
    }
    #[inline(always)]
    fn strain_rate<S: Scalar>(&self, _p: &KhdPrepared<S>, _y: &[S; 4], dy: &[S; 4]) -> S {
        dy[0]
    }
    fn state_names(&self) -> [&'static str; 4] {
        ["strain", "H", "Phi", "omega"]
    }
    fn output_names(&self) -> &'static [&'static str] {
        &OUTPUTS
    }
    fn outputs(&self, _p: &KhdPrepared<f64>, _t: f64, y: &[f64; 4], out: &mut Vec<f64>) {
        out.extend_from_slice(&y[1..]);
    }
}

/// The exact one-state reduction of [`Khd`] (DESIGN.md §1), state y = \[ε\]:
/// Φ(t) = 1 − (1 + Kc t)^(−1/3), ω = Cε, H = H*(1 − exp(−hε/(σH*))).
#[derive(Debug, Clone, Copy, Default)]
pub struct KhdReduced;

impl CreepModel<1> for KhdReduced {
    type Prepared<S: Scalar> = KhdPrepared<S>;
    fn prepare<S: Scalar>(&self, params: &[S], load: &Load) -> KhdPrepared<S> {
        prepare(params, load)
    }
    fn init<S: Scalar>(&self, _p: &KhdPrepared<S>) -> [S; 1] {
        [S::cst(0.0)]
    }
    #[inline(always)]
    fn rhs<S: Scalar>(&self, p: &KhdPrepared<S>, t: S, y: &[S; 1], dy: &mut [S; 1]) -> bool {
        self.rhs_tp(p, t, self.time_part(p, t), y, dy)
    }
    #[inline(always)]
    fn time_part<S: Scalar>(&self, p: &KhdPrepared<S>, t: S) -> S {
        coarsening_factor(p, t)
    }
    #[inline(always)]
    fn rhs_tp<S: Scalar>(
        &self,
        p: &KhdPrepared<S>,
        _t: S,
        tp: S,
        y: &[S; 1],
        dy: &mut [S; 1],
    ) -> bool {
        let eps = y[0];
        let hard = p.hstar * (S::cst(1.0) - (-(p.h_over_sigma * eps * p.inv_hstar)).exp());
        match khd_rate_coarsened(p, hard, tp, S::cst(1.0) - p.c * eps) {
            Some(rate) => {
                dy[0] = rate;
                true
            }
            None => false,
        }
    }
    #[inline(always)]
    fn event<S: Scalar>(&self, p: &KhdPrepared<S>, y: &[S; 1]) -> S {
        p.c * y[0] - p.omega_f
    }
    #[inline(always)]
    fn event_rate<S: Scalar>(&self, p: &KhdPrepared<S>, _y: &[S; 1], dy: &[S; 1]) -> S {
        p.c * dy[0]
    }
    #[inline(always)]
    fn strain<S: Scalar>(&self, _p: &KhdPrepared<S>, y: &[S; 1]) -> S {
        y[0]
    }
    #[inline(always)]
    fn strain_rate<S: Scalar>(&self, _p: &KhdPrepared<S>, _y: &[S; 1], dy: &[S; 1]) -> S {
        dy[0]
    }
    fn state_names(&self) -> [&'static str; 1] {
        ["strain"]
    }
    fn output_names(&self) -> &'static [&'static str] {
        &OUTPUTS
    }
    fn outputs(&self, p: &KhdPrepared<f64>, t: f64, y: &[f64; 1], out: &mut Vec<f64>) {
        outputs(p, t, y[0], y[0], p.c, out);
    }
}
