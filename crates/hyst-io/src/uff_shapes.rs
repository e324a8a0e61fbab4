//! Mode shapes read from a Universal File: datasets 55 ("data at nodes") of normal modes
//! (analysis type 2: frequency, modal mass, viscous and hysteretic damping ratios) or complex
//! modes (type 3: the eigenvalue λ, whose frequency is |λ|/2π and damping ratio −Re λ/|λ|),
//! each node's translation (3 DOF, or the first three of 6) real or complex; and the nodes'
//! positions from dataset 15 (`4I10,3E13.5`) or 2411 (`4I10` then `3D25.16`). What
//! [`write_shapes_uff`](super::write_shapes_uff) and
//! [`write_merged_shapes_uff`](super::write_merged_shapes_uff) write, and what other
//! programs write of these datasets. Every other dataset is passed over; a file without a
//! dataset 55 is an error, as is any field these datasets need that does not read.

use std::path::Path;

use num_complex::Complex64;

use super::IoError;
use super::uff::{Lines, bad, field, holds, int, is_delimiter, real, walk_datasets};

/// The shapes and nodes of a Universal File.
#[derive(Debug, Clone, PartialEq)]
pub struct UffShapes {
    /// Each node's number and x, y, z, from datasets 15 and 2411, in the file's order.
    pub nodes: Vec<(i64, [f64; 3])>,
    /// Each dataset 55, in the file's order.
    pub modes: Vec<UffMode>,
}

/// One dataset 55's mode.
#[derive(Debug, Clone, PartialEq)]
pub struct UffMode {
    /// The mode's number (record 7).
    pub number: i64,
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio (a normal mode's viscous one).
    pub damping_ratio: f64,
    /// Each node's x, y, z translation (a real shape with zero imaginary parts).
    pub motions: Vec<(i64, [Complex64; 3])>,
}

/// Read the mode shapes and node positions of the Universal File at `path` (see the
/// module's documentation).
pub fn read_shapes_uff(path: &Path) -> Result<UffShapes, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    let mut shapes = UffShapes {
        nodes: Vec::new(),
        modes: Vec::new(),
    };
    let others = walk_datasets(path, &bytes, |start, lines| {
        let mut data = Dataset {
            path,
            lines,
            here: format!(
                "dataset {} ({} at line {})",
                start.index, start.number, start.id_line
            ),
        };
        if start.binary.is_some() && matches!(start.number, 15 | 55 | 2411) {
            return Err(data.bad("binary; only a text dataset 15, 55 or 2411 is read"));
        }
        match start.number {
            15 => data.nodes_15(&mut shapes.nodes)?,
            2411 => data.nodes_2411(&mut shapes.nodes)?,
            55 => shapes.modes.push(data.mode()?),
            _ => return Ok(false),
        }
        Ok(true)
    })?;
    if shapes.modes.is_empty() {
        return Err(bad(
            path,
            format!(
                "no dataset 55 (data at nodes) to read as mode shapes; the file holds {}",
                holds(&others)
            ),
        ));
    }
    Ok(shapes)
}

/// A dataset being read: its lines and how errors name it.
struct Dataset<'p, 'l, 'b> {
    path: &'p Path,
    lines: &'l mut Lines<'b>,
    here: String,
}

impl<'b> Dataset<'_, '_, 'b> {
    fn bad(&self, what: impl std::fmt::Display) -> IoError {
        bad(self.path, format!("{}: {what}", self.here))
    }

    /// The next line, or `None` at the dataset's closing delimiter; an error at the file's end.
    fn line(&mut self) -> Result<Option<(usize, &'b [u8])>, IoError> {
        match self.lines.next_line() {
            None => Err(self.bad("the file ends before the dataset is closed by `    -1`")),
            Some((_, l)) if is_delimiter(l) => Ok(None),
            Some(l) => Ok(Some(l)),
        }
    }

    /// The next line, which must be inside the dataset.
    fn needed(&mut self, what: &str) -> Result<(usize, &'b [u8]), IoError> {
        self.line()?
            .ok_or_else(|| self.bad(format!("closed before its {what}")))
    }

    /// Field `k` of a line of `width`-character fields, read by `parse`.
    fn cell<T>(
        &self,
        (n, line): (usize, &[u8]),
        (k, width): (usize, usize),
        parse: fn(&str) -> Option<T>,
        what: &str,
    ) -> Result<T, IoError> {
        let text = field(line, k * width, (k + 1) * width);
        parse(text).ok_or_else(|| self.bad(format!("line {n}: {what} `{text}` does not read")))
    }

    /// `count` reals, `per_line` to a line of `width`-character fields.
    fn reals(
        &mut self,
        count: usize,
        (per_line, width): (usize, usize),
        what: &str,
    ) -> Result<Vec<f64>, IoError> {
        let mut values = Vec::with_capacity(count);
        while values.len() < count {
            let l = self.needed(what)?;
            for k in 0..per_line.min(count - values.len()) {
                let v = self.cell(l, (k, width), real, what)?;
                if !v.is_finite() {
                    return Err(self.bad(format!("line {}: {what} `{v}` is not finite", l.0)));
                }
                values.push(v);
            }
        }
        Ok(values)
    }

    /// Dataset 15: a node per line, `4I10,3E13.5` (node, two coordinate systems, colour;
    /// x, y, z), up to the closing delimiter.
    fn nodes_15(&mut self, nodes: &mut Vec<(i64, [f64; 3])>) -> Result<(), IoError> {
        while let Some(l) = self.line()? {
            let node = self.cell(l, (0, 10), int, "the node number")?;
            let mut xyz = [0.0; 3];
            for (a, v) in xyz.iter_mut().enumerate() {
                let text = field(l.1, 40 + 13 * a, 53 + 13 * a);
                *v = real(text).filter(|v| v.is_finite()).ok_or_else(|| {
                    self.bad(format!("line {}: coordinate `{text}` does not read", l.0))
                })?;
            }
            nodes.push((node, xyz));
        }
        Ok(())
    }

    /// Dataset 2411: per node a line `4I10` (node, coordinate systems, colour) and a line
    /// `3D25.16` (x, y, z), up to the closing delimiter.
    fn nodes_2411(&mut self, nodes: &mut Vec<(i64, [f64; 3])>) -> Result<(), IoError> {
        while let Some(l) = self.line()? {
            let node = self.cell(l, (0, 10), int, "the node number")?;
            let xyz = self.reals(3, (3, 25), "a coordinate")?;
            nodes.push((node, [xyz[0], xyz[1], xyz[2]]));
        }
        Ok(())
    }

    /// Dataset 55: five ID lines, records 6–8 (the data's kind, the mode's number, its
    /// frequency and damping or eigenvalue), then per node its number and values.
    fn mode(&mut self) -> Result<UffMode, IoError> {
        for _ in 0..5 {
            self.needed("ID lines")?;
        }
        let r6 = self.needed("record 6")?;
        let kind: Vec<i64> = (0..6)
            .map(|k| self.cell(r6, (k, 10), int, "a record 6 field"))
            .collect::<Result<_, _>>()?;
        let (analysis, characteristic, data_type, ndv) = (kind[1], kind[2], kind[4], kind[5]);
        let complex = match data_type {
            2 => false,
            5 => true,
            t => {
                return Err(self.bad(format!(
                    "data type {t} (2 real, 5 complex single precision)"
                )));
            }
        };
        let dofs = match (characteristic, ndv) {
            (2, 3) => 3,
            (3, 6) => 6,
            (c, n) => {
                return Err(self.bad(format!(
                    "data characteristic {c} with {n} values per node (2 with 3: a translation; 3 with 6: translation and rotation)"
                )));
            }
        };
        let r7 = self.needed("record 7")?;
        let nint = self.cell(r7, (0, 10), int, "record 7's integer count")?;
        let nrval = self.cell(r7, (1, 10), int, "record 7's real count")?;
        let wanted = match analysis {
            2 => 4,
            3 => 6,
            a => {
                return Err(self.bad(format!(
                    "analysis type {a} (2 normal mode, 3 complex eigenvalue: a mode shape)"
                )));
            }
        };
        if nint != 2 || nrval != wanted {
            return Err(self.bad(format!(
                "record 7 counts {nint} integers and {nrval} reals; analysis type {analysis} has 2 and {wanted}"
            )));
        }
        let number = self.cell(r7, (3, 10), int, "the mode number")?;
        let r8 = self.reals(wanted as usize, (6, 13), "a record 8 value")?;
        let (frequency_hz, damping_ratio) = if analysis == 2 {
            (r8[0], r8[2])
        } else {
            let norm = r8[0].hypot(r8[1]);
            (norm / (2.0 * std::f64::consts::PI), -r8[0] / norm)
        };
        if !(frequency_hz > 0.0 && damping_ratio.is_finite()) {
            return Err(self.bad(format!(
                "record 8 gives a frequency of {frequency_hz} Hz and a damping ratio of {damping_ratio}"
            )));
        }
        let per_node = if complex { 2 * dofs } else { dofs };
        let mut motions: Vec<(i64, [Complex64; 3])> = Vec::new();
        while let Some(l) = self.line()? {
            let node = self.cell(l, (0, 10), int, "the node number")?;
            if motions.iter().any(|(n, _)| *n == node) {
                return Err(self.bad(format!("line {}: node {node} a second time", l.0)));
            }
            let v = self.reals(per_node, (6, 13), "a node's value")?;
            let at = |a: usize| {
                if complex {
                    Complex64::new(v[2 * a], v[2 * a + 1])
                } else {
                    Complex64::new(v[a], 0.0)
                }
            };
            motions.push((node, [at(0), at(1), at(2)]));
        }
        Ok(UffMode {
            number,
            frequency_hz,
            damping_ratio,
            motions,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::file_path;

    /// A dataset 55 as another program writes it: a real normal mode (analysis type 2, data
    /// type 2) with a 6-DOF node, after a dataset 2411 of two nodes and a dataset 164 (units).
    const NORMAL_MODE: &str = "    -1
   164
         1  SI
    -1
    -1
  2411
         3         1         1        11
   1.0000000000000000D+00   2.5000000000000000D+00  -3.0000000000000000D+00
         7         1         1        11
   0.0000000000000000D+00   0.0000000000000000D+00   1.2500000000000000D+01
    -1
    -1
    55
NONE
NONE
NONE
NONE
NONE
         1         2         3         8         2         6
         2         4         1         2
  4.50000E+00  1.00000E+00  3.00000E-02  0.00000E+00
         3
  1.00000E+00 -5.00000E-01  2.50000E-01  9.00000E+00  9.00000E+00  9.00000E+00
         7
  0.00000E+00  0.00000E+00  1.25000E-01  0.00000E+00  0.00000E+00  0.00000E+00
    -1
";

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let p = file_path(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn normal_modes_and_dataset_2411_nodes_are_read() {
        let shapes = read_shapes_uff(&write("normal.uff", NORMAL_MODE)).unwrap();
        assert_eq!(
            shapes.nodes,
            vec![(3, [1.0, 2.5, -3.0]), (7, [0.0, 0.0, 12.5])]
        );
        let [m] = &shapes.modes[..] else {
            panic!("{shapes:?}")
        };
        assert_eq!((m.number, m.frequency_hz, m.damping_ratio), (2, 4.5, 0.03));
        let c = |re: f64| Complex64::new(re, 0.0);
        // Node 3's rotations (9) are not a translation: left out.
        assert_eq!(
            m.motions,
            vec![
                (3, [c(1.0), c(-0.5), c(0.25)]),
                (7, [c(0.0), c(0.0), c(0.125)])
            ]
        );
    }

    #[test]
    fn bad_shape_files_are_refused_naming_the_problem() {
        let with = |old: &str, new: &str| NORMAL_MODE.replacen(old, new, 1);
        let record6 = "         1         2         3         8         2         6";
        let cases = [
            (
                NORMAL_MODE.replace("    55\n", "    56\n"),
                "no dataset 55 (data at nodes) to read as mode shapes; the file holds datasets 164, 56",
            ),
            (
                with(
                    record6,
                    "         1         2         3         8         4         6",
                ),
                "dataset 3 (55 at line 13): data type 4 (2 real, 5 complex single precision)",
            ),
            (
                with(
                    record6,
                    "         1         2         2         8         2         6",
                ),
                "data characteristic 2 with 6 values per node",
            ),
            (
                with(
                    record6,
                    "         1         1         3         8         2         6",
                ),
                "analysis type 1 (2 normal mode, 3 complex eigenvalue: a mode shape)",
            ),
            (
                with(
                    "         2         4         1         2",
                    "         2         6         1         2",
                ),
                "record 7 counts 2 integers and 6 reals; analysis type 2 has 2 and 4",
            ),
            (
                with("  4.50000E+00", "  four Hertz "),
                "line 21: a record 8 value `four Hertz` does not read",
            ),
            (
                with("  4.50000E+00", " -4.50000E+00"),
                "record 8 gives a frequency of -4.5 Hz",
            ),
            (
                with("         7\n  0.00000E+00", "         3\n  0.00000E+00"),
                "line 24: node 3 a second time",
            ),
            (
                with(
                    "  0.00000E+00  0.00000E+00  1.25000E-01",
                    "  0.00000E+00  NaN          1.25000E-01",
                ),
                "line 25: a node's value `NaN` is not finite",
            ),
            (
                NORMAL_MODE.trim_end_matches("    -1\n").to_string(),
                "dataset 3 (55 at line 13): the file ends before the dataset is closed",
            ),
            (
                with(
                    "  1.00000E+00 -5.00000E-01  2.50000E-01  9.00000E+00  9.00000E+00  9.00000E+00\n",
                    "",
                ),
                "line 24: the node number `0.00000E` does not read",
            ),
            (
                with("NONE\nNONE\nNONE\nNONE\nNONE\n", "NONE\n    -1\n"),
                "closed before its ID lines",
            ),
            (
                with(
                    "   1.0000000000000000D+00   2.5",
                    "   1.0000000000000000D+00   x.5",
                ),
                "dataset 2 (2411 at line 6): line 8: a coordinate `x.5000000000000000D+00` does not read",
            ),
            (
                with("    55\n", "    55b     1     2    11       100\n"),
                "binary; only a text dataset 15, 55 or 2411 is read",
            ),
        ];
        for (k, (text, said)) in cases.iter().enumerate() {
            let p = write(&format!("bad{k}.uff"), text);
            let e = read_shapes_uff(&p).unwrap_err().to_string();
            assert!(e.starts_with(&p.display().to_string()), "{k}: {e}");
            assert!(e.contains(said), "{k}: {e}");
        }
    }

    proptest::proptest! {
        /// No bytes make the reader panic: the file above with bytes changed anywhere, cut
        /// anywhere and anything appended is read (every value finite, every frequency
        /// positive) or refused with an error naming the file.
        #[test]
        fn any_bytes_are_read_or_refused(
            tail in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..100),
            flips in proptest::collection::vec((0usize..900, proptest::prelude::any::<u8>()), 0..6),
            cut in 0usize..900,
        ) {
            let bytes = crate::test_files::mutated(NORMAL_MODE.as_bytes().to_vec(), &flips, cut, &tail);
            let path = file_path("fuzz_shapes.uff");
            std::fs::write(&path, &bytes).unwrap();
            match read_shapes_uff(&path) {
                Ok(s) => {
                    proptest::prop_assert!(s.modes.iter().all(|m| m.frequency_hz > 0.0
                        && m.damping_ratio.is_finite()
                        && m.motions.iter().all(|(_, v)| v.iter().all(|c| c.re.is_finite() && c.im.is_finite()))));
                    proptest::prop_assert!(s.nodes.iter().all(|(_, x)| x.iter().all(|v| v.is_finite())));
                }
                Err(e) => proptest::prop_assert!(e.to_string().starts_with(&path.display().to_string())),
            }
        }
    }
}
