//! Solver study: runs a sub-sample of a sweep's local fits (every STRIDE-th of STARTS Latin-
//! hypercube starts, every w) with the configuration's solver settings and prints throughput,
//! mean iterations and evaluations; with OUT.csv it writes every fit's objective, so that
//! two solver settings can be compared fit by fit on the same starts.
//!
//! Usage: cargo run --release --example lm_study -- CONFIG STARTS STRIDE [OUT.csv]
//! (README.md, "Speed", shows the runs behind the solver defaults.)
use std::io::Write;
use std::path::Path;
use std::time::Instant;

use creepfit::config::{Overrides, RunConfig};
use creepfit::fit::{local_fit, FitSettings};
use creepfit::model::build;
use creepfit::sweep::plan;
use rayon::prelude::*;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        anyhow::bail!("usage: lm_study CONFIG STARTS STRIDE [OUT.csv]");
    }
    let starts: usize = args[2].parse()?;
    let stride: usize = args[3].parse()?;
    let cli = Overrides {
        starts: Some(starts),
        ..Overrides::default()
    };
    let (cfg, data) = RunConfig::resolve(Path::new(&args[1]), &cli)?;
    let p = plan(&cfg, &cfg.calibration(&data)?, &data)?;
    let model = build(&cfg.model, &cfg.extensions)?;
    let space = cfg.space();
    let settings = FitSettings::from_config(&cfg);
    let jobs: Vec<(usize, usize)> = (0..p.starts.len())
        .step_by(stride.max(1))
        .flat_map(|s| (0..p.ws.len()).map(move |w| (s, w)))
        .collect();
    let t0 = Instant::now();
    let fits: Vec<_> = jobs
        .par_iter()
        .map(|&(s, wi)| {
            let f = local_fit(
                model.as_ref(),
                &data.curves,
                &space,
                &p.ws[wi],
                &p.starts[s],
                "",
                &settings,
            );
            (s, wi, f)
        })
        .collect();
    let wall = t0.elapsed().as_secs_f64();
    let n = fits.len() as f64;
    let it: usize = fits.iter().map(|f| f.2.lm.iterations).sum();
    let ev: usize = fits.iter().map(|f| f.2.lm.evaluations).sum();
    println!(
        "{} fits in {wall:.2} s on {} threads ({:.1} fits/s), mean iterations {:.1}, mean evaluations {:.1}",
        fits.len(),
        rayon::current_num_threads(),
        n / wall,
        it as f64 / n,
        ev as f64 / n
    );
    if let Some(out) = args.get(4) {
        let mut w = std::io::BufWriter::new(std::fs::File::create(out)?);
        writeln!(w, "start_id,w_idx,objective,iterations,evaluations,status")?;
        for (s, wi, f) in &fits {
            writeln!(
                w,
                "{s},{wi},{:.17e},{},{},{}",
                f.eval.objective,
                f.lm.iterations,
                f.lm.evaluations,
                f.lm.termination.as_str()
            )?;
        }
    }
    Ok(())
}
