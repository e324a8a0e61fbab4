//! The campaign store of `hyst track` under its `--out` folder: `records.jsonl`, one line per
//! record identified, each keyed by what made its result, so that a resumed run serves a
//! stored result only when nothing that makes it has changed.
//!
//! - **Key**: the record's source (its file's canonical path, size and modification time, or
//!   the window of one), the sampling rate and channels asked for, and the analysis options;
//!   any change recomputes the record ([`record_key`]).
//! - **Failures are not served**: a record that failed is identified again on the next run
//!   (a bad option, a file being written, a read error may all be gone).
//! - **One run at a time**: `--out/.lock` holds the running process's id; a second run is
//!   refused while that process lives, and takes over a lock whose process is gone.
//! - **Torn lines**: a run killed mid-line leaves a last line without its end; it is cut off
//!   before anything is appended (it was glued to the next record's line).
//! - **Rewritten whole** at the end of a run with exactly that run's records (through a
//!   temporary file renamed over the store), so that it never holds a record twice.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use hyst_monitor::RecordModes;

use crate::io::IoError;

/// The files `hyst track` writes into its `--out` folder.
pub const OUTPUT_FILES: [&str; 6] = [
    "records.jsonl",
    "records.jsonl.tmp",
    "table.csv",
    "table.jsonl",
    "report.json",
    ".lock",
];

/// Whether `file` is one of the files `hyst track` writes into `out` (by any path to it).
pub fn is_output(out: &Path, file: &Path) -> bool {
    let (Ok(out), Some(dir), Some(name)) = (
        std::fs::canonicalize(out),
        file.parent().map(|d| {
            if d.as_os_str().is_empty() {
                Path::new(".")
            } else {
                d
            }
        }),
        file.file_name(),
    ) else {
        return false;
    };
    std::fs::canonicalize(dir).is_ok_and(|d| d == out) && OUTPUT_FILES.iter().any(|o| name == *o)
}

/// A stored line: the key and the record.
#[derive(serde::Deserialize)]
struct Stored {
    key: String,
    #[serde(flatten)]
    record: RecordModes,
}

/// A line of the store, as written: the key beside the record's own fields.
fn stored_line(key: &str, record: &RecordModes) -> serde_json::Result<String> {
    #[derive(serde::Serialize)]
    struct Line<'a> {
        key: &'a str,
        #[serde(flatten)]
        record: &'a RecordModes,
    }
    serde_json::to_string(&Line { key, record })
}

/// The store of one `--out` folder, locked for this process while it lives.
pub struct CampaignStore {
    path: PathBuf,
    lock: PathBuf,
    /// Each stored record by name, with its key.
    stored: HashMap<String, (String, RecordModes)>,
}

fn file_error(path: &Path) -> impl Fn(std::io::Error) -> IoError + '_ {
    move |source| IoError::File {
        path: path.to_path_buf(),
        source,
    }
}

impl CampaignStore {
    /// Open (or create) the store in `dir`: make the folder, take its lock, cut a torn last
    /// line, and read what earlier runs stored.
    pub fn open(dir: &Path) -> Result<CampaignStore, IoError> {
        std::fs::create_dir_all(dir).map_err(file_error(dir))?;
        let lock = take_lock(dir)?;
        let path = dir.join("records.jsonl");
        let text = read_repaired(&path)?;
        // Later lines of a record replace earlier ones; lines of an older layout (no key)
        // are not read, so their records are identified again.
        let stored = text
            .lines()
            .filter_map(|l| serde_json::from_str::<Stored>(l).ok())
            .map(|s| (s.record.name.clone(), (s.key, s.record)))
            .collect();
        Ok(CampaignStore { path, lock, stored })
    }

    /// The stored result of the record `name` made with `key`, if it succeeded.
    pub fn cached(&self, name: &str, key: &str) -> Option<&RecordModes> {
        self.stored
            .get(name)
            .filter(|(k, r)| k == key && r.outcome.is_ok())
            .map(|(_, r)| r)
    }

    /// Append one record made with `key` (a line, flushed: a run killed later keeps it).
    pub fn append(&self, key: &str, record: &RecordModes) -> Result<(), IoError> {
        let line = stored_line(key, record).map_err(|e| file_error(&self.path)(e.into()))?;
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&self.path)
            .map_err(file_error(&self.path))?;
        f.write_all(format!("{line}\n").as_bytes())
            .map_err(file_error(&self.path))
    }

    /// Replace the store with exactly `records`, each made with the key beside it in `keys`:
    /// written to a temporary file in the folder, then renamed over the store.
    pub fn rewrite(&self, keys: &[String], records: &[RecordModes]) -> Result<(), IoError> {
        let tmp = self.path.with_extension("jsonl.tmp");
        {
            let mut w =
                std::io::BufWriter::new(std::fs::File::create(&tmp).map_err(file_error(&tmp))?);
            for (key, record) in keys.iter().zip(records) {
                let line = stored_line(key, record).map_err(|e| file_error(&tmp)(e.into()))?;
                writeln!(w, "{line}").map_err(file_error(&tmp))?;
            }
            w.flush().map_err(file_error(&tmp))?;
        }
        std::fs::rename(&tmp, &self.path).map_err(file_error(&self.path))
    }
}

impl Drop for CampaignStore {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.lock);
    }
}

/// The store's text at `path` (empty when there is none yet), its torn last line (a run
/// killed mid-write) cut from the file first, so that the next line appended starts a line
/// of its own.
fn read_repaired(path: &Path) -> Result<String, IoError> {
    let mut f = match std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
    {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(String::new()),
        Err(e) => return Err(file_error(path)(e)),
    };
    let mut bytes = Vec::new();
    f.read_to_end(&mut bytes).map_err(file_error(path))?;
    if bytes.last().is_some_and(|&b| b != b'\n') {
        let keep = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        f.set_len(keep as u64).map_err(file_error(path))?;
        bytes.truncate(keep);
    }
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

/// Take `dir/.lock` for this process: refused while another live process holds it.
fn take_lock(dir: &Path) -> Result<PathBuf, IoError> {
    let lock = dir.join(".lock");
    for _ in 0..2 {
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&lock)
        {
            Ok(mut f) => {
                write!(f, "{}", std::process::id()).map_err(file_error(&lock))?;
                return Ok(lock);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let holder = std::fs::read_to_string(&lock)
                    .ok()
                    .and_then(|t| t.trim().parse::<u32>().ok());
                match holder {
                    Some(pid) if process_lives(pid) => {
                        return Err(IoError::StoreLocked { path: lock, pid });
                    }
                    // Its process is gone (killed): the lock is stale.
                    _ => std::fs::remove_file(&lock).map_err(file_error(&lock))?,
                }
            }
            Err(e) => return Err(file_error(&lock)(e)),
        }
    }
    Err(IoError::StoreLocked { path: lock, pid: 0 })
}

/// Whether the process `pid` is running (Linux: its `/proc` entry; elsewhere assumed so).
fn process_lives(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists()
    } else {
        true
    }
}

/// The key of a record's result: FNV-1a (64 bits, hex) of everything that makes it — its
/// `source` (see [`file_source`]), and `settings` (the rate and channels asked for and the
/// analysis options, as text).
pub fn record_key(source: &str, settings: &str) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in source.bytes().chain([0u8]).chain(settings.bytes()) {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// What identifies a file's content for [`record_key`]: its canonical path, size and
/// modification time (ns); an unreadable file's path alone (its failure is not stored).
pub fn file_source(path: &Path) -> String {
    let canon = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let meta = std::fs::metadata(path).ok();
    let size = meta.as_ref().map(|m| m.len());
    let modified = meta
        .and_then(|m| m.modified().ok())
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map(|d| d.as_nanos());
    format!("{}|{size:?}|{modified:?}", canon.display())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(name: &str, ok: bool) -> RecordModes {
        RecordModes {
            name: name.into(),
            time: 1.0,
            covariates: vec![],
            outcome: if ok {
                Ok(hyst_monitor::Identified {
                    modes: vec![],
                    misfit: None,
                })
            } else {
                Err("bad".into())
            },
        }
    }

    /// A stored success is served under its key only; a failure never; a torn last line is
    /// cut and the next record starts on its own line; a second store on the folder is
    /// refused while the first is open, and allowed after.
    #[test]
    fn keyed_locked_and_repaired() {
        let dir = std::env::temp_dir().join(format!("hyst-store-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        {
            let s = CampaignStore::open(&dir).unwrap();
            s.append("k1", &record("a", true)).unwrap();
            s.append("k1", &record("b", false)).unwrap();
            let e = CampaignStore::open(&dir).err().unwrap();
            assert!(matches!(e, IoError::StoreLocked { .. }), "{e}");
            assert!(e.to_string().contains("another `hyst track`"), "{e}");
        }
        // A run killed mid-line.
        let p = dir.join("records.jsonl");
        let mut text = std::fs::read_to_string(&p).unwrap();
        text.push_str("{\"key\":\"k1\",\"name\":\"c\",\"ti");
        std::fs::write(&p, &text).unwrap();
        let s = CampaignStore::open(&dir).unwrap();
        assert!(s.cached("a", "k1").is_some());
        assert!(s.cached("a", "k2").is_none(), "another key recomputes");
        assert!(s.cached("b", "k1").is_none(), "a failure is retried");
        assert!(s.cached("c", "k1").is_none());
        s.append("k1", &record("d", true)).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.ends_with("\n") && text.lines().count() == 3, "{text}");
        s.rewrite(&["k9".into()], &[record("d", true)]).unwrap();
        drop(s);
        let s = CampaignStore::open(&dir).unwrap();
        assert!(s.cached("d", "k9").is_some() && s.cached("a", "k1").is_none());
        drop(s);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn keys_differ_with_what_makes_them() {
        assert_ne!(record_key("a", "b"), record_key("a", "c"));
        assert_ne!(record_key("ab", ""), record_key("a", "b"));
    }
}
