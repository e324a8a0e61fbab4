//! `hyst track --follow`: records (or rows of estimates) taken as they arrive, the campaign
//! tracked again over all of them at each arrival, new records and new alarms printed as
//! they come.
//!
//! Each pass is a batch run over what has arrived (the store serves every record already
//! identified), so its table and report are a batch run's over the same records; the
//! training is fixed (`--training`, else 336 records), so a record's chart never depends on
//! records after it. A file is taken once its size and modification time held for one poll
//! (one being written is left for the next look); the store makes a run killed at any moment
//! resume where it stopped.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use hyst::monitor::TrackReport;

use super::track::{
    TrackArgs, check_paths, checked_inputs, estimates_pass, record_files, records_among,
    records_pass, records_setup, write_outputs,
};
use super::{Error, fail};

/// `hyst track --follow`: what a batch run checks first (the outputs against the inputs,
/// the rate, the settings), then the folders or the table followed.
pub(crate) fn run(a: &TrackArgs) -> Result<(), Error> {
    let records = checked_inputs(a)?;
    if let Some(path) = &a.estimates {
        return follow_estimates(a, path);
    }
    let (asked, mut store) = records_setup(a)?;
    follow_records(a, &asked, &mut store, records)
}

/// What identifies a file's content between two looks: its size and modification time.
type Stamp = (u64, Option<SystemTime>);

fn stamp(path: &Path) -> Option<Stamp> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.len(), m.modified().ok()))
}

/// The wait between looks.
fn poll(a: &TrackArgs) -> Result<Duration, Error> {
    if a.poll.is_finite() && a.poll > 0.0 && a.poll <= 86_400.0 {
        Ok(Duration::from_secs_f64(a.poll))
    } else {
        Err(fail(format!(
            "--poll {}: give the seconds between looks, more than 0 and at most a day",
            a.poll
        )))
    }
}

/// Print the records of `report` whose outcome was not said (each with what it gave: a gap
/// said as skipped is said again when its file lands) and the alarms not in `alarms_said`,
/// and remember both.
fn say_new(report: &TrackReport, said: &mut HashSet<String>, alarms_said: &mut HashSet<String>) {
    let mut modes: HashMap<&str, usize> = HashMap::new();
    let mut order: Vec<&str> = Vec::new();
    for r in &report.rows {
        let n = modes.entry(r.name.as_str()).or_insert(0);
        if *n == 0 {
            order.push(r.name.as_str());
        }
        *n += 1;
    }
    for name in order {
        if said.insert(format!("{name}: tracked")) {
            println!("{name}: {} mode(s) tracked", modes[name]);
        }
    }
    for (name, why) in &report.skipped {
        if said.insert(format!("{name}: skipped: {why}")) {
            println!("{name}: skipped: {why}");
        }
    }
    for line in report.alarm_lines() {
        if alarms_said.insert(line.clone()) {
            println!("{line}");
        }
    }
}

/// The first pass's text: the whole report, then the alarms its text leaves out (it says a
/// mode's first few), each once; every record and alarm remembered as said.
fn say_first(report: &TrackReport, said: &mut HashSet<String>, alarms_said: &mut HashSet<String>) {
    let text = report.to_string();
    print!("{text}");
    said.extend(report.rows.iter().map(|r| format!("{}: tracked", r.name)));
    said.extend(
        report
            .skipped
            .iter()
            .map(|(name, why)| format!("{name}: skipped: {why}")),
    );
    for line in report.alarm_lines() {
        if !text.contains(&line) {
            println!("{line}");
        }
        alarms_said.insert(line);
    }
}

/// Follow the `--inputs` folders: a pass over `first` (the files there now), then one each
/// time settled new files appear.
fn follow_records(
    a: &TrackArgs,
    asked: &hyst::covssi::AnalysisOptions,
    store: &mut hyst::store::CampaignStore,
    first: Vec<PathBuf>,
) -> Result<(), Error> {
    let wait = poll(a)?;
    let mut taken: Vec<PathBuf> = first;
    let mut pending: HashMap<PathBuf, Stamp> = HashMap::new();
    let mut said = HashSet::new();
    let mut alarms_said = HashSet::new();
    let mut first_pass = true;
    let mut covariates_stamp = a.covariates.as_deref().and_then(stamp);
    let mut not_records = HashSet::new();
    loop {
        if !taken.is_empty() {
            match records_pass(a, asked, store, taken.clone(), first_pass) {
                Ok((report, table)) => {
                    if first_pass {
                        say_first(&report, &mut said, &mut alarms_said);
                    } else {
                        say_new(&report, &mut said, &mut alarms_said);
                    }
                    write_outputs(a, &report, &table)?;
                    first_pass = false;
                }
                // Too few records for a reference or a baseline yet: wait for more.
                Err(e) => println!("{} record(s) so far: {e}; waiting for more", taken.len()),
            }
        } else {
            println!("no record yet in {}; waiting", folders(a));
        }
        // Look until something new has settled.
        loop {
            std::thread::sleep(wait);
            let listed = record_files(a)?;
            let mut settled = Vec::new();
            for f in listed.iter().cloned() {
                if taken.contains(&f) {
                    continue;
                }
                let now = stamp(&f);
                if now.is_some() && pending.get(&f) == now.as_ref() {
                    settled.push(f);
                } else if let Some(now) = now {
                    pending.insert(f, now);
                }
            }
            // A settled file that is not a record (a note) stays pending, looked at again
            // at each look and named once.
            let new = records_among(settled, &mut not_records);
            for f in &new {
                pending.remove(f);
            }
            let covariates_now = a.covariates.as_deref().and_then(stamp);
            let covariates_changed = covariates_now != covariates_stamp;
            covariates_stamp = covariates_now;
            if !new.is_empty() || covariates_changed {
                taken.extend(new);
                // In the listing's order, as a batch run over them takes them: a file that
                // lands late among earlier names goes to its name's place.
                let place: HashMap<&PathBuf, usize> =
                    listed.iter().enumerate().map(|(i, f)| (f, i)).collect();
                taken.sort_by_key(|f| place.get(f).copied());
                check_paths(a, &taken)?;
                break;
            }
        }
    }
}

/// The folders followed, for the text.
fn folders(a: &TrackArgs) -> String {
    a.inputs
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Follow the `--estimates` table: a pass now, then one each time it changed and held for
/// a poll.
fn follow_estimates(a: &TrackArgs, path: &Path) -> Result<(), Error> {
    let wait = poll(a)?;
    let mut said = HashSet::new();
    let mut alarms_said = HashSet::new();
    let mut first_pass = true;
    let mut done: Option<Stamp> = None;
    let mut pending: Option<Stamp> = stamp(path);
    let mut covariates_done = a.covariates.as_deref().and_then(stamp);
    loop {
        let now = stamp(path);
        let covariates_now = a.covariates.as_deref().and_then(stamp);
        let settled = now.is_some() && now == pending;
        if settled && (now != done || covariates_now != covariates_done) {
            match estimates_pass(a, path, first_pass) {
                Ok((report, table)) => {
                    if first_pass {
                        say_first(&report, &mut said, &mut alarms_said);
                    } else {
                        say_new(&report, &mut said, &mut alarms_said);
                    }
                    write_outputs(a, &report, &table)?;
                    first_pass = false;
                }
                // A row being written, or too few rows yet: said, and looked at again.
                Err(e) => println!("{}: {e}; waiting", path.display()),
            }
            done = now;
            covariates_done = covariates_now;
        }
        pending = now;
        std::thread::sleep(wait);
    }
}
