//! The curves against truths computed without them: a linear oscillator's constant
//! frequency and damping, and a Bouc-Wen oscillator's describing function (harmonic
//! balance of the model itself, eqs. 13, 19, 20 of the paper in their exact form).

use super::*;
use hyst_model::{BoucWen, Oscillator};
use hyst_sim::{Decimation, Integrator, SimOptions};

/// The response of `model` to a white force of `rms` N, `n` samples at `fs` from a
/// trapezoidal integrator at 8 sub-steps with FIR decimation, after a start-up of 2 s.
fn record(model: &Oscillator, rms: f64, n: usize, fs: f64, seed: u64) -> Vec<f64> {
    let skip = (2.0 * fs) as usize;
    let u = hyst_sim::excitation::white_noise(n + skip, rms, seed).expect("white force");
    let opts = SimOptions {
        oversample: 8,
        integrator: Integrator::Trapezoidal,
        decimation: Decimation::fir_stages(8),
        ..SimOptions::default()
    };
    let y = hyst_sim::response(model, &u, fs, hyst_sim::InputKind::BandLimited, &opts)
        .expect("simulation");
    y[skip..].to_vec()
}

/// The truth of a Bouc-Wen oscillator at displacement amplitude `a`: (Hz, damping ratio)
/// of the linear mode its describing function gives.
fn bouc_wen_truth(model: &Oscillator, bw: &BoucWen, a: f64) -> (f64, f64) {
    let df = hyst_linearize::describing_function(bw, a).expect("describing function");
    let wn = ((model.stiffness + df.stiffness) / model.mass).sqrt();
    let zeta = (model.damping + df.loss / wn) / (2.0 * model.mass * wn);
    (wn / (2.0 * std::f64::consts::PI), zeta)
}

fn options(method: AmplitudeMethod, cycles: f64) -> AmplitudeOptions {
    AmplitudeOptions {
        method,
        cycles,
        ..AmplitudeOptions::default()
    }
}

fn benchmark_mode(f: f64) -> ModeToFollow {
    ModeToFollow {
        frequency_hz: f,
        damping_ratio: 0.02,
        shape: None,
    }
}

/// The linearity test of `model`'s mode (near 36 Hz) on a record of 2^`bits` samples at
/// 750 Hz under a 50 N white force.
fn bouc_wen_linearity(model: &Oscillator, bits: u32, seed: u64) -> Linearity {
    let fs = 750.0;
    let y = record(model, 50.0, 1 << bits, fs, seed);
    let r = amplitude_curves(
        &[&y],
        fs,
        &[benchmark_mode(36.0)],
        &[],
        &AmplitudeOptions::default(),
    )
    .expect("curves");
    r.modes[0].linearity.expect("a test")
}

/// z-scores of a linear oscillator's points against its exact frequency and damping, over
/// `seeds`, and the records called linear.
fn linear_study(
    method: AmplitudeMethod,
    cycles: f64,
    seeds: std::ops::Range<u64>,
) -> (Vec<f64>, Vec<f64>, usize) {
    let fs = 750.0;
    let lin = Oscillator::linear(2.0, 10.0, 1e5);
    let wn = (1e5f64 / 2.0).sqrt();
    let (ft, zt) = (wn / (2.0 * std::f64::consts::PI), 10.0 / (4.0 * wn));
    let (mut zf, mut zz, mut linear) = (Vec::new(), Vec::new(), 0);
    for seed in seeds {
        let y = record(&lin, 50.0, 1 << 16, fs, seed);
        let r = amplitude_curves(
            &[&y],
            fs,
            &[benchmark_mode(35.0)],
            &[],
            &options(method, cycles),
        )
        .expect("curves");
        for p in &r.modes[0].points {
            zf.push((p.frequency_hz - ft) / p.frequency_se_hz);
            zz.push((p.damping_ratio - zt) / p.damping_se);
        }
        linear += usize::from(r.modes[0].linearity.is_some_and(|l| l.linear));
    }
    (zf, zz, linear)
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

fn within_two(v: &[f64]) -> f64 {
    v.iter().filter(|x| x.abs() < 2.0).count() as f64 / v.len() as f64
}

/// The specification on a linear mode, over 20 fresh seeds (8 points each): every point
/// within 2 standard errors of the exact frequency and damping ratio for ≥ 90 % of points,
/// the standard errors calibrated (RMS z in 0.7–1.3: with 160 points, an RMS z of 1 has a
/// sampling spread of about 0.06, so the band holds a calibrated jackknife with room for the
/// points' mutual correlation), and the mode called linear on ≥ 19 of 20 records (the test's
/// level is 1 %).
#[test]
fn a_linear_mode_is_linear_with_calibrated_errors() {
    let (zf, zz, linear) = linear_study(AmplitudeMethod::Envelope, 3.0, 4100..4120);
    for (what, z) in [("frequency", &zf), ("damping", &zz)] {
        assert!((0.7..1.3).contains(&rms(z)), "{what}: RMS z {}", rms(z));
        assert!(
            within_two(z) >= 0.9,
            "{what}: {} within 2 SE",
            within_two(z)
        );
    }
    assert!(linear >= 19, "{linear} of 20 called linear");
}

/// The benchmark's Bouc-Wen oscillator under a 50 N white force, called amplitude-dependent
/// with its frequency rising significantly with the amplitude on each of three fresh 175 s
/// records, and its damping rising on a 350 s one, as the describing function of the element
/// says (a hardening element, δ < 0, whose loop widens with the amplitude). The study
/// `study_power` measured, over 20 seeds each: called amplitude-dependent on 18/20 records of
/// 87 s and 20/20 of 175 s and 350 s; the damping's fitted change positive on 15/20, 18/20
/// and 20/20 (the random response's damping rises less steeply than the describing
/// function's: docs/amplitude.md).
#[test]
fn a_bouc_wen_mode_is_amplitude_dependent() {
    let bw = BoucWen::benchmark();
    let model = Oscillator::bouc_wen(2.0, 10.0, 5e4, bw);
    let (f_lo, z_lo) = bouc_wen_truth(&model, &bw, 2e-4);
    let (f_hi, z_hi) = bouc_wen_truth(&model, &bw, 6e-4);
    assert!(f_hi > f_lo && z_hi > z_lo);
    for seed in 4300..4303 {
        let l = bouc_wen_linearity(&model, 17, seed);
        assert!(!l.linear, "seed {seed}: {l:?}");
        assert!(
            l.frequency.change > 2.0 * l.frequency.change_se,
            "seed {seed}: {l:?}"
        );
    }
    let l = bouc_wen_linearity(&model, 18, 4310);
    assert!(l.damping.change > 0.0, "{l:?}");
}

/// Bad input is refused with the value named; a record too short for any point says so.
#[test]
fn bad_input_is_named() {
    let y = vec![0.1f64; 1000];
    let m = benchmark_mode(10.0);
    let err = |o: AmplitudeOptions| {
        amplitude_curves(&[&y], 100.0, std::slice::from_ref(&m), &[], &o)
            .unwrap_err()
            .to_string()
    };
    assert!(
        err(AmplitudeOptions {
            levels: 0,
            ..Default::default()
        })
        .contains("levels = 0")
    );
    assert!(
        err(AmplitudeOptions {
            cycles: 0.1,
            ..Default::default()
        })
        .contains("cycles = 0.1")
    );
    assert!(
        err(AmplitudeOptions {
            period: Some(5000),
            ..Default::default()
        })
        .contains("fewer than one period")
    );
    let bad = [f64::NAN; 10];
    let e = amplitude_curves(
        &[&bad],
        100.0,
        std::slice::from_ref(&m),
        &[],
        &AmplitudeOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("sample 0"), "{e}");
    let e = amplitude_curves(
        &[&y, &y[..10]],
        100.0,
        std::slice::from_ref(&m),
        &[],
        &AmplitudeOptions::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("channel 1 has 10 samples"), "{e}");
    let far = ModeToFollow {
        frequency_hz: 60.0,
        ..m.clone()
    };
    let e = amplitude_curves(&[&y], 100.0, &[far], &[], &AmplitudeOptions::default()).unwrap_err();
    assert!(e.to_string().contains("not inside (0, 50)"), "{e}");
    // 40 samples of a 10 Hz mode hold too few triggers for a point.
    let short: Vec<f64> = (0..40).map(|i| (i as f64 * 0.6).sin()).collect();
    let r = amplitude_curves(&[&short], 100.0, &[m], &[], &AmplitudeOptions::default())
        .expect("a report");
    assert!(r.modes[0].points.is_empty());
    assert!(
        r.modes[0]
            .notes
            .iter()
            .any(|n| n.contains("fewer than the 50 triggers")),
        "{:?}",
        r.modes[0].notes
    );
}

/// A mode buried in white noise is said to be weak: a 2 % mode at 10 Hz whose band holds
/// white noise of about three times its variance; the same mode alone is not.
#[test]
fn a_weak_mode_is_said_to_be_weak() {
    let fs = 100.0;
    let lin = Oscillator::linear(1.0, 2.0 * 0.02 * 62.83, 62.83f64.powi(2));
    let clean = record(&lin, 1.0, 1 << 15, fs, 4400);
    let sd = (clean.iter().map(|v| v * v).sum::<f64>() / clean.len() as f64).sqrt();
    let mut noisy = clean.clone();
    // White noise of 4·sd over 0–50 Hz puts about 16·sd²·(6/50) ≈ 2·sd² in the ± 3 Hz band.
    hyst_sim::excitation::add_noise(&mut noisy, 4.0 * sd, 4401).expect("noise");
    let m = ModeToFollow {
        frequency_hz: 10.0,
        damping_ratio: 0.02,
        shape: None,
    };
    let weak = |y: &[f64]| {
        let r = amplitude_curves(
            &[y],
            fs,
            std::slice::from_ref(&m),
            &[],
            &AmplitudeOptions::default(),
        )
        .expect("a report");
        r.modes[0].notes.iter().any(|n| n.contains("weak"))
    };
    assert!(weak(&noisy));
    assert!(!weak(&clean));
}

/// A saturated channel is named; a clean one, or a constant-free sine, is not.
#[test]
fn clipped_channels_are_named() {
    let sine: Vec<f64> = (0..20_000).map(|i| (i as f64 * 0.0123).sin()).collect();
    let clipped: Vec<f64> = sine.iter().map(|v| v.clamp(-0.9, 0.9)).collect();
    // A sine of a whole number of samples per period reaches the same peak value every
    // period (issue 58: a pure sinusoid was called clipped); it is not clipped.
    let periodic: Vec<f64> = (0..20_000)
        .map(|i| (2.0 * std::f64::consts::PI * i as f64 / 20.0).sin())
        .collect();
    let found = clipped_channels(&[&sine, &clipped, &periodic]);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].channel, 1);
    assert!(
        found[0].value.abs() == 0.9 && found[0].samples > 1000,
        "{found:?}"
    );
}

/// The tables of docs/amplitude.md: the two methods on the linear oscillator over 30 fresh
/// seeds per setting, and the Bouc-Wen oscillators against their describing function and
/// a free decay. `cargo test --release -p hyst-ident --lib amplitude::tests::study --
/// --ignored --nocapture`.
#[test]
#[ignore = "a study for the documentation (about a minute)"]
fn study() {
    for method in [AmplitudeMethod::Envelope, AmplitudeMethod::Extrema] {
        for cycles in [1.0, 3.0, 6.0] {
            let (zf, zz, linear) = linear_study(method, cycles, 2000..2030);
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            println!(
                "| {method:?} | {cycles} | {:+.2} | {:.2} | {:.2} | {:+.2} | {:.2} | {:.2} | {linear}/30 |",
                mean(&zf),
                rms(&zf),
                within_two(&zf),
                mean(&zz),
                rms(&zz),
                within_two(&zz)
            );
        }
    }
    let fs = 750.0;
    let bw = BoucWen::benchmark();
    for (k, force) in [(5e4, 50.0), (5e4, 10.0), (2e5, 50.0), (5e5, 200.0)] {
        let model = Oscillator::bouc_wen(2.0, 10.0, k, bw);
        let y = record(&model, force, 1 << 17, fs, 31);
        let f0 = ((k + bw.alpha) / 2.0f64).sqrt() / (2.0 * std::f64::consts::PI);
        let r = amplitude_curves(
            &[&y],
            fs,
            &[benchmark_mode(f0)],
            &[],
            &AmplitudeOptions::default(),
        )
        .expect("curves");
        println!("k = {k:e} N/m, white force {force} N RMS:");
        for p in &r.modes[0].points {
            let (ft, zt) = bouc_wen_truth(&model, &bw, p.amplitude);
            println!(
                "| {:.3e} | {:.3} ± {:.3} | {:.3} | {:.2} ± {:.2} | {:.2} |",
                p.amplitude,
                p.frequency_hz,
                p.frequency_se_hz,
                ft,
                100.0 * p.damping_ratio,
                100.0 * p.damping_se,
                100.0 * zt
            );
        }
    }
    let model = Oscillator::bouc_wen(2.0, 10.0, 5e4, bw);
    println!("free decay from 1 mm, z = 0 (the first cycles):");
    for (a, f, z) in free_decay_truth(&model, 1.0e-3, fs, 1 << 12).iter().take(8) {
        let (ft, zt) = bouc_wen_truth(&model, &bw, *a);
        println!(
            "| {a:.3e} | {f:.3} | {ft:.3} | {:.2} | {:.2} |",
            100.0 * z,
            100.0 * zt
        );
    }
}

/// Free decay of `model` from displacement `x0` (z = 0), `n` samples at `fs`: the truth by
/// simulation, read by the analytic signal (FFT Hilbert transform): (amplitude, Hz, ζ) at
/// each full cycle after the first.
fn free_decay_truth(model: &Oscillator, x0: f64, fs: f64, n: usize) -> Vec<(f64, f64, f64)> {
    let opts = SimOptions {
        oversample: 16,
        integrator: Integrator::Trapezoidal,
        decimation: Decimation::Subsample,
        ..SimOptions::default()
    };
    let mut s0 = hyst_model::State::zeros();
    s0[0] = x0;
    let zeros = vec![0.0; n];
    let (x, _) = hyst_sim::simulate_from(model, s0, hyst_sim::Input::Sampled(&zeros), fs, n, &opts)
        .expect("free decay");
    // Analytic signal.
    let spec = crate::fft::rfft(&x);
    let m = x.len();
    let mut full = vec![crate::fft::C::new(0.0, 0.0); m];
    for (b, v) in spec.iter().enumerate() {
        let w = if b == 0 || (m % 2 == 0 && b == m / 2) {
            1.0
        } else {
            2.0
        };
        full[b] = v * w;
    }
    let mut p = rustfft_inverse(&full);
    p.iter_mut().for_each(|v| *v /= m as f64);
    let env: Vec<f64> = p.iter().map(|c| c.norm()).collect();
    let ph: Vec<f64> = p.iter().map(|c| c.arg()).collect();
    let mut out = Vec::new();
    // One cycle of the mode (about 36 Hz) per estimate.
    let step = (fs / 36.0) as usize;
    let mut i = step;
    while i + 2 * step < m / 2 {
        let j = i + step;
        let mut dphi = 0.0;
        for k in i..j {
            let mut d = ph[k + 1] - ph[k];
            while d <= -std::f64::consts::PI {
                d += 2.0 * std::f64::consts::PI;
            }
            while d > std::f64::consts::PI {
                d -= 2.0 * std::f64::consts::PI;
            }
            dphi += d;
        }
        let wd = dphi * fs / (j - i) as f64;
        let sigma = (env[i] / env[j]).ln() * fs / (j - i) as f64;
        let wn = wd.hypot(sigma);
        out.push((
            (env[i] * env[j]).sqrt(),
            wn / (2.0 * std::f64::consts::PI),
            sigma / wn,
        ));
        i = j;
    }
    out
}

fn rustfft_inverse(x: &[crate::fft::C]) -> Vec<crate::fft::C> {
    // A plain O(n²)-free route: the inverse DFT through realfft is for real outputs, so the
    // analytic signal's inverse is taken as two real inverses (its real and imaginary parts).
    let n = x.len();
    let half = n / 2 + 1;
    // Real part: inverse of the Hermitian part; imaginary: of the anti-Hermitian part / i.
    let mut re = vec![crate::fft::C::new(0.0, 0.0); half];
    let mut im = vec![crate::fft::C::new(0.0, 0.0); half];
    for b in 0..half {
        let a = x[b];
        let c = x[(n - b) % n].conj();
        re[b] = (a + c) * 0.5;
        im[b] = (a - c) * crate::fft::C::new(0.0, -0.5);
    }
    let r = crate::fft::irfft(&re, n);
    let i = crate::fft::irfft(&im, n);
    r.iter()
        .zip(&i)
        .map(|(a, b)| crate::fft::C::new(*a, *b) * n as f64)
        .collect()
}

/// The linearity test's power on the benchmark's Bouc-Wen oscillator (50 N white force),
/// by record length, over 20 fresh seeds each (docs/amplitude.md).
#[test]
#[ignore = "a study for the documentation"]
fn study_power() {
    let fs = 750.0;
    let bw = BoucWen::benchmark();
    let model = Oscillator::bouc_wen(2.0, 10.0, 5e4, bw);
    for (bits, seeds) in [(16, 5000..5020u64), (17, 5100..5120), (18, 5200..5220)] {
        let (mut nonlinear, mut f_up, mut z_up) = (0, 0, 0);
        for seed in seeds {
            let l = bouc_wen_linearity(&model, bits, seed);
            nonlinear += usize::from(!l.linear);
            f_up += usize::from(l.frequency.change > 0.0);
            z_up += usize::from(l.damping.change > 0.0);
        }
        println!(
            "| {:.0} s | {nonlinear}/20 | {f_up}/20 | {z_up}/20 |",
            (1u64 << bits) as f64 / fs
        );
    }
}

/// What is printed as a point is a mode's estimate, as covssi's decision takes one: on a
/// record with no mode near the one asked for (white noise, a "mode" at 59.6 Hz at 30 %,
/// issue 57's low-pass edge), every point kept has its frequency known to 5 % and a damping
/// ratio within 20 %, and each one left out is said; and a mode listed twice still gets a
/// band around it (it was 11.080–11.080 Hz, empty).
#[test]
fn points_are_modes_estimates_and_bands_are_never_empty() {
    use rand::{SeedableRng, rngs::StdRng};
    use rand_distr::{Distribution, StandardNormal};
    let fs = 200.0;
    let mut rng = StdRng::seed_from_u64(5_900_001);
    let y: Vec<f64> = (0..100_000)
        .map(|_| StandardNormal.sample(&mut rng))
        .collect();
    let edge = ModeToFollow {
        frequency_hz: 59.6,
        damping_ratio: 0.297,
        shape: None,
    };
    let r = amplitude_curves(
        &[&y],
        fs,
        std::slice::from_ref(&edge),
        std::slice::from_ref(&edge),
        &AmplitudeOptions::default(),
    )
    .unwrap();
    let curve = &r.modes[0];
    // The band: ±2ζ at least around the mode, though another is listed at its frequency.
    assert!(
        curve.band_hz.1 - curve.band_hz.0 > 0.5 * 59.6,
        "{:?}",
        curve.band_hz
    );
    let criteria = covssi::decision::ModeCriteria::default();
    for p in &curve.points {
        assert!(
            p.frequency_se_hz <= criteria.max_frequency_cv * p.frequency_hz
                && p.damping_ratio <= criteria.max_damping_ratio,
            "{p:?}"
        );
    }
    let left_out = curve
        .notes
        .iter()
        .filter(|n| n.contains("not a mode's estimate"))
        .count();
    // White noise through the band: fits of 3 cycles wander by more than 5 % (they were
    // printed as 36.30 ± 117.99 Hz); the rule, not luck, keeps them out.
    assert!(left_out >= 1, "{:?}", curve.notes);
}

/// The analysis judges its points by the criteria its modes were decided by (a user's
/// `--max-damping`), not by the defaults: a linear mode of 1.1 % damping keeps its points
/// under the default 20 % limit and loses each, said with the limit, under a 0.5 % one.
#[test]
fn points_are_judged_by_the_analysis_criteria() {
    let fs = 750.0;
    let lin = Oscillator::linear(2.0, 10.0, 1e5);
    let y = record(&lin, 50.0, 1 << 15, fs, 5_900_002);
    let run = |max_damping: f64| {
        let mut analysis = covssi::AnalysisOptions::default();
        analysis.modes.max_damping_ratio = max_damping;
        amplitude_analysis(&[&y], fs, &analysis, &AmplitudeOptions::default(), &[35.6])
            .expect("analysis")
    };
    let default = run(covssi::ModeCriteria::default().max_damping_ratio);
    assert!(!default.curves.modes[0].points.is_empty(), "{default:?}");
    let strict = run(0.005);
    let curve = &strict.curves.modes[0];
    assert!(curve.points.is_empty(), "{:?}", curve.points);
    assert!(
        curve.notes.iter().any(|n| n.contains("above 0.005")),
        "{:?}",
        curve.notes
    );
}

/// Options beyond what the record holds are refused before anything is allocated by them
/// (issue 58: `--levels 1000000000` aborted after 7.9 GB): levels, groups, and the cycles of
/// a mode so slow its signature outgrows the record, each named with the most it may be.
#[test]
fn options_beyond_the_record_are_refused_before_work() {
    let y = vec![0.5f64; 10_000];
    let slow = ModeToFollow {
        frequency_hz: 1e-6,
        ..benchmark_mode(10.0)
    };
    for (opts, mode, says) in [
        (
            AmplitudeOptions {
                levels: 1_000_000_000,
                ..AmplitudeOptions::default()
            },
            benchmark_mode(10.0),
            "levels = 1000000000 asks more than the record's 10000 samples hold: at most 10000",
        ),
        (
            AmplitudeOptions {
                groups: 1_000_000_000,
                ..AmplitudeOptions::default()
            },
            benchmark_mode(10.0),
            "groups = 1000000000 asks more",
        ),
        (
            AmplitudeOptions::default(),
            slow,
            "cycles = 3 asks more than the record's 10000 samples hold",
        ),
    ] {
        let e = amplitude_curves(&[&y], 100.0, std::slice::from_ref(&mode), &[], &opts)
            .unwrap_err()
            .to_string();
        assert!(e.contains(says), "{e}");
    }
}
