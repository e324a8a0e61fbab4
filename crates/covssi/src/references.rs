//! Reference channels chosen from the record when it has many channels: the few that
//! together see every mode best.
//!
//! SSI's correlations are taken against $r$ reference channels; with $l$ channels and $2i$
//! lags they hold $l\,r\,2i$ values, and the Toeplitz matrix has $r\,i$ columns. Any set of
//! references that sees every mode gives the same poles (the modes are the observability
//! of the channels and the controllability of the references), so with many channels a few
//! references keep the cost near that of a few channels without losing a mode.
//!
//! At each of the record's spectral peaks (the [survey](mod@crate::survey)'s), the cross-spectral
//! matrix of the channels, each divided by its standard deviation, is averaged over the peak's
//! bin and its two neighbours (Welch's segments, Hann window). Its leading eigenvectors are
//! the shapes of the modes there: the first, and up to three more whose eigenvalues are at
//! least [`CLOSE_MODE_SHARE`] of it (close modes under one peak). The references are then
//! chosen by a pivoted Gram–Schmidt over the channels' rows of those unit shapes (every mode
//! weighs alike): each step takes the channel whose row keeps the most of what the chosen
//! ones do not yet see, until what is left is below [`NEW_SHARE`] of the first channel's
//! or [`MAX_REFERENCES`] are chosen, and at least [`MIN_REFERENCES`].

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

use crate::linalg::C64;

/// Most references chosen.
pub const MAX_REFERENCES: usize = 8;

/// Fewest references chosen (or every channel, when there are fewer): a mode the peaks
/// do not show is still seen by some of them.
pub const MIN_REFERENCES: usize = 4;

/// A second, third or fourth eigenvector of a peak's cross-spectral matrix counts as a
/// mode when its eigenvalue is at least this share of the first's (−20 dB).
pub const CLOSE_MODE_SHARE: f64 = 0.01;

/// A channel is added while its row keeps at least this share of the first chosen row's
/// squared norm unseen by the others.
pub const NEW_SHARE: f64 = 0.01;

/// Most eigenvectors taken at one peak.
const MODES_PER_PEAK: usize = 4;

/// The references chosen from the record, and what they were chosen to see.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ChosenReferences {
    /// The chosen channels (indices), increasing.
    pub channels: Vec<usize>,
    /// The spectral peaks whose modes they see (Hz).
    pub peaks_hz: Vec<f64>,
    /// How many mode shapes the peaks' cross-spectra showed.
    pub modes_seen: usize,
}

/// The references for the centred channels `y` (`means` removed) sampled at `fs` Hz whose
/// survey found `peaks_hz`: see the [module](self). With no peak, the [`MIN_REFERENCES`]
/// channels of largest variance.
pub fn choose(y: &[&[f64]], means: &[f64], fs: f64, peaks_hz: &[f64]) -> ChosenReferences {
    let l = y.len();
    let shapes = peak_shapes(y, means, fs, peaks_hz);
    let rows: Vec<Vec<C64>> = if shapes.is_empty() {
        // No peak: every channel counts alike (scaled to unit variance), so the first ones.
        (0..l)
            .map(|c| vec![C64::new(if c < MIN_REFERENCES { 1.0 } else { 0.0 }, 0.0)])
            .collect()
    } else {
        (0..l)
            .map(|c| shapes.iter().map(|s| s[c]).collect())
            .collect()
    };
    ChosenReferences {
        channels: pivoted(rows),
        peaks_hz: peaks_hz.to_vec(),
        modes_seen: shapes.len(),
    }
}

/// Pivoted Gram–Schmidt over the rows: see the [module](self). Indices, increasing.
fn pivoted(mut rows: Vec<Vec<C64>>) -> Vec<usize> {
    let l = rows.len();
    let norm2 = |r: &[C64]| r.iter().map(|v| v.norm_sqr()).sum::<f64>();
    let mut chosen: Vec<usize> = Vec::new();
    let mut first = None;
    while chosen.len() < MAX_REFERENCES.min(l) {
        let Some((c, left)) = (0..l)
            .filter(|c| !chosen.contains(c))
            .map(|c| (c, norm2(&rows[c])))
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
        else {
            break;
        };
        let first = *first.get_or_insert(left);
        let enough = chosen.len() >= MIN_REFERENCES;
        if enough && left <= NEW_SHARE * first {
            break;
        }
        chosen.push(c);
        if left > 0.0 {
            let pivot: Vec<C64> = rows[c].iter().map(|v| v / left.sqrt()).collect();
            for row in rows.iter_mut() {
                let along: C64 = row.iter().zip(&pivot).map(|(x, p)| x * p.conj()).sum();
                row.iter_mut()
                    .zip(&pivot)
                    .for_each(|(x, p)| *x -= along * p);
            }
        }
    }
    chosen.sort_unstable();
    chosen
}

/// The unit mode shapes the peaks' cross-spectral matrices show (channels scaled to unit
/// variance).
fn peak_shapes(y: &[&[f64]], means: &[f64], fs: f64, peaks_hz: &[f64]) -> Vec<Vec<C64>> {
    let l = y.len();
    let n = y.first().map_or(0, |c| c.len());
    let len = crate::survey::segment_length(n);
    if l == 0 || n < len || peaks_hz.is_empty() {
        return Vec::new();
    }
    let bins: Vec<usize> = peaks_hz
        .iter()
        .map(|f| ((f * len as f64 / fs).round() as usize).clamp(1, len / 2 - 1))
        .collect();
    let scale: Vec<f64> = y
        .iter()
        .zip(means)
        .map(|(c, m)| {
            let var = c.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64;
            if var > 0.0 { 1.0 / var.sqrt() } else { 0.0 }
        })
        .collect();
    let window: Vec<f64> = (0..len)
        .map(|k| 0.5 * (1.0 - (2.0 * std::f64::consts::PI * k as f64 / len as f64).cos()))
        .collect();
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(len);
    let mut buf = vec![0.0; len];
    let mut spec = fwd.make_output_vec();
    // g[p][a + b l]: peak p's cross-spectral matrix.
    let mut g = vec![vec![C64::new(0.0, 0.0); l * l]; bins.len()];
    let mut x = vec![vec![Complex::new(0.0, 0.0); 3]; l * bins.len()];
    let mut start = 0;
    while start + len <= n {
        for (a, ch) in y.iter().enumerate() {
            for ((b, v), w) in buf.iter_mut().zip(&ch[start..start + len]).zip(&window) {
                *b = (v - means[a]) * scale[a] * w;
            }
            fwd.process(&mut buf, &mut spec)
                .expect("buffer sizes from the plan");
            for (p, &k) in bins.iter().enumerate() {
                x[p * l + a].copy_from_slice(&spec[k - 1..=k + 1]);
            }
        }
        for (p, gp) in g.iter_mut().enumerate() {
            for b in 0..l {
                for a in 0..l {
                    let s: Complex<f64> = (0..3)
                        .map(|d| x[p * l + a][d] * x[p * l + b][d].conj())
                        .sum();
                    gp[a + b * l] += C64::new(s.re, s.im);
                }
            }
        }
        start += len / 2;
    }
    let mut shapes = Vec::new();
    for gp in &g {
        let Ok((values, vectors)) = crate::linalg::hermitian_eigen(gp, l) else {
            continue;
        };
        let Some(&top) = values.first().filter(|v| **v > 0.0) else {
            continue;
        };
        shapes.extend(
            values
                .iter()
                .zip(vectors)
                .take(MODES_PER_PEAK.min(l))
                .filter(|(v, _)| **v >= CLOSE_MODE_SHARE * top)
                .map(|(_, s)| s),
        );
    }
    shapes
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two modes seen by distinct channel groups, a third channel group pure noise: each mode
    /// has a reference among the channels that see it, and noise channels are not chosen
    /// before them.
    #[test]
    fn each_mode_is_seen_by_a_reference() {
        let (fs, n) = (20.0, 1 << 15);
        let mut rng = 12345u64;
        let mut noise = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((rng >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        // Two narrow-band responses (AR(2) resonators at 1 and 3 Hz).
        let resonate = |f: f64, e: &[f64]| {
            let r = 0.995f64;
            let w = 2.0 * std::f64::consts::PI * f / fs;
            let (a1, a2) = (2.0 * r * w.cos(), -r * r);
            let mut out = vec![0.0; e.len()];
            for t in 2..e.len() {
                out[t] = a1 * out[t - 1] + a2 * out[t - 2] + e[t];
            }
            out
        };
        let e1: Vec<f64> = (0..n).map(|_| noise()).collect();
        let e2: Vec<f64> = (0..n).map(|_| noise()).collect();
        let (m1, m2) = (resonate(1.0, &e1), resonate(3.0, &e2));
        // Channels 0–3 see mode 1 (with weights), 4–7 mode 2, 8–11 only noise.
        let mut y: Vec<Vec<f64>> = Vec::new();
        for c in 0..12 {
            let w = 1.0 + 0.1 * c as f64;
            y.push(
                (0..n)
                    .map(|t| {
                        let s = match c {
                            0..=3 => w * m1[t],
                            4..=7 => w * m2[t],
                            _ => 0.0,
                        };
                        s + 0.05 * noise()
                    })
                    .collect(),
            );
        }
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let means = vec![0.0; 12];
        let s = crate::survey(&views, fs).unwrap();
        let chosen = choose(&views, &means, fs, &s.peaks_hz);
        assert!(
            chosen.channels.iter().any(|c| (0..4).contains(c)),
            "{chosen:?}"
        );
        assert!(
            chosen.channels.iter().any(|c| (4..8).contains(c)),
            "{chosen:?}"
        );
        assert!(chosen.channels.len() >= MIN_REFERENCES && chosen.channels.len() <= MAX_REFERENCES);
        assert!(chosen.channels.windows(2).all(|w| w[0] < w[1]));
        assert!(chosen.modes_seen >= 2, "{chosen:?}");
    }

    /// With no peak the first channels are taken, as many as [`MIN_REFERENCES`].
    #[test]
    fn without_peaks_the_fewest_references_are_taken() {
        let y: Vec<Vec<f64>> = (0..10).map(|c| vec![c as f64; 64]).collect();
        let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
        let chosen = choose(&views, &[0.0; 10], 10.0, &[]);
        assert_eq!(chosen.channels, vec![0, 1, 2, 3]);
        assert_eq!(chosen.modes_seen, 0);
    }
}
