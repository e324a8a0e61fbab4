//! Mode shapes as Universal File dataset 55 ("data at nodes"): one dataset per mode, its
//! complex eigenvalue (analysis type 3) and a 3-DOF translation vector per node, complex, in
//! the `E13.5` fields pyuff and the test-lab programs read.

use std::path::Path;

use num_complex::Complex64;

use covssi::multisetup::MergedModes;

use super::{Geometry, IoError, MeasurementPoint};

/// One identified mode, as dataset 55 writes it.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeMode<'a> {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// The shape, one entry per channel.
    pub shape: &'a [Complex64],
}

/// A node's X, Y, Z: the channel there (with the sign of its direction), if any.
type NodeAxes = [Option<(usize, f64)>; 3];

/// Write `modes` as datasets 55 at `path`: for each mode its complex eigenvalue
/// λ = 2πf(−ζ + i√(1−ζ²)) and, per node, the X, Y, Z entries of its shape. Each channel is
/// placed at its `points` entry (a translation along ±X, ±Y or ±Z, the sign applied; a scalar
/// point along +Z); without points, channel `c` is node `c + 1` along +Z. A rotation, or two
/// channels at one node and axis, is an error: a 3-DOF translation vector cannot hold them.
pub fn write_shapes_uff(
    path: &Path,
    modes: &[ShapeMode<'_>],
    points: Option<&[MeasurementPoint]>,
    description: &str,
) -> Result<(), IoError> {
    let channels = modes.first().map_or(0, |m| m.shape.len());
    let misfit = |what: String| IoError::ShapesUff {
        path: path.to_path_buf(),
        what,
    };
    if let Some(m) = modes.iter().find(|m| m.shape.len() != channels) {
        return Err(misfit(format!(
            "a mode at {} Hz has {} shape entries, the first has {channels}",
            m.frequency_hz,
            m.shape.len()
        )));
    }
    if let Some(m) = modes.iter().find(|m| {
        !(m.frequency_hz.is_finite() && m.damping_ratio.is_finite())
            || m.shape
                .iter()
                .any(|v| !(v.re.is_finite() && v.im.is_finite()))
    }) {
        return Err(misfit(format!(
            "the mode at {} Hz (damping ratio {}) has a value that is not finite",
            m.frequency_hz, m.damping_ratio
        )));
    }
    let points: Vec<MeasurementPoint> = match points {
        Some(p) if p.len() == channels => p.to_vec(),
        Some(p) => {
            return Err(misfit(format!(
                "{} points for {channels} channels",
                p.len()
            )));
        }
        None => (0..channels)
            .map(|c| MeasurementPoint {
                node: c as i64 + 1,
                direction: 0,
            })
            .collect(),
    };
    // Each node's axes: which channel (with its sign) is where.
    let mut nodes: Vec<(i64, NodeAxes)> = Vec::new();
    for (c, p) in points.iter().enumerate() {
        let (axis, sign) = match p.direction {
            0 => (2, 1.0),
            d @ (-3..=-1 | 1..=3) => (d.unsigned_abs() as usize - 1, f64::from(d.signum())),
            _ => {
                return Err(misfit(format!(
                    "channel {c} at point {p} is a rotation; dataset 55's 3-DOF translation vectors cannot hold it"
                )));
            }
        };
        let slot = match nodes.iter().position(|(n, _)| *n == p.node) {
            Some(i) => &mut nodes[i].1,
            None => {
                nodes.push((p.node, [None; 3]));
                &mut nodes.last_mut().expect("pushed").1
            }
        };
        if slot[axis].is_some() {
            return Err(misfit(format!(
                "two channels along the same axis of node {}",
                p.node
            )));
        }
        slot[axis] = Some((c, sign));
    }
    let mut text = String::new();
    for (k, m) in modes.iter().enumerate() {
        let motions: Vec<(i64, [Complex64; 3])> = nodes
            .iter()
            .map(|(node, axes)| {
                let mut v = [Complex64::new(0.0, 0.0); 3];
                for (a, slot) in axes.iter().enumerate() {
                    if let Some((c, sign)) = slot {
                        v[a] = m.shape[*c] * *sign;
                    }
                }
                (*node, v)
            })
            .collect();
        push_dataset_55(
            &mut text,
            k,
            m.frequency_hz,
            m.damping_ratio,
            description,
            &motions,
        );
    }
    write_text(path, &text)
}

/// The merged modes of a test of several setups as datasets 55 at `path`, each node's x, y,
/// z motion ([`NodeMotion`](covssi::multisetup::NodeMotion); an axis no setup measured is 0)
/// under its number, and with `geometry` first a dataset 15 of its nodes' positions, so that
/// a reader draws the shapes on the structure. Universal Files number nodes: every node's
/// name (the merge's and the geometry's) must be a whole number from 1, else an error names
/// it. A mode without a node motion is written with none.
pub fn write_merged_shapes_uff(
    path: &Path,
    merged: &MergedModes,
    geometry: Option<&Geometry>,
    description: &str,
) -> Result<(), IoError> {
    let misfit = |what: String| IoError::ShapesUff {
        path: path.to_path_buf(),
        what,
    };
    let label = |name: &str, whose: &str| -> Result<i64, IoError> {
        name.trim()
            .parse::<i64>()
            .ok()
            .filter(|n| *n >= 1)
            .ok_or_else(|| {
                misfit(format!(
                    "{whose} node `{name}` is not a whole number from 1: a Universal File numbers its nodes"
                ))
            })
    };
    let mut text = String::new();
    if let Some(g) = geometry {
        text.push_str("    -1\n    15\n");
        for (name, [x, y, z]) in &g.nodes {
            let n = label(name, "the geometry's")?;
            if ![x, y, z].iter().all(|v| v.is_finite()) {
                return Err(misfit(format!(
                    "the geometry's node `{name}` has a coordinate that is not finite"
                )));
            }
            // Node, definition and displacement coordinate systems (global), colour; x, y, z.
            text.push_str(&format!("{n:10}{:10}{:10}{:10}", 0, 0, 8));
            text.push_str(&e13(&[*x, *y, *z]));
        }
        text.push_str("    -1\n");
    }
    for (k, m) in merged.modes.iter().enumerate() {
        if !(m.frequency_hz.is_finite() && m.damping_ratio.is_finite()) {
            return Err(misfit(format!(
                "the mode at {} Hz (damping ratio {}) has a value that is not finite",
                m.frequency_hz, m.damping_ratio
            )));
        }
        let mut motions = Vec::with_capacity(m.nodes.len());
        for node in &m.nodes {
            let zero = Complex64::new(0.0, 0.0);
            let v = node.motion.map(|c| c.unwrap_or(zero));
            if v.iter().any(|c| !(c.re.is_finite() && c.im.is_finite())) {
                return Err(misfit(format!(
                    "the mode at {} Hz moves node `{}` by a value that is not finite",
                    m.frequency_hz, node.node
                )));
            }
            motions.push((label(&node.node, "the merged modes'")?, v));
        }
        push_dataset_55(
            &mut text,
            k,
            m.frequency_hz,
            m.damping_ratio,
            description,
            &motions,
        );
    }
    write_text(path, &text)
}

/// Mode `k` (numbered from 1 in the file) as one dataset 55: its complex eigenvalue
/// λ = 2πf(−ζ + i√(1−ζ²)) (analysis type 3) and each node's complex x, y, z translation.
fn push_dataset_55(
    text: &mut String,
    k: usize,
    frequency_hz: f64,
    damping_ratio: f64,
    description: &str,
    motions: &[(i64, [Complex64; 3])],
) {
    let w = 2.0 * std::f64::consts::PI * frequency_hz;
    let z = damping_ratio;
    let eig = Complex64::new(-z * w, w * (1.0 - z * z).max(0.0).sqrt());
    let id = |s: &str| format!("{:<80}\n", s.chars().take(80).collect::<String>());
    text.push_str("    -1\n    55\n");
    text.push_str(&id(&format!("hyst ssi: {description}")));
    text.push_str(&id("NONE"));
    text.push_str(&id("NONE"));
    text.push_str(&id("NONE"));
    text.push_str(&id(&format!(
        "Mode {:>10} Frequency {:13.5e} Hz, damping ratio {:.5}",
        k + 1,
        frequency_hz,
        z
    )));
    // Structural model, complex eigenvalue, 3-DOF translation, unknown data, complex, 3.
    text.push_str(&format!(
        "{:10}{:10}{:10}{:10}{:10}{:10}\n",
        1, 3, 2, 0, 5, 3
    ));
    text.push_str(&format!("{:10}{:10}{:10}{:10}\n", 2, 6, 1, k + 1));
    text.push_str(&e13(&[eig.re, eig.im, 0.0, 0.0, 0.0, 0.0]));
    for (node, v) in motions {
        text.push_str(&format!("{node:10}\n"));
        text.push_str(&e13(&[
            v[0].re, v[0].im, v[1].re, v[1].im, v[2].re, v[2].im,
        ]));
    }
    text.push_str("    -1\n");
}

fn write_text(path: &Path, text: &str) -> Result<(), IoError> {
    std::fs::write(path, text).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })
}

/// Values in Fortran's `E13.5` (`  1.23457E+00`), one line.
pub(super) fn e13(values: &[f64]) -> String {
    let mut line = String::new();
    for v in values {
        let s = format!("{v:.5e}");
        // Rust writes `1.23457e0`; Fortran writes a signed two-digit (or three-digit) exponent.
        let (mantissa, exponent) = s.split_once('e').unwrap_or((&s, "0"));
        let exponent: i32 = exponent.parse().unwrap_or(0);
        let sign = if exponent < 0 { '-' } else { '+' };
        line.push_str(&format!(
            "{:>13}",
            format!("{mantissa}E{sign}{:02}", exponent.unsigned_abs())
        ));
    }
    line.push('\n');
    line
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::file_path;

    #[test]
    fn fortran_e13_matches_the_printf_layout() {
        // What C's `%13.5e` prints, as pyuff writes it.
        assert_eq!(e13(&[1.0]), "  1.00000E+00\n");
        assert_eq!(e13(&[-0.000123456789]), " -1.23457E-04\n");
        assert_eq!(e13(&[0.0, 6.02e23]), "  0.00000E+00  6.02000E+23\n");
        assert_eq!(e13(&[-1e-300]), "-1.00000E-300\n");
    }

    #[test]
    fn shapes_are_written_per_node_and_refused_when_they_do_not_fit() {
        let shape = [
            Complex64::new(1.0, 0.0),
            Complex64::new(-0.5, 0.25),
            Complex64::new(0.125, -1e-7),
        ];
        let modes = [ShapeMode {
            frequency_hz: 2.0,
            damping_ratio: 0.05,
            shape: &shape,
        }];
        let p = file_path("shapes.uff");
        // Channels 0 and 1 at node 7 (+Z, −X), channel 2 at node 9 (+Y).
        let points = [
            MeasurementPoint {
                node: 7,
                direction: 3,
            },
            MeasurementPoint {
                node: 7,
                direction: -1,
            },
            MeasurementPoint {
                node: 9,
                direction: 2,
            },
        ];
        write_shapes_uff(&p, &modes, Some(&points), "test").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "    -1");
        assert_eq!(lines[1], "    55");
        assert_eq!(
            lines[7],
            "         1         3         2         0         5         3"
        );
        assert_eq!(lines[8], "         2         6         1         1");
        // λ = 2π·2·(−0.05 + i√(1 − 0.0025)).
        let w = 4.0 * std::f64::consts::PI;
        assert_eq!(
            lines[9],
            e13(&[-0.05 * w, w * (0.9975f64).sqrt(), 0.0, 0.0, 0.0, 0.0]).trim_end()
        );
        assert_eq!(lines[10], "         7");
        assert_eq!(lines[11], e13(&[0.5, -0.25, 0.0, 0.0, 1.0, 0.0]).trim_end());
        assert_eq!(lines[12], "         9");
        assert_eq!(
            lines[13],
            e13(&[0.0, 0.0, 0.125, -1e-7, 0.0, 0.0]).trim_end()
        );
        assert_eq!(lines[14], "    -1");
        for (pts, says) in [
            (
                vec![
                    MeasurementPoint {
                        node: 1,
                        direction: 4
                    };
                    3
                ],
                "is a rotation",
            ),
            (
                vec![
                    MeasurementPoint {
                        node: 1,
                        direction: 3,
                    },
                    MeasurementPoint {
                        node: 1,
                        direction: -3,
                    },
                    MeasurementPoint {
                        node: 2,
                        direction: 3,
                    },
                ],
                "two channels along the same axis of node 1",
            ),
            (
                vec![MeasurementPoint {
                    node: 1,
                    direction: 3,
                }],
                "1 points for 3 channels",
            ),
        ] {
            let e = write_shapes_uff(&p, &modes, Some(&pts), "test")
                .unwrap_err()
                .to_string();
            assert!(e.contains(says), "{e}");
        }
    }

    #[test]
    fn merged_shapes_follow_the_geometry_and_refuse_nodes_without_a_number() {
        use covssi::multisetup::{MergedMode, NodeMotion};
        let c = |re: f64, im: f64| Some(Complex64::new(re, im));
        let mode = MergedMode {
            frequency_hz: 3.0,
            frequency_se_hz: None,
            damping_ratio: 0.02,
            damping_se: None,
            scatter_ratio: None,
            seen_in: Vec::new(),
            shape: Vec::new(),
            shape_se: Vec::new(),
            nodes: vec![
                NodeMotion {
                    node: "12".into(),
                    motion: [c(1.0, 0.0), None, c(-0.5, 0.25)],
                    se: [None; 3],
                },
                NodeMotion {
                    node: "4".into(),
                    motion: [None, c(0.125, 0.0), None],
                    se: [None; 3],
                },
            ],
        };
        let merged = MergedModes {
            setups: vec!["one".into()],
            dofs: Vec::new(),
            modes: vec![mode],
            notes: Vec::new(),
        };
        let geometry = Geometry {
            nodes: vec![
                ("4".into(), [0.0, 1.0, 2.0]),
                ("12".into(), [3.5, -1.0, 0.0]),
            ],
            lines: vec![[0, 1]],
        };
        let p = file_path("merged.uff");
        write_merged_shapes_uff(&p, &merged, Some(&geometry), "test").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        // Dataset 15: each node's number, coordinate systems 0, colour 8, then x, y, z.
        assert_eq!(&lines[..2], ["    -1", "    15"]);
        let node4 = format!("{:10}{:10}{:10}{:10}{}", 4, 0, 0, 8, e13(&[0.0, 1.0, 2.0]));
        assert_eq!(lines[2], node4.trim_end());
        assert_eq!(lines[4], "    -1");
        // Dataset 55: node 12 moves along x and z, node 4 along y; an axis not measured is 0.
        assert_eq!(&lines[5..7], ["    -1", "    55"]);
        assert_eq!(lines[15], "        12");
        assert_eq!(lines[16], e13(&[1.0, 0.0, 0.0, 0.0, -0.5, 0.25]).trim_end());
        assert_eq!(lines[17], "         4");
        assert_eq!(lines[18], e13(&[0.0, 0.0, 0.125, 0.0, 0.0, 0.0]).trim_end());
        assert_eq!(lines[19], "    -1");
        // Read back: the nodes where the geometry puts them, the mode's frequency and damping
        // from its eigenvalue and each node's motion, to E13.5's six significant digits.
        let back = crate::read_shapes_uff(&p).unwrap();
        assert_eq!(
            back.nodes,
            vec![(4, [0.0, 1.0, 2.0]), (12, [3.5, -1.0, 0.0])]
        );
        let m = &back.modes[0];
        assert_eq!((back.modes.len(), m.number), (1, 1));
        assert!((m.frequency_hz - 3.0).abs() < 1e-5 * 3.0, "{m:?}");
        assert!((m.damping_ratio - 0.02).abs() < 1e-5 * 0.02, "{m:?}");
        let zero = Complex64::new(0.0, 0.0);
        assert_eq!(
            m.motions,
            vec![
                (
                    12,
                    [Complex64::new(1.0, 0.0), zero, Complex64::new(-0.5, 0.25)]
                ),
                (4, [zero, Complex64::new(0.125, 0.0), zero]),
            ]
        );
        // A node a Universal File cannot number, in the modes or the geometry: refused by name.
        let mut named = merged.clone();
        named.modes[0].nodes[1].node = "roof".into();
        let e = write_merged_shapes_uff(&p, &named, None, "test")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("node `roof` is not a whole number from 1"),
            "{e}"
        );
        let mut bad = geometry.clone();
        bad.nodes[0].0 = "0".into();
        let e = write_merged_shapes_uff(&p, &merged, Some(&bad), "test")
            .unwrap_err()
            .to_string();
        assert!(e.contains("the geometry's node `0`"), "{e}");
        bad.nodes[0] = ("4".into(), [f64::NAN, 0.0, 0.0]);
        let e = write_merged_shapes_uff(&p, &merged, Some(&bad), "test")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not finite"), "{e}");
        // Without the geometry, the modes alone.
        write_merged_shapes_uff(&p, &merged, None, "test").unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.starts_with("    -1\n    55\n"), "{text}");
    }
}
