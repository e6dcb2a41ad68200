//! Criterion benchmarks of the core: one right-hand-side evaluation (four-state and reduced
//! model), one simulation of one measured curve (560 °C, 100 MPa, the paper's start) in f64 and
//! in dual numbers, one eq. 8 residual evaluation and one sensitivity Jacobian (three curves),
//! and one local fit (560 °C, w = 1, from the paper's start); JᵀJ of a Jacobian shaped like the
//! hierarchical problem's at Alloy 617 850 °C (8,716 rows, 7 constants, 13 curves × 2 specimen
//! effects), by nalgebra's `tr_mul` and by `lsq::gram` (the same numbers bit for bit). The 1,000-start × 10-w sweep is
//! timed by `scripts/bench_sweep.sh` (a criterion sample of it would take minutes).

use std::path::Path;

use criterion::{black_box, criterion_group, criterion_main, Criterion};

use creepfit::config::RunConfig;
use creepfit::dual::{Dual, Scalar, SENS};
use creepfit::fit::{local_fit, FitSettings};
use creepfit::lsq::LeastSquaresProblem;
use creepfit::model::objective::{CreepProblem, JacobianMethod, Objective};
use creepfit::model::{registry, CreepModel, Khd, KhdReduced, Load};
use creepfit::ode::OdeOptions;
use nalgebra::DMatrix;

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
        temperature_k: curve.temperature_c + creepfit::model::ZERO_CELSIUS_K,
        omega_f: cfg.objective.omega_f,
    };
    let ode = OdeOptions {
        t_end: 100.0 * curve.rupture_time_h.unwrap(),
        ..settings.ode
    };
    // Right-hand side at a mid-life state.
    let p4 = Khd.prepare(&start, &load);
    let y4 = [0.01, 0.3, 0.05, 0.01 * start[5]];
    let mut dy4 = [0.0; 4];
    c.bench_function("rhs_khd4", |b| {
        b.iter(|| Khd.rhs(&p4, black_box(1.0e4), black_box(&y4), &mut dy4))
    });
    let p1 = KhdReduced.prepare(&start, &load);
    let mut dy1 = [0.0; 1];
    c.bench_function("rhs_khd1", |b| {
        b.iter(|| KhdReduced.rhs(&p1, black_box(1.0e4), black_box(&[0.01]), &mut dy1))
    });
    let mut out = vec![0.0; curve.times_h.len()];
    c.bench_function("simulate_curve_560C_100MPa", |b| {
        b.iter(|| model.simulate(black_box(&start), &load, &curve.times_h, &mut out, &ode))
    });
    let four = registry("khd4").unwrap();
    c.bench_function("simulate_curve_560C_100MPa_khd4", |b| {
        b.iter(|| four.simulate(black_box(&start), &load, &curve.times_h, &mut out, &ode))
    });
    let xd: Vec<Dual<SENS>> = start
        .iter()
        .enumerate()
        .map(|(k, &v)| Dual::var(v, k, 1.0))
        .collect();
    let mut outd = vec![Dual::<SENS>::cst(0.0); curve.times_h.len()];
    c.bench_function("simulate_curve_560C_100MPa_dual", |b| {
        b.iter(|| model.simulate_sens(black_box(&xd), &load, &curve.times_h, &mut outd, &ode))
    });
    let objective = Objective::new(
        model.as_ref(),
        &data.curves,
        vec![1.0; 3],
        settings.objective(),
    );
    let mut r = vec![0.0; objective.n_residuals()];
    c.bench_function("residuals_560C", |b| {
        b.iter(|| objective.residuals(black_box(&start), &mut r).unwrap())
    });
    let space = cfg.space();
    let problem = CreepProblem {
        objective,
        space: space.clone(),
        jacobian: JacobianMethod::Sensitivity,
    };
    let u = space.to_unit(&start);
    let mut jac = DMatrix::zeros(problem.n_residuals(), problem.n_params());
    c.bench_function("jacobian_sensitivity_560C", |b| {
        b.iter(|| {
            problem
                .jacobian(black_box(&u), &r, &mut jac)
                .unwrap()
                .unwrap()
        })
    });
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

    // 8,677 data rows + 13 rupture rows of 13 curves, 26 penalty rows; 7 dense columns, each
    // effect column non-zero on its curve's rows and its penalty row.
    let (curves, kinds, dense) = (13usize, 2usize, 7usize);
    let per = 668usize;
    let md = curves * per;
    let m = md + curves * kinds;
    let n = dense + curves * kinds;
    let mut jac = DMatrix::<f64>::zeros(m, n);
    for k in 0..dense {
        for r in 0..md {
            jac[(r, k)] = ((r * 7 + k * 13) as f64 * 0.001).sin();
        }
    }
    for kk in 0..kinds {
        for i in 0..curves {
            let col = dense + kk * curves + i;
            for r in i * per..(i + 1) * per {
                jac[(r, col)] = ((r + kk) as f64 * 0.01).cos();
            }
            jac[(md + kk * curves + i, col)] = 2.0;
        }
    }
    let mut g = c.benchmark_group("normal_equations_850C_effects");
    g.bench_function("nalgebra_tr_mul", |b| {
        b.iter(|| black_box(&jac).tr_mul(&jac))
    });
    g.bench_function("lsq_gram", |b| {
        b.iter(|| creepfit::lsq::gram(black_box(&jac)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
