//! Writes a large logged-curve data set for `scripts/bench_large.sh`: three creep tests at
//! 560 °C simulated from the 560 °C `fit` constants (README) with Gaussian noise, the 100 MPa
//! test logged at N points (a data logger), the 85 and 110 MPa tests at 1,000 points each,
//! times uniform up to 99.5 % of the life. Also writes `ruptures.csv` and `run.toml` (the
//! bundled 560 °C configuration pointed at these files).
//!
//! Usage: cargo run --release --example gen_large -- OUT_DIR [N = 1000000] [SEED = 1]
use std::io::{BufWriter, Write};
use std::path::PathBuf;

use creepfit::model::{build, Load};
use creepfit::ode::OdeOptions;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The 560 °C fit (README): A, B, H*, h, Kc, C.
const CONSTANTS: [f64; 6] = [
    1.0e-10,
    0.1749367,
    0.5630134,
    5.903132e4,
    2.212783e-5,
    4.031361,
];
/// Standard deviation of the noise, strain in percent (a good extensometer).
const NOISE_PCT: f64 = 0.002;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let out = PathBuf::from(
        args.get(1)
            .ok_or_else(|| anyhow::anyhow!("usage: gen_large OUT_DIR [N] [SEED]"))?,
    );
    let n: usize = args
        .get(2)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1_000_000);
    let seed: u64 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(1);
    std::fs::create_dir_all(&out)?;
    let model = build("khd", &[])?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut curves = BufWriter::new(std::fs::File::create(out.join("curves.csv"))?);
    let mut ruptures = BufWriter::new(std::fs::File::create(out.join("ruptures.csv"))?);
    writeln!(curves, "temperature_C,stress_MPa,time_h,strain_pct")?;
    writeln!(ruptures, "temperature_C,stress_MPa,rupture_time_h")?;
    for (stress, points) in [(85.0, 1000), (100.0, n), (110.0, 1000)] {
        let load = Load {
            stress_mpa: stress,
            temperature_k: 560.0 + creepfit::model::ZERO_CELSIUS_K,
            omega_f: 1.0 / 3.0,
        };
        let opts = OdeOptions::default();
        let rup = model.simulate(&CONSTANTS, &load, &[], &mut [], &opts);
        anyhow::ensure!(rup.ruptured(), "{stress} MPa did not rupture");
        let life = rup.t_end;
        let times: Vec<f64> = (0..points)
            .map(|k| 0.995 * life * k as f64 / (points - 1) as f64)
            .collect();
        let mut strain = vec![0.0; points];
        let res = model.simulate(&CONSTANTS, &load, &times, &mut strain, &opts);
        anyhow::ensure!(res.n_out == points, "output stopped early");
        for (t, e) in times.iter().zip(&strain) {
            // Box–Muller normal deviate.
            let (u1, u2): (f64, f64) = (rng.gen::<f64>().max(1e-300), rng.gen());
            let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            writeln!(
                curves,
                "560,{stress},{:.4},{:.5}",
                t,
                100.0 * e + NOISE_PCT * z
            )?;
        }
        writeln!(ruptures, "560,{stress},{:.2}", life)?;
    }
    curves.flush()?;
    ruptures.flush()?;
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let cfg = std::fs::read_to_string(root.join("configs/560C.toml"))?
        .replace("cmv-560C", "large-560C")
        .replace("../data/creep_560C.csv", "curves.csv")
        .replace("../data/lifetimes.csv", "ruptures.csv");
    std::fs::write(out.join("run.toml"), cfg)?;
    println!("wrote {} ({} + 2,000 points)", out.display(), n);
    Ok(())
}
