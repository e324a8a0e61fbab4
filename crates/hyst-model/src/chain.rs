//! The measurement chain between the structure's displacement and the record.

/// What the acquisition does to the measured displacement between the structure and the
/// record: a sensor's first-order lag τ and a delay d (the sensor's, the conditioning's, a skew
/// between the input's and the output's sampling). The record holds
/// $$y_m(t) = \int_0^\infty \tfrac{1}{\tau} e^{-s/\tau}\, x(t - d - s)\, ds,
/// \qquad Y_m(s) = \frac{e^{-sd}}{1 + s\tau}\, X(s),$$
/// $y_m(t) = x(t - d)$ when τ = 0. In the band it also stands for an anti-aliasing filter:
/// to first order in frequency any causal chain is a delay and a lag. It is not structure:
/// it moves no pole and no force, and the linearization ignores it. Since the structure is
/// time-invariant, a delay of the output is the same as one of the input; an output that
/// leads its input (a force channel that lags) is not modelled.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct MeasurementChain {
    /// Delay d (s), ≥ 0.
    #[cfg_attr(feature = "serde", serde(default))]
    pub delay: f64,
    /// The sensor's first-order time constant τ (s), ≥ 0.
    #[cfg_attr(feature = "serde", serde(default))]
    pub lag: f64,
}

impl MeasurementChain {
    /// Whether the chain does nothing (d = τ = 0).
    pub fn is_identity(&self) -> bool {
        self.delay == 0.0 && self.lag == 0.0
    }
}
