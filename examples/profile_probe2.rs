//! Development probe: do held fits converge? Δ at a profile point with default and tight LM.
use creepfit::config::RunConfig;
use creepfit::model::build;
use creepfit::uncertainty::constrained::held_fit;
use creepfit::uncertainty::report::context;
use creepfit::uncertainty::{fit_reference, starts, Context};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let cfg = RunConfig::load(std::path::Path::new(&a[1])).unwrap();
    let data = cfg.load_data().unwrap();
    let model = build(&cfg.model, &cfg.extensions).unwrap();
    let ctx = context(&cfg, model.as_ref(), &data);
    let guess = creepfit::guess::initial_guess(ctx.model, ctx.curves, &ctx.space, ctx.settings.omega_f, &ctx.settings.ode);
    let st = starts(&ctx, &[guess.params], 8, 1);
    let r = fit_reference(&ctx, &st).unwrap();
    println!("ref {:?} {} fits {}", r.params, r.neg2ll, r.fits);
    let mut tight = ctx.warm;
    tight.lm.ftol = 1e-13;
    tight.lm.xtol = 1e-14;
    tight.lm.gtol = 1e-14;
    tight.lm.max_iterations = 2000;
    let mut tight_ode = tight;
    tight_ode.ode.rtol = 1e-10;
    let ctx_t = Context { curves: ctx.curves, space: ctx.space.clone(), warm: tight, ..ctx };
    let ctx_o = Context { curves: ctx.curves, space: ctx.space.clone(), warm: tight_ode, settings: tight_ode, ..ctx };
    // free refit with tight settings
    let f = ctx_t.fit(&ctx.space, &r.params, true);
    println!("tight free refit {} ({:?}, {} it)", f.neg2ll - r.neg2ll, f.termination, f.iterations);
    if a.get(2).map(|s| s.as_str()) == Some("truthworld") {
        let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(a[3].clone()).unwrap()).unwrap();
        let t: Vec<f64> = truth["constants"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let sds: Vec<f64> = truth["noise_sd"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let phi = truth["noise_phi"].as_f64().unwrap();
        let noise = creepfit::errmodel::ErrorModel { strain: sds.iter().map(|&s| creepfit::errmodel::Ar1::with_marginal(s, phi)).collect(), lifetime_sd: 0.01 };
        let ev = creepfit::likelihood::raw_objective(ctx.model, ctx.curves, &ctx.settings).evaluate(&t);
        let res = creepfit::likelihood::residuals_at(ctx.model, ctx.curves, &t, &ctx.settings).unwrap();
        let est = creepfit::errmodel::ErrorModel::estimate(&res, 0.01);
        println!("data at truth: noise {:?} life {:?}", est.strain.iter().map(|p| (p.marginal_sd(), p.phi)).collect::<Vec<_>>(), res.lifetime);
        println!("truth noise {:?} phi {phi}", sds);
        println!("neg2ll at truth {} vs ref {}", est.neg2ll(&res), r.neg2ll);
        let mut sums = vec![0.0; 6];
        let nb = 12;
        for b in 0..nb {
            let mut rng = creepfit::diagnose::bootstrap::replicate_rng(5, 77, b);
            let data = creepfit::diagnose::bootstrap::replicate_data(ctx.curves, &ev, &noise, &mut rng);
            let c = Context { curves: &data, space: ctx.space.clone(), ..ctx };
            let f0 = c.fit(&c.space, &t, true);
            let f1 = c.fit(&c.space, &r.params, true);
            let f = if f0.neg2ll < f1.neg2ll { f0 } else { f1 };
            let mut line = format!("b{b}:");
            for j in 0..6 {
                let h1 = held_fit(&c, j, t[j], &f.params, true);
                let h2 = held_fit(&c, j, t[j], &t, true);
                let v = (h1.neg2ll.min(h2.neg2ll) - f.neg2ll).max(0.0);
                sums[j] += v;
                line += &format!(" {v:.2}");
            }
            println!("{line}");
        }
        println!("means {:?}", sums.iter().map(|s| s / nb as f64).collect::<Vec<_>>());
        return;
    }
    if a.get(2).map(|s| s.as_str()) == Some("cal") {
        let cons = creepfit::uncertainty::report::calibration_constants(&ctx, &r);
        let lowest = ctx.curves.iter().map(|c| c.stress_mpa).fold(f64::INFINITY, f64::min);
        let load = creepfit::model::Load { stress_mpa: (0.85 * lowest).round(), omega_f: 1.0 / 3.0 };
        let q = creepfit::uncertainty::constrained::Quantity::Prediction { load, what: creepfit::uncertainty::constrained::Predicted::LnRuptureTime };
        let c = creepfit::uncertainty::calibrate::bartlett(&ctx, &r, &cons, &[("rupture".into(), q)], 20, 7003);
        println!("{:?}", c);
        return;
    }
    if a.get(2).map(|s| s.as_str()) == Some("boot") {
        for b in 0..8 {
            let mut rng = creepfit::diagnose::bootstrap::replicate_rng(1, 99, b);
            let data = creepfit::diagnose::bootstrap::replicate_data(ctx.curves, &r.eval, &r.noise, &mut rng);
            let c = Context { curves: &data, space: ctx.space.clone(), ..ctx };
            let f = c.fit(&c.space, &r.params, true);
            let f2 = c.fit(&c.space, &r.params, false);
            let mut line = format!("b{b} free {:.3} ({:?} {}it) cold-geo {:.3} |", f.neg2ll, f.termination, f.iterations, f2.neg2ll - f.neg2ll);
            for j in 0..6 {
                let h = held_fit(&c, j, r.params[j], &f.params, true);
                line += &format!(" {:.2}", h.neg2ll - f.neg2ll);
            }
            let du: Vec<f64> = ctx.space.to_unit(&f.params).iter().zip(ctx.space.to_unit(&r.params)).map(|(a, b)| a - b).collect();
            println!("{line} du {:.3?}", du);
            println!("   noise ref {:?} fit {:?}", r.noise.strain.iter().map(|p| (p.marginal_sd(), p.phi)).collect::<Vec<_>>(), f.noise.strain.iter().map(|p| (p.marginal_sd(), p.phi)).collect::<Vec<_>>());
        }
        return;
    }
    if let Some(tp) = a.get(2) {
        let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(tp).unwrap()).unwrap();
        let t: Vec<f64> = truth["constants"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let ft = ctx.fit(&ctx.space, &t, true);
        println!("free fit from truth: {} {:?}", ft.neg2ll - r.neg2ll, ft.params);
        for j in 0..6 {
            let x = held_fit(&ctx, j, t[j], &r.params, true);
            let y = held_fit(&ctx, j, t[j], &t, true);
            let z = held_fit(&ctx, j, t[j], &ft.params, true);
            println!("held {j} at truth: from ref {:.3} from truth {:.3} from truth-fit {:.3}", x.neg2ll - r.neg2ll, y.neg2ll - r.neg2ll, z.neg2ll - r.neg2ll);
        }
        return;
    }
    for j in 0..6 {
        let u = ctx.space.to_unit_one(j, r.params[j]);
        for du in [-0.02, 0.02] {
            let v = ctx.space.from_unit_one(j, (u + du).clamp(0.0, 1.0));
            let a = held_fit(&ctx, j, v, &r.params, true);
            let b = held_fit(&ctx_t, j, v, &r.params, true);
            let c = held_fit(&ctx_o, j, v, &r.params, true);
            println!("{j} du {du}: default {:.4} ({:?} {}it) tight {:.4} ({:?} {}it) tight-ode {:.4}", a.neg2ll - r.neg2ll, a.termination, a.iterations, b.neg2ll - r.neg2ll, b.termination, b.iterations, c.neg2ll - r.neg2ll);
        }
    }
}
