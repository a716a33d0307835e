//! Small dense helpers shared by the estimators: least squares through a truncated SVD,
//! eigenvalues, spectral radius, LQ re-triangularisation.

use crate::error::{Result, SysidError};
use faer::{Mat, MatMut, MatRef, Par};

/// Householder QR of `a` in place, on the calling thread: afterwards the upper triangle of
/// `a` (its first `min(rows, cols)` rows) holds R (the rest holds the reflectors).
///
/// Sequential on purpose: faer's threaded QR may reassociate sums, so its last bits depend
/// on the thread count; every compression path goes through this function so that its
/// result does not. Threads are used one level up, on independent blocks of samples.
///
/// ```
/// use faer::mat;
/// use sysid_core::linalg::qr_r_in_place;
/// let mut a = mat![[3.0, 1.0], [4.0, 2.0]];
/// qr_r_in_place(a.as_mut());
/// assert!((a[(0, 0)].abs() - 5.0).abs() < 1e-14);
/// ```
pub fn qr_r_in_place(a: MatMut<'_, f64>) {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::qr::no_pivoting::factor;
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 || n == 0 {
        return;
    }
    let bs = factor::recommended_block_size::<f64>(m, n);
    let mut coeff = Mat::<f64>::zeros(bs, m.min(n));
    let mut buf = MemBuffer::new(factor::qr_in_place_scratch::<f64>(
        m,
        n,
        bs,
        Par::Seq,
        Default::default(),
    ));
    factor::qr_in_place(
        a,
        coeff.as_mut(),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    );
}

/// The `R` factor of the thin QR of `a` (`min(rows, cols) x cols`, upper triangular), on the
/// calling thread (as faer's `qr().thin_R()`, whose threads move the last bits above a few
/// hundred rows; see [`crate::optim::small_par`]).
///
/// ```
/// use faer::mat;
/// use sysid_core::linalg::thin_r_seq;
/// let r = thin_r_seq(mat![[3.0, 1.0], [4.0, 2.0], [0.0, 0.0]].as_ref());
/// assert_eq!((r.nrows(), r.ncols(), r[(1, 0)]), (2, 2, 0.0));
/// assert!((r[(0, 0)].abs() - 5.0).abs() < 1e-14);
/// ```
pub fn thin_r_seq(a: MatRef<'_, f64>) -> Mat<f64> {
    let mut q = a.to_owned();
    qr_r_in_place(q.as_mut());
    let k = a.nrows().min(a.ncols());
    Mat::from_fn(k, a.ncols(), |i, j| if i <= j { q[(i, j)] } else { 0.0 })
}

/// The thin `Q` of the Householder QR of `a` (at least as many rows as columns), as faer's
/// `qr().compute_thin_Q()` but on the calling thread (the same bits on any number of
/// threads; see [`crate::optim::small_par`]).
///
/// ```
/// use faer::mat;
/// use sysid_core::linalg::thin_q_seq;
/// let q = thin_q_seq(mat![[3.0], [4.0]].as_ref());
/// assert!((q[(0, 0)].abs() - 0.6).abs() < 1e-15 && (q[(1, 0)].abs() - 0.8).abs() < 1e-15);
/// ```
pub fn thin_q_seq(a: MatRef<'_, f64>) -> Mat<f64> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::{householder as hh, qr::no_pivoting::factor};
    let (m, n) = a.shape();
    if n == 0 {
        return Mat::zeros(m, 0);
    }
    let par = Par::Seq;
    let bs = factor::recommended_block_size::<f64>(m, n);
    let mut qr = a.to_owned();
    let mut coeff = Mat::<f64>::zeros(bs, n);
    let scratch = factor::qr_in_place_scratch::<f64>(m, n, bs, par, Default::default());
    factor::qr_in_place(
        qr.as_mut(),
        coeff.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    );
    // the Householder basis, unit lower trapezoidal (faer's split of the packed factors)
    let basis = Mat::from_fn(m, n, |i, j| match i.cmp(&j) {
        std::cmp::Ordering::Greater => qr[(i, j)],
        std::cmp::Ordering::Equal => 1.0,
        std::cmp::Ordering::Less => 0.0,
    });
    let mut q = Mat::<f64>::identity(m, n);
    let scratch =
        hh::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(m, bs, n);
    hh::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        basis.as_ref(),
        coeff.as_ref(),
        faer::Conj::No,
        q.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
    );
    q
}

/// Makes faer's own methods (`svd`, `qr`, `eigen`, `llt().solve`, products by `*`: they read
/// faer's global parallelism) run on the calling thread, so that every result of the crate
/// is the same on any number of threads: above a few hundred rows faer's decompositions and
/// triangular solves split their work by thread and the last bits move with the count (a
/// `pem` search on a 2 x 28 record of order 20 ended at another cost with two threads than
/// with one). The crate's large products and LU factorisations keep rayon's pool (they give the
/// same bits on any count). Call once, before any work (the Python module does at import).
///
/// ```
/// sysid_core::linalg::reproducible_threads();
/// assert!(matches!(faer::get_global_parallelism(), faer::Par::Seq));
/// ```
pub fn reproducible_threads() {
    faer::set_global_parallelism(Par::Seq);
}

/// Cholesky factor (lower) of a symmetric positive definite matrix, on the calling thread
/// (deterministic for any thread count, as [`qr_r_in_place`]); `None` when a pivot is not
/// positive.
pub fn cholesky_lower_seq(a: MatRef<'_, f64>) -> Option<Mat<f64>> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor;
    let n = a.nrows();
    let mut l = a.to_owned();
    let mut buf = MemBuffer::new(factor::cholesky_in_place_scratch::<f64>(
        n,
        Par::Seq,
        Default::default(),
    ));
    factor::cholesky_in_place(
        l.as_mut(),
        Default::default(),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .ok()?;
    for j in 0..n {
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
    }
    Some(l)
}

/// The product `a b`, on the calling thread.
///
/// The small products after the compression use this instead of faer's `*`, which runs
/// with the global (rayon) parallelism: for matrices of a few hundred rows the thread
/// wake-ups cost more than the work, and far more on a loaded machine.
pub fn mul_seq(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(out.as_mut(), faer::Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

/// [`svd_seq`] with the left singular vectors: `(s, U)`, `U` of `min(rows, cols)` columns.
///
/// ```
/// use faer::mat;
/// let (s, u) = sysid_core::linalg::svd_left_seq("doc", mat![[3.0, 0.0], [0.0, 2.0]].as_ref())
///     .unwrap();
/// assert_eq!((s, u.shape()), (vec![3.0, 2.0], (2, 2)));
/// ```
pub fn svd_left_seq(step: &'static str, a: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let (s, u, _) = svd_seq(step, a, true, false)?;
    Ok((s, u.unwrap_or_else(|| Mat::zeros(a.nrows(), 0))))
}

/// [`svd_seq`] with both sets of singular vectors: `(s, U, V)`, each of `min(rows, cols)`
/// columns.
///
/// ```
/// use faer::mat;
/// let (s, u, v) =
///     sysid_core::linalg::svd_both_seq("doc", mat![[0.0, 2.0, 0.0]].as_ref()).unwrap();
/// assert_eq!((s, u.shape(), v.shape()), (vec![2.0], (1, 1), (3, 1)));
/// ```
#[allow(clippy::type_complexity)]
pub fn svd_both_seq(
    step: &'static str,
    a: MatRef<'_, f64>,
) -> Result<(Vec<f64>, Mat<f64>, Mat<f64>)> {
    let (s, u, v) = svd_seq(step, a, true, true)?;
    Ok((
        s,
        u.unwrap_or_else(|| Mat::zeros(a.nrows(), 0)),
        v.unwrap_or_else(|| Mat::zeros(a.ncols(), 0)),
    ))
}

/// Thin SVD on the calling thread: the singular values (largest first) and, when asked,
/// the first `min(rows, cols)` left and right singular vectors. `step` names the caller in
/// the error when the SVD does not converge.
#[allow(clippy::type_complexity)]
pub fn svd_seq(
    step: &'static str,
    a: MatRef<'_, f64>,
    want_u: bool,
    want_v: bool,
) -> Result<(Vec<f64>, Option<Mat<f64>>, Option<Mat<f64>>)> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::svd::{svd, svd_scratch, ComputeSvdVectors};
    let (m, n) = (a.nrows(), a.ncols());
    let size = m.min(n);
    if size == 0 {
        return Ok((
            Vec::new(),
            want_u.then(|| Mat::zeros(m, 0)),
            want_v.then(|| Mat::zeros(n, 0)),
        ));
    }
    let how = |w: bool| {
        if w {
            ComputeSvdVectors::Thin
        } else {
            ComputeSvdVectors::No
        }
    };
    let mut s = faer::diag::Diag::<f64>::zeros(size);
    let mut u = want_u.then(|| Mat::<f64>::zeros(m, size));
    let mut v = want_v.then(|| Mat::<f64>::zeros(n, size));
    let mut buf = MemBuffer::new(svd_scratch::<f64>(
        m,
        n,
        how(want_u),
        how(want_v),
        Par::Seq,
        Default::default(),
    ));
    svd(
        a,
        s.as_mut(),
        u.as_mut().map(|x| x.as_mut()),
        v.as_mut().map(|x| x.as_mut()),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| SysidError::numerical(step, format!("{e:?}")))?;
    Ok((s.column_vector().iter().copied().collect(), u, v))
}

/// Eigenvalues of a symmetric matrix (its lower triangle is read), ascending, on the
/// calling thread.
pub fn sym_eigenvalues_seq(a: MatRef<'_, f64>) -> Result<Vec<f64>> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors};
    let n = a.nrows();
    if n == 0 {
        return Ok(Vec::new());
    }
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let mut buf = MemBuffer::new(self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::No,
        Par::Seq,
        Default::default(),
    ));
    self_adjoint_evd(
        a,
        s.as_mut(),
        None,
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    )
    .map_err(|e| SysidError::numerical("symmetric eigenvalues", format!("{e:?}")))?;
    let mut ev: Vec<f64> = s.column_vector().iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    Ok(ev)
}

/// The real eigendecomposition of faer's `eigen`/`eigenvalues` (Schur form, then the
/// eigenvectors when asked): the eigenvalues' real and imaginary parts and the real basis
/// (a complex pair `j, j + 1` as the columns `re, im`), on the calling thread: faer's own call
/// wakes the thread pool (which cost more than the decomposition of the small matrices of
/// every iterate) and, above a few hundred rows, splits its work by thread, which moves the
/// last bits (see [`crate::optim::small_par`]).
#[allow(clippy::type_complexity)]
fn evd_real(
    a: MatRef<'_, f64>,
    vectors: bool,
) -> std::result::Result<(Vec<f64>, Vec<f64>, Option<Mat<f64>>), faer::linalg::evd::EvdError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::evd::{self, ComputeEigenvectors};
    let n = a.nrows();
    let par = Par::Seq; // the same bits on any number of threads (optim::small_par)
    let (mut re, mut im) = (faer::diag::Diag::zeros(n), faer::diag::Diag::zeros(n));
    let mut u = vectors.then(|| Mat::<f64>::zeros(n, n));
    let right = if vectors {
        ComputeEigenvectors::Yes
    } else {
        ComputeEigenvectors::No
    };
    let scratch =
        evd::evd_scratch::<f64>(n, ComputeEigenvectors::No, right, par, Default::default());
    evd::evd_real(
        a,
        re.as_mut(),
        im.as_mut(),
        None,
        u.as_mut().map(|u| u.as_mut()),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )?;
    let col = |d: &faer::diag::Diag<f64>| d.column_vector().iter().copied().collect();
    Ok((col(&re), col(&im), u))
}

/// Eigenvalues and eigenvectors (columns) of a square matrix, as faer's `eigen` (a complex
/// pair's vectors conjugate), on the calling thread ([`evd_real`]).
#[allow(clippy::type_complexity)]
pub(crate) fn eigen(
    a: MatRef<'_, f64>,
) -> std::result::Result<(Vec<faer::c64>, Mat<faer::c64>), faer::linalg::evd::EvdError> {
    use faer::c64;
    let n = a.nrows();
    let (re, im, u) = evd_real(a, true)?;
    let u = u.unwrap_or_else(|| Mat::zeros(n, n));
    let (mut s, mut v) = (vec![c64::new(0.0, 0.0); n], Mat::<c64>::zeros(n, n));
    let mut j = 0;
    while j < n {
        if im[j] == 0.0 {
            s[j] = c64::new(re[j], 0.0);
            (0..n).for_each(|i| v[(i, j)] = c64::new(u[(i, j)], 0.0));
            j += 1;
        } else {
            s[j] = c64::new(re[j], im[j]);
            s[j + 1] = c64::new(re[j], -im[j]);
            for i in 0..n {
                v[(i, j)] = c64::new(u[(i, j)], u[(i, j + 1)]);
                v[(i, j + 1)] = c64::new(u[(i, j)], -u[(i, j + 1)]);
            }
            j += 2;
        }
    }
    Ok((s, v))
}

/// The inverse of a square matrix by LU with partial pivoting, as faer's
/// `partial_piv_lu().inverse()`, with [`crate::optim::small_par`] (see [`evd_real`]).
pub(crate) fn inverse<T: faer::traits::ComplexField>(a: MatRef<'_, T>) -> Mat<T> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::lu::partial_pivoting::{factor, inverse as inv};
    let n = a.nrows();
    let par = crate::optim::small_par(n, n);
    let mut lu = a.to_owned();
    let (mut fwd, mut bwd) = (vec![0usize; n], vec![0usize; n]);
    let scratch = factor::lu_in_place_scratch::<usize, T>(n, n, par, Default::default());
    let (_, perm) = factor::lu_in_place(
        lu.as_mut(),
        &mut fwd,
        &mut bwd,
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    );
    // L unit lower and U upper, as faer's split of the packed factors
    let l = Mat::from_fn(n, n, |i, j| match i.cmp(&j) {
        std::cmp::Ordering::Greater => lu[(i, j)].clone(),
        std::cmp::Ordering::Equal => T::one_impl(),
        std::cmp::Ordering::Less => T::zero_impl(),
    });
    let u = Mat::from_fn(n, n, |i, j| {
        if i <= j {
            lu[(i, j)].clone()
        } else {
            T::zero_impl()
        }
    });
    let mut out = Mat::<T>::zeros(n, n);
    let scratch = inv::inverse_scratch::<usize, T>(n, par);
    let stack = &mut MemBuffer::new(scratch);
    inv::inverse(
        out.as_mut(),
        l.as_ref(),
        u.as_ref(),
        perm,
        par,
        MemStack::new(stack),
    );
    out
}

/// The product `a b` with [`crate::optim::small_par`] (see [`mul_seq`]).
pub(crate) fn mul<T: faer::traits::ComplexField>(a: MatRef<'_, T>, b: MatRef<'_, T>) -> Mat<T> {
    let mut out = Mat::<T>::zeros(a.nrows(), b.ncols());
    let work = a
        .nrows()
        .saturating_mul(a.ncols())
        .saturating_mul(b.ncols());
    let par = if work >= 1 << 22 {
        Par::rayon(0)
    } else {
        Par::Seq
    };
    faer::linalg::matmul::matmul(out.as_mut(), faer::Accum::Replace, a, b, T::one_impl(), par);
    out
}

/// Eigenvalues of a square matrix as `(re, im)` pairs, on the calling thread ([`evd_real`]).
pub fn eigenvalues(a: MatRef<'_, f64>) -> Result<Vec<(f64, f64)>> {
    if a.nrows() == 0 {
        return Ok(Vec::new());
    }
    let (re, im, _) =
        evd_real(a, false).map_err(|e| SysidError::numerical("eigenvalues", format!("{e:?}")))?;
    Ok(re.into_iter().zip(im).collect())
}

/// Largest eigenvalue modulus of a square matrix.
pub fn spectral_radius(a: MatRef<'_, f64>) -> Result<f64> {
    Ok(eigenvalues(a)?
        .into_iter()
        .map(|(re, im)| re.hypot(im))
        .fold(0.0, f64::max))
}

/// `A` with every eigenvalue `z` on or outside the unit circle moved to `shrink / conj(z)`
/// (its reflection into the circle, pulled in by `shrink <= 1`); the other eigenvalues and
/// all eigenvectors are kept. Conjugate pairs stay pairs, so the result is real: it is
/// `A + V diag(z' - z) V^-1` over the moved eigenvalues, the imaginary round-off dropped.
/// A with no such eigenvalue is returned unchanged.
///
/// ```
/// use faer::mat;
/// use sysid_core::linalg::{reflect_unstable_poles, spectral_radius};
/// let a = mat![[2.0, 0.0], [0.0, 0.5]];
/// let s = reflect_unstable_poles(a.as_ref(), 0.99).unwrap();
/// assert!((s[(0, 0)] - 0.495).abs() < 1e-15 && s[(1, 1)] == 0.5);
/// assert!(spectral_radius(s.as_ref()).unwrap() < 1.0);
/// ```
pub fn reflect_unstable_poles(a: MatRef<'_, f64>, shrink: f64) -> Result<Mat<f64>> {
    use faer::linalg::solvers::DenseSolveCore;
    crate::error::check_finite("A", a)?;
    let n = a.nrows();
    if a.ncols() != n {
        return Err(SysidError::ShapeMismatch {
            what: "A".into(),
            expected: format!("({n}, {n})"),
            got: format!("({n}, {})", a.ncols()),
        });
    }
    if n == 0 || spectral_radius(a)? < 1.0 {
        return Ok(a.to_owned());
    }
    let e = a
        .eigen()
        .map_err(|e| SysidError::numerical("eigendecomposition of A", format!("{e:?}")))?;
    let (v, w) = (e.U(), e.S().column_vector());
    let vi = v.to_owned().partial_piv_lu().inverse();
    let mut out = a.to_owned();
    for k in 0..n {
        let z = w[k];
        if z.norm() < 1.0 {
            continue;
        }
        let dz = faer::c64::new(shrink, 0.0) / z.conj() - z;
        for j in 0..n {
            let row = dz * vi[(k, j)];
            for i in 0..n {
                out[(i, j)] += (v[(i, k)] * row).re;
            }
        }
    }
    Ok(out)
}

/// Moore-Penrose pseudo-inverse through the thin SVD; singular values below
/// `rtol * s_max` are treated as zero. On the calling thread: the matrices here are small
/// (a few hundred rows at most), where thread wake-ups cost more than the work (see
/// [`mul_seq`]), and the result does not depend on the thread count.
pub fn pinv(a: MatRef<'_, f64>, rtol: f64) -> Result<Mat<f64>> {
    let (m, n) = (a.nrows(), a.ncols());
    if m == 0 || n == 0 {
        return Ok(Mat::zeros(n, m));
    }
    let (s, u, v) = svd_both_seq("pseudo-inverse (SVD)", a)?;
    let cut = rtol * s[0];
    let r = s.iter().filter(|&&x| x > cut && x > 0.0).count();
    let mut vs = v.subcols(0, r).to_owned();
    for j in 0..r {
        let inv = 1.0 / s[j];
        for i in 0..vs.nrows() {
            vs[(i, j)] *= inv;
        }
    }
    Ok(mul_seq(vs.as_ref(), u.subcols(0, r).transpose()))
}

/// Solves `X A = B` for X in the least-squares sense (minimum norm), i.e. `X = B A^+`.
pub fn rsolve_lstsq(b: MatRef<'_, f64>, a: MatRef<'_, f64>, rtol: f64) -> Result<Mat<f64>> {
    Ok(mul_seq(b, pinv(a, rtol)?.as_ref()))
}

/// Least-squares solution `X` of `A X = B` (A tall, full column rank) by Householder QR of
/// `[A | B]` on the calling thread, so that the result does not depend on the thread count.
///
/// ```
/// use faer::mat;
/// use sysid_core::linalg::lstsq_seq;
/// let a = mat![[1.0, 0.0], [0.0, 2.0], [0.0, 0.0]];
/// let b = mat![[1.0], [4.0], [3.0]];
/// let x = lstsq_seq(a.as_ref(), b.as_ref());
/// assert!((x[(0, 0)] - 1.0).abs() < 1e-15 && (x[(1, 0)] - 2.0).abs() < 1e-15);
/// ```
pub fn lstsq_seq(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let (rows, n, r) = (a.nrows(), a.ncols(), b.ncols());
    let mut ab = Mat::<f64>::zeros(rows.max(n + r), n + r);
    ab.as_mut().submatrix_mut(0, 0, rows, n).copy_from(a);
    ab.as_mut().submatrix_mut(0, n, rows, r).copy_from(b);
    qr_r_in_place(ab.as_mut());
    // [R, Q^T B] in the first n rows: back substitution
    let mut x = Mat::<f64>::zeros(n, r);
    for c in 0..r {
        for i in (0..n).rev() {
            let mut v = ab[(i, n + c)];
            for j in (i + 1)..n {
                v -= ab[(i, j)] * x[(j, c)];
            }
            x[(i, c)] = v / ab[(i, i)];
        }
    }
    x
}

/// Lower-triangular L with `L L^T = M M^T` (the L of the LQ factorisation of M), with a
/// non-negative diagonal. M may have more columns than rows; L is `M.nrows() x M.nrows()`.
pub fn lq_lower(m: MatRef<'_, f64>) -> Mat<f64> {
    let rows = m.nrows();
    if m.ncols() == 0 || rows == 0 {
        return Mat::zeros(rows, rows);
    }
    let mut r = m.transpose().to_owned();
    qr_r_in_place(r.as_mut()); // upper trapezoidal in its first min(cols, rows) rows
    let mut l = Mat::<f64>::zeros(rows, rows);
    for i in 0..r.nrows().min(rows) {
        let sign = if r[(i, i)] < 0.0 { -1.0 } else { 1.0 };
        for j in i..rows {
            l[(j, i)] = sign * r[(i, j)];
        }
    }
    l
}

/// Lower-triangular L with `L L^T = M M^T` for `M = [T | 0] + c r^T`: `T` (k x k) lower
/// triangular, `c` of length k, `r` of length `n >= k` (M is k x n, its last `n - k` columns
/// come from the rank-one term only). Equals [`lq_lower`] of the explicit M up to round-off,
/// in `O(k n)` flops instead of `O(k^2 n)`: the rank-one update of a triangular factorisation
/// by Givens rotations (Golub & Van Loan, section 6.5.1, on `M^T`), on the calling thread.
///
/// ```
/// use faer::mat;
/// use sysid_core::linalg::{lq_lower, lq_lower_rank_one};
/// let t = mat![[2.0, 0.0], [1.0, 3.0]];
/// let (c, r) = ([0.5, -1.0], [1.0, 2.0, 0.5]);
/// let m = faer::Mat::<f64>::from_fn(2, 3, |i, j| (if j < 2 { t[(i, j)] } else { 0.0 }) + c[i] * r[j]);
/// let (a, b) = (lq_lower_rank_one(t.as_ref(), &c, &r), lq_lower(m.as_ref()));
/// assert!((&a - &b).norm_max() < 1e-14);
/// ```
pub fn lq_lower_rank_one(t: MatRef<'_, f64>, c: &[f64], r: &[f64]) -> Mat<f64> {
    let k = t.nrows();
    let n = r.len();
    assert!(
        t.ncols() == k && c.len() == k && n >= k,
        "lq_lower_rank_one: shapes"
    );
    if k == 0 {
        return Mat::zeros(0, 0);
    }
    // rows of M^T = [T^T; 0] + r c^T, row-major: row i of T^T is nonzero from column i
    let mut rt = vec![0.0; n * k];
    for j in 0..k {
        for i in 0..=j {
            rt[i * k + j] = t[(j, i)];
        }
    }
    let givens = |a: f64, b: f64| -> (f64, f64) {
        let h = a.hypot(b);
        if h == 0.0 {
            (1.0, 0.0)
        } else {
            (a / h, b / h)
        }
    };
    let rotate = |rt: &mut [f64], i: usize, from: usize, cs: f64, sn: f64| {
        let (top, bottom) = rt.split_at_mut((i + 1) * k);
        let x = &mut top[i * k + from..(i + 1) * k];
        let y = &mut bottom[from..k];
        for (xj, yj) in x.iter_mut().zip(y.iter_mut()) {
            let (a, b) = (*xj, *yj);
            *xj = cs * a + sn * b;
            *yj = cs * b - sn * a;
        }
    };
    // Q^T r = |r| e_0 by rotations of rows (i - 1, i), bottom up: the triangle becomes
    // upper Hessenberg (row i nonzero from column i - 1)
    let mut w = r.to_vec();
    for i in (1..n).rev() {
        let (cs, sn) = givens(w[i - 1], w[i]);
        w[i - 1] = cs * w[i - 1] + sn * w[i];
        w[i] = 0.0;
        let from = i - 1;
        if from < k {
            rotate(&mut rt, i - 1, from, cs, sn);
        }
    }
    for (x, cj) in rt[..k].iter_mut().zip(c) {
        *x += w[0] * cj;
    }
    // back to upper triangular: rotations of rows (i, i + 1), top down
    for i in 0..k.min(n - 1) {
        let (cs, sn) = givens(rt[i * k + i], rt[(i + 1) * k + i]);
        rotate(&mut rt, i, i, cs, sn);
        rt[(i + 1) * k + i] = 0.0;
    }
    let mut l = Mat::<f64>::zeros(k, k);
    for i in 0..k {
        let sign = if rt[i * k + i] < 0.0 { -1.0 } else { 1.0 };
        for j in i..k {
            l[(j, i)] = sign * rt[i * k + j];
        }
    }
    l
}

/// Streaming triangularisation of a tall matrix given row by row.
///
/// Rows are buffered below the current upper-triangular `R` (k x k); every `chunk_rows`
/// rows the stack `[R; rows]` is re-triangularised by Householder QR, so `R^T R` always
/// equals the Gram matrix of all rows pushed, in `(k + chunk) k` doubles of memory.
///
/// ```
/// use sysid_core::linalg::QrAccumulator;
/// let mut acc = QrAccumulator::new(2, 2);
/// for row in [[3.0, 0.0], [4.0, 0.0], [0.0, 2.0]] {
///     acc.push_row(&row);
/// }
/// let r = acc.finish();
/// assert!((r[(0, 0)].abs() - 5.0).abs() < 1e-14 && (r[(1, 1)].abs() - 2.0).abs() < 1e-14);
/// ```
#[derive(Debug, Clone)]
pub struct QrAccumulator {
    k: usize,
    chunk_rows: usize,
    work: Mat<f64>,
    pending: usize,
    rows: usize,
}

impl QrAccumulator {
    /// An accumulator for rows of length `k`, re-triangularising every `chunk_rows` rows.
    ///
    /// `chunk_rows` is capped so that the work matrix stays within
    /// [`crate::error::MAX_MATRIX_BYTES`] (the result does not depend on it beyond round-off).
    /// The work matrix is allocated with the first row: an accumulator that never receives
    /// one (a stream too short for a single window) costs nothing.
    pub fn new(k: usize, chunk_rows: usize) -> Self {
        let cap = (crate::error::MAX_MATRIX_BYTES / 8 / k.max(1)).saturating_sub(k);
        let chunk_rows = chunk_rows.min(cap).max(1);
        Self {
            k,
            chunk_rows,
            work: Mat::zeros(0, 0),
            pending: 0,
            rows: 0,
        }
    }

    /// Row length k.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Number of rows pushed so far.
    pub fn n_rows(&self) -> usize {
        self.rows
    }

    /// Appends one row (length k).
    #[inline]
    pub fn push_row(&mut self, row: &[f64]) {
        debug_assert_eq!(row.len(), self.k);
        if self.work.nrows() == 0 {
            self.work = Mat::zeros(self.k + self.chunk_rows, self.k);
        }
        let r = self.k + self.pending;
        for (j, v) in row.iter().enumerate() {
            self.work[(r, j)] = *v;
        }
        self.pending += 1;
        self.rows += 1;
        if self.pending == self.chunk_rows {
            self.flush();
        }
    }

    /// Re-triangularises the pending rows into R.
    pub fn flush(&mut self) {
        if self.pending == 0 {
            return;
        }
        let k = self.k;
        let rows = k + self.pending;
        qr_r_in_place(self.work.as_mut().subrows_mut(0, rows));
        // keep R (upper triangle of the first min(rows, k) rows), clear the reflectors
        for j in 0..k {
            for i in (j + 1)..rows {
                self.work[(i, j)] = 0.0;
            }
        }
        self.pending = 0;
    }

    /// The upper-triangular R (k x k) with `R^T R = sum of row row^T`, non-negative diagonal.
    pub fn finish(mut self) -> Mat<f64> {
        self.flush();
        let k = self.k;
        let mut r = Mat::<f64>::zeros(k, k);
        if self.work.nrows() == 0 {
            return r; // no rows: R = 0
        }
        for i in 0..k {
            let sign = if self.work[(i, i)] < 0.0 { -1.0 } else { 1.0 };
            for j in i..k {
                r[(i, j)] = sign * self.work[(i, j)];
            }
        }
        r
    }
}

/// Symmetric part `(M + M^T) / 2`.
pub fn symmetrize(m: &mut Mat<f64>) {
    let n = m.nrows();
    for i in 0..n {
        for j in 0..i {
            let v = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = v;
            m[(j, i)] = v;
        }
    }
}

/// Numerical rank: number of singular values above `rtol * s_max`.
pub fn rank(a: MatRef<'_, f64>, rtol: f64) -> Result<usize> {
    if a.nrows() == 0 || a.ncols() == 0 {
        return Ok(0);
    }
    let (s, _, _) = svd_seq("rank (SVD)", a, false, false)?;
    let smax = s[0];
    Ok(s.iter().filter(|&&x| x > rtol * smax && x > 0.0).count())
}

/// Determinant of a symmetric positive semi-definite matrix (a residual covariance) from its
/// Cholesky factor; 0 when the factorisation fails (singular or indefinite).
pub(crate) fn determinant(m: &Mat<f64>) -> f64 {
    match m.llt(faer::Side::Lower) {
        Ok(f) => (0..m.nrows()).map(|i| f.L()[(i, i)].powi(2)).product(),
        Err(_) => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::mat;

    #[test]
    fn accumulator_sizes_its_work_matrix_with_the_first_row() {
        // a stream too short for one window (past = 2000) allocated the 2.5 GB work
        // matrix of the exact compressor before the record was known to be too short
        let acc = QrAccumulator::new(8000, 32_000);
        assert_eq!(acc.work.nrows(), 0);
        assert_eq!(acc.finish().norm_max(), 0.0);
        let mut acc = QrAccumulator::new(3, 4);
        acc.push_row(&[3.0, 0.0, 4.0]);
        assert_eq!(acc.work.nrows(), 3 + 4);
        let r = acc.finish();
        let g = r.transpose() * &r;
        let want = [[9.0, 0.0, 12.0], [0.0, 0.0, 0.0], [12.0, 0.0, 16.0]];
        for (i, row) in want.iter().enumerate() {
            for (j, w) in row.iter().enumerate() {
                assert!((g[(i, j)] - w).abs() < 1e-12, "{i} {j}: {}", g[(i, j)]);
            }
        }
    }

    #[test]
    fn pinv_inverts_full_rank() {
        let a = mat![[2.0, 1.0], [1.0, 3.0], [0.0, 1.0]];
        let p = pinv(a.as_ref(), 1e-12).unwrap();
        let i = &p * &a;
        for r in 0..2 {
            for c in 0..2 {
                let e = if r == c { 1.0 } else { 0.0 };
                assert!((i[(r, c)] - e).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn lq_reproduces_gram() {
        let m = mat![
            [1.0, 2.0, 3.0, 4.0],
            [0.5, -1.0, 2.0, 0.0],
            [3.0, 1.0, 0.0, 1.0]
        ];
        let l = lq_lower(m.as_ref());
        let g1 = &l * l.transpose();
        let g2 = &m * m.transpose();
        for i in 0..3 {
            for j in 0..3 {
                assert!((g1[(i, j)] - g2[(i, j)]).abs() < 1e-12);
            }
            for j in i + 1..3 {
                assert_eq!(l[(i, j)], 0.0);
            }
        }
    }

    #[test]
    fn rank_one_lq_matches_householder_lq() {
        // T lower triangular (some zero pivots: rank-deficient), offsets large against the
        // triangle as centred data with big means give; n = k, k + 1, k + 3 columns
        let mut st: u64 = 7;
        let mut rnd = move || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((st >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        };
        for &(k, extra, offset) in &[
            (1usize, 0usize, 1.0),
            (1, 1, 1e3),
            (5, 1, 1.0),
            (12, 1, 1e4),
            (12, 3, 1e-3),
            (30, 0, 10.0),
            (30, 1, 1e6),
        ] {
            let n = k + extra;
            let t = Mat::from_fn(k, k, |i, j| {
                if j > i || (i == j && i % 7 == 3) {
                    0.0
                } else {
                    rnd()
                }
            });
            let c: Vec<f64> = (0..k).map(|_| offset * rnd()).collect();
            let r: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let m = Mat::from_fn(k, n, |i, j| {
                (if j < k { t[(i, j)] } else { 0.0 }) + c[i] * r[j]
            });
            let fast = lq_lower_rank_one(t.as_ref(), &c, &r);
            let gram_fast = &fast * fast.transpose();
            let gram = &m * m.transpose();
            let scale = gram.norm_max();
            assert!(
                (&gram_fast - &gram).norm_max() <= 1e-13 * scale,
                "k {k} n {n}: {:e}",
                (&gram_fast - &gram).norm_max() / scale
            );
            for i in 0..k {
                assert!(fast[(i, i)] >= 0.0);
                for j in i + 1..k {
                    assert_eq!(fast[(i, j)], 0.0);
                }
            }
            if (0..k).all(|i| i % 7 != 3) {
                // full rank: the triangle with a non-negative diagonal is unique
                let slow = lq_lower(m.as_ref());
                let size = slow.norm_max();
                assert!((&fast - &slow).norm_max() <= 1e-12 * size, "k {k} n {n}");
            }
        }
    }
}
