//! NumPy records: a `.npy` file, or one array of a `.npz` archive, holding a 1-D array (one
//! channel) or a 2-D array of samples × channels, of float64, float32 or integers, little- or
//! big-endian, in C or Fortran order, read by `npyz` (and `zip` for the archive). The columns
//! are named by their index, `0`, `1`, …, as the command line's `--columns` then takes them.
//! Every error names the file (and the archive's array) and what is wrong: the dtype, the
//! shape, a length the file does not hold, a value that is not finite (with its sample,
//! 1-based, and column).

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
    array_table(path, npy, size, "")
}

/// Read one array of the `.npz` archive at `path`: the one named `variable`, else the only
/// array with more than one element (see the module's documentation).
pub fn read_npz(path: &Path, variable: Option<&str>) -> Result<Table, IoError> {
    let file_error = |source| IoError::File {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(file_error)?;
    let mut zip = zip::ZipArchive::new(std::io::BufReader::new(file))
        .map_err(|e| bad(path, format!("not a NumPy .npz archive ({e})")))?;
    // Each member's name and shape, from its header alone.
    let mut arrays: Vec<(usize, String, Vec<u64>)> = Vec::new();
    for i in 0..zip.len() {
        let member = zip
            .by_index(i)
            .map_err(|e| bad(path, format!("archive member {i}: {e}")))?;
        let member_name = member
            .name()
            .map_err(|e| bad(path, format!("archive member {i}: {e}")))?
            .into_owned();
        let Some(name) = member_name.strip_suffix(".npy").map(str::to_string) else {
            continue;
        };
        let npy = NpyFile::new(member)
            .map_err(|e| bad(path, format!("array `{name}`: not a NumPy array ({e})")))?;
        arrays.push((i, name, npy.shape().to_vec()));
    }
    let listing = || {
        arrays
            .iter()
            .map(|(_, n, s)| format!("{n} {s:?}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let chosen: Vec<&(usize, String, Vec<u64>)> = match variable {
        Some(v) => arrays.iter().filter(|(_, n, _)| n == v).collect(),
        None => arrays
            .iter()
            .filter(|(_, _, s)| s.iter().product::<u64>() > 1)
            .collect(),
    };
    let &[(index, name, _)] = chosen.as_slice() else {
        return Err(IoError::Variable {
            path: path.to_path_buf(),
            asked: variable.map(str::to_string),
            available: listing(),
        });
    };
    let member = zip
        .by_index(*index)
        .map_err(|e| bad(path, format!("array `{name}`: {e}")))?;
    let size = member.size();
    let npy = NpyFile::new(member)
        .map_err(|e| bad(path, format!("array `{name}`: not a NumPy array ({e})")))?;
    array_table(path, npy, size, &format!("array `{name}`: "))
}

/// The table of the array `npy`, whose file holds `size` bytes in all; `label` starts its
/// errors (the archive's array).
fn array_table<R: Read>(
    path: &Path,
    npy: NpyFile<R>,
    size: u64,
    label: &str,
) -> Result<Table, IoError> {
    let shape = npy.shape().to_vec();
    let (n, l) = match shape[..] {
        [n] => (n, 1),
        [n, l] => (n, l),
        _ => {
            return Err(bad(
                path,
                format!(
                    "{label}the array has shape {shape:?}; a record is (samples,) or (samples, channels)"
                ),
            ));
        }
    };
    // Integers (an acquisition's counts) are read as the numbers they are; above 2^53 an
    // int64 or uint64 rounds to the nearest double.
    let (kind, width) = match npy.dtype() {
        DType::Plain(t)
            if (t.type_char() == TypeChar::Float && matches!(t.size_field(), 4 | 8))
                || (matches!(t.type_char(), TypeChar::Int | TypeChar::Uint)
                    && matches!(t.size_field(), 1 | 2 | 4 | 8)) =>
        {
            (t.type_char(), t.size_field())
        }
        other => {
            return Err(bad(
                path,
                format!(
                    "{label}dtype {} is not a float or integer array",
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
    // A (1, N) row is one channel, as a 1-D array is; other arrays of more columns than rows
    // are most likely channels × samples.
    if l > n && n > 1 {
        return Err(IoError::Transposed {
            path: path.to_path_buf(),
            rows: n as usize,
            columns: l as usize,
        });
    }
    // The header's shape against the file's size, before anything is allocated for it.
    let needed = n.checked_mul(l).and_then(|c| c.checked_mul(width));
    if needed.is_none_or(|b| b > size) {
        return Err(bad(
            path,
            format!(
                "{label}the header says {n} × {l} values of {width} bytes, more than the file's {size} bytes hold"
            ),
        ));
    }
    let (n, l) = if n == 1 {
        (l as usize, 1)
    } else {
        (n as usize, l as usize)
    };
    let fortran = npy.order() == Order::Fortran;
    let values = read_values(npy, kind, width)
        .map_err(|e| bad(path, format!("{label}reading the data: {e}")))?;
    if values.len() != n.saturating_mul(l) {
        return Err(bad(
            path,
            format!(
                "{label}the header says {} values, the data hold {}",
                n * l,
                values.len()
            ),
        ));
    }
    let at = |s: usize, c: usize| {
        if fortran || l == 1 {
            values[c * n + s]
        } else {
            values[s * l + c]
        }
    };
    let names: Vec<String> = (0..l).map(|c| c.to_string()).collect();
    let columns = (0..l).map(|c| (0..n).map(|s| at(s, c)).collect()).collect();
    Ok(Table::new(path, names, columns))
}

/// The array's values as f64, in the file's order.
fn read_values<R: Read>(npy: NpyFile<R>, kind: TypeChar, width: u64) -> std::io::Result<Vec<f64>> {
    fn all<T: Into<f64>>(v: Vec<T>) -> Vec<f64> {
        v.into_iter().map(Into::into).collect()
    }
    Ok(match (kind, width) {
        (TypeChar::Float, 4) => all(npy.into_vec::<f32>()?),
        (TypeChar::Float, _) => npy.into_vec::<f64>()?,
        (TypeChar::Int, 1) => all(npy.into_vec::<i8>()?),
        (TypeChar::Int, 2) => all(npy.into_vec::<i16>()?),
        (TypeChar::Int, 4) => all(npy.into_vec::<i32>()?),
        (TypeChar::Int, _) => npy
            .into_vec::<i64>()?
            .into_iter()
            .map(|v| v as f64)
            .collect(),
        (_, 1) => all(npy.into_vec::<u8>()?),
        (_, 2) => all(npy.into_vec::<u16>()?),
        (_, 4) => all(npy.into_vec::<u32>()?),
        (_, _) => npy
            .into_vec::<u64>()?
            .into_iter()
            .map(|v| v as f64)
            .collect(),
    })
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
        let path = crate::test_files::file_path(name);
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
        // Integers, as the README says they are read: int16 counts, a uint8, a big-endian
        // int64 beside them.
        let i16s: Vec<u8> = [-3i16, 1000, 7, -8]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let t = read_npy(&write(
            "i2.npy",
            &npy_bytes(
                "{'descr': '<i2', 'fortran_order': False, 'shape': (2, 2), }",
                &i16s,
            ),
        ))
        .unwrap();
        assert_eq!(t.columns, [vec![-3.0, 7.0], vec![1000.0, -8.0]]);
        let t = read_npy(&write(
            "u1.npy",
            &npy_bytes(
                "{'descr': '|u1', 'fortran_order': False, 'shape': (3,), }",
                &[0, 200, 255],
            ),
        ))
        .unwrap();
        assert_eq!(t.columns, [vec![0.0, 200.0, 255.0]]);
        let i64s: Vec<u8> = [-5i64, 1 << 40]
            .iter()
            .flat_map(|x| x.to_be_bytes())
            .collect();
        let t = read_npy(&write(
            "i8.npy",
            &npy_bytes(
                "{'descr': '>i8', 'fortran_order': False, 'shape': (2,), }",
                &i64s,
            ),
        ))
        .unwrap();
        assert_eq!(t.columns, [vec![-5.0, (1u64 << 40) as f64]]);
    }

    #[test]
    fn bad_files_are_errors_naming_the_file_and_the_problem() {
        let cases: [(&str, Vec<u8>, &str); 6] = [
            ("text.npy", b"t,y\n1,2\n".to_vec(), "not a NumPy .npy file"),
            (
                "complex.npy",
                npy_bytes(
                    "{'descr': '<c16', 'fortran_order': False, 'shape': (1,), }",
                    &le64(&[1.0, 2.0]),
                ),
                "dtype '<c16' is not a float or integer array",
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
        // A value that is not finite is named, by its row, when its column is taken.
        let path = write(
            "nan.npy",
            &npy_bytes(
                "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }",
                &le64(&[1.0, 5.0, f64::NAN, 6.0]),
            ),
        );
        let t = read_npy(&path).unwrap();
        let e = t.column("0").unwrap_err().to_string();
        assert!(
            e.contains("row 2, column `0`: value NaN is not finite"),
            "{e}"
        );
        assert_eq!(t.column("1").unwrap(), [5.0, 6.0]);
    }

    /// An archive of `members` (name, bytes), deflated when `deflate`.
    fn npz_bytes(members: &[(&str, Vec<u8>)], deflate: bool) -> Vec<u8> {
        use std::io::Write;
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        let method = if deflate {
            zip::CompressionMethod::Deflated
        } else {
            zip::CompressionMethod::Stored
        };
        let opts = zip::write::SimpleFileOptions::default().compression_method(method);
        for (name, bytes) in members {
            zip.start_file(*name, opts).unwrap();
            zip.write_all(bytes).unwrap();
        }
        zip.finish().unwrap().into_inner()
    }

    #[test]
    fn an_npz_array_is_read_by_name_or_as_the_only_record() {
        let y = npy_bytes(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (3, 2), }",
            &le64(&[1.0, 10.0, 2.0, 20.0, 3.0, 30.0]),
        );
        let fs = npy_bytes(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (), }",
            &le64(&[20.0]),
        );
        let want = [vec![1.0, 2.0, 3.0], vec![10.0, 20.0, 30.0]];
        for deflate in [false, true] {
            let p = write(
                "two.npz",
                &npz_bytes(&[("fs.npy", fs.clone()), ("y.npy", y.clone())], deflate),
            );
            assert_eq!(read_npz(&p, None).unwrap().columns, want);
            assert_eq!(read_npz(&p, Some("y")).unwrap().columns, want);
            let e = read_npz(&p, Some("z")).unwrap_err().to_string();
            assert!(
                e.contains("no array `z` (the file holds: fs [], y [3, 2])"),
                "{e}"
            );
            // A 0-d array is not a record.
            let e = read_npz(&p, Some("fs")).unwrap_err().to_string();
            assert!(e.contains("array `fs`: the array has shape []"), "{e}");
        }
        let p = write(
            "twice.npz",
            &npz_bytes(&[("a.npy", y.clone()), ("b.npy", y)], false),
        );
        let e = read_npz(&p, None).unwrap_err().to_string();
        assert!(
            e.contains("holds several arrays (a [3, 2], b [3, 2])"),
            "{e}"
        );
        let e = read_npz(&write("text.npz", b"t,y\n"), None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a NumPy .npz archive"), "{e}");
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
            let bytes = npy_bytes(
                "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 2), }",
                &le64(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]),
            );
            let bytes = crate::test_files::mutated(bytes, &flips, cut, &tail);
            let path = write("fuzz.npy", &bytes);
            if let Err(e) = read_npy(&path) {
                proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string()));
            }
        }

        /// Nor does any archive: a valid one (stored or deflated) with bytes changed anywhere,
        /// cut anywhere and anything appended.
        #[test]
        fn any_archive_bytes_are_read_or_refused(
            deflate in proptest::prelude::any::<bool>(),
            tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..100),
            flips in proptest::collection::vec((0usize..500, proptest::prelude::any::<u8>()), 0..6),
            cut in 0usize..500,
        ) {
            let y = npy_bytes(
                "{'descr': '<f8', 'fortran_order': False, 'shape': (4, 2), }",
                &le64(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]),
            );
            let bytes = npz_bytes(&[("y.npy", y)], deflate);
            let bytes = crate::test_files::mutated(bytes, &flips, cut, &tail);
            let path = write("fuzz.npz", &bytes);
            if let Err(e) = read_npz(&path, None) {
                proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string()));
            }
        }
    }
}
