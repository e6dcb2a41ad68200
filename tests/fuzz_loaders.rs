//! Fuzzing of every loader: valid files (the bundled curves and ruptures, a run
//! configuration, a `constants.csv`, a sweep journal) mutated thousands of times — bytes,
//! fields, whole lines, truncation, duplication — must load or give an error whose message
//! is one line; never a panic, never a hang (each call runs under a time budget).
//!
//! proptest drives the mutations from a fixed seed (so a CI failure reproduces) and shrinks a
//! failing case to a small one before reporting it.

use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{mpsc, Mutex};
use std::time::Duration;

use creepfit::config::RunConfig;
use creepfit::data::{self, LoadOptions};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestCaseError, TestRng, TestRunner};
use tempfile::TempDir;

/// Longest one loader call may take on a mutated file (they take milliseconds).
const BUDGET: Duration = Duration::from_secs(10);

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Cells and TOML values that break parsers: non-numbers, non-finite and extreme numbers,
/// quotes, separators, line breaks, odd Unicode, empty.
const TOKENS: &[&str] = &[
    "",
    " ",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "infinity",
    "-1",
    "-0",
    "0",
    "1e308",
    "1e309",
    "-1e308",
    "1e-320",
    "5e-324",
    "1e-400",
    "99999999999999999999999999",
    "0x10",
    "1_000",
    "\"",
    "\"\"",
    "\"a,b\"",
    "\"x\ny\"",
    "a",
    "\0",
    "\n",
    "\r\n",
    "\r",
    ",",
    ",,",
    ";",
    "٣",
    "\u{feff}",
    "\u{202e}",
    "é",
    "600",
    "560",
    "85",
    "100",
    "1e-10",
    "[",
    "]",
    "[]",
    "{}",
    "[1, 2",
    "{ lb = 1 }",
    "{ lb = 1, ub = 0 }",
    "[[1.0]]",
    "true",
    "\"../../x\"",
    "\"/\"",
    "= 1",
    "#",
    "null",
    "{\"header\": 1}",
    "{\"solution\": {}}",
    "-",
    "+",
    ".",
    "e",
    "1e",
];

/// One change to a file.
#[derive(Debug, Clone)]
enum Mutation {
    /// Overwrite the byte at a position (fraction of the length).
    SetByte(f64, u8),
    /// Insert bytes at a position.
    Insert(f64, Vec<u8>),
    /// Delete a run of bytes.
    Delete(f64, usize),
    /// Keep only the part before a position.
    Truncate(f64),
    /// Replace one comma/space-separated field of one line by a token.
    Field(f64, f64, usize),
    /// Delete a line.
    DeleteLine(f64),
    /// Repeat a line at another place.
    DuplicateLine(f64, f64),
    /// Swap two lines.
    SwapLines(f64, f64),
    /// Replace a line by a token.
    ReplaceLine(f64, usize),
    /// Append the whole file to itself.
    DuplicateFile,
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let pos = 0.0..1.0f64;
    let tok = 0..TOKENS.len();
    prop_oneof![
        (pos.clone(), any::<u8>()).prop_map(|(p, b)| Mutation::SetByte(p, b)),
        (pos.clone(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(p, b)| Mutation::Insert(p, b)),
        (pos.clone(), 1..64usize).prop_map(|(p, n)| Mutation::Delete(p, n)),
        pos.clone().prop_map(Mutation::Truncate),
        (pos.clone(), pos.clone(), tok.clone()).prop_map(|(l, f, t)| Mutation::Field(l, f, t)),
        (pos.clone(), pos.clone(), tok.clone()).prop_map(|(l, f, t)| Mutation::Field(l, f, t)),
        pos.clone().prop_map(Mutation::DeleteLine),
        (pos.clone(), pos.clone()).prop_map(|(a, b)| Mutation::DuplicateLine(a, b)),
        (pos.clone(), pos.clone()).prop_map(|(a, b)| Mutation::SwapLines(a, b)),
        (pos.clone(), tok).prop_map(|(l, t)| Mutation::ReplaceLine(l, t)),
        Just(Mutation::DuplicateFile),
    ]
}

/// 1–4 mutations, applied in order.
fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    prop::collection::vec(mutation(), 1..5)
}

fn at(frac: f64, len: usize) -> usize {
    ((frac * len as f64) as usize).min(len)
}

fn apply(text: &[u8], muts: &[Mutation]) -> Vec<u8> {
    let mut b = text.to_vec();
    for m in muts {
        let split_lines =
            |b: &[u8]| -> Vec<Vec<u8>> { b.split(|c| *c == b'\n').map(|l| l.to_vec()).collect() };
        match m {
            Mutation::SetByte(p, v) => {
                if !b.is_empty() {
                    let i = at(*p, b.len() - 1);
                    b[i] = *v;
                }
            }
            Mutation::Insert(p, bytes) => {
                let i = at(*p, b.len());
                b.splice(i..i, bytes.iter().copied());
            }
            Mutation::Delete(p, n) => {
                let i = at(*p, b.len());
                let j = (i + n).min(b.len());
                b.drain(i..j);
            }
            Mutation::Truncate(p) => b.truncate(at(*p, b.len())),
            Mutation::Field(l, f, t) => {
                let mut lines = split_lines(&b);
                let li = at(*l, lines.len().saturating_sub(1));
                if let Some(line) = lines.get_mut(li) {
                    let text = String::from_utf8_lossy(line).to_string();
                    let sep = if text.contains(',') { ',' } else { ' ' };
                    let mut fields: Vec<String> = text.split(sep).map(str::to_string).collect();
                    let fi = at(*f, fields.len().saturating_sub(1));
                    fields[fi] = TOKENS[*t].to_string();
                    *line = fields.join(&sep.to_string()).into_bytes();
                }
                b = lines.join(&b'\n');
            }
            Mutation::DeleteLine(l) => {
                let mut lines = split_lines(&b);
                if !lines.is_empty() {
                    let li = at(*l, lines.len() - 1);
                    lines.remove(li);
                }
                b = lines.join(&b'\n');
            }
            Mutation::DuplicateLine(a, c) => {
                let mut lines = split_lines(&b);
                let from = at(*a, lines.len().saturating_sub(1));
                let to = at(*c, lines.len());
                if let Some(line) = lines.get(from).cloned() {
                    lines.insert(to, line);
                }
                b = lines.join(&b'\n');
            }
            Mutation::SwapLines(a, c) => {
                let mut lines = split_lines(&b);
                let n = lines.len().saturating_sub(1);
                lines.swap(at(*a, n), at(*c, n));
                b = lines.join(&b'\n');
            }
            Mutation::ReplaceLine(l, t) => {
                let mut lines = split_lines(&b);
                let li = at(*l, lines.len().saturating_sub(1));
                if let Some(line) = lines.get_mut(li) {
                    *line = TOKENS[*t].as_bytes().to_vec();
                }
                b = lines.join(&b'\n');
            }
            Mutation::DuplicateFile => {
                let copy = b.clone();
                b.extend_from_slice(&copy);
            }
        }
    }
    b
}

/// Run `f` in a thread under [`BUDGET`]: a panic or a hang fails the case with `what`.
fn guarded<T: Send + 'static>(
    what: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, TestCaseError> {
    guarded_within(BUDGET, what, f)
}

fn guarded_within<T: Send + 'static>(
    budget: Duration,
    what: &str,
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, TestCaseError> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(AssertUnwindSafe(f));
        let _ = tx.send(r);
    });
    match rx.recv_timeout(budget) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(p)) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(TestCaseError::fail(format!("{what}: panicked: {msg}")))
        }
        Err(_) => Err(TestCaseError::fail(format!(
            "{what}: no answer within {budget:?}"
        ))),
    }
}

/// Outcomes seen over a test: every target must see both loads and errors, or the mutations
/// are not exercising it.
static OUTCOMES: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];

/// An `Ok`, or an error that is one line both alone and through the binary's error chain.
fn one_line<T>(what: &str, r: creepfit::Result<T>) -> Result<(), TestCaseError> {
    OUTCOMES[r.is_err() as usize].fetch_add(1, Ordering::Relaxed);
    if let Err(e) = r {
        let plain = e.to_string();
        let chain = format!("{:#}", anyhow::Error::from(e));
        for m in [&plain, &chain] {
            prop_assert!(
                !m.trim().is_empty() && !m.contains(['\n', '\r']),
                "{}: error is not one line: {:?}",
                what,
                m
            );
        }
    }
    Ok(())
}

/// Run `cases` mutations of `valid` through `check` (which gets the mutated bytes).
fn fuzz(
    name: &str,
    valid: Vec<u8>,
    cases: u32,
    seed_offset: u8,
    check: impl Fn(Vec<u8>) -> Result<(), TestCaseError>,
) {
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    let mut seed = [7u8; 32];
    seed[0] = seed_offset;
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed);
    let mut runner = TestRunner::new_with_rng(config, rng);
    // The counters are shared by the tests of this file, which run in parallel: one at a time.
    let _one = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    for o in &OUTCOMES {
        o.store(0, Ordering::Relaxed);
    }
    let result = runner.run(&mutations(), |muts| check(apply(&valid, &muts)));
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
    let (ok, err) = (
        OUTCOMES[0].load(Ordering::Relaxed),
        OUTCOMES[1].load(Ordering::Relaxed),
    );
    eprintln!("{name}: {cases} mutated files, {ok} loader calls returned Ok, {err} an error");
    assert!(ok > 0 && err > 0, "{name}: {ok} loaded, {err} errors");
}

static SERIAL: Mutex<()> = Mutex::new(());

/// The harness itself fails on a panic, a hang and a multi-line error.
#[test]
fn harness_catches_panics_hangs_and_multiline_errors() {
    let e = guarded("p", || panic!("boom")).unwrap_err().to_string();
    assert!(e.contains("panicked: boom"), "{e}");
    let e = guarded_within(Duration::from_millis(50), "h", || {
        std::thread::sleep(Duration::from_secs(2))
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("no answer within"), "{e}");
    let multi: creepfit::Result<()> = Err(creepfit::Error::Invalid("two\nlines".into()));
    assert!(one_line("m", multi).is_err());
    assert!(one_line("o", Ok(())).is_ok());
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// The curves loader (and the matching, rate estimation and checks after it).
#[test]
fn curves_file() {
    let dir = TempDir::new().unwrap();
    let valid = std::fs::read(root().join("data/creep_560C.csv")).unwrap();
    let ruptures = root().join("data/lifetimes.csv");
    let dir_path = dir.path().to_path_buf();
    // A specimen column too, so that the specimen logic is exercised.
    let mut with_specimen = String::new();
    for (i, l) in String::from_utf8(valid.clone())
        .unwrap()
        .lines()
        .enumerate()
    {
        let s = if i == 0 {
            "specimen"
        } else {
            ["a", "b", ""][i % 3]
        };
        with_specimen.push_str(&format!("{l},{s}\n"));
    }
    for (k, (text, cases)) in [(valid, 2500), (with_specimen.into_bytes(), 800)]
        .into_iter()
        .enumerate()
    {
        let (d, r) = (dir_path.clone(), ruptures.clone());
        fuzz("curves", text, cases, 1 + k as u8, move |bytes| {
            let (d, r) = (d.clone(), r.clone());
            let res = guarded("curves", move || {
                let c = write(&d, "curves.csv", &bytes);
                let filtered = LoadOptions {
                    temperature_c: Some(560.0),
                    ..Default::default()
                };
                (
                    data::load(&c, &r, &LoadOptions::default()),
                    data::load(&c, &r, &filtered),
                )
            })?;
            one_line("curves", res.0)?;
            one_line("curves (filtered)", res.1)
        });
    }
}

/// The ruptures loader.
#[test]
fn ruptures_file() {
    let dir = TempDir::new().unwrap();
    let mut valid = std::fs::read(root().join("data/lifetimes.csv")).unwrap();
    // Optional columns present, so that their parsing is exercised.
    let text = String::from_utf8(valid.clone()).unwrap();
    let mut extended = String::new();
    for (i, l) in text.lines().enumerate() {
        extended.push_str(l);
        extended.push_str(if i == 0 {
            ",rupture_strain_pct,min_rate_pct_per_h,specimen\n"
        } else {
            ",6.0,1e-5,\n"
        });
    }
    valid = extended.into_bytes();
    let curves = root().join("data/creep_560C.csv");
    let d = dir.path().to_path_buf();
    fuzz("ruptures", valid, 1500, 3, move |bytes| {
        let (d, c) = (d.clone(), curves.clone());
        let res = guarded("ruptures", move || {
            let r = write(&d, "ruptures.csv", &bytes);
            let opts = LoadOptions {
                temperature_c: Some(560.0),
                interrupted: vec![85.0.into()],
                ..Default::default()
            };
            data::load(&c, &r, &opts)
        })?;
        one_line("ruptures", res)
    });
}

/// The run configuration (TOML).
#[test]
fn run_configuration() {
    let path = root().join("configs/560C.toml");
    let plain = std::fs::read(&path).unwrap();
    // Also with every optional table and key, so that their parsing is exercised.
    let mut full = plain.clone();
    full.extend_from_slice(
        b"interrupted = []\n[solver]\nrtol = 1e-8\natol = 1e-13\nmax_iterations = 50\n\
          ftol = 1e-8\ngeodesic = true\njacobian = \"sensitivity\"\n",
    );
    let full = String::from_utf8(full)
        .unwrap()
        .replace(
            "extensions = []",
            "extensions = [\"constant_load\", \"stress_ductility\"]",
        )
        .replace("model = \"khd\"\n", "model = \"khd\"\ninterrupted = [85]\n")
        .replace("interrupted = []\n", "")
        .into_bytes();
    for (k, (text, cases)) in [(plain, 2500), (full, 1000)].into_iter().enumerate() {
        let p = path.clone();
        fuzz("configuration", text, cases, 4 + k as u8, move |bytes| {
            let p = p.clone();
            let res = guarded("configuration", move || {
                let text = String::from_utf8_lossy(&bytes).to_string();
                RunConfig::from_str(&text, &p).map(|c| c.load_options())
            })?;
            one_line("configuration", res)
        });
    }
}

/// `constants.csv` as `simulate --constants` reads it.
#[test]
fn constants_file() {
    let dir = TempDir::new().unwrap();
    let valid = b"name,value,unit,lb,ub\nA,1e-10,1/h,1e-10,1e-9\nB,0.1749,1/MPa,0.1,0.2\n\
                  Hstar,0.563,-,0.4,0.8\nh,59031.3,MPa,10000,200000\nKc,2.2e-5,1/h,1e-6,3e-5\n\
                  C,4.03,-,3,10\n"
        .to_vec();
    let d = dir.path().to_path_buf();
    fuzz("constants", valid, 1500, 6, move |bytes| {
        let d = d.clone();
        let res = guarded("constants", move || {
            let p = write(&d, "constants.csv", &bytes);
            let model = creepfit::model::build("khd", &[]).unwrap();
            creepfit::report::tables::read_constants(&p, model.as_ref())
        })?;
        one_line("constants", res)
    });
}

/// The sweep journal (`journal.jsonl`, what resume and merge read).
#[test]
fn sweep_journal() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("sweep");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_creepfit"))
        .args([
            "sweep",
            "tests/data/sweep_small.toml",
            "--starts",
            "1",
            "--threads",
            "1",
        ])
        .arg("--out")
        .arg(&out)
        .current_dir(root())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let valid = std::fs::read(out.join("journal.jsonl")).unwrap();
    assert!(valid.iter().filter(|b| **b == b'\n').count() >= 3);
    let d = dir.path().to_path_buf();
    fuzz("journal", valid, 1500, 7, move |bytes| {
        let d = d.clone();
        let res = guarded("journal", move || {
            let p = write(&d, "journal.jsonl", &bytes);
            creepfit::sweep::read_journal(&p)
        })?;
        one_line("journal", res)
    });
}
