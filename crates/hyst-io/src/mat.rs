//! MATLAB records: a numeric variable, or a struct of channels, of a level 5 MAT-file, the
//! format of MATLAB's `save` (`-v6`, and `-v7`, whose variables are zlib-compressed) and of
//! `scipy.io.savemat`.
//!
//! The file is a 128-byte header (text, then the version and an endian mark, `IM` for a
//! little-endian file) and a sequence of data elements, each a tag (type, byte count; the
//! small form packs both into 4 bytes with the data in the next 4) and its data padded to 8
//! bytes. A variable is an element of type miMATRIX, whose sub-elements are its flags (class,
//! complex), its dimensions, its name and its real (then imaginary) part, stored in whatever
//! integer or float type holds it; type miCOMPRESSED wraps such an element in zlib. Structs
//! and cells nest further miMATRIX elements ([`tree`]).
//!
//! The record is the variable named by the caller (a dotted path, `rec.p1`, reaches into a
//! struct), else the file's only numeric variable of more than one element, else its only
//! struct or cell that holds channels. A numeric record must be real and 2-D: rows are
//! samples and columns channels, named `0`, `1`, … (a 1 × N row vector is one channel; a
//! matrix of more columns than rows is refused as transposed). A struct's channels are found
//! as [`gather`] describes, named by the sensors. A scalar named `fs` (at the top, or in the
//! struct) states the sampling rate. Version 7.3 files are HDF5, and are refused with that
//! advice.

use std::io::Read;
use std::path::Path;

use super::{IoError, Table};

mod gather;
mod tree;

use gather::Gathered;
use tree::Node;

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
    let mut variables: Vec<(String, Node)> = Vec::new();
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
        let v = tree::node(matrix, endian, 0)
            .map_err(|x| bad(path, format!("element {}: {x}", k + 1)))?;
        variables.push(v);
    }
    let (name, chosen) = choose(path, &variables, variable_name, endian)?;
    let mut rates = Gathered::default();
    for (n, v) in &variables {
        rates.gather_rate(n, v, endian);
    }
    let mut t = match chosen {
        Node::Numeric(v) => table(path, v, endian)?,
        group => gathered(path, &name, group, endian, &mut rates)?,
    };
    t.rate_hz = rate(path, &rates.rates)?;
    Ok(t)
}

/// The variable that is the record: the one `asked` for (a dotted path reaches into
/// structs), else the only numeric array of more than one element or, if there is none, the
/// only struct or cell holding channels. Returns its name and value.
fn choose<'a>(
    path: &Path,
    variables: &'a [(String, Node)],
    asked: Option<&str>,
    endian: Endian,
) -> Result<(String, &'a Node), IoError> {
    let listing = || {
        variables
            .iter()
            .map(|(n, v)| format!("{n} ({})", v.describe()))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let missing = || IoError::Variable {
        path: path.to_path_buf(),
        asked: asked.map(str::to_string),
        available: listing(),
    };
    if let Some(asked) = asked {
        let mut steps = asked.split('.');
        let first = steps.next().unwrap_or_default();
        let mut at = variables
            .iter()
            .find(|(n, _)| n == first)
            .map(|(_, v)| v)
            .ok_or_else(missing)?;
        for step in steps {
            at = at.field(step).ok_or_else(|| {
                bad(
                    path,
                    format!(
                        "`{asked}`: `{step}` is not a field of a 1×1 struct there (it is {})",
                        at.describe()
                    ),
                )
            })?;
        }
        return Ok((asked.to_string(), at));
    }
    let arrays: Vec<&(String, Node)> = variables
        .iter()
        .filter(|(_, v)| matches!(v, Node::Numeric(a) if a.rows.saturating_mul(a.columns) > 1))
        .collect();
    let groups: Vec<&(String, Node)> = variables
        .iter()
        .filter(|(n, v)| {
            let mut g = Gathered::default();
            matches!(v, Node::Struct { .. } | Node::Cell { .. })
                && g.gather(n, v, endian)
                    .is_ok_and(|()| !g.channels.is_empty())
        })
        .collect();
    match (arrays.as_slice(), groups.as_slice()) {
        ([(n, v)], []) | ([], [(n, v)]) => Ok((n.clone(), v)),
        ([], []) if !variables.is_empty() => Err(bad(
            path,
            format!(
                "no numeric array, and no struct or cell of channels, in the file (it holds: {})",
                listing()
            ),
        )),
        _ => Err(missing()),
    }
}

/// The table of the channels a struct or cell gathers.
fn gathered(
    path: &Path,
    name: &str,
    group: &Node,
    endian: Endian,
    found: &mut Gathered,
) -> Result<Table, IoError> {
    // A 1×1 struct's fields are named by themselves; an array's elements by their index.
    let place = match group {
        Node::Struct { values, .. } if values.len() == 1 => "",
        _ => name,
    };
    let mut g = Gathered {
        root: name.to_string(),
        ..Gathered::default()
    };
    g.gather(place, group, endian)
        .map_err(|e| bad(path, format!("`{name}`: {e}")))?;
    let Some(first) = g.channels.first() else {
        return Err(bad(
            path,
            format!(
                "`{name}` ({}) holds no numeric array of more than {} values",
                group.describe(),
                gather::SHORTEST
            ),
        ));
    };
    if let Some(c) = g
        .channels
        .iter()
        .find(|c| c.values.len() != first.values.len())
    {
        return Err(bad(
            path,
            format!(
                "`{name}`: channel `{}` holds {} samples and `{}` {}; a record's channels are as long as each other",
                first.place,
                first.values.len(),
                c.place,
                c.values.len()
            ),
        ));
    }
    let (names, note) = gather::names(&g.channels);
    found.rates.extend(g.rates);
    let mut t = Table::new(
        path,
        names,
        g.channels.into_iter().map(|c| c.values).collect(),
    );
    t.notes.push(format!(
        "{}: {} channel(s) read from `{name}` ({})",
        path.display(),
        t.names.len(),
        group.describe()
    ));
    t.notes
        .extend(note.map(|n| format!("{}: {n}", path.display())));
    Ok(t)
}

/// The sampling rate the file states, if its fields state one rate.
fn rate(path: &Path, rates: &[(String, f64)]) -> Result<Option<f64>, IoError> {
    let Some((at, first)) = rates.first() else {
        return Ok(None);
    };
    if let Some((p, r)) = rates
        .iter()
        .find(|(_, r)| !(r.is_finite() && *r > 0.0) || (r - first).abs() > 1e-9 * first)
    {
        return Err(bad(
            path,
            if r.is_finite() && *r > 0.0 {
                format!("`{at}` states a sampling rate of {first} Hz and `{p}` of {r} Hz")
            } else {
                format!("`{p}` states a sampling rate of {r}, not a positive number of Hz")
            },
        ));
    }
    Ok(Some(*first))
}

/// The table of the chosen variable.
fn table(path: &Path, v: &Variable, endian: Endian) -> Result<Table, IoError> {
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
