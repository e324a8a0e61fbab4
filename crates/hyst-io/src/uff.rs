//! Universal File Format records: datasets 58, ASCII or binary.
//!
//! A Universal File is a sequence of datasets, each opened and closed by a line `    -1`,
//! its second line giving the dataset's number. A record is the file's datasets 58
//! ("function at nodal DOF"), one per channel: 11 header lines (five ID lines; record 6 the
//! function type and the response's node and direction; record 7 the ordinate type, the
//! number of values, the abscissa's spacing, start and increment; records 8–11 the axes),
//! then the values, as text (`6E13.5` single, `4E20.12` double precision) or, in the binary
//! form 58b, as the raw bytes the dataset's first line counts, in the byte order it names.
//! Other datasets (units, geometry, shapes) are passed over.
//!
//! Each function must be a real, evenly sampled time response, and the channels must agree
//! in length, start and increment; the sampling rate is 1 / increment. Record 7 writes the
//! increment with six significant digits (`E13.5`), so a rate within that precision of a
//! whole number of hertz is taken as that whole number (an increment of 4.88281e-04 s is
//! 2048 Hz, not 2048.0015 Hz). The channels are named by their point, `12+Z`.

use std::path::Path;

use super::{IoError, MeasurementPoint, Table};

/// The error of a file that is not a record this reader takes.
pub(crate) fn bad(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Uff {
        path: path.to_path_buf(),
        what: what.into(),
    }
}

/// The lines of a byte buffer, with their 1-based numbers, read one at a time; a binary
/// block of a known length can be taken between them.
pub(crate) struct Lines<'a> {
    bytes: &'a [u8],
    at: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    /// The next line without its line end (LF or CRLF), and its number.
    pub(crate) fn next_line(&mut self) -> Option<(usize, &'a [u8])> {
        if self.at >= self.bytes.len() {
            return None;
        }
        let rest = &self.bytes[self.at..];
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.at += (end + 1).min(rest.len());
        self.line += 1;
        let text = &rest[..end];
        Some((self.line, text.strip_suffix(b"\r").unwrap_or(text)))
    }

    /// The next `n` bytes, if the buffer holds them.
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n)?;
        let block = self.bytes.get(self.at..end)?;
        self.at = end;
        Some(block)
    }
}

/// Whether a line is a dataset's delimiter, `    -1`.
pub(crate) fn is_delimiter(line: &[u8]) -> bool {
    line.trim_ascii() == b"-1"
}

/// Columns `from..to` (0-based) of a line, blank where the line is shorter.
pub(crate) fn field(line: &[u8], from: usize, to: usize) -> &str {
    let end = to.min(line.len());
    let start = from.min(end);
    std::str::from_utf8(&line[start..end]).map_or("", str::trim)
}

/// A Fortran integer field (blank is 0).
pub(crate) fn int(text: &str) -> Option<i64> {
    if text.is_empty() {
        Some(0)
    } else {
        text.parse().ok()
    }
}

/// A Fortran real field: `E` or `D` exponents, blank is 0.
pub(crate) fn real(text: &str) -> Option<f64> {
    if text.is_empty() {
        return Some(0.0);
    }
    text.replace(['D', 'd'], "e").parse().ok()
}

/// One dataset 58 as read: where it is, what its header says, its values.
struct Function {
    /// The dataset's place among the file's datasets (1-based) and its first line.
    dataset: usize,
    line: usize,
    function_type: i64,
    point: MeasurementPoint,
    ordinate_type: i64,
    count: usize,
    even: bool,
    start: f64,
    increment: f64,
    abscissa_type: i64,
    values: Vec<f64>,
}

impl Function {
    /// How errors name this function.
    fn label(&self) -> String {
        format!(
            "dataset {} (58 at line {}, point {})",
            self.dataset, self.line, self.point
        )
    }
}

/// What a 58b dataset's first line says of its binary block.
#[derive(Clone, Copy)]
pub(crate) struct Binary {
    little_endian: bool,
    ascii_lines: usize,
    bytes: usize,
}

/// Read the Universal File at `path` as a record (see the module's documentation).
pub fn read_uff(path: &Path) -> Result<Table, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    let functions = functions(path, &bytes)?;
    record(path, functions)
}

/// Every dataset 58 of the file, in order; other datasets passed over.
fn functions(path: &Path, bytes: &[u8]) -> Result<Vec<Function>, IoError> {
    let mut functions = Vec::new();
    let others = walk_datasets(path, bytes, |start, lines| {
        if start.number != 58 {
            return Ok(false);
        }
        functions.push(function(
            path,
            lines,
            start.index,
            start.id_line,
            start.binary,
        )?);
        Ok(true)
    })?;
    if functions.is_empty() {
        return Err(bad(
            path,
            format!(
                "no dataset 58 (a function at a node) to read as a record; the file holds {}",
                holds(&others)
            ),
        ));
    }
    Ok(functions)
}

/// How an error says which datasets a file holds.
pub(crate) fn holds(numbers: &[u32]) -> String {
    if numbers.is_empty() {
        "no datasets".to_string()
    } else {
        let n: Vec<String> = numbers.iter().map(u32::to_string).collect();
        format!("datasets {}", n.join(", "))
    }
}

/// Where a dataset starts: its number, its place among the file's datasets (1-based), the
/// line of its number, and a binary dataset's layout.
pub(crate) struct DatasetStart {
    pub number: u32,
    pub index: usize,
    pub id_line: usize,
    pub binary: Option<Binary>,
}

/// Walk the datasets of the Universal File `bytes` (read from `path`): `visit` is given
/// each dataset's start with the lines after its number, reads it up to and with its closing
/// delimiter and returns `true`, or returns `false` to have it passed over. Returns the
/// numbers of the datasets passed over.
pub(crate) fn walk_datasets(
    path: &Path,
    bytes: &[u8],
    mut visit: impl FnMut(DatasetStart, &mut Lines<'_>) -> Result<bool, IoError>,
) -> Result<Vec<u32>, IoError> {
    let mut lines = Lines {
        bytes,
        at: 0,
        line: 0,
    };
    let mut others: Vec<u32> = Vec::new();
    let mut index = 0;
    while let Some((n, line)) = lines.next_line() {
        if line.trim_ascii().is_empty() {
            continue;
        }
        if !is_delimiter(line) {
            return Err(bad(
                path,
                format!(
                    "line {n}: `{}` where a dataset should open with `    -1`: not a Universal File",
                    String::from_utf8_lossy(&line[..line.len().min(40)])
                ),
            ));
        }
        let Some((id_line, id)) = lines.next_line() else {
            return Err(bad(
                path,
                format!("line {n}: a dataset opens at the end of the file"),
            ));
        };
        index += 1;
        let number_text = field(id, 0, 6);
        let number = number_text.parse::<u32>().map_err(|_| {
            bad(
                path,
                format!(
                    "line {id_line}: `{}` is not a dataset number",
                    String::from_utf8_lossy(&id[..id.len().min(40)])
                ),
            )
        })?;
        let binary = match id.get(6) {
            Some(b'b' | b'B') => Some(binary_header(path, id_line, id)?),
            _ => None,
        };
        let start = DatasetStart {
            number,
            index,
            id_line,
            binary,
        };
        if !visit(start, &mut lines)? {
            others.push(number);
            skip_dataset(path, &mut lines, id_line, number, binary)?;
        }
    }
    Ok(others)
}

/// The binary layout a `58b`-style first line gives: `Format(I6,1A1,I6,I6,I12,I12,…)`.
fn binary_header(path: &Path, n: usize, id: &[u8]) -> Result<Binary, IoError> {
    let order = int(field(id, 7, 13));
    let float = int(field(id, 13, 19));
    let ascii = int(field(id, 19, 31));
    let count = int(field(id, 31, 43));
    let (Some(order), Some(float), Some(ascii), Some(count)) = (order, float, ascii, count) else {
        return Err(bad(
            path,
            format!(
                "line {n}: a binary dataset's first line `{}` does not give its byte order, float format, line and byte counts",
                String::from_utf8_lossy(id)
            ),
        ));
    };
    if float != 2 {
        return Err(bad(
            path,
            format!(
                "line {n}: floating-point format {float} (1 is DEC VMS, 3 IBM 370); only IEEE 754 (2) is read"
            ),
        ));
    }
    let little_endian = match order {
        1 => true,
        2 => false,
        o => {
            return Err(bad(
                path,
                format!("line {n}: byte ordering {o} (1 little endian, 2 big endian)"),
            ));
        }
    };
    match (usize::try_from(ascii), usize::try_from(count)) {
        (Ok(ascii_lines), Ok(bytes)) => Ok(Binary {
            little_endian,
            ascii_lines,
            bytes,
        }),
        _ => Err(bad(
            path,
            format!("line {n}: negative line or byte count ({ascii}, {count})"),
        )),
    }
}

/// Pass over a dataset other than 58, up to and with its closing delimiter.
fn skip_dataset(
    path: &Path,
    lines: &mut Lines<'_>,
    id_line: usize,
    number: u32,
    binary: Option<Binary>,
) -> Result<(), IoError> {
    let unclosed = || {
        bad(
            path,
            format!("dataset {number} at line {id_line} is not closed by `    -1`"),
        )
    };
    if let Some(b) = binary {
        for _ in 0..b.ascii_lines {
            lines.next_line().ok_or_else(unclosed)?;
        }
        lines.take(b.bytes).ok_or_else(unclosed)?;
    }
    loop {
        let (_, line) = lines.next_line().ok_or_else(unclosed)?;
        if is_delimiter(line) {
            return Ok(());
        }
    }
}

/// Read a dataset 58 whose first line (`id_line`) has been read, up to and with its closing
/// delimiter.
fn function(
    path: &Path,
    lines: &mut Lines<'_>,
    dataset: usize,
    id_line: usize,
    binary: Option<Binary>,
) -> Result<Function, IoError> {
    let here = format!("dataset {dataset} (58 at line {id_line})");
    let mut header: Vec<(usize, &[u8])> = Vec::with_capacity(11);
    for _ in 0..11 {
        let l = lines
            .next_line()
            .ok_or_else(|| bad(path, format!("{here}: the file ends inside its header")))?;
        if is_delimiter(l.1) {
            return Err(bad(
                path,
                format!("{here}: closed at line {} inside its header", l.0),
            ));
        }
        header.push(l);
    }
    let mut f = parse_header(path, &here, &header, dataset, id_line)?;
    let width = match f.ordinate_type {
        2 => 4,
        4 => 8,
        5 | 6 => {
            return Err(bad(
                path,
                format!(
                    "{}: complex values (ordinate type {}); a record is real",
                    f.label(),
                    f.ordinate_type
                ),
            ));
        }
        t => {
            return Err(bad(
                path,
                format!(
                    "{}: ordinate data type {t} (2 real single, 4 real double precision)",
                    f.label()
                ),
            ));
        }
    };
    check_function(path, &f)?;
    f.values = match binary {
        Some(b) => binary_values(path, lines, &f, &b, width)?,
        None => text_values(path, lines, &f, width)?,
    };
    if f.values.len() != f.count {
        return Err(bad(
            path,
            format!(
                "{}: record 7 says {} values, the data hold {}",
                f.label(),
                f.count,
                f.values.len()
            ),
        ));
    }
    Ok(f)
}

/// The function records 6–8 of `header` describe (its values still to read); `here` starts
/// the errors.
fn parse_header(
    path: &Path,
    here: &str,
    header: &[(usize, &[u8])],
    dataset: usize,
    id_line: usize,
) -> Result<Function, IoError> {
    let (n6, r6) = header[5];
    let (n7, r7) = header[6];
    let (_, r8) = header[7];
    let ints = |line: &[u8], n: usize, fields: &[(usize, usize, &str)]| {
        fields
            .iter()
            .map(|&(a, b, name)| {
                int(field(line, a, b)).ok_or_else(|| {
                    bad(
                        path,
                        format!(
                            "{here}: line {n}: {name} `{}` is not an integer",
                            field(line, a, b)
                        ),
                    )
                })
            })
            .collect::<Result<Vec<i64>, IoError>>()
    };
    // Record 6: Format(2(I5,I10),2(1X,10A1,I10,I4)).
    let r6v = ints(
        r6,
        n6,
        &[
            (0, 5, "the function type"),
            (41, 51, "the response node"),
            (51, 55, "the response direction"),
        ],
    )?;
    // Record 7: Format(3I10,3E13.5).
    let r7v = ints(
        r7,
        n7,
        &[
            (0, 10, "the ordinate data type"),
            (10, 20, "the number of values"),
            (20, 30, "the abscissa spacing"),
        ],
    )?;
    let [start, increment] =
        [(30, 43, "the abscissa minimum"), (43, 56, "the increment")].map(|(a, b, name)| {
            real(field(r7, a, b)).ok_or_else(|| {
                bad(
                    path,
                    format!(
                        "{here}: line {n7}: {name} `{}` is not a number",
                        field(r7, a, b)
                    ),
                )
            })
        });
    let count = usize::try_from(r7v[1])
        .map_err(|_| bad(path, format!("{here}: line {n7}: {} values", r7v[1])))?;
    Ok(Function {
        dataset,
        line: id_line,
        function_type: r6v[0],
        point: MeasurementPoint {
            node: r6v[1],
            direction: i32::try_from(r6v[2]).unwrap_or(i32::MAX),
        },
        ordinate_type: r7v[0],
        count,
        even: r7v[2] == 1,
        start: start?,
        increment: increment?,
        abscissa_type: int(field(r8, 0, 10)).unwrap_or(0),
        values: Vec::new(),
    })
}

/// What a function must be to be a channel of a record, before its values are read.
fn check_function(path: &Path, f: &Function) -> Result<(), IoError> {
    const TYPES: [&str; 13] = [
        "general",
        "time response",
        "auto spectrum",
        "cross spectrum",
        "frequency response function",
        "transmissibility",
        "coherence",
        "auto correlation",
        "cross correlation",
        "power spectral density",
        "energy spectral density",
        "probability density function",
        "spectrum",
    ];
    if !matches!(f.function_type, 0 | 1) {
        let name = usize::try_from(f.function_type)
            .ok()
            .and_then(|t| TYPES.get(t))
            .copied()
            .unwrap_or("not a time response");
        return Err(bad(
            path,
            format!(
                "{}: function type {} ({name}); a record is time responses (type 1)",
                f.label(),
                f.function_type
            ),
        ));
    }
    if matches!(f.abscissa_type, 18..=20) {
        return Err(bad(
            path,
            format!(
                "{}: the abscissa is a frequency, rpm or order (data type {}), not time",
                f.label(),
                f.abscissa_type
            ),
        ));
    }
    if !f.even {
        return Err(bad(
            path,
            format!(
                "{}: uneven abscissa spacing; a record is sampled at a constant rate",
                f.label()
            ),
        ));
    }
    if !(f.increment.is_finite() && f.increment > 0.0) {
        return Err(bad(
            path,
            format!(
                "{}: the abscissa increment {} is not a positive sampling interval",
                f.label(),
                f.increment
            ),
        ));
    }
    Ok(())
}

/// A text dataset's values, up to and with its closing delimiter: fields 13 (single) or 20
/// (double precision) characters wide.
fn text_values(
    path: &Path,
    lines: &mut Lines<'_>,
    f: &Function,
    width: usize,
) -> Result<Vec<f64>, IoError> {
    let field_width = if width == 4 { 13 } else { 20 };
    let mut values = Vec::with_capacity(f.count.min(1 << 24));
    loop {
        let (n, line) = lines.next_line().ok_or_else(|| {
            bad(
                path,
                format!(
                    "{}: the file ends after {} of its {} values, before `    -1`",
                    f.label(),
                    values.len(),
                    f.count
                ),
            )
        })?;
        if is_delimiter(line) {
            return Ok(values);
        }
        for start in (0..line.len()).step_by(field_width) {
            let text = field(line, start, start + field_width);
            if text.is_empty() {
                continue;
            }
            let v = real(text).ok_or_else(|| {
                bad(
                    path,
                    format!("{}: line {n}: `{text}` is not a number", f.label()),
                )
            })?;
            values.push(v);
        }
    }
}

/// A 58b dataset's values: its remaining header lines, then the bytes its first line counts,
/// then the closing delimiter.
fn binary_values(
    path: &Path,
    lines: &mut Lines<'_>,
    f: &Function,
    b: &Binary,
    width: usize,
) -> Result<Vec<f64>, IoError> {
    // The 11 header lines are read; a first line counting more is followed.
    for _ in 11..b.ascii_lines {
        lines.next_line().ok_or_else(|| {
            bad(
                path,
                format!("{}: the file ends inside its header", f.label()),
            )
        })?;
    }
    if b.bytes != f.count.saturating_mul(width) {
        return Err(bad(
            path,
            format!(
                "{}: its first line counts {} bytes, but {} values of {width} bytes are {}",
                f.label(),
                b.bytes,
                f.count,
                f.count.saturating_mul(width)
            ),
        ));
    }
    let block = lines.take(b.bytes).ok_or_else(|| {
        bad(
            path,
            format!(
                "{}: the file ends inside its {} bytes of data",
                f.label(),
                b.bytes
            ),
        )
    })?;
    let values = block
        .chunks_exact(width)
        .map(|c| match (width, b.little_endian) {
            (4, true) => f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            (4, false) => f64::from(f32::from_be_bytes([c[0], c[1], c[2], c[3]])),
            (_, true) => f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]),
            (_, false) => f64::from_be_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]),
        })
        .collect();
    // The data end where the count says; the delimiter follows (on the same line or the next).
    loop {
        let (n, line) = lines.next_line().ok_or_else(|| {
            bad(
                path,
                format!("{}: not closed by `    -1` after its data", f.label()),
            )
        })?;
        if is_delimiter(line) {
            return Ok(values);
        }
        if !line.trim_ascii().is_empty() {
            return Err(bad(
                path,
                format!(
                    "{}: line {n}: more after its {} bytes of data where `    -1` should close it",
                    f.label(),
                    b.bytes
                ),
            ));
        }
    }
}

/// The sampling rate of an increment written with six significant digits: a whole number
/// of hertz when within that precision of one.
fn rate_of(increment: f64) -> f64 {
    let fs = 1.0 / increment;
    let whole = fs.round();
    if whole >= 1.0 && (fs - whole).abs() <= 5e-6 * fs {
        whole
    } else {
        fs
    }
}

/// The functions as one record's channels, which must agree in length, start and increment.
fn record(path: &Path, functions: Vec<Function>) -> Result<Table, IoError> {
    let first = &functions[0];
    for f in &functions[1..] {
        if f.count != first.count {
            return Err(bad(
                path,
                format!(
                    "channels of different lengths: {} has {} samples, {} has {}",
                    first.label(),
                    first.count,
                    f.label(),
                    f.count
                ),
            ));
        }
        // Record 7 holds six significant digits.
        if (f.increment - first.increment).abs() > 1e-5 * first.increment {
            return Err(bad(
                path,
                format!(
                    "channels at different rates: {} is sampled every {:e} s, {} every {:e} s",
                    first.label(),
                    first.increment,
                    f.label(),
                    f.increment
                ),
            ));
        }
        if (f.start - first.start).abs() > 0.5 * first.increment {
            return Err(bad(
                path,
                format!(
                    "channels starting at different times: {} at {} s, {} at {} s",
                    first.label(),
                    first.start,
                    f.label(),
                    f.start
                ),
            ));
        }
    }
    let rate = rate_of(first.increment);
    let points: Vec<MeasurementPoint> = functions.iter().map(|f| f.point).collect();
    let names: Vec<String> = points.iter().map(ToString::to_string).collect();
    for (j, f) in functions.iter().enumerate() {
        if let Some(i) = points[..j].iter().position(|p| *p == f.point) {
            return Err(bad(
                path,
                format!(
                    "two functions at point {}: {} and {}",
                    f.point,
                    functions[i].label(),
                    f.label()
                ),
            ));
        }
    }
    let columns = functions.into_iter().map(|f| f.values).collect();
    let mut table = Table::new(path, names, columns);
    table.rate_hz = Some(rate);
    table.points = Some(points);
    Ok(table)
}

#[cfg(test)]
mod tests;
