//! What a report page shows, as serializable types, and how an analysis becomes one.

use covssi::fdd::{efdd, efdd_of_mode};
use covssi::{Complex64 as C64, ModalAnalysis, PoleStatus, Rejection, Stability, mac, mpc, mpd};
use serde::Serialize;

use crate::io::Geometry;
use crate::setups::{SetupsReport, phase_quality};

/// Everything one page draws.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct PageData {
    /// The page's title.
    pub title: String,
    /// Lines of the summary under it.
    pub summary: Vec<String>,
    /// The stabilization diagram, when there is one (a single record).
    pub diagram: Option<Diagram>,
    /// Each setup's stabilization diagram, to choose from (merged setups).
    pub setup_diagrams: Vec<SetupDiagram>,
    /// The modes' table.
    pub modes: Vec<ModeRow>,
    /// MAC between the modes' shapes.
    pub mac: Vec<Vec<f64>>,
    /// The structure and each mode's motion of it.
    pub shapes: Shapes,
    /// A campaign's series (the page of `hyst track`).
    pub track: Option<TrackSeries>,
}

/// One reference mode's series.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ModeSeries {
    /// Its label.
    pub label: String,
    /// Each record's time (days from the first record).
    pub days: Vec<f64>,
    /// Frequency (Hz).
    pub frequency_hz: Vec<f64>,
    /// Its standard error (Hz; null without one).
    pub frequency_se_hz: Vec<Option<f64>>,
    /// Damping ratio.
    pub damping_ratio: Vec<f64>,
    /// Its standard error.
    pub damping_se: Vec<Option<f64>>,
    /// The times (days) of the alarms this mode raised.
    pub alarm_days: Vec<f64>,
}

/// A campaign's series.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct TrackSeries {
    /// One per reference mode.
    pub modes: Vec<ModeSeries>,
    /// The training ends here (days), when there is a baseline.
    pub training_end_days: Option<f64>,
}

/// The stabilization diagram: every pole, and the spectrum behind.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Diagram {
    /// Every pole of every order.
    pub poles: Vec<PolePoint>,
    /// The spectrum's line frequencies (Hz).
    pub spectrum_hz: Vec<f64>,
    /// The first few singular values of the spectral matrix at each line (one vector per
    /// singular value).
    pub singular_values: Vec<Vec<f64>>,
}

/// One setup's stabilization diagram, by the setup's name.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SetupDiagram {
    /// The setup.
    pub name: String,
    /// Its diagram (the spectrum behind it: the first singular value of SSI's survey).
    pub diagram: Diagram,
}

/// One pole as the diagram shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PolePoint {
    /// Frequency (Hz).
    pub f: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Model order.
    pub order: usize,
    /// `stable`, `frequency` (stable in frequency, or frequency and damping), `real`, or
    /// `rejected`.
    pub group: &'static str,
    /// Why it was kept or rejected, in words.
    pub reason: String,
}

/// One row of the modes' table.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ModeRow {
    /// The mode's name as the command's text report gives it: its number counted from 1,
    /// or the name an estimates table's columns give it.
    pub name: String,
    /// Frequency (Hz) and its standard error.
    pub frequency_hz: f64,
    /// Standard error (Hz).
    pub frequency_se_hz: Option<f64>,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Its standard error.
    pub damping_se: Option<f64>,
    /// Modal phase collinearity of its shape.
    pub mpc: Option<f64>,
    /// Mean phase deviation of its shape (degrees).
    pub mpd: Option<f64>,
    /// EFDD's frequency (Hz) and damping ratio for the same mode.
    pub efdd: Option<(f64, f64)>,
    /// Where it was seen (merged setups: "12/15 setups").
    pub seen: Option<String>,
}

/// The structure drawn and its motion in each mode.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Shapes {
    /// Node names.
    pub names: Vec<String>,
    /// Node positions.
    pub xyz: Vec<[f64; 3]>,
    /// Lines between nodes (indices).
    pub lines: Vec<[usize; 2]>,
    /// Per mode, per node, the x, y, z motion as [re, im] (0 where unknown).
    pub motion: Vec<Vec<[[f64; 2]; 3]>>,
}

/// Singular values drawn behind the diagram.
const SINGULAR_VALUES_SHOWN: usize = 3;

fn reason(status: &PoleStatus) -> (&'static str, String) {
    let pct = |v: f64| format!("{:.2} %", 100.0 * v);
    match status {
        PoleStatus::Stable(Stability::FrequencyDampingShape) => {
            ("stable", "stable in frequency, damping and shape".into())
        }
        PoleStatus::Stable(Stability::FrequencyDamping) => {
            ("frequency", "stable in frequency and damping".into())
        }
        PoleStatus::Stable(Stability::Frequency) => ("frequency", "stable in frequency".into()),
        PoleStatus::Stable(Stability::Real) => ("real", "a stable real pole".into()),
        PoleStatus::Rejected(r) => (
            "rejected",
            match r {
                Rejection::NoPrevious => {
                    "rejected: no pole of the previous order to compare".into()
                }
                Rejection::Unstable { real_part } => {
                    format!("rejected: unstable (Re λ = {real_part:.3} rad/s)")
                }
                Rejection::NegativeRealEigenvalue => "rejected: at Nyquist".into(),
                Rejection::DampingAboveLimit { damping, limit } => {
                    format!("rejected: damping ratio {damping:.3} above the limit {limit:.3}")
                }
                Rejection::Frequency { change, threshold } => format!(
                    "rejected: frequency changed {} from the previous order (limit {})",
                    pct(*change),
                    pct(*threshold)
                ),
                Rejection::RealPole { change, threshold } => {
                    format!("rejected: real pole changed {change:.3} (limit {threshold:.3})")
                }
            },
        ),
    }
}

pub(super) fn pair(v: C64) -> [f64; 2] {
    [v.re, v.im]
}

/// The stabilization diagram of analysis `a`: every pole with why it was kept or rejected,
/// over the FDD's first singular values when it was computed, else the first singular value
/// of SSI's survey.
pub fn diagram_of(a: &ModalAnalysis) -> Diagram {
    let fdd = a.fdd.as_ref().map(|(f, _)| f);
    let poles = a
        .ssi
        .diagram
        .orders
        .iter()
        .flat_map(|o| {
            o.poles.iter().map(move |p| {
                let (group, reason) = reason(&p.status);
                PolePoint {
                    f: p.frequency_hz,
                    zeta: p.damping_ratio,
                    order: o.order,
                    group,
                    reason,
                }
            })
        })
        .collect();
    let (spectrum_hz, singular_values) = match fdd {
        Some(f) => {
            let shown = f
                .singular_values
                .first()
                .map_or(0, |s| s.len().min(SINGULAR_VALUES_SHOWN));
            (
                f.frequencies_hz.clone(),
                (0..shown)
                    .map(|k| f.singular_values.iter().map(|s| s[k]).collect())
                    .collect(),
            )
        }
        None => (
            a.ssi.diagram.spectrum.frequencies_hz.clone(),
            vec![a.ssi.diagram.spectrum.first_singular_value.clone()],
        ),
    };
    Diagram {
        poles,
        spectrum_hz,
        singular_values,
    }
}

/// The mode within EFDD's reach of reported mode `i` whose shape EFDD cannot tell from
/// `i`'s (MAC at least its bell's threshold), with that MAC: EFDD then has no opinion of
/// either.
fn inseparable(
    a: &ModalAnalysis,
    reported: &[covssi::ReportedMode],
    i: usize,
) -> Option<(usize, f64)> {
    let (_, opts) = a.fdd.as_ref()?;
    let m = &reported[i];
    let shape = m.shape.as_deref()?;
    reported.iter().enumerate().find_map(|(j, n)| {
        let near =
            j != i && (n.frequency_hz / m.frequency_hz - 1.0).abs() <= covssi::fdd::EFDD_REACH;
        let alike = mac(shape, n.shape.as_deref()?);
        (near && alike >= opts.mac_threshold).then_some((j, alike))
    })
}

/// EFDD's opinion of reported mode `i`: from its own shape's bell ([`efdd_of_mode`]), so
/// that close modes each have their own; from the peak of s₁ for a mode without a shape;
/// none when a close mode's shape is alike (see [`inseparable`]).
fn efdd_opinion(
    a: &ModalAnalysis,
    reported: &[covssi::ReportedMode],
    i: usize,
) -> Option<covssi::fdd::EfddMode> {
    let (f, o) = a.fdd.as_ref()?;
    let m = &reported[i];
    if inseparable(a, reported, i).is_some() {
        return None;
    }
    match m.shape.as_deref() {
        Some(shape) => efdd_of_mode(f, m.frequency_hz, shape, o),
        None => efdd(f, m.frequency_hz, o),
    }
}

/// A line for each pair of close modes EFDD cannot tell apart.
fn inseparable_lines(a: &ModalAnalysis, reported: &[covssi::ReportedMode]) -> Vec<String> {
    (0..reported.len())
        .filter_map(|i| {
            let (j, alike) = inseparable(a, reported, i).filter(|&(j, _)| j > i)?;
            Some(format!(
                "No EFDD for modes {} and {} ({:.4} and {:.4} Hz): their shapes are alike (MAC {alike:.2}), so EFDD cannot tell their bells apart.",
                i + 1,
                j + 1,
                reported[i].frequency_hz,
                reported[j].frequency_hz
            ))
        })
        .collect()
}

/// The page of one record's analysis `a` (its FDD, when computed, behind the diagram and
/// EFDD's opinion on each mode).
pub fn ssi_page_data(title: &str, a: &ModalAnalysis) -> PageData {
    let fdd = a.fdd.as_ref().map(|(f, _)| f);
    let reported = a.reported_modes();
    let modes: Vec<ModeRow> = reported
        .iter()
        .enumerate()
        .map(|(i, m)| ModeRow {
            name: (i + 1).to_string(),
            frequency_hz: m.frequency_hz,
            frequency_se_hz: m.frequency_se_hz,
            damping_ratio: m.damping_ratio,
            damping_se: m.damping_se,
            mpc: m.shape.as_deref().map(mpc),
            mpd: m.shape.as_deref().map(mpd),
            efdd: efdd_opinion(a, &reported, i).map(|e| (e.frequency_hz, e.damping_ratio)),
            seen: None,
        })
        .collect();
    let shapes: Vec<Vec<C64>> = reported
        .iter()
        .map(|m| {
            m.shape
                .clone()
                .unwrap_or_else(|| vec![C64::new(0.0, 0.0); a.channels.len()])
        })
        .collect();
    // Without a geometry, the channels stand along a line, each moving across it.
    let n = a.channels.len();
    let lines: Vec<[usize; 2]> = (1..n).map(|i| [i - 1, i]).collect();
    let zero = [0.0, 0.0];
    PageData {
        title: title.to_string(),
        summary: std::iter::once(format!(
            "{} channels at {} Hz; {}.",
            n,
            a.fs_hz,
            a.decision.headline()
        ))
        .chain(a.decision.confirmed_lines())
        .chain(a.decision.set_apart_lines())
        .chain(inseparable_lines(a, &reported))
        .chain(fdd.is_none().then(|| {
            "No EFDD: the record's FDD was not computed with this analysis, or the record is \
             too short for its segments (the diagram shows the first singular value of SSI's \
             survey)."
                .to_string()
        }))
        .collect(),
        diagram: Some(diagram_of(a)),
        setup_diagrams: Vec::new(),
        mac: mac_matrix(&shapes),
        modes,
        shapes: Shapes {
            names: a.channels.clone(),
            xyz: (0..n).map(|i| [i as f64, 0.0, 0.0]).collect(),
            lines,
            motion: shapes
                .iter()
                .map(|s| s.iter().map(|v| [zero, zero, pair(*v)]).collect())
                .collect(),
        },
        track: None,
    }
}

pub(super) fn mac_matrix(shapes: &[Vec<C64>]) -> Vec<Vec<f64>> {
    shapes
        .iter()
        .map(|a| shapes.iter().map(|b| mac(a, b)).collect())
        .collect()
}

/// The page of a test's setups `report`: its merged modes drawn on `geometry` (else the
/// nodes along a line), each setup's stabilization diagram to choose from.
pub fn setups_page_data(
    title: &str,
    report: &SetupsReport,
    geometry: Option<&Geometry>,
) -> PageData {
    let m = &report.merged;
    let (names, xyz, lines) = match geometry {
        Some(g) => (
            g.nodes.iter().map(|n| n.0.clone()).collect::<Vec<_>>(),
            g.nodes.iter().map(|n| n.1).collect(),
            g.lines.clone(),
        ),
        None => {
            let mut names: Vec<String> = Vec::new();
            for d in &m.dofs {
                if !names.contains(&d.node) {
                    names.push(d.node.clone());
                }
            }
            let xyz = (0..names.len()).map(|i| [i as f64, 0.0, 0.0]).collect();
            (names, xyz, Vec::new())
        }
    };
    let zero = [0.0, 0.0];
    let motion = m
        .modes
        .iter()
        .map(|mode| {
            names
                .iter()
                .map(|name| match mode.nodes.iter().find(|n| &n.node == name) {
                    Some(n) => n.motion.map(|v| v.map_or(zero, pair)),
                    None => [zero; 3],
                })
                .collect()
        })
        .collect();
    let shapes: Vec<Vec<C64>> = m
        .modes
        .iter()
        .map(|mode| mode.shape.iter().map(|v| v.unwrap_or_default()).collect())
        .collect();
    PageData {
        title: title.to_string(),
        summary: vec![format!(
            "{} setups merged on their references: {} modes, {} nodes.",
            m.setups.len(),
            m.modes.len(),
            names.len()
        )]
        .into_iter()
        .chain(
            report
                .floor_factors
                .iter()
                .map(|f| format!("Sensors: {}.", f.sentence(&m.setups))),
        )
        .chain(m.notes.iter().cloned())
        .collect(),
        diagram: None,
        setup_diagrams: report
            .setups
            .iter()
            .map(|s| SetupDiagram {
                name: s.name.clone(),
                diagram: diagram_of(&s.analysis),
            })
            .collect(),
        modes: m
            .modes
            .iter()
            .enumerate()
            .map(|(i, mode)| {
                let quality = phase_quality(mode);
                ModeRow {
                    name: (i + 1).to_string(),
                    frequency_hz: mode.frequency_hz,
                    frequency_se_hz: mode.frequency_se_hz,
                    damping_ratio: mode.damping_ratio,
                    damping_se: mode.damping_se,
                    mpc: quality.map(|q| q.0),
                    mpd: quality.map(|q| q.1),
                    efdd: None,
                    seen: Some(format!("{}/{} setups", mode.seen_in.len(), m.setups.len())),
                }
            })
            .collect(),
        mac: mac_matrix(&shapes),
        shapes: Shapes {
            names,
            xyz,
            lines,
            motion,
        },
        track: None,
    }
}
