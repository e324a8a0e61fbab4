//! `hyst levels`: one Bouc-Wen model from records at several force levels.

use std::path::PathBuf;

use clap::Args;

use super::*;

#[derive(Args, Debug)]
pub(crate) struct LevelsArgs {
    /// Records with the measured output (CSV with a header), two or more, one per force level.
    #[arg(long, num_args = 2.., required = true)]
    pub(crate) data: Vec<PathBuf>,
    /// Sampling rate of the records (Hz).
    #[arg(long)]
    pub(crate) fs: f64,
    /// Mass of the oscillator (kg), assumed known.
    #[arg(long)]
    pub(crate) mass: f64,
    /// Column of the output (displacement).
    #[arg(long, default_value = "y")]
    pub(crate) output_column: String,
    /// Column of the input force (only used by --validate files).
    #[arg(long, default_value = "u")]
    pub(crate) input_column: String,
    /// Skip this many leading rows of each --data record (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    pub(crate) skip: usize,
    /// Validation records (input and output columns): the model is simulated with the input
    /// and compared with the output.
    #[arg(long, num_args = 1..)]
    pub(crate) validate: Vec<PathBuf>,
    /// The validation records are one steady-state period of a periodic force (else the
    /// model is simulated from rest).
    #[arg(long)]
    pub(crate) periodic: bool,
    /// The --data records are each one steady-state period of a periodic force (as `hyst
    /// simulate --periodic` writes them); --by-simulation then simulates them so. Without
    /// it they are taken as measured: simulated from rest, the warm-up dropped.
    #[arg(long)]
    pub(crate) data_periodic: bool,
    /// Write the results as JSON here.
    #[arg(long)]
    pub(crate) json: Option<PathBuf>,
    /// Write figures (SVG) into this folder: each level's k∞ and Ω beside the model's.
    #[arg(long)]
    pub(crate) svg_dir: Option<PathBuf>,
    /// Then fit the model by simulation (indirect inference): the Bouc-Wen model whose
    /// simulated records give the same Zener fits as the records. Removes the Gaussian
    /// closure's bias; each iteration simulates every level six times (for three records of 2¹⁷
    /// samples on two cores: about 7 s, 30 s with --data-periodic).
    #[arg(long)]
    pub(crate) by_simulation: bool,
    /// Fit the Bouc-Wen exponent ν too (three or more --data records), instead of ν = 1;
    /// with --by-simulation, there as well (slower: ν < 1 or > 1 costs a power per step).
    #[arg(long)]
    pub(crate) fit_exponent: bool,
}

/// One line of a Bouc-Wen model: c, k, α, βγ, βδ with their standard errors `se`, βγ and
/// βδ in their unit (they multiply |z|^ν: 1/m only at ν = 1), then `tail` in parentheses;
/// and a line with ν ± `nu_se` when ν was fitted.
pub(crate) fn print_bouc_wen(
    label: &str,
    o: &hyst::model::Oscillator,
    bw: &hyst::model::BoucWen,
    se: &[f64; 5],
    tail: &str,
    nu_se: Option<f64>,
) {
    let unit = if bw.nu == 1.0 {
        "1/m".to_string()
    } else {
        format!("1/(m·N^{:.3})", bw.nu - 1.0)
    };
    println!(
        "{label}: c {:.2} ± {:.2} N s/m, k {:.0} ± {:.0} N/m, α {:.0} ± {:.0} N/m, βγ {:.1} ± {:.1} {unit}, βδ {:.1} ± {:.1} {unit} ({tail})",
        o.damping,
        se[0],
        o.stiffness,
        se[1],
        bw.alpha,
        se[2],
        bw.beta_gamma(),
        se[3],
        bw.beta_delta(),
        se[4],
    );
    if let Some(nu_se) = nu_se {
        println!("  exponent ν {:.3} ± {nu_se:.3}", bw.nu);
    }
}

pub(crate) fn run(a: &LevelsArgs) -> Result<(), Error> {
    use hyst::ident::{self, IdentOptions};
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    if !(a.mass.is_finite() && a.mass > 0.0) {
        return Err(fail(format!("--mass must be > 0 kg, got {}", a.mass)));
    }
    let opts = IdentOptions {
        mass: a.mass,
        ..IdentOptions::default()
    };
    let mut fits = Vec::with_capacity(a.data.len());
    let mut sigma_x = Vec::with_capacity(a.data.len());
    let mut lengths = Vec::with_capacity(a.data.len());
    let mut rows = Vec::new();
    for path in &a.data {
        let name = path.display().to_string();
        let y = output_after_skip(path, &a.output_column, a.skip)?;
        let id = ident::identify(&y, fs, &opts).map_err(|e| fail(format!("{name}: {e}")))?;
        sigma_x.push(id.prepared.sigma_x);
        lengths.push(y.len());
        let f = id.zener_spectrum.ok_or_else(|| {
            fail(format!(
                "{name}: no Zener spectral fit, so no level for the model ({}); each record must \
                 be the response to a broadband random force",
                id.poles.notes.join("; ")
            ))
        })?;
        println!(
            "{name}: c {:.2} ± {:.2} N s/m, k {:.0} ± {:.0} N/m, k∞ {:.0} ± {:.0} N/m, Ω {:.2} ± {:.2} rad/s, force density {:.4} N² s",
            f.c, f.se[0], f.k, f.se[1], f.k_inf, f.se[2], f.omega, f.se[3], f.force_density
        );
        rows.push(
            json!({"file": name, "c": f.c, "k": f.k, "k_inf": f.k_inf, "omega": f.omega,
            "se": f.se, "force_density": f.force_density, "misfit": f.misfit}),
        );
        fits.push(f);
    }
    let refs: Vec<_> = fits.iter().collect();
    let model = if a.fit_exponent {
        ident::levels::bouc_wen_and_exponent_from_levels(&refs)
    } else {
        ident::levels::bouc_wen_from_levels(&refs)
    }
    .map_err(|e| fail(e.to_string()))?;
    let o = &model.oscillator;
    let hyst::model::Restoring::BoucWen(bw) = &o.restoring else {
        return Err(fail("the levels' model has no Bouc-Wen element"));
    };
    let se = model.se;
    print_bouc_wen(
        "Bouc-Wen of all levels",
        o,
        bw,
        &se,
        &format!("χ² per degree of freedom {:.2}", model.chi2_per_dof),
        a.fit_exponent.then_some(model.nu_se),
    );
    let values = [bw.alpha, bw.beta_gamma(), bw.beta_delta()];
    if values
        .iter()
        .zip(&se[2..])
        .any(|(v, s)| s.partial_cmp(&v.abs()) != Some(std::cmp::Ordering::Less))
    {
        println!(
            "warning: the levels do not determine α, βγ and βδ (a standard error as large as \
             its value): their response levels are too close together; record levels further apart"
        );
    }
    // The model's own statistical linearization at each level's force density, beside the
    // Zener identified there: how well one element explains every level.
    let own: Vec<Option<hyst::model::ZenerParams>> = fits
        .iter()
        .map(|f| {
            hyst::linearize::statistical::equivalent_zener(
                o.mass,
                o.damping,
                o.stiffness,
                bw,
                f.force_density,
            )
            .ok()
            .map(|(z, _)| z)
        })
        .collect();
    let show = |v: Option<f64>, digits: usize| v.map_or("—".into(), |v| format!("{v:.digits$}"));
    for ((r, m), (f, z)) in rows
        .iter_mut()
        .zip(&model.moments)
        .zip(fits.iter().zip(&own))
    {
        r["sigma_v"] = json!(m.sigma_v);
        r["sigma_z"] = json!(m.sigma_z);
        r["rho"] = json!(m.rho);
        r["model_k_inf"] = json!(z.map(|z| z.k_inf));
        r["model_omega"] = json!(z.map(|z| z.omega));
        println!(
            "  {}: k∞ {:.0} ± {:.0} (model {}), Ω {:.2} ± {:.2} (model {})",
            r["file"].as_str().unwrap_or(""),
            f.k_inf,
            f.se[2],
            show(z.map(|z| z.k_inf), 0),
            f.omega,
            f.se[3],
            show(z.map(|z| z.omega), 2)
        );
    }
    if let Some(dir) = &a.svg_dir {
        use hyst::plot::{chart, colors};
        std::fs::create_dir_all(dir).map_err(|e| fail(format!("{}: {e}", dir.display())))?;
        let at = |v: &dyn Fn(usize) -> Option<f64>| -> Vec<(f64, f64)> {
            (0..fits.len())
                .filter_map(|i| v(i).map(|y| (sigma_x[i], y)))
                .collect()
        };
        for (j, file, title, yl) in [
            (
                2,
                "levels_kinf.svg",
                "Zener stiffness k∞ by level",
                "k∞ (N/m)",
            ),
            (
                3,
                "levels_omega.svg",
                "Corner frequency Ω by level",
                "Ω (rad/s)",
            ),
        ] {
            let value = |i: usize| if j == 2 { fits[i].k_inf } else { fits[i].omega };
            let model = |i: usize| own[i].map(|z| if j == 2 { z.k_inf } else { z.omega });
            chart(
                &dir.join(file),
                title,
                "σₓ of the record (m)",
                yl,
                &[
                    ("identified".into(), at(&|i| Some(value(i))), colors::BLUE),
                    (
                        "− SE".into(),
                        at(&|i| Some(value(i) - fits[i].se[j])),
                        colors::GREY,
                    ),
                    (
                        "+ SE".into(),
                        at(&|i| Some(value(i) + fits[i].se[j])),
                        colors::GREY,
                    ),
                    (
                        "the model's statistical linearization".into(),
                        at(&model),
                        colors::BLACK,
                    ),
                ],
            )
            .map_err(fail)?;
        }
    }
    let mut validation = Vec::new();
    let by_sim = if a.by_simulation {
        eprintln!("fitting by simulation…");
        let t0 = std::time::Instant::now();
        let report = |it: usize, cost: f64| {
            eprintln!(
                "  iteration {it}: weighted sum of squares {cost:.2} ({:.1} s)",
                t0.elapsed().as_secs_f64()
            )
        };
        let s = ident::levels::bouc_wen_by_simulation(
            &refs,
            &lengths,
            o,
            &ident::levels::SimulationOptions {
                periodic: a.data_periodic,
                fit_exponent: a.fit_exponent,
                ..Default::default()
            },
            &report,
        )
        .map_err(|e| fail(format!("fit by simulation: {e}")))?;
        let hyst::model::Restoring::BoucWen(b) = &s.oscillator.restoring else {
            return Err(fail("the fit by simulation has no Bouc-Wen element"));
        };
        print_bouc_wen(
            "Bouc-Wen by simulation",
            &s.oscillator,
            b,
            &s.se,
            &format!(
                "whitened residual RMS {:.2}, {} iterations",
                s.residual_rms, s.iterations
            ),
            a.fit_exponent.then_some(s.nu_se),
        );
        Some(s)
    } else {
        None
    };
    for v in &a.validate {
        let name = v.display().to_string();
        let t = read_csv(v)?;
        let (u, yv) = (t.column(&a.input_column)?, t.column(&a.output_column)?);
        let r =
            ident::validate(o, u, yv, fs, a.periodic).map_err(|e| fail(format!("{name}: {e}")))?;
        println!("validation on {name}: ε = {:.3} %", 100.0 * r.epsilon);
        let mut row = json!({"file": name, "epsilon": r.epsilon, "rms": r.rms});
        if let Some(s) = &by_sim {
            let r = ident::validate(&s.oscillator, u, yv, fs, a.periodic)
                .map_err(|e| fail(format!("{name}: {e}")))?;
            println!(
                "validation on {name}, model by simulation: ε = {:.3} %",
                100.0 * r.epsilon
            );
            row["epsilon_by_simulation"] = json!(r.epsilon);
        }
        validation.push(row);
    }
    if let Some(path) = &a.json {
        let doc = json!({
            "levels": rows,
            "model": osc_json(o),
            "se": {"c": se[0], "k": se[1], "alpha": se[2], "beta_gamma": se[3], "beta_delta": se[4],
                   "nu": a.fit_exponent.then_some(model.nu_se)},
            "chi2_per_dof": model.chi2_per_dof,
            "by_simulation": by_sim.as_ref().map(|s| json!({
                "model": osc_json(&s.oscillator),
                "se": {"c": s.se[0], "k": s.se[1], "alpha": s.se[2], "beta_gamma": s.se[3], "beta_delta": s.se[4],
                       "nu": a.fit_exponent.then_some(s.nu_se)},
                "residual_rms": s.residual_rms,
                "iterations": s.iterations,
                "simulated": s.simulated,
            })),
            "validation": validation,
        });
        std::fs::write(path, serde_json::to_string_pretty(&doc)?)
            .map_err(|e| fail(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}
