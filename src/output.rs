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
//! **Fault injection for tests.** When the environment variable [`WRITE_BUDGET_ENV`] holds a
//! number of bytes, writes through this module fail with "no space left on device" once that
//! many bytes have been written in the process: the fallback of the full-disk test where a
//! small tmpfs cannot be mounted.

use std::fs::{File, OpenOptions};
use std::io::{self, BufWriter, Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::OnceLock;

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

/// Flush `tmp` to disk and rename it over `path`.
pub fn persist(tmp: NamedTempFile, path: &Path) -> Result<()> {
    tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
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
