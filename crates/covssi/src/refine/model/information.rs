//! The Fisher information's and the score covariance's blocks, summed frequency by frequency
//! without forming the full Jacobian.

use crate::linalg::{self, Dense};
use crate::refine::model::{Eval, Model, global};
use crate::refine::spectra::pair;
use std::ops::Range;

impl Model {
    /// The sandwich's middle over the frequencies `rows`: J = Σ_{c,c'} D_cᵀ diag(γ²_cc') D_c'
    /// (cov(I_c/S_c, I_c'/S_c') = γ²_cc'), D_c = [D_p D_c] in full, added into `acc.f`.
    pub(super) fn sandwich_blocks(
        &self,
        acc: &mut Eval,
        dp: &Dense,
        d: &[Dense],
        shape: &Shape,
        rows: Range<usize>,
    ) {
        let Shape { p, q, l, .. } = *shape;
        let (lo, hi) = (rows.start, rows.end);
        let per = p + q + 1;
        let d: Vec<Dense> = d
            .iter()
            .map(|dc| {
                let mut full = Dense::zeros(hi - lo, per);
                for row in 0..hi - lo {
                    for t in 0..p {
                        full.set(row, t, dp.at(row, t));
                    }
                    for t in 0..=q {
                        full.set(row, p + t, dc.at(row, t));
                    }
                }
                full
            })
            .collect();
        let mut block = Dense::zeros(per, per);
        for (c, dc) in d.iter().enumerate() {
            let off = p + c * (q + 1);
            for (c2, dc2) in d.iter().enumerate() {
                block.data.iter_mut().for_each(|v| *v = 0.0);
                if c2 == c {
                    linalg::gram_add(dc, &mut block);
                } else {
                    let g = &self.sp.coherence[pair(c, c2, l)][lo..hi];
                    let mut scaled = dc2.clone();
                    for t in 0..per {
                        for (row, gr) in g.iter().enumerate() {
                            scaled.set(row, t, scaled.at(row, t) * gr);
                        }
                    }
                    linalg::tn_add(dc, &scaled, &mut block);
                }
                let off2 = p + c2 * (q + 1);
                for a in 0..per {
                    for b in 0..per {
                        let (ga, gb) = (global(a, p, off), global(b, p, off2));
                        acc.f.set(ga, gb, acc.f.at(ga, gb) + block.at(a, b));
                    }
                }
            }
        }
    }
}

/// What the sizes of one evaluation are, and what it computes.
#[derive(Clone, Copy)]
pub(super) struct Shape {
    /// Pole parameters.
    pub(super) p: usize,
    /// Each numerator's degree.
    pub(super) q: usize,
    /// Channels.
    pub(super) l: usize,
    pub(super) derivs: bool,
    pub(super) pole_derivs: bool,
    pub(super) sandwich: bool,
    pub(super) ratios: bool,
    pub(super) misfit: bool,
}

/// F over one chunk: Σ_c [D_p D_c]ᵀ[D_p D_c], by blocks: l D_pᵀD_p for the poles, D_pᵀD_c
/// between the poles and channel c, D_cᵀD_c within channel c; added into `acc.f`.
pub(super) fn fisher_blocks(acc: &mut Eval, dp: &Dense, d: &[Dense], shape: &Shape) {
    let Shape {
        p,
        q,
        l,
        pole_derivs,
        ..
    } = *shape;
    let nb = q + 1;
    // `block` (or its transpose) added into f from row r0, column c0.
    let add = |f: &mut Dense, block: &Dense, r0: usize, c0: usize, t: bool| {
        for a in 0..block.rows {
            for b in 0..block.cols {
                let (i, j) = if t {
                    (r0 + b, c0 + a)
                } else {
                    (r0 + a, c0 + b)
                };
                f.set(i, j, f.at(i, j) + block.at(a, b));
            }
        }
    };
    if pole_derivs {
        let mut gp = Dense::zeros(p, p);
        linalg::gram_add(dp, &mut gp);
        gp.data.iter_mut().for_each(|v| *v *= l as f64);
        add(&mut acc.f, &gp, 0, 0, false);
    }
    let mut cross = Dense::zeros(p, nb);
    let mut gc = Dense::zeros(nb, nb);
    for (c, dc) in d.iter().enumerate() {
        let off = p + c * nb;
        gc.data.iter_mut().for_each(|v| *v = 0.0);
        linalg::gram_add(dc, &mut gc);
        add(&mut acc.f, &gc, off, off, false);
        if pole_derivs {
            cross.data.iter_mut().for_each(|v| *v = 0.0);
            linalg::tn_add(dp, dc, &mut cross);
            add(&mut acc.f, &cross, 0, off, false);
            add(&mut acc.f, &cross, off, 0, true);
        }
    }
}
