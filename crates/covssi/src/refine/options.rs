//! The refinement's settings.

/// Options of [`refine`](super::refine).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default, deny_unknown_fields))]
pub struct RefineOptions {
    /// Largest number of scoring iterations per fit. Default: 200.
    pub max_iterations: usize,
    /// A fit has converged when an accepted step lowers `L` by less than this. Default: 1e-6.
    pub tolerance: f64,
    /// Drop modes whose evidence is below the BIC penalty. Default: true.
    pub select: bool,
    /// Fit the chosen modes once more by the joint likelihood of all channels (cross-spectra
    /// included), or above [`JOINT_MAX_CHANNELS`](super::JOINT_MAX_CHANNELS) channels of that many combinations of them
    /// (with more modes than that, band by band), and report its estimates and standard
    /// errors; skipped
    /// when the record does not follow the per-channel model (misfit above
    /// [`MISFIT_LIMIT`](super::MISFIT_LIMIT)). Default: true.
    pub joint: bool,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            max_iterations: 200,
            tolerance: 1e-6,
            select: true,
            joint: true,
        }
    }
}
