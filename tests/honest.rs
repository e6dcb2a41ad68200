//! Nothing silently wrong, through the binary: each test reproduces a finding of a new user
//! on a fresh clone (all of which exited 0) and checks what the command does now — a number
//! in a file is what its column says, an impossible request is refused in one line, a run
//! owns its output folder.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use tempfile::TempDir;

mod common;
use common::*;

/// Run and require success; stdout.
fn ok(args: &[&str]) -> String {
    let o = creepfit(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Run and require a failure with ONE `error:` line on stderr; that line.
fn fails(args: &[&str]) -> String {
    let o = creepfit(args);
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{args:?} exited 0; stderr: {e}");
    let errors: Vec<&str> = e.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{e}");
    errors[0].to_string()
}

fn has(text: &str, parts: &[&str]) {
    for p in parts {
        assert!(text.contains(p), "{text:?} lacks {p:?}");
    }
}

/// A CSV file as rows of (column → cell).
fn rows(path: &Path) -> (Vec<String>, Vec<HashMap<String, String>>) {
    let mut rdr = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let h: Vec<String> = rdr.headers().unwrap().iter().map(str::to_string).collect();
    let r = rdr
        .records()
        .map(|r| {
            h.iter()
                .cloned()
                .zip(r.unwrap().iter().map(str::to_string))
                .collect()
        })
        .collect();
    (h, r)
}

fn num(row: &HashMap<String, String>, k: &str) -> f64 {
    row[k]
        .parse()
        .unwrap_or_else(|_| panic!("{k} = {:?} is not a number", row[k]))
}

/// `fit configs/560C.toml` into `dir/fit`: its constants.csv.
fn fit_560(dir: &Path) -> PathBuf {
    let out = dir.join("fit");
    ok(&["fit", "configs/560C.toml", "--out", out.to_str().unwrap()]);
    out.join("constants.csv")
}

/// A copy of configs/560C.toml in `dir` with its data paths made absolute, `extra` appended
/// (and `replace` applied as (from, to) pairs).
fn config_560(dir: &Path, name: &str, extra: &str, replace: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(root().join("configs/560C.toml"))
        .unwrap()
        .replace("../data/", &format!("{}/data/", root().display()));
    for (a, b) in replace {
        assert!(text.contains(a), "{a}");
        text = text.replace(a, b);
    }
    text.push_str(extra);
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

// ---- 1. one centre per prediction ---------------------------------------------------------

/// `predict --intervals` after `fit`: the row's numbers and its intervals have one centre
/// (the maximum-likelihood refit, `constants = ml_refit`), every interval contains it, the
/// given constants' predictions are in the `given_*` columns (equal to `predict` without
/// intervals), the printout shows the same centre, and the band surrounds that centre's curve
/// up to its rupture time. Before: 166,555 h against the confidence interval
/// [156,579, 158,751] h.
#[test]
fn predict_intervals_have_one_centre() {
    let tmp = TempDir::new().unwrap();
    let c = fit_560(tmp.path());
    let (plain, with) = (tmp.path().join("plain"), tmp.path().join("with"));
    let base = |out: &Path| {
        vec![
            "predict".to_string(),
            "configs/560C.toml".into(),
            "--constants".into(),
            c.to_str().unwrap().into(),
            "--at".into(),
            "560:70,560:85".into(),
            "--out".into(),
            out.to_str().unwrap().into(),
        ]
    };
    let args: Vec<String> = base(&plain);
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let mut args = base(&with);
    args.push("--intervals".into());
    let stdout = ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let (h0, p0) = rows(&plain.join("predictions.csv"));
    assert_eq!(&h0[5..], ["extrapolation", "outcome", "constants"]);
    let (h, p) = rows(&with.join("predictions.csv"));
    assert_eq!(h[..5], h0[..5]);
    assert_eq!(
        &h[17..],
        [
            "extrapolation",
            "outcome",
            "constants",
            "given_rupture_time_h",
            "given_rupture_strain_pct",
            "given_min_rate_pct_per_h",
            "given_outcome"
        ]
    );
    assert_eq!(p.len(), 2);
    for (r, r0) in p.iter().zip(&p0) {
        assert_eq!(r["constants"], "ml_refit");
        assert_eq!(r0["constants"], "given");
        assert_eq!(r["outcome"], "ruptured");
        for (v, unit) in [
            ("rupture_time", "h"),
            ("rupture_strain", "pct"),
            ("min_rate", "pct_per_h"),
        ] {
            let val = num(r, &format!("{v}_{unit}"));
            let (clo, chi) = (
                num(r, &format!("{v}_conf_lo95_{unit}")),
                num(r, &format!("{v}_conf_hi95_{unit}")),
            );
            let (plo, phi) = (
                num(r, &format!("{v}_lo95_{unit}")),
                num(r, &format!("{v}_hi95_{unit}")),
            );
            assert!(
                plo <= clo && clo <= val && val <= chi && chi <= phi,
                "{v}: {r:?}"
            );
            // The given constants' numbers: those of predict without intervals, to the digit.
            assert_eq!(r[&format!("given_{v}_{unit}")], r0[&format!("{v}_{unit}")]);
        }
        // The eq. 8 constants are not the likelihood's optimum: their life differs.
        assert!((num(r, "rupture_time_h") - num(r0, "rupture_time_h")).abs() > 1e3);
    }
    assert_eq!(p[0]["extrapolation"], "stress");
    assert_eq!(p[1]["extrapolation"], "none");
    // The printout's centre is the file's.
    let t70 = num(&p[0], "rupture_time_h");
    has(&stdout, &[&format!("{t70:.0}"), "ml_refit", "difference"]);
    let s = json(&with.join("summary.json"));
    assert_eq!(s["constants_source"], "ml_refit");
    let refit = &s["refit"];
    assert!(refit["delta_neg2ll"].as_f64().unwrap() > 0.0, "{refit}");
    let cons = refit["constants"].as_array().unwrap();
    assert_eq!(cons.len(), 6);
    let given = std::fs::read_to_string(&c).unwrap();
    for k in cons {
        let g = k["given"].as_f64().unwrap();
        assert!(given.contains(&format!("{},{g},", k["name"].as_str().unwrap())));
        let d = k["refit"].as_f64().unwrap() - g;
        assert!((k["difference"].as_f64().unwrap() - d).abs() <= 1e-12 * g.abs().max(1e-300));
    }
    // band.csv: around the refit's curve, from a ninth of its life up to its rupture time,
    // where the band's strain is the rupture strain.
    let (_, band) = rows(&with.join("band.csv"));
    for (k, r) in p.iter().enumerate() {
        let b: Vec<&HashMap<String, String>> = band[9 * k..9 * (k + 1)].iter().collect();
        let (t_r, e_r) = (num(r, "rupture_time_h"), num(r, "rupture_strain_pct"));
        let t_lo95 = num(r, "rupture_time_conf_lo95_h");
        for x in &b {
            assert_eq!(x["stress_MPa"], r["stress_MPa"]);
            let (e, lo) = (num(x, "strain_pct"), num(x, "strain_conf_lo95_pct"));
            assert!(lo <= e, "{x:?}");
            // From the rupture time's lower confidence bound on, the upper end is rupture.
            if num(x, "time_h") >= t_lo95 {
                assert_eq!(x["strain_conf_hi95_pct"], "", "{x:?}");
                assert_eq!(x["strain_conf_hi95_ruptured"], "true", "{x:?}");
            } else {
                assert!(e <= num(x, "strain_conf_hi95_pct"), "{x:?}");
                assert_eq!(x["strain_conf_hi95_ruptured"], "false", "{x:?}");
            }
        }
        let last = b[8];
        assert!(
            (num(last, "time_h") / t_r - 1.0).abs() < 1e-6,
            "{last:?} vs {t_r}"
        );
        assert!(
            (num(last, "strain_pct") / e_r - 1.0).abs() < 1e-4,
            "{last:?} vs {e_r}"
        );
        assert!((num(b[0], "time_h") / t_r - 1.0 / 9.0).abs() < 1e-6);
    }
    assert!(with.join("band.png").is_file());
}

// ---- 2. another temperature without a temperature law -------------------------------------

/// `predict configs/560C.toml --at 590:100` (no temperature law): refused in one line naming
/// the temperature and what to do; from `[predict] at` the line of the configuration.
/// Before: the 560 °C answer, 49,107 h (measured at 590 °C: 5,100 h), exit 0.
#[test]
fn another_temperature_without_a_law_is_refused() {
    let tmp = TempDir::new().unwrap();
    let c = fit_560(tmp.path());
    let out = tmp.path().join("p");
    let e = fails(&[
        "predict",
        "configs/560C.toml",
        "--constants",
        c.to_str().unwrap(),
        "--at",
        "590:100",
        "--out",
        out.to_str().unwrap(),
    ]);
    has(
        &e,
        &[
            "--at 590:100",
            "590 °C",
            "no temperature law",
            "560 °C",
            "law = ",
        ],
    );
    assert!(!out.exists(), "nothing is written for a refused request");
    let cfg = config_560(
        tmp.path(),
        "at.toml",
        "\n[predict]\nat = [\"560:70\", \"590:100\"]\n",
        &[],
    );
    let e = fails(&[
        "predict",
        cfg.to_str().unwrap(),
        "--constants",
        c.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let line = std::fs::read_to_string(&cfg)
        .unwrap()
        .lines()
        .position(|l| l.starts_with("at = "))
        .unwrap()
        + 1;
    has(
        &e,
        &[
            &format!("at.toml:{line}: predict.at[1]: \"590:100\""),
            "no temperature law",
        ],
    );
}

// ---- 4. profile --constants says it refits, and how far ----------------------------------

/// `profile --constants` of the eq. 8 fit: the intervals are those of a maximum-likelihood
/// refit; `intervals.csv` says so (`value_source = ml_refit`), holds the given constant and
/// whether it lies inside the 95 % interval; `summary.json` and `report.md` give the
/// distance per constant and the −2 ln L difference. Before: B 0.1749 outside [0.1067,
/// 0.1234], C 4.03 outside [5.53, 6.21], and the report said only "local fit from the given
/// constants".
#[test]
fn profile_from_given_constants_says_it_refits() {
    let tmp = TempDir::new().unwrap();
    let c = fit_560(tmp.path());
    let cfg = config_560(
        tmp.path(),
        "p.toml",
        "\n[profile]\nstarts = 0\ncalibrate = 0\n",
        &[],
    );
    let out = tmp.path().join("profile");
    ok(&[
        "profile",
        cfg.to_str().unwrap(),
        "--constants",
        c.to_str().unwrap(),
        "--threads",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (h, r) = rows(&out.join("intervals.csv"));
    assert_eq!(&h[7..10], ["value_source", "given_value", "given_in95"]);
    let (_, given) = rows(&c);
    let mut outside = Vec::new();
    for (row, g) in r.iter().zip(&given) {
        assert_eq!(row["name"], g["name"]);
        assert_eq!(row["value_source"], "ml_refit");
        assert_eq!(row["given_value"], g["value"]);
        let (gv, lo, hi) = (num(row, "given_value"), num(row, "lo95"), num(row, "hi95"));
        assert_eq!(row["given_in95"], (lo <= gv && gv <= hi).to_string());
        if row["given_in95"] == "false" {
            outside.push(row["name"].clone());
        }
    }
    assert!(
        outside.contains(&"B".to_string()) && outside.contains(&"C".to_string()),
        "{outside:?}"
    );
    let s = json(&out.join("summary.json"));
    let reference = &s["reference"];
    let d = reference["delta_neg2ll_given"].as_f64().unwrap();
    let (g, v) = (
        reference["given_neg2ll"].as_f64().unwrap(),
        reference["neg2ll"].as_f64().unwrap(),
    );
    assert!(
        d > 0.0 && (d - (g - v)).abs() < 1e-9 * g.abs(),
        "{reference}"
    );
    assert_eq!(reference["given_constants"].as_array().unwrap().len(), 6);
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    has(
        &md,
        &[
            "REFIT from the given constants",
            "The refit against the given constants",
            "| B |",
            "NO",
        ],
    );
    // Without --constants the file says where the values come from, and has no given ones.
    let out2 = tmp.path().join("profile2");
    ok(&[
        "profile",
        cfg.to_str().unwrap(),
        "--threads",
        "2",
        "--out",
        out2.to_str().unwrap(),
    ]);
    let (_, r) = rows(&out2.join("intervals.csv"));
    for row in &r {
        assert_eq!(row["value_source"], "ml_multistart");
        assert_eq!(row["given_value"], "");
        assert_eq!(row["given_in95"], "");
    }
}

// ---- 5. constants files -------------------------------------------------------------------

/// A constants file with a repeated constant, an unknown or missing one, a value that is not
/// finite or outside the configuration's bounds: a one-line error naming the file, the line
/// and the field. Before: the last of two rows silently won, and a value outside the bounds
/// gave "NaN (invalid_start)" with exit 0.
#[test]
fn bad_constants_files_are_one_line_errors() {
    let tmp = TempDir::new().unwrap();
    let good = "name,value\nA,1.023e-10\nB,0.11506\nHstar,0.4\nh,12261.7\nKc,2.7764e-5\nC,5.7764\n";
    let cases: [(&str, String, &[&str]); 5] = [
        (
            "duplicate",
            format!("{good}B,0.15\n"),
            &[
                "c.csv:8:",
                "column 'name'",
                "'B' appears again (first on line 3)",
            ],
        ),
        (
            "unknown",
            good.replace("Hstar", "Hstr"),
            &["c.csv:4:", "column 'name'", "'Hstr' is not a constant"],
        ),
        (
            "missing",
            good.replace("Kc,2.7764e-5\n", ""),
            &["c.csv: column 'name'", "Kc missing"],
        ),
        (
            "not finite",
            good.replace("0.11506", "NaN"),
            &["c.csv:3:", "column 'value'", "B = 'NaN' is not finite"],
        ),
        (
            "outside",
            good.replace("5.7764", "-3"),
            &[
                "c.csv:7:",
                "column 'value'",
                "C = -3",
                "bounds [3, 10]",
                "constants.C",
            ],
        ),
    ];
    for (what, text, want) in cases {
        let c = tmp.path().join("c.csv");
        std::fs::write(&c, text).unwrap();
        for cmd in ["predict", "simulate", "profile"] {
            let out = tmp.path().join(format!("out-{cmd}"));
            let mut args = vec![
                cmd,
                "configs/560C.toml",
                "--constants",
                c.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ];
            if cmd == "predict" {
                args.extend(["--at", "560:85"]);
            }
            let e = fails(&args);
            has(&e, want);
            assert!(!out.exists(), "{what}, {cmd}: nothing is written");
        }
    }
    // A reference temperature given twice (the joint fit's constants, T_ref = 575 °C).
    let fit = tmp.path().join("joint");
    ok(&[
        "fit",
        "configs/cmv-joint.toml",
        "--out",
        fit.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(fit.join("constants.csv")).unwrap();
    let last = text.lines().last().unwrap().to_string();
    assert!(last.starts_with("T_ref,575,"), "{text}");
    let c = tmp.path().join("c.csv");
    std::fs::write(&c, format!("{text}{last}\n")).unwrap();
    let n = text.lines().count() + 1;
    let e = fails(&[
        "predict",
        "configs/cmv-joint.toml",
        "--constants",
        c.to_str().unwrap(),
        "--at",
        "575:100",
        "--out",
        tmp.path().join("j").to_str().unwrap(),
    ]);
    has(&e, &[&format!("c.csv:{n}:"), "'T_ref' appears again"]);
}

// ---- 6. impossible requests ---------------------------------------------------------------

/// Requests beyond what the configuration can predict are refused in one line naming the
/// option or the setting: more than 25 °C outside the tested temperatures, more than a
/// factor 1.5 outside the stresses tested there, an untested stress for `profile` far beyond
/// them; data temperatures below absolute zero or below 0 °C name file, line and column.
/// Inside the margins a row says where it extrapolates; a failed simulation says how it
/// ended and writes no number. Before: a minimum rate of 4.5e28 %/h at 5000 °C (the
/// `step_underflow` only on stdout), a Larson–Miller parameter of −4694 K at 1e9 MPa, a
/// 61-digit life at 20 °C, an empty table for `predict_stress_MPa = [1e6]`, a data
/// temperature of −300 °C accepted.
#[test]
fn impossible_requests_are_refused_and_extrapolations_marked() {
    let tmp = TempDir::new().unwrap();
    let fit = tmp.path().join("joint");
    ok(&[
        "fit",
        "configs/cmv-joint.toml",
        "--out",
        fit.to_str().unwrap(),
    ]);
    let c = fit.join("constants.csv");
    let out = tmp.path().join("p");
    let predict = |at: &str| {
        vec![
            "predict".to_string(),
            "configs/cmv-joint.toml".into(),
            "--constants".into(),
            c.to_str().unwrap().into(),
            "--at".into(),
            at.into(),
            "--out".into(),
            out.to_str().unwrap().into(),
        ]
    };
    let s = |v: &[String]| v.iter().map(String::to_string).collect::<Vec<_>>();
    for (at, want) in [
        (
            "5000:100",
            &[
                "--at 5000:100",
                "more than 25 °C outside the tested temperatures (560–590 °C)",
            ][..],
        ),
        ("20:100", &["--at 20:100", "more than 25 °C outside"][..]),
        (
            "575:1e9",
            &["more than a factor 1.5 outside the stresses tested at 575 °C (85–120 MPa)"][..],
        ),
        ("560:50", &["more than a factor 1.5", "(85–110 MPa)"][..]),
        ("-300:100", &["--at", "above absolute zero"][..]),
    ] {
        let a = s(&predict(at));
        let e = fails(&a.iter().map(String::as_str).collect::<Vec<_>>());
        has(&e, want);
        assert!(!out.exists());
    }
    // Inside the margins: the row says where it extrapolates (per-temperature stress
    // ranges: 575 °C lies between 560 (85–110 MPa) and 590 °C (100–120 MPa)).
    let a = s(&predict("575:100,560:70,600:110,600:75,590:100"));
    ok(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let (_, r) = rows(&out.join("predictions.csv"));
    let x: Vec<&str> = r.iter().map(|r| r["extrapolation"].as_str()).collect();
    assert_eq!(x, ["none", "stress", "temperature", "both", "none"]);
    let s = json(&out.join("summary.json"));
    assert_eq!(s["predictions"][3]["extrapolation"], "both");
    assert_eq!(s["limits"]["temperature_margin_C"], 25.0);

    // [profile] predict_stress_MPa far beyond the tested stresses.
    let cfg = config_560(
        tmp.path(),
        "p.toml",
        "\n[profile]\nstarts = 0\ncalibrate = 0\npredict_stress_MPa = [1e6]\n",
        &[],
    );
    let line = std::fs::read_to_string(&cfg)
        .unwrap()
        .lines()
        .position(|l| l.starts_with("predict_stress_MPa"))
        .unwrap()
        + 1;
    let e = fails(&[
        "profile",
        cfg.to_str().unwrap(),
        "--out",
        tmp.path().join("pr").to_str().unwrap(),
    ]);
    has(
        &e,
        &[
            &format!("p.toml:{line}: profile.predict_stress_MPa: 1000000 MPa"),
            "factor 1.5",
        ],
    );

    // Data temperatures: below absolute zero, and below 0 °C (a typo or a unit mix-up).
    let curves = std::fs::read_to_string(root().join("data/creep_560C.csv")).unwrap();
    let n = curves.lines().count() + 1;
    for (t, want) in [
        ("-300", "below absolute zero"),
        ("-5", "between 0 and 2000 °C"),
    ] {
        let d = tmp.path().join(format!("c{t}.csv"));
        // A whole curve at that temperature (the configuration keeps only 560 °C).
        std::fs::write(
            &d,
            format!("{curves}{t},85,0,0\n{t},85,500,0.06\n{t},85,1000,0.1\n"),
        )
        .unwrap();
        let cfg = config_560(
            tmp.path(),
            "d.toml",
            "",
            &[(
                &format!("{}/data/creep_560C.csv", root().display()),
                d.to_str().unwrap(),
            )],
        );
        let e = fails(&[
            "fit",
            cfg.to_str().unwrap(),
            "--out",
            tmp.path().join("f").to_str().unwrap(),
        ]);
        has(
            &e,
            &[&format!("c{t}.csv:{n}: column 'temperature_C'"), want],
        );
    }

    // A simulation that fails: its outcome in the row, no number written.
    let cfg = config_560(tmp.path(), "w.toml", "", &[("ub = 0.2, ", "ub = 20,  ")]);
    let c = tmp.path().join("c.csv");
    std::fs::write(
        &c,
        "name,value\nA,1.023e-10\nB,15\nHstar,0.4\nh,12261.7\nKc,2.7764e-5\nC,5.7764\n",
    )
    .unwrap();
    let out = tmp.path().join("fail");
    let stdout = ok(&[
        "predict",
        cfg.to_str().unwrap(),
        "--constants",
        c.to_str().unwrap(),
        "--at",
        "560:85",
        "--out",
        out.to_str().unwrap(),
    ]);
    has(&stdout, &["invalid_start"]);
    let (_, r) = rows(&out.join("predictions.csv"));
    assert_eq!(r[0]["outcome"], "invalid_start");
    for k in ["rupture_time_h", "rupture_strain_pct", "min_rate_pct_per_h"] {
        assert_eq!(r[0][k], "", "{k}");
    }
}

// ---- 3'. gross outliers in curve data -----------------------------------------------------

/// One row `560,85,390,1000000` (strain 1,000,000 %) added to the 560 °C curves: `fit`
/// refuses in one line naming the file, line, value and robust z and the switch; with
/// `outliers = "drop"` the point is dropped, named in a warning and in manifest.json, and the
/// fit is exactly the fit of the clean data. Before: exit 0 with lifetime errors +48/−22/−45 %.
#[test]
fn a_gross_outlier_is_refused_or_dropped() {
    let tmp = TempDir::new().unwrap();
    let clean = tmp.path().join("clean");
    ok(&["fit", "configs/560C.toml", "--out", clean.to_str().unwrap()]);
    // The row goes in among the curve's own rows, after the measured point at 390 h.
    let curves = std::fs::read_to_string(root().join("data/creep_560C.csv")).unwrap();
    let at = "560,85,390,0.051\n";
    assert!(curves.contains(at));
    let n = 4;
    assert_eq!(curves.lines().nth(n - 2), Some(at.trim_end()));
    let d = tmp.path().join("typo.csv");
    std::fs::write(
        &d,
        curves.replacen(at, &format!("{at}560,85,390,1000000\n"), 1),
    )
    .unwrap();
    let from = format!("{}/data/creep_560C.csv", root().display());
    let cfg = config_560(tmp.path(), "t.toml", "", &[(&from, d.to_str().unwrap())]);
    let out = tmp.path().join("fit");
    let e = fails(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    has(
        &e,
        &[
            &format!("typo.csv:{n}: column 'strain_pct': 1000000 % at 390 h"),
            "gross outlier",
            "robust z = ",
            "outliers = \"drop\"",
        ],
    );
    assert!(!out.exists());
    let cfg = config_560(
        tmp.path(),
        "d.toml",
        "",
        &[
            (&from, d.to_str().unwrap()),
            ("model = ", "outliers = \"drop\"\nmodel = "),
        ],
    );
    let o = creepfit(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    has(
        &err,
        &[
            &format!("warning: {}:{n}: ", d.display()),
            "dropped (outliers = \"drop\")",
        ],
    );
    let m = json(&out.join("manifest.json"));
    let dropped = m["dropped_points"].as_array().unwrap();
    assert_eq!(dropped.len(), 1, "{m}");
    assert_eq!(dropped[0]["line"], n);
    assert_eq!(dropped[0]["strain_pct"], 1_000_000.0);
    assert!(dropped[0]["z"].as_f64().unwrap() > 50.0);
    assert_eq!(dropped[0]["column"], "strain_pct");
    assert!(dropped[0].get("rupture_time_h").is_none(), "{m}");
    assert_eq!(
        std::fs::read_to_string(out.join("constants.csv")).unwrap(),
        std::fs::read_to_string(clean.join("constants.csv")).unwrap()
    );
}

/// One reading's time mistyped (`560,85,390,0.051` as `560,85,3900000,0.051`: 43 × the
/// test's rupture time of 91,000 h): `fit` refuses in one line naming the file, line, column
/// and the rupture time; with `outliers = "drop"` the reading is dropped, named in a warning
/// and in manifest.json (`column` `time_h`, the rupture time), and the fit is exactly the fit
/// of the data without that row. Before: exit 0, the reading compared with the model's
/// continuation past the rupture, a warning on stderr only.
#[test]
fn a_reading_after_the_rupture_is_refused_or_dropped() {
    let tmp = TempDir::new().unwrap();
    let curves = std::fs::read_to_string(root().join("data/creep_560C.csv")).unwrap();
    let at = "560,85,390,0.051\n";
    assert!(curves.contains(at));
    let n = 3;
    assert_eq!(curves.lines().nth(n - 1), Some(at.trim_end()));
    let without = tmp.path().join("without.csv");
    std::fs::write(&without, curves.replacen(at, "", 1)).unwrap();
    let typo = tmp.path().join("typo.csv");
    std::fs::write(&typo, curves.replacen(at, "560,85,3900000,0.051\n", 1)).unwrap();
    let from = format!("{}/data/creep_560C.csv", root().display());
    let clean_cfg = config_560(
        tmp.path(),
        "w.toml",
        "",
        &[(&from, without.to_str().unwrap())],
    );
    let clean = tmp.path().join("clean");
    ok(&[
        "fit",
        clean_cfg.to_str().unwrap(),
        "--out",
        clean.to_str().unwrap(),
    ]);
    let cfg = config_560(tmp.path(), "t.toml", "", &[(&from, typo.to_str().unwrap())]);
    let out = tmp.path().join("fit");
    let e = fails(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    has(
        &e,
        &[
            &format!(
                "typo.csv:{n}: column 'time_h': 3900000 h is 42.86 × the rupture time 91000 h"
            ),
            "a reading after the rupture",
            "outliers = \"drop\"",
        ],
    );
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(!out.exists());
    let cfg = config_560(
        tmp.path(),
        "d.toml",
        "",
        &[
            (&from, typo.to_str().unwrap()),
            ("model = ", "outliers = \"drop\"\nmodel = "),
        ],
    );
    let o = creepfit(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    has(
        &err,
        &[
            &format!("warning: {}:{n}: column 'time_h'", typo.display()),
            "dropped (outliers = \"drop\")",
        ],
    );
    let m = json(&out.join("manifest.json"));
    let dropped = m["dropped_points"].as_array().unwrap();
    assert_eq!(dropped.len(), 1, "{m}");
    assert_eq!(dropped[0]["line"], n);
    assert_eq!(dropped[0]["column"], "time_h");
    assert_eq!(dropped[0]["time_h"], 3_900_000.0);
    assert_eq!(dropped[0]["rupture_time_h"], 91_000.0);
    assert!(dropped[0].get("z").is_none(), "{m}");
    assert_eq!(
        std::fs::read_to_string(out.join("constants.csv")).unwrap(),
        std::fs::read_to_string(clean.join("constants.csv")).unwrap()
    );
}

/// Real measurements stay data: every curve of the seed data and all 34 Alloy 617 curves
/// (small negative strains at the start, repeated times, a jump on loading at t = 0, steep
/// tertiary ends) load unchanged under the default (refuse) and have no point anywhere near
/// the outlier limit.
#[test]
fn real_curves_have_no_gross_outlier() {
    use creepfit::data::{self, outlier_z, LoadOptions, OutlierPolicy, OUTLIER_Z};
    let sets = [
        ("data/creep_560C.csv", "data/lifetimes.csv", 3),
        ("data/creep_590C.csv", "data/lifetimes.csv", 3),
        ("data/creep_cmv.csv", "data/lifetimes.csv", 6),
        (
            "data/alloy617/creep_alloy617.csv",
            "data/alloy617/ruptures_alloy617.csv",
            34,
        ),
    ];
    let mut worst = (0.0f64, String::new());
    for (c, r, n) in sets {
        let load = |outliers| {
            data::load(
                &root().join(c),
                &root().join(r),
                &LoadOptions {
                    several_temperatures: true,
                    outliers,
                    ..Default::default()
                },
            )
            .unwrap_or_else(|e| panic!("{c}: {e}"))
        };
        let refused = load(OutlierPolicy::Refuse);
        assert_eq!(refused.curves.len(), n, "{c}");
        assert!(refused.dropped.is_empty());
        assert_eq!(refused, load(OutlierPolicy::Keep), "{c}");
        for cu in &refused.curves {
            let z = outlier_z(&cu.strains);
            let (k, m) = z
                .iter()
                .enumerate()
                .fold((0, 0.0f64), |a, (k, v)| if *v > a.1 { (k, *v) } else { a });
            if m > worst.0 {
                worst = (m, format!("{c}: {} at {} h", cu.label(), cu.times_h[k]));
            }
        }
    }
    eprintln!(
        "largest robust z of the real curves: {:.3} ({})",
        worst.0, worst.1
    );
    assert!(worst.0 < OUTLIER_Z / 5.0, "{worst:?}");
}

// ---- 7. a run owns its output folder ------------------------------------------------------

/// The files a manifest lists, and the other keys.
fn manifest(dir: &Path) -> (Vec<String>, serde_json::Value) {
    let m = json(&dir.join("manifest.json"));
    let files = m["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap().to_string())
        .collect();
    (files, m)
}

/// Every (non-hidden) file of `dir` besides manifest.json, relative, sorted.
fn files_in(dir: &Path) -> Vec<String> {
    let mut v = Vec::new();
    fn walk(root: &Path, d: &Path, v: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if name.starts_with('.') || name == "manifest.json" {
                continue;
            }
            if p.is_dir() {
                walk(root, &p, v);
            } else {
                v.push(
                    p.strip_prefix(root)
                        .unwrap()
                        .to_string_lossy()
                        .replace('\\', "/"),
                );
            }
        }
    }
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// A second `predict` into the folder of a first one with `--intervals` leaves none of the
/// first run's files: band.csv and band.png go; the manifest lists exactly the files in the
/// folder, says complete, names the command and what it removed. A file put there by hand
/// stays and is named as not this run's. Before: band.csv and band.png of the first run
/// stayed.
#[test]
fn a_second_run_leaves_no_file_of_the_first() {
    let tmp = TempDir::new().unwrap();
    let c = fit_560(tmp.path());
    let out = tmp.path().join("p");
    let args = |intervals: bool| {
        let mut a = vec![
            "predict",
            "configs/560C.toml",
            "--constants",
            c.to_str().unwrap(),
            "--at",
            "560:85",
            "--out",
            out.to_str().unwrap(),
        ];
        if intervals {
            a.push("--intervals");
        }
        a
    };
    ok(&args(true));
    let (first, m) = manifest(&out);
    assert_eq!(m["complete"], true);
    assert_eq!(m["command"], "predict");
    assert!(first.contains(&"band.csv".to_string()) && first.contains(&"band.png".to_string()));
    assert_eq!(files_in(&out), first);
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    ok(&args(false));
    let (second, m) = manifest(&out);
    assert_eq!(m["complete"], true);
    assert!(!out.join("band.csv").exists() && !out.join("band.png").exists());
    let mut expect = second.clone();
    expect.push("notes.txt".into());
    expect.sort();
    assert_eq!(files_in(&out), expect);
    assert_eq!(m["other_files"], serde_json::json!(["notes.txt"]));
    let removed: Vec<&str> = m["removed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(removed.contains(&"band.csv") && removed.contains(&"band.png"));
    let argv = m["argv"].as_array().unwrap();
    assert!(argv.iter().any(|a| a == "predict") && !argv.iter().any(|a| a == "--intervals"));
}

/// A full disk during `profile` into the folder of an earlier `profile` at another
/// temperature: the command fails, the manifest says incomplete, and no file of the earlier
/// run is left beside the new one's. Before: a 590 °C intervals.csv beside 560 °C
/// profiles.csv, summary.json and report.md, nothing marking the set incomplete.
#[test]
fn a_failed_run_leaves_its_folder_marked_incomplete() {
    let tmp = TempDir::new().unwrap();
    let cfg590 = {
        let text = std::fs::read_to_string(root().join("configs/590C.toml"))
            .unwrap()
            .replace("../data/", &format!("{}/data/", root().display()));
        let p = tmp.path().join("590.toml");
        std::fs::write(
            &p,
            format!("{text}\n[profile]\nstarts = 0\ncalibrate = 0\n"),
        )
        .unwrap();
        p
    };
    let cfg560 = config_560(
        tmp.path(),
        "560.toml",
        "\n[profile]\nstarts = 0\ncalibrate = 0\n",
        &[],
    );
    let out = tmp.path().join("profile");
    ok(&[
        "profile",
        cfg590.to_str().unwrap(),
        "--threads",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (first, m) = manifest(&out);
    assert_eq!(m["complete"], true);
    let old: HashMap<String, Vec<u8>> = first
        .iter()
        .map(|f| (f.clone(), std::fs::read(out.join(f)).unwrap()))
        .collect();
    // Another run's journal would be refused (naming the differing setting): the folder is
    // taken over by a new run once its journal is removed, as the refusal says.
    std::fs::remove_file(out.join("journal.jsonl")).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_creepfit"))
        .args([
            "profile",
            cfg560.to_str().unwrap(),
            "--threads",
            "2",
            "--out",
        ])
        .arg(&out)
        .env(creepfit::output::WRITE_BUDGET_ENV, "4000")
        .current_dir(root())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    has(&err, &["no space left on device"]);
    let (_, m) = manifest(&out);
    assert_eq!(m["complete"], false, "{m}");
    for f in files_in(&out) {
        if let Some(bytes) = old.get(&f) {
            assert_ne!(
                &std::fs::read(out.join(&f)).unwrap(),
                bytes,
                "{f} of the 590 °C run is left"
            );
        }
    }
}

/// Every command's folder gets a manifest listing exactly the files it wrote.
#[test]
fn every_command_writes_a_manifest() {
    let tmp = TempDir::new().unwrap();
    let c = fit_560(tmp.path());
    let check = |dir: &Path, command: &str| {
        let (files, m) = manifest(dir);
        assert_eq!(m["command"], command, "{m}");
        assert_eq!(m["complete"], true, "{m}");
        assert_eq!(files_in(dir), files, "{command}");
        assert!(!files.is_empty());
    };
    check(&tmp.path().join("fit"), "fit");
    let sim = tmp.path().join("sim");
    ok(&[
        "simulate",
        "configs/560C.toml",
        "--constants",
        c.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
    ]);
    check(&sim, "simulate");
    let (h, r) = rows(&sim.join("ruptures.csv"));
    assert_eq!(h.last().unwrap(), "outcome");
    assert!(r.iter().all(|r| r["outcome"] == "ruptured"));
    // sweep twice into one folder (the second resumes: its journal stays), then merge.
    let sw = tmp.path().join("sweep");
    for _ in 0..2 {
        ok(&[
            "sweep",
            "tests/data/sweep_small.toml",
            "--starts",
            "1",
            "--threads",
            "1",
            "--out",
            sw.to_str().unwrap(),
        ]);
        check(&sw, "sweep");
        assert!(manifest(&sw).0.contains(&"journal.jsonl".to_string()));
    }
    let merged = tmp.path().join("merged");
    ok(&[
        "merge",
        sw.to_str().unwrap(),
        "--out",
        merged.to_str().unwrap(),
    ]);
    check(&merged, "merge");
    // diagnose, small.
    let cfg = config_560(
        tmp.path(),
        "d.toml",
        "\n[diagnose]\nextensions = [\"loading_strain\"]\nstarts = 0\nreplicate_basins = 1\nbootstrap = 19\nalpha = 0.5\n",
        &[],
    );
    let d = tmp.path().join("diag");
    ok(&[
        "diagnose",
        cfg.to_str().unwrap(),
        "--threads",
        "2",
        "--out",
        d.to_str().unwrap(),
    ]);
    check(&d, "diagnose");
}

// ---- 8. battery: one writer, one battery per folder ---------------------------------------

/// `battery` takes its folder's lock (a second run into it is refused at once, naming the
/// first's pid) and binds the folder to its first seed (another seed is refused, naming
/// both), before anything in the folder changes. Before: two runs wrote 6 records for 3 sets,
/// and a folder made with seed 50001 was silently reused for seed 50002.
#[test]
fn battery_is_locked_and_keeps_its_identity() {
    let tmp = TempDir::new().unwrap();
    let out = tmp.path().join("b");
    let mut first = Command::new(env!("CARGO_BIN_EXE_creepfit"))
        .args([
            "battery",
            "--sets",
            "1",
            "--seed",
            "50001",
            "--threads",
            "1",
        ])
        .arg(&out)
        .current_dir(root())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    // The identity is written first, then the manifest (the folder taken over).
    while !out.join("manifest.json").exists() {
        assert!(t0.elapsed().as_secs() < 60, "manifest.json never appeared");
        assert!(
            first.try_wait().unwrap().is_none(),
            "the first battery ended early"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let o = out.to_str().unwrap();
    let e = fails(&["battery", "--sets", "1", "--seed", "50001", o]);
    has(
        &e,
        &["another creepfit run", &format!("pid {}", first.id())],
    );
    first.kill().unwrap();
    first.wait().unwrap();
    let (_, m) = manifest(&out);
    assert_eq!(m["complete"], false, "a killed battery is incomplete: {m}");
    let id = json(&out.join("battery.json"));
    assert_eq!(id["identity"]["seed"], 50001);
    let e = fails(&["battery", "--sets", "1", "--seed", "50002", o]);
    has(&e, &["battery.json", "seed = 50001", "50002"]);
    // A battery of one scenario is another battery, and an unknown scenario is refused
    // before anything is touched.
    let e = fails(&[
        "battery",
        "--sets",
        "1",
        "--seed",
        "50001",
        "--scenario",
        "none",
        o,
    ]);
    has(&e, &["battery.json", "scenario"]);
    let e = fails(&["battery", "--sets", "1", "--scenario", "nonn", o]);
    has(&e, &["--scenario", "nonn", "known: none, constant_load"]);
    // So is one that measures another configuration's specimen effects, and an unknown kind
    // is refused by name.
    let e = fails(&[
        "battery",
        "--sets",
        "1",
        "--seed",
        "50001",
        "--specimen-effects",
        "rate,coarsening",
        o,
    ]);
    has(&e, &["battery.json", "specimen_effects", "coarsening"]);
    let e = fails(&["battery", "--specimen-effects", "rate,shape", o]);
    has(&e, &["--specimen-effects", "shape"]);
    assert_eq!(json(&out.join("battery.json")), id, "nothing changed");
}

// ---- property: constants files and --at requests ------------------------------------------

/// The joint seed configuration's constants, valid for it (`fit configs/cmv-joint.toml`).
const JOINT: [(&str, &str); 9] = [
    ("A", "5.324147248473007e-9"),
    ("B", "0.1"),
    ("Hstar", "0.40423178568034435"),
    ("h", "299999.9999999999"),
    ("Kc", "1.3874027846370444e-5"),
    ("C", "5.407353899534004"),
    ("A.Q", "597.6825235463488"),
    ("Kc.Q", "0"),
    ("T_ref", "575"),
];

/// Values a constants cell may hold besides the valid one.
const CELLS: &[&str] = &[
    "NaN", "inf", "-inf", "1e308", "1e309", "-1", "0", "1e-320", "x", "", "1e-12", "0.2", "1000",
    "3e5", "2", "10", "0.3", "575", "560",
];

/// Temperatures and stresses an `--at` request may hold.
const TEMPS: &[&str] = &[
    "560", "575", "590", "600", "614.9", "615.1", "535", "534", "-300", "-273.15", "5000", "20",
    "1e300", "NaN", "x", "",
];
const STRESSES: &[&str] = &[
    "85", "100", "120", "70", "56.7", "56", "180", "181", "1e-9", "1e9", "0", "-5", "inf", "x",
];

/// Every cell of every CSV file in `dir` that reads as a number is finite.
fn no_non_finite_number(dir: &Path) -> Result<usize, String> {
    let mut cells = 0;
    for e in std::fs::read_dir(dir).map_err(|e| e.to_string())? {
        let p = e.map_err(|e| e.to_string())?.path();
        if p.extension().is_none_or(|x| x != "csv") {
            continue;
        }
        let mut rdr = csv::Reader::from_path(&p).map_err(|e| e.to_string())?;
        for r in rdr.records() {
            for cell in r.map_err(|e| e.to_string())?.iter() {
                cells += 1;
                if let Ok(v) = cell.trim().parse::<f64>() {
                    if !v.is_finite() {
                        return Err(format!("{}: cell {cell:?}", p.display()));
                    }
                }
            }
        }
    }
    Ok(cells)
}

/// Random constants files (rows left out, repeated, unknown, shuffled; values not finite,
/// outside the bounds, not numbers) and random `--at` requests (inside and outside the
/// margins, impossible, malformed) for `predict configs/cmv-joint.toml`: never a panic;
/// either an error of one line or outputs whose every number is finite.
#[test]
fn predict_never_writes_a_non_finite_number() {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
    let tmp = TempDir::new().unwrap();
    // Mostly whole files with a few changes, so that both refusals and outputs occur.
    let row = (
        0..JOINT.len(),
        prop_oneof![1 => Just(None), 3 => (0..CELLS.len()).prop_map(Some)],
    );
    let extra = prop_oneof![
        2 => Just(vec![]),
        1 => prop::collection::vec(row, 1..4),
    ];
    let constants = (
        extra,
        prop::collection::vec(prop::bool::weighted(0.95), JOINT.len()),
    );
    let cond = (
        0..TEMPS.len(),
        0..STRESSES.len(),
        540.0..610.0f64,
        60.0..170.0f64,
        prop_oneof![4 => Just(0u8), 1 => 1..4u8],
    );
    let at = prop::collection::vec(cond, 1..3);
    let mut runner = TestRunner::new_with_rng(
        Config {
            cases: 96,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]),
    );
    let (errors, written) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    let case = std::cell::Cell::new(0);
    runner
        .run(&(constants, at), |((extra, keep), at)| {
            let k = case.get();
            case.set(k + 1);
            // The valid rows kept, then the extra ones (repeats, other values).
            let mut text = String::from("name,value\n");
            for (i, (n, v)) in JOINT.iter().enumerate() {
                if keep[i] {
                    text += &format!("{n},{v}\n");
                }
            }
            for (i, cell) in &extra {
                let v = cell.map_or(JOINT[*i].1, |c| CELLS[c]);
                let n = if *i == 0 && cell.is_some() {
                    "Z"
                } else {
                    JOINT[*i].0
                };
                text += &format!("{n},{v}\n");
            }
            let c = tmp.path().join(format!("c{k}.csv"));
            std::fs::write(&c, &text).unwrap();
            let at: Vec<String> = at
                .iter()
                .map(|(t, s, tf, sf, pick)| match pick {
                    0 => format!("{tf}:{sf}"),
                    1 => format!("{}:{sf}", TEMPS[*t]),
                    2 => format!("{tf}:{}", STRESSES[*s]),
                    _ => format!("{}:{}", TEMPS[*t], STRESSES[*s]),
                })
                .collect();
            let out = tmp.path().join(format!("o{k}"));
            let config = root().join("configs/cmv-joint.toml");
            let args = [
                "creepfit",
                "predict",
                config.to_str().unwrap(),
                "--constants",
                c.to_str().unwrap(),
                "--at",
                &at.join(","),
                "--out",
                out.to_str().unwrap(),
            ];
            use clap::Parser;
            let cli = creepfit::cli::Cli::try_parse_from(args).unwrap();
            let res = creepfit::cli::run(cli);
            match res {
                Err(e) => {
                    let m = e.to_string();
                    prop_assert!(!m.contains('\n'), "{m}");
                    prop_assert!(!out.join("predictions.csv").exists(), "{m}");
                    errors.set(errors.get() + 1);
                }
                Ok(()) => {
                    let n = no_non_finite_number(&out).map_err(TestCaseError::fail)?;
                    prop_assert!(n > 0);
                    written.set(written.get() + 1);
                }
            }
            Ok(())
        })
        .unwrap();
    eprintln!("{} runs refused, {} written", errors.get(), written.get());
    assert!(errors.get() > 0 && written.get() > 0);
}

/// The generated data `battery` diagnoses load under the default (refuse): 140 sets, every
/// scenario (a mid-life step and a primary transient included), none near the limit.
#[test]
fn generated_sets_have_no_gross_outlier() {
    use creepfit::config::RunConfig;
    use creepfit::data::{outlier_z, OUTLIER_Z};
    let tmp = TempDir::new().unwrap();
    let mut worst = (0.0f64, String::new());
    for i in 0..140usize {
        let seed = 90_001 + i as u64;
        let scenario = creepfit::synth::scenario_of(i);
        let name = format!("set-{seed}");
        let set = creepfit::synth::generate(&name, scenario, seed).unwrap();
        let dir = tmp.path().join(&name);
        creepfit::synth::write_set(&set, &dir).unwrap();
        let cfg = RunConfig::load(&dir.join("config.toml")).unwrap();
        let data = cfg
            .load_data()
            .unwrap_or_else(|e| panic!("{name} ({scenario}): {e}"));
        for c in &data.curves {
            let m = outlier_z(&c.strains).into_iter().fold(0.0, f64::max);
            if m > worst.0 {
                worst = (m, format!("{name} ({scenario}), {}", c.label()));
            }
        }
    }
    eprintln!(
        "largest robust z of 140 generated sets: {:.3} ({})",
        worst.0, worst.1
    );
    assert!(worst.0 < OUTLIER_Z / 5.0, "{worst:?}");
}

/// A best fit that has fitted nothing says so in summary.json and on stdout. First measured on
/// a generated 590 °C set with a hidden loading strain under specimen scatter (seed 95102): the
/// fit from the (moved) initial guess stopped after one iteration with `converged_gradient`
/// while every predicted rupture time was 0.03–0.3 % of the measured. Since the integrator
/// follows fast primary transients (2026-11-27) that guess is evaluable and its fit ends within
/// a factor of 3, so the case is built here: the seed's 560 °C data from a configured start at
/// the corner of its box (A, B at their upper bounds: lives 45–350× too short), one iteration
/// allowed. The seed's own 560 °C fit carries no caution.
#[test]
fn a_fit_that_fitted_nothing_is_marked() {
    let dir = TempDir::new().unwrap();
    let cfg = config_560(
        dir.path(),
        "nofit.toml",
        "\n[solver]\nmax_iterations = 1\n",
        &[(
            "B     = { lb = 0.1,   ub = 0.2,   start = 0.11 }",
            "B     = { lb = 0.1,   ub = 0.2,   start = 0.2 }",
        )],
    );
    let out = dir.path().join("fit");
    let stdout = ok(&[
        "fit",
        cfg.to_str().unwrap(),
        "--start",
        "config",
        "--out",
        out.to_str().unwrap(),
    ]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let errs: Vec<f64> = s["lifetime_err_pct"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(errs.iter().all(|e| *e <= -90.0), "{errs:?}");
    let caution = s["caution"].as_str().expect("a caution");
    has(caution, &["factor of 10", "has not fitted"]);
    has(&stdout, &["caution: every predicted rupture time"]);
    let good = fit_560(dir.path());
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(good.with_file_name("summary.json")).unwrap(),
    )
    .unwrap();
    assert!(s["caution"].is_null(), "{}", s["caution"]);
}

/// A likelihood fit whose reading error took the misfit for correlated noise says so
/// (`fit::absorbed_noise_caution`): Alloy 617 at 850 °C, all points, no specimen effects, φ
/// 1.00 on every one of its 13 curves (measured 2026-12-02). The seed's 560 °C likelihood fit
/// has it on 1 of 3 curves and carries no caution.
#[test]
fn a_likelihood_fit_whose_error_model_took_the_misfit_is_marked() {
    let dir = TempDir::new().unwrap();
    let text = std::fs::read_to_string(root().join("configs/alloy617-850C.toml"))
        .unwrap()
        .replace("../data/", &format!("{}/data/", root().display()))
        .replace(
            "specimen_effects = \"auto\"",
            "specimen_effects = []\nkind = \"likelihood\"",
        )
        .replace("specimen_scatter = \"beyond_stress_trend\"\n", "");
    assert!(text.contains("kind = \"likelihood\"") && !text.contains("\nspecimen_scatter"));
    let cfg = dir.path().join("a617.toml");
    std::fs::write(&cfg, text).unwrap();
    let out = dir.path().join("fit");
    let stdout = ok(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let caution = s["caution"].as_str().expect("a caution");
    has(
        caution,
        &["φ ≥ 0.99 on 13 of 13 curves", "correlated noise"],
    );
    has(&stdout, &["caution: the likelihood's reading error"]);
    let cfg = config_560(
        dir.path(),
        "lik560.toml",
        "",
        &[("[objective]\n", "[objective]\nkind = \"likelihood\"\n")],
    );
    let out = dir.path().join("fit560");
    ok(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["caution"].is_null(), "{}", s["caution"]);
}

/// A likelihood fit whose reading error writes curves off as noise says so (issue 20: on a
/// single-crystal data set a fit took a whole curve for reading error of sd 9 % strain), and
/// summary.json marks each such curve (`error_model.curves[].written_off`, from its sd and
/// largest strain as written there). Data far from the seed's steel (`tests/data/far_material`,
/// theta-projection curves whose rupture strains differ 8–28 % between specimens): fitted
/// without specimen factors (`specimen_scatter = "likelihood"`, no replicates), 8 of its 17
/// curves are written off (measured 2026-12-03); with the specimens' rate and ductility
/// factors (the default since 2026-12-04, `specimen_scatter = "beyond_stress_trend"`), none,
/// and no caution.
#[test]
fn a_likelihood_fit_that_writes_curves_off_as_noise_is_marked() {
    let dir = TempDir::new().unwrap();
    let data = root().join("tests/data/far_material");
    let abs = |f: &str| format!("\"{}\"", data.join(f).display());
    let text = std::fs::read_to_string(data.join("config.toml"))
        .unwrap()
        .replace("\"curves.csv\"", &abs("curves.csv"))
        .replace("\"ruptures.csv\"", &abs("ruptures.csv"));
    let written_off = |s: &serde_json::Value| -> usize {
        let curves = s["error_model"]["curves"].as_array().unwrap();
        for c in curves {
            let ratio =
                c["residual_sd_pct"].as_f64().unwrap() / c["largest_strain_pct"].as_f64().unwrap();
            assert_eq!(c["written_off"].as_bool().unwrap(), ratio >= 0.25, "{c}");
        }
        curves.iter().filter(|c| c["written_off"] == true).count()
    };
    let cfg = dir.path().join("far.toml");
    // Without factors: the likelihood's own scatter estimate fits none without replicates
    // (the default since 2026-12-04, beyond the stress trend, fits them: below).
    std::fs::write(
        &cfg,
        text.replace(
            "[objective]\n",
            "[objective]\nspecimen_scatter = \"likelihood\"\n",
        ),
    )
    .unwrap();
    let out = dir.path().join("fit");
    let stdout = ok(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let s = json(&out.join("summary.json"));
    let k = written_off(&s);
    assert!(k >= 3, "{k} curves written off");
    let caution = s["caution"].as_str().expect("a caution");
    has(
        caution,
        &[
            &format!("writes {k} of 17 curves off as noise"),
            "specimen_effects",
        ],
    );
    // On stdout the cautions' line (the lives' caution may come first: SX01 is missed 9×).
    let line = stdout
        .lines()
        .find(|l| l.starts_with("caution: "))
        .expect("a caution line");
    has(line, &["the likelihood's reading error writes"]);
    // The default: the scatter beyond the stress trend.
    let cfg = dir.path().join("far_beyond.toml");
    std::fs::write(&cfg, &text).unwrap();
    let out = dir.path().join("fit_beyond");
    ok(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let s = json(&out.join("summary.json"));
    assert_eq!(s["specimens"]["fitted"], true, "{}", s["specimens"]);
    // Labels SX01 … SX17 name no campaign of two specimens: no table by campaign.
    assert_eq!(
        s["specimens"]["by_campaign"].as_array().map_or(0, Vec::len),
        0,
        "{}",
        s["specimens"]["by_campaign"]
    );
    assert_eq!(written_off(&s), 0);
    assert!(
        s["caution"]
            .as_str()
            .is_none_or(|c| !c.contains("off as noise")),
        "{}",
        s["caution"]
    );
}

/// A rupture time with a lost digit (3,111 h for the seed's 560 °C, 110 MPa life of 31,111 h,
/// whose curve runs to about 31,000 h) is before the curve's last reading: the loader's
/// warning names file and line on stderr and in `manifest.json` → `data_warnings`; the data as
/// shipped carry no such warning.
#[test]
fn a_rupture_time_before_its_curves_end_is_marked_in_the_manifest() {
    let tmp = TempDir::new().unwrap();
    for (life, marked) in [("3111", true), ("31111", false)] {
        let dir = tmp.path().join(life);
        std::fs::create_dir(&dir).unwrap();
        let cfg = seed_560_with_life(&dir, "560,110,31111,", &format!("560,110,{life},"));
        let out = dir.join("fit");
        let o = creepfit(&["fit", cfg.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        let m = json(&out.join("manifest.json"));
        let before = |w: &str| w.contains("is before the last measured time");
        let noted: Vec<String> = m["data_warnings"]
            .as_array()
            .map(|a| a.iter().map(|v| v.as_str().unwrap().to_string()).collect())
            .unwrap_or_default();
        if marked {
            let lives = dir.join("lifetimes.csv");
            let line = std::fs::read_to_string(&lives)
                .unwrap()
                .lines()
                .position(|l| l.starts_with("560,110,3111,"))
                .unwrap()
                + 1;
            let w = noted
                .iter()
                .find(|w| before(w))
                .expect("the warning in the manifest");
            assert!(
                w.starts_with(&format!(
                    "{}:{line}: rupture_time_h = 3111",
                    lives.display()
                )),
                "{w}"
            );
            assert!(err.contains(&format!("warning: {w}")), "{err}");
        } else {
            assert!(!noted.iter().any(|w| before(w)), "{noted:?}");
        }
    }
}
