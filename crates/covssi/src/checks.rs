//! What a record and the options must be, checked before any work: the channels (equal
//! lengths, finite, not constant), the rate, and the options no record changes. Every entry
//! point ([`crate::identify`], [`crate::survey`], [`crate::analyze`]) calls these, so that
//! the same input gets the same error whichever it enters by.

use crate::{SsiError, SsiOption, SsiOptions};

/// Check the channels (equal lengths, finite, not constant) and return their length and means,
/// reading each channel once.
pub(crate) fn check_channels(y: &[&[f64]]) -> Result<(usize, Vec<f64>), SsiError> {
    let first = y.first().ok_or(SsiError::NoChannels)?;
    let n = first.len();
    let mut means = Vec::with_capacity(y.len());
    for (c, ch) in y.iter().enumerate() {
        if ch.len() != n {
            return Err(SsiError::LengthMismatch {
                channel: c,
                len: ch.len(),
                expected: n,
            });
        }
        // A sum is finite only if every sample is (barring overflow): one pass in the common
        // case, a search for the culprit only when it is not.
        let sum = sum(ch);
        if !sum.is_finite()
            && let Some((index, &value)) = ch.iter().enumerate().find(|(_, v)| !v.is_finite())
        {
            return Err(SsiError::NonFinite {
                channel: c,
                index,
                value,
            });
        }
        if n > 0 && ch.iter().all(|v| *v == ch[0]) {
            return Err(SsiError::ConstantChannel {
                channel: c,
                value: ch[0],
            });
        }
        let mean = if sum.is_finite() {
            sum / n.max(1) as f64
        } else {
            // Finite samples whose sum overflows.
            ch.iter().map(|v| v / n as f64).sum()
        };
        means.push(mean);
    }
    Ok((n, means))
}

/// Sum with eight independent accumulators: a single running sum is one chain of dependent
/// additions, each waiting for the last, and cannot vectorise.
fn sum(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; 8];
    let chunks = v.chunks_exact(8);
    let tail: f64 = chunks.remainder().iter().sum();
    for c in chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            *a += x;
        }
    }
    acc.iter().sum::<f64>() + tail
}

pub(crate) fn check_fs(fs: f64) -> Result<(), SsiError> {
    if fs.is_finite() && fs > 0.0 {
        Ok(())
    } else {
        Err(SsiError::NonPositiveRate { fs })
    }
}

/// The options that are not checked where they are used: counts at least 1, thresholds
/// positive and finite (a threshold of 0 or below would reject every pole, and the user would
/// see "no mode found" instead of the option at fault).
pub(crate) fn check_options(opts: &SsiOptions) -> Result<(), SsiError> {
    let counts = [
        (SsiOption::OrderStep, Some(opts.order_step)),
        (SsiOption::MaxOrder, opts.max_order),
        (SsiOption::MinClusterSize, opts.min_cluster_size),
    ];
    if let Some((name, _)) = counts.iter().find(|(_, v)| *v == Some(0)) {
        return Err(SsiError::InvalidOption {
            option: *name,
            value: 0.0,
        });
    }
    let c = &opts.criteria;
    let thresholds = [
        (SsiOption::CriteriaFrequency, c.frequency),
        (SsiOption::CriteriaDamping, c.damping),
        (SsiOption::CriteriaMac, c.mac),
        (SsiOption::CriteriaReal, c.real),
        (SsiOption::MaxDamping, opts.max_damping),
        (SsiOption::ClusterTolerance, opts.cluster_tolerance),
    ];
    match thresholds
        .iter()
        .find(|(_, v)| !(v.is_finite() && *v > 0.0))
    {
        Some(&(name, value)) => Err(SsiError::InvalidOption {
            option: name,
            value,
        }),
        None => Ok(()),
    }
}
