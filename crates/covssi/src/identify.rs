//! SSI itself: the channels checked, their correlations, the block Toeplitz matrix and its
//! SVD, the poles of every order, labelled and clustered into modes.

use crate::checks::{check_channels, check_fs, check_options};
use crate::linalg::{self, C64, Dense};
use crate::progress::Progress;
use crate::{
    AutoLag, Correlations, Mode, Pole, RealPoleCluster, RecordSurvey, SsiError, SsiOption,
    SsiOptions, Stability, corr, stabilize,
};
use rayon::prelude::*;

/// The poles of one model order.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OrderPoles {
    /// Model order n (size of A).
    pub order: usize,
    /// Poles: one per complex-conjugate pair (positive imaginary part) and every real pole.
    pub poles: Vec<Pole>,
}

/// An estimate of the output spectrum, drawn behind the stabilization diagram.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Spectrum {
    /// Frequencies (Hz).
    pub frequencies_hz: Vec<f64>,
    /// First singular value of the output spectral matrix (the PSD for one channel), from the
    /// correlations with a Hann lag window.
    pub first_singular_value: Vec<f64>,
}

/// Poles over model order with their labels, and the spectrum behind them.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct StabilizationDiagram {
    /// Orders in increasing order.
    pub orders: Vec<OrderPoles>,
    /// Output spectrum.
    pub spectrum: Spectrum,
    /// Sampling rate (Hz).
    pub fs: f64,
    /// Number of channels.
    pub channels: usize,
}

impl StabilizationDiagram {
    /// The label a pole needs to count as fully stable and join a [`Mode`]: stable in
    /// frequency, damping and shape with several channels, in frequency and damping with one.
    pub fn full_stability(&self) -> Stability {
        if self.channels > 1 {
            Stability::FrequencyDampingShape
        } else {
            Stability::FrequencyDamping
        }
    }
}

/// Everything [`identify`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SsiResult {
    /// Block rows used.
    pub block_rows: usize,
    /// Singular values of the Toeplitz matrix: all of them when it is stored, the leading
    /// ones (as many as the largest order asks for, and as many again) when it is large
    /// enough to be applied by FFT.
    pub singular_values: Vec<f64>,
    /// The stabilization diagram.
    pub diagram: StabilizationDiagram,
    /// Modes (clusters of fully stable oscillating poles), by increasing frequency.
    pub modes: Vec<Mode>,
    /// Clusters of stable real poles, by increasing magnitude.
    pub real_poles: Vec<RealPoleCluster>,
    /// Remarks, e.g. why no mode was found, or a lag shorter than a mode's period.
    pub notes: Vec<String>,
    /// How the block rows were read from the record ([`crate::BlockRows::Auto`]); `None`
    /// when the options gave them.
    pub auto_lag: Option<AutoLag>,
    /// The record's survey, when the options left anything to it.
    pub survey: Option<RecordSurvey>,
    /// The reference channels the correlations were taken against (indices).
    #[cfg_attr(feature = "serde", serde(default))]
    pub references: Vec<usize>,
    /// When the options named none and the record has many channels: the references chosen
    /// from it ([`crate::references`]).
    #[cfg_attr(feature = "serde", serde(default))]
    pub chosen_references: Option<crate::references::ChosenReferences>,
}

pub(crate) fn references(opts: &SsiOptions, l: usize) -> Result<Vec<usize>, SsiError> {
    match &opts.references {
        None => Ok((0..l).collect()),
        Some(r) => {
            if r.is_empty() {
                return Err(SsiError::InvalidOption {
                    option: SsiOption::ReferencesEmpty,
                    value: 0.0,
                });
            }
            if let Some(&bad) = r.iter().find(|&&b| b >= l) {
                return Err(SsiError::InvalidOption {
                    option: SsiOption::ReferenceOutOfRange,
                    value: bad as f64,
                });
            }
            if let Some((_, &twice)) = r.iter().enumerate().find(|(k, b)| r[..*k].contains(b)) {
                return Err(SsiError::InvalidOption {
                    option: SsiOption::ReferenceRepeated,
                    value: twice as f64,
                });
            }
            Ok(r.clone())
        }
    }
}

/// The smallest largest lag-0 correlation (a variance, for one channel) SSI works with:
/// below it the correlations are too close to the smallest normal double (2.2e-308) for
/// their lags to keep their precision, and [`SsiError::OutOfRange`] asks for other units.
pub const MIN_CORRELATION: f64 = 1e-290;

/// Identify modes from the output channels `y` (equal lengths) sampled at `fs` Hz.
///
/// The channels' means are removed first.
pub fn identify(y: &[&[f64]], fs: f64, opts: &SsiOptions) -> Result<SsiResult, SsiError> {
    identify_surveyed(y, fs, opts, None, &|_| {})
}

/// The block rows and reference channels SSI uses on a record, and, when read from the
/// record, its survey and how the lag was chosen.
pub(crate) struct LagChoice {
    /// Block rows.
    pub(crate) block_rows: usize,
    /// Reference channels (indices).
    pub(crate) references: Vec<usize>,
    /// With [`crate::BlockRows::Auto`]: the survey and the lag it gave.
    pub(crate) auto: Option<(RecordSurvey, AutoLag)>,
    /// The references, when chosen from the record.
    pub(crate) chosen: Option<crate::references::ChosenReferences>,
}

/// Most correlation values (channels × references × lags) SSI takes against every channel
/// when the options name no references: 2²⁰ (8 MB), past which a record with more than
/// [`crate::references::MAX_REFERENCES`] channels has its references chosen from it
/// ([`crate::references`]). The FFT-applied Toeplitz matrix costs that many complex
/// products per vector; 24 channels at 250 block rows (a bridge's 0.2 Hz mode at 10 Hz)
/// stay within it, 66 at 500 do not.
pub const MAX_ALL_REFERENCE_ENTRIES: usize = 1 << 20;

/// The block rows `opts` give for the checked channels `y` (`n` samples each, of means
/// `means`) at `fs` Hz, with the reference channels; read from the record
/// ([`crate::BlockRows::Auto`]: from `known`, its survey when the caller has it, else surveyed
/// here), with that survey and how the lag was chosen.
pub(crate) fn block_rows_for(
    y: &[&[f64]],
    fs: f64,
    (n, means): (usize, &[f64]),
    opts: &SsiOptions,
    known: Option<RecordSurvey>,
) -> Result<LagChoice, SsiError> {
    let mut references = references(opts, y.len())?;
    let mut survey = known;
    let mut surveyed = || {
        survey
            .get_or_insert_with(|| crate::survey::surveyed(y, fs, means, n))
            .clone()
    };
    let (block_rows, lag) = match opts.block_rows.resolve(fs)? {
        Some(block_rows) => (block_rows, None),
        None => {
            let (block_rows, lag) = surveyed().block_rows(n, y.len(), references.len());
            (block_rows, Some(lag))
        }
    };
    let l = y.len();
    let many = l > crate::references::MAX_REFERENCES
        && l.saturating_mul(l).saturating_mul(2 * block_rows) > MAX_ALL_REFERENCE_ENTRIES;
    let chosen = (opts.references.is_none() && many).then(|| {
        let s = surveyed();
        crate::references::choose(y, means, fs, &s.peaks_hz)
    });
    if let Some(c) = &chosen {
        references = c.channels.clone();
    }
    let auto = match (lag, survey) {
        (Some(lag), Some(s)) => Some((s, lag)),
        _ => None,
    };
    Ok(LagChoice {
        block_rows,
        references,
        auto,
        chosen,
    })
}

/// [`identify`], with the record's survey when the caller has made it (not made again),
/// telling `progress` of each step: the correlations, the SVD, then each model order as it
/// is done (from rayon's threads); [`SSI_STEPS_BEFORE_ORDERS`] steps before the orders.
pub(crate) fn identify_surveyed(
    y: &[&[f64]],
    fs: f64,
    opts: &SsiOptions,
    known: Option<RecordSurvey>,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<SsiResult, SsiError> {
    identify_surveyed_with_basis(y, fs, opts, known, progress).map(|(r, _)| r)
}

/// [`identify_surveyed`], with the Toeplitz matrix's leading left singular vectors
/// ([`identify_with_basis`]): the jackknife's replicates start from them.
pub(crate) fn identify_surveyed_with_basis(
    y: &[&[f64]],
    fs: f64,
    opts: &SsiOptions,
    known: Option<RecordSurvey>,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(SsiResult, Dense), SsiError> {
    check_fs(fs)?;
    let (n, means) = check_channels(y)?;
    let LagChoice {
        block_rows: i,
        references: refs,
        auto,
        chosen,
    } = block_rows_for(y, fs, (n, &means), opts, known)?;
    // 2i lags (0 … 2i − 1) need 2i + 1 samples; saturating, so that a count too large for
    // any record (a lag time of years) is reported as too short rather than wrapping round.
    let lags = i.saturating_mul(2);
    if n < lags.saturating_add(1) {
        return Err(SsiError::TooShort {
            samples: n,
            block_rows: i,
            lags: lags - 1,
            needed: lags.saturating_add(1),
        });
    }
    let what = format!(
        "SSI: correlations of {} channel(s) up to lag {}",
        y.len(),
        lags - 1
    );
    progress(Progress {
        done: 0,
        total: SSI_STEPS_BEFORE_ORDERS,
        what: &what,
    });
    let corr = corr::estimate_centred(y, &refs, lags, &means);
    let cap = auto
        .as_ref()
        .map_or(DEFAULT_ORDER_CAP, |(survey, _)| survey.max_order());
    let (mut res, basis) = identify_with_basis(
        &corr,
        fs,
        i,
        opts,
        (cap, None, Run::Record(&refs)),
        progress,
    )?;
    if let Some((survey, lag)) = auto {
        res.auto_lag = Some(lag);
        res.survey = Some(survey);
    }
    res.references = refs;
    res.chosen_references = chosen;
    Ok((res, basis))
}

/// Identify from given correlations (at least `2·block_rows` lags), e.g. exact ones.
pub fn identify_from_correlations(
    corr: &Correlations,
    fs: f64,
    block_rows: usize,
    opts: &SsiOptions,
) -> Result<SsiResult, SsiError> {
    identify_with_order_cap(corr, fs, block_rows, opts, DEFAULT_ORDER_CAP, &|_| {})
}

/// The largest model order when neither the options nor the record's survey set it.
const DEFAULT_ORDER_CAP: usize = 40;

/// Steps of SSI before its model orders: the correlations and the SVD.
pub(crate) const SSI_STEPS_BEFORE_ORDERS: usize = 2;

/// What [`identify_with_basis`] runs on: a record, whose result is reported, or a jackknife
/// replicate of one, of which only the modes are used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Run<'a> {
    /// A record whose correlations are against these channels (for its spectrum).
    Record(&'a [usize]),
    Replicate,
}

/// [`identify_from_correlations`], the largest order at most `order_cap` when the options
/// leave it open, telling `progress` of the SVD and of each order done.
pub(crate) fn identify_with_order_cap(
    corr: &Correlations,
    fs: f64,
    block_rows: usize,
    opts: &SsiOptions,
    order_cap: usize,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<SsiResult, SsiError> {
    // The references' rows are not known here: the first channels stand in.
    let rows: Vec<usize> = (0..corr.channels.min(corr.references)).collect();
    identify_with_basis(
        corr,
        fs,
        block_rows,
        opts,
        (order_cap, None, Run::Record(&rows)),
        progress,
    )
    .map(|(r, _)| r)
}

/// Sweeps of subspace iteration a replicate's SVD may take from the record's basis before
/// the full SVD is taken instead (a few reach [`NEAR_TOLERANCE`] on the replicates of
/// `jackknife::tests::replicates_from_the_records_basis_give_the_full_svds_errors`, a
/// record shaped as the steel frame's setups).
const NEAR_SWEEPS: usize = 16;

/// Each of a replicate's leading singular triplets is accepted from the record's basis when
/// its residual ‖T v − σ u‖ is within this fraction of σ₁: exact for a Toeplitz matrix that
/// differs from the replicate's by about 10⁻¹¹ of its norm, less than rounding the
/// correlations to ten significant digits and far below their estimation error (1/√N,
/// 10⁻³ to 10⁻² for records of 10⁴ to 10⁶ samples).
const NEAR_TOLERANCE: f64 = 1e-12;

/// [`identify_with_order_cap`] (`cap.0` the order cap), with `cap.1` the leading left
/// singular vectors of a Toeplitz matrix near this one's (the record's, for a jackknife
/// replicate of it, whose order the options fix): the SVD is then found by subspace
/// iteration from them ([`linalg::leading_svd_near`]), the full SVD only if that does not
/// converge. Returns also this Toeplitz matrix's leading left singular vectors, as many as
/// [`basis_width`] asks for the largest order, to start its replicates from.
pub(crate) fn identify_with_basis(
    corr: &Correlations,
    fs: f64,
    block_rows: usize,
    opts: &SsiOptions,
    (order_cap, near, run): (usize, Option<&Dense>, Run<'_>),
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(SsiResult, Dense), SsiError> {
    check_fs(fs)?;
    let i = block_rows;
    let (l, r) = check_correlations(corr, i)?;
    check_options(opts)?;
    let (rows, cols) = (l * i, r * i);
    let what = format!("SSI: SVD of the {rows}×{cols} block Toeplitz matrix");
    progress(Progress {
        done: 1,
        total: SSI_STEPS_BEFORE_ORDERS,
        what: &what,
    });
    let wanted = opts.max_order.unwrap_or(order_cap);
    let sweep_what = |sweep: usize| {
        let what = format!(
            "SSI: leading singular triplets of the {rows}×{cols} block Toeplitz matrix, sweep {sweep}"
        );
        progress(Progress {
            done: 1,
            total: SSI_STEPS_BEFORE_ORDERS,
            what: &what,
        })
    };
    let (u, s, svd_note) = toeplitz_svd(corr, i, (near.zip(opts.max_order), wanted), &sweep_what)?;
    let s0 = s.first().copied().unwrap_or(0.0);
    let rank = s.iter().filter(|&&v| v > s0 * 1e-12).count();
    let max_order = match opts.max_order {
        Some(m) => m,
        None => rank.min(order_cap),
    };
    if max_order > rank || max_order == 0 {
        return Err(SsiError::OrderAboveRank {
            order: max_order,
            rank,
            rows,
            cols,
        });
    }
    let up_rows = l * (i - 1);
    let (q, rr) = shift_qr(&u, up_rows, max_order).map_err(|c| SsiError::OrderAboveRank {
        order: c + 1,
        rank: c,
        rows,
        cols,
    })?;
    // M = Qᵀ U_down.
    let mut m = Dense::zeros(max_order, max_order);
    for a in 0..max_order {
        for b in 0..max_order {
            let d: f64 = (0..up_rows)
                .map(|row| q.at(row, a) * u.at(row + l, b))
                .sum();
            m.set(a, b, d);
        }
    }
    let orders = poles_by_order(max_order, (&m, &rr, &u), l, fs, opts.order_step, progress)?;
    let basis = linalg::leading_columns(&u, basis_width(max_order));
    // A replicate's modes alone are used (for their errors): the spectrum behind its
    // diagram would be drawn for no one (5 % of the steel frame's setups' time without the
    // refinement: 4.65 → 4.42 s).
    let spectrum = match run {
        Run::Record(rows) => spectrum_from_correlations(corr, fs, rows),
        Run::Replicate => Spectrum::default(),
    };
    let mut diagram = StabilizationDiagram {
        orders,
        spectrum,
        fs,
        channels: l,
    };
    stabilize::label(&mut diagram, opts);
    let (modes, real_poles, mut notes) = crate::cluster::cluster(&diagram, opts);
    notes.extend(svd_note);
    notes.extend(lag_notes(&modes, i, fs));
    let result = SsiResult {
        block_rows: i,
        singular_values: s,
        diagram,
        modes,
        real_poles,
        notes,
        auto_lag: None,
        survey: None,
        references: (0..r).collect(),
        chosen_references: None,
    };
    Ok((result, basis))
}

/// The poles of every order `order_step, 2·order_step, …, max_order` from the shift
/// equation's `(M, R, U)`. Orders are independent: in parallel (rayon; faer
/// single-threaded inside), collected in order, so the result does not depend on the
/// thread count.
fn poles_by_order(
    max_order: usize,
    (m, rr, u): (&Dense, &Dense, &Dense),
    l: usize,
    fs: f64,
    order_step: usize,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Vec<OrderPoles>, SsiError> {
    let order_list: Vec<usize> = (1..=max_order / order_step)
        .map(|k| k * order_step)
        .collect();
    let total = SSI_STEPS_BEFORE_ORDERS + order_list.len();
    let what = format!("SSI: poles of 0 of {} model orders", order_list.len());
    progress(Progress {
        done: SSI_STEPS_BEFORE_ORDERS,
        total,
        what: &what,
    });
    let finished = std::sync::atomic::AtomicUsize::new(0);
    order_list
        .par_iter()
        .map(|&order| {
            let poles = order_poles(order, m, rr, u, l, fs);
            let done = 1 + finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let what = format!("SSI: poles of {done} of {} model orders", order_list.len());
            progress(Progress {
                done: SSI_STEPS_BEFORE_ORDERS + done,
                total,
                what: &what,
            });
            poles
        })
        .collect::<Result<Vec<OrderPoles>, SsiError>>()
}

/// How many leading left singular vectors start a replicate's SVD whose largest order is
/// `order`: as many again as the order (at least 20), the margin that lets subspace
/// iteration converge in a few sweeps.
pub(crate) fn basis_width(order: usize) -> usize {
    order + order.max(20)
}

/// A note for each mode whose period is longer than the largest lag 2i − 1: its
/// correlation is seen over less than one period, and its estimate is biased (a damping of
/// several percent where the record's is a fraction of one).
fn lag_notes(modes: &[Mode], i: usize, fs: f64) -> Vec<String> {
    let lag_s = (2 * i - 1) as f64 / fs;
    modes
        .iter()
        .filter(|m| m.frequency_hz * lag_s < 1.0)
        .map(|m| {
            format!(
                "the largest lag ({lag_s:.3} s) is shorter than one period of the mode at {:.4} Hz ({:.3} s): its estimate is not to be trusted; give a lag of several periods (ten: {:.1} s)",
                m.frequency_hz,
                1.0 / m.frequency_hz,
                crate::survey::LAG_PERIODS / m.frequency_hz
            )
        })
        .collect()
}

/// The correlations' channels and references, when they hold `2·i` lags of that shape and
/// are finite.
fn check_correlations(corr: &Correlations, i: usize) -> Result<(usize, usize), SsiError> {
    let (l, r) = (corr.channels, corr.references);
    if l == 0 || r == 0 {
        return Err(SsiError::NoChannels);
    }
    if let Some((lag, m)) = corr
        .r
        .iter()
        .enumerate()
        .find(|(_, m)| m.len() != l.saturating_mul(r))
    {
        return Err(SsiError::CorrelationShape {
            lag,
            len: m.len(),
            channels: l,
            references: r,
        });
    }
    if i < 2 || corr.r.len() < i.saturating_mul(2) {
        return Err(SsiError::InvalidOption {
            option: SsiOption::BlockRowsLags,
            value: i as f64,
        });
    }
    if let Some(&value) = corr.r.iter().flatten().find(|v| !v.is_finite()) {
        return Err(SsiError::OutOfRange { value });
    }
    let peak = corr.r[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if peak < MIN_CORRELATION {
        return Err(SsiError::OutOfRange { value: peak });
    }
    Ok((l, r))
}

/// Residual of the iterated SVD's triplets (a share of σ₁) at which they are taken:
/// far below the correlations' estimation error (1/√N, 10⁻³ to 10⁻² for records of 10⁴ to
/// 10⁶ samples); a matrix that does not reach it in [`ITERATED_SWEEPS`] is said in a note.
const ITERATED_TOLERANCE: f64 = 1e-9;

/// Most sweeps of the iterated SVD; past them its triplets are used with a note.
const ITERATED_SWEEPS: usize = 200;

/// The left singular vectors and singular values of the block Toeplitz matrix of `i`
/// block rows, and a note when they are approximate. A stored matrix
/// ([`crate::toeplitz::MAX_STORED_ENTRIES`]) has its full SVD, or with `near` (a basis
/// and the order) its leading triplets from that basis when they converge
/// ([`linalg::leading_svd_near`]); a larger one is applied by FFT and only its leading
/// triplets are found, by subspace iteration from `near`'s basis or from a random block as
/// wide as [`basis_width`] asks for the `wanted` order ([`linalg::leading_svd_iterated`]),
/// `on_sweep` hearing each sweep.
fn toeplitz_svd(
    corr: &Correlations,
    i: usize,
    (near, wanted): (Option<(&Dense, usize)>, usize),
    on_sweep: &dyn Fn(usize),
) -> Result<(Dense, Vec<f64>, Option<String>), SsiError> {
    // The SVD loses accuracy, or fails, on entries near the ends of the double range (a record
    // in units that make its values 1e100 or 1e-100), so T is built from the correlations
    // times the power of two that brings their largest lag-0 value near 1: exact in floating
    // point, so the poles and shapes are those of the correlations as given.
    let peak = corr.r[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let scale = 2f64.powi(-(peak.log2().round() as i32));
    let (u, mut s, note) = match crate::toeplitz::Toeplitz::new(corr, i, scale) {
        crate::toeplitz::Toeplitz::Stored(t) => {
            let warm = match near {
                Some((start, order)) => {
                    linalg::leading_svd_near(&t, start, order, (NEAR_TOLERANCE, NEAR_SWEEPS))
                        .map_err(SsiError::LinearAlgebra)?
                }
                None => None,
            };
            let (u, s) = match warm {
                Some(found) => found,
                None => linalg::thin_svd_u(&t).map_err(SsiError::LinearAlgebra)?,
            };
            (u, s, None)
        }
        crate::toeplitz::Toeplitz::Applied(t) => {
            use linalg::Operator;
            let (start, k) = match near {
                Some((basis, order)) => (basis.clone(), order),
                None => {
                    let width = basis_width(wanted).min(t.rows().min(t.cols()));
                    (
                        crate::toeplitz::gaussian_start(t.rows(), width, 0x5551),
                        wanted,
                    )
                }
            };
            let k = k.min(start.cols.saturating_sub(1)).max(1);
            let found = linalg::leading_svd_iterated(
                &t,
                start,
                k,
                (ITERATED_TOLERANCE, ITERATED_SWEEPS),
                on_sweep,
            )
            .map_err(SsiError::LinearAlgebra)?;
            let note = (!found.converged).then(|| {
                format!(
                    "the leading {k} singular triplets of the {}×{} block Toeplitz matrix did not converge in {} sweeps (residual {:.1e} of σ₁): its poles are those of a nearby matrix",
                    t.rows(),
                    t.cols(),
                    found.sweeps,
                    found.residual
                )
            });
            (found.u, found.values, note)
        }
    };
    for v in &mut s {
        *v /= scale;
    }
    Ok((u, s, note))
}

/// QR of the first `up_rows` rows of `u`'s first `max_order` columns by modified
/// Gram–Schmidt, twice; the index of the first column that depends on the others, if one
/// does.
fn shift_qr(u: &Dense, up_rows: usize, max_order: usize) -> Result<(Dense, Dense), usize> {
    // QR of the upper part of U (all max_order columns) by modified Gram–Schmidt, twice.
    let mut q = Dense::zeros(up_rows, max_order);
    let mut rr = Dense::zeros(max_order, max_order);
    for c in 0..max_order {
        let mut v: Vec<f64> = (0..up_rows).map(|row| u.at(row, c)).collect();
        for _pass in 0..2 {
            for k in 0..c {
                let d: f64 = (0..up_rows).map(|row| q.at(row, k) * v[row]).sum();
                rr.set(k, c, rr.at(k, c) + d);
                for (row, vr) in v.iter_mut().enumerate() {
                    *vr -= d * q.at(row, k);
                }
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm == 0.0 {
            return Err(c);
        }
        rr.set(c, c, norm);
        for (row, vr) in v.iter().enumerate() {
            q.set(row, c, vr / norm);
        }
    }
    Ok((q, rr))
}

/// The poles of model order `order`: B = R_n⁻¹ M_n (similar to A_n), its eigenvalues, and
/// with several channels the shapes U_top ψ_B.
fn order_poles(
    order: usize,
    m: &Dense,
    rr: &Dense,
    u: &Dense,
    l: usize,
    fs: f64,
) -> Result<OrderPoles, SsiError> {
    // B = R_n⁻¹ M_n is similar to A_n = S^{-1/2} B S^{1/2}; shapes are U_top ψ_B.
    let mut bmat = Dense::zeros(order, order);
    for col in 0..order {
        for row in (0..order).rev() {
            let mut v = m.at(row, col);
            for k in row + 1..order {
                v -= rr.at(row, k) * bmat.at(k, col);
            }
            bmat.set(row, col, v / rr.at(row, row));
        }
    }
    let mut poles = Vec::new();
    if l == 1 {
        // One channel: the shape is the single entry 1; eigenvalues suffice.
        let mu = linalg::eigenvalues(&bmat).map_err(SsiError::LinearAlgebra)?;
        for muj in mu.iter().filter(|m| m.im >= 0.0) {
            poles.push(stabilize::Pole::new(*muj, fs, vec![C64::new(1.0, 0.0)]));
        }
    } else {
        let (mu, vecs) = linalg::eigen(&bmat).map_err(SsiError::LinearAlgebra)?;
        for (j, muj) in mu.iter().enumerate() {
            if muj.im < 0.0 {
                continue; // the conjugate partner is kept
            }
            let shape: Vec<C64> = (0..l)
                .map(|a| (0..order).map(|k| vecs[j * order + k] * u.at(a, k)).sum())
                .collect();
            poles.push(stabilize::Pole::new(*muj, fs, shape));
        }
    }
    Ok(OrderPoles { order, poles })
}

/// First singular value of the spectral matrix of the reference channels (`rows`, the
/// channels the references are, in the references' order), from the correlations with a
/// Hann lag window, at 256 frequencies from 0 to fs/2.
fn spectrum_from_correlations(corr: &Correlations, fs: f64, rows: &[usize]) -> Spectrum {
    use std::f64::consts::PI;
    let l = corr.channels;
    let d = rows.len().min(corr.references);
    let k_max = corr.r.len() - 1;
    let window: Vec<f64> = (0..=k_max)
        .map(|k| 0.5 * (1.0 + (PI * k as f64 / (k_max + 1) as f64).cos()))
        .collect();
    let npts = 256;
    let mut freqs = Vec::with_capacity(npts);
    let mut sv1 = Vec::with_capacity(npts);
    let mut s = vec![C64::new(0.0, 0.0); d * d];
    let (mut x, mut y) = (vec![C64::new(0.0, 0.0); d], vec![C64::new(0.0, 0.0); d]);
    for p in 0..npts {
        let f = fs / 2.0 * p as f64 / (npts - 1) as f64;
        let w = 2.0 * PI * f / fs;
        s.fill(C64::new(0.0, 0.0));
        // e^{−iωk} by rotation: its modulus drifts by about k ulps, nothing at these lags.
        let step = C64::from_polar(1.0, -w);
        let mut e = C64::new(1.0, 0.0);
        for (k, rk) in corr.r.iter().enumerate() {
            for (a, &row) in rows.iter().enumerate().take(d) {
                for b in 0..d {
                    let v = rk[row + b * l];
                    if k == 0 {
                        s[a + b * d] += v;
                    } else {
                        // R(−k) = R(k)ᵀ
                        s[a + b * d] += e * v * window[k];
                        s[b + a * d] += e.conj() * v * window[k];
                    }
                }
            }
            e *= step;
        }
        let lam = if d == 1 {
            s[0].norm()
        } else {
            // Largest singular value of the Hermitian matrix s: power iteration.
            x.fill(C64::new(1.0, 0.0));
            let mut lam = 0.0;
            for _ in 0..30 {
                for (a, ya) in y.iter_mut().enumerate() {
                    *ya = (0..d).map(|b| s[a + b * d] * x[b]).sum();
                }
                let norm = y.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
                if norm == 0.0 {
                    break;
                }
                lam = norm;
                for (xa, ya) in x.iter_mut().zip(&y) {
                    *xa = ya / norm;
                }
            }
            lam
        };
        freqs.push(f);
        sv1.push(lam / fs);
    }
    Spectrum {
        frequencies_hz: freqs,
        first_singular_value: sv1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn correlations(channels: usize, r: Vec<Vec<f64>>) -> Correlations {
        Correlations {
            channels,
            references: channels,
            r,
        }
    }

    /// White noise: R₀ = σ², Rₖ = 0, so the spectrum is σ²/fs at every frequency.
    #[test]
    fn spectrum_of_white_noise_is_flat() {
        let mut r = vec![vec![0.0]; 40];
        r[0][0] = 2.0;
        let sp = spectrum_from_correlations(&correlations(1, r), 50.0, &[0]);
        assert_eq!(sp.frequencies_hz.len(), 256);
        approx::assert_relative_eq!(sp.frequencies_hz[255], 25.0);
        for v in &sp.first_singular_value {
            // Only R₀ contributes: exact.
            approx::assert_relative_eq!(*v, 2.0 / 50.0, max_relative = 1e-15);
        }
    }

    /// Two uncorrelated white channels of variances 1 and 3: the spectral matrix is
    /// diag(1, 3)/fs and its first singular value 3/fs.
    #[test]
    fn first_singular_value_of_uncorrelated_channels_is_the_larger_variance() {
        let mut r = vec![vec![0.0; 4]; 20];
        r[0][0] = 1.0;
        r[0][3] = 3.0;
        let sp = spectrum_from_correlations(&correlations(2, r), 10.0, &[0, 1]);
        for v in &sp.first_singular_value {
            // Power iteration from (1, 1): the error falls as (1/3)^30, about 5e-15.
            approx::assert_relative_eq!(*v, 0.3, max_relative = 1e-12);
        }
    }

    /// Rₖ = cos(2π f₀ k / fs) (a sinusoid's correlation): the spectrum peaks at f₀.
    #[test]
    fn spectrum_of_a_sinusoid_peaks_at_its_frequency() {
        let (fs, f0) = (20.0, 4.0);
        let r: Vec<Vec<f64>> = (0..120)
            .map(|k| vec![(2.0 * std::f64::consts::PI * f0 * k as f64 / fs).cos()])
            .collect();
        let sp = spectrum_from_correlations(&correlations(1, r), fs, &[0]);
        let (imax, _) = sp
            .first_singular_value
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
        // The grid spacing is fs / 2 / 255.
        assert!((sp.frequencies_hz[imax] - f0).abs() <= fs / 2.0 / 255.0);
    }
}
