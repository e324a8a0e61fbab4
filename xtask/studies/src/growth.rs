//! `cargo xtask bench growth`: how covssi's cost grows with the record's length, its channels
//! and its modes, as bench lines and as three figures under `docs/figures/covssi_growth/`.
//!
//! Each point is one record of the bench's linear system (`linear_record`: up to eight modes
//! 1.1–18.6 Hz at 50 Hz, dense gains, 5 % measurement noise), identified by SSI (20 block rows,
//! 40 for one channel; orders up to 40) and refined (`covssi::refine_with_real_poles`, as
//! `hyst ssi` does), each timed twice, the better kept. The three sweeps hold the other two at 10 channels,
//! 5 modes and 2¹⁷ samples.

use std::path::Path;
use std::time::Instant;

use hyst::plot::{Series, chart, chart_log_y, colors};

/// One point's times (ms) and what the refinement did.
struct Point {
    ssi_ms: f64,
    refine_ms: f64,
    kept: usize,
    fitted: String,
}

/// SSI and the refinement of the first `samples` samples of `rec`'s first `channels`
/// channels, the better of two runs of each.
fn measure(rec: &[Vec<f64>], samples: usize, channels: usize) -> Result<Point, String> {
    let (a, b) = (once(rec, samples, channels)?, once(rec, samples, channels)?);
    Ok(Point {
        ssi_ms: a.ssi_ms.min(b.ssi_ms),
        refine_ms: a.refine_ms.min(b.refine_ms),
        ..a
    })
}

/// One run of SSI and the refinement, as [`measure`].
fn once(rec: &[Vec<f64>], samples: usize, channels: usize) -> Result<Point, String> {
    use covssi::{BlockRows, RefineOptions, SsiOptions, identify, refine_with_real_poles};
    let views: Vec<&[f64]> = rec[..channels].iter().map(|c| &c[..samples]).collect();
    let block_rows = if channels == 1 { 40 } else { 20 };
    let opts = SsiOptions {
        block_rows: BlockRows::Count(block_rows),
        max_order: Some(40.min(block_rows * channels)),
        ..SsiOptions::default()
    };
    let t = Instant::now();
    let ssi = identify(&views, 50.0, &opts).map_err(|e| e.to_string())?;
    let ssi_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let r = refine_with_real_poles(
        &views,
        50.0,
        &ssi.modes,
        &ssi.real_poles,
        &RefineOptions::default(),
    )
    .map_err(|e| e.to_string())?;
    Ok(Point {
        ssi_ms,
        refine_ms: t.elapsed().as_secs_f64() * 1e3,
        kept: r.modes.len(),
        fitted: r.fitted_by(),
    })
}

/// The two curves (SSI, refinement) of a sweep's points against `x`.
fn series(points: &[(f64, Point)]) -> Vec<Series> {
    let curve = |name: &str, f: fn(&Point) -> f64, color| {
        let data = points.iter().map(|(x, p)| (*x, f(p))).collect();
        (name.to_string(), data, color)
    };
    vec![
        curve("SSI", |p| p.ssi_ms, colors::BLUE),
        curve("refinement", |p| p.refine_ms, colors::RED),
    ]
}

/// A sweep: its name in the bench lines, what it varies and holds fixed, its x axis, and
/// whether the time is drawn on a log axis.
struct Sweep {
    name: &'static str,
    varies: &'static str,
    held: &'static str,
    x: &'static str,
    log_y: bool,
}

/// A sweep's bench lines (one per point) and its figure `<name>.svg` in `dir`.
fn report(dir: &Path, sweep: &Sweep, points: &[(f64, Point)]) -> Result<(), String> {
    for (x, p) in points {
        println!(
            "covssi_growth_{} {x} ({}): ssi {:.0} ms, refine {:.0} ms ({} modes kept, {})",
            sweep.name, sweep.held, p.ssi_ms, p.refine_ms, p.kept, p.fitted
        );
    }
    let path = dir.join(format!("{}.svg", sweep.name));
    let title = format!("covssi's cost against {} ({})", sweep.varies, sweep.held);
    let draw = if sweep.log_y { chart_log_y } else { chart };
    draw(&path, &title, sweep.x, "ms", &series(points))
}

/// The three sweeps, their lines and figures.
pub fn run() -> Result<(), String> {
    let dir = hyst_testkit::workspace_root().join("docs/figures/covssi_growth");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let n = 1 << 17;
    // Length: 2¹⁴ to 2²⁰ samples, prefixes of one record.
    let long = crate::linear_record(1 << 20, 10, 5, 11);
    let by_length: Vec<(f64, Point)> = (14..=20)
        .map(|e| Ok(((e as f64), measure(&long, 1 << e, 10)?)))
        .collect::<Result<_, String>>()?;
    drop(long);
    let length = Sweep {
        name: "samples",
        varies: "the record's length",
        held: "10 channels, 5 modes",
        x: "log2 samples",
        log_y: true,
    };
    report(&dir, &length, &by_length)?;
    // Channels: 1 to 16, the first channels of one record.
    let wide = crate::linear_record(n, 16, 5, 12);
    let by_channels: Vec<(f64, Point)> = [1, 2, 3, 4, 6, 8, 12, 16]
        .iter()
        .map(|&l| Ok((l as f64, measure(&wide, n, l)?)))
        .collect::<Result<_, String>>()?;
    drop(wide);
    let channels = Sweep {
        name: "channels",
        varies: "the channels",
        held: "2^17 samples, 5 modes",
        x: "channels",
        log_y: false,
    };
    report(&dir, &channels, &by_channels)?;
    // Modes: 1 to 8, a record of each.
    let by_modes: Vec<(f64, Point)> = (1..=8)
        .map(|m| {
            let rec = crate::linear_record(n, 10, m, 13);
            Ok((m as f64, measure(&rec, n, 10)?))
        })
        .collect::<Result<_, String>>()?;
    let modes = Sweep {
        name: "modes",
        varies: "the modes",
        held: "2^17 samples, 10 channels",
        x: "modes",
        log_y: false,
    };
    report(&dir, &modes, &by_modes)?;
    println!("covssi_growth figures in {}", dir.display());
    Ok(())
}
