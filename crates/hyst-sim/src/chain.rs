//! The measurement chain ([`MeasurementChain`]) applied to a simulated displacement.
//!
//! The displacement is known at every sub-step $t_j = jh$ (the integrator's own points);
//! between them it is the cubic Hermite through $x_j$, $x_{j+1}$ with central-difference
//! slopes (error $O(h^4)$ in value). On each interval the lag $\tau\dot s + s = x$ is solved
//! exactly for that cubic:
//! $$s_{j+1} = e^{-h/\tau}s_j + \sum_{k=0}^{3} p_k I_k,\qquad
//!   I_k = \int_0^h \tfrac{1}{\tau}e^{-(h-\theta)/\tau}\theta^k\,d\theta,$$
//! $p_k$ the cubic's coefficients, and $\dot s = (x - s)/\tau$ exactly at the points. The delay
//! then reads $s(t_j - d)$ from the cubic Hermite through $s$ and $\dot s$; before $t = 0$ the
//! chain holds the initial displacement (a run from rest reads 0 there, which is exact).

use hyst_model::{MeasurementChain, Oscillator};

/// The chain `model`'s output goes through, unless it has none or it does nothing.
pub(crate) fn of(model: &Oscillator) -> Option<MeasurementChain> {
    model.chain.filter(|c| !c.is_identity())
}

/// The weights of $s_{j+1} = E s_j + w_0 x_j + w_1 x_{j+1} + w_2 h m_j + w_3 h m_{j+1}$ ($m$ the
/// slopes), from the integrals $I_k$ of the lag's kernel against $\theta^k$.
struct LagStep {
    e: f64,
    w: [f64; 4],
}

impl LagStep {
    fn new(h: f64, tau: f64) -> Self {
        let r = h / tau;
        // J_k = I_k / h^k (dimensionless): ∫₀¹ (h/τ) e^{−(1−u)h/τ} u^k du.
        let j: [f64; 4] = if r > 1.0 {
            // Integration by parts, stable when τ < h: J_k = 1 − (k/r) J_{k−1}.
            let mut j = [0.0; 4];
            j[0] = -(-r).exp_m1();
            for k in 1..4 {
                j[k] = 1.0 - k as f64 / r * j[k - 1];
            }
            j
        } else {
            // The kernel's series: J_k = r·k!·Σₙ (−r)ⁿ/(n+k+1)!, which converges fast when
            // τ ≥ h (r ≤ 1: 25 terms leave under 1e-25).
            std::array::from_fn(|k| {
                let mut fact = 1.0; // (n + k + 1)!
                for i in 1..=k + 1 {
                    fact *= i as f64;
                }
                let kf: f64 = (1..=k).map(|i| i as f64).product();
                let mut sum = 0.0;
                let mut pow = 1.0;
                for n in 0..25 {
                    sum += pow / fact;
                    pow *= -r;
                    fact *= (n + k + 2) as f64;
                }
                r * kf * sum
            })
        };
        // The cubic on [0, h] in u = θ/h: x_j + h m_j u + (3Δ − 2h m_j − h m_{j+1}) u²
        // + (h m_j + h m_{j+1} − 2Δ) u³, Δ = x_{j+1} − x_j.
        let (j0, j1, j2, j3) = (j[0], j[1], j[2], j[3]);
        LagStep {
            e: (-r).exp(),
            w: [
                j0 - 3.0 * j2 + 2.0 * j3,
                3.0 * j2 - 2.0 * j3,
                j1 - 2.0 * j2 + j3,
                -j2 + j3,
            ],
        }
    }
}

/// Central-difference slopes of `x` (spacing `h`), one-sided second order at the ends.
fn slopes(x: &[f64], h: f64) -> Vec<f64> {
    let n = x.len();
    if n < 3 {
        let m = if n == 2 { (x[1] - x[0]) / h } else { 0.0 };
        return vec![m; n];
    }
    let mut m = Vec::with_capacity(n);
    m.push((-3.0 * x[0] + 4.0 * x[1] - x[2]) / (2.0 * h));
    m.extend(x.windows(3).map(|w| (w[2] - w[0]) / (2.0 * h)));
    m.push((3.0 * x[n - 1] - 4.0 * x[n - 2] + x[n - 3]) / (2.0 * h));
    m
}

/// The chain's output at every point of `x` (displacements every `h` seconds from t = 0).
pub(crate) fn apply(x: &[f64], h: f64, chain: &MeasurementChain) -> Vec<f64> {
    if x.is_empty() || chain.is_identity() {
        return x.to_vec();
    }
    let mx = slopes(x, h);
    let (s, ms) = if chain.lag > 0.0 {
        let step = LagStep::new(h, chain.lag);
        let mut s = Vec::with_capacity(x.len());
        s.push(x[0]);
        for i in 0..x.len() - 1 {
            let w = &step.w;
            let next = step.e * s[i]
                + w[0] * x[i]
                + w[1] * x[i + 1]
                + w[2] * h * mx[i]
                + w[3] * h * mx[i + 1];
            s.push(next);
        }
        let ms: Vec<f64> = s.iter().zip(x).map(|(s, x)| (x - s) / chain.lag).collect();
        (s, ms)
    } else {
        (x.to_vec(), mx)
    };
    if chain.delay == 0.0 {
        return s;
    }
    // t_j − d = (j − q − 1) h + θ h with θ in (0, 1]: the Hermite basis at θ, fixed.
    let steps = chain.delay / h;
    let q = steps.floor() as usize;
    let theta = 1.0 - (steps - q as f64);
    let (t2, t3) = (theta * theta, theta * theta * theta);
    let (h00, h10, h01, h11) = (
        2.0 * t3 - 3.0 * t2 + 1.0,
        t3 - 2.0 * t2 + theta,
        -2.0 * t3 + 3.0 * t2,
        t3 - t2,
    );
    (0..s.len())
        .map(|j| match j.checked_sub(q + 1) {
            Some(i) => h00 * s[i] + h10 * h * ms[i] + h01 * s[i + 1] + h11 * h * ms[i + 1],
            // At or before t = 0 the chain holds the initial value.
            None => s[0],
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine through the chain, after its transient, is the sine scaled by
    /// 1/√(1 + (ωτ)²) and shifted by d + atan(ωτ)/ω: the exact frequency response.
    #[test]
    fn a_sine_comes_out_with_the_chains_gain_and_phase() {
        let fs = 3000.0; // the sub-step rate of 750 Hz at 4 sub-steps
        let h = 1.0 / fs;
        for (f, delay, lag) in [
            (25.0, 0.0, 3e-4),
            (25.0, 2.7e-3, 0.0),
            (100.0, 1.1e-3, 5e-4),
            (150.0, 4.0e-4, 2e-3),
            (25.0, 0.0, 2e-5),
            (10.0, 0.0, 0.05),
        ] {
            let w = 2.0 * std::f64::consts::PI * f;
            let n = 6000;
            let x: Vec<f64> = (0..n).map(|j| (w * j as f64 * h).sin()).collect();
            let y = apply(&x, h, &MeasurementChain { delay, lag });
            let gain = 1.0 / (1.0 + (w * lag).powi(2)).sqrt();
            let phase = w * delay + (w * lag).atan();
            // After 20 lags and the delay the transient is below e^-20.
            let from = ((delay + 20.0 * lag) * fs).ceil() as usize + 2;
            let err = (from..n)
                .map(|j| (y[j] - gain * (w * j as f64 * h - phase).sin()).abs())
                .fold(0.0, f64::max);
            // The central-difference slopes err by (ωh)²/6 of ωA; through the Hermite basis
            // (|h10|, |h11| ≤ 4/27 each) that is at most (ωh)³/20 of A in value, which
            // bounds both the interpolated delay and the lag's integral of the cubic.
            let bound = (w * h).powi(3) / 20.0;
            assert!(
                err < bound,
                "f {f}, d {delay}, τ {lag}: error {err:e} > {bound:e}"
            );
        }
    }

    /// An integer number of steps' delay shifts the samples exactly.
    #[test]
    fn a_whole_step_delay_shifts() {
        let x: Vec<f64> = (0..50).map(|j| ((j as f64) * 0.3).sin()).collect();
        let y = apply(
            &x,
            0.01,
            &MeasurementChain {
                delay: 0.03,
                lag: 0.0,
            },
        );
        for j in 3..50 {
            assert!((y[j] - x[j - 3]).abs() < 1e-12, "{j}");
        }
        assert_eq!(&y[..3], &[x[0]; 3]);
    }

    /// The identity chain and a constant input leave the output alone.
    #[test]
    fn constants_pass_through() {
        let x = vec![0.7; 40];
        let y = apply(
            &x,
            1e-3,
            &MeasurementChain {
                delay: 2.5e-3,
                lag: 4e-3,
            },
        );
        assert!(y.iter().all(|v| (v - 0.7).abs() < 1e-13), "{y:?}");
    }
}
