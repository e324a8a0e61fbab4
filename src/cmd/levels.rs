//! `hyst levels`: one Bouc-Wen model from records at several force levels.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

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
    #[arg(long, required_unless_present = "masses", conflicts_with = "masses")]
    pub(crate) mass: Option<f64>,
    /// A shear structure instead of one oscillator: its floor masses (kg), the lowest first.
    /// The records' --channels are then read at once, and the storey holding a hysteretic
    /// element is located (or none), fitted by simulation with standard errors.
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) masses: Vec<f64>,
    /// With --masses: the records' columns, one per sensor (default: every column but the
    /// time column).
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) channels: Option<Vec<String>>,
    /// With --masses: each channel's floor, 1 = the lowest (default: 1, 2, … in order).
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) floors: Option<Vec<usize>>,
    /// With --masses: what the channels read [default: acceleration].
    #[arg(long, value_enum, help_heading = "A structure of several floors")]
    pub(crate) quantity: Option<QuantityArg>,
    /// With --masses: the floors the force acts on, 1 = the lowest (default: every floor).
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) load_floors: Option<Vec<usize>>,
    /// With --masses: levels not recorded to predict, each a force this many times the
    /// loudest record's RMS (e.g. 2 for a storm twice as strong): each storey's RMS drift and
    /// each mode's band, with their standard errors.
    #[arg(
        long,
        value_delimiter = ',',
        help_heading = "A structure of several floors"
    )]
    pub(crate) predict: Vec<f64>,
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

/// What the channels of a structure's records read.
#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum QuantityArg {
    /// Accelerations.
    Acceleration,
    /// Velocities.
    Velocity,
    /// Displacements.
    Displacement,
}

pub(crate) fn run(a: &LevelsArgs) -> Result<(), Error> {
    use hyst::ident::levels::{self, LevelsOptions, SimulationOptions};
    let fs = check_fs(a.fs)?;
    // One file given as two levels would be fitted as two records that agree exactly.
    for (i, p) in a.data.iter().enumerate() {
        let same = |q: &std::path::PathBuf| {
            q == p
                || matches!(
                    (std::fs::canonicalize(q), std::fs::canonicalize(p)),
                    (Ok(x), Ok(y)) if x == y
                )
        };
        if let Some(j) = a.data[..i].iter().position(same) {
            return Err(fail(format!(
                "--data {}: given as level {} and level {}; each level is its own record",
                p.display(),
                j + 1,
                i + 1
            )));
        }
    }
    let Some(mass) = a.mass else {
        return run_storeys(a, fs);
    };
    if a.channels.is_some()
        || a.floors.is_some()
        || a.quantity.is_some()
        || a.load_floors.is_some()
        || !a.predict.is_empty()
    {
        return Err(fail(
            "--channels, --floors, --quantity, --load-floors and --predict describe a structure of several floors: give its --masses instead of --mass",
        ));
    }
    if !(mass.is_finite() && mass > 0.0) {
        return Err(fail(format!("--mass must be > 0 kg, got {mass}")));
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
    let opts = LevelsOptions::with_mass(mass)
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

/// `hyst levels --masses`: the storey fit of a shear structure.
fn run_storeys(a: &LevelsArgs, fs: f64) -> Result<(), Error> {
    use hyst::ident::storeys::{Quantity, StoreyOptions, StoreyStructure, fit_storeys};
    let one_based = |flag: &str, v: &[usize]| -> Result<Vec<usize>, Error> {
        v.iter()
            .map(|&f| {
                f.checked_sub(1)
                    .ok_or_else(|| fail(format!("{flag}: floors count from 1, got 0")))
            })
            .collect()
    };
    if !a.validate.is_empty()
        || a.svg_dir.is_some()
        || a.by_simulation
        || a.fit_exponent
        || a.periodic
        || a.data_periodic
    {
        return Err(fail(
            "--masses fits a structure by simulation of random forces: --validate, --periodic, --data-periodic, --svg-dir, --by-simulation and --fit-exponent are the one-oscillator route's",
        ));
    }
    if let Some(given) = &a.channels
        && let Some((i, c)) = given
            .iter()
            .enumerate()
            .find(|(i, c)| given[..*i].contains(c))
    {
        return Err(fail(format!(
            "--channels names `{c}` twice (entries {} and {}): each channel is one sensor on its own floor",
            given.iter().position(|g| g == c).map_or(0, |j| j + 1),
            i + 1
        )));
    }
    let mut records = Vec::new();
    let mut names: Option<Vec<String>> = None;
    for p in &a.data {
        let t = read_record(p)?;
        // The file's own rate or time column, when it has one, must agree with --fs.
        t.rate(Some(fs))?;
        let cols = super::channel_names(&t, a.channels.as_deref(), &[])?;
        let skip = a.columns.skip;
        let channels = cols
            .iter()
            .map(|c| {
                let v = t.column(c)?;
                if skip >= v.len() {
                    return Err(fail(format!(
                        "--skip {skip} leaves none of the {} rows of {}",
                        v.len(),
                        p.display()
                    )));
                }
                Ok(v[skip..].to_vec())
            })
            .collect::<Result<Vec<_>, Error>>()?;
        records.push(channels);
        names.get_or_insert(cols);
    }
    let channels = names.map_or(0, |n| n.len());
    let sensors = match &a.floors {
        Some(f) => one_based("--floors", f)?,
        None => (0..channels).collect(),
    };
    let quantity = match a.quantity.unwrap_or(QuantityArg::Acceleration) {
        QuantityArg::Acceleration => Quantity::Acceleration,
        QuantityArg::Velocity => Quantity::Velocity,
        QuantityArg::Displacement => Quantity::Displacement,
    };
    let structure = StoreyStructure::new(a.masses.clone(), sensors, quantity, fs);
    let mut opts = StoreyOptions::default();
    if let Some(l) = &a.load_floors {
        opts.load_floors = Some(one_based("--load-floors", l)?);
    }
    opts.predict = a.predict.clone();
    let bar = steps_bar();
    let fit = fit_storeys(&records, &structure, &opts, &|p| {
        bar.set_message(format!("{} [iteration {}]", p.stage, p.iteration));
    });
    bar.finish_and_clear();
    let fit = fit.map_err(|e| fail(e.to_string()))?;
    print!("{fit}");
    if let Some(path) = &a.json {
        hyst::report::write_json(&fit, path)?;
    }
    if fit.agreement.verdict == hyst::ident::storeys::FitVerdict::Far {
        // Written, so that what went wrong can be read; not a result a script takes.
        return Err(fail(
            "the storey fit did not reach its records (a mode band of the model lies outside the record's): nothing is located; the report above says where",
        ));
    }
    Ok(())
}
