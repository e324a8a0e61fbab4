//! The reader against files laid out as the format's description gives (records 1–12 and
//! the 58b first line), written here field by field; pyuff's own files are read in the
//! Python tests.

use super::*;
use crate::test_files::file_path;

/// A dataset 58's text: function type `ftype` at `node`/`dir`, ordinate type `ord`, `count`
/// values said, increment `dx`, and the data part `data` (text lines, or binary bytes after
/// a 58b first line when `binary` gives its byte order and byte count).
struct Ds58<'a> {
    ftype: i64,
    node: i64,
    dir: i32,
    ord: i64,
    count: usize,
    even: i64,
    dx: f64,
    start: f64,
    abscissa: i64,
    binary: Option<(i64, usize)>,
    data: &'a [u8],
}

impl Default for Ds58<'_> {
    fn default() -> Self {
        Ds58 {
            ftype: 1,
            node: 1,
            dir: 3,
            ord: 4,
            count: 0,
            even: 1,
            dx: 0.05,
            start: 0.0,
            abscissa: 17,
            binary: None,
            data: b"",
        }
    }
}

impl Ds58<'_> {
    fn bytes(&self) -> Vec<u8> {
        let mut out = b"    -1\n    58".to_vec();
        match self.binary {
            Some((order, n)) => out.extend(
                format!(
                    "b{order:6}{:6}{:12}{n:12}{:6}{:6}{:12}{:12}\n",
                    2, 11, 0, 0, 0, 0
                )
                .bytes(),
            ),
            None => out.extend(format!("{:74}\n", "").bytes()),
        }
        for id in ["test record", "NONE", "NONE", "NONE", "NONE"] {
            out.extend(format!("{id:<80}\n").bytes());
        }
        out.extend(
            format!(
                "{:5}{:10}{:5}{:10} {:<10}{:10}{:4} {:<10}{:10}{:4}\n",
                self.ftype, 0, 0, 0, "NONE", self.node, self.dir, "NONE", 0, 0
            )
            .bytes(),
        );
        let e = |v: f64| crate::shapes_uff::e13(&[v]).trim_end().to_string();
        out.extend(
            format!(
                "{:10}{:10}{:10}{:>13}{:>13}{:>13}\n",
                self.ord,
                self.count,
                self.even,
                e(self.start),
                e(self.dx),
                e(0.0)
            )
            .bytes(),
        );
        for t in [self.abscissa, 12, 0, 0] {
            out.extend(
                format!(
                    "{t:10}{:5}{:5}{:5} {:<20} {:<20}\n",
                    0, 0, 0, "NONE", "NONE"
                )
                .bytes(),
            );
        }
        out.extend(self.data);
        out.extend(b"    -1\n");
        out
    }
}

/// Values in `4E20.12` lines.
fn double_lines(v: &[f64]) -> Vec<u8> {
    let mut s = String::new();
    for row in v.chunks(4) {
        for x in row {
            s.push_str(&format!("{x:20.11e}"));
        }
        s.push('\n');
    }
    s.into_bytes()
}

/// Values in `6E13.5` lines.
fn single_lines(v: &[f64]) -> Vec<u8> {
    let mut s = String::new();
    for row in v.chunks(6) {
        s.push_str(crate::shapes_uff::e13(row).as_str());
    }
    s.into_bytes()
}

fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = file_path(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn ramp(n: usize, k: f64) -> Vec<f64> {
    (0..n).map(|i| k * (i as f64 * 0.37).sin()).collect()
}

/// Two channels in double precision text, a third dataset of another kind between them,
/// single precision, and the binary form in both byte orders and widths read alike.
#[test]
fn every_layout_reads_to_the_same_record() {
    let a = ramp(11, 1.0);
    let b = ramp(11, -2.5);
    let text = |v: &[f64], node, dir, single: bool| {
        let data = if single {
            single_lines(v)
        } else {
            double_lines(v)
        };
        Ds58 {
            node,
            dir,
            ord: if single { 2 } else { 4 },
            count: v.len(),
            data: &data,
            ..Ds58::default()
        }
        .bytes()
    };
    let mut file = text(&a, 1, 3, false);
    file.extend(b"    -1\n   164\nSI units\n  1.0 1.0\n    -1\n");
    file.extend(text(&b, 2, -1, false));
    let t = read_uff(&write("two.uff", &file)).unwrap();
    assert_eq!(t.names, ["1+Z", "2-X"]);
    // 4E20.12 keeps 12 significant digits.
    for (col, truth) in t.columns.iter().zip([&a, &b]) {
        for (x, y) in col.iter().zip(truth.iter()) {
            assert!((x - y).abs() <= 1e-11 * y.abs().max(1e-300), "{x} {y}");
        }
    }
    assert_eq!(t.rate_hz, Some(20.0));
    assert_eq!(
        t.points.as_deref(),
        Some(
            &[
                MeasurementPoint {
                    node: 1,
                    direction: 3
                },
                MeasurementPoint {
                    node: 2,
                    direction: -1
                }
            ][..]
        )
    );
    // Single precision: six significant digits.
    let single = read_uff(&write("single.uff", &text(&a, 1, 3, true))).unwrap();
    for (x, y) in single.columns[0].iter().zip(&a) {
        assert!((x - y).abs() <= 5e-6 * y.abs().max(1e-300), "{x} {y}");
    }
    // Binary: every byte order and width gives back the values exactly (f32 as rounded).
    for (order, width) in [(1, 8), (2, 8), (1, 4), (2, 4)] {
        let data: Vec<u8> = a
            .iter()
            .flat_map(|&x| match (order, width) {
                (1, 8) => x.to_le_bytes().to_vec(),
                (2, 8) => x.to_be_bytes().to_vec(),
                (1, _) => (x as f32).to_le_bytes().to_vec(),
                _ => (x as f32).to_be_bytes().to_vec(),
            })
            .collect();
        let bytes = Ds58 {
            ord: if width == 8 { 4 } else { 2 },
            count: a.len(),
            binary: Some((order, data.len())),
            data: &data,
            ..Ds58::default()
        }
        .bytes();
        let t = read_uff(&write(&format!("b{order}{width}.uff"), &bytes)).unwrap();
        let want: Vec<f64> = if width == 8 {
            a.clone()
        } else {
            a.iter().map(|&x| f64::from(x as f32)).collect()
        };
        assert_eq!(t.columns[0], want, "order {order} width {width}");
    }
}

#[test]
fn the_rate_is_the_increments_whole_number_when_within_its_six_digits() {
    assert_eq!(rate_of(4.88281e-4), 2048.0);
    assert_eq!(rate_of(1.6384e-3), 610.3515625);
    // 1651.6 Hz is not near a whole number: 1/6.05473e-4 as it is.
    assert_eq!(rate_of(6.05473e-4), 1.0 / 6.05473e-4);
    assert_eq!(rate_of(0.5), 2.0);
}

/// Each way a file can be wrong gives an error naming the file and the problem.
#[test]
fn bad_files_are_refused_naming_the_problem() {
    let v = ramp(8, 1.0);
    let d = double_lines(&v);
    let ok = Ds58 {
        count: 8,
        data: &d,
        ..Ds58::default()
    };
    let cut = double_lines(&v[..6]);
    let nan = double_lines(&[1.0, f64::NAN, 2.0]);
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("text.uff", b"t,y\n0,1\n".to_vec(), "not a Universal File"),
        (
            "only55.uff",
            b"    -1\n    55\nNONE\n    -1\n    -1\n    15\n         1\n    -1\n".to_vec(),
            "no dataset 58 (a function at a node) to read as a record; the file holds datasets 55, 15",
        ),
        (
            "frf.uff",
            Ds58 {
                ftype: 4,
                ..Ds58 {
                    count: 8,
                    data: &d,
                    ..Ds58::default()
                }
            }
            .bytes(),
            "function type 4 (frequency response function)",
        ),
        (
            "complex.uff",
            Ds58 {
                ord: 6,
                ..Ds58 {
                    count: 8,
                    data: &d,
                    ..Ds58::default()
                }
            }
            .bytes(),
            "complex values",
        ),
        (
            "uneven.uff",
            Ds58 {
                even: 0,
                ..Ds58 {
                    count: 8,
                    data: &d,
                    ..Ds58::default()
                }
            }
            .bytes(),
            "uneven abscissa",
        ),
        (
            "spectrum_axis.uff",
            Ds58 {
                abscissa: 18,
                ..Ds58 {
                    count: 8,
                    data: &d,
                    ..Ds58::default()
                }
            }
            .bytes(),
            "the abscissa is a frequency",
        ),
        (
            "truncated.uff",
            Ds58 {
                count: 8,
                data: &cut,
                ..Ds58::default()
            }
            .bytes(),
            "record 7 says 8 values, the data hold 6",
        ),
        (
            "unclosed.uff",
            {
                let mut b = ok.bytes();
                b.truncate(b.len() - 7);
                b
            },
            "the file ends after 8 of its 8 values",
        ),
        (
            "lengths.uff",
            {
                let mut b = ok.bytes();
                b.extend(
                    Ds58 {
                        node: 2,
                        count: 6,
                        data: &cut,
                        ..Ds58::default()
                    }
                    .bytes(),
                );
                b
            },
            "channels of different lengths",
        ),
        (
            "rates.uff",
            {
                let mut b = ok.bytes();
                b.extend(
                    Ds58 {
                        node: 2,
                        dx: 0.01,
                        ..Ds58 {
                            count: 8,
                            data: &d,
                            ..Ds58::default()
                        }
                    }
                    .bytes(),
                );
                b
            },
            "channels at different rates",
        ),
        (
            "twice.uff",
            {
                let mut b = ok.bytes();
                b.extend(ok.bytes());
                b
            },
            "two functions at point 1+Z",
        ),
        (
            "nan.uff",
            Ds58 {
                count: 3,
                data: &nan,
                ..Ds58::default()
            }
            .bytes(),
            "row 2, column `1+Z`: value NaN is not finite",
        ),
    ];
    assert_refused(cases);
}

/// Each case's file is refused with an error naming the file and saying `says`.
fn assert_refused(cases: Vec<(&str, Vec<u8>, &str)>) {
    for (name, bytes, says) in cases {
        let path = write(name, &bytes);
        // Refused by the reader, or (a cell that is not finite) when its column is taken.
        let e = crate::test_files::taken(read_uff(&path))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&path.display().to_string()), "{e}");
        assert!(e.contains(says), "{name}: {e}");
    }
}

/// A 58b file cut inside its data, counting bytes its values do not fill, or in a float
/// format other than IEEE 754 is refused naming the problem.
#[test]
fn bad_binary_files_are_refused_naming_the_problem() {
    let v = ramp(8, 1.0);
    let bin: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "binary_cut.uff",
            {
                let mut b = Ds58 {
                    count: 8,
                    binary: Some((1, 64)),
                    data: &bin,
                    ..Ds58::default()
                }
                .bytes();
                b.truncate(b.len() - 20);
                b
            },
            "the file ends inside its 64 bytes of data",
        ),
        (
            "binary_count.uff",
            Ds58 {
                count: 9,
                binary: Some((1, 64)),
                data: &bin,
                ..Ds58::default()
            }
            .bytes(),
            "counts 64 bytes, but 9 values of 8 bytes are 72",
        ),
        (
            "binary_vms.uff",
            {
                let b = Ds58 {
                    count: 8,
                    binary: Some((1, 64)),
                    data: &bin,
                    ..Ds58::default()
                }
                .bytes();
                String::from_utf8_lossy(&b[..60])
                    .replace("     2          11", "     1          11")
                    .into_bytes()
                    .into_iter()
                    .chain(b[60..].iter().copied())
                    .collect()
            },
            "floating-point format 1",
        ),
    ];
    assert_refused(cases);
}

proptest::proptest! {
    /// No bytes make the reader panic: a valid two-channel file (text then binary) with bytes
    /// changed anywhere, cut anywhere and anything appended is read or refused with an error
    /// naming the file.
    #[test]
    fn any_bytes_are_read_or_refused(
        tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..100),
        flips in proptest::collection::vec((0usize..2400, proptest::prelude::any::<u8>()), 0..6),
        cut in 0usize..2400,
    ) {
        let v = ramp(6, 1.0);
        let d = double_lines(&v);
        let bin: Vec<u8> = v.iter().flat_map(|x| x.to_be_bytes()).collect();
        let mut bytes = Ds58 { count: 6, data: &d, ..Ds58::default() }.bytes();
        bytes.extend(Ds58 { node: 2, count: 6, binary: Some((2, 48)), data: &bin, ..Ds58::default() }.bytes());
        let bytes = crate::test_files::mutated(bytes, &flips, cut, &tail);
        let path = write("fuzz.uff", &bytes);
        match read_uff(&path) {
            Ok(t) => proptest::prop_assert!(crate::test_files::well_formed(&t)),
            Err(e) => proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string())),
        }
    }
}
