//! The reader against files laid out as the MAT-file format's description gives, written
//! here element by element; scipy.io.savemat's files are read in the Python tests.

use std::io::Write;

use super::*;
use crate::test_files::file_path;

/// A tag and its data, padded to 8 bytes (the small form for 1–4 bytes when `small`).
fn element(code: u32, data: &[u8], big: bool, small: bool) -> Vec<u8> {
    let u = |x: u32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let mut out = Vec::new();
    if small && !data.is_empty() && data.len() <= 4 {
        out.extend(u(((data.len() as u32) << 16) | code));
        out.extend(data);
        out.resize(8, 0);
        return out;
    }
    out.extend(u(code));
    out.extend(u(data.len() as u32));
    out.extend(data);
    while out.len() % 8 != 0 {
        out.push(0);
    }
    out
}

/// A variable: `name`, class code `class`, dimensions `dims`, data `values` stored as element
/// type `code` (`width` bytes each, converted by `enc`), complex flag.
struct Var<'a> {
    name: &'a str,
    class: u32,
    dims: Vec<i32>,
    code: u32,
    data: Vec<u8>,
    complex: bool,
}

fn doubles(v: &[f64], big: bool) -> Vec<u8> {
    v.iter()
        .flat_map(|x| {
            if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            }
        })
        .collect()
}

impl Var<'_> {
    fn double<'a>(name: &'a str, rows: i32, cols: i32, v: &[f64]) -> Var<'a> {
        Var {
            name,
            class: 6,
            dims: vec![rows, cols],
            code: 9,
            data: doubles(v, false),
            complex: false,
        }
    }

    fn matrix(&self, big: bool) -> Vec<u8> {
        let u = |x: u32| {
            if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            }
        };
        let mut flags = u(self.class | if self.complex { 0x0800 } else { 0 }).to_vec();
        flags.extend([0; 4]);
        let dims: Vec<u8> = self
            .dims
            .iter()
            .flat_map(|d| {
                if big {
                    d.to_be_bytes()
                } else {
                    d.to_le_bytes()
                }
            })
            .collect();
        let mut body = element(6, &flags, big, false);
        body.extend(element(5, &dims, big, false));
        body.extend(element(1, self.name.as_bytes(), big, true));
        body.extend(element(self.code, &self.data, big, false));
        if self.complex {
            body.extend(element(self.code, &self.data, big, false));
        }
        element(14, &body, big, false)
    }
}

/// A MAT-file of `vars`, each compressed when `compress`.
fn mat_file(vars: &[Var<'_>], big: bool, compress: bool) -> Vec<u8> {
    let mut out = format!("{:<116}", "MATLAB 5.0 MAT-file, written by hyst's tests").into_bytes();
    out.extend([0u8; 8]);
    out.extend(if big { [1u8, 0] } else { [0, 1] });
    out.extend(if big { b"MI" } else { b"IM" });
    for v in vars {
        let m = v.matrix(big);
        if compress {
            let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
            z.write_all(&m).unwrap();
            let z = z.finish().unwrap();
            let u = |x: u32| {
                if big {
                    x.to_be_bytes()
                } else {
                    x.to_le_bytes()
                }
            };
            out.extend(u(15));
            out.extend(u(z.len() as u32));
            out.extend(z);
        } else {
            out.extend(m);
        }
    }
    out
}

fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = file_path(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A 4 × 2 matrix, column-major.
const M: [f64; 8] = [1.0, 2.0, 3.0, 4.0, 10.0, 20.0, 30.0, 40.0];

#[test]
fn plain_compressed_big_endian_and_integer_stored_matrices_read_alike() {
    let want = vec![vec![1.0, 2.0, 3.0, 4.0], vec![10.0, 20.0, 30.0, 40.0]];
    for (big, compress) in [(false, false), (false, true), (true, false), (true, true)] {
        let mut v = Var::double("y", 4, 2, &M);
        v.data = doubles(&M, big);
        let mut fs = Var::double("fs", 1, 1, &[20.0]);
        fs.data = doubles(&[20.0], big);
        let p = write("m.mat", &mat_file(&[fs, v], big, compress));
        let t = read_mat(&p, None).unwrap();
        assert_eq!(t.columns, want, "big {big} compressed {compress}");
        assert_eq!(t.names, ["0", "1"]);
        // The scalar is there to be asked for.
        assert_eq!(read_mat(&p, Some("fs")).unwrap().columns, [vec![20.0]]);
    }
    // MATLAB stores a double array of small integers as uint8 or int16.
    let mut v = Var::double("y", 4, 2, &M);
    v.code = 2;
    v.data = M.iter().map(|&x| x as u8).collect();
    assert_eq!(
        read_mat(&write("u8.mat", &mat_file(&[v], false, false)), None)
            .unwrap()
            .columns,
        want
    );
    let mut v = Var::double("y", 4, 2, &M);
    v.code = 3;
    v.data = M
        .iter()
        .flat_map(|&x| (-(x as i16)).to_le_bytes())
        .collect();
    let t = read_mat(&write("i16.mat", &mat_file(&[v], false, false)), None).unwrap();
    assert_eq!(t.columns[1], [-10.0, -20.0, -30.0, -40.0]);
    // A row vector is one channel.
    let v = Var::double("y", 1, 8, &M);
    let t = read_mat(&write("row.mat", &mat_file(&[v], false, false)), None).unwrap();
    assert_eq!(t.columns, [M.to_vec()]);
}

#[test]
fn bad_files_are_refused_naming_the_problem() {
    let hdf5 = {
        let mut b = format!("{:<116}", "MATLAB 7.3 MAT-file").into_bytes();
        b.resize(512, 0);
        b.extend(b"\x89HDF\r\n\x1a\n");
        b.resize(600, 0);
        b
    };
    let two = mat_file(
        &[Var::double("a", 4, 2, &M), Var::double("b", 4, 2, &M)],
        false,
        false,
    );
    let complex = {
        let mut v = Var::double("z", 4, 2, &M);
        v.complex = true;
        mat_file(&[v], false, true)
    };
    let cube = {
        let mut v = Var::double("c", 2, 2, &M);
        v.dims = vec![2, 2, 2];
        mat_file(&[v], false, false)
    };
    let nan = mat_file(
        &[Var::double("y", 4, 1, &[1.0, 2.0, f64::NAN, 3.0])],
        false,
        false,
    );
    let wide = mat_file(&[Var::double("y", 2, 4, &M)], false, false);
    let short = {
        let mut b = mat_file(&[Var::double("y", 4, 2, &M)], false, false);
        b.truncate(b.len() - 16);
        b
    };
    let overstated = {
        let mut v = Var::double("y", 4, 2, &M);
        v.dims = vec![400, 2];
        mat_file(&[v], false, false)
    };
    let text = {
        let mut v = Var::double("s", 1, 3, &[]);
        v.class = 4;
        v.code = 4;
        v.data = b"a\0b\0c\0".to_vec();
        mat_file(&[v], false, false)
    };
    let cases: Vec<(&str, Vec<u8>, Option<&str>, &str)> = vec![
        ("v73.mat", hdf5, None, "a MATLAB 7.3 file (HDF5)"),
        (
            "csv.mat",
            b"t,y\n0,1\n".to_vec(),
            None,
            "not a MATLAB level 5 MAT-file",
        ),
        (
            "two.mat",
            two.clone(),
            None,
            "the file holds several arrays (a (4×2 double), b (4×2 double))",
        ),
        (
            "two_asked.mat",
            two,
            Some("c"),
            "no array `c` (the file holds: a (4×2 double), b (4×2 double))",
        ),
        (
            "complex.mat",
            complex,
            None,
            "variable z (4×2 double) is complex",
        ),
        ("cube.mat", cube, None, "variable `c` has 3 dimensions"),
        (
            "nan.mat",
            nan,
            None,
            "row 3, column `0`: value NaN is not finite",
        ),
        ("wide.mat", wide, None, "the array is 2 × 4"),
        (
            "short.mat",
            short,
            None,
            "an element at offset 0 counts 112 bytes, more than the 96 left",
        ),
        (
            "overstated.mat",
            overstated,
            None,
            "more than its 64 bytes of data",
        ),
        ("text.mat", text, None, "no numeric array in the file"),
    ];
    for (name, bytes, var, says) in cases {
        let path = write(name, &bytes);
        // Refused by the reader, or (a cell that is not finite) when its column is taken.
        let e = crate::test_files::taken(read_mat(&path, var))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&path.display().to_string()), "{e}");
        assert!(e.contains(says), "{name}: {e}");
    }
}

proptest::proptest! {
    /// No bytes make the reader panic: a valid file (one plain and one compressed variable)
    /// with bytes changed anywhere, cut anywhere and anything appended is read or refused
    /// with an error naming the file.
    #[test]
    fn any_bytes_are_read_or_refused(
        tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..100),
        flips in proptest::collection::vec((0usize..600, proptest::prelude::any::<u8>()), 0..6),
        cut in 0usize..600,
    ) {
        let mut bytes = mat_file(&[Var::double("y", 4, 2, &M)], false, false);
        bytes.extend(mat_file(&[Var::double("x", 8, 1, &M)], false, true)[128..].iter());
        let bytes = crate::test_files::mutated(bytes, &flips, cut, &tail);
        let path = write("fuzz.mat", &bytes);
        for var in [None, Some("x")] {
            match read_mat(&path, var) {
                Ok(t) => proptest::prop_assert!(crate::test_files::well_formed(&t)),
                Err(e) => proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string())),
            }
        }
    }
}
