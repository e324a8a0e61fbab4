//! The paper's relations exactly as printed, for comparison. Several do not hold; see the crate
//! docs and `docs/paper-deviations.md`. Nothing here checks its inputs: these are formulas,
//! kept verbatim so that tests can measure how far they are from what holds.

use nalgebra::Complex;

/// Eq. (13): $k_\infty/\Omega = \frac{3\pi}{4}\,\frac{\alpha}{2A\omega(\beta\gamma+\beta\delta)}$.
pub fn eq13_kinf_over_omega(alpha: f64, beta_gamma: f64, beta_delta: f64, a: f64, w: f64) -> f64 {
    0.75 * std::f64::consts::PI * alpha / (2.0 * a * w * (beta_gamma + beta_delta))
}

/// Eq. (19): $k_\infty = \frac{3\pi}{4}\,\frac{\alpha}{A\beta\delta + 3\pi/4}$.
pub fn eq19_kinf(alpha: f64, beta_delta: f64, a: f64) -> f64 {
    let q = 0.75 * std::f64::consts::PI;
    q * alpha / (a * beta_delta + q)
}

/// Eq. (20): $\Omega = 2A\omega\,\frac{\beta\gamma+\beta\delta}{A\beta\delta + 3\pi/4}$.
pub fn eq20_omega(beta_gamma: f64, beta_delta: f64, a: f64, w: f64) -> f64 {
    2.0 * a * w * (beta_gamma + beta_delta) / (a * beta_delta + 0.75 * std::f64::consts::PI)
}

/// Eq. (33): $k = \frac{m^2\lambda_1\lambda_2\lambda_3}{(\lambda_1+\lambda_2+\lambda_3)m + c}$.
pub fn eq33_k(m: f64, c: f64, l: [Complex<f64>; 3]) -> f64 {
    let num = l[0] * l[1] * l[2] * (m * m);
    let den = (l[0] + l[1] + l[2]) * m + c;
    (num / den).re
}

/// Eq. (34): $k_\infty = -\frac{(m\lambda_1^2+c\lambda_1+k)(m\lambda_2^2+c\lambda_2+k)}{-m\lambda_1\lambda_2+k}$.
pub fn eq34_kinf(m: f64, c: f64, k: f64, l: [Complex<f64>; 3]) -> f64 {
    let p = |x: Complex<f64>| x * x * m + x * c + k;
    (-(p(l[0]) * p(l[1])) / (-(l[0] * l[1]) * m + k)).re
}

/// Eq. (35): $\Omega = \lambda_1\left(1 + \frac{k_\infty}{m\lambda_1^2+c\lambda_1+k}\right)$.
pub fn eq35_omega(m: f64, c: f64, k: f64, k_inf: f64, l: [Complex<f64>; 3]) -> f64 {
    let l1 = l[0];
    (l1 * (Complex::new(1.0, 0.0) + Complex::new(k_inf, 0.0) / (l1 * l1 * m + l1 * c + k))).re
}

/// Eq. (37) with the + sign: $\alpha = \frac{c^2}{4m} + \operatorname{Im}(\lambda)^2 m - k$.
pub fn eq37_alpha(m: f64, c: f64, k: f64, im_lambda: f64) -> f64 {
    c * c / (4.0 * m) + im_lambda * im_lambda * m - k
}

/// Eq. (38): returns $(\beta\gamma, \beta\delta)$ with
/// $\beta\delta = \frac{3\pi}{4A}(\alpha/k_\infty - 1)$ and
/// $\beta\gamma = \frac{3\pi}{4A}\left(1 + \frac{\Omega\alpha}{2\omega k_\infty} - \frac{\alpha}{k_\infty}\right)$.
pub fn eq38_beta(alpha: f64, k_inf: f64, omega: f64, a: f64, w: f64) -> (f64, f64) {
    let q = 0.75 * std::f64::consts::PI / a;
    let bd = q * (alpha / k_inf - 1.0);
    let bg = q * (1.0 + omega * alpha / (2.0 * w * k_inf) - alpha / k_inf);
    (bg, bd)
}
