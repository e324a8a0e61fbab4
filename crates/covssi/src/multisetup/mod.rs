//! Several setups of one modal test merged into one mode set: post-standardization (PoSER)
//! with the uncertainty of every setup carried into the result.
//!
//! A test of a large structure is made in setups: a few reference sensors stay put while the
//! others rove. Each setup $s$ is identified alone (its modes with their standard errors),
//! then:
//!
//! 1. **Units.** Each channel reads $g_c\,\lambda^{p_c}\,d_c^\top u$, the motion $u$ of its node
//!    along its unit direction $d_c$, in displacement ($p=0$), velocity ($p=1$) or acceleration
//!    ($p=2$), times a gain $g_c$ (a calibration or sign the channel is told). A mode's shape
//!    entry is divided by $g_c\lambda^{p_c}$, with $\lambda$ that setup's pole of the mode, so that
//!    every entry is a displacement and velocities and accelerations compare.
//! 2. **Matching.** Modes of different setups are the same mode when their frequencies differ
//!    by at most [`MergeOptions::frequency_tolerance`] and, with two or more references the
//!    mode moves beyond twice their standard errors, their reference parts agree (MAC of those
//!    at least [`MergeOptions::min_reference_mac`]); nearest pairs first, one mode of a setup
//!    to one merged mode.
//! 3. **Scaling.** The references' common shape $\rho$ and each setup's complex scale
//!    $\alpha_s$ minimise $\sum_s\sum_{c\in R} |\alpha_s r_{s,c}-\rho_c|^2 / (|\alpha_s|^2\sigma_{s,c}^2)$
//!    (alternating weighted least squares, $\max_c|\rho_c| = 1$); every entry of setup $s$ is
//!    multiplied by $\alpha_s$. A roving entry $v = \alpha_s\varphi_{s,c}$ has
//!    $\operatorname{E}|\delta v|^2 = |\alpha_s|^2\sigma_{s,c}^2 + |\varphi_{s,c}|^2\operatorname{E}|\delta\alpha_s|^2$,
//!    where $\operatorname{E}|\delta\alpha_s|^2$ holds both the setup's own reference noise and
//!    that of $\rho$ (first order). A reference entry is $\rho_c$, with
//!    $\operatorname{E}|\delta\rho_c|^2 = 1/\sum_s (|\alpha_s|^2\sigma_{s,c}^2)^{-1}$.
//! 4. **Frequency and damping.** The inverse-variance mean of the setups' values,
//!    $\bar f = \sum f_s/\sigma_s^2 / \sum 1/\sigma_s^2$, its standard error
//!    $(\sum 1/\sigma_s^2)^{-1/2}$ times the Birge ratio $\sqrt{\chi^2/(n-1)}$ when that exceeds 1
//!    (setups that disagree beyond their errors, e.g. a structure that warmed between them).
//!    A mode seen in one setup keeps that setup's error. Without standard errors (SSI's modes),
//!    the plain mean and the scatter's standard error ($\mathrm{sd}/\sqrt n$, none for one setup).
//! 5. **Nodes.** Where a node's directions span some axes (three skewed laser beams, or a
//!    reference accelerometer's x and y), the node's motion on those axes is the weighted least
//!    squares solution $u = (D^\top W D)^{-1} D^\top W v$, $W = \operatorname{diag}(1/\sigma^2)$, its
//!    standard errors the diagonal of $(D^\top W D)^{-1}$ ([`NodeMotion`]).
//!
//! ```
//! use covssi::multisetup::{merge, MergeOptions, Quantity, SetupChannel, SetupModes};
//! use covssi::ReportedMode;
//! use covssi::Complex64 as C;
//! let channel = |node: &str, x: f64, reference: bool| SetupChannel {
//!     node: node.into(), direction: [x, 0.0, 0.0], quantity: Quantity::Displacement,
//!     gain: 1.0, reference,
//! };
//! let mode = |shape: [f64; 2]| ReportedMode {
//!     frequency_hz: 2.0, frequency_se_hz: Some(0.01), damping_ratio: 0.01, damping_se: Some(0.001),
//!     shape: Some(shape.iter().map(|&v| C::new(v, 0.0)).collect()), shape_from_ssi: false,
//!     shape_se: Some(vec![0.0, 0.01]), ssi_mode: None,
//! };
//! // the reference (node "top") and a roving node, seen in two setups at different scales
//! let a = SetupModes { name: "a".into(), channels: vec![channel("top", 1.0, true), channel("1", 1.0, false)],
//!     modes: vec![mode([1.0, 0.5])] };
//! let b = SetupModes { name: "b".into(), channels: vec![channel("top", 1.0, true), channel("2", 1.0, false)],
//!     modes: vec![mode([1.0, 0.8])] };
//! let merged = merge(&[a, b], &MergeOptions::default()).unwrap();
//! let m = &merged.modes[0];
//! assert_eq!(merged.dofs.len(), 3);
//! assert!((m.frequency_se_hz.unwrap() - 0.01 / 2f64.sqrt()).abs() < 1e-12);
//! assert!((m.shape[2].unwrap().re - 0.8).abs() < 1e-9);
//! ```

mod global;
mod matching;
mod nodes;
mod scale;

pub use global::{GlobalError, SetupRecord, merge_global};

use crate::{Complex64 as C64, ReportedMode};

pub use nodes::NodeMotion;

/// The decades (log₁₀ |gain|) a channel's gain may lie in: sensors' calibration factors
/// (V per m/s², counts per g, a sign) span a few decades about 1, never twelve.
pub const GAIN_DECADES: std::ops::RangeInclusive<f64> = -12.0..=12.0;

/// What a channel measures: the motion of a node along a direction, as displacement, velocity
/// or acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Quantity {
    /// Displacement (λ⁰).
    Displacement,
    /// Velocity (λ¹).
    Velocity,
    /// Acceleration (λ²).
    Acceleration,
}

impl Quantity {
    /// Its names in a setup file.
    pub const NAMES: [&'static str; 3] = ["displacement", "velocity", "acceleration"];

    /// The power of the pole λ by which this quantity's shape exceeds the displacement's.
    pub fn power(self) -> i32 {
        match self {
            Quantity::Displacement => 0,
            Quantity::Velocity => 1,
            Quantity::Acceleration => 2,
        }
    }
}

/// One channel of a setup.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SetupChannel {
    /// The node it measures.
    pub node: String,
    /// The direction it measures along (a unit vector in the geometry's x, y, z).
    pub direction: [f64; 3],
    /// What it measures.
    pub quantity: Quantity,
    /// The factor its reading carries (1 for a calibrated channel; −1 for one mounted the
    /// other way round).
    pub gain: f64,
    /// Whether it is a reference: it stays at its node and direction in every setup.
    pub reference: bool,
}

/// One setup: its channels and the modes identified from its record alone (shapes with one
/// entry per channel).
#[derive(Debug, Clone, PartialEq)]
pub struct SetupModes {
    /// Its name (a file, a folder).
    pub name: String,
    /// Its channels, in the order of the shapes' entries.
    pub channels: Vec<SetupChannel>,
    /// Its modes.
    pub modes: Vec<ReportedMode>,
}

/// How setups are merged.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct MergeOptions {
    /// Largest relative frequency difference between one mode in two setups. Default 0.01.
    pub frequency_tolerance: f64,
    /// Least MAC of two setups' reference parts for one mode (with two or more references).
    /// Default 0.8.
    pub min_reference_mac: f64,
}

impl Default for MergeOptions {
    fn default() -> Self {
        MergeOptions {
            frequency_tolerance: 0.01,
            min_reference_mac: 0.8,
        }
    }
}

/// A degree of freedom of the merged shapes: a node and a direction some setup measured.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MergedDof {
    /// The node.
    pub node: String,
    /// The direction (unit vector).
    pub direction: [f64; 3],
    /// Whether it is a reference (measured in every setup).
    pub reference: bool,
    /// The setups that measured it (indices into the setups given).
    pub setups: Vec<usize>,
}

/// Where a merged mode was seen.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SeenIn {
    /// The setup (index into the setups given).
    pub setup: usize,
    /// The mode's index among that setup's modes.
    pub mode: usize,
    /// The complex scale its shape was multiplied by.
    pub scale: C64,
}

/// A mode of the merged set.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MergedMode {
    /// Natural frequency (Hz).
    pub frequency_hz: f64,
    /// Its standard error (Hz); `None` when it was seen in one setup without one.
    pub frequency_se_hz: Option<f64>,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Its standard error; `None` as for the frequency.
    pub damping_se: Option<f64>,
    /// The setups' frequency scatter against their errors, √(χ²/(n−1)) (the Birge ratio);
    /// `None` for a mode seen in one setup or without errors. Above 1 it has widened both
    /// standard errors.
    pub scatter_ratio: Option<f64>,
    /// The setups that saw it (empty from [`merge_global`], where every setup's
    /// correlations made each mode).
    pub seen_in: Vec<SeenIn>,
    /// Its shape at every [`MergedDof`] as a displacement, the largest entry 1; `None` where
    /// the setups measuring that DOF did not see the mode.
    pub shape: Vec<Option<C64>>,
    /// Standard error of each entry (√E|δ|²); `None` with the entry or without the setups'
    /// errors.
    pub shape_se: Vec<Option<f64>>,
    /// The motion of each node whose directions span some axes.
    pub nodes: Vec<NodeMotion>,
}

/// What [`merge`] finds.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MergedModes {
    /// The setups' names, in the order given.
    pub setups: Vec<String>,
    /// Every node and direction measured: the references first.
    pub dofs: Vec<MergedDof>,
    /// The merged modes, by frequency.
    pub modes: Vec<MergedMode>,
    /// Remarks: a reference that moved, a mode whose scale the references do not fix.
    pub notes: Vec<String>,
}

/// What makes setups impossible to merge.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MergeError {
    /// No setup was given.
    #[error("no setups given")]
    NoSetups,
    /// A setup's modes do not have one shape entry per channel.
    #[error(
        "setup `{setup}`, mode {mode}: its shape has {entries} entries for {channels} channels"
    )]
    ShapeLength {
        /// The setup's name.
        setup: String,
        /// The mode's index.
        mode: usize,
        /// Entries of its shape.
        entries: usize,
        /// Channels of the setup.
        channels: usize,
    },
    /// No node and direction is a reference in every setup.
    #[error(
        "no reference is common to every setup ({detail}): setups are scaled on the references they share"
    )]
    NoCommonReference {
        /// Which references each setup has.
        detail: String,
    },
    /// A channel's direction is not a finite nonzero vector, or its gain is zero.
    #[error("setup `{setup}`, channel {channel}: {problem}")]
    Channel {
        /// The setup's name.
        setup: String,
        /// The channel (0-based).
        channel: usize,
        /// What is wrong.
        problem: String,
    },
    /// An option is out of range.
    #[error("merge option `{option}` must be {expected}, got {value}")]
    InvalidOption {
        /// Its name.
        option: &'static str,
        /// What it must be.
        expected: &'static str,
        /// Its value.
        value: f64,
    },
}

/// A note for each setup (of several) none of whose modes matched another setup's: its
/// record, rate or references may not be the others', and its modes stand alone in the
/// merge. Each such setup's frequencies are said beside the others'.
fn unmatched_setups(setups: &[SetupModes], groups: &[Vec<(usize, usize)>]) -> Vec<String> {
    if setups.len() < 2 {
        return Vec::new();
    }
    let freqs = |s: usize| -> String {
        let f: Vec<String> = setups[s]
            .modes
            .iter()
            .map(|m| format!("{:.3}", m.frequency_hz))
            .collect();
        f.join(", ")
    };
    (0..setups.len())
        .filter(|&s| {
            !setups[s].modes.is_empty()
                && groups
                    .iter()
                    .filter(|g| g.iter().any(|&(t, _)| t == s))
                    .all(|g| g.iter().all(|&(t, _)| t == s))
        })
        .map(|s| {
            let others: Vec<String> = (0..setups.len())
                .filter(|&t| t != s)
                .map(|t| format!("`{}` {}", setups[t].name, freqs(t)))
                .collect();
            format!(
                "setup `{}` shares no mode with the other setups (its modes at {} Hz; {} Hz): its modes are merged alone; check its rate, record and references",
                setups[s].name,
                freqs(s),
                others.join("; ")
            )
        })
        .collect()
}

/// Two directions are one when their cosine is at least this (about 0.8°).
const SAME_DIRECTION: f64 = 0.9999;

/// Merge the modes of `setups` into one mode set (see the [module](self) for the method).
/// A mode without a shape (the refinement gave it none) cannot be scaled: it is left out,
/// and said.
pub fn merge(setups: &[SetupModes], opts: &MergeOptions) -> Result<MergedModes, MergeError> {
    check(setups, opts)?;
    let mut notes = Vec::new();
    // The modes with shapes, and each one's index among its setup's modes as given.
    let mut given_index: Vec<Vec<usize>> = Vec::with_capacity(setups.len());
    let with_shapes: Vec<SetupModes> = setups
        .iter()
        .map(|s| {
            let mut index = Vec::new();
            let mut modes = Vec::new();
            for (i, m) in s.modes.iter().enumerate() {
                if m.shape.is_some() {
                    index.push(i);
                    modes.push(m.clone());
                } else {
                    notes.push(format!(
                        "setup `{}`: the mode at {:.4} Hz has no shape and is left out",
                        s.name, m.frequency_hz
                    ));
                }
            }
            given_index.push(index);
            SetupModes { modes, ..s.clone() }
        })
        .collect();
    let setups = with_shapes.as_slice();
    let described: Vec<(String, Vec<SetupChannel>)> = setups
        .iter()
        .map(|s| (s.name.clone(), s.channels.clone()))
        .collect();
    let dofs = dofs_of(&described, &mut notes)?;
    let converted: Vec<Vec<scale::Shape>> = setups
        .iter()
        .map(|setup| {
            setup
                .modes
                .iter()
                .map(|m| scale::Shape::in_displacement(m, setup, &dofs))
                .collect()
        })
        .collect();
    let references: Vec<usize> = (0..dofs.len()).filter(|&d| dofs[d].reference).collect();
    let groups = matching::group(setups, &converted, &references, opts);
    notes.extend(unmatched_setups(setups, &groups));
    let mut modes: Vec<MergedMode> = groups
        .iter()
        .map(|group| {
            let members: Vec<(usize, usize, &ReportedMode, &scale::Shape)> = group
                .iter()
                .map(|&(s, i)| (s, i, &setups[s].modes[i], &converted[s][i]))
                .collect();
            let mode = merge_one(&members, &references, &dofs);
            if mode.seen_in.iter().any(|x| !x.scale.is_finite()) {
                notes.push(format!(
                    "the mode at {:.4} Hz does not move the references: its setups' scales are not fixed",
                    mode.frequency_hz
                ));
            }
            mode
        })
        .collect();
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    for seen in modes.iter_mut().flat_map(|m| m.seen_in.iter_mut()) {
        seen.mode = given_index[seen.setup][seen.mode];
    }
    Ok(MergedModes {
        setups: setups.iter().map(|s| s.name.clone()).collect(),
        dofs,
        modes,
        notes,
    })
}

fn check(setups: &[SetupModes], opts: &MergeOptions) -> Result<(), MergeError> {
    if setups.is_empty() {
        return Err(MergeError::NoSetups);
    }
    if !(opts.frequency_tolerance > 0.0 && opts.frequency_tolerance < 1.0) {
        return Err(MergeError::InvalidOption {
            option: "frequency_tolerance",
            expected: "in (0, 1)",
            value: opts.frequency_tolerance,
        });
    }
    if !(0.0..=1.0).contains(&opts.min_reference_mac) {
        return Err(MergeError::InvalidOption {
            option: "min_reference_mac",
            expected: "in [0, 1]",
            value: opts.min_reference_mac,
        });
    }
    for setup in setups {
        for (c, ch) in setup.channels.iter().enumerate() {
            let norm = ch.direction.iter().map(|v| v * v).sum::<f64>().sqrt();
            let problem = if !(norm.is_finite() && norm > 0.0) {
                Some(format!(
                    "direction {:?} is not a nonzero vector",
                    ch.direction
                ))
            } else if !(ch.gain.is_finite() && ch.gain != 0.0) {
                Some(format!("gain {} is not a finite nonzero number", ch.gain))
            } else if !(GAIN_DECADES.contains(&ch.gain.abs().log10())) {
                // A shape entry is divided by its gain and squared in every MAC: a gain of
                // 1e-300 made them infinite (NaN shapes, exit 0, issue 77).
                Some(format!(
                    "gain {:e} is more than 12 decades from 1: a sensor's calibration factor so far off is a slip of units",
                    ch.gain
                ))
            } else {
                None
            };
            let twin = setup.channels[..c].iter().position(|b| same_axis(b, ch));
            let problem = problem.or_else(|| {
                twin.map(|b| {
                    format!(
                        "it measures node {} along the axis channel {b} measures: give each node and axis once",
                        ch.node
                    )
                })
            });
            if let Some(problem) = problem {
                return Err(MergeError::Channel {
                    setup: setup.name.clone(),
                    channel: c,
                    problem,
                });
            }
        }
        for (i, m) in setup.modes.iter().enumerate() {
            let Some(entries) = m.shape.as_ref().map(|s| s.len()) else {
                continue;
            };
            if entries != setup.channels.len() {
                return Err(MergeError::ShapeLength {
                    setup: setup.name.clone(),
                    mode: i,
                    entries,
                    channels: setup.channels.len(),
                });
            }
        }
    }
    Ok(())
}

fn unit(d: [f64; 3]) -> [f64; 3] {
    let n = d.iter().map(|v| v * v).sum::<f64>().sqrt();
    d.map(|v| v / n)
}

/// The cosine between two directions (any nonzero length).
fn cosine(a: [f64; 3], b: [f64; 3]) -> f64 {
    let (a, b) = (unit(a), unit(b));
    (0..3).map(|k| a[k] * b[k]).sum()
}

/// Whether two channels measure one axis of one node: the same node, and directions within
/// about 0.8° (a cosine of 0.9999) of each other or of each other's opposite. Two channels
/// of one setup that do are one reading twice, which [`merge`] refuses.
pub fn same_axis(a: &SetupChannel, b: &SetupChannel) -> bool {
    a.node == b.node && cosine(a.direction, b.direction).abs() >= SAME_DIRECTION
}

/// Whether a channel at `node` along `direction` is the merged DOF `dof`: its axis, and
/// the same sense.
fn same_dof(node: &str, direction: [f64; 3], dof: &MergedDof) -> bool {
    node == dof.node && cosine(direction, dof.direction) >= SAME_DIRECTION
}

/// The merged DOFs: the references every setup shares first, then every other node and
/// direction in the order met. A reference some setups lack is said and kept as a roving DOF.
fn dofs_of(
    setups: &[(String, Vec<SetupChannel>)],
    notes: &mut Vec<String>,
) -> Result<Vec<MergedDof>, MergeError> {
    let mut dofs: Vec<MergedDof> = Vec::new();
    for (s, (_, channels)) in setups.iter().enumerate() {
        for ch in channels {
            match dofs
                .iter_mut()
                .find(|d| same_dof(&ch.node, ch.direction, d))
            {
                Some(d) => {
                    if !d.setups.contains(&s) {
                        d.setups.push(s);
                    }
                    d.reference &= ch.reference;
                }
                None => dofs.push(MergedDof {
                    node: ch.node.clone(),
                    direction: unit(ch.direction),
                    reference: ch.reference,
                    setups: vec![s],
                }),
            }
        }
    }
    for d in &mut dofs {
        if d.reference && d.setups.len() < setups.len() {
            d.reference = false;
            let missing: Vec<&str> = (0..setups.len())
                .filter(|s| !d.setups.contains(s))
                .map(|s| setups[s].0.as_str())
                .collect();
            notes.push(format!(
                "the reference at node {} along {:?} is not in setup(s) {}: it moved, and is merged as a roving channel",
                d.node,
                d.direction.map(|v| (v * 1000.0).round() / 1000.0),
                missing.join(", ")
            ));
        }
    }
    if !dofs.iter().any(|d| d.reference) {
        let detail = setups
            .iter()
            .map(|(name, channels)| {
                let refs: Vec<String> = channels
                    .iter()
                    .filter(|c| c.reference)
                    .map(|c| format!("{} {:?}", c.node, unit(c.direction)))
                    .collect();
                format!("`{name}`: [{}]", refs.join(", "))
            })
            .collect::<Vec<_>>()
            .join("; ");
        return Err(MergeError::NoCommonReference { detail });
    }
    dofs.sort_by_key(|d| !d.reference);
    Ok(dofs)
}

/// One merged mode from its members (setup, mode index, the mode, its shape in displacement).
fn merge_one(
    members: &[(usize, usize, &ReportedMode, &scale::Shape)],
    references: &[usize],
    dofs: &[MergedDof],
) -> MergedMode {
    let freq: Vec<(f64, Option<f64>)> = members
        .iter()
        .map(|m| (m.2.frequency_hz, m.2.frequency_se_hz))
        .collect();
    let damp: Vec<(f64, Option<f64>)> = members
        .iter()
        .map(|m| (m.2.damping_ratio, m.2.damping_se))
        .collect();
    let (frequency_hz, frequency_se, ratio) = pooled(&freq);
    let (damping_ratio, damping_se, damping_ratio_scatter) = pooled(&damp);
    // The Birge ratio widens each quantity's error by its own scatter.
    let widen = |se: Option<f64>, r: Option<f64>| se.map(|e| e * r.unwrap_or(1.0).max(1.0));
    let shapes: Vec<&scale::Shape> = members.iter().map(|m| m.3).collect();
    let scaled = scale::scale(&shapes, references, dofs.len());
    let seen_in = members
        .iter()
        .zip(&scaled.scales)
        .map(|(m, &scale)| SeenIn {
            setup: m.0,
            mode: m.1,
            scale,
        })
        .collect();
    let nodes = nodes::node_motions(dofs, &scaled.shape, &scaled.shape_se);
    MergedMode {
        frequency_hz,
        frequency_se_hz: widen(frequency_se, ratio),
        damping_ratio,
        damping_se: widen(damping_se, damping_ratio_scatter),
        scatter_ratio: ratio,
        seen_in,
        shape: scaled.shape,
        shape_se: scaled.shape_se,
        nodes,
    }
}

/// Pooled value, its standard error (not yet widened) and the Birge ratio (see the module).
fn pooled(values: &[(f64, Option<f64>)]) -> (f64, Option<f64>, Option<f64>) {
    let n = values.len() as f64;
    let errors: Option<Vec<f64>> = values
        .iter()
        .map(|v| v.1.filter(|e| *e > 0.0 && e.is_finite()))
        .collect();
    match errors {
        Some(e) => {
            let w: Vec<f64> = e.iter().map(|s| 1.0 / (s * s)).collect();
            let sw: f64 = w.iter().sum();
            let mean = values.iter().zip(&w).map(|(v, w)| v.0 * w).sum::<f64>() / sw;
            let ratio = (values.len() > 1).then(|| {
                let chi2: f64 = values
                    .iter()
                    .zip(&w)
                    .map(|(v, w)| (v.0 - mean).powi(2) * w)
                    .sum();
                (chi2 / (n - 1.0)).sqrt()
            });
            (mean, Some(sw.powf(-0.5)), ratio)
        }
        None => {
            let mean = values.iter().map(|v| v.0).sum::<f64>() / n;
            let se = (values.len() > 1).then(|| {
                let var = values.iter().map(|v| (v.0 - mean).powi(2)).sum::<f64>() / (n - 1.0);
                (var / n).sqrt()
            });
            (mean, se, None)
        }
    }
}

#[cfg(test)]
mod tests;
