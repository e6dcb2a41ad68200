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

/// A spreadsheet's export with ';' between fields (and decimal commas) is named as such.
#[test]
fn semicolon_separated_curves_are_named() {
    let e = curves_error(&CURVES.replace(',', ";").replace(";1\n", ";1,0\n"));
    has(
        &e,
        &[
            "curves.csv:1",
            "missing required column 'temperature_C'",
            "separated by ';'",
        ],
    );
    assert!(!curves_error("temperature_C,stress_MPa,time_h\n600,100,0\n").contains("separated by"));
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

/// A row of a labelled test whose 'specimen' cell is empty becomes a curve of its own with too
/// few points: the error says so. A curve short of points among unlabelled tests does not.
#[test]
fn an_empty_specimen_cell_is_named() {
    let labelled = "temperature_C,stress_MPa,time_h,strain_pct,specimen\n\
                    600,100,0,0,a\n600,100,10,1,a\n600,100,20,2,\n600,100,30,3,a\n\
                    600,120,0,0,b\n600,120,5,1,b\n600,120,10,2,b\n";
    let e = curves_error(labelled);
    has(
        &e,
        &[
            "curves.csv:4",
            "stress_MPa = 100 has 1 distinct point(s)",
            "empty 'specimen' cell",
        ],
    );
    let e = curves_error(&CURVES.replace("600,120,10,2\n", ""));
    assert!(!e.contains("specimen"), "{e}");
}

/// A rupture strain given as a fraction (0.02 for a curve that reached 2 %) is refused, naming
/// the ruptures file's line and column; one a little below the curve's last reading loads.
#[test]
fn a_rupture_strain_below_the_curves_is_refused() {
    let dir = TempDir::new().unwrap();
    let c = write(&dir, "curves.csv", CURVES);
    let load = |strain: &str| {
        let text = format!(
            "temperature_C,stress_MPa,rupture_time_h,rupture_strain_pct\n600,100,25,{strain}\n600,120,12,2.5\n"
        );
        let r = write(&dir, "ruptures.csv", &text);
        data::load(&c, &r, &LoadOptions::default())
    };
    let e = load("0.02")
        .expect_err("a fraction for percent")
        .to_string();
    assert_one_line(&e);
    has(
        &e,
        &[
            "ruptures.csv:2: column 'rupture_strain_pct': 0.02 % is 0.010 × the largest strain 2 %",
            "600 °C, 100 MPa",
            "percent",
        ],
    );
    let d = load("1.9").expect("a rupture strain a little below the last reading is data");
    assert_eq!(d.curves[0].rupture_strain, 0.019);
}

/// Units mixed up: strains as fractions where percent is expected, and curve times in
/// seconds against rupture times in hours, are each named in a warning; the test data as
/// they are give neither.
#[test]
fn mixed_up_units_are_named_in_warnings() {
    let load = |curves: &str, ruptures: &str| {
        let dir = TempDir::new().unwrap();
        let c = write(&dir, "curves.csv", curves);
        let r = write(&dir, "ruptures.csv", ruptures);
        data::load(&c, &r, &LoadOptions::default())
            .unwrap()
            .warnings
    };
    let units = |w: &[String]| {
        (
            w.iter().any(|w| w.contains("strain_pct is in percent")),
            w.iter().any(|w| w.contains("are both files in hours?")),
        )
    };
    assert_eq!(units(&load(CURVES, RUPTURES)), (false, false));
    let fractions = "temperature_C,stress_MPa,time_h,strain_pct\n\
                     600,100,0,0\n600,100,10,0.01\n600,100,20,0.02\n\
                     600,120,0,0\n600,120,5,0.01\n600,120,10,0.02\n";
    let w = load(fractions, RUPTURES);
    assert_eq!(units(&w), (true, false), "{w:?}");
    assert!(w
        .iter()
        .any(|w| w.contains("curves.csv: column 'strain_pct'")));
    // Rupture times in seconds: the curves end at 1/3600 of them.
    let seconds = "temperature_C,stress_MPa,rupture_time_h\n600,100,90000\n600,120,43200\n";
    let w = load(CURVES, seconds);
    assert_eq!(units(&w), (false, true), "{w:?}");
    assert!(
        w.iter()
            .any(|w| w.contains("curves.csv:2: column 'time_h'") && w.contains("ruptures.csv:2")),
        "{w:?}"
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
        interrupted: vec![120.0.into()],
        ..Default::default()
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
        &CURVES.replace(
            "600,100,20,2\n",
            "600,100,20,2\n600,100,10,1\n600,100,10,1.5\n",
        ),
    );
    let r = write(&dir, "ruptures.csv", RUPTURES);
    let ds = data::load(&c, &r, &LoadOptions::default()).unwrap();
    assert_eq!(ds.warnings.len(), 1, "{:?}", ds.warnings);
    has(&ds.warnings[0], &["curves.csv:5:", "of line 3 dropped"]);
    assert_eq!(ds.curves[0].times_h, vec![0.0, 10.0, 10.0, 20.0]);
}

/// Real laboratory data (`data/alloy617/`): 34 curves, 28,933 rows, replicate specimens,
/// negative strains at the start of four tests, a repeated (0, 0) row at the start of every
/// curve and 601 more exact repeats, times that step back by 3 h. Everything loads as it
/// is, one temperature at a time.
#[test]
fn alloy617_loads_as_it_is() {
    let c = repo("data/alloy617/creep_alloy617.csv");
    let r = repo("data/alloy617/ruptures_alloy617.csv");
    let (mut curves, mut points, mut negative_warnings) = (0, 0, 0);
    for t in [750.0, 850.0, 900.0, 950.0] {
        let opts = LoadOptions {
            temperature_c: Some(t),
            ..Default::default()
        };
        let ds = data::load(&c, &r, &opts).unwrap();
        curves += ds.curves.len();
        points += ds.curves.iter().map(|c| c.times_h.len()).sum::<usize>();
        for c in &ds.curves {
            assert!(c.specimen.is_some());
            assert!(c.rupture_time_h.is_some());
            assert!(c.times_h.windows(2).all(|w| w[0] <= w[1]));
        }
        // The repeated (0, 0) rows: one warning for the file.
        let dup: Vec<&String> = ds
            .warnings
            .iter()
            .filter(|w| w.contains("duplicate"))
            .collect();
        assert_eq!(dup.len(), 1, "{:?}", ds.warnings);
        has(
            dup[0],
            &[
                "creep_alloy617.csv:3:",
                "of line 2",
                "635 in all, in 34 curve(s)",
            ],
        );
        negative_warnings += ds
            .warnings
            .iter()
            .filter(|w| w.contains("negative strain"))
            .count();
    }
    assert_eq!(curves, 34);
    // 28,933 rows less the 635 exact repeats.
    assert_eq!(points, 28_933 - 635);
    assert_eq!(negative_warnings, 4);
    // The 750 °C, 137 MPa, INL2-b test: 21 negative strains down to −0.155 %.
    let ds = data::load(
        &c,
        &r,
        &LoadOptions {
            temperature_c: Some(750.0),
            ..Default::default()
        },
    )
    .unwrap();
    let w: Vec<&String> = ds
        .warnings
        .iter()
        .filter(|w| w.contains("negative"))
        .collect();
    assert_eq!(w.len(), 1, "{w:?}");
    has(
        w[0],
        &[
            "column 'strain_pct'",
            "21 negative strain(s)",
            "INL2-b",
            "-0.155 %",
        ],
    );
    let curve = ds
        .curves
        .iter()
        .find(|c| c.stress_mpa == 137.0 && c.specimen.as_deref() == Some("INL2-b"))
        .unwrap();
    assert_eq!(curve.strains.iter().filter(|e| **e < 0.0).count(), 21);
    assert!((curve.strains.iter().cloned().fold(0.0, f64::min) + 0.00155).abs() < 1e-15);
    // Without a temperature filter: an error naming the temperatures.
    let e = data::load(&c, &r, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(
        &e,
        &[
            "creep_alloy617.csv:",
            "temperature_C",
            "4 temperatures (750, 850, 900, 950 °C)",
        ],
    );
    // …unless the caller says the constants depend on temperature.
    let ds = data::load(
        &c,
        &r,
        &LoadOptions {
            several_temperatures: true,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(ds.curves.len(), 34);
}

/// Load `curves` with ruptures at 100 and 120 MPa; the result or the one-line error.
fn load_text(curves: &str) -> Result<data::Dataset, String> {
    let dir = TempDir::new().unwrap();
    let c = write(&dir, "curves.csv", curves);
    let r = write(&dir, "ruptures.csv", RUPTURES);
    data::load(&c, &r, &LoadOptions::default()).map_err(|e| {
        let e = e.to_string();
        assert_one_line(&e);
        e
    })
}

#[test]
fn two_specimens_without_specimen_column() {
    let h = "temperature_C,stress_MPa,time_h,strain_pct\n";
    // The time restarts within one block (lines 2–4, then 5–7).
    let e = load_text(&format!(
        "{h}600,100,0,0\n600,100,10,1\n600,100,20,2\n600,100,0,0\n600,100,8,1.1\n600,100,19,2.2\n\
         600,120,0,0\n600,120,5,1\n600,120,10,2\n"
    ))
    .unwrap_err();
    has(
        &e,
        &[
            "curves.csv:5:",
            "column 'time_h'",
            "stress_MPa = 100",
            "lines 2–4 and 5–7",
            "specimen",
        ],
    );
    // A second block of the same (T, σ) after other rows, resuming before the time reached.
    let e = load_text(&format!(
        "{h}600,100,0,0\n600,100,10,1\n600,100,20,2\n600,120,0,0\n600,120,5,1\n600,120,10,2\n\
         600,100,5,0.4\n600,100,12,1.3\n600,100,22,2.5\n"
    ))
    .unwrap_err();
    has(
        &e,
        &[
            "curves.csv:8:",
            "lines 2–4 and 8–10",
            "20 h already reached on line 4",
        ],
    );
    // With a specimen column: two curves.
    let ds = load_text(
        "temperature_C,stress_MPa,time_h,strain_pct,specimen\n\
         600,100,0,0,a\n600,100,10,1,a\n600,100,20,2,a\n600,100,0,0,b\n600,100,8,1.1,b\n\
         600,100,19,2.2,b\n600,120,0,0,a\n600,120,5,1,a\n600,120,10,2,a\n",
    )
    .unwrap();
    assert_eq!(ds.curves.len(), 3);
    // Curves interleaved row by row in time order (a file sorted by time) are not specimens.
    let ds = load_text(&format!(
        "{h}600,100,0,0\n600,120,0,0\n600,120,5,1\n600,100,10,1\n600,120,10,2\n600,100,20,2\n"
    ))
    .unwrap();
    assert_eq!(ds.curves.len(), 2);
    assert_eq!(ds.curves[0].times_h, vec![0.0, 10.0, 20.0]);
    // Local disorder, repeated times and a repeated first time stay data (seed, Alloy 617).
    let ds = load_text(&format!(
        "{h}600,100,0,0\n600,100,0,0.2\n600,100,12,1\n600,100,10,1.1\n600,100,10,1.2\n600,100,20,2\n\
         600,120,0,0\n600,120,5,1\n600,120,10,2\n"
    ))
    .unwrap();
    assert_eq!(ds.curves[0].times_h, vec![0.0, 0.0, 10.0, 10.0, 12.0, 20.0]);
    // Rows in no order at all (a shuffled table; DESIGN: times need not be sorted) load as
    // one curve each: nothing tells specimens apart there.
    let mut rows: Vec<String> = (0..40)
        .map(|k| format!("600,100,{},{}", k * 10, k as f64 * 0.1))
        .chain((0..30).map(|k| format!("600,120,{},{}", k * 5, k as f64 * 0.2)))
        .collect();
    let mut x: u64 = 12345;
    for i in (1..rows.len()).rev() {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        rows.swap(i, (x >> 33) as usize % (i + 1));
    }
    let ds = load_text(&format!("{h}{}\n", rows.join("\n"))).unwrap();
    assert_eq!(ds.curves.len(), 2);
    assert_eq!(ds.curves[0].times_h.len(), 40);
    assert!(ds.curves[0].times_h.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn all_times_equal() {
    let e = load_text(&CURVES.replace(
        "600,120,0,0\n600,120,5,1\n600,120,10,2\n",
        "600,120,5,0.5\n600,120,5,1\n600,120,5,2\n",
    ))
    .unwrap_err();
    has(
        &e,
        &[
            "curves.csv:5:",
            "column 'time_h'",
            "stress_MPa = 120",
            "all its 3 points at time_h = 5",
        ],
    );
}

#[test]
fn negative_strains_are_data() {
    let ds = load_text(&CURVES.replace(
        "600,100,0,0\n600,100,10,1\n",
        "600,100,0,0\n600,100,1,-0.02\n600,100,2,-0.03\n600,100,10,1\n",
    ))
    .unwrap();
    assert_eq!(ds.warnings.len(), 1, "{:?}", ds.warnings);
    has(
        &ds.warnings[0],
        &[
            "curves.csv:3:",
            "column 'strain_pct'",
            "2 negative strain(s)",
            "-0.03 %",
            "100 MPa",
        ],
    );
    assert_eq!(ds.curves[0].strains[1], -0.0002);
    // A curve that never rises above zero has nothing to fit.
    let e = load_text(&CURVES.replace(
        "600,120,0,0\n600,120,5,1\n600,120,10,2\n",
        "600,120,0,0\n600,120,5,-1\n600,120,10,-2\n",
    ))
    .unwrap_err();
    has(
        &e,
        &["curves.csv:5:", "column 'strain_pct'", "not above zero"],
    );
    // Non-finite numbers and negative times stay errors.
    let e = load_text(&CURVES.replace("600,100,10,1\n", "600,100,10,-inf\n")).unwrap_err();
    has(&e, &["curves.csv:3:", "column 'strain_pct'", "-inf"]);
}

#[test]
fn several_temperatures_need_a_filter() {
    let e = load_text(&format!("{CURVES}650,100,0,0\n650,100,3,1\n650,100,6,2\n")).unwrap_err();
    has(
        &e,
        &[
            "curves.csv:8:",
            "column 'temperature_C'",
            "2 temperatures (600, 650 °C)",
            "temperature_C = ",
        ],
    );
}

/// Lines are the file's physical lines, after blank lines, quoted multi-line cells and
/// `\r\n` endings (the csv crate's own positions are not).
#[test]
fn physical_line_numbers() {
    let text =
        "temperature_C,stress_MPa,time_h,strain_pct,note\r\n\r\n600,100,0,0,\"two\r\nlines\"\r\n\
                \r\n\r\n600,100,10,1,x\r\n600,100,2o,2,x\r\n";
    let e = load_text(text).unwrap_err();
    has(&e, &["curves.csv:8:", "column 'time_h'", "2o"]);
    let text = "temperature_C,stress_MPa,time_h,strain_pct\n\n\n600,100,0,0\n\n600,100\n";
    let e = load_text(text).unwrap_err();
    has(&e, &["curves.csv:6:", "2 fields"]);
}

#[test]
fn constants_file_errors_name_the_physical_line() {
    let dir = TempDir::new().unwrap();
    let model = creepfit::model::build("khd", &[]).unwrap();
    let p = write(&dir, "constants.csv", "name,value\n\nA,1e-9\n\n\nB,zero\n");
    let e = creepfit::report::tables::read_constants(&p, model.as_ref())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(&e, &["constants.csv:6:", "column 'value'", "zero"]);
    let p = write(&dir, "constants.csv", "name,value\nA,\"1e-9\n\"\nBee,1\n");
    let e = creepfit::report::tables::read_constants(&p, model.as_ref())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(&e, &["constants.csv:4:", "column 'name'", "Bee"]);
    let p = write(&dir, "constants.csv", "name,value\n\nA,\"1e\n9\"\n");
    let e = creepfit::report::tables::read_constants(&p, model.as_ref())
        .unwrap_err()
        .to_string();
    assert_one_line(&e);
    has(&e, &["constants.csv:3:", "column 'value'", "'1e\\n9'"]);
}
