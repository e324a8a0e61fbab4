//! A record's time column checked before it gives or checks the rate: its rows in order and
//! none missing, since the analysis takes the samples as equally spaced.
//!
//! A step that is not positive is a pair of rows out of order, or a restart of the clock; a
//! step beyond [`GAP`] times the record's median step is a gap (a missing sample at least
//! doubles the step; timestamps rounded when written, 3 or 4 ms for 256 Hz written in
//! milliseconds, stay well within it).

use std::path::Path;

use super::IoError;

/// A step this many times the median step is a gap.
pub const GAP: f64 = 1.5;

/// The first step of `time` (the column `column` of the file `path`) that is not positive or
/// is a gap, said with its row (counted from 1 at the first data row, as a cell's is).
pub(crate) fn check_steps(path: &Path, column: &str, time: &[f64]) -> Result<(), IoError> {
    let (_, unit) = unit_of(column);
    if time.len() < 3 {
        return Ok(());
    }
    let steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
    let fail = |k: usize, what: String| IoError::TimeColumn {
        path: path.to_path_buf(),
        column: column.to_string(),
        row: k + 2,
        what,
    };
    if let Some(k) = steps.iter().position(|&d| d <= 0.0) {
        return Err(fail(
            k,
            format!(
                "goes from {} to {}: rows out of order, or the clock restarted; sort the rows or cut the record there",
                time[k],
                time[k + 1]
            ),
        ));
    }
    let mut sorted = steps.clone();
    let middle = sorted.len() / 2;
    let median = *sorted.select_nth_unstable_by(middle, f64::total_cmp).1;
    if let Some(k) = steps.iter().position(|&d| d > GAP * median) {
        return Err(fail(
            k,
            format!(
                "jumps from {} to {} (a step of {:.6} {unit} where the record's is {median:.6} {unit}): about {} sample(s) are missing, and the analysis takes the samples as equally spaced; cut the record there",
                time[k],
                time[k + 1],
                steps[k],
                (steps[k] / median).round() as usize - 1
            ),
        ));
    }
    Ok(())
}

/// Seconds per unit of a time column named `name`, and the unit's symbol: the unit after
/// the name's first word (`time_ms`, `Time (ms)`, `t [us]`, `zeit_min`), seconds when none
/// is written or the word after it is not a unit of time.
pub(crate) fn unit_of(name: &str) -> (f64, &'static str) {
    let lower = name.trim().to_lowercase();
    let (_, rest) = words(&lower);
    let unit = rest.trim_matches(|c: char| "()[]_ ".contains(c) || c.is_whitespace());
    match unit {
        "ms" | "msec" | "millis" | "millisecond" | "milliseconds" => (1e-3, "ms"),
        "us" | "µs" | "μs" | "usec" | "microsecond" | "microseconds" => (1e-6, "µs"),
        "ns" | "nanosecond" | "nanoseconds" => (1e-9, "ns"),
        "min" | "mins" | "minute" | "minutes" => (60.0, "min"),
        "h" | "hr" | "hrs" | "hour" | "hours" => (3600.0, "h"),
        _ => (1.0, "s"),
    }
}

/// Whether a column's name says it holds time (`t`, `time`, `Time (s)`, `zeit_ms`, …): its
/// first word, before any unit.
pub(crate) fn named_time(name: &str) -> bool {
    let lower = name.trim().to_lowercase();
    matches!(
        words(&lower).0,
        "t" | "time" | "times" | "timestamp" | "zeit" | "temps" | "tiempo" | "tempo"
    )
}

/// A column's name split at its first `(`, `[`, `_` or space: its first word, and the rest
/// (where a unit is written).
fn words(name: &str) -> (&str, &str) {
    let at = name
        .find(|c: char| c == '(' || c == '[' || c == '_' || c.is_whitespace())
        .unwrap_or(name.len());
    name.split_at(at)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_time_column_names_its_unit() {
        for (name, seconds) in [
            ("t", 1.0),
            ("Time (s)", 1.0),
            ("time_ms", 1e-3),
            ("Time (ms)", 1e-3),
            ("t [us]", 1e-6),
            ("zeit_min", 60.0),
            ("time [h]", 3600.0),
            ("timestamp", 1.0),
            ("time_utc", 1.0),
        ] {
            assert_eq!(unit_of(name).0, seconds, "{name}");
        }
        let e = check_steps(
            Path::new("r.csv"),
            "time_ms",
            &[0.0, 50.0, 100.0, 150.0, 400.0],
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("a step of 250.000000 ms"), "{e}");
    }

    fn said(time: &[f64]) -> String {
        check_steps(Path::new("r.csv"), "t", time)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn rows_out_of_order_a_restart_and_a_gap_are_said_with_the_row() {
        let t: Vec<f64> = (0..200).map(|k| k as f64 / 20.0).collect();
        check_steps(Path::new("r.csv"), "t", &t).unwrap();
        let mut swapped = t.clone();
        swapped.swap(40, 41);
        // Samples 41 and 42 (rows 41, 42) swapped: the step into row 42 goes back.
        let e = said(&swapped);
        assert!(
            e.starts_with("r.csv: the time column `t` at row 42 goes from 2.05 to 2:"),
            "{e}"
        );
        let restarted: Vec<f64> = t[..100].iter().chain(&t[..100]).copied().collect();
        assert!(
            said(&restarted).contains("at row 101 goes from 4.95 to 0"),
            "{}",
            said(&restarted)
        );
        // 100 rows missing after row 60 (the rate would read 1.2 % low).
        let gapped: Vec<f64> = t[..60].iter().chain(&t[160..]).copied().collect();
        let e = said(&gapped);
        assert!(e.contains("at row 61 jumps from 2.95 to 8"), "{e}");
        assert!(e.contains("about 100 sample(s) are missing"), "{e}");
        // Timestamps of 256 Hz written in milliseconds step by 3 or 4 ms: no gap.
        let ms: Vec<f64> = (0..512)
            .map(|k| (k as f64 / 256.0 * 1e3).round() / 1e3)
            .collect();
        check_steps(Path::new("r.csv"), "t", &ms).unwrap();
    }
}
