//! The journal of a resumable command (`diagnose`, `profile`, `holdout`): `journal.jsonl` in
//! its output folder, one header line with the run identity, then one line per finished unit
//! of work (a bootstrap replicate's statistics, a profile side, a training fit), appended and
//! flushed as each finishes. A rerun of the same command into the same folder reads it and
//! computes only what is missing; a kill (even `kill -9`) loses at most the units running at
//! that moment. Numbers are written exactly ([`exact`]: shortest round-trip form, and the
//! non-finite ones by name), so a resumed run's results are those of an uninterrupted one bit
//! for bit.
//!
//! Safe: the header holds the run identity (the configuration's [`crate::identity`], the
//! command's own settings, the data's hash, the crate version); a rerun whose identity
//! differs is refused, naming the first differing setting, before anything in the folder
//! changes. A record's key names what it depends on beyond the identity (e.g. the hash of
//! the fitted model a replicate was drawn from), so a record is only ever reused for the very
//! computation that made it. Call [`Journal::open`] under the folder's lock.

use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::error::{Error, Result};
use crate::identity::{first_difference, hash_value};

/// File name of the journal in an output folder.
pub const FILE: &str = "journal.jsonl";

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum Line {
    Header {
        fingerprint: String,
        identity: Value,
        /// The creepfit build that wrote the records ([`build_id`]).
        #[serde(default)]
        build: String,
    },
    Record {
        key: String,
        value: Value,
    },
}

/// An open journal: the records found, and the file new ones are appended to.
pub struct Journal {
    path: PathBuf,
    records: Mutex<HashMap<String, Value>>,
    file: Mutex<File>,
    found: usize,
    discarded: usize,
    written: AtomicU64,
}

/// The creepfit build that runs: the crate version, and the size and modification time of
/// the executable (a rebuilt binary, whose code may compute differently while the version is
/// the same, is another build). Records of another build are not reused.
pub fn build_id() -> String {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    ID.get_or_init(|| {
        let exe = std::env::current_exe()
            .and_then(std::fs::metadata)
            .ok()
            .map(|m| {
                let t = m
                    .modified()
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_nanos());
                format!("{}-{t}", m.len())
            })
            .unwrap_or_else(|| "unknown".into());
        format!("{}-{exe}", env!("CARGO_PKG_VERSION"))
    })
    .clone()
}

impl std::fmt::Debug for Journal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Journal")
            .field("path", &self.path)
            .field("found", &self.found)
            .finish()
    }
}

/// What a journal file holds: its header's identity and its records (a torn last line, an
/// interrupted write, is left out); `None` when there is no file or no complete header.
/// A journal file's header identity, the build that wrote it, and its records.
type Held = (Value, String, Vec<(String, Value)>);

fn read(path: &Path) -> Result<Option<Held>> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(path, e)),
    };
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len();
    let mut identity = None;
    let mut build = String::new();
    let mut records = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Line>(l) {
            Ok(Line::Header {
                identity: id,
                build: b,
                ..
            }) if i == 0 => {
                identity = Some(id);
                build = b;
            }
            Ok(Line::Record { key, value }) if identity.is_some() => records.push((key, value)),
            // A torn last line (the header's too: nothing was journaled).
            Err(_) if i + 1 == n => {}
            _ => return Err(Error::data(path, i + 1, "not a journal line")),
        }
    }
    Ok(identity.map(|id| (id, build, records)))
}

impl Journal {
    /// Open the journal `dir/journal.jsonl` of a run with identity `identity` (a JSON
    /// object): a new one when the folder has none (or an empty or torn one), else resume
    /// it — refused, naming the first differing setting, when it holds another run. The
    /// records of another creepfit build ([`build_id`]) are discarded (a new journal).
    pub fn open(dir: &Path, identity: &Value) -> Result<Journal> {
        Self::open_as(dir, identity, &build_id())
    }

    /// [`Journal::open`] as build `build`.
    fn open_as(dir: &Path, identity: &Value, build: &str) -> Result<Journal> {
        let path = dir.join(FILE);
        let fingerprint = hash_value(identity);
        let mut records = HashMap::new();
        let mut discarded = 0;
        let held = read(&path)?;
        if let Some((held, _, _)) = &held {
            if hash_value(held) != fingerprint {
                let (field, here, asked) = first_difference(held, identity).unwrap_or((
                    "run identity".into(),
                    hash_value(held),
                    fingerprint.clone(),
                ));
                return Err(Error::Folder {
                    path,
                    message: format!(
                        "this folder holds the journal of a run with {field} = {here}, this command asks for {asked}; use another --out or delete the folder"
                    ),
                });
            }
        }
        match held {
            Some((_, b, found)) if b == build => records.extend(found),
            other => {
                discarded = other.map_or(0, |(_, _, found)| found.len());
                let line = serde_json::to_string(&Line::Header {
                    fingerprint,
                    identity: identity.clone(),
                    build: build.to_string(),
                })
                .expect("JSON of plain values");
                crate::output::write_atomic(&path, |w| writeln!(w, "{line}"))?;
            }
        }
        // Cut a torn last line off, so that the next record starts on a line of its own.
        let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
        let keep = bytes.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1);
        if keep < bytes.len() {
            let f = OpenOptions::new()
                .write(true)
                .open(&path)
                .map_err(|e| Error::io(&path, e))?;
            f.set_len(keep as u64).map_err(|e| Error::io(&path, e))?;
        }
        let file = OpenOptions::new()
            .append(true)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        crate::output::record(&path);
        Ok(Journal {
            path,
            discarded,
            found: records.len(),
            records: Mutex::new(records),
            file: Mutex::new(file),
            written: AtomicU64::new(0),
        })
    }

    /// The journal's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Records found when the journal was opened (an earlier run's).
    pub fn found(&self) -> usize {
        self.found
    }

    /// Records of another creepfit build found and discarded when the journal was opened.
    pub fn discarded(&self) -> usize {
        self.discarded
    }

    /// Records this run appended.
    pub fn written(&self) -> u64 {
        self.written.load(Ordering::SeqCst)
    }

    /// Whether a record `key` exists.
    pub fn contains(&self, key: &str) -> bool {
        self.records
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .contains_key(key)
    }

    /// Number of records whose key starts with `prefix`.
    pub fn count_prefix(&self, prefix: &str) -> usize {
        self.records
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .keys()
            .filter(|k| k.starts_with(prefix))
            .count()
    }

    /// The record `key` as a `T` (`None` when absent, or when it does not read as a `T`:
    /// then it is simply computed again).
    pub fn get<T: DeserializeOwned>(&self, key: &str) -> Option<T> {
        let v = self
            .records
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(key)
            .cloned()?;
        serde_json::from_value(v).ok()
    }

    /// Append the record `key` and flush it to the file.
    pub fn put<T: Serialize>(&self, key: &str, value: &T) -> Result<()> {
        let value = serde_json::to_value(value).expect("a journal record serialises");
        let mut line = serde_json::to_string(&Line::Record {
            key: key.to_string(),
            value: value.clone(),
        })
        .expect("JSON of plain values");
        line.push('\n');
        {
            let mut f = self.file.lock().unwrap_or_else(|e| e.into_inner());
            crate::output::charge(line.len())
                .and_then(|_| f.write_all(line.as_bytes()))
                .and_then(|_| f.flush())
                .map_err(|e| Error::io(&self.path, e))?;
        }
        self.records
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(key.to_string(), value);
        self.written.fetch_add(1, Ordering::SeqCst);
        Ok(())
    }
}

/// The hash (16 hex digits) of a value's `Debug` text: a key part for what a record depends
/// on that has no serialisation (a fitted model). `Debug` writes every `f64` in shortest
/// round-trip form, so two values hash alike only when they are equal bit for bit (up to
/// NaN payloads).
pub fn debug_hash<T: std::fmt::Debug + ?Sized>(v: &T) -> String {
    format!(
        "{:016x}",
        crate::identity::fnv1a(format!("{v:?}").as_bytes())
    )
}

/// Exact JSON of `f64`: finite values as numbers in shortest round-trip form (bit for bit
/// back), the non-finite ones as the strings `NaN`, `inf` and `-inf` (JSON has no numbers for
/// them, and a failed fit's NaN must not come back as something else). For `#[serde(with)]`.
pub mod exact {
    use serde::{Deserialize, Deserializer, Serializer};
    use serde_json::Value;

    /// The JSON of `x`.
    pub fn to_json(x: f64) -> Value {
        if x.is_finite() {
            serde_json::json!(x)
        } else if x.is_nan() {
            Value::String("NaN".into())
        } else if x > 0.0 {
            Value::String("inf".into())
        } else {
            Value::String("-inf".into())
        }
    }

    /// The `f64` of `v` (`None` for anything [`to_json`] does not write).
    pub fn from_json(v: &Value) -> Option<f64> {
        match v {
            Value::Number(n) => n.as_f64(),
            Value::String(s) => match s.as_str() {
                "NaN" => Some(f64::NAN),
                "inf" => Some(f64::INFINITY),
                "-inf" => Some(f64::NEG_INFINITY),
                _ => None,
            },
            _ => None,
        }
    }

    pub fn serialize<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        to_json(*x).serialize(s)
    }
    use serde::Serialize;

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        let v = Value::deserialize(d)?;
        from_json(&v).ok_or_else(|| serde::de::Error::custom(format!("not a number: {v}")))
    }

    /// [`exact`](self) for `Vec<f64>`.
    pub mod vec {
        use serde::{Deserialize, Deserializer, Serialize, Serializer};
        use serde_json::Value;

        pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
            v.iter()
                .map(|x| super::to_json(*x))
                .collect::<Vec<_>>()
                .serialize(s)
        }
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
            Vec::<Value>::deserialize(d)?
                .iter()
                .map(|v| {
                    super::from_json(v)
                        .ok_or_else(|| serde::de::Error::custom(format!("not a number: {v}")))
                })
                .collect()
        }
    }
}

/// A `Vec<f64>` that serialises exactly ([`exact`]): a journal record of statistics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Exact(#[serde(with = "exact::vec")] pub Vec<f64>);

/// Take the output folder `out` over for a resumable run of `command` with run identity `id`:
/// the lock, then the journal (a folder of another run is refused before anything in it
/// changes), then the folder is this run's, its journal kept to resume from.
pub fn take_with_journal(
    out: &Path,
    command: &str,
    id: &serde_json::Value,
) -> Result<(crate::output::RunFolder, Journal)> {
    let lock = crate::output::lock_folder(out)?;
    let journal = Journal::open(out, id)?;
    let folder = crate::output::RunFolder::take_over(lock, command, &|f| f == FILE)?;
    crate::output::record(journal.path());
    if journal.discarded() > 0 {
        eprintln!(
            "warning: {}: {} records of another creepfit build discarded (computed again)",
            journal.path().display(),
            journal.discarded()
        );
    }
    if journal.found() > 0 {
        eprintln!(
            "{}: resuming from {} journaled records",
            journal.path().display(),
            journal.found()
        );
    }
    Ok((folder, journal))
}

/// The records of a JSON-lines results file (one finished set per line, appended as each
/// finishes: a battery's `results.jsonl`, a coverage run's `coverage.jsonl`), by `key`. A
/// missing file is none; a torn last line (the run was killed while writing it) is skipped
/// and recomputed; any other unreadable line is an error naming the file, the line and
/// `what` the line should be.
pub fn read_lines_by<T: DeserializeOwned>(
    path: &Path,
    what: &str,
    key: impl Fn(&T) -> u64,
) -> Result<std::collections::BTreeMap<u64, T>> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Default::default()),
        Err(e) => return Err(Error::io(path, e)),
    };
    let lines: Vec<&str> = text.lines().collect();
    let mut out = std::collections::BTreeMap::new();
    for (i, l) in lines.iter().enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<T>(l) {
            Ok(r) => {
                out.insert(key(&r), r);
            }
            Err(_) if i + 1 == lines.len() => {} // torn last line: recomputed
            Err(e) => return Err(Error::data(path, i + 1, format!("not {what}: {e}"))),
        }
    }
    Ok(out)
}

/// `path` opened for appending results after cutting a torn last line (what
/// [`read_lines_by`] skipped), shared by the workers that append to it.
pub fn append_lines(path: &Path) -> Result<Mutex<File>> {
    if let Ok(bytes) = std::fs::read(path) {
        let keep = bytes.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1);
        if keep < bytes.len() {
            std::fs::write(path, &bytes[..keep]).map_err(|e| Error::io(path, e))?;
        }
    }
    let file = OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(|e| Error::io(path, e))?;
    Ok(Mutex::new(file))
}

/// A number JSON wrote as `null` (NaN, ±∞) reads back as NaN (`#[serde(deserialize_with)]`).
pub fn de_nan_f64<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn exact_numbers_come_back_bit_for_bit() {
        let xs = vec![
            0.1,
            -0.0,
            1e-308,
            5e-324,
            f64::MAX,
            std::f64::consts::PI,
            1.0 / 3.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let text = serde_json::to_string(&Exact(xs.clone())).unwrap();
        let back: Exact = serde_json::from_str(&text).unwrap();
        for (a, b) in xs.iter().zip(&back.0) {
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{a} -> {b} ({text})"
            );
        }
        assert!(serde_json::from_str::<Exact>("[\"x\"]").is_err());
        assert!(serde_json::from_str::<Exact>("[null]").is_err());
    }

    #[test]
    fn a_journal_resumes_its_records_and_refuses_another_run() {
        let d = tempfile::TempDir::new().unwrap();
        let id = json!({"command": "diagnose", "diagnose": {"seed": 1, "bootstrap": 159}});
        let j = Journal::open(d.path(), &id).unwrap();
        assert_eq!(j.found(), 0);
        j.put("rep/1/x/0", &Exact(vec![1.5, f64::NAN])).unwrap();
        j.put("rep/1/x/1", &Exact(vec![2.5, 0.0])).unwrap();
        assert_eq!(j.written(), 2);
        drop(j);
        // A torn last line (a kill in the middle of a write) is dropped and cut off.
        let p = d.path().join(FILE);
        let mut f = OpenOptions::new().append(true).open(&p).unwrap();
        f.write_all(b"{\"record\":{\"key\":\"rep/1/x/2\",\"val")
            .unwrap();
        drop(f);
        let j = Journal::open(d.path(), &id).unwrap();
        assert_eq!(j.found(), 2);
        assert_eq!(j.count_prefix("rep/1/x/"), 2);
        let r: Exact = j.get("rep/1/x/0").unwrap();
        assert!(r.0[0] == 1.5 && r.0[1].is_nan());
        assert!(j.get::<Exact>("rep/1/x/2").is_none());
        j.put("rep/1/x/2", &Exact(vec![3.0])).unwrap();
        drop(j);
        let text = std::fs::read_to_string(&p).unwrap();
        assert_eq!(text.lines().count(), 4, "{text}");
        assert!(text
            .lines()
            .all(|l| serde_json::from_str::<Line>(l).is_ok()));
        // Another run's settings: refused, naming the setting, nothing changed.
        let mut other = id.clone();
        other["diagnose"]["seed"] = json!(2);
        let e = Journal::open(d.path(), &other).unwrap_err().to_string();
        assert!(
            e.contains("a run with diagnose.seed = 1, this command asks for 2"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&p).unwrap(), text);
        // A line in the middle that is not a journal line is an error naming it.
        std::fs::write(&p, text.replacen("\n", "\nrubbish\n", 1)).unwrap();
        let e = Journal::open(d.path(), &id).unwrap_err().to_string();
        assert!(e.contains(":2:"), "{e}");
        // Another build's records are not reused: a new journal.
        std::fs::write(&p, &text).unwrap();
        let j = Journal::open_as(d.path(), &id, "another build").unwrap();
        assert_eq!((j.found(), j.discarded()), (0, 3));
        drop(j);
        assert_eq!(std::fs::read_to_string(&p).unwrap().lines().count(), 1);
        // An empty journal (a kill before its header was written) starts anew.
        std::fs::write(&p, "").unwrap();
        let j = Journal::open(d.path(), &id).unwrap();
        assert_eq!(j.found(), 0);
    }

    #[test]
    fn debug_hash_tells_values_apart_bit_for_bit() {
        assert_eq!(debug_hash(&vec![1.0, 2.0]), debug_hash(&vec![1.0, 2.0]));
        assert_ne!(
            debug_hash(&vec![1.0, 2.0]),
            debug_hash(&vec![1.0, 2.0 + f64::EPSILON * 2.0])
        );
    }
}
