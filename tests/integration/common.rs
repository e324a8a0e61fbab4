//! Helpers shared by the integration tests.

use std::sync::OnceLock;

use hyst::covssi::multisetup::MergeOptions;
use hyst::io::{ReadOptions, SetupSpec, read_setups};
use hyst::setups::{SetupsReport, analyze_setups};

/// The steel frame's 15 setups (`shared/data/steelframe`, pyOMA's layout, read as is) and
/// their analysis as `hyst ssi --setups` makes it with its defaults (each setup's SSI with
/// the jackknife's errors, then the merge and the global estimation). Made once per test run
/// and shared by the tests that read it: three tests made it alone before, 50–110 s apiece
/// of CI's run. `None` (skipped, or failed under CI) without the data.
pub fn steel_frame() -> Option<&'static (Vec<SetupSpec>, SetupsReport)> {
    static MADE: OnceLock<(Vec<SetupSpec>, SetupsReport)> = OnceLock::new();
    let dir = data_file("steelframe/grid.txt")?.parent()?.to_path_buf();
    Some(MADE.get_or_init(|| {
        let setups = read_setups(&dir).unwrap();
        assert_eq!(setups.len(), 15);
        let opts = hyst::settings::SsiSettings::default().analysis().unwrap();
        let read = ReadOptions::default();
        let report = analyze_setups(&setups, None, &read, &opts, &MergeOptions::default()).unwrap();
        (setups, report)
    }))
}

pub use hyst_testkit::{data_file, rel_rms};
