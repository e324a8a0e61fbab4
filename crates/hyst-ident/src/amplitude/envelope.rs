//! Random decrement conditioned on the envelope: with $z = q + i\mathcal{H}q$ the analytic
//! signal of a mode's band-passed response and $A = |z|$ its envelope, the signature of an
//! amplitude band is
//! $$D(\tau) = \overline{\,z(t+\tau)\,\overline{z(t)}/|z(t)|\,}\quad\text{over } A(t) \text{ in the band},$$
//! the decay from the band's amplitude with its phase turned to zero. For a linear mode
//! (a Gaussian, circular analytic signal) $\mathrm{E}[z(t+\tau)\mid z(t)] = \rho(\tau)z(t)$ with
//! $\rho$ the complex correlation, so $D(\tau) = \bar A\,\rho(\tau)$ at every level: no
//! amplitude dependence is made where there is none (extremum triggering conditions on the
//! second derivative too, whose share changes with the level). ρ is fitted as
//! [`super::decay`] says.

use crate::fft::{C, irfft, rfft};

/// The band-passed response and its Hilbert transform (zero phase, raised-cosine edges a
/// tenth of the band wide, as [`super::filter::band_pass`]).
pub(super) fn analytic(x: &[f64], fs: f64, lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let spec = rfft(x);
    let w = super::filter::band_weights(spec.len(), n, fs, lo, hi);
    let re: Vec<C> = spec.iter().zip(&w).map(|(v, w)| v * *w).collect();
    let im: Vec<C> = re.iter().map(|v| v * C::new(0.0, -1.0)).collect();
    (irfft(&re, n), irfft(&im, n))
}

/// Complex segment sums of one amplitude band, by group.
#[derive(Debug, Clone)]
pub(super) struct BandSums {
    /// Per group: Σ z(t+τ) conj(z(t))/|z(t)|, τ = 0..len.
    pub sums: Vec<Vec<C>>,
    /// Per group: triggers.
    pub counts: Vec<usize>,
}

impl BandSums {
    /// Triggers in all.
    pub(super) fn total(&self) -> usize {
        self.counts.iter().sum()
    }

    /// The signature without group `skip` (`None`: every group).
    pub(super) fn signature(&self, skip: Option<usize>) -> Option<Vec<C>> {
        let len = self.sums.first()?.len();
        let mut s = vec![C::new(0.0, 0.0); len];
        let mut n = 0usize;
        for (g, sum) in self.sums.iter().enumerate() {
            if Some(g) != skip {
                s.iter_mut().zip(sum).for_each(|(a, b)| *a += b);
                n += self.counts[g];
            }
        }
        (n > 0).then(|| s.iter().map(|v| v / n as f64).collect())
    }
}

/// Each band's sums: triggers every `stride` samples whose envelope lies in a band (of
/// `edges`), each segment `len` long, groups by time; a `circular` record's segments wrap.
pub(super) fn band_sums(
    re: &[f64],
    im: &[f64],
    edges: &[f64],
    len: usize,
    stride: usize,
    groups: usize,
    circular: bool,
) -> Vec<BandSums> {
    let bands = edges.len().saturating_sub(1);
    let mut out = vec![
        BandSums {
            sums: vec![vec![C::new(0.0, 0.0); len]; groups],
            counts: vec![0; groups],
        };
        bands
    ];
    let n = re.len();
    let end = if circular { n } else { n.saturating_sub(len) };
    for t in (0..end).step_by(stride.max(1)) {
        let z0 = C::new(re[t], im[t]);
        let a = z0.norm();
        let Some(k) = super::randec::band_of(edges, a) else {
            continue;
        };
        let turn = z0.conj() / a;
        let g = (t * groups / n.max(1)).min(groups - 1);
        let b = &mut out[k];
        for (s, j) in b.sums[g].iter_mut().zip(t..t + len) {
            let j = j % n;
            *s += C::new(re[j], im[j]) * turn;
        }
        b.counts[g] += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The analytic signal of a sine in the band is the sine and its quarter-period shift.
    #[test]
    fn analytic_signals_are_exact() {
        let (fs, f) = (100.0, 4.0);
        let wn = 2.0 * std::f64::consts::PI * f;
        let x: Vec<f64> = (0..1000).map(|i| (wn * i as f64 / fs).cos()).collect();
        let (re, im) = analytic(&x, fs, 2.0, 6.0);
        for i in (0..1000).step_by(37) {
            assert!((re[i] - x[i]).abs() < 1e-9);
            assert!((im[i] - (wn * i as f64 / fs).sin()).abs() < 1e-9, "{i}");
        }
    }
}
