//! Helpers shared by the integration tests.

use std::path::PathBuf;
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

/// Path of a shared data file, e.g. `boucwen/multisine_val.csv`.
///
/// When the data folder or the file is missing: a test run under CI (`CI` set) fails, since
/// CI must have the data; elsewhere the test is skipped with a message saying so.
pub fn data_file(rel: &str) -> Option<PathBuf> {
    let found = hyst_testkit::data_dir()
        .map(|d| d.join(rel))
        .filter(|p| p.is_file());
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

/// Columns `u` and `y` of a shared data file.
pub fn load_uy(rel: &str) -> Option<(Vec<f64>, Vec<f64>)> {
    let p = data_file(rel)?;
    let t = hyst::io::read_csv(&p).expect("shared data must parse");
    Some((
        t.column("u").unwrap().to_vec(),
        t.column("y").unwrap().to_vec(),
    ))
}

/// ‖a − b‖ / ‖b‖ (RMS error relative to the reference's RMS).
pub fn rel_rms(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den).sqrt()
}

/// Each of a fit's free parameters, in order, is the named one and lies within `max_z` of its
/// standard errors of the expected value; prints every z, each line after `label`.
pub fn assert_estimates_near(
    label: &str,
    estimates: &[hyst::ident::residual::Estimate],
    expected: &[(&str, f64)],
    max_z: f64,
) {
    assert_eq!(estimates.len(), expected.len(), "{estimates:?}");
    for (e, &(name, value)) in estimates.iter().zip(expected) {
        assert_eq!(e.name, name);
        let z = (e.value - value) / e.se;
        eprintln!("{label}{name}: {:.5} ± {:.5} (z = {z:+.2})", e.value, e.se);
        assert!(
            z.abs() < max_z,
            "{name}: {} ± {} against {value}",
            e.value,
            e.se
        );
    }
}
