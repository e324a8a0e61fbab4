//! What every fit of [`super::fit_storeys`] shares: the records checked against the
//! structure, the modes of the quietest level (the project's decision of what is a mode),
//! the reading they fix, the linear start, and each candidate's start.

use hyst_sim::building::{Reading as Quantity, ShearBuilding};

use super::error::StoreyError;
use super::model::{self, Layout};
use super::statistics::{Reading, Simulator};
use super::types::{StoreyOptions, StoreyProgress, StoreyStructure};
use crate::IdentError;

/// The records' statistics and what every fit shares.
pub(super) struct Setup {
    pub(super) reading: Reading,
    pub(super) template: ShearBuilding,
    pub(super) floors: usize,
    pub(super) channels: usize,
    pub(super) levels: usize,
    /// Accelerations: the folded band is a parameter.
    pub(super) folded: bool,
    pub(super) load_floors: Vec<usize>,
    /// Oversampling and warm-up of the simulations.
    pub(super) stepping: (usize, usize),
    /// The start: linear stiffnesses, damping ratios, each level's density.
    pub(super) start: Vec<f64>,
}

impl Setup {
    /// The simulator of records of `lengths` samples (none: replicates only), its forces
    /// drawn from `seed`.
    pub(super) fn simulator(&self, lengths: &[usize], seed: u64) -> Simulator {
        Simulator::new(
            (self.floors, self.channels),
            self.load_floors.clone(),
            self.stepping,
            lengths,
            seed,
        )
    }
}

/// The most replicates behind a spread, and iterations of a fit: past them a run takes
/// hours and says nothing more.
const MOST_REPLICATES: usize = 1000;
const MOST_ITERATIONS: usize = 1000;

/// The largest Bouc-Wen exponent a fit holds or a document carries: at 20 the loop is a
/// step already.
pub(super) const MAX_NU: f64 = 20.0;

/// The options within their ranges, each named when not.
fn check_options(opts: &StoreyOptions) -> Result<(), StoreyError> {
    let bad = |name, value: f64, expected| {
        Err(StoreyError::BadOption {
            name,
            value,
            expected,
        })
    };
    if !(1.0..=MAX_NU).contains(&opts.nu) {
        return bad(
            "nu",
            opts.nu,
            "the Bouc-Wen exponent must be in [1, 20] (|z|^(ν−1) is infinite at 0 below 1; at 20 the loop is already a step)",
        );
    }
    if !(0.0..1.0).contains(&opts.tolerance) {
        return bad(
            "tolerance",
            opts.tolerance,
            "a share of the weighted sum of squares, in [0, 1)",
        );
    }
    if !(3..=MOST_REPLICATES).contains(&opts.replicates) {
        return bad(
            "replicates",
            opts.replicates as f64,
            "at least 3 replicates make a spread, and at most 1000",
        );
    }
    if opts.max_iterations > MOST_ITERATIONS {
        return bad(
            "max_iterations",
            opts.max_iterations as f64,
            "at most 1000 iterations",
        );
    }
    Ok(())
}

/// The records and the structure agree; the number of floors.
pub(super) fn check(
    records: &[Vec<Vec<f64>>],
    structure: &StoreyStructure,
    opts: &StoreyOptions,
) -> Result<usize, StoreyError> {
    check_options(opts)?;
    let floors = structure.masses.len();
    if records.len() < 2 {
        return Err(StoreyError::FewLevels {
            levels: records.len(),
        });
    }
    if floors == 0 {
        return Err(StoreyError::BadMass {
            floor: 1,
            mass: f64::NAN,
        });
    }
    if let Some((i, &m)) = structure
        .masses
        .iter()
        .enumerate()
        .find(|(_, m)| !(**m > 0.0 && m.is_finite()))
    {
        return Err(StoreyError::BadMass {
            floor: i + 1,
            mass: m,
        });
    }
    let beyond = |channel: usize, &floor: &usize| {
        (floor >= floors).then_some(StoreyError::SensorBeyondTop {
            channel: channel + 1,
            floor: floor.saturating_add(1),
            floors,
        })
    };
    if let Some(e) = structure
        .sensors
        .iter()
        .enumerate()
        .find_map(|(c, f)| beyond(c, f))
    {
        return Err(e);
    }
    let loaded = opts.load_floors.as_deref().unwrap_or(&[]);
    for (i, &f) in loaded.iter().enumerate() {
        let why = if f >= floors {
            "not a floor of the structure"
        } else if loaded[..i].contains(&f) {
            "named twice (each loaded floor carries its own force)"
        } else {
            continue;
        };
        return Err(StoreyError::BadLoadFloor {
            floor: f.saturating_add(1),
            floors,
            why,
        });
    }
    if let Some(&s) = opts.candidates.iter().flatten().find(|&&s| s >= floors) {
        return Err(StoreyError::NoSuchStorey {
            storey: s.saturating_add(1),
            floors,
        });
    }
    if let Some(&factor) = opts.predict.iter().find(|f| !(**f > 0.0 && f.is_finite())) {
        return Err(StoreyError::Unphysical {
            name: "a predicted level's force factor",
            value: factor,
        });
    }
    // Each half must hold SSI's lags and a few periods; 400 samples is a floor, not a
    // target (the statistics' spread says what a length is worth).
    let needed = 800;
    for (l, r) in records.iter().enumerate() {
        if r.len() != structure.sensors.len() {
            return Err(StoreyError::ChannelCount {
                level: l + 1,
                channels: r.len(),
                sensors: structure.sensors.len(),
            });
        }
        let first = r[0].len();
        if let Some((c, ch)) = r
            .iter()
            .enumerate()
            .find(|(_, c)| c.len() != first || c.len() < needed)
        {
            return Err(StoreyError::BadLength {
                level: l + 1,
                channel: c + 1,
                samples: ch.len(),
                first,
                needed,
            });
        }
    }
    Ok(floors)
}

/// The modes of the quietest level (the project's decision of what is a mode), the reading
/// they fix, the linear start and each level's force density.
pub(super) fn setup(
    records: &[Vec<Vec<f64>>],
    structure: &StoreyStructure,
    opts: &StoreyOptions,
    floors: usize,
    progress: &(dyn Fn(StoreyProgress<'_>) + Sync),
) -> Result<Setup, IdentError> {
    let fs = structure.fs;
    let loudness = |r: &Vec<Vec<f64>>| -> f64 {
        r.iter()
            .map(|c| {
                let m = c.iter().sum::<f64>() / c.len() as f64;
                (c.iter().map(|v| (v - m).powi(2)).sum::<f64>() / c.len() as f64).ln()
            })
            .sum()
    };
    let quiet = (0..records.len())
        .min_by(|&i, &j| loudness(&records[i]).total_cmp(&loudness(&records[j])))
        .unwrap_or(0);
    progress(StoreyProgress {
        stage: "the quietest level's modes",
        iteration: 0,
        cost: f64::NAN,
    });
    let modes = structure_modes(&records[quiet], fs, floors)?;
    let hz: Vec<f64> = modes.iter().map(|m| m.0).collect();
    let shortest = records.iter().map(|r| r[0].len() / 2).min().unwrap_or(0);
    let reading = Reading::new(fs, &hz, shortest);
    let k = model::stiffnesses_for(&structure.masses, &hz);
    let load_floors = opts
        .load_floors
        .clone()
        .unwrap_or_else(|| (0..floors).collect());
    let template = model::template(
        &structure.masses,
        &structure.sensors,
        structure.quantity,
        fs,
        &load_floors,
    );
    // Fixed steps for the whole fit, from the start's modes.
    let (oversample, warm_up) = stepping(hz[0], hz[floors - 1], modes[0].1, fs);
    let mut start: Vec<f64> = k;
    start.extend(modes.iter().map(|m| m.1.clamp(1e-3, 0.5)));
    // Each level's density: the linear start's band powers at unit density against the
    // record's (a linear response's power scales as q).
    let folded = structure.quantity == Quantity::Acceleration;
    let unit_layout = Layout {
        floors,
        levels: 1,
        storey: None,
        folded,
    };
    let mut theta = start.clone();
    theta.push(1.0);
    if folded {
        theta.push(1.0);
    }
    let (unit, _, _) = model::building(&template, &unit_layout, &theta, opts.nu)?;
    let sim = Simulator::new(
        (floors, structure.sensors.len()),
        load_floors.clone(),
        (oversample, warm_up),
        &[],
        opts.seed,
    );
    let n = records[quiet][0].len();
    // The first simulation: masses past what the simulation can hold fail here, and are
    // named as the masses (not a diverged state).
    let stiffest = start[..floors].iter().copied().fold(0.0, f64::max);
    let unphysical = |why: String| StoreyError::MassesNotSimulable {
        mass: structure.masses.iter().copied().fold(0.0, f64::max),
        stiffness: stiffest,
        why,
    };
    let unit_records = sim
        .replicate(&unit, n, (1.0, 1.0), opts.seed + 77)
        .map_err(|e| unphysical(e.to_string()))?;
    let unit_stats = reading.of(&unit_records);
    if let Some(bad) = unit_stats.iter().find(|v| !v.is_finite()) {
        return Err(unphysical(format!("its response reads as {bad}")).into());
    }
    let channels = structure.sensors.len();
    for r in records {
        let m = reading.of(r);
        // Each band's log summed power (a linear response's scales as q).
        let d: f64 = (0..floors)
            .map(|j| {
                let at = 2 * floors + j * channels;
                m[at] - unit_stats[at]
            })
            .sum::<f64>()
            / floors as f64;
        start.push(d.exp());
    }
    if let Some(q) = start[2 * floors..]
        .iter()
        .find(|q| !(q.is_finite() && **q > 0.0))
    {
        return Err(
            unphysical(format!("the force density the records need is {q:e} N²/Hz")).into(),
        );
    }
    if folded {
        // The folded band starts at the record's own rate (a force white to Nyquist).
        start.push(1.0);
    }

    Ok(Setup {
        reading,
        template,
        floors,
        channels: structure.sensors.len(),
        levels: records.len(),
        folded,
        load_floors,
        stepping: (oversample, warm_up),
        start,
    })
}

/// A candidate's start: the linear start, and for an element a share a = 0.5,
/// β = 0.2/σ_d and γ = 0.1/σ_d (the element's z saturating at 3.3 times the storey's RMS
/// drift σ_d at the loudest level under the linear start).
pub(super) fn start_for(
    setup: &Setup,
    layout: &Layout,
    linear: &ShearBuilding,
    q: &[f64],
    records: &[Vec<Vec<f64>>],
    opts: &StoreyOptions,
) -> Result<Vec<f64>, IdentError> {
    let mut theta = setup.start.clone();
    let Some(storey) = layout.storey else {
        return Ok(theta);
    };
    let mut drifts = linear.clone();
    drifts.sensors = (0..setup.floors).collect();
    drifts.reading = Quantity::Displacement;
    let sim = setup.simulator(&[], opts.seed);
    let loudest = q.iter().copied().fold(0.0, f64::max);
    let n = records.iter().map(|r| r[0].len()).max().unwrap_or(0) / 4;
    let x = sim.replicate(&drifts, n.max(1000), (loudest, 0.0), opts.seed + 91)?;
    let d: Vec<f64> = (0..x[0].len())
        .map(|t| x[storey][t] - if storey > 0 { x[storey - 1][t] } else { 0.0 })
        .collect();
    let sigma = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    // Inside the bounded element's range (γ < β), not on its edge, where every step that
    // raises γ alone would be refused.
    theta.extend([0.5, 0.2 / sigma, 0.1 / sigma]);
    Ok(theta)
}

/// The structure's modes (frequency, damping ratio), lowest first, from one record (the
/// project's decision of what is a mode): a chain of n floors has n, and when more are
/// reported, the n standing highest in the channels' summed spectrum (a weak neighbour of a
/// strong peak is not the structure's).
fn structure_modes(
    record: &[Vec<f64>],
    fs: f64,
    floors: usize,
) -> Result<Vec<(f64, f64)>, IdentError> {
    let y: Vec<&[f64]> = record.iter().map(Vec::as_slice).collect();
    let analysis = covssi::analyze(&y, fs, &covssi::AnalysisOptions::default())?;
    let mut modes: Vec<(f64, f64)> = analysis
        .decision
        .modes
        .iter()
        .map(|m| (m.frequency_hz, m.damping_ratio))
        .collect();
    if modes.len() < floors {
        return Err(StoreyError::TooFewModes {
            found: modes.len(),
            floors,
            max_hz: fs / 2.0,
        }
        .into());
    }
    let segment = (fs / (0.01 * modes.iter().map(|m| m.0).fold(f64::INFINITY, f64::min)))
        .ceil()
        .max(64.0) as usize;
    let spectra: Vec<(Vec<f64>, Vec<f64>)> = record
        .iter()
        .map(|c| crate::welch_psd(c, fs, segment.min(c.len() / 3)))
        .collect();
    let height = |hz: f64| -> f64 {
        let f = &spectra[0].0;
        let i = f.partition_point(|&v| v < hz).min(f.len() - 1);
        spectra.iter().map(|(_, p)| p[i]).sum()
    };
    modes.sort_by(|a, b| height(b.0).total_cmp(&height(a.0)));
    modes.truncate(floors);
    modes.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(modes)
}

/// The damping ratio below which the warm-up no longer grows.
pub(super) const WARM_UP_LEAST_DAMPING: f64 = 0.005;

/// A fit's fixed steps (integration steps per sample, samples of warm-up) for a structure
/// whose lowest mode is at `f1_hz` damped `zeta1` and whose highest is at `f_max_hz`, at
/// `fs`: ω_max h ≤ 0.1 with a margin of 30 % for a stiffer model, at least 4 steps; a
/// warm-up of 20 time constants of the lowest mode, its damping ratio taken no lower than
/// [`WARM_UP_LEAST_DAMPING`].
pub(super) fn stepping(f1_hz: f64, f_max_hz: f64, zeta1: f64, fs: f64) -> (usize, usize) {
    let two_pi = 2.0 * std::f64::consts::PI;
    let oversample = ((13.0 * two_pi * f_max_hz / fs).ceil() as usize).max(4);
    let zeta1 = zeta1.max(WARM_UP_LEAST_DAMPING);
    let warm_up = (20.0 / (two_pi * f1_hz * zeta1) * fs).ceil() as usize;
    (oversample, warm_up)
}
