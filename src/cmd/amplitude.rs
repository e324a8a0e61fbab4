//! `hyst amplitude`: each mode's frequency and damping ratio against its amplitude.

use std::path::PathBuf;

use clap::{Args, ValueEnum};

use super::ssi::{ChannelArgs, SsiFlags, channels, flag_error};
use super::*;
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
    #[arg(
        help_heading = "Amplitude curves",
        long,
        value_enum,
        default_value = "displacement"
    )]
    pub(crate) measured: QuantityArg,
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
    #[command(flatten)]
    pub(crate) ssi: SsiFlags,
    /// Write the curves as JSON here (optional: the report is printed either way).
    #[arg(help_heading = "Output files", long)]
    pub(crate) json: Option<PathBuf>,
    /// Draw each mode's frequency and damping against amplitude, with error bars (SVG).
    #[arg(help_heading = "Output files", long)]
    pub(crate) svg: Option<PathBuf>,
}

impl AmplitudeArgs {
    fn options(&self) -> AmplitudeOptions {
        let mut o = AmplitudeOptions::default();
        o.levels = self.levels;
        o.cycles = self.cycles;
        o.groups = self.groups;
        o.min_triggers = self.min_triggers;
        o.band = self.band;
        o.measured = self.measured.into();
        o.report_as = self.amplitude_of.map(Into::into);
        o.period = self.period;
        o.method = match self.method {
            MethodArg::Envelope => AmplitudeMethod::Envelope,
            MethodArg::Extrema => AmplitudeMethod::Extrema,
        };
        o
    }
}

pub(crate) fn run(a: &AmplitudeArgs) -> Result<(), Error> {
    let analysis = a.ssi.analysis()?;
    let opts = a.options();
    let ch = channels(&a.record)?;
    let views: Vec<&[f64]> = ch.data.iter().map(|c| c.as_slice()).collect();
    let bar = spinner();
    bar.set_message("identifying the modes, then their amplitude bands");
    let result = amplitude::amplitude_analysis(&views, ch.fs, &analysis, &opts, &a.modes);
    bar.finish_and_clear();
    let result = result.map_err(|e| match e {
        hyst::ident::IdentError::Ssi(e) => flag_error(&a.record, &a.ssi, e, &ch.names, ch.fs),
        e => fail(format!("{}: {e}", a.record.input.display())),
    })?;
    let report = hyst::report::FileReport::new(a.record.input.display().to_string(), result);
    print!("{report}");
    if let Some(json) = &a.json {
        report.write_json(json)?;
    }
    if let Some(svg) = &a.svg {
        let title = format!("Amplitude dependence: {}", a.record.input.display());
        std::fs::write(
            svg,
            hyst::figures::amplitude_svg(&report.report.curves, &title),
        )
        .map_err(|e| fail(format!("{}: {e}", svg.display())))?;
    }
    Ok(())
}
