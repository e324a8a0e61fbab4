//! `cargo xtask`: the project's tasks.
//!
//! - `cargo xtask test` runs every test, the README's test command: the workspace's, then the
//!   Python package's (`test_all.rs`).
//! - `cargo xtask unused-deps` and `cargo xtask sizes` check the workspace's manifests and the
//!   size of its files and functions (`deps.rs`, `sizes.rs`; the tests run both in CI).
//! - Every other task — `bench`, `sweep`, `compare-tools`, `corpus`, … (`cargo xtask studies`
//!   lists them) — is the `hyst-studies` package's (`xtask/studies`), built and run on demand
//!   with `cargo run --release`.
//!
//! This runner depends on none of the libraries: it builds in seconds, and the libraries are
//! compiled once in a test run, with the features the tests' graph unifies.

mod deps;
mod sizes;
mod test_all;

use std::ffi::OsString;
use std::process::Command;

/// The project's tasks.
#[derive(clap::Parser)]
#[command(
    name = "cargo xtask",
    bin_name = "cargo xtask",
    after_help = "Every other task (bench, sweep, compare-tools, corpus, …) is run by the \
                  hyst-studies package: `cargo xtask studies` lists them."
)]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(clap::Subcommand)]
enum Task {
    /// Every test: `cargo test --workspace --release`, then the Python package's pytest
    /// (`test_all.rs`).
    Test,
    /// Fail if a workspace member declares a dependency its sources do not use (`deps.rs`).
    UnusedDeps,
    /// Fail if a source file, a function or `src/main.rs` outgrows its limit, or the command
    /// line builds JSON by hand (`sizes.rs`).
    Sizes,
    /// The studies' tasks (benchmarks, sweeps, comparisons, figures) and their help.
    Studies,
    /// A study's task, run by `hyst-studies` with its arguments.
    #[command(external_subcommand)]
    Study(Vec<OsString>),
}

fn or_exit(result: Result<(), String>) {
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// `cargo run --release -p hyst-studies -- ARGS`, its exit status passed on.
fn study(args: &[OsString]) -> ! {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .args(["run", "--release", "--package", "hyst-studies", "--"])
        .args(args)
        .current_dir(hyst_testkit::workspace_root())
        .status();
    match status {
        Ok(s) => std::process::exit(s.code().unwrap_or(1)),
        Err(e) => {
            eprintln!("error: cargo run -p hyst-studies could not start: {e}");
            std::process::exit(1);
        }
    }
}

fn main() {
    use clap::Parser;
    match Cli::parse().task {
        Task::Test => or_exit(test_all::run_all()),
        Task::UnusedDeps => or_exit(deps::run()),
        Task::Sizes => {
            let found = sizes::breaches(&hyst_testkit::workspace_root());
            for b in &found {
                eprintln!("{b}");
            }
            if !found.is_empty() {
                eprintln!("error: {} breach(es) of the size limits", found.len());
                std::process::exit(1);
            }
            println!(
                "sizes: every file within {} lines of code, every function within {} lines",
                sizes::MAX_FILE_LINES,
                sizes::MAX_FN_LINES
            );
        }
        Task::Studies => study(&["--help".into()]),
        Task::Study(args) => study(&args),
    }
}
