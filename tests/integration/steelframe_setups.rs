//! The steel frame's 15 setups (`shared/data/steelframe`, pyOMA's layout, read as is) merged
//! by `hyst::setups`: the modes the data README lists, every one in every setup but the
//! doubtful 13.86 Hz one; the factor between the laser velocities and the reference
//! accelerations found from the rigid top floor (−0.5, as the README says), and, told that
//! factor, the merged shapes keep the top floor rigid.
//!
//! `cargo test --release --test steelframe_setups -- --nocapture` prints the merged modes.

use crate::common;

use covssi::Complex64 as C64;
use covssi::multisetup::{MergeOptions, MergedMode, Quantity};
use hyst::setups::{SetupsReport, merge_analysed};

/// The README's modes (pyOMA2 1.4 and by hand), Hz.
const README_HZ: [f64; 11] = [
    1.2287, 1.4359, 2.1000, 4.0172, 4.7706, 6.6822, 7.6156, 9.6652, 12.1668, 12.5982, 13.863,
];

/// Node `node`'s motion along axis `k` in `mode`, and its standard error.
fn motion(mode: &MergedMode, node: &str, k: usize) -> (C64, f64) {
    let n = mode.nodes.iter().find(|n| n.node == node).unwrap();
    (n.motion[k].unwrap(), n.se[k].unwrap())
}

/// On the rigid top floor, node 21 moves as node 24 in x (same y) and node 23 as node 24 in
/// y (same x): the ratios of the laser-derived to the reference motion, each with its
/// standard error (first order, from both entries'), over the modes where the reference
/// moves at least `least` of the shape's largest entry, among the modes every setup saw (the
/// doubtful 13.86 Hz one left out).
fn rigid_floor_ratios(report: &SetupsReport, least: f64) -> Vec<(C64, f64)> {
    let mut ratios = Vec::new();
    for m in report.merged.modes.iter().filter(|m| m.seen_in.len() == 15) {
        for (node, k) in [("21", 0), ("23", 1)] {
            let (reference, se_ref) = motion(m, "24", k);
            if reference.norm() >= least && m.nodes.iter().any(|n| n.node == node) {
                let (laser, se_laser) = motion(m, node, k);
                let r = laser / reference;
                let se = r.norm() * (se_laser / laser.norm()).hypot(se_ref / reference.norm());
                ratios.push((r, se));
            }
        }
    }
    ratios
}

/// Each ratio's distance from `expected` in its standard errors.
fn ratio_z(ratios: &[(C64, f64)], expected: f64) -> Vec<f64> {
    ratios
        .iter()
        .map(|(r, se)| (r - C64::new(expected, 0.0)).norm() / se)
        .collect()
}

#[test]
fn the_steel_frames_setups_merge_into_its_modes_and_find_the_sensors_factor() {
    let Some((setups, report, _)) = common::steel_frame() else {
        return;
    };
    let mut setups = setups.clone();
    println!("{report}");
    let modes = &report.merged.modes;
    assert_eq!(modes.len(), README_HZ.len(), "{report}");
    for (m, f) in modes.iter().zip(README_HZ) {
        // Each within three of its standard errors (from the 15 setups' scatter) of the
        // README's, plus the README's rounding to four decimals.
        let se = m.frequency_se_hz.unwrap();
        assert!(
            (m.frequency_hz - f).abs() < 3.0 * se + 5e-5,
            "{} ± {se} vs {f}",
            m.frequency_hz
        );
    }
    // Every mode but the doubtful 13.86 Hz one is in all 15 setups.
    assert!(modes[..10].iter().all(|m| m.seen_in.len() == 15));
    // The global estimation (SSI once on all setups' correlations) finds every one of the
    // README's modes within 0.2 % (measured: 0.0002–0.13 %); the MAC of its shapes with the
    // merge's is printed in the report above (0.79–0.97 when this was written).
    let global = report.global.as_ref().expect("the global estimation ran");
    for f in README_HZ {
        assert!(
            global
                .modes
                .iter()
                .any(|m| (m.frequency_hz - f).abs() < 2e-3 * f),
            "no global mode near {f} Hz: {:?}",
            global
                .modes
                .iter()
                .map(|m| m.frequency_hz)
                .collect::<Vec<_>>()
        );
    }
    // The rigid top floor: laser over reference is −0.5 in every mode where the reference
    // moves at least half the largest entry (the README's factor, found).
    // Each within 3.5 of its standard errors (the setups' jackknife errors carried through
    // the merge): over 13 ratios a |z| above 3.5 has a chance of 0.6 % if the errors hold.
    let ratios = rigid_floor_ratios(report, 0.5);
    let z = ratio_z(&ratios, -0.5);
    println!("laser/reference on the rigid top floor (ratio, se, z): ");
    for ((r, se), z) in ratios.iter().zip(&z) {
        println!("  {:.4}{:+.4}i ± {se:.4}  z {z:.2}", r.re, r.im);
    }
    assert!(ratios.len() >= 8, "{ratios:?}");
    assert!(z.iter().all(|z| *z < 3.5), "{ratios:?} {z:?}");
    // The command's check (hyst ssi --setups --rigid-floors: the top floor's rigid motion
    // fitted to the lasers' nodes 21–23, against the references at node 24) finds the same
    // factor: within 3.5 of its standard error of −0.5 and of these ratios' weighted mean
    // (a second estimate from two of the floor's nodes alone), and says it is one to check.
    let folder = common::data_file("steelframe/grid.txt").unwrap();
    let (geometry, _) = hyst::io::setups_geometry(folder.parent().unwrap(), None, None)
        .unwrap()
        .unwrap();
    let check = |r: &SetupsReport, expected: f64| {
        let floors = hyst::rigid_floors::floor_factors(&r.merged, &geometry);
        let [f] = &floors[..] else {
            panic!("one floor holds the references: {floors:?}")
        };
        assert_eq!(
            (f.reference_node.as_str(), f.nodes.len()),
            ("24", 3),
            "{f:?}"
        );
        let z = (f.factor - C64::new(expected, 0.0)).norm() / f.factor_se;
        assert!(z < 3.5 && f.factor_se < 0.02, "{f:?}");
        f.clone()
    };
    let found = check(report, -0.5);
    assert!(found.to_check);
    let w: f64 = ratios.iter().map(|(_, se)| se.powi(-2)).sum();
    let mean = ratios.iter().map(|(r, se)| r / (se * se)).sum::<C64>() / w;
    let se_mean = w.sqrt().recip();
    assert!(
        (found.factor - mean).norm() < 3.5 * found.factor_se.hypot(se_mean),
        "{found:?} against {mean} ± {se_mean}"
    );
    // Told the factor (the laser channels read −0.5 times the motion), the floor is rigid.
    for ch in setups.iter_mut().flat_map(|s| s.channels.iter_mut()) {
        if ch.quantity == Quantity::Velocity {
            ch.gain = -0.5;
        }
    }
    let told = merge_analysed(&setups, report.setups.clone(), &MergeOptions::default()).unwrap();
    let ratios = rigid_floor_ratios(&told, 0.5);
    let z = ratio_z(&ratios, 1.0);
    println!("told the factor, node/reference on the top floor: {ratios:.4?}, z {z:.2?}");
    assert!(z.iter().all(|z| *z < 3.5), "{ratios:?} {z:?}");
    // And the command's check then finds the channels read as the setups state.
    assert!(!check(&told, 1.0).to_check);
}

#[test]
fn the_setups_progress_is_told_setup_by_setup() {
    let Some((setups, _, told)) = common::steel_frame() else {
        return;
    };
    // Every setup tells its analysis's steps before it is identified, and each identified
    // setup is counted once: 1, 2, … up to all of them (two setups finishing together may
    // tell their counts in either order).
    for s in setups {
        let own: Vec<&common::Told> = told
            .iter()
            .filter(|t| t.setup.as_deref() == Some(&s.name))
            .collect();
        let done = own.iter().position(|t| t.what == "identified");
        assert!(
            matches!(done, Some(i) if i > 0),
            "setup {}: {own:?}",
            s.name
        );
    }
    let mut counts: Vec<usize> = told
        .iter()
        .filter(|t| t.what == "identified")
        .map(|t| t.identified)
        .collect();
    counts.sort_unstable();
    assert_eq!(counts, (1..=setups.len()).collect::<Vec<_>>());
    // Then the global estimation and the merge, told after every setup.
    let last: Vec<&str> = told.iter().rev().take(2).map(|t| t.what.as_str()).collect();
    assert!(
        last[0].starts_with("merging") && last[1].starts_with("the global"),
        "{last:?}"
    );
    assert!(told.iter().rev().take(2).all(|t| t.setup.is_none()));
    // The longest silence, for the record (the test binary shares the machine with the
    // other tests, so this is no measure of the command alone).
    let (gap, after) = told
        .windows(2)
        .map(|w| (w[1].seconds - w[0].seconds, &w[0]))
        .fold(
            (0.0, None),
            |(g, a), (d, t)| if d > g { (d, Some(t)) } else { (g, a) },
        );
    eprintln!(
        "steel frame: {} steps told in {:.1} s, the longest silence {gap:.1} s, after {after:?}",
        told.len(),
        told.last().map_or(0.0, |t| t.seconds)
    );
}
