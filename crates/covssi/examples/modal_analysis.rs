//! Operational modal analysis of a simulated record with covssi, beside the truth.
//!
//! Four sensors on a structure with three modes (one of them weak in every sensor), excited by
//! white noise, with 5 % sensor noise: SSI-COV finds the modes and the maximum-likelihood
//! refinement sharpens them and gives each a standard error.
//!
//! ```sh
//! cargo run --release -p covssi --example modal_analysis -- [diagram.svg] [seed]
//! ```

use covssi::synth::ModalRecord;
use covssi::{BlockRows, RefineOptions, SsiOptions, identify, refine};

/// Natural frequency (Hz) and damping ratio of each mode.
const MODES: [(f64, f64); 3] = [(1.2, 0.015), (2.9, 0.02), (4.6, 0.03)];
/// How each sensor reads each mode's two state coordinates.
const SHAPES: [[f64; 6]; 4] = [
    [1.0, 0.2, 0.10, 0.02, -0.8, 0.3],
    [0.7, -0.4, -0.12, 0.05, 1.0, -0.2],
    [0.3, 0.9, 0.08, -0.10, 0.6, 0.5],
    [-0.5, 0.1, 0.15, 0.03, -0.4, 0.9],
];
const FS: f64 = 25.0;
const SAMPLES: usize = 65_536;

/// Each mode an exactly sampled oscillator driven by white noise; the sensors read their
/// states, plus white noise of 5 % of each sensor's standard deviation.
fn record(seed: u64) -> Vec<Vec<f64>> {
    ModalRecord::new(FS, &MODES)
        .with_gains(SHAPES.iter().map(|row| row.to_vec()).collect())
        .with_noise(0.05)
        .with_warm_up(0)
        .generate(SAMPLES, seed)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let svg_path = args.next();
    let seed = args.next().map(|s| s.parse()).transpose()?.unwrap_or(1);
    let y = record(seed);
    let channels: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
    let truth = |f_hz: f64| {
        MODES
            .iter()
            .copied()
            .min_by(|a, b| (a.0 - f_hz).abs().total_cmp(&(b.0 - f_hz).abs()))
            .unwrap_or(MODES[0])
    };
    println!(
        "{} sensors, {} samples at {FS} Hz; truth: {}",
        channels.len(),
        SAMPLES,
        MODES
            .iter()
            .map(|(f, z)| format!("{f} Hz at {:.1} %", z * 100.0))
            .collect::<Vec<_>>()
            .join(", ")
    );

    let opts = SsiOptions {
        block_rows: BlockRows::Count(20),
        max_order: Some(40),
        ..SsiOptions::default()
    };
    let t = std::time::Instant::now();
    let ssi = identify(&channels, FS, &opts)?;
    println!(
        "\nSSI-COV ({} block rows, orders up to 40): {} modes in {:.0} ms",
        ssi.block_rows,
        ssi.modes.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    for m in &ssi.modes {
        let (f, z) = truth(m.frequency_hz);
        println!(
            "  {:7.4} ± {:.4} Hz  damping {:.4} ± {:.4}  ({:2} poles)   truth {f} Hz, {z}",
            m.frequency_hz,
            m.frequency_std_hz,
            m.damping_ratio,
            m.damping_std,
            m.members.len()
        );
    }
    for r in &ssi.real_poles {
        println!(
            "  real pole {:.3} rad/s ({} poles)",
            r.lambda,
            r.members.len()
        );
    }

    let t = std::time::Instant::now();
    let refined = refine(&channels, FS, &ssi.modes, &RefineOptions::default())?;
    println!(
        "\nrefined by maximum likelihood ({}) in {:.2} s; misfit {:.4} (limit {})",
        refined.fitted_by(),
        t.elapsed().as_secs_f64(),
        refined.misfit,
        covssi::refine::MISFIT_LIMIT
    );
    for m in &refined.modes {
        let (f, z) = truth(m.frequency_hz);
        let (f_se, z_se) = (
            m.frequency_se_hz.unwrap_or(f64::NAN),
            m.damping_se.unwrap_or(f64::NAN),
        );
        println!(
            "  {:7.4} ± {:.4} Hz  damping {:.4} ± {:.4}   truth {f} Hz, {z}: {:+.1} / {:+.1} standard errors",
            m.frequency_hz,
            f_se,
            m.damping_ratio,
            z_se,
            (m.frequency_hz - f) / f_se,
            (m.damping_ratio - z) / z_se
        );
    }
    for d in &refined.dropped {
        println!(
            "  dropped the SSI mode at {:.4} Hz: evidence {:.1} below the penalty {:.1}",
            d.frequency_hz, d.evidence, refined.penalty
        );
    }

    if let Some(path) = svg_path {
        let title = format!("{} sensors, three modes", channels.len());
        std::fs::write(
            &path,
            covssi::svg::stabilization_svg(&ssi.diagram, Some(8.0), &title),
        )?;
        println!("\nstabilization diagram: {path}");
    }
    Ok(())
}
