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
/// per column of the header, and every cell must be a finite number.
pub fn read_csv(path: &Path) -> Result<Table, IoError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(IoError::NoHeader {
            path: path.to_path_buf(),
        });
    };
    let names: Vec<String> = header.split(',').map(|s| s.trim().to_string()).collect();
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
