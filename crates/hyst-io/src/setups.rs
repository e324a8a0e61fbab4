//! A setup file: the setups of a modal test, which record each reads and where each of its
//! channels is.
//!
//! Delimited text (read as a record's CSV is), one row per channel analysed. Columns:
//! - `setup`: the setup's name (its rows together make it; setups in the order first met);
//! - `file`: its record, relative to the setup file's folder;
//! - `column`: the record's column (a CSV header's name; `0`, `1`, … of an array; `12+Z` of
//!   a Universal File);
//! - `quantity`: `displacement`, `velocity` or `acceleration`;
//! - `reference`: `yes` or `no` (also `true`/`false`, `1`/`0`);
//! - `node`: the node it measures; empty for a Universal File's column, whose point names it;
//! - the direction, in one of three forms: `direction` (`x`, `+y`, `-z`), `dx`, `dy`, `dz`
//!   (a vector), or `azimuth`, `elevation` (degrees: (cos e cos a, cos e sin a, sin e));
//!   none for a Universal File's column, whose point states it;
//! - `gain` (optional, default 1): the factor the channel's reading carries.
//!
//! A column not listed is not analysed. Any other header name is an error.

use std::path::{Path, PathBuf};

use super::delimited::{DelimitedRows, number};
use super::{Delimiter, IoError};
use covssi::multisetup::{Quantity, SetupChannel};

/// One setup as a setup file describes it.
#[derive(Debug, Clone, PartialEq)]
pub struct SetupSpec {
    /// Its name.
    pub name: String,
    /// Its record.
    pub file: PathBuf,
    /// The record's columns analysed, in the file's row order.
    pub columns: Vec<String>,
    /// Where each of those columns is.
    pub channels: Vec<SetupChannel>,
    /// The rate the setup's description states (Hz), for a record that states none.
    pub fs_hz: Option<f64>,
}

/// The header names a setup file may have.
const KNOWN: [&str; 13] = [
    "setup",
    "file",
    "column",
    "quantity",
    "reference",
    "node",
    "direction",
    "dx",
    "dy",
    "dz",
    "azimuth",
    "elevation",
    "gain",
];

/// Read a setup file (columns: setup, file, column, quantity, reference, and node,
/// direction, dx/dy/dz, azimuth/elevation, gain; see the README), or a folder of setups in pyOMA's layout
/// ([`read_pyoma_setups`](super::read_pyoma_setups)).
pub fn read_setups(path: &Path) -> Result<Vec<SetupSpec>, IoError> {
    read_setups_with(path, RecordPaths::InsideFolder)
}

/// Where a setup file's records may be.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum RecordPaths {
    /// Inside the setup file's folder, named by their path from there (the default: a
    /// setup file from elsewhere cannot make hyst read, and quote, any file on the machine).
    #[default]
    InsideFolder,
    /// Anywhere: absolute paths and `..` allowed (`hyst ssi --records-anywhere`).
    Anywhere,
}

/// [`read_setups`], the records' paths allowed as `paths` says.
pub fn read_setups_with(path: &Path, paths: RecordPaths) -> Result<Vec<SetupSpec>, IoError> {
    let setups = if path.is_dir() {
        super::read_pyoma_setups(path)?
    } else {
        read_setup_file(path, paths)?
    };
    for s in &setups {
        check_setup(s, path)?;
    }
    Ok(setups)
}

/// What every setup must hold, whichever layout described it: a regular file as its record,
/// and one channel per axis of a node ([`covssi::multisetup::same_axis`], the merge's own
/// definition; two would make one reading stand for both).
fn check_setup(s: &SetupSpec, path: &Path) -> Result<(), IoError> {
    let bad = |what: String| IoError::Params {
        path: path.to_path_buf(),
        what,
    };
    if s.file.exists() && !s.file.is_file() {
        return Err(bad(format!(
            "setup `{}`: {} is not a regular file; a setup's record is a file",
            s.name,
            s.file.display()
        )));
    }
    for (i, a) in s.channels.iter().enumerate() {
        // One definition of one axis of a node, the merge's.
        if let Some(j) = s.channels[..i]
            .iter()
            .position(|b| covssi::multisetup::same_axis(a, b))
        {
            return Err(bad(format!(
                "setup `{}`: columns `{}` and `{}` both measure node {} along ({:.3}, {:.3}, {:.3}): give each node and axis once",
                s.name,
                s.columns[j],
                s.columns[i],
                a.node,
                a.direction[0],
                a.direction[1],
                a.direction[2]
            )));
        }
    }
    Ok(())
}

/// The setups of a setup file (see the module doc).
fn read_setup_file(path: &Path, paths: RecordPaths) -> Result<Vec<SetupSpec>, IoError> {
    let rows = DelimitedRows::open(path, Delimiter::Auto)?;
    let names = rows.names.clone();
    let sep = rows.sep;
    let malformed = |row: usize, what: String| IoError::Malformed {
        path: path.to_path_buf(),
        row,
        what,
    };
    if let Some(unknown) = names.iter().find(|n| !KNOWN.contains(&n.as_str())) {
        return Err(malformed(
            1,
            format!(
                "unknown column `{unknown}`: a setup file's columns are {}",
                KNOWN.join(", ")
            ),
        ));
    }
    for needed in ["setup", "file", "column", "quantity", "reference"] {
        if !names.iter().any(|n| n == needed) {
            return Err(IoError::MissingColumn {
                path: path.to_path_buf(),
                column: needed.into(),
                available: names.join(","),
            });
        }
    }
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut setups: Vec<SetupSpec> = Vec::new();
    for r in rows {
        let (row, cells) = r?;
        let cell = |name: &str| {
            names
                .iter()
                .position(|n| n == name)
                .map(|i| cells[i].trim())
                .filter(|c| !c.is_empty())
        };
        let (name, file, column) = match (cell("setup"), cell("file"), cell("column")) {
            (Some(s), Some(f), Some(c)) => (s, f, c),
            _ => {
                return Err(malformed(
                    row,
                    "`setup`, `file` and `column` must each be given".into(),
                ));
            }
        };
        let channel = channel_of(&cell, column, sep).map_err(|what| malformed(row, what))?;
        let inside = Path::new(file).components().all(|c| {
            matches!(
                c,
                std::path::Component::Normal(_) | std::path::Component::CurDir
            )
        });
        if !inside && paths == RecordPaths::InsideFolder {
            return Err(malformed(
                row,
                format!(
                    "file `{file}` is not inside the setup file's folder: name each record by its path from there (no `..`, not absolute), or allow it with --records-anywhere"
                ),
            ));
        }
        let file = folder.join(file);
        match setups.iter_mut().find(|s| s.name == name) {
            Some(s) if s.file != file => {
                return Err(malformed(
                    row,
                    format!(
                        "setup `{name}` names the file {} here and {} before: one record per setup",
                        file.display(),
                        s.file.display()
                    ),
                ));
            }
            Some(s) if s.columns.iter().any(|c| c == column) => {
                return Err(malformed(
                    row,
                    format!("setup `{name}` lists column `{column}` twice"),
                ));
            }
            Some(s) => {
                s.columns.push(column.to_string());
                s.channels.push(channel);
            }
            None => setups.push(SetupSpec {
                name: name.to_string(),
                file,
                columns: vec![column.to_string()],
                channels: vec![channel],
                fs_hz: None,
            }),
        }
    }
    if setups.is_empty() {
        return Err(IoError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(setups)
}

/// One row's channel, from its cells (`cell` gives a non-empty cell by column name).
fn channel_of<'a>(
    cell: &dyn Fn(&str) -> Option<&'a str>,
    column: &str,
    sep: u8,
) -> Result<SetupChannel, String> {
    let quantity = match cell("quantity").map(str::to_ascii_lowercase).as_deref() {
        Some("displacement") => Quantity::Displacement,
        Some("velocity") => Quantity::Velocity,
        Some("acceleration") => Quantity::Acceleration,
        other => {
            return Err(format!(
                "quantity `{}` is not one of {}",
                other.unwrap_or(""),
                Quantity::NAMES.join(", ")
            ));
        }
    };
    let reference = match cell("reference").map(str::to_ascii_lowercase).as_deref() {
        Some("yes" | "true" | "1") => true,
        Some("no" | "false" | "0") => false,
        other => {
            return Err(format!(
                "reference `{}` is not yes or no",
                other.unwrap_or("")
            ));
        }
    };
    let num = |name: &str| -> Result<Option<f64>, String> {
        cell(name)
            .map(|t| {
                number(t, sep)
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("column `{name}`: `{t}` is not a finite number"))
            })
            .transpose()
    };
    let gain = num("gain")?.unwrap_or(1.0);
    if gain == 0.0 {
        return Err("gain 0 would erase the channel".into());
    }
    let given = direction_given(cell, &num)?;
    let (node, direction) = match (cell("node"), given) {
        (Some(node), Some(d)) => (node.to_string(), d),
        (None, None) => uff_point(column).ok_or_else(|| {
            format!(
                "column `{column}` has no node: give `node` and a direction (only a Universal File's column, such as `12+Z`, states its own)"
            )
        })?,
        (Some(node), None) => {
            return Err(format!(
                "node {node} has no direction: give `direction`, `dx`/`dy`/`dz`, or `azimuth`/`elevation`"
            ));
        }
        (None, Some(_)) => return Err(format!("column `{column}` has a direction but no node")),
    };
    Ok(SetupChannel {
        node,
        direction,
        quantity,
        gain,
        reference,
    })
}

type Num<'n> = dyn Fn(&str) -> Result<Option<f64>, String> + 'n;

/// The direction a row gives, in whichever of its three forms (exactly one), as a unit
/// vector.
fn direction_given<'a>(
    cell: &dyn Fn(&str) -> Option<&'a str>,
    num: &Num,
) -> Result<Option<[f64; 3]>, String> {
    let axis = cell("direction")
        .map(|t| axis(t).ok_or_else(|| format!("direction `{t}` is not x, y or z (signed)")))
        .transpose()?;
    let vector = match (num("dx")?, num("dy")?, num("dz")?) {
        (None, None, None) => None,
        (x, y, z) => Some([x.unwrap_or(0.0), y.unwrap_or(0.0), z.unwrap_or(0.0)]),
    };
    let angles = match (num("azimuth")?, num("elevation")?) {
        (None, None) => None,
        (Some(a), Some(e)) => {
            let (a, e) = (a.to_radians(), e.to_radians());
            Some([e.cos() * a.cos(), e.cos() * a.sin(), e.sin()])
        }
        _ => return Err("`azimuth` and `elevation` go together".into()),
    };
    let forms: Vec<[f64; 3]> = [axis, vector, angles].into_iter().flatten().collect();
    match forms.as_slice() {
        [] => Ok(None),
        [d] => {
            let n = d.iter().map(|v| v * v).sum::<f64>().sqrt();
            if n > 0.0 {
                Ok(Some(d.map(|v| v / n)))
            } else {
                Err("the direction (dx, dy, dz) is the zero vector".into())
            }
        }
        _ => Err("the direction is given in more than one form: give one of `direction`, `dx`/`dy`/`dz`, `azimuth`/`elevation`".into()),
    }
}

/// `x`, `+Y`, `-z` as a unit vector.
fn axis(text: &str) -> Option<[f64; 3]> {
    let t = text.to_ascii_lowercase();
    let (sign, name) = match t.strip_prefix('-') {
        Some(rest) => (-1.0, rest),
        None => (1.0, t.strip_prefix('+').unwrap_or(&t)),
    };
    let k = ["x", "y", "z"].iter().position(|a| *a == name)?;
    let mut d = [0.0; 3];
    d[k] = sign;
    Some(d)
}

/// A Universal File's column name, `12+Z`, as its node and direction.
fn uff_point(column: &str) -> Option<(String, [f64; 3])> {
    let at = column.rfind(['+', '-']).filter(|&i| i > 0)?;
    let (node, dir) = column.split_at(at);
    node.parse::<i64>().ok()?;
    Some((node.to_string(), axis(dir)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::file_path;

    const GOOD: &str =
        "setup,file,column,node,direction,dx,dy,dz,azimuth,elevation,quantity,reference,gain
one,a.npy,0,5,,,,,28.9,-8.7,velocity,no,-2
one,a.npy,3,24,-x,,,,,,acceleration,yes,
two,b.uff,7+Y,,,,,,,,acceleration,yes,
two,b.uff,9,9,,0,3,4,,,velocity,no,
";

    #[test]
    fn a_setup_file_reads_each_form_of_direction() {
        let p = file_path("setups.csv");
        std::fs::write(&p, GOOD).unwrap();
        let s = read_setups(&p).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].file, p.parent().unwrap().join("a.npy"));
        assert_eq!(s[0].columns, ["0", "3"]);
        let laser = &s[0].channels[0];
        let (a, e) = (28.9f64.to_radians(), (-8.7f64).to_radians());
        assert!((laser.direction[0] - e.cos() * a.cos()).abs() < 1e-15);
        assert!((laser.direction[2] - e.sin()).abs() < 1e-15);
        assert_eq!((laser.gain, laser.reference), (-2.0, false));
        assert_eq!(s[0].channels[1].direction, [-1.0, 0.0, 0.0]);
        // A Universal File's point gives the node and direction.
        assert_eq!(s[1].channels[0].node, "7");
        assert_eq!(s[1].channels[0].direction, [0.0, 1.0, 0.0]);
        assert_eq!(s[1].channels[1].direction, [0.0, 0.6, 0.8]);
    }

    #[test]
    fn bad_setup_files_are_named_by_row_and_column() {
        let p = file_path("bad_setups.csv");
        let head = "setup,file,column,node,direction,quantity,reference\n";
        for (text, says) in [
            (
                "setup,file,column,quantity,reference,colour\n",
                "unknown column `colour`",
            ),
            ("setup,file,column,quantity\n", "no column `reference`"),
            (
                &format!("{head}a,r.csv,y1,,,velocity,no\n"),
                "row 2: column `y1` has no node",
            ),
            (
                &format!("{head}a,r.csv,y1,3,,velocity,no\n"),
                "row 2: node 3 has no direction",
            ),
            (
                &format!("{head}a,r.csv,y1,3,w,velocity,no\n"),
                "direction `w` is not x, y or z",
            ),
            (
                &format!("{head}a,r.csv,y1,3,x,speed,no\n"),
                "quantity `speed` is not one of",
            ),
            (
                &format!("{head}a,r.csv,y1,3,x,velocity,maybe\n"),
                "reference `maybe` is not yes or no",
            ),
            (
                &format!("{head}a,r.csv,y1,3,x,velocity,no\na,s.csv,y2,4,x,velocity,no\n"),
                "row 3: setup `a` names the file",
            ),
            (
                &format!("{head}a,r.csv,y1,3,x,velocity,no\na,r.csv,y1,4,x,velocity,no\n"),
                "row 3: setup `a` lists column `y1` twice",
            ),
            (head, "the record is empty"),
            (
                &format!("{head}a,r.csv,y1,3,x,velocity,no\na,r.csv,y2,3,-x,velocity,no\n"),
                "columns `y1` and `y2` both measure node 3",
            ),
            (
                &format!("{head}a,../../etc/passwd,y1,3,x,velocity,no\n"),
                "row 2: file `../../etc/passwd` is not inside the setup file's folder",
            ),
            (
                &format!("{head}a,/dev/zero,y1,3,x,velocity,no\n"),
                "file `/dev/zero` is not inside",
            ),
        ] {
            std::fs::write(&p, text).unwrap();
            let e = read_setups(&p).unwrap_err().to_string();
            assert!(e.contains(says), "{text}: {e}");
        }
        let both =
            "setup,file,column,node,direction,dx,quantity,reference\na,r,y,3,x,1,velocity,no\n";
        std::fs::write(&p, both).unwrap();
        let e = read_setups(&p).unwrap_err().to_string();
        assert!(e.contains("more than one form"), "{e}");
    }

    /// Issue 58's setups: a reference channel the setup does not have, an empty setup
    /// folder, and a record that is no regular file (a link to a device) are each refused,
    /// named, rather than dropped, skipped or read until memory runs out.
    #[test]
    fn setups_refuse_an_unknown_reference_an_empty_folder_and_a_device() {
        let dir = file_path("pyoma-bad");
        let _ = std::fs::remove_dir_all(&dir);
        let one = dir.join("s1");
        std::fs::create_dir_all(&one).unwrap();
        let info = |refs: &str| {
            format!(
                "Setup Name:\ns1\nSampling Rate [Hz]:\n100\nReference Channels:\n{refs}\nDelete Channels:\n\nAccel. Channels:\n0 1\nVelo. Channels:\n\nDisp. Channels:\n\n"
            )
        };
        std::fs::write(one.join("setup_info.txt"), info("0 99")).unwrap();
        std::fs::write(
            one.join("channel_dofs.txt"),
            "Channel-Nr.\tNode\tAzimuth\tElevation\n0\t1\t0\t0\n1\t2\t0\t0\n",
        )
        .unwrap();
        std::fs::write(one.join("rec.npy"), b"").unwrap();
        let e = read_setups(&dir).unwrap_err().to_string();
        assert!(e.contains("reference channel 99 is not among"), "{e}");
        std::fs::write(one.join("setup_info.txt"), info("0")).unwrap();
        assert_eq!(read_setups(&dir).unwrap().len(), 1);
        std::fs::create_dir_all(dir.join("s2")).unwrap();
        let e = read_setups(&dir).unwrap_err().to_string();
        assert!(e.contains("s2") && e.contains("no setup_info.txt"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
        #[cfg(unix)]
        {
            let link = file_path("device-link.csv");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
            let p = file_path("device_setups.csv");
            std::fs::write(
                &p,
                "setup,file,column,node,direction,quantity,reference\na,device-link.csv,y,1,x,velocity,yes\n",
            )
            .unwrap();
            let e = read_setups(&p).unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
    }

    /// A pyOMA setup folder's `channel_gains.txt`: each listed channel takes its gain, the
    /// others keep 1; a zero, a word, a channel the setup does not analyse (not in
    /// channel_dofs.txt, or deleted) or listed twice is refused with its row.
    #[test]
    fn pyoma_setups_take_each_channels_gain_from_channel_gains_txt() {
        let dir = file_path("pyoma-gains");
        let _ = std::fs::remove_dir_all(&dir);
        let one = dir.join("s1");
        std::fs::create_dir_all(&one).unwrap();
        std::fs::write(
            one.join("setup_info.txt"),
            "Setup Name:\ns1\nSampling Rate [Hz]:\n100\nReference Channels:\n0\nDelete Channels:\n2\nAccel. Channels:\n0 1 2\nVelo. Channels:\n\nDisp. Channels:\n\n",
        )
        .unwrap();
        std::fs::write(
            one.join("channel_dofs.txt"),
            "Channel-Nr.\tNode\tAzimuth\tElevation\n0\t1\t0\t0\n1\t2\t0\t0\n2\t3\t0\t0\n",
        )
        .unwrap();
        std::fs::write(one.join("rec.npy"), b"").unwrap();
        let gains = one.join("channel_gains.txt");
        std::fs::write(&gains, "Channel-Nr.\tGain\n\n1\t-0.5\n").unwrap();
        let s = read_setups(&dir).unwrap();
        let g: Vec<f64> = s[0].channels.iter().map(|c| c.gain).collect();
        assert_eq!(g, [1.0, -0.5]);
        for (text, says) in [
            (
                "c g\n1 0\n",
                "row 2: gain `0` is not a finite nonzero number",
            ),
            ("c g\n1 NaN\n", "gain `NaN`"),
            ("c g\nx 2\n", "`x` is not a channel number"),
            ("c g\n1\n", "expected a channel number and its gain"),
            ("c g\n7 2\n", "channel 7 is not analysed by this setup"),
            ("c g\n2 2\n", "channel 2 is not analysed by this setup"),
            ("c g\n1 2\n1 3\n", "row 3: channel 1 is given a gain twice"),
        ] {
            std::fs::write(&gains, text).unwrap();
            let e = read_setups(&dir).unwrap_err().to_string();
            assert!(
                e.contains("channel_gains.txt") && e.contains(says),
                "{text}: {e}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A valid file with bytes replaced, cut or added never panics the reader; what it reads
    /// has a unit direction and a nonzero gain on every channel.
    mod fuzz {
        use super::*;
        use crate::test_files::mutated;
        use proptest::prelude::*;

        proptest! {
            #[test]
            fn mutated_setup_files_read_or_fail_cleanly(
                flips in proptest::collection::vec((0usize..260, any::<u8>()), 0..6),
                cut in 0usize..280,
                tail in proptest::collection::vec(any::<u8>(), 0..20),
            ) {
                let p = file_path("fuzz-setups.csv");
                std::fs::write(&p, mutated(GOOD.as_bytes().to_vec(), &flips, cut, &tail)).unwrap();
                if let Ok(setups) = read_setups(&p) {
                    for ch in setups.iter().flat_map(|s| &s.channels) {
                        let n: f64 = ch.direction.iter().map(|v| v * v).sum::<f64>().sqrt();
                        prop_assert!((n - 1.0).abs() < 1e-12 && ch.gain != 0.0, "{ch:?}");
                    }
                }
            }

            #[test]
            fn mutated_gain_files_read_or_fail_cleanly(
                flips in proptest::collection::vec((0usize..40, any::<u8>()), 0..6),
                cut in 0usize..45,
                tail in proptest::collection::vec(any::<u8>(), 0..20),
            ) {
                let dir = file_path("fuzz-pyoma-gains");
                let one = dir.join("s1");
                std::fs::create_dir_all(&one).unwrap();
                std::fs::write(
                    one.join("setup_info.txt"),
                    "Sampling Rate [Hz]:\n100\nReference Channels:\n0\nAccel. Channels:\n0 1\n",
                )
                .unwrap();
                std::fs::write(
                    one.join("channel_dofs.txt"),
                    "Channel-Nr.\tNode\tAzimuth\tElevation\n0\t1\t0\t0\n1\t2\t0\t0\n",
                )
                .unwrap();
                std::fs::write(one.join("rec.npy"), b"").unwrap();
                let good = b"Channel-Nr.\tGain\n0\t1\n1\t-0.5\n".to_vec();
                std::fs::write(one.join("channel_gains.txt"), mutated(good, &flips, cut, &tail))
                    .unwrap();
                if let Ok(setups) = read_setups(&dir) {
                    for ch in setups.iter().flat_map(|s| &s.channels) {
                        prop_assert!(ch.gain.is_finite() && ch.gain != 0.0, "{ch:?}");
                    }
                }
            }
        }
    }
}
