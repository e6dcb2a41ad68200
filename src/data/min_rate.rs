//! The minimum creep rate estimated from a measured curve: the smallest positive
//! least-squares slope over windows of consecutive points (see [`estimate_min_rate`]).
//!
//! The scan is linear in the number of points: the windows' ends only move forward (two
//! pointers) and each window's sums are kept as running sums in double-double arithmetic
//! over values shifted to the curve's first point, so adding and removing points does not
//! accumulate rounding and the centred sums (Σ(t − t̄)², Σ(t − t̄)(ε − ε̄)) suffer no
//! cancellation. The chosen window's slope is then recomputed by the two-pass formula, so
//! the result is the same number the direct O(n²) scan gives.

use super::{MIN_RATE_WINDOW_FRACTION, MIN_RATE_WINDOW_POINTS};

/// Estimate the minimum creep rate (1/h when `strains` are fractions) of a measured curve.
///
/// Method: from every start point, a window of consecutive points is grown until it spans at
/// least [`MIN_RATE_WINDOW_FRACTION`] × `life_h` in time **and** holds at least
/// [`MIN_RATE_WINDOW_POINTS`] points; a least-squares line strain-vs-time is fitted to each
/// such window, and the estimate is the smallest positive slope over all windows. Fitting
/// over a fixed fraction of the life averages out digitizing noise (single points that fall
/// back would make point-to-point slopes zero or negative), while windows short against the
/// life still resolve the secondary stage. The estimate is biased slightly high on a curved
/// secondary stage (a window's mean slope exceeds its minimum).
///
/// Fallback, when no window qualifies (curve shorter than the window) or no window has a
/// positive slope: the overall secant slope (last − first point) of the curve; 0 when the
/// points span no time. A non-finite or non-positive `life_h` is replaced by the time span of
/// the points. `times_h` must be sorted ascending (as [`super::Curve::times_h`] is).
///
/// Cost: O(n) time, O(1) extra memory (a 1 M-point curve takes milliseconds).
pub fn estimate_min_rate(times_h: &[f64], strains: &[f64], life_h: f64) -> f64 {
    let n = times_h.len().min(strains.len());
    if n < 2 {
        return 0.0;
    }
    let (t, e) = (&times_h[..n], &strains[..n]);
    let span = t[n - 1] - t[0];
    let life = if life_h.is_finite() && life_h > 0.0 {
        life_h
    } else {
        span
    };
    let width = MIN_RATE_WINDOW_FRACTION * life;
    let p = MIN_RATE_WINDOW_POINTS.min(n);
    let mut sums = WindowSums::new(t[0], e[0]);
    // The window is [i, j]; `sums` holds points i..=j once j is set.
    let mut best: Option<(f64, usize, usize)> = None;
    let mut j = 0;
    let mut filled = false;
    for i in 0..n {
        if filled {
            sums.remove(t[i - 1], e[i - 1]);
        }
        let mut jj = if filled { j.max(i + p - 1) } else { i + p - 1 };
        while jj < n && t[jj] - t[i] < width {
            jj += 1;
        }
        if jj >= n {
            break; // later starts cannot qualify either
        }
        let from = if filled { j + 1 } else { i };
        for k in from..=jj {
            sums.add(t[k], e[k]);
        }
        j = jj;
        filled = true;
        if let Some(slope) = sums.slope() {
            if slope > 0.0 && best.is_none_or(|(b, _, _)| slope < b) {
                best = Some((slope, i, j));
            }
        }
    }
    if let Some((fast, i, j)) = best {
        // The two-pass slope of the chosen window: the direct scan's number, bit for bit.
        match ls_slope(&t[i..=j], &e[i..=j]) {
            Some(s) if s > 0.0 => s,
            _ => fast,
        }
    } else if span > 0.0 {
        (e[n - 1] - e[0]) / span
    } else {
        0.0
    }
}

/// Least-squares slope of y against x (centred two-pass sums); `None` when x has no spread.
pub(crate) fn ls_slope(x: &[f64], y: &[f64]) -> Option<f64> {
    let m = x.len() as f64;
    let mx = x.iter().sum::<f64>() / m;
    let my = y.iter().sum::<f64>() / m;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        let dx = a - mx;
        sxx += dx * dx;
        sxy += dx * (b - my);
    }
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Running sums of a window of points (x, y), shifted by a fixed origin, in double-double.
struct WindowSums {
    x0: f64,
    y0: f64,
    m: usize,
    sx: Dd,
    sy: Dd,
    sxx: Dd,
    sxy: Dd,
}

impl WindowSums {
    fn new(x0: f64, y0: f64) -> Self {
        WindowSums {
            x0,
            y0,
            m: 0,
            sx: Dd::ZERO,
            sy: Dd::ZERO,
            sxx: Dd::ZERO,
            sxy: Dd::ZERO,
        }
    }

    /// Shifted point as double-doubles (the shift itself is exact to double-double).
    fn shifted(&self, x: f64, y: f64) -> (Dd, Dd) {
        (Dd::diff(x, self.x0), Dd::diff(y, self.y0))
    }

    fn add(&mut self, x: f64, y: f64) {
        let (dx, dy) = self.shifted(x, y);
        self.m += 1;
        self.sx = self.sx.add(dx);
        self.sy = self.sy.add(dy);
        self.sxx = self.sxx.add(dx.mul(dx));
        self.sxy = self.sxy.add(dx.mul(dy));
    }

    fn remove(&mut self, x: f64, y: f64) {
        let (dx, dy) = self.shifted(x, y);
        self.m -= 1;
        self.sx = self.sx.sub(dx);
        self.sy = self.sy.sub(dy);
        self.sxx = self.sxx.sub(dx.mul(dx));
        self.sxy = self.sxy.sub(dx.mul(dy));
    }

    /// Slope of the window's least-squares line; `None` when x has no spread.
    fn slope(&self) -> Option<f64> {
        let m = self.m as f64;
        let cxx = self.sxx.sub(self.sx.mul(self.sx).div_f64(m));
        let cxy = self.sxy.sub(self.sx.mul(self.sy).div_f64(m));
        let cxx = cxx.to_f64();
        (cxx > 0.0).then(|| cxy.to_f64() / cxx)
    }
}

/// A double-double number hi + lo (|lo| ≤ ulp(hi)/2): about 32 significant digits.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Dd {
    hi: f64,
    lo: f64,
}

impl Dd {
    const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };

    /// a + b exactly as (sum, error) (Knuth's TwoSum).
    fn two_sum(a: f64, b: f64) -> Dd {
        let s = a + b;
        let bb = s - a;
        let err = (a - (s - bb)) + (b - bb);
        Dd { hi: s, lo: err }
    }

    fn quick(hi: f64, lo: f64) -> Dd {
        let s = hi + lo;
        Dd {
            hi: s,
            lo: lo - (s - hi),
        }
    }

    /// a − b exactly.
    fn diff(a: f64, b: f64) -> Dd {
        Dd::two_sum(a, -b)
    }

    fn add(self, o: Dd) -> Dd {
        let s = Dd::two_sum(self.hi, o.hi);
        let t = Dd::two_sum(self.lo, o.lo);
        let s = Dd::quick(s.hi, s.lo + t.hi);
        Dd::quick(s.hi, s.lo + t.lo)
    }

    fn sub(self, o: Dd) -> Dd {
        self.add(Dd {
            hi: -o.hi,
            lo: -o.lo,
        })
    }

    fn mul(self, o: Dd) -> Dd {
        let p = self.hi * o.hi;
        let err = self.hi.mul_add(o.hi, -p);
        Dd::quick(p, err + (self.hi * o.lo + self.lo * o.hi))
    }

    fn div_f64(self, d: f64) -> Dd {
        let q1 = self.hi / d;
        // remainder self − q1·d, exactly enough with an FMA
        let p = q1 * d;
        let perr = q1.mul_add(d, -p);
        let r = Dd::two_sum(self.hi, -p);
        let q2 = ((r.hi + r.lo) - perr + self.lo) / d;
        Dd::quick(q1, q2)
    }

    fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The direct O(n²) scan this module replaced: kept as the oracle.
    fn estimate_min_rate_direct(times_h: &[f64], strains: &[f64], life_h: f64) -> f64 {
        let n = times_h.len().min(strains.len());
        if n < 2 {
            return 0.0;
        }
        let (t, e) = (&times_h[..n], &strains[..n]);
        let span = t[n - 1] - t[0];
        let life = if life_h.is_finite() && life_h > 0.0 {
            life_h
        } else {
            span
        };
        let width = MIN_RATE_WINDOW_FRACTION * life;
        let mut best = f64::INFINITY;
        for i in 0..n {
            let mut j = i + MIN_RATE_WINDOW_POINTS.min(n) - 1;
            while j < n && t[j] - t[i] < width {
                j += 1;
            }
            if j >= n {
                break;
            }
            if let Some(slope) = ls_slope(&t[i..=j], &e[i..=j]) {
                if slope > 0.0 && slope < best {
                    best = slope;
                }
            }
        }
        if best.is_finite() {
            best
        } else if span > 0.0 {
            (e[n - 1] - e[0]) / span
        } else {
            0.0
        }
    }

    /// Deterministic pseudo-random numbers in [0, 1) (xorshift).
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn assert_same(t: &[f64], e: &[f64], life: f64, what: &str) {
        let fast = estimate_min_rate(t, e, life);
        let direct = estimate_min_rate_direct(t, e, life);
        let rel = (fast - direct).abs() / direct.abs().max(f64::MIN_POSITIVE);
        assert!(
            rel <= 1e-12 || fast == direct,
            "{what}: fast {fast:e}, direct {direct:e}, relative difference {rel:e}"
        );
    }

    #[test]
    fn same_as_direct_scan_on_random_curves() {
        let mut rng = Rng(0x2545F4914F6CDD1D);
        let mut exact = 0;
        for case in 0..400 {
            let n = 2 + (rng.next() * 600.0) as usize;
            // Time origins far from zero and irregular steps (some repeated times) stress
            // the cancellation the running sums must avoid.
            let t0 = [0.0, 1e3, 1e6, 3.7e7][case % 4];
            let mut t = vec![t0];
            for _ in 1..n {
                let dt = if rng.next() < 0.05 {
                    0.0
                } else {
                    (10.0 * rng.next()).powi(3)
                };
                t.push(t.last().unwrap() + dt);
            }
            let life = match case % 5 {
                0 => f64::NAN,
                1 => 0.0,
                _ => (t[n - 1] - t0) * (1.0 + rng.next()),
            };
            let (a, b, c) = (1e-5 * rng.next(), 1e-2 * rng.next(), 1e-3 * rng.next());
            let tau = 1.0 + (t[n - 1] - t0) * 0.1 * rng.next();
            let noise = [0.0, 1e-6, 1e-4, 3e-3][case % 4 / 2 + case % 2];
            let e: Vec<f64> = t
                .iter()
                .map(|&ti| {
                    let s = ti - t0;
                    0.3 + a * s
                        + b * (1.0 - (-s / tau).exp())
                        + c * (s / tau.max(1.0)).powi(2) * 1e-3
                        + noise * (rng.next() - 0.5)
                })
                .collect();
            assert_same(&t, &e, life, &format!("case {case}, n = {n}"));
            exact += (estimate_min_rate(&t, &e, life) == estimate_min_rate_direct(&t, &e, life))
                as usize;
        }
        // The chosen window's slope is recomputed by the direct formula: equal bit for bit
        // unless two windows tie to rounding.
        assert!(exact >= 395, "only {exact} of 400 bit-identical");
    }

    #[test]
    fn same_as_direct_scan_on_the_seed_data() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut curves = 0;
        for file in ["data/creep_560C.csv", "data/creep_590C.csv"] {
            let (raw, _) = crate::data::read_curves(&root.join(file)).unwrap();
            for c in raw {
                let life = c.times_h.last().unwrap() * 1.03;
                for l in [life, f64::NAN] {
                    let fast = estimate_min_rate(&c.times_h, &c.strains, l);
                    let direct = estimate_min_rate_direct(&c.times_h, &c.strains, l);
                    assert_eq!(fast.to_bits(), direct.to_bits(), "{file} {}", c.stress_mpa);
                }
                curves += 1;
            }
        }
        assert_eq!(curves, 6);
    }

    #[test]
    fn double_double_sums_are_exact_where_f64_is_not() {
        // Adding and removing 1e16 around a small value keeps the small value.
        let mut s = WindowSums::new(0.0, 0.0);
        s.add(1.0, 1.0);
        s.add(1e16, 0.0);
        s.remove(1e16, 0.0);
        assert_eq!(s.sx.to_f64(), 1.0);
        assert_eq!(s.sxx.to_f64(), 1.0);
        let q = Dd { hi: 1.0, lo: 0.0 }.div_f64(3.0);
        assert!(
            (q.mul(Dd { hi: 3.0, lo: 0.0 }).sub(Dd { hi: 1.0, lo: 0.0 }))
                .to_f64()
                .abs()
                < 1e-30
        );
    }

    #[test]
    fn long_curve() {
        // 200 k points (the direct scan needs minutes for these; this scan milliseconds).
        let n = 200_000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.5).collect();
        let e: Vec<f64> = t.iter().map(|t| 1e-4 * t + 1e-9 * t * t).collect();
        let r = estimate_min_rate(&t, &e, t[n - 1]);
        // The first window, [0, t_j] with t_j the first time ≥ 15 % of the life, has the
        // smallest slope; on a uniform grid the least-squares slope of t² is 2·mean(t) = t_j.
        let w = MIN_RATE_WINDOW_FRACTION * t[n - 1];
        let tj = *t.iter().find(|&&x| x >= w).unwrap();
        let expect = 1e-4 + 1e-9 * tj;
        assert!((r - expect).abs() / expect < 1e-12, "{r} vs {expect}");
    }
}
