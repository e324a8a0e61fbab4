//! One merged mode's shape: each setup's shape in displacement on the merged DOFs, the
//! setups' scales fitted on the references, and the standard errors carried through.

use super::{MergedDof, SetupModes, same_dof};
use crate::{Complex64 as C64, ReportedMode};

/// A setup's mode shape on the merged DOFs (`None` where the setup has no channel), as a
/// displacement, with its standard errors when the setup has them.
#[derive(Debug, Clone)]
pub(super) struct Shape {
    pub values: Vec<Option<C64>>,
    pub se: Vec<Option<f64>>,
}

impl Shape {
    /// Mode `m` of `setup` on `dofs`: each entry divided by its channel's gain · λ^power.
    pub fn in_displacement(m: &ReportedMode, setup: &SetupModes, dofs: &[MergedDof]) -> Shape {
        let w = 2.0 * std::f64::consts::PI * m.frequency_hz;
        let z = m.damping_ratio.clamp(-1.0, 1.0);
        let lambda = w * C64::new(-z, (1.0 - z * z).sqrt());
        let mut values = vec![None; dofs.len()];
        let mut se = vec![None; dofs.len()];
        let shape = m.shape.as_deref().unwrap_or(&[]);
        for (c, ch) in setup.channels.iter().enumerate() {
            let Some(d) = dofs
                .iter()
                .position(|d| same_dof(&ch.node, ch.direction, d))
            else {
                continue;
            };
            let factor = ch.gain * lambda.powi(ch.quantity.power());
            values[d] = shape.get(c).map(|v| v / factor);
            se[d] = m
                .shape_se
                .as_ref()
                .and_then(|e| e.get(c))
                .map(|e| e / factor.norm());
        }
        Shape { values, se }
    }
}

/// A merged mode's shape, its standard errors and each setup's scale.
pub(super) struct Scaled {
    pub shape: Vec<Option<C64>>,
    pub shape_se: Vec<Option<f64>>,
    pub scales: Vec<C64>,
}

/// The scale fit's sweeps at most; it converges in a few.
const SWEEPS: usize = 200;

/// A standard error of 0 (the entry a setup's shape was scaled to 1 by) is floored to this
/// fraction of the largest entry, so that its weight stays finite.
const SE_FLOOR: f64 = 1e-9;

/// Scale `shapes` (one per setup that saw the mode) on `references` and merge them.
pub(super) fn scale(shapes: &[&Shape], references: &[usize], dofs: usize) -> Scaled {
    let with_se = shapes.iter().all(|s| {
        references
            .iter()
            .all(|&r| s.values[r].is_none() || s.se[r].is_some())
    });
    // Each setup's reference entries and their weights 1/σ² (1 without errors).
    let refs: Vec<Vec<(usize, C64, f64)>> = shapes
        .iter()
        .map(|s| {
            let top = s
                .values
                .iter()
                .flatten()
                .map(|v| v.norm())
                .fold(0.0, f64::max);
            references
                .iter()
                .filter_map(|&r| {
                    let v = s.values[r]?;
                    let w = if with_se {
                        1.0 / s.se[r].unwrap_or(0.0).max(SE_FLOOR * top).powi(2)
                    } else {
                        1.0
                    };
                    Some((r, v, w))
                })
                .collect()
        })
        .collect();
    let (rho, alpha) = fit_scales(&refs, dofs);
    // E|δρ_c|² and E|δα_s|² (first order; see the module).
    let mut rho_var = vec![0.0; dofs];
    for (setup, a) in refs.iter().zip(&alpha) {
        for &(r, _, w) in setup {
            rho_var[r] += w / a.norm_sqr();
        }
    }
    let rho_var: Vec<f64> = rho_var
        .iter()
        .map(|&p| if p > 0.0 { 1.0 / p } else { f64::INFINITY })
        .collect();
    let alpha_var: Vec<f64> = refs
        .iter()
        .zip(&alpha)
        .map(|(setup, a)| {
            let d: f64 = setup.iter().map(|&(_, v, w)| w * v.norm_sqr()).sum();
            let own = a.norm_sqr() / d;
            let common: f64 = setup
                .iter()
                .map(|&(r, v, w)| (w * v.norm()).powi(2) * rho_var[r])
                .sum::<f64>()
                / (d * d);
            own + common
        })
        .collect();
    let mut shape = vec![None; dofs];
    let mut shape_se = vec![None; dofs];
    for d in 0..dofs {
        if references.contains(&d) {
            shape[d] = Some(rho[d]);
            shape_se[d] = with_se.then(|| rho_var[d].sqrt());
            continue;
        }
        // Every setup that measured this DOF and saw the mode (one, for a roving DOF).
        let estimates: Vec<(C64, Option<f64>)> = shapes
            .iter()
            .zip(&alpha)
            .zip(&alpha_var)
            .filter_map(|((s, a), av)| {
                let v = s.values[d]?;
                let var = s.se[d].map(|e| a.norm_sqr() * e * e + v.norm_sqr() * av);
                Some((a * v, var))
            })
            .collect();
        (shape[d], shape_se[d]) = pool(&estimates);
    }
    normalize(&mut shape, &mut shape_se, alpha)
}

/// Inverse-variance mean of complex estimates (plain mean without variances) and its error.
fn pool(estimates: &[(C64, Option<f64>)]) -> (Option<C64>, Option<f64>) {
    if estimates.is_empty() {
        return (None, None);
    }
    let vars: Option<Vec<f64>> = estimates.iter().map(|e| e.1).collect();
    match vars {
        Some(v) if v.iter().all(|x| *x > 0.0 && x.is_finite()) => {
            let sw: f64 = v.iter().map(|x| 1.0 / x).sum();
            let mean = estimates.iter().zip(&v).map(|(e, x)| e.0 / *x).sum::<C64>() / sw;
            (Some(mean), Some(sw.recip().sqrt()))
        }
        Some(v) if estimates.len() == 1 => (Some(estimates[0].0), Some(v[0].sqrt())),
        _ => {
            let n = estimates.len() as f64;
            (Some(estimates.iter().map(|e| e.0).sum::<C64>() / n), None)
        }
    }
}

/// ρ and α by alternating weighted least squares (see the module), ρ's largest entry 1.
fn fit_scales(refs: &[Vec<(usize, C64, f64)>], dofs: usize) -> (Vec<C64>, Vec<C64>) {
    let strength =
        |s: &Vec<(usize, C64, f64)>| s.iter().map(|&(_, v, w)| w * v.norm_sqr()).sum::<f64>();
    let anchor = (0..refs.len())
        .max_by(|&a, &b| strength(&refs[a]).total_cmp(&strength(&refs[b])))
        .unwrap_or(0);
    let mut rho = vec![C64::new(0.0, 0.0); dofs];
    for &(r, v, _) in &refs[anchor] {
        rho[r] = v;
    }
    let mut alpha = vec![C64::new(1.0, 0.0); refs.len()];
    for _ in 0..SWEEPS {
        set_largest_to_one(&mut rho, &mut alpha);
        let before = alpha.clone();
        for (a, setup) in alpha.iter_mut().zip(refs) {
            let num: C64 = setup.iter().map(|&(r, v, w)| w * v.conj() * rho[r]).sum();
            *a = num / strength(setup);
        }
        let mut sum = vec![C64::new(0.0, 0.0); dofs];
        let mut weight = vec![0.0; dofs];
        for (a, setup) in alpha.iter().zip(refs) {
            for &(r, v, w) in setup {
                let w = w / a.norm_sqr();
                sum[r] += w * a * v;
                weight[r] += w;
            }
        }
        for r in 0..dofs {
            if weight[r] > 0.0 {
                rho[r] = sum[r] / weight[r];
            }
        }
        let change = alpha
            .iter()
            .zip(&before)
            .map(|(a, b)| (a - b).norm() / a.norm())
            .fold(0.0, f64::max);
        if change < 1e-13 {
            break;
        }
    }
    set_largest_to_one(&mut rho, &mut alpha);
    (rho, alpha)
}

/// Divide ρ by its largest entry and multiply α by it, so that α r ≈ ρ still holds.
fn set_largest_to_one(rho: &mut [C64], alpha: &mut [C64]) {
    let Some(k) = largest(rho.iter().map(|v| Some(*v))) else {
        return;
    };
    let top = rho[k];
    rho.iter_mut().for_each(|v| *v /= top);
    alpha.iter_mut().for_each(|a| *a /= top);
}

fn largest(values: impl Iterator<Item = Option<C64>>) -> Option<usize> {
    values
        .enumerate()
        .filter_map(|(i, v)| v.map(|v| (i, v.norm())))
        .filter(|(_, n)| *n > 0.0 && n.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// The merged shape scaled so its largest entry is 1, the scales and errors with it.
fn normalize(shape: &mut [Option<C64>], se: &mut [Option<f64>], mut scales: Vec<C64>) -> Scaled {
    if let Some(k) = largest(shape.iter().copied()) {
        let top = shape[k].unwrap_or(C64::new(1.0, 0.0));
        for (v, e) in shape.iter_mut().zip(se.iter_mut()) {
            *v = v.map(|v| v / top);
            *e = e.map(|e| e / top.norm());
        }
        scales.iter_mut().for_each(|a| *a /= top);
    }
    Scaled {
        shape: shape.to_vec(),
        shape_se: se.to_vec(),
        scales,
    }
}
