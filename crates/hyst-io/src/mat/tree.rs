//! A MAT-file variable as the tree it is: numeric arrays, text, structs and cells nested in
//! one another.
//!
//! A miMATRIX element's sub-elements are its flags (the class in the low byte), its
//! dimensions and its name, then by class: a numeric array's real (and imaginary) part; a
//! character array's codes; a struct's field-name length (miINT32), its field names (miINT8,
//! each NUL-padded to that length) and one miMATRIX per element and field, elements in
//! column-major order and fields in order within each; a cell's one miMATRIX per element.
//! An empty field is a miMATRIX of no bytes.

use super::{CLASSES, Endian, Variable, element_width, elements};

/// How deep structs and cells may nest: a file deeper than this is refused rather than
/// followed (a real record nests two or three levels).
const DEEPEST: usize = 16;

/// A variable's value.
pub(super) enum Node {
    /// A real or complex numeric array.
    Numeric(Variable),
    /// A character array, as its text.
    Text(String),
    /// A struct array: `shape`, field names, and per element (column-major) the field values.
    Struct {
        shape: (usize, usize),
        fields: Vec<String>,
        values: Vec<Vec<Node>>,
    },
    /// A cell array: `shape` and its items, column-major.
    Cell {
        shape: (usize, usize),
        items: Vec<Node>,
    },
    /// Anything else (sparse, logical, object, function handle): its class.
    Other { class: &'static str },
    /// A field left empty.
    Empty,
}

/// The class names by class code 1–5.
const NON_NUMERIC: [&str; 5] = ["cell", "struct", "object", "char", "sparse"];

/// The variable in a miMATRIX element's data: its name and value; `Err` says what is
/// malformed.
pub(super) fn node(data: &[u8], endian: Endian, depth: usize) -> Result<(String, Node), String> {
    if data.is_empty() {
        return Ok((String::new(), Node::Empty));
    }
    if depth > DEEPEST {
        return Err(format!("structs and cells nested more than {DEEPEST} deep"));
    }
    let parts = elements(data, endian)?;
    let [flags, dims, name, rest @ ..] = parts.as_slice() else {
        return Err("a variable without its flags, dimensions and name".into());
    };
    if flags.data.len() < 8 || dims.data.len() < 8 || dims.data.len() % 4 != 0 {
        return Err("a variable whose flags or dimensions are cut short".into());
    }
    let f = endian.u32(flags.data);
    let class = (f & 0xff) as usize;
    let name = String::from_utf8_lossy(name.data)
        .trim_end_matches('\0')
        .to_string();
    let shape: Vec<i32> = dims.data.chunks_exact(4).map(|c| endian.i32(c)).collect();
    if shape.iter().any(|&d| d < 0) {
        return Err(format!("variable `{name}` has dimensions {shape:?}"));
    }
    let count = shape
        .iter()
        .try_fold(1usize, |a, &d| a.checked_mul(d as usize));
    let plane = (shape[0] as usize, shape[1] as usize);
    let value = match class {
        // Logical arrays are stored as uint8 with a flag.
        6..=15 if f & 0x0200 != 0 => Node::Other { class: "logical" },
        6..=15 => Node::Numeric(numeric(&name, class, &shape, count, rest, f)?),
        4 => Node::Text(text(plane, rest, endian)),
        2 => structure(&name, plane, count, rest, endian, depth)?,
        1 => {
            let items = children(&name, count, 1, rest, endian, depth)?;
            Node::Cell {
                shape: plane,
                items,
            }
        }
        _ => Node::Other {
            class: NON_NUMERIC
                .get(class.wrapping_sub(1))
                .copied()
                .unwrap_or("opaque"),
        },
    };
    Ok((name, value))
}

/// A numeric array's parts: its data checked to hold every element its shape counts.
fn numeric(
    name: &str,
    class: usize,
    shape: &[i32],
    count: Option<usize>,
    rest: &[super::Element<'_>],
    flags: u32,
) -> Result<Variable, String> {
    let Some(real) = rest.first() else {
        return Err(format!("variable `{name}` has no data"));
    };
    let width = element_width(real.code)
        .ok_or_else(|| format!("variable `{name}` is stored as element type {}", real.code))?;
    // Trailing dimensions of 1 do not count (MATLAB drops them).
    let ndims = if shape[2..].iter().any(|&d| d != 1) {
        shape.len()
    } else {
        2
    };
    match count.and_then(|e| e.checked_mul(width)) {
        Some(b) if b <= real.data.len() => {}
        _ => {
            return Err(format!(
                "variable `{name}` is {shape:?} values of {width} bytes, more than its {} bytes of data",
                real.data.len()
            ));
        }
    }
    Ok(Variable {
        name: name.to_string(),
        class: CLASSES[class - 6],
        rows: shape[0] as usize,
        columns: shape[1] as usize,
        code: real.code,
        data: real.data.to_vec(),
        complex: flags & 0x0800 != 0,
        ndims,
    })
}

/// A character array's text: rows joined by a space (a name is one row).
fn text(shape: (usize, usize), rest: &[super::Element<'_>], endian: Endian) -> String {
    let Some(codes) = rest.first() else {
        return String::new();
    };
    let chars: Vec<char> = match codes.code {
        16 => String::from_utf8_lossy(codes.data).chars().collect(),
        17 | 4 => char::decode_utf16(codes.data.chunks_exact(2).map(|c| {
            let a = [c[0], c[1]];
            if endian.little {
                u16::from_le_bytes(a)
            } else {
                u16::from_be_bytes(a)
            }
        }))
        .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
        .collect(),
        _ => codes.data.iter().map(|&b| char::from(b)).collect(),
    };
    let (rows, columns) = shape;
    let row = |i: usize| -> String {
        (0..columns)
            .filter_map(|j| chars.get(i + rows * j))
            .collect::<String>()
    };
    let text = if rows > 1 && rows.checked_mul(columns) == Some(chars.len()) {
        (0..rows).map(row).collect::<Vec<_>>().join(" ")
    } else {
        chars.into_iter().collect()
    };
    text.trim_matches(|c: char| c == '\0' || c.is_whitespace())
        .to_string()
}

/// A struct array's field names and values.
fn structure(
    name: &str,
    shape: (usize, usize),
    count: Option<usize>,
    rest: &[super::Element<'_>],
    endian: Endian,
    depth: usize,
) -> Result<Node, String> {
    let [length, names, values @ ..] = rest else {
        return Err(format!("struct `{name}` without its field names"));
    };
    let width = if length.data.len() >= 4 {
        endian.u32(length.data) as usize
    } else {
        0
    };
    if width == 0 || names.data.len() % width != 0 {
        return Err(format!(
            "struct `{name}`: field names of {} bytes are not a whole number of {width}-byte names",
            names.data.len()
        ));
    }
    let fields: Vec<String> = names
        .data
        .chunks(width)
        .map(|c| {
            let end = c.iter().position(|&b| b == 0).unwrap_or(c.len());
            String::from_utf8_lossy(&c[..end]).into_owned()
        })
        .collect();
    let mut all = children(name, count, fields.len(), values, endian, depth)?.into_iter();
    // A struct without fields holds nothing, however many elements it counts.
    let elements = if fields.is_empty() {
        0
    } else {
        count.unwrap_or(0)
    };
    let values = (0..elements)
        .map(|_| all.by_ref().take(fields.len()).collect())
        .collect();
    Ok(Node::Struct {
        shape,
        fields,
        values,
    })
}

/// The `count` × `per` miMATRIX elements a struct or cell holds, read.
fn children(
    name: &str,
    count: Option<usize>,
    per: usize,
    values: &[super::Element<'_>],
    endian: Endian,
    depth: usize,
) -> Result<Vec<Node>, String> {
    if count.and_then(|c| c.checked_mul(per)) != Some(values.len()) {
        return Err(format!(
            "`{name}` holds {} values where its dimensions count {} × {per}",
            values.len(),
            count.map_or("too many".to_string(), |c| c.to_string())
        ));
    }
    values
        .iter()
        .enumerate()
        .map(|(k, e)| {
            if e.code != 14 {
                return Err(format!(
                    "`{name}`: value {} is element type {}, not a matrix",
                    k + 1,
                    e.code
                ));
            }
            node(e.data, endian, depth + 1).map(|(_, n)| n)
        })
        .collect()
}

impl Node {
    /// The value's shape and class, as a listing names it: `4×2 double`,
    /// `1×1 struct; fields a, b`.
    pub(super) fn describe(&self) -> String {
        match self {
            Node::Numeric(v) => format!("{}×{} {}", v.rows, v.columns, v.class),
            Node::Text(t) if t.chars().count() > 24 => {
                format!("char '{}…'", t.chars().take(24).collect::<String>())
            }
            Node::Text(t) => format!("char '{t}'"),
            Node::Struct { shape, fields, .. } => {
                let mut names = fields
                    .iter()
                    .take(6)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ");
                if fields.len() > 6 {
                    names.push_str(", …");
                }
                format!("{}×{} struct; fields {names}", shape.0, shape.1)
            }
            Node::Cell { shape, .. } => format!("{}×{} cell", shape.0, shape.1),
            Node::Other { class } => class.to_string(),
            Node::Empty => "empty".to_string(),
        }
    }

    /// The field `name` of a 1 × 1 struct.
    pub(super) fn field(&self, name: &str) -> Option<&Node> {
        match self {
            Node::Struct { fields, values, .. } if values.len() == 1 => {
                fields.iter().position(|f| f == name).map(|i| &values[0][i])
            }
            _ => None,
        }
    }
}
