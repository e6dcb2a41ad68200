//! Study of the per-temperature initial guess on random synthetic data: N data sets (seeds
//! SEED..SEED+N) of KHD with A and Kc Arrhenius about 575 °C, nine curves at 560/575/590 °C,
//! the truth drawn about the seed steel's (A, h, Kc ×/÷ 2, B ±15 %, H* 0.45–0.65, C 4–6,
//! Q_A 250–450, Q_Kc 150–350 kJ/mol), uniform reading noise of sd 0.5 % of the rupture strain.
//! Per set: the guess's activation energies, then a local fit at w = 1 from the guess
//! (iterations, evaluations, ms) and whether it reaches the objective of a fit from the truth.
//! README ("Several temperatures") compares the guess with and without its second pass
//! (measured with the `if temps.len() > 1` of `guess::per_temperature` switched off).
//!
//! Usage: cargo run --release --example guess_study -- N SEED
use creepfit::config::RunConfig;
use creepfit::data::{estimate_min_rate, Curve};
use creepfit::fit::{local_fit, FitSettings};
use creepfit::model::objective::ParamSpace;
use creepfit::model::{build, with_laws, LawKind, Load, Scale};
use creepfit::ode::OdeOptions;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = args[1].parse().unwrap();
    let seed0: u64 = args[2].parse().unwrap();
    use LawKind::*;
    let model = with_laws(
        build("khd", &[]).unwrap(),
        &[Arrhenius, Constant, Constant, Constant, Arrhenius, Constant],
        575.0,
    );
    use Scale::Log;
    let space = ParamSpace::new(
        vec![1e-11, 0.05, 0.2, 1e3, 1e-7, 1.5, 0.0, 0.0],
        vec![1e-7, 0.3, 0.9, 1e6, 1e-3, 10.0, 800.0, 800.0],
        vec![
            Log,
            Scale::Linear,
            Scale::Linear,
            Log,
            Log,
            Scale::Linear,
            Scale::Linear,
            Scale::Linear,
        ],
    );
    let cfg = RunConfig::load(Path::new("configs/560C.toml")).unwrap();
    let settings = FitSettings::from_config(&cfg);
    let ode = OdeOptions {
        rtol: 1e-10,
        atol: 1e-13,
        ..OdeOptions::default()
    };
    let tests = [
        (560.0, 85.0),
        (560.0, 100.0),
        (560.0, 110.0),
        (575.0, 80.0),
        (575.0, 95.0),
        (575.0, 105.0),
        (590.0, 75.0),
        (590.0, 90.0),
        (590.0, 100.0),
    ];
    for seed in seed0..seed0 + n {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let lf = |rng: &mut ChaCha8Rng, x: f64, f: f64| x * f.powf(rng.gen_range(-1.0..1.0));
        let truth = [
            lf(&mut rng, 1.2e-9, 2.0),
            0.12 * rng.gen_range(0.85..1.15),
            rng.gen_range(0.45..0.65),
            lf(&mut rng, 6e4, 2.0),
            lf(&mut rng, 1.5e-5, 2.0),
            rng.gen_range(4.0..6.0),
            rng.gen_range(250.0..450.0),
            rng.gen_range(150.0..350.0),
        ];
        let mut curves = Vec::new();
        let mut ok = true;
        for &(t, s) in &tests {
            let load = Load::new(s, t, 1.0 / 3.0);
            let r = model.simulate(&truth, &load, &[], &mut [], &ode);
            if !r.ruptured() {
                ok = false;
                break;
            }
            let times: Vec<f64> = (0..36)
                .map(|k| r.t_end * (1.0 - (1.0 - k as f64 / 36.0).powf(1.5)))
                .collect();
            let mut e = vec![0.0; times.len()];
            model.simulate(&truth, &load, &times, &mut e, &ode);
            for v in e.iter_mut().skip(1) {
                *v += 0.005 * r.strain_end * (rng.gen::<f64>() - 0.5) * 3.46;
            }
            curves.push(Curve {
                temperature_c: t,
                stress_mpa: s,
                specimen: None,
                groups: None,
                min_rate_estimated: estimate_min_rate(&times, &e, r.t_end),
                times_h: times,
                strains: e,
                rupture_time_h: Some(r.t_end),
                rupture_strain: r.strain_end,
                min_rate_measured: None,
            });
        }
        if !ok {
            println!("{seed} skipped");
            continue;
        }
        let w = vec![1.0; curves.len()];
        let ft = local_fit(model.as_ref(), &curves, &space, &w, &truth, "", &settings);
        let g = model.initial_guess(&curves, &space, settings.omega_f, &settings.ode);
        let t0 = std::time::Instant::now();
        let f = local_fit(
            model.as_ref(),
            &curves,
            &space,
            &w,
            &g.params,
            "",
            &settings,
        );
        let el = t0.elapsed().as_secs_f64() * 1e3;
        let rel = (f.eval.objective - ft.eval.objective) / ft.eval.objective;
        println!("{seed} it {} ev {} ms {:.1} rel {:.2e} basin {} gQ {:.0} {:.0} fQ {:.0} {:.0} tQ {:.0} {:.0}", f.lm.iterations, f.lm.evaluations, el, rel, rel < 1e-4, g.params[6], g.params[7], f.params[6], f.params[7], truth[6], truth[7]);
    }
}
