//! Run identity: what makes two runs the same computation, so that a sweep is resumed or
//! merged only with its own results.
//!
//! The identity of a run is the canonical JSON of its `RunConfig` (`crate::config::identity`) (sorted keys, numbers in
//! shortest round-trip form) without the fields of `IDENTITY_EXCLUDED`, together with the
//! crate version (code changes can change results); the sweep adds its drawn start points.
//! Its label is the 64-bit FNV-1a hash of that text. FNV-1a is enough here: the hash is not a
//! security boundary (nobody forges a journal to fool their own sweep), the sweep journal
//! keeps the whole identity text and compares it field by field, and the hash is only its
//! short name (accidental collisions among a user's runs: ~n²/2⁶⁵).

use serde_json::Value;

/// 64-bit FNV-1a of `bytes`.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_from(0xcbf29ce484222325, bytes)
}

/// 64-bit FNV-1a of `bytes` continued from the hash `h`.
pub fn fnv1a_from(mut h: u64, bytes: &[u8]) -> u64 {
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

/// The hash of a JSON value's canonical text, as 16 hex digits.
pub fn hash_value(v: &Value) -> String {
    format!("{:016x}", fnv1a(v.to_string().as_bytes()))
}

/// Whether a JSON value is a leaf of the identity: a scalar, or an array of scalars (a list
/// such as `extensions` or `w_grid` is compared whole).
fn is_leaf(v: &Value) -> bool {
    match v {
        Value::Object(_) => false,
        Value::Array(a) => a.iter().all(|x| !x.is_object() && !x.is_array()),
        _ => true,
    }
}

/// Readable name of array element `i`: `.NAME` when the element is an object with a
/// `name` (the constants), else `[i]`.
fn element_name(e: &Value, i: usize) -> String {
    match e.get("name").and_then(Value::as_str) {
        Some(n) => format!(".{n}"),
        None => format!("[{i}]"),
    }
}

/// JSON pointers of every leaf of `v` (see `is_leaf`), in key order; with the dotted name
/// of each (`solver.ftol`, `constants.A.lb`, `objective.w_sets[0]`).
pub fn leaves(v: &Value) -> Vec<(String, String)> {
    fn walk(v: &Value, ptr: &str, name: &str, out: &mut Vec<(String, String)>) {
        if is_leaf(v) {
            out.push((ptr.to_string(), name.to_string()));
            return;
        }
        match v {
            Value::Object(m) => {
                for (k, x) in m {
                    let n = if name.is_empty() {
                        k.clone()
                    } else {
                        format!("{name}.{k}")
                    };
                    walk(
                        x,
                        &format!("{ptr}/{}", k.replace('~', "~0").replace('/', "~1")),
                        &n,
                        out,
                    );
                }
            }
            Value::Array(a) => {
                for (i, x) in a.iter().enumerate() {
                    walk(
                        x,
                        &format!("{ptr}/{i}"),
                        &format!("{name}{}", element_name(x, i)),
                        out,
                    );
                }
            }
            _ => unreachable!("scalars are leaves"),
        }
    }
    let mut out = Vec::new();
    walk(v, "", "", &mut out);
    out
}

/// The first field (in key order) where `a` and `b` differ: its dotted name and its value
/// in `a` and in `b` (`(absent)` where one side lacks it).
pub fn first_difference(a: &Value, b: &Value) -> Option<(String, String, String)> {
    fn text(v: Option<&Value>) -> String {
        v.map_or_else(|| "(absent)".to_string(), |v| v.to_string())
    }
    fn walk(a: Option<&Value>, b: Option<&Value>, name: &str) -> Option<(String, String, String)> {
        if a == b {
            return None;
        }
        match (a, b) {
            (Some(Value::Object(x)), Some(Value::Object(y))) => {
                let mut keys: Vec<&String> = x.keys().chain(y.keys()).collect();
                keys.sort();
                keys.dedup();
                keys.into_iter().find_map(|k| {
                    let n = if name.is_empty() {
                        k.clone()
                    } else {
                        format!("{name}.{k}")
                    };
                    walk(x.get(k), y.get(k), &n)
                })
            }
            (Some(va @ Value::Array(x)), Some(vb @ Value::Array(y)))
                if !(is_leaf(va) && is_leaf(vb)) && x.len() == y.len() =>
            {
                (0..x.len()).find_map(|i| {
                    walk(
                        Some(&x[i]),
                        Some(&y[i]),
                        &format!("{name}{}", element_name(&x[i], i)),
                    )
                })
            }
            _ => Some((name.to_string(), text(a), text(b))),
        }
    }
    walk(Some(a), Some(b), "")
}

/// Bind the output folder `dir` to a run identity `id`, kept in `dir/file` as
/// `{"fingerprint", "identity"}` (written atomically): a folder without that file takes it;
/// one that holds another identity is refused, naming the first differing field; one that
/// holds `results` (e.g. `results.jsonl`) but no identity file (an earlier creepfit version)
/// is refused too, since nothing says whose results they are. Call it under the folder's
/// lock, before anything in the folder changes.
pub fn bind_folder(
    dir: &std::path::Path,
    file: &str,
    results: &str,
    id: &Value,
) -> crate::Result<()> {
    use crate::error::Error;
    let path = dir.join(file);
    let fingerprint = hash_value(id);
    let refuse = |what: String| Error::Folder {
        path: path.clone(),
        message: format!("this folder holds {what}; use another folder or delete this one"),
    };
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            let held: Value = serde_json::from_str(&text)
                .map_err(|e| Error::data(&path, 0, format!("not a run identity: {e}")))?;
            if held["fingerprint"].as_str() == Some(fingerprint.as_str()) {
                return Ok(());
            }
            let (field, here, asked) = first_difference(&held["identity"], id).unwrap_or((
                "run identity".into(),
                held["fingerprint"].to_string(),
                fingerprint.clone(),
            ));
            Err(refuse(format!(
                "a run with {field} = {here}, this command asks for {asked}"
            )))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let r = dir.join(results);
            if std::fs::metadata(&r).is_ok_and(|m| m.len() > 0) {
                return Err(refuse(format!(
                    "{results} without a run identity ({file}: an earlier creepfit version)"
                )));
            }
            let text = serde_json::to_string_pretty(
                &serde_json::json!({"fingerprint": fingerprint, "identity": id}),
            )
            .expect("JSON of plain values");
            crate::output::write_atomic(&path, |w| {
                w.write_all(text.as_bytes())?;
                w.write_all(b"\n")
            })
        }
        Err(e) => Err(Error::io(&path, e)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_folder_keeps_its_identity() {
        let d = tempfile::TempDir::new().unwrap();
        let a = json!({"command": "battery", "seed": 50001, "version": "x"});
        bind_folder(d.path(), "id.json", "results.jsonl", &a).unwrap();
        bind_folder(d.path(), "id.json", "results.jsonl", &a).expect("the same run again");
        let mut b = a.clone();
        b["seed"] = json!(50002);
        let e = bind_folder(d.path(), "id.json", "results.jsonl", &b)
            .unwrap_err()
            .to_string();
        assert!(e.contains("seed = 50001") && e.contains("50002"), "{e}");
        // Results without an identity (an earlier version) are refused.
        let d2 = tempfile::TempDir::new().unwrap();
        std::fs::write(d2.path().join("results.jsonl"), "{}\n").unwrap();
        let e = bind_folder(d2.path(), "id.json", "results.jsonl", &a)
            .unwrap_err()
            .to_string();
        assert!(e.contains("without a run identity"), "{e}");
        assert!(!d2.path().join("id.json").exists());
    }

    #[test]
    fn first_difference_names_the_field() {
        let a = json!({"solver": {"ftol": 1e-8, "rtol": 1e-8}, "extensions": [],
                        "constants": [{"name": "A", "lb": 1.0}, {"name": "B", "lb": 2.0}]});
        let mut b = a.clone();
        assert_eq!(first_difference(&a, &b), None);
        b["solver"]["ftol"] = json!(1e-10);
        assert_eq!(
            first_difference(&a, &b),
            Some(("solver.ftol".into(), "1e-8".into(), "1e-10".into()))
        );
        let mut c = a.clone();
        c["extensions"] = json!(["constant_load"]);
        assert_eq!(
            first_difference(&a, &c),
            Some((
                "extensions".into(),
                "[]".into(),
                "[\"constant_load\"]".into()
            ))
        );
        let mut d = a.clone();
        d["constants"][1]["lb"] = json!(3.0);
        assert_eq!(first_difference(&a, &d).unwrap().0, "constants.B.lb");
        let names: Vec<String> = leaves(&a).into_iter().map(|l| l.1).collect();
        assert_eq!(
            names,
            [
                "constants.A.lb",
                "constants.A.name",
                "constants.B.lb",
                "constants.B.name",
                "extensions",
                "solver.ftol",
                "solver.rtol"
            ]
        );
    }

    #[test]
    fn fnv1a_reference_values() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a(b""), 0xcbf29ce484222325);
        assert_eq!(fnv1a(b"a"), 0xaf63dc4c8601ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x85944171f73967e8);
    }
}
