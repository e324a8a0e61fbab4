//! The composite Whittle likelihood L at θ, and what [`What`] asks for besides: the score,
//! the Fisher information or the score's covariance, the ratios I/S, the misfit; and each
//! channel's fitted noise floor.

use crate::linalg::{C64, Dense};
use crate::refine::model::information::{Shape, fisher_blocks};
use crate::refine::model::{CHUNK, Eval, Model, What};
use crate::refine::parametrization::{Denominator, LogProduct, poly_at};
use crate::refine::results::MisfitCounts;
use crate::refine::spectra::{FREQUENCY_CHUNK, Spectra};
use rayon::iter::{IntoParallelIterator, ParallelIterator};
use std::ops::Range;

impl Model {
    /// The lowest value over frequency of each channel's fitted spectrum S_c (θ of a
    /// per-channel fit with `m` modes): a bound on its white measurement noise's spectral
    /// level, and near it where the modes' tails are below the noise.
    pub(in crate::refine) fn noise_floor(&self, th: &[f64], m: usize) -> Option<Vec<f64>> {
        let q = self.poles(m);
        let den = Denominator::with_reals(th, m, self.reals, self.fs)?;
        let floor = (0..self.l())
            .map(|c| {
                let off = q + c * (q + 1);
                let mut b = vec![1.0];
                b.extend_from_slice(&th[off + 1..=off + q]);
                self.sp
                    .z
                    .iter()
                    .map(|&z| {
                        let b2 = poly_at(&b, z.conj()).norm_sqr();
                        (th[off] + b2.ln() - den.at(z, false, &mut [])).exp()
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .collect::<Vec<f64>>();
        floor
            .iter()
            .all(|v| *v > 0.0 && v.is_finite())
            .then_some(floor)
    }

    /// L at θ and what `what` asks for besides. `None` when θ is outside the model (a pole at
    /// Nyquist, a numerator zero on the unit circle, overflow).
    pub(in crate::refine) fn eval(&self, th: &[f64], m: usize, what: What) -> Option<Eval> {
        let derivs = matches!(what, What::Fisher | What::Sandwich | What::FisherNumerators);
        // Pole parameters, and each numerator's degree: 2m, plus one per real pole.
        let p = self.poles(m);
        // ∂ log S_c by the poles' parameters is −∂ ln|A|², the same for every channel: its
        // columns D_p are stored once (none when the poles are held), and each channel's
        // D_c holds those by ln σ_c² and by B_c's coefficients.
        let shape = Shape {
            p,
            q: p,
            l: self.l(),
            derivs,
            pole_derivs: derivs && what != What::FisherNumerators,
            sandwich: what == What::Sandwich,
            #[cfg(test)]
            ratios: what == What::Ratios,
            #[cfg(not(test))]
            ratios: false,
            misfit: what == What::Misfit,
        };
        let np = p + shape.l * (shape.q + 1);
        let den = Denominator::with_reals(th, m, self.reals, self.fs)?;
        let zero = || Eval::zero(if derivs { np } else { 0 });
        // The ratios are per frequency: the misfit needs them so. Everything else sums over
        // the bins. Chunks are summed in order, so the result does not depend on the threads.
        let parts: Vec<Eval> = if shape.ratios || shape.misfit {
            let k = self.k();
            (0..k.div_ceil(FREQUENCY_CHUNK))
                .into_par_iter()
                .map(|ci| {
                    let lo = ci * FREQUENCY_CHUNK;
                    let f = self.sp.frequencies(lo..(lo + FREQUENCY_CHUNK).min(k));
                    let mut acc = zero();
                    acc.misfit = shape.misfit.then(MisfitCounts::new);
                    self.chunk(&f, th, &den, &shape, 0..f.bins(), acc).0
                })
                .collect()
        } else {
            let bins = self.sp.bins();
            (0..bins.div_ceil(CHUNK))
                .into_par_iter()
                .map(|ci| {
                    let lo = ci * CHUNK;
                    let hi = (lo + CHUNK).min(bins);
                    let (mut acc, dp, d) = self.chunk(&self.sp, th, &den, &shape, lo..hi, zero());
                    if shape.derivs && !shape.sandwich {
                        fisher_blocks(&mut acc, &dp, &d, &shape);
                    }
                    if shape.sandwich {
                        self.sandwich_blocks(&mut acc, &dp, &d, &shape, lo..hi);
                    }
                    acc
                })
                .collect()
        };
        let total = parts.into_iter().reduce(Eval::merge).unwrap_or_else(zero);
        total.l.is_finite().then_some(total)
    }

    /// `L` over the bins `rows` of `sp`, and with derivatives the score and the rows of
    /// D_p (the poles' columns) and of each channel's D_c, each row times √n_b (so that
    /// their Gram matrices sum n_b ∂ln S ∂ln Sᵀ).
    pub(super) fn chunk(
        &self,
        sp: &Spectra,
        th: &[f64],
        den: &Denominator,
        shape: &Shape,
        rows: Range<usize>,
        mut acc: Eval,
    ) -> (Eval, Dense, Vec<Dense>) {
        let Shape {
            p,
            q,
            l,
            derivs,
            pole_derivs,
            ratios,
            ..
        } = *shape;
        let (lo, hi) = (rows.start, rows.end);
        let mut d = if derivs {
            vec![Dense::zeros(hi - lo, q + 1); l]
        } else {
            Vec::new()
        };
        let mut dp = Dense::zeros(if pole_derivs { hi - lo } else { 0 }, p);
        let mut da = vec![0.0; p];
        // z̄ᵏ, k = 0..=q, as real and imaginary parts (contiguous for the loops over k).
        let (mut pw_re, mut pw_im) = (vec![0.0; q + 1], vec![0.0; q + 1]);
        // S_c = e^{θ_c} |B_c|² / |A|²: each channel's level once per call and 1/|A|² once per
        // frequency, and Σ_c ln S_c through one logarithm of Π_c |B_c|² (a logarithm and an
        // exponential per channel and frequency were a fifth of the refinement's time).
        let levels: Vec<f64> = (0..l).map(|c| th[p + c * (q + 1)].exp()).collect();
        let level_logs: f64 = (0..l).map(|c| th[p + c * (q + 1)]).sum();
        for (row, kk) in (lo..hi).enumerate() {
            let z = sp.z[kk];
            let (w, sw) = (sp.w[kk], sp.w[kk].sqrt());
            let log_a2 = den.at(z, pole_derivs, &mut da);
            let inv_a2 = (-log_a2).exp();
            let zc = z.conj();
            let mut power = C64::new(1.0, 0.0);
            for (re, im) in pw_re.iter_mut().zip(pw_im.iter_mut()) {
                (*re, *im) = (power.re, power.im);
                power *= zc;
            }
            // Σ_c n_b r_c, by which the poles' score grows.
            let mut r_sum = 0.0;
            let mut b2_product = LogProduct::default();
            let mut ratio_sum = 0.0;
            for (c, level) in levels.iter().enumerate() {
                let off = p + c * (q + 1);
                let (b_re, b_im) = powers_dot(&pw_re[1..], &pw_im[1..], &th[off + 1..=off + q]);
                let (b_re, b_im) = (1.0 + b_re, b_im);
                let b2 = b_re * b_re + b_im * b_im;
                b2_product.times(b2);
                // Where the product leaves the doubles (a factor beyond e^±700), the
                // exponential of the logarithm, as before.
                let product = level * b2 * inv_a2;
                let s = if product.is_normal() {
                    product
                } else {
                    (th[off] + b2.ln() - log_a2).exp()
                };
                let ic = sp.at(kk, c, c).re;
                ratio_sum += ic / s;
                if ratios {
                    acc.ratios.push(ic / s);
                }
                if let Some(counts) = &mut acc.misfit {
                    counts.add(ic / s);
                }
                // With derivatives: the row of D_c (∂ log S_c, times √n_b), and U += its
                // entries times n_b r. The score is summed as the row is written: reading
                // the row back would stride across D_c's columns.
                if let Some(dc) = d.get_mut(c) {
                    let r = w * (ic / s - 1.0);
                    r_sum += r;
                    // ∂ln|B|²/∂b_k = 2 Re(z̄ᵏ B̄)/|B|² = (Re z̄ᵏ·Re B + Im z̄ᵏ·Im B)·2/|B|²;
                    // D_c is column-major, so its row is every `rows`-th entry from `row`.
                    let g = 2.0 / b2;
                    let (g_re, g_im) = (b_re * g, b_im * g);
                    let rows = dc.rows;
                    let u = &mut acc.u[off..=off + q];
                    u[0] += r;
                    let entries = dc.data[row..].iter_mut().step_by(rows);
                    for (k, entry) in entries.enumerate() {
                        if k == 0 {
                            *entry = sw;
                            continue;
                        }
                        let v = pw_re[k] * g_re + pw_im[k] * g_im;
                        *entry = v * sw;
                        u[k] += v * r;
                    }
                }
            }
            if pole_derivs {
                for (t, dat) in da.iter().enumerate() {
                    dp.set(row, t, -dat * sw);
                    acc.u[t] -= dat * r_sum;
                }
            }
            // Σ_c (ln S_c + I_c/S_c) at this frequency.
            acc.l += w * (level_logs + b2_product.ln() - l as f64 * log_a2 + ratio_sum);
        }
        (acc, dp, d)
    }
}

/// (Σ_k re_k b_k, Σ_k im_k b_k): B(z̄) − 1 from the powers z̄ᵏ (k from 1) and the
/// coefficients b_k, in four interleaved sums (independent chains the processor overlaps).
/// Both sums in one pass over a numerator's ~20 coefficients: `corr`'s dot product (sixteen
/// sums) called twice instead made `hyst ssi --setups` on the steel frame 10 % slower
/// (12.4–12.6 s against 11.2 s, one run after the other).
#[inline]
fn powers_dot(re: &[f64], im: &[f64], b: &[f64]) -> (f64, f64) {
    let (mut sr, mut si) = ([0.0; 4], [0.0; 4]);
    let n = b.len() / 4 * 4;
    for ((r4, i4), b4) in re[..n]
        .chunks_exact(4)
        .zip(im[..n].chunks_exact(4))
        .zip(b[..n].chunks_exact(4))
    {
        for j in 0..4 {
            sr[j] += r4[j] * b4[j];
            si[j] += i4[j] * b4[j];
        }
    }
    let (mut tr, mut ti) = (
        (sr[0] + sr[1]) + (sr[2] + sr[3]),
        (si[0] + si[1]) + (si[2] + si[3]),
    );
    for k in n..b.len() {
        tr += re[k] * b[k];
        ti += im[k] * b[k];
    }
    (tr, ti)
}
