//! The inputs of a monitoring run: the record files a list of paths names (folders
//! expanded), and the covariates file (per record: its time and covariates).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use super::IoError;

/// Per record name, its time (s, if the file gives one) and its covariates; and the
/// covariates' names.
pub type Covariates = (HashMap<String, (Option<f64>, Vec<f64>)>, Vec<String>);

/// The files `paths` name: each file as given, each folder's files in name order.
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
            inside.sort();
            files.extend(inside);
        } else {
            files.push(p.clone());
        }
    }
    Ok(files)
}

/// Read a covariates file: a CSV whose header names a column `record` (the record's file
/// name, or its window's number), optionally `time` (s), and one column per covariate; every
/// other cell a number.
pub fn read_covariates(path: &Path) -> Result<Covariates, IoError> {
    let table = |what: String| IoError::Malformed {
        path: path.to_path_buf(),
        row: 0,
        what,
    };
    let text = std::fs::read_to_string(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<String> = lines
        .next()
        .ok_or_else(|| IoError::NoHeader {
            path: path.to_path_buf(),
        })?
        .split(',')
        .map(|s| s.trim().to_string())
        .collect();
    let at = header
        .iter()
        .position(|h| h == "record")
        .ok_or_else(|| IoError::MissingColumn {
            path: path.to_path_buf(),
            column: "record".into(),
            available: header.join(","),
        })?;
    let time = header.iter().position(|h| h == "time");
    let names: Vec<String> = header
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != at && Some(*i) != time)
        .map(|(_, h)| h.clone())
        .collect();
    let mut out = HashMap::new();
    for (k, line) in lines.enumerate() {
        let row = k + 2;
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if cells.len() != header.len() {
            return Err(IoError::CellCount {
                path: path.to_path_buf(),
                row,
                found: cells.len(),
                expected: header.len(),
            });
        }
        let number = |i: usize| {
            cells[i].parse::<f64>().map_err(|_| IoError::NotANumber {
                path: path.to_path_buf(),
                row,
                column: header[i].clone(),
                text: cells[i].to_string(),
            })
        };
        let t = time.map(number).transpose()?;
        let values = (0..cells.len())
            .filter(|&i| i != at && Some(i) != time)
            .map(number)
            .collect::<Result<Vec<f64>, IoError>>()?;
        if out.insert(cells[at].to_string(), (t, values)).is_some() {
            return Err(table(format!("record `{}` is listed twice", cells[at])));
        }
    }
    Ok((out, names))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_files::file_path;

    #[test]
    fn covariates_are_read_by_record_and_bad_files_named() {
        let p = file_path("cov.csv");
        std::fs::write(&p, "record,time,temperature\na.csv,0,10.5\nb.csv,3600,11\n").unwrap();
        let (map, names) = read_covariates(&p).unwrap();
        assert_eq!(names, ["temperature"]);
        assert_eq!(map["b.csv"], (Some(3600.0), vec![11.0]));
        for (text, says) in [
            ("name,t\na,1\n", "no column `record`"),
            (
                "record,temperature\na,warm\n",
                "row 2, column `temperature`: `warm` is not a number",
            ),
            (
                "record,temperature\na,1\na,2\n",
                "record `a` is listed twice",
            ),
            ("record,temperature\na\n", "row 2 has 1 cells"),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = read_covariates(&p).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        }
    }
}
