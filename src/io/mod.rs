//! Reading and writing the records the command line works on.
//!
//! A record is a header line of column names followed by rows of numbers separated by `,`,
//! `;` or tabs (detected from the header, or given), read by the `csv` crate; or a NumPy
//! `.npy` array (the `npy` module), chosen by the file's extension ([`read_record`]).
//! Every error names the file, and where it applies the column, the row (1-based, counting the
//! header as row 1, as a spreadsheet does) and the offending text.

use std::io::{BufRead, Seek};
use std::path::{Path, PathBuf};

/// Errors of reading or writing records.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be opened, read or written.
    #[error("{path}: {source}")]
    File {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The file has no header line.
    #[error("{path}: the file is empty (no header line)")]
    NoHeader {
        /// The file.
        path: PathBuf,
    },
    /// A requested column is not in the header.
    #[error("{path}: no column `{column}` (the header has: {available})")]
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column asked for.
        column: String,
        /// The columns the header names, comma-separated.
        available: String,
    },
    /// A cell is not a number.
    #[error("{path}: row {row}, column `{column}`: `{text}` is not a number")]
    NotANumber {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// Column name.
        column: String,
        /// The cell's text.
        text: String,
    },
    /// A cell is NaN or infinite.
    #[error("{path}: row {row}, column `{column}`: value {value} is not finite")]
    NonFinite {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// Column name.
        column: String,
        /// The value.
        value: f64,
    },
    /// A row has fewer or more cells than the header names columns.
    #[error("{path}: row {row} has {found} cells, the header has {expected}")]
    CellCount {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// Cells found.
        found: usize,
        /// Cells expected.
        expected: usize,
    },
    /// The header names one column twice (a column asked for by name would be ambiguous).
    #[error("{path}: the header names column `{column}` twice")]
    DuplicateColumn {
        /// The file.
        path: PathBuf,
        /// The repeated name.
        column: String,
    },
    /// The file is not well-formed delimited text (a quote left open, bytes that are not
    /// UTF-8).
    #[error("{path}: row {row}: {what}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        row: usize,
        /// What the CSV reader found.
        what: String,
    },
    /// A parameters file that is not an oscillator in the schema.
    #[error("{path}: {what}")]
    Params {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the key.
        what: String,
    },
    /// Columns of different lengths given to be written side by side.
    #[error("{path}: columns {names} have lengths {lengths:?}; a table needs them equal")]
    UnequalColumns {
        /// The file.
        path: PathBuf,
        /// The columns' names.
        names: String,
        /// Their lengths.
        lengths: Vec<usize>,
    },
    /// The file has a header but no data rows.
    #[error("{path}: the record is empty (a header but no rows)")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// A `.npy` file that is not a record: not NumPy's format, a dtype other than float64 or
    /// float32, a shape other than (samples,) or (samples, channels), data missing.
    #[error("{path}: {what}")]
    Npy {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

mod npy;
pub use npy::read_npy;

/// The record at `path`: a NumPy `.npy` array when its extension says so ([`read_npy`]), else
/// delimited text with `delimiter` ([`read_csv_with`]).
pub fn read_record(path: &Path, delimiter: Delimiter) -> Result<Table, IoError> {
    let npy = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npy"));
    if npy {
        read_npy(path)
    } else {
        read_csv_with(path, delimiter)
    }
}

/// A table of named numeric columns of equal length.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names in file order.
    pub names: Vec<String>,
    /// Columns, each as long as the record.
    pub columns: Vec<Vec<f64>>,
    /// Where the table came from.
    pub path: PathBuf,
}

impl Table {
    /// The column with this name, or an error listing the available ones.
    pub fn column(&self, name: &str) -> Result<&[f64], IoError> {
        match self.names.iter().position(|n| n == name) {
            Some(i) => Ok(&self.columns[i]),
            None => Err(IoError::MissingColumn {
                path: self.path.clone(),
                column: name.to_string(),
                available: self.names.join(","),
            }),
        }
    }

    /// The column with this name taken out of the table (its place left empty), or an error
    /// listing the available ones: for a caller that needs the record once, not a copy.
    pub fn take_column(&mut self, name: &str) -> Result<Vec<f64>, IoError> {
        self.column(name)?;
        let i = self.names.iter().position(|n| n == name).unwrap_or(0);
        Ok(std::mem::take(&mut self.columns[i]))
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The separator between a record's cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Delimiter {
    /// Whichever of `,` `;` and tab the header line uses most (outside quotes); a header with
    /// none of them is one column.
    #[default]
    Auto,
    /// `,`
    Comma,
    /// `;` (where a comma is the decimal mark, `1,5` reads as 1.5)
    Semicolon,
    /// A tab.
    Tab,
}

impl Delimiter {
    fn byte(self) -> Option<u8> {
        match self {
            Delimiter::Auto => None,
            Delimiter::Comma => Some(b','),
            Delimiter::Semicolon => Some(b';'),
            Delimiter::Tab => Some(b'\t'),
        }
    }

    /// The delimiter the header line uses most, outside double quotes.
    fn detect(header: &[u8]) -> u8 {
        let mut counts = [0usize; 3];
        let mut quoted = false;
        for &b in header {
            match b {
                b'"' => quoted = !quoted,
                b',' if !quoted => counts[0] += 1,
                b';' if !quoted => counts[1] += 1,
                b'\t' if !quoted => counts[2] += 1,
                _ => {}
            }
        }
        let best = (0..3).max_by_key(|&i| (counts[i], 3 - i)).unwrap_or(0);
        if counts[best] == 0 {
            b','
        } else {
            [b',', b';', b'\t'][best]
        }
    }
}

/// A cell as a number: a plain float, or with `;` separating cells, a decimal comma.
fn number(text: &str, delimiter: u8) -> Option<f64> {
    text.parse().ok().or_else(|| {
        (delimiter != b',' && text.matches(',').count() == 1)
            .then(|| text.replace(',', ".").parse().ok())
            .flatten()
    })
}

/// [`read_csv_with`] with the delimiter detected.
pub fn read_csv(path: &Path) -> Result<Table, IoError> {
    read_csv_with(path, Delimiter::Auto)
}

/// Read a delimited file with a header line (RFC 4180, by the `csv` crate): cells separated by
/// `delimiter`, any of them quoted, CRLF or LF line ends, a byte-order mark, spaces around the
/// cells; empty lines are skipped. Every row must have one cell per column of the header, and
/// every cell must be a finite number.
pub fn read_csv_with(path: &Path, delimiter: Delimiter) -> Result<Table, IoError> {
    let file_error = |source| IoError::File {
        path: path.to_path_buf(),
        source,
    };
    // The file is read as a stream (the record is kept once, as numbers, not also as text);
    // its first non-blank line is read first to detect the delimiter, then it is read again
    // from its start.
    let file = std::fs::File::open(path).map_err(file_error)?;
    let mut file = std::io::BufReader::with_capacity(1 << 16, file);
    let first_line = first_line(&mut file, path)?;
    file.rewind().map_err(file_error)?;
    // A byte-order mark (spreadsheets write one) would become part of the first name.
    if file
        .fill_buf()
        .map_err(file_error)?
        .starts_with(b"\xEF\xBB\xBF")
    {
        file.consume(3);
    }
    let sep = delimiter
        .byte()
        .unwrap_or_else(|| Delimiter::detect(&first_line));
    let mut reader = csv::ReaderBuilder::new()
        .delimiter(sep)
        .has_headers(false)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(file);
    let mut records = reader.records();
    let csv_error = |e: csv::Error| {
        let row = e.position().map_or(0, |p| p.line() as usize);
        IoError::Malformed {
            path: path.to_path_buf(),
            row,
            what: e.to_string(),
        }
    };
    let header = loop {
        match records.next() {
            None => {
                return Err(IoError::NoHeader {
                    path: path.to_path_buf(),
                });
            }
            Some(r) => {
                let r = r.map_err(csv_error)?;
                if !(r.len() == 1 && r[0].is_empty()) {
                    break r;
                }
            }
        }
    };
    let names: Vec<String> = header.iter().map(str::to_string).collect();
    if let Some(column) = repeated(&names) {
        return Err(IoError::DuplicateColumn {
            path: path.to_path_buf(),
            column: column.to_string(),
        });
    }
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    for r in records {
        let r = r.map_err(csv_error)?;
        let row = r.position().map_or(0, |p| p.line() as usize);
        if r.len() == 1 && r[0].is_empty() {
            continue;
        }
        if r.len() != names.len() {
            return Err(IoError::CellCount {
                path: path.to_path_buf(),
                row,
                found: r.len(),
                expected: names.len(),
            });
        }
        for (c, t) in r.iter().enumerate() {
            let v = number(t, sep).ok_or_else(|| IoError::NotANumber {
                path: path.to_path_buf(),
                row,
                column: names[c].clone(),
                text: t.to_string(),
            })?;
            if !v.is_finite() {
                return Err(IoError::NonFinite {
                    path: path.to_path_buf(),
                    row,
                    column: names[c].clone(),
                    value: v,
                });
            }
            columns[c].push(v);
        }
    }
    if columns.first().is_none_or(Vec::is_empty) {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(Table {
        names,
        columns,
        path: path.to_path_buf(),
    })
}

/// The first line of `file` (read from `path`) that is not blank, or why there is none.
fn first_line(file: &mut impl BufRead, path: &Path) -> Result<Vec<u8>, IoError> {
    let mut line = Vec::new();
    loop {
        line.clear();
        let read = file.read_until(b'\n', &mut line);
        if read.map_err(|source| IoError::File {
            path: path.to_path_buf(),
            source,
        })? == 0
        {
            return Err(IoError::NoHeader {
                path: path.to_path_buf(),
            });
        }
        if !line.iter().all(u8::is_ascii_whitespace) {
            return Ok(line);
        }
    }
}

/// The first name that appears twice in `names`, if any.
pub fn repeated(names: &[String]) -> Option<&str> {
    names
        .iter()
        .enumerate()
        .find(|(i, n)| names[..*i].contains(n))
        .map(|(_, n)| n.as_str())
}

/// Write columns of equal length under a header, comma-separated, numbers with 17
/// significant digits (they read back bit-identical). Columns of different lengths are an
/// error, not a file cut to the shortest.
pub fn write_csv(path: &Path, names: &[&str], columns: &[&[f64]]) -> Result<(), IoError> {
    let lengths: Vec<usize> = columns.iter().map(|c| c.len()).collect();
    if names.len() != columns.len() || lengths.windows(2).any(|w| w[0] != w[1]) {
        return Err(IoError::UnequalColumns {
            path: path.to_path_buf(),
            names: names.join(","),
            lengths,
        });
    }
    let err = |source| IoError::File {
        path: path.to_path_buf(),
        source,
    };
    let csv_err = |e: csv::Error| match e.into_kind() {
        csv::ErrorKind::Io(source) => err(source),
        other => err(std::io::Error::other(format!("{other:?}"))),
    };
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = csv::Writer::from_writer(std::io::BufWriter::new(file));
    w.write_record(names).map_err(csv_err)?;
    let mut row = Vec::with_capacity(columns.len());
    for i in 0..lengths.first().copied().unwrap_or(0) {
        row.clear();
        row.extend(columns.iter().map(|c| format!("{:e}", c[i])));
        w.write_record(&row).map_err(csv_err)?;
    }
    w.flush().map_err(err)
}

/// Read an oscillator from a JSON file in the schema every report writes
/// ([`hyst_model::schema`]). `FILE#/POINTER` reads the model at that JSON pointer inside the
/// file, e.g. `ident.json#/bouc_wen` or `refine.json#/model`.
pub fn read_oscillator(spec: &Path) -> Result<hyst_model::Oscillator, IoError> {
    let text = spec.to_string_lossy();
    let (path, pointer) = match text.rsplit_once("#/") {
        Some((p, ptr)) => (PathBuf::from(p), Some(format!("/{ptr}"))),
        None => (spec.to_path_buf(), None),
    };
    let params = |what: String| IoError::Params {
        path: path.clone(),
        what,
    };
    let body = std::fs::read_to_string(&path).map_err(|source| IoError::File {
        path: path.clone(),
        source,
    })?;
    let value: serde_json::Value =
        serde_json::from_str(&body).map_err(|e| params(format!("not valid JSON: {e}")))?;
    let value = match &pointer {
        None => &value,
        Some(ptr) => value
            .pointer(ptr)
            .ok_or_else(|| params(format!("nothing at `#{ptr}`")))?,
    };
    serde_json::from_value(value.clone()).map_err(|e| params(e.to_string()))
}

/// The folder of the shared data sets: `HYST_DATA_DIR` if set, else `../shared/data` from the
/// current directory, else `../shared/data` beside this source tree. `None` when none exists.
pub fn data_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("HYST_DATA_DIR") {
        return Some(PathBuf::from(d));
    }
    let candidates = [
        PathBuf::from("../shared/data"),
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
    ];
    candidates.into_iter().find(|p| p.is_dir())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path for the test file `name` in this process's temporary folder (the `.npy`
    /// reader's tests write theirs there too).
    pub(super) fn file_path(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hyst-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    fn file(name: &str, text: &str) -> PathBuf {
        let p = file_path(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// What spreadsheets and other tools write reads as the plain file does: a byte-order
    /// mark (invisible in an error, so `--columns y` failed against a header that printed as
    /// `y`), quoted names, CRLF line ends, spaces after the commas.
    #[test]
    fn spreadsheet_exports_read_as_plain_files() {
        let plain = read_csv(&file("plain.csv", "t,y\n0,1.5\n1,-2\n")).unwrap();
        for (name, text) in [
            ("bom.csv", "\u{feff}t,y\n0,1.5\n1,-2\n"),
            ("quoted.csv", "\"t\",\"y\"\n0,1.5\n1,-2\n"),
            ("crlf.csv", "t,y\r\n0,1.5\r\n1,-2\r\n"),
            ("spaces.csv", "t, y\n0, 1.5\n1, -2\n\n"),
        ] {
            let t = read_csv(&file(name, text)).unwrap();
            assert_eq!(t.names, plain.names, "{name}");
            assert_eq!(t.columns, plain.columns, "{name}");
        }
    }

    /// `;` and tab files, quoted numbers, a BOM and CRLF read as the plain file does; a
    /// semicolon file may use a decimal comma.
    #[test]
    fn every_delimiter_and_quoting_reads_alike() {
        let plain = read_csv(&file("plain2.csv", "t,y\n0,1.5\n1,-2\n")).unwrap();
        for (name, text) in [
            ("semi.csv", "t;y\n0;1.5\n1;-2\n"),
            ("semi_decimal_comma.csv", "t;y\n0;1,5\n1;-2\n"),
            ("tab.csv", "t\ty\n0\t1.5\n1\t-2\n"),
            (
                "quoted_numbers.csv",
                "\"t\",\"y\"\n\"0\",\"1.5\"\n\"1\",\"-2\"\n",
            ),
            (
                "all.csv",
                "\u{feff}\"t\";\"y\"\r\n0;\"1,5\"\r\n\r\n1;-2\r\n",
            ),
        ] {
            let t = read_csv(&file(name, text)).unwrap();
            assert_eq!(t.names, plain.names, "{name}");
            assert_eq!(t.columns, plain.columns, "{name}");
        }
        // Given explicitly, a delimiter the file does not use makes one column per line.
        let e = read_csv_with(&file("semi2.csv", "t;y\n0;1.5\n"), Delimiter::Comma).unwrap_err();
        assert!(e.to_string().contains("`0;1.5` is not a number"), "{e}");
        // One column whose name has no separator in it is still a one-column file.
        let t = read_csv(&file("one.csv", "y\n1\n2\n")).unwrap();
        assert_eq!(t.names, ["y"]);
        // A comma-separated file keeps a comma a separator, never a decimal mark.
        let e = read_csv(&file("bad.csv", "t,y\n0,\"1,5\"\n")).unwrap_err();
        assert!(e.to_string().contains("`1,5` is not a number"), "{e}");
    }

    /// Errors name the file, the row and what is wrong.
    #[test]
    fn malformed_files_are_named() {
        let e = read_csv(&file("short_row.csv", "t,y\n0,1\n2\n")).unwrap_err();
        assert!(
            e.to_string()
                .contains("row 3 has 1 cells, the header has 2"),
            "{e}"
        );
        let e = read_csv(&file("nan.csv", "t,y\n0,NaN\n")).unwrap_err();
        assert!(
            e.to_string()
                .contains("row 2, column `y`: value NaN is not finite"),
            "{e}"
        );
        let e = read_csv(&file("bytes.csv", "t,y\n0,1\n")).map(|_| ());
        assert!(e.is_ok());
        std::fs::write(file("latin1.csv", ""), b"t,y\n0,\xff\n").unwrap();
        let e = read_csv(&file_path("latin1.csv")).unwrap_err();
        assert!(e.to_string().contains("latin1.csv: row 2"), "{e}");
        let e = read_csv(&file("blank.csv", "\n \n")).unwrap_err();
        assert!(matches!(e, IoError::NoHeader { .. }), "{e}");
    }

    /// Columns of different lengths are refused, not cut to the shortest.
    #[test]
    fn unequal_columns_are_not_written() {
        let p = file_path("unequal.csv");
        let e = write_csv(&p, &["a", "b"], &[&[1.0, 2.0], &[1.0]]).unwrap_err();
        assert!(e.to_string().contains("lengths [2, 1]"), "{e}");
        write_csv(&p, &["a", "b,c"], &[&[1.0, 0.1], &[2.0, 1e-300]]).unwrap();
        let t = read_csv(&p).unwrap();
        assert_eq!(t.names, ["a", "b,c"]);
        assert_eq!(t.columns, [vec![1.0, 0.1], vec![2.0, 1e-300]]);
    }

    /// Arbitrary bytes never panic the reader.
    mod fuzz {
        use super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(512))]
            #[test]
            fn any_bytes_read_or_fail_cleanly(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
                let p = file_path(&format!("fuzz-{}.csv", std::thread::current().name().unwrap_or("t").replace("::", "_")));
                std::fs::write(&p, &bytes).unwrap();
                if let Ok(t) = read_csv(&p) {
                    prop_assert!(t.columns.iter().all(|c| c.len() == t.len()));
                    prop_assert!(t.columns.iter().flatten().all(|v| v.is_finite()));
                }
            }
        }
    }
}
