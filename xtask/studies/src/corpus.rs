//! `cargo xtask corpus`: the modal analysis with its defaults over the corpus of realistic
//! building records (`hyst_sim::corpus`), scored against their truth: true modes found,
//! reported modes that are not structural, and the z-scores of the reported errors.

use rayon::prelude::*;

/// Arguments of `cargo xtask corpus`.
#[derive(clap::Args)]
pub struct CorpusArgs {
    /// Records (one per seed).
    #[arg(long, default_value_t = 40)]
    seeds: u64,
    /// The first seed.
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// The step between seeds.
    #[arg(long, default_value_t = 1)]
    seed_step: u64,
    /// Each record's length in periods of its first mode (at least 5 minutes).
    #[arg(long, default_value_t = 1000.0)]
    periods: f64,
    /// Print each record's report too.
    #[arg(long)]
    verbose: bool,
    /// Score the answer as hyst reported it before the decision (the refined modes the
    /// likelihood calls physical when its misfit is within the limit, else every SSI
    /// cluster, without errors), on the same analyses.
    #[arg(long)]
    before: bool,
    /// Also run `hyst amplitude`'s analysis with its defaults on each record with a Bouc-Wen
    /// storey, and judge it as issue 57 asks: every mode followed structural (within the
    /// corpus's tolerance of a true mode), no point whose error exceeds a tenth of its
    /// frequency, no empty band.
    #[arg(long)]
    amplitude: bool,
    /// SSI's largest model order (default: the analysis's own, 40 or four per spectral peak).
    #[arg(long)]
    max_order: Option<usize>,
}

/// The amplitude checks' totals over the records they ran on.
fn print_amplitude(all: &[[usize; 5]]) {
    let sum = |k: usize| all.iter().map(|c| c[k]).sum::<usize>();
    println!(
        "amplitude on {} hysteretic records: {} modes followed, {} not structural; {} points, {} with an error above a tenth of the frequency; {} empty bands",
        all.len(),
        sum(0),
        sum(1),
        sum(2),
        sum(3),
        sum(4)
    );
}

/// `hyst amplitude` with its defaults on a hysteretic case: a line, and the counts (modes
/// followed, of them not structural, points, of them with an error above f/10, empty bands).
fn amplitude_check(
    case: &hyst_sim::corpus::CorpusCase,
    views: &[&[f64]],
) -> Result<(String, [usize; 5]), String> {
    use hyst_ident::amplitude::{AmplitudeOptions, Quantity, amplitude_analysis};
    use hyst_sim::building::Reading;
    let mut opts = AmplitudeOptions::default();
    opts.measured = match case.building.reading {
        Reading::Displacement => Quantity::Displacement,
        Reading::Velocity => Quantity::Velocity,
        Reading::Acceleration => Quantity::Acceleration,
    };
    let r = amplitude_analysis(
        views,
        case.building.fs,
        &covssi::AnalysisOptions::default(),
        &opts,
        &[],
    )
    .map_err(|e| e.to_string())?;
    let tol = case.tolerance();
    let mut counts = [0usize; 5];
    let mut followed = Vec::new();
    for c in &r.curves.modes {
        let f = c.mode.frequency_hz;
        let structural = case
            .truth
            .iter()
            .any(|t| (t.frequency_hz - f).abs() <= tol * t.frequency_hz);
        counts[0] += 1;
        counts[1] += usize::from(!structural);
        counts[2] += c.points.len();
        counts[3] += c
            .points
            .iter()
            .filter(|p| p.frequency_se_hz.is_nan() || p.frequency_se_hz > 0.1 * p.frequency_hz)
            .count();
        counts[4] += usize::from(c.band_hz.1.is_nan() || c.band_hz.1 <= c.band_hz.0);
        followed.push(format!(
            "{f:.3} Hz{} ({} points)",
            if structural { "" } else { " NOT STRUCTURAL" },
            c.points.len()
        ));
    }
    Ok((format!("  amplitude: {}", followed.join(", ")), counts))
}

/// The modes `hyst ssi` reported before `covssi::decision` (commit a064d96's
/// `ModalAnalysis::reported_modes`), from the same analysis.
fn reported_before(a: &covssi::ModalAnalysis) -> Vec<hyst_sim::corpus::Estimate> {
    let physical = |i: usize| !a.not_reported.iter().any(|n| n.index == i && !n.real_pole);
    match a
        .refined
        .as_ref()
        .filter(|r| r.misfit <= covssi::MISFIT_LIMIT && (0..r.modes.len()).any(physical))
    {
        Some(r) => r
            .modes
            .iter()
            .enumerate()
            .filter(|(i, _)| physical(*i))
            .map(|(_, m)| {
                (
                    m.frequency_hz,
                    m.frequency_se_hz,
                    m.damping_ratio,
                    m.damping_se,
                )
            })
            .collect(),
        None => a
            .ssi
            .modes
            .iter()
            .map(|m| (m.frequency_hz, None, m.damping_ratio, None))
            .collect(),
    }
}

/// The corpus analysed and scored, one line per record, then the summary.
pub fn run(a: &CorpusArgs) -> Result<(), String> {
    let seeds: Vec<u64> = (0..a.seeds)
        .map(|k| a.first_seed + k * a.seed_step)
        .collect();
    // Per record: the answer was the refinement's, its lines, its score, and the amplitude
    // check's counts when it ran.
    type Row = (bool, String, hyst_sim::corpus::Score, Option<[usize; 5]>);
    let rows: Vec<Result<Row, String>> = seeds
        .par_iter()
        .map(|&seed| {
            let case = hyst_sim::corpus::realistic(seed, a.periods).map_err(|e| e.to_string())?;
            let y = case.generate().map_err(|e| format!("seed {seed}: {e}"))?;
            let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
            let mut opts = covssi::AnalysisOptions::default();
            if let Some(order) = a.max_order {
                opts = opts.with_ssi(covssi::SsiOptions {
                    max_order: Some(order),
                    ..covssi::SsiOptions::default()
                });
            }
            let analysis = covssi::analyze(&views, case.building.fs, &opts)
                .map_err(|e| format!("seed {seed}: {e}"))?;
            let reported: Vec<hyst_sim::corpus::Estimate> = if a.before {
                reported_before(&analysis)
            } else {
                analysis
                    .reported_modes()
                    .iter()
                    .map(|m| (m.frequency_hz, m.frequency_se_hz, m.damping_ratio, m.damping_se))
                    .collect()
            };
            let score = case.score(&reported);
            let truth: Vec<String> = case
                .in_band
                .iter()
                .map(|&j| format!("{:.3}", case.truth[j].frequency_hz))
                .collect();
            let mut line = format!(
                "seed {seed}: {}\n  truth in band {} Hz; found {}/{}, reported {}, spurious {:?}, missed {:?}\n  z frequency {:.2?}, z damping {:.2?}",
                case.description,
                truth.join(", "),
                score.found,
                score.in_band,
                score.reported,
                score.spurious,
                score.missed,
                score.z_frequency,
                score.z_damping
            );
            if a.verbose {
                line.push_str(&format!("\n{analysis}"));
            }
            let mut amplitude = None;
            if a.amplitude && case.hysteretic {
                let (text, counts) = amplitude_check(&case, &views)?;
                line.push_str(&format!("\n{text}"));
                amplitude = Some(counts);
            }
            let refined = analysis.decision.source == covssi::ModeSource::Refined;
            Ok((refined, line, score, amplitude))
        })
        .collect();
    let mut scores = Vec::new();
    let (mut by_refined, mut by_ssi) = (Vec::new(), Vec::new());
    let mut amplitude = Vec::new();
    for r in rows {
        let (refined, line, score, counts) = r?;
        println!("{line}");
        amplitude.extend(counts);
        if refined {
            by_refined.push(score.clone());
        } else {
            by_ssi.push(score.clone());
        }
        scores.push(score);
    }
    println!("{}", hyst_sim::corpus::Summary::of(&scores));
    if a.amplitude {
        print_amplitude(&amplitude);
    }
    // Found by how far each mode's peak stands out of the sensor noise (density ratio).
    let classes = [
        (1.0, 3.0),
        (3.0, 10.0),
        (10.0, 100.0),
        (100.0, f64::INFINITY),
    ];
    let by_class: Vec<String> = classes
        .iter()
        .map(|&(lo, hi)| {
            let (found, all) = scores
                .iter()
                .flat_map(|s| &s.visibility_found)
                .filter(|(v, _)| *v >= lo && *v < hi)
                .fold((0, 0), |(f, n), (_, ok)| (f + usize::from(*ok), n + 1));
            format!("{lo}–{hi}: {found}/{all}")
        })
        .collect();
    println!(
        "found by the peak's density over the sensor noise's: {}",
        by_class.join(", ")
    );
    println!(
        "answer the refinement's: {}",
        hyst_sim::corpus::Summary::of(&by_refined)
    );
    println!(
        "answer SSI's (jackknife errors): {}",
        hyst_sim::corpus::Summary::of(&by_ssi)
    );
    Ok(())
}
