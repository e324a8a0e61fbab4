//! The setups of a modal test in pyOMA's layout (the steel frame of `shared/data`): one folder
//! per setup, each holding its record (`.npy`), `setup_info.txt` (rate, reference, deleted,
//! acceleration, velocity and displacement channels) and `channel_dofs.txt` (per channel:
//! node, azimuth and elevation of its direction in degrees), and optionally
//! `channel_gains.txt` (per channel: the factor its reading carries, as a setup file's `gain`:
//! −1 for a sensor mounted the other way, a calibration in other units).

use std::path::{Path, PathBuf};

use super::{IoError, SetupSpec};
use covssi::multisetup::{Quantity, SetupChannel};

/// Every setup folder of `dir` (natural name order) read as a [`SetupSpec`]: the channels not
/// deleted, their directions (cos e cos a, cos e sin a, sin e), and their gains from the
/// folder's `channel_gains.txt` when it has one (1 for a channel it does not list).
pub fn read_pyoma_setups(dir: &Path) -> Result<Vec<SetupSpec>, IoError> {
    let entries = std::fs::read_dir(dir).map_err(|source| IoError::File {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut folders: Vec<PathBuf> = Vec::new();
    for p in entries.filter_map(|e| e.ok().map(|e| e.path())) {
        if p.join("setup_info.txt").is_file() {
            folders.push(p);
        } else if p.is_dir() && is_setup_like(&p) {
            return Err(IoError::Params {
                path: p,
                what: "a folder among the setups with no setup_info.txt (it is empty, or holds a record or channel_dofs.txt): each setup folder needs setup_info.txt, channel_dofs.txt and its .npy record".into(),
            });
        }
    }
    folders
        .sort_by(|a, b| super::covariates::natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    if folders.is_empty() {
        return Err(IoError::Params {
            path: dir.to_path_buf(),
            what: "no setup folder (one holding setup_info.txt) in this folder".into(),
        });
    }
    folders.iter().map(|f| read_one(f)).collect()
}

/// A folder that is empty or holds a setup's files: one the user meant as a setup.
fn is_setup_like(dir: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return false;
    };
    let names: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    names.is_empty()
        || names.iter().any(|p| {
            p.extension().is_some_and(|e| e == "npy")
                || p.file_name().is_some_and(|n| n == "channel_dofs.txt")
        })
}

fn read_text(path: &Path) -> Result<String, IoError> {
    std::fs::read_to_string(path).map_err(|source| IoError::File {
        path: path.to_path_buf(),
        source,
    })
}

/// The channel lists and rate `setup_info.txt` gives, by section.
struct Info {
    name: String,
    rate: f64,
    references: Vec<usize>,
    deleted: Vec<usize>,
    quantity: Vec<(usize, Quantity)>,
}

fn info(path: &Path) -> Result<Info, IoError> {
    let text = read_text(path)?;
    let bad = |what: String| IoError::Params {
        path: path.to_path_buf(),
        what,
    };
    let mut sections: Vec<(String, String)> = Vec::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with("####") {
            break;
        }
        if line.ends_with(':') {
            sections.push((line.to_string(), String::new()));
        } else if let Some(last) = sections.last_mut() {
            last.1.push_str(line);
            last.1.push(' ');
        }
    }
    let section = |head: &str| {
        sections
            .iter()
            .find(|s| s.0.starts_with(head))
            .map(|s| s.1.trim().to_string())
    };
    let list = |head: &str| -> Result<Vec<usize>, IoError> {
        section(head)
            .unwrap_or_default()
            .split_whitespace()
            .map(|t| {
                t.parse()
                    .map_err(|_| bad(format!("`{head}`: `{t}` is not a channel number")))
            })
            .collect()
    };
    let rate_text =
        section("Sampling Rate").ok_or_else(|| bad("no `Sampling Rate [Hz]:`".into()))?;
    let rate: f64 = rate_text
        .parse()
        .ok()
        .filter(|r: &f64| r.is_finite() && *r > 0.0)
        .ok_or_else(|| {
            bad(format!(
                "sampling rate `{rate_text}` is not a positive number"
            ))
        })?;
    let mut quantity = Vec::new();
    for (head, q) in [
        ("Accel.", Quantity::Acceleration),
        ("Velo.", Quantity::Velocity),
        ("Disp.", Quantity::Displacement),
    ] {
        quantity.extend(list(head)?.into_iter().map(|c| (c, q)));
    }
    Ok(Info {
        name: section("Setup Name").unwrap_or_default(),
        rate,
        references: list("Reference Channels")?,
        deleted: list("Delete Channels")?,
        quantity,
    })
}

fn read_one(folder: &Path) -> Result<SetupSpec, IoError> {
    let info = info(&folder.join("setup_info.txt"))?;
    let dofs_path = folder.join("channel_dofs.txt");
    let text = read_text(&dofs_path)?;
    let bad = |row: usize, what: String| IoError::Malformed {
        path: dofs_path.clone(),
        row,
        what,
    };
    let record = std::fs::read_dir(folder)
        .map_err(|source| IoError::File {
            path: folder.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|e| e == "npy"))
        .ok_or_else(|| IoError::Params {
            path: folder.to_path_buf(),
            what: "no .npy record in this setup folder".into(),
        })?;
    let mut columns = Vec::new();
    let mut channels = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let cells: Vec<&str> = line.split('\t').map(str::trim).collect();
        if line.trim().is_empty() {
            continue;
        }
        let row = i + 1;
        let [c, node, az, el, ..] = cells.as_slice() else {
            return Err(bad(
                row,
                "expected channel, node, azimuth, elevation".into(),
            ));
        };
        let c: usize = c
            .parse()
            .map_err(|_| bad(row, format!("`{c}` is not a channel number")))?;
        if info.deleted.contains(&c) {
            continue;
        }
        let angle = |t: &str| {
            t.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(row, format!("`{t}` is not an angle in degrees")))
        };
        let (a, e) = (angle(az)?.to_radians(), angle(el)?.to_radians());
        let quantity = info
            .quantity
            .iter()
            .find(|q| q.0 == c)
            .map(|q| q.1)
            .ok_or_else(|| {
                bad(
                    row,
                    format!(
                        "channel {c} is in no `Accel.`, `Velo.` or `Disp.` list of setup_info.txt"
                    ),
                )
            })?;
        columns.push(c.to_string());
        channels.push(SetupChannel {
            node: node.to_string(),
            direction: [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()],
            quantity,
            gain: 1.0,
            reference: info.references.contains(&c),
        });
    }
    let gains_path = folder.join("channel_gains.txt");
    if gains_path.is_file() {
        for (i, gain) in gains(&gains_path, &columns)? {
            channels[i].gain = gain;
        }
    }
    for r in &info.references {
        if !columns.iter().any(|c| *c == r.to_string()) {
            return Err(IoError::Params {
                path: folder.join("setup_info.txt"),
                what: format!(
                    "reference channel {r} is not among the channels of channel_dofs.txt ({}) or is deleted",
                    columns.join(" ")
                ),
            });
        }
    }
    let name = if info.name.is_empty() {
        folder
            .file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into_owned())
    } else {
        info.name
    };
    Ok(SetupSpec {
        name,
        file: record,
        columns,
        channels,
        fs_hz: Some(info.rate),
    })
}

/// The gains `channel_gains.txt` at `path` gives (a header line, then per line a channel
/// number and the factor its reading carries, separated by tabs or spaces), as (index among
/// `columns`, gain): each a finite nonzero number, each channel once and among those the
/// setup analyses; blank lines skipped.
fn gains(path: &Path, columns: &[String]) -> Result<Vec<(usize, f64)>, IoError> {
    let text = read_text(path)?;
    let bad = |row: usize, what: String| IoError::Malformed {
        path: path.to_path_buf(),
        row,
        what,
    };
    let mut found: Vec<(usize, f64)> = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let row = i + 1;
        let cells: Vec<&str> = line.split_whitespace().collect();
        let [c, g] = cells.as_slice() else {
            if cells.is_empty() {
                continue;
            }
            return Err(bad(row, "expected a channel number and its gain".into()));
        };
        let channel: usize = c
            .parse()
            .map_err(|_| bad(row, format!("`{c}` is not a channel number")))?;
        let gain = g
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v != 0.0)
            .ok_or_else(|| bad(row, format!("gain `{g}` is not a finite nonzero number")))?;
        let index = columns
            .iter()
            .position(|x| *x == channel.to_string())
            .ok_or_else(|| {
                bad(
                    row,
                    format!(
                        "channel {channel} is not analysed by this setup (channel_dofs.txt: {}; deleted ones left out)",
                        columns.join(" ")
                    ),
                )
            })?;
        if found.iter().any(|(j, _)| *j == index) {
            return Err(bad(row, format!("channel {channel} is given a gain twice")));
        }
        found.push((index, gain));
    }
    Ok(found)
}
