//! Channels that carry no signal: a sensor that recorded nothing (every value NaN or
//! infinite) or a constant (a disconnected or saturated channel). Left in, such a channel
//! either stops the analysis at its first NaN or adds a column of zeros to every
//! correlation; it is dropped from the default channel list and named, while a NaN inside
//! a channel that does carry a signal stays the error that names its cell.

use super::Table;

/// Why a channel carries no signal.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Dead {
    /// No value of it is finite (all NaN or infinite).
    NoFiniteValue,
    /// Every value is this one.
    Constant(f64),
}

/// A channel left out of the default list, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct DeadChannel {
    /// The column's name.
    pub name: String,
    /// Why it carries no signal.
    pub why: Dead,
}

impl std::fmt::Display for DeadChannel {
    /// `` `s3` (no finite value) ``, `` `s7` (constant 0) ``.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.why {
            Dead::NoFiniteValue => write!(f, "`{}` (no finite value)", self.name),
            Dead::Constant(v) => write!(f, "`{}` (constant {v})", self.name),
        }
    }
}

/// Why `column` carries no signal, if it does not: no finite value, or (two samples or
/// more) every value equal to the first.
pub(crate) fn dead(column: &[f64]) -> Option<Dead> {
    let first = column.first()?;
    if column.iter().all(|v| !v.is_finite()) {
        return Some(Dead::NoFiniteValue);
    }
    (column.len() > 1 && first.is_finite() && column.iter().all(|v| v == first))
        .then_some(Dead::Constant(*first))
}

/// The channels a record's analysis takes by default: every column but the time column
/// ([`Table::time_column`]), those named in `besides` (a force, say) and those that carry
/// no signal, which are returned apart so that the caller can say so.
pub fn default_channels(t: &Table, besides: &[&str]) -> (Vec<String>, Vec<DeadChannel>) {
    let time = t.time_column();
    let mut names = Vec::new();
    let mut dropped = Vec::new();
    for (i, n) in t.names.iter().enumerate() {
        if besides.contains(&n.as_str()) || Some(i) == time {
            continue;
        }
        match dead(&t.columns[i]) {
            Some(why) => dropped.push(DeadChannel {
                name: n.clone(),
                why,
            }),
            None => names.push(n.clone()),
        }
    }
    (names, dropped)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn channels_without_a_signal_are_set_apart_and_named() {
        let n = 40;
        let t = Table::new(
            Path::new("r.csv"),
            ["t", "a", "nan", "flat", "holed", "u"]
                .map(String::from)
                .to_vec(),
            vec![
                (0..n).map(|k| k as f64 * 0.1).collect(),
                (0..n).map(|k| (k as f64).sin()).collect(),
                vec![f64::NAN; n],
                vec![0.5; n],
                // A NaN inside a channel with a signal is not a dead channel: it stays the
                // error that names its cell when the channel is taken.
                (0..n)
                    .map(|k| if k == 7 { f64::NAN } else { (k as f64).cos() })
                    .collect(),
                (0..n).map(|k| (k as f64 * 0.3).sin()).collect(),
            ],
        );
        let (names, dropped) = default_channels(&t, &["u"]);
        assert_eq!(names, ["a", "holed"]);
        assert_eq!(
            dropped.iter().map(ToString::to_string).collect::<Vec<_>>(),
            ["`nan` (no finite value)", "`flat` (constant 0.5)"]
        );
        assert!(dead(&[f64::INFINITY, f64::NAN]) == Some(Dead::NoFiniteValue));
        // One sample is not a constant: there is nothing to compare it with.
        assert_eq!(dead(&[1.0]), None);
        assert_eq!(dead(&[]), None);
    }
}
