//! Output-only modal analysis by covariance-driven stochastic subspace identification (SSI-COV).
//!
//! One job: from one or more measured response channels alone, find the poles of the linear
//! system that produced them, say which are physical, and group them into modes.
//!
//! 1. Correlations by the unbiased estimator (eq. 27 of the paper),
//!    $\hat R_k = \frac{1}{N-k}\sum_n y(n+k)\,y_{\text{ref}}(n)^\top$ ([`corr`]), computed by
//!    direct blocked sums or segmented zero-padded FFTs without building block data matrices.
//! 2. The block Toeplitz matrix $T_{1|i}$ with block $(p, q) = R_{i+p-q}$ (lags $1 \dots 2i-1$)
//!    and its SVD $T = U S V^\top$; for each model order $n$ the observability matrix
//!    $\mathcal O = U_n S_n^{1/2}$, $A = \mathcal O_{\uparrow}^{\dagger}\mathcal O_{\downarrow}$
//!    from its shift structure, $C$ = its first block row.
//! 3. Eigenvalues $\mu$ of $A$ → continuous poles $\lambda = f_s \ln\mu$ (eq. 28), frequency
//!    $|\lambda|/2\pi$ and damping $-\operatorname{Re}\lambda/|\lambda|$ (eq. 29), mode shapes
//!    $C\psi$. Real poles stay real poles.
//! 4. Each pole is compared with the nearest pole of the previous order (eq. 30:
//!    $d\omega = |\omega_h-\omega_j|/\max$, $d\zeta$ likewise, $1-\text{MAC}$ for several channels;
//!    eq. 31 for real poles) and labelled [`PoleStatus`]: stable in frequency, in frequency and
//!    damping, also in shape, a stable real pole — or rejected, with the criterion and by how much.
//! 5. Fully stable poles are clustered into [`Mode`]s (mean ± standard deviation) by their
//!    distance in the complex plane, $|\lambda_i-\lambda_j|/\max(|\lambda_i|,|\lambda_j|)$, so that
//!    poles of one frequency but different damping stay apart; stable real poles into
//!    [`RealPoleCluster`]s. Shapes compare by [`mac`]; [`mpc`] tells how close a shape is to
//!    a real (normal) mode.
//! 6. Optionally, [`refine()`]: the modes (with [`refine_with_real_poles`], the real poles too)
//!    fitted to the whole record by maximum likelihood
//!    (Whittle; several channels jointly, cross-spectra included, above 4 channels through 4
//!    combinations of them, band by band for more than 4 modes), with standard errors, the
//!    modes the record does not support dropped, and a check that the record follows the model
//!    ([`refine`](mod@refine) module).
//!
//! ```
//! # use covssi::{identify, SsiOptions, BlockRows};
//! // a decaying oscillation sampled at 100 Hz (its correlation is again one)
//! let y: Vec<f64> = (0..4000).map(|n| {
//!     let t = n as f64 / 100.0;
//!     (-0.3 * t).exp() * (2.0 * std::f64::consts::PI * 5.0 * t).cos()
//! }).collect();
//! let opts = SsiOptions { block_rows: BlockRows::Count(10), max_order: Some(2), ..SsiOptions::default() };
//! let result = identify(&[&y], 100.0, &opts).unwrap();
//! let pole = result.diagram.orders.last().unwrap().poles[0].lambda;
//! assert!((pole.im / (2.0 * std::f64::consts::PI) - 5.0).abs() < 1e-3);
//! ```

#![warn(missing_docs)]

// The README's example runs as a doctest, so what it shows stays true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod analysis;
mod checks;
mod cluster;
pub mod corr;
pub mod decimate;
pub mod decision;
mod error;
pub mod fdd;
pub mod harmonic;
mod identify;
pub mod jackknife;
mod linalg;
pub mod multisetup;
mod options;
pub mod plausibility;
pub mod progress;
pub mod references;
pub mod refine;
mod stabilize;
pub mod survey;
#[cfg(feature = "svg")]
pub mod svg;
#[cfg(feature = "synth")]
pub mod synth;
mod toeplitz;

pub use analysis::{
    AnalysisOptions, Decimation, DecimationReport, JACKKNIFE_BLOCKS, ModalAnalysis, analyze,
    analyze_with_progress, shape_text,
};
pub use cluster::{Mode, RealPoleCluster};
pub use corr::Correlations;
pub use decision::{ModeCriteria, ModeDecision, ModeSource, NotAMode, ReportedMode};
pub use error::{SsiError, SsiOption};
pub use identify::{
    MIN_CORRELATION, OrderPoles, Spectrum, SsiResult, StabilizationDiagram, identify,
    identify_from_correlations,
};
pub use linalg::C64 as Complex64;
pub use options::{BlockRows, SsiOptions, StabilityCriteria};
pub use plausibility::{NotPhysical, NotReported};
pub use progress::Progress;
pub use refine::{
    DroppedMode, DroppedRealPole, FittedPole, MISFIT_LIMIT, RefineOptions, RefinedMode,
    RefinedRealPole, Refinement, refine, refine_with_real_poles,
};
pub use stabilize::{Pole, PoleStatus, Rejection, Stability, mac, mpc, mpd};
pub use survey::{AutoLag, LagLimit, RecordSurvey, survey};
