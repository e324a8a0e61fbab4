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
        (
            "text.mat",
            text,
            None,
            "no numeric array, and no struct or cell of channels, in the file (it holds: s (char 'abc'))",
        ),
    ];
    refused(cases);
}

/// Each case (file name, bytes, variable asked, what the error says) refused by the reader,
/// or (a cell that is not finite) when its column is taken, naming the file and the problem.
fn refused(cases: Vec<(&str, Vec<u8>, Option<&str>, &str)>) {
    for (name, bytes, var, says) in cases {
        let path = write(name, &bytes);
        let e = crate::test_files::taken(read_mat(&path, var))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&path.display().to_string()), "{e}");
        assert!(e.contains(says), "{name}: {e}");
    }
}

/// `bytes` (a changed file) read as each of `vars` or refused naming the file, never a panic.
fn read_or_refused(
    name: &str,
    bytes: &[u8],
    vars: &[Option<&str>],
) -> Result<(), proptest::test_runner::TestCaseError> {
    let path = write(name, bytes);
    for &var in vars {
        match read_mat(&path, var) {
            Ok(t) => proptest::prop_assert!(crate::test_files::well_formed(&t)),
            Err(e) => {
                proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string()))
            }
        }
    }
    Ok(())
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
        read_or_refused("fuzz.mat", &bytes, &[None, Some("x")])?;
    }
}

/// A MAT-file of whole miMATRIX elements, little-endian and uncompressed.
fn mat_of(matrices: &[Vec<u8>]) -> Vec<u8> {
    let mut out = mat_file(&[], false, false);
    matrices.iter().for_each(|m| out.extend(m));
    out
}

/// A character array `name` holding `text`, as MATLAB stores it (UTF-16 code units).
fn text_matrix(name: &str, text: &str) -> Vec<u8> {
    let units: Vec<u16> = text.encode_utf16().collect();
    let mut v = Var::double(name, 1, units.len() as i32, &[]);
    v.class = 4;
    v.code = 4;
    v.data = units.iter().flat_map(|u| u.to_le_bytes()).collect();
    v.matrix(false)
}

/// A numeric column vector `name`.
fn column(name: &str, values: &[f64]) -> Vec<u8> {
    Var::double(name, values.len() as i32, 1, values).matrix(false)
}

/// A struct array `name` of `dims` with `fields`; `values` per element (column-major), per
/// field, each a whole miMATRIX element (named "" as fields are).
fn struct_matrix(name: &str, dims: [i32; 2], fields: &[&str], values: &[Vec<u8>]) -> Vec<u8> {
    let mut body = element(6, &[2, 0, 0, 0, 0, 0, 0, 0], false, false);
    body.extend(element(
        5,
        &dims
            .iter()
            .flat_map(|d| d.to_le_bytes())
            .collect::<Vec<_>>(),
        false,
        false,
    ));
    body.extend(element(1, name.as_bytes(), false, true));
    body.extend(element(5, &32i32.to_le_bytes(), false, true));
    let names: Vec<u8> = fields
        .iter()
        .flat_map(|f| {
            let mut b = f.as_bytes().to_vec();
            b.resize(32, 0);
            b
        })
        .collect();
    body.extend(element(1, &names, false, false));
    values.iter().for_each(|v| body.extend(v));
    element(14, &body, false, false)
}

/// A sensor as a data owner saves it: its samples, name, units, position and direction.
fn sensor(name: &str, direction: &str, samples: &[f64]) -> Vec<u8> {
    struct_matrix(
        "",
        [1, 1],
        &["data", "name", "units", "position", "direction", "fs"],
        &[
            column("", samples),
            text_matrix("", name),
            text_matrix("", "m/s^2"),
            Var::double("", 1, 3, &[1.0, 2.0, 0.5]).matrix(false),
            text_matrix("", direction),
            Var::double("", 1, 1, &[10.0]).matrix(false),
        ],
    )
}

const A: [f64; 6] = [1.0, -2.0, 3.0, -4.0, 5.0, -6.0];
const B: [f64; 6] = [0.5, 0.25, -0.5, 1.5, -1.0, 2.0];

#[test]
fn a_struct_of_sensors_is_read_as_its_channels_named_by_the_sensors() {
    // One sub-struct per sensor, each naming itself: the channels in field order, named by
    // the sensors, at the rate their `fs` states.
    let rec = struct_matrix(
        "recording",
        [1, 1],
        &["p1", "p2", "note"],
        &[
            sensor("P1z", "z", &A),
            sensor("P2z", "z", &B),
            text_matrix("", "pontoons, ambient"),
        ],
    );
    let p = write("sensors.mat", &mat_of(std::slice::from_ref(&rec)));
    let t = read_mat(&p, None).unwrap();
    assert_eq!(t.names, ["P1z", "P2z"]);
    assert_eq!(t.columns, [A.to_vec(), B.to_vec()]);
    assert_eq!(t.rate_hz, Some(10.0));
    assert!(
        t.notes[0].contains("2 channel(s) read from `recording` (1×1 struct; fields p1, p2, note)"),
        "{:?}",
        t.notes
    );
    // Asked for by name, or one sensor by its path.
    assert_eq!(
        read_mat(&p, Some("recording")).unwrap().names,
        ["P1z", "P2z"]
    );
    assert_eq!(
        read_mat(&p, Some("recording.p2")).unwrap().columns,
        [B.to_vec()]
    );
    let e = read_mat(&p, Some("recording.p9")).unwrap_err().to_string();
    assert!(
        e.contains("`recording.p9`: `p9` is not a field of a 1×1 struct there"),
        "{e}"
    );

    // The same sensors as a 1 × 2 struct array; names that repeat (a triaxial sensor's
    // axes) are told apart by direction.
    let fields = ["data", "name", "units", "position", "direction", "fs"];
    let array = {
        let mut values = Vec::new();
        for (dir, v) in [("x", &A), ("y", &B)] {
            values.extend([
                column("", v),
                text_matrix("", "P1"),
                text_matrix("", "g"),
                Var::double("", 1, 3, &[0.0, 0.0, 0.0]).matrix(false),
                text_matrix("", dir),
                Var::double("", 1, 1, &[10.0]).matrix(false),
            ]);
        }
        struct_matrix("s", [1, 2], &fields, &values)
    };
    let t = read_mat(&write("array.mat", &mat_of(&[array])), None).unwrap();
    assert_eq!(t.names, ["P1_x", "P1_y"]);
    assert_eq!(t.columns, [A.to_vec(), B.to_vec()]);

    // Without names or directions to tell them apart, channels are named by their place.
    let same = struct_matrix(
        "rec",
        [1, 1],
        &["a", "b"],
        &[sensor("P1", "", &A), sensor("P1", "", &B)],
    );
    let t = read_mat(&write("same.mat", &mat_of(&[same])), None).unwrap();
    assert_eq!(t.names, ["a", "b"]);
    assert!(
        t.notes
            .iter()
            .any(|n| n.contains("sensor names repeat (`P1`)")),
        "{:?}",
        t.notes
    );
}

#[test]
fn a_struct_of_vectors_or_of_a_matrix_and_its_names_is_read_as_channels() {
    // Fields that are vectors are channels named by their field; a short one describes.
    let rec = struct_matrix(
        "rec",
        [1, 1],
        &["x", "y", "gain"],
        &[
            column("", &A),
            column("", &B),
            Var::double("", 1, 2, &[1.0, 2.0]).matrix(false),
        ],
    );
    let t = read_mat(&write("vectors.mat", &mat_of(&[rec])), None).unwrap();
    assert_eq!(t.names, ["x", "y"]);
    assert_eq!(t.rate_hz, None);
    // A samples × channels matrix beside the channels' names in a cell.
    let names = {
        let mut body = element(6, &[1, 0, 0, 0, 0, 0, 0, 0], false, false);
        body.extend(element(5, &[1, 0, 0, 0, 2, 0, 0, 0], false, false));
        body.extend(element(1, b"", false, true));
        body.extend(text_matrix("", "north"));
        body.extend(text_matrix("", "south"));
        element(14, &body, false, false)
    };
    let data: Vec<f64> = A.iter().chain(&B).copied().collect();
    let rec = struct_matrix(
        "recording",
        [1, 1],
        &["data", "names", "Fs"],
        &[
            Var::double("", 6, 2, &data).matrix(false),
            names,
            Var::double("", 1, 1, &[200.0]).matrix(false),
        ],
    );
    let t = read_mat(&write("matrix.mat", &mat_of(&[rec])), None).unwrap();
    assert_eq!(t.names, ["north", "south"]);
    assert_eq!(t.columns, [A.to_vec(), B.to_vec()]);
    assert_eq!(t.rate_hz, Some(200.0));
}

#[test]
fn structs_that_are_not_a_record_are_refused_naming_what_the_file_holds() {
    let rec = || {
        struct_matrix(
            "rec",
            [1, 1],
            &["p1", "p2"],
            &[sensor("a", "", &A), sensor("b", "", &B)],
        )
    };
    let uneven = struct_matrix(
        "rec",
        [1, 1],
        &["p1", "p2"],
        &[sensor("a", "", &A), sensor("b", "", &B[..5])],
    );
    let rates = {
        let s = |fs: f64| {
            struct_matrix(
                "",
                [1, 1],
                &["data", "fs"],
                &[column("", &A), Var::double("", 1, 1, &[fs]).matrix(false)],
            )
        };
        struct_matrix("rec", [1, 1], &["p1", "p2"], &[s(10.0), s(20.0)])
    };
    let described = struct_matrix("meta", [1, 1], &["site"], &[text_matrix("", "bridge")]);
    let wrong_count = struct_matrix("rec", [1, 3], &["data"], &[column("", &A)]);
    let deep = (0..40).fold(column("", &A), |inner, _| {
        struct_matrix("", [1, 1], &["inner"], &[inner])
    });
    let cases: Vec<(&str, Vec<u8>, Option<&str>, &str)> = vec![
        (
            "both.mat",
            mat_of(&[rec(), column("y", &A)]),
            None,
            "the file holds several arrays (rec (1×1 struct; fields p1, p2), y (6×1 double))",
        ),
        (
            "uneven.mat",
            mat_of(&[uneven]),
            None,
            "`rec`: channel `p1` holds 6 samples and `p2` 5",
        ),
        (
            "rates.mat",
            mat_of(&[rates]),
            None,
            "`p1.fs` states a sampling rate of 10 Hz and `p2.fs` of 20 Hz",
        ),
        (
            "described.mat",
            mat_of(std::slice::from_ref(&described)),
            None,
            "no numeric array, and no struct or cell of channels, in the file (it holds: meta (1×1 struct; fields site))",
        ),
        (
            "described_asked.mat",
            mat_of(&[described]),
            Some("meta"),
            "`meta` (1×1 struct; fields site) holds no numeric array of more than 3 values",
        ),
        (
            "count.mat",
            mat_of(&[wrong_count]),
            None,
            "`rec` holds 1 values where its dimensions count 3 × 1",
        ),
        (
            "deep.mat",
            mat_of(&[struct_matrix("d", [1, 1], &["inner"], &[deep])]),
            None,
            "nested more than 16 deep",
        ),
    ];
    refused(cases);
}

proptest::proptest! {
    /// A file of structs, cells and text with bytes changed anywhere, cut anywhere and
    /// anything appended is read or refused naming the file, never a panic.
    #[test]
    fn any_bytes_in_a_struct_are_read_or_refused(
        tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..100),
        flips in proptest::collection::vec((128usize..1400, proptest::prelude::any::<u8>()), 0..8),
        cut in 128usize..1400,
    ) {
        let rec = struct_matrix("rec", [1, 1], &["p1", "p2"], &[sensor("a", "x", &A), sensor("b", "y", &B)]);
        let bytes = crate::test_files::mutated(mat_of(&[rec]), &flips, cut, &tail);
        read_or_refused("fuzz-struct.mat", &bytes, &[None, Some("rec.p1")])?;
    }
}
