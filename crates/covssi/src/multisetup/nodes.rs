//! A merged mode's motion at each node, in the geometry's axes, from the directions measured
//! there.

use super::MergedDof;
use crate::Complex64 as C64;
use crate::linalg::{Dense, spd_inverse};

/// A node's motion in one mode: its x, y, z components where the directions measured at the
/// node determine them (`None` on an axis no direction reaches, or for every axis when the
/// directions do not separate the axes they reach).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct NodeMotion {
    /// The node.
    pub node: String,
    /// Its displacement along x, y, z (the shape's scale).
    pub motion: [Option<C64>; 3],
    /// Standard error of each component (√E|δ|²); `None` where the motion is, or without the
    /// setups' errors.
    pub se: [Option<f64>; 3],
}

/// A direction component below this reaches no axis.
const NO_COMPONENT: f64 = 1e-9;

/// The motion of every node of `dofs` that the merged `shape` has an entry at.
pub(super) fn node_motions(
    dofs: &[MergedDof],
    shape: &[Option<C64>],
    se: &[Option<f64>],
) -> Vec<NodeMotion> {
    let mut nodes: Vec<&str> = Vec::new();
    for d in dofs {
        if !nodes.contains(&d.node.as_str()) {
            nodes.push(&d.node);
        }
    }
    nodes
        .into_iter()
        .filter_map(|node| {
            let at: Vec<usize> = (0..dofs.len())
                .filter(|&d| dofs[d].node == node && shape[d].is_some())
                .collect();
            (!at.is_empty()).then(|| solve(node, &at, dofs, shape, se))
        })
        .collect()
}

/// Weighted least squares for one node (see the module).
fn solve(
    node: &str,
    at: &[usize],
    dofs: &[MergedDof],
    shape: &[Option<C64>],
    se: &[Option<f64>],
) -> NodeMotion {
    let axes: Vec<usize> = (0..3)
        .filter(|&k| {
            at.iter()
                .any(|&d| dofs[d].direction[k].abs() > NO_COMPONENT)
        })
        .collect();
    let with_se = at.iter().all(|&d| se[d].is_some());
    let top = at.iter().filter_map(|&d| se[d]).fold(0.0, f64::max);
    let weight = |d: usize| {
        if with_se {
            1.0 / se[d].unwrap_or(0.0).max(1e-9 * top.max(1e-300)).powi(2)
        } else {
            1.0
        }
    };
    let n = axes.len();
    let mut m = Dense::zeros(n, n);
    let mut b = vec![C64::new(0.0, 0.0); n];
    for &d in at {
        let w = weight(d);
        let dir = dofs[d].direction;
        let v = shape[d].unwrap_or_default();
        for (i, &ki) in axes.iter().enumerate() {
            b[i] += w * dir[ki] * v;
            for (j, &kj) in axes.iter().enumerate() {
                m.set(i, j, m.at(i, j) + w * dir[ki] * dir[kj]);
            }
        }
    }
    let mut out = NodeMotion {
        node: node.to_string(),
        motion: [None; 3],
        se: [None; 3],
    };
    if let Some(inv) = spd_inverse(&m).filter(|_| n > 0) {
        for (i, &k) in axes.iter().enumerate() {
            let u: C64 = (0..n).map(|j| inv.at(i, j) * b[j]).sum();
            out.motion[k] = Some(u);
            out.se[k] = with_se.then(|| inv.at(i, i).max(0.0).sqrt());
        }
    }
    out
}
