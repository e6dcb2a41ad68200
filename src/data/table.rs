//! A CSV data file read into memory, its header mapped to columns, and each record with its
//! physical line in the file.
//!
//! The csv crate's record positions count neither the blank lines it skips before a record
//! nor, after a `\r\n` ending, the `\n`; a record after blank lines gets the line number
//! of the first blank line. Every line number given here is instead counted from the
//! record's byte offset over the file's own bytes, so an error names the line an editor
//! shows (quoted multi-line cells, blank lines and `\r\n` endings included).

use std::collections::HashMap;
use std::io::{IsTerminal, Read};
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};

use crate::error::{Error, Result};

/// Files at least this large (bytes) show a progress line on stderr while they load, when
/// stderr is a terminal.
pub const PROGRESS_MIN_BYTES: u64 = 16 << 20;

/// Read a whole file; a progress bar on stderr for a large file when stderr is a terminal.
pub(crate) fn read_file(path: &Path) -> Result<(Vec<u8>, Option<ProgressBar>)> {
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::with_capacity(len as usize + 1);
    let progress = (len >= PROGRESS_MIN_BYTES && std::io::stderr().is_terminal()).then(|| {
        let pb = ProgressBar::new(2 * len);
        pb.set_style(
            ProgressStyle::with_template("{msg} [{bar:30}] {percent:>3} % ({elapsed})")
                .expect("valid template")
                .progress_chars("=> "),
        );
        pb.set_message(format!("loading {}", path.display()));
        pb
    });
    match &progress {
        // First half of the bar: reading the bytes; second half: parsing them.
        Some(pb) => pb.wrap_read(&mut file).read_to_end(&mut bytes),
        None => file.read_to_end(&mut bytes),
    }
    .map_err(|e| Error::io(path, e))?;
    Ok((bytes, progress))
}

/// Physical line numbers of byte offsets, counted forward incrementally.
struct Lines<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Lines {
            bytes,
            pos: 0,
            line: 1,
        }
    }

    /// 1-based line of the first byte at or after `byte` that is not a line break (where
    /// the csv reader starts a record after skipping blank lines). A line break is `\n`,
    /// `\r\n` or a lone `\r`.
    fn line_at(&mut self, byte: usize) -> usize {
        let b = self.bytes;
        let mut at = byte.min(b.len());
        while at < b.len() && (b[at] == b'\n' || b[at] == b'\r') {
            at += 1;
        }
        if at < self.pos {
            self.pos = 0;
            self.line = 1;
        }
        for i in self.pos..at {
            match b[i] {
                b'\n' => self.line += 1,
                b'\r' if b.get(i + 1) != Some(&b'\n') => self.line += 1,
                _ => {}
            }
        }
        self.pos = at;
        self.line
    }
}

/// A CSV table over in-memory bytes: header mapped to column indices, records streamed one
/// at a time (memory stays that of the file plus one record).
pub(crate) struct Table<'a> {
    path: &'a Path,
    reader: csv::Reader<&'a [u8]>,
    columns: HashMap<String, usize>,
    lines: Lines<'a>,
    progress: Option<ProgressBar>,
    rows: usize,
}

/// A header that is one field holding another separator (`;`, as spreadsheets write where
/// the decimal mark is a comma, or a tab) is not comma-separated: the words the user needs,
/// appended to the missing-column error; empty otherwise.
fn separator_hint(header: &csv::StringRecord) -> String {
    if header.len() != 1 {
        return String::new();
    }
    let only = header.get(0).unwrap_or("");
    let sep = if only.contains(';') {
        "';'"
    } else if only.contains('\t') {
        "tabs"
    } else {
        return String::new();
    };
    format!(
        "; the header is separated by {sep}: creepfit reads comma-separated files with a decimal point (in a spreadsheet, save as CSV with ',' between fields and '.' as the decimal mark)"
    )
}

impl<'a> Table<'a> {
    /// Parse the header; every name in `required` must be a column. A repeated column name
    /// is an error.
    pub(crate) fn open(
        path: &'a Path,
        bytes: &'a [u8],
        required: &[&str],
        progress: Option<ProgressBar>,
    ) -> Result<Table<'a>> {
        let mut table = Table {
            path,
            reader: csv::ReaderBuilder::new()
                .has_headers(true)
                .flexible(false)
                .trim(csv::Trim::All)
                .from_reader(bytes),
            columns: HashMap::new(),
            lines: Lines::new(bytes),
            progress,
            rows: 0,
        };
        let header = match table.reader.headers() {
            Ok(h) => h.clone(),
            Err(e) => return Err(table.csv_error(e)),
        };
        let header_line = table.lines.line_at(0);
        if header.iter().all(|h| h.is_empty()) {
            return Err(Error::data(
                path,
                header_line,
                format!("no header (it must contain {})", required.join(", ")),
            ));
        }
        for (i, name) in header.iter().enumerate() {
            if table.columns.insert(name.to_string(), i).is_some() && !name.is_empty() {
                return Err(Error::data(
                    path,
                    header_line,
                    format!("column '{name}' appears more than once in the header"),
                ));
            }
        }
        for name in required {
            if !table.columns.contains_key(*name) {
                return Err(Error::data(
                    path,
                    header_line,
                    format!(
                        "missing required column '{name}' (header must contain {}){}",
                        required.join(", "),
                        separator_hint(&header)
                    ),
                ));
            }
        }
        Ok(table)
    }

    /// Read the next record into `rec`; its physical 1-based line, or `None` at the end.
    pub(crate) fn next_row(&mut self, rec: &mut csv::StringRecord) -> Result<Option<usize>> {
        match self.reader.read_record(rec) {
            Ok(true) => {
                let byte = rec.position().map(|p| p.byte() as usize).unwrap_or(0);
                self.rows += 1;
                if let Some(pb) = &self.progress {
                    if self.rows.is_multiple_of(65_536) {
                        pb.set_position(pb.length().unwrap_or(0) / 2 + byte as u64);
                    }
                }
                Ok(Some(self.lines.line_at(byte)))
            }
            Ok(false) => {
                if let Some(pb) = self.progress.take() {
                    pb.finish_and_clear();
                }
                Ok(None)
            }
            Err(e) => Err(self.csv_error(e)),
        }
    }

    /// Index of a column.
    pub(crate) fn col(&self, name: &str) -> Option<usize> {
        self.columns.get(name).copied()
    }

    /// A csv error as a one-line data error at its physical line.
    fn csv_error(&mut self, e: csv::Error) -> Error {
        let line = e
            .position()
            .map(|p| self.lines.line_at(p.byte() as usize))
            .unwrap_or(0);
        let path = self.path;
        match e.into_kind() {
            csv::ErrorKind::Io(io) => Error::io(path, io),
            csv::ErrorKind::UnequalLengths {
                expected_len, len, ..
            } => Error::data(
                path,
                line,
                format!("row has {len} fields, the header has {expected_len}"),
            ),
            csv::ErrorKind::Utf8 { err, .. } => Error::data(
                path,
                line,
                format!("invalid UTF-8 in field {}", err.field() + 1),
            ),
            other => Error::data(path, line, format!("{other:?}").replace('\n', " ")),
        }
    }
}

impl Drop for Table<'_> {
    fn drop(&mut self) {
        if let Some(pb) = self.progress.take() {
            pb.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every record's line as an editor shows it, whatever the csv crate's positions say.
    #[test]
    fn physical_lines() {
        let text = "a,b,c\n1,2,3\n\n\n4,\"x\ny\nz\",6\n7,8,9\r\n\r\n10,11,12\r\r13,14,15\n\
                    16,\"\r\n\",17\n\n\n18,19";
        let path = Path::new("t.csv");
        let mut t = Table::open(path, text.as_bytes(), &["a"], None).unwrap();
        let mut rec = csv::StringRecord::new();
        let mut got = Vec::new();
        let err = loop {
            match t.next_row(&mut rec) {
                Ok(Some(line)) => got.push((rec.get(0).unwrap().to_string(), line)),
                Ok(None) => panic!("the last row is ragged"),
                Err(e) => break e.to_string(),
            }
        };
        let want = [
            ("1", 2),
            ("4", 5),
            ("7", 8),
            ("10", 10),
            ("13", 12),
            ("16", 13),
        ];
        let want: Vec<(String, usize)> = want.iter().map(|(a, l)| (a.to_string(), *l)).collect();
        assert_eq!(got, want);
        assert!(err.starts_with("t.csv:17: row has 2 fields"), "{err}");
    }

    #[test]
    fn header_after_blank_lines_and_errors() {
        let path = Path::new("t.csv");
        let e = Table::open(path, b"\n\na,b\n1,2\n", &["c"], None)
            .err()
            .unwrap()
            .to_string();
        assert!(e.starts_with("t.csv:3: missing required column 'c'"), "{e}");
        let e = Table::open(path, b"a,a\n", &["a"], None)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("t.csv:1: column 'a' appears more than once"),
            "{e}"
        );
        // Another separator is named.
        for (bytes, word) in [
            (&b"a;b\n1,5;2\n"[..], "separated by ';'"),
            (&b"a\tb\n1\t2\n"[..], "separated by tabs"),
        ] {
            let e = Table::open(path, bytes, &["a"], None)
                .err()
                .unwrap()
                .to_string();
            assert!(
                e.starts_with("t.csv:1: missing required column 'a'") && e.contains(word),
                "{e}"
            );
        }
        let e = Table::open(path, b"x,y\n", &["a"], None)
            .err()
            .unwrap()
            .to_string();
        assert!(!e.contains("separated by"), "{e}");
        let e = Table::open(path, b"", &["a"], None)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("no header"), "{e}");
        let mut t = Table::open(path, b"a,b\n\n\n1,\xff\n", &["a"], None).unwrap();
        let e = t
            .next_row(&mut csv::StringRecord::new())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.csv:4: invalid UTF-8 in field 2"), "{e}");
    }
}
