//! Property tests of the models: the state-space poles of eqs. (25)/(32) are the roots of the
//! characteristic polynomial.

use hyst_model::{Oscillator, ZenerParams, poly};
use nalgebra::Complex;
use proptest::prelude::*;

/// Every root in `a` has a partner in `b` within `tol` relative to its magnitude.
fn same_roots(a: &[Complex<f64>], b: &[Complex<f64>], tol: f64) -> bool {
    a.len() == b.len()
        && a.iter()
            .all(|r| b.iter().any(|s| (r - s).norm() <= tol * r.norm().max(1.0)))
}

proptest! {
    #[test]
    fn zener_poles_are_roots_of_eq32(
        m in 0.5f64..5.0, c in 0.0f64..50.0, k in 1.0f64..1e5,
        k_inf in 1e3f64..2e5, omega in 0.1f64..500.0,
    ) {
        let o = Oscillator::zener(m, c, k, ZenerParams { k_inf, omega });
        let eig = o.poles().unwrap();
        let roots = poly::roots(&o.characteristic_polynomial().unwrap());
        // Eigenvalues (Schur) and polynomial roots (Aberth) are independent computations; both
        // are accurate to ~1e-12 of the largest root for these well-separated roots.
        prop_assert!(same_roots(&eig, &roots, 1e-8), "eig {eig:?} roots {roots:?}");
        // The real pole exists and is negative: the relaxation adds an overdamped mode.
        prop_assert!(eig.iter().any(|l| l.im.abs() < 1e-9 * l.norm() && l.re < 0.0));
    }

    #[test]
    fn linear_poles_are_roots(m in 0.5f64..5.0, c in 0.0f64..50.0, k in 1.0f64..1e5) {
        let o = Oscillator::linear(m, c, k);
        let eig = o.poles().unwrap();
        let roots = poly::roots(&o.characteristic_polynomial().unwrap());
        prop_assert!(same_roots(&eig, &roots, 1e-8));
    }
}
