//! Helpers shared by the integration tests.

use std::sync::{Mutex, OnceLock};
use std::time::Instant;

use hyst::covssi::multisetup::MergeOptions;
use hyst::io::{ReadOptions, SetupSpec, read_setups};
use hyst::setups::{SetupsReport, analyze_setups_with_progress};

/// The steel frame's 15 setups (`shared/data/steelframe`, pyOMA's layout, read as is) and
/// their analysis as `hyst ssi --setups` makes it with its defaults (each setup's SSI with
/// the jackknife's errors, then the merge and the global estimation). Made once per test run
/// and shared by the tests that read it: three tests made it alone before, 50–110 s apiece
/// of CI's run. `None` (skipped, or failed under CI) without the data.
pub fn steel_frame() -> Option<&'static SteelFrame> {
    static MADE: OnceLock<SteelFrame> = OnceLock::new();
    let dir = data_file("steelframe/grid.txt")?.parent()?.to_path_buf();
    Some(MADE.get_or_init(|| {
        let setups = read_setups(&dir).unwrap();
        assert_eq!(setups.len(), 15);
        let opts = hyst::settings::SsiSettings::default().analysis().unwrap();
        let read = ReadOptions::default();
        let start = Instant::now();
        let told = Mutex::new(Vec::new());
        let report = analyze_setups_with_progress(
            &setups,
            None,
            &read,
            &opts,
            &MergeOptions::default(),
            &|p| {
                told.lock().unwrap().push(Told {
                    seconds: start.elapsed().as_secs_f64(),
                    identified: p.identified,
                    setup: p.setup.map(str::to_string),
                    what: p.what.to_string(),
                })
            },
        )
        .unwrap();
        let told = told.into_inner().unwrap();
        (setups, report, told)
    }))
}

/// The steel frame's setups, their analysis, and what its progress told as it ran.
pub type SteelFrame = (Vec<SetupSpec>, SetupsReport, Vec<Told>);

/// One step the analysis of several setups told, and when (s from its start).
#[derive(Debug, Clone)]
pub struct Told {
    pub seconds: f64,
    pub identified: usize,
    pub setup: Option<String>,
    pub what: String,
}

pub use hyst_testkit::{data_file, rel_rms};
