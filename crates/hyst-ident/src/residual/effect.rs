//! The effects the loop can add to a model.

/// An effect the loop can add.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(rename_all = "snake_case"))]
pub enum Effect {
    /// Cubic spring $k_3x^3$.
    CubicStiffness,
    /// Quadratic (asymmetric) spring $k_qx^2$.
    QuadraticStiffness,
    /// A spring engaging beyond a clearance $\pm g$ ([`hyst_model::Clearance`]).
    Clearance,
    /// Quadratic damping $c_q\dot x|\dot x|$.
    QuadraticDamping,
    /// Coulomb friction $F_c\tanh(\dot x/v_\varepsilon)$.
    CoulombFriction,
    /// A constant force $f_0$: a preload, or an offset of the measured input against the
    /// output (a bias the sensors add).
    Offset,
    /// A second mass on a spring and damper.
    SecondMode,
    /// A Bouc-Wen hysteretic element: added to a model without a restoring element, or in
    /// place of a Zener element (its linearization), started from the Bouc-Wen elements
    /// whose describing function equals the Zener's at the model's resonance.
    Hysteresis,
    /// The Bouc-Wen element's exponent ν freed (ν = 1 until then): how sharply the element
    /// turns from stiff to slipping. Started from elements of several ν whose describing
    /// function at A = σₓ equals the current element's.
    HysteresisExponent,
    /// The record's output delayed against its input by d
    /// ([`hyst_model::MeasurementChain::delay`]): the acquisition (a sensor, its conditioning,
    /// a skew between the channels, an anti-aliasing filter's group delay), not structure.
    OutputDelay,
    /// The output sensor's first-order lag τ ([`hyst_model::MeasurementChain::lag`]): the
    /// acquisition, not structure.
    SensorLag,
    /// The missing force's own fit on the surface basis ([`hyst_model::ForceSurface`]): its
    /// significant terms, kept when no named effect explains the residual as well.
    RestoringSurface,
}

impl Effect {
    /// The name used in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Effect::CubicStiffness => "cubic_stiffness",
            Effect::QuadraticStiffness => "quadratic_stiffness",
            Effect::Clearance => "clearance",
            Effect::QuadraticDamping => "quadratic_damping",
            Effect::CoulombFriction => "coulomb_friction",
            Effect::Offset => "offset",
            Effect::SecondMode => "second_mode",
            Effect::Hysteresis => "hysteresis",
            Effect::HysteresisExponent => "hysteresis_exponent",
            Effect::OutputDelay => "output_delay",
            Effect::SensorLag => "sensor_lag",
            Effect::RestoringSurface => "restoring_surface",
        }
    }

    /// Every candidate.
    pub const ALL: [Effect; 12] = [
        Effect::CubicStiffness,
        Effect::QuadraticStiffness,
        Effect::Clearance,
        Effect::QuadraticDamping,
        Effect::CoulombFriction,
        Effect::Offset,
        Effect::SecondMode,
        Effect::Hysteresis,
        Effect::HysteresisExponent,
        Effect::OutputDelay,
        Effect::SensorLag,
        Effect::RestoringSurface,
    ];

    /// Whether the effect is one of the named ones (every one but the surface).
    pub fn is_named(&self) -> bool {
        *self != Effect::RestoringSurface
    }

    /// Whether the effect is the measurement chain's, not the structure's.
    pub fn is_measurement_chain(&self) -> bool {
        matches!(self, Effect::OutputDelay | Effect::SensorLag)
    }
}
