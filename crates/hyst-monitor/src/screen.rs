//! A record screened before it is identified, for what breaks a real campaign's records
//! rather than the structure: a channel with values that are not numbers (a NaN burst, a
//! dropped packet), a channel stuck at one value (a dead or disconnected sensor), a clipped
//! channel (the acquisition's range exceeded). Such a record is skipped with the reason —
//! its modes would be the acquisition's, not the structure's.
//!
//! The rules, for a channel of n samples:
//! - **not finite**: any NaN or infinite value;
//! - **stuck**: a run of identical consecutive values at least max(50, n/20) long — a
//!   continuous signal repeats a value a few samples at a time at most, even quantized to
//!   16 bits at a small amplitude;
//! - **clipped**: at least [`CLIPPED_SAMPLES`] (8) samples equal to the channel's maximum or
//!   its minimum — a continuous signal reaches each extreme once, and one quantized reaches
//!   its top level a few times at most (a Gaussian signal quantized to a tenth of its
//!   standard deviation, 10⁶ samples: about 2), while a Gaussian signal clipped at 3.6 σ
//!   (80 % of its largest excursion in 10⁵ samples) holds the limit 16 times in 10⁵ — and
//!   two of them consecutive (a flat top): a periodic signal (a multisine excitation
//!   repeated period after period) reaches the same extremes once a period, one sample at a
//!   time.

/// Samples at a channel's extreme that make it clipped.
pub const CLIPPED_SAMPLES: usize = 8;

/// Why a record is not fit to be identified.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Unfit {
    /// Values that are not numbers.
    #[error(
        "channel {channel} has {count} value(s) that are not finite numbers, the first at sample {first}: skipped (a gap in the acquisition)"
    )]
    NotFinite {
        /// The channel (0-based).
        channel: usize,
        /// How many.
        count: usize,
        /// The first one's sample (0-based).
        first: usize,
    },
    /// A channel stuck at one value.
    #[error(
        "channel {channel} holds {value} for {run} consecutive samples from sample {from}: stuck (a dead or disconnected sensor); skipped"
    )]
    Stuck {
        /// The channel (0-based).
        channel: usize,
        /// The value it holds.
        value: f64,
        /// For how many samples.
        run: usize,
        /// From which sample (0-based).
        from: usize,
    },
    /// A channel clipped at its range.
    #[error(
        "channel {channel} has {count} samples at its extremes {min} and {max}: clipped (the acquisition's range exceeded); skipped"
    )]
    Clipped {
        /// The channel (0-based).
        channel: usize,
        /// Samples at either extreme.
        count: usize,
        /// Its smallest value.
        min: f64,
        /// Its largest value.
        max: f64,
    },
}

/// Screen a record's channels: the first thing wrong, in the order of the rules above, or
/// `Ok` when nothing is.
pub fn screen(channels: &[&[f64]]) -> Result<(), Unfit> {
    for (channel, y) in channels.iter().enumerate() {
        let n = y.len();
        let bad = y.iter().filter(|v| !v.is_finite()).count();
        if bad > 0 {
            let first = y.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(Unfit::NotFinite {
                channel,
                count: bad,
                first,
            });
        }
        let (run, from) = longest_run(y);
        if n > 0 && run >= (n / 20).max(50) {
            return Err(Unfit::Stuck {
                channel,
                value: y[from],
                run,
                from,
            });
        }
        let max = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let min = y.iter().copied().fold(f64::INFINITY, f64::min);
        let at = |v: f64| v == max || v == min;
        let count = y.iter().filter(|&&v| at(v)).count();
        // A flat top: two consecutive samples at an extreme (a periodic signal's recurring
        // peak is one sample each period).
        let flat = y.windows(2).any(|w| at(w[0]) && w[0] == w[1]);
        if count >= CLIPPED_SAMPLES && flat && max > min {
            return Err(Unfit::Clipped {
                channel,
                count,
                min,
                max,
            });
        }
    }
    Ok(())
}

/// The longest run of identical consecutive values: its length and start.
fn longest_run(y: &[f64]) -> (usize, usize) {
    let (mut best, mut best_from) = (0, 0);
    let mut from = 0;
    for i in 1..=y.len() {
        if i == y.len() || y[i] != y[from] {
            if i - from > best {
                (best, best_from) = (i - from, from);
            }
            from = i;
        }
    }
    (best, best_from)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random-looking continuous signal (a sum of incommensurate sines), quantized to
    /// 16 bits over ±4 when `quantized`.
    fn signal(n: usize, quantized: bool) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64 * 0.01;
                let v = (2.1 * t).sin() + 0.7 * (5.3 * t + 1.0).sin() + 0.4 * (11.9 * t).cos();
                if quantized {
                    (v / 8.0 * 65536.0).round() * 8.0 / 65536.0
                } else {
                    v
                }
            })
            .collect()
    }

    /// Each fault is named with its channel and where; a clean signal, quantized or not,
    /// passes.
    #[test]
    fn each_fault_is_named_and_clean_signals_pass() {
        let n = 20_000;
        for q in [false, true] {
            let y = signal(n, q);
            assert_eq!(screen(&[&y, &y]), Ok(()), "quantized {q}");
        }
        let good = signal(n, false);
        let mut nan = good.clone();
        nan[300..360].fill(f64::NAN);
        assert_eq!(
            screen(&[&good, &nan]),
            Err(Unfit::NotFinite {
                channel: 1,
                count: 60,
                first: 300
            })
        );
        let mut stuck = good.clone();
        stuck[5000..6200].fill(0.25);
        let e = screen(&[&stuck]).unwrap_err();
        assert_eq!(
            e,
            Unfit::Stuck {
                channel: 0,
                value: 0.25,
                run: 1200,
                from: 5000
            }
        );
        assert!(e.to_string().contains("stuck"), "{e}");
        let dead = vec![0.0; n];
        assert!(matches!(
            screen(&[&good, &good, &dead]),
            Err(Unfit::Stuck { channel: 2, .. })
        ));
        let clipped: Vec<f64> = good.iter().map(|v| v.min(1.5)).collect();
        let e = screen(&[&clipped]).unwrap_err();
        assert!(
            matches!(e, Unfit::Clipped { channel: 0, max, count, .. } if max == 1.5 && count > 20),
            "{e}"
        );
    }

    #[test]
    fn longest_run_finds_its_start() {
        assert_eq!(longest_run(&[1.0, 2.0, 2.0, 2.0, 3.0, 3.0]), (3, 1));
        assert_eq!(longest_run(&[]), (0, 0));
        assert_eq!(longest_run(&[4.0]), (1, 0));
    }
}
