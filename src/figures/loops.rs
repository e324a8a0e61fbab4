//! Hysteresis loops: the restoring force k·x + z each identified model's element gives along
//! the measured displacement.

use crate::model::{Oscillator, Restoring};
use crate::plot::{Series, chart, colors};

/// The element force z along the displacement `x` sampled at `fs` Hz, from z = 0: the
/// velocity by central differences, linear between samples, and z by one RK4 step per
/// sample (the element's own rate: Zener's k∞ẋ − Ωz, Bouc-Wen's eq. 2).
fn element_force(restoring: &Restoring, x: &[f64], fs: f64) -> Vec<f64> {
    let n = x.len();
    let v: Vec<f64> = (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            (x[b] - x[a]) * fs / (b - a).max(1) as f64
        })
        .collect();
    let rate = |v: f64, z: f64| match restoring {
        Restoring::None => 0.0,
        Restoring::Zener(p) => p.k_inf * v - p.omega * z,
        Restoring::BoucWen(b) => b.rate(v, z),
    };
    let h = 1.0 / fs;
    let mut z = 0.0;
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        out.push(z);
        let (v0, v1) = (v[k], v[(k + 1).min(n - 1)]);
        let vm = 0.5 * (v0 + v1);
        let k1 = rate(v0, z);
        let k2 = rate(vm, z + 0.5 * h * k1);
        let k3 = rate(vm, z + 0.5 * h * k2);
        let k4 = rate(v1, z + h * k3);
        z += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    out
}

/// Draw, into `path`, the restoring force k·x + z (N) against x (m) of each model along the
/// displacement `x` at `fs` Hz over its last `cycles` periods of `dominant_hz` (z started
/// from rest at the record's start, so its start-up is not drawn).
pub(crate) fn loops_figure(
    path: &std::path::Path,
    models: &[(&str, &Oscillator)],
    x: &[f64],
    fs: f64,
    dominant_hz: f64,
    cycles: f64,
) -> Result<(), String> {
    let shown = ((cycles * fs / dominant_hz).ceil() as usize).clamp(2, x.len());
    let start = x.len() - shown;
    let palette = [colors::GREY, colors::BLUE, colors::RED, colors::GREEN];
    let series: Vec<Series> = models
        .iter()
        .zip(palette.iter().cycle())
        .map(|((label, m), c)| {
            let z = element_force(&m.restoring, x, fs);
            let points = (start..x.len())
                .map(|k| (x[k], m.stiffness * x[k] + z[k]))
                .collect();
            (label.to_string(), points, *c)
        })
        .collect();
    chart(
        path,
        "Restoring force k·x + z of each model along the measured displacement",
        "x (m)",
        "k·x + z (N)",
        &series,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Along x = A sin ωt the Zener element's steady force is k∞ A ω/√(ω²+Ω²) in amplitude
    /// (its transfer function k∞ s/(s + Ω)); the integration along sampled x gets it to the
    /// error of central differences at 200 samples per period, (ωh)²/6 = 1.6e-4.
    #[test]
    fn a_zener_element_driven_harmonically_has_its_transfer_functions_amplitude() {
        let (k_inf, omega, a, f, fs) = (8e4, 60.0, 1e-3, 10.0, 2000.0);
        let w = 2.0 * std::f64::consts::PI * f;
        let x: Vec<f64> = (0..4000).map(|k| a * (w * k as f64 / fs).sin()).collect();
        let r = Restoring::Zener(crate::model::ZenerParams { k_inf, omega });
        let z = element_force(&r, &x, fs);
        let last = &z[3800..];
        let amplitude = last.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let want = k_inf * a * w / (w * w + omega * omega).sqrt();
        approx::assert_relative_eq!(amplitude, want, max_relative = 1e-3);
    }
}
