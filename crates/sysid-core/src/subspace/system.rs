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
use super::{FitOptions, Identified};
use crate::error::{Result, SysidError};
use crate::hankel::{Block, HankelFactor};
use crate::linalg::{pinv, spectral_radius, symmetrize};
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
        ca = &ca * a;
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
    let a = pinv(up, PINV_TOL)? * down;
    if stable && spectral_radius(a.as_ref())? >= 1.0 {
        let mut padded = Mat::<f64>::zeros(fl, n);
        padded.as_mut().subrows_mut(0, fl - l).copy_from(down);
        let a_st = pinv(gamma, PINV_TOL)? * &padded;
        return Ok((a_st, c, true));
    }
    Ok((a, c, false))
}

struct KMap<'a> {
    a: MatRef<'a, f64>,
    c: MatRef<'a, f64>,
    o_pinv: Mat<f64>,
    o1_pinv: Mat<f64>,
    ca: Vec<Mat<f64>>, // C A^j, j = 0..f-2
    f: usize,
}

impl KMap<'_> {
    /// 𝒦(B, D) ((n + l) x f m).
    fn eval(&self, b: MatRef<'_, f64>, d: MatRef<'_, f64>) -> Mat<f64> {
        let (n, m, l, f) = (self.a.nrows(), b.ncols(), self.c.nrows(), self.f);
        // block Toeplitz H_f: (j, q) = D if j == q, C A^{j-q-1} B if j > q
        let markov: Vec<Mat<f64>> = self.ca.iter().map(|ca| ca * b).collect();
        let mut h = Mat::<f64>::zeros(f * l, f * m);
        for j in 0..f {
            for q in 0..=j {
                let blk = if j == q {
                    d
                } else {
                    markov[j - q - 1].as_ref()
                };
                h.as_mut().submatrix_mut(j * l, q * m, l, m).copy_from(blk);
            }
        }
        let gh = &self.o_pinv * &h; // n x f m
        let h1 = h.as_ref().submatrix(0, 0, (f - 1) * l, (f - 1) * m);
        let g1h = &self.o1_pinv * h1; // n x (f-1) m
        let mut k = Mat::<f64>::zeros(n + l, f * m);
        k.as_mut().submatrix_mut(0, 0, n, m).copy_from(b);
        k.as_mut()
            .submatrix_mut(0, m, n, (f - 1) * m)
            .copy_from(&g1h);
        k.as_mut().submatrix_mut(n, 0, l, m).copy_from(d);
        let agh = self.a * &gh;
        let cgh = self.c * &gh;
        let mut top = k.as_mut().subrows_mut(0, n);
        top -= &agh;
        let mut bot = k.as_mut().subrows_mut(n, l);
        bot -= &cgh;
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
    let (a, c, stabilized) = shift_invariance(gamma.as_ref(), l, opts.stable)?;

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

    let x_i = &o_pinv * &z_i; // n x k
    let mut p = Mat::<f64>::zeros(n + l, k_rows);
    p.as_mut().subrows_mut(0, n).copy_from(&o1_pinv * &z_i1);
    p.as_mut().subrows_mut(n, l).copy_from(y_ii);
    {
        let ax = &a * &x_i;
        let cx = &c * &x_i;
        let mut top = p.as_mut().subrows_mut(0, n);
        top -= &ax;
        let mut bot = p.as_mut().subrows_mut(n, l);
        bot -= &cx;
    }

    let mut b = Mat::<f64>::zeros(n, m);
    let mut d = Mat::<f64>::zeros(l, m);
    let mut resid = p.clone();
    if m > 0 {
        let (uf_s, uf_n) = lay.block(Block::UFuture);
        let l11 = lmat.submatrix(uf_s, uf_s, uf_n, uf_n);
        let kmap = KMap {
            a: a.as_ref(),
            c: c.as_ref(),
            o_pinv,
            o1_pinv,
            ca: (0..f.saturating_sub(1))
                .scan(c.clone(), |acc, _| {
                    let cur = acc.clone();
                    *acc = &*acc * &a;
                    Some(cur)
                })
                .collect(),
            f,
        };
        // unknowns: B (n x m) then D (l x m) if estimated, column-major
        let n_b = n * m;
        let n_theta = n_b + if opts.feedthrough { l * m } else { 0 };
        let rows = (n + l) * uf_n;
        let mut design = Mat::<f64>::zeros(rows, n_theta);
        let mut eb = Mat::<f64>::zeros(n, m);
        let mut ed = Mat::<f64>::zeros(l, m);
        for t in 0..n_theta {
            eb.fill(0.0);
            ed.fill(0.0);
            if t < n_b {
                eb[(t % n, t / n)] = 1.0;
            } else {
                let s = t - n_b;
                ed[(s % l, s / l)] = 1.0;
            }
            let kt = kmap.eval(eb.as_ref(), ed.as_ref()) * l11; // (n + l) x f m
            for j in 0..uf_n {
                for i in 0..n + l {
                    design[(j * (n + l) + i, t)] = kt[(i, j)];
                }
            }
        }
        let mut rhs = Mat::<f64>::zeros(rows, 1);
        for j in 0..uf_n {
            for i in 0..n + l {
                rhs[(j * (n + l) + i, 0)] = p[(i, uf_s + j)];
            }
        }
        let theta = if n_theta > 0 {
            // sequential QR: the same bits for any thread count
            crate::linalg::lstsq_seq(design.as_ref(), rhs.as_ref())
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
        let kt = kmap.eval(b.as_ref(), d.as_ref()) * l11;
        let mut fit_cols = resid.as_mut().subcols_mut(uf_s, uf_n);
        fit_cols -= &kt;
    }

    let mut cov = &resid * resid.transpose();
    let scale = 1.0 / factor.n_columns() as f64;
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
    let (k, innovation_cov) = if opts.kalman {
        let sol = kalman_gain(
            sys.a.as_ref(),
            sys.c.as_ref(),
            q.as_ref(),
            r.as_ref(),
            s.as_ref(),
        )?;
        (Some(sol.k), Some(sol.innovation_cov))
    } else {
        (None, None)
    };
    Ok(Identified {
        sys,
        k,
        innovation_cov,
        q,
        r,
        s,
        stabilized,
    })
}
