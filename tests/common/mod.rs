//! Helpers shared by the integration tests: the repository root, the binary, JSON files.
#![allow(dead_code)] // each test file uses its own share

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root (configurations and data paths are relative to it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A bundled configuration (`configs/<name>`), loaded.
pub fn config(name: &str) -> creepfit::config::RunConfig {
    creepfit::config::RunConfig::load(&root().join("configs").join(name)).unwrap()
}

/// Run the `creepfit` binary with `args` from the repository root.
pub fn creepfit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_creepfit"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("binary runs")
}

/// A copy of the seed's 560 °C configuration and data in `dir` with the rupture-time row
/// `from` of `data/lifetimes.csv` replaced by `to` (e.g. `"560,110,31111,"` →
/// `"560,110,3111100,"`: the 110 MPa life 100× longer); returns the configuration's path.
pub fn seed_560_with_life(dir: &Path, from: &str, to: &str) -> PathBuf {
    let lives = std::fs::read_to_string(root().join("data/lifetimes.csv")).unwrap();
    let edited = lives.replace(from, to);
    assert!(from == to || edited != lives, "{from} is in the file");
    std::fs::write(dir.join("lifetimes.csv"), edited).unwrap();
    std::fs::copy(
        root().join("data/creep_560C.csv"),
        dir.join("creep_560C.csv"),
    )
    .unwrap();
    let cfg = std::fs::read_to_string(root().join("configs/560C.toml"))
        .unwrap()
        .replace("../data/creep_560C.csv", "creep_560C.csv")
        .replace("../data/lifetimes.csv", "lifetimes.csv");
    let path = dir.join("c.toml");
    std::fs::write(&path, cfg).unwrap();
    path
}

/// A JSON file, parsed.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Progress of a slow test, written straight to the process's stderr (the test harness
/// captures `eprintln!`, not the stream itself), so that a long statistical test shows its
/// sets as they finish: `[name] 3/8 sets 41 s: <the set's line>`.
pub struct TestProgress {
    name: &'static str,
    start: std::time::Instant,
    total: std::sync::atomic::AtomicU64,
    done: std::sync::atomic::AtomicU64,
}

impl TestProgress {
    /// Progress lines prefixed with the test's `name`.
    pub fn new(name: &'static str) -> TestProgress {
        TestProgress {
            name,
            start: std::time::Instant::now(),
            total: Default::default(),
            done: Default::default(),
        }
    }

    /// One line on stderr, past the harness's capture.
    pub fn line(&self, text: &str) {
        use std::io::Write;
        use std::sync::atomic::Ordering::Relaxed;
        let line = format!(
            "[{}] {}/{} {:.0} s: {text}\n",
            self.name,
            self.done.load(Relaxed),
            self.total.load(Relaxed),
            self.start.elapsed().as_secs_f64()
        );
        let _ = std::io::stderr().lock().write_all(line.as_bytes());
    }
}

impl creepfit::progress::Observer for TestProgress {
    fn phase(&self, name: &str, total: Option<u64>) {
        use std::sync::atomic::Ordering::Relaxed;
        self.total.store(total.unwrap_or(0), Relaxed);
        self.done.store(0, Relaxed);
        self.line(&format!("{name} begins"));
    }
    fn resumed(&self, n: u64) {
        self.done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    }
    fn note(&self, line: &str) {
        self.line(line);
    }
}

/// One generated set of `creepfit synth` (world `identical`, the default) with seed `seed` and
/// hidden effect `scenario`, written under `dir/sets`: its folder (config.toml, curves.csv,
/// ruptures.csv, truth.json).
pub fn synth_set(dir: &Path, seed: u64, scenario: &str) -> PathBuf {
    let sets = dir.join("sets");
    let seed_text = seed.to_string();
    let o = creepfit(&[
        "synth",
        sets.to_str().unwrap(),
        "--sets",
        "1",
        "--seed",
        &seed_text,
        "--scenario",
        scenario,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    sets.join(format!("set-{seed}"))
}

/// Asserts that `summary` (a summary.json of `fit`, `sweep` or `holdout`) says its objective
/// `kind` leaves out the specimen effects `kinds`, in a note that contains `word`; the note.
#[allow(dead_code)]
pub fn left_out_note<'a>(
    summary: &'a serde_json::Value,
    kind: &str,
    kinds: &[&str],
    word: &str,
) -> &'a str {
    assert_eq!(summary["objective_kind"], kind, "{summary}");
    assert_eq!(
        summary["specimen_effects_not_fitted"],
        serde_json::json!(kinds),
        "{summary}"
    );
    let note = summary["objective_note"].as_str().expect("a note");
    assert!(note.contains(word), "{note}");
    note
}

/// The configuration `configs/alloy617-<t>C.toml` with its data paths made absolute and
/// `objective` lines added under `[objective]`, written to `dir/name`; its path and text.
#[allow(dead_code)]
pub fn alloy617_at(dir: &Path, t: u32, objective: &str, name: &str) -> (PathBuf, String) {
    let data = root().join("data/alloy617");
    let text = std::fs::read_to_string(root().join(format!("configs/alloy617-{t}C.toml")))
        .unwrap()
        .replace("\"../data/alloy617/", &format!("\"{}/", data.display()))
        .replace("[objective]\n", &format!("[objective]\n{objective}"));
    assert!(text.contains(&*data.to_string_lossy()) && text.contains(objective));
    let path = dir.join(name);
    std::fs::write(&path, &text).unwrap();
    (path, text)
}
