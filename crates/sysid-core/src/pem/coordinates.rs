//! Data-driven local coordinates (McKelvey, Helmersson & Ribarits 2004).
//!
//! A fully parameterised model is only determined up to a change of state basis. The tangent
//! space of the similarity orbit `{(T^-1 A T, T^-1 B, C T, D, T^-1 K, T^-1 x0)}` at `theta`
//! is spanned, for `T = I + X` with `X = E_ab`, by `(A X - X A, -X B, C X, 0, -X K, -X x0)`.
//! The search moves in its orthogonal complement, orthogonal in the metric the search asks
//! for: the parameters themselves, or, once its steps crawl, the metric it damps them in
//! (each parameter scaled by its Gauss-Newton diagonal), because in the parameters a basis
//! mixes parameters whose effects differ by orders of magnitude (the state of an unstable
//! plant grows with its outputs) and the damped steps crawl, short of the minimum at the
//! iteration cap ([`crate::optim::Problem::search_basis`]). This is exact when every quantity the
//! similarity moves is a parameter or zero; with a fixed non-zero `K` or a given non-zero `x0`
//! there is no orbit in the parameters and the search uses all directions. In the modal chart
//! ([`super::chart`]) the orbit is that of the similarities that keep the chart's blocks, and
//! the complement is taken among the parameters the chart does not hold.

use super::predictor::Predictor;
use super::InitialState;
use crate::error::{Result, SysidError};
use faer::Mat;

/// The matrix an entry of [`similarity_tangent`] belongs to.
#[derive(Clone, Copy)]
pub(crate) enum Part {
    A,
    B,
    C,
}

/// The tangent of the similarity orbit along `T = I + E_pq`, one column per pair `(p, q)`:
/// `(A E - E A, -E B, C E)`, handed to `add(column, part, index, value)` with `index`
/// row-major in that matrix (the time-domain predictor and the frequency-domain fit each
/// place it in their own parameter layout).
pub(crate) fn similarity_tangent(
    a: &Mat<f64>,
    b: &Mat<f64>,
    c: &Mat<f64>,
    pairs: &[(usize, usize)],
    mut add: impl FnMut(usize, Part, usize, f64),
) {
    let (n, m, l) = (a.nrows(), b.ncols(), c.nrows());
    for (col, &(p, q)) in pairs.iter().enumerate() {
        for i in 0..n {
            add(col, Part::A, i * n + q, a[(i, p)]);
        }
        for j in 0..n {
            add(col, Part::A, p * n + j, -a[(q, j)]);
        }
        for j in 0..m {
            add(col, Part::B, p * m + j, -b[(q, j)]);
        }
        for i in 0..l {
            add(col, Part::C, i * n + q, c[(i, p)]);
        }
    }
}

impl Predictor<'_> {
    /// Tangent vectors (p x n^2; fewer in the modal chart) of the similarity orbit at `theta`; `None` when there is no
    /// orbit in the parameters (a fixed non-zero `K` or a given non-zero `x0`).
    pub(super) fn orbit_tangent(&self, th: &[f64]) -> Option<Mat<f64>> {
        if self.n == 0 {
            return None;
        }
        let pm = self.unpack(th);
        let (n, l) = (self.n, self.l);
        let k_ok = self.est_k || (0..n).all(|i| (0..l).all(|j| pm.k[(i, j)] == 0.0));
        let x0_ok = self
            .x0_mode
            .iter()
            .all(|s| !matches!(s, InitialState::Given(v) if v.iter().any(|&x| x != 0.0)));
        if !k_ok || !x0_ok {
            return None;
        }
        let off = self.offsets();
        // in the modal chart only the similarities that keep its blocks stay in the chart
        let pairs: Vec<(usize, usize)> = (0..n)
            .flat_map(|a| (0..n).map(move |b| (a, b)))
            .filter(|&(a, b)| !self.held(a, b))
            .collect();
        let mut tan = Mat::<f64>::zeros(self.p, pairs.len());
        similarity_tangent(&pm.a, &pm.b, &pm.c, &pairs, |col, part, idx, v| {
            let base = match part {
                Part::A => off.a,
                Part::B => off.b,
                Part::C => off.c,
            };
            tan[(base + idx, col)] += v;
        });
        for (col, &(a, b)) in pairs.iter().enumerate() {
            if let Some(ik) = off.k {
                for j in 0..l {
                    tan[(ik + a * l + j, col)] -= pm.k[(b, j)];
                }
            }
            for (ex, o) in self.x0_off.iter().enumerate() {
                if let Some(o) = o {
                    tan[(o + a, col)] -= pm.x0[ex][b];
                }
            }
        }
        Some(tan)
    }

    /// A basis of the complement of the orbit's tangent space at `theta`, orthonormal in the
    /// metric `diag(scale)` ([`crate::optim::Problem::search_basis`]), or `None` when local
    /// coordinates are off or there is no orbit.
    pub(super) fn local_basis(&self, th: &[f64], scale: &[f64]) -> Result<Option<Mat<f64>>> {
        let Some(tan) = self.local.then(|| self.orbit_tangent(th)).flatten() else {
            return Ok(None);
        };
        // the complement within the parameters that move (all but those the chart holds)
        let mask = self.chart_mask();
        let free: Vec<usize> = (0..self.p).filter(|&i| !mask[i]).collect();
        let tf = Mat::from_fn(free.len(), tan.ncols(), |i, j| tan[(free[i], j)]);
        let sf: Vec<f64> = free.iter().map(|&i| scale[i]).collect();
        let u = scaled_complement(&tf, &sf)?;
        let mut basis = Mat::<f64>::zeros(self.p, u.ncols());
        for (i, &fi) in free.iter().enumerate() {
            for j in 0..u.ncols() {
                basis[(fi, j)] = u[(i, j)];
            }
        }
        Ok(Some(basis))
    }
}

/// A basis `T` of the complement of the column space of `tan` in the metric `diag(scale)`:
/// `diag(scale) T` is an orthonormal basis of the orthogonal complement of `diag(scale) tan`.
/// A scale that is not positive and finite counts as 1. The number of directions follows
/// the rank of `tan` itself (singular values above `1e-10` of the largest): a metric whose
/// entries differ by orders of magnitude must not make the orbit look smaller than it is.
pub(super) fn scaled_complement(tan: &Mat<f64>, scale: &[f64]) -> Result<Mat<f64>> {
    let s: Vec<f64> = (0..tan.nrows())
        .map(|i| match scale.get(i) {
            Some(&v) if v > 0.0 && v.is_finite() => v,
            _ => 1.0,
        })
        .collect();
    let (u, rank) = if s.iter().all(|&v| v == 1.0) {
        // the plain metric: one decomposition gives both
        let (u, sv) = left_svd(tan, true)?;
        (u, numerical_rank(&sv))
    } else {
        let (_, sv) = left_svd(tan, false)?;
        let ts = Mat::from_fn(tan.nrows(), tan.ncols(), |i, j| s[i] * tan[(i, j)]);
        (left_svd(&ts, true)?.0, numerical_rank(&sv))
    };
    let rows = tan.nrows();
    Ok(Mat::from_fn(rows, rows - rank, |i, j| {
        u[(i, rank + j)] / s[i]
    }))
}

/// Singular values above `1e-10` of the largest.
fn numerical_rank(sv: &[f64]) -> usize {
    let smax = sv.first().copied().unwrap_or(0.0);
    sv.iter().filter(|&&v| v > 1e-10 * smax && v > 0.0).count()
}

/// The singular values of `tan` (descending) and, with `vectors`, its full left singular
/// vectors (rows x rows; empty otherwise). A small SVD (every iterate of winding-sized
/// problems) runs on the calling thread: waking the pool cost more than the decomposition.
fn left_svd(tan: &Mat<f64>, vectors: bool) -> Result<(Mat<f64>, Vec<f64>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::svd::{self, ComputeSvdVectors};
    let (rows, cols) = tan.shape();
    let size = rows.min(cols);
    let par = faer::Par::Seq; // the same bits on any number of threads (optim::small_par)
    let mut u = Mat::<f64>::zeros(
        if vectors { rows } else { 0 },
        if vectors { rows } else { 0 },
    );
    let mut s = faer::diag::Diag::<f64>::zeros(size);
    // the right singular vectors are not needed
    let left = if vectors {
        ComputeSvdVectors::Full
    } else {
        ComputeSvdVectors::No
    };
    let none = ComputeSvdVectors::No;
    let scratch = svd::svd_scratch::<f64>(rows, cols, left, none, par, Default::default());
    svd::svd(
        tan.as_ref(),
        s.as_mut(),
        vectors.then_some(u.as_mut()),
        None,
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|e| SysidError::numerical("local coordinates (SVD)", format!("{e:?}")))?;
    let sv = s.column_vector();
    Ok((u, (0..size).map(|i| sv[i]).collect()))
}
