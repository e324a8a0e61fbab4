//! Step 1 and 2: the record prepared (mean removed, decimated, its moments) and SSI run on it.

use crate::{IdentError, IdentOptions};
use covssi::{BlockRows, SsiOptions, SsiResult};

/// The prepared output record.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Prepared {
    /// Centred, decimated record (not in JSON: the record is the caller's).
    #[cfg_attr(feature = "serde", serde(skip))]
    pub y: Vec<f64>,
    /// Its sampling rate (Hz).
    pub fs: f64,
    /// Decimation factor applied.
    pub decimation: usize,
    /// Mean removed.
    pub mean: f64,
    /// Standard deviation σₓ of the (undecimated) record.
    pub sigma_x: f64,
    /// Skewness of the prepared record.
    pub skewness: f64,
    /// Kurtosis of the prepared record (3 for a Gaussian).
    pub kurtosis: f64,
    /// Dominant frequency of the spectrum (Hz).
    pub dominant_hz: f64,
}

/// Mean, standard deviation, skewness and kurtosis. The deviations are divided by the
/// largest of them first, so that their fourth powers neither underflow nor overflow in any
/// units the record may be in.
pub(crate) fn moments(y: &[f64]) -> (f64, f64, f64, f64) {
    let n = y.len() as f64;
    let sum = y.iter().sum::<f64>();
    let mean = if sum.is_finite() {
        sum / n
    } else {
        y.iter().map(|v| v / n).sum()
    };
    let s = y.iter().fold(0.0f64, |m, v| m.max((v - mean).abs()));
    let d = |v: &f64| (v - mean) / s;
    let m2 = y.iter().map(|v| d(v).powi(2)).sum::<f64>() / n;
    let m3 = y.iter().map(|v| d(v).powi(3)).sum::<f64>() / n;
    let m4 = y.iter().map(|v| d(v).powi(4)).sum::<f64>() / n;
    (mean, s * m2.sqrt(), m3 / m2.powf(1.5), m4 / (m2 * m2))
}

/// The frequency of the largest peak of the record's correlation-based spectrum.
pub(crate) fn dominant_frequency(y: &[f64], fs: f64) -> Result<f64, IdentError> {
    let lags = 256.min(y.len() / 2).max(2);
    let c = covssi::corr::estimate(&[y], &[0], lags);
    let mut best = (0.0, f64::MIN);
    let npts = 2048;
    for p in 1..npts {
        let f = fs / 2.0 * p as f64 / npts as f64;
        let w = 2.0 * std::f64::consts::PI * f / fs;
        let mut s = c.r[0][0];
        for (k, rk) in c.r.iter().enumerate().skip(1) {
            let win = 0.5 * (1.0 + (std::f64::consts::PI * k as f64 / lags as f64).cos());
            s += 2.0 * win * rk[0] * (w * k as f64).cos();
        }
        if s > best.1 {
            best = (f, s);
        }
    }
    Ok(best.0)
}

/// Step 1: centre, decimate, describe.
pub fn prepare(y: &[f64], fs: f64, opts: &IdentOptions) -> Result<Prepared, IdentError> {
    if y.len() < 64 {
        return Err(IdentError::TooShort {
            samples: y.len(),
            needed: 64,
        });
    }
    if !(fs.is_finite() && fs > 0.0) {
        return Err(IdentError::Ssi(covssi::SsiError::NonPositiveRate { fs }));
    }
    if let Some((index, &value)) = y.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(IdentError::Ssi(covssi::SsiError::NonFinite {
            channel: 0,
            index,
            value,
        }));
    }
    if y.iter().all(|v| *v == y[0]) {
        return Err(IdentError::Ssi(covssi::SsiError::ConstantChannel {
            channel: 0,
            value: y[0],
        }));
    }
    let (mean, sigma_x, _, _) = moments(y);
    // The correlations SSI works from are of the order of the variance: it must be a normal
    // double with room to spare (covssi's own range), or every later step reads garbage.
    let variance = sigma_x * sigma_x;
    if !(variance.is_finite() && variance >= covssi::MIN_CORRELATION) {
        return Err(IdentError::Ssi(covssi::SsiError::OutOfRange {
            value: variance,
        }));
    }
    let centred: Vec<f64> = y.iter().map(|v| v - mean).collect();
    let dominant_hz = dominant_frequency(&centred, fs)?;
    let r = ((fs / dominant_hz / opts.samples_per_period).floor() as usize).max(1);
    let yd = hyst_sim::resample::decimate(&centred, r);
    let (_, _, skewness, kurtosis) = moments(&yd);
    Ok(Prepared {
        y: yd,
        fs: fs / r as f64,
        decimation: r,
        mean,
        sigma_x,
        skewness,
        kurtosis,
        dominant_hz,
    })
}

/// Step 2: SSI-COV with lags covering `opts.periods` periods of the dominant mode.
pub fn run_ssi(p: &Prepared, opts: &IdentOptions) -> Result<SsiResult, IdentError> {
    // The paper sizes the Toeplitz matrix so that τ = i·Δt spans the periods (its lags then
    // reach twice that).
    let i = (opts.periods * p.fs / p.dominant_hz).ceil().max(2.0) as usize;
    let so = SsiOptions {
        block_rows: BlockRows::Count(i),
        max_order: Some(opts.max_order),
        criteria: opts.criteria,
        ..SsiOptions::default()
    };
    match covssi::identify(&[&p.y], p.fs, &so) {
        // A record with little noise (a simulated one, a free decay) can leave the Toeplitz
        // matrix of lower rank than the order asked for: every order it has is then used.
        Err(covssi::SsiError::OrderAboveRank { order, rank, .. }) if rank >= 2 => {
            let lower = SsiOptions {
                max_order: Some(rank),
                ..so
            };
            let mut res = covssi::identify(&[&p.y], p.fs, &lower)?;
            res.notes.push(format!(
                "the block Toeplitz matrix has rank {rank}, below the maximum order {order}: orders up to {rank} used"
            ));
            Ok(res)
        }
        other => Ok(other?),
    }
}
