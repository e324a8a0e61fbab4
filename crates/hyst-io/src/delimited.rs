//! Delimited text records: a header line of column names, then rows of numbers separated by
//! `,`, `;`, tabs or runs of spaces (detected from the header line, or given), read as a
//! stream by the `csv` crate; and the writer of the tables the command line produces.

use std::io::{BufRead, Seek};
use std::path::Path;

use super::{IoError, Table, repeated};

/// The separator between a record's cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Delimiter {
    /// Whichever of `,` `;` and tab the header line uses most (outside quotes); a header with
    /// none of them is split at runs of spaces (a `.dat` file's columns), and one without
    /// spaces either is one column.
    #[default]
    Auto,
    /// `,`
    Comma,
    /// `;` (where a comma is the decimal mark, `1,5` reads as 1.5)
    Semicolon,
    /// A tab.
    Tab,
    /// One or more spaces (leading and trailing ones ignored).
    Spaces,
}

impl Delimiter {
    /// Every delimiter's name, as the command line's `--delimiter` takes it; Python's
    /// `delimiter=` takes the character itself (`","`, `";"`, `"\t"`), which is read too.
    pub const NAMES: &'static [&'static str] = &["auto", "comma", "semicolon", "tab", "spaces"];

    /// What the delimiter is, in a line (the command line's help).
    pub fn description(self) -> &'static str {
        match self {
            Delimiter::Auto => "whichever of `,` `;` tab the header uses most, else runs of spaces",
            Delimiter::Comma => "`,`",
            Delimiter::Semicolon => "`;` (a decimal comma is read too)",
            Delimiter::Tab => "a tab",
            Delimiter::Spaces => "one or more spaces",
        }
    }

    fn byte(self) -> Option<u8> {
        match self {
            Delimiter::Auto => None,
            Delimiter::Comma => Some(b','),
            Delimiter::Semicolon => Some(b';'),
            Delimiter::Tab => Some(b'\t'),
            Delimiter::Spaces => Some(b' '),
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
            // Names separated by spaces only: a `.dat` file's columns.
            let text = String::from_utf8_lossy(header);
            if text.split_whitespace().count() > 1 {
                b' '
            } else {
                b','
            }
        } else {
            [b',', b';', b'\t'][best]
        }
    }
}

impl std::str::FromStr for Delimiter {
    type Err = IoError;

    /// The delimiter of one of [`Delimiter::NAMES`], or of its character.
    fn from_str(name: &str) -> Result<Self, IoError> {
        Ok(match name {
            "auto" => Delimiter::Auto,
            "comma" | "," => Delimiter::Comma,
            "semicolon" | ";" => Delimiter::Semicolon,
            "tab" | "\t" => Delimiter::Tab,
            "spaces" | " " => Delimiter::Spaces,
            _ => {
                return Err(IoError::UnknownName {
                    what: "delimiter",
                    given: name.to_string(),
                    allowed: Delimiter::NAMES,
                });
            }
        })
    }
}

/// A cell as a number: a plain float, or with `;` separating cells, a decimal comma.
pub(super) fn number(text: &str, delimiter: u8) -> Option<f64> {
    text.parse().ok().or_else(|| {
        (delimiter != b',' && text.matches(',').count() == 1)
            .then(|| text.replace(',', ".").parse().ok())
            .flatten()
    })
}

/// Cell `text` of `row` in `column` as a number, or the error naming it.
fn cell(path: &Path, (row, column): (usize, &str), text: &str, sep: u8) -> Result<f64, IoError> {
    number(text, sep).ok_or_else(|| IoError::NotANumber {
        path: path.to_path_buf(),
        row,
        column: column.to_string(),
        text: text.to_string(),
    })
}

/// [`read_csv_with`] with the delimiter detected.
pub fn read_csv(path: &Path) -> Result<Table, IoError> {
    read_csv_with(path, Delimiter::Auto)
}

/// Read a delimited file with a header line (RFC 4180, by the `csv` crate): cells separated by
/// `delimiter`, any of them quoted, CRLF or LF line ends, a byte-order mark, spaces around the
/// cells; empty lines are skipped. Every row must have one cell per column of the header, and
/// every cell must be a number; one that is not finite (`NaN`, `inf`) is refused when its
/// column is taken ([`Table::column`]), naming its line.
///
/// A file whose first line is numbers only has no header line: its columns are named `0`,
/// `1`, … (as an array's are), the first line is the first row, and the table's notes say so.
pub fn read_csv_with(path: &Path, delimiter: Delimiter) -> Result<Table, IoError> {
    read_csv_named(path, delimiter, true)
}

/// Every header cell a name, none twice: a column unnamed or named twice could not be
/// asked for by name, and would be read as a channel called nothing.
pub(super) fn header_names(path: &Path, names: &[String]) -> Result<(), IoError> {
    if let Some(k) = names.iter().position(|n| n.trim().is_empty()) {
        return Err(IoError::UnnamedColumn {
            path: path.to_path_buf(),
            position: k + 1,
        });
    }
    if let Some(column) = repeated(names) {
        return Err(IoError::DuplicateColumn {
            path: path.to_path_buf(),
            column: column.to_string(),
        });
    }
    Ok(())
}

/// [`read_csv_with`], its header's names checked only when `check_names` (not when the
/// caller replaces them, as `--names` does).
pub(super) fn read_csv_named(
    path: &Path,
    delimiter: Delimiter,
    check_names: bool,
) -> Result<Table, IoError> {
    let rows = DelimitedRows::open_record(path, delimiter)?;
    if check_names {
        header_names(path, &rows.names)?;
    }
    let (names, sep, headerless) = (rows.names.clone(), rows.sep, rows.pending.is_some());
    // A plain record (no quotes, LF or CRLF line ends, every cell a number) is read in
    // parallel blocks; anything else, and every error, by the `csv` reader below.
    let (columns, non_finite) = match super::bulk::read(path, names.len(), sep, headerless) {
        Some(c) => (c.values, c.non_finite),
        None => streamed(path, rows)?,
    };
    if columns.first().is_none_or(Vec::is_empty) {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    let mut table = Table::with_non_finite(path, names, columns, non_finite);
    if headerless {
        table.notes.push(format!(
            "{}: no header line (the first line is numbers): the columns are named 0 to {} as an array's are; --names names them",
            path.display(),
            table.names.len() - 1
        ));
    }
    Ok(table)
}

/// Whether `path` reads as a delimited record, from its header and first rows only (a file
/// of prose, or one whose writer has put only its header so far, does not): the error the
/// full read would give there.
pub(super) fn probe(path: &Path, delimiter: Delimiter) -> Result<(), IoError> {
    const ROWS: usize = 2;
    let rows = DelimitedRows::open_record(path, delimiter)?;
    header_names(path, &rows.names)?;
    let (names, sep) = (rows.names.clone(), rows.sep);
    let mut seen = 0;
    for r in rows.take(ROWS) {
        let (row, r) = r?;
        for (c, t) in r.iter().enumerate() {
            cell(path, (row, &names[c]), t, sep)?;
        }
        seen += 1;
    }
    if seen == 0 {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(())
}

/// The columns of a delimited record's `rows` (opened from `path`), read by the `csv`
/// crate, with each column's first cell that is not finite.
#[allow(clippy::type_complexity)]
pub(super) fn streamed(
    path: &Path,
    rows: DelimitedRows,
) -> Result<(Vec<Vec<f64>>, Vec<Option<super::NonFiniteCell>>), IoError> {
    let (names, sep) = (rows.names.clone(), rows.sep);
    let mut columns: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
    // Each column's first cell that is not finite, by its line: refused only if the column
    // is taken (a NaN in a column no one analyses does not make the file unreadable).
    let mut non_finite: Vec<Option<super::NonFiniteCell>> = vec![None; names.len()];
    for r in rows {
        let (row, r) = r?;
        for (c, t) in r.iter().enumerate() {
            let v = cell(path, (row, &names[c]), t, sep)?;
            if !v.is_finite() && non_finite[c].is_none() {
                non_finite[c] = Some(super::NonFiniteCell { row, value: v });
            }
            columns[c].push(v);
        }
    }
    Ok((columns, non_finite))
}

/// A delimited file opened for reading (see [`read_csv_with`] for what is read): its header's
/// names and its delimiter, then its rows as an iterator of (row, cells), the row 1-based
/// with the header as row 1, blank lines skipped, each row checked to have one cell per
/// column.
pub(super) struct DelimitedRows {
    /// The header's names, none twice.
    pub(super) names: Vec<String>,
    /// The delimiter, given or detected.
    pub(super) sep: u8,
    path: std::path::PathBuf,
    records: csv::StringRecordsIntoIter<std::io::BufReader<LineBounded<std::fs::File>>>,
    /// A headerless record's first line, the first row.
    pub(super) pending: Option<csv::StringRecord>,
    /// Each record's line in the file, from its byte offset.
    lines: LineCounter,
}

impl DelimitedRows {
    /// Open `path`, its delimiter `delimiter` or detected from its header line, and read the
    /// header; a first line of numbers only is an error (a table of named columns).
    pub(super) fn open(path: &Path, delimiter: Delimiter) -> Result<Self, IoError> {
        Self::opened(path, delimiter, false)
    }

    /// [`open`](Self::open) for a record: a first line of numbers only is its first row,
    /// its columns named `0`, `1`, ….
    pub(super) fn open_record(path: &Path, delimiter: Delimiter) -> Result<Self, IoError> {
        Self::opened(path, delimiter, true)
    }

    fn opened(path: &Path, delimiter: Delimiter, headerless: bool) -> Result<Self, IoError> {
        let file_error = |source| IoError::File {
            path: path.to_path_buf(),
            source,
        };
        // The file is read as a stream (a record is kept once, as numbers, not also as text);
        // its first non-blank line is read first to detect the delimiter, then it is read
        // again from its start.
        let file = std::fs::File::open(path).map_err(file_error)?;
        let mut file = std::io::BufReader::with_capacity(1 << 16, LineBounded::new(file));
        let first_line = first_line(&mut file, path)?;
        file.rewind().map_err(file_error)?;
        // A byte-order mark (spreadsheets write one) would become part of the first name.
        let bom = file
            .fill_buf()
            .map_err(file_error)?
            .starts_with(b"\xEF\xBB\xBF");
        if bom {
            file.consume(3);
        }
        let sep = delimiter
            .byte()
            .unwrap_or_else(|| Delimiter::detect(&first_line));
        let mut rows = DelimitedRows {
            names: Vec::new(),
            sep,
            path: path.to_path_buf(),
            records: csv::ReaderBuilder::new()
                .delimiter(sep)
                .has_headers(false)
                .flexible(true)
                .trim(csv::Trim::All)
                .from_reader(file)
                .into_records(),
            pending: None,
            lines: LineCounter::open(path, if bom { 3 } else { 0 })?,
        };
        let header = rows.next_cells().ok_or_else(|| IoError::NoHeader {
            path: path.to_path_buf(),
        })??;
        // A first line of numbers only is data, not names: taking it as the header would lose
        // a row and name the channels by numbers, silently. Columns named by their index
        // (`0,1,2` or `1,2,3`, as the readers of arrays name them) are names.
        let indices: Vec<Option<usize>> = header.iter().map(|t| t.parse().ok()).collect();
        let by_index = |first: usize| {
            indices
                .iter()
                .enumerate()
                .all(|(k, v)| *v == Some(k + first))
        };
        if header.iter().all(|t| number(t, sep).is_some()) && !by_index(0) && !by_index(1) {
            if headerless {
                rows.names = (0..header.len()).map(|k| k.to_string()).collect();
                rows.pending = Some(header);
                return Ok(rows);
            }
            return Err(IoError::HeaderOfNumbers {
                path: path.to_path_buf(),
                line: header
                    .iter()
                    .collect::<Vec<_>>()
                    .join(&*(sep as char).to_string()),
            });
        }
        rows.names = header.iter().map(str::to_string).collect();
        // A record's names may yet be replaced (`--names`): its reader checks them after.
        if !headerless {
            header_names(path, &rows.names)?;
        }
        Ok(rows)
    }

    /// The next line that is not blank, as cells.
    fn next_cells(&mut self) -> Option<Result<csv::StringRecord, IoError>> {
        loop {
            match self.records.next()? {
                Err(e) => {
                    let row = e.position().map_or(0, |p| self.lines.line_at(p.byte()));
                    return Some(Err(IoError::Malformed {
                        path: self.path.clone(),
                        row,
                        what: e.to_string(),
                    }));
                }
                Ok(r) if r.len() == 1 && r[0].is_empty() => continue,
                // Runs of spaces separate one cell from the next: the empty cells between
                // them (and before a leading space) are not cells.
                Ok(r) if self.sep == b' ' => {
                    let mut cells = csv::StringRecord::new();
                    for c in r.iter().filter(|c| !c.is_empty()) {
                        cells.push_field(c);
                    }
                    if cells.is_empty() {
                        continue;
                    }
                    cells.set_position(r.position().cloned());
                    return Some(Ok(cells));
                }
                Ok(r) => return Some(Ok(r)),
            }
        }
    }
}

impl Iterator for DelimitedRows {
    type Item = Result<(usize, csv::StringRecord), IoError>;

    fn next(&mut self) -> Option<Self::Item> {
        let next = match self.pending.take() {
            Some(first) => Ok(first),
            None => self.next_cells()?,
        };
        Some(next.and_then(|r| {
            let row = r.position().map_or(0, |p| self.lines.line_at(p.byte()));
            if r.len() != self.names.len() {
                return Err(IoError::CellCount {
                    path: self.path.clone(),
                    row,
                    found: r.len(),
                    expected: self.names.len(),
                });
            }
            Ok((row, r))
        }))
    }
}

/// The line (1-based) of each record of a file, from its byte offset: the `csv` crate's own
/// count is of records, not lines (a blank line skipped, or a CRLF line end, made a cell on
/// line 3 read as on line 2). The file is read a second time, forwards, counting line ends
/// (LF, CRLF, or a CR alone) as the records' offsets advance.
struct LineCounter {
    reader: std::io::BufReader<std::fs::File>,
    /// Bytes before the offsets the `csv` reader counts from (a byte-order mark).
    skip: u64,
    /// Bytes read, and line ends among them.
    at: u64,
    ends: usize,
    /// Whether the last byte read is a CR (an LF next ends the same line).
    after_cr: bool,
}

impl LineCounter {
    fn open(path: &Path, skip: u64) -> Result<Self, IoError> {
        let file = std::fs::File::open(path).map_err(|source| IoError::File {
            path: path.to_path_buf(),
            source,
        })?;
        Ok(LineCounter {
            reader: std::io::BufReader::with_capacity(1 << 16, file),
            skip,
            at: 0,
            ends: 0,
            after_cr: false,
        })
    }

    /// The line of the record the `csv` reader puts at byte `offset`; offsets asked for
    /// must not decrease. A file that cannot be read again gives the lines counted so
    /// far.
    fn line_at(&mut self, offset: u64) -> usize {
        let target = offset + self.skip;
        while self.at < target {
            let Ok(buf) = self.reader.fill_buf() else {
                break;
            };
            if buf.is_empty() {
                break;
            }
            let take = buf.len().min((target - self.at) as usize);
            for &b in &buf[..take] {
                match b {
                    b'\n' if self.after_cr => {}
                    b'\n' | b'\r' => self.ends += 1,
                    _ => {}
                }
                self.after_cr = b == b'\r';
            }
            self.reader.consume(take);
            self.at += take as u64;
        }
        // The `csv` reader's offset of a record after blank lines is where they begin: the
        // record's line is that of its first byte past them.
        while let Ok(buf) = self.reader.fill_buf() {
            let Some(&b) = buf.first() else { break };
            if b != b'\n' && b != b'\r' {
                break;
            }
            if !(b == b'\n' && self.after_cr) {
                self.ends += 1;
            }
            self.after_cr = b == b'\r';
            self.reader.consume(1);
            self.at += 1;
        }
        self.ends + 1
    }
}

/// The longest line a delimited file may hold (bytes): 10 000 channels of 25-character
/// numbers is 250 kB; a "line" past this is no record's (a binary file, or one that never
/// ends), and reading it whole would hold it all in memory.
pub(super) const MAX_LINE_BYTES: usize = 16 << 20;

/// A reader that fails, saying so, on a line longer than [`MAX_LINE_BYTES`].
pub(super) struct LineBounded<R> {
    inner: R,
    since_newline: usize,
}

impl<R> LineBounded<R> {
    pub(super) fn new(inner: R) -> Self {
        LineBounded {
            inner,
            since_newline: 0,
        }
    }
}

impl<R: std::io::Read> std::io::Read for LineBounded<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let chunk = &buf[..n];
        let too_long = || {
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "a line longer than {} MiB: not a delimited record (a binary file, or a line that never ends)",
                    MAX_LINE_BYTES >> 20
                ),
            )
        };
        // Only the first and last line ends of a read are looked for (each a line's length
        // from its end of the read): a line wholly inside a read is shorter than the read,
        // and reads are far shorter than the bound (a longer one is scanned whole).
        match chunk.iter().position(|&b| b == b'\n') {
            None => self.since_newline += n,
            Some(first) => {
                if self.since_newline + first > MAX_LINE_BYTES {
                    return Err(too_long());
                }
                if n > MAX_LINE_BYTES
                    && chunk
                        .split(|&b| b == b'\n')
                        .any(|l| l.len() > MAX_LINE_BYTES)
                {
                    return Err(too_long());
                }
                let last = chunk.iter().rposition(|&b| b == b'\n').unwrap_or(first);
                self.since_newline = n - last - 1;
            }
        }
        if self.since_newline > MAX_LINE_BYTES {
            return Err(too_long());
        }
        Ok(n)
    }
}

impl<R: Seek> Seek for LineBounded<R> {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        self.since_newline = 0;
        self.inner.seek(pos)
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_files::file_path;
    use std::path::PathBuf;

    fn file(name: &str, text: &str) -> PathBuf {
        let p = file_path(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// The probe tells a record from a note by what the full read would say of its first
    /// lines: prose and a header alone are not records; a record with or without a header,
    /// and one whose later rows are bad (the full read's business), are.
    #[test]
    fn a_probe_tells_records_from_notes() {
        let cases = [
            (
                "probe_note.txt",
                "Hourly records.\nSensor 3 re-glued.\n",
                false,
            ),
            ("probe_header.csv", "y1,y2\n", false),
            ("probe_text_row.csv", "y1,y2\n1,abc\n", false),
            ("probe_record.csv", "y1,y2\n1,2\n3,4\n", true),
            ("probe_headerless.txt", "1 2\n3 4\n", true),
            ("probe_bad_later.csv", "y1,y2\n1,2\n3,4\n5,x\n", true),
        ];
        for (name, text, record) in cases {
            let p = file(name, text);
            let got = crate::probe_record(&p);
            assert_eq!(got.is_ok(), record, "{name}: {got:?}");
            let _ = std::fs::remove_file(p);
        }
    }

    /// A line that never ends is refused when it passes the bound, as a header or as a
    /// row, rather than held whole (issue 58: a 2 GB line took 4.2 GB): the error says so.
    #[test]
    fn a_line_past_the_bound_is_refused() {
        let long = "1".repeat(MAX_LINE_BYTES + 10);
        for (name, text) in [
            ("long_header.csv", long.clone()),
            ("long_row.csv", format!("y\n1\n{long}\n")),
        ] {
            let e = read_csv(&file(name, &text)).unwrap_err().to_string();
            assert!(e.contains("a line longer than 16 MiB"), "{name}: {e}");
            let _ = std::fs::remove_file(file_path(name));
        }
        // A line of exactly the bound is read (its cell then judged as a number: too large).
        let at = format!("y\n1\n{}\n2\n", "1".repeat(MAX_LINE_BYTES));
        let e = crate::test_files::taken(read_csv(&file("at_bound.csv", &at)))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("row 3, column `y`: value inf is not finite"),
            "{e}"
        );
        let _ = std::fs::remove_file(file_path("at_bound.csv"));
        // Through reads of any size: lines under the bound pass, one over it fails.
        for chunk in [1, 7, 4096] {
            struct Chunks<'a>(&'a [u8], usize);
            impl std::io::Read for Chunks<'_> {
                fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                    let n = self.1.min(buf.len()).min(self.0.len());
                    buf[..n].copy_from_slice(&self.0[..n]);
                    self.0 = &self.0[n..];
                    Ok(n)
                }
            }
            let read_all = |bytes: &[u8]| {
                let mut out = Vec::new();
                std::io::Read::read_to_end(&mut LineBounded::new(Chunks(bytes, chunk)), &mut out)
                    .map(|_| out.len())
            };
            let mut ok = b"ab\n".repeat(3);
            ok.extend(vec![b'x'; MAX_LINE_BYTES]);
            ok.extend(b"\ncd\n");
            assert_eq!(read_all(&ok).unwrap(), ok.len(), "chunk {chunk}");
            let mut over = b"ab\n".to_vec();
            over.extend(vec![b'x'; MAX_LINE_BYTES + 1]);
            over.extend(b"\ncd\n");
            assert!(read_all(&over).is_err(), "chunk {chunk}");
        }
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

    /// A `.dat` file of columns separated by runs of spaces (leading ones too) is read by
    /// its header's names; `--delimiter spaces` says so explicitly.
    #[test]
    fn space_separated_columns_are_read() {
        let p = file(
            "spaces.dat",
            "  t    y1  y2\n0  1.5   -2\n\n 0.1 2.5e-1    3\n",
        );
        for d in [Delimiter::Auto, Delimiter::Spaces] {
            let t = read_csv_with(&p, d).unwrap();
            assert_eq!(t.names, ["t", "y1", "y2"]);
            assert_eq!(
                t.columns,
                [vec![0.0, 0.1], vec![1.5, 0.25], vec![-2.0, 3.0]]
            );
        }
        let e = read_csv(&file("spaces_short.dat", "a b\n1 2\n3\n")).unwrap_err();
        assert!(
            e.to_string()
                .contains("row 3 has 1 cells, the header has 2"),
            "{e}"
        );
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
        // A cell that is not finite is named, by its line, when its column is taken; the
        // file's other columns are read (a NaN in a column no one analyses is no error).
        let t = read_csv(&file("nan.csv", "t,y,z\n0,1,2\n1,NaN,3\n2,inf,4\n")).unwrap();
        let e = t.column("y").unwrap_err();
        assert!(
            e.to_string()
                .ends_with("nan.csv: row 3, column `y`: value NaN is not finite"),
            "{e}"
        );
        assert_eq!(t.column("z").unwrap(), [2.0, 3.0, 4.0]);
        // The row is the file's line, whatever the line ends and blank lines before it
        // (the `csv` crate counted records: CRLF files' rows read one short, and so did
        // every row after a blank line), on the streamed path and the fast one alike.
        for (name, text) in [
            ("crlf_short.csv", "t,y\r\n0,1\r\n2\r\n"),
            ("blank_short.csv", "t,y\n\n0,1\n2\n"),
            ("crlf_quoted_short.csv", "t,y\r\n\"0\",1\r\n2\r\n"),
        ] {
            let want = if name.starts_with("blank") { 4 } else { 3 };
            let e = read_csv(&file(name, text)).unwrap_err();
            assert!(
                e.to_string().contains(&format!("row {want} has 1 cells")),
                "{e}"
            );
        }
        for (name, text) in [
            ("crlf_nan.csv", "t,y\r\n0,1\r\n1,NaN\r\n"),
            ("crlf_nan_quoted.csv", "t,y\r\n\"0\",1\r\n1,NaN\r\n"),
            ("blank_nan.csv", "t,y\n0,1\n\n\n1,NaN\n"),
        ] {
            let want = if name.starts_with("blank") { 5 } else { 3 };
            let e = read_csv(&file(name, text))
                .unwrap()
                .column("y")
                .unwrap_err();
            assert!(
                e.to_string().contains(&format!("row {want}, column `y`")),
                "{e}"
            );
        }
        let e = read_csv(&file("bytes.csv", "t,y\n0,1\n")).map(|_| ());
        assert!(e.is_ok());
        std::fs::write(file("latin1.csv", ""), b"t,y\n0,\xff\n").unwrap();
        let e = read_csv(&file_path("latin1.csv")).unwrap_err();
        assert!(e.to_string().contains("latin1.csv: row 2"), "{e}");
        let e = read_csv(&file("blank.csv", "\n \n")).unwrap_err();
        assert!(matches!(e, IoError::NoHeader { .. }), "{e}");
        // Columns named by their index are names, not data.
        let t = read_csv(&file("indexed.csv", "0,1,2\n1.5,2,3\n")).unwrap();
        assert_eq!(t.names, ["0", "1", "2"]);
        let t = read_csv(&file("indexed1.csv", "1;2\n0,5;2\n")).unwrap();
        assert_eq!(t.names, ["1", "2"]);
        // A headerless file: its first line is its first row (not names, which would lose a
        // row and name the channels `0.12` and `3.4e-2`), its columns named as an array's,
        // and said.
        for (name, text, first) in [
            ("headerless.csv", "0.12,3.4e-2\n0.2,0.1\n", [0.12, 3.4e-2]),
            ("headerless.tsv", "0.12\t3.4e-2\n0.2\t0.1\n", [0.12, 3.4e-2]),
            ("headerless_semicolon.csv", "0,12;3;4\n1;2;3\n", [0.12, 3.0]),
            (
                "headerless.dat",
                "  0.12   3.4e-2\n 0.2  0.1\n",
                [0.12, 3.4e-2],
            ),
        ] {
            let t = read_csv(&file(name, text)).unwrap();
            let generated: Vec<String> = (0..t.names.len()).map(|k| k.to_string()).collect();
            assert_eq!(t.names, generated, "{name}");
            assert_eq!(t.len(), 2, "{name}");
            assert_eq!([t.columns[0][0], t.columns[1][0]], first, "{name}");
            assert!(t.notes[0].contains("no header line"), "{:?}", t.notes);
        }
        // A headerless file with a bad cell names its row: the first line is row 1.
        let e = read_csv(&file("headerless_bad.dat", "1.5 2\n3 x\n")).unwrap_err();
        assert!(e.to_string().contains("row 2, column `1`"), "{e}");
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
            // The default case count (256), which PROPTEST_CASES raises for a long run.
            #[test]
            fn any_bytes_read_or_fail_cleanly(bytes in proptest::collection::vec(any::<u8>(), 0..200)) {
                let p = file_path(&format!("fuzz-{}.csv", std::thread::current().name().unwrap_or("t").replace("::", "_")));
                std::fs::write(&p, &bytes).unwrap();
                if let Ok(t) = read_csv(&p) {
                    prop_assert!(crate::test_files::well_formed(&t));
                }
            }
        }
    }
}
