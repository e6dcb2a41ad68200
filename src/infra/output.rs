//! Writing into an output folder safely: one writer per folder (an advisory lock), and every
//! file replaced atomically (a temporary file in the same folder, flushed to disk, renamed
//! over the old one), so that an interruption or a full disk leaves the old file or none,
//! never a truncated one.
//!
//! **Lock.** `LOCK_FILE` in the output folder, locked with the standard library's
//! [`std::fs::File::try_lock`] (an OS advisory lock: `flock` on Unix, `LockFileEx` on
//! Windows), which the OS releases when the holder exits, however it exits: a lock left by
//! a killed run is no obstacle. The holder writes its pid into the file so that a refused
//! second writer can name it. The file itself stays (removing it would race with a waiting
//! writer); it is empty of meaning without the lock.
//!
//! **Run folders and their manifest.** A command takes its output folder over with
//! [`RunFolder::begin`] (or [`RunFolder::take_over`] after checks of its own under the lock):
//! the files the previous run's `manifest.json` lists are removed (except those the command
//! resumes from, e.g. a sweep's journal), and a manifest saying `"complete": false` is
//! written before anything else. Every file this module renames into place inside the folder
//! ([`persist`], [`write_atomic`]) or that the command adopts ([`record`]) is recorded;
//! [`RunFolder::finish`] writes the manifest last, with the files, the command line and
//! whether the run completed. A run that fails (or is killed) leaves a manifest saying
//! `"complete": false`. Files that no manifest lists (put there by hand, or by a creepfit
//! version without manifests) are left alone and named in `other_files`.
//!
//! **Fault injection for tests.** When the environment variable [`WRITE_BUDGET_ENV`] holds a
//! number of bytes, writes through this module fail with "no space left on device" once that
//! many bytes have been written in the process: the fallback of the full-disk test where a
//! small tmpfs cannot be mounted.

use std::collections::BTreeSet;
use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};

use serde_json::{json, Value};

use tempfile::NamedTempFile;

use crate::error::{Error, Result};

/// Name of the lock file in an output folder.
pub const LOCK_FILE: &str = ".creepfit.lock";

/// Environment variable of the test-only write budget (bytes), see the module docs.
pub const WRITE_BUDGET_ENV: &str = "CREEPFIT_TEST_WRITE_BUDGET";

fn budget() -> &'static AtomicI64 {
    static BUDGET: OnceLock<AtomicI64> = OnceLock::new();
    BUDGET.get_or_init(|| {
        let b = std::env::var(WRITE_BUDGET_ENV)
            .ok()
            .and_then(|v| v.trim().parse::<i64>().ok())
            .unwrap_or(i64::MAX);
        AtomicI64::new(b)
    })
}

/// Take `n` bytes from the test write budget; an error once it is spent.
pub fn charge(n: usize) -> io::Result<()> {
    let b = budget();
    if b.load(Ordering::Relaxed) == i64::MAX {
        return Ok(());
    }
    if b.fetch_sub(n as i64, Ordering::SeqCst) < n as i64 {
        return Err(io::Error::new(
            io::ErrorKind::StorageFull,
            "no space left on device (injected by CREEPFIT_TEST_WRITE_BUDGET)",
        ));
    }
    Ok(())
}

/// A writer that charges the test write budget.
struct Budgeted<W: Write>(W);

impl<W: Write> Write for Budgeted<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        charge(buf.len())?;
        self.0.write(buf)
    }
    fn flush(&mut self) -> io::Result<()> {
        self.0.flush()
    }
}

/// A temporary file beside `path` (same folder, so that the rename is atomic), named
/// `.<file name>.<random><suffix>`; removed again unless persisted.
pub fn temp_beside(path: &Path, suffix: &str) -> Result<NamedTempFile> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let prefix = format!(
        ".{}.",
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let mut b = tempfile::Builder::new();
    b.prefix(&prefix).suffix(suffix);
    // The permissions a plain File::create gives (0o666 less the umask), not tempfile's
    // private 0o600: the outputs are for everyone who may read the folder.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666));
    }
    b.tempfile_in(dir).map_err(|e| Error::io(path, e))
}

/// Flush `tmp` to disk and rename it over `path`; the file is recorded as written by the
/// run that owns its folder, if one does ([`record`]).
pub fn persist(tmp: NamedTempFile, path: &Path) -> Result<()> {
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    record(path);
    Ok(())
}

/// Write `path` atomically: `fill` writes the content into a temporary file beside it, which
/// is flushed to disk and renamed into place only if everything succeeded.
pub fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> io::Result<()>,
) -> Result<()> {
    let tmp = temp_beside(path, ".tmp")?;
    {
        let mut w = BufWriter::new(Budgeted(tmp.as_file()));
        fill(&mut w)
            .and_then(|_| w.flush())
            .map_err(|e| Error::io(path, e))?;
    }
    persist(tmp, path)
}

/// The exclusive write lock of an output folder, held until dropped.
#[derive(Debug)]
pub struct FolderLock {
    _file: File,
    path: PathBuf,
}

impl FolderLock {
    /// The lock file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// Create `dir` if needed and take its write lock, or fail at once with a one-line error
/// naming the holder's pid.
pub fn lock_folder(dir: &Path) -> Result<FolderLock> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let path = dir.join(LOCK_FILE);
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|e| Error::io(&path, e))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut text = String::new();
            let _ = file.read_to_string(&mut text);
            let holder = match text.trim().parse::<u32>() {
                Ok(pid) => format!("pid {pid}"),
                Err(_) => "a process that has not yet written its pid".to_string(),
            };
            return Err(Error::Folder {
                path: dir.to_path_buf(),
                message: format!(
                    "another creepfit run ({holder}) is writing into this folder; wait for it to end or use another --out"
                ),
            });
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(&path, e)),
    }
    let pid = format!("{}\n", std::process::id());
    file.set_len(0)
        .and_then(|_| file.rewind())
        .and_then(|_| file.write_all(pid.as_bytes()))
        .and_then(|_| file.flush())
        .map_err(|e| Error::io(&path, e))?;
    Ok(FolderLock { _file: file, path })
}

/// Name of the manifest of a run folder.
pub const MANIFEST_FILE: &str = "manifest.json";

/// The folders taken over by runs of this process, with the files written into each.
struct Active {
    id: u64,
    dir: PathBuf,
    files: BTreeSet<String>,
}

fn active() -> &'static Mutex<Vec<Active>> {
    static ACTIVE: OnceLock<Mutex<Vec<Active>>> = OnceLock::new();
    ACTIVE.get_or_init(|| Mutex::new(Vec::new()))
}

/// `path` relative to `dir`, as `/`-separated text, if it lies inside it.
fn relative(dir: &Path, path: &Path) -> Option<String> {
    let rel = path.strip_prefix(dir).ok()?;
    let parts: Vec<String> = rel
        .components()
        .map(|c| match c {
            std::path::Component::Normal(p) => Some(p.to_string_lossy().into_owned()),
            _ => None,
        })
        .collect::<Option<_>>()?;
    (!parts.is_empty()).then(|| parts.join("/"))
}

/// Record `path` as written by the run whose folder holds it (the innermost such folder):
/// it goes into that run's manifest. A path outside every run folder is ignored.
pub fn record(path: &Path) {
    let mut a = active().lock().unwrap_or_else(|e| e.into_inner());
    let best = a
        .iter_mut()
        .filter_map(|r| relative(&r.dir, path).map(|rel| (r, rel)))
        .max_by_key(|(r, _)| r.dir.components().count());
    if let Some((r, rel)) = best {
        if rel != MANIFEST_FILE {
            r.files.insert(rel);
        }
    }
}

/// A relative path from a manifest that stays inside the folder (no `..`, not absolute).
fn inside(rel: &str) -> bool {
    !rel.is_empty()
        && Path::new(rel)
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)))
}

/// Files of the folder (relative, `/`-separated), recursively, without hidden files (the
/// lock, temporaries), the manifest, and sub-folders that hold a manifest of their own (the
/// folders of other runs, e.g. a sweep's shards).
fn folder_files(dir: &Path) -> Vec<String> {
    fn walk(root: &Path, d: &Path, out: &mut Vec<String>) {
        let Ok(rd) = std::fs::read_dir(d) else {
            return;
        };
        for e in rd.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let Ok(ft) = e.file_type() else { continue };
            if ft.is_dir() {
                if !p.join(MANIFEST_FILE).exists() {
                    walk(root, &p, out);
                }
            } else if let Some(rel) = relative(root, &p) {
                if rel != MANIFEST_FILE {
                    out.push(rel);
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// The files a manifest in `dir` lists (empty without one, or for one that does not parse).
pub fn manifest_files(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join(MANIFEST_FILE))
        .ok()
        .and_then(|t| serde_json::from_str::<Value>(&t).ok())
        .and_then(|v| {
            v.get("files").and_then(Value::as_array).map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(str::to_string))
                    .collect()
            })
        })
        .unwrap_or_default()
}

/// An output folder owned by one run: locked, emptied of the previous run's files, and
/// described by `manifest.json` (see the module docs). Dropping it without
/// [`RunFolder::finish`] writes the manifest as incomplete (best effort).
#[derive(Debug)]
pub struct RunFolder {
    id: u64,
    dir: PathBuf,
    _lock: FolderLock,
    command: String,
    argv: Vec<String>,
    started_unix_s: f64,
    removed: Vec<String>,
    notes: serde_json::Map<String, Value>,
    finished: bool,
}

fn unix_now() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

impl RunFolder {
    /// Lock `dir` (created if needed) and take it over for a run of `command`
    /// ([`RunFolder::take_over`], nothing kept).
    pub fn begin(dir: &Path, command: &str) -> Result<RunFolder> {
        let lock = lock_folder(dir)?;
        Self::take_over(lock, command, &|_| false)
    }

    /// Take over the folder of `lock` for a run of `command`: write a manifest saying the
    /// run is incomplete, then remove the files the previous run's manifest lists, except
    /// those `keep` accepts (what the run resumes from); kept files that still exist count
    /// as this run's. Fails, removing nothing, if the manifest cannot be written.
    pub fn take_over(
        lock: FolderLock,
        command: &str,
        keep: &dyn Fn(&str) -> bool,
    ) -> Result<RunFolder> {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        let dir = lock
            .path()
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let previous = manifest_files(&dir);
        let id = NEXT.fetch_add(1, Ordering::SeqCst);
        let mut run = RunFolder {
            id,
            dir: dir.clone(),
            _lock: lock,
            command: command.to_string(),
            argv: std::env::args().collect(),
            started_unix_s: unix_now(),
            removed: Vec::new(),
            notes: serde_json::Map::new(),
            finished: false,
        };
        let kept: BTreeSet<String> = previous
            .iter()
            .filter(|f| inside(f) && keep(f) && dir.join(f).exists())
            .cloned()
            .collect();
        active()
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(Active {
                id,
                dir: dir.clone(),
                files: kept,
            });
        // The manifest first: a failure here leaves the previous run's files and manifest.
        run.write_manifest(false, Some("the run has not finished"))?;
        for f in previous
            .iter()
            .filter(|f| inside(f) && !keep(f) && *f != MANIFEST_FILE && *f != LOCK_FILE)
        {
            let p = dir.join(f);
            // Only files (a manifest edited by hand may name a folder: left alone).
            if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_dir()) {
                continue;
            }
            match std::fs::remove_file(&p) {
                Ok(()) => run.removed.push(f.clone()),
                Err(e) if e.kind() == io::ErrorKind::NotFound => {}
                Err(e) => return Err(Error::io(&p, e)),
            }
            // Folders the removal left empty go too (a battery's set folders).
            let mut d = p.parent();
            while let Some(x) = d.filter(|x| *x != dir.as_path()) {
                if std::fs::remove_dir(x).is_err() {
                    break;
                }
                d = x.parent();
            }
        }
        Ok(run)
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Add `key` to the manifest (e.g. the data points the run dropped).
    pub fn note(&mut self, key: &str, value: Value) {
        self.notes.insert(key.to_string(), value);
    }

    /// The files written so far, sorted.
    pub fn files(&self) -> Vec<String> {
        active()
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .find(|a| a.id == self.id)
            .map(|a| a.files.iter().cloned().collect())
            .unwrap_or_default()
    }

    fn write_manifest(&self, complete: bool, error: Option<&str>) -> Result<()> {
        let files = self.files();
        let listed: BTreeSet<&String> = files.iter().collect();
        let other: Vec<String> = folder_files(&self.dir)
            .into_iter()
            .filter(|f| !listed.contains(f))
            .collect();
        let mut m = json!({
            "command": self.command,
            "argv": self.argv,
            "creepfit_version": env!("CARGO_PKG_VERSION"),
            "complete": complete,
            "error": error,
            "started_unix_s": self.started_unix_s,
            "written_unix_s": unix_now(),
            "files": files,
            "removed": self.removed,
            "other_files": other,
        });
        for (k, v) in &self.notes {
            m[k] = v.clone();
        }
        let text = serde_json::to_string_pretty(&m).expect("JSON of plain values");
        write_atomic(&self.dir.join(MANIFEST_FILE), |w| {
            w.write_all(text.as_bytes())?;
            w.write_all(b"\n")
        })
    }

    /// End the run with `outcome`: the manifest, written last, says whether it completed (an
    /// `Err`, a plot that failed included, is incomplete, with its message). A manifest that
    /// cannot be written fails a run that had succeeded.
    pub fn finish<T>(mut self, outcome: Result<T>) -> Result<T> {
        self.finished = true;
        let written = match &outcome {
            Ok(_) => self.write_manifest(true, None),
            Err(e) => self.write_manifest(false, Some(&e.to_string())),
        };
        match (outcome, written) {
            (Ok(v), Ok(())) => Ok(v),
            (Ok(_), Err(e)) => Err(e),
            (Err(e), _) => Err(e),
        }
    }
}

impl Drop for RunFolder {
    fn drop(&mut self) {
        if !self.finished {
            let _ = self.write_manifest(false, Some("the run ended before it finished"));
        }
        active()
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|a| a.id != self.id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_or_keeps_the_old_file() {
        let d = tempfile::TempDir::new().unwrap();
        let p = d.path().join("a.csv");
        write_atomic(&p, |w| w.write_all(b"old\n")).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old\n");
        // A failure in the middle of writing keeps the old file and leaves no temporary.
        let e = write_atomic(&p, |w| {
            w.write_all(b"new, half")?;
            Err(io::Error::other("disk gone"))
        })
        .unwrap_err();
        assert!(e.to_string().contains("disk gone"), "{e}");
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old\n");
        let names: Vec<_> = std::fs::read_dir(d.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "a temporary file was left: {names:?}");
        write_atomic(&p, |w| w.write_all(b"new\n")).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new\n");
        // Same permissions as a file created the ordinary way.
        let plain = d.path().join("plain");
        File::create(&plain).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions();
        assert_eq!(mode(&p), mode(&plain));
    }

    fn manifest_of(dir: &Path) -> Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(MANIFEST_FILE)).unwrap()).unwrap()
    }

    #[test]
    fn a_run_folder_lists_its_files_and_removes_the_previous_runs() {
        let d = tempfile::TempDir::new().unwrap();
        let dir = d.path().join("out");
        // First run: two files, one in a sub-folder; complete.
        let run = RunFolder::begin(&dir, "first").unwrap();
        write_atomic(&dir.join("a.csv"), |w| w.write_all(b"a")).unwrap();
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        write_atomic(&dir.join("sub/b.csv"), |w| w.write_all(b"b")).unwrap();
        // A file outside the folder is not this run's.
        write_atomic(&d.path().join("outside.csv"), |w| w.write_all(b"x")).unwrap();
        run.finish(Ok(())).unwrap();
        let m = manifest_of(&dir);
        assert_eq!(m["complete"], true);
        assert_eq!(m["command"], "first");
        assert_eq!(m["files"], json!(["a.csv", "sub/b.csv"]));
        // A file put there by hand, and a manifest entry that would leave the folder.
        std::fs::write(dir.join("mine.txt"), "mine").unwrap();
        let mut m2 = m.clone();
        m2["files"] = json!([
            "a.csv",
            "sub/b.csv",
            "../outside.csv",
            "/etc/hostname",
            "manifest.json",
            ".creepfit.lock",
            "sub"
        ]);
        std::fs::write(dir.join(MANIFEST_FILE), m2.to_string()).unwrap();
        // Second run: keeps a.csv (what it resumes from), writes c.csv, fails.
        let run =
            RunFolder::take_over(lock_folder(&dir).unwrap(), "second", &|f| f == "a.csv").unwrap();
        assert!(
            !dir.join("sub").exists(),
            "sub/b.csv and its emptied folder are removed"
        );
        assert!(
            d.path().join("outside.csv").exists(),
            "never outside the folder"
        );
        assert!(
            dir.join("mine.txt").exists(),
            "a file no manifest lists stays"
        );
        let m = manifest_of(&dir);
        assert_eq!(m["complete"], false, "incomplete until finished: {m}");
        write_atomic(&dir.join("c.csv"), |w| w.write_all(b"c")).unwrap();
        let e = run
            .finish::<()>(Err(Error::Invalid("it went wrong".into())))
            .unwrap_err();
        assert_eq!(e.to_string(), "it went wrong");
        let m = manifest_of(&dir);
        assert_eq!(m["complete"], false);
        assert_eq!(m["error"], "it went wrong");
        assert_eq!(m["files"], json!(["a.csv", "c.csv"]));
        assert_eq!(m["removed"], json!(["sub/b.csv"]));
        assert_eq!(m["other_files"], json!(["mine.txt"]));
        // A run dropped without finishing (an early return) leaves it incomplete too.
        {
            let _run = RunFolder::begin(&dir, "third").unwrap();
            write_atomic(&dir.join("d.csv"), |w| w.write_all(b"d")).unwrap();
        }
        let m = manifest_of(&dir);
        assert_eq!(
            (m["complete"].clone(), m["command"].clone()),
            (json!(false), json!("third"))
        );
        assert_eq!(m["files"], json!(["d.csv"]));
        assert!(!dir.join("c.csv").exists() && !dir.join("a.csv").exists());
    }

    #[test]
    fn second_lock_is_refused_with_the_pid_and_released_on_drop() {
        let d = tempfile::TempDir::new().unwrap();
        let l = lock_folder(d.path()).unwrap();
        let e = lock_folder(d.path()).unwrap_err().to_string();
        assert!(
            e.contains(&format!("pid {}", std::process::id())),
            "the holder's pid is named: {e}"
        );
        assert!(!e.contains('\n'));
        drop(l);
        lock_folder(d.path()).expect("free again once the holder is gone");
    }
}
