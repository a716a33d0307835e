//! The real modal form of the predictor matrix and the change of basis it induces on the
//! parameters.
//!
//! `Lambda = T^-1 Abar T` is block diagonal with 1x1 (real pole) and 2x2 (complex pair)
//! blocks. In the modal coordinates `phi' = (T^-1 Abar T, T^-1 Bbar, C T, D, T^-1 K, T^-1 x0)`
//! (a linear map `phi' = M phi` at the current point) the sensitivity of every state-moving
//! parameter lives in one block. `M^T` is applied by `n x n` products per column
//! ([`Predictor::modal_mt_cols`]), never as a dense `p x p` matrix.

use super::predictor::Predictor;
use faer::{Mat, MatRef};

/// A real block-diagonal (modal) form `Lambda = T^-1 Abar T` with 1x1 and 2x2 blocks.
pub(crate) struct Modal {
    pub t: Mat<f64>,
    pub ti: Mat<f64>,
    pub lam: Mat<f64>,
    /// For each state index: (first row, size) of its block.
    pub block: Vec<(usize, usize)>,
}

/// Column `idx` of the eigenvectors rotated to be real, into column `k` of `t`.
fn real_vector(t: &mut Mat<f64>, v: faer::ColRef<'_, faer::c64>, k: usize) {
    let n = v.nrows();
    let mut big = 0usize;
    for i in 0..n {
        if v[i].norm() > v[big].norm() {
            big = i;
        }
    }
    let ph = v[big].conj() * (1.0 / v[big].norm());
    for i in 0..n {
        t[(i, k)] = (v[i] * ph).re;
    }
}

/// The modal form of `abar`, or `None` when its eigenvectors are ill-conditioned (then the
/// plain structured evaluation is used).
pub(crate) fn modal_form(abar: MatRef<'_, f64>) -> Option<Modal> {
    use crate::linalg::mul;
    let n = abar.nrows();
    let eig = crate::realization::modal::eigen_decomposition(abar).ok()?;
    let mut t = Mat::<f64>::zeros(n, n);
    let mut lam = Mat::<f64>::zeros(n, n);
    let mut block = vec![(0usize, 0usize); n];
    let mut k = 0usize;
    let scale = 1.0 + eig.values.iter().map(|z| z.norm()).fold(0.0, f64::max);
    for (idx, z) in eig.values.iter().enumerate() {
        let v = eig.vectors.col(idx);
        if z.im.abs() <= 1e-13 * scale {
            if k >= n {
                return None;
            }
            real_vector(&mut t, v, k);
            lam[(k, k)] = z.re;
            block[k] = (k, 1);
            k += 1;
        } else if z.im > 0.0 {
            if k + 1 >= n {
                return None;
            }
            for i in 0..n {
                t[(i, k)] = v[i].re;
                t[(i, k + 1)] = v[i].im;
            }
            lam[(k, k)] = z.re;
            lam[(k, k + 1)] = z.im;
            lam[(k + 1, k)] = -z.im;
            lam[(k + 1, k + 1)] = z.re;
            block[k] = (k, 2);
            block[k + 1] = (k, 2);
            k += 2;
        }
    }
    if k != n {
        return None;
    }
    let ti = crate::linalg::inverse(t.as_ref());
    // a defective A (a double pole: parallel eigenvectors) gives a singular T: its inverse
    // holds inf or NaN, which the norms below (f64::max skips NaN) would not show
    if ti.has_nan() || !ti.is_all_finite() {
        return None;
    }
    let norm1 = |m: &Mat<f64>| {
        (0..n)
            .map(|j| (0..n).map(|i| m[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let cond = norm1(&t) * norm1(&ti);
    if !cond.is_finite() || cond > 1e6 {
        return None;
    }
    let check = mul(mul(ti.as_ref(), abar).as_ref(), t.as_ref()) - &lam;
    let anorm = abar.norm_max().max(1e-300);
    // NaN in the check counts as a failure
    let accurate = !check.has_nan() && check.norm_max() <= 1e-11 * anorm * cond;
    if !accurate {
        return None;
    }
    Some(Modal { t, ti, lam, block })
}

/// `dst = sum_k s_k v_k` over the terms whose `s_k` is not zero, in their order; for up to 8
/// entries the sums run in a fixed-size array (registers, not memory), the same sums.
fn weighted_sum<'a>(dst: &mut [f64], terms: impl Iterator<Item = (f64, &'a [f64])>) {
    let mut acc = [0.0; 8];
    let short = dst.len() <= acc.len();
    dst.fill(0.0);
    for (s, v) in terms {
        if s == 0.0 {
            continue;
        }
        let sums: &mut [f64] = if short { &mut acc } else { &mut *dst };
        for (dv, x) in sums.iter_mut().zip(v) {
            *dv += s * x;
        }
    }
    if short {
        let w = dst.len();
        dst.copy_from_slice(&acc[..w]);
    }
}

/// `dst[i, :] = sum_a ti[a][i] src(a)` for the rows of an `n x w` block: `T^-1`-transposed
/// applied from the left.
fn left_block(ticol: &[Vec<f64>], src: &[f64], dst: &mut [f64], w: usize) {
    for (i, ti) in ticol.iter().enumerate() {
        let terms = ti
            .iter()
            .enumerate()
            .map(|(a, &s)| (s, &src[a * w..a * w + w]));
        weighted_sum(&mut dst[i * w..i * w + w], terms);
    }
}

/// `dst[r, :] = sum_b src[r, b] T[:, b]` for the rows of an `r x n` block.
fn right_block(tcol: &[Vec<f64>], src: &[f64], dst: &mut [f64], rows: usize) {
    let n = tcol.len();
    for r in 0..rows {
        let terms = tcol
            .iter()
            .enumerate()
            .map(|(b, tb)| (src[r * n + b], tb.as_slice()));
        weighted_sum(&mut dst[r * n..r * n + n], terms);
    }
}

/// Where a change of state basis acts in a parameter vector (row-major blocks): the `n x n`
/// block at `a` (`A -> T^-T X T^T`), the `n x width` blocks in `left` (`B, K, x0 -> T^-T X`)
/// and the `rows x n` block at `c` (`C -> X T^T`); everything else is unchanged.
pub(crate) struct StateBlocks {
    pub a: usize,
    pub left: Vec<(usize, usize)>,
    pub c: usize,
    pub rows: usize,
}

/// `M^T X` for every column of `X`, for the modal change of basis `phi' = M phi` of the
/// parameters laid out as `at` says. `O(n^2 (n + widths + rows))` per column, on contiguous
/// slices; zero columns, and the zero entries of `X`, `T` and `T^-1` (block diagonal in the
/// modal chart) are skipped, which leaves every sum with finite terms unchanged.
pub(crate) fn modal_mt_cols(md: &Modal, at: &StateBlocks, x: &Mat<f64>) -> Mat<f64> {
    let n = md.t.nrows();
    let l = at.rows;
    let mut out = x.clone();
    let tcol: Vec<Vec<f64>> = (0..n)
        .map(|b| (0..n).map(|j| md.t[(j, b)]).collect())
        .collect();
    let ticol: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|a| md.ti[(a, i)]).collect())
        .collect();
    let mut tmp = vec![0.0; n * n];
    for c in 0..x.ncols() {
        let xs = x.col_as_slice(c);
        if xs.iter().all(|v| *v == 0.0) {
            // M^T 0 = 0 (the Gauss-Newton matrix's columns of parameters the chart holds)
            continue;
        }
        let os = out.col_as_slice_mut(c);
        right_block(&tcol, &xs[at.a..at.a + n * n], &mut tmp, n);
        left_block(&ticol, &tmp, &mut os[at.a..at.a + n * n], n);
        for &(o, wd) in &at.left {
            left_block(&ticol, &xs[o..o + n * wd], &mut os[o..o + n * wd], wd);
        }
        right_block(
            &tcol,
            &xs[at.c..at.c + l * n],
            &mut os[at.c..at.c + l * n],
            l,
        );
    }
    out
}

impl Predictor<'_> {
    /// `M^T X` for every column of `X`, for the modal change of basis `phi' = M phi`
    /// (row-major blocks): `A -> T^-T X T^T`, `B, K, x0 -> T^-T X`, `C -> X T^T`, `D`
    /// unchanged ([`modal_mt_cols`] in this predictor's layout).
    pub(super) fn modal_mt_cols(&self, md: &Modal, x: &Mat<f64>) -> Mat<f64> {
        let off = self.offsets();
        let mut left = vec![(off.b, self.m)];
        if let Some(k0) = off.k {
            left.push((k0, self.l));
        }
        for o in self.x0_off.iter().flatten() {
            left.push((*o, 1));
        }
        let at = StateBlocks {
            a: off.a,
            left,
            c: off.c,
            rows: self.l,
        };
        modal_mt_cols(md, &at, x)
    }

    /// `M^T x` for one vector (see [`Self::modal_mt_cols`]).
    pub(super) fn modal_mt(&self, md: &Modal, x: &[f64]) -> Vec<f64> {
        let col = Mat::from_fn(x.len(), 1, |i, _| x[i]);
        self.modal_mt_cols(md, &col).col_as_slice(0).to_vec()
    }

    /// The modal form of the predictor matrix at `theta` (see [`modal_form`]); in the modal
    /// chart, block by block ([`chart_modal`](super::chart::chart_modal)).
    pub(super) fn modal_at(&self, th: &[f64]) -> Option<Modal> {
        let abar = self.unpack(th).abar;
        match &self.chart {
            Some(chart) => super::chart::chart_modal(abar.as_ref(), chart),
            None => modal_form(abar.as_ref()),
        }
    }
}
