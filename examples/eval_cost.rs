//! Integrator study: for every curve of a configuration, at given constants, the accepted and
//! rejected steps of one simulation in `f64` and in dual numbers (value + 8 derivatives, as
//! the fits' Jacobians), and the time of each (mean of 200 runs), at the configuration's
//! `[solver]` tolerances. Session 83 found the tertiary stage's rejected steps with it.
//!
//! Usage: cargo run --release --example eval_cost -- CONFIG A,B,H*,h,Kc,C
use creepfit::config::{Overrides, RunConfig};
use creepfit::dual::{Dual, Scalar};
use creepfit::fit::FitSettings;
use creepfit::model::{build, Load};
use std::path::Path;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        anyhow::bail!("usage: eval_cost CONFIG A,B,H*,h,Kc,C");
    }
    let (cfg, data) = RunConfig::resolve(Path::new(&args[1]), &Overrides::default())?;
    let params: Vec<f64> = args[2]
        .split(',')
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let model = build(&cfg.model, &cfg.extensions)?;
    let settings = FitSettings::from_config(&cfg);
    let ode = settings.ode;
    let (mut tot, mut totd, mut st, mut rj) = (0.0, 0.0, 0, 0);
    for c in &data.curves {
        let load = Load::of_curve(c, settings.omega_f);
        let mut out = vec![0.0; c.times_h.len()];
        let r = model.simulate(&params, &load, &c.times_h, &mut out, &ode);
        let n = 200;
        let t0 = Instant::now();
        for _ in 0..n {
            model.simulate(&params, &load, &c.times_h, &mut out, &ode);
        }
        let dt = t0.elapsed().as_secs_f64() / n as f64 * 1e6;
        let pd: Vec<Dual<8>> = params
            .iter()
            .enumerate()
            .map(|(i, v)| Dual::var(*v, i, 1.0))
            .collect();
        let mut outd = vec![Dual::cst(0.0); c.times_h.len()];
        let rd = model.simulate_sens(&pd, &load, &c.times_h, &mut outd, &ode);
        let t0 = Instant::now();
        for _ in 0..n {
            model.simulate_sens(&pd, &load, &c.times_h, &mut outd, &ode);
        }
        let dtd = t0.elapsed().as_secs_f64() / n as f64 * 1e6;
        tot += dt;
        totd += dtd;
        st += rd.stats.steps;
        rj += rd.stats.rejected;
        println!("{} MPa: {} points, steps {} rej {} | dual steps {} rej {} | {:.1} us f64, {:.1} us dual, {}",
            c.stress_mpa, c.times_h.len(), r.stats.steps, r.stats.rejected, rd.stats.steps, rd.stats.rejected, dt, dtd, r.outcome.as_str());
    }
    println!("total {tot:.1} us f64, {totd:.1} us dual; dual steps {st} rejected {rj}");
    Ok(())
}
