//! NumPy `.npy` records: a 1-D array (one channel) or a 2-D array of samples × channels, of
//! float64 or float32, little- or big-endian, in C or Fortran order, read by `npyz`. The
//! columns are named by their index, `0`, `1`, …, as the command line's `--columns` then
//! takes them. Every error names the file and what is wrong: the dtype, the shape, a length
//! the file does not hold, a value that is not finite (with its sample, 1-based, and column).

use std::io::Read;
use std::path::Path;

use npyz::{DType, NpyFile, Order, TypeChar};

use super::{IoError, Table};

/// The error of a file that is not a record this reader takes.
fn bad(path: &Path, what: impl Into<String>) -> IoError {
    IoError::Npy {
        path: path.to_path_buf(),
        what: what.into(),
    }
}

/// Read the `.npy` file at `path` as a table of its columns (see the module's documentation).
pub fn read_npy(path: &Path) -> Result<Table, IoError> {
    let file_error = |source| IoError::File {
        path: path.to_path_buf(),
        source,
    };
    let size = std::fs::metadata(path).map_err(file_error)?.len();
    let file = std::fs::File::open(path).map_err(file_error)?;
    let npy = NpyFile::new(std::io::BufReader::new(file))
        .map_err(|e| bad(path, format!("not a NumPy .npy file ({e})")))?;
    let shape = npy.shape().to_vec();
    let (n, l) = match shape[..] {
        [n] => (n, 1),
        [n, l] => (n, l),
        _ => {
            return Err(bad(
                path,
                format!(
                    "the array has shape {shape:?}; a record is (samples,) or (samples, channels)"
                ),
            ));
        }
    };
    let width = match npy.dtype() {
        DType::Plain(t) if t.type_char() == TypeChar::Float && matches!(t.size_field(), 4 | 8) => {
            t.size_field()
        }
        other => {
            return Err(bad(
                path,
                format!(
                    "dtype {} is not a float64 or float32 array",
                    other.descr().trim()
                ),
            ));
        }
    };
    if n == 0 || l == 0 {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    // The header's shape against the file's size, before anything is allocated for it.
    let needed = n.checked_mul(l).and_then(|c| c.checked_mul(width));
    if needed.is_none_or(|b| b > size) {
        return Err(bad(
            path,
            format!(
                "the header says {n} × {l} values of {width} bytes, more than the file's {size} bytes hold"
            ),
        ));
    }
    let (n, l) = (n as usize, l as usize);
    let fortran = npy.order() == Order::Fortran;
    let values =
        read_values(npy, width).map_err(|e| bad(path, format!("reading the data: {e}")))?;
    let at = |s: usize, c: usize| {
        if fortran || l == 1 {
            values[c * n + s]
        } else {
            values[s * l + c]
        }
    };
    let names: Vec<String> = (0..l).map(|c| c.to_string()).collect();
    let mut columns = Vec::with_capacity(l);
    for (c, name) in names.iter().enumerate() {
        let column: Vec<f64> = (0..n).map(|s| at(s, c)).collect();
        if let Some(s) = column.iter().position(|v| !v.is_finite()) {
            return Err(IoError::NonFinite {
                path: path.to_path_buf(),
                row: s + 1,
                column: name.clone(),
                value: column[s],
            });
        }
        columns.push(column);
    }
    Ok(Table {
        names,
        columns,
        path: path.to_path_buf(),
    })
}

/// The array's values as f64, in the file's order.
fn read_values<R: Read>(npy: NpyFile<R>, width: u64) -> std::io::Result<Vec<f64>> {
    if width == 4 {
        Ok(npy.into_vec::<f32>()?.into_iter().map(f64::from).collect())
    } else {
        npy.into_vec::<f64>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `.npy` file's bytes: version 1.0, the header dict `header`, then `data`.
    fn npy_bytes(header: &str, data: &[u8]) -> Vec<u8> {
        let mut dict = header.to_string();
        // The magic (6), version (2) and length (2) plus the dict and its newline pad to 64.
        while !(10 + dict.len() + 1).is_multiple_of(64) {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend((dict.len() as u16).to_le_bytes());
        out.extend(dict.as_bytes());
        out.extend(data);
        out
    }

    fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let path = crate::io::tests::file_path(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    fn le64(v: &[f64]) -> Vec<u8> {
        v.iter().flat_map(|x| x.to_le_bytes()).collect()
    }

    #[test]
    fn c_and_fortran_order_give_the_same_columns() {
        let c = npy_bytes(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (3, 2), }",
            &le64(&[1.0, 10.0, 2.0, 20.0, 3.0, 30.0]),
        );
        let f = npy_bytes(
            "{'descr': '<f8', 'fortran_order': True, 'shape': (3, 2), }",
            &le64(&[1.0, 2.0, 3.0, 10.0, 20.0, 30.0]),
        );
        for (name, bytes) in [("c.npy", c), ("f.npy", f)] {
            let t = read_npy(&write(name, &bytes)).unwrap();
            assert_eq!(t.names, ["0", "1"]);
            assert_eq!(t.columns, [vec![1.0, 2.0, 3.0], vec![10.0, 20.0, 30.0]]);
        }
    }

    #[test]
    fn one_dimension_float32_and_big_endian_are_read() {
        let f32s: Vec<u8> = [0.5f32, -1.25]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let t = read_npy(&write(
            "f4.npy",
            &npy_bytes(
                "{'descr': '<f4', 'fortran_order': False, 'shape': (2,), }",
                &f32s,
            ),
        ))
        .unwrap();
        assert_eq!(t.columns, [vec![0.5, -1.25]]);
        let be: Vec<u8> = [7.0f64, 8.0].iter().flat_map(|x| x.to_be_bytes()).collect();
        let t = read_npy(&write(
            "be.npy",
            &npy_bytes(
                "{'descr': '>f8', 'fortran_order': False, 'shape': (2,), }",
                &be,
            ),
        ))
        .unwrap();
        assert_eq!(t.columns, [vec![7.0, 8.0]]);
    }

    #[test]
    fn bad_files_are_errors_naming_the_file_and_the_problem() {
        let cases: [(&str, Vec<u8>, &str); 7] = [
            ("text.npy", b"t,y\n1,2\n".to_vec(), "not a NumPy .npy file"),
            (
                "int.npy",
                npy_bytes(
                    "{'descr': '<i8', 'fortran_order': False, 'shape': (2,), }",
                    &le64(&[1.0, 2.0]),
                ),
                "dtype '<i8' is not a float64 or float32 array",
            ),
            (
                "3d.npy",
                npy_bytes(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (1, 1, 2), }",
                    &le64(&[1.0, 2.0]),
                ),
                "shape [1, 1, 2]",
            ),
            (
                "short.npy",
                npy_bytes(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (4,), }",
                    &le64(&[1.0, 2.0]),
                ),
                "reading the data",
            ),
            (
                "huge.npy",
                npy_bytes(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000,), }",
                    &le64(&[1.0]),
                ),
                "more than the file's",
            ),
            (
                "nan.npy",
                npy_bytes(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }",
                    &le64(&[1.0, f64::NAN]),
                ),
                "row 2, column `0`: value NaN is not finite",
            ),
            (
                "empty.npy",
                npy_bytes(
                    "{'descr': '<f8', 'fortran_order': False, 'shape': (0,), }",
                    &[],
                ),
                "the record is empty",
            ),
        ];
        for (name, bytes, says) in cases {
            let path = write(name, &bytes);
            let e = read_npy(&path).unwrap_err().to_string();
            assert!(e.starts_with(&path.display().to_string()), "{e}");
            assert!(e.contains(says), "{name}: {e}");
        }
    }

    proptest::proptest! {
        /// No bytes make the reader panic: a valid header followed by anything, or a valid
        /// file with bytes changed anywhere, is read or refused with an error naming the file.
        #[test]
        fn any_bytes_are_read_or_refused(
            tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..200),
            flips in proptest::collection::vec((0usize..400, proptest::prelude::any::<u8>()), 0..6),
            cut in 0usize..400,
        ) {
            let mut bytes = npy_bytes(
                "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 2), }",
                &le64(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]),
            );
            for (at, b) in flips {
                if at < bytes.len() {
                    bytes[at] = b;
                }
            }
            bytes.truncate(cut.max(1));
            bytes.extend(&tail);
            let path = write("fuzz.npy", &bytes);
            if let Err(e) = read_npy(&path) {
                proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string()));
            }
        }
    }
}
