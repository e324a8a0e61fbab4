//! Which modes of different setups are one mode: frequencies within a tolerance and, with two
//! or more references the mode moves beyond their errors, reference parts alike.
//!
//! A reference part can only tell modes apart where the mode moves the references: an entry
//! within twice its standard error of zero is noise, and the MAC of parts made of such
//! entries is noise too (two halves of a bridge sharing two references at a mode's nodes
//! split one mode in two on it). Where fewer than two references are determined in both,
//! the frequency tolerance decides, as it does with a single reference.

use super::{MergeOptions, SetupModes, scale::Shape};
use crate::Complex64 as C64;

/// A merged mode being assembled: its members (setup, mode), mean frequency, and the
/// reference part of its first member.
struct Group {
    members: Vec<(usize, usize)>,
    frequency_sum: f64,
    references: Part,
}

/// A mode's entries at the references, each with its standard error if known.
type Part = Vec<Option<(C64, Option<f64>)>>;

/// The reference part of `shape`.
fn part(shape: &Shape, references: &[usize]) -> Part {
    references
        .iter()
        .map(|&r| shape.values[r].map(|v| (v, shape.se[r])))
        .collect()
}

/// A standard error's multiple within which an entry is not told from zero (about 95 %
/// two-sided).
const WITHIN: f64 = 2.0;

impl Group {
    fn frequency(&self) -> f64 {
        self.frequency_sum / self.members.len() as f64
    }
}

/// The merged modes as lists of (setup, mode index). Setups are taken richest first; each of
/// a setup's modes joins the nearest group in frequency it may join, nearest pairs first, or
/// starts its own.
pub(super) fn group(
    setups: &[SetupModes],
    shapes: &[Vec<Shape>],
    references: &[usize],
    opts: &MergeOptions,
) -> Vec<Vec<(usize, usize)>> {
    let mut order: Vec<usize> = (0..setups.len()).collect();
    order.sort_by_key(|&s| std::cmp::Reverse(setups[s].modes.len()));
    let mut groups: Vec<Group> = Vec::new();
    for s in order {
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for (i, m) in setups[s].modes.iter().enumerate() {
            let refs = part(&shapes[s][i], references);
            for (g, group) in groups.iter().enumerate() {
                let f = group.frequency();
                let distance = (m.frequency_hz - f).abs() / f;
                if distance <= opts.frequency_tolerance
                    && alike(&refs, &group.references, opts.min_reference_mac)
                {
                    pairs.push((distance, i, g));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut taken_mode = vec![false; setups[s].modes.len()];
        let mut taken_group = vec![false; groups.len()];
        for (_, i, g) in pairs {
            if !taken_mode[i] && !taken_group[g] {
                taken_mode[i] = true;
                taken_group[g] = true;
                groups[g].members.push((s, i));
                groups[g].frequency_sum += setups[s].modes[i].frequency_hz;
            }
        }
        for (i, m) in setups[s].modes.iter().enumerate() {
            if !taken_mode[i] {
                groups.push(Group {
                    members: vec![(s, i)],
                    frequency_sum: m.frequency_hz,
                    references: part(&shapes[s][i], references),
                });
            }
        }
    }
    groups
        .into_iter()
        .map(|mut g| {
            g.members.sort();
            g.members
        })
        .collect()
}

/// Whether two reference parts are one mode's: always when fewer than two references are
/// determined (beyond [`WITHIN`] standard errors of zero, or without errors) in both, else
/// when the MAC of those is at least `min_mac`.
fn alike(a: &Part, b: &Part, min_mac: f64) -> bool {
    let determined = |e: &Option<(C64, Option<f64>)>| match *e {
        Some((v, Some(se))) => (v.norm() > WITHIN * se).then_some(v),
        Some((v, None)) => Some(v),
        None => None,
    };
    let (x, y): (Vec<C64>, Vec<C64>) = a
        .iter()
        .zip(b)
        .filter_map(|(a, b)| Some((determined(a)?, determined(b)?)))
        .unzip();
    x.len() < 2 || crate::mac(&x, &y) >= min_mac
}
