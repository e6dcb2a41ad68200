//! `diagnose`, `profile`, `holdout` and `predict --intervals` resume after an interruption: a run stopped part way (the hidden
//! `--stop-after`, which stops once so many new records are journaled, as a kill would leave
//! them) and rerun into the same folder computes only what is missing and writes result
//! files byte-identical to an uninterrupted run's; a folder of another run is refused naming
//! the differing setting; nothing is drawn on a stderr that is not a terminal.

use std::path::{Path, PathBuf};
use std::process::Output;

use tempfile::TempDir;

mod common;
use common::*;

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

fn bytes(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn timings(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&bytes(&dir.join("timings.json"))).unwrap()
}

/// Records in a journal (its lines but the header).
fn records(dir: &Path) -> u64 {
    String::from_utf8(bytes(&dir.join("journal.jsonl")))
        .unwrap()
        .lines()
        .count() as u64
        - 1
}

/// The keys of a journal's records, in file order.
fn keys(dir: &Path) -> Vec<String> {
    String::from_utf8(bytes(&dir.join("journal.jsonl")))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            v["record"]["key"].as_str().unwrap().to_string()
        })
        .collect()
}

/// The side a profile step's key belongs to (`side/…/3/lower/step2` → `side/…/3/lower`).
fn side_of(key: &str) -> Option<&str> {
    key.rsplit_once("/step").map(|(side, _)| side)
}

/// A small diagnosis of the seed's 560 °C data: 2 random starts per model, 19 replicates
/// (α = 0.5 so that 19 replicates can reject over the 8 tests).
fn diagnose(out: &Path, extra: &[&str]) -> Output {
    diagnose_config(Path::new("configs/560C.toml"), out, extra)
}

/// The same small diagnosis of the configuration `cfg`.
fn diagnose_config(cfg: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "diagnose",
        cfg.to_str().unwrap(),
        "--starts",
        "2",
        "--bootstrap",
        "19",
        "--alpha",
        "0.5",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    creepfit(&args)
}

/// The stopped run: exits non-zero, says it was interrupted and where the work is kept.
fn interrupted(o: &Output, journal: &Path) {
    assert!(!o.status.success(), "an interrupted run exits non-zero");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("interrupted"), "{err}");
    assert!(err.contains(journal.to_str().unwrap()), "{err}");
}

#[test]
fn an_interrupted_diagnosis_resumes_to_the_same_files() {
    let d = TempDir::new().unwrap();
    let plain = d.path().join("plain");
    let o = diagnose(&plain, &["--threads", "2"]);
    ok(&o);
    // Nothing drawn on a stderr that is not a terminal (a pipe here).
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("ETA") && !err.contains('\r'), "{err}");
    let total = records(&plain);
    assert_eq!(timings(&plain)["journal_records_written"], total);
    assert!(total > 12, "{total}");
    // The Levenberg–Marquardt work per phase: the phases add up to the whole.
    let lm = &timings(&plain)["phase_lm"];
    let count = |phase: &str, what: &str| lm[phase][what].as_u64().unwrap();
    for what in [
        "runs",
        "iterations",
        "runs_at_limit",
        "iterations_at_limit",
        "evaluations",
    ] {
        let phases: u64 = ["fits", "null_bootstrap", "cause_bootstrap", "loo"]
            .iter()
            .map(|p| count(p, what))
            .sum();
        assert_eq!(phases, count("total", what), "{what}: {lm}");
    }
    assert!(
        count("fits", "runs") > 0 && count("null_bootstrap", "runs") > 0,
        "{lm}"
    );
    assert!(
        count("total", "iterations") >= count("total", "runs"),
        "{lm}"
    );
    assert!(
        count("null_bootstrap", "runs") >= count("null_again", "runs"),
        "{lm}"
    );

    let resumed = d.path().join("resumed");
    // Stopped during the fits on the data (one record per model: 7 models), then again
    // during the null bootstrap.
    let o = diagnose(
        &resumed,
        &["--threads", "1", "--stop-after", "3", "--quiet"],
    );
    interrupted(&o, &resumed.join("journal.jsonl"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("during the fits on the data"), "{err}");
    assert_eq!(records(&resumed), 3);
    let o = diagnose(
        &resumed,
        &["--threads", "1", "--stop-after", "9", "--quiet"],
    );
    interrupted(&o, &resumed.join("journal.jsonl"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("during the null bootstrap"), "{err}");
    assert!(!resumed.join("diagnosis.json").exists());
    let kept = records(&resumed);
    assert!((12..total - 7).contains(&kept), "{kept} of {total}");
    // And during the leave-one-stress-out checks (one record per model, the last 7), 3 short.
    let left = (total - kept - 3).to_string();
    let o = diagnose(&resumed, &["--threads", "1", "--stop-after", &left, "-q"]);
    interrupted(&o, &resumed.join("journal.jsonl"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("during the leave-one-stress-out"), "{err}");
    let kept = records(&resumed);
    assert_eq!(kept, total - 3);
    let o = diagnose(&resumed, &["--threads", "2"]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("resuming from {kept} journaled records")),
        "{err}"
    );
    // Only the missing work was done: the journaled records were all reused.
    let t = timings(&resumed);
    assert_eq!(t["journal_records_resumed"], kept);
    assert_eq!(t["journal_records_written"], total - kept);
    for f in ["diagnosis.json", "report.md", "residuals_base.png"] {
        assert!(
            bytes(&plain.join(f)) == bytes(&resumed.join(f)),
            "{f} differs after resuming"
        );
    }
    // A rerun of a finished run recomputes nothing and writes the same files.
    ok(&diagnose(&resumed, &["--threads", "2"]));
    assert_eq!(timings(&resumed)["journal_records_written"], 0);
    // Its fits are the journal's: a few polishing runs at most, not the diagnosis again.
    let rerun = timings(&resumed)["phase_lm"]["total"]["runs"]
        .as_u64()
        .unwrap();
    let first = timings(&plain)["phase_lm"]["total"]["runs"]
        .as_u64()
        .unwrap();
    assert!(10 * rerun < first, "{rerun} runs against {first}");
    assert!(bytes(&plain.join("diagnosis.json")) == bytes(&resumed.join("diagnosis.json")));
}

#[test]
fn a_diagnosis_with_other_settings_is_refused_in_the_folder() {
    let d = TempDir::new().unwrap();
    let o = diagnose(d.path(), &["--threads", "1", "--stop-after", "1"]);
    interrupted(&o, &d.path().join("journal.jsonl"));
    let before = bytes(&d.path().join("journal.jsonl"));
    let o = diagnose(d.path(), &["--threads", "1", "--seed", "99"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("journal.jsonl: this folder holds the journal of a run with diagnose.seed = ")
            && err.contains("this command asks for 99"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        bytes(&d.path().join("journal.jsonl")) == before,
        "nothing changed"
    );
}

/// The 560 °C configuration with a small `[profile]` table, written into `dir`.
fn profile_config(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("configs/560C.toml"))
        .unwrap()
        .replace(
            "../data/",
            &format!("{}/", root().join("data").to_str().unwrap()),
        )
        + "\n[profile]\ncalibrate = 10\npredict_stress_MPa = [70]\nband_points = 3\n";
    let p = dir.join("560.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn an_interrupted_profile_resumes_to_the_same_files() {
    let d = TempDir::new().unwrap();
    let cfg = profile_config(d.path());
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "profile",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        creepfit(&args)
    };
    let plain = d.path().join("plain");
    ok(&run(&plain, &["--threads", "2"]));
    let total = records(&plain);
    // 10 calibration replicates, 2 sides of each of 6 constants, and each side's steps.
    let all = keys(&plain);
    let sides = all
        .iter()
        .filter(|k| side_of(k).is_none() && k.starts_with("side/"));
    assert_eq!(sides.count(), 12, "{all:?}");
    let steps = all.iter().filter(|k| side_of(k).is_some()).count() as u64;
    assert!(steps >= 12, "{all:?}");
    assert_eq!(total, 22 + steps);
    let resumed = d.path().join("resumed");
    // Stopped inside a profile side: one thread takes the sides in order (constant 0 lower,
    // 0 upper, 1 lower, ...); stop after the calibration replicates, the sides before the
    // first one of several steps, and that side's first step.
    let steps_of = |side: &str| all.iter().filter(|k| side_of(k) == Some(side)).count() as u64;
    let mut order: Vec<&String> = all
        .iter()
        .filter(|k| side_of(k).is_none() && k.starts_with("side/"))
        .collect();
    let rank = |k: &str| {
        let mut p = k.rsplit('/');
        let dir = p.next().unwrap() == "upper";
        (p.next().unwrap().parse::<usize>().unwrap(), dir)
    };
    order.sort_by_key(|k| rank(k));
    let first = order
        .iter()
        .position(|s| steps_of(s) >= 2)
        .expect("a side of 2 steps");
    let before: u64 = order[..first].iter().map(|s| steps_of(s) + 1).sum();
    let stop = (10 + before + 1).to_string();
    let o = run(&resumed, &["--threads", "1", "--stop-after", &stop, "-q"]);
    interrupted(&o, &resumed.join("journal.jsonl"));
    let kept = records(&resumed);
    assert!((11..total).contains(&kept), "{kept}");
    // A side with journaled steps and no record of its own: the rerun resumes inside it.
    let partial = keys(&resumed);
    assert!(
        partial
            .iter()
            .filter_map(|k| side_of(k))
            .any(|s| !partial.contains(&s.to_string())),
        "{partial:?}"
    );
    ok(&run(&resumed, &["--threads", "2"]));
    let t = timings(&resumed);
    assert_eq!(t["journal_records_resumed"], kept);
    assert_eq!(t["journal_records_written"], total - kept);
    for f in [
        "intervals.csv",
        "profiles.csv",
        "summary.json",
        "report.md",
        "profile_B.png",
    ] {
        assert!(
            bytes(&plain.join(f)) == bytes(&resumed.join(f)),
            "{f} differs after resuming"
        );
    }
    // No wall time in the result files: they are in timings.json.
    let summary = String::from_utf8(bytes(&plain.join("summary.json"))).unwrap();
    assert!(!summary.contains("timings_s"), "{summary}");
    assert!(timings(&plain)["timings_s"]["total"].as_f64().unwrap() > 0.0);
}

/// Every file of `dir` but the journal, the manifest and the timings, by name.
fn results(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| (p.file_name().unwrap().to_str().unwrap().to_string(), p))
        .filter(|(n, _)| {
            ![
                "journal.jsonl",
                "manifest.json",
                "timings.json",
                ".creepfit.lock",
            ]
            .contains(&n.as_str())
        })
        .map(|(n, p)| (n, bytes(&p)))
        .collect();
    files.sort();
    files
}

#[test]
fn an_interrupted_holdout_resumes_to_the_same_files() {
    let d = TempDir::new().unwrap();
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "holdout",
            "configs/alloy617.toml",
            "--temperature",
            "950",
            "--starts",
            "3",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        creepfit(&args)
    };
    let plain = d.path().join("plain");
    ok(&run(&plain, &[]));
    let total = records(&plain);
    assert!(total >= 4, "{total}");
    let resumed = d.path().join("resumed");
    let o = run(&resumed, &["--stop-after", "2", "-q"]);
    interrupted(&o, &resumed.join("journal.jsonl"));
    let kept = records(&resumed);
    assert!((2..total).contains(&kept), "{kept} of {total}");
    ok(&run(&resumed, &[]));
    let t = timings(&resumed);
    assert_eq!(t["journal_records_resumed"], kept);
    assert_eq!(t["journal_records_written"], total - kept);
    let (a, b) = (results(&plain), results(&resumed));
    assert_eq!(
        a.iter().map(|f| &f.0).collect::<Vec<_>>(),
        b.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert!(a.len() >= 5, "{a:?}");
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name} differs after resuming");
    }
    let summary = String::from_utf8(bytes(&plain.join("summary.json"))).unwrap();
    assert!(!summary.contains("wall_s"), "{summary}");
}

#[test]
fn an_interrupted_prediction_with_intervals_resumes_to_the_same_files() {
    let d = TempDir::new().unwrap();
    let cfg = profile_config(d.path());
    let fit = d.path().join("fit");
    ok(&creepfit(&[
        "fit",
        cfg.to_str().unwrap(),
        "--out",
        fit.to_str().unwrap(),
        "-q",
    ]));
    let constants = fit.join("constants.csv");
    // `predict … --at AT --out OUT EXTRA…`, with `--intervals` unless `plain`.
    let predict = |out: &Path, at: &str, plain: bool, extra: &[&str]| {
        let mut args = vec![
            "predict",
            cfg.to_str().unwrap(),
            "--constants",
            constants.to_str().unwrap(),
            "--at",
            at,
            "--out",
            out.to_str().unwrap(),
        ];
        if !plain {
            args.push("--intervals");
        }
        args.extend_from_slice(extra);
        creepfit(&args)
    };
    let run = |out: &Path, at: &str, extra: &[&str]| predict(out, at, false, extra);
    let at = "560:70,560:80";
    let plain = d.path().join("plain");
    ok(&run(&plain, at, &["--threads", "2"]));
    // 10 calibration replicates and one record per condition.
    let all = keys(&plain);
    assert_eq!(all.len(), 12, "{all:?}");
    assert_eq!(
        all.iter().filter(|k| k.starts_with("intervals/")).count(),
        2,
        "{all:?}"
    );
    // Stopped after the replicates and the first condition.
    let resumed = d.path().join("resumed");
    let o = run(
        &resumed,
        at,
        &["--threads", "1", "--stop-after", "11", "-q"],
    );
    interrupted(&o, &resumed.join("journal.jsonl"));
    assert_eq!(records(&resumed), 11);
    let o = run(&resumed, at, &["--threads", "2"]);
    ok(&o);
    let t = timings(&resumed);
    assert_eq!(t["journal_records_resumed"], 11);
    assert_eq!(t["journal_records_written"], 1);
    // Where the time went, phase by phase (the resumed phases cost nothing).
    let phases = &timings(&plain)["intervals_s"];
    for p in ["refit", "calibration", "scatter", "intervals", "bands"] {
        assert!(phases[p].as_f64().unwrap() >= 0.0, "{phases}");
    }
    assert!(phases["intervals"].as_f64().unwrap() > 0.0, "{phases}");
    assert!(
        t["intervals_s"]["calibration"].as_f64().unwrap() < phases["calibration"].as_f64().unwrap(),
        "{t} against {phases}"
    );
    let (a, b) = (results(&plain), results(&resumed));
    assert_eq!(
        a.iter().map(|f| &f.0).collect::<Vec<_>>(),
        b.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    assert!(a.iter().any(|f| f.0 == "predictions.csv"), "{a:?}");
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name} differs after resuming");
    }
    // Another condition into that folder is refused, naming the setting.
    let o = run(&resumed, "560:90", &["-q"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("predict"), "{err}");
    // Without --intervals nothing is journaled and the journal of the run before is removed.
    ok(&predict(&plain, at, true, &["-q"]));
    assert!(!plain.join("journal.jsonl").exists());
    assert!(!plain.join("timings.json").exists());
}

/// Runs `creepfit args` with its stderr on a pseudo-terminal (`libc::openpty`, 30 × 100):
/// the exit status and everything it drew there.
fn on_a_terminal(args: &[&str]) -> (std::process::ExitStatus, String) {
    use std::io::Read;
    use std::os::fd::{FromRawFd, OwnedFd};
    let (mut master, mut slave) = (-1, -1);
    let size = libc::winsize {
        ws_row: 30,
        ws_col: 100,
        ws_xpixel: 0,
        ws_ypixel: 0,
    };
    // SAFETY: openpty writes two descriptors it opened; each is owned exactly once below.
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            &size,
        )
    };
    assert_eq!(rc, 0, "openpty: {}", std::io::Error::last_os_error());
    let (mut master, slave) = unsafe {
        (
            std::fs::File::from_raw_fd(master),
            OwnedFd::from_raw_fd(slave),
        )
    };
    // `cmd`, and with it the parent's copy of the terminal's other end, is dropped at the end
    // of this block, so that reading ends once the child has exited.
    let mut child = {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_creepfit"));
        cmd.args(args)
            .current_dir(root())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::from(slave));
        cmd.spawn().expect("binary runs")
    };
    let reader = std::thread::spawn(move || {
        let mut out = Vec::new();
        let mut buf = [0u8; 4096];
        // The terminal reads until EIO once no process holds its other end.
        while let Ok(n) = master.read(&mut buf) {
            if n == 0 {
                break;
            }
            out.extend_from_slice(&buf[..n]);
        }
        String::from_utf8_lossy(&out).into_owned()
    });
    let status = child.wait().unwrap();
    (status, reader.join().unwrap())
}

/// Finding 9: long work is not silent. On a terminal, `diagnose` and `profile` draw a bar
/// per phase with its name and count; `--quiet` draws nothing. (Off a terminal nothing is
/// drawn: the other tests of this file read clean stderr.)
#[test]
fn progress_is_drawn_on_a_terminal_and_silenced_by_quiet() {
    let d = TempDir::new().unwrap();
    let out = d.path().join("diagnose");
    let out_s = out.to_str().unwrap();
    let args = [
        "diagnose",
        "configs/560C.toml",
        "--starts",
        "2",
        "--bootstrap",
        "19",
        "--alpha",
        "0.5",
        "--out",
        out_s,
    ];
    let (status, drawn) = on_a_terminal(&args);
    assert!(status.success(), "{drawn}");
    for phase in ["null bootstrap", "/19"] {
        assert!(drawn.contains(phase), "no {phase:?} drawn: {drawn}");
    }
    let quiet = d.path().join("quiet");
    let mut q = args.to_vec();
    let last = q.len() - 1;
    q[last] = quiet.to_str().unwrap();
    q.push("--quiet");
    let (status, drawn) = on_a_terminal(&q);
    assert!(status.success(), "{drawn}");
    assert!(drawn.trim().is_empty(), "--quiet drew: {drawn}");
    let cfg = profile_config(d.path());
    let prof = d.path().join("profile");
    let (status, drawn) = on_a_terminal(&[
        "profile",
        cfg.to_str().unwrap(),
        "--out",
        prof.to_str().unwrap(),
    ]);
    assert!(status.success(), "{drawn}");
    for phase in ["calibration", "profile sides"] {
        assert!(drawn.contains(phase), "no {phase:?} drawn: {drawn}");
    }
}

/// The diagnosis that goes on without the specimen factors `auto` chose (their scatter beyond
/// the stress trend zero at the base: docs/SPECIMENS.md, "Session 65") resumes like any other:
/// the base with factors and the base refitted without them are journaled under their own
/// keys, and a run stopped after the first, then after the second, then finished writes the
/// uninterrupted run's files byte for byte. The set is the identical world's 189002 (five
/// specimens, one per stress, no scatter), with the default scatter estimate.
#[test]
fn a_diagnosis_without_the_zero_scatter_factors_resumes_to_the_same_files() {
    let d = TempDir::new().unwrap();
    let set = common::synth_set(d.path(), 189002, "constant_load");
    let cfg = set.join("config.toml");
    let run = |out: &Path, extra: &[&str]| diagnose_config(&cfg, out, extra);
    let plain = d.path().join("plain");
    ok(&run(&plain, &["--threads", "2", "-q"]));
    let j: serde_json::Value =
        serde_json::from_slice(&bytes(&plain.join("diagnosis.json"))).unwrap();
    assert_eq!(j["specimen_scatter_zero"], true, "{}", j["decision"]);
    let all = keys(&plain);
    let without = all
        .iter()
        .position(|k| k.starts_with("fits/0/base/without-specimen-factors/"))
        .unwrap_or_else(|| panic!("{all:?}"));
    // Stopped right after the base with factors, then right after the base without them.
    let resumed = d.path().join("resumed");
    let o = run(
        &resumed,
        &["--threads", "1", "--stop-after", &without.to_string(), "-q"],
    );
    interrupted(&o, &resumed.join("journal.jsonl"));
    assert_eq!(keys(&resumed), all[..without]);
    let o = run(&resumed, &["--threads", "1", "--stop-after", "1", "-q"]);
    interrupted(&o, &resumed.join("journal.jsonl"));
    assert_eq!(keys(&resumed), all[..=without]);
    ok(&run(&resumed, &["--threads", "2", "-q"]));
    assert_eq!(
        timings(&resumed)["journal_records_resumed"],
        without as u64 + 1
    );
    for f in ["diagnosis.json", "report.md", "residuals_base.png"] {
        assert!(
            bytes(&plain.join(f)) == bytes(&resumed.join(f)),
            "{f} differs after resuming"
        );
    }
}
