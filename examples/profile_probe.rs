//! Development probe: smoothness of the predicted quantities around the reference optimum.
//! `cargo run --release --example profile_probe -- CONFIG STRESS`
use creepfit::config::RunConfig;
use creepfit::model::{build, Load};
use creepfit::uncertainty::constrained::{Predicted, Quantity};
use creepfit::uncertainty::report::context;
use creepfit::uncertainty::{fit_reference, starts};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let cfg = RunConfig::load(std::path::Path::new(&a[1])).unwrap();
    let stress: f64 = a[2].parse().unwrap();
    let data = cfg.load_data().unwrap();
    let model = build(&cfg.model, &cfg.extensions).unwrap();
    let ctx = context(&cfg, model.as_ref(), &data);
    let st = starts(&ctx, &[cfg.starts_all_given().unwrap()], 8, 1);
    let r = fit_reference(&ctx, &st).unwrap();
    println!("ref {:?} {}", r.params, r.neg2ll);
    let load = Load {
        stress_mpa: stress,
        omega_f: cfg.objective.omega_f,
    };
    for what in [
        Predicted::LnRuptureTime,
        Predicted::LnMinRate,
        Predicted::LnRuptureStrain,
    ] {
        let q = Quantity::Prediction { load, what };
        let u0 = ctx.space.to_unit(&r.params);
        let (g, grad) = q.value_and_gradient(&ctx, &ctx.space, &u0).unwrap();
        println!("{what:?} g {g} grad {grad:?}");
        let n2: f64 = grad.iter().map(|v| v * v).sum();
        for d in [-0.07, -0.02, -0.005, 0.005, 0.02, 0.07] {
            let u: Vec<f64> = u0
                .iter()
                .zip(&grad)
                .map(|(a, b)| (a + d * b / n2).clamp(0.0, 1.0))
                .collect();
            let mut x = vec![0.0; 6];
            ctx.space.from_unit(&u, &mut x);
            println!(
                "  along grad d {d}: dg {:?}",
                q.value(&ctx, &x).map(|v| v - g)
            );
        }
        let (gh, se) = creepfit::uncertainty::profile::quantity_se(&ctx, &r, &q);
        for dir in [-1.0, -0.5, 0.5, 1.0] {
            let t = gh + dir * se * 1.96;
            let f = creepfit::uncertainty::constrained::constrained_fit(
                &ctx,
                &q,
                t,
                q.penalty_fraction() * se,
                &r.params,
                true,
            );
            println!(
                "  target {t} -> g {} d {} {:?} it {} {:?} x {:?}",
                f.coord,
                f.neg2ll - r.neg2ll,
                f.termination,
                f.iterations,
                f.failure,
                f.params
            );
        }
        for k in [1usize, 4] {
            let mut line = String::new();
            for i in -4i32..=4 {
                let mut u = u0.clone();
                u[k] = (u[k] + i as f64 * 1e-4).clamp(0.0, 1.0);
                let mut x = vec![0.0; 6];
                ctx.space.from_unit(&u, &mut x);
                line += &format!(" {:.9}", q.value(&ctx, &x).unwrap_or(f64::NAN) - g);
            }
            println!("  coord {k}:{line}");
        }
    }
}

#[allow(dead_code)]
fn unused() {}
