//! Pure geometry of the plots: which points are drawable, axis ranges that cover what is
//! drawn, clipping lines to the axes and cutting runaway predictions.

/// Coordinates with a larger magnitude are treated like non-finite ones (skipped).
pub const MAX_ABS: f64 = 1e150;
/// Smallest value shown on a log axis.
pub const LOG_MIN: f64 = 1e-150;
/// Most decades a log axis spans (from the largest value down); smaller values sit at the floor.
pub const MAX_LOG_DECADES: f64 = 40.0;

/// A point that can be drawn: finite, magnitudes at most [`MAX_ABS`].
pub fn plottable(p: (f64, f64)) -> bool {
    plottable_value(p.0) && plottable_value(p.1)
}

pub fn plottable_value(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_ABS
}

/// Min and max of the plottable values, `None` if there are none.
pub fn data_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values
        .filter(|v| plottable_value(*v))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// Widens `[lo, hi]` by `frac` of its span on both sides; a degenerate range (one value, or a
/// span below 1e-12 of the magnitude) becomes `c ± 10 %` of `c` (or `±1` around zero).
pub fn padded((lo, hi): (f64, f64), frac: f64) -> (f64, f64) {
    let span = hi - lo;
    let scale = lo.abs().max(hi.abs());
    if span.is_finite() && span > 1e-12 * scale && span > 0.0 {
        (lo - frac * span, hi + frac * span)
    } else {
        let c = 0.5 * lo + 0.5 * hi;
        let h = if c != 0.0 { 0.1 * c.abs() } else { 1.0 };
        (c - h, c + h)
    }
}

/// An axis that starts at 0 (time, strain) and covers the values: `[0, max]` padded by
/// `frac` at the top, or padded on both sides when a value is negative; `[0, 1]` without
/// values.
pub fn from_zero(range: Option<(f64, f64)>, frac: f64) -> (f64, f64) {
    let (lo, hi) = range.unwrap_or((0.0, 1.0));
    let (lo, hi) = (lo.min(0.0), hi.max(0.0));
    let (plo, phi) = padded((lo, hi), frac);
    (if lo >= 0.0 { 0.0 } else { plo }, phi)
}

/// A log axis range covering the (positive) values, padded by 5 % of the decades (at least
/// 0.1 decade), or one decade each side of a single value.
pub fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold(None, |acc: Option<(f64, f64)>, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
        .unwrap_or((1.0, 1.0));
    let (l0, l1) = (
        lo.clamp(LOG_MIN, MAX_ABS).log10(),
        hi.clamp(LOG_MIN, MAX_ABS).log10(),
    );
    let l0 = l0.max(l1 - MAX_LOG_DECADES);
    let span = l1 - l0;
    let pad = if span > 1e-9 {
        (0.05 * span).max(0.1)
    } else {
        1.0
    };
    (10f64.powf(l0 - pad), 10f64.powf(l1 + pad))
}

/// About `max` integer ticks 1..=n with a 1-2-5 step.
pub fn integer_ticks(n: usize, max: usize) -> Vec<f64> {
    let mut step = 1usize;
    'search: for decade in [
        1usize, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000,
    ] {
        for m in [1usize, 2, 5] {
            step = m * decade;
            if n / step < max {
                break 'search;
            }
        }
    }
    let mut ticks = vec![1.0];
    ticks.extend(
        (1..=n / step)
            .map(|i| (i * step) as f64)
            .filter(|&v| v > 1.0),
    );
    ticks
}

/// Whether `p` is plottable and inside the rectangle.
pub fn within(p: (f64, f64), x: (f64, f64), y: (f64, f64)) -> bool {
    plottable(p) && p.0 >= x.0 && p.0 <= x.1 && p.1 >= y.0 && p.1 <= y.1
}

/// The plottable points inside the axes.
pub fn inside(
    points: &[(f64, f64)],
    x: (f64, f64),
    y: (f64, f64),
) -> impl Iterator<Item = (f64, f64)> + '_ {
    points.iter().copied().filter(move |&p| within(p, x, y))
}

/// The part of a curve (in drawing order) up to where it first leaves `x ≤ x_max` and
/// `|y| ≤ y_max`, cut at that crossing (interpolated), and whether it was cut. Non-plottable
/// points are kept (they break the line where they are).
pub fn cut_polyline(points: &[(f64, f64)], x_max: f64, y_max: f64) -> (Vec<(f64, f64)>, bool) {
    let ok = |p: (f64, f64)| p.0 <= x_max && p.1.abs() <= y_max;
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(points.len());
    let mut last: Option<(f64, f64)> = None;
    for &p in points {
        if !plottable(p) {
            out.push(p);
            last = None;
            continue;
        }
        if ok(p) {
            out.push(p);
            last = Some(p);
            continue;
        }
        // p lies beyond a limit: end at the crossing from the last drawable point.
        if let Some(q) = last {
            let mut t: f64 = 1.0;
            if p.0 > x_max && p.0 != q.0 {
                t = t.min((x_max - q.0) / (p.0 - q.0));
            }
            if p.1.abs() > y_max && p.1 != q.1 {
                let bound = y_max.copysign(p.1);
                t = t.min((bound - q.1) / (p.1 - q.1));
            }
            let t = t.clamp(0.0, 1.0);
            let c = (q.0 + t * (p.0 - q.0), q.1 + t * (p.1 - q.1));
            if c != q {
                out.push(c);
            }
        }
        return (out, true);
    }
    (out, false)
}

/// Liang–Barsky clipping of the segment `p`–`q` to the rectangle; unclipped ends are returned
/// bit-for-bit so consecutive segments join exactly.
pub fn clip_segment(
    p: (f64, f64),
    q: (f64, f64),
    x: (f64, f64),
    y: (f64, f64),
) -> Option<((f64, f64), (f64, f64))> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (pk, qk) in [
        (-dx, p.0 - x.0),
        (dx, x.1 - p.0),
        (-dy, p.1 - y.0),
        (dy, y.1 - p.1),
    ] {
        if pk == 0.0 {
            if qk < 0.0 {
                return None;
            }
        } else {
            let r = qk / pk;
            if pk < 0.0 {
                if r > t1 {
                    return None;
                }
                t0 = t0.max(r);
            } else {
                if r < t0 {
                    return None;
                }
                t1 = t1.min(r);
            }
        }
    }
    let a = if t0 == 0.0 {
        p
    } else {
        (p.0 + t0 * dx, p.1 + t0 * dy)
    };
    let b = if t1 == 1.0 {
        q
    } else {
        (p.0 + t1 * dx, p.1 + t1 * dy)
    };
    Some((a, b))
}

/// Splits a polyline at non-plottable points and clips it to the rectangle; returns the
/// visible pieces (each with at least two points).
pub fn clip_polyline(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut pieces = Vec::new();
    let mut current: Vec<(f64, f64)> = Vec::new();
    let finish = |current: &mut Vec<(f64, f64)>, pieces: &mut Vec<Vec<(f64, f64)>>| {
        if current.len() >= 2 {
            pieces.push(std::mem::take(current));
        } else {
            current.clear();
        }
    };
    for w in points.windows(2) {
        let (p, q) = (w[0], w[1]);
        let clipped = if plottable(p) && plottable(q) {
            clip_segment(p, q, x, y)
        } else {
            None
        };
        match clipped {
            Some((a, b)) => {
                if current.last() != Some(&a) {
                    finish(&mut current, &mut pieces);
                    current.push(a);
                }
                current.push(b);
            }
            None => finish(&mut current, &mut pieces),
        }
    }
    finish(&mut current, &mut pieces);
    pieces
}

/// At most `max` of `points`, evenly by index, the first and the last kept: the markers a
/// plot draws of a dense measured curve (the line of a curve keeps every point).
pub fn thin_markers(points: &[(f64, f64)], max: usize) -> Vec<(f64, f64)> {
    let n = points.len();
    let max = max.max(2);
    if n <= max {
        return points.to_vec();
    }
    (0..max)
        .map(|k| points[(k * (n - 1) + (max - 1) / 2) / (max - 1)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping() {
        let r = (0.0, 1.0);
        assert_eq!(
            clip_segment((0.2, 0.2), (0.8, 0.8), r, r),
            Some(((0.2, 0.2), (0.8, 0.8)))
        );
        assert_eq!(
            clip_segment((0.5, 0.5), (0.5, 2.0), r, r),
            Some(((0.5, 0.5), (0.5, 1.0)))
        );
        assert_eq!(clip_segment((2.0, 2.0), (3.0, 3.0), r, r), None);
        assert_eq!(
            clip_segment((-1.0, 0.5), (2.0, 0.5), r, r),
            Some(((0.0, 0.5), (1.0, 0.5)))
        );
        let pieces = clip_polyline(
            &[
                (0.1, 0.1),
                (0.2, 0.2),
                (0.3, 5.0),
                (0.4, 0.4),
                (0.5, 0.5),
                (f64::NAN, 0.5),
                (0.7, 0.7),
                (0.8, 0.8),
            ],
            r,
            r,
        );
        assert_eq!(pieces.len(), 3, "{pieces:?}");
        assert_eq!(pieces[0].first(), Some(&(0.1, 0.1)));
        assert!(pieces.iter().all(|p| p.len() >= 2));
        assert!(pieces
            .iter()
            .flatten()
            .all(|p| (0.0..=1.0).contains(&p.0) && (0.0..=1.0).contains(&p.1)));
    }

    #[test]
    fn cutting_a_runaway_curve() {
        // Inside the limits: unchanged.
        let pts = vec![(0.0, 0.0), (1.0, 1.0), (2.0, 2.0)];
        assert_eq!(cut_polyline(&pts, 3.0, 3.0), (pts.clone(), false));
        // Past x_max: cut at the crossing x = 1.5.
        let (c, cut) = cut_polyline(&pts, 1.5, 10.0);
        assert!(cut);
        assert_eq!(c, vec![(0.0, 0.0), (1.0, 1.0), (1.5, 1.5)]);
        // A strain blowing up: cut where |y| reaches y_max, nothing after.
        let pts = vec![(0.0, 0.0), (1.0, 1.0), (2.0, 1e9), (3.0, 1.0)];
        let (c, cut) = cut_polyline(&pts, 10.0, 5.0);
        assert!(cut);
        assert_eq!(c.len(), 3);
        let end = c[2];
        assert!(
            (end.1 - 5.0).abs() < 1e-9 && end.0 > 1.0 && end.0 < 1.00001,
            "{end:?}"
        );
        // The first point already beyond: nothing drawn.
        assert_eq!(
            cut_polyline(&[(5.0, 0.0), (6.0, 0.0)], 1.0, 1.0),
            (vec![], true)
        );
    }

    #[test]
    fn ranges() {
        assert_eq!(padded((2.0, 2.0), 0.05), (1.8, 2.2));
        assert_eq!(padded((0.0, 0.0), 0.05), (-1.0, 1.0));
        assert_eq!(from_zero(Some((3.0, 10.0)), 0.0), (0.0, 10.0));
        let (lo, hi) = from_zero(Some((-1.0, 10.0)), 0.1);
        assert!(lo < -1.0 && hi > 10.0);
        assert_eq!(from_zero(None, 0.0), (0.0, 1.0));
        let (lo, hi) = log_range([0.5].into_iter());
        assert!(lo > 0.0 && lo < 0.5 && hi > 0.5);
        let (lo, hi) = log_range(std::iter::empty());
        assert!(lo > 0.0 && hi > lo);
        assert_eq!(integer_ticks(5, 10), vec![1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!(integer_ticks(5000, 10).len() <= 11);
    }

    #[test]
    fn marker_thinning_keeps_ends() {
        let pts: Vec<(f64, f64)> = (0..1000).map(|i| (i as f64, 0.0)).collect();
        let t = thin_markers(&pts, 50);
        assert_eq!(t.len(), 50);
        assert_eq!(t[0], pts[0]);
        assert_eq!(t[49], pts[999]);
        assert!(t.windows(2).all(|w| w[0].0 < w[1].0));
        assert_eq!(thin_markers(&pts[..10], 50).len(), 10);
    }
}
