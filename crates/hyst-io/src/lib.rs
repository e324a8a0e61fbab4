//! Reading and writing the records the command line and the Python package work on.
//!
//! A record is a table of channels sampled together. It is read from
//! - delimited text: a header line of column names, then rows of numbers separated by `,`,
//!   `;` or tabs (detected from the header, or given), read in parallel blocks when plain
//!   (no quotes, LF or CRLF line ends), else by the `csv` crate;
//! - a NumPy `.npy` array, or one array of a `.npz` archive (samples × channels);
//! - one numeric variable of a MATLAB `.mat` file (level 5, the format of `save -v7` and
//!   `scipy.io.savemat`; `-v7.3` files are HDF5 and are refused with that advice);
//! - the Universal File Format's dataset 58 (one function per channel, ASCII or binary 58b),
//!   which also states the sampling rate and each channel's node and direction;
//!
//! chosen by the file's extension or by [`Format`] ([`read_record`]). The identified mode
//! shapes can be written as dataset 55 ([`write_shapes_uff`]; a test's merged modes with its
//! nodes' positions as dataset 15, [`write_merged_shapes_uff`]), and read back with the
//! nodes' positions ([`read_shapes_uff`]). Every error names the file,
//! and where it applies the column, the row (1-based, counting the header as row 1, as a
//! spreadsheet does), the dataset or variable, and the offending text.

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
    /// An output path names a file the command reads: writing it would destroy the input.
    #[error(
        "{output_flag} {path} is the file {input_flag} reads: writing it would overwrite the input; choose another path"
    )]
    OutputIsInput {
        /// The output's flag (`--json`).
        output_flag: String,
        /// The input's flag (`--input`).
        input_flag: String,
        /// The path.
        path: PathBuf,
    },
    /// Two outputs name one file: the second would overwrite the first.
    #[error("{first_flag} and {second_flag} both name {path}: each output needs its own file")]
    OutputsCollide {
        /// The first output's flag.
        first_flag: String,
        /// The second output's flag.
        second_flag: String,
        /// The path.
        path: PathBuf,
    },
    /// The record would take more memory than the machine has free.
    #[error(
        "{path}: reading it takes about {} MB, more than the {} MB of memory free: cut it into shorter records (e.g. `hyst track --input` with --window), or free memory",
        needed / 1_000_000,
        available / 1_000_000
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Bytes its reading needs at least.
        needed: u64,
        /// Bytes of memory free.
        available: u64,
    },
    /// The first line holds numbers only: the file has no header line of names.
    #[error(
        "{path}: the first line `{line}` is numbers, not column names: the file has no header line; add one naming the columns (e.g. `t,y1,y2`), or save the array as .npy"
    )]
    HeaderOfNumbers {
        /// The file.
        path: PathBuf,
        /// The first line, as read.
        line: String,
    },
    /// `--names` (`ReadOptions::names`) does not name every column once.
    #[error(
        "{path}: --names gives {given} name(s) for the file's {columns} column(s): one for each"
    )]
    NamesCount {
        /// The file.
        path: PathBuf,
        /// Names given.
        given: usize,
        /// Columns in the file.
        columns: usize,
    },
    /// `--gains` does not give one finite nonzero factor per channel.
    #[error("--gains: {what}")]
    Gains {
        /// What is wrong, naming the channel.
        what: String,
    },
    /// `--fs` disagrees with the record's time column.
    #[error(
        "{path}: --fs {given} Hz disagrees with the time column `{column}`, whose step is {rate:.6} Hz's: the record is at {rate:.6} Hz (--fs {rate:.6})"
    )]
    RateVsTime {
        /// The file.
        path: PathBuf,
        /// The time column's name.
        column: String,
        /// The rate given (Hz).
        given: f64,
        /// The rate of the time column's mean step (Hz).
        rate: f64,
    },
    /// A name given for the columns (`--names`) is empty.
    #[error("{path}: the names given for its columns (--names) leave column {position} unnamed")]
    EmptyName {
        /// The file.
        path: PathBuf,
        /// The column (from 1).
        position: usize,
    },
    /// A header cell is empty (a table's index written without a name, say).
    #[error(
        "{path}: the header leaves column {position} unnamed (a table's index written without a name?): name it in the file, or give every column's name with --names"
    )]
    UnnamedColumn {
        /// The file.
        path: PathBuf,
        /// The column (from 1).
        position: usize,
    },
    /// The time column's rows are out of order, restart, or miss samples.
    #[error("{path}: the time column `{column}` at row {row} {what}")]
    TimeColumn {
        /// The file.
        path: PathBuf,
        /// The time column's name.
        column: String,
        /// The row (from 1 at the first data row) of the step's later sample.
        row: usize,
        /// What its step does.
        what: String,
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
    /// A JSON document (an oscillator, a fitted structure) that is not what was asked for.
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
    /// A Universal File that is not a record this reader takes: no dataset 58, a function
    /// that is not a time response, complex or unevenly spaced values, channels of different
    /// lengths or rates, data cut short.
    #[error("{path}: {what}")]
    Uff {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the dataset (its place in the file and its first line).
        what: String,
    },
    /// A MATLAB file that is not a level 5 MAT-file, or whose chosen variable is not a real
    /// numeric matrix.
    #[error("{path}: {what}")]
    Mat {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the variable.
        what: String,
    },
    /// A file of several arrays (`.mat`, `.npz`) where the one asked for is missing, or none
    /// was named and more than one could be the record.
    #[error("{path}: {}", variable_message(.asked.as_deref(), .available))]
    Variable {
        /// The file.
        path: PathBuf,
        /// The name asked for, if one was.
        asked: Option<String>,
        /// The arrays the file holds that could be a record, with their shapes.
        available: String,
    },
    /// A 2-D array with more columns than rows: a record is samples × channels, and this one
    /// is most likely channels × samples.
    #[error(
        "{path}: the array is {rows} × {columns}; a record is samples × channels, so this looks transposed (save its transpose)"
    )]
    Transposed {
        /// The file.
        path: PathBuf,
        /// Rows (taken as samples).
        rows: usize,
        /// Columns (taken as channels).
        columns: usize,
    },
    /// No sampling rate: none given and the file states none; or one given that disagrees
    /// with the file's.
    #[error("{path}: {}", rate_message(*.given, *.stated))]
    Rate {
        /// The file.
        path: PathBuf,
        /// The rate given (Hz).
        given: Option<f64>,
        /// The rate the file states (Hz).
        stated: Option<f64>,
    },
    /// A rate given that no record has (zero, negative, not finite).
    #[error("{path}: --fs {given}: a sampling rate is a positive, finite number of hertz")]
    NotARate {
        /// The file it was given for.
        path: PathBuf,
        /// The rate given.
        given: f64,
    },
    /// A format or delimiter named by a name that is not one of them.
    #[error("{what} `{given}` is not one of {}", .allowed.join(", "))]
    UnknownName {
        /// What was named: "format" or "delimiter".
        what: &'static str,
        /// The name given.
        given: String,
        /// The names allowed.
        allowed: &'static [&'static str],
    },
    /// Shapes that do not fit in a dataset 55 of 3-DOF translations.
    #[error("{path}: {what}")]
    ShapesUff {
        /// The file to be written.
        path: PathBuf,
        /// What does not fit.
        what: String,
    },
}

fn rate_message(given: Option<f64>, stated: Option<f64>) -> String {
    match (given, stated) {
        (Some(g), Some(s)) => format!(
            "a sampling rate of {g} Hz was given, but the file states {s} Hz (its sampling interval {:e} s)",
            1.0 / s
        ),
        _ => "the file does not state its sampling rate: give it (`--fs`, or `fs=` in Python)"
            .to_string(),
    }
}

fn variable_message(asked: Option<&str>, available: &str) -> String {
    match asked {
        Some(a) => format!("no array `{a}` (the file holds: {available})"),
        None if available.is_empty() => "no numeric array in the file".to_string(),
        None => format!(
            "the file holds several arrays ({available}); name the record's (`--variable`, or `variable=` in Python)"
        ),
    }
}

mod bulk;
mod covariates;
mod dead;
mod delimited;
mod estimates;
mod geometry;
mod mat;
mod npy;
mod paths;
mod setups;
mod setups_pyoma;
mod shapes_uff;
mod time;
mod uff;
mod uff_shapes;
pub use covariates::{Covariates, list_records, read_covariates};
pub use dead::{Dead, DeadChannel, default_channels};
pub use delimited::{Delimiter, read_csv, read_csv_with, write_csv};
pub use estimates::{EstimatesTable, read_estimates};
pub use geometry::{Geometry, read_geometry, setups_geometry};
pub use mat::read_mat;
pub use npy::{read_npy, read_npz};
pub use paths::check_outputs;
pub use setups::{RecordPaths, SetupSpec, read_setups, read_setups_with};
pub use setups_pyoma::read_pyoma_setups;
pub use shapes_uff::{ShapeMode, write_merged_shapes_uff, write_shapes_uff};
pub use uff::read_uff;
pub use uff_shapes::{UffMode, UffShapes, read_shapes_uff};

/// A record file's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Format {
    /// By the file's extension: `.npy`, `.npz`, `.mat`, `.uff`/`.unv`/`.uf`, anything else
    /// delimited text.
    #[default]
    Auto,
    /// Delimited text with a header line.
    Csv,
    /// A NumPy `.npy` array.
    Npy,
    /// A NumPy `.npz` archive of arrays.
    Npz,
    /// A MATLAB level 5 MAT-file.
    Mat,
    /// A Universal File of dataset 58 functions (ASCII or 58b).
    Uff,
}

impl Format {
    /// Every format's name, as the command line's `--format` and Python's `format=` take it.
    pub const NAMES: &'static [&'static str] = &["auto", "csv", "npy", "npz", "mat", "uff"];

    /// What the format is, in a line (the command line's help).
    pub fn description(self) -> &'static str {
        match self {
            Format::Auto => "by the file's extension",
            Format::Csv => "delimited text with a header line",
            Format::Npy => "a NumPy array (samples × channels)",
            Format::Npz => "a NumPy archive (one array of it)",
            Format::Mat => "a MATLAB level 5 MAT-file (one variable of it)",
            Format::Uff => {
                "a Universal File of dataset 58 functions, ASCII or binary (58b); the rate is the file's"
            }
        }
    }

    /// The format `path`'s extension says (delimited text when it says none of the others).
    pub fn of_path(path: &Path) -> Format {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("npy") => Format::Npy,
            Some("npz") => Format::Npz,
            Some("mat") => Format::Mat,
            Some("uff" | "unv" | "uf") => Format::Uff,
            _ => Format::Csv,
        }
    }
}

impl std::str::FromStr for Format {
    type Err = IoError;

    /// The format of one of [`Format::NAMES`].
    fn from_str(name: &str) -> Result<Self, IoError> {
        Ok(match name {
            "auto" => Format::Auto,
            "csv" => Format::Csv,
            "npy" => Format::Npy,
            "npz" => Format::Npz,
            "mat" => Format::Mat,
            "uff" => Format::Uff,
            _ => {
                return Err(IoError::UnknownName {
                    what: "format",
                    given: name.to_string(),
                    allowed: Format::NAMES,
                });
            }
        })
    }
}

/// How to read a record file: its format, the delimiter of delimited text, the array of a
/// file that holds several.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
#[non_exhaustive]
pub struct ReadOptions {
    /// The file's format (by default, by its extension).
    pub format: Format,
    /// The cell separator of delimited text.
    pub delimiter: Delimiter,
    /// The variable of a `.mat` file or the array of a `.npz` archive; needed when the file
    /// holds more than one that could be the record.
    pub variable: Option<String>,
    /// The columns' names, replacing the file's (a headerless file's `0`, `1`, …): as many
    /// as the file has columns, none twice.
    pub names: Option<Vec<String>>,
}

impl ReadOptions {
    /// These options with the columns' `names`.
    pub fn with_names(mut self, names: Option<Vec<String>>) -> Self {
        self.names = names;
        self
    }
    /// These options with `format`.
    pub fn with_format(mut self, format: Format) -> Self {
        self.format = format;
        self
    }
    /// These options with `delimiter`.
    pub fn with_delimiter(mut self, delimiter: Delimiter) -> Self {
        self.delimiter = delimiter;
        self
    }
    /// These options with the array `variable`.
    pub fn with_variable(mut self, variable: Option<String>) -> Self {
        self.variable = variable;
        self
    }
}

/// Whether `path` is a record [`read_record`] could read, from its first lines (a
/// delimited file: its header and first rows; the binary formats by their name): the error
/// reading it would give, found without reading it all. Used to tell records from the other
/// files of a folder of them (a note, a page).
pub fn probe_record(path: &Path) -> Result<(), IoError> {
    match Format::of_path(path) {
        Format::Csv | Format::Auto => delimited::probe(path, Delimiter::Auto),
        Format::Npy | Format::Npz | Format::Mat | Format::Uff => Ok(()),
    }
}

/// The record at `path`, read as `options` say (see the module's documentation).
pub fn read_record(path: &Path, options: &ReadOptions) -> Result<Table, IoError> {
    let format = match options.format {
        Format::Auto => Format::of_path(path),
        f => f,
    };
    let variable = options.variable.as_deref();
    check_fits_in_memory(path, format)?;
    let mut table = match format {
        Format::Npy => read_npy(path),
        Format::Npz => read_npz(path, variable),
        Format::Mat => read_mat(path, variable),
        Format::Uff => read_uff(path),
        Format::Csv | Format::Auto => {
            delimited::read_csv_named(path, options.delimiter, options.names.is_none())
        }
    }?;
    if let Some(names) = &options.names {
        if names.len() != table.names.len() {
            return Err(IoError::NamesCount {
                path: path.to_path_buf(),
                given: names.len(),
                columns: table.names.len(),
            });
        }
        if let Some(position) = names.iter().position(|n| n.trim().is_empty()) {
            return Err(IoError::EmptyName {
                path: path.to_path_buf(),
                position: position + 1,
            });
        }
        if let Some(column) = repeated(names) {
            return Err(IoError::DuplicateColumn {
                path: path.to_path_buf(),
                column: column.to_string(),
            });
        }
        table.names = names.clone();
        // The names are the user's now: a note that they were generated no longer holds.
        table.notes.retain(|n| !n.contains("no header line"));
    }
    Ok(table)
}

/// Bytes of memory a record read from a file of `bytes` bytes of `format` takes at its peak,
/// at least: a `.npy` file's values are read, then laid out as columns (twice its size); a text
/// file's numbers take about as many bytes as their text (a 17-digit number and its comma,
/// 18 bytes of text, are 8 bytes of double; a short one fewer of text than of double).
fn peak_bytes(bytes: u64, format: Format) -> u64 {
    match format {
        Format::Npy => bytes.saturating_mul(2),
        _ => bytes,
    }
}

/// A record too large for the memory this machine has free is refused before it is read
/// (it was read whole, until the system ran out): Linux's `MemAvailable`; elsewhere no check.
fn check_fits_in_memory(path: &Path, format: Format) -> Result<(), IoError> {
    let Ok(meta) = std::fs::metadata(path) else {
        // The reader says what is wrong with the path.
        return Ok(());
    };
    let available = std::fs::read_to_string("/proc/meminfo").ok().and_then(|t| {
        t.lines()
            .find_map(|l| l.strip_prefix("MemAvailable:"))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| kb * 1024)
    });
    match available {
        Some(free) => fits(path, peak_bytes(meta.len(), format), free),
        None => Ok(()),
    }
}

/// [`check_fits_in_memory`]'s decision: `needed` bytes against `free`.
fn fits(path: &Path, needed: u64, free: u64) -> Result<(), IoError> {
    if needed > free {
        return Err(IoError::TooLarge {
            path: path.to_path_buf(),
            needed,
            available: free,
        });
    }
    Ok(())
}

/// Where a channel was measured: a node of the test geometry and a direction, as the
/// Universal File Format numbers them (0 scalar, ±1 ±2 ±3 translations along X Y Z, ±4 ±5 ±6
/// rotations about them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeasurementPoint {
    /// The node's number.
    pub node: i64,
    /// The direction.
    pub direction: i32,
}

impl std::fmt::Display for MeasurementPoint {
    /// `12+Z`, `3-X`, `7+RY`; a scalar point is its node alone.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let d = self.direction;
        if d == 0 {
            return write!(f, "{}", self.node);
        }
        let sign = if d > 0 { '+' } else { '-' };
        let axis = ["X", "Y", "Z", "RX", "RY", "RZ"]
            .get(d.unsigned_abs() as usize - 1)
            .copied();
        match axis {
            Some(a) => write!(f, "{}{sign}{a}", self.node),
            None => write!(f, "{}:{d}", self.node),
        }
    }
}

/// Fewest samples over which a column's constant step makes it a time column (a short
/// test record of 1, 2, 3 is a response).
pub const TIME_MIN_SAMPLES: usize = 16;

/// A table of named numeric columns of equal length.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names in file order.
    pub names: Vec<String>,
    /// Columns, each as long as the record.
    pub columns: Vec<Vec<f64>>,
    /// Where the table came from.
    pub path: PathBuf,
    /// The sampling rate the file states (Hz), if it states one (a Universal File does).
    pub rate_hz: Option<f64>,
    /// Where each column was measured, if the file says (a Universal File does).
    pub points: Option<Vec<MeasurementPoint>>,
    /// What the reader assumed and a user should hear (a headerless file's generated names).
    pub notes: Vec<String>,
    /// Each column's first cell that is not finite, if it has one: a file may hold NaN in a
    /// column no one analyses, and is refused only when such a column is taken.
    non_finite: Vec<Option<NonFiniteCell>>,
}

/// A cell that is not finite: its row as the file counts it, and its value.
#[derive(Debug, Clone, Copy, PartialEq)]
struct NonFiniteCell {
    pub(crate) row: usize,
    pub(crate) value: f64,
}

impl Table {
    /// A table of `names` and `columns` read from `path`, stating no rate and no points; a
    /// cell that is not finite is kept, and named (by its sample, 1-based) when its column is
    /// taken ([`column`](Self::column), [`take_column`](Self::take_column)).
    pub fn new(path: &Path, names: Vec<String>, columns: Vec<Vec<f64>>) -> Table {
        let non_finite = columns
            .iter()
            .map(|c| {
                c.iter()
                    .position(|v| !v.is_finite())
                    .map(|s| NonFiniteCell {
                        row: s + 1,
                        value: c[s],
                    })
            })
            .collect();
        Table::with_non_finite(path, names, columns, non_finite)
    }

    /// [`new`](Self::new) for a reader that found each column's first cell that is not
    /// finite as it read, by the row the file counts (a CSV's line).
    fn with_non_finite(
        path: &Path,
        names: Vec<String>,
        columns: Vec<Vec<f64>>,
        non_finite: Vec<Option<NonFiniteCell>>,
    ) -> Table {
        Table {
            names,
            columns,
            path: path.to_path_buf(),
            rate_hz: None,
            points: None,
            notes: Vec::new(),
            non_finite,
        }
    }

    /// Column `i` if every cell of it is finite, else its first cell that is not, named by
    /// the file's row and the column's name.
    fn finite(&self, i: usize) -> Result<&[f64], IoError> {
        match self.non_finite.get(i).copied().flatten() {
            Some(cell) => Err(IoError::NonFinite {
                path: self.path.clone(),
                row: cell.row,
                column: self.names[i].clone(),
                value: cell.value,
            }),
            None => Ok(&self.columns[i]),
        }
    }

    /// The column with this name, or an error listing the available ones, or naming the
    /// column's first cell that is not finite.
    pub fn column(&self, name: &str) -> Result<&[f64], IoError> {
        match self.names.iter().position(|n| n == name) {
            Some(i) => self.finite(i),
            None => Err(IoError::MissingColumn {
                path: self.path.clone(),
                column: name.to_string(),
                available: self.names.join(","),
            }),
        }
    }

    /// The column with this name taken out of the table (its place left empty), or the error
    /// [`column`](Self::column) gives: for a caller that needs the record once, not a copy.
    pub fn take_column(&mut self, name: &str) -> Result<Vec<f64>, IoError> {
        self.column(name)?;
        let i = self.names.iter().position(|n| n == name).unwrap_or(0);
        Ok(std::mem::take(&mut self.columns[i]))
    }

    /// The column that holds time, if one does: named so (`t`, `time`, `Time (s)`,
    /// `time_s`, `timestamp`, `zeit`, …, by its name before any unit), or, beside other
    /// columns, increasing by a constant step over at least [`TIME_MIN_SAMPLES`] samples
    /// (every step within 1 % of the mean: no response does that over a record).
    pub fn time_column(&self) -> Option<usize> {
        let named = time::named_time;
        let uniform = |c: &[f64]| {
            let n = c.len();
            if n < TIME_MIN_SAMPLES {
                return false;
            }
            let step = (c[n - 1] - c[0]) / (n - 1) as f64;
            step > 0.0
                && c.windows(2)
                    .all(|w| ((w[1] - w[0]) - step).abs() <= 0.01 * step)
        };
        (0..self.names.len())
            .find(|&i| named(&self.names[i]))
            .or_else(|| {
                (self.columns.len() > 1)
                    .then(|| (0..self.columns.len()).find(|&i| uniform(&self.columns[i])))
                    .flatten()
            })
    }

    /// The sampling rate the time column's mean step gives, with the column's name: when it
    /// increases throughout.
    pub fn time_rate(&self) -> Option<(&str, f64)> {
        self.rate_of_time_column(self.time_column()?)
    }

    /// [`time_rate`](Self::time_rate) of column `i`.
    fn rate_of_time_column(&self, i: usize) -> Option<(&str, f64)> {
        let c = &self.columns[i];
        let n = c.len();
        // A column of sample numbers (0, 1, 2, … as a table's index is written) counts
        // samples, not seconds: it gives no rate, unless its name says it is time.
        if !time::named_time(&self.names[i])
            && c.iter().all(|v| v.fract() == 0.0)
            && c.windows(2).all(|w| w[1] - w[0] == 1.0)
        {
            return None;
        }
        (n >= 2 && c.windows(2).all(|w| w[1] > w[0])).then(|| {
            // Twelve significant digits: a time column written in decimal gives its rate
            // only to rounding (20 Hz read as 19.999999999999996), and two records cut from
            // one must state one rate.
            let rate = (n - 1) as f64 / ((c[n - 1] - c[0]) * time::unit_of(&self.names[i]).0);
            let rounded = format!("{rate:.11e}").parse().unwrap_or(rate);
            (self.names[i].as_str(), rounded)
        })
    }

    /// The sampling rate: the one `given`, which must agree with the file's if the file
    /// states one (within the six significant digits a Universal File writes it with) and
    /// with its time column's mean step if it has one (within 1 %), else the file's, else
    /// the time column's.
    pub fn rate(&self, given: Option<f64>) -> Result<f64, IoError> {
        if let Some(g) = given.filter(|g| !(g.is_finite() && *g > 0.0)) {
            return Err(IoError::NotARate {
                path: self.path.clone(),
                given: g,
            });
        }
        // A time column that checks or gives the rate must be finite throughout.
        let time = self.rate_hz.is_none().then(|| self.time_column()).flatten();
        if let Some(i) = time {
            time::check_steps(&self.path, &self.names[i], self.finite(i)?)?;
        }
        if let Some((column, rate)) = time.and_then(|i| self.rate_of_time_column(i)) {
            return match given {
                Some(g) if (g - rate).abs() > 0.01 * rate => Err(IoError::RateVsTime {
                    path: self.path.clone(),
                    column: column.to_string(),
                    given: g,
                    rate,
                }),
                Some(g) => Ok(g),
                None => Ok(rate),
            };
        }
        match (given, self.rate_hz) {
            (Some(g), Some(s)) if (g - s).abs() > 1e-5 * s => Err(IoError::Rate {
                path: self.path.clone(),
                given,
                stated: self.rate_hz,
            }),
            (Some(g), _) => Ok(g),
            (None, Some(s)) => Ok(s),
            (None, None) => Err(IoError::Rate {
                path: self.path.clone(),
                given,
                stated: None,
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

/// Each channel divided by the factor its reading carries (`gains`, one per channel, in the
/// order of `names`): a sensor mounted the other way (−1) or reading in other units then
/// reads the structure's motion, as a setup file's `gain` does for a setup's channels.
pub fn divide_by_gains(
    names: &[String],
    channels: &mut [Vec<f64>],
    gains: &[f64],
) -> Result<(), IoError> {
    if gains.len() != channels.len() {
        return Err(IoError::Gains {
            what: format!(
                "{} gain(s) for {} channel(s) ({}): one for each",
                gains.len(),
                channels.len(),
                names.join(",")
            ),
        });
    }
    for ((name, c), &g) in names.iter().zip(channels.iter_mut()).zip(gains) {
        if !(g.is_finite() && g != 0.0) {
            return Err(IoError::Gains {
                what: format!("channel `{name}`: gain {g} is not a finite nonzero number"),
            });
        }
        // The setups' bound: a factor that far from 1 is a slip of units, and overflows.
        if !covssi::multisetup::GAIN_DECADES.contains(&g.abs().log10()) {
            return Err(IoError::Gains {
                what: format!(
                    "channel `{name}`: gain {g:e} is more than 12 decades from 1: a sensor's calibration factor so far off is a slip of units"
                ),
            });
        }
        c.iter_mut().for_each(|v| *v /= g);
    }
    Ok(())
}

/// The first name that appears twice in `names`, if any.
pub fn repeated(names: &[String]) -> Option<&str> {
    names
        .iter()
        .enumerate()
        .find(|(i, n)| names[..*i].contains(n))
        .map(|(_, n)| n.as_str())
}

/// Read an oscillator from a JSON file in the schema every report writes
/// ([`hyst_model::schema`]). `FILE#/POINTER` reads the model at that JSON pointer inside the
/// file, e.g. `ident.json#/bouc_wen` or `refine.json#/model`.
pub fn read_oscillator(spec: &Path) -> Result<hyst_model::Oscillator, IoError> {
    read_document(
        spec,
        "the model must be a JSON object of named parameters ({\"mass\": …})",
    )
}

/// Read a value a report wrote (a JSON object; its type refuses keys it does not know) from
/// `FILE` or from the JSON pointer `FILE#/POINTER` inside it. `what` says what the value must
/// be, for the error when it is not an object.
pub fn read_document<T: serde::de::DeserializeOwned>(
    spec: &Path,
    what: &str,
) -> Result<T, IoError> {
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
    // serde reads a struct from an array too, by position: [1, 10, 5e4, …] would silently
    // become its fields in whatever order they are declared.
    if !value.is_object() {
        return Err(params(format!(
            "{what}, not {}",
            match value {
                serde_json::Value::Array(_) => "an array",
                serde_json::Value::String(_) => "a string",
                serde_json::Value::Number(_) => "a number",
                serde_json::Value::Bool(_) => "a boolean",
                _ => "null",
            }
        )));
    }
    serde_json::from_value(value.clone()).map_err(|e| params(e.to_string()))
}

#[cfg(test)]
pub(crate) mod test_files {
    use std::path::PathBuf;

    /// A reader's answer with every column taken: the first error, the reader's or a
    /// column's (a cell that is not finite).
    pub(crate) fn taken(read: Result<super::Table, super::IoError>) -> Result<(), super::IoError> {
        let t = read?;
        t.names.iter().try_for_each(|n| t.column(n).map(|_| ()))
    }

    /// What a reader's table must hold, whatever the file: columns of one length, each
    /// taken finite or refused naming the file, its row and the column.
    pub(crate) fn well_formed(t: &super::Table) -> bool {
        let path = t.path.display().to_string();
        t.columns.iter().all(|c| c.len() == t.len())
            && t.names.iter().all(|n| match t.column(n) {
                Ok(c) => c.iter().all(|v| v.is_finite()),
                Err(e) => {
                    let e = e.to_string();
                    e.starts_with(&path) && e.contains(&format!("column `{n}`"))
                }
            })
    }

    /// A path for the test file `name` in this process's temporary folder (every reader's
    /// tests write theirs there).
    pub(crate) fn file_path(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("hyst-io-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    /// A fuzz case: `bytes` with the bytes at `flips` replaced, cut after `cut` bytes (at
    /// least one kept), and `tail` appended.
    pub(crate) fn mutated(
        mut bytes: Vec<u8>,
        flips: &[(usize, u8)],
        cut: usize,
        tail: &[u8],
    ) -> Vec<u8> {
        for &(at, b) in flips {
            if at < bytes.len() {
                bytes[at] = b;
            }
        }
        bytes.truncate(cut.max(1));
        bytes.extend(tail);
        bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(names: &[&str], columns: Vec<Vec<f64>>) -> Table {
        Table::new(
            Path::new("r.csv"),
            names.iter().map(|n| n.to_string()).collect(),
            columns,
        )
    }

    /// A time column is found by its name (before any unit) or by a constant step, and its
    /// step checks `--fs` (a rate ten times too large is refused) or gives the rate.
    #[test]
    fn a_time_column_is_recognised_and_checks_the_rate() {
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.01).collect();
        let y: Vec<f64> = (0..100).map(|k| (0.3 * k as f64).sin()).collect();
        for name in ["t", "Time (s)", "time_s", "TIME[s]", "Zeit", "timestamp"] {
            let tb = table(&["y", name], vec![y.clone(), t.clone()]);
            assert_eq!(tb.time_column(), Some(1), "{name}");
        }
        // Unnamed, found by its constant step (written with rounding: within 1 %).
        let rounded: Vec<f64> = t.iter().map(|v| (v * 1e4).round() / 1e4 + 1.0).collect();
        let tb = table(&["y", "x"], vec![y.clone(), rounded]);
        assert_eq!(tb.time_column(), Some(1));
        // A response is not a time column; nor is a ramp with a varying step.
        let ramp: Vec<f64> = (0..100).map(|k| (k * k) as f64).collect();
        let tb = table(&["y", "ramp"], vec![y.clone(), ramp]);
        assert_eq!(tb.time_column(), None);
        // A record's only column, or a short one, is a response whatever its values.
        let steps: Vec<f64> = (0..100).map(|k| k as f64).collect();
        assert_eq!(table(&["y"], vec![steps.clone()]).time_column(), None);
        let short = table(&["y", "x"], vec![y[..3].to_vec(), steps[..3].to_vec()]);
        assert_eq!(short.time_column(), None);
        assert!(tb.rate(None).is_err());
        let tb = table(&["Time (s)", "y"], vec![t.clone(), y.clone()]);
        // 99 steps of 0.01 s: 100 Hz.
        assert!((tb.rate(None).unwrap() - 100.0).abs() < 1e-9);
        assert_eq!(tb.rate(Some(100.5)).unwrap(), 100.5);
        let e = tb.rate(Some(1000.0)).unwrap_err();
        assert!(
            e.to_string()
                .contains("--fs 1000 Hz disagrees with the time column `Time (s)`, whose step is 100.000000 Hz's"),
            "{e}"
        );
    }

    /// Issue 77's second pass: a time column in milliseconds read as seconds (every
    /// frequency 1000 times low), a table's index (0, 1, 2, …) taken for seconds at 1 Hz
    /// against the --fs given, a rate of 19.999999999999996 Hz from a decimal column, and
    /// a --fs of NaN accepted.
    #[test]
    fn a_time_column_gives_its_rate_in_its_unit_and_an_index_gives_none() {
        let y: Vec<f64> = (0..100).map(|k| (0.3 * k as f64).sin()).collect();
        let ms: Vec<f64> = (0..100).map(|k| 50.0 * k as f64).collect();
        let tb = table(&["time_ms", "y"], vec![ms, y.clone()]);
        assert_eq!(tb.rate(None).unwrap(), 20.0);
        let index: Vec<f64> = (0..100).map(|k| k as f64).collect();
        let tb = table(&["k", "y"], vec![index.clone(), y.clone()]);
        assert_eq!(tb.time_column(), Some(0), "an index is not a channel");
        assert_eq!(tb.rate(Some(20.0)).unwrap(), 20.0);
        assert!(tb.rate(None).is_err(), "an index states no rate");
        // Named as time, whole seconds are time: 1 Hz.
        let tb = table(&["t", "y"], vec![index, y.clone()]);
        assert_eq!(tb.rate(None).unwrap(), 1.0);
        let decimal: Vec<f64> = (0..6000).map(|k| 0.05 * k as f64).collect();
        let long_y: Vec<f64> = (0..6000).map(|k| (0.3 * k as f64).sin()).collect();
        let tb = table(&["t", "y"], vec![decimal, long_y]);
        assert_eq!(tb.rate(None).unwrap(), 20.0);
        for bad in [f64::NAN, f64::INFINITY, 0.0, -20.0] {
            let e = tb.rate(Some(bad)).unwrap_err().to_string();
            assert!(
                e.contains("a sampling rate is a positive, finite number"),
                "{e}"
            );
        }
    }

    /// Gains divide their channels; a count that differs or a zero gain is refused, named.
    #[test]
    fn gains_divide_their_channels_or_are_refused() {
        let names = vec!["a".to_string(), "b".to_string()];
        let mut c = vec![vec![2.0, -4.0], vec![1.0, 3.0]];
        divide_by_gains(&names, &mut c, &[-1.0, 0.5]).unwrap();
        assert_eq!(c, [vec![-2.0, 4.0], vec![2.0, 6.0]]);
        let e = divide_by_gains(&names, &mut c, &[1.0]).unwrap_err();
        assert!(
            e.to_string().contains("1 gain(s) for 2 channel(s) (a,b)"),
            "{e}"
        );
        let e = divide_by_gains(&names, &mut c, &[1.0, 0.0]).unwrap_err();
        assert!(e.to_string().contains("channel `b`: gain 0 is not"), "{e}");
        // Past twelve decades a gain is a slip of units (1e-300 overflowed into NaN).
        let e = divide_by_gains(&names, &mut c, &[1.0, 1e-300]).unwrap_err();
        assert!(e.to_string().contains("more than 12 decades"), "{e}");
    }

    /// `--names` names every column once, or is refused naming the counts.
    #[test]
    fn names_given_replace_the_files_or_are_refused() {
        let p = test_files::file_path("names.dat");
        std::fs::write(&p, "0.5 1\n0.25 2\n0.125 3\n").unwrap();
        let t = read_record(&p, &ReadOptions::default()).unwrap();
        assert_eq!(t.names, ["0", "1"]);
        assert_eq!(t.notes.len(), 1);
        let named = ReadOptions::default().with_names(Some(vec!["a".into(), "b".into()]));
        let t = read_record(&p, &named).unwrap();
        assert_eq!(
            (t.names.as_slice(), t.notes.len()),
            (&["a".to_string(), "b".to_string()][..], 0)
        );
        assert_eq!(t.columns[0], [0.5, 0.25, 0.125]);
        let three = ReadOptions::default().with_names(Some(vec!["a".into(); 3]));
        let e = read_record(&p, &three).unwrap_err();
        assert!(
            e.to_string()
                .contains("--names gives 3 name(s) for the file's 2 column(s)"),
            "{e}"
        );
        let twice = ReadOptions::default().with_names(Some(vec!["a".into(); 2]));
        assert!(matches!(
            read_record(&p, &twice),
            Err(IoError::DuplicateColumn { .. })
        ));
        let empty = ReadOptions::default().with_names(Some(vec!["a".into(), " ".into()]));
        let e = read_record(&p, &empty).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "names.dat: the names given for its columns (--names) leave column 2 unnamed"
            ),
            "{e}"
        );
    }

    /// A record larger than the free memory is refused naming both sizes; one that fits,
    /// and this machine's real check on a small file, pass.
    #[test]
    fn a_record_beyond_free_memory_is_refused() {
        let p = Path::new("huge.csv");
        let e = fits(p, peak_bytes(30_000_000_000, Format::Csv), 20_000_000_000).unwrap_err();
        assert!(
            e.to_string()
                .contains("huge.csv: reading it takes about 30000 MB, more than the 20000 MB"),
            "{e}"
        );
        assert!(fits(p, peak_bytes(6_000_000_000, Format::Npy), 20_000_000_000).is_ok());
        assert!(fits(p, peak_bytes(12_000_000_000, Format::Npy), 20_000_000_000).is_err());
        let small = test_files::file_path("fits.csv");
        std::fs::write(&small, "y\n1\n2\n").unwrap();
        check_fits_in_memory(&small, Format::Csv).unwrap();
    }

    /// Every listed name reads as a format and a delimiter; an unknown one is an error that
    /// lists them.
    #[test]
    fn names_parse() {
        for name in Format::NAMES {
            assert!(name.parse::<Format>().is_ok(), "{name}");
        }
        for name in Delimiter::NAMES.iter().chain(&[",", ";", "\t"]) {
            assert!(name.parse::<Delimiter>().is_ok(), "{name}");
        }
        assert_eq!("uff".parse::<Format>().ok(), Some(Format::Uff));
        assert_eq!("\t".parse::<Delimiter>().ok(), Some(Delimiter::Tab));
        let e = "xls".parse::<Format>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "format `xls` is not one of auto, csv, npy, npz, mat, uff"
        );
        let e = "|".parse::<Delimiter>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "delimiter `|` is not one of auto, comma, semicolon, tab, spaces"
        );
    }
}
