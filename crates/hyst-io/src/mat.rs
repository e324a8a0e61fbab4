//! MATLAB records: one numeric variable of a level 5 MAT-file, the format of MATLAB's
//! `save` (`-v6`, and `-v7`, whose variables are zlib-compressed) and of `scipy.io.savemat`.
//!
//! The file is a 128-byte header (text, then the version and an endian mark, `IM` for a
//! little-endian file) and a sequence of data elements, each a tag (type, byte count; the
//! small form packs both into 4 bytes with the data in the next 4) and its data padded to 8
//! bytes. A variable is an element of type miMATRIX, whose sub-elements are its flags (class,
//! complex), its dimensions, its name and its real (then imaginary) part, stored in whatever
//! integer or float type holds it; type miCOMPRESSED wraps such an element in zlib.
//!
//! The record is the variable named by the caller, else the file's only numeric variable of
//! more than one element. It must be real and 2-D: rows are samples and columns channels,
//! named `0`, `1`, … (a 1 × N row vector is one channel; a matrix of more columns than rows
//! is refused as transposed). Version 7.3 files are HDF5, and are refused with that advice.

use std::io::Read;
use std::path::Path;

use super::{IoError, Table};

/// The error of a file that is not a record this reader takes.
fn bad(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Mat {
        path: path.to_path_buf(),
        what: what.into(),
    }
}

/// The element types (miINT8 …) a numeric array's data may be stored in, by their codes.
fn element_width(code: u32) -> Option<usize> {
    match code {
        1 | 2 => Some(1),
        3 | 4 => Some(2),
        5..=7 => Some(4),
        9 | 12 | 13 => Some(8),
        _ => None,
    }
}

/// The byte order of the file.
#[derive(Clone, Copy)]
struct Endian {
    little: bool,
}

impl Endian {
    fn u32(self, b: &[u8]) -> u32 {
        let a = [b[0], b[1], b[2], b[3]];
        if self.little {
            u32::from_le_bytes(a)
        } else {
            u32::from_be_bytes(a)
        }
    }

    fn i32(self, b: &[u8]) -> i32 {
        self.u32(b) as i32
    }

    /// The `i`-th value of `data`, stored as element type `code`, as f64.
    fn value(self, code: u32, data: &[u8], i: usize) -> f64 {
        macro_rules! at {
            ($t:ty, $w:expr) => {{
                let mut a = [0u8; $w];
                a.copy_from_slice(&data[i * $w..(i + 1) * $w]);
                if self.little {
                    <$t>::from_le_bytes(a) as f64
                } else {
                    <$t>::from_be_bytes(a) as f64
                }
            }};
        }
        match code {
            1 => at!(i8, 1),
            2 => at!(u8, 1),
            3 => at!(i16, 2),
            4 => at!(u16, 2),
            5 => at!(i32, 4),
            6 => at!(u32, 4),
            7 => at!(f32, 4),
            12 => at!(i64, 8),
            13 => at!(u64, 8),
            _ => at!(f64, 8),
        }
    }
}

/// One data element: its type and its data.
struct Element<'a> {
    code: u32,
    data: &'a [u8],
}

/// The data elements of `bytes`, in order; `Err` names the offset where one does not fit.
fn elements(bytes: &[u8], endian: Endian) -> Result<Vec<Element<'_>>, String> {
    let mut out = Vec::new();
    let mut at = 0usize;
    while at < bytes.len() {
        if bytes.len() - at < 8 {
            return Err(format!("{} stray bytes at offset {at}", bytes.len() - at));
        }
        let first = endian.u32(&bytes[at..]);
        if first >> 16 != 0 {
            // The small form: the count in the upper half, the data in the next 4 bytes.
            let count = (first >> 16) as usize;
            if count > 4 {
                return Err(format!(
                    "a small element of {count} bytes at offset {at} (at most 4)"
                ));
            }
            out.push(Element {
                code: first & 0xffff,
                data: &bytes[at + 4..at + 4 + count],
            });
            at += 8;
            continue;
        }
        let count = endian.u32(&bytes[at + 4..]) as usize;
        let start = at + 8;
        let end = start
            .checked_add(count)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                format!(
                    "an element at offset {at} counts {count} bytes, more than the {} left",
                    bytes.len() - start
                )
            })?;
        out.push(Element {
            code: first,
            data: &bytes[start..end],
        });
        // Every element but a compressed one is padded to 8 bytes.
        at = if first == 15 {
            end
        } else {
            end.div_ceil(8).saturating_mul(8).min(bytes.len().max(end))
        };
    }
    Ok(out)
}

/// A numeric variable as found: its name, class, shape and data.
struct Variable {
    name: String,
    class: &'static str,
    rows: usize,
    columns: usize,
    code: u32,
    data: Vec<u8>,
    complex: bool,
    ndims: usize,
}

impl Variable {
    fn describe(&self) -> String {
        format!(
            "{} ({}×{} {})",
            self.name, self.rows, self.columns, self.class
        )
    }
}

/// The numeric class names, by class code 6–15.
const CLASSES: [&str; 10] = [
    "double", "single", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
];

/// The variable in a miMATRIX element's data, if it is a numeric array; `Err` says what is
/// malformed.
fn variable(data: &[u8], endian: Endian) -> Result<Option<Variable>, String> {
    let parts = elements(data, endian)?;
    let [flags, dims, name, rest @ ..] = parts.as_slice() else {
        return Err("a variable without its flags, dimensions and name".into());
    };
    if flags.data.len() < 8 || dims.data.len() < 8 || dims.data.len() % 4 != 0 {
        return Err("a variable whose flags or dimensions are cut short".into());
    }
    let f = endian.u32(flags.data);
    let class = (f & 0xff) as usize;
    let name = String::from_utf8_lossy(name.data).into_owned();
    // Logical arrays are stored as uint8 with a flag; neither they nor cells, structs,
    // characters or sparse matrices are records.
    if !(6..=15).contains(&class) || f & 0x0200 != 0 {
        return Ok(None);
    }
    let shape: Vec<i32> = dims.data.chunks_exact(4).map(|c| endian.i32(c)).collect();
    if shape.iter().any(|&d| d < 0) {
        return Err(format!("variable `{name}` has dimensions {shape:?}"));
    }
    let Some(real) = rest.first() else {
        return Err(format!("variable `{name}` has no data"));
    };
    let width = element_width(real.code)
        .ok_or_else(|| format!("variable `{name}` is stored as element type {}", real.code))?;
    let elements: Option<usize> = shape
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d as usize));
    // Trailing dimensions of 1 do not count (MATLAB drops them).
    let ndims = if shape[2..].iter().any(|&d| d != 1) {
        shape.len()
    } else {
        2
    };
    let (rows, columns) = (shape[0] as usize, shape[1] as usize);
    match elements.and_then(|e| e.checked_mul(width)) {
        Some(b) if b <= real.data.len() => {}
        _ => {
            return Err(format!(
                "variable `{name}` is {shape:?} values of {width} bytes, more than its {} bytes of data",
                real.data.len()
            ));
        }
    }
    Ok(Some(Variable {
        name,
        class: CLASSES[class - 6],
        rows,
        columns,
        code: real.code,
        data: real.data.to_vec(),
        complex: f & 0x0800 != 0,
        ndims,
    }))
}

/// Read one variable of the MAT-file at `path` as a table of its columns: the one named
/// `variable`, else the only numeric variable of more than one element (see the module's
/// documentation).
pub fn read_mat(path: &Path, variable_name: Option<&str>) -> Result<Table, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.len() >= 520 && &bytes[512..520] == b"\x89HDF\r\n\x1a\n" {
        return Err(bad(
            path,
            "a MATLAB 7.3 file (HDF5), which is not read: save it with `save -v7` (or scipy.io.savemat)",
        ));
    }
    if bytes.len() < 128 || !bytes.starts_with(b"MATLAB 5.0 MAT-file") {
        return Err(bad(
            path,
            "not a MATLAB level 5 MAT-file (its header does not start `MATLAB 5.0 MAT-file`)",
        ));
    }
    let endian = match &bytes[126..128] {
        b"IM" => Endian { little: true },
        b"MI" => Endian { little: false },
        other => {
            return Err(bad(
                path,
                format!("endian mark {other:?} is neither `IM` nor `MI`"),
            ));
        }
    };
    let top = elements(&bytes[128..], endian).map_err(|e| bad(path, e))?;
    let mut variables = Vec::new();
    for (k, e) in top.iter().enumerate() {
        let inflated;
        let matrix = match e.code {
            14 => e.data,
            15 => {
                let mut out = Vec::new();
                flate2::read::ZlibDecoder::new(e.data)
                    .read_to_end(&mut out)
                    .map_err(|x| bad(path, format!("element {}: not zlib data ({x})", k + 1)))?;
                inflated = out;
                let inner = elements(&inflated, endian)
                    .map_err(|x| bad(path, format!("element {} (compressed): {x}", k + 1)))?;
                match inner.first() {
                    Some(m) if m.code == 14 => m.data,
                    _ => continue,
                }
            }
            _ => continue,
        };
        if let Some(v) =
            variable(matrix, endian).map_err(|x| bad(path, format!("element {}: {x}", k + 1)))?
        {
            variables.push(v);
        }
    }
    let listing = variables
        .iter()
        .map(Variable::describe)
        .collect::<Vec<_>>()
        .join(", ");
    let mut chosen: Vec<Variable> = variables
        .into_iter()
        .filter(|v| match variable_name {
            Some(n) => v.name == n,
            None => v.rows.saturating_mul(v.columns) > 1,
        })
        .collect();
    if chosen.len() != 1 {
        return Err(IoError::Variable {
            path: path.to_path_buf(),
            asked: variable_name.map(str::to_string),
            available: listing,
        });
    }
    let v = chosen.remove(0);
    table(path, v, endian)
}

/// The table of the chosen variable.
fn table(path: &Path, v: Variable, endian: Endian) -> Result<Table, IoError> {
    if v.complex {
        return Err(bad(
            path,
            format!("variable {} is complex; a record is real", v.describe()),
        ));
    }
    if v.ndims > 2 {
        return Err(bad(
            path,
            format!(
                "variable `{}` has {} dimensions; a record is samples × channels",
                v.name, v.ndims
            ),
        ));
    }
    // A row vector is one channel; otherwise rows are samples.
    let (n, l, row_vector) = if v.rows == 1 {
        (v.columns, 1, true)
    } else {
        (v.rows, v.columns, false)
    };
    if n == 0 || l == 0 {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    if l > n {
        return Err(IoError::Transposed {
            path: path.to_path_buf(),
            rows: n,
            columns: l,
        });
    }
    let names: Vec<String> = (0..l).map(|c| c.to_string()).collect();
    // Column-major: a column's samples are contiguous (and so are a row vector's).
    let columns = (0..l)
        .map(|c| {
            let base = if row_vector { 0 } else { c * n };
            (0..n)
                .map(|s| endian.value(v.code, &v.data, base + s))
                .collect()
        })
        .collect();
    Ok(Table::new(path, names, columns))
}

#[cfg(test)]
mod tests;
