//! `hyst ssi`: output-only modal analysis by covariance-driven SSI and its refinement.

use std::path::PathBuf;

use clap::Args;

use super::*;

#[derive(Args, Debug)]
pub(crate) struct SsiArgs {
    /// Input CSV file with a header line.
    #[arg(long)]
    pub(crate) input: PathBuf,
    /// Sampling rate of the file (Hz).
    #[arg(long)]
    pub(crate) fs: f64,
    /// Channels to analyse, comma-separated; default: every column except `t` and `time` (with
    /// a warning for columns named like a force: `u`, `force`, `input`, `excitation`, `load`).
    #[arg(long, value_delimiter = ',')]
    pub(crate) columns: Option<Vec<String>>,
    /// Decimate by this factor first (MATLAB-style FIR decimation).
    #[arg(long, default_value_t = 1)]
    pub(crate) decimate: usize,
    /// Skip this many leading rows (e.g. a start-up transient).
    #[arg(long, default_value_t = 0)]
    pub(crate) skip: usize,
    /// Block rows of the Toeplitz matrix (lags up to 2·N−1).
    #[arg(long, default_value_t = 20)]
    pub(crate) block_rows: usize,
    /// Instead of --block-rows: as many block rows as make the largest lag cover this many
    /// seconds (after --decimate).
    #[arg(
        long,
        value_name = "SECONDS",
        conflicts_with_all = ["block_rows", "lag_periods"]
    )]
    pub(crate) lag_seconds: Option<f64>,
    /// Instead of --block-rows: as many block rows as make the largest lag cover COUNT periods
    /// of HZ, e.g. `--lag-periods 10 1.5` for ten periods of a 1.5 Hz mode (the paper's
    /// choice: ten periods of the dominant mode).
    #[arg(
        long,
        num_args = 2,
        value_names = ["COUNT", "HZ"],
        conflicts_with = "block_rows"
    )]
    pub(crate) lag_periods: Option<Vec<f64>>,
    /// Largest model order (default: the Toeplitz rank, at most 40).
    #[arg(long)]
    pub(crate) max_order: Option<usize>,
    /// Model order step.
    #[arg(long, default_value_t = 1)]
    pub(crate) order_step: usize,
    /// Stabilization threshold on the relative frequency change.
    #[arg(long, default_value_t = 0.01)]
    pub(crate) df: f64,
    /// Stabilization threshold on the relative damping change.
    #[arg(long, default_value_t = 0.05)]
    pub(crate) dzeta: f64,
    /// Stabilization threshold on 1 − MAC (several channels).
    #[arg(long, default_value_t = 0.02)]
    pub(crate) dmac: f64,
    /// Stabilization threshold of eq. (31) for real poles.
    #[arg(long, default_value_t = 1.5)]
    pub(crate) dreal: f64,
    /// Reference channels (0-based indices among --columns), comma-separated; default: all.
    #[arg(long, value_delimiter = ',')]
    pub(crate) references: Option<Vec<usize>>,
    /// Write the modes, real poles and per-order poles as JSON here.
    #[arg(long)]
    pub(crate) json: PathBuf,
    /// Draw the stabilization diagram as SVG here.
    #[arg(long)]
    pub(crate) svg: Option<PathBuf>,
    /// Skip the maximum-likelihood refinement of the modes and real poles (on by default: it
    /// fits them to the whole record, gives each a standard error, and drops those the record
    /// does not support).
    #[arg(long)]
    pub(crate) no_refine: bool,
    /// Refine with each channel's likelihood alone, not the joint likelihood of all channels
    /// (which uses their cross-spectra; on by default for 2 to 4 channels, and above 4 through 4
    /// combinations of them, band by band when there are more than 4 modes).
    #[arg(long)]
    pub(crate) no_joint: bool,
}

pub(crate) fn c64(v: hyst::covssi::Complex64) -> serde_json::Value {
    serde_json::json!([v.re, v.im])
}

pub(crate) fn run(a: &SsiArgs) -> Result<(), Error> {
    use hyst::covssi::{self, BlockRows, PoleStatus, Rejection, SsiOptions, StabilityCriteria};
    use serde_json::json;
    let fs = check_fs(a.fs)?;
    if a.decimate == 0 {
        return Err(fail("--decimate must be at least 1, got 0"));
    }
    let t = read_csv(&a.input)?;
    let names = channel_names(&t, a.columns.as_deref(), &[]);
    if a.columns.is_none() {
        warn_on_force_like(&names);
    }
    if let Some(n) = hyst::io::repeated(&names) {
        return Err(fail(format!(
            "--columns names `{n}` twice: each channel once"
        )));
    }
    if a.skip >= t.len() {
        return Err(fail(format!(
            "--skip {} leaves no rows of the {} in {}",
            a.skip,
            t.len(),
            a.input.display()
        )));
    }
    let mut channels = Vec::new();
    for n in &names {
        let c = &t.column(n)?[a.skip..];
        channels.push(hyst::sim::resample::decimate(c, a.decimate));
    }
    let fs_used = fs / a.decimate as f64;
    let views: Vec<&[f64]> = channels.iter().map(|c| c.as_slice()).collect();
    let block_rows = match (a.lag_seconds, a.lag_periods.as_deref()) {
        (Some(t), _) => BlockRows::Seconds(t),
        (None, Some(&[count, frequency_hz])) => BlockRows::Periods {
            count,
            frequency_hz,
        },
        _ => BlockRows::Count(a.block_rows),
    };
    let opts = SsiOptions {
        block_rows,
        max_order: a.max_order,
        order_step: a.order_step,
        criteria: StabilityCriteria {
            frequency: a.df,
            damping: a.dzeta,
            mac: a.dmac,
            real: a.dreal,
        },
        references: a.references.clone(),
        ..SsiOptions::default()
    };
    // Errors of covssi name the file and the columns they came from; an option out of
    // range is named by the flag that set it.
    let lag_too_short = |flag: &str, rows: f64| {
        fail(format!(
            "{flag} gives {rows} block row(s) at {fs_used} Hz; SSI needs at least 2: give a longer lag"
        ))
    };
    let context = |e: covssi::SsiError| {
        if let covssi::SsiError::InvalidOption { option, value } = &e {
            use covssi::SsiOption;
            let flag = match option {
                // A lag given as a time is too short for the rate: say what it gave.
                SsiOption::BlockRows => match block_rows {
                    BlockRows::Count(_) => Some(("--block-rows", "at least 2")),
                    BlockRows::Seconds(_) => return lag_too_short("--lag-seconds", *value),
                    BlockRows::Periods { .. } => return lag_too_short("--lag-periods", *value),
                },
                SsiOption::BlockRowsSeconds => Some(("--lag-seconds", "positive and finite")),
                SsiOption::BlockRowsPeriodsCount => {
                    Some(("--lag-periods COUNT", "positive and finite"))
                }
                SsiOption::BlockRowsPeriodsFrequency => {
                    Some(("--lag-periods HZ", "positive and finite"))
                }
                SsiOption::ReferenceOutOfRange => {
                    return fail(format!(
                        "--references {value} is out of range: {} channel(s), numbered from 0",
                        names.len()
                    ));
                }
                SsiOption::ReferenceRepeated => {
                    return fail(format!("--references names channel {value} twice"));
                }
                SsiOption::MaxOrder => Some(("--max-order", "at least 1")),
                SsiOption::OrderStep => Some(("--order-step", "at least 1")),
                SsiOption::CriteriaFrequency => Some(("--df", "positive and finite")),
                SsiOption::CriteriaDamping => Some(("--dzeta", "positive and finite")),
                SsiOption::CriteriaMac => Some(("--dmac", "positive and finite")),
                SsiOption::CriteriaReal => Some(("--dreal", "positive and finite")),
                _ => None,
            };
            if let Some((flag, needed)) = flag {
                return fail(format!("{flag} must be {needed}, got {value}"));
            }
        }
        // An error about the record after decimation says so: "too short" or "constant"
        // may be the decimation's doing, not the file's.
        let decimated = if a.decimate > 1 {
            format!(
                ", decimated by {} to {} of {} rows",
                a.decimate,
                views.first().map_or(0, |c| c.len()),
                t.len() - a.skip
            )
        } else {
            String::new()
        };
        fail(format!(
            "{}: columns {}{decimated}: {e}",
            a.input.display(),
            names.join(",")
        ))
    };
    let res = covssi::identify(&views, fs_used, &opts).map_err(context)?;
    let modes: Vec<_> = res
        .modes
        .iter()
        .map(|m| {
            json!({
                "frequency_hz": m.frequency_hz,
                "damping_ratio": m.damping_ratio,
                "frequency_std_hz": m.frequency_std_hz,
                "damping_std": m.damping_std,
                "poles": m.members.len(),
                "members": m.members,
                "shape": m.shape.iter().map(|v| c64(*v)).collect::<Vec<_>>(),
                "shape_std": m.shape_std,
                "mpc": covssi::mpc(&m.shape),
                "lambda": c64(m.lambda),
            })
        })
        .collect();
    let real: Vec<_> = res
        .real_poles
        .iter()
        .map(|r| json!({"lambda": r.lambda, "lambda_std": r.lambda_std, "poles": r.members.len()}))
        .collect();
    let orders: Vec<_> = res
        .diagram
        .orders
        .iter()
        .map(|o| {
            let poles: Vec<_> = o
                .poles
                .iter()
                .map(|p| {
                    let why = match p.status {
                        PoleStatus::Rejected(Rejection::Frequency { change, threshold })
                        | PoleStatus::Rejected(Rejection::RealPole { change, threshold }) => {
                            json!({"change": change, "threshold": threshold})
                        }
                        PoleStatus::Rejected(Rejection::DampingAboveLimit { damping, limit }) => {
                            json!({"damping": damping, "limit": limit})
                        }
                        PoleStatus::Rejected(Rejection::Unstable { real_part }) => {
                            json!({"real_part": real_part})
                        }
                        _ => serde_json::Value::Null,
                    };
                    json!({
                        "lambda": c64(p.lambda),
                        "frequency_hz": p.frequency_hz,
                        "damping_ratio": p.damping_ratio,
                        "real": p.is_real,
                        "label": p.status.name(),
                        "why": why,
                        "d_frequency": p.d_frequency,
                        "d_damping": p.d_damping,
                        "d_mac": p.d_mac,
                        "d_real": p.d_real,
                    })
                })
                .collect();
            json!({"order": o.order, "poles": poles})
        })
        .collect();
    // The block rows first: given as a lag time or periods they are worked out here.
    let largest_lag = 2 * res.block_rows - 1;
    println!(
        "{} block rows: correlations up to lag {largest_lag} ({:.4} s at {fs_used} Hz)",
        res.block_rows,
        largest_lag as f64 / fs_used
    );
    // The SSI result first: the refinement can take a minute on many channels and modes.
    if !res.modes.is_empty() || !res.real_poles.is_empty() {
        println!("SSI (± is the spread over each cluster's poles, not a standard error):");
    }
    for m in &res.modes {
        // Members come by increasing order: the first and last give the span of orders.
        let span = match (m.members.first(), m.members.last()) {
            (Some(lo), Some(hi)) => format!(", orders {}–{}", lo.0, hi.0),
            _ => String::new(),
        };
        println!(
            "mode {:>9.4} ± {:.4} Hz  damping {:.4} ± {:.4}  ({} poles{span})",
            m.frequency_hz,
            m.frequency_std_hz,
            m.damping_ratio,
            m.damping_std,
            m.members.len()
        );
    }
    // Shapes say something with several channels only (a one-channel shape is a number).
    let mac: Vec<Vec<f64>> = res
        .modes
        .iter()
        .map(|a| {
            res.modes
                .iter()
                .map(|b| covssi::mac(&a.shape, &b.shape))
                .collect()
        })
        .collect();
    if views.len() > 1 && !res.modes.is_empty() {
        println!(
            "shapes (channels {}; magnitude∠phase, the largest entry 1; MPC 1 for a real mode):",
            names.join(", ")
        );
        for m in &res.modes {
            println!(
                "  {:>9.4} Hz  {}  MPC {:.3}",
                m.frequency_hz,
                hyst::shape_text(&m.shape, "  "),
                covssi::mpc(&m.shape)
            );
        }
        println!(
            "MAC between the modes (1 on the diagonal; near 0 where the channels tell two modes apart):"
        );
        for (m, row) in res.modes.iter().zip(&mac) {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:.3}")).collect();
            println!("  {:>9.4} Hz  {}", m.frequency_hz, cells.join("  "));
        }
    }
    for r in &res.real_poles {
        println!(
            "real pole {:.4} ± {:.4} rad/s ({} poles)",
            r.lambda,
            r.lambda_std,
            r.members.len()
        );
    }
    for n in &res.notes {
        println!("note: {n}");
    }
    let refined = if a.no_refine || (res.modes.is_empty() && res.real_poles.is_empty()) {
        None
    } else {
        eprintln!(
            "refining {} SSI mode(s) and {} real pole(s) by maximum likelihood on {} channel(s) of {} samples…",
            res.modes.len(),
            res.real_poles.len(),
            views.len(),
            views.first().map_or(0, |v| v.len())
        );
        Some(
            covssi::refine_with_real_poles(
                &views,
                fs_used,
                &res.modes,
                &res.real_poles,
                &covssi::RefineOptions {
                    joint: !a.no_joint,
                    ..Default::default()
                },
            )
            .map_err(context)?,
        )
    };
    let refined_json = refined.as_ref().map(|r| {
        json!({
            "modes": r.modes.iter().map(|m| json!({
                "frequency_hz": m.frequency_hz,
                "damping_ratio": m.damping_ratio,
                "frequency_se_hz": m.frequency_se_hz,
                "damping_se": m.damping_se,
                "lambda": c64(m.lambda),
                "shape": m.shape.as_ref().map(|v| v.iter().map(|c| c64(*c)).collect::<Vec<_>>()),
                "shape_se": m.shape_se,
                "mpc": m.shape.as_ref().map(|v| covssi::mpc(v)),
                "evidence": m.evidence,
                "ssi_mode": m.source,
            })).collect::<Vec<_>>(),
            "dropped": r.dropped.iter().map(|d| json!({
                "ssi_mode": d.source,
                "frequency_hz": d.frequency_hz,
                "evidence": d.evidence,
            })).collect::<Vec<_>>(),
            "penalty": r.penalty,
            "real_poles": r.real_poles.iter().map(|p| json!({
                "lambda": p.lambda,
                "lambda_se": p.lambda_se,
                "evidence": p.evidence,
                "ssi_real_pole": p.source,
            })).collect::<Vec<_>>(),
            "dropped_real_poles": r.dropped_real_poles.iter().map(|d| json!({
                "ssi_real_pole": d.source,
                "lambda": d.lambda,
                "evidence": d.evidence,
            })).collect::<Vec<_>>(),
            "real_pole_penalty": r.real_pole_penalty,
            "neg_log_likelihood": r.neg_log_likelihood,
            "misfit": r.misfit,
            "misfit_limit": covssi::refine::MISFIT_LIMIT,
            "frequencies": r.frequencies,
            "iterations": r.iterations,
            "joint": r.joint,
            "combinations": r.combinations,
            "bands": r.bands,
        })
    });
    let doc = json!({
        "input": a.input.display().to_string(),
        "channels": names,
        "fs_hz": fs_used,
        "block_rows": res.block_rows,
        "modes": modes,
        "mac": mac,
        "refined": refined_json,
        "real_poles": real,
        "notes": res.notes,
        "orders": orders,
    });
    std::fs::write(&a.json, serde_json::to_string_pretty(&doc)?)
        .map_err(|e| fail(format!("{}: {e}", a.json.display())))?;
    if let Some(svg) = &a.svg {
        let title = format!("Stabilization diagram: {}", a.input.display());
        std::fs::write(
            svg,
            covssi::svg::stabilization_svg(&res.diagram, None, &title),
        )
        .map_err(|e| fail(format!("{}: {e}", svg.display())))?;
    }
    if let Some(r) = &refined {
        println!(
            "refined by maximum likelihood ({} frequencies, {}; a mode needs evidence above {:.1}; ± one standard error):",
            r.frequencies,
            r.fitted_by(),
            r.penalty
        );
        // A standard error beyond 1e5 (a real pole far outside the band, say) in exponent
        // form: thirty digits say nothing more than that the record does not determine it.
        let se = |v: Option<f64>| {
            v.map_or("?".to_string(), |v| {
                if v.abs() < 1e5 {
                    format!("{v:.4}")
                } else {
                    format!("{v:.1e}")
                }
            })
        };
        for m in &r.modes {
            let ssi = m.source.map_or_else(
                || {
                    format!(
                        "no SSI mode within {:.0} % of its pole",
                        100.0 * covssi::refine::SAME_MODE_DISTANCE
                    )
                },
                |i| format!("SSI mode at {:.4} Hz", res.modes[i].frequency_hz),
            );
            println!(
                "mode {:>9.4} ± {} Hz  damping {:.4} ± {}  (evidence {:.0}; {ssi})",
                m.frequency_hz,
                se(m.frequency_se_hz),
                m.damping_ratio,
                se(m.damping_se),
                m.evidence,
            );
            if let (Some(shape), Some(sd)) = (&m.shape, &m.shape_se) {
                // Two digits whatever the size; the entry scaled to 1 has none.
                let se: Vec<String> = sd
                    .iter()
                    .map(|&v| {
                        if v == 0.0 {
                            "0".into()
                        } else {
                            format!("{v:.1e}")
                        }
                    })
                    .collect();
                println!(
                    "     shape {}  (standard errors {}; MPC {:.3})",
                    hyst::shape_text(shape, "  "),
                    se.join(", "),
                    covssi::mpc(shape)
                );
            }
        }
        for d in &r.dropped {
            println!(
                "dropped the SSI mode at {:.4} Hz: evidence {:.1}",
                d.frequency_hz, d.evidence
            );
        }
        for p in &r.real_poles {
            println!(
                "real pole {:.4} ± {} rad/s  (evidence {:.0}, above {:.1}; SSI real pole at {:.4})",
                p.lambda,
                se(p.lambda_se),
                p.evidence,
                r.real_pole_penalty,
                res.real_poles[p.source].lambda
            );
        }
        for d in &r.dropped_real_poles {
            println!(
                "dropped the SSI real pole at {:.4} rad/s: evidence {:.1}, below {:.1}",
                d.lambda, d.evidence, r.real_pole_penalty
            );
        }
        if r.misfit > covssi::refine::MISFIT_LIMIT {
            println!(
                "warning: the record does not follow the refinement's model (misfit {:.3} > {}): \
                 the excitation may not be broadband random (e.g. a multisine), or the record \
                 holds what the model lacks; trust the SSI modes above instead",
                r.misfit,
                covssi::refine::MISFIT_LIMIT
            );
        } else {
            println!("misfit {:.3} (the record follows the model)", r.misfit);
        }
    }
    Ok(())
}
