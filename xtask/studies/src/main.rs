//! The project's studies, run through `cargo xtask` (which passes every task but `test`,
//! `sizes` and `unused-deps` here): benchmarks, the paper's sweeps, comparisons with other
//! tools, corpora and the documentation's figures. A package of its own so that the task
//! runner builds in seconds and `cargo xtask test` compiles the libraries once, with the tests.
//!
//! - `cargo xtask bench` prints one line per figure, `name value unit`.
//! - `cargo xtask sweep [--levels 10:90:10] [--samples N] [--seed S] [--out DIR]` runs the
//!   paper's Section 5 amplitude study (see `sweep.rs`).
//! - `cargo xtask sweep-random [--levels 10:90:10] [--samples N] [--seed S] [--out DIR]` runs
//!   it under a white force, with c from the Zener spectral fit and from the paper's guess
//!   (see `random_sweep.rs`).
//! - `cargo xtask compare-tools [--seeds N] [--first-seed S] [--timing] [--clusters] [--crb] [--cases NAMES]`
//!   runs covssi beside pyOMA2 and koma (see `compare.rs`).
//! - `cargo xtask loop-battery --seed S [--cases NAMES] [--forces periodic,random] [--out FILE]`
//!   runs the residual loop on records with undeclared effects (see `loop_battery.rs`).
//! - `cargo xtask compare-setups` runs the steel frame's merge and EFDD beside pyOMA2's
//!   (`compare_setups.rs`).
//! - `cargo xtask vendor-js` remakes the HTML reports' bundled libraries from npm, and
//!   `cargo xtask report-screenshots` the documentation's pictures of the reports
//!   (`report_pages.rs`).

mod acquisition;
mod bench_command;
mod bench_refine;
mod bench_setups;
mod bench_storeys;
mod compare;
mod compare_roving;
mod compare_setups;
mod corpus;
mod f16;
mod growth;
mod json_values;
mod loop_battery;
mod monitor;
mod random_sweep;
mod refine_corpus;
mod report_pages;
mod sweep;

use std::time::Instant;

use hyst_model::Oscillator;
use hyst_sim::excitation::{Multisine, white_noise};
use hyst_sim::{Input, SimOptions, simulate};

/// `cargo xtask f16 [--out DIR]`: the F-16's wing modes over its four force levels.
fn f16_cmd(out: Option<&std::path::Path>) {
    let out = out.map_or_else(
        || hyst_testkit::workspace_root().join("target/f16"),
        std::path::Path::to_path_buf,
    );
    let Some(dir) = hyst_testkit::data_dir() else {
        eprintln!(
            "error: no data folder (set HYST_DATA_DIR, or put the shared data in ../shared/data)"
        );
        std::process::exit(1);
    };
    let t0 = Instant::now();
    let rows = match f16::run(&dir) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let table = f16::markdown(&rows);
    print!("{table}");
    let written = std::fs::create_dir_all(&out)
        .and_then(|_| std::fs::write(out.join("f16_levels.md"), &table))
        .map_err(|e| format!("{}: {e}", out.display()))
        .and_then(|_| f16::figures(&rows, &out));
    match written {
        Ok(paths) => {
            for p in paths {
                eprintln!("wrote {}", p.display());
            }
            eprintln!("{:.1} s", t0.elapsed().as_secs_f64());
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}

/// `FROM:TO:STEP` (or one level) in newtons, each > 0.
fn parse_levels(s: &str) -> Result<Levels, String> {
    let bad = || format!("`{s}` is not FROM:TO:STEP (or one level) with levels > 0 N");
    let p: Vec<f64> = s
        .split(':')
        .map(|v| v.trim().parse().ok())
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    let levels = match p.as_slice() {
        [a] => vec![*a],
        [a, b, st] if *st > 0.0 && b >= a => {
            let n = ((b - a) / st + 1e-9).floor() as usize;
            (0..=n).map(|i| a + i as f64 * st).collect()
        }
        _ => return Err(bad()),
    };
    if levels.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(bad());
    }
    Ok(Levels(levels))
}

/// Force levels in newtons.
#[derive(Clone, Debug)]
struct Levels(Vec<f64>);

/// The options of `sweep` and `sweep-random`.
#[derive(clap::Args, Debug)]
struct SweepArgs {
    /// Force levels (N RMS), FROM:TO:STEP or one level. Default 10:90:10.
    #[arg(long, value_parser = parse_levels)]
    levels: Option<Levels>,
    /// Samples per record (at least 8192); default 2^20 for `sweep`, 2^17 for `sweep-random`.
    #[arg(long, value_parser = clap::value_parser!(u64).range(8192..))]
    samples: Option<u64>,
    /// Seed of the first level's records.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Folder for the tables and figures; default target/sweep or target/sweep-random.
    #[arg(long)]
    out: Option<std::path::PathBuf>,
}

/// The sweep's options from its arguments, with the study's defaults.
fn sweep_options(args: &SweepArgs, samples: usize, out: &str) -> sweep::SweepOptions {
    sweep::SweepOptions {
        levels: args
            .levels
            .clone()
            .map_or_else(|| (1..=9).map(|i| 10.0 * i as f64).collect(), |l| l.0),
        samples: args.samples.map_or(samples, |n| n as usize),
        seed: args.seed,
        out: args
            .out
            .clone()
            .unwrap_or_else(|| hyst_testkit::workspace_root().join(out)),
        progress: true,
    }
}

/// A sweep's study: run the levels, write the tables and figures, and the tables as Markdown.
struct Study<T> {
    run: fn(&sweep::SweepOptions) -> sweep::Outcome<T>,
    write: fn(&std::path::Path, &[T], f64, usize) -> Result<(), String>,
    markdown: fn(&[T], f64, usize) -> String,
}

/// Run `study` with the options `args` gives (defaults: `samples`, the folder `out`), print
/// its tables and the wall time as `{name}_seconds`; exit 1 with the message on failure.
fn sweep_cmd<T>(args: &SweepArgs, samples: usize, out: &str, name: &str, study: Study<T>) {
    let opts = sweep_options(args, samples, out);
    let done = (study.run)(&opts).and_then(|(results, secs)| {
        (study.write)(&opts.out, &results, secs, opts.samples).map(|()| (results, secs))
    });
    match done {
        Ok((results, secs)) => {
            print!("{}", (study.markdown)(&results, secs, opts.samples));
            println!("\nwritten to {}", opts.out.display());
            println!("{name}_seconds {secs:.2} s");
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}

/// Best of `reps` wall times of `f`, in seconds.
fn best_of<T>(reps: usize, mut f: impl FnMut() -> T) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn bench() {
    let n = 1usize << 20;
    let fs = 750.0;
    let opts = SimOptions::default();
    let steps = ((n - 1) * opts.oversample) as f64;
    let model = Oscillator::benchmark();

    let u = white_noise(n, 50.0, 1).expect("valid rms");
    let t = best_of(3, || {
        simulate(&model, Input::Sampled(&u), fs, n, &opts).expect("stable")
    });
    println!("rk4_ns_per_step {:.2} ns", t / steps * 1e9);

    let period = Multisine::benchmark(50.0)
        .generate(1)
        .expect("valid multisine");
    let t = best_of(3, || {
        simulate(&model, Input::Periodic(&period), fs, n, &opts).expect("stable")
    });
    println!("rk4_ns_per_step_periodic_input {:.2} ns", t / steps * 1e9);
    c_reference();
}

/// Build and run `bench/rk4_reference.c` (a plain hand-written RK4 loop of the same
/// oscillator and sizes) with the system's C compiler, so that the Rust loop is compared with
/// C under the same machine load; says so when there is no C compiler.
fn c_reference() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/rk4_reference.c");
    let exe = std::env::temp_dir().join(format!("hyst-rk4-reference-{}", std::process::id()));
    let built = std::process::Command::new("cc")
        .args(["-O3", "-march=native", "-ffp-contract=fast", "-o"])
        .arg(&exe)
        .arg(&src)
        .arg("-lm")
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    let out = built
        .then(|| std::process::Command::new(&exe).output().ok())
        .flatten()
        .and_then(|o| String::from_utf8(o.stdout).ok());
    let _ = std::fs::remove_file(&exe);
    match out.as_deref().and_then(|s| s.split_whitespace().next()) {
        Some(ns) => println!("c_reference_rk4_ns_per_step {ns} ns"),
        None => println!("c_reference_rk4_ns_per_step unavailable (no working `cc`)"),
    }
}

/// The modes of [`linear_record`]: frequency (Hz) and damping ratio. Each is sampled exactly
/// (the discrete pole is e^{λ dt}), so these are the continuous-time truth.
const BENCH_MODES: [(f64, f64); 8] = [
    (1.1, 0.01),
    (2.7, 0.02),
    (4.4, 0.02),
    (6.8, 0.03),
    (9.3, 0.04),
    (12.1, 0.03),
    (15.2, 0.035),
    (18.6, 0.04),
];

/// Response of a linear system of up to 8 modes (1.1–18.6 Hz, 1–4 % damping) at 50 Hz to white
/// noise ([`covssi::synth::ModalRecord`]), seen through `channels` channels with 5 % white
/// measurement noise; only the lowest `modes` modes respond.
fn linear_record(n: usize, channels: usize, modes: usize, seed: u64) -> Vec<Vec<f64>> {
    let modes = &BENCH_MODES[..modes.min(BENCH_MODES.len())];
    covssi::synth::ModalRecord::new(50.0, modes)
        .with_gains(dense_gains(channels, modes.len(), 0.0))
        .with_noise(0.05)
        .generate(n, seed)
}

/// Fixed, dense gains of `channels` channels reading `modes` modes' two states each:
/// sin(0.7 i + `phase`) for the i-th gain in row order, so every channel sees every state.
fn dense_gains(channels: usize, modes: usize, phase: f64) -> Vec<Vec<f64>> {
    (0..channels)
        .map(|ch| {
            (0..2 * modes)
                .map(|j| (((ch * 2 * modes + j) as f64) * 0.7 + phase).sin())
                .collect()
        })
        .collect()
}

fn bench_covssi() {
    use hyst::covssi::{BlockRows, SsiOptions, identify};
    let n = 1_000_000;
    let all_modes = 5;
    let all = linear_record(n, 10, all_modes, 7);
    for (name, ch, br, order) in [
        ("covssi_ms_1e6_1ch", 1usize, 20usize, 40usize),
        ("covssi_ms_1e6_3ch", 3, 20, 40),
        ("covssi_ms_1e6_10ch", 10, 20, 40),
        ("covssi_ms_1e6_10ch_50br", 10, 50, 100),
    ] {
        let views: Vec<&[f64]> = all[..ch].iter().map(|c| c.as_slice()).collect();
        let opts = SsiOptions {
            block_rows: BlockRows::Count(br),
            max_order: Some(order.min(ch * br)),
            ..SsiOptions::default()
        };
        let t = best_of(3, || identify(&views, 50.0, &opts).expect("identifiable"));
        println!("{name} {:.1} ms", t * 1e3);
        let refs: Vec<usize> = (0..ch).collect();
        let tc = best_of(3, || hyst::covssi::corr::estimate(&views, &refs, 2 * br));
        let tf = best_of(3, || hyst::covssi::corr::fft(&views, &refs, 2 * br));
        let td = best_of(1, || hyst::covssi::corr::direct(&views, &refs, 2 * br));
        println!(
            "{name}_correlation_only {:.1} ms (fft {:.1}, direct {:.1})",
            tc * 1e3,
            tf * 1e3,
            td * 1e3
        );
    }
    // The floor: reading the 10-channel record once (a sum over every sample).
    let t = best_of(5, || all.iter().map(|c| c.iter().sum::<f64>()).sum::<f64>());
    println!("read_record_ms_1e6_10ch {:.2} ms", t * 1e3);
    bench_covssi_refine(&all, all_modes);
    bench_real_poles();
}

/// The maximum-likelihood refinement of the SSI modes on records of the OMA files' length
/// and on the long one `all` (of `all_modes` modes), each line with its calibration.
fn bench_covssi_refine(all: &[Vec<f64>], all_modes: usize) {
    use hyst::covssi::{BlockRows, SsiOptions, identify};
    let n = all[0].len();
    // Three modes in ten channels: the joint fit through four combinations of them (the
    // five-mode record's ten channels are fitted band by band).
    let three_modes = 3;
    let three = linear_record(65536, 10, three_modes, 7);
    // Sixteen channels reading eight modes: the per-channel selection's cost grows with both.
    let large_modes = 8;
    let large = linear_record(131_072, 16, large_modes, 7);
    // Each line: name, record, its modes, samples, channels, SSI block rows, runs (the best
    // counts). One channel needs 40 block rows (correlations up to 1.6 s) for SSI to find
    // the five modes; with 20 (0.8 s) it hands over three and the refined model does not
    // hold.
    let lines = [
        (
            "covssi_refine_ms_65536_1ch",
            all,
            all_modes,
            65536usize,
            1usize,
            40usize,
            2usize,
        ),
        (
            "covssi_refine_ms_65536_3ch",
            all,
            all_modes,
            65536,
            3,
            20,
            2,
        ),
        (
            "covssi_refine_ms_65536_10ch",
            all,
            all_modes,
            65536,
            10,
            20,
            2,
        ),
        (
            "covssi_refine_ms_65536_10ch_3modes",
            &three[..],
            three_modes,
            65536,
            10,
            20,
            2,
        ),
        ("covssi_refine_ms_1e6_1ch", all, all_modes, n, 1, 40, 2),
        (
            "covssi_refine_ms_131072_16ch_8modes",
            &large[..],
            large_modes,
            131072,
            16,
            20,
            1,
        ),
    ];
    for (name, rec, modes, len, ch, block_rows, runs) in lines {
        let views: Vec<&[f64]> = rec[..ch].iter().map(|c| &c[..len]).collect();
        let opts = SsiOptions {
            block_rows: BlockRows::Count(block_rows),
            max_order: Some(40.min(block_rows * ch)),
            ..SsiOptions::default()
        };
        let res = identify(&views, 50.0, &opts).expect("identifiable");
        let ro = hyst::covssi::RefineOptions::default();
        let mut t = f64::INFINITY;
        let mut r = None;
        for _ in 0..runs {
            let start = Instant::now();
            r = Some(hyst::covssi::refine(&views, 50.0, &res.modes, &ro).expect("refines"));
            t = t.min(start.elapsed().as_secs_f64());
        }
        let r = r.expect("at least one run");
        println!(
            "{name} {:.0} ms ({} SSI modes in, {} kept{}; misfit {:.3}; {})",
            t * 1e3,
            res.modes.len(),
            r.modes.len(),
            if r.joint {
                format!(", {}", r.fitted_by())
            } else {
                String::new()
            },
            r.misfit,
            calibration(&r, modes)
        );
    }
}

/// The refined estimates against the generator's first `modes` modes, in standard errors:
/// their RMS is near 1 when the standard errors are right.
fn calibration(r: &hyst::covssi::Refinement, modes: usize) -> String {
    let z: Vec<f64> = r
        .modes
        .iter()
        .flat_map(|m| {
            let &(f, zeta) = BENCH_MODES[..modes]
                .iter()
                .min_by(|a, b| {
                    (a.0 - m.frequency_hz)
                        .abs()
                        .total_cmp(&(b.0 - m.frequency_hz).abs())
                })
                .expect("records have modes");
            [
                m.frequency_se_hz.map(|se| (m.frequency_hz - f) / se),
                m.damping_se.map(|se| (m.damping_ratio - zeta) / se),
            ]
        })
        .flatten()
        .collect();
    if z.is_empty() {
        "no standard errors".to_string()
    } else {
        let z_rms = (z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64).sqrt();
        let z_max = z.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        format!(
            "z-score RMS {z_rms:.2}, largest |z| {z_max:.1}, over {} estimates",
            z.len()
        )
    }
}

/// The refinement with real poles on ten records of the Zener oscillator the pipeline
/// identifies on the benchmark (m = 2, c = 11.70, k = 46899, k∞ = 81432, Ω = 61.72), as in
/// `crates/hyst-ident/tests/integration/zener_real_pole.rs`: 2¹⁵ samples at 750 Hz under white noise, 5 % measurement
/// noise, SSI with 60 block rows. Each record is refined once by `refine_with_real_poles` and
/// once by `refine`; the line gives the median and range of their times and the kept real
/// pole's RMS error against the model's exact one, beside SSI's (its largest real cluster).
fn bench_real_poles() {
    use hyst::covssi::{self, BlockRows, RefineOptions, SsiOptions};
    use hyst_model::{Restoring, ZenerParams};
    let fs = 750.0;
    let mut model = Oscillator::linear(2.0, 11.70, 46899.0);
    model.restoring = Restoring::Zener(ZenerParams {
        k_inf: 81432.0,
        omega: 61.72,
    });
    let exact = model
        .poles()
        .expect("a linear model")
        .iter()
        .find(|p| p.im == 0.0)
        .expect("a real pole")
        .re;
    let opts = SsiOptions {
        block_rows: BlockRows::Count(60),
        ..SsiOptions::default()
    };
    let ro = RefineOptions::default();
    let (n, warm) = (1usize << 15, 8192);
    let (mut with, mut without, mut err, mut ssi_err) = (vec![], vec![], vec![], vec![]);
    // Records where `refine` alone kept a mode damped above 0.9 (in the real pole's place).
    let mut near_critical = 0;
    for seed in 0..10 {
        let u = white_noise(n + warm, 50.0, seed).expect("valid rms");
        let mut y = simulate(
            &model,
            Input::Sampled(&u),
            fs,
            n + warm,
            &SimOptions::default(),
        )
        .expect("stable")
        .split_off(warm);
        let sd = (y.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        hyst_sim::excitation::add_noise(&mut y, 0.05 * sd, 1000 + seed).expect("valid noise");
        let res = covssi::identify(&[&y], fs, &opts).expect("identifiable");
        let start = Instant::now();
        let r = covssi::refine_with_real_poles(&[&y], fs, &res.modes, &res.real_poles, &ro)
            .expect("refines");
        with.push(start.elapsed().as_secs_f64());
        let start = Instant::now();
        let plain = covssi::refine(&[&y], fs, &res.modes, &ro).expect("refines");
        without.push(start.elapsed().as_secs_f64());
        near_critical += usize::from(plain.modes.iter().any(|m| m.damping_ratio > 0.9));
        err.extend(r.real_poles.first().map(|p| p.lambda - exact));
        ssi_err.extend(
            res.real_poles
                .iter()
                .max_by_key(|p| p.members.len())
                .map(|p| p.lambda - exact),
        );
    }
    let spread = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let median = 0.5 * (v[4] + v[5]);
        (median * 1e3, v[0] * 1e3, v[9] * 1e3)
    };
    let rms = |v: &[f64]| (v.iter().map(|e| e * e).sum::<f64>() / v.len() as f64).sqrt();
    let (a, b) = (spread(&mut with), spread(&mut without));
    println!(
        "covssi_refine_real_poles_ms_32768_1ch {:.0} ms median ({:.0}-{:.0} over 10 Zener records; refine alone {:.0} ms, {:.0}-{:.0}, a mode damped above 0.9 kept on {near_critical}; real pole found on {} records, RMS error {:.2} rad/s, SSI's {:.2})",
        a.0,
        a.1,
        a.2,
        b.0,
        b.1,
        b.2,
        err.len(),
        rms(&err),
        rms(&ssi_err)
    );
}

/// `hyst ident`'s identification step on its built-in record (the benchmark at 50 N, four
/// multisine periods, noise 7.4e-6 m): steps 1-4, output only; then step 4b, the flatness fit
/// from both starts.
fn bench_ident() {
    let period = Multisine::benchmark(50.0)
        .generate(11)
        .expect("valid multisine");
    let n = period.len();
    let model = Oscillator::benchmark();
    let mut y = simulate(
        &model,
        Input::Periodic(&period),
        750.0,
        5 * n,
        &SimOptions::default(),
    )
    .expect("stable")
    .split_off(n);
    hyst_sim::excitation::add_noise(&mut y, 7.4e-6, 12).expect("valid noise");
    let opts = hyst_ident::IdentOptions::default();
    let t = best_of(5, || {
        hyst_ident::identify(&y, 750.0, &opts).expect("identifiable")
    });
    println!("ident_ms_default_record {:.1} ms", t * 1e3);
    let id = hyst_ident::identify(&y, 750.0, &opts).expect("identifiable");
    let band = hyst_ident::flatness::ExcitationBand::benchmark();
    let t = best_of(5, || {
        hyst_ident::fit_flatness(&y, 750.0, &id.models, &band).expect("fits")
    });
    println!("ident_flatness_ms_default_record {:.1} ms", t * 1e3);

    // Under a white force (one steady-state period of 2^17 samples at 50 N, the benchmark's
    // noise) the pipeline refines the poles and fits the Zener spectrum (step 3b): the whole
    // pipeline with c from the fit and with the paper's guess, and step 3b alone from the
    // refined poles.
    let u = white_noise(1 << 17, 50.0, 21).expect("valid rms");
    let mut y =
        hyst_sim::steady_state_period(&model, &u, 750.0, &SimOptions::default(), 1e-10, 200)
            .expect("stable")
            .y;
    hyst_sim::excitation::add_noise(&mut y, 7.4e-6, 22).expect("valid noise");
    let t = best_of(3, || {
        hyst_ident::identify(&y, 750.0, &opts).expect("identifiable")
    });
    println!("ident_ms_white_record_2e17 {:.1} ms", t * 1e3);
    let guess = hyst_ident::IdentOptions {
        damping_guess: hyst_ident::DampingGuess::LowDampingCluster,
        ..opts.clone()
    };
    let t = best_of(3, || {
        hyst_ident::identify(&y, 750.0, &guess).expect("identifiable")
    });
    println!("ident_ms_white_record_2e17_paper_guess {:.1} ms", t * 1e3);
    let id = hyst_ident::identify(&y, 750.0, &guess).expect("identifiable");
    let t = best_of(3, || {
        let mut poles = id.poles.clone();
        hyst_ident::fit_zener_spectrum(&y, 750.0, &id.prepared, &mut poles, &opts).expect("fits")
    });
    println!("ident_zener_spectrum_ms_2e17 {:.1} ms", t * 1e3);
}

/// `hyst amplitude`'s analysis on a ten-channel, ten-minute record at 100 Hz (the five-mode
/// record of `bench command`, 60 000 samples): SSI and its refinement, then every reported
/// mode's amplitude curves (the target: under 10 s on this machine), and the curves alone.
fn bench_amplitude() {
    use hyst_ident::amplitude::{
        AmplitudeOptions, ModeToFollow, amplitude_analysis, amplitude_curves,
    };
    let y = bench_command::record(60_000, 77);
    let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
    let analysis = covssi::AnalysisOptions::default();
    let opts = AmplitudeOptions::default();
    let mut modes = 0;
    let t = best_of(2, || {
        let r =
            amplitude_analysis(&views, bench_command::FS, &analysis, &opts, &[]).expect("curves");
        modes = r.curves.modes.len();
        r
    });
    println!("amplitude_10ch_10min_100hz_s {t:.2} s ({modes} modes)");
    let follow: Vec<ModeToFollow> = bench_command::MODES
        .iter()
        .map(|&(f, z)| ModeToFollow {
            frequency_hz: f,
            damping_ratio: z,
            shape: None,
        })
        .collect();
    let t = best_of(2, || {
        amplitude_curves(&views, bench_command::FS, &follow, &[], &opts).expect("curves")
    });
    println!("amplitude_curves_only_10ch_10min_5modes_s {t:.2} s");
}

/// How often `hyst ssi`'s progress moves: the longest time between two progress reports of
/// `covssi::analyze_with_progress` (defaults), on the ten-channel 10⁶-sample record of `bench
/// command` and on the steel frame's first setup (five channels at 256 Hz) when the shared
/// data is there.
fn bench_progress() {
    let longest_gap = |views: &[&[f64]], fs: f64| -> (f64, f64) {
        let t0 = Instant::now();
        let last = std::sync::Mutex::new((0.0f64, 0.0f64));
        covssi::analyze_with_progress(views, fs, &covssi::AnalysisOptions::default(), &|_| {
            let now = t0.elapsed().as_secs_f64();
            if let Ok(mut l) = last.lock() {
                *l = (now, l.1.max(now - l.0));
            }
        })
        .expect("analysed");
        let end = t0.elapsed().as_secs_f64();
        let (at, gap) = last.into_inner().expect("lock");
        (gap.max(end - at), end)
    };
    let y = bench_command::record(bench_command::SAMPLES, 5);
    let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
    let (gap, total) = longest_gap(&views, bench_command::FS);
    println!("ssi_progress_longest_gap_s_10ch_1e6 {gap:.2} s (of {total:.2} s)");
    let Some(dir) = hyst_testkit::data_dir() else {
        println!("ssi_progress_longest_gap_s_steelframe skipped: no shared data");
        return;
    };
    let path = dir.join("steelframe/measurement_1/measurement_1.npy");
    match hyst::io::read_npy(&path) {
        Ok(t) => {
            let cols: Vec<&[f64]> = (0..5)
                .filter_map(|c| t.column(&c.to_string()).ok())
                .collect();
            let (gap, total) = longest_gap(&cols, 256.0);
            println!("ssi_progress_longest_gap_s_steelframe_1 {gap:.2} s (of {total:.2} s)");
        }
        Err(e) => println!("ssi_progress_longest_gap_s_steelframe skipped: {e}"),
    }
}

/// `cargo xtask bench growth` (`growth.rs`).
fn bench_growth() {
    or_exit(growth::run());
}

/// `cargo xtask bench command` (`bench_command.rs`).
fn bench_command() {
    or_exit(bench_command::run());
}

/// A task's error printed, and the process ended with status 1.
fn or_exit(result: Result<(), String>) {
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// Project tasks: benches, studies, comparisons.
#[derive(clap::Parser)]
#[command(name = "cargo xtask", bin_name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

/// A group of `cargo xtask bench`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum BenchGroup {
    Rk4,
    Covssi,
    Ident,
    Refine,
    /// The whole `hyst ssi` command on a 10-channel 10⁶-sample record, beside pyOMA2 and koma.
    Command,
    /// covssi's cost against the record's length, channels and modes, with figures.
    Growth,
    /// Monitoring's throughput: 1-hour 10-channel records at 100 Hz identified per minute.
    Monitor,
    /// `hyst amplitude` on a 10-channel 10-minute record at 100 Hz.
    Amplitude,
    /// The longest time between two of SSI's progress reports.
    Progress,
    /// The storey fit of a three-storey chain from three levels (`bench_storeys.rs`).
    Storeys,
    /// `hyst ssi --setups` on the steel frame's 15 setups beside pyOMA2's PoSER
    /// (`bench_setups.rs`).
    Setups,
}

#[derive(clap::Subcommand)]
enum Task {
    /// One `name value unit` line per figure: all groups, or those named.
    Bench {
        #[arg(value_enum)]
        groups: Vec<BenchGroup>,
    },
    /// The paper's Section 5 amplitude study (`sweep.rs`).
    Sweep(SweepArgs),
    /// The amplitude study under a white force (`random_sweep.rs`).
    SweepRandom(SweepArgs),
    /// The F-16's wing modes over its four force levels (`f16.rs`).
    F16 {
        /// Folder for the table and figures; default target/f16.
        #[arg(long)]
        out: Option<std::path::PathBuf>,
    },
    /// covssi beside pyOMA2 and koma; the arguments go to xtask/studies/compare/oma_tools.py
    /// (`--seeds N`, `--first-seed S`, `--timing`, `--clusters`, `--covssi-only`, `--crb`,
    /// `--cases NAMES`).
    CompareTools {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// The residual loop on records with undeclared effects (`loop_battery.rs`).
    LoopBattery(loop_battery::BatteryArgs),
    /// Issue 33's synthetic monitoring campaign, identified and tracked (`monitor.rs`).
    MonitorDemo(monitor::DemoArgs),
    /// The modal analysis's defaults over the corpus of realistic building records
    /// (`corpus.rs`): true modes found, modes reported that are not structural, z-scores.
    Corpus(corpus::CorpusArgs),
    /// Where the refinement holds on the corpus and what it gains there over SSI's answer
    /// on the same records, with the time it costs (`refine_corpus.rs`).
    RefineCorpus(refine_corpus::RefineCorpusArgs),
    /// hyst's multi-setup merge and EFDD beside pyOMA2's PoSER, PreGER, FDD and EFDD on the
    /// same files (`compare_setups.rs`).
    CompareSetups,
    /// Remake the HTML reports' bundled uPlot and three.js from npm (`report_pages.rs`).
    VendorJs,
    /// The documentation's screenshots of the HTML reports, taken in headless Chromium
    /// (`report_pages.rs`).
    ReportScreenshots,
}

fn main() {
    use clap::Parser;
    match Cli::parse().task {
        Task::Bench { groups } => {
            let all: [(BenchGroup, fn()); 11] = [
                (BenchGroup::Rk4, bench),
                (BenchGroup::Covssi, bench_covssi),
                (BenchGroup::Ident, bench_ident),
                (BenchGroup::Refine, bench_refine::run),
                (BenchGroup::Command, bench_command),
                (BenchGroup::Growth, bench_growth),
                (BenchGroup::Monitor, monitor::bench),
                (BenchGroup::Amplitude, bench_amplitude),
                (BenchGroup::Progress, bench_progress),
                (BenchGroup::Storeys, bench_storeys::run),
                (BenchGroup::Setups, || or_exit(bench_setups::run())),
            ];
            for (group, run) in all {
                if groups.is_empty() || groups.contains(&group) {
                    run();
                }
            }
        }
        Task::Sweep(a) => sweep_cmd(
            &a,
            1 << 20,
            "target/sweep",
            "sweep",
            Study {
                run: sweep::run,
                write: sweep::write,
                markdown: sweep::markdown,
            },
        ),
        Task::SweepRandom(a) => sweep_cmd(
            &a,
            1 << 17,
            "target/sweep-random",
            "sweep_random",
            Study {
                run: random_sweep::run,
                write: random_sweep::write,
                markdown: random_sweep::markdown,
            },
        ),
        Task::F16 { out } => f16_cmd(out.as_deref()),
        Task::LoopBattery(a) => or_exit(loop_battery::run(&a)),
        Task::MonitorDemo(a) => or_exit(monitor::run(&a)),
        Task::Corpus(a) => or_exit(corpus::run(&a)),
        Task::RefineCorpus(a) => or_exit(refine_corpus::run(&a)),
        Task::VendorJs => or_exit(report_pages::vendor_js()),
        Task::CompareSetups => or_exit(compare_setups::run()),
        Task::ReportScreenshots => or_exit(report_pages::screenshots()),
        Task::CompareTools { args } => or_exit(compare::run(&args)),
    }
}
