//! A long logged curve: loaded whole (every point kept, sorted, the minimum rate estimated
//! over all of them), and plotted from a thinned copy. Timings are `scripts/bench_large.sh`'s.

use std::fmt::Write as _;

use creepfit::data::{self, LoadOptions};
use creepfit::report::tables::thin;

#[test]
fn long_logged_curve_loads_whole() {
    // ε = a·t + b·(1 − e^(−t/τ)) + c·t⁴ (%), logged every 0.05 h over 98 % of a 10,000 h
    // life (196,000 rows, written in reverse time order), two short curves besides.
    let (a, b, tau, c) = (1e-4, 0.2, 300.0, 2.5e-16);
    let eps = |t: f64| a * t + b * (1.0 - (-t / tau).exp()) + c * t.powi(4);
    let mut text = String::from("temperature_C,stress_MPa,time_h,strain_pct\n");
    let n = 196_000;
    for k in (0..n).rev() {
        let t = k as f64 * 0.05;
        writeln!(text, "560,100,{t},{}", eps(t)).unwrap();
    }
    for s in [90, 110] {
        for k in 0..50 {
            let t = k as f64 * 200.0;
            writeln!(text, "560,{s},{t},{}", eps(t)).unwrap();
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let cp = dir.path().join("curves.csv");
    let rp = dir.path().join("ruptures.csv");
    std::fs::write(&cp, text).unwrap();
    std::fs::write(
        &rp,
        "temperature_C,stress_MPa,rupture_time_h\n560,90,10000\n560,100,10000\n560,110,10000\n",
    )
    .unwrap();
    let ds = data::load(&cp, &rp, &LoadOptions::default()).unwrap();
    assert!(ds.warnings.is_empty(), "{:?}", ds.warnings);
    let cu = &ds.curves[1];
    assert_eq!(cu.times_h.len(), n);
    assert!(cu.times_h.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(cu.strains[n - 1], eps((n - 1) as f64 * 0.05) / 100.0);
    // The smallest slope over windows of 15 % of life lies a little above the true minimum
    // rate (the curve of `data::tests::min_rate_three_stage_curve`, same bound).
    let true_min = (0..10_000)
        .map(|k| {
            let t = k as f64;
            a + b / tau * (-t / tau).exp() + 4.0 * c * t.powi(3)
        })
        .fold(f64::INFINITY, f64::min)
        / 100.0;
    let rel = (cu.min_rate_estimated - true_min) / true_min;
    assert!(
        rel > 0.0 && rel < 0.05,
        "estimate {} vs {true_min}",
        cu.min_rate_estimated
    );
}

#[test]
fn thinning_keeps_ends_and_spacing() {
    let v: Vec<usize> = (0..1_000_003).collect();
    let t = thin(v, 2000);
    assert!(t.len() <= 2001 && t.len() >= 1000, "{}", t.len());
    assert_eq!((t[0], *t.last().unwrap()), (0, 1_000_002));
    let gaps: Vec<usize> = t.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(gaps[..gaps.len() - 1].iter().all(|g| *g == gaps[0]));
    let short: Vec<u8> = (0..10).collect();
    assert_eq!(thin(short.clone(), 2000), short);
}
