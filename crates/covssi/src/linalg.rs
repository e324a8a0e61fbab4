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
    let (m, n) = (a.rows, a.cols);
    let size = m.min(n);
    let mut u = Mat::<f64>::zeros(m, size);
    let mut s = Diag::<f64>::zeros(size);
    let par = Par::Seq;
    let mut buf = MemBuffer::new(svd::svd_scratch::<f64>(
        m,
        n,
        ComputeSvdVectors::Thin,
        ComputeSvdVectors::No,
        par,
        Default::default(),
    ));
    svd::svd(
        a.view(),
        s.as_mut(),
        Some(u.as_mut()),
        None,
        par,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| format!("SVD did not converge: {e:?}"))?;
    let sv: Vec<f64> = (0..size).map(|i| s[i]).collect();
    Ok((Dense::from_faer(u.as_ref()), sv))
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
