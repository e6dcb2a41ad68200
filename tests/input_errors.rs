//! Bad input is an error with a one-line message naming the file, the line (where there is
//! one) and what is wrong; the bundled configurations and data load.

use std::path::{Path, PathBuf};

use creepfit::config::RunConfig;
use creepfit::data::{self, LoadOptions};
use tempfile::TempDir;

const CURVES: &str = "temperature_C,stress_MPa,time_h,strain_pct\n\
                      600,100,0,0\n600,100,10,1\n600,100,20,2\n\
                      600,120,0,0\n600,120,5,1\n600,120,10,2\n";
const RUPTURES: &str = "temperature_C,stress_MPa,rupture_time_h\n600,100,25\n600,120,12\n";

fn write(dir: &TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Load `curves` text with the good ruptures file and return the error message.
fn curves_error(curves: &str) -> String {
    let dir = TempDir::new().unwrap();
    let c = write(&dir, "curves.csv", curves);
    let r = write(&dir, "ruptures.csv", RUPTURES);
    let e = data::load(&c, &r, &LoadOptions::default())
        .expect_err("bad curves must be an error")
        .to_string();
    assert_one_line(&e);
    e
}

fn config_error(extra: &str) -> String {
    let dir = TempDir::new().unwrap();
    let text = format!("curves = \"c.csv\"\nruptures = \"r.csv\"\n{extra}");
    let p = write(&dir, "run.toml", &text);
    let e = RunConfig::load(&p)
        .expect_err("bad config must be an error")
        .to_string();
    assert_one_line(&e);
    assert!(e.contains("run.toml"), "{e}");
    e
}

fn assert_one_line(e: &str) {
    assert!(!e.trim().is_empty());
    assert!(!e.trim_end().contains('\n'), "multi-line error: {e}");
}

fn has(e: &str, parts: &[&str]) {
    for p in parts {
        assert!(e.contains(p), "error {e:?} lacks {p:?}");
    }
}

#[test]
fn good_input_loads() {
    let dir = TempDir::new().unwrap();
    let c = write(&dir, "curves.csv", CURVES);
    let r = write(&dir, "ruptures.csv", RUPTURES);
    let ds = data::load(&c, &r, &LoadOptions::default()).unwrap();
    assert_eq!(ds.curves.len(), 2);
    assert!(ds.warnings.is_empty());
}

#[test]
fn missing_file() {
    let dir = TempDir::new().unwrap();
    let r = write(&dir, "ruptures.csv", RUPTURES);
    let c = dir.path().join("nope.csv");
    let e = data::load(&c, &r, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(&e, &["nope.csv"]);
    let e = RunConfig::load(&dir.path().join("absent.toml"))
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(&e, &["absent.toml"]);
}

#[test]
fn missing_column() {
    let e = curves_error("temperature_C,stress_MPa,time_h\n600,100,0\n");
    has(&e, &["curves.csv:1", "strain_pct"]);
    let dir = TempDir::new().unwrap();
    let c = write(&dir, "curves.csv", CURVES);
    let r = write(&dir, "ruptures.csv", "temperature_C,stress_MPa\n600,100\n");
    let e = data::load(&c, &r, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(&e, &["ruptures.csv:1", "rupture_time_h"]);
}

#[test]
fn unparsable_number() {
    let e = curves_error(&CURVES.replace("600,100,10,1\n", "600,100,10,1.2.3\n"));
    has(&e, &["curves.csv:3", "strain_pct", "1.2.3"]);
}

#[test]
fn nan_strain() {
    let e = curves_error(&CURVES.replace("600,100,10,1\n", "600,100,10,NaN\n"));
    has(&e, &["curves.csv:3", "strain_pct", "NaN"]);
}

#[test]
fn negative_time() {
    let e = curves_error(&CURVES.replace("600,120,5,1\n", "600,120,-5,1\n"));
    has(&e, &["curves.csv:6", "time_h", "negative"]);
}

#[test]
fn too_few_points() {
    let e = curves_error(&CURVES.replace("600,120,10,2\n", ""));
    has(
        &e,
        &[
            "curves.csv:5",
            "stress_MPa = 120",
            "temperature_C = 600",
            "2",
        ],
    );
}

#[test]
fn curve_without_rupture_record() {
    let dir = TempDir::new().unwrap();
    let c = write(&dir, "curves.csv", CURVES);
    let r = write(
        &dir,
        "ruptures.csv",
        "temperature_C,stress_MPa,rupture_time_h\n600,100,25\n",
    );
    let e = data::load(&c, &r, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(
        &e,
        &["curves.csv:5", "stress_MPa = 120", "no rupture record"],
    );
    // Declared interrupted: fine.
    let opts = LoadOptions {
        temperature_c: None,
        interrupted: vec![120.0],
    };
    let ds = data::load(&c, &r, &opts).unwrap();
    assert_eq!(ds.curves[1].rupture_time_h, None);
}

#[test]
fn lb_not_below_ub() {
    let e = config_error("[constants]\nB = { lb = 0.2, ub = 0.1 }\n");
    has(&e, &["constants.B", "lb", "ub"]);
}

#[test]
fn start_outside_bounds() {
    let e = config_error("[constants]\nC = { lb = 3, ub = 10, start = 11 }\n");
    has(&e, &["constants.C", "start", "outside"]);
}

#[test]
fn unknown_config_key() {
    let e = config_error("[sweep]\nstarts = 4\nsead = 3\n");
    has(&e, &["run.toml:5: sweep.sead: ", "unknown field `sead`"]);
}

#[test]
fn unknown_model() {
    let e = config_error("model = \"hayhurst9\"\n");
    has(&e, &["hayhurst9", "unknown model"]);
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
}

#[test]
fn bundled_configs_load() {
    for (file, name, temp, c_start, expected_stresses) in [
        (
            "configs/560C.toml",
            "cmv-560C",
            560.0,
            4.311,
            [85.0, 100.0, 110.0],
        ),
        (
            "configs/590C.toml",
            "cmv-590C",
            590.0,
            2.88,
            [100.0, 110.0, 120.0],
        ),
    ] {
        let cfg = RunConfig::load(&repo(file)).unwrap();
        assert_eq!(cfg.name, name);
        assert_eq!(cfg.model, "khd");
        assert_eq!(cfg.temperature_c, Some(temp));
        assert_eq!(cfg.sweep.starts, 200);
        assert_eq!(cfg.sweep.seed, 1);
        let start = cfg.starts_all_given().expect("all starts given");
        assert_eq!(start[5], c_start);
        let ds = cfg.load_data().unwrap();
        assert_eq!(ds.curves.len(), 3);
        let stresses: Vec<f64> = ds.curves.iter().map(|c| c.stress_mpa).collect();
        assert_eq!(stresses, expected_stresses);
        for c in &ds.curves {
            assert!(c.temperature_c == temp);
            assert!(c.times_h.windows(2).all(|w| w[0] <= w[1]));
            assert!(c.rupture_time_h.is_some());
            assert!(c.min_rate_estimated > 0.0);
        }
        // No exact duplicate points in the bundled tables (repeated times have different
        // strains), no unused rupture records at the run's temperature.
        assert!(ds.warnings.is_empty(), "{:?}", ds.warnings);
        let w = cfg
            .objective
            .weight_vectors(ds.curves.len(), &cfg.path)
            .unwrap();
        assert_eq!(w.len(), if temp == 590.0 { 11 } else { 10 });
    }
}

#[test]
fn bundled_590_120_sorted_and_repeated_times_kept() {
    let cfg = RunConfig::load(&repo("configs/590C.toml")).unwrap();
    let ds = cfg.load_data().unwrap();
    let c = &ds.curves[2];
    assert_eq!(c.stress_mpa, 120.0);
    assert_eq!(c.times_h.len(), 70);
    // 1286 then 1281 in the file: sorted.
    let i = c.times_h.iter().position(|&t| t == 1281.0).unwrap();
    assert_eq!(c.times_h[i + 1], 1286.0);
    // 1389 h five times with different strains: all kept, file order.
    let at: Vec<f64> = c
        .times_h
        .iter()
        .zip(&c.strains)
        .filter(|(t, _)| **t == 1389.0)
        .map(|(_, e)| *e)
        .collect();
    assert_eq!(at.len(), 5);
    assert!(at.windows(2).all(|w| w[0] < w[1]));
    assert!((c.rupture_strain - 0.11002).abs() < 1e-15);
    assert_eq!(c.rupture_time_h, Some(1400.0));
}

#[test]
fn exact_duplicates_warned() {
    let dir = TempDir::new().unwrap();
    let c = write(
        &dir,
        "curves.csv",
        &format!("{CURVES}600,100,10,1\n600,100,10,1.5\n"),
    );
    let r = write(&dir, "ruptures.csv", RUPTURES);
    let ds = data::load(&c, &r, &LoadOptions::default()).unwrap();
    assert_eq!(ds.warnings.len(), 1, "{:?}", ds.warnings);
    assert!(ds.warnings[0].contains("curves.csv:8"));
    assert_eq!(ds.curves[0].times_h, vec![0.0, 10.0, 10.0, 20.0]);
}
