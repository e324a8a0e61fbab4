//! The campaign store of `hyst track` under its `--out` folder: one SQLite file,
//! `store.sqlite`, holding each record's result keyed by what made it, so that a resumed run
//! serves a stored result only when nothing that makes it has changed, and the tracked table
//! of the last run.
//!
//! - **Key**: the record's source (its file's canonical path, size and modification time, or
//!   the window of one), the sampling rate and channels asked for, and the analysis options;
//!   any change recomputes the record ([`record_key`]).
//! - **Failures are not served**: a record that failed is identified again on the next run
//!   (a bad option, a file being written, a read error may all be gone).
//! - **Transactions**: each record is written in a transaction of its own as it completes,
//!   and the run's end (its records and its tracked table) in one; a run killed at any moment
//!   loses at most the records in flight, and SQLite's journal undoes a half-written
//!   transaction when the store is next opened.
//! - **One run at a time**: the store is opened in SQLite's exclusive locking mode and held
//!   for the whole run; a second run finds it busy and is refused. The operating system frees
//!   the lock of a killed process, so there is no stale lock to clear.
//! - **Tables**: `records(name, key, ok, record)` with the record's modes as JSON, and
//!   `tracked`, the tidy table of `table.csv` ([`table`]), for SQL users.

pub mod table;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use hyst_monitor::RecordModes;
use rusqlite::{Connection, ErrorCode, params};

use crate::io::IoError;
pub use table::TrackTable;

/// Errors of the campaign store.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StoreError {
    /// Another run holds the campaign store.
    #[error(
        "{path}: another `hyst track` is writing this --out folder (its store is locked); wait for it, or give another --out"
    )]
    Locked {
        /// The store's file.
        path: PathBuf,
    },
    /// The campaign store could not be read or written.
    #[error("{path}: the campaign store: {message}")]
    Database {
        /// The store's file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Its folder could not be made.
    #[error(transparent)]
    Io(#[from] IoError),
}

/// The store's file in the `--out` folder.
pub const STORE_FILE: &str = "store.sqlite";

/// The files `hyst track` writes into its `--out` folder (and those earlier versions wrote,
/// so that an old run's folder given as input is not read as records).
pub const OUTPUT_FILES: [&str; 11] = [
    STORE_FILE,
    "store.sqlite-journal",
    "store.sqlite-wal",
    "table.csv",
    "table.jsonl",
    "table.parquet",
    "table.parquet.tmp",
    "report.json",
    "records.jsonl",
    "records.jsonl.tmp",
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

/// The layout of the store's tables; a store of another layout is refused.
const LAYOUT: i64 = 1;

/// SQLite's `application_id` of a hyst store: "hyst" in ASCII. A database of another
/// application is refused rather than written into.
pub const APPLICATION_ID: i32 = 0x6879_7374;

/// Mark the open database as hyst's, or say why it is another's: its `application_id` is
/// hyst's; or it is unset and the file is new (no tables) or a store of a hyst that did not
/// set it (its only table `records`, with hyst's columns).
fn claim(conn: &Connection) -> Result<(), String> {
    let sql = |e: rusqlite::Error| e.to_string();
    let id: i32 = conn
        .pragma_query_value(None, "application_id", |r| r.get(0))
        .map_err(sql)?;
    if id == APPLICATION_ID {
        return Ok(());
    }
    if id != 0 {
        return Err(format!(
            "it belongs to another application (SQLite application_id {id:#010x}, hyst's is {APPLICATION_ID:#010x}): give another --out"
        ));
    }
    let tables: Vec<String> = {
        let mut q = conn
            .prepare("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name")
            .map_err(sql)?;
        let rows = q.query_map([], |r| r.get::<_, String>(0)).map_err(sql)?;
        rows.collect::<Result<_, _>>().map_err(sql)?
    };
    let hysts = |t: &String| {
        t == "tracked"
            || (t == "records"
                && conn
                    .prepare("SELECT name, key, ok, record FROM records LIMIT 0")
                    .is_ok())
    };
    if let Some(other) = tables.iter().find(|t| !hysts(t)) {
        return Err(format!(
            "it is a database hyst did not make (it holds a table `{other}`): give another --out"
        ));
    }
    conn.pragma_update(None, "application_id", APPLICATION_ID)
        .map_err(sql)
}

/// The store of one `--out` folder, held (locked) by this process while it lives.
pub struct CampaignStore {
    path: PathBuf,
    conn: Mutex<Connection>,
    /// Each stored record by name, with its key.
    stored: HashMap<String, (String, RecordModes)>,
}

fn file_error(path: &Path) -> impl Fn(std::io::Error) -> IoError + '_ {
    move |source| IoError::File {
        path: path.to_path_buf(),
        source,
    }
}

/// An SQLite failure on the store at `path`: busy (another run holds it) said as such.
fn sql_error(path: &Path) -> impl Fn(rusqlite::Error) -> StoreError + '_ {
    move |e| match e.sqlite_error_code() {
        Some(ErrorCode::DatabaseBusy | ErrorCode::DatabaseLocked) => StoreError::Locked {
            path: path.to_path_buf(),
        },
        _ => StoreError::Database {
            path: path.to_path_buf(),
            message: e.to_string(),
        },
    }
}

impl CampaignStore {
    /// Open (or create) the store in `dir`: make the folder, take the store for this
    /// process, and read what earlier runs stored.
    pub fn open(dir: &Path) -> Result<CampaignStore, StoreError> {
        std::fs::create_dir_all(dir).map_err(file_error(dir))?;
        let path = dir.join(STORE_FILE);
        let err = sql_error(&path);
        let conn = Connection::open(&path).map_err(&err)?;
        conn.busy_timeout(std::time::Duration::ZERO).map_err(&err)?;
        conn.pragma_update(None, "locking_mode", "EXCLUSIVE")
            .map_err(&err)?;
        conn.pragma_update(None, "synchronous", "FULL")
            .map_err(&err)?;
        // A write transaction takes the exclusive lock, kept until the connection closes;
        // the file is hyst's (or new) before anything is written into it.
        conn.execute_batch("BEGIN EXCLUSIVE;").map_err(&err)?;
        if let Err(message) = claim(&conn) {
            let _ = conn.execute_batch("ROLLBACK;");
            return Err(StoreError::Database {
                path: path.clone(),
                message,
            });
        }
        conn.execute_batch(
            "CREATE TABLE IF NOT EXISTS records (
                 name TEXT PRIMARY KEY NOT NULL,
                 key TEXT NOT NULL,
                 ok INTEGER NOT NULL,
                 record TEXT NOT NULL
             );
             COMMIT;",
        )
        .map_err(&err)?;
        let layout: i64 = conn
            .pragma_query_value(None, "user_version", |r| r.get(0))
            .map_err(&err)?;
        match layout {
            0 => conn
                .pragma_update(None, "user_version", LAYOUT)
                .map_err(&err)?,
            LAYOUT => {}
            other => {
                return Err(StoreError::Database {
                    path: path.clone(),
                    message: format!(
                        "its layout is version {other}, this hyst writes version {LAYOUT}: give another --out"
                    ),
                });
            }
        }
        // A row this version cannot read (of a later one) is identified again.
        let stored = {
            let mut q = conn
                .prepare("SELECT key, record FROM records")
                .map_err(&err)?;
            let rows = q
                .query_map([], |r| Ok((r.get::<_, String>(0)?, r.get::<_, String>(1)?)))
                .map_err(&err)?;
            let mut stored = HashMap::new();
            for row in rows {
                let (key, text) = row.map_err(&err)?;
                if let Ok(record) = serde_json::from_str::<RecordModes>(&text) {
                    stored.insert(record.name.clone(), (key, record));
                }
            }
            stored
        };
        Ok(CampaignStore {
            path: path.clone(),
            conn: Mutex::new(conn),
            stored,
        })
    }

    /// The stored result of the record `name` made with `key`, if it succeeded.
    pub fn cached(&self, name: &str, key: &str) -> Option<&RecordModes> {
        self.stored
            .get(name)
            .filter(|(k, r)| k == key && r.outcome.is_ok())
            .map(|(_, r)| r)
    }

    /// The connection, for this thread.
    fn connection(&self) -> Result<std::sync::MutexGuard<'_, Connection>, StoreError> {
        self.conn.lock().map_err(|_| StoreError::Database {
            path: self.path.clone(),
            message: "a thread writing it failed".into(),
        })
    }

    /// Store one record made with `key`, in a transaction of its own (a run killed later
    /// keeps it; one killed during it has not written it).
    pub fn append(&self, key: &str, record: &RecordModes) -> Result<(), StoreError> {
        insert(&*self.connection()?, key, record).map_err(sql_error(&self.path))
    }

    /// End a run (or a pass of `hyst track --follow`) in one transaction: the store holds
    /// exactly `records`, each made with the key beside it in `keys`, and `table` as its
    /// tracked table; what [`CampaignStore::cached`] serves is then these records.
    pub fn finish(
        &mut self,
        keys: &[String],
        records: &[RecordModes],
        table: &TrackTable,
    ) -> Result<(), StoreError> {
        let err = sql_error(&self.path);
        {
            let mut conn = self.connection()?;
            let tx = conn.transaction().map_err(&err)?;
            tx.execute("DELETE FROM records", []).map_err(&err)?;
            for (key, record) in keys.iter().zip(records) {
                insert(&tx, key, record).map_err(&err)?;
            }
            table.write_sql(&tx, "tracked").map_err(&err)?;
            tx.commit().map_err(&err)?;
        }
        self.stored = keys
            .iter()
            .zip(records)
            .map(|(k, r)| (r.name.clone(), (k.clone(), r.clone())))
            .collect();
        Ok(())
    }
}

/// Insert (or replace) one record's row.
fn insert(conn: &Connection, key: &str, record: &RecordModes) -> rusqlite::Result<()> {
    let text = serde_json::to_string(record)
        .map_err(|e| rusqlite::Error::ToSqlConversionFailure(Box::new(e)))?;
    conn.execute(
        "INSERT OR REPLACE INTO records (name, key, ok, record) VALUES (?1, ?2, ?3, ?4)",
        params![record.name, key, record.outcome.is_ok(), text],
    )
    .map(|_| ())
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
                Ok(hyst_monitor::Identified::default())
            } else {
                Err("bad".into())
            },
        }
    }

    /// A stored success is served under its key only; a failure never; a second store on
    /// the folder is refused while the first is open, and allowed after; the run's end
    /// leaves exactly its records.
    #[test]
    fn keyed_locked_and_finished() {
        let dir = std::env::temp_dir().join(format!("hyst-store-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        {
            let s = CampaignStore::open(&dir).unwrap();
            s.append("k1", &record("a", true)).unwrap();
            s.append("k1", &record("b", false)).unwrap();
            let e = CampaignStore::open(&dir).err().unwrap();
            assert!(matches!(e, StoreError::Locked { .. }), "{e}");
            assert!(e.to_string().contains("another `hyst track`"), "{e}");
        }
        let mut s = CampaignStore::open(&dir).unwrap();
        assert!(s.cached("a", "k1").is_some());
        assert!(s.cached("a", "k2").is_none(), "another key recomputes");
        assert!(s.cached("b", "k1").is_none(), "a failure is retried");
        assert!(s.cached("c", "k1").is_none());
        s.finish(&["k9".into()], &[record("d", true)], &TrackTable::default())
            .unwrap();
        // What it serves is then what it holds (a --follow run's next pass).
        assert!(s.cached("d", "k9").is_some() && s.cached("a", "k1").is_none());
        drop(s);
        let s = CampaignStore::open(&dir).unwrap();
        assert!(s.cached("d", "k9").is_some() && s.cached("a", "k1").is_none());
        drop(s);
        // A store of a later layout is refused, named.
        let conn = Connection::open(dir.join(STORE_FILE)).unwrap();
        conn.pragma_update(None, "user_version", 7).unwrap();
        drop(conn);
        let e = CampaignStore::open(&dir).err().unwrap();
        assert!(e.to_string().contains("layout is version 7"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Another application's database is never written into (issue 58): one whose
    /// application_id is another's, and one with tables hyst does not make, are refused,
    /// named, and left as they were; a store of a hyst that set no id is taken and marked.
    #[test]
    fn another_applications_database_is_refused_untouched() {
        let dir = std::env::temp_dir().join(format!("hyst-store-app-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join(STORE_FILE);
        let conn = Connection::open(&file).unwrap();
        conn.pragma_update(None, "application_id", 0x4750_4b47)
            .unwrap();
        drop(conn);
        let before = std::fs::read(&file).unwrap();
        let e = CampaignStore::open(&dir).err().unwrap();
        assert!(e.to_string().contains("another application"), "{e}");
        assert_eq!(std::fs::read(&file).unwrap(), before, "left as it was");
        std::fs::remove_file(&file).unwrap();
        let conn = Connection::open(&file).unwrap();
        conn.execute_batch("CREATE TABLE accounts (id INTEGER);")
            .unwrap();
        drop(conn);
        let e = CampaignStore::open(&dir).err().unwrap();
        assert!(e.to_string().contains("table `accounts`"), "{e}");
        let conn = Connection::open(&file).unwrap();
        let tables: i64 = conn
            .query_row("SELECT count(*) FROM sqlite_master", [], |r| r.get(0))
            .unwrap();
        assert_eq!(tables, 1, "no table of hyst's written into it");
        drop(conn);
        std::fs::remove_file(&file).unwrap();
        // A store made before the id: its records table alone.
        let conn = Connection::open(&file).unwrap();
        conn.execute_batch(
            "CREATE TABLE records (name TEXT PRIMARY KEY NOT NULL, key TEXT NOT NULL, ok INTEGER NOT NULL, record TEXT NOT NULL);",
        )
        .unwrap();
        drop(conn);
        drop(CampaignStore::open(&dir).unwrap());
        let conn = Connection::open(&file).unwrap();
        let id: i32 = conn
            .pragma_query_value(None, "application_id", |r| r.get(0))
            .unwrap();
        assert_eq!(id, APPLICATION_ID);
        drop(conn);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn keys_differ_with_what_makes_them() {
        assert_ne!(record_key("a", "b"), record_key("a", "c"));
        assert_ne!(record_key("ab", ""), record_key("a", "b"));
    }
}
