//! The crate's real FFTs (realfft), in one place: a forward transform of a real record and
//! its inverse, normalised so that `irfft(&rfft(x), x.len()) == x` up to rounding.

use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

pub(crate) type C = Complex<f64>;

/// Bins 0..=n/2 of the DFT of `x`.
pub(crate) fn rfft(x: &[f64]) -> Vec<C> {
    let mut planner = RealFftPlanner::<f64>::new();
    let f = planner.plan_fft_forward(x.len());
    let mut buf = x.to_vec();
    let mut out = f.make_output_vec();
    f.process(&mut buf, &mut out).expect("sizes from the plan");
    out
}

/// The real signal of length `n` whose DFT bins 0..=n/2 are `spec` (divided by n). The
/// imaginary parts a real signal cannot have (DC, and Nyquist for even n) are dropped.
pub(crate) fn irfft(spec: &[C], n: usize) -> Vec<f64> {
    let mut planner = RealFftPlanner::<f64>::new();
    let f = planner.plan_fft_inverse(n);
    let mut buf = spec.to_vec();
    buf[0].im = 0.0;
    if n.is_multiple_of(2)
        && let Some(last) = buf.last_mut()
    {
        last.im = 0.0;
    }
    let mut out = f.make_output_vec();
    f.process(&mut buf, &mut out).expect("sizes from the plan");
    out.iter().map(|v| v / n as f64).collect()
}
