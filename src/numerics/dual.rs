//! Forward-mode automatic differentiation: the [`Scalar`] the models and the integrator are
//! generic over, implemented by `f64` (plain simulation) and by [`Dual`] (value plus the
//! gradient with respect to up to `K` constants).
//!
//! Integrating a model in `Dual` numbers is integrating the forward sensitivity equations
//! alongside the state: the gradient part of every Runge–Kutta stage is f_y·S + f_p, so the
//! result is the exact derivative of the discrete solution at the accepted step sizes. Every
//! arithmetic operation's value part is the `f64` operation.

use std::fmt::Debug;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// The number type of a model's state and constants.
pub trait Scalar:
    Copy
    + Debug
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    /// Number of gradient components (0 for `f64`).
    const N_GRAD: usize;
    /// Gradient component `k` (< [`Scalar::N_GRAD`]).
    fn grad(&self, k: usize) -> f64;
    /// A constant (zero gradient).
    fn cst(v: f64) -> Self;
    /// The value part.
    fn re(&self) -> f64;
    fn sinh(self) -> Self;
    fn cosh(self) -> Self;
    fn exp(self) -> Self;
    fn ln(self) -> Self;
    fn sqrt(self) -> Self;
    /// self^e for a constant exponent.
    fn powf(self, e: f64) -> Self;
    /// Cube root (faster than `powf(1/3)`).
    fn cbrt(self) -> Self;
    /// Whether value and gradient are finite.
    fn is_finite(&self) -> bool;
}

impl Scalar for f64 {
    const N_GRAD: usize = 0;
    #[inline(always)]
    fn grad(&self, _k: usize) -> f64 {
        0.0
    }
    #[inline(always)]
    fn cst(v: f64) -> Self {
        v
    }
    #[inline(always)]
    fn re(&self) -> f64 {
        *self
    }
    #[inline(always)]
    fn sinh(self) -> Self {
        sinh(self)
    }
    #[inline(always)]
    fn cosh(self) -> Self {
        f64::cosh(self)
    }
    #[inline(always)]
    fn exp(self) -> Self {
        f64::exp(self)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        f64::ln(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn powf(self, e: f64) -> Self {
        f64::powf(self, e)
    }
    #[inline(always)]
    fn cbrt(self) -> Self {
        cbrt(self)
    }
    #[inline(always)]
    fn is_finite(&self) -> bool {
        f64::is_finite(*self)
    }
}

/// Largest |x| for which sinh is computed from one exponential (below exp's overflow).
const SINH_EXP_MAX: f64 = 700.0;

/// sinh(x) from one exponential where no cancellation threatens (1 ≤ |x| ≤ 700; within
/// 2 ulp there), libm elsewhere: libm's sinh goes through expm1 and costs twice as much.
#[inline(always)]
pub fn sinh(x: f64) -> f64 {
    if x.abs() >= 1.0 && x.abs() <= SINH_EXP_MAX {
        let e = x.exp();
        0.5 * (e - 1.0 / e)
    } else {
        x.sinh()
    }
}

/// Cube root of a number in [1e-300, 1e300] by three Halley iterations from a bit-level
/// first guess (within 2 ulp; measured 4.4e-16 relative); other arguments go to libm. The
/// bundled libm's cube root is correctly rounded and three times slower, and the one-state
/// model takes one per right-hand side.
#[inline(always)]
pub fn cbrt(x: f64) -> f64 {
    // Bounds keep 2·y³ + x finite and y³ normal.
    if !(1e-300..=1e300).contains(&x) {
        return x.cbrt();
    }
    // Dividing the bit pattern by 3 divides the exponent by 3 (first guess within ~3 %).
    let mut y = f64::from_bits(x.to_bits() / 3 + 0x2A9F_7893_782D_A1CE);
    for _ in 0..3 {
        let y3 = y * y * y;
        y *= (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    y
}

/// Number of constants a [`Dual`] carries derivatives for in the fit's sensitivity Jacobian
/// when at most this many constants are free (the base model's six plus two): the narrow,
/// fast width.
pub const SENS: usize = 8;

/// The wide width of the sensitivity Jacobian: used when more than [`SENS`] constants are
/// free (extensions, temperature laws); above it the constants are seeded in chunks of this
/// many, one simulation per chunk ([`crate::model::objective::CreepProblem`]). Never finite
/// differences unless the configuration asks for them.
pub const SENS_WIDE: usize = 16;

/// A value and its gradient with respect to `K` independent variables.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const K: usize> {
    /// Value.
    pub v: f64,
    /// ∂value/∂x_k.
    pub d: [f64; K],
}

impl<const K: usize> Dual<K> {
    /// The `k`-th independent variable at value `v`, with derivative `scale` (dx/du of a
    /// change of variables).
    pub fn var(v: f64, k: usize, scale: f64) -> Self {
        let mut d = [0.0; K];
        d[k] = scale;
        Dual { v, d }
    }
    /// Chain rule for a scalar function with value `f` and derivative `df` at `self.v`.
    #[inline(always)]
    fn chain(self, f: f64, df: f64) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= df;
        }
        Dual { v: f, d }
    }
}

impl<const K: usize> Add for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        let mut d = self.d;
        for k in 0..K {
            d[k] += o.d[k];
        }
        Dual { v: self.v + o.v, d }
    }
}

impl<const K: usize> Sub for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        let mut d = self.d;
        for k in 0..K {
            d[k] -= o.d[k];
        }
        Dual { v: self.v - o.v, d }
    }
}

impl<const K: usize> Mul for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        let mut d = [0.0; K];
        for k in 0..K {
            d[k] = self.d[k] * o.v + self.v * o.d[k];
        }
        Dual { v: self.v * o.v, d }
    }
}

impl<const K: usize> Div for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        let v = self.v / o.v;
        let inv = 1.0 / o.v;
        let mut d = [0.0; K];
        for k in 0..K {
            d[k] = (self.d[k] - v * o.d[k]) * inv;
        }
        Dual { v, d }
    }
}

impl<const K: usize> Neg for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = -*x;
        }
        Dual { v: -self.v, d }
    }
}

impl<const K: usize> Add<f64> for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: f64) -> Self {
        Dual {
            v: self.v + o,
            d: self.d,
        }
    }
}

impl<const K: usize> Sub<f64> for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: f64) -> Self {
        Dual {
            v: self.v - o,
            d: self.d,
        }
    }
}

impl<const K: usize> Mul<f64> for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: f64) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= o;
        }
        Dual { v: self.v * o, d }
    }
}

impl<const K: usize> Div<f64> for Dual<K> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: f64) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x /= o;
        }
        Dual { v: self.v / o, d }
    }
}

impl<const K: usize> Scalar for Dual<K> {
    const N_GRAD: usize = K;
    #[inline(always)]
    fn grad(&self, k: usize) -> f64 {
        self.d[k]
    }
    #[inline(always)]
    fn cst(v: f64) -> Self {
        Dual { v, d: [0.0; K] }
    }
    #[inline(always)]
    fn re(&self) -> f64 {
        self.v
    }
    #[inline(always)]
    fn sinh(self) -> Self {
        // One exponential for value and derivative where no cancellation threatens.
        if self.v.abs() >= 1.0 && self.v.abs() <= SINH_EXP_MAX {
            let e = self.v.exp();
            let ie = 1.0 / e;
            self.chain(0.5 * (e - ie), 0.5 * (e + ie))
        } else {
            self.chain(self.v.sinh(), self.v.cosh())
        }
    }
    #[inline(always)]
    fn cosh(self) -> Self {
        self.chain(self.v.cosh(), self.v.sinh())
    }
    #[inline(always)]
    fn exp(self) -> Self {
        let e = self.v.exp();
        self.chain(e, e)
    }
    #[inline(always)]
    fn ln(self) -> Self {
        self.chain(self.v.ln(), 1.0 / self.v)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        self.chain(s, 0.5 / s)
    }
    #[inline(always)]
    fn powf(self, e: f64) -> Self {
        let p = self.v.powf(e);
        self.chain(p, e * p / self.v)
    }
    #[inline(always)]
    fn cbrt(self) -> Self {
        let c = cbrt(self.v);
        self.chain(c, c / (3.0 * self.v))
    }
    #[inline(always)]
    fn is_finite(&self) -> bool {
        self.v.is_finite() && self.d.iter().all(|x| x.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast cube root and sinh against libm over many decades, at 2 ulp.
    #[test]
    fn fast_cbrt_and_sinh_match_libm() {
        let mut x = 1e-300_f64;
        while x < 1e300 {
            for s in [1.0, -1.0] {
                let (fast, lib) = (cbrt(s * x), (s * x).cbrt());
                assert!(
                    (fast - lib).abs() <= 4.5e-16 * lib.abs(),
                    "cbrt({}) = {fast} vs {lib}",
                    s * x
                );
            }
            x *= 1.0137;
        }
        for v in [
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e-310,
            f64::MAX,
        ] {
            assert_eq!(cbrt(v).to_bits(), v.cbrt().to_bits());
        }
        assert!(cbrt(f64::NAN).is_nan());
        let mut x = -720.0_f64;
        while x < 720.0 {
            let (fast, lib) = (sinh(x), x.sinh());
            assert!(
                fast == lib || (fast - lib).abs() <= 4.5e-16 * lib.abs(),
                "sinh({x}) = {fast} vs {lib}"
            );
            x += 0.0123;
        }
    }

    /// Central difference of f at x.
    fn cd(f: impl Fn(f64) -> f64, x: f64) -> f64 {
        let h = 1e-6 * x.abs().max(1.0);
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    #[test]
    fn elementary_functions_against_closed_forms() {
        let x = Dual::<2>::var(0.7, 0, 1.0);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-14 * b.abs().max(1.0);
        assert!(close(x.sinh().d[0], 0.7f64.cosh()));
        assert!(close(x.cosh().d[0], 0.7f64.sinh()));
        assert!(close(x.exp().d[0], 0.7f64.exp()));
        assert!(close(x.ln().d[0], 1.0 / 0.7));
        assert!(close(x.sqrt().d[0], 0.5 / 0.7f64.sqrt()));
        assert!(close(x.cbrt().d[0], 0.7f64.powf(-2.0 / 3.0) / 3.0));
        let big = Dual::<2>::var(7.5, 0, 1.0);
        assert!(close(big.sinh().v, 7.5f64.sinh()));
        assert!(close(big.sinh().d[0], 7.5f64.cosh()));
        assert!(close(
            x.powf(-1.0 / 3.0).d[0],
            -(0.7f64.powf(-4.0 / 3.0)) / 3.0
        ));
        assert_eq!(x.sinh().d[1], 0.0);
    }

    #[test]
    fn compound_expression_against_finite_differences() {
        // f(a, b) = a·sinh(b/(1−a)) / (1 + exp(−a·b)) + sqrt(b)·ln(a+2) − b^1.5
        fn f<S: Scalar>(a: S, b: S) -> S {
            a * (b / (-a + 1.0)).sinh() / ((-(a * b)).exp() + 1.0) + b.sqrt() * (a + 2.0).ln()
                - b.powf(1.5)
        }
        let (a0, b0) = (0.3, 1.7);
        let r = f(Dual::<2>::var(a0, 0, 1.0), Dual::<2>::var(b0, 1, 1.0));
        assert_eq!(r.v, f(a0, b0));
        let da = cd(|a| f(a, b0), a0);
        let db = cd(|b| f(a0, b), b0);
        assert!((r.d[0] - da).abs() <= 1e-8 * da.abs(), "{} {}", r.d[0], da);
        assert!((r.d[1] - db).abs() <= 1e-8 * db.abs(), "{} {}", r.d[1], db);
    }

    #[test]
    fn value_part_is_bitwise_the_f64_computation() {
        let (a, b) = (0.123456789, 3.987654321);
        let plain = (a * b).sinh() / (a - b) + (a / b).powf(0.3) * 7.0;
        let (x, y) = (Dual::<3>::var(a, 0, 1.0), Dual::<3>::var(b, 2, 1.0));
        let dual = (x * y).sinh() / (x - y) + (x / y).powf(0.3) * 7.0;
        assert_eq!(dual.v.to_bits(), plain.to_bits());
    }

    #[test]
    fn scaled_variable_and_finiteness() {
        let x = Dual::<1>::var(2.0, 0, 3.0);
        assert_eq!((x * x).d[0], 12.0);
        assert!(!(x / Dual::cst(0.0)).is_finite());
    }
}
