use super::*;
use approx::assert_relative_eq;

#[test]
fn benchmark_linear_modal_parameters() {
    // README of the benchmark: stiffness k + α gives 35.59 Hz and 1.12 % damping.
    let bw = Oscillator::benchmark();
    let lin = Oscillator::linear(bw.mass, bw.damping, bw.stiffness + 5e4);
    let p = lin.poles().unwrap();
    let l = p.iter().find(|l| l.im > 0.0).unwrap();
    let f = l.norm() / (2.0 * std::f64::consts::PI);
    let zeta = -l.re / l.norm();
    assert!((f - 35.59).abs() < 0.005, "{f}");
    assert!((zeta - 0.0112).abs() < 5e-5, "{zeta}");
}

#[test]
fn bouc_wen_rate_is_finite_at_rest_for_any_nu_and_its_gradient_matches() {
    for nu in [0.3, 0.7, 1.0, 1.5, 3.0] {
        let bw = BoucWen::from_products(5e4, 800.0, -300.0, nu);
        // From rest, z = 0: ż = αv whatever ν (it was NaN for ν < 1).
        assert_eq!(bw.rate(0.01, 0.0), 5e4 * 0.01, "ν = {nu}");
        // Away from z = 0 the gradient is the rate's central difference (relative step
        // 1e-6: truncation and rounding both well below 1e-6 of the derivative).
        for (v, z) in [(0.01, 3.0), (-0.02, 5.0), (0.03, -2.0), (-0.01, -4.0)] {
            let (dv, dz) = bw.rate_gradient(v, z);
            let hv = 1e-6 * v.abs();
            let hz = 1e-6 * z.abs();
            let nv = (bw.rate(v + hv, z) - bw.rate(v - hv, z)) / (2.0 * hv);
            let nz = (bw.rate(v, z + hz) - bw.rate(v, z - hz)) / (2.0 * hz);
            assert_relative_eq!(dv, nv, max_relative = 1e-6);
            assert_relative_eq!(dz, nz, max_relative = 1e-6);
        }
    }
}

#[test]
fn validation_names_the_bad_value() {
    let mut o = Oscillator::benchmark();
    o.mass = 0.0;
    assert_eq!(
        o.validate(),
        Err(ModelError::NonPositive {
            name: "mass",
            value: 0.0
        })
    );
    let mut o = Oscillator::benchmark();
    if let Restoring::BoucWen(bw) = &mut o.restoring {
        bw.nu = -1.0;
    }
    assert!(matches!(
        o.validate(),
        Err(ModelError::NonPositive { name: "nu", .. })
    ));
    let mut o = Oscillator::benchmark();
    o.stiffness = f64::NAN;
    assert!(matches!(
        o.validate(),
        Err(ModelError::NonFinite {
            name: "stiffness",
            ..
        })
    ));
    let o = Oscillator::zener(
        2.0,
        1.0,
        1.0,
        ZenerParams {
            k_inf: 1.0,
            omega: -3.0,
        },
    );
    assert!(matches!(
        o.validate(),
        Err(ModelError::NonPositive { name: "omega", .. })
    ));
    assert!(matches!(
        Oscillator::benchmark().state_space(),
        Err(ModelError::NotLinear { .. })
    ));
}

#[test]
fn jacobian_matches_finite_differences() {
    let mut o = Oscillator::benchmark();
    o.extras = ExtraForces {
        cubic_stiffness: 1e9,
        quadratic_stiffness: -3e6,
        // Engaged at the state below (x = 1e-3): the force's slope is the spring's there.
        clearance: Some(Clearance {
            stiffness: 2e4,
            gap: 5e-4,
        }),
        quadratic_damping: 3.0,
        coulomb: Some(Coulomb {
            force: 2.0,
            smoothing_velocity: 0.05,
        }),
        surface: Some(ForceSurface {
            x_scale: 8e-4,
            v_scale: 0.1,
            coefficients: [1.0, -2.0, 0.5, 0.3, -0.7, 1.1, 0.2, 0.4, -0.9, 0.6],
        }),
        second_mass: Some(SecondMass {
            mass: 0.5,
            stiffness: 2e4,
            damping: 3.0,
        }),
        offset: 0.4,
    };
    let s = State::new(1e-3, 0.07, 20.0, -2e-4, 0.01);
    let j = o.jacobian(&s);
    for c in 0..5 {
        let h = 1e-6 * s[c].abs().max(1e-3);
        let mut sp = s;
        sp[c] += h;
        let mut sm = s;
        sm[c] -= h;
        let d = (o.derivative(&sp, 0.3) - o.derivative(&sm, 0.3)) / (2.0 * h);
        for r in 0..5 {
            // Central differences: truncation O(h²) relative to the entry's scale.
            assert_relative_eq!(j[(r, c)], d[r], epsilon = 1e-6, max_relative = 1e-6);
        }
    }
}

/// The clearance spring is off within its gap and continuous where it engages; the
/// surface's force is its coefficients times its basis at the scaled state; a model with
/// either is not linear, and their bad values are named.
#[test]
fn clearance_and_surface_forces_are_what_they_say() {
    let g = Clearance {
        stiffness: 3e4,
        gap: 1e-3,
    };
    assert_eq!(g.force(0.5e-3), 0.0);
    assert_eq!(g.force(-1e-3), 0.0);
    assert_relative_eq!(g.force(1.5e-3), 15.0, max_relative = 1e-12);
    assert_relative_eq!(g.force(-3e-3), -60.0, max_relative = 1e-12);
    let mut c = [0.0; SURFACE_TERMS];
    c[1] = 2.0; // ξ³
    c[5] = -1.0; // η|η|
    let sf = ForceSurface {
        x_scale: 1e-3,
        v_scale: 0.2,
        coefficients: c,
    };
    // ξ = 2, η = −0.5: 2·8 − (−0.5·0.5) = 16.25 N.
    assert_relative_eq!(sf.force(2e-3, -0.1), 16.25, max_relative = 1e-12);
    let mut o = Oscillator::linear(1.0, 1.0, 1.0);
    o.extras.surface = Some(sf);
    assert!(matches!(
        o.state_space(),
        Err(ModelError::NotLinear {
            what: "a force surface"
        })
    ));
    o.extras.surface = None;
    o.extras.clearance = Some(Clearance {
        stiffness: 1.0,
        gap: 0.0,
    });
    assert_eq!(
        o.validate(),
        Err(ModelError::NonPositive {
            name: "clearance.gap",
            value: 0.0
        })
    );
}

#[test]
fn zener_polynomial_matches_state_space() {
    let o = Oscillator::zener(
        2.0,
        6.4,
        3334.4,
        ZenerParams {
            k_inf: 122150.0,
            omega: 37.68,
        },
    );
    let p = o.characteristic_polynomial().unwrap();
    let q = o.state_space().unwrap().characteristic_polynomial();
    for (a, b) in p.iter().zip(&q) {
        // q is monic: compare with p / m; Faddeev-LeVerrier is exact up to rounding.
        assert_relative_eq!(a / p[0], *b, max_relative = 1e-12);
    }
}
