//! A table of modal estimates made by another monitoring system (`hyst track --estimates`):
//! one row per record, a column `record`, an optional `time` (s) and per tracked mode
//! `<mode>_hz`, optionally `<mode>_hz_se` and `<mode>_damping`; an empty cell is a mode the
//! record did not have.

use std::path::Path;

use hyst_monitor::ModeEstimate;

use super::delimited::DelimitedRows;
use super::{Delimiter, IoError};

/// An estimates table as read.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimatesTable {
    /// The tracked modes' names, in the order of their `<mode>_hz` columns.
    pub modes: Vec<String>,
    /// Each row: the record's name, its time if the table gives one, and each mode's
    /// estimate (`None` where the cell is empty).
    pub rows: Vec<(String, Option<f64>, Vec<Option<ModeEstimate>>)>,
}

/// What a column of the table is.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Column {
    Record,
    Time,
    Frequency(usize),
    FrequencySe(usize),
    Damping(usize),
}

/// The columns of `header`, and the modes' names; an unknown column, or a mode's standard
/// error or damping without its frequency, is the error.
fn columns(header: &[String], path: &Path) -> Result<(Vec<Column>, Vec<String>), IoError> {
    let bad = |what: String| IoError::Malformed {
        path: path.to_path_buf(),
        row: 1,
        what,
    };
    let modes: Vec<String> = header
        .iter()
        .filter_map(|h| h.strip_suffix("_hz").map(str::to_string))
        .filter(|m| !m.is_empty())
        .collect();
    let mode_of = |name: &str, suffix: &str| {
        let m = name.strip_suffix(suffix)?;
        modes.iter().position(|x| x == m)
    };
    let mut cols = Vec::with_capacity(header.len());
    for h in header {
        let c = match h.as_str() {
            "record" => Column::Record,
            "time" => Column::Time,
            _ => {
                if let Some(k) = mode_of(h, "_hz") {
                    Column::Frequency(k)
                } else if let Some(k) = mode_of(h, "_hz_se") {
                    Column::FrequencySe(k)
                } else if let Some(k) = mode_of(h, "_damping") {
                    Column::Damping(k)
                } else {
                    return Err(bad(format!(
                        "unknown column `{h}`: expected `record`, `time`, and per mode \
                         `<mode>_hz` with optional `<mode>_hz_se` and `<mode>_damping` \
                         (a standard error or damping needs its mode's `_hz` column)"
                    )));
                }
            }
        };
        cols.push(c);
    }
    if !cols.contains(&Column::Record) {
        return Err(IoError::MissingColumn {
            path: path.to_path_buf(),
            column: "record".into(),
            available: header.join(","),
        });
    }
    if modes.is_empty() {
        return Err(bad(
            "no mode column: name each tracked mode's frequency `<mode>_hz`".into(),
        ));
    }
    Ok((cols, modes))
}

/// Read an estimates table (delimited text read as a record's CSV is, see
/// [`read_csv_with`](super::read_csv_with)): empty cells are modes a record did not have;
/// every other cell a finite number, frequencies and standard errors positive; the times,
/// when given, increasing; no record twice; every mode with a value somewhere.
pub fn read_estimates(path: &Path) -> Result<EstimatesTable, IoError> {
    let rows = DelimitedRows::open(path, Delimiter::Auto)?;
    let (header, sep) = (rows.names.clone(), rows.sep);
    let (cols, modes) = columns(&header, path)?;
    let mut out: Vec<(String, Option<f64>, Vec<Option<ModeEstimate>>)> = Vec::new();
    let mut last_time: Option<(f64, usize)> = None;
    let mut first_row: std::collections::HashMap<String, usize> = std::collections::HashMap::new();
    for r in rows {
        let (row, cells) = r?;
        let malformed = |what: String| IoError::Malformed {
            path: path.to_path_buf(),
            row,
            what,
        };
        let mut record = String::new();
        let mut time = None;
        let mut f: Vec<Option<f64>> = vec![None; modes.len()];
        let mut se: Vec<Option<f64>> = vec![None; modes.len()];
        let mut damping: Vec<Option<f64>> = vec![None; modes.len()];
        for ((c, column), text) in cols.iter().zip(&header).zip(cells.iter()) {
            if let Column::Record = c {
                record = text.to_string();
                continue;
            }
            if text.trim().is_empty() {
                continue;
            }
            let v = super::delimited::number(text, sep)
                .filter(|v| v.is_finite())
                .ok_or_else(|| IoError::NotANumber {
                    path: path.to_path_buf(),
                    row,
                    column: column.clone(),
                    text: text.to_string(),
                })?;
            let positive = || {
                if v > 0.0 {
                    Ok(v)
                } else {
                    Err(malformed(format!("`{column}` is {v}; it must be positive")))
                }
            };
            match *c {
                Column::Time => time = Some(v),
                Column::Frequency(k) => f[k] = Some(positive()?),
                Column::FrequencySe(k) => se[k] = Some(positive()?),
                Column::Damping(_) if !(0.0..=1.0).contains(&v) => {
                    return Err(malformed(format!(
                        "`{column}` is {v}; a damping ratio lies between 0 and 1"
                    )));
                }
                Column::Damping(k) => damping[k] = Some(v),
                Column::Record => {}
            }
        }
        if record.trim().is_empty() {
            return Err(malformed("the record's name is empty".into()));
        }
        if let Some(first) = first_row.insert(record.clone(), row) {
            return Err(malformed(format!(
                "record `{record}` is listed twice (rows {first} and {row})"
            )));
        }
        if let (Some(t), Some((prev, prev_row))) = (time, last_time)
            && t <= prev
        {
            return Err(malformed(format!(
                "time {t} s is not after row {prev_row}'s {prev} s: the rows must be in time order"
            )));
        }
        if let Some(t) = time {
            last_time = Some((t, row));
        }
        let mut estimates = Vec::with_capacity(modes.len());
        for k in 0..modes.len() {
            match f[k] {
                Some(freq) => estimates.push(Some(ModeEstimate {
                    frequency_hz: freq,
                    frequency_se_hz: se[k],
                    damping_ratio: damping[k].unwrap_or(f64::NAN),
                    damping_se: None,
                    shape: None,
                })),
                None if se[k].is_some() || damping[k].is_some() => {
                    return Err(malformed(format!(
                        "mode `{}` has a standard error or damping but no frequency",
                        modes[k]
                    )));
                }
                None => estimates.push(None),
            }
        }
        out.push((record, time, estimates));
    }
    if out.is_empty() {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    for (k, m) in modes.iter().enumerate() {
        if out.iter().all(|(_, _, e)| e[k].is_none()) {
            return Err(IoError::Malformed {
                path: path.to_path_buf(),
                row: 1,
                what: format!("column `{m}_hz` has no values: a mode no record had"),
            });
        }
    }
    Ok(EstimatesTable { modes, rows: out })
}

impl EstimatesTable {
    /// The table's records as tracking takes them, their covariates joined by record name
    /// from `covariates` ([`super::read_covariates`]'s map and names; a record without them
    /// gets NaN, tracked and not charted); each record's time the table's, else the
    /// covariates file's, else its row's number.
    pub fn records(&self, covariates: &super::Covariates) -> Vec<hyst_monitor::RecordEstimates> {
        let (covs, names) = covariates;
        self.rows
            .iter()
            .enumerate()
            .map(|(i, (name, time, modes))| {
                let (cov_time, values) = match covs.get(name) {
                    Some((t, v)) => (*t, v.clone()),
                    None => (None, vec![f64::NAN; names.len()]),
                };
                hyst_monitor::RecordEstimates {
                    name: name.clone(),
                    time: time.or(cov_time).unwrap_or(i as f64),
                    covariates: values,
                    modes: modes.clone(),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::file_path;

    /// Read `text` from a file of its own (the tests run in parallel).
    fn read(text: &str) -> Result<EstimatesTable, String> {
        let name = format!(
            "estimates-{}.csv",
            std::thread::current()
                .name()
                .unwrap_or("t")
                .replace("::", "_")
        );
        let p = file_path(&name);
        std::fs::write(&p, text).unwrap();
        read_estimates(&p).map_err(|e| e.to_string())
    }

    #[test]
    fn a_table_is_read_with_its_gaps() {
        let t = read(
            "record,time,first_hz,first_hz_se,first_damping,second_hz\n\
             a,0,4.01,0.002,0.011,9.5\n\
             b,3600,,,,9.52\n",
        )
        .unwrap();
        assert_eq!(t.modes, ["first", "second"]);
        assert_eq!(t.rows.len(), 2);
        let a = t.rows[0].2[0].as_ref().unwrap();
        assert_eq!(
            (a.frequency_hz, a.frequency_se_hz, a.damping_ratio),
            (4.01, Some(0.002), 0.011)
        );
        assert!(t.rows[1].2[0].is_none());
        assert_eq!(t.rows[1].1, Some(3600.0));
        assert!(t.rows[1].2[1].as_ref().unwrap().damping_ratio.is_nan());
    }

    #[test]
    fn bad_tables_are_named() {
        for (text, says) in [
            (
                "record,first_hz,colour\na,4,red\n",
                "unknown column `colour`",
            ),
            (
                "record,first_hz,second_hz\na,4,\nb,4.1,\n",
                "`second_hz` has no values",
            ),
            (
                "record,time,first_hz\na,10,4\nb,5,4.1\n",
                "row 3: time 5 s is not after row 2's 10 s",
            ),
            (
                "record,first_hz,first_hz_se\na,4,\nb,,0.1\n",
                "row 3: mode `first` has a standard error",
            ),
            (
                "record,first_hz\na,4\na,4.1\n",
                "`a` is listed twice (rows 2 and 3)",
            ),
            (
                "record,first_hz,first_damping\na,4,-5\n",
                "row 2: `first_damping` is -5; a damping ratio lies between 0 and 1",
            ),
            (
                "record,first_hz,first_damping\na,4,1.5\n",
                "`first_damping` is 1.5",
            ),
            (
                "record,first_hz\na,-4\n",
                "`first_hz` is -4; it must be positive",
            ),
            ("record,first_hz\na,four\n", "four"),
            ("time,first_hz\n0,4\n", "record"),
            ("record,time\na,0\n", "no mode column"),
            (
                "record,second_hz_se\na,0.1\n",
                "unknown column `second_hz_se`",
            ),
        ] {
            let e = read(text).unwrap_err();
            assert!(e.contains(says), "{text:?}: {e}");
        }
    }

    /// A valid table with bytes replaced, cut or added never panics the reader; what it
    /// reads has positive frequencies, one estimate slot per mode, and times in order.
    mod fuzz {
        use super::*;
        use crate::test_files::mutated;
        use proptest::prelude::*;

        const VALID: &[u8] = b"record,time,first_hz,first_hz_se,first_damping,second_hz\n\
            a,0,4.01,0.002,0.011,9.5\nb,3600,,,,9.52\nc,7200,4.02,0.003,0.012,\n";

        proptest! {
            #[test]
            fn mutated_tables_read_or_fail_cleanly(
                flips in proptest::collection::vec((0usize..120, any::<u8>()), 0..6),
                cut in 0usize..140,
                tail in proptest::collection::vec(any::<u8>(), 0..20),
            ) {
                let name = format!(
                    "fuzz-est-{}.csv",
                    std::thread::current().name().unwrap_or("t").replace("::", "_")
                );
                let p = file_path(&name);
                std::fs::write(&p, mutated(VALID.to_vec(), &flips, cut, &tail)).unwrap();
                if let Ok(t) = read_estimates(&p) {
                    let mut last = f64::NEG_INFINITY;
                    for (_, time, e) in &t.rows {
                        prop_assert_eq!(e.len(), t.modes.len());
                        prop_assert!(e.iter().flatten().all(|m| m.frequency_hz > 0.0));
                        prop_assert!(e.iter().flatten().all(|m| m.damping_ratio.is_nan()
                            || (0.0..=1.0).contains(&m.damping_ratio)));
                        if let Some(time) = time {
                            prop_assert!(*time > last);
                            last = *time;
                        }
                    }
                }
            }
        }
    }
}
