//! Random decrement at several trigger levels: the mode's response averaged over the
//! segments that start at its extrema within each amplitude band, as the free decay from
//! that amplitude (for a linear mode, the response's correlation function scaled to the
//! trigger level). The triggers are kept in time-ordered groups so that every estimate can
//! be recomputed with one group left out (the jackknife).

/// Triggers of one amplitude band: per group, the sum of its segments and their count, and
/// the sum of the trigger values.
#[derive(Debug, Clone)]
pub(super) struct LevelSums {
    /// Per group: Σ of its segments (each `len` long).
    pub sums: Vec<Vec<f64>>,
    /// Per group: segments.
    pub counts: Vec<usize>,
    /// Per group: Σ |trigger value|.
    pub values: Vec<f64>,
}

impl LevelSums {
    /// Segments in all.
    pub(super) fn total(&self) -> usize {
        self.counts.iter().sum()
    }

    /// The signature without group `skip` (`None`: with every group), and the mean trigger
    /// value it starts from.
    pub(super) fn signature(&self, skip: Option<usize>) -> Option<(Vec<f64>, f64)> {
        let len = self.sums.first()?.len();
        let mut s = vec![0.0; len];
        let (mut n, mut v) = (0usize, 0.0);
        for (g, sum) in self.sums.iter().enumerate() {
            if Some(g) == skip {
                continue;
            }
            s.iter_mut().zip(sum).for_each(|(a, b)| *a += b);
            n += self.counts[g];
            v += self.values[g];
        }
        (n > 0).then(|| {
            let k = n as f64;
            (s.iter().map(|x| x / k).collect(), v / k)
        })
    }
}

/// The extrema of `q` that can start a segment of `len` samples (a maximum counts with its
/// value, a minimum with the sign turned: both start a decay from |q|), as (index, |q|).
/// A `circular` record (one period of a periodic response) wraps around: every sample can.
pub(super) fn extrema(q: &[f64], len: usize, circular: bool) -> Vec<(usize, f64)> {
    let n = q.len();
    let (start, end) = if circular {
        (0, n)
    } else {
        (1, n.saturating_sub(len))
    };
    (start..end)
        .filter_map(|i| {
            let (a, b, c) = (q[(i + n - 1) % n], q[i], q[(i + 1) % n]);
            if b > a && b >= c && b > 0.0 {
                Some((i, b))
            } else if b < a && b <= c && b < 0.0 {
                Some((i, -b))
            } else {
                None
            }
        })
        .collect()
}

/// The band edges: `levels` bands between the `lo` and `hi` quantiles of the extrema's
/// values, each holding the same share of them.
pub(super) fn level_edges(values: &[f64], levels: usize, lo: f64, hi: f64) -> Vec<f64> {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let at = |p: f64| {
        let x = p * (v.len() - 1) as f64;
        let (i, f) = (x.floor() as usize, x.fract());
        v[i] + f * (v[(i + 1).min(v.len() - 1)] - v[i])
    };
    (0..=levels)
        .map(|k| at(lo + (hi - lo) * k as f64 / levels as f64))
        .collect()
}

/// The band of `edges` holding `a` (the top edge belongs to the top band).
pub(super) fn band_of(edges: &[f64], a: f64) -> Option<usize> {
    let bands = edges.len().checked_sub(1)?;
    (0..bands)
        .find(|&k| a >= edges[k] && (a < edges[k + 1] || (k + 1 == bands && a <= edges[k + 1])))
}

/// Each band's segment sums, by group: the segment of `len` samples from each extremum
/// whose |value| lies in the band, signed so that it starts positive; extrema assigned to
/// `groups` equal stretches of the record by their time.
pub(super) fn level_sums(
    q: &[f64],
    triggers: &[(usize, f64)],
    edges: &[f64],
    len: usize,
    groups: usize,
) -> Vec<LevelSums> {
    let levels = edges.len().saturating_sub(1);
    let mut out = vec![
        LevelSums {
            sums: vec![vec![0.0; len]; groups],
            counts: vec![0; groups],
            values: vec![0.0; groups],
        };
        levels
    ];
    let n = q.len().max(1);
    for &(i, v) in triggers {
        // (A circular record's segments wrap; others' never reach its end.)
        // The band holding v (the last edge belongs to the top band).
        let Some(k) = band_of(edges, v) else {
            continue;
        };
        let g = (i * groups / n).min(groups - 1);
        let sign = q[i].signum();
        let l = &mut out[k];
        l.sums[g]
            .iter_mut()
            .zip(i..i + len)
            .for_each(|(a, j)| *a += sign * q[j % n]);
        l.counts[g] += 1;
        l.values[g] += v;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each band's signature is the mean of the segments from its extrema (a minimum's
    /// turned), computed here directly; leaving a group out removes exactly its segments.
    #[test]
    fn signatures_are_the_band_means_of_the_segments() {
        let q: Vec<f64> = (0..3000)
            .map(|i| {
                let t = i as f64 / 100.0;
                (1.0 + 0.5 * (0.3 * t).sin()) * (2.0 * std::f64::consts::PI * 5.0 * t).cos()
                    + 0.2 * (2.0 * std::f64::consts::PI * 13.0 * t).sin()
            })
            .collect();
        let len = 40;
        let ext = extrema(&q, len, false);
        assert!(
            ext.iter()
                .all(|&(i, v)| v > 0.0 && (q[i].abs() - v).abs() < 1e-15)
        );
        let values: Vec<f64> = ext.iter().map(|e| e.1).collect();
        let edges = level_edges(&values, 3, 0.0, 1.0);
        let groups = 4;
        let sums = level_sums(&q, &ext, &edges, len, groups);
        for (k, l) in sums.iter().enumerate() {
            let inside: Vec<usize> = ext
                .iter()
                .filter(|e| e.1 >= edges[k] && (e.1 < edges[k + 1] || k == 2))
                .map(|e| e.0)
                .collect();
            assert_eq!(l.total(), inside.len());
            for skip in [None, Some(1)] {
                let kept: Vec<usize> = inside
                    .iter()
                    .copied()
                    .filter(|&i| skip != Some(i * groups / q.len()))
                    .collect();
                let (s, v) = l.signature(skip).expect("triggers");
                for j in 0..len {
                    let want = kept.iter().map(|&i| q[i].signum() * q[i + j]).sum::<f64>()
                        / kept.len() as f64;
                    assert!((s[j] - want).abs() < 1e-12, "band {k} lag {j}");
                }
                let mean = kept.iter().map(|&i| q[i].abs()).sum::<f64>() / kept.len() as f64;
                assert!((v - mean).abs() < 1e-12);
            }
        }
    }
}
