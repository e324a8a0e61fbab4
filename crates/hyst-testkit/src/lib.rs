//! What the project's tests and tasks (`cargo xtask`) share and no user of the libraries
//! needs, with nothing but the standard library so that the task runner builds in seconds:
//!
//! - [`data_dir`]: the shared data sets' folder (`HYST_DATA_DIR`, else `../shared/data`),
//!   and [`data_file`], one of its files as a test takes it (missing: a failure under CI,
//!   else a skip that says so), and [`rel_rms`], a record's error relative to another;
//! - [`chromium`]: Debian's headless Chromium opening a report page (the tests of what a
//!   browser shows, the documentation's screenshots);
//! - [`run_ok`], [`succeeded`]: a command run to success, its failure naming it.
//!
//! Kept out of the libraries' public API: a path on the build machine and a browser
//! launcher are no part of identifying a structure.

pub mod chromium;

use std::path::{Path, PathBuf};
use std::process::Command;

/// The folder of the shared data sets: `HYST_DATA_DIR` if set, else `../shared/data` from the
/// current directory, else `../shared/data` beside the workspace. `None` when none exists.
pub fn data_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("HYST_DATA_DIR") {
        return Some(PathBuf::from(d));
    }
    let candidates = [
        PathBuf::from("../shared/data"),
        workspace_root().join("../shared/data"),
    ];
    candidates.into_iter().find(|p| p.is_dir())
}

/// Path of a shared data file, e.g. `boucwen/multisine_val.csv`.
///
/// When the data folder or the file is missing: a test run under CI (`CI` set) fails, since
/// CI must have the data; elsewhere the test is skipped with a message saying so.
pub fn data_file(rel: &str) -> Option<PathBuf> {
    let found = data_dir().map(|d| d.join(rel)).filter(|p| p.is_file());
    match found {
        Some(p) => Some(p),
        None if std::env::var_os("CI").is_some() => {
            panic!(
                "shared data file `{rel}` is missing (set HYST_DATA_DIR or provide ../shared/data)"
            )
        }
        None => {
            eprintln!(
                "SKIPPED: shared data file `{rel}` not found (set HYST_DATA_DIR or provide ../shared/data)"
            );
            None
        }
    }
}

/// ‖a − b‖ / ‖b‖: the RMS of `a`'s error relative to the reference `b`'s RMS.
pub fn rel_rms(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den).sqrt()
}

/// The workspace's root folder (this crate is `crates/hyst-testkit` in it).
pub fn workspace_root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    here.ancestors()
        .nth(2)
        .map_or_else(|| here.join("../.."), Path::to_path_buf)
}

/// Run `cmd` and wait: an error naming `what` when it cannot start or does not succeed.
pub fn run_ok(cmd: &mut Command, what: &str) -> Result<(), String> {
    let status = cmd
        .status()
        .map_err(|e| format!("{what}: could not start: {e}"))?;
    succeeded(status, what)
}

/// An error naming `what` unless `status` is success.
pub fn succeeded(status: std::process::ExitStatus, what: &str) -> Result<(), String> {
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what}: failed ({status})"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failing_command_is_named_and_a_missing_one_too() {
        assert!(run_ok(Command::new("true").arg("x"), "true").is_ok());
        let e = run_ok(&mut Command::new("false"), "the false command").unwrap_err();
        assert!(e.starts_with("the false command: failed"), "{e}");
        let e = run_ok(&mut Command::new("/nonexistent/hyst-x"), "no such").unwrap_err();
        assert!(e.starts_with("no such: could not start"), "{e}");
    }

    #[test]
    fn the_workspace_root_holds_the_workspace_manifest() {
        let manifest = std::fs::read_to_string(workspace_root().join("Cargo.toml")).unwrap();
        assert!(manifest.contains("[workspace]"));
    }
}
