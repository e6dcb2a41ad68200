//! The library's error type: every failure a user can cause (bad files, bad configuration) or
//! meet (a simulation that cannot be carried out) is one variant with a message that names
//! the file, line and field where there is one.

use std::path::PathBuf;

/// All errors crossing the library boundary.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A data file (curves, ruptures, constants) has bad content; `line` is 1-based and
    /// counts the header as line 1. `line == 0` means the whole file.
    #[error("{}{}: {message}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Data {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// The run configuration (TOML) is invalid: `FILE:LINE: field: what` (`line == 0`: no
    /// line is known, e.g. a setting given on the command line).
    #[error("{}{}: {message}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Config {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// A model or extension name that is not registered.
    #[error("unknown model '{0}' (known: {1})")]
    UnknownModel(String, String),
    /// A numerical failure that makes a requested result impossible.
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A plot could not be drawn or written (includes panics caught inside the plotting
    /// library).
    #[error("plot {}: {message}", path.display())]
    Plot { path: PathBuf, message: String },
    /// An output folder that cannot be used: another run holds its lock, or it holds the
    /// results of a different run.
    #[error("{}: {message}", path.display())]
    Folder { path: PathBuf, message: String },
    /// The numeric outputs were written, but plots were not (each failure as `plot PATH: why`).
    #[error("{}: the numeric outputs are written, but {} plot(s) failed: {}", out.display(), failures.len(), failures.join("; "))]
    PlotsNotWritten { out: PathBuf, failures: Vec<String> },
    /// Anything else that is the caller's fault (bad arguments).
    #[error("{0}")]
    Invalid(String),
    /// The diagnosis could not be carried out.
    #[error("diagnose: {0}")]
    Diagnose(String),
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An I/O error tied to the path it happened on.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
    /// A data error at a 1-based line of a file.
    pub fn data(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Data {
            path: path.into(),
            line,
            message: message.into(),
        }
    }
    /// A plotting error for the image at `path`.
    pub fn plot(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Plot {
            path: path.into(),
            message: message.into(),
        }
    }
    /// A configuration error in a file, at no particular line.
    pub fn config(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::config_at(path, 0, message)
    }
    /// A configuration error at a 1-based line of the file (0: no line).
    pub fn config_at(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Config {
            path: path.into(),
            line,
            message: message.into(),
        }
    }
}
