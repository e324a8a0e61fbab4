//! Tests of the frequency-response fit.

use super::*;
use crate::fft::irfft;
use std::f64::consts::TAU;

/// Acceleration response of two modes to a force: $s^2 \sum_r \phi_r/(s^2 + 2\zeta_r\omega_r s + \omega_r^2)$.
fn accel(s: C, modes: &[(f64, f64, f64)]) -> C {
    modes
        .iter()
        .map(|&(f, z, phi)| {
            let w = TAU * f;
            s * s * phi / (s * s + 2.0 * z * w * s + w * w)
        })
        .sum()
}

/// A periodic record whose response is exactly `h` at every line: the output is built in
/// the frequency domain from a random-phase multisine, then repeated.
fn periodic_record(
    m: usize,
    fs: f64,
    periods: usize,
    band: (f64, f64),
    amp: &dyn Fn(f64) -> f64,
    hs: &[&dyn Fn(C) -> C],
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let df = fs / m as f64;
    let mut u = vec![C::new(0.0, 0.0); m / 2 + 1];
    let mut seed = 12345_u64;
    for (k, v) in u.iter_mut().enumerate() {
        let f = k as f64 * df;
        if f >= band.0 && f <= band.1 {
            // A small linear congruential generator for the phases.
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let ph = TAU * ((seed >> 11) as f64 / (1u64 << 53) as f64);
            *v = C::from_polar(amp(f), ph);
        }
    }
    let u1 = irfft(&u, m);
    let ys: Vec<Vec<f64>> = hs
        .iter()
        .map(|h| {
            let y: Vec<C> = u
                .iter()
                .enumerate()
                .map(|(k, &uk)| uk * h(C::new(0.0, TAU * k as f64 * df)))
                .collect();
            irfft(&y, m).repeat(periods)
        })
        .collect();
    (u1.repeat(periods), ys)
}

/// Two modes of exact responses over `periods` periods: the fit over 4.5–8 Hz must give
/// them back to rounding, whatever the band within 10 % of its width. Returns the fit.
fn two_exact_modes(periods: usize, hs: &[&dyn Fn(C) -> C], truth: &[(f64, f64, f64)]) -> FrfFit {
    let (u, ys) = periodic_record(4096, 100.0, periods, (2.0, 15.0), &|_| 1.0, hs);
    let outs: Vec<&[f64]> = ys.iter().map(|v| v.as_slice()).collect();
    let rec = PeriodicRecord {
        input: &u,
        outputs: &outs,
        fs: 100.0,
        period: 4096,
    };
    let fit = modes_from_frf(&rec, (4.5, 8.0), 2).unwrap();
    assert_eq!(fit.modes.len(), 2, "{fit:?}");
    for (m, &(f, z, _)) in fit.modes.iter().zip(truth) {
        // Exact data: only rounding separates the fit from the truth.
        approx::assert_relative_eq!(m.frequency_hz, f, max_relative = 1e-8);
        approx::assert_relative_eq!(m.damping_ratio, z, max_relative = 1e-6);
        assert_eq!(m.shape.len(), hs.len());
    }
    // Exact data: the band does not matter.
    for d in band_spread(&rec, (4.5, 8.0), 2, &fit) {
        assert!(d.frequency_hz < 1e-8 && d.damping < 1e-8, "{d:?}");
    }
    fit
}

#[test]
fn exact_response_gives_the_poles_back() {
    let truth = [(5.2, 0.008, 1.0), (7.3, 0.005, 0.6)];
    let h1 = |s: C| accel(s, &truth);
    let h2 = |s: C| accel(s, &[(5.2, 0.008, -0.4), (7.3, 0.005, 1.3)]);
    let fit = two_exact_modes(1, &[&h1, &h2], &truth);
    // With one period the misfit has unit weights: the rounding of the transforms.
    assert!(fit.misfit < 1e-20, "{}", fit.misfit);
    // Each output's residue at mode r is λ²φ_r/(λ − λ̄): the shape is (φ at output 1,
    // φ at output 2), here (1, −0.4) and (0.6, 1.3), the largest entry 1.
    for (m, want) in fit.modes.iter().zip([[1.0, -0.4], [0.6 / 1.3, 1.0]]) {
        for (got, w) in m.shape.iter().zip(want) {
            // Exact data: rounding, as the poles (1e-8).
            assert!(
                (got - Complex64::new(w, 0.0)).norm() < 1e-8,
                "{:?}",
                m.shape
            );
        }
    }
}

#[test]
fn identical_periods_do_not_break_the_weights() {
    // Copies of one period: no noise at all, so the spread over periods is 0 or rounding.
    let truth = [(5.2, 0.008, 1.0), (7.3, 0.005, 0.6)];
    let h = |s: C| accel(s, &truth);
    two_exact_modes(4, &[&h], &truth);
}

/// [`modes_from_frf`] of `modes` modes over `band` on a record of whole periods.
fn fit_of(
    u: &[f64],
    ys: &[Vec<f64>],
    (fs, period): (f64, usize),
    band: (f64, f64),
    modes: usize,
) -> FrfFit {
    let outs: Vec<&[f64]> = ys.iter().map(|v| v.as_slice()).collect();
    let rec = PeriodicRecord {
        input: u,
        outputs: &outs,
        fs,
        period,
    };
    modes_from_frf(&rec, band, modes).unwrap()
}

/// Standard normal draws: Box-Muller on a small LCG, deterministic and adequate for a
/// test.
fn gaussians(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (next(), next());
        (-2.0 * a.ln()).sqrt() * (TAU * b).cos()
    }
}

/// One mode seen by two outputs (shape (1, 0.6)), eight noisy periods: the jackknife
/// standard error of the shape's second entry describes its spread over 40 noise draws.
#[test]
fn shape_standard_errors_are_calibrated() {
    let h1 = |s: C| accel(s, &[(7.3, 0.006, 1.0)]);
    let h2 = |s: C| accel(s, &[(7.3, 0.006, 0.6)]);
    let (u, ys) = periodic_record(2048, 50.0, 8, (2.0, 15.0), &|_| 1.0, &[&h1, &h2]);
    let rms: Vec<f64> = ys
        .iter()
        .map(|y| (y.iter().map(|v| v * v).sum::<f64>() / y.len() as f64).sqrt())
        .collect();
    let mut gauss = gaussians(11);
    let mut z2 = Vec::new();
    for _ in 0..40 {
        let noisy: Vec<Vec<f64>> = ys
            .iter()
            .zip(&rms)
            .map(|(y, r)| y.iter().map(|v| v + 0.05 * r * gauss()).collect())
            .collect();
        let fit = fit_of(&u, &noisy, (50.0, 2048), (6.5, 8.0), 1);
        let m = &fit.modes[0];
        assert_eq!(m.shape_se[0], 0.0, "{m:?}");
        z2.push((m.shape[1] - Complex64::new(0.6, 0.0)).norm_sqr() / m.shape_se[1].powi(2));
    }
    // The complex error over its standard error, RMS: t-like with 7 degrees of freedom
    // per component, √(7/5) ≈ 1.18 (as for the poles, below); 0.7–1.6 as there.
    let z = (z2.iter().sum::<f64>() / z2.len() as f64).sqrt();
    eprintln!("shape z RMS over 40 draws: {z:.3}");
    assert!(z > 0.7 && z < 1.6, "shape z RMS {z}");
}

#[test]
fn noise_gives_calibrated_standard_errors() {
    // One mode, eight noisy periods: the jackknife standard errors must describe the
    // spread of the estimates over noise draws (checked over 40 draws).
    let truth = (7.3, 0.006, 1.0);
    let h = |s: C| accel(s, &[truth]);
    let (u, ys) = periodic_record(2048, 50.0, 8, (2.0, 15.0), &|_| 1.0, &[&h]);
    let rms = (ys[0].iter().map(|v| v * v).sum::<f64>() / ys[0].len() as f64).sqrt();
    let mut zf = Vec::new();
    let mut zz = Vec::new();
    let mut gauss = gaussians(7);
    for _ in 0..40 {
        let y: Vec<f64> = ys[0].iter().map(|v| v + 0.05 * rms * gauss()).collect();
        let fit = fit_of(&u, &[y], (50.0, 2048), (6.5, 8.0), 1);
        assert_eq!(fit.modes.len(), 1);
        let m = &fit.modes[0];
        zf.push((m.frequency_hz - truth.0) / m.frequency_se_hz);
        zz.push((m.damping_ratio - truth.1) / m.damping_se);
        // Fitted to the noise: the misfit's expectation is 1.
        assert!(fit.misfit > 0.3 && fit.misfit < 3.0, "{}", fit.misfit);
    }
    let rms_z = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    // With a jackknife over 8 periods the standardized error is t-like with 7 degrees of
    // freedom, RMS √(7/5) ≈ 1.18; over 40 draws that RMS is itself uncertain by about
    // ±0.15 (heavier tails than 1/√80 of a Gaussian), so 0.7–1.6 is allowed. Over 400 draws
    // it measured 1.16 (frequency) and 1.18 (damping); with the full record's weights in
    // every jackknife fit (a defect) it was 1.30 and 1.30.
    let (a, b) = (rms_z(&zf), rms_z(&zz));
    eprintln!("z RMS over 40 draws: frequency {a:.3}, damping {b:.3}");
    assert!(a > 0.7 && a < 1.6, "frequency z RMS {a}");
    assert!(b > 0.7 && b < 1.6, "damping z RMS {b}");
}

#[test]
fn a_coloured_input_is_made_flat() {
    // The same structure driven by a flat and by a coloured multisine (same phases): with
    // the colour divided out, the second record's outputs are the first's times the mean
    // line amplitude of the coloured input.
    let h = |s: C| accel(s, &[(7.3, 0.005, 1.0)]);
    let colour = |f: f64| 1.0 + 0.8 * (f / 1.3).sin();
    let (m, fs, band) = (1024, 40.0, (2.0, 15.0));
    let (_, flat) = periodic_record(m, fs, 3, band, &|_| 1.0, &[&h]);
    let (u, ys) = periodic_record(m, fs, 3, band, &colour, &[&h]);
    let outs: Vec<&[f64]> = ys.iter().map(|v| v.as_slice()).collect();
    let rec = PeriodicRecord {
        input: &u,
        outputs: &outs,
        fs,
        period: m,
    };
    let got = outputs_under_flat_input(&rec).unwrap();
    let df = fs / m as f64;
    let lines: Vec<f64> = (1..=m / 2)
        .map(|k| k as f64 * df)
        .filter(|f| *f >= band.0 && *f <= band.1)
        .map(colour)
        .collect();
    let mean = lines.iter().sum::<f64>() / lines.len() as f64;
    let scale = flat[0].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for (a, b) in got[0].iter().zip(&flat[0]) {
        // Two transforms each way: rounding at 1e-12 of the signal's peak.
        assert!((a - mean * b).abs() < 1e-12 * scale, "{a} vs {}", mean * b);
    }
}

#[test]
fn bad_records_are_named() {
    let u = vec![1.0; 100];
    let y = vec![0.0; 90];
    let outs = [y.as_slice()];
    let rec = PeriodicRecord {
        input: &u,
        outputs: &outs,
        fs: 100.0,
        period: 50,
    };
    let e = modes_from_frf(&rec, (1.0, 10.0), 1).unwrap_err();
    assert!(
        e.to_string().contains("input has 100 samples, output 90"),
        "{e}"
    );
    let mut y = vec![0.5; 100];
    y[17] = f64::NAN;
    let outs = [y.as_slice()];
    let rec = PeriodicRecord {
        outputs: &outs,
        ..rec
    };
    let e = modes_from_frf(&rec, (1.0, 10.0), 1).unwrap_err();
    assert!(e.to_string().contains("sample 17"), "{e}");
    let mut big = vec![0.5; 100];
    big[17] = 3e200;
    let outs = [big.as_slice()];
    let rec = PeriodicRecord {
        outputs: &outs,
        ..rec
    };
    let e = modes_from_frf(&rec, (1.0, 10.0), 1).unwrap_err();
    assert!(
        e.to_string()
            .contains("sample 17: value 3e200 is too large"),
        "{e}"
    );
    let y = vec![0.5; 100];
    let outs = [y.as_slice()];
    let rec = PeriodicRecord {
        outputs: &outs,
        ..rec
    };
    // A constant input excites no line.
    let e = modes_from_frf(&rec, (1.0, 10.0), 1).unwrap_err();
    assert!(e.to_string().contains("excited lines"), "{e}");
    // No mode, and a band beyond Nyquist.
    let (u, ys) = periodic_record(256, 10.0, 2, (1.0, 4.0), &|_| 1.0, &[&|s: C| s / (s + 1.0)]);
    let outs = [ys[0].as_slice()];
    let good = PeriodicRecord {
        input: &u,
        outputs: &outs,
        fs: 10.0,
        period: 256,
    };
    assert!(matches!(
        modes_from_frf(&good, (1.0, 4.0), 0),
        Err(IdentError::NoModesAsked)
    ));
    let e = modes_from_frf(&good, (1.0, 6.0), 1).unwrap_err();
    assert!(
        e.to_string()
            .contains("band 1..6 Hz is not an interval within 0..5 Hz"),
        "{e}"
    );
    // More modes than any band holds: too few lines, with the count saturated rather
    // than wrapped round (it read 2^63 before).
    match modes_from_frf(&good, (1.0, 4.0), usize::MAX) {
        Err(IdentError::FewLines { needed, .. }) => {
            assert_eq!(needed, usize::MAX.div_ceil(2), "{needed}")
        }
        other => panic!("{other:?}"),
    }
    // A wrong period: the multisine repeats every 256 samples, not 200.
    let short = PeriodicRecord {
        period: 200,
        ..good
    };
    let e = modes_from_frf(&short, (1.0, 4.0), 1).unwrap_err();
    assert!(
        e.to_string().contains("does not repeat every 200 samples"),
        "{e}"
    );
    let rec = PeriodicRecord { fs: 0.0, ..rec };
    assert!(matches!(
        modes_from_frf(&rec, (1.0, 10.0), 1),
        Err(IdentError::BadRate { .. })
    ));
}
