//! The free parameters of a model, by name, in a fixed order, and which of them physics
//! keeps positive.

#[cfg(test)]
use hyst_model::ForceSurface;
use hyst_model::{BoucWen, Oscillator, Restoring, SURFACE_TERMS};

/// The free parameters of a model, in a fixed order. A Bouc-Wen element's exponent ν is
/// free when it differs from 1 (the elements the loop builds have ν = 1 until
/// [`super::Effect::HysteresisExponent`] frees it); a force surface's terms are free where
/// they are not zero.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum P {
    Mass,
    Damping,
    Stiffness,
    KInf,
    Omega,
    Alpha,
    BetaGamma,
    BetaDelta,
    Nu,
    Cubic,
    QuadStiffness,
    ClearanceStiffness,
    ClearanceGap,
    Quad,
    Coulomb,
    Offset,
    Surface(usize),
    M2,
    K2,
    C2,
    Delay,
    Lag,
}

pub(super) fn free(o: &Oscillator, fit_mass: bool) -> Vec<P> {
    let mut v = Vec::new();
    if fit_mass {
        v.push(P::Mass);
    }
    v.extend([P::Damping, P::Stiffness]);
    match o.restoring {
        Restoring::None => {}
        Restoring::Zener(_) => v.extend([P::KInf, P::Omega]),
        Restoring::BoucWen(b) => {
            v.extend([P::Alpha, P::BetaGamma, P::BetaDelta]);
            if b.nu != 1.0 {
                v.push(P::Nu);
            }
        }
    }
    let e = &o.extras;
    if e.cubic_stiffness != 0.0 {
        v.push(P::Cubic);
    }
    if e.quadratic_stiffness != 0.0 {
        v.push(P::QuadStiffness);
    }
    if e.clearance.is_some() {
        v.extend([P::ClearanceStiffness, P::ClearanceGap]);
    }
    if e.quadratic_damping != 0.0 {
        v.push(P::Quad);
    }
    if e.coulomb.is_some() {
        v.push(P::Coulomb);
    }
    if e.offset != 0.0 {
        v.push(P::Offset);
    }
    if let Some(s) = &e.surface {
        v.extend(
            (0..SURFACE_TERMS)
                .filter(|&i| s.coefficients[i] != 0.0)
                .map(P::Surface),
        );
    }
    if e.second_mass.is_some() {
        v.extend([P::M2, P::K2, P::C2]);
    }
    if let Some(c) = o.chain {
        if c.delay != 0.0 {
            v.push(P::Delay);
        }
        if c.lag != 0.0 {
            v.push(P::Lag);
        }
    }
    v
}

/// Whether physics keeps the parameter positive: masses, viscous and quadratic damping,
/// friction, the stiffness and damping of a second mode, a clearance's gap and spring, the
/// Zener element's constants, the Bouc-Wen element's βγ (its loss) and ν, and the
/// measurement chain's delay and lag (a chain that leads its input is not causal). The fits move
/// these on a log scale, so that they cannot cross zero.
pub(super) fn positive(p: P) -> bool {
    matches!(
        p,
        P::Mass
            | P::Damping
            | P::KInf
            | P::Omega
            | P::BetaGamma
            | P::Nu
            | P::ClearanceStiffness
            | P::ClearanceGap
            | P::Quad
            | P::Coulomb
            | P::M2
            | P::K2
            | P::C2
            | P::Delay
            | P::Lag
    )
}

pub(super) fn get(o: &Oscillator, p: P) -> f64 {
    let e = &o.extras;
    match (p, &o.restoring) {
        (P::Mass, _) => o.mass,
        (P::Damping, _) => o.damping,
        (P::Stiffness, _) => o.stiffness,
        (P::KInf, Restoring::Zener(z)) => z.k_inf,
        (P::Omega, Restoring::Zener(z)) => z.omega,
        (P::Alpha, Restoring::BoucWen(b)) => b.alpha,
        (P::BetaGamma, Restoring::BoucWen(b)) => b.beta_gamma(),
        (P::BetaDelta, Restoring::BoucWen(b)) => b.beta_delta(),
        (P::Nu, Restoring::BoucWen(b)) => b.nu,
        (P::Cubic, _) => e.cubic_stiffness,
        (P::QuadStiffness, _) => e.quadratic_stiffness,
        (P::ClearanceStiffness, _) => e.clearance.map_or(0.0, |g| g.stiffness),
        (P::ClearanceGap, _) => e.clearance.map_or(0.0, |g| g.gap),
        (P::Quad, _) => e.quadratic_damping,
        (P::Coulomb, _) => e.coulomb.map_or(0.0, |c| c.force),
        (P::Offset, _) => e.offset,
        (P::Surface(i), _) => e.surface.map_or(0.0, |s| s.coefficients[i]),
        (P::M2, _) => e.second_mass.map_or(0.0, |s| s.mass),
        (P::K2, _) => e.second_mass.map_or(0.0, |s| s.stiffness),
        (P::C2, _) => e.second_mass.map_or(0.0, |s| s.damping),
        (P::Delay, _) => o.chain.map_or(0.0, |c| c.delay),
        (P::Lag, _) => o.chain.map_or(0.0, |c| c.lag),
        _ => 0.0,
    }
}

pub(super) fn set(o: &mut Oscillator, p: P, v: f64) {
    let e = &mut o.extras;
    match p {
        P::Mass => o.mass = v,
        P::Damping => o.damping = v,
        P::Stiffness => o.stiffness = v,
        P::KInf | P::Omega => {
            if let Restoring::Zener(z) = &mut o.restoring {
                if p == P::KInf {
                    z.k_inf = v
                } else {
                    z.omega = v
                }
            }
        }
        P::Alpha | P::BetaGamma | P::BetaDelta | P::Nu => {
            if let Restoring::BoucWen(b) = &mut o.restoring {
                let (mut a, mut bg, mut bd, mut nu) =
                    (b.alpha, b.beta_gamma(), b.beta_delta(), b.nu);
                match p {
                    P::Alpha => a = v,
                    P::BetaGamma => bg = v,
                    P::BetaDelta => bd = v,
                    _ => nu = v,
                }
                *b = BoucWen::from_products(a, bg, bd, nu);
            }
        }
        P::Cubic => e.cubic_stiffness = v,
        P::QuadStiffness => e.quadratic_stiffness = v,
        P::ClearanceStiffness | P::ClearanceGap => {
            if let Some(g) = &mut e.clearance {
                if p == P::ClearanceGap {
                    g.gap = v
                } else {
                    g.stiffness = v
                }
            }
        }
        P::Quad => e.quadratic_damping = v,
        P::Offset => e.offset = v,
        P::Coulomb => {
            if let Some(c) = &mut e.coulomb {
                c.force = v
            }
        }
        P::Surface(i) => {
            if let Some(s) = &mut e.surface {
                s.coefficients[i] = v
            }
        }
        P::M2 | P::K2 | P::C2 => {
            if let Some(s) = &mut e.second_mass {
                match p {
                    P::M2 => s.mass = v,
                    P::K2 => s.stiffness = v,
                    _ => s.damping = v,
                }
            }
        }
        P::Delay | P::Lag => {
            if let Some(c) = &mut o.chain {
                if p == P::Delay {
                    c.delay = v
                } else {
                    c.lag = v
                }
            }
        }
    }
}

/// Names of a surface's terms as parameters (`surface xi^3`, …).
const SURFACE_NAMES: [&str; SURFACE_TERMS] = [
    "surface xi^2",
    "surface xi^3",
    "surface xi^4",
    "surface xi^5",
    "surface eta^2",
    "surface eta|eta|",
    "surface eta^3",
    "surface jump(eta)",
    "surface xi^2 eta",
    "surface xi eta^2",
];

impl P {
    pub(super) fn name(self) -> &'static str {
        match self {
            P::Mass => "mass",
            P::Damping => "damping",
            P::Stiffness => "stiffness",
            P::KInf => "k_inf",
            P::Omega => "omega",
            P::Alpha => "alpha",
            P::BetaGamma => "beta_gamma",
            P::BetaDelta => "beta_delta",
            P::Nu => "nu",
            P::Cubic => "cubic_stiffness",
            P::QuadStiffness => "quadratic_stiffness",
            P::ClearanceStiffness => "clearance_stiffness",
            P::ClearanceGap => "clearance_gap",
            P::Quad => "quadratic_damping",
            P::Coulomb => "coulomb_force",
            P::Offset => "offset",
            P::Surface(i) => SURFACE_NAMES[i],
            P::M2 => "second_mass",
            P::K2 => "second_stiffness",
            P::C2 => "second_damping",
            P::Delay => "chain_delay",
            P::Lag => "chain_lag",
        }
    }
}

impl P {
    /// Every parameter, each surface term once.
    #[cfg(any(feature = "serde", test))]
    fn all() -> impl Iterator<Item = P> {
        [
            P::Mass,
            P::Damping,
            P::Stiffness,
            P::KInf,
            P::Omega,
            P::Alpha,
            P::BetaGamma,
            P::BetaDelta,
            P::Nu,
            P::Cubic,
            P::QuadStiffness,
            P::ClearanceStiffness,
            P::ClearanceGap,
            P::Quad,
            P::Coulomb,
            P::Offset,
            P::M2,
            P::K2,
            P::C2,
            P::Delay,
            P::Lag,
        ]
        .into_iter()
        .chain((0..SURFACE_TERMS).map(P::Surface))
    }
}

/// A parameter's name read from JSON: one of the names [`P::name`] gives, else an error
/// listing them.
#[cfg(feature = "serde")]
pub(super) fn deserialize_name<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<std::borrow::Cow<'static, str>, D::Error> {
    let s = <String as serde::Deserialize>::deserialize(d)?;
    let found = P::all().map(P::name).find(|n| *n == s);
    found.map(std::borrow::Cow::Borrowed).ok_or_else(|| {
        let known: Vec<&str> = P::all().map(P::name).collect();
        serde::de::Error::custom(format!(
            "unknown parameter `{s}`, expected one of {}",
            known.join(", ")
        ))
    })
}

/// Every name of [`SURFACE_NAMES`] is the model's own term name after `surface `.
#[cfg(test)]
#[test]
fn surface_parameter_names_follow_the_model() {
    assert_eq!(P::all().count(), 21 + SURFACE_TERMS);
    for (n, t) in SURFACE_NAMES.iter().zip(ForceSurface::TERMS) {
        assert_eq!(n.strip_prefix("surface "), Some(t));
    }
}
