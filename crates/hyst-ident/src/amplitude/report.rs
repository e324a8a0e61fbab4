//! The whole job on one record ([`amplitude_analysis`]): the modes by [`covssi`], the
//! ones asked for followed, and the text `hyst amplitude` prints.

use std::fmt;

use super::{AmplitudeOptions, AmplitudeReport, ModeCurve, ModeToFollow};

/// What [`amplitude_analysis`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AmplitudeAnalysis {
    /// Where the modes followed came from: `"refined"` (covssi's maximum likelihood) or
    /// `"ssi"`.
    pub modes_from: String,
    /// Frequencies asked for that no identified mode lies within 5 % of (followed there,
    /// with every channel weighted alike).
    pub unidentified: Vec<f64>,
    /// Channels that look clipped (saturated): many samples at exactly their largest or
    /// smallest value. A clipped channel's large amplitudes are cut, and its curves there
    /// are not the structure's.
    #[cfg_attr(feature = "serde", serde(default))]
    pub clipped: Vec<ClippedChannel>,
    /// The curves.
    pub curves: AmplitudeReport,
}

/// Samples in a row at one extreme that only a held value makes.
pub const CLIP_RUN: usize = 3;

/// A channel that looks clipped.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ClippedChannel {
    /// The channel (0-based).
    pub channel: usize,
    /// Samples at exactly its extreme value.
    pub samples: usize,
    /// That value.
    pub value: f64,
}

/// Channels of `y` with more than `max(8, n/2000)` samples held at exactly their largest or
/// smallest value, in runs of at least [`CLIP_RUN`] samples: a saturated sensor or converter
/// holds its extreme, while a smooth signal passes its peak in at most two equal samples (a
/// periodic one reaches the same peak value every period, and is not clipped).
pub fn clipped_channels(y: &[&[f64]]) -> Vec<ClippedChannel> {
    let held = |c: &[f64], v: f64| {
        let mut total = 0;
        let mut run = 0;
        for &x in c.iter().chain(std::iter::once(&f64::NAN)) {
            if x == v {
                run += 1;
            } else {
                if run >= CLIP_RUN {
                    total += run;
                }
                run = 0;
            }
        }
        total
    };
    y.iter()
        .enumerate()
        .filter_map(|(channel, c)| {
            let hi = c.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let lo = c.iter().copied().fold(f64::INFINITY, f64::min);
            let limit = 8.max(c.len() / 2000);
            [hi, lo]
                .into_iter()
                .map(|v| (v, held(c, v)))
                .filter(|&(_, n)| n > limit)
                .max_by_key(|&(_, n)| n)
                .map(|(value, samples)| ClippedChannel {
                    channel,
                    samples,
                    value,
                })
        })
        .collect()
}

/// Identify `y`'s modes (`analysis`), then follow those nearest `follow` (Hz; every
/// reported mode when empty) through their amplitudes.
pub fn amplitude_analysis(
    y: &[&[f64]],
    fs: f64,
    analysis: &covssi::AnalysisOptions,
    opts: &AmplitudeOptions,
    follow: &[f64],
) -> Result<AmplitudeAnalysis, crate::IdentError> {
    opts.check()?;
    super::check_channels(y)?;
    // What the record can hold, before its modal analysis.
    super::within_record(y[0].len(), fs, &[], opts)?;
    let modal = covssi::analyze(y, fs, analysis)?;
    let reported = modal.reported_modes();
    let modes_from = if modal.reported_refinement().is_some() {
        "refined"
    } else {
        "ssi"
    };
    let as_follow = |m: &covssi::ReportedMode| ModeToFollow {
        frequency_hz: m.frequency_hz,
        damping_ratio: m.damping_ratio,
        shape: m.shape.clone(),
    };
    let identified: Vec<ModeToFollow> = reported.iter().map(as_follow).collect();
    let mut unidentified = Vec::new();
    let mut followed = Vec::new();
    let mut others: Vec<ModeToFollow> = Vec::new();
    if follow.is_empty() {
        followed = identified;
    } else {
        let mut taken = vec![false; identified.len()];
        for &f in follow {
            let near = (0..identified.len())
                .filter(|&i| (identified[i].frequency_hz - f).abs() <= 0.05 * f)
                .min_by(|&a, &b| {
                    (identified[a].frequency_hz - f)
                        .abs()
                        .total_cmp(&(identified[b].frequency_hz - f).abs())
                });
            match near {
                Some(i) => {
                    taken[i] = true;
                    followed.push(identified[i].clone());
                }
                None => {
                    unidentified.push(f);
                    followed.push(ModeToFollow {
                        frequency_hz: f,
                        damping_ratio: 0.01,
                        shape: None,
                    });
                }
            }
        }
        others.extend(
            (0..identified.len())
                .filter(|&i| !taken[i])
                .map(|i| identified[i].clone()),
        );
    }
    let curves = super::curves_judged(y, fs, (&followed, &others), opts, &analysis.modes)?;
    Ok(AmplitudeAnalysis {
        modes_from: modes_from.into(),
        unidentified,
        clipped: clipped_channels(y),
        curves,
    })
}

impl fmt::Display for AmplitudeAnalysis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "modes from {}, as `hyst ssi` reports them",
            if self.modes_from == "refined" {
                "the maximum-likelihood refinement"
            } else {
                "SSI"
            }
        )?;
        for c in &self.clipped {
            writeln!(
                f,
                "warning: channel {} looks clipped: {} samples at exactly {:e}; its largest amplitudes are cut, and the curves there are not the structure's",
                c.channel, c.samples, c.value
            )?;
        }
        for u in &self.unidentified {
            writeln!(
                f,
                "note: no identified mode within 5 % of {u} Hz: followed there with every channel weighted alike"
            )?;
        }
        if self.curves.modes.is_empty() {
            writeln!(
                f,
                "no mode found: the modal analysis reported none to follow (`hyst ssi` on the record lists what it set apart and why; --modes follows given frequencies)"
            )?;
        }
        self.curves.fmt(f)
    }
}

impl fmt::Display for AmplitudeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let unit = match (self.measured, self.amplitude_of) {
            (a, b) if a == b => format!("{}, in the record's unit", a.name()),
            (a, b) => format!(
                "{} from the measured {} (the record's unit × s^{})",
                b.name(),
                a.name(),
                a.order() - b.order()
            ),
        };
        writeln!(
            f,
            "amplitude: of each mode's coordinate ({unit}); ± one standard error (jackknife over stretches of the record)"
        )?;
        for c in &self.modes {
            c.fmt(f)?;
        }
        Ok(())
    }
}

impl fmt::Display for super::Linearity {
    /// The two changes with their errors and p-values, as the reports print them.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "frequency {:+.4} ± {:.4} Hz (p = {:.2e}), damping ratio {:+.3} ± {:.3} % (p = {:.2e})",
            self.frequency.change,
            self.frequency.change_se,
            self.frequency.p_value,
            100.0 * self.damping.change,
            100.0 * self.damping.change_se,
            self.damping.p_value
        )
    }
}

impl fmt::Display for ModeCurve {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "mode {:.4} Hz (damping ratio {:.2} %), filtered to {:.3}–{:.3} Hz:",
            self.mode.frequency_hz,
            100.0 * self.mode.damping_ratio,
            self.band_hz.0,
            self.band_hz.1
        )?;
        if !self.points.is_empty() {
            writeln!(
                f,
                "  {:>11}  {:>20}  {:>18}  {:>8}",
                "amplitude", "frequency (Hz)", "damping ratio (%)", "triggers"
            )?;
        }
        for p in &self.points {
            writeln!(
                f,
                "  {:>11.4e}  {:>10.4} ± {:<7.4}  {:>7.3} ± {:<7.3}  {:>8}",
                p.amplitude,
                p.frequency_hz,
                p.frequency_se_hz,
                100.0 * p.damping_ratio,
                100.0 * p.damping_se,
                p.triggers
            )?;
        }
        if let Some(p) = self.points.iter().find(|p| p.amplitude > 0.0) {
            // A storey whose floor (or the one below) has no channel has no drift: "—".
            let per = |v: &[f64]| -> String {
                v.iter()
                    .map(|x| {
                        if x.is_finite() {
                            format!("{:.3}", x / p.amplitude)
                        } else {
                            "—".into()
                        }
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            if !p.channels.is_empty() {
                write!(
                    f,
                    "  where it moves: each channel's amplitude is the amplitude × [{}]",
                    per(&p.channels)
                )?;
                if !p.drifts.is_empty() {
                    write!(
                        f,
                        "; each storey's drift, from the ground up, × [{}]",
                        per(&p.drifts)
                    )?;
                    let unmeasured: Vec<String> = p
                        .drifts
                        .iter()
                        .enumerate()
                        .filter(|(_, d)| !d.is_finite())
                        .map(|(s, _)| (s + 1).to_string())
                        .collect();
                    if !unmeasured.is_empty() {
                        write!(
                            f,
                            " (storey {}: a floor of it has no channel)",
                            unmeasured.join(", ")
                        )?;
                    }
                }
                writeln!(f)?;
            }
        }
        if let Some(l) = &self.linearity {
            let (a0, a1) = self
                .points
                .iter()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
                    (lo.min(p.amplitude), hi.max(p.amplitude))
                });
            writeln!(
                f,
                "  from {a0:.3e} to {a1:.3e}: {l}: {}",
                if l.linear {
                    "no significant change: linear over these amplitudes"
                } else {
                    "amplitude-dependent"
                }
            )?;
        }
        for n in &self.notes {
            writeln!(f, "  note: {n}")?;
        }
        Ok(())
    }
}

/// Several records of one structure (force levels, or a campaign), each analysed alike with
/// the same modes followed, and each mode's change pooled over all their points.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AmplitudeCampaign {
    /// Each record's name and analysis.
    pub records: Vec<(String, AmplitudeAnalysis)>,
    /// Per followed mode (the first record's order): the test over every record's points.
    pub pooled: Vec<PooledMode>,
}

/// One mode's change over every record's points.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PooledMode {
    /// The mode as the first record has it (Hz).
    pub frequency_hz: f64,
    /// Points pooled.
    pub points: usize,
    /// [`super::pooled_linearity`] of them (`None` with fewer than three).
    pub linearity: Option<super::Linearity>,
}

/// A campaign of `count` records: `analyse(i, follow)` gives record i's name and analysis
/// following the modes at `follow` (Hz; every reported mode when empty). The first record
/// follows `asked`; the others the modes it followed, in its order (so that mode j is the
/// same mode in every record); then each mode's change is pooled ([`super::pooled_linearity`]).
pub fn amplitude_campaign<E>(
    count: usize,
    asked: &[f64],
    mut analyse: impl FnMut(usize, &[f64]) -> Result<(String, AmplitudeAnalysis), E>,
) -> Result<AmplitudeCampaign, E> {
    let mut records = Vec::with_capacity(count);
    let mut follow = asked.to_vec();
    for i in 0..count {
        let r = analyse(i, &follow)?;
        if i == 0 {
            follow = campaign_modes(asked, &r.1);
        }
        records.push(r);
    }
    Ok(pool_records(records))
}

/// The frequencies every record of a campaign follows: `asked`, else the modes the first
/// record's analysis followed.
fn campaign_modes(asked: &[f64], first: &AmplitudeAnalysis) -> Vec<f64> {
    if asked.is_empty() {
        first
            .curves
            .modes
            .iter()
            .map(|m| m.mode.frequency_hz)
            .collect()
    } else {
        asked.to_vec()
    }
}

/// The campaign of `records` (each analysed with the same modes followed, in the same
/// order): the pooled test of each mode ([`super::pooled_linearity`]).
fn pool_records(records: Vec<(String, AmplitudeAnalysis)>) -> AmplitudeCampaign {
    let modes = records.first().map_or(0, |r| r.1.curves.modes.len());
    let pooled = (0..modes)
        .map(|j| {
            let points: Vec<super::AmplitudePoint> = records
                .iter()
                .filter_map(|r| r.1.curves.modes.get(j))
                .flat_map(|c| c.points.iter().cloned())
                .collect();
            PooledMode {
                frequency_hz: records[0].1.curves.modes[j].mode.frequency_hz,
                points: points.len(),
                linearity: super::pooled_linearity(&points),
            }
        })
        .collect();
    AmplitudeCampaign { records, pooled }
}

impl fmt::Display for AmplitudeCampaign {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (name, a) in &self.records {
            writeln!(f, "record: {name}")?;
            a.fmt(f)?;
        }
        writeln!(
            f,
            "pooled over the {} records (each point with its standard error):",
            self.records.len()
        )?;
        for m in &self.pooled {
            match &m.linearity {
                Some(l) => writeln!(
                    f,
                    "mode {:.4} Hz, {} points: {l} over the amplitudes reached: {}",
                    m.frequency_hz,
                    m.points,
                    if l.linear {
                        "no significant change"
                    } else {
                        "amplitude-dependent"
                    }
                )?,
                None => writeln!(
                    f,
                    "mode {:.4} Hz: {} points, too few to test",
                    m.frequency_hz, m.points
                )?,
            }
        }
        Ok(())
    }
}
