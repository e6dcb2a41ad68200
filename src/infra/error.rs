//! The library's error type: every failure a user can cause (bad files, bad configuration) or
//! meet (a simulation that cannot be carried out) is one variant with a message that names
//! the file, line and field where there is one.

use std::path::PathBuf;

/// All errors crossing the library boundary.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written. The OS text is part of the message and
    /// deliberately not a `source`: an error chain (`{:#}` in the binary) would print it twice.
    #[error("{}: {err}", path.display())]
    Io { path: PathBuf, err: std::io::Error },
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
    /// A resumable run stopped before it finished (asked to, by `--stop-after`); what it
    /// finished is journaled and a rerun resumes from it.
    #[error("interrupted: {0}")]
    Interrupted(String),
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An I/O error tied to the path it happened on.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            err: source,
        }
    }
    /// A data error at a 1-based line of a file. Line breaks in the message (quoted from a
    /// multi-line cell, say) are shown as `\n`: every error is one line.
    pub fn data(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Data {
            path: path.into(),
            line,
            message: one_line(message.into()),
        }
    }
    /// A plotting error for the image at `path`.
    pub fn plot(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Plot {
            path: path.into(),
            message: message.into(),
        }
    }
    /// A configuration error in a file, at no particular line (one line, as [`Error::data`]).
    pub fn config(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Self::config_at(path, 0, message)
    }
    /// A configuration error at a 1-based line of the file (0: no line).
    pub fn config_at(path: impl Into<PathBuf>, line: usize, message: impl Into<String>) -> Self {
        Error::Config {
            path: path.into(),
            line,
            message: one_line(message.into()),
        }
    }
}

/// `text` with its line breaks escaped (`\n`, `\r`).
fn one_line(text: String) -> String {
    if text.contains(['\n', '\r']) {
        text.replace('\r', "\\r").replace('\n', "\\n")
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The binary prints errors as `{:#}` through anyhow, which appends every `source`.
    #[test]
    fn io_error_text_appears_once() {
        let e = Error::io(
            "/no/such/file.csv",
            std::io::Error::from(std::io::ErrorKind::NotFound),
        );
        let os = std::io::Error::from(std::io::ErrorKind::NotFound).to_string();
        let chain = format!("{:#}", anyhow::Error::from(e));
        assert_eq!(chain.matches(&os).count(), 1, "{chain}");
        assert_eq!(chain, format!("/no/such/file.csv: {os}"));
    }

    #[test]
    fn messages_are_one_line() {
        let e = Error::data(
            "c.csv",
            3,
            "column 'x': cannot parse '1\n2\r\n' as a number",
        );
        assert_eq!(
            e.to_string(),
            "c.csv:3: column 'x': cannot parse '1\\n2\\r\\n' as a number"
        );
        assert!(!Error::config("r.toml", "a\nb").to_string().contains('\n'));
    }
}
