//! Criterion benchmarks of the core: one simulation of one measured curve (560 °C, 100 MPa,
//! the paper's start), one eq. 8 residual evaluation (three curves) and one local fit (560 °C,
//! w = 1, from the paper's start).

use std::path::Path;

use criterion::{black_box, criterion_group, criterion_main, Criterion};

use creepfit::config::RunConfig;
use creepfit::fit::{local_fit, param_space, FitSettings};
use creepfit::model::{registry, Load};
use creepfit::objective::Objective;
use creepfit::ode::OdeOptions;

fn bench(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cfg = RunConfig::load(&root.join("configs/560C.toml")).unwrap();
    let data = cfg.load_data().unwrap();
    let model = registry(&cfg.model).unwrap();
    let start = cfg.starts_all_given().unwrap();
    let settings = FitSettings::from_config(&cfg);
    let curve = &data.curves[1];
    let load = Load {
        stress_mpa: curve.stress_mpa,
        omega_f: cfg.objective.omega_f,
    };
    let ode = OdeOptions {
        t_end: 100.0 * curve.rupture_time_h.unwrap(),
        ..settings.ode
    };
    let mut out = vec![0.0; curve.times_h.len()];
    c.bench_function("simulate_curve_560C_100MPa", |b| {
        b.iter(|| model.simulate(black_box(&start), &load, &curve.times_h, &mut out, &ode))
    });
    let objective = Objective {
        model: model.as_ref(),
        curves: &data.curves,
        w: vec![1.0; 3],
        lifetime: settings.lifetime,
        omega_f: settings.omega_f,
        ode: settings.ode,
    };
    let mut r = vec![0.0; objective.n_residuals()];
    c.bench_function("residuals_560C", |b| {
        b.iter(|| objective.residuals(black_box(&start), &mut r).unwrap())
    });
    let space = param_space(&cfg);
    let mut g = c.benchmark_group("fit");
    g.sample_size(10);
    g.bench_function("local_fit_560C_w1", |b| {
        b.iter(|| {
            local_fit(
                model.as_ref(),
                &data.curves,
                &space,
                &[1.0; 3],
                black_box(&start),
                "bench",
                &settings,
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
