//! Pole labels (eqs. 30–31): each pole of the diagram judged against the previous orders'.
//! Their clustering into modes is [`crate::cluster`].

use crate::linalg::C64;
use crate::{SsiOptions, StabilizationDiagram};

/// How far a pole is stable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Stability {
    /// Stable in frequency only (dζ above its threshold).
    Frequency,
    /// Stable in frequency and damping (the top level for one channel).
    FrequencyDamping,
    /// Stable in frequency, damping and shape (1 − MAC), for several channels.
    FrequencyDampingShape,
    /// A real (non-oscillating) pole stable by eq. (31).
    Real,
}

/// Why a pole is not stable.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Rejection {
    /// No pole of the same kind at the previous order to compare with.
    NoPrevious,
    /// Re λ ≥ 0: not a decaying mode.
    Unstable {
        /// Re λ (1/s).
        real_part: f64,
    },
    /// A negative real discrete eigenvalue: a pole at the Nyquist frequency, not physical.
    NegativeRealEigenvalue,
    /// Damping ratio above the hard limit.
    DampingAboveLimit {
        /// ζ of the pole.
        damping: f64,
        /// The limit.
        limit: f64,
    },
    /// Frequency changed too much from the previous order (eq. 30).
    Frequency {
        /// dω.
        change: f64,
        /// Its threshold.
        threshold: f64,
    },
    /// A real pole changed too much from the previous order (eq. 31).
    RealPole {
        /// dr.
        change: f64,
        /// Its threshold.
        threshold: f64,
    },
}

/// The label of a pole. In JSON (feature `serde`) one flat object: `{"label": "stable_fd"}`,
/// `{"label": "rejected_frequency", "change": 0.03, "threshold": 0.01}`, the label being
/// [`PoleStatus::name`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(into = "label::Label", from = "label::Label")
)]
pub enum PoleStatus {
    /// Stable to this level.
    Stable(Stability),
    /// Rejected, with the reason.
    Rejected(Rejection),
}

impl PoleStatus {
    /// A short name for reports: `stable_f`, `stable_fd`, `stable_fdm`, `stable_real`, or
    /// `rejected_<criterion>`.
    pub fn name(&self) -> &'static str {
        match self {
            PoleStatus::Stable(Stability::Frequency) => "stable_f",
            PoleStatus::Stable(Stability::FrequencyDamping) => "stable_fd",
            PoleStatus::Stable(Stability::FrequencyDampingShape) => "stable_fdm",
            PoleStatus::Stable(Stability::Real) => "stable_real",
            PoleStatus::Rejected(Rejection::NoPrevious) => "rejected_no_previous",
            PoleStatus::Rejected(Rejection::Unstable { .. }) => "rejected_unstable",
            PoleStatus::Rejected(Rejection::NegativeRealEigenvalue) => "rejected_nyquist",
            PoleStatus::Rejected(Rejection::DampingAboveLimit { .. }) => "rejected_damping_limit",
            PoleStatus::Rejected(Rejection::Frequency { .. }) => "rejected_frequency",
            PoleStatus::Rejected(Rejection::RealPole { .. }) => "rejected_real",
        }
    }
}

/// The flat JSON form of [`PoleStatus`].
#[cfg(feature = "serde")]
mod label {
    use super::{PoleStatus, Rejection, Stability};

    #[derive(serde::Serialize, serde::Deserialize)]
    #[serde(tag = "label", rename_all = "snake_case")]
    pub(super) enum Label {
        StableF,
        StableFd,
        StableFdm,
        StableReal,
        RejectedNoPrevious,
        RejectedUnstable { real_part: f64 },
        RejectedNyquist,
        RejectedDampingLimit { damping: f64, limit: f64 },
        RejectedFrequency { change: f64, threshold: f64 },
        RejectedReal { change: f64, threshold: f64 },
    }

    impl From<PoleStatus> for Label {
        fn from(s: PoleStatus) -> Label {
            use PoleStatus::*;
            match s {
                Stable(Stability::Frequency) => Label::StableF,
                Stable(Stability::FrequencyDamping) => Label::StableFd,
                Stable(Stability::FrequencyDampingShape) => Label::StableFdm,
                Stable(Stability::Real) => Label::StableReal,
                Rejected(Rejection::NoPrevious) => Label::RejectedNoPrevious,
                Rejected(Rejection::Unstable { real_part }) => {
                    Label::RejectedUnstable { real_part }
                }
                Rejected(Rejection::NegativeRealEigenvalue) => Label::RejectedNyquist,
                Rejected(Rejection::DampingAboveLimit { damping, limit }) => {
                    Label::RejectedDampingLimit { damping, limit }
                }
                Rejected(Rejection::Frequency { change, threshold }) => {
                    Label::RejectedFrequency { change, threshold }
                }
                Rejected(Rejection::RealPole { change, threshold }) => {
                    Label::RejectedReal { change, threshold }
                }
            }
        }
    }

    impl From<Label> for PoleStatus {
        fn from(l: Label) -> PoleStatus {
            use PoleStatus::*;
            match l {
                Label::StableF => Stable(Stability::Frequency),
                Label::StableFd => Stable(Stability::FrequencyDamping),
                Label::StableFdm => Stable(Stability::FrequencyDampingShape),
                Label::StableReal => Stable(Stability::Real),
                Label::RejectedNoPrevious => Rejected(Rejection::NoPrevious),
                Label::RejectedUnstable { real_part } => {
                    Rejected(Rejection::Unstable { real_part })
                }
                Label::RejectedNyquist => Rejected(Rejection::NegativeRealEigenvalue),
                Label::RejectedDampingLimit { damping, limit } => {
                    Rejected(Rejection::DampingAboveLimit { damping, limit })
                }
                Label::RejectedFrequency { change, threshold } => {
                    Rejected(Rejection::Frequency { change, threshold })
                }
                Label::RejectedReal { change, threshold } => {
                    Rejected(Rejection::RealPole { change, threshold })
                }
            }
        }
    }
}

/// One pole of one model order.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Pole {
    /// Continuous-time pole λ (rad/s); for a pair, the member with Im λ > 0.
    pub lambda: C64,
    /// Natural frequency |λ|/2π (Hz).
    pub frequency_hz: f64,
    /// Damping ratio −Re λ/|λ| (1 for a real negative pole).
    pub damping_ratio: f64,
    /// Whether λ is real.
    pub is_real: bool,
    /// Mode shape Cψ (one entry per channel).
    pub shape: Vec<C64>,
    /// Relative frequency change from the nearest pole of the previous order.
    pub d_frequency: Option<f64>,
    /// Relative damping change.
    pub d_damping: Option<f64>,
    /// 1 − MAC with that pole's shape (several channels).
    pub d_mac: Option<f64>,
    /// Eq. (31) change for a real pole.
    pub d_real: Option<f64>,
    /// The label (in JSON: `label`, its [`PoleStatus::name`], beside the pole's other fields,
    /// with the values behind a rejection).
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub status: PoleStatus,
    /// Whether the discrete eigenvalue was negative real (Nyquist); used while labelling.
    #[cfg_attr(feature = "serde", serde(skip))]
    negative_real: bool,
}

impl Pole {
    pub(crate) fn new(mu: C64, fs: f64, shape: Vec<C64>) -> Pole {
        let is_real = mu.im == 0.0;
        let negative_real = is_real && mu.re <= 0.0;
        let lambda = if is_real && !negative_real {
            C64::new(mu.re.ln() * fs, 0.0)
        } else {
            mu.ln() * fs
        };
        let w = lambda.norm();
        Pole {
            lambda,
            frequency_hz: w / (2.0 * std::f64::consts::PI),
            damping_ratio: if w > 0.0 { -lambda.re / w } else { 0.0 },
            is_real: is_real && !negative_real,
            shape,
            d_frequency: None,
            d_damping: None,
            d_mac: None,
            d_real: None,
            status: PoleStatus::Rejected(Rejection::NoPrevious),
            negative_real,
        }
    }
}

pub(crate) fn rel(a: f64, b: f64) -> f64 {
    let m = a.abs().max(b.abs());
    if m == 0.0 { 0.0 } else { (a - b).abs() / m }
}

/// Modal assurance criterion of two complex shapes,
/// $\text{MAC}(a, b) = |a^{\mathsf H} b|^2 / (a^{\mathsf H} a \; b^{\mathsf H} b)$: 1 when one
/// is a complex multiple of the other, 0 when they are orthogonal; 0 if either is zero.
/// Shapes of one channel are numbers, so their MAC is always 1.
pub fn mac(a: &[C64], b: &[C64]) -> f64 {
    let num: C64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let da: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let db: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if da == 0.0 || db == 0.0 {
        0.0
    } else {
        num.norm_sqr() / (da * db)
    }
}

/// Modal phase collinearity of a complex shape $\varphi = x + \mathrm i y$: how close its
/// entries lie to one line through the origin of the complex plane, as they do for a real
/// (normal) mode under any complex scale. With $S_{xx} = x^\top x$, $S_{yy} = y^\top y$,
/// $S_{xy} = x^\top y$, the eigenvalues $\sigma_1 \ge \sigma_2$ of
/// $\begin{pmatrix} S_{xx} & S_{xy} \\ S_{xy} & S_{yy} \end{pmatrix}$ give
/// $\text{MPC} = ((\sigma_1 - \sigma_2)/(\sigma_1 + \sigma_2))^2
/// = ((S_{xx} - S_{yy})^2 + 4 S_{xy}^2)/(S_{xx} + S_{yy})^2$: 1 for a normal mode, 0 when the
/// entries spread evenly in phase (e.g. $(1, \mathrm i)$). A shape of one channel always has
/// MPC 1, so it tells nothing there; 0 for a zero shape.
pub fn mpc(shape: &[C64]) -> f64 {
    let (sxx, syy, sxy) = phase_moments(shape);
    let total = sxx + syy;
    if total == 0.0 {
        return 0.0;
    }
    ((sxx - syy).powi(2) + 4.0 * sxy * sxy) / (total * total)
}

/// Mean phase deviation of a complex shape (degrees): the entries' angles from the shape's
/// mean phase line (the principal direction of their points in the complex plane, at angle
/// $\theta = \tfrac12 \operatorname{atan2}(2S_{xy}, S_{xx} - S_{yy})$ with the sums of
/// [`mpc`]), each weighted by its magnitude: $\text{MPD} = \sum_j |\varphi_j|
/// \arccos\big(|x_j\cos\theta + y_j\sin\theta| / |\varphi_j|\big) / \sum_j |\varphi_j|$
/// (Reynders, Houbrechts and De Roeck 2012). 0 for a normal mode; entries of equal
/// magnitude at phases $\alpha \pm \delta$ give $\delta$; 0 for a zero shape.
pub fn mpd(shape: &[C64]) -> f64 {
    let (sxx, syy, sxy) = phase_moments(shape);
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let (c, s) = (theta.cos(), theta.sin());
    let (weighted, total) = shape.iter().fold((0.0, 0.0), |(w, t), v| {
        let m = v.norm();
        if m == 0.0 {
            return (w, t);
        }
        // The angle from the line, as atan2 of the parts across and along it (exact near
        // 0, where arccos of the cosine loses half the digits).
        let along = (v.re * c + v.im * s).abs();
        let across = (v.im * c - v.re * s).abs();
        (w + m * across.atan2(along), t + m)
    });
    if total == 0.0 {
        0.0
    } else {
        (weighted / total).to_degrees()
    }
}

/// The sums $S_{xx} = x^\top x$, $S_{yy} = y^\top y$, $S_{xy} = x^\top y$ of a shape
/// $x + \mathrm i y$ that [`mpc`] and [`mpd`] read.
fn phase_moments(shape: &[C64]) -> (f64, f64, f64) {
    shape.iter().fold((0.0, 0.0, 0.0), |(xx, yy, xy), v| {
        (xx + v.re * v.re, yy + v.im * v.im, xy + v.re * v.im)
    })
}

fn hard_rejection(p: &Pole, opts: &SsiOptions) -> Option<Rejection> {
    if p.negative_real {
        return Some(Rejection::NegativeRealEigenvalue);
    }
    if p.lambda.re >= 0.0 {
        return Some(Rejection::Unstable {
            real_part: p.lambda.re,
        });
    }
    if !p.is_real && p.damping_ratio > opts.max_damping {
        return Some(Rejection::DampingAboveLimit {
            damping: p.damping_ratio,
            limit: opts.max_damping,
        });
    }
    None
}

/// Label every pole against the nearest pole of the same kind at the previous order.
pub(crate) fn label(d: &mut StabilizationDiagram, opts: &SsiOptions) {
    let c = &opts.criteria;
    let multi = d.channels > 1;
    for o in 0..d.orders.len() {
        let (prev, cur) = d.orders.split_at_mut(o);
        for p in cur[0].poles.iter_mut() {
            if let Some(r) = hard_rejection(p, opts) {
                p.status = PoleStatus::Rejected(r);
                continue;
            }
            // The nearest previous order that has poles of the same kind, looking back at most
            // two orders: with an order step of 1, a lone real pole appears only at every
            // other order (complex poles come in pairs).
            let candidates = prev
                .iter()
                .rev()
                .take(2)
                .map(|po| {
                    po.poles
                        .iter()
                        .filter(|q| q.is_real == p.is_real && hard_rejection(q, opts).is_none())
                        .collect::<Vec<_>>()
                })
                .find(|c| !c.is_empty())
                .unwrap_or_default();
            let nearest = candidates.iter().min_by(|a, b| {
                (a.frequency_hz - p.frequency_hz)
                    .abs()
                    .total_cmp(&(b.frequency_hz - p.frequency_hz).abs())
            });
            let Some(q) = nearest else {
                p.status = PoleStatus::Rejected(Rejection::NoPrevious);
                continue;
            };
            if p.is_real {
                // Eq. (31) as printed, |λ_h − λ_j| / max(λ_h, λ_j): for negative real poles the
                // max is the one nearer zero, i.e. the smaller magnitude.
                let dr = (p.lambda.re - q.lambda.re).abs()
                    / p.lambda
                        .re
                        .abs()
                        .min(q.lambda.re.abs())
                        .max(f64::MIN_POSITIVE);
                p.d_real = Some(dr);
                p.d_frequency = Some(rel(p.frequency_hz, q.frequency_hz));
                p.status = if dr <= c.real {
                    PoleStatus::Stable(Stability::Real)
                } else {
                    PoleStatus::Rejected(Rejection::RealPole {
                        change: dr,
                        threshold: c.real,
                    })
                };
                continue;
            }
            let df = rel(p.frequency_hz, q.frequency_hz);
            let dz = rel(p.damping_ratio, q.damping_ratio);
            p.d_frequency = Some(df);
            p.d_damping = Some(dz);
            if multi {
                p.d_mac = Some(1.0 - mac(&p.shape, &q.shape));
            }
            p.status = if df > c.frequency {
                PoleStatus::Rejected(Rejection::Frequency {
                    change: df,
                    threshold: c.frequency,
                })
            } else if dz > c.damping {
                PoleStatus::Stable(Stability::Frequency)
            } else if !multi {
                PoleStatus::Stable(Stability::FrequencyDamping)
            } else if p.d_mac.unwrap_or(1.0) <= c.mac {
                PoleStatus::Stable(Stability::FrequencyDampingShape)
            } else {
                PoleStatus::Stable(Stability::FrequencyDamping)
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// MPD against its definition's closed forms: 0 for a real shape under any complex
    /// scale, δ for entries of equal magnitude at phases α ± δ, 45° for (1, i) (the phases
    /// spread evenly), a magnitude-weighted mean otherwise, 0 for a zero shape; and MPC 1 and
    /// less alongside.
    #[test]
    fn mean_phase_deviation_reads_the_phases_spread() {
        let polar = |m: f64, deg: f64| C64::from_polar(m, deg.to_radians());
        let real: Vec<C64> = [1.0, -0.5, 0.25]
            .iter()
            .map(|&v| polar(v, 0.0) * polar(1.3, 37.0))
            .collect();
        assert!(mpd(&real) < 1e-12, "{}", mpd(&real));
        assert!((mpc(&real) - 1.0).abs() < 1e-12);
        for (alpha, delta) in [(30.0, 10.0), (-120.0, 3.0), (80.0, 25.0)] {
            let spread = [polar(2.0, alpha + delta), polar(2.0, alpha - delta)];
            assert!((mpd(&spread) - delta).abs() < 1e-9, "{alpha} {delta}");
            // With an entry on the line the mean halves (weights 2, 2 and 4).
            let third = [spread[0], spread[1], polar(4.0, alpha + 180.0)];
            assert!((mpd(&third) - delta / 2.0).abs() < 1e-9, "{alpha} {delta}");
        }
        let even = [C64::new(1.0, 0.0), C64::new(0.0, 1.0)];
        assert!((mpd(&even) - 45.0).abs() < 1e-9);
        assert_eq!(mpd(&[C64::new(0.0, 0.0); 3]), 0.0);
    }
}
