//! A structure's geometry for drawing mode shapes: its nodes (name, x, y, z) and the lines
//! between them, from two whitespace- or tab-separated text files (the steel frame's
//! `grid.txt` and `lines.txt`): a header line, then one node (`name x y z`) or one line
//! (`name name`) per row.

use std::path::Path;

use super::IoError;

/// Nodes and lines.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Geometry {
    /// Each node's name and position.
    pub nodes: Vec<(String, [f64; 3])>,
    /// Lines as pairs of indices into `nodes`.
    pub lines: Vec<[usize; 2]>,
}

/// The rows of a whitespace-separated file after its header line, with their 1-based line
/// numbers; blank lines skipped.
fn rows(path: &Path) -> Result<Vec<(usize, Vec<String>)>, IoError> {
    let text = std::fs::read_to_string(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(text
        .lines()
        .enumerate()
        .skip(1)
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| (i + 1, l.split_whitespace().map(str::to_string).collect()))
        .collect())
}

/// Read the nodes of `grid` and, if given, the lines of `lines` (each naming two nodes of
/// the grid).
pub fn read_geometry(grid: &Path, lines: Option<&Path>) -> Result<Geometry, IoError> {
    let bad = |path: &Path, row: usize, what: String| IoError::Malformed {
        path: path.to_path_buf(),
        row,
        what,
    };
    let mut nodes: Vec<(String, [f64; 3])> = Vec::new();
    for (row, cells) in rows(grid)? {
        let [name, x, y, z] = cells.as_slice() else {
            return Err(bad(
                grid,
                row,
                format!("expected `name x y z`, found {} cells", cells.len()),
            ));
        };
        let mut xyz = [0.0; 3];
        for (v, t) in xyz.iter_mut().zip([x, y, z]) {
            *v = t
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(grid, row, format!("`{t}` is not a coordinate")))?;
        }
        if nodes.iter().any(|n| &n.0 == name) {
            return Err(bad(grid, row, format!("node {name} is listed twice")));
        }
        nodes.push((name.clone(), xyz));
    }
    if nodes.is_empty() {
        return Err(IoError::Empty {
            path: grid.to_path_buf(),
        });
    }
    let mut out = Vec::new();
    if let Some(path) = lines {
        for (row, cells) in rows(path)? {
            let [a, b] = cells.as_slice() else {
                return Err(bad(
                    path,
                    row,
                    format!("expected two node names, found {} cells", cells.len()),
                ));
            };
            let index = |n: &String| {
                nodes.iter().position(|m| &m.0 == n).ok_or_else(|| {
                    bad(
                        path,
                        row,
                        format!(
                            "node {n} is not in the geometry's nodes ({})",
                            grid.display()
                        ),
                    )
                })
            };
            out.push([index(a)?, index(b)?]);
        }
    }
    Ok(Geometry { nodes, lines: out })
}

/// The geometry to draw merged setups on: `grid` (and `lines`) when given, else a pyOMA setup
/// folder's own `grid.txt` and `lines.txt`, else none; with the file the nodes came from.
pub fn setups_geometry(
    setups: &Path,
    grid: Option<&Path>,
    lines: Option<&Path>,
) -> Result<Option<(Geometry, std::path::PathBuf)>, IoError> {
    let (grid, lines) = match grid {
        Some(g) => (g.to_path_buf(), lines.map(Path::to_path_buf)),
        None if setups.is_dir() && setups.join("grid.txt").is_file() => {
            let l = setups.join("lines.txt");
            (setups.join("grid.txt"), l.is_file().then_some(l))
        }
        None => return Ok(None),
    };
    let g = read_geometry(&grid, lines.as_deref())?;
    Ok(Some((g, grid)))
}

impl Geometry {
    /// Check the nodes the channels name against the geometry: a channel's node missing from
    /// it is an error; the geometry's nodes no channel measures are returned (drawn at rest).
    pub fn unmeasured<'a>(
        &self,
        grid: &Path,
        measured: impl IntoIterator<Item = &'a str>,
    ) -> Result<Vec<String>, IoError> {
        let measured: Vec<&str> = measured.into_iter().collect();
        if let Some(missing) = measured
            .iter()
            .find(|m| !self.nodes.iter().any(|n| n.0 == **m))
        {
            return Err(IoError::Params {
                path: grid.to_path_buf(),
                what: format!(
                    "a channel measures node {missing}, which the geometry does not have"
                ),
            });
        }
        Ok(self
            .nodes
            .iter()
            .filter(|n| !measured.contains(&n.0.as_str()))
            .map(|n| n.0.clone())
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::file_path;

    #[test]
    fn the_steel_frames_geometry_reads_and_bad_files_are_named() {
        let grid = file_path("grid.txt");
        let lines = file_path("lines.txt");
        std::fs::write(&grid, "node x y z\n1 0 0 0\n2 0 0 1.5\n\n3 1 0 1.5\n").unwrap();
        std::fs::write(&lines, "a b\n1 2\n2 3\n").unwrap();
        let g = read_geometry(&grid, Some(&lines)).unwrap();
        assert_eq!(g.nodes.len(), 3);
        assert_eq!(g.lines, [[0, 1], [1, 2]]);
        assert_eq!(g.unmeasured(&grid, ["2", "3"]).unwrap(), ["1"]);
        let e = g.unmeasured(&grid, ["2", "9"]).unwrap_err().to_string();
        assert!(
            e.contains("measures node 9, which the geometry does not have"),
            "{e}"
        );
        std::fs::write(&lines, "a b\n1 2\n2 7\n").unwrap();
        let e = read_geometry(&grid, Some(&lines)).unwrap_err().to_string();
        assert!(
            e.contains("row 3: node 7 is not in the geometry's nodes"),
            "{e}"
        );
        for (text, says) in [
            (
                "n x y z\n1 0 0\n",
                "row 2: expected `name x y z`, found 3 cells",
            ),
            ("n x y z\n1 0 a 0\n", "`a` is not a coordinate"),
            (
                "n x y z\n1 0 0 0\n1 0 0 1\n",
                "row 3: node 1 is listed twice",
            ),
            ("n x y z\n", "the record is empty"),
        ] {
            std::fs::write(&grid, text).unwrap();
            let e = read_geometry(&grid, None).unwrap_err().to_string();
            assert!(e.contains(says), "{text}: {e}");
        }
    }
}
