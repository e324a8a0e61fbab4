//! The measured F-16 at its four force levels (12–98 N RMS): output-only SSI on the three
//! accelerations follows the wing torsion mode's softening and rising damping, which the
//! mounting's friction and clearance cause. Checked against a second method with the force,
//! the fit of the force-to-acceleration response (`hyst_ident::frf`), and that fit at the
//! lowest level against the figures the benchmark's README publishes. The offset between the
//! two methods is the force's colour: the shaker's force drops at the resonance, which
//! output-only methods cannot see, and flattening the force removes it.
//! (`cargo xtask f16` prints the full table and draws the figures.)

use crate::common;

use covssi::{self, BlockRows, SsiOptions};
use hyst_ident::frf::{self, PeriodicRecord};

const PERIOD: usize = 8192;
const FS: f64 = 400.0;

struct Level {
    /// Output-only SSI (frequency Hz, damping ratio) of the torsion and bending clusters.
    ssi: [(f64, f64); 2],
    /// The same with the force made flat.
    ssi_flat: [(f64, f64); 2],
    /// The response fit of each mode alone in its band.
    fit: [(f64, f64); 2],
    /// Each acceleration's RMS over the record, then within each mode's band (torsion,
    /// bending), from the fit's measured lines.
    rms: Vec<f64>,
    /// MAC of each mode's SSI shape (acc1, acc2, acc3) with the fit's (its residues).
    shape_mac: [f64; 2],
}

const TORSION: usize = 0;
const BENDING: usize = 1;
/// (nominal Hz, band of the response fit).
const MODES: [(f64, (f64, f64)); 2] = [(7.3, (6.8, 7.8)), (5.2, (4.6, 5.8))];

fn level(n: u32) -> Option<Level> {
    let p = common::data_file(&format!("f16/msine_level{n}.csv"))?;
    let t = hyst_io::read_csv(&p).expect("shared data must parse");
    // The first period is the start-up transient.
    let col = |c: &str| t.column(c).unwrap()[PERIOD..].to_vec();
    let force = col("force");
    let acc: Vec<Vec<f64>> = ["acc1", "acc2", "acc3"].iter().map(|c| col(c)).collect();
    let outs: Vec<&[f64]> = acc.iter().map(|c| c.as_slice()).collect();
    let rec = PeriodicRecord {
        input: &force,
        outputs: &outs,
        fs: FS,
        period: PERIOD,
    };
    let opts = SsiOptions {
        block_rows: BlockRows::Count(40),
        max_order: Some(60),
        ..SsiOptions::default()
    };
    // 400 → 50 Hz keeps the 2–15 Hz band (as f16_bending_and_torsion_modes in covssi_data).
    let ssi = |ch: &[Vec<f64>]| -> [(f64, f64, Vec<covssi::Complex64>); 2] {
        let dec: Vec<Vec<f64>> = ch
            .iter()
            .map(|c| hyst_sim::resample::decimate(c, 8))
            .collect();
        let views: Vec<&[f64]> = dec.iter().map(|c| c.as_slice()).collect();
        let res = covssi::identify(&views, FS / 8.0, &opts).unwrap();
        MODES.map(|(f, _)| {
            let m = res
                .modes
                .iter()
                .filter(|m| (m.frequency_hz - f).abs() <= 0.3)
                .max_by_key(|m| m.members.len())
                .unwrap_or_else(|| panic!("level {n}: no SSI mode near {f} Hz"));
            (m.frequency_hz, m.damping_ratio, m.shape.clone())
        })
    };
    let flat = frf::outputs_under_flat_input(&rec).unwrap();
    let mut rms: Vec<f64> = acc
        .iter()
        .map(|c| {
            let m = c.iter().sum::<f64>() / c.len() as f64;
            (c.iter().map(|v| (v - m).powi(2)).sum::<f64>() / c.len() as f64).sqrt()
        })
        .collect();
    let fits = MODES.map(|(_, band)| {
        let r = frf::modes_from_frf(&rec, band, 1).unwrap();
        assert_eq!(r.modes.len(), 1, "level {n}, band {band:?}: {:?}", r.modes);
        rms.extend(r.response_rms());
        r.modes[0].clone()
    });
    let (out_only, flat_only) = (ssi(&acc), ssi(&flat));
    let l = Level {
        ssi: out_only.each_ref().map(|m| (m.0, m.1)),
        ssi_flat: flat_only.each_ref().map(|m| (m.0, m.1)),
        fit: fits.each_ref().map(|m| (m.frequency_hz, m.damping_ratio)),
        rms,
        shape_mac: [0, 1].map(|i| covssi::mac(&out_only[i].2, &fits[i].shape)),
    };
    for (i, name) in ["torsion", "bending"].iter().enumerate() {
        eprintln!(
            "level {n} {name}: SSI {:.3} Hz {:.2} %, flat force {:.3} Hz {:.2} %, fit {:.3} Hz {:.2} %, shapes' MAC {:.4}",
            l.ssi[i].0,
            100.0 * l.ssi[i].1,
            l.ssi_flat[i].0,
            100.0 * l.ssi_flat[i].1,
            l.fit[i].0,
            100.0 * l.fit[i].1,
            l.shape_mac[i]
        );
    }
    Some(l)
}

#[test]
fn output_only_follows_the_torsion_mode_over_force_levels() {
    let mut levels = Vec::new();
    for n in [1, 3, 5, 7] {
        let Some(l) = level(n) else { return };
        levels.push(l);
    }
    // The second method against published figures: the README gives the torsion peak at
    // about 7.32 Hz with 0.3–0.5 % damping at the lowest (sine-sweep) level.
    let (f1, z1) = levels[0].fit[TORSION];
    assert!((f1 - 7.32).abs() <= 0.01, "{f1}");
    assert!((0.003..=0.005).contains(&z1), "{z1}");
    // Softening and rising damping with force, by both methods, at every step.
    for w in levels.windows(2) {
        for est in [|l: &Level| l.ssi[TORSION], |l: &Level| l.fit[TORSION]] {
            let (a, b) = (est(&w[0]), est(&w[1]));
            assert!(b.0 < a.0 && b.1 > a.1, "{a:?} -> {b:?}");
        }
        assert!(w[1].ssi[BENDING].0 < w[0].ssi[BENDING].0);
        assert!(w[1].fit[BENDING].0 < w[0].fit[BENDING].0);
    }
    // Output-only shapes against the input-output fit's residues: the same shapes, by the
    // customary 0.99 (measured: 0.9950–0.9998 over both modes and the four levels).
    for (n, l) in [1, 3, 5, 7].iter().zip(&levels) {
        for (i, mac) in l.shape_mac.iter().enumerate() {
            assert!(*mac >= 0.99, "level {n}, mode {i}: MAC {mac}");
        }
    }
    // Output only measures the torsion mode's softening from 12 to 98 N to within 10 % of
    // the input-output fit (measured: 0.167 Hz against 0.166 Hz).
    let drop = |e: fn(&Level) -> (f64, f64)| e(&levels[0]).0 - e(&levels[3]).0;
    let (d_ssi, d_fit) = (drop(|l| l.ssi[TORSION]), drop(|l| l.fit[TORSION]));
    assert!((d_ssi / d_fit - 1.0).abs() < 0.1, "{d_ssi} vs {d_fit}");
    // Output-only frequencies sit above the fit's (by 0.3–0.5 % here), and the force's colour
    // is why: with the force made flat they move to within 0.3 % of the fit, closer at every
    // level.
    for (n, l) in [1, 3, 5, 7].iter().zip(&levels) {
        let (s, g, f) = (l.ssi[TORSION].0, l.ssi_flat[TORSION].0, l.fit[TORSION].0);
        assert!(s > f && s < 1.01 * f, "level {n}: SSI {s}, fit {f}");
        assert!((g - f).abs() < (s - f).abs(), "level {n}: {g} {s} {f}");
        assert!((g - f).abs() < 0.003 * f, "level {n}: {g} {f}");
    }
}

/// The torsion mode's damping sets in faster than a Bouc-Wen element with ν = 1 allows. For
/// −γ ≤ δ < γ the element's loss grows no faster than A^ν (the property test
/// `loss_grows_no_faster_than_amplitude_to_the_nu` in hyst-linearize), and a viscous part
/// beside it only slows that. The torsion loss 2ζω² at 74 N over that at 37 N, from the least
/// favourable pair of the estimates free of the force's colour (the fit and SSI under the
/// flat force: the smaller at 74 N, the larger at 37 N), outgrows the fastest-growing
/// response there is: any sensor's, in either mode's band or over the record. Measured: a
/// ratio of 2.02 over a growth of 1.92 (acc1 in the bending band), so ν ≥ 1.08. With SSI on
/// the measured accelerations among the estimates (biased by the force's drop at the
/// resonance, see the test above) the ratio is 1.86, ν ≥ 0.95: printed, not asserted.
#[test]
fn torsion_damping_sets_in_faster_than_nu_one_allows() {
    let (Some(l3), Some(l5)) = (level(3), level(5)) else {
        return;
    };
    let loss = |(f, z): (f64, f64)| 2.0 * z * (std::f64::consts::TAU * f).powi(2);
    let growth = l3
        .rms
        .iter()
        .zip(&l5.rms)
        .map(|(a, b)| b / a)
        .fold(f64::NAN, f64::max);
    let least_nu = |lo: &[(f64, f64)], hi: &[(f64, f64)]| {
        let lower = lo
            .iter()
            .map(|&e| loss(e))
            .fold(f64::NEG_INFINITY, f64::max);
        let upper = hi.iter().map(|&e| loss(e)).fold(f64::INFINITY, f64::min);
        (upper / lower, (upper / lower).ln() / growth.ln())
    };
    let (ratio, nu) = least_nu(
        &[l3.fit[TORSION], l3.ssi_flat[TORSION]],
        &[l5.fit[TORSION], l5.ssi_flat[TORSION]],
    );
    let (ratio_raw, nu_raw) = least_nu(
        &[l3.fit[TORSION], l3.ssi_flat[TORSION], l3.ssi[TORSION]],
        &[l5.fit[TORSION], l5.ssi_flat[TORSION], l5.ssi[TORSION]],
    );
    eprintln!(
        "torsion loss ratio 37 -> 74 N {ratio:.3} (with raw SSI {ratio_raw:.3}), largest response growth {growth:.3}: ν ≥ {nu:.2} ({nu_raw:.2})"
    );
    assert!(nu > 1.0, "ν ≥ {nu}");
}
