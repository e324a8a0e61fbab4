//! Which modes of different setups are one mode: frequencies within a tolerance and, with two
//! or more references, reference parts alike.

use super::{MergeOptions, SetupModes, scale::Shape};
use crate::Complex64 as C64;

/// A merged mode being assembled: its members (setup, mode), mean frequency, and the
/// reference part of its first member.
struct Group {
    members: Vec<(usize, usize)>,
    frequency_sum: f64,
    references: Vec<Option<C64>>,
}

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
            let refs: Vec<Option<C64>> =
                references.iter().map(|&r| shapes[s][i].values[r]).collect();
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
                    references: references.iter().map(|&r| shapes[s][i].values[r]).collect(),
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

/// Whether two reference parts are one mode's: always with fewer than two references in
/// common, else their MAC is at least `min_mac`.
fn alike(a: &[Option<C64>], b: &[Option<C64>], min_mac: f64) -> bool {
    let (x, y): (Vec<C64>, Vec<C64>) = a
        .iter()
        .zip(b)
        .filter_map(|(a, b)| Some(((*a)?, (*b)?)))
        .unzip();
    x.len() < 2 || crate::mac(&x, &y) >= min_mac
}
