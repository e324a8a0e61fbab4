//! A check of the sensors' factors on floors the user states are rigid in their plane: on a
//! floor (the geometry's nodes at one height, z vertical) that holds a reference node and
//! other measured nodes, the others' in-plane motion in each mode fixes the floor's rigid
//! motion — a translation $(a, b)$ of the reference node and a rotation $\theta$ about it,
//! node $j$ moving $(a - \theta\,\Delta y_j,\; b + \theta\,\Delta x_j)$ — fitted by weighted
//! least squares (weights $1/\sigma^2$ of each entry's standard error, or 1 without). What
//! that motion predicts at the reference, over what the references measured there, is the
//! factor the other channels read against the references: 1 when gains, signs and units
//! are as the setups state, $g$ when those channels carry a factor $g$ the setups do not say.
//!
//! Each (mode, in-plane reference direction) where the reference moves at least
//! [`LEAST_REFERENCE`] of the mode's largest entry gives a ratio $r = \hat u / u_{\text{ref}}$
//! with a first-order standard error (the fit's covariance and the reference's error), kept
//! when that error is within [`MOST_RELATIVE_SE`] of the ratio; the
//! floor's factor is their inverse-variance weighted mean, its error widened by the Birge
//! ratio when the ratios scatter more than their errors. A factor further than
//! [`SIGMAS`] of its errors from 1 is said: "a gain or sign to check".

use covssi::Complex64 as C64;
use covssi::multisetup::{MergedMode, MergedModes};

use crate::io::Geometry;

/// A ratio is formed only where the reference moves at least this share of the mode's
/// largest entry: a small reference motion makes a ratio of noise.
pub const LEAST_REFERENCE: f64 = 0.1;

/// A ratio is kept only where its first-order standard error is at most this share of it:
/// beyond, the ratio of two noisy numbers is far from normal and its error unreliable.
pub const MOST_RELATIVE_SE: f64 = 0.2;

/// A factor this many standard errors (Birge-widened) or more from 1 is said.
pub const SIGMAS: f64 = 3.0;

/// What one rigid floor says of the other channels' factor against the references.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FloorFactor {
    /// The floor's height (the geometry's z).
    pub z: f64,
    /// The reference node on it.
    pub reference_node: String,
    /// The other measured nodes whose motion fixed the floor's.
    pub nodes: Vec<String>,
    /// The setups (indices into the merged setups) that measured them.
    pub setups: Vec<usize>,
    /// The factor those channels read against the references (complex; real for a gain or
    /// sign).
    pub factor: C64,
    /// Its standard error (Birge-widened).
    pub factor_se: f64,
    /// How many (mode, direction) ratios made it.
    pub ratios: usize,
    /// Whether it is further than [`SIGMAS`] standard errors from 1.
    pub to_check: bool,
}

impl FloorFactor {
    /// The sentence the reports give.
    pub fn sentence(&self, setup_names: &[String]) -> String {
        let names: Vec<&str> = self
            .setups
            .iter()
            .filter_map(|&s| setup_names.get(s).map(String::as_str))
            .collect();
        let factor = if self.factor.im.abs() <= self.factor_se.max(1e-3 * self.factor.norm()) {
            format!("{:.3}", self.factor.re)
        } else {
            format!(
                "{:.3}∠{:.0}°",
                self.factor.norm(),
                self.factor.arg().to_degrees()
            )
        };
        let verdict = if self.to_check {
            ": a gain or sign to check"
        } else {
            ": as the setups state"
        };
        format!(
            "on the floor at z = {} (node {} and nodes {}, taken as rigid in its plane), the channels of {} read {factor} ± {:.3} × the references ({} ratios){verdict}",
            self.z,
            self.reference_node,
            self.nodes.join(", "),
            if names.len() == 1 {
                format!("setup {}", names[0])
            } else {
                format!("setups {}", names.join(", "))
            },
            self.factor_se,
            self.ratios
        )
    }
}

/// The factor each rigid floor of `geometry` gives for the channels on it against the
/// references of `merged` (see the module's documentation): one per floor with a reference
/// node and enough other measured in-plane motion (three equations) in some mode.
pub fn floor_factors(merged: &MergedModes, geometry: &Geometry) -> Vec<FloorFactor> {
    let position = |name: &str| geometry.nodes.iter().find(|n| n.0 == name).map(|n| n.1);
    let extent = geometry
        .nodes
        .iter()
        .flat_map(|n| n.1)
        .fold(0.0f64, |m, v| m.max(v.abs()))
        .max(1.0);
    let mut out = Vec::new();
    let mut seen_refs: Vec<&str> = Vec::new();
    for dof in merged.dofs.iter().filter(|d| d.reference) {
        let r = dof.node.as_str();
        let Some(pr) = position(r) else { continue };
        if seen_refs.contains(&r) {
            continue;
        }
        seen_refs.push(r);
        // The floor: measured nodes at the reference's height, the reference not among them.
        let floor: Vec<(&str, [f64; 3])> = merged
            .dofs
            .iter()
            .filter(|d| !d.reference && d.node != r)
            .filter_map(|d| Some((d.node.as_str(), position(&d.node)?)))
            .filter(|(_, p)| (p[2] - pr[2]).abs() <= 1e-6 * extent)
            .fold(Vec::new(), |mut v, n| {
                if !v.iter().any(|(m, _)| *m == n.0) {
                    v.push(n);
                }
                v
            });
        let ratios: Vec<(C64, f64)> = merged
            .modes
            .iter()
            .flat_map(|m| mode_ratios(m, r, pr, &floor))
            .collect();
        let Some((factor, factor_se)) = pooled(&ratios) else {
            continue;
        };
        let setups = {
            let mut s: Vec<usize> = merged
                .dofs
                .iter()
                .filter(|d| !d.reference && floor.iter().any(|(n, _)| *n == d.node))
                .flat_map(|d| d.setups.iter().copied())
                .collect();
            s.sort_unstable();
            s.dedup();
            s
        };
        out.push(FloorFactor {
            z: pr[2],
            reference_node: r.to_string(),
            nodes: floor.iter().map(|(n, _)| n.to_string()).collect(),
            setups,
            factor,
            factor_se,
            ratios: ratios.len(),
            to_check: (factor - C64::new(1.0, 0.0)).norm() > SIGMAS * factor_se,
        });
    }
    out
}

/// Mode `m`'s ratios on the floor of reference node `r` (at `pr`) and the other nodes
/// `floor`: one per in-plane direction where the reference moves enough.
fn mode_ratios(
    m: &MergedMode,
    r: &str,
    pr: [f64; 3],
    floor: &[(&str, [f64; 3])],
) -> Vec<(C64, f64)> {
    let top = m
        .nodes
        .iter()
        .flat_map(|n| n.motion.iter().flatten())
        .map(|v| v.norm())
        .fold(0.0, f64::max);
    let Some(reference) = m.nodes.iter().find(|n| n.node == r) else {
        return Vec::new();
    };
    // Rows (1, 0, −Δy) for x and (0, 1, Δx) for y, each with its value and weight.
    let mut rows: Vec<([f64; 3], C64, f64)> = Vec::new();
    // Whether every entry has its standard error (its weight 1/σ²), else all weigh 1.
    let mut with_se = true;
    for (name, p) in floor {
        let Some(n) = m.nodes.iter().find(|n| n.node == *name) else {
            continue;
        };
        let (dx, dy) = (p[0] - pr[0], p[1] - pr[1]);
        for (k, row) in [(0, [1.0, 0.0, -dy]), (1, [0.0, 1.0, dx])] {
            if let Some(v) = n.motion[k] {
                let se = n.se[k].filter(|e| *e > 0.0);
                with_se &= se.is_some();
                rows.push((row, v, se.map_or(1.0, |e| 1.0 / (e * e))));
            }
        }
    }
    if rows.len() < 3 || top == 0.0 {
        return Vec::new();
    }
    // Weighted normal equations N x = Aᵀ W u, N = Aᵀ W A (3 × 3, real).
    let mut n = [[0.0; 3]; 3];
    let mut rhs = [C64::new(0.0, 0.0); 3];
    for (row, v, w) in &rows {
        for i in 0..3 {
            rhs[i] += row[i] * w * v;
            for j in 0..3 {
                n[i][j] += row[i] * w * row[j];
            }
        }
    }
    let Some(inv) = inverse3(&n) else {
        return Vec::new();
    };
    let fit: Vec<C64> = (0..3)
        .map(|i| (0..3).map(|j| rhs[j] * inv[i][j]).sum())
        .collect();
    // Without the entries' errors the weights are 1: the fit's variance from its residual.
    let scale = if with_se || rows.len() <= 3 {
        1.0
    } else {
        let rss: f64 = rows
            .iter()
            .map(|(row, v, w)| w * (v - (0..3).map(|i| fit[i] * row[i]).sum::<C64>()).norm_sqr())
            .sum();
        rss / (rows.len() - 3) as f64
    };
    (0..2)
        .filter_map(|k| {
            let measured = reference.motion[k]?;
            if measured.norm() < LEAST_REFERENCE * top {
                return None;
            }
            let predicted = fit[k];
            let ratio = predicted / measured;
            let var_pred = inv[k][k] * scale;
            let rel_ref = reference.se[k].map_or(0.0, |e| e / measured.norm());
            let se = ratio.norm()
                * (var_pred / predicted.norm_sqr().max(f64::MIN_POSITIVE) + rel_ref * rel_ref)
                    .sqrt();
            (se.is_finite() && se > 0.0 && se <= MOST_RELATIVE_SE * ratio.norm())
                .then_some((ratio, se))
        })
        .collect()
}

/// The inverse-variance weighted mean of `ratios` and its standard error, widened by the
/// Birge ratio when they scatter more than their errors; `None` without any.
fn pooled(ratios: &[(C64, f64)]) -> Option<(C64, f64)> {
    if ratios.is_empty() {
        return None;
    }
    let w: Vec<f64> = ratios.iter().map(|(_, s)| 1.0 / (s * s)).collect();
    let total: f64 = w.iter().sum();
    let mean: C64 = ratios.iter().zip(&w).map(|((r, _), w)| r * w).sum::<C64>() / total;
    let se = total.sqrt().recip();
    let birge = if ratios.len() > 1 {
        let chi2: f64 = ratios
            .iter()
            .zip(&w)
            .map(|((r, _), w)| w * (r - mean).norm_sqr())
            .sum();
        // A complex ratio has two parts: 2(n − 1) degrees of freedom.
        (chi2 / (2 * (ratios.len() - 1)) as f64).sqrt().max(1.0)
    } else {
        1.0
    };
    Some((mean, se * birge))
}

/// The inverse of a symmetric 3 × 3 matrix, `None` when it is singular.
fn inverse3(a: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
        let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
        a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]
    };
    let det = a[0][0] * c(0, 0) + a[0][1] * c(0, 1) + a[0][2] * c(0, 2);
    let size = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    // Singular, or not a number.
    if det.is_nan() || det.abs() <= 1e-12 * size * size * size {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for (i, row) in inv.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            // The adjugate is the cofactors' transpose.
            *v = c(j, i) / det;
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use covssi::multisetup::{MergedDof, NodeMotion};

    /// A square floor at z = 3 (reference node `r` at a corner, nodes `a`, `b`, `c` at the
    /// others) moving rigidly in two modes, the other nodes read `gain` times their motion;
    /// entries with standard error 0.01 and a deterministic error of that size.
    fn floor(gain: C64) -> (MergedModes, Geometry) {
        let at = |name: &str, x: f64, y: f64| (name.to_string(), [x, y, 3.0]);
        let geometry = Geometry {
            nodes: vec![
                at("r", 0.0, 0.0),
                at("a", 2.0, 0.0),
                at("b", 2.0, 2.0),
                at("c", 0.0, 2.0),
                ("ground".into(), [0.0, 0.0, 0.0]),
            ],
            lines: Vec::new(),
        };
        let dof = |node: &str, k: usize, reference: bool, setup: usize| MergedDof {
            node: node.into(),
            direction: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]][k],
            reference,
            setups: if reference { vec![0, 1] } else { vec![setup] },
        };
        let dofs = vec![
            dof("r", 0, true, 0),
            dof("r", 1, true, 0),
            dof("a", 0, false, 0),
            dof("a", 1, false, 0),
            dof("b", 0, false, 1),
            dof("b", 1, false, 1),
            dof("c", 0, false, 1),
        ];
        let mut wobble = 0.0f64;
        let mut noisy = |v: C64| {
            wobble += 1.0;
            v + C64::new(0.01 * (wobble * 1.7).sin(), 0.01 * (wobble * 0.9).cos())
        };
        let modes = [(1.0, 0.8, 0.1), (0.9, -1.0, -0.2)]
            .iter()
            .map(|&(a, b, theta)| {
                let motion =
                    |x: f64, y: f64| (C64::new(a - theta * y, 0.0), C64::new(b + theta * x, 0.0));
                let node = |name: &str,
                            x: f64,
                            y: f64,
                            g: C64,
                            y_axis: bool,
                            noisy: &mut dyn FnMut(C64) -> C64| {
                    let (u, v) = motion(x, y);
                    NodeMotion {
                        node: name.into(),
                        motion: [Some(noisy(g * u)), y_axis.then(|| noisy(g * v)), None],
                        se: [Some(0.01), y_axis.then_some(0.01), None],
                    }
                };
                let one = C64::new(1.0, 0.0);
                MergedMode {
                    frequency_hz: 1.0,
                    frequency_se_hz: None,
                    damping_ratio: 0.01,
                    damping_se: None,
                    scatter_ratio: None,
                    seen_in: Vec::new(),
                    shape: Vec::new(),
                    shape_se: Vec::new(),
                    nodes: vec![
                        node("r", 0.0, 0.0, one, true, &mut noisy),
                        node("a", 2.0, 0.0, gain, true, &mut noisy),
                        node("b", 2.0, 2.0, gain, true, &mut noisy),
                        node("c", 0.0, 2.0, gain, false, &mut noisy),
                    ],
                }
            })
            .collect();
        let merged = MergedModes {
            setups: vec!["one".into(), "two".into()],
            dofs,
            modes,
            notes: Vec::new(),
        };
        (merged, geometry)
    }

    #[test]
    fn a_rigid_floor_tells_the_other_channels_factor() {
        for (gain, check) in [
            (C64::new(-0.5, 0.0), true),
            (C64::new(1.0, 0.0), false),
            (C64::new(0.0, 2.0), true),
        ] {
            let (merged, geometry) = floor(gain);
            let [f] = &floor_factors(&merged, &geometry)[..] else {
                panic!("one floor")
            };
            assert_eq!((f.reference_node.as_str(), f.z), ("r", 3.0));
            assert_eq!(f.nodes, ["a", "b", "c"]);
            assert_eq!(f.setups, [0, 1]);
            // Both modes, both directions: the reference moves well in each.
            assert_eq!(f.ratios, 4);
            // Entries' errors of 0.01 on motions near 1: the factor within a few of its
            // standard errors (about 0.01) of the gain.
            assert!(
                (f.factor - gain).norm() < 4.0 * f.factor_se.max(0.005),
                "{f:?}"
            );
            assert!(f.factor_se > 0.0 && f.factor_se < 0.05, "{f:?}");
            assert_eq!(f.to_check, check, "{f:?}");
            let said = f.sentence(&merged.setups);
            assert!(
                said.contains("the channels of setups one, two read"),
                "{said}"
            );
            assert!(
                said.ends_with(if check {
                    "a gain or sign to check"
                } else {
                    "as the setups state"
                }),
                "{said}"
            );
        }
        // A floor without a reference, or too few motions on it, says nothing.
        let (mut merged, geometry) = floor(C64::new(1.0, 0.0));
        merged.dofs.retain(|d| !d.reference);
        assert!(floor_factors(&merged, &geometry).is_empty());
        let (mut merged, geometry) = floor(C64::new(1.0, 0.0));
        for m in &mut merged.modes {
            m.nodes.retain(|n| n.node == "r" || n.node == "c");
        }
        assert!(floor_factors(&merged, &geometry).is_empty());
    }
}
