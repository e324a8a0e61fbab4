//! Reading and writing the CSV records the command line works on.
//!
//! A record is a header line of column names followed by rows of numbers separated by commas.
//! Every error names the file, and where it applies the column, the row (1-based, counting the
//! header as row 1, as a spreadsheet does) and the offending text.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Errors of reading or writing CSV records.
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
    /// The header has no comma but another separator: the file is not comma-separated.
    #[error(
        "{path}: the header `{header}` has no comma but {separator}: hyst reads comma-separated values (save the file as CSV with commas)"
    )]
    NotCommaSeparated {
        /// The file.
        path: PathBuf,
        /// The header line.
        header: String,
        /// The separator it seems to use.
        separator: &'static str,
    },
    /// The file has a header but no data rows.
    #[error("{path}: the record is empty (a header but no rows)")]
    Empty {
        /// The file.
        path: PathBuf,
    },
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

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Read a CSV file with a header line. Empty lines are skipped; every row must have one cell
/// per column of the header, and every cell must be a finite number. A byte-order mark, CRLF
/// line ends and double quotes around the names are accepted; a file separated by `;` or tabs
/// is an error that says so.
pub fn read_csv(path: &Path) -> Result<Table, IoError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    // A byte-order mark (spreadsheets write one) would become part of the first name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(IoError::NoHeader {
            path: path.to_path_buf(),
        });
    };
    if !header.contains(',') {
        let separator = if header.contains(';') {
            Some("`;`")
        } else if header.contains('\t') {
            Some("tabs")
        } else {
            None
        };
        if let Some(separator) = separator {
            return Err(IoError::NotCommaSeparated {
                path: path.to_path_buf(),
                header: header.to_string(),
                separator,
            });
        }
    }
    // Names may be quoted ("y"); the quotes are not part of them.
    let names: Vec<String> = header
        .split(',')
        .map(|s| {
            let s = s.trim();
            s.strip_prefix('"')
                .and_then(|q| q.strip_suffix('"'))
                .unwrap_or(s)
                .to_string()
        })
        .collect();
    if let Some(column) = repeated(&names) {
        return Err(IoError::DuplicateColumn {
            path: path.to_path_buf(),
            column: column.to_string(),
        });
    }
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    for (i, line) in lines {
        let row = i + 1;
        let found = line.matches(',').count() + 1;
        if found != names.len() {
            return Err(IoError::CellCount {
                path: path.to_path_buf(),
                row,
                found,
                expected: names.len(),
            });
        }
        for (c, cell) in line.split(',').enumerate() {
            let t = cell.trim();
            let v: f64 = t.parse().map_err(|_| IoError::NotANumber {
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

/// The first name that appears twice in `names`, if any.
pub fn repeated(names: &[String]) -> Option<&str> {
    names
        .iter()
        .enumerate()
        .find(|(i, n)| names[..*i].contains(n))
        .map(|(_, n)| n.as_str())
}

/// Write columns of equal length under a header, numbers with 17 significant digits
/// (they read back bit-identical).
pub fn write_csv(path: &Path, names: &[&str], columns: &[&[f64]]) -> Result<(), IoError> {
    let err = |source| IoError::File {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::create(path).map_err(err)?;
    let mut w = std::io::BufWriter::new(file);
    writeln!(w, "{}", names.join(",")).map_err(err)?;
    let n = columns.iter().map(|c| c.len()).min().unwrap_or(0);
    for i in 0..n {
        let row: Vec<String> = columns.iter().map(|c| format!("{:e}", c[i])).collect();
        writeln!(w, "{}", row.join(",")).map_err(err)?;
    }
    w.flush().map_err(err)
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

    fn file(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hyst-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
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

    /// A file separated by semicolons or tabs is named as such, not as a cell that is not a
    /// number.
    #[test]
    fn another_separator_is_named() {
        for (name, text, sep) in [
            ("semi.csv", "t;y\n0;1.5\n", "`;`"),
            ("tab.csv", "t\ty\n0\t1.5\n", "tabs"),
        ] {
            let e = read_csv(&file(name, text)).unwrap_err();
            assert!(
                matches!(e, IoError::NotCommaSeparated { .. }),
                "{name}: {e}"
            );
            let said = e.to_string();
            assert!(
                said.contains(name) && said.contains(sep) && said.contains("comma-separated"),
                "{said}"
            );
        }
        // One column whose name has no separator in it is still a one-column file.
        let t = read_csv(&file("one.csv", "y\n1\n2\n")).unwrap();
        assert_eq!(t.names, ["y"]);
    }
}
