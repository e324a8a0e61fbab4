//! Pairing the refined modes with the SSI modes they came from.

use crate::cluster::{Mode, pole_distance};
use crate::linalg::C64;
use crate::refine::results::RefinedMode;

/// Index of the mode whose pole is nearest λ, by the clustering's relative distance. Poles may
/// trade places while fitting, so a fitted pole is named by this rather than by the mode it
/// started from. (Every fitted pole started from one of `modes`, so they are not empty.)
/// The largest relative pole distance |λ − λ_SSI| / max(|λ|, |λ_SSI|) at which a refined mode
/// is called the same mode as an SSI mode: 5 %, eight times the largest move of a refined
/// mode from its SSI mode on the shared OMA records (0.6 %, the third mode from y1 alone), and
/// far below the distance of the F-16's refined 7.56 Hz mode at 23 % damping from the SSI
/// mode at 7.35 Hz and 0.5 % (22 %).
pub const SAME_MODE_DISTANCE: f64 = 0.05;

/// Each refined mode's SSI mode: the pairs (refined, SSI) within [`SAME_MODE_DISTANCE`],
/// nearest first, each mode in at most one pair.
pub(super) fn pair_with_ssi_modes(kept: &mut [RefinedMode], modes: &[Mode]) {
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    for (j, m) in kept.iter().enumerate() {
        for (i, sm) in modes.iter().enumerate() {
            let d = pole_distance(m.lambda, sm.lambda);
            if d <= SAME_MODE_DISTANCE {
                pairs.push((d, j, i));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut taken = vec![false; modes.len()];
    for (_, j, i) in pairs {
        if kept[j].source.is_none() && !taken[i] {
            kept[j].source = Some(i);
            taken[i] = true;
        }
    }
}

pub(super) fn nearest_mode(modes: &[Mode], lam: C64) -> usize {
    modes
        .iter()
        .enumerate()
        .min_by(|a, b| pole_distance(a.1.lambda, lam).total_cmp(&pole_distance(b.1.lambda, lam)))
        .map_or(0, |(k, _)| k)
}
