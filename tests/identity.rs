//! The run identity covers every setting of the resolved configuration: each field of its
//! serialisation (the list is generated from the serialised form, so a field added later is
//! covered without touching this test), changed alone, makes a resume and a merge of the
//! sweep refuse with an error naming that field; the fields documented as not changing
//! results (`IDENTITY_EXCLUDED`) change nothing.

use std::path::{Path, PathBuf};

use creepfit::config::{Overrides, RunConfig, RunOptions, IDENTITY_EXCLUDED};
use creepfit::data::Dataset;
use creepfit::identity::leaves;
use creepfit::sweep::{merge, plan, run_sweep, Header};
use serde_json::{json, Value};
use tempfile::TempDir;

const CONFIG: &str = "tests/data/sweep_small.toml";

fn resolved(out: &Path) -> (RunConfig, Dataset) {
    let cli = Overrides {
        run: RunOptions {
            out: Some(out.to_path_buf()),
            stop_after: Some(0),
            ..RunOptions::default()
        },
        ..Overrides::default()
    };
    RunConfig::resolve(&Path::new(env!("CARGO_MANIFEST_DIR")).join(CONFIG), &cli).unwrap()
}

/// Candidate new values for a leaf; the first that gives a valid configuration is used.
fn candidates(v: &Value) -> Vec<Value> {
    match v {
        Value::Bool(b) => vec![json!(!b)],
        Value::Number(n) => {
            let x = n.as_f64().unwrap();
            let mut c = Vec::new();
            if n.is_u64() {
                c.push(json!(n.as_u64().unwrap() + 1));
                c.push(json!(n.as_u64().unwrap() + 60));
                if n.as_u64().unwrap() > 1 {
                    c.push(json!(n.as_u64().unwrap() - 1));
                }
            }
            for f in [1.001, 0.999, 1.5, 0.5] {
                c.push(json!(x * f));
            }
            c.push(json!(x + 1.0));
            c
        }
        Value::String(s) => {
            let mut c: Vec<Value> = [
                "khd1",
                "khd4",
                "log",
                "linear",
                "both",
                "late",
                "finite_difference",
                "sensitivity",
                "config",
                "guess",
                "likelihood",
                "eq8",
            ]
            .iter()
            .filter(|x| **x != s)
            .map(|x| json!(x))
            .collect();
            c.push(json!(format!("{s}0")));
            // A word that may also be a list (`specimen_effects = "auto"` or `["rate"]`).
            c.push(json!(["rate"]));
            c
        }
        Value::Null => vec![json!(560.0), json!(0.5), json!(1.0)],
        Value::Array(a) if a.is_empty() => vec![
            json!(["constant_load"]),
            json!([[0.5, 0.5, 0.5]]),
            json!([70.0]),
        ],
        Value::Array(a) => {
            let mut c = Vec::new();
            let mut longer = a.clone();
            longer.push(a[a.len() - 1].clone());
            let mut changed = a.clone();
            changed[0] = json!(a[0].as_f64().map_or(0.3, |x| x * 0.5));
            c.push(Value::Array(changed));
            c.push(Value::Array(a[..a.len() - 1].to_vec()));
            c.push(Value::Array(longer));
            c
        }
        Value::Object(_) => unreachable!("leaves are not objects"),
    }
}

/// `cfg` with the value at JSON pointer `ptr` replaced by the first candidate that gives a
/// valid configuration.
fn changed(base: &Value, ptr: &str) -> Option<(RunConfig, Value)> {
    let old = base.pointer(ptr).unwrap().clone();
    candidates(&old).into_iter().find_map(|new| {
        let mut v = base.clone();
        *v.pointer_mut(ptr).unwrap() = new.clone();
        let mut c: RunConfig = serde_json::from_value(v).ok()?;
        c.validate().ok()?;
        // Units are the model's, not settings (not serialised): take them from the model.
        let m = creepfit::model::build(&c.model, &c.extensions).ok()?;
        for (k, spec) in c.constants.iter_mut().zip(m.constants()) {
            k.unit = spec.unit;
        }
        Some((c, new))
    })
}

fn write_journal(dir: &Path, header: &Header) {
    std::fs::create_dir_all(dir).unwrap();
    let line = serde_json::to_string(&json!({ "header": header })).unwrap();
    std::fs::write(dir.join("journal.jsonl"), format!("{line}\n")).unwrap();
}

fn shard_journal(cfg: &RunConfig, data: &Dataset, dir: &Path, shard: (usize, usize)) {
    let mut h = plan(cfg, &cfg.calibration(data).unwrap(), data)
        .unwrap()
        .header;
    h.shard = shard;
    write_journal(dir, &h);
}

#[test]
fn every_setting_changed_alone_makes_resume_and_merge_refuse() {
    let tmp = TempDir::new().unwrap();
    let folder = tmp.path().join("sweep");
    let (cfg, data) = resolved(&folder);
    // The sweep to resume: its journal holds the header and no fit yet (stop after 0).
    let (_, run) = run_sweep(&cfg, &data).unwrap();
    assert_eq!(run.computed, 0);
    drop(run);
    let shard1 = tmp.path().join("shard1");
    shard_journal(&cfg, &data, &shard1, (1, 2));

    let base = serde_json::to_value(&cfg).unwrap();
    let top: Vec<&String> = base.as_object().unwrap().keys().collect();
    for k in IDENTITY_EXCLUDED {
        assert!(
            top.iter().any(|t| t == k),
            "excluded field {k} is not in the serialisation"
        );
    }
    let fields: Vec<(String, String)> = leaves(&base)
        .into_iter()
        .filter(|(_, name)| {
            let head = name.split(['.', '[']).next().unwrap();
            !IDENTITY_EXCLUDED.contains(&head)
        })
        .collect();
    assert!(fields.len() >= 40, "{} fields: {fields:?}", fields.len());

    let mut tested = Vec::new();
    let mut fixed_by_model = Vec::new();
    for (k, (ptr, name)) in fields.iter().enumerate() {
        let Some((mut m, new)) = changed(&base, ptr) else {
            fixed_by_model.push(name.clone());
            continue;
        };
        // Resume into the folder of the original sweep: refused, naming the field.
        m.run.out = Some(folder.clone());
        let e = match run_sweep(&m, &data) {
            Ok(_) => panic!("{name} = {new}: the resume was not refused"),
            Err(e) => e.to_string(),
        };
        assert!(
            e.contains("this folder holds a sweep with") && e.contains(&format!("{name} = ")),
            "{name} = {new}: {e}"
        );
        assert!(!e.contains('\n'), "{e}");
        // Merge of a shard of the original with a shard of the changed one: refused too.
        let shard2 = tmp.path().join(format!("shard2-{k}"));
        shard_journal(&m, &data, &shard2, (2, 2));
        let e = merge(&[shard1.clone(), shard2.clone()])
            .err()
            .unwrap_or_else(|| panic!("{name} = {new}: the merge was not refused"))
            .to_string();
        assert!(
            e.contains("a different sweep") && e.contains(&format!("{name} = ")),
            "{name} = {new}: {e}"
        );
        tested.push(name.clone());
    }
    // Only the constants' names and temperature laws cannot change alone: the model fixes
    // the names, and a law brings its parameter as a constant of its own (changing either
    // alone is an invalid configuration, caught by validation, not a different sweep).
    assert!(
        fixed_by_model
            .iter()
            .all(|n| n.starts_with("constants.") && (n.ends_with(".name") || n.ends_with(".law"))),
        "fields no valid change was found for: {fixed_by_model:?}"
    );
    for must in [
        "extensions",
        "solver.ftol",
        "solver.jacobian",
        "solver.geodesic",
        "data_hash",
        "model",
        "sweep.starts",
        "sweep.seed",
        "constants.A.lb",
        "constants.A.held",
        "T_ref",
        "objective.kind",
        "objective.lifetime_sd_floor",
        "objective.max_points",
        "objective.w_grid",
        "objective.w_sets",
    ] {
        assert!(
            tested.iter().any(|t| t == must),
            "{must} not tested: {tested:?}"
        );
    }
    eprintln!("{} fields tested: {}", tested.len(), tested.join(", "));

    // The fields that do not change results do not make a resume refuse.
    let mut same = cfg.clone();
    same.name = "another-name".into();
    same.run.threads = Some(1);
    same.run.progress = true;
    same.curves = PathBuf::from("moved/elsewhere.csv");
    let (_, run) = run_sweep(&same, &data).expect("excluded fields change nothing");
    assert_eq!(run.computed, 0);
}
