//! The only place that talks to faer: dense SVD and real non-symmetric eigenproblems on plain
//! column-major buffers, always single-threaded (`Par::Seq`) so that callers parallelised with
//! rayon do not nest thread pools. faer changes its API at every minor release; this module
//! keeps that in one place.

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::linalg::svd::{self, ComputeSvdVectors};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};

pub use num_complex::Complex64 as C64;

/// A dense column-major matrix.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Dense {
    pub rows: usize,
    pub cols: usize,
    pub data: Vec<f64>,
}

impl Dense {
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Dense {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }
    #[inline]
    pub fn at(&self, r: usize, c: usize) -> f64 {
        self.data[c * self.rows + r]
    }
    #[inline]
    pub fn set(&mut self, r: usize, c: usize, v: f64) {
        self.data[c * self.rows + r] = v;
    }
    fn view(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.data, self.rows, self.cols)
    }
    fn from_faer(m: MatRef<'_, f64>) -> Self {
        let mut d = Dense::zeros(m.nrows(), m.ncols());
        for c in 0..m.ncols() {
            for r in 0..m.nrows() {
                d.set(r, c, m[(r, c)]);
            }
        }
        d
    }
}

/// Thin SVD `a = U diag(s) Vᵀ`, singular values in non-increasing order. Returns (U, s).
pub(crate) fn thin_svd_u(a: &Dense) -> Result<(Dense, Vec<f64>), String> {
    let (u, s, _) = svd_parts(a.view(), false)?;
    Ok((Dense::from_faer(u.as_ref()), s))
}

/// The leading `k` singular triplets of `a` by subspace iteration from `start` (orthonormal
/// columns, more than `k`, close to `a`'s leading left singular vectors: those of a matrix
/// `a` differs little from), with Rayleigh–Ritz on the subspace after each sweep:
/// Q ← orth(a aᵀ Q), then the SVD of Qᵀa gives U = Q·U_B, s, V. Accepted when every one of the
/// first `k` triplets has ‖a v − σ u‖ ≤ `tol`·σ₁ (the triplets are then exact for a matrix
/// within about √k·`tol`·‖a‖ of `a`); `Ok(None)` when `max_sweeps` do not get there, for the
/// caller to take the full SVD. Returns U's `start.cols` columns and their singular values.
pub(crate) fn leading_svd_near(
    a: &Dense,
    start: &Dense,
    k: usize,
    (tol, max_sweeps): (f64, usize),
) -> Result<Option<(Dense, Vec<f64>)>, String> {
    let width = start.cols;
    if start.rows != a.rows || k == 0 || width <= k || width > a.rows.min(a.cols) {
        return Ok(None);
    }
    let m = a.view();
    let product = |lhs: MatRef<'_, f64>, rhs: MatRef<'_, f64>| {
        let mut out = Mat::<f64>::zeros(lhs.nrows(), rhs.ncols());
        faer::linalg::matmul::matmul(out.as_mut(), Accum::Replace, lhs, rhs, 1.0, Par::Seq);
        out
    };
    let mut q = start.view().to_owned();
    for _ in 0..max_sweeps {
        // Q ← an orthonormal basis of a aᵀ Q (its left singular vectors).
        let y = product(m, product(m.transpose(), q.as_ref()).as_ref());
        q = svd_parts(y.as_ref(), false)?.0;
        // Rayleigh–Ritz: Qᵀa = U_B diag(s) Vᵀ.
        let (ub, values, v) = svd_parts(product(q.transpose(), m).as_ref(), true)?;
        let u = product(q.as_ref(), ub.as_ref());
        let av = product(m, v.subcols(0, k));
        let converged = (0..k).all(|j| {
            let r2: f64 = (0..a.rows)
                .map(|row| (av[(row, j)] - values[j] * u[(row, j)]).powi(2))
                .sum();
            r2.sqrt() <= tol * values[0]
        });
        if converged {
            return Ok(Some((Dense::from_faer(u.as_ref()), values)));
        }
    }
    Ok(None)
}

/// A linear map that can be applied to blocks of vectors and transposed: a stored matrix,
/// or one applied without being stored (the block Toeplitz matrix by FFT).
pub(crate) trait Operator: Sync {
    /// Rows of the map.
    fn rows(&self) -> usize;
    /// Columns of the map.
    fn cols(&self) -> usize;
    /// `A x` for each column of `x` (`cols × k`).
    fn apply(&self, x: &Dense) -> Dense;
    /// `Aᵀ y` for each column of `y` (`rows × k`).
    fn apply_t(&self, y: &Dense) -> Dense;
}

impl Operator for Dense {
    fn rows(&self) -> usize {
        self.rows
    }
    fn cols(&self) -> usize {
        self.cols
    }
    fn apply(&self, x: &Dense) -> Dense {
        product(self.view(), x.view())
    }
    fn apply_t(&self, y: &Dense) -> Dense {
        product(self.view().transpose(), y.view())
    }
}

/// `lhs · rhs`, single-threaded.
fn product(lhs: MatRef<'_, f64>, rhs: MatRef<'_, f64>) -> Dense {
    let mut out = Dense::zeros(lhs.nrows(), rhs.ncols());
    let o = MatMut::from_column_major_slice_mut(&mut out.data, lhs.nrows(), rhs.ncols());
    faer::linalg::matmul::matmul(o, Accum::Replace, lhs, rhs, 1.0, Par::Seq);
    out
}

/// What [`leading_svd_iterated`] found: the leading left singular vectors and values of
/// the subspace it ended on, the sweeps it took, and whether the asked triplets converged.
#[derive(Debug, Clone)]
pub(crate) struct Iterated {
    /// Left singular vectors (the subspace's width of them).
    pub u: Dense,
    /// Their singular values, non-increasing.
    pub values: Vec<f64>,
    /// Sweeps taken.
    pub sweeps: usize,
    /// Largest residual ‖Aᵀu − σv‖ of the asked triplets, as a share of σ₁.
    pub residual: f64,
    /// Whether that residual is within the tolerance.
    pub converged: bool,
}

/// The leading `k` singular triplets of `a` by subspace iteration from `start` (`a.rows() ×
/// p`, `p > k` columns: a random block, or the leading left singular vectors of a matrix near
/// `a`), one application of `a` and one of `aᵀ` per sweep: W = orth(aᵀQ); a W = U_B S V_Bᵀ;
/// Q ← U_B. The triplets (U_B, S, W V_B) satisfy a v = σ u exactly, so each sweep checks
/// the other half, ‖aᵀ u − σ v‖ ≤ `tol`·σ₁, on the product it makes anyway; the triplets are
/// then exact for a matrix within about √k·`tol`·‖a‖ of `a`. Stops there or after
/// `max_sweeps`, saying which; `on_sweep` hears each sweep's number.
pub(crate) fn leading_svd_iterated(
    a: &dyn Operator,
    start: Dense,
    k: usize,
    (tol, max_sweeps): (f64, usize),
    on_sweep: &dyn Fn(usize),
) -> Result<Iterated, String> {
    let mut q = start;
    let mut last: Option<(Dense, Vec<f64>)> = None; // (V, values) of the previous sweep
    let mut residual = f64::INFINITY;
    for sweep in 1..=max_sweeps.max(1) {
        on_sweep(sweep);
        let z = a.apply_t(&q);
        if let Some((v, values)) = &last {
            residual = (0..k.min(values.len()))
                .map(|j| {
                    (0..z.rows)
                        .map(|row| (z.at(row, j) - values[j] * v.at(row, j)).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max)
                / values[0].max(f64::MIN_POSITIVE);
            if residual <= tol {
                return Ok(Iterated {
                    u: q,
                    values: values.clone(),
                    sweeps: sweep - 1,
                    residual,
                    converged: true,
                });
            }
        }
        let w = thin_q(&z);
        let y = a.apply(&w);
        let (ub, values, vb) = svd_parts(y.view(), true)?;
        let v = product(w.view(), vb.as_ref());
        q = Dense::from_faer(ub.as_ref());
        last = Some((v, values));
    }
    let (_, values) = last.ok_or("no sweep was made")?;
    Ok(Iterated {
        u: q,
        values,
        sweeps: max_sweeps.max(1),
        residual,
        converged: false,
    })
}

/// An orthonormal basis of the columns of `a` (rows ≥ cols): the thin Q of its Householder
/// QR, single-threaded.
pub(crate) fn thin_q(a: &Dense) -> Dense {
    use faer::linalg::{householder, qr::no_pivoting::factor};
    let (m, n) = (a.rows, a.cols);
    let size = m.min(n);
    let mut qr = a.view().to_owned();
    let block = factor::recommended_block_size::<f64>(m, n);
    let mut coeff = Mat::<f64>::zeros(block, size);
    factor::qr_in_place(
        qr.as_mut(),
        coeff.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(factor::qr_in_place_scratch::<f64>(
            m,
            n,
            block,
            Par::Seq,
            Default::default(),
        ))),
        Default::default(),
    );
    let mut q = Mat::<f64>::identity(m, size);
    householder::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        qr.as_ref().subcols(0, size),
        coeff.as_ref(),
        faer::Conj::No,
        q.as_mut(),
        Par::Seq,
        MemStack::new(&mut MemBuffer::new(
            householder::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
                m, block, size,
            ),
        )),
    );
    Dense::from_faer(q.as_ref())
}

/// A thin SVD's U, singular values and V (empty when not asked for).
type SvdParts = (Mat<f64>, Vec<f64>, Mat<f64>);

/// Thin SVD of `a` (single-threaded): U, the singular values and, when asked, V.
fn svd_parts(a: MatRef<'_, f64>, with_v: bool) -> Result<SvdParts, String> {
    let (m, n) = (a.nrows(), a.ncols());
    let size = m.min(n);
    let mut u = Mat::<f64>::zeros(m, size);
    let mut v = Mat::<f64>::zeros(n, if with_v { size } else { 0 });
    let mut s = Diag::<f64>::zeros(size);
    let v_kind = if with_v {
        ComputeSvdVectors::Thin
    } else {
        ComputeSvdVectors::No
    };
    let mut buf = MemBuffer::new(svd::svd_scratch::<f64>(
        m,
        n,
        ComputeSvdVectors::Thin,
        v_kind,
        Par::Seq,
        Default::default(),
    ));
    svd::svd(
        a,
        s.as_mut(),
        Some(u.as_mut()),
        with_v.then(|| v.as_mut()),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| format!("SVD did not converge: {e:?}"))?;
    Ok((u, (0..size).map(|i| s[i]).collect(), v))
}

/// The first `cols` columns of `a`.
pub(crate) fn leading_columns(a: &Dense, cols: usize) -> Dense {
    let cols = cols.min(a.cols);
    Dense {
        rows: a.rows,
        cols,
        data: a.data[..a.rows * cols].to_vec(),
    }
}

/// faer's real eigen-decomposition: real and imaginary parts of the eigenvalues and, when
/// asked, the eigenvector columns (a conjugate pair in two adjacent real columns).
struct EvdParts {
    re: Vec<f64>,
    im: Vec<f64>,
    vectors: Option<Mat<f64>>,
}

fn evd_parts(a: &Dense, vectors: bool) -> Result<EvdParts, String> {
    let n = a.rows;
    let par = Par::Seq;
    let mut u = vectors.then(|| Mat::<f64>::zeros(n, n));
    let mut s_re = Diag::<f64>::zeros(n);
    let mut s_im = Diag::<f64>::zeros(n);
    let want = if vectors {
        ComputeEigenvectors::Yes
    } else {
        ComputeEigenvectors::No
    };
    let mut buf = MemBuffer::new(evd::evd_scratch::<f64>(
        n,
        ComputeEigenvectors::No,
        want,
        par,
        Default::default(),
    ));
    evd::evd_real(
        a.view(),
        s_re.as_mut(),
        s_im.as_mut(),
        None,
        u.as_mut().map(|m| m.as_mut()),
        par,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| format!("eigen-decomposition did not converge: {e:?}"))?;
    Ok(EvdParts {
        re: (0..n).map(|j| s_re[j]).collect(),
        im: (0..n).map(|j| s_im[j]).collect(),
        vectors: u,
    })
}

/// Eigenvalues of a real square matrix (no eigenvectors: cheaper). Real eigenvalues have an
/// imaginary part of exactly zero.
pub(crate) fn eigenvalues(a: &Dense) -> Result<Vec<C64>, String> {
    let p = evd_parts(a, false)?;
    Ok(p.re
        .iter()
        .zip(&p.im)
        .map(|(&r, &i)| C64::new(r, i))
        .collect())
}

/// Eigenvalues and right eigenvectors of a real square matrix; eigenvector `j` is column `j`
/// of the returned column-major complex buffer (n × n). Real eigenvalues have an imaginary
/// part of exactly zero.
pub(crate) fn eigen(a: &Dense) -> Result<(Vec<C64>, Vec<C64>), String> {
    let n = a.rows;
    let EvdParts {
        re: s_re,
        im: s_im,
        vectors,
    } = evd_parts(a, true)?;
    let u = vectors.ok_or("eigenvectors were not computed")?;
    let mut vals = vec![C64::new(0.0, 0.0); n];
    let mut vecs = vec![C64::new(0.0, 0.0); n * n];
    let mut j = 0;
    while j < n {
        if s_im[j] == 0.0 || j + 1 == n {
            vals[j] = C64::new(s_re[j], 0.0);
            for i in 0..n {
                vecs[j * n + i] = C64::new(u[(i, j)], 0.0);
            }
            j += 1;
        } else {
            // A conjugate pair: columns j and j+1 hold the real and imaginary parts.
            vals[j] = C64::new(s_re[j], s_im[j]);
            vals[j + 1] = C64::new(s_re[j], -s_im[j]);
            for i in 0..n {
                vecs[j * n + i] = C64::new(u[(i, j)], u[(i, j + 1)]);
                vecs[(j + 1) * n + i] = C64::new(u[(i, j)], -u[(i, j + 1)]);
            }
            j += 2;
        }
    }
    Ok((vals, vecs))
}

/// Eigenvalues (non-increasing) and unit eigenvectors of the complex Hermitian `l × l`
/// matrix `h` (column-major), through the real symmetric embedding
/// $\begin{pmatrix}A & -B\\ B & A\end{pmatrix}$ of $H = A + \mathrm i B$, whose eigenvalues are
/// $H$'s, each twice, with eigenvectors $(x; y) \leftrightarrow x + \mathrm i y$.
pub(crate) fn hermitian_eigen(h: &[C64], l: usize) -> Result<(Vec<f64>, Vec<Vec<C64>>), String> {
    let n = 2 * l;
    let mut m = Mat::<f64>::zeros(n, n);
    for c in 0..l {
        for r in 0..l {
            let v = h[c * l + r];
            m[(r, c)] = v.re;
            m[(r + l, c + l)] = v.re;
            m[(r + l, c)] = v.im;
            m[(r, c + l)] = -v.im;
        }
    }
    let evd = m
        .as_ref()
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| format!("Hermitian eigen-decomposition did not converge: {e:?}"))?;
    let (s, u) = (evd.S().column_vector(), evd.U());
    // Non-decreasing from faer: the pairs from the top, one of each.
    let mut values = Vec::with_capacity(l);
    let mut vectors = Vec::with_capacity(l);
    for k in (0..n).rev().step_by(2) {
        values.push(s[k]);
        vectors.push((0..l).map(|r| C64::new(u[(r, k)], u[(r + l, k)])).collect());
    }
    Ok((values, vectors))
}

/// Eigenvalues (non-decreasing) and unit eigenvectors (the columns, in the same order) of
/// the real symmetric `a`; `None` if the decomposition does not converge.
pub(crate) fn symmetric_eigen(a: &Dense) -> Option<(Vec<f64>, Dense)> {
    let evd = a.view().self_adjoint_eigen(Side::Lower).ok()?;
    let s = evd.S().column_vector();
    let values: Vec<f64> = (0..a.rows).map(|k| s[k]).collect();
    Some((values, Dense::from_faer(evd.U())))
}

/// `out += dᵀ d` (a Gram matrix update), single-threaded.
pub(crate) fn gram_add(d: &Dense, out: &mut Dense) {
    debug_assert_eq!((out.rows, out.cols), (d.cols, d.cols));
    let dv = d.view();
    let o = MatMut::from_column_major_slice_mut(&mut out.data, d.cols, d.cols);
    faer::linalg::matmul::matmul(o, Accum::Add, dv.transpose(), dv, 1.0, Par::Seq);
}

/// `out += aᵀ b`, single-threaded.
pub(crate) fn tn_add(a: &Dense, b: &Dense, out: &mut Dense) {
    debug_assert_eq!((out.rows, out.cols, a.rows), (a.cols, b.cols, b.rows));
    let o = MatMut::from_column_major_slice_mut(&mut out.data, a.cols, b.cols);
    faer::linalg::matmul::matmul(o, Accum::Add, a.view().transpose(), b.view(), 1.0, Par::Seq);
}

/// `a b a` for symmetric `a` and `b` (the sandwich covariance `F⁻¹ J F⁻¹`).
pub(crate) fn sandwich(a: &Dense, b: &Dense) -> Dense {
    let n = a.rows;
    let mut ab = Mat::<f64>::zeros(n, n);
    faer::linalg::matmul::matmul(
        ab.as_mut(),
        Accum::Replace,
        a.view(),
        b.view(),
        1.0,
        Par::Seq,
    );
    let mut aba = Mat::<f64>::zeros(n, n);
    faer::linalg::matmul::matmul(
        aba.as_mut(),
        Accum::Replace,
        ab.as_ref(),
        a.view(),
        1.0,
        Par::Seq,
    );
    Dense::from_faer(aba.as_ref())
}

/// Solve `a x = b` for symmetric positive definite `a` (Cholesky); `None` if `a` is not
/// numerically positive definite.
pub(crate) fn spd_solve(a: &Dense, b: &[f64]) -> Option<Vec<f64>> {
    let llt = a.view().llt(Side::Lower).ok()?;
    let rhs = MatRef::from_column_major_slice(b, b.len(), 1);
    let x = llt.solve(rhs);
    let v: Vec<f64> = (0..b.len()).map(|i| x[(i, 0)]).collect();
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// Inverse of a symmetric positive definite matrix; `None` if it is not numerically positive
/// definite.
pub(crate) fn spd_inverse(a: &Dense) -> Option<Dense> {
    let llt = a.view().llt(Side::Lower).ok()?;
    let inv = llt.inverse();
    let d = Dense::from_faer(inv.as_ref());
    d.data.iter().all(|x| x.is_finite()).then_some(d)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic, irregular `rows × cols` matrix.
    fn irregular(rows: usize, cols: usize, seed: usize) -> Dense {
        let mut a = Dense::zeros(rows, cols);
        for c in 0..cols {
            for r in 0..rows {
                let t = (r * 31 + c * 17 + seed * 7) as f64;
                a.set(
                    r,
                    c,
                    (t * 0.618).sin() + ((r * c + seed) % 13) as f64 * 0.05,
                );
            }
        }
        a
    }

    #[test]
    fn leading_svd_near_a_close_matrix_is_its_svd() {
        let a = irregular(60, 45, 1);
        let e = irregular(60, 45, 2);
        let mut b = a.clone();
        b.data
            .iter_mut()
            .zip(&e.data)
            .for_each(|(v, d)| *v += 1e-3 * d);
        let (ua, _) = thin_svd_u(&a).unwrap();
        let (ub, sb) = thin_svd_u(&b).unwrap();
        let (k, width) = (8, 20);
        let (u, s) = leading_svd_near(&b, &leading_columns(&ua, width), k, (1e-12, 30))
            .unwrap()
            .expect("converges from a close basis");
        assert_eq!((u.rows, u.cols, s.len()), (60, width, width));
        for j in 0..k {
            // A residual of 1e-12 σ₁ moves a singular value by as much at most.
            assert!(
                (s[j] - sb[j]).abs() <= 2e-12 * sb[0],
                "{j}: {} {}",
                s[j],
                sb[j]
            );
            // And a singular vector by that over its gap to the others (≥ 1e-2 σ₁ here).
            let dot: f64 = (0..60).map(|r| u.at(r, j) * ub.at(r, j)).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-9, "{j}: {dot}");
        }
        // From a basis far from b's leading vectors (its trailing ones) one sweep does not
        // get there: the caller is told to take the full SVD.
        let far = Dense {
            rows: 60,
            cols: width,
            data: ua.data[ua.rows * 20..ua.rows * 40].to_vec(),
        };
        assert!(leading_svd_near(&b, &far, k, (1e-12, 1)).unwrap().is_none());
        // A basis no wider than k, or of other rows, is refused the same way.
        assert!(
            leading_svd_near(&b, &leading_columns(&ua, k), k, (1e-12, 30))
                .unwrap()
                .is_none()
        );
        let other = irregular(50, width, 3);
        assert!(
            leading_svd_near(&b, &other, k, (1e-12, 30))
                .unwrap()
                .is_none()
        );
    }

    #[test]
    fn eigen_of_a_rotation_block() {
        let mut a = Dense::zeros(3, 3);
        a.set(0, 0, 0.5);
        a.set(0, 1, -0.8);
        a.set(1, 0, 0.8);
        a.set(1, 1, 0.5);
        a.set(2, 2, 0.3);
        let (vals, vecs) = eigen(&a).unwrap();
        for (j, l) in vals.iter().enumerate() {
            // A v = λ v for each returned pair.
            for i in 0..3 {
                let av: C64 = (0..3).map(|k| vecs[j * 3 + k] * a.at(i, k)).sum();
                assert!((av - l * vecs[j * 3 + i]).norm() < 1e-12);
            }
        }
        assert!(
            vals.iter()
                .any(|l| l.im == 0.0 && (l.re - 0.3).abs() < 1e-14)
        );
    }

    #[test]
    fn svd_singular_values() {
        let mut a = Dense::zeros(4, 2);
        a.set(0, 0, 3.0);
        a.set(1, 1, 2.0);
        let (_, s) = thin_svd_u(&a).unwrap();
        assert!((s[0] - 3.0).abs() < 1e-14 && (s[1] - 2.0).abs() < 1e-14);
    }
}
