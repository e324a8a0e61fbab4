//! FDD and EFDD (`covssi::fdd`) on the OMA records made outside the project
//! (`shared/data/oma`, exact discretisations with 5 % measurement noise): EFDD's frequencies
//! and damping ratios against the truth files, beside SSI's refined ones on the same record.
//!
//! `cargo test --release --test fdd_oma -- --nocapture` prints the table.

use crate::common;

use covssi::fdd::{FddOptions, efdd, efdd_of_mode, fdd};
use hyst::io::{ReadOptions, read_record};

fn truth(name: &str) -> Vec<(f64, f64)> {
    let path = common::data_file(&format!("oma/truth_{name}.json")).unwrap();
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let f = doc["fn_hz"].as_array().unwrap();
    let z = doc["zeta"].as_array().unwrap();
    f.iter()
        .zip(z)
        .map(|(f, z)| (f.as_f64().unwrap(), z.as_f64().unwrap()))
        .collect()
}

#[test]
fn efdd_finds_the_true_modes_of_the_oma_records() {
    for name in ["sdof", "3dof"] {
        let Some(path) = common::data_file(&format!("oma/data_{name}.csv")) else {
            return;
        };
        let table = read_record(&path, &ReadOptions::default()).unwrap();
        let y: Vec<&[f64]> = table
            .names
            .iter()
            .zip(&table.columns)
            .filter(|(n, _)| n.as_str() != "t")
            .map(|(_, c)| c.as_slice())
            .collect();
        let spectra = fdd(&y, 20.0, &FddOptions::default()).unwrap();
        let ssi = covssi::analyze(&y, 20.0, &covssi::AnalysisOptions::default()).unwrap();
        let ssi_modes = ssi.reported_modes();
        for (f, z) in truth(name) {
            let e = efdd(&spectra, f, &FddOptions::default()).unwrap();
            let s = ssi_modes
                .iter()
                .min_by(|a, b| {
                    (a.frequency_hz - f)
                        .abs()
                        .total_cmp(&(b.frequency_hz - f).abs())
                })
                .unwrap();
            println!(
                "{name}: truth {f:.4} Hz ζ {z:.3}; EFDD {:.4} Hz ({:+.2} %) ζ {:.4} ({:+.1} %) over {} extrema; SSI {:.4} Hz ({:+.2} %) ζ {:.4} ({:+.1} %)",
                e.frequency_hz,
                100.0 * (e.frequency_hz / f - 1.0),
                e.damping_ratio,
                100.0 * (e.damping_ratio / z - 1.0),
                e.extrema_fitted,
                s.frequency_hz,
                100.0 * (s.frequency_hz / f - 1.0),
                s.damping_ratio,
                100.0 * (s.damping_ratio / z - 1.0),
            );
            // EFDD's spread and bias over 30 seeds of these systems (covssi/tests/fdd.rs):
            // frequency within 0.8 %, damping within 7 ± 11 %: one record within 1 % and 25 %.
            assert!((e.frequency_hz / f - 1.0).abs() < 0.01, "{e:?}");
            assert!((e.damping_ratio / z - 1.0).abs() < 0.25, "{e:?}");
            // From SSI's shape (as the page asks it), the same bell for a mode with no
            // close neighbour: the same answer as from the peak, to the bell's line.
            let own = efdd_of_mode(
                &spectra,
                s.frequency_hz,
                s.shape.as_deref().unwrap(),
                &FddOptions::default(),
            )
            .unwrap();
            println!(
                "{name}: EFDD of SSI's shape {:.4} Hz ζ {:.4}, bell {:?} (from the peak {:?})",
                own.frequency_hz, own.damping_ratio, own.bell_hz, e.bell_hz
            );
            assert!((own.frequency_hz / f - 1.0).abs() < 0.01, "{own:?}");
            assert!((own.damping_ratio / z - 1.0).abs() < 0.25, "{own:?}");
        }
    }
}
