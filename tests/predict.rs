//! `creepfit predict` and `creepfit holdout` through the binary: the contract columns in the
//! order asked, predictions at tested conditions equal to `simulate`, the reference
//! temperature of the constants checked, bad conditions refused in one line, and a hold-out
//! temperature predicted from synthetic curves of known constants.

use std::path::{Path, PathBuf};

use creepfit::baseline::{
    BaselineSettings, MansonHaferd, OrrSherbyDorn, RuptureParameter, TensileStrength, Wilshire,
};
use creepfit::data::estimate_min_rate;
use creepfit::model::{build, with_laws, LawKind, Load};
use creepfit::ode::OdeOptions;
use tempfile::TempDir;

mod common;
use common::*;

fn ok(args: &[&str]) -> String {
    let o = creepfit(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn csv(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// Each of `files` in `dir` is a whole, non-empty PNG (signature, IHDR, IEND).
fn assert_pngs(dir: &Path, files: &[&str]) {
    for f in files {
        let bytes = std::fs::read(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(bytes.len() > 5_000, "{f}: {} bytes", bytes.len());
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{f}");
        assert_eq!(&bytes[12..16], b"IHDR", "{f}");
        assert_eq!(&bytes[bytes.len() - 8..bytes.len() - 4], b"IEND", "{f}");
    }
}

/// The joint seed calibration fitted once into `dir`: its constants.csv. `fit` draws the
/// curves and the three diagrams (two temperatures: the Larson–Miller one too).
fn joint_constants(dir: &Path) -> PathBuf {
    let out = dir.join("fit");
    ok(&[
        "fit",
        "configs/cmv-joint.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_pngs(
        &out,
        &[
            "fit.png",
            "stress_rupture.png",
            "norton.png",
            "larson_miller.png",
        ],
    );
    out.join("constants.csv")
}

#[test]
fn predict_at_tested_conditions_equals_simulate_and_keeps_the_contract() {
    let tmp = TempDir::new().unwrap();
    let constants = joint_constants(tmp.path());
    let text = std::fs::read_to_string(&constants).unwrap();
    assert!(
        text.lines().last().unwrap().starts_with("T_ref,575,"),
        "{text}"
    );
    let c = constants.to_str().unwrap();
    let sim = tmp.path().join("sim");
    ok(&[
        "simulate",
        "configs/cmv-joint.toml",
        "--constants",
        c,
        "--out",
        sim.to_str().unwrap(),
    ]);
    // Every tested condition, in an order of our own (not the data's).
    let at = "590:120,560:85,590:100,560:110,590:110,560:100";
    let pred = tmp.path().join("pred");
    let stdout = ok(&[
        "predict",
        "configs/cmv-joint.toml",
        "--constants",
        c,
        "--at",
        at,
        "--out",
        pred.to_str().unwrap(),
    ]);
    assert!(stdout.contains("Larson–Miller baseline: C = "), "{stdout}");
    let p = csv(&pred.join("predictions.csv"));
    // The contract's five columns, then where each condition lies, how its simulation ended
    // and which constants the numbers come from.
    assert_eq!(
        p[0],
        [
            "temperature_C",
            "stress_MPa",
            "rupture_time_h",
            "rupture_strain_pct",
            "min_rate_pct_per_h",
            "extrapolation",
            "outcome",
            "constants"
        ]
    );
    let asked: Vec<(String, String)> = at
        .split(',')
        .map(|s| {
            let (t, s) = s.split_once(':').unwrap();
            (t.to_string(), s.to_string())
        })
        .collect();
    assert_eq!(p.len(), asked.len() + 1);
    let s = csv(&sim.join("ruptures.csv"));
    for (row, (t, sig)) in p[1..].iter().zip(&asked) {
        assert_eq!((&row[0], &row[1]), (t, sig), "rows in the order asked");
        let same = s
            .iter()
            .find(|r| &r[0] == t && &r[1] == sig)
            .expect("simulate has the tested condition");
        // Rupture time, rupture strain and minimum rate: the same numbers, to the last digit.
        assert_eq!(&row[2..5], &same[2..5], "{t} °C {sig} MPa");
    }
    // The predicted curves are simulate's at the times both hold.
    let pc = csv(&pred.join("curves.csv"));
    let sc = csv(&sim.join("curves.csv"));
    assert_eq!(pc[0], sc[0]);
    assert_eq!(
        pc[0],
        [
            "temperature_C",
            "stress_MPa",
            "time_h",
            "strain_pct",
            "H",
            "Phi",
            "omega"
        ]
    );
    let index: std::collections::HashMap<(&str, &str, &str), &Vec<String>> = sc[1..]
        .iter()
        .map(|r| ((r[0].as_str(), r[1].as_str(), r[2].as_str()), r))
        .collect();
    let mut common = 0;
    for r in &pc[1..] {
        if let Some(o) = index.get(&(r[0].as_str(), r[1].as_str(), r[2].as_str())) {
            assert_eq!(r, *o);
            common += 1;
        }
    }
    assert!(common >= 6 * 150, "only {common} common rows");
    for f in ["larson_miller.csv", "summary.json"] {
        assert!(pred.join(f).exists(), "{f}");
    }
    assert_pngs(
        &pred,
        &[
            "curves.png",
            "stress_rupture.png",
            "norton.png",
            "larson_miller.png",
        ],
    );

    // Untested conditions: a row each, the Larson–Miller prediction beside.
    let pred2 = tmp.path().join("pred2");
    ok(&[
        "predict",
        "configs/cmv-joint.toml",
        "--constants",
        c,
        "--at",
        "575:100,560:70",
        "--out",
        pred2.to_str().unwrap(),
    ]);
    let p = csv(&pred2.join("predictions.csv"));
    let l = csv(&pred2.join("larson_miller.csv"));
    assert_eq!(p.len(), 3);
    assert_eq!(
        l[0][..4],
        [
            "temperature_C",
            "stress_MPa",
            "rupture_time_h",
            "larson_miller_parameter_K"
        ]
    );
    // The other baselines after the contract columns, each with its extrapolation mark.
    assert_eq!(
        l[0][4..],
        [
            "lmp_extrapolation",
            "osd_rupture_time_h",
            "osd_extrapolation",
            "mh_rupture_time_h",
            "mh_extrapolation",
            "wilshire_rupture_time_h",
            "wilshire_extrapolation"
        ]
    );
    for (a, b) in p[1..].iter().zip(&l[1..]) {
        assert_eq!(a[..2], b[..2]);
        let (m, lm): (f64, f64) = (a[2].parse().unwrap(), b[2].parse().unwrap());
        assert!(m > 0.0 && lm > 0.0);
        let osd: f64 = b[5].parse().unwrap();
        assert!(osd > 0.0);
        // No tensile strengths in cmv-joint.toml: no Wilshire, the cells empty.
        assert_eq!(b[9..], ["", ""]);
    }
    // 575 °C, 100 MPa lies inside the tested 560–590 °C and 85–120 MPa; 70 MPa does not: the
    // file says so for each baseline.
    assert_eq!([&l[1][4], &l[1][6]], ["none", "none"]);
    assert_eq!([&l[2][4], &l[2][6]], ["stress", "stress"]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pred2.join("summary.json")).unwrap())
            .unwrap();
    let b = &summary["predictions"][1]["baselines"];
    assert_eq!(b["osd"]["extrapolation"], "stress");
    assert_eq!(
        b["osd"]["rupture_time_h"].as_f64(),
        Some(l[2][5].parse().unwrap())
    );
    assert!(b["wilshire"]["rupture_time_h"].is_null());
    let w = &summary["baselines"][3];
    assert_eq!(w["kind"], "wilshire");
    assert!(
        w["error"].as_str().unwrap().contains("no tensile strength"),
        "{w}"
    );

    // Constants about another reference temperature are refused, naming T_ref.
    let other = tmp.path().join("other.csv");
    std::fs::write(&other, text.replace("T_ref,575,", "T_ref,560,")).unwrap();
    let o = creepfit(&[
        "predict",
        "configs/cmv-joint.toml",
        "--constants",
        other.to_str().unwrap(),
        "--at",
        "575:100",
        "--out",
        tmp.path().join("x").to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        e.contains("T_ref") && e.contains("560") && e.contains("575"),
        "{e}"
    );
    assert_eq!(e.trim().lines().count(), 1, "{e}");
}

/// `predict --intervals` on the 560 °C data (constants near its maximum-likelihood
/// optimum): the contract's five columns, then the 95 % prediction interval of a new test and
/// the 95 % confidence interval of the model's prediction for each quantity; every interval
/// ordered around the prediction, the new-test interval containing the model's, the rupture
/// time at an untested 70 MPa longer and its interval above the 85 MPa one's lower end; the
/// printout says which interval is which. Without the flag the columns stay five.
#[test]
fn predict_intervals_add_their_columns() {
    let tmp = TempDir::new().unwrap();
    let c = tmp.path().join("c.csv");
    std::fs::write(
        &c,
        "name,value\nA,1.023e-10\nB,0.11506\nHstar,0.4\nh,12261.7\nKc,2.7764e-5\nC,5.7764\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let args = [
        "predict",
        "configs/560C.toml",
        "--constants",
        c.to_str().unwrap(),
        "--at",
        "560:70,560:85",
        "--out",
        out.to_str().unwrap(),
    ];
    let plain = csv(&{
        ok(&args);
        out.join("predictions.csv")
    });
    assert_eq!(plain[0][5..], ["extrapolation", "outcome", "constants"]);
    let mut with = args.to_vec();
    with.push("--intervals");
    let stdout = ok(&with);
    assert!(
        stdout.contains("NEW TEST") && stdout.contains("confidence interval"),
        "{stdout}"
    );
    let rows = csv(&out.join("predictions.csv"));
    let mut want: Vec<&str> = plain[0][..5].iter().map(String::as_str).collect();
    want.extend([
        "rupture_time_lo95_h",
        "rupture_time_hi95_h",
        "rupture_strain_lo95_pct",
        "rupture_strain_hi95_pct",
        "min_rate_lo95_pct_per_h",
        "min_rate_hi95_pct_per_h",
        "rupture_time_conf_lo95_h",
        "rupture_time_conf_hi95_h",
        "rupture_strain_conf_lo95_pct",
        "rupture_strain_conf_hi95_pct",
        "min_rate_conf_lo95_pct_per_h",
        "min_rate_conf_hi95_pct_per_h",
        "extrapolation",
        "outcome",
        "constants",
        "given_rupture_time_h",
        "given_rupture_strain_pct",
        "given_min_rate_pct_per_h",
        "given_outcome",
    ]);
    assert_eq!(rows[0], want);
    assert_eq!(rows.len(), 3);
    let f = |r: &[String], k: usize| -> f64 { r[k].parse().unwrap() };
    for r in &rows[1..] {
        // (value column, new-test lo/hi, model lo/hi)
        for (v, p, m) in [(2, 5, 11), (3, 7, 13), (4, 9, 15)] {
            let (val, plo, phi, mlo, mhi) = (f(r, v), f(r, p), f(r, p + 1), f(r, m), f(r, m + 1));
            assert!(plo <= mlo && mlo < mhi && mhi <= phi, "{r:?}");
            // The interval's centre is the maximum-likelihood fit from the given constants,
            // which are rounded values of the optimum: the prediction lies inside.
            assert!(mlo < val && val < mhi, "{r:?}");
        }
    }
    assert!(f(&rows[1], 2) > f(&rows[2], 2) && f(&rows[1], 11) > f(&rows[2], 11));
    // Without specimen effects the refit's likelihood is that of identical specimens: no
    // effects named, no note.
    let summary = |dir: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
    };
    assert_eq!(
        summary(&out)["refit"]["specimen_effects"],
        serde_json::json!([])
    );
    assert!(!stdout.contains("hierarchical likelihood"), "{stdout}");
    // With specimen effects asked for, the refit and every interval's fit are hierarchical
    // (the rate factors integrated out): the printout and the summary say so, and the refit's
    // −2 ln L is the hierarchical one, never above that of identical specimens on the same
    // data (the model without effects is its limit of zero scatter).
    let cfg = tmp.path().join("sp.toml");
    std::fs::write(
        &cfg,
        std::fs::read_to_string("configs/560C.toml")
            .unwrap()
            .replace("../data/", &format!("{}/data/", root().display()))
            // The likelihood's own scatter estimate: beyond the stress trend (the default
            // since 2026-12-04) three specimens at three stresses leave one degree of
            // freedom, the scatter goes to zero and the refit is that of identical specimens.
            .replace(
                "[objective]",
                "[objective]\nspecimen_effects = [\"rate\"]\nspecimen_scatter = \"likelihood\"",
            ),
    )
    .unwrap();
    let out_sp = tmp.path().join("out_sp");
    let stdout = ok(&[
        "predict",
        cfg.to_str().unwrap(),
        "--constants",
        c.to_str().unwrap(),
        "--at",
        "560:70",
        "--intervals",
        "--out",
        out_sp.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("integrates the specimens' rate factors out"),
        "{stdout}"
    );
    assert_eq!(
        summary(&out_sp)["refit"]["specimen_effects"],
        serde_json::json!(["rate"])
    );
    // The thresholds' bootstrap calibration is in the summary: its replicates
    // (`[profile] calibrate`, 20 by default) and the factor on the χ² thresholds (≥ 1).
    for dir in [&out, &out_sp] {
        let cal = &summary(dir)["interval_calibration"];
        assert_eq!(cal["replicates"], 20, "{cal}");
        let f = cal["prediction_factor"].as_f64().unwrap();
        assert!(f >= 1.0 && f.is_finite(), "{cal}");
        assert!(!cal["per_quantity"].as_array().unwrap().is_empty(), "{cal}");
    }
    let (plain, hier) = (
        summary(&out)["refit"]["neg2ll"].as_f64().unwrap(),
        summary(&out_sp)["refit"]["neg2ll"].as_f64().unwrap(),
    );
    assert!(
        hier <= plain + 1e-6,
        "hierarchical {hier} vs identical specimens {plain}"
    );
    // band.csv: the 95 % confidence band of each predicted curve at 9 times before rupture,
    // in the order asked, each band around its strain; band.png drawn. From the rupture
    // time's lower 95 % confidence bound on, the upper end is rupture (cell empty, marked);
    // before it, a strain above the centre.
    let band = csv(&out.join("band.csv"));
    assert_eq!(
        band[0],
        [
            "temperature_C",
            "stress_MPa",
            "time_h",
            "strain_pct",
            "strain_conf_lo95_pct",
            "strain_conf_hi95_pct",
            "strain_conf_hi95_ruptured",
            "strain_conf_lo95_open"
        ]
    );
    assert_eq!(band.len(), 1 + 2 * 9);
    for (k, r) in band[1..].iter().enumerate() {
        assert_eq!(r[1], if k < 9 { "70" } else { "85" });
        let (t, e, lo) = (f(r, 2), f(r, 3), f(r, 4));
        let (t_r, t_lo95) = (f(&rows[1 + k / 9], 2), f(&rows[1 + k / 9], 11));
        assert!(t > 0.0 && t < t_r * 1.05, "{r:?}");
        assert!(lo <= e && lo > 0.0, "{r:?}");
        assert!(matches!(r[7].as_str(), "true" | "false"), "{r:?}");
        if t >= t_lo95 {
            assert_eq!((r[5].as_str(), r[6].as_str()), ("", "true"), "{r:?}");
        } else {
            let hi = f(r, 5);
            assert!(e <= hi && lo < hi && r[6] == "false", "{r:?}");
        }
    }
    // The last point is the predicted rupture, after the lower bound of its own interval.
    assert_eq!(band[9][6], "true");
    assert_eq!(band[18][6], "true");
    assert!(out.join("band.png").exists());
}

#[test]
fn bad_conditions_are_one_line_errors() {
    let tmp = TempDir::new().unwrap();
    let c = tmp.path().join("c.csv");
    std::fs::write(&c, "name,value\n").unwrap();
    for (at, want) in [
        ("575-100", "expected T:stress"),
        ("575:abc", "cannot parse the stress"),
        ("575:-3", "stress must be positive"),
        ("-300:100", "above absolute zero"),
    ] {
        let o = creepfit(&[
            "predict",
            "configs/cmv-joint.toml",
            "--constants",
            c.to_str().unwrap(),
            "--at",
            at,
        ]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(e.contains("--at") && e.contains(want), "{at}: {e}");
        assert_eq!(e.trim().lines().count(), 1, "{e}");
    }
}

#[test]
fn predict_tests_scores_a_file_of_measured_lives() {
    let tmp = TempDir::new().unwrap();
    let constants = joint_constants(tmp.path());
    let c = constants.to_str().unwrap();
    // Another campaign's lives: a replicate pair at a temperature between the tested ones,
    // one test at a tested temperature, with a specimen label and a column of its own order.
    let tests = tmp.path().join("campaign.csv");
    std::fs::write(
        &tests,
        "stress_MPa,temperature_C,rupture_time_h,specimen\n\
         100,575,20000,X-1\n\
         110,590,5000,X-2\n\
         100,575,31000,X-3\n",
    )
    .unwrap();
    // `predict configs/cmv-joint.toml --tests FILE --out DIR` at the fit's constants.
    let predict_tests = |out: &Path| {
        creepfit(&[
            "predict",
            "configs/cmv-joint.toml",
            "--constants",
            c,
            "--tests",
            tests.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let pred = tmp.path().join("pred");
    let o = predict_tests(&pred);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    // One prediction per distinct condition, in file order (the configuration's `at` replaced).
    let p = csv(&pred.join("predictions.csv"));
    assert_eq!(p.len(), 3, "{p:?}");
    assert_eq!((p[1][0].as_str(), p[1][1].as_str()), ("575", "100"));
    assert_eq!((p[2][0].as_str(), p[2][1].as_str()), ("590", "110"));
    let t = csv(&pred.join("tests.csv"));
    let col = |name: &str| {
        t[0].iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name}: {:?}", t[0]))
    };
    assert_eq!(t.len(), 4, "one row per test");
    let f = |r: &[String], name: &str| r[col(name)].parse::<f64>().unwrap();
    let measured = [20000.0, 5000.0, 31000.0];
    for (k, r) in t[1..].iter().enumerate() {
        assert_eq!(f(r, "rupture_time_h"), measured[k]);
        assert_eq!(r[col("line")], (k + 2).to_string());
        assert_eq!(r[col("specimen")], format!("X-{}", k + 1));
        // creepfit's life is predictions.csv's at the test's condition, to the digit.
        let row = p[1..]
            .iter()
            .find(|q| q[0] == r[col("temperature_C")] && q[1] == r[col("stress_MPa")])
            .unwrap();
        assert_eq!(r[col("model_rupture_time_h")], row[2]);
        let e = (f(r, "model_rupture_time_h") / measured[k]).log10();
        assert!((f(r, "model_log10_err") - e).abs() < 1e-9, "{r:?}");
        let e = (f(r, "lmp_rupture_time_h") / measured[k]).log10();
        assert!((f(r, "lmp_log10_err") - e).abs() < 1e-9, "{r:?}");
    }
    assert_eq!(t[1][col("extrapolation")], "none");
    // Which simulation and which constants each of creepfit's lives comes from.
    assert!(t[1..]
        .iter()
        .all(|r| r[col("outcome")] == "ruptured" && r[col("constants")] == "given"));
    // The summary's means are those of the file's errors; the one to beat is the baseline
    // with the smallest among those that predicted every test.
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pred.join("summary.json")).unwrap()).unwrap();
    let mean = |name: &str| t[1..].iter().map(|r| f(r, name).abs()).sum::<f64>() / 3.0;
    let j = &s["tests"];
    assert_eq!(j["tests"], 3);
    assert_eq!(j["conditions"], 2);
    let m = j["model_mean_abs_log10_err"].as_f64().unwrap();
    assert!((m - mean("model_log10_err")).abs() < 1e-9, "{j}");
    // The level the lives share: the signed mean.
    let level = t[1..].iter().map(|r| f(r, "model_log10_err")).sum::<f64>() / 3.0;
    assert!(
        (j["model_mean_log10_err"].as_f64().unwrap() - level).abs() < 1e-9,
        "{j}"
    );
    assert!(
        stdout.contains(&format!("creepfit {level:+.3}")),
        "{stdout}"
    );
    let mut best: Option<(String, f64)> = None;
    for b in j["baselines"].as_array().unwrap() {
        let Some(v) = b["mean_abs_log10_err"].as_f64() else {
            continue;
        };
        let key = match b["kind"].as_str().unwrap() {
            "larson_miller" => "lmp".to_string(),
            "orr_sherby_dorn" => "osd".to_string(),
            "manson_haferd" => "mh".to_string(),
            k => k.to_string(),
        };
        assert!((v - mean(&format!("{key}_log10_err"))).abs() < 1e-9, "{b}");
        if b["tests_predicted"] == 3 && best.as_ref().is_none_or(|(_, w)| v < *w) {
            best = Some((b["name"].as_str().unwrap().to_string(), v));
        }
    }
    let (name, v) = best.expect("a baseline predicted every test");
    assert_eq!(j["one_to_beat"]["name"], name.as_str(), "{j}");
    let verdict = if m < v { "beats" } else { "does_not_beat" };
    assert_eq!(j["creepfit_vs_one_to_beat"], verdict);
    assert!(
        stdout.contains("over the 3 tests of")
            && stdout.contains(&format!("the one to beat: {name}")),
        "{stdout}"
    );
    // A test beyond the limits of a prediction (640 °C: 50 °C above the tested 590 °C, the
    // margin 25 °C) is predicted, marked and counted, not refused: the others are scored.
    std::fs::write(
        &tests,
        "stress_MPa,temperature_C,rupture_time_h,specimen\n100,575,20000,X-1\n100,640,50,X-9\n",
    )
    .unwrap();
    let beyond = tmp.path().join("beyond");
    let o = predict_tests(&beyond);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("640 °C, 100 MPa: beyond the limits of a prediction")
            && e.contains("more than 25 °C outside"),
        "{e}"
    );
    let t = csv(&beyond.join("tests.csv"));
    let col = |name: &str| t[0].iter().position(|h| h == name).unwrap();
    assert_eq!(t[1][col("extrapolation")], "none");
    assert_eq!(t[2][col("extrapolation")], "beyond_limits");
    assert!(!t[2][col("model_rupture_time_h")].is_empty(), "{:?}", t[2]);
    let j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(beyond.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(j["tests"]["beyond_limits"], 1, "{}", j["tests"]);
    assert_eq!(j["tests"]["tests"], 2);
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("1 of the 2 tests lie beyond the limits"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // A bad cell: one line naming file and line.
    std::fs::write(
        &tests,
        "stress_MPa,temperature_C,rupture_time_h,specimen\n100,575,20000,X-1\n100,575,abc,X-9\n",
    )
    .unwrap();
    let o = predict_tests(&tmp.path().join("bad"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("campaign.csv") && e.contains(":3:"), "{e}");
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    // --tests replaces --at: both at once is refused.
    let o = creepfit(&[
        "predict",
        "configs/cmv-joint.toml",
        "--constants",
        c,
        "--tests",
        tests.to_str().unwrap(),
        "--at",
        "575:100",
    ]);
    assert!(!o.status.success());
}

/// `[predict] tests = "FILE"` (relative to the configuration) scores the file as `--tests`
/// does, to the byte; `--at` replaces it; `at` and `tests` both in the file are refused
/// naming the field; a missing file is a one-line error naming it.
#[test]
fn predict_tests_from_the_configuration() {
    let tmp = TempDir::new().unwrap();
    let constants = joint_constants(tmp.path());
    let c = constants.to_str().unwrap();
    let dir = tmp.path().join("cfg");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(
        dir.join("campaign.csv"),
        "temperature_C,stress_MPa,rupture_time_h,specimen\n575,100,20000,X-1\n590,110,5000,X-2\n",
    )
    .unwrap();
    let text = std::fs::read_to_string(root().join("configs/cmv-joint.toml"))
        .unwrap()
        .replace(
            "../data/",
            &format!("{}/", root().join("data").to_str().unwrap()),
        );
    assert!(text.contains("at = [\"575:100\", \"560:70\"]"));
    let write = |name: &str, predict: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text.replace("at = [\"575:100\", \"560:70\"]", predict)).unwrap();
        p
    };
    let keyed = write("keyed.toml", "tests = \"campaign.csv\"");
    let run = |cfg: &Path, out: &Path, extra: &[&str]| {
        let mut args = vec![
            "predict",
            cfg.to_str().unwrap(),
            "--constants",
            c,
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        creepfit(&args)
    };
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    let o = run(&keyed, &a, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let file = dir.join("campaign.csv");
    let o = run(&keyed, &b, &["--tests", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["tests.csv", "predictions.csv", "summary.json"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs");
    }
    assert_eq!(csv(&a.join("tests.csv")).len(), 3);
    // --at replaces the file's tests: predictions at 575:90 only, nothing scored.
    let at = tmp.path().join("at");
    let o = run(&keyed, &at, &["--at", "575:90"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(csv(&at.join("predictions.csv")).len(), 2);
    assert!(!at.join("tests.csv").exists());
    // Both keys: refused, naming the field.
    let both = write("both.toml", "at = [\"575:100\"]\ntests = \"campaign.csv\"");
    let o = run(&both, &tmp.path().join("both"), &[]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("predict.tests") && e.contains("not both"), "{e}");
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    // A missing file: one line naming it.
    let missing = write("missing.toml", "tests = \"nowhere.csv\"");
    let o = run(&missing, &tmp.path().join("missing"), &[]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(e.contains("nowhere.csv"), "{e}");
    assert_eq!(e.trim().lines().count(), 1, "{e}");
}

/// The model, constants and integrator [`law_data`] makes its tests with: KHD with Arrhenius A
/// and Kc about 575 °C.
fn law_truth() -> (Box<dyn creepfit::model::Model>, [f64; 8], OdeOptions) {
    use LawKind::*;
    let model = with_laws(
        build("khd", &[]).unwrap(),
        &[Arrhenius, Constant, Constant, Constant, Arrhenius, Constant],
        575.0,
    );
    let ode = OdeOptions {
        rtol: 1e-12,
        atol: 1e-15,
        ..OdeOptions::default()
    };
    (
        model,
        [1.2e-9, 0.12, 0.55, 6e4, 1.5e-5, 5.0, 350.0, 250.0],
        ode,
    )
}

/// Curves and rupture times at `tests` (°C, MPa, specimen label; no `specimen` column when
/// every label is empty) made by the KHD model with Arrhenius A and Kc (30 points to
/// rupture), written into `dir` with the hold-out configuration h.toml, whose path it returns.
fn law_data(dir: &Path, tests: &[(f64, f64, &str)]) -> PathBuf {
    let (model, truth, ode) = law_truth();
    let labelled = tests.iter().any(|t| !t.2.is_empty());
    let col = |label: &str| {
        if labelled {
            format!(",{label}")
        } else {
            String::new()
        }
    };
    let mut curves = format!(
        "temperature_C,stress_MPa,time_h,strain_pct{}\n",
        col("specimen")
    );
    let mut ruptures = format!(
        "temperature_C,stress_MPa,rupture_time_h{}\n",
        col("specimen")
    );
    for &(t, s, label) in tests {
        let load = Load::new(s, t, 1.0 / 3.0);
        let r = model.simulate(&truth, &load, &[], &mut [], &ode);
        let times: Vec<f64> = (0..30).map(|k| r.t_end * k as f64 / 30.0).collect();
        let mut e = vec![0.0; times.len()];
        model.simulate(&truth, &load, &times, &mut e, &ode);
        assert!(estimate_min_rate(&times, &e, r.t_end) > 0.0);
        for (ti, ei) in times.iter().zip(&e) {
            curves += &format!("{t},{s},{ti},{}{}\n", 100.0 * ei, col(label));
        }
        ruptures += &format!("{t},{s},{}{}\n", r.t_end, col(label));
    }
    std::fs::write(dir.join("c.csv"), curves).unwrap();
    std::fs::write(dir.join("r.csv"), ruptures).unwrap();
    let cfg = dir.join("h.toml");
    std::fs::write(
        &cfg,
        r#"name = "h"
curves = "c.csv"
ruptures = "r.csv"
T_ref = 575
[constants]
A     = { lb = 1e-11, ub = 1e-7, scale = "log", start = 1.1e-9, law = "arrhenius", Q = { lb = 100, ub = 600, start = 330 } }
B     = { lb = 0.05,  ub = 0.3, start = 0.125 }
Hstar = { lb = 0.2,   ub = 0.9, start = 0.56 }
h     = { lb = 1e3,   ub = 1e6, scale = "log", start = 5.5e4 }
Kc    = { lb = 1e-7,  ub = 1e-3, scale = "log", start = 1.6e-5, law = "arrhenius", Q = { lb = 100, ub = 600, start = 270 } }
C     = { lb = 1.5,   ub = 10, start = 4.9 }
[objective]
w_grid = [1.0]
lifetime_term = "both"
[sweep]
starts = 2
[predict]
tensile_strength = ["560:420", "575:400", "590:380"]
"#,
    )
    .unwrap();
    cfg
}

/// Tests at 560, 575 and 590 °C (3 + 2 + 3) for [`law_data`].
const THREE_TEMPERATURES: [(f64, f64, &str); 8] = [
    (560.0, 85.0, ""),
    (560.0, 100.0, ""),
    (560.0, 110.0, ""),
    (575.0, 80.0, ""),
    (575.0, 95.0, ""),
    (590.0, 75.0, ""),
    (590.0, 90.0, ""),
    (590.0, 100.0, ""),
];

/// Without a configured `T_ref` the hold-out's training fit resolves it from the training
/// curves alone, as a run on them would: the tests left out do not set the laws' reference
/// temperature (nor, through it, the box and the starts). Leaving 590 °C out of 3 + 2 + 3
/// curves at 560, 575, 590 °C: (3·560 + 2·575)/5 = 566 °C, where the full data's mean is 575.
#[test]
fn holdout_resolves_the_reference_temperature_from_its_training_data() {
    let tmp = TempDir::new().unwrap();
    let cfg = law_data(tmp.path(), &THREE_TEMPERATURES);
    let text = std::fs::read_to_string(&cfg).unwrap();
    std::fs::write(&cfg, text.replace("T_ref = 575\n", "")).unwrap();
    let out = tmp.path().join("ho");
    ok(&[
        "holdout",
        cfg.to_str().unwrap(),
        "--temperature",
        "590",
        "--out",
        out.to_str().unwrap(),
    ]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let t_ref = s["T_ref_C"].as_f64().unwrap();
    assert!((t_ref - 566.0).abs() < 1e-9, "{t_ref}");
    // constants.csv states the same reference temperature.
    let c = csv(&out.join("constants.csv"));
    let row = c.iter().find(|r| r[0] == "T_ref").unwrap();
    assert!(
        (row[1].parse::<f64>().unwrap() - 566.0).abs() < 1e-9,
        "{row:?}"
    );
    // A fit of all the data resolves the mean of all of them (575 °C).
    let fit_out = tmp.path().join("fit");
    ok(&[
        "fit",
        cfg.to_str().unwrap(),
        "--out",
        fit_out.to_str().unwrap(),
    ]);
    let c = csv(&fit_out.join("constants.csv"));
    let row = c.iter().find(|r| r[0] == "T_ref").unwrap();
    assert!(
        (row[1].parse::<f64>().unwrap() - 575.0).abs() < 1e-9,
        "{row:?}"
    );
}

/// Curves at three temperatures made by the model with Arrhenius A and Kc: leaving 575 °C
/// out, the fit on 560 and 590 °C predicts its rupture times (to the integration accuracy;
/// the constants are recovered) and the files say so.
#[test]
fn holdout_predicts_a_temperature_left_out() {
    let tmp = TempDir::new().unwrap();
    let cfg = law_data(tmp.path(), &THREE_TEMPERATURES);
    // Leave 575 °C out into `out` (with `extra` options): stdout and summary.json.
    let holdout_575 = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec!["holdout", cfg.to_str().unwrap(), "--temperature", "575"];
        args.extend(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        let stdout = ok(&args);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        (stdout, summary)
    };
    let out = tmp.path().join("ho");
    let (stdout, s) = holdout_575(&out, &[]);
    assert!(stdout.contains("mean |log10 error|"), "{stdout}");
    let h = csv(&out.join("holdout.csv"));
    assert_eq!(
        h[0],
        [
            "temperature_C",
            "stress_MPa",
            "rupture_time_h",
            "model_rupture_time_h",
            "lmp_rupture_time_h",
            "model_log10_err",
            "lmp_log10_err",
            "curve_rms_pct",
            "osd_rupture_time_h",
            "osd_log10_err",
            "mh_rupture_time_h",
            "mh_log10_err",
            "wilshire_rupture_time_h",
            "wilshire_log10_err",
            "predicted_life_pct",
            "curve_outcome",
            "curve_points"
        ]
    );
    assert_eq!(h.len(), 3);
    // The baselines as fitted to the training rupture times alone (560 and 590 °C), to the
    // last digit; Wilshire with the configured tensile strengths.
    let training: Vec<(f64, f64, f64)> = std::fs::read_to_string(tmp.path().join("r.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            (v[0], v[1], v[2])
        })
        .filter(|t| t.0 != 575.0)
        .collect();
    let tensile = [
        TensileStrength::parse("560:420").unwrap(),
        TensileStrength::parse("575:400").unwrap(),
        TensileStrength::parse("590:380").unwrap(),
    ];
    let bs = BaselineSettings {
        degree: 2,
        tensile: &tensile,
    };
    let osd = OrrSherbyDorn::fit(&training, &bs).unwrap();
    let wil = Wilshire::fit(&training, &bs).unwrap();
    let mh = MansonHaferd::fit(&training, &bs);
    for r in &h[1..] {
        let v = |i: usize| -> f64 { r[i].parse().unwrap() };
        let err = v(5);
        assert!(err.abs() < 1e-3, "held-out log10 error {err}");
        let (t, sig, meas) = (v(0), v(1), v(2));
        assert_eq!(v(8), osd.predict(t, sig));
        assert_eq!(v(9), (osd.predict(t, sig) / meas).log10());
        assert_eq!(v(12), wil.predict(t, sig));
        match &mh {
            Ok(m) => assert_eq!(v(10), m.predict(t, sig)),
            Err(_) => assert_eq!(r[10], ""),
        }
        // The life as % of the measured one, and the curve compared up to its rupture.
        assert!((v(14) - 100.0 * v(3) / meas).abs() < 1e-9 * v(14));
        // Against the curve's last point (law_data's: 29/30 of the life), not the life:
        // a prediction as exact as this one falls on either side of the life by rounding.
        let outcome = if v(3) >= meas * 29.0 / 30.0 {
            "complete"
        } else {
            "ruptured_early"
        };
        assert_eq!(r[15], outcome, "{r:?}");
        assert!(r[16].parse::<usize>().unwrap() >= 2);
    }
    assert_eq!(s["tests"], 2);
    // The configuration's T_ref (given) is the training fit's.
    assert_eq!(s["T_ref_C"], 575.0);
    assert!(s["model_mean_abs_log10_err"].as_f64().unwrap() < 1e-3);
    assert!(s["lmp_mean_abs_log10_err"].as_f64().is_some());
    // Every baseline's mean beside creepfit's, the best named, the verdict consistent.
    let b = s["baselines"].as_array().unwrap();
    assert_eq!(
        b.iter()
            .map(|x| x["kind"].as_str().unwrap())
            .collect::<Vec<_>>(),
        [
            "larson_miller",
            "orr_sherby_dorn",
            "manson_haferd",
            "wilshire"
        ]
    );
    assert_eq!(b[0]["mean_abs_log10_err"], s["lmp_mean_abs_log10_err"]);
    assert_eq!(b[1]["q_kj_per_mol"].as_f64(), Some(osd.q_kj_per_mol));
    let best = b
        .iter()
        .filter(|x| x["tests_predicted"] == 2)
        .min_by(|x, y| {
            let f = |z: &serde_json::Value| z["mean_abs_log10_err"].as_f64().unwrap();
            f(x).total_cmp(&f(y))
        })
        .unwrap();
    assert_eq!(s["one_to_beat"]["kind"], best["kind"]);
    let beats = s["model_mean_abs_log10_err"].as_f64().unwrap()
        < best["mean_abs_log10_err"].as_f64().unwrap();
    assert_eq!(
        s["creepfit_vs_one_to_beat"],
        if beats { "beats" } else { "does_not_beat" }
    );
    assert!(stdout.contains(&format!(
        "the one to beat: {}",
        best["name"].as_str().unwrap()
    )));
    let co = &s["curve_outcomes"];
    assert_eq!(
        ["complete", "ruptured_early", "no_rupture", "failed"]
            .iter()
            .map(|k| co[k].as_u64().unwrap())
            .sum::<u64>(),
        2
    );
    assert_eq!(s["temperature_extrapolation"], false);
    assert!(out.join("constants.csv").exists());
    assert_pngs(
        &out,
        &[
            "curves.png",
            "parity.png",
            "stress_rupture.png",
            "norton.png",
            "larson_miller.png",
        ],
    );
    // The folder's manifest: this holdout's files, complete.
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(
        (&m["command"], &m["complete"]),
        (&serde_json::json!("holdout"), &serde_json::json!(true))
    );
    for f in [
        "holdout.csv",
        "constants.csv",
        "summary.json",
        "curves.png",
        "parity.png",
    ] {
        assert!(
            m["files"].as_array().unwrap().iter().any(|x| x == f),
            "{f}: {m}"
        );
    }
    // With --intervals: the 95 % intervals of each held-out life from the training data, the
    // model's inside the new test's, and the count of measured lives inside.
    let out_i = tmp.path().join("hoi");
    let (stdout, s) = holdout_575(&out_i, &["--intervals"]);
    assert!(
        stdout.contains("inside the 95 % prediction interval of a new test: 2 of 2"),
        "{stdout}"
    );
    let hi = csv(&out_i.join("holdout.csv"));
    assert_eq!(
        hi[0][8..13],
        [
            "rupture_time_lo95_h",
            "rupture_time_hi95_h",
            "rupture_time_conf_lo95_h",
            "rupture_time_conf_hi95_h",
            "ml_rupture_time_h"
        ]
    );
    for r in &hi[1..] {
        let v: Vec<f64> = r[8..13].iter().map(|x| x.parse().unwrap()).collect();
        let measured: f64 = r[2].parse().unwrap();
        assert!(
            v[0] <= v[2] && v[2] <= v[4] && v[4] <= v[3] && v[3] <= v[1],
            "{r:?}"
        );
        assert!(v[0] <= measured && measured <= v[1], "{r:?}");
        // The new test's interval holds at least the 1 % lifetime-scatter floor each side.
        assert!(
            v[1] / v[0] >= (2.0 * 1.96 * 0.01f64).exp() * (1.0 - 1e-6),
            "{r:?}"
        );
    }
    // The intervals' refit of the training constants, said in the printout and the summary.
    assert!(
        stdout.contains("centred on the maximum-likelihood refit"),
        "{stdout}"
    );
    let r = &s["intervals_refit"];
    assert!(r["delta_neg2ll"].as_f64().is_some(), "{r}");
    assert_eq!(r["constants"].as_array().unwrap().len(), 8);
    assert_eq!(s["inside_pred95"]["inside"], 2);
    assert_eq!(s["inside_pred95"]["tests"], 2);
    // A temperature left out: the interval's scope needs no word.
    assert_eq!(s.get("interval_scope"), Some(&serde_json::Value::Null));
    // Leaving out a temperature that leaves one to fit is refused.
    let o = creepfit(&[
        "holdout",
        "configs/cmv-joint.toml",
        "--temperature",
        "590",
        "--out",
        tmp.path().join("x").to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("two or more"), "{e}");
}

/// Two campaigns of the same material (the model's curves, specimens P-… and Q-…): leaving
/// campaign Q out fits on P's tests alone and predicts exactly Q's, at every temperature
/// they were run at (575 °C only Q tested: through the laws), to the integration accuracy.
#[test]
fn holdout_leaves_a_campaign_out() {
    let tmp = TempDir::new().unwrap();
    let cfg = law_data(
        tmp.path(),
        &[
            (560.0, 85.0, "P-1"),
            (560.0, 110.0, "P-2"),
            (560.0, 100.0, "Q-a"),
            (575.0, 95.0, "Q-b"),
            (590.0, 75.0, "P-1"),
            (590.0, 100.0, "P-2"),
            (590.0, 90.0, "Q-a"),
        ],
    );
    // `holdout CFG --campaign Q --out DIR` with `extra` arguments: (stdout, DIR).
    let hold_q = |dir: &str, extra: &[&str]| {
        let out = tmp.path().join(dir);
        let mut args = vec!["holdout", cfg.to_str().unwrap(), "--campaign", "Q"];
        args.extend_from_slice(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        (ok(&args), out)
    };
    let (stdout, out) = hold_q("hq", &[]);
    assert!(stdout.contains("held out campaign Q: 3 tests"), "{stdout}");
    let h = csv(&out.join("holdout.csv"));
    assert_eq!(h[0][..3], ["temperature_C", "stress_MPa", "rupture_time_h"]);
    let specimen = h[0].iter().position(|c| c == "specimen").unwrap();
    let held: Vec<(String, String, String)> = h[1..]
        .iter()
        .map(|r| (r[0].clone(), r[1].clone(), r[specimen].clone()))
        .collect();
    assert_eq!(
        held,
        [
            ("560", "100", "Q-a"),
            ("575", "95", "Q-b"),
            ("590", "90", "Q-a")
        ]
        .map(|(a, b, c)| (a.to_string(), b.to_string(), c.to_string()))
    );
    for r in &h[1..] {
        let err: f64 = r[5].parse().unwrap();
        assert!(err.abs() < 1e-3, "held-out log10 error {err}: {r:?}");
    }
    let s = json(&out.join("summary.json"));
    assert_eq!(s["held_out"]["kind"], "campaign");
    assert_eq!(s["held_out"]["campaign"], "Q");
    assert!(s["held_out_temperature_C"].is_null());
    // Trained on P's four tests, at 560 and 590 °C; 575 °C lies between them.
    assert_eq!(s["training_lifetime_err_pct"].as_array().unwrap().len(), 4);
    // A training fit that follows every life carries no caution (the key is there, null).
    assert_eq!(s.get("training_caution"), Some(&serde_json::Value::Null));
    assert_eq!(
        s["training_temperatures_C"],
        serde_json::json!([560.0, 590.0])
    );
    assert_eq!(s["temperature_extrapolation"], false);
    assert_eq!(s["tests"], 3);
    // creepfit against every baseline: the mean difference of |log10 error| recomputed from
    // holdout.csv, over the 3 tests at 3 conditions, inside its own interval.
    let col = |name: &str| h[0].iter().position(|c| c == name).unwrap();
    for (b, prefix) in s["baselines"]
        .as_array()
        .unwrap()
        .iter()
        .zip(["lmp", "osd", "mh", "wilshire"])
    {
        let Some(d) = b.get("creepfit_difference") else {
            continue;
        };
        let (m, e) = (col("model_log10_err"), col(&format!("{prefix}_log10_err")));
        let want = h[1..]
            .iter()
            .map(|r| r[m].parse::<f64>().unwrap().abs() - r[e].parse::<f64>().unwrap().abs())
            .sum::<f64>()
            / 3.0;
        let mean = d["mean"].as_f64().unwrap();
        assert!(
            (mean - want).abs() < 1e-9,
            "{prefix}: {mean} against {want}"
        );
        assert_eq!(
            (d["tests"].as_u64(), d["conditions"].as_u64()),
            (Some(3), Some(3))
        );
        let (lo, hi) = (d["lo95"].as_f64().unwrap(), d["hi95"].as_f64().unwrap());
        assert!(lo <= mean && mean <= hi, "{d}");
    }
    let k = s["one_to_beat"]["creepfit_difference"]["mean"]
        .as_f64()
        .unwrap();
    assert!(
        stdout.contains(&format!("{k:+.3} in mean |log10 error|")),
        "{stdout}"
    );
    // `predict --tests` of the held-out campaign's lives, at the training fit's constants and
    // on the training data alone, is the hold-out by another road: creepfit's lives (a
    // simulation to rupture at each condition, against the hold-out's evaluation along each
    // measured curve) and every baseline's are the same, and so are the means.
    let keep = |file: &str, to: &str, campaign: &str| {
        let text = std::fs::read_to_string(tmp.path().join(file)).unwrap();
        let mut lines = text.lines();
        let mut kept = format!("{}\n", lines.next().unwrap());
        for l in lines.filter(|l| l.contains(&format!(",{campaign}-"))) {
            kept += &format!("{l}\n");
        }
        std::fs::write(tmp.path().join(to), kept).unwrap();
    };
    keep("c.csv", "c_p.csv", "P");
    keep("r.csv", "r_p.csv", "P");
    keep("r.csv", "r_q.csv", "Q");
    let cfg_p = tmp.path().join("p.toml");
    std::fs::write(
        &cfg_p,
        std::fs::read_to_string(&cfg)
            .unwrap()
            .replace("\"c.csv\"", "\"c_p.csv\"")
            .replace("\"r.csv\"", "\"r_p.csv\""),
    )
    .unwrap();
    let pred = tmp.path().join("pq");
    ok(&[
        "predict",
        cfg_p.to_str().unwrap(),
        "--constants",
        out.join("constants.csv").to_str().unwrap(),
        "--tests",
        tmp.path().join("r_q.csv").to_str().unwrap(),
        "--out",
        pred.to_str().unwrap(),
    ]);
    let t = csv(&pred.join("tests.csv"));
    assert_eq!(t.len(), h.len());
    let tcol = |name: &str| t[0].iter().position(|c| c == name).unwrap();
    for (r, q) in h[1..].iter().zip(&t[1..]) {
        assert_eq!((&r[0], &r[1]), (&q[0], &q[1]));
        for name in [
            "model_rupture_time_h",
            "lmp_rupture_time_h",
            "osd_rupture_time_h",
            "mh_rupture_time_h",
            "wilshire_rupture_time_h",
        ] {
            let (a, b) = (&r[col(name)], &q[tcol(name)]);
            if a.is_empty() || b.is_empty() {
                assert_eq!(a, b, "{name}: absent in one only");
                continue;
            }
            let (a, b): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
            assert!(
                (a - b).abs() <= 1e-7 * a.abs(),
                "{name}: holdout {a}, predict --tests {b}"
            );
        }
    }
    let sp = json(&pred.join("summary.json"));
    let (a, b) = (
        s["model_mean_abs_log10_err"].as_f64().unwrap(),
        sp["tests"]["model_mean_abs_log10_err"].as_f64().unwrap(),
    );
    assert!((a - b).abs() < 1e-7, "{a} {b}");
    assert_eq!(sp["tests"]["one_to_beat"]["name"], s["one_to_beat"]["name"]);
    // Without intervals there is no interval to scope.
    assert_eq!(s.get("interval_scope"), Some(&serde_json::Value::Null));
    // With them, the interval of a new test is said to hold the training campaign's scatter
    // and not the held-out campaign's own level, in the printout and the summary.
    let (stdout, out_i) = hold_q("hqi", &["--intervals"]);
    let s = json(&out_i.join("summary.json"));
    assert_eq!(s["inside_pred95"]["tests"], 3, "{s}");
    let scope = s["interval_scope"].as_str().expect("a scope");
    assert!(
        scope.contains("campaign(s) P,") || scope.contains("campaign(s) P "),
        "{scope}"
    );
    assert!(scope.contains("not campaign Q's own level"), "{scope}");
    assert!(stdout.contains(&format!("note: {scope}")), "{stdout}");
    // A campaign the data lack is refused in one line naming the ones they have.
    let o = creepfit(&[
        "holdout",
        cfg.to_str().unwrap(),
        "--campaign",
        "R",
        "--out",
        tmp.path().join("x").to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("--campaign R") && e.contains("P, Q"),
        "{e}"
    );
}

/// Life-only tests (rupture records without a curve) are data too: the loader names them,
/// no fit uses them, and `holdout` predicts those it leaves out by simulating to rupture — of
/// a campaign with curves and of a campaign with lives only.
#[test]
fn holdout_predicts_life_only_tests() {
    let tmp = TempDir::new().unwrap();
    let cfg = law_data(
        tmp.path(),
        &[
            (560.0, 85.0, "P-1"),
            (560.0, 110.0, "P-2"),
            (560.0, 100.0, "Q-a"),
            (590.0, 75.0, "P-1"),
            (590.0, 100.0, "P-2"),
            (590.0, 90.0, "Q-a"),
        ],
    );
    // Three lives without curves, made by the same model: Q's at 575 °C and at a tested
    // temperature, and campaign R's only test.
    let (model, truth, ode) = law_truth();
    let life = |t: f64, s: f64| {
        let r = model.simulate(&truth, &Load::new(s, t, 1.0 / 3.0), &[], &mut [], &ode);
        assert!(r.ruptured());
        r.t_end
    };
    let lone = [
        (575.0, 95.0, "Q-b"),
        (560.0, 90.0, "Q-c"),
        (575.0, 85.0, "R-1"),
    ];
    let mut r = std::fs::read_to_string(tmp.path().join("r.csv")).unwrap();
    for (t, s, label) in lone {
        r += &format!("{t},{s},{},{label}\n", life(t, s));
    }
    std::fs::write(tmp.path().join("r.csv"), r).unwrap();
    let hold = |campaign: &str| {
        let out = tmp.path().join(campaign);
        let o = creepfit(&[
            "holdout",
            cfg.to_str().unwrap(),
            "--campaign",
            campaign,
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{stderr}");
        (String::from_utf8_lossy(&o.stdout).into_owned(), stderr, out)
    };
    let (stdout, stderr, out) = hold("Q");
    // The loader names them: one at a tested temperature, two where no curve is.
    assert!(
        stderr.contains("560 °C, 90 MPa, specimen Q-c matches no curve: a life-only test"),
        "{stderr}"
    );
    assert!(
        stderr.contains("2 rupture record(s) at 575 °C, where the curves file has no curve"),
        "{stderr}"
    );
    let h = csv(&out.join("holdout.csv"));
    let col = |name: &str| h[0].iter().position(|c| c == name).unwrap();
    let rows: Vec<(String, String, String, String)> = h[1..]
        .iter()
        .map(|r| {
            (
                r[0].clone(),
                r[1].clone(),
                r[col("specimen")].clone(),
                r[col("curve_outcome")].clone(),
            )
        })
        .collect();
    let row = |t: &str, s: &str, sp: &str, o: &str| {
        (t.to_string(), s.to_string(), sp.to_string(), o.to_string())
    };
    assert_eq!(
        rows,
        [
            row("560", "90", "Q-c", "no_curve"),
            row("560", "100", "Q-a", "complete"),
            row("575", "95", "Q-b", "no_curve"),
            row("590", "90", "Q-a", "complete"),
        ]
    );
    // Every life predicted as the curves' are: to the recovered constants' accuracy.
    for r in &h[1..] {
        let err: f64 = r[col("model_log10_err")].parse().unwrap();
        assert!(err.abs() < 1e-3, "{r:?}");
        if r[col("curve_outcome")] == "no_curve" {
            assert_eq!(
                (
                    r[col("curve_rms_pct")].as_str(),
                    r[col("curve_points")].as_str()
                ),
                ("", "0")
            );
        }
    }
    assert!(stdout.contains("life only (no curve)"), "{stdout}");
    let s = json(&out.join("summary.json"));
    assert_eq!(s["tests"], 4);
    assert_eq!(s["curve_outcomes"]["no_curve"], 2);
    // The training fit is P's four curves: no life-only test trains it, R's included.
    assert_eq!(s["training_lifetime_err_pct"].as_array().unwrap().len(), 4);
    // A campaign with a life and no curve is held out too; its one test predicted the same way.
    let (_, _, out) = hold("R");
    let h = csv(&out.join("holdout.csv"));
    assert_eq!(h.len(), 2);
    assert_eq!((h[1][0].as_str(), h[1][1].as_str()), ("575", "85"));
    let err: f64 = h[1][col("model_log10_err")].parse().unwrap();
    assert!(err.abs() < 1e-3, "{:?}", h[1]);
    assert!(!out.join("curves.png").exists());
}

/// `holdout`'s training fit under eq. 8 (the configuration's objective) fits every specimen
/// as the population's: on training data with a replicate pair, where `specimen_effects =
/// "auto"` resolves to both kinds, summary.json and stdout say so; without the pair, nothing.
#[test]
fn holdout_says_its_eq8_training_fit_leaves_the_specimen_effects_out() {
    let tmp = TempDir::new().unwrap();
    let run = |tests: &[(f64, f64, &str)], dir: &str| {
        let d = tmp.path().join(dir);
        std::fs::create_dir_all(&d).unwrap();
        let cfg = law_data(&d, tests);
        let out = d.join("ho");
        let stdout = ok(&[
            "holdout",
            cfg.to_str().unwrap(),
            "--temperature",
            "575",
            "--out",
            out.to_str().unwrap(),
        ]);
        (stdout, json(&out.join("summary.json")))
    };
    let (stdout, s) = run(
        &[
            (560.0, 85.0, "a"),
            (560.0, 100.0, "b"),
            (560.0, 100.0, "c"),
            (575.0, 95.0, "d"),
            (590.0, 75.0, "e"),
            (590.0, 100.0, "f"),
        ],
        "pair",
    );
    let note = left_out_note(&s, "eq8", &["rate", "ductility"], "eq. 8");
    assert!(
        stdout.contains(&format!("note (the training fit): {note}")),
        "{stdout}"
    );
    // One specimen per load: `auto` fits none, and there is nothing to say.
    let (stdout, s) = run(
        &[
            (560.0, 85.0, "a"),
            (560.0, 100.0, "b"),
            (575.0, 95.0, "d"),
            (590.0, 75.0, "e"),
            (590.0, 100.0, "f"),
        ],
        "single",
    );
    assert_eq!(
        s["specimen_effects_not_fitted"],
        serde_json::json!([]),
        "{s}"
    );
    assert!(s["objective_note"].is_null(), "{s}");
    assert!(!stdout.contains("note (the training fit)"), "{stdout}");
}
