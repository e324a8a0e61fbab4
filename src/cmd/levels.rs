//! `hyst levels`: one Bouc-Wen model from records at several force levels.

use std::path::PathBuf;

use clap::Args;

use super::{Error, check_fs, fail, output_after_skip, read_record, show, steps_bar};

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
    #[command(flatten)]
    pub(crate) columns: super::args::RecordColumns,
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
    #[arg(help_heading = "Output files", long)]
    pub(crate) json: Option<PathBuf>,
    /// Write figures (SVG) into this folder: each level's k∞ and Ω beside the model's.
    #[arg(help_heading = "Output files", long)]
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

pub(crate) fn run(a: &LevelsArgs) -> Result<(), Error> {
    use hyst::ident::levels::{self, LevelsOptions, SimulationOptions};
    let fs = check_fs(a.fs)?;
    if !(a.mass.is_finite() && a.mass > 0.0) {
        return Err(fail(format!("--mass must be > 0 kg, got {}", a.mass)));
    }
    let data: Vec<(String, Vec<f64>)> = a
        .data
        .iter()
        .map(|p| {
            let (y, _) = output_after_skip(p, &a.columns.output_column, a.columns.skip, Some(fs))?;
            Ok((p.display().to_string(), y))
        })
        .collect::<Result<_, Error>>()?;
    let records: Vec<(String, &[f64])> = data.iter().map(|(n, y)| (n.clone(), &y[..])).collect();
    let mut validations = Vec::new();
    for v in &a.validate {
        let t = read_record(v)?;
        validations.push(hyst::ident::ValidationRecord {
            name: v.display().to_string(),
            u: t.column(&a.columns.input_column)?.to_vec(),
            y: t.column(&a.columns.output_column)?.to_vec(),
            periodic: a.periodic,
        });
    }
    let simulation = a.by_simulation.then(|| SimulationOptions {
        periodic: a.data_periodic,
        ..SimulationOptions::default()
    });
    let opts = LevelsOptions::with_mass(a.mass)
        .fit_exponent(a.fit_exponent)
        .by_simulation(simulation);
    let bar = steps_bar();
    let report = levels::levels_report(&records, fs, &opts, &validations, &|p| show(&bar, p));
    bar.finish_and_clear();
    let report = report.map_err(|e| fail(e.to_string()))?;
    print!("{report}");
    if let Some(dir) = &a.svg_dir {
        hyst::figures::levels_figures(dir, &report).map_err(fail)?;
    }
    if let Some(path) = &a.json {
        hyst::report::write_json(&report, path)?;
    }
    Ok(())
}
