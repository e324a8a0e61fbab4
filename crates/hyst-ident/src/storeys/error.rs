//! What can stop a storey fit.

/// Errors of [`crate::storeys`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StoreyError {
    /// Fewer than two levels were given.
    #[error("a storey fit needs records at two or more levels, got {levels}")]
    FewLevels {
        /// Levels given.
        levels: usize,
    },
    /// No floor mass, or a mass that is not a positive number.
    #[error("floor {floor}'s mass must be > 0 kg, got {mass}")]
    BadMass {
        /// The floor (1 = the lowest).
        floor: usize,
        /// The mass given (NaN when none was).
        mass: f64,
    },
    /// The masses make a structure that cannot be simulated at the records' modes (its
    /// stiffnesses or forces past what a double holds).
    #[error(
        "the floor masses (the heaviest {mass:.3e} kg) give storey stiffnesses up to {stiffness:.3e} N/m at the records' modes, and a structure of them cannot be simulated ({why}): give the masses in kg"
    )]
    MassesNotSimulable {
        /// The heaviest mass given (kg).
        mass: f64,
        /// The stiffest storey the start gives (N/m).
        stiffness: f64,
        /// What the simulation said.
        why: String,
    },
    /// A channel's floor is not in the structure.
    #[error("channel {channel} is said to be on floor {floor}; the structure has {floors} floors")]
    SensorBeyondTop {
        /// The channel (1-based).
        channel: usize,
        /// Its floor (1-based).
        floor: usize,
        /// Floors of the structure.
        floors: usize,
    },
    /// A loaded floor not in the structure, or named twice.
    #[error("load floor {floor}: {why} (the structure has {floors} floors, counted from 1)")]
    BadLoadFloor {
        /// The floor (1-based).
        floor: usize,
        /// Floors of the structure.
        floors: usize,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A level's record has another number of channels than the sensors named.
    #[error(
        "level {level}'s record has {channels} channel(s); {sensors} sensor floor(s) were named"
    )]
    ChannelCount {
        /// The level (1-based).
        level: usize,
        /// Its channels.
        channels: usize,
        /// Sensors named.
        sensors: usize,
    },
    /// A level's channels differ in length, or are too short.
    #[error(
        "level {level}'s record: channel {channel} has {samples} samples (the first has {first}; at least {needed} are needed)"
    )]
    BadLength {
        /// The level (1-based).
        level: usize,
        /// The channel (1-based).
        channel: usize,
        /// Its samples.
        samples: usize,
        /// The first channel's.
        first: usize,
        /// Fewest usable.
        needed: usize,
    },
    /// SSI of the quietest level did not find a mode per floor.
    #[error(
        "the quietest level's record shows {found} mode(s) below {max_hz:.3} Hz; a shear structure of {floors} floors has {floors}: are the masses and the records of one structure?"
    )]
    TooFewModes {
        /// Modes found.
        found: usize,
        /// Floors.
        floors: usize,
        /// Highest frequency searched (Hz).
        max_hz: f64,
    },
    /// A model the fit reached is not physical (the step is refused).
    #[error("{name} = {value} is not physical")]
    Unphysical {
        /// Which parameter.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// No candidate's fit could be made.
    #[error("no candidate location could be fitted: {}", reasons.join("; "))]
    NoCandidateFitted {
        /// Each failed fit's reason.
        reasons: Vec<String>,
    },
    /// A candidate storey is not in the structure.
    #[error("candidate storey {storey} is not in a structure of {floors} storeys")]
    NoSuchStorey {
        /// The storey (1-based).
        storey: usize,
        /// Storeys.
        floors: usize,
    },
    /// A fit given to a prediction whose parts disagree (read from an edited report).
    #[error("the document does not hold together: {what}")]
    InconsistentFit {
        /// What disagrees.
        what: String,
    },
    /// An option of the fit outside its range.
    #[error("option `{name}` = {value}: {expected}")]
    BadOption {
        /// The [`super::StoreyOptions`] field.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// A record set beside the fit does not read as the level it was given for.
    #[error(
        "record {record} does not read as the fit's level {record}{closest}: its statistics lie at a whitened distance {distance:.1} from that level's, where another record of it lies within {limit:.1} 999 times in 1000; give the records the fit was given, in its order, read as it read them (the same quantity, the channels on the same floors)"
    )]
    NotItsLevel {
        /// The record (1-based).
        record: usize,
        /// ", but as its level j" when another level is nearer, else empty.
        closest: String,
        /// Its whitened squared distance from its level's statistics.
        distance: f64,
        /// What chance reaches.
        limit: f64,
    },
    /// A prediction whose simulated response is not finite.
    #[error("{what}: the fitted structure does not give a finite response at this level")]
    NotFinite {
        /// What is not finite.
        what: String,
    },
    /// A prediction or a record shorter than the fit's reading needs.
    #[error("{samples} samples are too few: the fit's reading needs at least {needed}")]
    TooShort {
        /// Samples asked for or given.
        samples: usize,
        /// Fewest usable (three of Welch's segments).
        needed: usize,
    },
    /// Force columns given for another number of loaded floors.
    #[error("{given} force column(s) given; the fit loads {loaded} floor(s), one column each")]
    ForceColumns {
        /// Columns given.
        given: usize,
        /// Floors loaded.
        loaded: usize,
    },
}
