//! Delta-method (Wald) standard error of ln t_r at the first `[profile] predict_stress_MPa`
//! of CONFIG, with all constants free and with the constants within 0.02 (unit box) of a
//! bound held there (README, "How sure": the narrow, lopsided life interval).
//! `cargo run --release --example wald_check -- CONFIG VALUE…` (VALUE…: the constants, model
//! order, that a local maximum-likelihood fit starts from, e.g. `profile`'s optimum).
use std::path::PathBuf;

use creepfit::config::{Overrides, RunConfig};
use creepfit::uncertainty::constrained::{Predicted, Quantity};
use creepfit::uncertainty::report::{context, loads};
use creepfit::uncertainty::{covariance, information, reference_from};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!("usage: wald_check CONFIG VALUE…");
        std::process::exit(2);
    }
    let path = PathBuf::from(&args[0]);
    let (cfg, data) = RunConfig::resolve(&path, &Overrides::default()).unwrap();
    let model = cfg.build_model().unwrap();
    let ctx = context(&cfg.likelihood_setup(&data), model.as_ref(), &data);
    let given: Vec<f64> = args[1..].iter().map(|s| s.parse().unwrap()).collect();
    let f = ctx.fit(&ctx.space, &given, false);
    let reference = reference_from(&ctx, vec![f]).unwrap();
    println!("params {:?} neg2ll {}", reference.params, reference.neg2ll);
    let load = loads(&cfg, &data, &cfg.profile)
        .into_iter()
        .map(|(_, l)| l)
        .next()
        .unwrap();
    let q = Quantity::Prediction {
        load,
        what: Predicted::LnRuptureTime,
    };
    let names = ctx.names();
    let at_bound: Vec<usize> = (0..ctx.space.len())
        .filter(|&j| {
            let u = ctx.space.to_unit_one(j, reference.params[j]);
            !(0.02..=0.98).contains(&u)
        })
        .collect();
    for (label, held) in [("all free", vec![]), ("bounds held", at_bound.clone())] {
        let mut space = ctx.space.clone();
        for &j in &held {
            space.hold(j, reference.params[j]);
        }
        let i = information(&ctx, &space, &reference.params, &reference.noise, None).unwrap();
        let c = covariance(&i);
        let u = space.to_unit(&reference.params);
        let (g, grad) = q.value_and_gradient(&ctx, &space, &u).unwrap();
        let n = grad.len();
        let mut var = 0.0;
        for a in 0..n {
            for b in 0..n {
                var += grad[a] * c[(a, b)] * grad[b];
            }
        }
        let held_names: Vec<&str> = held.iter().map(|&j| names[j]).collect();
        println!(
            "{label} (held {held_names:?}): t_r {:.5e} h, se ln {:.5}",
            g.exp(),
            var.sqrt()
        );
    }
}
