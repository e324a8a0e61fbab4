//! Exact recovery: fed the exact correlations of known linear systems, SSI-COV returns their
//! poles to 1e-8 relative, and their shapes C·ψ as well.

use covssi::{Complex64, Correlations, SsiOptions, identify_from_correlations, mac, mpc};

/// Real modal form of a discrete system with the given continuous poles (pairs given once,
/// with Im > 0; real poles with Im = 0) at sampling interval dt. Returns A_d (column-major).
fn modal_a(poles: &[Complex64], dt: f64) -> (usize, Vec<f64>) {
    let n: usize = poles.iter().map(|p| if p.im == 0.0 { 1 } else { 2 }).sum();
    let mut a = vec![0.0; n * n];
    let mut k = 0;
    for p in poles {
        let mu = (p * dt).exp();
        if p.im == 0.0 {
            a[k * n + k] = mu.re;
            k += 1;
        } else {
            a[k * n + k] = mu.re;
            a[(k + 1) * n + k] = -mu.im;
            a[k * n + k + 1] = mu.im;
            a[(k + 1) * n + k + 1] = mu.re;
            k += 2;
        }
    }
    (n, a)
}

/// R_k = C A^k G for k < lags, with fixed pseudo-random C (l × n) and G (n × l); also C
/// (column-major, `c[a + j·l]`).
fn exact_correlations(
    poles: &[Complex64],
    dt: f64,
    l: usize,
    lags: usize,
) -> (Correlations, Vec<f64>) {
    let (n, a) = modal_a(poles, dt);
    let mut seed = 12345u64;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let c: Vec<f64> = (0..l * n).map(|_| rnd()).collect(); // c[a + j·l]
    let mut ag: Vec<f64> = (0..n * l).map(|_| rnd()).collect(); // A^k G, column-major n × l
    let mut r = Vec::with_capacity(lags);
    for _ in 0..lags {
        let mut rk = vec![0.0; l * l];
        for b in 0..l {
            for row in 0..l {
                rk[row + b * l] = (0..n).map(|j| c[row + j * l] * ag[j + b * n]).sum();
            }
        }
        r.push(rk);
        let mut next = vec![0.0; n * l];
        for b in 0..l {
            for row in 0..n {
                next[row + b * n] = (0..n).map(|j| a[row + j * n] * ag[j + b * n]).sum();
            }
        }
        ag = next;
    }
    (
        Correlations {
            channels: l,
            references: l,
            r,
        },
        c,
    )
}

/// The true shapes C·ψ of `poles` in `modal_a`'s form: a pair's block [[Re μ, −Im μ],
/// [Im μ, Re μ]] at states (k, k+1) has the eigenvector e_k − i e_{k+1} for μ (Im > 0),
/// a real pole the unit vector of its state.
fn true_shapes(poles: &[Complex64], c: &[f64], l: usize) -> Vec<Vec<Complex64>> {
    let mut k = 0;
    poles
        .iter()
        .map(|p| {
            let col = |j: usize| &c[j * l..(j + 1) * l];
            let shape = if p.im == 0.0 {
                col(k).iter().map(|&v| Complex64::new(v, 0.0)).collect()
            } else {
                col(k)
                    .iter()
                    .zip(col(k + 1))
                    .map(|(&re, &im)| Complex64::new(re, -im))
                    .collect()
            };
            k += if p.im == 0.0 { 1 } else { 2 };
            shape
        })
        .collect()
}

fn recover(poles: &[Complex64], fs: f64, l: usize, block_rows: usize) {
    let order: usize = poles.iter().map(|p| if p.im == 0.0 { 1 } else { 2 }).sum();
    let (corr, c) = exact_correlations(poles, 1.0 / fs, l, 2 * block_rows);
    let opts = SsiOptions {
        max_order: Some(order),
        ..SsiOptions::default()
    };
    let res = identify_from_correlations(&corr, fs, block_rows, &opts).unwrap();
    let last = res.diagram.orders.last().unwrap();
    assert_eq!(last.order, order);
    for (p, shape) in poles.iter().zip(true_shapes(poles, &c, l)) {
        let (best, q) = last
            .poles
            .iter()
            .map(|q| ((q.lambda - p).norm() / p.norm(), q))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .expect("poles at the system's order");
        assert!(best <= 1e-8, "pole {p}: relative error {best:e}");
        // The identified (A, C) is (T⁻¹AT, CT) for some T, so C·ψ is the true shape up to a
        // complex scale; its error is of the poles' order, so 1 − MAC of its square, ~1e-16
        // (allowed: 1e-12). MPC compares the shape with itself: identified and true agree.
        let miss = 1.0 - mac(&q.shape, &shape);
        eprintln!(
            "pole {p}: 1 - MAC {miss:.1e}, MPC {:.6} (true {:.6})",
            mpc(&q.shape),
            mpc(&shape)
        );
        assert!(miss <= 1e-12, "pole {p}: 1 - MAC = {miss:e}");
        assert!((mpc(&q.shape) - mpc(&shape)).abs() <= 1e-10);
    }
    assert_eq!(last.poles.len(), poles.len());
}

#[test]
fn sdof() {
    // 1.5 Hz, 2 % damping, fs = 20 Hz.
    let w = 2.0 * std::f64::consts::PI * 1.5;
    let z: f64 = 0.02;
    recover(
        &[Complex64::new(-z * w, w * (1.0 - z * z).sqrt())],
        20.0,
        1,
        10,
    );
}

/// The 3-DOF chain of the OMA records: 1.0017 Hz 1 %, 2.8067 Hz 2 %, 4.0558 Hz 5 %.
fn three_dof_poles() -> Vec<Complex64> {
    [(1.0017f64, 0.01f64), (2.8067, 0.02), (4.0558, 0.05)]
        .iter()
        .map(|&(f, z)| {
            let w = 2.0 * std::f64::consts::PI * f;
            Complex64::new(-z * w, w * (1.0 - z * z).sqrt())
        })
        .collect()
}

#[test]
fn three_dof_three_channels() {
    let poles = three_dof_poles();
    recover(&poles, 20.0, 3, 10);
}

#[test]
fn three_dof_one_channel() {
    let poles = three_dof_poles();
    recover(&poles, 20.0, 1, 20);
}

#[test]
fn zener_three_states_with_its_real_pole() {
    // The paper's Section 4 system: λ = −19.9414 ± 249.7904i and the relaxation pole −1,
    // sampled at 750 Hz.
    recover(
        &[
            Complex64::new(-19.9414, 249.7904),
            Complex64::new(-1.0, 0.0),
        ],
        750.0,
        1,
        30,
    );
}
