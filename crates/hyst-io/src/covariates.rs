//! The inputs of a monitoring run: the record files a list of paths names (folders
//! expanded), and the covariates file (per record: its time and covariates).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::delimited::DelimitedRows;
use super::{Delimiter, IoError};

/// Per record name, its time (s, if the file gives one) and its covariates; and the
/// covariates' names.
pub type Covariates = (HashMap<String, (Option<f64>, Vec<f64>)>, Vec<String>);

/// The files `paths` name: each file as given, each folder's files in natural name order
/// (`rec_2` before `rec_10`).
pub fn list_records(paths: &[PathBuf]) -> Result<Vec<PathBuf>, IoError> {
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let entries = std::fs::read_dir(p).map_err(|source| IoError::File {
                path: p.clone(),
                source,
            })?;
            let mut inside: Vec<PathBuf> = entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.is_file())
                .collect();
            inside.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
            files.extend(inside);
        } else {
            files.push(p.clone());
        }
    }
    Ok(files)
}

/// Order of names as a person reads them: runs of digits compared as numbers (`rec_2`
/// before `rec_10`), the rest as text.
pub(crate) fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    let (mut x, mut y) = (a.as_bytes(), b.as_bytes());
    loop {
        match (x.first(), y.first()) {
            (None, None) => return a.cmp(b),
            (None, _) => return std::cmp::Ordering::Less,
            (_, None) => return std::cmp::Ordering::Greater,
            (Some(p), Some(q)) if p.is_ascii_digit() && q.is_ascii_digit() => {
                let dx = x.iter().take_while(|c| c.is_ascii_digit()).count();
                let dy = y.iter().take_while(|c| c.is_ascii_digit()).count();
                let (nx, ny) = (trim_zeros(&x[..dx]), trim_zeros(&y[..dy]));
                let o = nx.len().cmp(&ny.len()).then_with(|| nx.cmp(ny));
                if o != std::cmp::Ordering::Equal {
                    return o;
                }
                (x, y) = (&x[dx..], &y[dy..]);
            }
            (Some(p), Some(q)) => {
                if p != q {
                    return p.cmp(q);
                }
                (x, y) = (&x[1..], &y[1..]);
            }
        }
    }
}

fn trim_zeros(d: &[u8]) -> &[u8] {
    let z = d.iter().take_while(|&&c| c == b'0').count();
    &d[z.min(d.len().saturating_sub(1))..]
}

/// Read a covariates file: delimited text read as a record's CSV is (see
/// [`read_csv_with`](super::read_csv_with)) whose header names a column `record` (the record's
/// file name, or its window's number), optionally `time` (s), and one column per covariate;
/// every other cell a number (NaN where a covariate is missing).
pub fn read_covariates(path: &Path) -> Result<Covariates, IoError> {
    let rows = DelimitedRows::open(path, Delimiter::Auto)?;
    let (header, sep) = (rows.names.clone(), rows.sep);
    let at = header
        .iter()
        .position(|h| h == "record")
        .ok_or_else(|| IoError::MissingColumn {
            path: path.to_path_buf(),
            column: "record".into(),
            available: header.join(","),
        })?;
    let time = header.iter().position(|h| h == "time");
    let is_covariate = |i: usize| i != at && Some(i) != time;
    let names: Vec<String> = (0..header.len())
        .filter(|&i| is_covariate(i))
        .map(|i| header[i].clone())
        .collect();
    let mut out = HashMap::new();
    for r in rows {
        let (row, cells) = r?;
        let number = |i: usize| {
            super::delimited::number(&cells[i], sep).ok_or_else(|| IoError::NotANumber {
                path: path.to_path_buf(),
                row,
                column: header[i].clone(),
                text: cells[i].to_string(),
            })
        };
        let t = time.map(number).transpose()?;
        let values = (0..cells.len())
            .filter(|&i| is_covariate(i))
            .map(number)
            .collect::<Result<Vec<f64>, IoError>>()?;
        if out.insert(cells[at].to_string(), (t, values)).is_some() {
            return Err(IoError::Malformed {
                path: path.to_path_buf(),
                row,
                what: format!("record `{}` is listed twice", &cells[at]),
            });
        }
    }
    Ok((out, names))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::file_path;

    #[test]
    fn names_in_natural_order() {
        let mut v = vec!["rec_10", "rec_2", "rec_1", "rec_02b", "a"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, vec!["a", "rec_1", "rec_2", "rec_02b", "rec_10"]);
    }

    #[test]
    fn covariates_are_read_by_record_and_bad_files_named() {
        let p = file_path("cov.csv");
        std::fs::write(&p, "record,time,temperature\na.csv,0,10.5\nb.csv,3600,11\n").unwrap();
        let (map, names) = read_covariates(&p).unwrap();
        assert_eq!(names, ["temperature"]);
        assert_eq!(map["b.csv"], (Some(3600.0), vec![11.0]));
        // Read as a record's CSV is: a spreadsheet's semicolons and decimal commas, quotes.
        std::fs::write(&p, "record;temperature\n\"a;1.csv\";10,5\n").unwrap();
        let (map, _) = read_covariates(&p).unwrap();
        assert_eq!(map["a;1.csv"], (None, vec![10.5]));
        for (text, says) in [
            ("name,t\na,1\n", "no column `record`"),
            (
                "record,temperature\na,warm\n",
                "row 2, column `temperature`: `warm` is not a number",
            ),
            (
                "record,temperature\na,1\na,2\n",
                "row 3: record `a` is listed twice",
            ),
            ("record,temperature\na\n", "row 2 has 1 cells"),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = read_covariates(&p).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        }
    }
}
