//! What a record says about how to analyse it: the band its response occupies and its
//! spectral peaks, from which the defaults are read — a decimation when the modes sit far
//! below Nyquist, and a lag long enough for the lowest mode.
//!
//! The spectrum is Welch's: Hann segments of $L$ samples (the largest power of two at most
//! $N/8$, so that about 15 segments overlapping by half are averaged), each channel's divided
//! by its total power so that channels of other units or sizes count alike, then averaged
//! over the channels: $\bar P(f_k)$, summing to 1.
//!
//! - The **band** is the frequency below which 99 % of $\bar P$ lies (bins 0–1, the mean and
//!   drift a Hann window leaks, left out).
//! - A **peak** is a local maximum of $\bar P$ that stands at least 10 dB above the higher of
//!   the two lowest points between it and the nearest higher maximum on each side (its
//!   topographic prominence), at bin 3 or above, and within 40 dB of the highest peak. A
//!   Welch estimate averaging about 15 segments has a standard deviation of about 0.26 in
//!   its logarithm, so the difference of two has about 0.37, and 10 dB (2.3) is six of
//!   those: among the thousands of bins of one channel's noise, no bump reaches it (at 6 dB
//!   one did, on the shared one-channel record, at 0.10 Hz). 40 dB below the strongest mode
//!   is the noise floor's bumps (the steel frame's records, 256 Hz, modes to 14 Hz, have two
//!   at 61 and 95 Hz, 50 dB down).
//!
//! From them:
//! - **decimation** r = ⌊f_s / (5 · band)⌋, so that the new Nyquist lies at 2.5 times the
//!   band or more, lowered until every peak lies below 0.8 of the new Nyquist and at least
//!   [`MIN_DECIMATED_SAMPLES`] samples remain;
//! - **block rows** i such that the largest lag 2i − 1 covers [`LAG_PERIODS`] periods of the
//!   lowest peak (the paper's rule: ten periods of the dominant mode; here the lowest, whose
//!   correlation needs the longest lags), at least 20, and at most what keeps the Toeplitz
//!   matrix within [`MAX_TOEPLITZ_ROWS`] rows and columns and the largest lag within an
//!   eighth of the record;
//! - the **largest model order** 40, or four per peak when there are more than ten peaks.

use realfft::RealFftPlanner;

use crate::SsiError;

/// Periods of the lowest spectral peak the automatic lag covers.
pub const LAG_PERIODS: f64 = 10.0;

/// Most rows (and columns) of the block Toeplitz matrix the automatic lag makes: its SVD
/// takes about a second at this size.
pub const MAX_TOEPLITZ_ROWS: usize = 1200;

/// The fewest samples an automatic decimation leaves.
pub const MIN_DECIMATED_SAMPLES: usize = 4096;

/// Fewest block rows the automatic lag gives (the fixed default before it).
const MIN_AUTO_BLOCK_ROWS: usize = 20;

/// Share of the averaged power below the band's edge.
const BAND_SHARE: f64 = 0.99;

/// A peak's least prominence over its surroundings (a power ratio: 10 dB).
const PEAK_PROMINENCE: f64 = 10.0;

/// A peak's least level, relative to the highest peak's (a power ratio: −40 dB).
const PEAK_LEVEL: f64 = 1e-4;

/// The new Nyquist is at least this multiple of the band.
const DECIMATION_MARGIN: f64 = 2.5;

/// Every peak stays below this share of the new Nyquist.
const PEAK_BELOW_NYQUIST: f64 = 0.8;

/// What the record's averaged spectrum shows.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RecordSurvey {
    /// Sampling rate surveyed (Hz).
    pub fs_hz: f64,
    /// Frequency resolution of the spectrum, f_s/L (Hz).
    pub resolution_hz: f64,
    /// Frequency below which 99 % of the channels' averaged normalised power lies (Hz).
    pub band_hz: f64,
    /// Spectral peaks standing 10 dB above their surroundings, by increasing frequency (Hz).
    pub peaks_hz: Vec<f64>,
}

/// Why the automatic lag covers fewer than [`LAG_PERIODS`] periods of the lowest peak.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
#[non_exhaustive]
pub enum LagLimit {
    /// The Toeplitz matrix would exceed [`MAX_TOEPLITZ_ROWS`] rows or columns.
    MatrixSize,
    /// The largest lag would exceed an eighth of the record.
    RecordLength,
}

/// How the block rows were chosen when the options left them to the record
/// ([`BlockRows::Auto`](crate::BlockRows::Auto)).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AutoLag {
    /// The lowest spectral peak (Hz), whose periods the lag counts; `None` when the spectrum
    /// has no peak (then 20 block rows).
    pub lowest_peak_hz: Option<f64>,
    /// Periods of that peak the largest lag covers.
    pub periods: Option<f64>,
    /// What kept the lag shorter than [`LAG_PERIODS`] periods, if anything.
    pub limited_by: Option<LagLimit>,
}

/// Survey the channels `y` (checked, equal lengths) sampled at `fs` Hz.
pub fn survey(y: &[&[f64]], fs: f64) -> Result<RecordSurvey, SsiError> {
    crate::checks::check_fs(fs)?;
    let (n, means) = crate::checks::check_channels(y)?;
    Ok(surveyed(y, fs, &means, n))
}

/// [`survey`] of channels already checked: `n` samples each, of means `means`.
pub(crate) fn surveyed(y: &[&[f64]], fs: f64, means: &[f64], n: usize) -> RecordSurvey {
    let p = averaged_spectrum(y, means, n);
    let len = 2 * (p.len() - 1);
    let df = fs / len as f64;
    // Bins 0 and 1 hold the mean and the drift the Hann window leaks.
    let total: f64 = p[2..].iter().sum();
    let mut acc = 0.0;
    let mut band_bin = p.len() - 1;
    for (k, v) in p.iter().enumerate().skip(2) {
        acc += v;
        if acc >= BAND_SHARE * total {
            band_bin = k;
            break;
        }
    }
    let peaks_hz = peaks(&p).into_iter().map(|k| k as f64 * df).collect();
    RecordSurvey {
        fs_hz: fs,
        resolution_hz: df,
        band_hz: band_bin as f64 * df,
        peaks_hz,
    }
}

impl RecordSurvey {
    /// This survey restated for the record decimated by `factor` ([`crate::decimate`]: an
    /// ideal low-pass below the new Nyquist, so the spectrum below it is the record's own):
    /// the rate divided, the band and the peaks below the new Nyquist kept at this survey's
    /// finer resolution. A second survey of the decimated record would see the same spectrum
    /// through segments as many samples long, so `factor` times coarser: on the F-16's
    /// multisine records that hid the wing-bending peak (5.2 Hz) beside the torsion mode,
    /// and the lag, sized by the torsion mode alone, was too short for SSI to find it.
    pub fn decimated(&self, factor: usize) -> RecordSurvey {
        let fs_hz = self.fs_hz / factor.max(1) as f64;
        let nyquist = fs_hz / 2.0;
        RecordSurvey {
            fs_hz,
            resolution_hz: self.resolution_hz,
            band_hz: self.band_hz.min(nyquist),
            peaks_hz: self
                .peaks_hz
                .iter()
                .copied()
                .filter(|&f| f < nyquist)
                .collect(),
        }
    }

    /// The decimation factor the record asks for (1: none): see the [module](self).
    pub fn decimation(&self, samples: usize) -> usize {
        let nyquist_for = |hz: f64| self.fs_hz / (2.0 * hz);
        let mut r = nyquist_for(DECIMATION_MARGIN * self.band_hz).floor();
        if let Some(&top) = self.peaks_hz.last() {
            r = r.min(nyquist_for(top / PEAK_BELOW_NYQUIST).floor());
        }
        let r = if r.is_finite() && r >= 1.0 {
            r as usize
        } else {
            1
        };
        r.min(samples / MIN_DECIMATED_SAMPLES).max(1)
    }

    /// The block rows for `channels` channels and `references` references of `samples`
    /// samples at the surveyed rate, and how they were chosen: see the [module](self).
    pub fn block_rows(
        &self,
        samples: usize,
        channels: usize,
        references: usize,
    ) -> (usize, AutoLag) {
        let Some(&lowest) = self.peaks_hz.first() else {
            return (
                MIN_AUTO_BLOCK_ROWS,
                AutoLag {
                    lowest_peak_hz: None,
                    periods: None,
                    limited_by: None,
                },
            );
        };
        let wanted = ((LAG_PERIODS * self.fs_hz / lowest + 1.0) / 2.0).ceil() as usize;
        let by_size = MAX_TOEPLITZ_ROWS / channels.max(references).max(1);
        let by_length = samples / 16;
        let mut i = wanted.max(MIN_AUTO_BLOCK_ROWS);
        let mut limited_by = None;
        if i > by_size {
            i = by_size;
            limited_by = Some(LagLimit::MatrixSize);
        }
        if i > by_length {
            i = by_length;
            limited_by = Some(LagLimit::RecordLength);
        }
        let i = i.max(2);
        let periods = (2 * i - 1) as f64 / self.fs_hz * lowest;
        (
            i,
            AutoLag {
                lowest_peak_hz: Some(lowest),
                periods: Some(periods),
                limited_by,
            },
        )
    }

    /// The largest model order when the options leave it open: 40, or four per peak when
    /// the record shows more than ten (each mode takes two orders, and as many again go to
    /// noise before a weak mode stabilises).
    pub fn max_order(&self) -> usize {
        (4 * self.peaks_hz.len()).max(40)
    }
}

/// Welch's spectrum of each centred channel, normalised to unit sum, averaged over channels.
fn averaged_spectrum(y: &[&[f64]], means: &[f64], n: usize) -> Vec<f64> {
    let len = segment_length(n);
    let hop = len / 2;
    let window: Vec<f64> = (0..len)
        .map(|k| 0.5 * (1.0 - (2.0 * std::f64::consts::PI * k as f64 / len as f64).cos()))
        .collect();
    let mut planner = RealFftPlanner::<f64>::new();
    let fwd = planner.plan_fft_forward(len);
    let bins = len / 2 + 1;
    let mut avg = vec![0.0; bins];
    let mut buf = vec![0.0; len];
    let mut spec = fwd.make_output_vec();
    let mut p = vec![0.0; bins];
    for (ch, &mean) in y.iter().zip(means) {
        p.fill(0.0);
        let mut start = 0;
        while start + len <= n {
            for ((b, x), w) in buf.iter_mut().zip(&ch[start..start + len]).zip(&window) {
                *b = (x - mean) * w;
            }
            fwd.process(&mut buf, &mut spec)
                .expect("buffer sizes from the plan");
            for (pk, s) in p.iter_mut().zip(&spec) {
                *pk += s.norm_sqr();
            }
            start += hop;
        }
        let total: f64 = p.iter().sum();
        if total > 0.0 && total.is_finite() {
            for (a, v) in avg.iter_mut().zip(&p) {
                *a += v / total;
            }
        }
    }
    let l = y.len().max(1) as f64;
    avg.iter_mut().for_each(|a| *a /= l);
    avg
}

/// The segment length: the largest power of two at most n/8, at least 16 (and at most n).
pub(crate) fn segment_length(n: usize) -> usize {
    let target = (n / 8).max(16).min(n.max(2));
    1 << (usize::BITS - 1 - target.leading_zeros())
}

/// Bins of the peaks of `p` (bin 3 and above): local maxima whose topographic prominence is
/// at least [`PEAK_PROMINENCE`].
fn peaks(p: &[f64]) -> Vec<usize> {
    let n = p.len();
    let mut out = Vec::new();
    for k in 3..n.saturating_sub(1) {
        if !(p[k] > p[k - 1] && p[k] >= p[k + 1]) {
            continue;
        }
        // The lowest point on each side before a higher value (or the end).
        let side_min = |range: &mut dyn Iterator<Item = usize>| {
            let mut lo = p[k];
            for j in range {
                if p[j] > p[k] {
                    break;
                }
                lo = lo.min(p[j]);
            }
            lo
        };
        let left = side_min(&mut (2..k).rev());
        let right = side_min(&mut (k + 1..n));
        let base = left.max(right);
        if base <= 0.0 || p[k] >= PEAK_PROMINENCE * base {
            out.push(k);
        }
    }
    let highest = out.iter().map(|&k| p[k]).fold(0.0, f64::max);
    out.retain(|&k| p[k] >= PEAK_LEVEL * highest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Restated after decimation, a survey keeps its resolution, band and the peaks below
    /// the new Nyquist, at the new rate.
    #[test]
    fn a_decimated_survey_keeps_its_resolution_and_peaks() {
        let s = RecordSurvey {
            fs_hz: 400.0,
            resolution_hz: 0.0244,
            band_hz: 14.4,
            peaks_hz: vec![3.5, 5.2, 7.3, 16.5, 45.0],
        };
        let d = s.decimated(5);
        assert_eq!(d.fs_hz, 80.0);
        assert_eq!(d.resolution_hz, s.resolution_hz);
        assert_eq!(d.band_hz, 14.4);
        assert_eq!(d.peaks_hz, vec![3.5, 5.2, 7.3, 16.5]);
        assert_eq!(s.decimated(1), s);
    }

    /// Two decaying resonances in white noise, made by a second-order recursion each: the
    /// survey finds their peaks, a band above the higher one, and from the lower one a lag of
    /// ten periods.
    #[test]
    fn finds_the_peaks_band_and_lag_of_two_resonances() {
        let fs = 200.0;
        let n = 1 << 16;
        // A resonance at f Hz, damping 1 %, driven by a deterministic pseudo-random sequence.
        let mut state = 12345u64;
        let mut noise = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let e: Vec<f64> = (0..n).map(|_| noise()).collect();
        let resonance = |f: f64| {
            let r = (-0.01 * 2.0 * PI * f / fs).exp();
            let a1 = 2.0 * r * (2.0 * PI * f / fs).cos();
            let mut y = vec![0.0; n];
            for k in 2..n {
                y[k] = a1 * y[k - 1] - r * r * y[k - 2] + e[k];
            }
            y
        };
        let (a, b) = (resonance(2.0), resonance(11.0));
        let y: Vec<f64> = a.iter().zip(&b).map(|(a, b)| a + b).collect();
        let s = survey(&[&y], fs).unwrap();
        assert_eq!(s.peaks_hz.len(), 2, "{s:?}");
        // Within two bins of each resonance: the peak falls on the bin grid, and the Hann
        // window's main lobe (four bins wide) leans the sampled maximum to the side where the
        // resonance's skirt is higher.
        assert!(
            (s.peaks_hz[0] - 2.0).abs() <= 2.0 * s.resolution_hz,
            "{s:?}"
        );
        assert!(
            (s.peaks_hz[1] - 11.0).abs() <= 2.0 * s.resolution_hz,
            "{s:?}"
        );
        // Driven alike, the lower resonance holds most of the power: the band lies above it.
        assert!(s.band_hz > 2.0 && s.band_hz < 11.0, "{s:?}");
        // The band alone would allow ⌊200 / (5 · band)⌋; the 11 Hz peak must stay below 0.8
        // of the new Nyquist, which allows ⌊0.4 · 200 / 11⌋ = 7.
        let r = s.decimation(n);
        let by_band = (fs / (5.0 * s.band_hz)).floor() as usize;
        let by_peak = (0.4 * fs / s.peaks_hz[1]).floor() as usize;
        assert_eq!(by_peak, 7);
        assert_eq!(r, by_band.min(by_peak), "{s:?}");
        let (i, lag) = s.block_rows(n, 1, 1);
        assert_eq!(lag.lowest_peak_hz, Some(s.peaks_hz[0]));
        // Ten periods of the lowest peak, rounded up to whole block rows.
        let periods = lag.periods.unwrap();
        assert!((10.0..10.0 + 2.0 * s.peaks_hz[0] / fs).contains(&periods));
        assert_eq!(lag.limited_by, None);
        assert_eq!(2 * i - 1, (periods * fs / s.peaks_hz[0]).round() as usize);
    }

    /// White noise has no peak: 20 block rows, no decimation.
    #[test]
    fn white_noise_has_no_peak() {
        let mut state = 7u64;
        let y: Vec<f64> = (0..20000)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect();
        let s = survey(&[&y], 100.0).unwrap();
        assert!(s.peaks_hz.is_empty(), "{s:?}");
        assert_eq!(s.decimation(y.len()), 1);
        assert_eq!(s.block_rows(y.len(), 1, 1).0, 20);
    }

    /// A lag the matrix budget cannot hold is cut to it, and said.
    #[test]
    fn the_lag_is_cut_to_the_matrix_budget() {
        let s = RecordSurvey {
            fs_hz: 100.0,
            resolution_hz: 0.01,
            band_hz: 20.0,
            peaks_hz: vec![0.1],
        };
        let (i, lag) = s.block_rows(1_000_000, 10, 10);
        assert_eq!(i, MAX_TOEPLITZ_ROWS / 10);
        assert_eq!(lag.limited_by, Some(LagLimit::MatrixSize));
        let (i, lag) = s.block_rows(3200, 1, 1);
        assert_eq!(i, 200);
        assert_eq!(lag.limited_by, Some(LagLimit::RecordLength));
    }
}
