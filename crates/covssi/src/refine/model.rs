//! The composite (per-channel) Whittle likelihood of the modes, its gradient and Fisher
//! information.

use super::*;

/// The record's spectra and the model's shape: how many real poles it has.
pub(super) struct Model {
    /// The record as the likelihood sees it.
    pub(super) sp: Arc<Spectra>,
    pub(super) fs: f64,
    /// Real poles of the model besides its modes: θ holds their ln ρ (λ = −ρ) after the
    /// modes' parameters, and each numerator's degree is 2m + `reals`.
    pub(super) reals: usize,
}

/// A fitted model.
pub(super) struct Fit {
    pub(super) theta: Vec<f64>,
    pub(super) lambdas: Vec<C64>,
    /// The real poles λ = −ρ, after the modes in θ.
    pub(super) reals: Vec<f64>,
    pub(super) l: f64,
    pub(super) fisher: Dense,
    pub(super) iterations: usize,
}

/// What [`Model::eval`] computes besides L.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum What {
    /// L alone.
    Value,
    /// The score U = −∇L and the Fisher information F.
    Fisher,
    /// U and F of the numerators alone (the poles held): the poles' entries of U and their
    /// rows and columns of F are zero.
    FisherNumerators,
    /// U, and the covariance J of the score in place of F.
    Sandwich,
    /// The ratios I/S of every channel and frequency.
    #[cfg(test)]
    Ratios,
    /// The misfit of those ratios, counted without keeping them.
    Misfit,
}

/// L and what was asked for besides (empty otherwise).
pub(super) struct Eval {
    pub(super) l: f64,
    pub(super) u: Vec<f64>,
    pub(super) f: Dense,
    pub(super) ratios: Vec<f64>,
    /// The misfit's counts of the ratios (with [`What::Misfit`]).
    pub(super) misfit: Option<MisfitCounts>,
}

impl Eval {
    /// Nothing summed yet, with room for the score and Fisher information of `np` parameters
    /// (0 when they are not asked for).
    pub(super) fn zero(np: usize) -> Self {
        Eval {
            l: 0.0,
            u: vec![0.0; np],
            f: Dense::zeros(np, np),
            ratios: Vec::new(),
            misfit: None,
        }
    }

    /// The sums over two sets of frequencies, as one.
    pub(super) fn merge(mut self, other: Self) -> Self {
        self.l += other.l;
        self.u.iter_mut().zip(&other.u).for_each(|(x, y)| *x += y);
        self.f
            .data
            .iter_mut()
            .zip(&other.f.data)
            .for_each(|(x, y)| *x += y);
        self.ratios.extend(other.ratios);
        match (&mut self.misfit, other.misfit) {
            (Some(a), Some(b)) => a.merge(&b),
            (None, b) => self.misfit = b,
            _ => {}
        }
        self
    }
}

/// Bins per parallel chunk of an evaluation.
pub(super) const CHUNK: usize = 128;

impl Model {
    /// The model of the record `sp` sampled at `fs` Hz, without real poles.
    pub(super) fn new(sp: Spectra, fs: f64) -> Self {
        Model {
            sp: Arc::new(sp),
            fs,
            reals: 0,
        }
    }

    /// The exact Whittle likelihood's model of the channels `y` less `means` (every
    /// frequency its own bin).
    #[cfg(test)]
    pub(super) fn unbinned(y: &[&[f64]], means: &[f64], fs: f64) -> Self {
        Self::new(Spectra::unbinned(y, means), fs)
    }

    /// This record's model with `r` real poles.
    pub(super) fn with_reals(&self, r: usize) -> Self {
        Model {
            sp: Arc::clone(&self.sp),
            fs: self.fs,
            reals: r,
        }
    }

    /// Channels.
    pub(super) fn l(&self) -> usize {
        self.sp.l
    }

    /// Number of pole parameters of a model of `m` modes: 2m, and one per real pole.
    pub(super) fn poles(&self, m: usize) -> usize {
        2 * m + self.reals
    }

    /// Frequencies of the likelihood, K.
    pub(super) fn k(&self) -> usize {
        self.sp.k()
    }

    /// The lowest value over frequency of each channel's fitted spectrum S_c (θ of a
    /// per-channel fit with `m` modes): a bound on its white measurement noise's spectral
    /// level, and near it where the modes' tails are below the noise.
    pub(super) fn noise_floor(&self, th: &[f64], m: usize) -> Option<Vec<f64>> {
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

    /// `p` combinations of the channels that carry the modes `lambdas` (rows of l weights),
    /// each channel first divided by `scale` (the square root of its noise floor, so
    /// that the noise is white with equal level in all: then the directions orthogonal to the
    /// modes' shapes hold noise alone, independent of the rest). For each mode the
    /// cross-spectral matrix of the scaled channels over its half-power band (at least ±3
    /// frequencies) is normalised to unit trace, so a weak mode weighs as much as a strong one;
    /// the combinations are the leading `p` eigenvectors of the real part of their sum, which
    /// spans the modes' shapes (real and imaginary parts). Scaling a channel changes nothing
    /// (its scale scales with it); permuting them changes the combinations' signs at most.
    /// `None` if a band holds no power or the eigenvectors cannot be computed.
    pub(super) fn project(
        &self,
        lambdas: &[C64],
        p: usize,
        scale: &[f64],
    ) -> Option<Vec<Vec<f64>>> {
        let l = self.l();
        let bin = 2.0 * std::f64::consts::PI / self.sp.n as f64;
        let mut g = Dense::zeros(l, l);
        for lam in lambdas {
            let centre = lam.im / self.fs;
            let half = (-lam.re / self.fs).max(3.0 * bin);
            let (lo, hi) = (self.sp.bin_at(centre - half), self.sp.bin_at(centre + half));
            let mut s = Dense::zeros(l, l);
            for b in lo..=hi {
                let w = self.sp.w[b];
                for a in 0..l {
                    for c in 0..l {
                        let v = w * self.sp.at(b, a, c).re / (scale[a] * scale[c]);
                        s.set(a, c, s.at(a, c) + v);
                    }
                }
            }
            let trace: f64 = (0..l).map(|a| s.at(a, a)).sum();
            if !(trace > 0.0 && trace.is_finite()) {
                return None;
            }
            g.data
                .iter_mut()
                .zip(&s.data)
                .for_each(|(gv, sv)| *gv += sv / trace);
        }
        let (u, _) = linalg::thin_svd_u(&g).ok()?;
        Some(
            (0..p.min(l))
                .map(|j| (0..l).map(|c| u.at(c, j) / scale[c]).collect())
                .collect(),
        )
    }

    /// Starting numerator of channel c: σ² and B from the autocovariances of the record
    /// filtered by A (an MA process of order 2m), tapered by a triangle so that the spectrum
    /// they describe is positive (a biased autocovariance times a triangle is a positive
    /// definite sequence), then factored.
    pub(super) fn start_numerator(&self, c: usize, mu: &[C64]) -> Vec<f64> {
        let q = mu.len();
        let a = poly(mu);
        // The record's start is enough for a start ([`HEAD`] samples).
        let y = &self.sp.head[c];
        let e: Vec<f64> = (0..y.len() - q)
            .map(|t| (0..=q).map(|k| a[k] * y[t + q - k]).sum())
            .collect();
        let r: Vec<f64> = (0..=q)
            .map(|k| {
                let biased = e[..e.len() - k]
                    .iter()
                    .zip(&e[k..])
                    .map(|(u, v)| u * v)
                    .sum::<f64>()
                    / e.len() as f64;
                biased * (1.0 - k as f64 / (q + 1) as f64)
            })
            .collect();
        let flat = {
            let mut v = vec![r[0].ln()];
            v.extend(std::iter::repeat_n(0.0, q));
            v
        };
        if q == 0 || r[q].abs() < 1e-12 * r[0] {
            return flat;
        }
        // Roots of z^q · Σ_k r_|k| z^k (degree 2q), by the companion matrix; they pair as
        // (z, 1/z̄), and the q inside the unit circle make B minimum-phase.
        let deg = 2 * q;
        let coef: Vec<f64> = (0..=deg)
            .map(|k| r[(k as isize - q as isize).unsigned_abs()])
            .collect();
        let mut comp = Dense::zeros(deg, deg);
        for k in 0..deg {
            comp.set(0, k, -coef[k + 1] / coef[0]);
            if k + 1 < deg {
                comp.set(k + 1, k, 1.0);
            }
        }
        let Ok(mut roots) = linalg::eigenvalues(&comp) else {
            return flat;
        };
        roots.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
        let inside: Vec<C64> = roots[..q]
            .iter()
            .map(|z| {
                if z.norm() > 0.98 {
                    z * (0.98 / z.norm())
                } else {
                    *z
                }
            })
            .collect();
        let b = poly(&inside);
        let grid = 256;
        let mean_b2 = (0..grid)
            .map(|g| {
                let w = std::f64::consts::PI * (g as f64 + 0.5) / grid as f64;
                poly_at(&b, C64::from_polar(1.0, -w)).norm_sqr()
            })
            .sum::<f64>()
            / grid as f64;
        let mut v = vec![(r[0] / mean_b2).ln()];
        v.extend_from_slice(&b[1..]);
        if v.iter().all(|x| x.is_finite()) {
            v
        } else {
            flat
        }
    }

    /// L at θ and what `what` asks for besides. `None` when θ is outside the model (a pole at
    /// Nyquist, a numerator zero on the unit circle, overflow).
    pub(super) fn eval(&self, th: &[f64], m: usize, what: What) -> Option<Eval> {
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
    fn chunk(
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
        let mut pw = vec![C64::new(0.0, 0.0); q + 1];
        for (row, kk) in (lo..hi).enumerate() {
            let z = sp.z[kk];
            let (w, sw) = (sp.w[kk], sp.w[kk].sqrt());
            let log_a2 = den.at(z, pole_derivs, &mut da);
            let zc = z.conj();
            pw[0] = C64::new(1.0, 0.0);
            for k in 1..=q {
                pw[k] = pw[k - 1] * zc;
            }
            // Σ_c n_b r_c, by which the poles' score grows.
            let mut r_sum = 0.0;
            for c in 0..l {
                let off = p + c * (q + 1);
                let b = pw[0]
                    + pw[1..]
                        .iter()
                        .zip(&th[off + 1..=off + q])
                        .map(|(p, bk)| p * bk)
                        .sum::<C64>();
                let b2 = b.norm_sqr();
                let log_s = th[off] + b2.ln() - log_a2;
                let s = log_s.exp();
                let ic = sp.at(kk, c, c).re;
                acc.l += w * (log_s + ic / s);
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
                    dc.set(row, 0, sw);
                    acc.u[off] += r;
                    let bc = b.conj();
                    for (k, pk) in pw.iter().enumerate().skip(1) {
                        let v = 2.0 * (pk * bc).re / b2;
                        dc.set(row, k, v * sw);
                        acc.u[off + k] += v * r;
                    }
                }
            }
            if pole_derivs {
                for (t, dat) in da.iter().enumerate() {
                    dp.set(row, t, -dat * sw);
                    acc.u[t] -= dat * r_sum;
                }
            }
        }
        (acc, dp, d)
    }

    /// The sandwich's middle over the frequencies `rows`: J = Σ_{c,c'} D_cᵀ diag(γ²_cc') D_c'
    /// (cov(I_c/S_c, I_c'/S_c') = γ²_cc'), D_c = [D_p D_c] in full, added into `acc.f`.
    fn sandwich_blocks(
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

    /// Fit a model with the given starting poles (numerators from [`Self::start_numerator`]);
    /// `tol` is the convergence threshold on L. With `hold_poles` only the numerators move.
    pub(super) fn fit(
        &self,
        start: &[C64],
        opts: &RefineOptions,
        tol: f64,
        hold_poles: bool,
    ) -> Result<Fit, SsiError> {
        self.fit_from(self.start(start)?, start.len(), opts, tol, hold_poles, None)
    }

    /// θ of the starting poles, with numerators from [`Self::start_numerator`].
    pub(super) fn start(&self, poles: &[C64]) -> Result<Vec<f64>, SsiError> {
        self.start_with(poles, &[])
    }

    /// θ of the starting modes' poles and real poles (as many as the model has), with
    /// numerators from [`Self::start_numerator`].
    pub(super) fn start_with(&self, poles: &[C64], reals: &[f64]) -> Result<Vec<f64>, SsiError> {
        debug_assert_eq!(reals.len(), self.reals);
        let (mut th, logits): (Vec<f64>, Vec<f64>) = poles.iter().map(|&s| pole_params(s)).unzip();
        th.extend(logits);
        th.extend(reals.iter().map(|v| (-v).ln()));
        let mut mu = discrete_poles(poles, self.fs).ok_or(SsiError::Refinement {
            reason: "a starting pole is at or above the Nyquist frequency",
        })?;
        mu.extend(reals.iter().map(|v| C64::new((v / self.fs).exp(), 0.0)));
        for c in 0..self.l() {
            th.extend(self.start_numerator(c, &mu));
        }
        Ok(th)
    }

    /// The start that nests `prev` in a model with one more mode `new`: its pole pair is
    /// cancelled by a numerator zero pair, so the spectrum and L are exactly `prev`'s. The
    /// fit from here can only lower L.
    pub(super) fn nested_start(&self, prev: &Fit, new: C64) -> Option<Vec<f64>> {
        let (m, r) = (prev.lambdas.len(), prev.reals.len());
        debug_assert_eq!(self.reals, r);
        let q = 2 * m + r;
        let mu = discrete_poles(&[new], self.fs)?[0];
        let factor = [1.0, -2.0 * mu.re, mu.norm_sqr()];
        let (ln_w, logit_zeta) = pole_params(new);
        let mut th: Vec<f64> = prev.theta[..m].to_vec();
        th.push(ln_w);
        th.extend_from_slice(&prev.theta[m..2 * m]);
        th.push(logit_zeta);
        th.extend_from_slice(&prev.theta[2 * m..q]);
        th.extend(self.numerators_times(&prev.theta, q, &factor));
        Some(th)
    }

    /// The start that nests `prev` (a fit with one real pole fewer than this model has) in
    /// this model, its new real pole `new` (λ < 0) cancelled by a numerator zero: the
    /// spectrum and L are exactly `prev`'s.
    pub(super) fn nested_real_start(&self, prev: &Fit, new: f64) -> Vec<f64> {
        let (m, r) = (prev.lambdas.len(), prev.reals.len());
        debug_assert_eq!(self.reals, r + 1);
        let q = 2 * m + r;
        let mu = (new / self.fs).exp();
        let mut th: Vec<f64> = prev.theta[..q].to_vec();
        th.push((-new).ln());
        th.extend(self.numerators_times(&prev.theta, q, &[1.0, -mu]));
        th
    }

    /// The numerators of θ (pole parameters and numerator degree `q`), each multiplied by
    /// `factor` (coefficients of z⁻ᵏ from k = 0, leading 1): every channel's ln σ², then its
    /// new B's coefficients after the leading 1. They cancel the poles `factor` adds to A.
    pub(super) fn numerators_times(&self, theta: &[f64], q: usize, factor: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.l() * (q + factor.len()));
        for c in 0..self.l() {
            let off = q + c * (q + 1);
            out.push(theta[off]);
            let mut b = vec![1.0];
            b.extend_from_slice(&theta[off + 1..off + 1 + q]);
            let mut nb = vec![0.0; q + factor.len()];
            for (k, bk) in b.iter().enumerate() {
                for (t, ft) in factor.iter().enumerate() {
                    nb[k + t] += bk * ft;
                }
            }
            out.extend_from_slice(&nb[1..]);
        }
        out
    }

    /// `prev` with the mode `new` added, refitted from two starts, fresh numerators and
    /// [`Self::nested_start`]; the better fit.
    pub(super) fn fit_with(
        &self,
        prev: &Fit,
        new: C64,
        penalty: Option<f64>,
        opts: &RefineOptions,
    ) -> Result<Fit, SsiError> {
        let mut trial = prev.lambdas.clone();
        trial.push(new);
        let ev = Evidence::adding(prev.l, penalty);
        let (tol, m) = (opts.tolerance, trial.len());
        let fresh = self
            .start_with(&trial, &prev.reals)
            .and_then(|th| self.fit_from(th, m, opts, tol, false, ev));
        let nested = self.nested_start(prev, new).map_or(
            Err(SsiError::Refinement {
                reason: "the new pole is at or above the Nyquist frequency",
            }),
            |th| self.fit_from(th, m, opts, tol, false, ev),
        );
        better(fresh, nested)
    }

    /// `full` without one of its poles, as this model (as many real poles as `reals`) with
    /// the modes `pairs` and the real poles `reals`: the rise of L when the poles are held and
    /// the numerators refitted (the removed pole's evidence, to about 10⁻⁵ of itself), and
    /// the fit with everything let move from there. That fit stops once L is within `penalty`
    /// of `full`'s (the pole goes whatever further iterations would find) or once that is out
    /// of reach; with no penalty (no selection) at convergence. With `hold_modes` the modes
    /// stay held in that fit too (for a real pole removed: the other real poles may take its
    /// place, but a mode left free would turn into a pole pair damped near ζ = 1 that mimics
    /// it, at twice its parameters).
    pub(super) fn without(
        &self,
        full: &Fit,
        pairs: &[C64],
        reals: &[f64],
        penalty: Option<f64>,
        hold_modes: bool,
        opts: &RefineOptions,
    ) -> Result<(f64, Fit), SsiError> {
        // These fits need L only to well within the penalty, and a model missing one of its
        // real modes descends slowly while its poles wander (hundreds of iterations, seconds
        // each fit) without coming near the penalty: 40 iterations decide, and a fit stops
        // sooner once its gains are small against the rise or the penalty is out of reach
        // ([`Evidence`]).
        let loose = 1e-3;
        let eopts = &RefineOptions {
            max_iterations: opts.max_iterations.min(40),
            ..opts.clone()
        };
        let report = Evidence {
            full: full.l,
            drop_below: f64::NEG_INFINITY,
            stop_below: true,
        };
        let m = pairs.len();
        let th = self.start_with(pairs, reals)?;
        let held = self.fit_from(th, m, eopts, loose, true, Some(report))?;
        let decide = Evidence {
            drop_below: penalty.map_or(f64::NEG_INFINITY, |p| full.l + p),
            ..report
        };
        let hold = if hold_modes { 2 * m } else { 0 };
        let free = self.fit_holding(held.theta, m, eopts, loose, hold, Some(decide))?;
        Ok((held.l - full.l, free))
    }

    /// [`scoring`] on this model's likelihood.
    pub(super) fn fit_from(
        &self,
        th: Vec<f64>,
        m: usize,
        opts: &RefineOptions,
        tol: f64,
        hold_poles: bool,
        evidence: Option<Evidence>,
    ) -> Result<Fit, SsiError> {
        let held = if hold_poles { self.poles(m) } else { 0 };
        self.fit_holding(th, m, opts, tol, held, evidence)
    }

    /// [`scoring`] on this model's likelihood with θ's first `held` entries held: none, the
    /// modes' 2m, or all pole parameters.
    pub(super) fn fit_holding(
        &self,
        th: Vec<f64>,
        m: usize,
        opts: &RefineOptions,
        tol: f64,
        held: usize,
        evidence: Option<Evidence>,
    ) -> Result<Fit, SsiError> {
        // Held poles need no derivatives by the poles.
        let fisher = if held == self.poles(m) && held > 0 {
            What::FisherNumerators
        } else {
            What::Fisher
        };
        let eval =
            |t: &[f64], derivs: bool| self.eval(t, m, if derivs { fisher } else { What::Value });
        scoring(eval, th, (m, self.reals), opts, tol, held, evidence)
    }
}

/// Index of the unordered channel pair (a, b), a ≠ b, among l channels.
pub(super) fn pair(a: usize, b: usize, l: usize) -> usize {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    a * l + b
}

/// Global index of local parameter `t` of a channel block starting at `off`: the first `p`
/// are the shared pole parameters.
pub(super) fn global(t: usize, p: usize, off: usize) -> usize {
    if t < p { t } else { off + t - p }
}

/// What the sizes of one evaluation are, and what it computes.
#[derive(Clone, Copy)]
struct Shape {
    /// Pole parameters.
    p: usize,
    /// Each numerator's degree.
    q: usize,
    /// Channels.
    l: usize,
    derivs: bool,
    pole_derivs: bool,
    sandwich: bool,
    ratios: bool,
    misfit: bool,
}

/// F over one chunk: Σ_c [D_p D_c]ᵀ[D_p D_c], by blocks: l D_pᵀD_p for the poles, D_pᵀD_c
/// between the poles and channel c, D_cᵀD_c within channel c; added into `acc.f`.
fn fisher_blocks(acc: &mut Eval, dp: &Dense, d: &[Dense], shape: &Shape) {
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
