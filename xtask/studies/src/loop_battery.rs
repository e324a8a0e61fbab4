//! `cargo xtask loop-battery`: the residual loop (`hyst refine`) on records made by the
//! project's own simulator, each with one undeclared effect (or none, or two), and a table of
//! what the loop found against what is there.
//!
//! Every record is the Bouc-Wen benchmark oscillator (m = 2 kg) plus the case's effect, under
//! a 5–150 Hz force of 50 N RMS: a random-phase multisine of 8192-sample periods (periodic),
//! or band-limited Gaussian noise (random). It is simulated at 20× the rate (15 kHz, RK4 on
//! the band-limited input), FIR-decimated to 750 Hz in stages 2·2·5, and 8e-6 m of sensor
//! noise is added (white, or coloured: an AR(1) process with φ = 0.95 of the same RMS);
//! 32768 samples. The effects are sized from the base system's response to the same force
//! (σₓ, σᵥ) so that each is a fixed share of the linear spring's force k·2σₓ. A drifting
//! stiffness is simulated in 64 pieces, each with its own k.
//!
//! The loop estimates on the first 75 % and tests on the last 25 %, as `hyst refine` does by
//! default, with the mass known.

use std::time::Instant;

use crate::acquisition::{Chain, TAIL};
use hyst_ident::residual::{self, ModelClass, Record, Refinement};
use hyst_model::{
    BoucWen, Clearance, Coulomb, ForceSurface, Oscillator, SURFACE_TERMS, SecondMass,
};
use hyst_sim::Input;
use hyst_sim::excitation::{Multisine, band_limited_noise};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rand::{RngExt, SeedableRng};
use rand_distr::StandardNormal;

const FS: f64 = 750.0;
const N: usize = 32768;
const PERIOD: usize = 8192;
const STAGES: [usize; 3] = [2, 2, 5];
const FORCE_RMS: f64 = 50.0;
const NOISE_STD: f64 = 8e-6;
/// Pieces of a drifting record, each simulated with its own stiffness.
const DRIFT_PIECES: usize = 64;

/// How the force is made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Force {
    /// A random-phase multisine, four periods of 8192 samples.
    Periodic,
    /// Band-limited Gaussian noise.
    Random,
}

/// How the records are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Generator {
    /// RK4 at 20× the rate, FIR decimation 2·2·5 (the battery's own).
    #[default]
    Project,
    /// Another integrator, step and decimation than the loop's forward model and the
    /// project's generator: the implicit trapezoidal rule at 40× the rate, FIR decimation
    /// 2·4·5 (a drifting record keeps the project's generator).
    Independent,
}

/// What the loop should find.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expect {
    /// Nothing: a control.
    Nothing,
    /// One of these named effects first (beyond the hysteresis of the base system, unless
    /// the case is that hysteresis); two when the record has two effects.
    First(&'static [&'static str]),
    /// A change over the record: `nonstationary` or `unexplained`, never a named effect
    /// without a significant gain.
    Drift,
}

/// One kind of record.
pub struct Case {
    /// Its name in the table.
    pub name: &'static str,
    /// The effect added to the base system, sized from its response (σₓ, σᵥ).
    pub effect: fn(&mut Oscillator, f64, f64),
    /// Relative change of the linear stiffness from the first to the last sample.
    pub drift: f64,
    /// Coloured sensor noise instead of white.
    pub coloured_noise: bool,
    /// What the loop should find.
    pub expect: Expect,
    /// The model the loop starts from.
    pub start: ModelClass,
    /// The measurement chain between the structure and the record, applied by the battery
    /// ([`crate::acquisition`]), not by the simulator.
    pub chain: Option<Chain>,
}

/// The base system's linear spring k (N/m).
const K: f64 = 5e4;

fn nothing(_: &mut Oscillator, _: f64, _: f64) {}

/// A case started from Bouc-Wen, without drift or coloured noise.
fn case(name: &'static str, effect: fn(&mut Oscillator, f64, f64), expect: Expect) -> Case {
    Case {
        name,
        effect,
        drift: 0.0,
        coloured_noise: false,
        expect,
        start: ModelClass::BoucWen,
        chain: None,
    }
}

/// The cases, each run under both forces: the controls, one effect at a time, then two
/// together and the drifts.
pub fn cases() -> Vec<Case> {
    let mut all = controls();
    all.extend(single_effects());
    all.extend(pairs_and_drifts());
    all.extend(chains());
    all
}

/// The controls (nothing to add), and hysteresis from a linear start.
fn controls() -> Vec<Case> {
    vec![
        case("control", nothing, Expect::Nothing),
        case("control, second record", nothing, Expect::Nothing),
        Case {
            coloured_noise: true,
            ..case("control, coloured noise", nothing, Expect::Nothing)
        },
        Case {
            start: ModelClass::Linear,
            ..case(
                "hysteresis (linear start)",
                nothing,
                Expect::First(&["hysteresis"]),
            )
        },
    ]
}

/// One effect at a time, each of a size a user would want found.
fn single_effects() -> Vec<Case> {
    vec![
        // k₃(2σ)³ = 10 % of k·2σ.
        case(
            "cubic spring",
            |o, sx, _| o.extras.cubic_stiffness = 0.10 * K / (4.0 * sx * sx),
            Expect::First(&["cubic_stiffness"]),
        ),
        // k_q(2σ)² = 14 % of k·2σ (the asymmetric spring).
        case(
            "quadratic spring",
            |o, sx, _| o.extras.quadratic_stiffness = 0.14 * K / (2.0 * sx),
            Expect::First(&["quadratic_stiffness"]),
        ),
        // A spring of 0.3 k beyond ±σ: 15 % of k·2σ at 2σ.
        case(
            "clearance",
            |o, sx, _| {
                o.extras.clearance = Some(Clearance {
                    stiffness: 0.3 * K,
                    gap: sx,
                })
            },
            Expect::First(&["clearance"]),
        ),
        // c_q(2σᵥ)² = 5 % of k·2σₓ.
        case(
            "quadratic damping",
            |o, sx, sv| o.extras.quadratic_damping = 0.05 * K * 2.0 * sx / (4.0 * sv * sv),
            Expect::First(&["quadratic_damping"]),
        ),
        // F_c = 2 % of k·2σₓ, smoothed over 1 % of σᵥ.
        case(
            "Coulomb friction",
            |o, sx, sv| {
                o.extras.coulomb = Some(Coulomb {
                    force: 0.02 * K * 2.0 * sx,
                    smoothing_velocity: 0.01 * sv,
                })
            },
            Expect::First(&["coulomb_friction"]),
        ),
        // 0.1 kg at 60 Hz (uncoupled), 2 % damping.
        case(
            "second mode",
            |o, _, _| {
                let m2: f64 = 0.1;
                let w = 2.0 * std::f64::consts::PI * 60.0;
                o.extras.second_mass = Some(SecondMass {
                    mass: m2,
                    stiffness: m2 * w * w,
                    damping: 2.0 * 0.02 * m2 * w,
                })
            },
            Expect::First(&["second_mode"]),
        ),
        // The element with ν = 2 saturating at |z| = (α/(βγ + βδ))^(1/ν) = 46 N, twice the
        // benchmark element's force at σₓ. (With the benchmark's hardening sign, βγ + βδ < 0,
        // an element with ν = 2 is a Riccati equation in x: z blows up at a finite
        // displacement, within this record's range for products of this size.)
        case(
            "exponent nu = 2",
            |o, _, _| {
                o.restoring =
                    hyst_model::Restoring::BoucWen(BoucWen::from_products(5e4, 40.0, -16.0, 2.0))
            },
            Expect::First(&["hysteresis_exponent"]),
        ),
        // Damping that grows with amplitude, c₃x²ẋ (no named effect has it): 5 % of k·2σₓ
        // at (2σₓ, 2σᵥ).
        case(
            "x^2 v damping (outside the list)",
            |o, sx, sv| {
                let mut c = [0.0; SURFACE_TERMS];
                c[8] = 0.05 * K * 2.0 * sx / 8.0;
                o.extras.surface = Some(ForceSurface {
                    x_scale: sx,
                    v_scale: sv,
                    coefficients: c,
                })
            },
            Expect::First(&["restoring_surface"]),
        ),
    ]
}

/// Two effects together, and a stiffness drifting over the record.
fn pairs_and_drifts() -> Vec<Case> {
    vec![
        Case {
            drift: -0.08,
            ..case("stiffness drifting 8 % down", nothing, Expect::Drift)
        },
        case(
            "cubic spring and quadratic damping",
            |o, sx, sv| {
                o.extras.cubic_stiffness = 0.10 * K / (4.0 * sx * sx);
                o.extras.quadratic_damping = 0.05 * K * 2.0 * sx / (4.0 * sv * sv);
            },
            Expect::First(&["cubic_stiffness", "quadratic_damping"]),
        ),
        case(
            "quadratic spring and Coulomb friction",
            |o, sx, sv| {
                o.extras.quadratic_stiffness = 0.14 * K / (2.0 * sx);
                o.extras.coulomb = Some(Coulomb {
                    force: 0.02 * K * 2.0 * sx,
                    smoothing_velocity: 0.01 * sv,
                });
            },
            Expect::First(&["quadratic_stiffness", "coulomb_friction"]),
        ),
        Case {
            drift: 0.05,
            ..case("stiffness drifting 5 % up", nothing, Expect::Drift)
        },
    ]
}

/// The benchmark structure behind a measurement chain the loop's model lacks: what the
/// acquisition does, which the loop should take for the acquisition (`output_delay` or
/// `sensor_lag`; to first order in frequency the two are one), not for structure.
fn chains() -> Vec<Case> {
    let chained = |name, chain| Case {
        chain: Some(chain),
        ..case(
            name,
            nothing,
            Expect::First(&["output_delay", "sensor_lag"]),
        )
    };
    vec![
        // A sensor with its corner at 800 Hz (above the 375 Hz Nyquist): 3 % of the
        // response at the 25 Hz resonance.
        chained(
            "sensor lag 0.2 ms",
            Chain::DelayLag {
                delay: 0.0,
                lag: 2e-4,
            },
        ),
        // The output channel sampled 0.4 samples after the input's (a multiplexed converter).
        chained(
            "output delay 0.4 samples",
            Chain::DelayLag {
                delay: 0.4 / FS,
                lag: 0.0,
            },
        ),
        // A second-order Butterworth anti-aliasing filter at 300 Hz on the output only.
        chained(
            "anti-aliasing filter on the output",
            Chain::Butterworth2 { corner: 300.0 },
        ),
    ]
}

/// The force of a record, `n` samples.
fn force(kind: Force, seed: u64, n: usize) -> Vec<f64> {
    match kind {
        Force::Periodic => {
            let p = Multisine::band(PERIOD, FS, 5.0, 150.0, FORCE_RMS)
                .and_then(|m| m.generate(seed))
                .expect("a valid band");
            p.iter().cycle().take(n).copied().collect()
        }
        Force::Random => {
            band_limited_noise(n, FS, 5.0, 150.0, FORCE_RMS, seed).expect("a valid band")
        }
    }
}

/// The noise-free output of `o` under `u` (of `kind`), the stiffness drifting by `drift`
/// over the record ([`hyst_sim::simulate_drifting`]).
fn respond(
    o: &Oscillator,
    u: &[f64],
    kind: Force,
    drift: f64,
    generator: Generator,
) -> Option<Vec<f64>> {
    let input = match kind {
        Force::Periodic => Input::Periodic(&u[..PERIOD]),
        Force::Random => Input::BandLimited(u),
    };
    if generator == Generator::Independent && drift == 0.0 {
        let opts = hyst_sim::SimOptions {
            oversample: 40,
            integrator: hyst_sim::Integrator::Trapezoidal,
            decimation: hyst_sim::Decimation::Fir(vec![2, 4, 5]),
            ..hyst_sim::SimOptions::default()
        };
        return hyst_sim::simulate(o, input, FS, u.len(), &opts).ok();
    }
    let pieces = if drift == 0.0 { 1 } else { DRIFT_PIECES };
    hyst_sim::simulate_drifting(o, input, FS, u.len(), &STAGES, drift, pieces).ok()
}

/// Sensor noise of standard deviation [`NOISE_STD`]: white, or AR(1) with φ = 0.95 scaled to
/// the same standard deviation.
fn sensor_noise(coloured: bool, seed: u64) -> Vec<f64> {
    let mut r = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut e: Vec<f64> = (0..N).map(|_| r.sample::<f64, _>(StandardNormal)).collect();
    if coloured {
        let phi: f64 = 0.95;
        let mut prev = 0.0;
        for v in e.iter_mut() {
            prev = phi * prev + (1.0 - phi * phi).sqrt() * *v;
            *v = prev;
        }
    }
    e.iter().map(|v| NOISE_STD * v).collect()
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// One record of the battery.
pub struct Made {
    /// Input and measured output.
    pub u: Vec<f64>,
    /// See `u`.
    pub y: Vec<f64>,
    /// The true model (without the drift).
    pub truth: Oscillator,
    /// The sensor noise's ε on the test rows: what a perfect model scores there.
    pub noise_eps: f64,
}

/// Make the record of `case` under `kind` with `seed`.
pub fn make(case: &Case, kind: Force, seed: u64, generator: Generator) -> Option<Made> {
    // A chain's record is made longer and cut after the chain ([`TAIL`]).
    let long = case.chain.map_or(N, |_| N + TAIL);
    let mut u = force(kind, seed, long);
    let base = Oscillator::benchmark();
    let y0 = respond(&base, &u, kind, 0.0, generator)?;
    let v0: Vec<f64> = y0.windows(2).map(|w| (w[1] - w[0]) * FS).collect();
    let (sx, sv) = (rms(&y0), rms(&v0));
    let mut truth = base;
    (case.effect)(&mut truth, sx, sv);
    let mut clean = respond(&truth, &u, kind, case.drift, generator)?;
    if let Some(c) = case.chain {
        clean = c.apply(&clean, FS);
        clean.truncate(N);
        u.truncate(N);
        if let Chain::DelayLag { delay, lag } = c {
            truth.chain = Some(hyst_model::MeasurementChain { delay, lag });
        }
    }
    let noise = sensor_noise(case.coloured_noise, seed.wrapping_add(0x5eed));
    let y: Vec<f64> = clean.iter().zip(&noise).map(|(a, b)| a + b).collect();
    let test = 3 * N / 4..N;
    // ε (eq. 39) of the noise-free output: the sensor noise's RMS over the output's range.
    let noise_eps = hyst_ident::epsilon(&clean[test.clone()], &y[test]).epsilon;
    Some(Made {
        u,
        y,
        truth,
        noise_eps,
    })
}

/// One row of the table.
pub struct Row {
    case: &'static str,
    force: Force,
    seed: u64,
    outcome: Result<Refinement, String>,
    noise_eps: f64,
    expect: Expect,
    seconds: f64,
    truth: Oscillator,
}

/// The true value of the parameter the loop reports as `name`, if the truth has it.
fn truth_value(name: &str, t: &Oscillator) -> Option<f64> {
    use hyst_model::Restoring;
    let e = &t.extras;
    let bw = match t.restoring {
        Restoring::BoucWen(b) => Some(b),
        _ => None,
    };
    match name {
        "damping" => Some(t.damping),
        "stiffness" => Some(t.stiffness),
        "alpha" => bw.map(|b| b.alpha),
        "beta_gamma" => bw.map(|b| b.beta_gamma()),
        "beta_delta" => bw.map(|b| b.beta_delta()),
        "nu" => bw.map(|b| b.nu),
        "cubic_stiffness" => Some(e.cubic_stiffness).filter(|v| *v != 0.0),
        "quadratic_stiffness" => Some(e.quadratic_stiffness).filter(|v| *v != 0.0),
        "quadratic_damping" => Some(e.quadratic_damping).filter(|v| *v != 0.0),
        "coulomb_force" => e.coulomb.map(|c| c.force),
        "clearance_stiffness" => e.clearance.map(|g| g.stiffness),
        "clearance_gap" => e.clearance.map(|g| g.gap),
        "second_mass" => e.second_mass.map(|m| m.mass),
        "second_stiffness" => e.second_mass.map(|m| m.stiffness),
        "second_damping" => e.second_mass.map(|m| m.damping),
        "chain_delay" => t.chain.map(|c| c.delay).filter(|v| *v != 0.0),
        "chain_lag" => t.chain.map(|c| c.lag).filter(|v| *v != 0.0),
        _ => None,
    }
}

impl Row {
    /// The z of each estimate against the truth, when the final model has exactly the
    /// truth's terms (every estimate has a true value and the count matches the truth's
    /// free terms), else none.
    fn z_scores(&self) -> Vec<(&str, f64)> {
        let Ok(r) = &self.outcome else {
            return Vec::new();
        };
        let z: Vec<(&str, f64)> = r
            .estimates
            .iter()
            .filter_map(|e| {
                Some((
                    e.name.as_ref(),
                    (e.value - truth_value(&e.name, &self.truth)?) / e.se,
                ))
            })
            .collect();
        let same_structure = z.len() == r.estimates.len()
            && r.model.extras.surface.is_none()
            && self.truth.extras.surface.is_none()
            && (r.model.extras.coulomb.is_some() == self.truth.extras.coulomb.is_some())
            && (r.model.extras.second_mass.is_some() == self.truth.extras.second_mass.is_some())
            && (r.model.extras.clearance.is_some() == self.truth.extras.clearance.is_some())
            && (r.model.chain.is_some() == self.truth.chain.is_some())
            && ((r.model.extras.cubic_stiffness != 0.0)
                == (self.truth.extras.cubic_stiffness != 0.0))
            && ((r.model.extras.quadratic_stiffness != 0.0)
                == (self.truth.extras.quadratic_stiffness != 0.0))
            && ((r.model.extras.quadratic_damping != 0.0)
                == (self.truth.extras.quadratic_damping != 0.0))
            && matches!(
                (r.model.restoring, self.truth.restoring),
                (hyst_model::Restoring::BoucWen(a), hyst_model::Restoring::BoucWen(b)) if (a.nu == 1.0) == (b.nu == 1.0)
            );
        if same_structure && self.expect != Expect::Drift {
            z
        } else {
            Vec::new()
        }
    }

    fn effects(&self) -> Vec<&'static str> {
        match &self.outcome {
            Ok(r) => r
                .steps
                .iter()
                .filter_map(|s| s.effect.map(|e| e.name()))
                .collect(),
            Err(_) => Vec::new(),
        }
    }

    /// The effects added beyond the base system's hysteresis (which the loop adds first
    /// when its start has none), unless the case is that hysteresis.
    fn found(&self) -> Vec<&'static str> {
        let all = self.effects();
        match self.expect {
            Expect::First(e) if e.contains(&"hysteresis") => all,
            _ => {
                let skip = usize::from(all.first() == Some(&"hysteresis"));
                all[skip..].to_vec()
            }
        }
    }

    fn eps(&self) -> Option<(f64, f64)> {
        let r = self.outcome.as_ref().ok()?;
        let before = r.steps.first()?.before.first()?.epsilon;
        Some((before, r.tests.first()?.epsilon))
    }

    /// Whether the row meets its target: controls add nothing; an effect in the list comes
    /// first; a drift adds no named effect.
    fn verdict(&self) -> &'static str {
        if self.outcome.is_err() {
            return "FAILED";
        }
        let found = self.found();
        match self.expect {
            Expect::Nothing if found.is_empty() => "ok",
            Expect::Nothing => "spurious",
            Expect::First(e) if found.first().is_some_and(|f| e.contains(f)) => "ok",
            Expect::First(_) => "wrong",
            Expect::Drift if !found.is_empty() => "named",
            Expect::Drift => match &self.outcome {
                Ok(r) if r.nonstationary || r.unexplained.is_some() => "ok",
                _ => "silent",
            },
        }
    }
}

/// Options of the battery.
#[derive(Debug, clap::Args)]
pub struct BatteryArgs {
    /// Base seed: record i of the battery uses seed + i (force) and a derived seed (noise).
    /// Use seeds no earlier run used to judge the targets.
    #[arg(long)]
    pub seed: u64,
    /// Only the cases whose names contain one of these (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub cases: Vec<String>,
    /// Forces to run (both by default).
    #[arg(long, value_delimiter = ',', value_enum)]
    pub forces: Vec<Force>,
    /// Write the table as Markdown here too.
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
    /// Write each record as a CSV (`u,y`) into this folder, to run `hyst refine` on it, named
    /// after its case, force and seed (`quadratic_spring_random_9011.csv`).
    #[arg(long)]
    pub records: Option<std::path::PathBuf>,
    /// Only write the records (with --records), without running the loop.
    #[arg(long, requires = "records")]
    pub records_only: bool,
    /// How the records are made.
    #[arg(long, value_enum, default_value = "project")]
    pub generator: Generator,
}

/// A file name for the record of `case` under `kind` with `seed`: the case's name in lower
/// case with every run of other characters made one `_`.
fn record_name(case: &str, kind: Force, seed: u64) -> String {
    let mut slug = String::new();
    for c in case.chars() {
        if c.is_ascii_alphanumeric() {
            slug.push(c.to_ascii_lowercase());
        } else if !slug.ends_with('_') {
            slug.push('_');
        }
    }
    let force = match kind {
        Force::Periodic => "periodic",
        Force::Random => "random",
    };
    format!("{}_{force}_{seed}.csv", slug.trim_end_matches('_'))
}

/// Run the battery and print the table and its summary.
pub fn run(args: &BatteryArgs) -> Result<(), String> {
    let forces = if args.forces.is_empty() {
        vec![Force::Periodic, Force::Random]
    } else {
        args.forces.clone()
    };
    let all = cases();
    let chosen: Vec<&Case> = all
        .iter()
        .filter(|c| args.cases.is_empty() || args.cases.iter().any(|n| c.name.contains(n.as_str())))
        .collect();
    if chosen.is_empty() {
        let names: Vec<&str> = all.iter().map(|c| c.name).collect();
        return Err(format!(
            "no case matches --cases; the cases: {}",
            names.join("; ")
        ));
    }
    let jobs: Vec<(&Case, Force, u64)> = chosen
        .iter()
        .flat_map(|c| forces.iter().map(move |f| (*c, *f)))
        .enumerate()
        .map(|(i, (c, f))| (c, f, args.seed + i as u64))
        .collect();
    let bar = ProgressBar::with_draw_target(Some(jobs.len() as u64), ProgressDrawTarget::stderr());
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} records, {elapsed} ({msg})")
            .expect("a valid template"),
    );
    let t0 = Instant::now();
    let mut rows = Vec::new();
    for (case, kind, seed) in jobs {
        bar.set_message(format!("{} ({kind:?})", case.name));
        let t = Instant::now();
        let made = make(case, kind, seed, args.generator);
        let truth = made.as_ref().map_or(Oscillator::benchmark(), |m| m.truth);
        let (outcome, noise_eps) = match made {
            None => (
                Err("the record's simulation diverged".to_string()),
                f64::NAN,
            ),
            Some(m) => {
                if let Some(dir) = &args.records {
                    let name = record_name(case.name, kind, seed);
                    let mut text = String::from("u,y\n");
                    for (u, y) in m.u.iter().zip(&m.y) {
                        text.push_str(&format!("{u:e},{y:e}\n"));
                    }
                    std::fs::create_dir_all(dir)
                        .and_then(|_| std::fs::write(dir.join(&name), text))
                        .map_err(|e| format!("{}: {e}", dir.display()))?;
                    if args.records_only {
                        bar.suspend(|| eprintln!("wrote {}", dir.join(&name).display()));
                        bar.inc(1);
                        continue;
                    }
                }
                let rec = Record {
                    u: &m.u,
                    y: &m.y,
                    fs: FS,
                    interpolation: residual::InputInterpolation::BandLimited,
                };
                let r = residual::refine_record(
                    &rec,
                    Some(2.0),
                    case.start,
                    (0, 3 * N / 4),
                    &[(3 * N / 4, N)],
                )
                .map_err(|e| e.to_string());
                (r, m.noise_eps)
            }
        };
        let row = Row {
            case: case.name,
            force: kind,
            seed,
            outcome,
            noise_eps,
            expect: case.expect,
            seconds: t.elapsed().as_secs_f64(),
            truth,
        };
        bar.suspend(|| eprintln!("{}", line(&row)));
        rows.push(row);
        bar.inc(1);
    }
    bar.finish_and_clear();
    if args.records_only {
        return Ok(());
    }
    let table = markdown(&rows, t0.elapsed().as_secs_f64());
    print!("{table}");
    if let Some(path) = &args.out {
        std::fs::write(path, &table).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn pct(v: f64) -> String {
    format!("{:.3}", 100.0 * v)
}

fn line(r: &Row) -> String {
    let Ok(out) = &r.outcome else {
        let e = r.outcome.as_ref().err().cloned().unwrap_or_default();
        return format!(
            "| {} | {:?} | {} | – | FAILED: {e} | | | | | | FAILED | {:.0} |",
            r.case, r.force, r.seed, r.seconds
        );
    };
    let effects: Vec<String> = out
        .steps
        .iter()
        .filter_map(|s| {
            let e = s.effect?;
            Some(match s.gain {
                Some(g) => format!("{} (p {:.0e})", e.name(), g.p_value),
                None => e.name().to_string(),
            })
        })
        .collect();
    let (b, a) = r.eps().unwrap_or((f64::NAN, f64::NAN));
    let start = if out.start.used != out.start.requested {
        format!("{} (fell back)", out.start.used.name())
    } else if !out.start.notes.is_empty() {
        format!("{} (element afresh)", out.start.used.name())
    } else {
        out.start.used.name().to_string()
    };
    let est = out.noise_epsilon.first().copied().unwrap_or(f64::NAN);
    let left = match (&out.unexplained, out.nonstationary) {
        (_, true) => "nonstationary".to_string(),
        (Some(u), false) => format!("unexplained ({:.2})", u.residual_to_noise),
        (None, false) => "–".to_string(),
    };
    format!(
        "| {} | {:?} | {} | {start} | {} | {} → {} | {} | {} | {:.2} | {left} | {} | {:.0} |",
        r.case,
        r.force,
        r.seed,
        if effects.is_empty() {
            "none".to_string()
        } else {
            effects.join(", ")
        },
        pct(b),
        pct(a),
        pct(r.noise_eps),
        pct(est),
        a / r.noise_eps,
        r.verdict(),
        r.seconds
    )
}

fn markdown(rows: &[Row], seconds: f64) -> String {
    let mut s = String::from(
        "| case | force | seed | start | effects added (held-out p) | held-out ε before → after (%) | noise ε (%) | estimated (%) | after / noise | left | verdict | s |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&line(r));
        s.push('\n');
    }
    let controls: Vec<&Row> = rows
        .iter()
        .filter(|r| r.expect == Expect::Nothing)
        .collect();
    let named: Vec<&Row> = rows
        .iter()
        .filter(|r| matches!(r.expect, Expect::First(_)))
        .collect();
    let drift: Vec<&Row> = rows.iter().filter(|r| r.expect == Expect::Drift).collect();
    let count = |v: &[&Row], f: &dyn Fn(&Row) -> bool| v.iter().filter(|r| f(r)).count();
    let near_noise = |r: &Row| r.eps().is_some_and(|(_, a)| a <= 1.3 * r.noise_eps);
    s.push_str(&format!(
        "\nsummary: controls with a step added {}/{}; right first effect {}/{}; final ε ≤ 1.3 × noise {}/{}; drift reported without a named effect {}/{}; runs stopped on a start {}/{}; {:.0} s\n",
        count(&controls, &|r| r.verdict() != "ok"),
        controls.len(),
        count(&named, &|r| r.verdict() == "ok"),
        named.len(),
        count(&named, &near_noise),
        named.len(),
        count(&drift, &|r| r.verdict() == "ok"),
        drift.len(),
        count(&rows.iter().collect::<Vec<_>>(), &|r| r.outcome.is_err()),
        rows.len(),
        seconds
    ));
    // Calibration of the standard errors: z of every estimate against the truth, on the
    // records whose final model has the truth's terms.
    let mut by_name: Vec<(&str, Vec<f64>)> = Vec::new();
    let mut records = 0;
    for r in rows {
        let z = r.z_scores();
        records += usize::from(!z.is_empty());
        for (name, v) in z {
            match by_name.iter_mut().find(|(n, _)| *n == name) {
                Some((_, list)) => list.push(v),
                None => by_name.push((name, vec![v])),
            }
        }
    }
    let rms = |v: &[f64]| (v.iter().map(|a| a * a).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let sd = |v: &[f64]| {
        let m = mean(v);
        (v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (v.len().max(2) - 1) as f64).sqrt()
    };
    let all: Vec<f64> = by_name
        .iter()
        .flat_map(|(_, v)| v.iter().copied())
        .collect();
    // The mean z is the estimates' bias in standard errors (common to every record: the
    // loop's simulator against the records' own), the spread around it the standard
    // errors' calibration.
    let parts: Vec<String> = by_name
        .iter()
        .map(|(n, v)| {
            format!(
                "{n} mean {:+.2}, sd {:.2}, RMS {:.2} ({})",
                mean(v),
                sd(v),
                rms(v),
                v.len()
            )
        })
        .collect();
    if !all.is_empty() {
        s.push_str(&format!(
            "standard errors: z against the truth over {} estimates of {records} records with the truth's terms: RMS {:.2}, sd {:.2}; by parameter: {}\n",
            all.len(),
            rms(&all),
            sd(&all),
            parts.join("; ")
        ));
    }
    s
}
