//! `cargo xtask f16`: the measured F-16's wing modes at its four force levels, output-only
//! (covssi on the three accelerations) beside the input-output fit of the force-to-acceleration
//! response (`hyst_ident::frf`), and output-only again on the accelerations as they would be
//! under a force of flat spectrum; figures of frequency and damping over force, and of the
//! force's spectrum around each mode; each mode's shape over the three accelerations both
//! ways, with their MAC and MPC; and the smallest Bouc-Wen exponent ν each mode's loss
//! growth between levels allows ([`NuBound`]).

use std::path::{Path, PathBuf};

use hyst::covssi::{self, BlockRows, SsiOptions};
use hyst::plot::Series;
use hyst_ident::frf::{self, FrfFit, FrfMode, PeriodicRecord};
use rayon::prelude::*;

/// The records (README beside the data): 9 periods of 8192 samples at 400 Hz, the first a
/// start-up transient.
pub const LEVELS: [u32; 4] = [1, 3, 5, 7];
const FS: f64 = 400.0;
const PERIOD: usize = 8192;
/// 400 → 50 Hz keeps the 2–15 Hz band for SSI.
const DECIMATE: usize = 8;

/// A mode followed over the levels.
pub struct Target {
    /// Name in the table.
    pub name: &'static str,
    /// The SSI cluster with most poles within `search` Hz of this frequency is taken.
    pub nominal_hz: f64,
    /// Search half-width (Hz).
    pub search: f64,
    /// The narrow band fitted with this mode alone (Hz).
    pub narrow: (f64, f64),
    /// A wide band and the modes fitted in it, neighbours included.
    pub wide: ((f64, f64), usize),
}

/// The wing bending mode near 5.2 Hz and the wing torsion mode near 7.3 Hz (README).
pub const TARGETS: [Target; 2] = [
    Target {
        name: "wing bending",
        nominal_hz: 5.2,
        search: 0.3,
        narrow: (4.6, 5.8),
        wide: ((3.2, 6.2), 3),
    },
    Target {
        name: "wing torsion",
        nominal_hz: 7.3,
        search: 0.3,
        narrow: (6.8, 7.8),
        wide: ((6.0, 9.6), 3),
    },
];

/// An SSI cluster: frequency (Hz), its spread over the cluster, damping ratio, its spread,
/// and the number of poles.
pub type Cluster = (f64, f64, f64, f64, usize);

/// One mode at one level by every method.
#[derive(Debug, Clone)]
pub struct Row {
    /// Level number of the file.
    pub level: u32,
    /// RMS of the force over the periods used (N).
    pub force_rms: f64,
    /// Index into [`TARGETS`].
    pub target: usize,
    /// Output-only SSI on the measured accelerations.
    pub ssi: Option<Cluster>,
    /// That cluster's mean shape over acc1, acc2, acc3 (largest entry 1).
    pub ssi_shape: Option<Vec<covssi::Complex64>>,
    /// The same on the accelerations under a force of flat spectrum.
    pub ssi_flat: Option<Cluster>,
    /// The response fit of the narrow band (this mode alone) and its misfit.
    pub narrow: (Option<FrfMode>, f64),
    /// The response fit of the wide band (neighbours too) and its misfit.
    pub wide: (Option<FrfMode>, f64),
    /// Frequencies (Hz) and force amplitudes (N) of the lines of the narrow band.
    pub force_lines: Vec<(f64, f64)>,
    /// Frequencies (Hz) and |acc2 / force| at the lines of the narrow band (acc2: the wing
    /// next to the interface).
    pub response_lines: Vec<(f64, f64)>,
    /// RMS of each acceleration's periodic response within the narrow band.
    pub band_rms: Vec<f64>,
    /// RMS of each acceleration over the whole record (mean removed).
    pub total_rms: Vec<f64>,
}

/// The SSI mode taken for a target: the one with most poles within its search band.
fn ssi_mode<'a>(res: &'a covssi::SsiResult, tg: &Target) -> Option<&'a covssi::Mode> {
    res.modes
        .iter()
        .filter(|m| (m.frequency_hz - tg.nominal_hz).abs() <= tg.search)
        .max_by_key(|m| m.members.len())
}

fn cluster(res: &covssi::SsiResult, tg: &Target) -> Option<Cluster> {
    ssi_mode(res, tg).map(|m| {
        (
            m.frequency_hz,
            m.frequency_std_hz,
            m.damping_ratio,
            m.damping_std,
            m.members.len(),
        )
    })
}

fn nearest(fit: &FrfFit, f: f64) -> Option<FrfMode> {
    fit.modes
        .iter()
        .min_by(|a, b| {
            (a.frequency_hz - f)
                .abs()
                .total_cmp(&(b.frequency_hz - f).abs())
        })
        .cloned()
}

/// Every analysis of one level's file.
pub fn analyse(dir: &Path, level: u32) -> Result<Vec<Row>, String> {
    let path = dir.join(format!("f16/msine_level{level}.csv"));
    let err = |what: &str, e: &dyn std::fmt::Display| format!("{}: {what}{e}", path.display());
    let t = hyst::io::read_csv(&path).map_err(|e| err("", &e))?;
    let col = |n: &str| {
        let c = t.column(n).map_err(|e| err("", &e))?;
        // Drop the first period, the start-up transient.
        c.get(PERIOD..)
            .map(<[f64]>::to_vec)
            .ok_or_else(|| err("", &format!("column {n} is shorter than one period")))
    };
    let force = col("force")?;
    let acc: Vec<Vec<f64>> = ["acc1", "acc2", "acc3"]
        .iter()
        .map(|c| col(c))
        .collect::<Result<_, _>>()?;
    let rms = |x: &[f64]| {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
    };
    let force_rms = rms(&force);
    let total_rms: Vec<f64> = acc.iter().map(|c| rms(c)).collect();
    let outs: Vec<&[f64]> = acc.iter().map(|c| c.as_slice()).collect();
    let rec = PeriodicRecord {
        input: &force,
        outputs: &outs,
        fs: FS,
        period: PERIOD,
    };
    let flat = frf::outputs_under_flat_input(&rec).map_err(|e| err("flat force: ", &e))?;
    // Output only, with the settings of the test and docs/covssi.md.
    let opts = SsiOptions {
        block_rows: BlockRows::Count(40),
        max_order: Some(60),
        ..SsiOptions::default()
    };
    let ssi = |channels: &[Vec<f64>]| {
        let dec: Vec<Vec<f64>> = channels
            .iter()
            .map(|c| hyst::sim::resample::decimate(c, DECIMATE))
            .collect();
        let views: Vec<&[f64]> = dec.iter().map(|c| c.as_slice()).collect();
        covssi::identify(&views, FS / DECIMATE as f64, &opts).map_err(|e| err("SSI: ", &e))
    };
    let (res, res_flat) = (ssi(&acc)?, ssi(&flat)?);
    let mut rows = Vec::new();
    for (i, tg) in TARGETS.iter().enumerate() {
        let s = cluster(&res, tg);
        let near = s.map_or(tg.nominal_hz, |c| c.0);
        let narrow = frf::modes_from_frf(&rec, tg.narrow, 1).map_err(|e| err("fit: ", &e))?;
        let wide = frf::modes_from_frf(&rec, tg.wide.0, tg.wide.1).map_err(|e| err("fit: ", &e))?;
        rows.push(Row {
            level,
            force_rms,
            target: i,
            ssi: s,
            ssi_shape: ssi_mode(&res, tg).map(|m| m.shape.clone()),
            ssi_flat: cluster(&res_flat, tg),
            narrow: (nearest(&narrow, near), narrow.misfit),
            wide: (nearest(&wide, near), wide.misfit),
            force_lines: narrow
                .frequency_hz
                .iter()
                .copied()
                .zip(narrow.input_amplitude.iter().copied())
                .collect(),
            response_lines: narrow
                .frequency_hz
                .iter()
                .zip(&narrow.response[1])
                .map(|(f, h)| (*f, h.norm()))
                .collect(),
            band_rms: narrow.response_rms(),
            total_rms: total_rms.clone(),
        });
    }
    Ok(rows)
}

/// Every level, in parallel, in level order.
pub fn run(dir: &Path) -> Result<Vec<Row>, String> {
    let per: Vec<Result<Vec<Row>, String>> = LEVELS.par_iter().map(|&l| analyse(dir, l)).collect();
    let mut rows = Vec::new();
    for r in per {
        rows.extend(r?);
    }
    rows.sort_by_key(|r| (r.target, r.level));
    Ok(rows)
}

/// Loss stiffness per unit modal mass, 2ζω² (rad²/s²), of a mode of this frequency (Hz) and
/// damping ratio.
fn loss_of(frequency_hz: f64, damping_ratio: f64) -> f64 {
    let w = std::f64::consts::TAU * frequency_hz;
    2.0 * damping_ratio * w * w
}

/// [`loss_of`] a fitted mode.
fn loss(m: &FrfMode) -> f64 {
    loss_of(m.frequency_hz, m.damping_ratio)
}

/// A mode's loss 2ζω² at one level by the estimates free of the force's colour (the fit
/// alone, the fit with neighbours, SSI under the flat force), then by SSI on the measured
/// accelerations, which the force's drop at the resonance biases (docs/results.md).
fn losses(r: &Row) -> (Vec<f64>, Option<f64>) {
    let ssi = |c: Option<Cluster>| c.map(|(f, _, z, _, _)| loss_of(f, z));
    let clean = [
        r.narrow.0.as_ref().map(loss),
        r.wide.0.as_ref().map(loss),
        ssi(r.ssi_flat),
    ];
    (clean.into_iter().flatten().collect(), ssi(r.ssi))
}

/// Between two levels, the smallest Bouc-Wen exponent ν a mode's loss growth allows. For
/// −γ ≤ δ < γ a Bouc-Wen element's loss stiffness grows no faster than A^ν (property test
/// `loss_grows_no_faster_than_amplitude_to_the_nu` in hyst-linearize), and a viscous part
/// beside it only slows the growth, so a loss ratio L₂/L₁ over an amplitude ratio g needs
/// ν ≥ ln(L₂/L₁)/ln g. The joint's amplitude is not measured: g is the largest growth of
/// any sensor's response, in any mode's band or over the whole record, which gives the
/// smallest ν.
#[derive(Debug, Clone, Copy)]
pub struct NuBound {
    /// Index into [`TARGETS`].
    pub target: usize,
    /// The two levels.
    pub levels: (u32, u32),
    /// The largest growth of a sensor's response RMS between them.
    pub growth: f64,
    /// The fit's (mode alone) loss at the two levels (rad²/s²).
    pub loss_fit: (f64, f64),
    /// The least loss ratio two estimates free of the force's colour give: the smallest at
    /// the upper level over the largest at the lower.
    pub least_ratio: f64,
    /// The same with SSI on the measured accelerations among the estimates.
    pub least_ratio_raw: f64,
}

impl NuBound {
    /// The smallest ν from a loss ratio (`None` where the loss did not grow: no bound).
    pub fn nu(&self, ratio: f64) -> Option<f64> {
        (ratio > 1.0 && self.growth > 1.0).then(|| ratio.ln() / self.growth.ln())
    }
}

/// The largest growth from level `a` to level `b` of any response measure: each sensor's
/// RMS in each mode's band and over the whole record.
fn largest_growth(rows: &[Row], a: u32, b: u32) -> f64 {
    let measures = |level: u32| -> Vec<f64> {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.level == level).collect();
        let mut v: Vec<f64> = mine.iter().flat_map(|r| r.band_rms.clone()).collect();
        v.extend(mine.first().map_or(Vec::new(), |r| r.total_rms.clone()));
        v
    };
    measures(a)
        .iter()
        .zip(&measures(b))
        .map(|(x, y)| y / x)
        .fold(f64::NAN, f64::max)
}

/// [`NuBound`] for each mode between consecutive levels.
pub fn nu_bounds(rows: &[Row]) -> Vec<NuBound> {
    let least = |a: &[f64], b: &[f64]| {
        b.iter().copied().fold(f64::INFINITY, f64::min)
            / a.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    };
    let mut out = Vec::new();
    for (i, _) in TARGETS.iter().enumerate() {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.target == i).collect();
        for w in mine.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (Some(fa), Some(fb)) = (&a.narrow.0, &b.narrow.0) else {
                continue;
            };
            let growth = largest_growth(rows, a.level, b.level);
            let ((ca, ra), (cb, rb)) = (losses(a), losses(b));
            let with_raw =
                |c: &[f64], r: Option<f64>| c.iter().copied().chain(r).collect::<Vec<_>>();
            out.push(NuBound {
                target: i,
                levels: (a.level, b.level),
                growth,
                loss_fit: (loss(fa), loss(fb)),
                least_ratio: least(&ca, &cb),
                least_ratio_raw: least(&with_raw(&ca, ra), &with_raw(&cb, rb)),
            });
        }
    }
    out
}

fn fmt_cluster(c: Option<Cluster>) -> String {
    match c {
        Some((f, fs, z, zs, n)) => format!(
            "{f:.3} ± {fs:.3} | {:.2} ± {:.2} | {n}",
            100.0 * z,
            100.0 * zs
        ),
        None => "none | | ".into(),
    }
}

fn fmt_fit(m: Option<&FrfMode>, misfit: f64) -> String {
    match m {
        Some(m) => format!(
            "{:.3} ± {:.3} | {:.2} ± {:.2} | {misfit:.0}",
            m.frequency_hz,
            m.frequency_se_hz,
            100.0 * m.damping_ratio,
            100.0 * m.damping_se
        ),
        None => format!("none | | {misfit:.0}"),
    }
}

/// The table, as markdown: for SSI the "±" is the spread over the cluster's poles; for the
/// fits it is the jackknife standard error over periods (noise only, see docs/results.md).
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| mode | level | force RMS (N) | SSI f (Hz) | SSI ζ (%) | poles | SSI, flat force: f (Hz) | ζ (%) | poles | fit, mode alone: f (Hz) | ζ (%) | misfit | fit with neighbours: f (Hz) | ζ (%) | misfit |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {:.1} | {} | {} | {} | {} |\n",
            TARGETS[r.target].name,
            r.level,
            r.force_rms,
            fmt_cluster(r.ssi),
            fmt_cluster(r.ssi_flat),
            fmt_fit(r.narrow.0.as_ref(), r.narrow.1),
            fmt_fit(r.wide.0.as_ref(), r.wide.1),
        );
    }
    s += "\n| mode | level | force per line across the band: mean (N) | lowest (N, at Hz) | highest (N, at Hz) |\n|---|---|---|---|---|\n";
    for r in rows {
        let lines = &r.force_lines;
        let mean = lines.iter().map(|l| l.1).sum::<f64>() / lines.len().max(1) as f64;
        let lo = lines.iter().min_by(|a, b| a.1.total_cmp(&b.1));
        let hi = lines.iter().max_by(|a, b| a.1.total_cmp(&b.1));
        if let (Some(lo), Some(hi)) = (lo, hi) {
            s += &format!(
                "| {} | {} | {mean:.3} | {:.3} at {:.3} | {:.3} at {:.3} |\n",
                TARGETS[r.target].name, r.level, lo.1, lo.0, hi.1, hi.0
            );
        }
    }
    s += "\n| mode | level | response RMS in the band: acc1, acc2, acc3 | whole record: acc1, acc2, acc3 | loss 2ζω² of the fit, mode alone (rad²/s²) | peak of the measured \\|acc2 / force\\| (at Hz) |\n|---|---|---|---|---|---|\n";
    let three = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.4}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for r in rows {
        let loss = r.narrow.0.as_ref().map_or(f64::NAN, loss);
        // No fit at all: the largest measured response in the band.
        let peak = r
            .response_lines
            .iter()
            .copied()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((f64::NAN, f64::NAN));
        s += &format!(
            "| {} | {} | {} | {} | {loss:.1} | {:.4} at {:.3} |\n",
            TARGETS[r.target].name,
            r.level,
            three(&r.band_rms),
            three(&r.total_rms),
            peak.1,
            peak.0
        );
    }
    s += &shapes_markdown(rows);
    s += "\n| mode | levels | largest response growth | loss 2ζω² of the fit, mode alone | smallest ν | least loss ratio, estimates free of the force's colour | smallest ν | least loss ratio, SSI on the measured accelerations too | smallest ν |\n|---|---|---|---|---|---|---|---|---|\n";
    let nu = |v: Option<f64>| v.map_or("any (no growth)".into(), |v| format!("{v:.2}"));
    for b in nu_bounds(rows) {
        let ratio = b.loss_fit.1 / b.loss_fit.0;
        s += &format!(
            "| {} | {} → {} | {:.3} | {:.1} → {:.1} | {} | {:.3} | {} | {:.3} | {} |\n",
            TARGETS[b.target].name,
            b.levels.0,
            b.levels.1,
            b.growth,
            b.loss_fit.0,
            b.loss_fit.1,
            nu(b.nu(ratio)),
            b.least_ratio,
            nu(b.nu(b.least_ratio)),
            b.least_ratio_raw,
            nu(b.nu(b.least_ratio_raw)),
        );
    }
    s
}

/// Per mode and level, its shape over acc1, acc2, acc3 two ways: output-only (the SSI
/// cluster's mean) and input-output (the residues of the fit of the mode alone), their MAC,
/// each one's MPC, and the MAC of the fit's shape with its shape at the lowest level.
fn shapes_markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "\n| mode | level | shape, SSI (acc1, acc2, acc3) | MPC | shape, fit of the mode alone | its standard errors (jackknife) | MPC | MAC SSI–fit | MAC of the fit with level 1's |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let first = rows
            .iter()
            .find(|q| q.target == r.target && q.level == LEVELS[0])
            .and_then(|q| q.narrow.0.as_ref());
        let fit = r.narrow.0.as_ref();
        let cell = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.4}"));
        let se = |m: &FrfMode| {
            m.shape_se
                .iter()
                .map(|v| format!("{v:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            TARGETS[r.target].name,
            r.level,
            r.ssi_shape
                .as_deref()
                .map_or(String::new(), |v| hyst::shape_text(v, ", ")),
            cell(r.ssi_shape.as_deref().map(covssi::mpc)),
            fit.map_or(String::new(), |m| hyst::shape_text(&m.shape, ", ")),
            fit.map_or(String::new(), se),
            cell(fit.map(|m| covssi::mpc(&m.shape))),
            cell(
                r.ssi_shape
                    .as_deref()
                    .zip(fit)
                    .map(|(a, m)| covssi::mac(a, &m.shape))
            ),
            cell(first.zip(fit).map(|(a, b)| covssi::mac(&a.shape, &b.shape))),
        );
    }
    s
}

/// Per mode: frequency and damping over force by every method, and the force's line
/// amplitudes across the mode's band at each level.
pub fn figures(rows: &[Row], out: &Path) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut paths = Vec::new();
    for (i, tg) in TARGETS.iter().enumerate() {
        let mine: Vec<&Row> = rows.iter().filter(|r| r.target == i).collect();
        let slug = tg.name.replace(' ', "_");
        paths.extend(modal_figures(&mine, tg, &slug, out)?);
        paths.push(loss_figure(rows, &mine, tg, &slug, out)?);
        paths.extend(line_figures(&mine, tg, &slug, out)?);
    }
    Ok(paths)
}

/// A target mode's frequency and damping over the force level, by each method.
fn modal_figures(
    mine: &[&Row],
    tg: &Target,
    slug: &str,
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    use hyst::plot::colors;
    let mut paths = Vec::new();
    let series = |f: &dyn Fn(&Row) -> Option<f64>| -> Vec<(f64, f64)> {
        mine.iter()
            .filter_map(|r| f(r).map(|v| (r.force_rms, v)))
            .collect()
    };
    let freq: Vec<Series> = vec![
        (
            "SSI, accelerations only".into(),
            series(&|r| r.ssi.map(|c| c.0)),
            colors::BLUE,
        ),
        (
            "SSI, force made flat".into(),
            series(&|r| r.ssi_flat.map(|c| c.0)),
            colors::GREEN,
        ),
        (
            "fit of the response, mode alone".into(),
            series(&|r| r.narrow.0.as_ref().map(|m| m.frequency_hz)),
            colors::RED,
        ),
        (
            "fit of the response, with neighbours".into(),
            series(&|r| r.wide.0.as_ref().map(|m| m.frequency_hz)),
            colors::ORANGE,
        ),
    ];
    let damp: Vec<Series> = vec![
        (
            freq[0].0.clone(),
            series(&|r| r.ssi.map(|c| 100.0 * c.2)),
            colors::BLUE,
        ),
        (
            freq[1].0.clone(),
            series(&|r| r.ssi_flat.map(|c| 100.0 * c.2)),
            colors::GREEN,
        ),
        (
            freq[2].0.clone(),
            series(&|r| r.narrow.0.as_ref().map(|m| 100.0 * m.damping_ratio)),
            colors::RED,
        ),
        (
            freq[3].0.clone(),
            series(&|r| r.wide.0.as_ref().map(|m| 100.0 * m.damping_ratio)),
            colors::ORANGE,
        ),
    ];
    for (what, unit, s) in [
        ("frequency", "natural frequency (Hz)", freq),
        ("damping", "damping ratio (%)", damp),
    ] {
        let p = out.join(format!("f16_{slug}_{what}.svg"));
        hyst::plot::chart(
            &p,
            &format!("F-16 {}: {what} over force level", tg.name),
            "force RMS (N)",
            unit,
            &s,
        )?;
        paths.push(p);
    }
    Ok(paths)
}

/// A target mode's loss 2ζω² over the force level, beside the most a ν = 1 Bouc-Wen element
/// allows from the second level.
fn loss_figure(
    rows: &[Row],
    mine: &[&Row],
    tg: &Target,
    slug: &str,
    out: &Path,
) -> Result<PathBuf, String> {
    use hyst::plot::colors;
    // The loss over force, and the most a ν = 1 Bouc-Wen element allows above the second
    // level: its loss grows no faster than its amplitude (docs/results.md), here taken to
    // grow as the fastest-growing response measure ([`NuBound`]).
    let loss_fit: Vec<(f64, f64)> = mine
        .iter()
        .filter_map(|r| Some((r.force_rms, loss(r.narrow.0.as_ref()?))))
        .collect();
    let second = mine
        .get(1)
        .and_then(|r| Some((r.level, loss(r.narrow.0.as_ref()?))));
    let bound: Vec<(f64, f64)> = match second {
        // At the second level itself the growth is 1.
        Some((l2, l2_loss)) => mine[1..]
            .iter()
            .map(|r| (r.force_rms, l2_loss * largest_growth(rows, l2, r.level)))
            .collect(),
        None => Vec::new(),
    };
    let p = out.join(format!("f16_{slug}_loss.svg"));
    hyst::plot::chart(
        &p,
        &format!("F-16 {}: loss 2ζω² over force", tg.name),
        "force RMS (N)",
        "loss 2ζω² (rad²/s²)",
        &[
            (
                "fit of the response, mode alone".into(),
                loss_fit,
                colors::RED,
            ),
            (
                "largest a ν = 1 Bouc-Wen element allows from the second level".into(),
                bound,
                colors::GREY,
            ),
        ],
    )?;
    Ok(p)
}

/// One curve per level across a target mode's band: the force's lines, the response's.
fn line_figures(
    mine: &[&Row],
    tg: &Target,
    slug: &str,
    out: &Path,
) -> Result<Vec<PathBuf>, String> {
    use hyst::plot::colors;
    let mut paths = Vec::new();
    let palette = [colors::BLACK, colors::BLUE, colors::GREEN, colors::RED];
    let per_level = |lines: fn(&Row) -> &Vec<(f64, f64)>| -> Vec<Series> {
        mine.iter()
            .zip(palette)
            .map(|(r, c)| {
                let name = format!("level {} ({:.0} N RMS)", r.level, r.force_rms);
                (name, lines(r).clone(), c)
            })
            .collect()
    };
    for (file, title, axis, series) in [
        (
            "response",
            format!("F-16: |acc2 / force| across the {} band", tg.name),
            "|acc2 / force| (log10)",
            per_level(|r| &r.response_lines),
        ),
        (
            "force",
            format!("F-16: force amplitude per line across the {} band", tg.name),
            "force amplitude per line (N, log10)",
            per_level(|r| &r.force_lines),
        ),
    ] {
        let p = out.join(format!("f16_{slug}_{file}.svg"));
        hyst::plot::chart_log_y(&p, &title, "frequency (Hz)", axis, &series)?;
        paths.push(p);
    }
    Ok(paths)
}
