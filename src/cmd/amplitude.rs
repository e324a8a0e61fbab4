//! `hyst amplitude`: each mode's frequency and damping ratio against its amplitude.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::ssi::{ChannelArgs, channels, flag_error};
use super::{Error, fail, steps_bar};
use hyst::ident::amplitude::{self, AmplitudeMethod, AmplitudeOptions, Quantity};

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum QuantityArg {
    /// Displacement.
    Displacement,
    /// Velocity.
    Velocity,
    /// Acceleration.
    Acceleration,
}

impl From<QuantityArg> for Quantity {
    fn from(q: QuantityArg) -> Self {
        match q {
            QuantityArg::Displacement => Quantity::Displacement,
            QuantityArg::Velocity => Quantity::Velocity,
            QuantityArg::Acceleration => Quantity::Acceleration,
        }
    }
}

#[derive(Clone, Copy, ValueEnum, PartialEq, Eq, Debug)]
pub(crate) enum MethodArg {
    /// Random decrement conditioned on the envelope of the analytic signal (every sample a
    /// trigger, turned to zero phase): unbiased for a linear mode at every level.
    Envelope,
    /// Classical random decrement at the response's extrema, a damped cosine fitted.
    Extrema,
}

#[derive(Args, Debug)]
pub(crate) struct AmplitudeArgs {
    /// The record, or several of one structure (force levels, a campaign): each analysed
    /// alike, the same modes followed in each, and each mode's change pooled over all their
    /// points. Formats as `hyst ssi --input`.
    #[arg(long, num_args = 1.., required = true)]
    pub(crate) input: Vec<PathBuf>,
    #[command(flatten)]
    pub(crate) record: ChannelArgs,
    /// Modes to follow, by frequency (Hz), comma-separated: the identified mode nearest each
    /// (within 5 %); default every mode `hyst ssi` reports.
    #[arg(
        help_heading = "Amplitude curves",
        long,
        value_delimiter = ',',
        value_name = "HZ"
    )]
    pub(crate) modes: Vec<f64>,
    /// What the channels measure.
    /// [default: displacement; beside a --model, what its records read]
    #[arg(help_heading = "Amplitude curves", long, value_enum)]
    pub(crate) measured: Option<QuantityArg>,
    /// Report amplitudes as this quantity (converted at each point's frequency); default: as
    /// measured.
    #[arg(help_heading = "Amplitude curves", long, value_enum)]
    pub(crate) amplitude_of: Option<QuantityArg>,
    /// Amplitude bands (points per curve), of equal trigger counts.
    #[arg(help_heading = "Amplitude curves", long, default_value_t = AmplitudeOptions::default().levels)]
    pub(crate) levels: usize,
    /// Cycles of each band's decay fitted: fewer follow the amplitude more closely, more
    /// lower the scatter (below 3, the band-pass biases the damping of a linear mode low).
    #[arg(help_heading = "Amplitude curves", long, default_value_t = AmplitudeOptions::default().cycles)]
    pub(crate) cycles: f64,
    /// Stretches of the record the jackknife leaves out in turn (standard errors).
    #[arg(help_heading = "Amplitude curves", long, default_value_t = AmplitudeOptions::default().groups)]
    pub(crate) groups: usize,
    /// Fewest triggers a point needs.
    #[arg(help_heading = "Amplitude curves", long, default_value_t = AmplitudeOptions::default().min_triggers)]
    pub(crate) min_triggers: usize,
    /// Band-pass half-width, as a share of each mode's frequency; default 0.3, or half the
    /// relative distance to the nearest other mode.
    #[arg(help_heading = "Amplitude curves", long, value_name = "SHARE")]
    pub(crate) band: Option<f64>,
    /// How each band's decay is found.
    #[arg(
        help_heading = "Amplitude curves",
        long,
        value_enum,
        default_value = "envelope"
    )]
    pub(crate) method: MethodArg,
    /// Samples per period of a periodic excitation (a multisine): the record's whole periods
    /// are averaged into one, read as circular (without it a periodic record's stretches
    /// repeat one another and the standard errors come out too small).
    #[arg(help_heading = "Amplitude curves", long, value_name = "SAMPLES")]
    pub(crate) period: Option<usize>,
    /// Each channel's floor, 1 = the lowest above the ground, one channel per floor: each
    /// point's amplitude is then also given across every storey (its drift), beside each
    /// channel's.
    #[arg(help_heading = "Amplitude curves", long, value_delimiter = ',')]
    pub(crate) floors: Option<Vec<usize>>,
    /// A structure fitted to these records (`hyst levels --masses ... --json`, the same
    /// records in the same order): its own records at each level are simulated, analysed
    /// alike, drawn beside the measured curves, and each measured point is set against the
    /// model's curve at its amplitude.
    #[arg(help_heading = "Amplitude curves", long, value_name = "STOREY_FIT")]
    pub(crate) model: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) ssi: hyst::settings::SsiSettings,
    /// Write the curves as JSON here (optional: the report is printed either way).
    #[arg(help_heading = "Output files", long)]
    pub(crate) json: Option<PathBuf>,
    /// Draw each mode's frequency and damping against amplitude, with error bars (SVG).
    #[arg(help_heading = "Output files", long)]
    pub(crate) svg: Option<PathBuf>,
}

/// An option out of range in the words of the command line: named by its flag.
fn flag_of(e: amplitude::AmplitudeError) -> Error {
    use amplitude::AmplitudeError;
    match e {
        AmplitudeError::BadOption {
            option,
            value,
            needs,
        } => fail(format!(
            "--{} {value} is out of range: {needs}",
            option.name()
        )),
        e => fail(e.to_string()),
    }
}

impl AmplitudeArgs {
    fn options(&self) -> Result<AmplitudeOptions, Error> {
        let mut o = AmplitudeOptions::default();
        o.floors = match &self.floors {
            None => None,
            Some(f) => Some(
                f.iter()
                    .map(|&v| {
                        v.checked_sub(1)
                            .ok_or_else(|| fail("--floors: floors count from 1, got 0"))
                    })
                    .collect::<Result<_, _>>()?,
            ),
        };
        o.levels = self.levels;
        o.cycles = self.cycles;
        o.groups = self.groups;
        o.min_triggers = self.min_triggers;
        o.band = self.band;
        o.measured = self.measured.unwrap_or(QuantityArg::Displacement).into();
        o.report_as = self.amplitude_of.map(Into::into);
        o.period = self.period;
        o.method = match self.method {
            MethodArg::Envelope => AmplitudeMethod::Envelope,
            MethodArg::Extrema => AmplitudeMethod::Extrema,
        };
        Ok(o)
    }
}

/// What a record read holds: its channels, samples and rate.
#[derive(Clone, Copy)]
struct RecordShape {
    channels: usize,
    samples: usize,
    fs: f64,
}

/// One record's analysis, following `modes` (every reported mode when empty), and the
/// record's shape.
fn analyse(
    a: &AmplitudeArgs,
    input: &std::path::Path,
    analysis: &hyst::covssi::AnalysisOptions,
    opts: &AmplitudeOptions,
    (modes, fit): (&[f64], Option<(&hyst::ident::storeys::StoreyFit, usize)>),
) -> Result<(amplitude::AmplitudeAnalysis, RecordShape), Error> {
    let ch = channels(input, &a.record)?;
    let shape = RecordShape {
        channels: ch.data.len(),
        samples: ch.data.first().map_or(0, Vec::len),
        fs: ch.fs,
    };
    if let Some((fit, level)) = fit {
        // Beside a model, the record must be the fit's level, read as it read them, before
        // it is analysed: else its curves would be set beside another level's (issue 77:
        // reversed records, another quantity, permuted floors were compared as if matched).
        use hyst::ident::storeys::{check_level, level_statistics};
        let b = &fit.building;
        if shape.channels != b.sensors.len() || (shape.fs - b.fs).abs() > 1e-9 * shape.fs {
            return Err(fail(format!(
                "{}: {} channels at {} Hz; the --model was fitted to {} at {} Hz",
                input.display(),
                shape.channels,
                shape.fs,
                b.sensors.len(),
                b.fs
            )));
        }
        level_statistics(fit, &ch.data)
            .and_then(|s| check_level(fit, level, &s))
            .map_err(|e| fail(format!("{} beside --model: {e}", input.display())))?;
    }
    let views: Vec<&[f64]> = ch.data.iter().map(|c| c.as_slice()).collect();
    amplitude::amplitude_analysis(&views, ch.fs, analysis, opts, modes)
        .map(|r| (r, shape))
        .map_err(|e| match e {
            hyst::ident::IdentError::Ssi(e) => flag_error(input, &a.ssi, e, &ch.names, ch.fs),
            e => fail(format!("{}: {e}", input.display())),
        })
}

pub(crate) fn run(a: &AmplitudeArgs) -> Result<(), Error> {
    // Settings that are wrong whatever the record, before any is read.
    let analysis = super::ssi::analysis_of(&a.ssi)?;
    let mut opts = a.options()?;
    let fit = match &a.model {
        None => None,
        Some(path) => Some(read_fit(a, path)?),
    };
    if let Some((_, read)) = &fit {
        // Beside a model the records read what its records read.
        opts.measured = (*read).into();
    }
    opts.check().map_err(flag_of)?;
    let fit = fit.map(|(f, _)| f);
    let name = |p: &PathBuf| p.display().to_string();
    let mut shapes = Vec::with_capacity(a.input.len());
    let bar = steps_bar();
    bar.set_length(a.input.len() as u64);
    let campaign = amplitude::amplitude_campaign(a.input.len(), &a.modes, |i, follow| {
        let input = &a.input[i];
        bar.set_position(i as u64);
        bar.set_message(format!(
            "{}: its modes, then their amplitude bands",
            input.display()
        ));
        let beside = fit.as_ref().map(|f| (f, i));
        let (analysis, shape) = analyse(a, input, &analysis, &opts, (follow, beside))?;
        shapes.push(shape);
        Ok::<_, Error>((name(input), analysis))
    });
    bar.finish_and_clear();
    let mut campaign = campaign?;
    if let Some(fit) = &fit {
        return beside_model(a, campaign, (fit, &shapes), (&analysis, &opts));
    }
    if campaign.records.len() == 1 {
        let (record, analysis) = campaign.records.remove(0);
        let report = hyst::report::FileReport::new(record.clone(), analysis);
        print!("{report}");
        if let Some(json) = &a.json {
            report.write_json(json)?;
        }
        return draw(a, &[(record, &report.report.curves)]);
    }
    print!("{campaign}");
    if let Some(json) = &a.json {
        hyst::report::write_json(&campaign, json)?;
    }
    let curves: Vec<(String, &amplitude::AmplitudeReport)> = campaign
        .records
        .iter()
        .map(|(n, r)| (n.clone(), &r.curves))
        .collect();
    draw(a, &curves)
}

/// The storey fit of `--model`, checked against the records before any is analysed.
fn read_fit(
    a: &AmplitudeArgs,
    path: &std::path::Path,
) -> Result<(hyst::ident::storeys::StoreyFit, QuantityArg), Error> {
    let fit = super::read_storey_fit("--model", path)?;
    // What the records read, and where the channels are, are the fit's: a --measured or
    // --floors that says otherwise would compare other quantities or floors as if matched.
    use hyst::ident::storeys::Quantity as Read;
    let read = match fit.building.reading {
        Read::Acceleration => QuantityArg::Acceleration,
        Read::Velocity => QuantityArg::Velocity,
        Read::Displacement => QuantityArg::Displacement,
    };
    if let Some(m) = a.measured.filter(|m| *m != read) {
        return Err(fail(format!(
            "--measured {}: --model {} was fitted to records of {}; the records beside it read the same (leave --measured out)",
            flag_value(m),
            path.display(),
            flag_value(read)
        )));
    }
    if let Some(floors) = &a.floors {
        let sensors: Vec<usize> = fit.building.sensors.iter().map(|f| f + 1).collect();
        if *floors != sensors {
            return Err(fail(format!(
                "--floors {floors:?}: --model {} has its channels on floors {sensors:?}; the records beside it are read so (leave --floors out)",
                path.display()
            )));
        }
    }
    if a.input.len() != fit.force_densities.len() {
        return Err(fail(format!(
            "--model {} was fitted to {} records; give the same {} as --input, in the same order ({} given)",
            path.display(),
            fit.force_densities.len(),
            fit.force_densities.len(),
            a.input.len()
        )));
    }
    Ok((fit, read))
}

/// A `--measured` value as the flag spells it (clap's own name for it).
fn flag_value(q: QuantityArg) -> String {
    q.to_possible_value()
        .map_or_else(|| format!("{q:?}"), |v| v.get_name().to_string())
}

/// The measured campaign beside the fitted model's own records analysed alike.
fn beside_model(
    a: &AmplitudeArgs,
    measured: amplitude::AmplitudeCampaign,
    (fit, shapes): (&hyst::ident::storeys::StoreyFit, &[RecordShape]),
    (analysis, opts): (&hyst::covssi::AnalysisOptions, &AmplitudeOptions),
) -> Result<(), Error> {
    let lengths: Vec<usize> = shapes.iter().map(|r| r.samples).collect();
    let bar = steps_bar();
    bar.set_message("the fitted model's records");
    let records = hyst::ident::storeys::model_records(fit, &lengths, 9500)
        .map_err(|e| fail(e.to_string()))?;
    let followed: Vec<f64> = measured
        .records
        .first()
        .map(|r| {
            r.1.curves
                .modes
                .iter()
                .map(|m| m.mode.frequency_hz)
                .collect()
        })
        .unwrap_or_default();
    bar.set_length(records.len() as u64);
    let model = amplitude::amplitude_campaign(records.len(), &followed, |i, follow| {
        bar.set_position(i as u64);
        bar.set_message(format!("the model's record {}: its amplitude bands", i + 1));
        let views: Vec<&[f64]> = records[i].iter().map(Vec::as_slice).collect();
        let r = amplitude::amplitude_analysis(&views, fit.building.fs, analysis, opts, follow)
            .map_err(|e| fail(format!("the model's record {}: {e}", i + 1)))?;
        let name = format!("{}{}", a.input[i].display(), hyst::figures::MODEL_SUFFIX);
        Ok::<_, Error>((name, r))
    });
    bar.finish_and_clear();
    let both = amplitude::CurvesBesideModel::new(measured, model?);
    print!("{both}");
    if let Some(json) = &a.json {
        hyst::report::write_json(&both, json)?;
    }
    let curves: Vec<(String, &amplitude::AmplitudeReport)> = both
        .measured
        .records
        .iter()
        .chain(&both.model.records)
        .map(|(n, r)| (n.clone(), &r.curves))
        .collect();
    draw(a, &curves)
}

/// The figure, when asked for.
fn draw(a: &AmplitudeArgs, curves: &[(String, &amplitude::AmplitudeReport)]) -> Result<(), Error> {
    if let Some(svg) = &a.svg {
        let title = if curves.len() == 1 {
            format!("Amplitude dependence: {}", curves[0].0)
        } else {
            format!("Amplitude dependence: {} records", curves.len())
        };
        std::fs::write(svg, hyst::figures::amplitude_svg(curves, &title))
            .map_err(|e| fail(format!("{}: {e}", svg.display())))?;
    }
    Ok(())
}
