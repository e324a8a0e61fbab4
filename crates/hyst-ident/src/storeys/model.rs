//! The model the fit moves: a shear chain of known floor masses, its storey stiffnesses
//! $k_s$, each mode's damping ratio $\zeta_j$ (classical damping), each level's force
//! density $q_l$, and in one storey (a candidate) a Bouc-Wen element of share $1-a$ of the
//! storey's stiffness with (β, γ) at a fixed ν. The fit sees them divided by their starting
//! values (every parameter near 1, so one finite-difference rule suits all).

use hyst_sim::building::{Load, Reading as Quantity, ShearBuilding, StoreyHysteresis};
use nalgebra::{DMatrix, SymmetricEigen};

use super::error::StoreyError;

/// Where each parameter sits in the vector.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Layout {
    /// Floors (= storeys = modes).
    pub(crate) floors: usize,
    /// Levels (one force density each).
    pub(crate) levels: usize,
    /// The storey holding the element (0-based), if any.
    pub(crate) storey: Option<usize>,
    /// Accelerations: the force's folded band `b` is a parameter (`statistics.rs`).
    pub(crate) folded: bool,
}

impl Layout {
    /// Each parameter's name: `k1`…, `zeta1`…, `q1`…, then `a`, `beta`, `gamma`.
    pub(crate) fn names(&self) -> Vec<String> {
        let mut out: Vec<String> = (1..=self.floors).map(|s| format!("k{s}")).collect();
        out.extend((1..=self.floors).map(|j| format!("zeta{j}")));
        out.extend((1..=self.levels).map(|l| format!("q{l}")));
        if self.folded {
            out.push("b".into());
        }
        if self.storey.is_some() {
            out.extend(["a", "beta", "gamma"].map(String::from));
        }
        out
    }
}

/// The structure the parameters `theta` (physical units, in the layout's order) make from
/// `template` (masses, sensors, quantity read, rate), with each level's force density and
/// the folded band (0 unless a parameter).
pub(crate) fn building(
    template: &ShearBuilding,
    layout: &Layout,
    theta: &[f64],
    nu: f64,
) -> Result<(ShearBuilding, Vec<f64>, f64), StoreyError> {
    let n = layout.floors;
    let check = |name: &'static str, v: f64, ok: bool| {
        if ok && v.is_finite() {
            Ok(v)
        } else {
            Err(StoreyError::Unphysical { name, value: v })
        }
    };
    let stiffnesses = theta[..n]
        .iter()
        .map(|&k| check("a storey stiffness (N/m)", k, k > 0.0))
        .collect::<Result<Vec<_>, _>>()?;
    let damping_ratios = theta[n..2 * n]
        .iter()
        .map(|&z| check("a damping ratio", z, z > 0.0 && z < 1.0))
        .collect::<Result<Vec<_>, _>>()?;
    let q = theta[2 * n..2 * n + layout.levels]
        .iter()
        .map(|&q| check("a force density (N²/Hz)", q, q > 0.0))
        .collect::<Result<Vec<_>, _>>()?;
    let mut at = 2 * n + layout.levels;
    let folded = if layout.folded {
        at += 1;
        check("the folded band b", theta[at - 1], theta[at - 1] >= 0.0)?
    } else {
        0.0
    };
    let hysteresis = match layout.storey {
        None => None,
        Some(storey) => {
            let h = &theta[at..];
            let (a, beta, gamma) = (h[0], h[1], h[2]);
            check("the linear share a", a, (0.0..1.0).contains(&a))?;
            check("β (1/m^ν)", beta, beta >= 0.0)?;
            // Bounded z (Ismail et al. 2009, Bouc-Wen's stability): β + γ > 0 and γ ≤ β.
            check("β + γ (1/m^ν)", beta + gamma, beta + gamma > 0.0)?;
            check("β − γ (1/m^ν)", beta - gamma, beta >= gamma)?;
            Some(StoreyHysteresis {
                storey,
                linear_share: a,
                beta,
                gamma,
                nu,
            })
        }
    };
    Ok((
        ShearBuilding {
            stiffnesses,
            damping_ratios,
            hysteresis,
            ..template.clone()
        },
        q,
        folded,
    ))
}

/// A template: the masses, the channels' floors, the quantity read, the rate; a unit load
/// on `load_floors`, no sensor errors.
pub(crate) fn template(
    masses: &[f64],
    sensors: &[usize],
    quantity: Quantity,
    fs: f64,
    load_floors: &[usize],
) -> ShearBuilding {
    ShearBuilding {
        masses: masses.to_vec(),
        stiffnesses: vec![1.0; masses.len()],
        damping_ratios: vec![0.01; masses.len()],
        hysteresis: None,
        load: Load {
            floors: load_floors.to_vec(),
            rms: 1.0,
            colours: vec![],
            modulation: None,
            harmonic: None,
        },
        sensors: sensors.to_vec(),
        reading: quantity,
        noise: 0.0,
        drift: 0.0,
        fs,
    }
}

/// The storey stiffnesses of a chain of `masses` whose natural frequencies are `hz` (lowest
/// first, one per floor): Gauss–Newton on the logarithms, the eigenvalues' derivatives
/// $\partial\omega_j^2/\partial k_s = (\phi_{j,s}-\phi_{j,s-1})^2$ (mass-normalized shapes),
/// from equal storeys matching the lowest mode.
pub(crate) fn stiffnesses_for(masses: &[f64], hz: &[f64]) -> Vec<f64> {
    let n = masses.len();
    let target: Vec<f64> = hz
        .iter()
        .map(|f| (2.0 * std::f64::consts::PI * f).powi(2))
        .collect();
    let mut k = vec![1.0; n];
    let (w0, _) = eigen(masses, &k);
    k.iter_mut().for_each(|v| *v = target[0] / w0[0]);
    for _ in 0..50 {
        let (w2, phi) = eigen(masses, &k);
        let r: Vec<f64> = (0..n).map(|j| (w2[j] / target[j]).ln()).collect();
        if r.iter().all(|v| v.abs() < 1e-12) {
            break;
        }
        // ∂ ln ω_j² / ∂ ln k_s.
        let jac = DMatrix::from_fn(n, n, |j, s| {
            let below = if s > 0 { phi[(s - 1, j)] } else { 0.0 };
            k[s] * (phi[(s, j)] - below).powi(2) / w2[j]
        });
        let Some(step) = jac.lu().solve(&nalgebra::DVector::from_vec(r)) else {
            break;
        };
        // At most a factor e per step in any storey.
        let big = step.amax().max(1.0);
        for (v, d) in k.iter_mut().zip(step.iter()) {
            *v *= (-d / big).exp();
        }
    }
    k
}

/// Squared natural frequencies (ascending) and mass-normalized shapes (columns).
fn eigen(masses: &[f64], k: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
    let n = masses.len();
    let mut kk = DMatrix::<f64>::zeros(n, n);
    for (s, &ks) in k.iter().enumerate() {
        kk[(s, s)] += ks;
        if s > 0 {
            kk[(s - 1, s - 1)] += ks;
            kk[(s - 1, s)] -= ks;
            kk[(s, s - 1)] -= ks;
        }
    }
    let inv: Vec<f64> = masses.iter().map(|m| 1.0 / m.sqrt()).collect();
    let a = DMatrix::from_fn(n, n, |i, j| inv[i] * kk[(i, j)] * inv[j]);
    let e = SymmetricEigen::new(a);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| e.eigenvalues[i].total_cmp(&e.eigenvalues[j]));
    let w2 = order.iter().map(|&i| e.eigenvalues[i]).collect();
    let phi = DMatrix::from_fn(n, n, |r, c| inv[r] * e.eigenvectors[(r, order[c])]);
    (w2, phi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stiffnesses_give_the_frequencies_back() {
        let masses = [2000.0, 1500.0, 1000.0];
        let k = [3e6, 2e6, 1.5e6];
        let (w2, _) = eigen(&masses, &k);
        let hz: Vec<f64> = w2
            .iter()
            .map(|w| w.sqrt() / (2.0 * std::f64::consts::PI))
            .collect();
        let got = stiffnesses_for(&masses, &hz);
        for (g, t) in got.iter().zip(k) {
            // Newton to a residual of 1e-12 in ln ω²: the stiffnesses to ~1e-10.
            assert!((g / t - 1.0).abs() < 1e-8, "{got:?}");
        }
    }

    #[test]
    fn an_unphysical_parameter_is_refused_by_name() {
        let t = template(&[1.0, 1.0], &[0, 1], Quantity::Acceleration, 100.0, &[0, 1]);
        let layout = Layout {
            floors: 2,
            levels: 1,
            storey: Some(1),
            folded: false,
        };
        let good = [1e4, 1e4, 0.02, 0.02, 1.0, 0.5, 10.0, 5.0];
        assert!(building(&t, &layout, &good, 1.0).is_ok());
        let mut bad = good;
        bad[3] = -0.01;
        assert!(matches!(
            building(&t, &layout, &bad, 1.0),
            Err(StoreyError::Unphysical { name: "a damping ratio", value }) if value == -0.01
        ));
        let mut bad = good;
        bad[5] = 1.0;
        assert!(matches!(
            building(&t, &layout, &bad, 1.0),
            Err(StoreyError::Unphysical {
                name: "the linear share a",
                ..
            })
        ));
        assert_eq!(layout.names().len(), good.len());
    }
}
