//! A campaign's record files put in time order and joined to their covariates, as
//! `hyst track --inputs … --covariates …` takes them: by their times in the covariates file
//! when it gives one for every file (a file it times that is not among the records is a gap,
//! kept in its place and said), else by the files' names as listed; each record's time and
//! covariates by its file's name ([`covariates_of`]).

use std::collections::HashSet;
use std::path::PathBuf;

use hyst_io::Covariates;

/// Why a gap in the campaign has no modes.
pub const GAP_REASON: &str = "no such file: listed with a time in the covariates file, not among the records (a gap in the campaign)";

/// The campaign's records in their order.
#[derive(Debug, Clone, PartialEq)]
pub struct CampaignFiles {
    /// The records in order, the gaps among them by name.
    pub files: Vec<PathBuf>,
    /// The records the covariates file times that no file is (each in `files` too).
    pub gaps: Vec<String>,
    /// Whether the order is the covariates' times (else the names', as listed).
    pub by_time: bool,
}

/// `files` (in natural order of their names) put in time order with the gaps among them, as
/// the covariates file `covariates` says.
pub fn order_records(mut files: Vec<PathBuf>, covariates: &Covariates) -> CampaignFiles {
    let covs = &covariates.0;
    let name = |f: &PathBuf| f.file_name().map(|n| n.to_string_lossy().into_owned());
    let have: HashSet<String> = files.iter().filter_map(name).collect();
    let timed = |n: &String| covs.get(n).is_some_and(|(t, _)| t.is_some());
    // Gaps only when every record has a time: the order is then the times'.
    let mut gaps: Vec<String> = Vec::new();
    if !covs.is_empty() && have.iter().all(timed) {
        gaps = covs
            .keys()
            .filter(|n| !have.contains(*n) && timed(n))
            .cloned()
            .collect();
        gaps.sort();
        files.extend(gaps.iter().map(PathBuf::from));
    }
    let time = |f: &PathBuf| name(f).and_then(|n| covs.get(&n)).and_then(|(t, _)| *t);
    let by_time = !covs.is_empty() && files.iter().all(|f| time(f).is_some());
    if by_time {
        files.sort_by(|x, y| time(x).unwrap_or(0.0).total_cmp(&time(y).unwrap_or(0.0)));
    }
    CampaignFiles {
        files,
        gaps,
        by_time,
    }
}

/// Record `name`'s time and covariates from the covariates file: its time there, else
/// `fallback_time`; its covariates, NaN each when the file does not name it.
pub fn covariates_of(covariates: &Covariates, name: &str, fallback_time: f64) -> (f64, Vec<f64>) {
    match covariates.0.get(name) {
        Some((t, v)) => (t.unwrap_or(fallback_time), v.clone()),
        None => (fallback_time, vec![f64::NAN; covariates.1.len()]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn covariates(rows: &[(&str, Option<f64>)]) -> Covariates {
        let map = rows
            .iter()
            .map(|(n, t)| (n.to_string(), (*t, vec![1.0])))
            .collect();
        (map, vec!["temperature".into()])
    }

    fn paths(names: &[&str]) -> Vec<PathBuf> {
        names
            .iter()
            .map(|n| PathBuf::from(format!("dir/{n}")))
            .collect()
    }

    #[test]
    fn records_go_in_time_order_with_the_gaps_among_them() {
        let c = covariates(&[
            ("b.csv", Some(2.0)),
            ("a.csv", Some(3.0)),
            ("gap.csv", Some(2.5)),
        ]);
        let r = order_records(paths(&["a.csv", "b.csv"]), &c);
        assert!(r.by_time);
        assert_eq!(r.gaps, ["gap.csv"]);
        let names: Vec<_> = r.files.iter().map(|f| f.file_name().unwrap()).collect();
        assert_eq!(names, ["b.csv", "gap.csv", "a.csv"]);
        assert_eq!(covariates_of(&c, "gap.csv", 9.0), (2.5, vec![1.0]));
    }

    #[test]
    fn without_a_time_for_every_record_the_names_order_and_there_is_no_gap() {
        let c = covariates(&[
            ("b.csv", None),
            ("a.csv", Some(3.0)),
            ("gap.csv", Some(2.5)),
        ]);
        let r = order_records(paths(&["a.csv", "b.csv"]), &c);
        assert!(!r.by_time);
        assert!(r.gaps.is_empty());
        assert_eq!(r.files, paths(&["a.csv", "b.csv"]));
        assert_eq!(covariates_of(&c, "b.csv", 1.0), (1.0, vec![1.0]));
        let (t, v) = covariates_of(&c, "other.csv", 4.0);
        assert_eq!(t, 4.0);
        assert!(v.len() == 1 && v[0].is_nan());
        let none = order_records(paths(&["a.csv"]), &Default::default());
        assert!(!none.by_time && none.gaps.is_empty());
    }
}
