//! System matrices from the weighted SVD: A and C by shift invariance, B, D and the noise
//! covariances by least squares on L, K from the Riccati equation.
//!
//! B and D follow the robust combined algorithm of Van Overschee & De Moor (1996, sec. 4.3.3):
//! with `Z_i = Y_f / [W_p; U_f]` and `Z_{i+1} = Y_f^- / [W_p^+; U_f^-]` (orthogonal
//! projections, which in the coordinates of L are truncations of the rows of L), the state
//! sequences `Γ_f^+ Z_i`, `Γ_{f-1}^+ Z_{i+1}` satisfy
//!
//! ```text
//! [Γ_{f-1}^+ Z_{i+1}; Y_{i|i}] = [A; C] Γ_f^+ Z_i + 𝒦(B, D) U_f + [ρ_w; ρ_v]
//! ```
//!
//! with `𝒦` linear in B and D. Least squares gives B and D; the residual covariance gives
//! `[Q S; S^T R]`. `Γ_f` is recomputed from A and C first, so that the state basis of every
//! step is that of A and C.

use super::weighting::Weighted;
use super::{FitOptions, Identified, SystemMatrices};
use crate::error::{Result, SysidError};
use crate::hankel::{Block, HankelFactor};
use crate::linalg::{mul_seq, pinv, spectral_radius, symmetrize};
use crate::model::StateSpace;
use crate::riccati::kalman_gain;
use faer::{Mat, MatRef};

const PINV_TOL: f64 = 1e-12;

/// `[C; C A; ...; C A^{rows-1}]`.
pub fn observability(a: MatRef<'_, f64>, c: MatRef<'_, f64>, rows: usize) -> Mat<f64> {
    let (l, n) = (c.nrows(), c.ncols());
    let mut o = Mat::<f64>::zeros(rows * l, n);
    let mut ca = c.to_owned();
    for j in 0..rows {
        o.as_mut().subrows_mut(j * l, l).copy_from(&ca);
        ca = mul_seq(ca.as_ref(), a);
    }
    o
}

/// A and C from `Γ` (f l x n) by shift invariance; with `stable`, the zero-padded shift
/// (Chui & Maciejowski 1996) replaces an unstable least-squares A.
pub fn shift_invariance(
    gamma: MatRef<'_, f64>,
    l: usize,
    stable: bool,
) -> Result<(Mat<f64>, Mat<f64>, bool)> {
    let (fl, n) = (gamma.nrows(), gamma.ncols());
    let c = gamma.subrows(0, l).to_owned();
    let up = gamma.subrows(0, fl - l);
    let down = gamma.subrows(l, fl - l);
    let a = mul_seq(pinv(up, PINV_TOL)?.as_ref(), down);
    if stable && spectral_radius(a.as_ref())? >= 1.0 {
        let mut padded = Mat::<f64>::zeros(fl, n);
        padded.as_mut().subrows_mut(0, fl - l).copy_from(down);
        let a_st = mul_seq(pinv(gamma, PINV_TOL)?.as_ref(), padded.as_ref());
        return Ok((a_st, c, true));
    }
    Ok((a, c, false))
}

/// The linear map `(B, D) -> 𝒦(B, D)` ((n + l) x f m) as blocks: column block `q` of
/// `𝒦(B, D)` is `T_q B + S_q D` with `T_q` ((n + l) x n) and `S_q` ((n + l) x l).
///
/// With `Γ_f^+ = [P_0 .. P_{f-1}]`, `Γ_{f-1}^+ = [P1_0 .. P1_{f-2}]` (blocks of l columns),
/// `M_q = sum_{j > q} P_j C A^{j-q-1}` and `M1_q` likewise from `P1`: `T_0 = [I - A M_0;
/// -C M_0]`, `S_0 = [-A P_0; I - C P_0]`, and for `q >= 1` `T_q = [M1_{q-1} - A M_q; -C M_q]`,
/// `S_q = [P1_{q-1} - A P_q; -C P_q]` (Van Overschee & De Moor 1996, sec. 4.3.3, where
/// `𝒦` is the product of the block Toeplitz matrix of (B, D) with these projections).
struct KBlocks {
    t: Vec<Mat<f64>>,
    s: Vec<Mat<f64>>,
}

impl KBlocks {
    fn new(
        a: MatRef<'_, f64>,
        c: MatRef<'_, f64>,
        o_pinv: MatRef<'_, f64>,
        o1_pinv: MatRef<'_, f64>,
        f: usize,
    ) -> Self {
        let (n, l) = (a.nrows(), c.nrows());
        // C A^j, j = 0..f-2
        let mut ca: Vec<Mat<f64>> = Vec::with_capacity(f.saturating_sub(1));
        let mut cur = c.to_owned();
        for _ in 0..f.saturating_sub(1) {
            let next = mul_seq(cur.as_ref(), a);
            ca.push(cur);
            cur = next;
        }
        // M_q = sum_{j=q+1}^{last} P_j C A^{j-q-1}, from the blocks P_j of `pinv`
        let m_blocks = |pinv: MatRef<'_, f64>, blocks: usize| -> Vec<Mat<f64>> {
            (0..blocks)
                .map(|q| {
                    let mut mq = Mat::<f64>::zeros(n, n);
                    for j in q + 1..blocks {
                        faer::linalg::matmul::matmul(
                            mq.as_mut(),
                            faer::Accum::Add,
                            pinv.subcols(j * l, l),
                            ca[j - q - 1].as_ref(),
                            1.0,
                            faer::Par::Seq,
                        );
                    }
                    mq
                })
                .collect()
        };
        let m0 = m_blocks(o_pinv, f);
        let m1 = m_blocks(o1_pinv, f - 1);
        let mut t = Vec::with_capacity(f);
        let mut s = Vec::with_capacity(f);
        for q in 0..f {
            let pq = o_pinv.subcols(q * l, l);
            let mut tq = Mat::<f64>::zeros(n + l, n);
            let mut sq = Mat::<f64>::zeros(n + l, l);
            if q == 0 {
                for i in 0..n {
                    tq[(i, i)] = 1.0;
                }
                for i in 0..l {
                    sq[(n + i, i)] = 1.0;
                }
            } else {
                tq.as_mut().subrows_mut(0, n).copy_from(&m1[q - 1]);
                sq.as_mut()
                    .subrows_mut(0, n)
                    .copy_from(o1_pinv.subcols((q - 1) * l, l));
            }
            for (blk, rhs) in [(&mut tq, m0[q].as_ref()), (&mut sq, pq)] {
                let (top, bot) = blk.as_mut().split_at_row_mut(n);
                for (dst, lhs) in [(top, a), (bot, c)] {
                    faer::linalg::matmul::matmul(
                        dst,
                        faer::Accum::Add,
                        lhs,
                        rhs,
                        -1.0,
                        faer::Par::Seq,
                    );
                }
            }
            t.push(tq);
            s.push(sq);
        }
        Self { t, s }
    }

    /// `𝒦(B, D)` ((n + l) x f m).
    fn eval(&self, b: MatRef<'_, f64>, d: MatRef<'_, f64>) -> Mat<f64> {
        let (rows, m, f) = (self.t[0].nrows(), b.ncols(), self.t.len());
        let mut k = Mat::<f64>::zeros(rows, f * m);
        for q in 0..f {
            let mut blk = k.as_mut().subcols_mut(q * m, m);
            faer::linalg::matmul::matmul(
                blk.as_mut(),
                faer::Accum::Add,
                self.t[q].as_ref(),
                b,
                1.0,
                faer::Par::Seq,
            );
            faer::linalg::matmul::matmul(
                blk,
                faer::Accum::Add,
                self.s[q].as_ref(),
                d,
                1.0,
                faer::Par::Seq,
            );
        }
        k
    }
}

/// Estimates the model of order `n` from the weighted SVD.
pub fn identify(
    factor: &HankelFactor,
    w: &Weighted,
    n: usize,
    opts: &FitOptions,
) -> Result<Identified> {
    let lay = factor.layout();
    let (m, l, f) = (lay.n_inputs, lay.n_outputs, lay.future);
    let lmat = factor.l();
    let k_rows = lay.k();

    // Γ_f = basis[:, :n] diag(sqrt(s))
    let mut gamma = w.basis.as_ref().subcols(0, n).to_owned();
    for j in 0..n {
        let s = w.singular_values[j].sqrt();
        for i in 0..gamma.nrows() {
            gamma[(i, j)] *= s;
        }
    }
    // the shift estimate, once: `Auto` reads its A first (with `stable`, a stabilised A says
    // the plain one was unstable)
    let mut shift = None;
    let states = match opts.matrices {
        SystemMatrices::Shift => false,
        SystemMatrices::States => true,
        SystemMatrices::Auto => {
            let est = shift_invariance(gamma.as_ref(), l, opts.stable)?;
            let unstable = est.2 || spectral_radius(est.0.as_ref())? >= 1.0;
            shift = Some(est);
            unstable
        }
    };
    if states {
        let (a, b, c, d, cov) = from_states(factor, gamma.as_ref(), opts.feedthrough)?;
        // an unstable estimate gives way to the shift path (stabilised with `stable`) where
        // the states were a fallback or `stable` asks for a stable A
        let keep = opts.matrices == SystemMatrices::States && !opts.stable;
        if keep || spectral_radius(a.as_ref())? < 1.0 {
            return finish(a, b, c, d, cov, factor.n_columns(), false, opts);
        }
    }
    let (a, c, stabilized) = match shift {
        Some(est) => est,
        None => shift_invariance(gamma.as_ref(), l, opts.stable)?,
    };

    let o = observability(a.as_ref(), c.as_ref(), f);
    let o_pinv = pinv(o.as_ref(), PINV_TOL)?;
    let o1_pinv = pinv(o.as_ref().subrows(0, (f - 1) * l), PINV_TOL)?;

    // projections as truncated rows of L
    let (yf_s, _) = lay.block(Block::YFuture);
    let r1 = yf_s; // rows of [U_f; U_p; Y_p]
    let mut z_i = lmat.subrows(yf_s, f * l).to_owned();
    z_i.as_mut().subcols_mut(r1, k_rows - r1).fill(0.0);
    let mut z_i1 = lmat.subrows(yf_s + l, (f - 1) * l).to_owned();
    z_i1.as_mut().subcols_mut(r1 + l, k_rows - r1 - l).fill(0.0);
    let y_ii = lmat.subrows(yf_s, l);

    let x_i = mul_seq(o_pinv.as_ref(), z_i.as_ref()); // n x k
    let mut p = Mat::<f64>::zeros(n + l, k_rows);
    p.as_mut()
        .subrows_mut(0, n)
        .copy_from(mul_seq(o1_pinv.as_ref(), z_i1.as_ref()));
    p.as_mut().subrows_mut(n, l).copy_from(y_ii);
    {
        let (top, bot) = p.as_mut().split_at_row_mut(n);
        for (dst, lhs) in [(top, a.as_ref()), (bot, c.as_ref())] {
            faer::linalg::matmul::matmul(
                dst,
                faer::Accum::Add,
                lhs,
                x_i.as_ref(),
                -1.0,
                faer::Par::Seq,
            );
        }
    }

    let mut b = Mat::<f64>::zeros(n, m);
    let mut d = Mat::<f64>::zeros(l, m);
    let mut resid = p.clone();
    if m > 0 {
        let (uf_s, uf_n) = lay.block(Block::UFuture);
        let l11 = lmat.submatrix(uf_s, uf_s, uf_n, uf_n);
        let kb = KBlocks::new(a.as_ref(), c.as_ref(), o_pinv.as_ref(), o1_pinv.as_ref(), f);
        // unknowns: B (n x m) then D (l x m) if estimated, column-major; the column of
        // unknown (r, s) is vec(𝒦(E_rs) L11): row j (n + l) + i holds
        // sum_q T_q[i, r] L11[q m + s, j] (S_q for D), only q m + s >= j (L11 is lower
        // triangular)
        let n_b = n * m;
        let n_theta = n_b + if opts.feedthrough { l * m } else { 0 };
        let nl = n + l;
        let rows = nl * uf_n;
        let mut design = Mat::<f64>::zeros(rows, n_theta);
        for sidx in 0..m {
            for q in 0..f {
                let row = q * m + sidx;
                let (tq, sq) = (&kb.t[q], &kb.s[q]);
                for j in 0..=row.min(uf_n - 1) {
                    let coef = l11[(row, j)];
                    if coef == 0.0 {
                        continue;
                    }
                    for r in 0..n {
                        let col = design.as_mut().col_mut(sidx * n + r);
                        let src = tq.col(r);
                        let dst = col.subrows_mut(j * nl, nl);
                        zip_axpy(dst, coef, src);
                    }
                    if opts.feedthrough {
                        for r in 0..l {
                            let col = design.as_mut().col_mut(n_b + sidx * l + r);
                            let src = sq.col(r);
                            let dst = col.subrows_mut(j * nl, nl);
                            zip_axpy(dst, coef, src);
                        }
                    }
                }
            }
        }
        let mut rhs = Mat::<f64>::zeros(rows, 1);
        for j in 0..uf_n {
            for i in 0..nl {
                rhs[(j * nl + i, 0)] = p[(i, uf_s + j)];
            }
        }
        let theta = if n_theta > 0 {
            // sequential QR: the same bits for any thread count
            let theta = crate::linalg::lstsq_seq(design.as_ref(), rhs.as_ref());
            if !theta.col(0).iter().all(|v| v.is_finite()) {
                // a design of deficient rank: an order at the data matrix's numerical rank
                // whose last state the input does not reach (a minimum-norm B simulated
                // nothing of a tracking record that order n - 1 fits at 25 %)
                return Err(SysidError::numerical(
                    "B and D",
                    format!(
                        "the input does not determine B at order {n} (the least-squares \
                         design of B and D has deficient rank: the order is at the numerical \
                         rank of the data matrix, or above what the input excites); {}",
                        if n > 1 {
                            format!("choose order {} or lower", n - 1)
                        } else {
                            "use a richer input".to_string()
                        }
                    ),
                ));
            }
            theta
        } else {
            Mat::zeros(0, 1)
        };
        for t in 0..n_theta {
            if t < n_b {
                b[(t % n, t / n)] = theta[(t, 0)];
            } else {
                let s = t - n_b;
                d[(s % l, s / l)] = theta[(t, 0)];
            }
        }
        let kt = mul_seq(kb.eval(b.as_ref(), d.as_ref()).as_ref(), l11);
        let mut fit_cols = resid.as_mut().subcols_mut(uf_s, uf_n);
        fit_cols -= &kt;
    }

    let cov = mul_seq(resid.as_ref(), resid.transpose());
    finish(a, b, c, d, cov, factor.n_columns(), stabilized, opts)
}

/// The model and its noise description from A, B, C, D and the residuals' sum of squares
/// `[Q S; S^T R]` (times the number of data columns `cols`).
#[allow(clippy::too_many_arguments)]
fn finish(
    a: Mat<f64>,
    b: Mat<f64>,
    c: Mat<f64>,
    d: Mat<f64>,
    mut cov: Mat<f64>,
    cols: usize,
    stabilized: bool,
    opts: &FitOptions,
) -> Result<Identified> {
    let (n, l) = (a.nrows(), c.nrows());
    let scale = 1.0 / cols as f64;
    for j in 0..n + l {
        for i in 0..n + l {
            cov[(i, j)] *= scale;
        }
    }
    symmetrize(&mut cov);
    let q = cov.as_ref().submatrix(0, 0, n, n).to_owned();
    let s = cov.as_ref().submatrix(0, n, n, l).to_owned();
    let r = cov.as_ref().submatrix(n, n, l, l).to_owned();

    let sys = StateSpace::new(a, b, c, d).map_err(|_| {
        SysidError::numerical(
            "system matrices",
            "non-finite estimates; the data may be degenerate for this order and horizon",
        )
    })?;
    let (k, innovation_cov, kalman_regularization, kalman_residual) = if opts.kalman {
        let sol = kalman_gain(
            sys.a.as_ref(),
            sys.c.as_ref(),
            q.as_ref(),
            r.as_ref(),
            s.as_ref(),
        )?;
        (
            Some(sol.k),
            Some(sol.innovation_cov),
            sol.regularization,
            sol.residual,
        )
    } else {
        (None, None, 0.0, 0.0)
    };
    Ok(Identified {
        sys,
        k,
        innovation_cov,
        q,
        r,
        s,
        stabilized,
        predictor_stabilized: false,
        kalman_regularization,
        kalman_residual,
    })
}

/// A, B, C, D and the residuals' sum of squares by least squares on the estimated state
/// sequence ([`SystemMatrices::States`]).
///
/// The state of the window starting at sample `t` is `x(t+p) = Γ_f^+ L32 L22^+ w_p(t)`, the
/// oblique projection of the future outputs onto the past `w_p(t)` (`u(t), ..., u(t+p-1)`
/// and `y(t), ..., y(t+p-1)`) mapped to the states; the next one, `x(t+p+1)`, is the same
/// map of the past one sample later, `w_p(t+1)`, whose rows are rows of the same data column
/// (the last p - 1 past blocks and the first future one). Every regressor and regressand is
/// thus a fixed combination of rows of the data matrix `H = L Q^T`, and the least squares
/// over the columns of `H` are those over the columns of `L` (`Q` has orthonormal columns):
///
/// ```text
/// [x(t+p+1); y(t+p)] = [A B; C D] [x(t+p); u(t+p)] + residuals
/// ```
///
/// (without feedthrough, `y` on `x` alone). On noise-free data of order n the states are
/// exact and so are the matrices; on noisy data the states are those of a bank of Kalman
/// filters of p past samples, as in the state-sequence methods of Larimore (1990) and
/// Verhaegen & Verdult (2007, sec. 9.6), SIPPY's and nfoursid's.
#[allow(clippy::type_complexity)]
fn from_states(
    factor: &HankelFactor,
    gamma: MatRef<'_, f64>,
    feedthrough: bool,
) -> Result<(Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>)> {
    let lay = factor.layout();
    let (m, l, p, f) = (lay.n_inputs, lay.n_outputs, lay.past, lay.future);
    let n = gamma.ncols();
    let lmat = factor.l();
    let (uf_s, _) = lay.block(Block::UFuture);
    let (up_s, _) = lay.block(Block::UPast);
    let (yp_s, _) = lay.block(Block::YPast);
    let (yf_s, _) = lay.block(Block::YFuture);
    let wp_n = p * (m + l);
    // the map from a past window to the state
    let l32 = lmat.submatrix(yf_s, up_s, f * l, wp_n);
    let l22 = lmat.submatrix(up_s, up_s, wp_n, wp_n);
    let theta = mul_seq(l32, pinv(l22, PINV_TOL)?.as_ref());
    let g = mul_seq(pinv(gamma, PINV_TOL)?.as_ref(), theta.as_ref());
    // the past of this window and of the next one, as rows of L
    let w0 = lmat.subrows(up_s, wp_n);
    let mut w1 = Mat::<f64>::zeros(wp_n, lmat.ncols());
    let shifted = [
        (up_s + m, (p - 1) * m, 0),
        (uf_s, m, (p - 1) * m),
        (yp_s + l, (p - 1) * l, p * m),
        (yf_s, l, p * m + (p - 1) * l),
    ];
    for (src, rows, dst) in shifted {
        w1.as_mut()
            .subrows_mut(dst, rows)
            .copy_from(lmat.subrows(src, rows));
    }
    let x0 = mul_seq(g.as_ref(), w0);
    let x1 = mul_seq(g.as_ref(), w1.as_ref());
    let u0 = lmat.subrows(uf_s, m);
    let y0 = lmat.subrows(yf_s, l);
    let cols = lmat.ncols();
    // regressors [x; u] and regressands [x+; y] as columns of the design (one row per column
    // of L)
    let mut phi = Mat::<f64>::zeros(cols, n + m);
    phi.as_mut().subcols_mut(0, n).copy_from(x0.transpose());
    phi.as_mut().subcols_mut(n, m).copy_from(u0.transpose());
    let mut psi = Mat::<f64>::zeros(cols, n + l);
    psi.as_mut().subcols_mut(0, n).copy_from(x1.transpose());
    psi.as_mut().subcols_mut(n, l).copy_from(y0.transpose());
    let mut theta_sys = Mat::<f64>::zeros(n + m, n + l); // [A B; C D]^T
    if feedthrough {
        theta_sys.copy_from(crate::linalg::lstsq_seq(phi.as_ref(), psi.as_ref()));
    } else {
        theta_sys
            .as_mut()
            .subcols_mut(0, n)
            .copy_from(crate::linalg::lstsq_seq(
                phi.as_ref(),
                psi.as_ref().subcols(0, n),
            ));
        theta_sys
            .as_mut()
            .submatrix_mut(0, n, n, l)
            .copy_from(crate::linalg::lstsq_seq(
                phi.as_ref().subcols(0, n),
                psi.as_ref().subcols(n, l),
            ));
    }
    let sys = theta_sys.transpose().to_owned(); // (n + l) x (n + m)
    let a = sys.as_ref().submatrix(0, 0, n, n).to_owned();
    let b = sys.as_ref().submatrix(0, n, n, m).to_owned();
    let c = sys.as_ref().submatrix(n, 0, l, n).to_owned();
    let d = sys.as_ref().submatrix(n, n, l, m).to_owned();
    let resid = &psi - mul_seq(phi.as_ref(), theta_sys.as_ref()); // cols x (n + l)
    let cov = mul_seq(resid.transpose(), resid.as_ref());
    Ok((a, b, c, d, cov))
}

/// `dst += coef * src` (columns of equal length).
#[inline]
fn zip_axpy(dst: faer::ColMut<'_, f64>, coef: f64, src: faer::ColRef<'_, f64>) {
    for (d, s) in dst.iter_mut().zip(src.iter()) {
        *d += coef * s;
    }
}
