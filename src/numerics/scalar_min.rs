//! Minimising a function of one variable on an interval: a uniform grid, then golden-section
//! search about the best grid point. For the error model's and the scatter's one-dimensional
//! profiles, which are smooth but can have several local minima on the whole interval (the
//! grid finds the best basin; the section refines it).

/// How [`grid_golden`] searches `[lo, hi]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridGolden {
    /// Grid intervals: f is evaluated at lo + i·(hi − lo)/grid, i = 0..=grid.
    pub grid: usize,
    /// Most golden-section iterations.
    pub iterations: usize,
    /// The section stops when its bracket is narrower than this.
    pub tol: f64,
    /// Keep the section's end point when it ties with the best grid point (`<=`), or only
    /// when it is strictly better (`<`).
    pub tie_to_section: bool,
    /// Where the section is centred when no grid value is below +∞ (NaN everywhere).
    pub fallback: f64,
}

/// The minimiser of `f` on `[lo, hi]`: the grid's best point x_g (the first of equal values),
/// then golden section on [x_g − step, x_g + step] ∩ [lo, hi]; the bracket's midpoint if it is
/// better than x_g (or as good, with `tie_to_section`), else x_g. Returns (x, f(x) as
/// compared: the midpoint's value or the grid's best).
pub fn grid_golden(
    lo: f64,
    hi: f64,
    opts: GridGolden,
    mut f: impl FnMut(f64) -> f64,
) -> (f64, f64) {
    let step = (hi - lo) / opts.grid as f64;
    let mut best = (f64::INFINITY, opts.fallback);
    for i in 0..=opts.grid {
        let x = lo + i as f64 * step;
        let v = f(x);
        if v < best.0 {
            best = (v, x);
        }
    }
    let (mut a, mut b) = ((best.1 - step).max(lo), (best.1 + step).min(hi));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..opts.iterations {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(x2);
        }
        if b - a < opts.tol {
            break;
        }
    }
    let x = 0.5 * (a + b);
    let fx = f(x);
    let better = if opts.tie_to_section {
        fx <= best.0
    } else {
        fx < best.0
    };
    if better {
        (x, fx)
    } else {
        (best.1, best.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OPTS: GridGolden = GridGolden {
        grid: 40,
        iterations: 60,
        tol: 1e-10,
        tie_to_section: true,
        fallback: 0.0,
    };

    /// Closed-form minima: an interior quadratic, a minimum on each bound, and the better of
    /// two basins (the grid picks it, the section refines it).
    #[test]
    fn finds_known_minima() {
        let (x, f) = grid_golden(-1.0, 2.0, OPTS, |x| (x - 0.3137).powi(2) + 1.5);
        assert!(
            (x - 0.3137).abs() < 1e-5 && (f - 1.5).abs() < 1e-10,
            "{x} {f}"
        );
        let (x, _) = grid_golden(0.0, 5.0, OPTS, |x| x + 1.0);
        assert!(x.abs() < 1e-9, "{x}");
        let (x, _) = grid_golden(0.0, 5.0, OPTS, |x| -x);
        assert!((x - 5.0).abs() < 1e-9, "{x}");
        // Two wells, at −0.6 (depth 1) and +0.7 (depth 2): the deeper one.
        let two = |x: f64| {
            -((-(x + 0.6f64).powi(2) * 50.0).exp()) - 2.0 * (-(x - 0.7f64).powi(2) * 50.0).exp()
        };
        let (x, _) = grid_golden(-1.0, 1.0, OPTS, two);
        assert!((x - 0.7).abs() < 1e-4, "{x}");
    }

    /// A flat function: the grid's first point is kept without the tie rule, the section's
    /// midpoint with it.
    #[test]
    fn ties_follow_the_rule() {
        let (x, _) = grid_golden(
            0.0,
            1.0,
            GridGolden {
                tie_to_section: false,
                ..OPTS
            },
            |_| 1.0,
        );
        assert_eq!(x, 0.0);
        let (x, _) = grid_golden(0.0, 1.0, OPTS, |_| 1.0);
        assert!(x > 0.0 && x < 1.0 / 40.0, "{x}");
    }
}
