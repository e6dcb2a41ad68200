//! The sweep journal `journal.jsonl`: one header line that identifies the sweep, then one
//! line per finished fit, appended and flushed as fits complete. Numbers are written in
//! shortest round-trip form, so a resumed or merged sweep reproduces them bit for bit.

use std::fs::{File, OpenOptions};
use std::io::{BufReader, Read, Write};
use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::config::identity;
use crate::config::{LocalFits, RunConfig};
use crate::data::Dataset;
use crate::error::{Error, Result};
use crate::identity::{first_difference, hash_value};
use crate::likelihood::EffectKind;
use crate::model::objective::{ObjectiveKind, ParamSpace};
use crate::model::Scale;
use crate::output;

/// Key of the drawn start points' hash in a sweep's identity.
const START_POINTS: &str = "sweep_start_points";

/// File name of the journal in a sweep folder.
pub const FILE: &str = "journal.jsonl";

/// What identifies a sweep, and what its final files need besides the solutions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The run identity's hash ([`crate::identity`]): configuration, data, start points.
    pub fingerprint: String,
    /// The run identity itself, compared field by field on resume and merge (`null` in
    /// journals of earlier versions, which had none).
    #[serde(default)]
    pub identity: Value,
    /// Configuration name.
    pub name: String,
    /// Model name with its extensions, e.g. `khd+constant_load`.
    pub model: String,
    /// The extensions, in the configuration's order.
    #[serde(default)]
    pub extensions: Vec<String>,
    /// Constant names, units, bounds and scales.
    pub names: Vec<String>,
    pub units: Vec<String>,
    pub lb: Vec<f64>,
    pub ub: Vec<f64>,
    pub log_scale: Vec<bool>,
    /// Latin-hypercube starts.
    pub n_starts: usize,
    /// Seed of the starts.
    pub seed: u64,
    /// Label of the extra start (`config` or `guess`), if any; its start_id is `n_starts`.
    pub extra_start: Option<String>,
    /// The w candidates, indexed by `w_idx`.
    pub w: Vec<Vec<f64>>,
    /// Stresses of the curves (ascending), MPa.
    pub stresses: Vec<f64>,
    /// The curves' labels ([`crate::data::Curve::label`]: temperature, stress, specimen), in
    /// the order of `stresses`; empty in journals of earlier versions.
    #[serde(default)]
    pub labels: Vec<String>,
    /// (I, N) of the part this journal holds.
    pub shard: (usize, usize),
    /// Latin-hypercube starts that could not be evaluated where they were drawn and were
    /// pulled toward the extra start ([`crate::fit::repair_starts`]), by start_id.
    #[serde(default)]
    pub repaired_starts: Vec<usize>,
    /// What every fit's `objective` is: eq. 8 at its w, or −2 ln L (`None` in journals of
    /// earlier versions).
    #[serde(default)]
    pub objective_kind: Option<ObjectiveKind>,
    /// The specimen effects the configuration's likelihood asks for on these data, which the
    /// sweep's local fits do not carry: their −2 ln L is the population model's alone, the
    /// number `fit` reports as `specimens.neg2ll_without_effects` before it adds them (empty
    /// under eq. 8, without effects, and in journals of earlier versions).
    #[serde(default)]
    pub effects_not_fitted: Vec<EffectKind>,
}

impl Header {
    /// Build the header of a sweep of the resolved configuration `cfg` on `data`; its
    /// identity is the configuration's ([`identity`]) plus the drawn start points.
    pub fn new(
        cfg: &RunConfig,
        data: &Dataset,
        names: &[String],
        space: &ParamSpace,
        extra_start: Option<String>,
        w: &[Vec<f64>],
        starts: &[Vec<f64>],
    ) -> Header {
        let mut id = identity(cfg);
        id[START_POINTS] = Value::String(hash_value(&serde_json::json!(starts)));
        Header {
            fingerprint: hash_value(&id),
            identity: id,
            name: cfg.name.clone(),
            model: cfg.model_name(),
            extensions: cfg.extensions.clone(),
            names: names.to_vec(),
            units: cfg.constants.iter().map(|c| c.unit.to_string()).collect(),
            lb: space.lb.clone(),
            ub: space.ub.clone(),
            log_scale: space.scale.iter().map(|s| *s == Scale::Log).collect(),
            n_starts: cfg.sweep.starts,
            seed: cfg.sweep.seed,
            extra_start,
            w: w.to_vec(),
            stresses: data.curves.iter().map(|c| c.stress_mpa).collect(),
            labels: data.curves.iter().map(crate::data::Curve::label).collect(),
            shard: (1, 1),
            repaired_starts: Vec::new(),
            objective_kind: Some(cfg.objective.kind),
            effects_not_fitted: cfg
                .objective
                .effects_left_out(&data.curves, LocalFits::Sweep),
        }
    }

    /// What the objective of this sweep's fits is and is not, for a user comparing it with
    /// `fit`'s: a sentence where the configuration's specimen effects are left out, else `None`.
    pub fn objective_note(&self) -> Option<String> {
        crate::config::objective_note(
            self.objective_kind.unwrap_or_default(),
            &self.effects_not_fitted,
        )
    }

    /// The first setting in which `other`'s sweep differs from this one: (dotted field,
    /// value here, value in `other`); `None` when they are the same sweep.
    pub fn difference(&self, other: &Header) -> Option<(String, String, String)> {
        if self.fingerprint == other.fingerprint {
            return None;
        }
        let old = "(none: a journal of an earlier creepfit version)".to_string();
        if self.identity.is_null() {
            return Some(("run identity".into(), old, other.fingerprint.clone()));
        }
        if other.identity.is_null() {
            return Some(("run identity".into(), self.fingerprint.clone(), old));
        }
        // The configuration's settings first, then what derives from them (start points)
        // and the version, so that the message names the setting the user changed.
        let settings = |v: &Value| {
            let mut v = v.clone();
            if let Value::Object(m) = &mut v {
                m.remove(START_POINTS);
                m.remove("version");
            }
            v
        };
        first_difference(&settings(&self.identity), &settings(&other.identity))
            .or_else(|| first_difference(&self.identity, &other.identity))
            .or_else(|| {
                Some((
                    "run identity".into(),
                    self.fingerprint.clone(),
                    other.fingerprint.clone(),
                ))
            })
    }

    /// The curves' labels: `labels`, or for a journal of an earlier version without them, each
    /// curve's stress (`110 MPa`).
    pub fn curve_labels(&self) -> Vec<String> {
        if self.labels.len() == self.stresses.len() {
            return self.labels.clone();
        }
        self.stresses.iter().map(|s| format!("{s} MPa")).collect()
    }

    /// Number of starts including the extra one.
    pub fn n_starts_total(&self) -> usize {
        self.n_starts + usize::from(self.extra_start.is_some())
    }
    /// Unit-box coordinate of constant `j` at `x`.
    pub fn to_unit(&self, j: usize, x: f64) -> f64 {
        if self.log_scale[j] {
            (x.ln() - self.lb[j].ln()) / (self.ub[j].ln() - self.lb[j].ln())
        } else {
            (x - self.lb[j]) / (self.ub[j] - self.lb[j])
        }
    }
}

/// One finished local fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Solution {
    /// Start index (`n_starts` is the extra start).
    pub start_id: usize,
    /// Index into the header's w candidates.
    pub w_idx: usize,
    /// Eq. 8 at the fitted constants (NaN: simulation failed).
    #[serde(with = "nan_null")]
    pub objective: f64,
    /// Strain term alone.
    #[serde(with = "nan_null")]
    pub norm_residual: f64,
    /// Mean absolute lifetime error, %.
    #[serde(with = "nan_null")]
    pub lifetime_err_pct: f64,
    /// Mean absolute minimum-rate error, %.
    #[serde(with = "nan_null")]
    pub min_rate_err_pct: f64,
    /// Signed lifetime error per curve, %.
    #[serde(with = "nan_null_vec")]
    pub lifetime_errs_pct: Vec<f64>,
    /// LM termination, or `simulation_failure`.
    pub status: String,
    /// LM iterations.
    pub iterations: usize,
    /// Residual evaluations.
    pub evaluations: usize,
    /// Fitted constants (physical).
    #[serde(with = "nan_null_vec")]
    pub params: Vec<f64>,
}

impl Solution {
    /// Whether the fit produced a finite objective.
    pub fn ok(&self) -> bool {
        self.objective.is_finite()
    }
}

mod nan_null {
    use serde::{Deserialize, Deserializer, Serializer};
    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

mod nan_null_vec {
    use serde::{Deserialize, Deserializer, Serializer};
    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(
            v.iter()
                .map(|x| if x.is_finite() { Some(*x) } else { None }),
        )
    }
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Ok(Vec::<Option<f64>>::deserialize(d)?
            .into_iter()
            .map(|x| x.unwrap_or(f64::NAN))
            .collect())
    }
}

#[derive(Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
enum Line {
    Header(Box<Header>),
    Solution(Solution),
}

/// Start a new journal with its header, atomically (the header line whole, or no journal).
pub fn create(path: &Path, header: &Header) -> Result<()> {
    let line =
        serde_json::to_string(&Line::Header(Box::new(header.clone()))).expect("header serialises");
    output::write_atomic(path, |w| writeln!(w, "{line}"))
}

/// Read a journal: `None` if it does not exist or holds no complete header line (a kill
/// right after its creation, by an earlier version that did not create it atomically). A
/// last line cut short by an interruption is ignored (its fit is simply computed again).
pub fn read(path: &Path) -> Result<Option<(Header, Vec<Solution>)>> {
    let f = match File::open(path) {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::io(path, e)),
    };
    let mut text = String::new();
    BufReader::new(f)
        .read_to_string(&mut text)
        .map_err(|e| Error::io(path, e))?;
    if !text.contains('\n') && serde_json::from_str::<Line>(text.trim()).is_err() {
        return Ok(None); // empty, or a torn header line: nothing was journaled
    }
    let lines: Vec<&str> = text.lines().collect();
    let mut header = None;
    let mut sols = Vec::new();
    let n = lines.len();
    for (i, l) in lines.iter().enumerate() {
        if l.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Line>(l) {
            Ok(Line::Header(h)) if i == 0 => header = Some(*h),
            Ok(Line::Solution(s)) if header.is_some() => sols.push(s),
            Err(_) if i + 1 == n && header.is_some() => {} // torn last line
            _ => return Err(Error::data(path, i + 1, "not a sweep journal line")),
        }
    }
    let header = header.ok_or_else(|| Error::data(path, 1, "missing journal header"))?;
    let mut seen = std::collections::HashSet::new();
    sols.retain(|s: &Solution| seen.insert((s.start_id, s.w_idx)));
    Ok(Some((header, sols)))
}

/// Appends solutions to a journal, one flushed line each.
pub struct Appender {
    file: File,
    path: std::path::PathBuf,
}

impl Appender {
    /// Open an existing journal for appending; a torn last line (an interrupted write) is cut
    /// off first, so that the next record starts on a line of its own.
    pub fn open(path: &Path) -> Result<Appender> {
        let text = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        let keep = text.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1);
        let whole_last = serde_json::from_slice::<Line>(&text[keep..]).is_ok();
        if keep < text.len() && !whole_last {
            let f = OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(|e| Error::io(path, e))?;
            f.set_len(keep as u64).map_err(|e| Error::io(path, e))?;
        }
        let mut file = OpenOptions::new()
            .append(true)
            .open(path)
            .map_err(|e| Error::io(path, e))?;
        if keep < text.len() && whole_last {
            // a whole last record without its newline: end its line
            file.write_all(b"\n").map_err(|e| Error::io(path, e))?;
        }
        Ok(Appender {
            file,
            path: path.to_path_buf(),
        })
    }
    /// Append one solution and flush it to the file.
    pub fn append(&mut self, s: &Solution) -> Result<()> {
        let mut line =
            serde_json::to_string(&Line::Solution(s.clone())).expect("solution serialises");
        line.push('\n');
        output::charge(line.len())
            .and_then(|_| self.file.write_all(line.as_bytes()))
            .and_then(|_| self.file.flush())
            .map_err(|e| Error::io(&self.path, e))
    }
}
