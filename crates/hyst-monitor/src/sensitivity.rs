//! The subspace residual's sensitivity to the reference modes' frequencies (Basseville et
//! al. 2000; Döhler and Mevel 2013, the test on the modal parameters): the directions in which
//! ζ = vec(Sᵀ H V₀) moves when one mode's frequency changes, from the reference alone.
//!
//! The reference Hankel matrix H₀ = O 𝒞 (observability times controllability, by its SVD:
//! O = U₁Σ₁^½, 𝒞 = Σ₁^½V₁ᵀ), its state matrix A = O↑⁺O↓ (shift invariance, r rows per block),
//! and in modal coordinates (A = ΦΛΦ⁻¹) O_m = OΦ, whose block row i holds c_j λ_jⁱ, and
//! 𝒞_m = Φ⁻¹𝒞. When eigenvalue λ_j moves by δλ_j, O_m's column j moves by i c_j λ_jⁱ⁻¹δλ_j in
//! block row i; since SᵀO = 0, the change of 𝒞 does not reach ζ to first order, so
//! δζ = vec(Sᵀ δO_m 𝒞_m V₀). A relative change ε of the mode's frequency at a fixed damping
//! ratio moves its continuous pole s = ln(λ)/Δt to s(1 + ε), so δλ_j = λ_j ln(λ_j) ε (no
//! Δt needed); the pair (λ_j, λ̄_j) together gives 2 Re of the one's term.
//!
//! nalgebra gives a real matrix's complex eigenvalues but not its eigenvectors: each is found
//! by inverse iteration on A − λI (complex LU), a few steps from a fixed start.

use nalgebra::{Complex, DMatrix, DVector};

type C64 = Complex<f64>;

/// The sensitivity J (entries of ζ × modes, ascending in frequency) of the residual to a
/// relative change of each mode's frequency of the reference `h0` (its mean Hankel matrix,
/// `channels` rows per block row) at model order `order`, for the left null space `null`
/// and the column compression `columns`; `None` when the reference holds no oscillating pole
/// or its eigenvectors cannot be found; beside it, each mode's pole frequency (cycles per
/// sample, the damped frequency's).
pub(crate) fn frequency_sensitivity(
    h0: &DMatrix<f64>,
    channels: usize,
    order: usize,
    null: &DMatrix<f64>,
    columns: &DMatrix<f64>,
) -> Option<(DMatrix<f64>, Vec<f64>)> {
    let rows = h0.nrows();
    if channels == 0 || !rows.is_multiple_of(channels) || order == 0 {
        return None;
    }
    let blocks = rows / channels;
    if blocks < 3 || (blocks - 1) * channels < order {
        return None;
    }
    let (o, ctrl) = factors(h0, order)?;
    let up = o.rows(0, rows - channels).into_owned();
    let down = o.rows(channels, rows - channels).into_owned();
    // Shift invariance needs O↑ of full column rank: with real mode shapes C has rank
    // order/2, so O↑ must hold at least two block rows.
    let sv = up.singular_values();
    let (largest, smallest) = (sv.max(), sv.min());
    if smallest.is_nan() || smallest <= 1e-8 * largest {
        return None;
    }
    let a = up.pseudo_inverse(0.0).ok()? * down;
    let (values, phi) = eigen(&a)?;
    let phi_inv = phi.clone().try_inverse()?;
    let o_m = o.map(|v| C64::new(v, 0.0)) * &phi;
    let c_m = &phi_inv * ctrl.map(|v| C64::new(v, 0.0));
    let mut poles: Vec<usize> = (0..values.len())
        .filter(|&j| values[j].im > 1e-9 * values[j].norm().max(1e-300))
        .collect();
    poles.sort_by(|&a, &b| values[a].arg().total_cmp(&values[b].arg()));
    let sens: Vec<DVector<f64>> = poles
        .iter()
        .map(|&j| {
            let l = values[j];
            let dl = l * l.ln();
            let mut d = DMatrix::<C64>::zeros(rows, 1);
            for i in 1..blocks {
                let factor = l.powi(i as i32 - 1) * C64::new(i as f64, 0.0) * dl;
                for c in 0..channels {
                    d[(i * channels + c, 0)] = o_m[(c, j)] * factor;
                }
            }
            let dh = (d * c_m.row(j)).map(|v| 2.0 * v.re);
            let z = null.transpose() * dh * columns;
            DVector::from_column_slice(z.as_slice())
        })
        .collect();
    let frequencies = poles
        .iter()
        .map(|&j| values[j].arg() / (2.0 * std::f64::consts::PI))
        .collect();
    (!sens.is_empty()).then(|| (DMatrix::from_columns(&sens), frequencies))
}

/// O (rows × order) and 𝒞 (order × columns) of `h` by its SVD, the singular values split
/// evenly.
fn factors(h: &DMatrix<f64>, order: usize) -> Option<(DMatrix<f64>, DMatrix<f64>)> {
    let svd = h.clone().svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let mut by_size: Vec<usize> = (0..svd.singular_values.len()).collect();
    by_size.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let kept = by_size.get(..order)?;
    let o = DMatrix::from_columns(
        &kept
            .iter()
            .map(|&k| u.column(k) * svd.singular_values[k].sqrt())
            .collect::<Vec<_>>(),
    );
    let ctrl = DMatrix::from_rows(
        &kept
            .iter()
            .map(|&k| vt.row(k) * svd.singular_values[k].sqrt())
            .collect::<Vec<_>>(),
    );
    Some((o, ctrl))
}

/// The eigenvalues of the real `a` and their eigenvectors (columns), each by inverse
/// iteration on a − λI shifted by a hair off the eigenvalue.
fn eigen(a: &DMatrix<f64>) -> Option<(Vec<C64>, DMatrix<C64>)> {
    let n = a.nrows();
    let values: Vec<C64> = a.complex_eigenvalues().iter().copied().collect();
    let ac = a.map(|v| C64::new(v, 0.0));
    let scale = a.norm().max(1e-300);
    let mut vectors = Vec::with_capacity(n);
    for (j, &l) in values.iter().enumerate() {
        let shift = l + C64::new(1e-10 * scale, 1e-10 * scale);
        let m = &ac - DMatrix::<C64>::identity(n, n) * shift;
        let lu = m.lu();
        // A start with a part along every eigenvector (not all ones: a symmetric structure
        // could miss one).
        let mut x = DVector::<C64>::from_fn(n, |i, _| C64::new(1.0 + 0.37 * (i + j) as f64, 0.1));
        for _ in 0..3 {
            x = lu.solve(&x)?;
            let norm = x.norm();
            if !norm.is_finite() || norm == 0.0 {
                return None;
            }
            x /= C64::new(norm, 0.0);
        }
        vectors.push(x);
    }
    Some((values, DMatrix::from_columns(&vectors)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subspace::eigenvectors;

    /// A two-mode Hankel matrix of exact correlations (3 channels, 4 block rows): the
    /// sensitivity of each mode agrees with a central finite difference of ζ under a 10⁻⁵
    /// relative frequency change (its second-order error about 10⁻⁵ of the derivative,
    /// taken 10⁻³ with the eigenvectors' own error).
    #[test]
    fn agrees_with_a_finite_difference() {
        let dt = 0.05;
        let modes = [(1.3, 0.02), (3.4, 0.03)];
        let shapes = [[1.0, 0.8, 0.3], [0.6, -0.5, 1.0]];
        let gains = [[0.9, 0.4, -0.2], [0.3, 1.0, 0.7]];
        let hankel = |eps: f64, which: usize| -> DMatrix<f64> {
            let (r, blocks) = (3, 4);
            let mut h = DMatrix::<f64>::zeros(r * blocks, r * blocks);
            for (m, &(f, z)) in modes.iter().enumerate() {
                let f = if m == which { f * (1.0 + eps) } else { f };
                let w = 2.0 * std::f64::consts::PI * f;
                let s = C64::new(-z * w, w * (1.0 - z * z).sqrt());
                let l = (s * dt).exp();
                for i in 0..blocks {
                    for k in 0..blocks {
                        let p = l.powi((i + k + 1) as i32);
                        for a in 0..r {
                            for b in 0..r {
                                // Rank one per pole: a complex shape entry of channel a
                                // times a complex gain of reference b.
                                let c = C64::new(shapes[m][a], 0.3 * shapes[m][(a + 1) % r])
                                    * C64::new(gains[m][b], 0.1 * b as f64);
                                h[(i * r + a, k * r + b)] += 2.0 * (c * p).re;
                            }
                        }
                    }
                }
            }
            h
        };
        let h0 = hankel(0.0, 9);
        let order = 4;
        let null = eigenvectors(&h0 * h0.transpose(), 12 - order, false);
        let columns = eigenvectors(h0.transpose() * &h0, order, true);
        let (j, frequencies) =
            frequency_sensitivity(&h0, 3, order, &null, &columns).expect("sensitivity");
        // The poles' (damped) frequencies in cycles per sample: f√(1 − ζ²)·Δt.
        for (f, (hz, z)) in frequencies.iter().zip(modes) {
            let damped = hz * (1.0f64 - z * z).sqrt() * dt;
            assert!((f - damped).abs() < 1e-9, "{f} against {damped}");
        }
        assert_eq!(j.shape(), ((12 - order) * order, 2));
        let eps = 1e-5;
        for m in 0..2 {
            let zeta = |e: f64| {
                let h = hankel(e, m);
                DVector::from_column_slice((null.transpose() * h * &columns).as_slice())
            };
            let fd = (zeta(eps) - zeta(-eps)) / (2.0 * eps);
            let err = (&fd - j.column(m)).norm() / fd.norm();
            assert!(err < 1e-3, "mode {m}: relative error {err:.2e}");
        }
    }
}
