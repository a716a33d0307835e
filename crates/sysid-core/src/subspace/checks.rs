//! Checks of a record read from its compressed factor alone (no pass over the samples): the
//! regressions of the feedback test and the persistent-excitation order of the input.
//!
//! Both run on the calling thread with faer's explicit sequential kernels: the matrices
//! have a few hundred rows, and a threaded LAPACK or rayon call would spend more in thread
//! wake-ups than in work (on a loaded machine a first call could wait for seconds).

use crate::error::Result;
use crate::hankel::HankelFactor;
use crate::linalg::{mul_seq, qr_r_in_place, rsolve_lstsq, svd_left_seq, sym_eigenvalues_seq};
use faer::{Mat, MatRef, Par};

/// Residual sums of squares of the feedback test's two regressions (see
/// `sysid.validation.feedback`): the first input sample of the future, `u(t)` (the first `m`
/// rows of L), regressed on the past inputs alone (restricted) and on the past inputs and
/// the past outputs' innovations (full).
#[derive(Debug, Clone, PartialEq)]
pub struct FeedbackRegressions {
    /// Residual sum of squares of each input on the past inputs.
    pub rss_restricted: Vec<f64>,
    /// Residual sum of squares of each input on the past inputs and output innovations.
    pub rss_full: Vec<f64>,
    /// Numerical rank of the past-input regressors.
    pub rank_restricted: usize,
    /// Numerical rank of the past-input and output-innovation regressors.
    pub rank_full: usize,
    /// Sum of squares of each input (`u(t)^T u(t)`).
    pub total: Vec<f64>,
}

/// The regressions of the feedback test on the factor; `rtol` is the relative singular value
/// below which regressor directions are dropped (rows scaled to unit norm first).
///
/// In the row order `[U_f; U_p; Y_p; Y_f]` of L, `u(t)` is rows `0..m`, the past inputs rows
/// `f m .. (f + p) m` (time order: the last block is `u(t - 1)`) and the past outputs the next
/// `p l` rows; L is lower triangular, so only the leading `(f + p) m` (restricted) or
/// `(f + p) m + p l` (full) columns enter.
///
/// The full regression does not take the past outputs themselves but their innovations
/// ([`output_innovations`]): in open loop the outputs also carry the inputs older than the
/// window (through the state), and an input with a long memory (a band-limited multisine,
/// which its own `p` lags predict to 1e-6 but not exactly) is then "predicted" by them,
/// a false detection on any long record. The innovations are free of the inputs' past; under
/// feedback the input depends on them through the controller.
pub fn feedback_regressions(factor: &HankelFactor, rtol: f64) -> Result<FeedbackRegressions> {
    let lay = factor.layout();
    let (m, l, p, f) = (lay.n_inputs, lay.n_outputs, lay.past, lay.future);
    let lm = factor.l();
    let c_full = (f + p) * m + p * l;
    let c_restr = (f + p) * m;
    let innov = output_innovations(lm.subcols(0, c_full), m, l, p, f)?;
    let mut full = Mat::<f64>::zeros(p * m + innov.nrows(), c_full);
    full.as_mut()
        .submatrix_mut(0, 0, p * m, c_full)
        .copy_from(lm.submatrix(f * m, 0, p * m, c_full));
    full.as_mut()
        .submatrix_mut(p * m, 0, innov.nrows(), c_full)
        .copy_from(innov.as_ref());
    let total = (0..m)
        .map(|i| {
            let r = lm.row(i).subcols(0, c_full);
            r.iter().map(|v| v * v).sum()
        })
        .collect();
    let (rss_restricted, rank_restricted) = row_regression(
        lm.submatrix(f * m, 0, p * m, c_restr),
        lm.submatrix(0, 0, m, c_restr),
        rtol,
    )?;
    let (rss_full, rank_full) = row_regression(full.as_ref(), lm.submatrix(0, 0, m, c_full), rtol)?;
    Ok(FeedbackRegressions {
        rss_restricted,
        rss_full,
        rank_restricted,
        rank_full,
        total,
    })
}

/// The one-step innovations of the past outputs inside the window, as rows over the columns
/// of `lm` (the leading columns of L): `y(t - k)`, `k = 1 ..= p - q` with `q = p / 2`, less
/// its least-squares regression on `y(t - k - 1 .. t - k - q)` and `u(t - k - q .. t - k)`
/// (an ARX model of order `q`, the direct term included, fitted on the factor). A row at
/// round-off level (a noise-free record: the outputs are a function of the inputs) is zeroed,
/// so the test makes no claim from it.
fn output_innovations(
    lm: MatRef<'_, f64>,
    m: usize,
    l: usize,
    p: usize,
    f: usize,
) -> Result<Mat<f64>> {
    let q = p / 2;
    let cols = lm.ncols();
    let u_row = |k: usize| f * m + (p - k) * m; // first row of u(t - k), 1 <= k <= p
    let y_row = |k: usize| (f + p) * m + (p - k) * l;
    let mut out = Mat::<f64>::zeros((p - q) * l, cols);
    for k in 1..=p - q {
        let mut x = Mat::<f64>::zeros(q * l + (q + 1) * m, cols);
        let mut r = 0;
        for j in k + 1..=k + q {
            x.as_mut()
                .submatrix_mut(r, 0, l, cols)
                .copy_from(lm.submatrix(y_row(j), 0, l, cols));
            r += l;
        }
        for j in k..=k + q {
            x.as_mut()
                .submatrix_mut(r, 0, m, cols)
                .copy_from(lm.submatrix(u_row(j), 0, m, cols));
            r += m;
        }
        for i in 0..x.nrows() {
            let nrm = x.row(i).norm_l2();
            if nrm > 0.0 {
                x.row_mut(i).iter_mut().for_each(|v| *v /= nrm);
            }
        }
        let target = lm.submatrix(y_row(k), 0, l, cols);
        let coef = rsolve_lstsq(target, x.as_ref(), 1e-10)?;
        let fitted = mul_seq(coef.as_ref(), x.as_ref());
        for i in 0..l {
            let scale = target.row(i).norm_l2();
            let o = (k - 1) * l + i;
            for c in 0..cols {
                out[(o, c)] = target[(i, c)] - fitted[(i, c)];
            }
            if out.row(o).norm_l2() <= 1e-9 * scale {
                out.row_mut(o).fill(0.0);
            }
        }
    }
    Ok(out)
}

/// Residual sums of squares of each row of `targets` regressed (least squares, minimum
/// norm) on the rows of `x`, and the numerical rank of `x`.
///
/// The rows of `x` are scaled to unit norm (zero rows dropped); singular values at or below
/// `rtol` times the largest count as zero (LAPACK `gelsd`'s rule). One Householder QR of
/// `[x^T | targets^T]` gives `R_xx`, the targets' coordinates `w` on the regressors' span
/// and the norms of their parts outside it. When `||R_xx||_F ||R_xx^{-1}||_F < 1 / rtol`
/// (a bound on the condition number) every singular value is above the cut and the residual
/// is the outside part; otherwise the SVD of `R_xx` (r x r) decides the rank and the
/// residual adds the part of `w` outside the retained singular vectors.
pub fn row_regression(
    x: MatRef<'_, f64>,
    targets: MatRef<'_, f64>,
    rtol: f64,
) -> Result<(Vec<f64>, usize)> {
    let cols = x.ncols();
    let nt = targets.nrows();
    let norms: Vec<f64> = (0..x.nrows())
        .map(|i| x.row(i).iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect();
    let kept: Vec<usize> = (0..x.nrows()).filter(|&i| norms[i] > 0.0).collect();
    let r = kept.len();
    let sq = |v: &mut dyn Iterator<Item = f64>| v.map(|a| a * a).sum::<f64>();
    if r == 0 {
        let rss = (0..nt)
            .map(|i| sq(&mut targets.row(i).iter().copied()))
            .collect();
        return Ok((rss, 0));
    }
    let rows = cols.max(r + nt);
    let mut a = Mat::<f64>::zeros(rows, r + nt);
    for (j, &i) in kept.iter().enumerate() {
        let s = 1.0 / norms[i];
        for (dst, v) in a.col_mut(j).iter_mut().zip(x.row(i).iter()) {
            *dst = v * s;
        }
    }
    for i in 0..nt {
        for (dst, v) in a.col_mut(r + i).iter_mut().zip(targets.row(i).iter()) {
            *dst = *v;
        }
    }
    qr_r_in_place(a.as_mut());
    // the part of target i outside span(x): rows r ..= r + i of its column of R
    let outside: Vec<f64> = (0..nt)
        .map(|i| {
            let top = (r + i + 1).min(rows);
            sq(&mut (r..top).map(|k| a[(k, r + i)]))
        })
        .collect();
    let mut rxx = Mat::<f64>::zeros(r, r);
    for j in 0..r {
        for i in 0..=j {
            rxx[(i, j)] = a[(i, j)];
        }
    }
    if well_conditioned(rxx.as_ref(), rtol) {
        return Ok((outside, r));
    }
    let (s, u) = svd_left_seq("feedback test (SVD)", rxx.as_ref())?;
    let smax = s.first().copied().unwrap_or(0.0);
    let rank = s.iter().filter(|&&v| v > rtol * smax).count();
    let w = a.as_ref().submatrix(0, r, r, nt);
    let uk = u.as_ref().subcols(0, rank);
    let coord = mul_seq(uk.transpose(), w);
    let fitted = mul_seq(uk, coord.as_ref());
    let rss = (0..nt)
        .map(|i| outside[i] + sq(&mut (0..r).map(|k| w[(k, i)] - fitted[(k, i)])))
        .collect();
    Ok((rss, rank))
}

/// True when the upper-triangular `r` has `||r||_F ||r^{-1}||_F < 1 / rtol`: then
/// `s_min / s_max >= 1 / (||r||_F ||r^{-1}||_F) > rtol`, all singular values pass the cut.
pub(crate) fn well_conditioned(r: MatRef<'_, f64>, rtol: f64) -> bool {
    let n = r.nrows();
    if (0..n).any(|i| r[(i, i)] == 0.0 || !r[(i, i)].is_finite()) {
        return false;
    }
    let mut inv = Mat::<f64>::identity(n, n);
    faer::linalg::triangular_solve::solve_upper_triangular_in_place(r, inv.as_mut(), Par::Seq);
    let fro = |m: MatRef<'_, f64>| {
        let mut s = 0.0;
        for j in 0..m.ncols() {
            for i in 0..=j.min(m.nrows() - 1) {
                s += m[(i, j)] * m[(i, j)];
            }
        }
        s.sqrt()
    };
    let bound = fro(r) * fro(inv.as_ref());
    // a margin of 2 against the rounding of the bound itself
    bound.is_finite() && bound < 0.5 / rtol
}

/// Persistent-excitation order of the input read from the factor: the largest
/// `d <= min(needed, p + f)` for which the input's block Hankel matrix with `d` block rows
/// (the input rows of L in time order, `U_p` then `U_f`) has full rank, i.e. the smallest
/// eigenvalue of its Gram matrix is above `tol` times the largest eigenvalue of the Gram
/// matrix of all `min(needed, p + f)` block rows. Beyond the window the factor cannot tell:
/// when every block row of the window passes, `needed` is returned.
///
/// The smallest eigenvalue of the leading `d m` block `G_d` exceeds `τ` exactly when
/// `G_d - τ I` is positive definite, and the Cholesky factor of a leading block is the
/// leading block of the Cholesky factor: one Cholesky of `G - τ I` answers every `d` (the
/// first non-positive pivot, in row `j`, gives `d = j / m`).
pub fn excitation_order(factor: &HankelFactor, needed: usize, tol: f64) -> Result<usize> {
    let lay = factor.layout();
    let (m, p, f) = (lay.n_inputs, lay.past, lay.future);
    if m == 0 || needed == 0 {
        return Ok(needed);
    }
    let depth = needed.min(p + f);
    let lm = factor.l();
    let cols = (f + p) * m;
    // input rows in time order: U_p (rows f m .. (f + p) m) then U_f (rows 0 .. f m)
    let rows: Vec<usize> = (f * m..(f + p) * m)
        .chain(0..f * m)
        .take(depth * m)
        .collect();
    let mut mrows = Mat::<f64>::zeros(rows.len(), cols);
    for (k, &i) in rows.iter().enumerate() {
        mrows.row_mut(k).copy_from(lm.row(i).subcols(0, cols));
    }
    let g = mul_seq(mrows.as_ref(), mrows.transpose());
    let top = sym_eigenvalues_seq(g.as_ref())?
        .last()
        .copied()
        .unwrap_or(0.0);
    let tau = tol * top;
    let n = g.nrows();
    let mut c = g;
    for i in 0..n {
        c[(i, i)] -= tau;
    }
    let good = first_nonpositive_pivot(c.as_mut());
    let got = good / m;
    Ok(if got == p + f { needed } else { got })
}

/// Cholesky of `a` (lower triangle, in place, on the calling thread); the row of the first
/// pivot that is not positive, or `a.nrows()` when `a` is positive definite.
fn first_nonpositive_pivot(a: faer::MatMut<'_, f64>) -> usize {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor::{
        cholesky_in_place, cholesky_in_place_scratch, LltError,
    };
    let n = a.nrows();
    let mut buf = MemBuffer::new(cholesky_in_place_scratch::<f64>(
        n,
        Par::Seq,
        Default::default(),
    ));
    match cholesky_in_place(
        a,
        Default::default(),
        Par::Seq,
        MemStack::new(&mut buf),
        Default::default(),
    ) {
        Ok(_) => n,
        Err(LltError::NonPositivePivot { index }) => index.min(n),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_failing_pivot_is_the_first_leading_block_that_is_not_definite() {
        // a positive definite matrix whose leading block of size k + 1 is indefinite
        for n in [5usize, 40, 130] {
            for k in [1usize, 3, n / 2, n - 1] {
                let mut a = Mat::<f64>::from_fn(n, n, |i, j| {
                    let x = (i as f64 + 1.0) * 0.37 - (j as f64) * 0.11;
                    if i == j {
                        4.0 + x.sin()
                    } else {
                        0.0
                    }
                });
                let v: Vec<f64> = (0..n).map(|i| ((i * 7 % 5) as f64 - 2.0) * 0.5).collect();
                for i in 0..n {
                    for j in 0..n {
                        a[(i, j)] += v[i] * v[j];
                    }
                }
                for j in 0..n {
                    let val = a[(k - 1, j)];
                    a[(k, j)] = val;
                }
                for i in 0..n {
                    let val = a[(i, k - 1)];
                    a[(i, k)] = val;
                }
                // the Schur complement of row k is now -1: its pivot is clearly negative
                a[(k, k)] -= 1.0;
                let got = first_nonpositive_pivot(a.as_mut());
                assert_eq!(got, k, "n = {n}, k = {k}");
            }
        }
    }

    /// The F statistic of the feedback test on a simulated record.
    fn feedback_f(u: &Mat<f64>, y: &Mat<f64>, p: usize) -> f64 {
        use crate::hankel::{Compressor, HankelLayout, QrCompressor};
        let mut c = QrCompressor::new(HankelLayout::new(1, 1, p, 1).unwrap());
        c.push(u.as_ref(), y.as_ref()).unwrap();
        let fac = c.finish().unwrap();
        let r = feedback_regressions(&fac, 1e-9).unwrap();
        let (q, df2) = (
            r.rank_full - r.rank_restricted,
            fac.n_columns() - r.rank_full,
        );
        (r.rss_restricted[0] - r.rss_full[0]).max(0.0) / q as f64 / (r.rss_full[0] / df2 as f64)
    }

    #[test]
    fn feedback_test_ignores_a_long_memory_input_and_sees_the_loop() {
        use rand::{rngs::StdRng, SeedableRng};
        use rand_distr::{Distribution, Normal};
        let n = 2048;
        let mut rng = StdRng::seed_from_u64(7);
        let g = Normal::new(0.0, 1.0).unwrap();
        // a band-limited multisine (period 512, lines 1..127): its 20 lags predict it to 1e-6
        let ms: Vec<f64> = (0..n)
            .map(|t| {
                (1..128)
                    .map(|k| {
                        let ph = (k * k) as f64 * 0.7;
                        (2.0 * std::f64::consts::PI * (k * t) as f64 / 512.0 + ph).cos()
                    })
                    .sum::<f64>()
                    / 8.0
            })
            .collect();
        let e: Vec<f64> = (0..n).map(|_| 0.3 * g.sample(&mut rng)).collect();
        let (mut uo, mut yo) = (Mat::<f64>::zeros(n, 1), Mat::<f64>::zeros(n, 1));
        let (mut uc, mut yc) = (Mat::<f64>::zeros(n, 1), Mat::<f64>::zeros(n, 1));
        for t in 0..n {
            uo[(t, 0)] = ms[t];
            if t > 0 {
                yo[(t, 0)] = 0.9 * yo[(t - 1, 0)] + uo[(t - 1, 0)] + e[t];
                yc[(t, 0)] = 0.9 * yc[(t - 1, 0)] + uc[(t - 1, 0)] + e[t];
            }
            uc[(t, 0)] = ms[t] - 0.3 * yc[(t, 0)];
        }
        // open loop: F near 1 (before the innovations, F was about 6 here: p < 1e-14)
        let open = feedback_f(&uo, &yo, 20);
        assert!(open < 2.5, "open loop F = {open}");
        // closed loop with the same reference: detected
        let closed = feedback_f(&uc, &yc, 20);
        assert!(closed > 20.0, "closed loop F = {closed}");
    }
}
