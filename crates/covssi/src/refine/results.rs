//! What the refinement returns: the refined modes and real poles with their standard
//! errors, those dropped with their evidence, and whether the record follows the model.

use crate::linalg::C64;

/// Above this [`Refinement::misfit`] the record does not follow the model.
pub const MISFIT_LIMIT: f64 = 0.05;

/// Kolmogorov–Smirnov distance of the sample `x` from the unit exponential law: the
/// [`Refinement::misfit`] of the ratios $I/S$ of a periodogram to a fitted spectrum, which a
/// record following the model makes unit exponential variables. Other spectral fits can use it
/// to report their misfit on the same scale (compare it with [`MISFIT_LIMIT`]).
pub fn exponential_misfit(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len() as f64;
    x.iter()
        .enumerate()
        .map(|(i, &v)| {
            let f = 1.0 - (-v.max(0.0)).exp();
            (f - i as f64 / n).abs().max(((i + 1) as f64 / n - f).abs())
        })
        .fold(0.0, f64::max)
}

/// The [`exponential_misfit`] of ratios counted as they come, without keeping them: each
/// ratio's value under the unit exponential law, 1 − e^{−v}, counted in one of
/// [`MisfitCounts::CELLS`] equal cells of [0, 1]. The distance is bounded from above within
/// each cell, so it exceeds the exact one by at most the share of the ratios in one cell
/// plus 1/CELLS (under the law, about 3·10⁻⁵).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct MisfitCounts {
    counts: Vec<u32>,
    total: u64,
}

impl MisfitCounts {
    const CELLS: usize = 1 << 15;

    pub(super) fn new() -> Self {
        MisfitCounts {
            counts: vec![0; Self::CELLS],
            total: 0,
        }
    }

    pub(super) fn add(&mut self, v: f64) {
        let u = 1.0 - (-v.max(0.0)).exp();
        let i = ((u * Self::CELLS as f64) as usize).min(Self::CELLS - 1);
        self.counts[i] += 1;
        self.total += 1;
    }

    pub(super) fn merge(&mut self, other: &Self) {
        self.counts
            .iter_mut()
            .zip(&other.counts)
            .for_each(|(a, b)| *a += b);
        self.total += other.total;
    }

    /// The Kolmogorov–Smirnov distance from the unit exponential law (bounded above, see
    /// the type); 1 with nothing counted.
    pub(super) fn distance(&self) -> f64 {
        if self.total == 0 {
            return 1.0;
        }
        let (n, cells) = (self.total as f64, Self::CELLS as f64);
        let mut below = 0u64;
        let mut d = 0.0f64;
        for (i, &c) in self.counts.iter().enumerate() {
            let (lo, hi) = (i as f64 / cells, (i + 1) as f64 / cells);
            let f_lo = below as f64 / n;
            below += u64::from(c);
            let f_hi = below as f64 / n;
            d = d.max(f_hi - lo).max(hi - f_lo);
        }
        d.min(1.0)
    }
}

/// A mode after refinement.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RefinedMode {
    /// Index of the SSI mode this one is: SSI modes and refined modes are paired nearest
    /// first, one to one, within [`SAME_MODE_DISTANCE`](crate::refine::SAME_MODE_DISTANCE) (poles may trade places while
    /// fitting). `None` when the fit moved this mode away from every SSI mode not paired
    /// with a nearer one: the likelihood put it where SSI saw none. (`ssi_mode` in JSON.)
    #[cfg_attr(feature = "serde", serde(rename = "ssi_mode"))]
    pub source: Option<usize>,
    /// Natural frequency |λ|/2π (Hz).
    pub frequency_hz: f64,
    /// Damping ratio −Re λ/|λ|.
    pub damping_ratio: f64,
    /// Standard error of the frequency (Hz) from the Fisher information; `None` if that is
    /// singular, or if this mode's damping has saturated (ζ = 1 to twelve digits: the
    /// likelihood no longer depends on it, and the other modes' errors are taken with it held).
    pub frequency_se_hz: Option<f64>,
    /// Standard error of the damping ratio; `None` as the frequency's.
    pub damping_se: Option<f64>,
    /// Continuous-time pole (rad/s).
    pub lambda: C64,
    /// The mode's shape in every channel, in the channels' own units, scaled so that its
    /// largest entry is 1: from the joint likelihood of the channels (its $c_r$), or, above
    /// [`JOINT_MAX_CHANNELS`](crate::refine::JOINT_MAX_CHANNELS) channels, each channel regressed on the joint fit of the
    /// combinations (see [`Refinement::combinations`]). `None` when the channels were
    /// fitted each alone (one channel, `joint` off, a real pole kept, or a record the joint
    /// fit did not take).
    pub shape: Option<Vec<C64>>,
    /// Standard error of each entry of `shape`, √(E|δ|²) of the complex entry (0 for the
    /// entry scaled to 1), from the Fisher information (through combinations: the
    /// regression's, plus what the combinations' fit's own uncertainty carries into it);
    /// `None` with `shape`. When two entries are
    /// about equally large, which one is scaled to 1 depends on the noise, and the other's
    /// ratio to it is pulled below 1 by that choice, which these standard errors do not hold.
    pub shape_se: Option<Vec<f64>>,
    /// Modal phase collinearity of `shape` ([`mpc`](crate::mpc)); `None` with `shape`.
    pub mpc: Option<f64>,
    /// Rise of `L` (negative log-likelihood) when this mode is removed, the other poles held
    /// and the numerators refitted: what this mode explains that the others, where they are,
    /// do not. At least [`Refinement::penalty`] when selecting.
    pub evidence: f64,
}

/// An SSI mode the likelihood does not support.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DroppedMode {
    /// Index of the SSI mode (for one dropped from the final model: the nearest to its pole).
    /// (`ssi_mode` in JSON.)
    #[cfg_attr(feature = "serde", serde(rename = "ssi_mode"))]
    pub source: usize,
    /// Its SSI frequency (Hz).
    pub frequency_hz: f64,
    /// Below [`Refinement::penalty`]: the fall of `L` when it was added (forward step; that fit
    /// stops once the penalty is out of its reach, so this is what it had gained by then),
    /// or its rise when it was removed from the model and everything refitted (backward
    /// step).
    pub evidence: f64,
    /// Where the fit had moved the pole before it was removed (backward step; `None` for a
    /// mode never kept): its frequency (Hz) and damping ratio. Fitted poles may wander from
    /// their SSI modes, so two dropped poles can share their nearest SSI mode.
    #[cfg_attr(feature = "serde", serde(default))]
    pub fitted: Option<FittedPole>,
}

/// A fitted pole as frequency and damping ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FittedPole {
    /// Natural frequency |λ|/2π (Hz).
    pub frequency_hz: f64,
    /// Damping ratio −Re λ/|λ|.
    pub damping_ratio: f64,
}

impl FittedPole {
    /// The pole λ (rad/s) as frequency and damping ratio.
    pub fn of(lambda: crate::Complex64) -> Self {
        let w = lambda.norm();
        FittedPole {
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            damping_ratio: if w > 0.0 { -lambda.re / w } else { 0.0 },
        }
    }
}

/// A real pole (a non-oscillating, exponentially decaying component) after refinement.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct RefinedRealPole {
    /// Index of the SSI real-pole cluster it started from. (`ssi_real_pole` in JSON.)
    #[cfg_attr(feature = "serde", serde(rename = "ssi_real_pole"))]
    pub source: usize,
    /// The pole λ (rad/s, negative).
    pub lambda: f64,
    /// Standard error of λ (rad/s) from the Fisher information; `None` if that is singular.
    pub lambda_se: Option<f64>,
    /// Rise of `L` when this pole is removed, the other poles held and the numerators
    /// refitted. At least [`Refinement::real_pole_penalty`] when selecting.
    pub evidence: f64,
}

/// An SSI real pole the likelihood does not support.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DroppedRealPole {
    /// Index of the SSI real-pole cluster. (`ssi_real_pole` in JSON.)
    #[cfg_attr(feature = "serde", serde(rename = "ssi_real_pole"))]
    pub source: usize,
    /// Its SSI value λ (rad/s).
    pub lambda: f64,
    /// Below [`Refinement::real_pole_penalty`]: the fall of `L` when it was added (what the
    /// fit had gained when the penalty went out of its reach), or its rise when it was
    /// removed and everything refitted.
    pub evidence: f64,
}

/// What [`refine`](crate::refine()) finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Refinement {
    /// Kept modes, by increasing frequency.
    pub modes: Vec<RefinedMode>,
    /// Dropped SSI modes, in the order they were dropped (forward, then backward).
    pub dropped: Vec<DroppedMode>,
    /// BIC penalty of one mode, ½(2 + 2l) ln K.
    pub penalty: f64,
    /// Kept real poles ([`refine_with_real_poles`](crate::refine_with_real_poles)), slowest first; empty from [`refine`](crate::refine()).
    pub real_poles: Vec<RefinedRealPole>,
    /// Real poles the likelihood does not support, in the order they were dropped.
    pub dropped_real_poles: Vec<DroppedRealPole>,
    /// BIC penalty of one real pole, ½(1 + l) ln K: its own parameter and each channel's
    /// numerator coefficient.
    pub real_pole_penalty: f64,
    /// `L` of the final model.
    pub neg_log_likelihood: f64,
    /// How far the record is from the model: the Kolmogorov–Smirnov distance between the
    /// ratios I/S (every channel and frequency) and the unit exponential law they follow when
    /// the model holds. Near 0 when it does (0.003–0.004 on the shared OMA records); large
    /// when the excitation is not broadband random (0.59 on the F-16's multisine record) or
    /// the record holds what the model lacks. Above [`MISFIT_LIMIT`] the refined values
    /// should not be trusted.
    pub misfit: f64,
    /// Frequencies K used (0 < ω < π).
    pub frequencies: usize,
    /// Scoring iterations of the final fit.
    pub iterations: usize,
    /// Whether the estimates, standard errors, `neg_log_likelihood` and `misfit` are the
    /// joint likelihood's (see [`RefineOptions::joint`](crate::RefineOptions::joint)); the evidence is always the
    /// per-channel likelihood's, by which the modes were chosen.
    pub joint: bool,
    /// For a joint fit of more than [`JOINT_MAX_CHANNELS`](crate::refine::JOINT_MAX_CHANNELS) channels: the number of
    /// combinations of the channels it was fitted to (`neg_log_likelihood` and `misfit` are
    /// then theirs; each channel's shape is then regressed on that fit, its cross-spectra
    /// with the combinations' innovations being linear in the shape once the poles, gains
    /// and innovations' covariance are known); `None` when the channels themselves were
    /// fitted.
    pub combinations: Option<usize>,
    /// Bands of frequencies the joint fit was split into: 1, or with more modes than
    /// combinations one per group of at most that many modes, each fitted over its own band
    /// through combinations of its own (`neg_log_likelihood` is then the sum of theirs,
    /// `misfit` over all of them).
    pub bands: usize,
}

impl Refinement {
    /// Which likelihood gave the estimates, in words: "each channel's spectrum", "channels
    /// jointly", "channels jointly, through 4 combinations" or "channels jointly, through 4
    /// combinations in each of 2 bands".
    pub fn fitted_by(&self) -> String {
        match (self.joint, self.combinations) {
            (true, Some(p)) if self.bands > 1 => format!(
                "channels jointly, through {p} combinations in each of {} bands",
                self.bands
            ),
            (true, Some(p)) => format!("channels jointly, through {p} combinations"),
            (true, None) => "channels jointly".to_string(),
            (false, _) => "each channel's spectrum".to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// λ = ω(−ζ + i√(1−ζ²)) reads back as ω/2π and ζ, to rounding.
    #[test]
    fn a_fitted_pole_reads_as_frequency_and_damping() {
        let (f, z) = (37.3, 0.02);
        let w = 2.0 * std::f64::consts::PI * f;
        let p = FittedPole::of(crate::Complex64::new(-z * w, w * (1.0 - z * z).sqrt()));
        approx::assert_relative_eq!(p.frequency_hz, f, max_relative = 1e-12);
        approx::assert_relative_eq!(p.damping_ratio, z, max_relative = 1e-12);
    }
}
