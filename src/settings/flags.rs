//! [`SsiSettings`] and [`TrackSettings`] as flags of the command line (`hyst ssi`,
//! `hyst track`, `hyst amplitude` flatten them): each field is one flag, a setting on by
//! default as `--no-…` (`--no-joint`, `--no-whiten`), one off by default as itself (`--refine`). The flags are read into the settings
//! by one struct literal that names every field, so a setting without its flag does not
//! compile; the Python keywords are the same fields, read by `from_json`, which refuses a
//! name it does not know.

use super::{SsiSettings, TrackSettings};

/// `clap::Args` for a settings type, through its flags' derived parser and `From`.
macro_rules! settings_are_flags {
    ($settings:ty, $flags:ty) => {
        impl clap::FromArgMatches for $settings {
            fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
                <$flags>::from_arg_matches(matches).map(<$settings>::from)
            }

            fn update_from_arg_matches(
                &mut self,
                matches: &clap::ArgMatches,
            ) -> Result<(), clap::Error> {
                *self = <$settings>::from_arg_matches(matches)?;
                Ok(())
            }
        }

        impl clap::Args for $settings {
            fn augment_args(cmd: clap::Command) -> clap::Command {
                <$flags>::augment_args(cmd)
            }

            fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
                <$flags>::augment_args_for_update(cmd)
            }
        }
    };
}

/// The flags as clap reads them; [`SsiSettings`] is what the command line takes.
#[derive(clap::Args, Debug)]
#[command(next_help_heading = "SSI and its refinement")]
pub(super) struct SsiFlags {
    /// Decimate by this factor first (an ideal low-pass below the new Nyquist, then every
    /// FACTOR-th sample); default: read from the record's spectrum (said in the report), 1
    /// keeps the rate.
    #[arg(long, value_name = "FACTOR")]
    decimate: Option<usize>,
    /// Block rows of the Toeplitz matrix (lags up to 2·N−1); default: read from the record,
    /// enough for ten periods of its lowest spectral peak within a size budget (said in the
    /// report).
    #[arg(long)]
    block_rows: Option<usize>,
    /// Instead of --block-rows: as many block rows as make the largest lag cover this many
    /// seconds (after any --decimate).
    #[arg(
        long,
        value_name = "SECONDS",
        conflicts_with_all = ["block_rows", "lag_periods"]
    )]
    lag_seconds: Option<f64>,
    /// Instead of --block-rows: as many block rows as make the largest lag cover COUNT periods
    /// of HZ, e.g. `--lag-periods 10 1.5` for ten periods of a 1.5 Hz mode (the paper's
    /// choice: ten periods of the dominant mode).
    #[arg(
        long,
        num_args = 2,
        value_names = ["COUNT", "HZ"],
        conflicts_with = "block_rows"
    )]
    lag_periods: Option<Vec<f64>>,
    /// Largest model order; default: 40, or four per spectral peak when the record shows
    /// more than ten, at most the Toeplitz rank.
    #[arg(long)]
    max_order: Option<usize>,
    /// Model order step.
    #[arg(long, default_value_t = SsiSettings::default().order_step)]
    order_step: usize,
    /// Stabilization threshold on the relative frequency change.
    #[arg(long, default_value_t = SsiSettings::default().df)]
    df: f64,
    /// Stabilization threshold on the relative damping change.
    #[arg(long, default_value_t = SsiSettings::default().dzeta)]
    dzeta: f64,
    /// Stabilization threshold on 1 − MAC (several channels).
    #[arg(long, default_value_t = SsiSettings::default().dmac)]
    dmac: f64,
    /// Stabilization threshold for real poles: eq. (31) of Bajrić & Høgsberg (2018), the paper
    /// hyst implements (see the README).
    #[arg(long, default_value_t = SsiSettings::default().dreal)]
    dreal: f64,
    /// Reference channels (0-based indices among --columns), comma-separated; default: all.
    #[arg(long, value_delimiter = ',')]
    references: Option<Vec<usize>>,
    /// Refine the modes and real poles by maximum likelihood: fit them to the whole record,
    /// each with a standard error, dropping those the record does not support. Off by
    /// default (the answer is SSI's modes with the jackknife's errors): its model is a white
    /// load, and on coloured loads it rarely holds; under a broadband white load (a shaker's
    /// random test) its errors are up to half SSI's.
    #[arg(long, conflicts_with = "no_refine")]
    refine: bool,
    /// Skip the refinement: the default (kept so that scripts written for the earlier
    /// default still run).
    #[arg(long)]
    no_refine: bool,
    /// Standard errors for SSI's modes: the jackknife over at most BLOCKS blocks of the
    /// record (default 10; 0: none). They are the errors reported where SSI's modes are the
    /// answer, and the decision of what is a mode reads them: a mode must be found again in
    /// the record's parts, its frequency determined.
    #[arg(long, value_name = "BLOCKS")]
    ssi_errors: Option<usize>,
    /// The largest damping ratio of a mode (default 0.2): a candidate damped more is set
    /// apart with its reason, not reported.
    #[arg(long, value_name = "RATIO")]
    max_damping: Option<f64>,
    /// Refine with each channel's likelihood alone, not the joint likelihood of all channels
    /// (which uses their cross-spectra; on by default for 2 to 4 channels, and above 4 through 4
    /// combinations of them, band by band when there are more than 4 modes).
    #[arg(long)]
    no_joint: bool,
}

impl From<SsiFlags> for SsiSettings {
    fn from(f: SsiFlags) -> Self {
        // Every field named, none defaulted: a field added to SsiSettings fails here
        // until it has its flag.
        SsiSettings {
            block_rows: f.block_rows,
            lag_seconds: f.lag_seconds,
            lag_periods: match f.lag_periods.as_deref() {
                Some(&[count, hz]) => Some((count, hz)),
                _ => None,
            },
            decimate: f.decimate,
            max_order: f.max_order,
            order_step: f.order_step,
            references: f.references,
            df: f.df,
            dzeta: f.dzeta,
            dmac: f.dmac,
            dreal: f.dreal,
            refine: f.refine && !f.no_refine,
            joint: !f.no_joint,
            ssi_errors: f.ssi_errors,
            max_damping: f.max_damping,
        }
    }
}

settings_are_flags!(SsiSettings, SsiFlags);

/// [`TrackSettings`]' flags as clap reads them.
#[derive(clap::Args, Debug)]
pub(super) struct TrackFlags {
    /// The first this many records train the baselines (default: 336, at most half).
    #[arg(long)]
    training: Option<usize>,
    /// Chart the standardized residuals as they are, even when the training records show a
    /// slow effect the covariates leave unexplained (by default its model's filter is run
    /// and its innovations charted, so that the effect is not taken for a change).
    #[arg(long)]
    no_whiten: bool,
    /// Regress on the covariates as they are. By default each mode's environmental model is
    /// chosen on the training records by BIC: each covariate through a first-order lag of
    /// whole hours (up to 12) and its slope changing below a breakpoint (frost); the report
    /// says what was chosen, and the table which records lie outside the training range
    /// (column `extrapolated`).
    #[arg(long)]
    no_environment_model: bool,
    /// Add each record's excitation level as a covariate (`log_rms`: ln of its RMS
    /// response, in the record's units), for frequencies that drift with amplitude.
    #[arg(long, conflicts_with = "estimates")]
    level_covariate: bool,
    /// Each chart's limit the one independent standard normal values would ask (h = 12).
    /// By default each limit is calibrated on the training records' own charted values
    /// (their block bootstrap: their correlation from record to record and their tail), never
    /// below that, and the report says the false-alarm rate measured on them.
    #[arg(long)]
    no_calibrate: bool,
    /// Chart each mode alone only. By default the modes' residuals are also judged
    /// together: the factors they share (a slow effect of the environment common to all)
    /// set apart on the training records, and what they leave charted as one statistic,
    /// whose alarms name the modes that drive them.
    #[arg(long)]
    no_joint_chart: bool,
}

impl From<TrackFlags> for TrackSettings {
    fn from(f: TrackFlags) -> Self {
        // Every field named: a field added to TrackSettings fails here until it has its flag.
        TrackSettings {
            training: f.training,
            whiten: !f.no_whiten,
            environment_model: !f.no_environment_model,
            level_covariate: f.level_covariate,
            calibrate: !f.no_calibrate,
            joint_chart: !f.no_joint_chart,
        }
    }
}

settings_are_flags!(TrackSettings, TrackFlags);
