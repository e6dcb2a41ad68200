//! Solver study of the maximum-likelihood fits: the fresh starts of `diagnose`'s fits on the
//! data (its Latin hypercube, its seed) of one model variant, each fitted by maximum
//! likelihood without specimen effects on `diagnose`'s direct path (it also fits each start
//! white first and keeps the better); prints every fit's −2 ln L,
//! iterations, termination and time, then the totals (iterations, fits at the iteration
//! limit, wall time); with `hier`, the best of them then gets its specimen effects.
//! Two solver settings are compared fit by fit on the same starts (docs/DIAGNOSE.md, "Where
//! the time goes today").
//!
//! Usage: cargo run --release --example ml_study -- CONFIG VARIANT STARTS [hier]
//! (VARIANT: 0 the base model, k the k-th extension of the configuration's diagnosis.)
use std::path::Path;
use std::time::Instant;

use creepfit::config::{Overrides, RunConfig};
use creepfit::data::binned;
use creepfit::likelihood::{ml_fit, with_specimens, MlOptions, SpecimenOptions};
use creepfit::lsq::Termination;
use creepfit::sampling::latin_hypercube;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        anyhow::bail!("usage: ml_study CONFIG VARIANT STARTS [hier]");
    }
    let (cfg, data) = RunConfig::resolve(Path::new(&args[1]), &Overrides::default())?;
    let variant: usize = args[2].parse()?;
    let n_starts: usize = args[3].parse()?;
    let hier = args.get(4).is_some_and(|a| a == "hier");
    let setup = cfg.diagnose_setup()?;
    let dc = &cfg.diagnose;
    let curves: Vec<_> = data
        .curves
        .iter()
        .map(|c| binned(c, dc.max_points))
        .collect();
    let Some(spec) = setup.variants.get(variant) else {
        anyhow::bail!(
            "variant {variant}: the diagnosis has {}",
            setup.variants.len()
        );
    };
    let settings = setup.settings;
    let plain = MlOptions {
        lifetime_sd_floor: dc.lifetime_sd_floor,
        white_first: false,
        specimen: SpecimenOptions::NONE,
        hold_scatter: None,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(dc.seed);
    let starts: Vec<Vec<f64>> = latin_hypercube(n_starts, spec.space.n_free(), &mut rng)
        .into_iter()
        .map(|u| {
            let mut x = spec.space.fixed.clone();
            spec.space.from_unit(&u, &mut x);
            x
        })
        .collect();
    let t0 = Instant::now();
    let fits: Vec<_> = starts
        .par_iter()
        .map(|s| {
            let t = Instant::now();
            let f = ml_fit(
                spec.model.as_ref(),
                &curves,
                &spec.space,
                s,
                &settings,
                &plain,
            );
            (f, t.elapsed().as_secs_f64())
        })
        .collect();
    let wall = t0.elapsed().as_secs_f64();
    let (mut iterations, mut at_limit, mut ok) = (0, 0, 0);
    for (i, (f, t)) in fits.iter().enumerate() {
        iterations += f.iterations;
        at_limit += usize::from(f.termination == Termination::IterationLimit);
        ok += usize::from(f.ok());
        println!(
            "start {i:3}  -2lnL {:12.3}  iterations {:4}  {:<20} {t:.2} s",
            f.neg2ll,
            f.iterations,
            f.termination.as_str()
        );
    }
    println!(
        "{}: {ok} of {n_starts} fits evaluable, {iterations} iterations, {at_limit} at the limit, {wall:.1} s",
        spec.name
    );
    if hier {
        let Some(best) = fits
            .iter()
            .map(|(f, _)| f)
            .filter(|f| f.ok())
            .min_by(|a, b| a.neg2ll.total_cmp(&b.neg2ll))
        else {
            anyhow::bail!("no fit to add specimen effects to");
        };
        let t = Instant::now();
        let spo = setup
            .specimen_effects
            .resolve(&curves, setup.specimen_scatter)
            .0;
        let h = with_specimens(
            best.clone(),
            spec.model.as_ref(),
            &curves,
            &spec.space,
            &settings,
            &MlOptions {
                specimen: spo,
                white_first: true,
                ..plain
            },
        );
        println!(
            "with specimen effects: -2lnL {:.3}, {} iterations, {}, {:.2} s, scatter {:?}",
            h.neg2ll,
            h.iterations,
            h.termination.as_str(),
            t.elapsed().as_secs_f64(),
            h.specimen.as_ref().map(|s| s.scatter.clone())
        );
    }
    Ok(())
}
