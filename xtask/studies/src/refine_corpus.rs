//! `cargo xtask refine-corpus`: where the maximum-likelihood refinement holds on the corpus
//! of realistic building records (`hyst_sim::corpus`: coloured, band-limited and modulated
//! loads, machines, close modes), and what it gains there over SSI's answer on the same
//! records.
//!
//! Each record is analysed twice, with the refinement asked for and with the defaults (no
//! refinement: the answer SSI's with the jackknife's errors), each timed. The
//! refinement's verdicts are counted; on the records where it holds, every true mode both
//! answers found gives a pair of errors, and the ratios of their RMS (refined over SSI's,
//! relative frequency and damping errors) are given with a 95 % interval from resampling the
//! records (a record's modes resampled together: its errors share its load).

use std::time::Instant;

/// Arguments of `cargo xtask refine-corpus`.
#[derive(clap::Args)]
pub struct RefineCorpusArgs {
    /// Records (one per seed).
    #[arg(long, default_value_t = 20)]
    seeds: u64,
    /// The first seed.
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// The step between seeds.
    #[arg(long, default_value_t = 1)]
    seed_step: u64,
    /// Each record's length in periods of its first mode (at least 5 minutes).
    #[arg(long, default_value_t = 800.0)]
    periods: f64,
    /// Print each record's refinement report too.
    #[arg(long)]
    verbose: bool,
}

/// One record's two analyses, scored.
struct Row {
    seed: u64,
    line: String,
    verdict: &'static str,
    /// Relative errors (frequency, damping) of each true mode both answers found: the
    /// refined answer's, then SSI's.
    pairs: Vec<([f64; 2], [f64; 2])>,
    with: hyst_sim::corpus::Score,
    without: hyst_sim::corpus::Score,
    seconds: (f64, f64),
}

/// The verdict's name as the JSON spells it.
fn verdict_name(v: &covssi::decision::RefinementVerdict) -> &'static str {
    match v {
        covssi::decision::RefinementVerdict::NotRun => "not_run",
        covssi::decision::RefinementVerdict::Holds => "holds",
        covssi::decision::RefinementVerdict::Misfit { .. } => "misfit",
        covssi::decision::RefinementVerdict::LostModes { .. } => "lost_modes",
        covssi::decision::RefinementVerdict::SparePole { .. } => "spare_pole",
    }
}

/// A record analysed with and without the refinement.
fn analyse(seed: u64, a: &RefineCorpusArgs) -> Result<Row, String> {
    let case = hyst_sim::corpus::realistic(seed, a.periods).map_err(|e| e.to_string())?;
    let y = case.generate().map_err(|e| format!("seed {seed}: {e}"))?;
    let views: Vec<&[f64]> = y.iter().map(|c| c.as_slice()).collect();
    let fs = case.building.fs;
    let t0 = Instant::now();
    let refined =
        covssi::AnalysisOptions::default().with_refine(Some(covssi::RefineOptions::default()));
    let with = covssi::analyze(&views, fs, &refined).map_err(|e| format!("seed {seed}: {e}"))?;
    let t1 = Instant::now();
    // The defaults: SSI's answer with the jackknife's errors (no refinement).
    let without = covssi::analyze(&views, fs, &covssi::AnalysisOptions::default())
        .map_err(|e| format!("seed {seed}: {e}"))?;
    let t2 = Instant::now();
    let estimates = |an: &covssi::ModalAnalysis| -> Vec<hyst_sim::corpus::Estimate> {
        an.reported_modes()
            .iter()
            .map(|m| {
                (
                    m.frequency_hz,
                    m.frequency_se_hz,
                    m.damping_ratio,
                    m.damping_se,
                )
            })
            .collect()
    };
    let (ew, eo) = (estimates(&with), estimates(&without));
    let (sw, so) = (case.score(&ew), case.score(&eo));
    let verdict = verdict_name(&with.decision.refinement);
    let rel = |e: &hyst_sim::corpus::Estimate, j: usize| {
        let t = &case.truth[j];
        [
            (e.0 - t.frequency_hz) / t.frequency_hz,
            (e.2 - t.damping_ratio) / t.damping_ratio,
        ]
    };
    let pairs = if verdict == "holds" && !case.hysteretic {
        sw.matched
            .iter()
            .filter_map(|&(j, r)| {
                let other = so.matched.iter().find(|(jj, _)| *jj == j)?;
                Some((rel(&ew[r], j), rel(&eo[other.1], j)))
            })
            .collect()
    } else {
        Vec::new()
    };
    let mut line = format!(
        "seed {seed}: {}\n  refinement: {verdict}{}; found {}/{} (without: {}/{}), spurious {:?} (without: {:?}); {:.1} s against {:.1} s",
        case.description,
        match &with.refined {
            Some(r) => format!(" (misfit {:.3})", r.misfit),
            None => String::new(),
        },
        sw.found,
        sw.in_band,
        so.found,
        so.in_band,
        sw.spurious,
        so.spurious,
        (t1 - t0).as_secs_f64(),
        (t2 - t1).as_secs_f64(),
    );
    if a.verbose {
        line.push_str(&format!("\n{with}"));
    }
    Ok(Row {
        seed,
        line,
        verdict,
        pairs,
        with: sw,
        without: so,
        seconds: ((t1 - t0).as_secs_f64(), (t2 - t1).as_secs_f64()),
    })
}

/// RMS of the `k`-th relative error of the refined (`refined`) or SSI's answer over the
/// records `rows` (indices into `all`).
fn rms(all: &[&Vec<([f64; 2], [f64; 2])>], rows: &[usize], k: usize, refined: bool) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for &i in rows {
        for (r, o) in all[i] {
            let v = if refined { r[k] } else { o[k] };
            s += v * v;
            n += 1;
        }
    }
    (s / n.max(1) as f64).sqrt()
}

/// The ratio of RMS errors (refined over SSI's) for error `k`, and its 95 % interval from
/// 2000 resamplings of the records (a fixed generator: the interval is repeatable).
fn ratio_with_interval(all: &[&Vec<([f64; 2], [f64; 2])>], k: usize) -> (f64, f64, f64) {
    use rand::{RngExt, SeedableRng};
    let idx: Vec<usize> = (0..all.len()).collect();
    let ratio = |rows: &[usize]| rms(all, rows, k, true) / rms(all, rows, k, false);
    let point = ratio(&idx);
    let mut rng = rand::rngs::StdRng::seed_from_u64(0x5EED);
    let mut boots: Vec<f64> = (0..2000)
        .map(|_| {
            let rows: Vec<usize> = (0..all.len())
                .map(|_| rng.random_range(0..all.len()))
                .collect();
            ratio(&rows)
        })
        .filter(|v| v.is_finite())
        .collect();
    boots.sort_by(f64::total_cmp);
    let q = |p: f64| boots[((boots.len() - 1) as f64 * p).round() as usize];
    (point, q(0.025), q(0.975))
}

/// The study: one block per record, then the verdicts, the gains where it holds, the
/// answers' scores with and without, and the time.
pub fn run(a: &RefineCorpusArgs) -> Result<(), String> {
    let seeds: Vec<u64> = (0..a.seeds)
        .map(|k| a.first_seed + k * a.seed_step)
        .collect();
    // One record at a time, each analysis using both cores, so that the times are each
    // analysis's own as a user would see it.
    let rows: Vec<Row> = seeds
        .iter()
        .map(|&s| analyse(s, a))
        .collect::<Result<_, _>>()?;
    let mut tally: Vec<(&str, usize)> = Vec::new();
    for r in &rows {
        println!("{}", r.line);
        match tally.iter_mut().find(|(v, _)| *v == r.verdict) {
            Some((_, n)) => *n += 1,
            None => tally.push((r.verdict, 1)),
        }
    }
    let counts: Vec<String> = tally.iter().map(|(v, n)| format!("{v} {n}")).collect();
    println!(
        "verdicts over {} records: {}",
        rows.len(),
        counts.join(", ")
    );
    let held: Vec<&Vec<([f64; 2], [f64; 2])>> = rows
        .iter()
        .filter(|r| !r.pairs.is_empty())
        .map(|r| &r.pairs)
        .collect();
    let modes: usize = held.iter().map(|p| p.len()).sum();
    if held.len() >= 2 {
        let (f, f_lo, f_hi) = ratio_with_interval(&held, 0);
        let (z, z_lo, z_hi) = ratio_with_interval(&held, 1);
        println!(
            "where it holds ({} linear records, {modes} modes found by both): RMS relative error refined / SSI's: frequency {f:.3} [{f_lo:.3}, {f_hi:.3}], damping {z:.3} [{z_lo:.3}, {z_hi:.3}] (refined {:.4} / {:.3}, SSI {:.4} / {:.3})",
            held.len(),
            rms(&held, &(0..held.len()).collect::<Vec<_>>(), 0, true),
            rms(&held, &(0..held.len()).collect::<Vec<_>>(), 1, true),
            rms(&held, &(0..held.len()).collect::<Vec<_>>(), 0, false),
            rms(&held, &(0..held.len()).collect::<Vec<_>>(), 1, false),
        );
        let held_scores: Vec<hyst_sim::corpus::Score> = rows
            .iter()
            .filter(|r| !r.pairs.is_empty())
            .map(|r| r.with.clone())
            .collect();
        println!(
            "  the refined answers there: {}",
            hyst_sim::corpus::Summary::of(&held_scores)
        );
    } else {
        println!(
            "where it holds: {} linear record(s), too few to compare",
            held.len()
        );
    }
    let with: Vec<_> = rows.iter().map(|r| r.with.clone()).collect();
    let without: Vec<_> = rows.iter().map(|r| r.without.clone()).collect();
    println!(
        "with the refinement:    {}",
        hyst_sim::corpus::Summary::of(&with)
    );
    println!(
        "without the refinement: {}",
        hyst_sim::corpus::Summary::of(&without)
    );
    let (tw, to): (f64, f64) = rows
        .iter()
        .fold((0.0, 0.0), |(a, b), r| (a + r.seconds.0, b + r.seconds.1));
    println!(
        "time: {tw:.1} s with the refinement, {to:.1} s without ({:.2}x); seeds {}..{}",
        tw / to,
        rows.first().map_or(0, |r| r.seed),
        rows.last().map_or(0, |r| r.seed)
    );
    Ok(())
}
