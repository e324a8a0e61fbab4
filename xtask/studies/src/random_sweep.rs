//! `cargo xtask sweep-random`: the amplitude study under a random force.
//!
//! For each level |F| (RMS, N): the benchmark system driven by a periodic white force of that
//! RMS (exactly white up to the Nyquist frequency: hyst-sim interpolates a periodic input
//! band-limited), one steady-state period of `samples` samples at 750 Hz with the benchmark's
//! measurement noise (7.4e-6 m); identified from the output only, twice: with c from the
//! Zener spectral fit (step 3b, the default) and with the paper's low-damping cluster; the
//! Zener and the Bouc-Wen model (the paper's mapping at A = σₓ) of each validated with the
//! input on one steady-state period (8192 samples) of a fresh realization. Levels run in
//! parallel; each level's seeds derive from (seed, level index).
//!
//! Then, across the levels: the statistical linearization
//! ([`hyst_linearize::statistical`]) of the true benchmark predicts each level's Zener
//! (k∞, Ω), against which the identified ones are compared; and one Bouc-Wen model is
//! identified from all levels' Zener fits ([`levels_model`]) and validated at every level.

use std::path::Path;

use hyst_ident::levels::LevelsBoucWen;
use hyst_ident::zener_spectrum::ZenerSpectralFit;
use hyst_ident::{DampingGuess, IdentOptions, Linearization};
use hyst_linearize::statistical;
use hyst_model::{Oscillator, ZenerParams};
use hyst_sim::SimOptions;
use hyst_sim::excitation::{add_noise, white_noise};

use crate::sweep::{SweepOptions, eps_of};

const FS: f64 = 750.0;
const NOISE: f64 = 7.4e-6;
const VALIDATION_SAMPLES: usize = 8192;

/// What one level gives.
#[derive(Debug, Clone, PartialEq)]
pub struct RandomLevel {
    pub level_n: f64,
    pub sigma_x: f64,
    /// The Zener spectral fit: (c, k, k∞, Ω) and their standard errors.
    pub fit: [f64; 4],
    pub fit_se: [f64; 4],
    /// The most likely c when the fit was held at c = 0 (else NaN), and its standard error.
    pub c_unconstrained: f64,
    pub c_unconstrained_se: f64,
    /// The fitted force density over the true one, rms²/fs, and its standard error.
    pub force_ratio: f64,
    pub force_ratio_se: f64,
    pub misfit: f64,
    /// 1 when the pipeline took c from the fit, 0 when it kept the cluster's guess.
    pub fit_used: f64,
    /// c from the paper's low-damping cluster.
    pub c_cluster: f64,
    /// ε on the validation period: Zener and Bouc-Wen (A = σₓ), with c from the fit and
    /// from the cluster.
    pub eps_zener_fit: f64,
    pub eps_bouc_wen_fit: f64,
    pub eps_zener_cluster: f64,
    pub eps_bouc_wen_cluster: f64,
    /// The fitted force density q (N² s).
    pub force_density: f64,
    /// (σ_v, σ_z, ρ) of the fitted Zener oscillator under q.
    pub moments: [f64; 3],
    /// (k∞, Ω) that the statistical linearization of the true benchmark predicts under the
    /// true force density.
    pub predicted: [f64; 2],
    /// The σₓ it predicts (the record's is `sigma_x`).
    pub predicted_sigma_x: f64,
    /// ε of the one Bouc-Wen model identified from all levels ([`levels_model`]).
    pub eps_bouc_wen_levels: f64,
    /// ε of the Bouc-Wen model of all levels by simulation ([`levels_models`]).
    pub eps_bouc_wen_simulated: f64,
    /// (c, k, k∞, Ω) fitted to that model's simulated record at this level.
    pub simulated_fit: [f64; 4],
    /// That model (c, k, α, βγ, βδ), its residual RMS, iterations and the five standard
    /// errors (the same at every level).
    pub simulated_model: [f64; 12],
    /// The spectral fit itself.
    pub spectral: ZenerSpectralFit,
}

/// The validation record of level `i`: input and noise-free output.
fn validation(level: f64, i: usize, seed: u64) -> Result<(Vec<f64>, Vec<f64>), String> {
    let s0 = seed.wrapping_mul(1000).wrapping_add(10 * i as u64);
    let uv = white_noise(VALIDATION_SAMPLES, level, s0 + 3).map_err(|e| e.to_string())?;
    let yv = steady(&uv)?;
    Ok((uv, yv))
}

fn steady(u: &[f64]) -> Result<Vec<f64>, String> {
    hyst_sim::steady_state_period(
        &Oscillator::benchmark(),
        u,
        FS,
        &SimOptions::default(),
        1e-10,
        200,
    )
    .map(|s| s.y)
    .map_err(|e| e.to_string())
}

/// Run one level (index `i` for the seeds).
pub fn run_level(level: f64, i: usize, samples: usize, seed: u64) -> Result<RandomLevel, String> {
    let s0 = seed.wrapping_mul(1000).wrapping_add(10 * i as u64);
    let u = white_noise(samples, level, s0 + 1).map_err(|e| e.to_string())?;
    let mut y = steady(&u)?;
    add_noise(&mut y, NOISE, s0 + 2).map_err(|e| e.to_string())?;
    let (uv, yv) = validation(level, i, seed)?;
    let ident = |damping_guess| {
        let o = IdentOptions {
            linearization: Linearization::Paper,
            damping_guess,
            ..IdentOptions::default()
        };
        hyst_ident::identify(&y, FS, &o).map_err(|e| format!("{level} N: {e}"))
    };
    let id = ident(DampingGuess::ZenerSpectrum)?;
    let paper = ident(DampingGuess::LowDampingCluster)?;
    let f = id
        .zener_spectrum
        .as_ref()
        .ok_or_else(|| format!("{level} N: no Zener spectral fit: {:?}", id.poles.notes))?;
    let q = level * level / FS;
    let eps = |m: Option<&Oscillator>| eps_of(m, &uv, &yv).0;
    let [cu, cu_se] = f.unconstrained_c.unwrap_or([f64::NAN; 2]);
    let fit_used = id.poles.c_source.starts_with("Zener spectral fit");
    let zener = ZenerParams {
        k_inf: f.k_inf,
        omega: f.omega,
    };
    let mo = statistical::zener_response_moments(f.mass, f.c, f.k, &zener, f.force_density)
        .map_err(|e| format!("{level} N: moments of the fitted model: {e}"))?;
    let truth = Oscillator::benchmark();
    let hyst_model::Restoring::BoucWen(bw) = &truth.restoring else {
        return Err("the benchmark has no Bouc-Wen element".into());
    };
    let (pz, pm) = statistical::equivalent_zener(truth.mass, truth.damping, truth.stiffness, bw, q)
        .map_err(|e| format!("{level} N: statistical linearization of the benchmark: {e}"))?;
    Ok(RandomLevel {
        level_n: level,
        sigma_x: id.prepared.sigma_x,
        fit: [f.c, f.k, f.k_inf, f.omega],
        fit_se: f.se,
        c_unconstrained: cu,
        c_unconstrained_se: cu_se,
        force_ratio: f.force_density / q,
        force_ratio_se: f.force_density_se / q,
        misfit: f.misfit,
        fit_used: if fit_used { 1.0 } else { 0.0 },
        c_cluster: paper.poles.c,
        eps_zener_fit: eps(id.models.zener.as_ref()),
        eps_bouc_wen_fit: eps(id.models.bouc_wen_mapped.as_ref()),
        eps_zener_cluster: eps(paper.models.zener.as_ref()),
        eps_bouc_wen_cluster: eps(paper.models.bouc_wen_mapped.as_ref()),
        force_density: f.force_density,
        moments: [mo.sigma_v, mo.sigma_z, mo.rho],
        predicted: [pz.k_inf, pz.omega],
        predicted_sigma_x: pm.sigma_x,
        eps_bouc_wen_levels: f64::NAN,
        eps_bouc_wen_simulated: f64::NAN,
        simulated_fit: [f64::NAN; 4],
        simulated_model: [f64::NAN; 12],
        spectral: f.clone(),
    })
}

/// The Bouc-Wen models of all levels ([`hyst_ident::levels::fit_levels`], as `hyst levels`
/// fits them) from the levels' Zener spectral fits: by the statistical linearization, and by
/// simulation (the records simulated as one steady-state period each, as they were made)
/// when `samples` is given; `progress` shows the latter's iterations as a bar.
pub fn levels_models(
    results: &[RandomLevel],
    samples: Option<usize>,
    progress: bool,
) -> Result<hyst_ident::levels::LevelsModels, String> {
    use hyst_ident::levels::{LevelsOptions, SimulationOptions, fit_levels};
    let refs: Vec<&ZenerSpectralFit> = results.iter().map(|r| &r.spectral).collect();
    let lengths = vec![samples.unwrap_or(0); refs.len()];
    let simulation = samples.map(|_| SimulationOptions {
        periodic: true,
        ..SimulationOptions::default()
    });
    // A bar of the fit's iterations (as many as it may take), hidden when not asked or when
    // stderr is not a terminal.
    let bar = match (&simulation, progress) {
        (Some(s), true) => indicatif::ProgressBar::new(s.max_iterations as u64),
        _ => indicatif::ProgressBar::hidden(),
    };
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "levels' fit by simulation {bar:30} {pos}/{len} iterations {elapsed} {msg}",
    ) {
        bar.set_style(style);
    }
    let report = |it: usize, cost: f64| {
        bar.set_position(it as u64);
        bar.set_message(format!("(weighted sum of squares {cost:.2})"));
    };
    let fit = fit_levels(
        &refs,
        &lengths,
        &LevelsOptions::default().by_simulation(simulation),
        &report,
    )
    .map_err(|e| e.to_string());
    bar.finish_and_clear();
    fit
}

/// The one Bouc-Wen model of all levels by the statistical linearization.
pub fn levels_model(results: &[RandomLevel]) -> Result<LevelsBoucWen, String> {
    levels_models(results, None, false).map(|m| m.statistical)
}

/// Run all levels in parallel, then the levels' Bouc-Wen models (by the statistical
/// linearization and by simulation), each validated at each level; returns the results in
/// level order and the wall time (s).
pub fn run(opts: &SweepOptions) -> crate::sweep::Outcome<RandomLevel> {
    use rayon::prelude::*;
    let (mut results, secs) = crate::sweep::run_levels(opts, "random sweep", run_level)?;
    let t = std::time::Instant::now();
    if results.len() >= 2 {
        let models = levels_models(&results, Some(opts.samples), opts.progress)?;
        let model = models.statistical.oscillator;
        let sim = models
            .by_simulation
            .ok_or("the levels' fit by simulation was asked for")?;
        let eps: Vec<(f64, f64)> = results
            .par_iter()
            .enumerate()
            .map(|(i, r)| {
                let (uv, yv) = validation(r.level_n, i, opts.seed)?;
                Ok((
                    eps_of(Some(&model), &uv, &yv).0,
                    eps_of(Some(&sim.oscillator), &uv, &yv).0,
                ))
            })
            .collect::<Result<_, String>>()?;
        let o = &sim.oscillator;
        let hyst_model::Restoring::BoucWen(bw) = o.restoring else {
            return Err("the simulation fit gave no Bouc-Wen element".into());
        };
        let summary = [
            o.damping,
            o.stiffness,
            bw.alpha,
            bw.beta_gamma(),
            bw.beta_delta(),
            sim.residual_rms,
            sim.iterations as f64,
            sim.se[0],
            sim.se[1],
            sim.se[2],
            sim.se[3],
            sim.se[4],
        ];
        for ((r, (e, es)), s) in results.iter_mut().zip(eps).zip(&sim.simulated) {
            r.eps_bouc_wen_levels = e;
            r.eps_bouc_wen_simulated = es;
            r.simulated_fit = *s;
            r.simulated_model = summary;
        }
    }
    Ok((results, secs + t.elapsed().as_secs_f64()))
}

const COLUMNS: [&str; 34] = [
    "level_n",
    "sigma_x",
    "c",
    "k",
    "k_inf",
    "omega_c",
    "c_se",
    "k_se",
    "k_inf_se",
    "omega_c_se",
    "c_unconstrained",
    "c_unconstrained_se",
    "force_ratio",
    "force_ratio_se",
    "misfit",
    "fit_used",
    "c_cluster",
    "eps_zener_fit",
    "eps_bouc_wen_fit",
    "eps_zener_cluster",
    "eps_bouc_wen_cluster",
    "force_density",
    "sigma_v",
    "sigma_z",
    "rho",
    "k_inf_predicted",
    "omega_c_predicted",
    "eps_bouc_wen_levels",
    "sigma_x_predicted",
    "eps_bouc_wen_simulated",
    "c_simulated",
    "k_simulated",
    "k_inf_simulated",
    "omega_c_simulated",
];

fn row(r: &RandomLevel) -> Vec<f64> {
    let mut v = vec![r.level_n, r.sigma_x];
    v.extend(r.fit);
    v.extend(r.fit_se);
    v.extend([
        r.c_unconstrained,
        r.c_unconstrained_se,
        r.force_ratio,
        r.force_ratio_se,
        r.misfit,
        r.fit_used,
        r.c_cluster,
        r.eps_zener_fit,
        r.eps_bouc_wen_fit,
        r.eps_zener_cluster,
        r.eps_bouc_wen_cluster,
        r.force_density,
    ]);
    v.extend(r.moments);
    v.extend(r.predicted);
    v.push(r.eps_bouc_wen_levels);
    v.push(r.predicted_sigma_x);
    v.push(r.eps_bouc_wen_simulated);
    v.extend(r.simulated_fit);
    v
}

/// The results as CSV (ε as fractions).
pub fn csv(results: &[RandomLevel]) -> String {
    crate::sweep::csv_table(&COLUMNS, results.iter().map(row))
}

/// The results tables as Markdown.
pub fn markdown(results: &[RandomLevel], seconds: f64, samples: usize) -> String {
    let mut s = format!(
        "# Random-force sweep results\n\n{} levels × {} samples, {:.2} s wall time.\n\n\
         ## The Zener spectral fit (truth of the benchmark: c = 10, k = 50000)\n\n\
         | \\|F\\| (N) | σₓ (m) | c (N s/m) | k (N/m) | k∞ (N/m) | Ω (rad/s) | q / (rms²/fs) | misfit | c, paper's cluster |\n\
         |---|---|---|---|---|---|---|---|---|\n",
        results.len(),
        samples,
        seconds
    );
    for r in results {
        let c = if r.c_unconstrained.is_nan() {
            format!("{:.2} ± {:.2}", r.fit[0], r.fit_se[0])
        } else {
            format!(
                "0 (held; most likely {:.2} ± {:.2})",
                r.c_unconstrained, r.c_unconstrained_se
            )
        };
        let used = if r.fit_used == 1.0 { "" } else { " (not used)" };
        s += &format!(
            "| {} | {:.3e} | {c}{used} | {:.0} ± {:.0} | {:.0} ± {:.0} | {:.2} ± {:.2} | {:.3} ± {:.3} | {:.3} | {:.2} |\n",
            r.level_n,
            r.sigma_x,
            r.fit[1],
            r.fit_se[1],
            r.fit[2],
            r.fit_se[2],
            r.fit[3],
            r.fit_se[3],
            r.force_ratio,
            r.force_ratio_se,
            r.misfit,
            r.c_cluster
        );
    }
    s += &validation_table(results);
    s += &linearization_table(results);
    s += &levels_section(results);
    s += &simulation_section(results);
    s
}

/// Each level's validation errors, with c from the fit and from the paper's cluster.
fn validation_table(results: &[RandomLevel]) -> String {
    let p = |v: f64| format!("{:.2} %", 100.0 * v);
    let mut s = String::new();
    s += "\n## Validation error ε (one steady-state period of a fresh white force)\n\n\
          | \\|F\\| (N) | ε Zener, c from the fit | ε Zener, cluster's c | ε Bouc-Wen, c from the fit | ε Bouc-Wen, cluster's c |\n\
          |---|---|---|---|---|\n";
    for r in results {
        s += &format!(
            "| {} | {} | {} | {} | {} |\n",
            r.level_n,
            p(r.eps_zener_fit),
            p(r.eps_zener_cluster),
            p(r.eps_bouc_wen_fit),
            p(r.eps_bouc_wen_cluster)
        );
    }
    s
}

/// Each level's Zener beside the statistical linearization of the benchmark.
fn linearization_table(results: &[RandomLevel]) -> String {
    let mut s = String::new();
    s += "\n## The identified Zener against the statistical linearization of the benchmark\n\n\
          Predicted: the fixed point of the Gaussian linearization of the true benchmark under the \
          true force density. z: (identified − predicted) / standard error.\n\n\
          | \\|F\\| (N) | k∞ identified | k∞ predicted | z | Ω identified | Ω predicted | z | σₓ simulated / predicted | σ_v (m/s) | σ_z (N) | ρ |\n\
          |---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in results {
        let z = |j: usize| (r.fit[2 + j] - r.predicted[j]) / r.fit_se[2 + j];
        s += &format!(
            "| {} | {:.0} ± {:.0} | {:.0} | {:+.2} | {:.2} ± {:.2} | {:.2} | {:+.2} | {:.3} | {:.4} | {:.2} | {:.3} |\n",
            r.level_n,
            r.fit[2],
            r.fit_se[2],
            r.predicted[0],
            z(0),
            r.fit[3],
            r.fit_se[3],
            r.predicted[1],
            z(1),
            r.sigma_x / r.predicted_sigma_x,
            r.moments[0],
            r.moments[1],
            r.moments[2]
        );
    }
    s
}

/// The one Bouc-Wen model of all levels and its error at each level.
fn levels_section(results: &[RandomLevel]) -> String {
    let p = |v: f64| format!("{:.2} %", 100.0 * v);
    let mut s = String::new();
    match levels_model(results) {
        Ok(fit) => {
            let model = fit.oscillator;
            let hyst_model::Restoring::BoucWen(bw) = model.restoring else {
                unreachable!("the levels' model is a Bouc-Wen oscillator")
            };
            s += &format!(
                "\n## One Bouc-Wen model from all levels\n\n\
                 (α, βγ, βδ) by weighted least squares from the levels' Zener fits; c and k the \
                 levels' weighted means. Benchmark: c = 10, k = 50000, α = 50000, βγ = 800, βδ = −1100.\n\n\
                 c = {:.2} ± {:.2} N s/m, k = {:.0} ± {:.0} N/m, α = {:.0} ± {:.0} N/m, \
                 βγ = {:.1} ± {:.1} 1/m, βδ = {:.1} ± {:.1} 1/m; χ² per degree of freedom {:.2}.\n\n\
                 | \\|F\\| (N) | ε Bouc-Wen, all levels | ε Bouc-Wen, this level (A = σₓ) | ε Zener, this level |\n\
                 |---|---|---|---|\n",
                model.damping,
                fit.se[0],
                model.stiffness,
                fit.se[1],
                bw.alpha,
                fit.se[2],
                bw.beta_gamma(),
                fit.se[3],
                bw.beta * bw.delta,
                fit.se[4],
                fit.chi2_per_dof
            );
            for r in results {
                s += &format!(
                    "| {} | {} | {} | {} |\n",
                    r.level_n,
                    p(r.eps_bouc_wen_levels),
                    p(r.eps_bouc_wen_fit),
                    p(r.eps_zener_fit)
                );
            }
        }
        Err(e) => s += &format!("\n## One Bouc-Wen model from all levels\n\nnone: {e}\n"),
    }
    s
}

/// The model of all levels by simulation, and what each level's simulated record gives.
fn simulation_section(results: &[RandomLevel]) -> String {
    let p = |v: f64| format!("{:.2} %", 100.0 * v);
    let mut s = String::new();
    if let Some(m) = results.first().map(|r| r.simulated_model) {
        s += &format!(
            "\n## One Bouc-Wen model from all levels, by simulation\n\n\
             (c, k, α, βγ, βδ) whose simulated records give the levels' Zener fits (indirect \
             inference, started from the model above): c = {:.2} ± {:.2} N s/m, k = {:.0} ± {:.0} N/m, \
             α = {:.0} ± {:.0} N/m, βγ = {:.1} ± {:.1} 1/m, βδ = {:.1} ± {:.1} 1/m; whitened residual RMS {:.2} (about √2 when each level is explained within the noise of both records), {} iterations.\n\n\
             | \\|F\\| (N) | ε by simulation | ε by statistical linearization | c measured / simulated | k | k∞ | Ω |\n\
             |---|---|---|---|---|---|---|\n",
            m[0], m[7], m[1], m[8], m[2], m[9], m[3], m[10], m[4], m[11], m[5], m[6]
        );
        for r in results {
            let f = &r.simulated_fit;
            s += &format!(
                "| {} | {} | {} | {:.2} / {:.2} | {:.0} / {:.0} | {:.0} / {:.0} | {:.2} / {:.2} |\n",
                r.level_n,
                p(r.eps_bouc_wen_simulated),
                p(r.eps_bouc_wen_levels),
                r.fit[0],
                f[0],
                r.fit[1],
                f[1],
                r.fit[2],
                f[2],
                r.fit[3],
                f[3]
            );
        }
    }
    s
}

/// Write results.csv, results.md and the figures into `out`.
pub fn write(
    out: &Path,
    results: &[RandomLevel],
    seconds: f64,
    samples: usize,
) -> Result<(), String> {
    use hyst::plot::chart;
    use hyst::plot::colors::{
        BLACK as black, BLUE as blue, GREEN as green, GREY as grey, ORANGE as orange, RED as red,
    };
    crate::sweep::write_tables(out, csv(results), markdown(results, seconds, samples))?;
    let by = |f: &dyn Fn(&RandomLevel) -> f64| -> Vec<(f64, f64)> {
        results.iter().map(|r| (r.level_n, f(r))).collect()
    };
    chart(
        &out.join("fig_random_epsilon.svg"),
        "Validation error under a white force, by model and source of c",
        "|F| (N)",
        "ε",
        &[
            (
                "Zener, c from the fit".into(),
                by(&|r| r.eps_zener_fit),
                blue,
            ),
            (
                "Zener, cluster's c".into(),
                by(&|r| r.eps_zener_cluster),
                grey,
            ),
            (
                "Bouc-Wen (A = σₓ), c from the fit".into(),
                by(&|r| r.eps_bouc_wen_fit),
                red,
            ),
            (
                "Bouc-Wen (A = σₓ), cluster's c".into(),
                by(&|r| r.eps_bouc_wen_cluster),
                black,
            ),
            (
                "Bouc-Wen, one model of all levels".into(),
                by(&|r| r.eps_bouc_wen_levels),
                orange,
            ),
            (
                "Bouc-Wen, one model of all levels by simulation".into(),
                by(&|r| r.eps_bouc_wen_simulated),
                green,
            ),
        ],
    )?;
    for (i, file, title, yl, truth) in [
        (
            0,
            "fig_random_c.svg",
            "Viscous damping c",
            "c (N s/m)",
            Some(10.0),
        ),
        (1, "fig_random_k.svg", "Stiffness k", "k (N/m)", Some(5e4)),
        (
            2,
            "fig_random_kinf.svg",
            "Zener stiffness k∞",
            "k∞ (N/m)",
            None,
        ),
        (
            3,
            "fig_random_omega.svg",
            "Corner frequency Ω",
            "Ω (rad/s)",
            None,
        ),
    ] {
        let mut series = vec![
            ("spectral fit".into(), by(&|r| r.fit[i]), blue),
            ("− SE".into(), by(&|r| r.fit[i] - r.fit_se[i]), grey),
            ("+ SE".into(), by(&|r| r.fit[i] + r.fit_se[i]), grey),
        ];
        if i == 0 {
            series.push(("paper's cluster".into(), by(&|r| r.c_cluster), red));
            series.push((
                "most likely c, where held at 0".into(),
                by(&|r| r.c_unconstrained),
                orange,
            ));
        }
        if i >= 2 {
            series.push((
                "statistical linearization of the benchmark".into(),
                by(&|r| r.predicted[i - 2]),
                black,
            ));
        }
        if let Some(t) = truth {
            series.push(("benchmark".into(), by(&|_| t), black));
        }
        chart(
            &out.join(file),
            &format!("{title} of the Zener fitted to the spectrum, under a white force"),
            "|F| (N)",
            yl,
            &series,
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two levels on short records: the same seed gives the same table bit for bit on one
    /// thread and on several; the files are written; the fitted force density is the drive's
    /// within four standard errors (the fit never sees the force: the mass sets the scale).
    #[test]
    fn two_levels_reproducible_and_the_force_level_recovered() {
        let (r1, dir) = crate::sweep::reproducible("hyst-random-sweep", 1 << 14, run, csv);
        write(&dir, &r1, 0.0, 1 << 14).unwrap();
        let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
        assert_eq!(text.lines().count(), 3);
        assert_eq!(text.lines().next().unwrap().split(',').count(), 34);
        for r in &r1 {
            // Wired: the levels' model was built and validated at each level. (On these
            // short records and two levels it is no better than each level's mapping; the
            // claim is made on the full sweep, docs/results.md.)
            assert!(
                r.eps_bouc_wen_levels > 0.0 && r.eps_bouc_wen_levels < 0.5,
                "{r:?}"
            );
            let z = (r.force_ratio - 1.0) / r.force_ratio_se;
            assert!(z.abs() < 4.0, "{r:?}");
            assert!(r.eps_zener_fit > 0.0 && r.eps_zener_fit < 0.2, "{r:?}");
        }
        assert!(r1[1].sigma_x > r1[0].sigma_x);
        assert!(dir.join("fig_random_epsilon.svg").is_file());
        assert!(dir.join("fig_random_c.svg").is_file());
    }
}
