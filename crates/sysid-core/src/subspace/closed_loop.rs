//! Closed-loop subspace identification: PBSID-opt (Chiuso 2007) and SSARX (Jansson 2003),
//! both from one compressed record.
//!
//! Under feedback the future inputs are correlated with the past noise, which biases the
//! open-loop methods (they project the noise onto the future inputs). Both methods here
//! work with the *predictor* form
//!
//! ```text
//!   x(t+1) = Ā x(t) + B̃ z(t),   y(t) = C x(t) + D u(t) + e(t),
//!   Ā = A - K C,  B̃ = [B - K D, K],  z(t) = [u(t); y(t)],
//! ```
//!
//! whose state is a function of the past data only, `x(t) ≈ Σ_{k=1}^{p} Ā^{k-1} B̃ z(t-k)`
//! once `Ā^p` is negligible. First a VARX (high-order ARX) of order p,
//!
//! ```text
//!   y(t) = D u(t) + Σ_{k=1}^{p} Ξ_k z(t-k) + e(t),   Ξ_k = C Ā^{k-1} B̃,
//! ```
//!
//! is a least-squares problem with white residuals, consistent whatever the feedback when
//! the loop has a delay (D = 0, or a controller without direct feedthrough when D is
//! estimated). Then
//!
//! * **PBSID-opt** builds `Γ_f K_p` from the VARX coefficients (block (i, k) = `Ξ_{i+k}`,
//!   zero beyond p), takes the SVD of `Γ_f K_p` weighted by the covariance of the past, and
//!   reads the state sequence `x(t) = Γ_f^+ Γ_f K_p z_p(t)`;
//! * **SSARX** removes the future-innovation influence from the future outputs with the
//!   VARX coefficients, `ỹ(t+i) = y(t+i) - Σ_{j<i} Ξ_{i-j} z(t+j) - D u(t+i) = C Ā^i x(t) +
//!   e(t+i)`, then a canonical correlation analysis between `ỹ_f` and `z_p` gives the state.
//!
//! Finally `C, D` come from `y(t) = C x(t) + D u(t) + e(t)` and `A, B, K` from
//! `x(t+1) = A x(t) + B u(t) + K e(t)` by least squares; `K` needs no Riccati equation
//! unless it leaves the predictor `A - K C` unstable, when [`stable_predictor`] replaces it by
//! the stabilising Kalman gain of the same noise spectrum.
//!
//! Everything works on the triangular factor `L` of the block-Hankel matrix ([`crate::hankel`])
//! with the current time at the first future block: every regression above is between
//! linear combinations of rows of the data matrix, i.e. of rows of L, so nothing depends on
//! the record length after the compression. The VARX may be regularised (ridge, or a TC-like
//! prior `c α^k` on the coefficients of lag k with `(c, α)` tuned by marginal likelihood), as
//! in the regularised PBSID of Chiuso (2010) and Pillonetto et al.

use super::order::largest_log_gap;
use super::Identified;
use crate::error::{Result, SysidError};
use crate::hankel::HankelFactor;
use crate::linalg::{lq_lower, pinv};
use crate::model::StateSpace;
use faer::prelude::Solve;
use faer::{Mat, MatRef, Side};

const PINV_TOL: f64 = 1e-11;

/// The closed-loop method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum ClosedLoopMethod {
    /// PBSID-opt: `Γ_f K_p` from the VARX coefficients.
    #[default]
    Pbsid,
    /// SSARX: future outputs corrected with the VARX, then canonical correlation analysis.
    Ssarx,
}

crate::names::option_names! { ClosedLoopMethod, "method", true, [
    ("pbsid", ClosedLoopMethod::Pbsid), ("pbsid-opt", ClosedLoopMethod::Pbsid),
    ("pbsidopt", ClosedLoopMethod::Pbsid), ("ssarx", ClosedLoopMethod::Ssarx),
] }

impl ClosedLoopMethod {
    /// Parses `"pbsid" | "pbsid-opt" | "ssarx"` (ASCII case ignored); the same as
    /// `name.parse()`.
    pub fn parse(name: &str) -> Result<Self> {
        name.parse()
    }
}

/// Regularisation of the VARX least squares (on channels scaled to unit variance).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub enum VarxRegularization {
    /// Plain least squares.
    #[default]
    None,
    /// Ridge: `λ` times the mean diagonal of the regressors' Gram matrix added to it.
    Ridge(f64),
    /// Prior variance `c α^k` on every coefficient of lag k (lag 0 for `u(t)`), `(c, α)`
    /// tuned per output by maximising the marginal likelihood on a grid.
    Tc,
}

/// Ridge weight of `"ridge"` parsed without a value (the Python default).
pub const DEFAULT_RIDGE: f64 = 1e-3;

crate::names::option_names! { VarxRegularization, "regularization", false, [
    ("none", VarxRegularization::None), ("ridge", VarxRegularization::Ridge(DEFAULT_RIDGE)),
    ("tc", VarxRegularization::Tc),
] }

impl VarxRegularization {
    /// The regularisation named `name` (`"none"`, `"ridge"`, `"tc"`), ridge weight `ridge`.
    ///
    /// ```
    /// use sysid_core::subspace::closed_loop::VarxRegularization;
    /// let r = VarxRegularization::from_name("ridge", 0.1).unwrap();
    /// assert_eq!(r, VarxRegularization::Ridge(0.1));
    /// assert!(VarxRegularization::from_name("lasso", 0.1).is_err());
    /// ```
    pub fn from_name(name: &str, ridge: f64) -> Result<Self> {
        Ok(match name.parse()? {
            VarxRegularization::Ridge(_) => VarxRegularization::Ridge(ridge),
            other => other,
        })
    }
}

/// Options of [`ClosedLoop::new`].
#[derive(Debug, Clone, Default)]
#[non_exhaustive]
pub struct ClosedLoopOptions {
    /// PBSID-opt or SSARX.
    pub method: ClosedLoopMethod,
    /// VARX regularisation.
    pub regularization: VarxRegularization,
    /// Estimate D (only consistent when the controller has no direct feedthrough).
    pub feedthrough: bool,
}

/// Row indices of the samples around the current time t (the first future block).
#[derive(Debug, Clone, Copy)]
struct Rows {
    m: usize,
    l: usize,
    p: usize,
    f: usize,
}

impl Rows {
    /// Row of input channel c at time t + j (`-p <= j < f`).
    fn u(&self, j: isize, c: usize) -> usize {
        let (m, p) = (self.m, self.p as isize);
        if j < 0 {
            self.f * m + ((p + j) as usize) * m + c
        } else {
            (j as usize) * m + c
        }
    }

    /// Row of output channel c at time t + j.
    fn y(&self, j: isize, c: usize) -> usize {
        let (m, l, p) = (self.m, self.l, self.p as isize);
        if j < 0 {
            (self.f + self.p) * m + ((p + j) as usize) * l + c
        } else {
            (self.f + self.p) * m + self.p * l + (j as usize) * l + c
        }
    }

    /// Rows of `z_p(t + s) = [z(t+s-1); ...; z(t+s-p)]`, `z = [u; y]`.
    fn past(&self, s: isize) -> Vec<usize> {
        let mut out = Vec::with_capacity(self.p * (self.m + self.l));
        for k in 1..=self.p as isize {
            out.extend((0..self.m).map(|c| self.u(s - k, c)));
            out.extend((0..self.l).map(|c| self.y(s - k, c)));
        }
        out
    }
}

fn pick(l: MatRef<'_, f64>, rows: &[usize]) -> Mat<f64> {
    Mat::from_fn(rows.len(), l.ncols(), |i, j| l[(rows[i], j)])
}

fn vstack(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows() + b.nrows(), a.ncols());
    out.as_mut().subrows_mut(0, a.nrows()).copy_from(a);
    out.as_mut().subrows_mut(a.nrows(), b.nrows()).copy_from(b);
    out
}

/// Least squares `tgt ≈ Θ phi` between row combinations of the data matrix (given in the
/// coordinates of L): returns Θ (minimum norm when `phi` is rank deficient).
fn lstsq(phi: MatRef<'_, f64>, tgt: MatRef<'_, f64>) -> Result<Mat<f64>> {
    let d = phi.nrows();
    if d == 0 {
        return Ok(Mat::zeros(tgt.nrows(), 0));
    }
    let t = lq_lower(vstack(phi, tgt).as_ref());
    let t11 = t.as_ref().submatrix(0, 0, d, d);
    let t21 = t.as_ref().submatrix(d, 0, tgt.nrows(), d);
    Ok(t21 * pinv(t11, PINV_TOL)?)
}

/// The VARX estimate: `[D, Ξ_1, ..., Ξ_p]` (D block present only with feedthrough).
#[derive(Debug, Clone)]
struct Varx {
    d: Mat<f64>,
    xi: Vec<Mat<f64>>,
}

fn varx(
    lmat: MatRef<'_, f64>,
    rows: &Rows,
    opts: &ClosedLoopOptions,
    n_columns: usize,
) -> Result<Varx> {
    let (m, l, p) = (rows.m, rows.l, rows.p);
    let mut reg: Vec<usize> = Vec::new();
    let mut lag: Vec<usize> = Vec::new();
    if opts.feedthrough {
        reg.extend((0..m).map(|c| rows.u(0, c)));
        lag.extend(std::iter::repeat_n(0, m));
    }
    let past = rows.past(0);
    for k in 1..=p {
        lag.extend(std::iter::repeat_n(k, m + l));
    }
    reg.extend(past);
    let phi = pick(lmat, &reg);
    let tgt = pick(lmat, &(0..l).map(|c| rows.y(0, c)).collect::<Vec<_>>());
    let theta = match opts.regularization {
        VarxRegularization::None => lstsq(phi.as_ref(), tgt.as_ref())?,
        r => regularized(phi.as_ref(), tgt.as_ref(), &lag, r, n_columns)?,
    };
    if theta.as_ref().norm_max().is_nan() || !theta.as_ref().norm_max().is_finite() {
        return Err(SysidError::numerical(
            "VARX least squares",
            "non-finite coefficients; the past data may be degenerate (constant channels?)",
        ));
    }
    let off = if opts.feedthrough { m } else { 0 };
    let d = if opts.feedthrough {
        theta.as_ref().subcols(0, m).to_owned()
    } else {
        Mat::zeros(l, m)
    };
    let xi = (0..p)
        .map(|k| theta.as_ref().subcols(off + k * (m + l), m + l).to_owned())
        .collect();
    Ok(Varx { d, xi })
}

/// Ridge or TC-prior least squares on regressors scaled to unit variance.
fn regularized(
    phi: MatRef<'_, f64>,
    tgt: MatRef<'_, f64>,
    lag: &[usize],
    reg: VarxRegularization,
    n_columns: usize,
) -> Result<Mat<f64>> {
    let d = phi.nrows();
    let nt = tgt.nrows();
    let nn = n_columns.max(1) as f64;
    let scale: Vec<f64> = (0..d)
        .map(|i| {
            let s = (phi.row(i).norm_l2() / nn.sqrt()).max(f64::MIN_POSITIVE);
            if s.is_finite() {
                s
            } else {
                1.0
            }
        })
        .collect();
    let phis = Mat::from_fn(d, phi.ncols(), |i, j| phi[(i, j)] / scale[i]);
    let g11 = &phis * phis.transpose();
    let g21 = tgt * phis.transpose(); // nt x d
    let mut theta = Mat::<f64>::zeros(nt, d);
    match reg {
        VarxRegularization::Ridge(lambda) => {
            let mean_diag = (0..d).map(|i| g11[(i, i)]).sum::<f64>() / d.max(1) as f64;
            let mut a = g11.clone();
            for i in 0..d {
                a[(i, i)] += lambda.max(0.0) * mean_diag;
            }
            let ainv = pinv(a.as_ref(), 1e-14)?;
            theta = &g21 * &ainv;
        }
        VarxRegularization::Tc => {
            // noise variance per output from the unregularised residuals
            let theta_ls = lstsq(phis.as_ref(), tgt)?;
            let resid = tgt - &theta_ls * &phis;
            let dof = (nn - d as f64).max(1.0);
            for o in 0..nt {
                let sigma2 = (resid.row(o).norm_l2().powi(2) / dof).max(f64::MIN_POSITIVE);
                let yy = tgt.row(o).norm_l2().powi(2);
                let b: Vec<f64> = (0..d).map(|j| g21[(o, j)]).collect();
                let ms = (0..d).map(|j| theta_ls[(o, j)].powi(2)).sum::<f64>() / d as f64;
                let base = ms.max(sigma2 / nn).max(f64::MIN_POSITIVE);
                let mut best = (f64::INFINITY, Vec::new());
                for alpha in [
                    0.3f64, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.93, 0.95, 0.97, 0.98, 0.99,
                ] {
                    for ic in 0..13 {
                        let c = base * 10f64.powf(-4.0 + 0.5 * ic as f64);
                        let mut a = g11.clone();
                        let mut logdet_p = 0.0;
                        for j in 0..d {
                            let pj = c * alpha.powi(lag[j] as i32);
                            logdet_p += pj.ln();
                            a[(j, j)] += sigma2 / pj;
                        }
                        let Ok(ch) = a.llt(Side::Lower) else { continue };
                        let lo = ch.L();
                        let logdet_a: f64 = (0..d).map(|j| 2.0 * lo[(j, j)].ln()).sum();
                        let bm = Mat::from_fn(d, 1, |j, _| b[j]);
                        let sol = ch.solve(&bm);
                        let quad: f64 = (0..d).map(|j| b[j] * sol[(j, 0)]).sum();
                        let nll = (yy - quad) / sigma2
                            + (nn - d as f64) * sigma2.ln()
                            + logdet_p
                            + logdet_a;
                        if nll.is_finite() && nll < best.0 {
                            best = (nll, (0..d).map(|j| sol[(j, 0)]).collect());
                        }
                    }
                }
                if best.1.is_empty() {
                    return Err(SysidError::numerical(
                        "VARX regularisation",
                        "no hyperparameter gave a finite marginal likelihood; use \
                         regularization=None",
                    ));
                }
                for j in 0..d {
                    theta[(o, j)] = best.1[j];
                }
            }
        }
        VarxRegularization::None => unreachable!("handled by the caller"),
    }
    for j in 0..d {
        for o in 0..nt {
            theta[(o, j)] /= scale[j];
        }
    }
    Ok(theta)
}

/// A closed-loop subspace estimate on a compressed record, ready to fit any order.
#[derive(Debug, Clone)]
pub struct ClosedLoop {
    factor: HankelFactor,
    opts: ClosedLoopOptions,
    varx: Varx,
    rows: Rows,
    /// `Γ_f K_p`-like matrix in the past coordinates: `state = S^{-1/2} U^T W z_p`.
    w: Mat<f64>,
    u: Mat<f64>,
    s: Vec<f64>,
    rank: usize,
}

impl ClosedLoop {
    /// Estimates the VARX and the weighted SVD. Uses the past horizon p of the factor as the
    /// VARX order and its future horizon f (>= 2, <= p + 1) for the observability matrix.
    pub fn new(factor: &HankelFactor, opts: &ClosedLoopOptions) -> Result<Self> {
        let lay = factor.layout();
        let (m, l, p, f) = (lay.n_inputs, lay.n_outputs, lay.past, lay.future);
        if f < 2 || f > p + 1 {
            return Err(SysidError::invalid(
                "future horizon",
                format!(
                    "closed-loop methods need 2 <= future <= past + 1 (got past={p}, \
                     future={f}); use a longer past horizon or a shorter future one"
                ),
            ));
        }
        let d_reg = p * (m + l) + if opts.feedthrough { m } else { 0 };
        if factor.n_columns() < 2 * d_reg + 2 {
            return Err(SysidError::InsufficientData {
                context: format!("a VARX with {d_reg} regressors (past={p})"),
                needed: 2 * d_reg + 2 + lay.window() - 1,
                got: factor.n_columns() + lay.window() - 1,
                fix: crate::error::horizon_fix(p, f),
            });
        }
        let rows = Rows { m, l, p, f };
        let lmat = factor.l();
        let varx = varx(lmat, &rows, opts, factor.n_columns())?;
        let zp = pick(lmat, &rows.past(0));
        let (w, svd_target) = match opts.method {
            ClosedLoopMethod::Pbsid => {
                // Γ_f K_p: block (i, k) = Ξ_{i+k} (k = 1..p), zero beyond p
                let mut gk = Mat::<f64>::zeros(f * l, p * (m + l));
                for i in 0..f {
                    for k in 1..=p {
                        if i + k <= p {
                            gk.as_mut()
                                .submatrix_mut(i * l, (k - 1) * (m + l), l, m + l)
                                .copy_from(&varx.xi[i + k - 1]);
                        }
                    }
                }
                // weight with the covariance of the past: SVD of Γ K T_p, T_p T_p^T = Z_p Z_p^T
                let tp = lq_lower(zp.as_ref());
                let target = &gk * &tp;
                (gk, target)
            }
            ClosedLoopMethod::Ssarx => {
                // ỹ(t+i) = y(t+i) - Σ_{j<i} Ξ_{i-j} z(t+j) - D u(t+i), rows of L
                let mut yt = Mat::<f64>::zeros(f * l, lmat.ncols());
                for i in 0..f {
                    let yi = pick(
                        lmat,
                        &(0..l).map(|c| rows.y(i as isize, c)).collect::<Vec<_>>(),
                    );
                    let mut blk = yi;
                    if m > 0 {
                        let ui = pick(
                            lmat,
                            &(0..m).map(|c| rows.u(i as isize, c)).collect::<Vec<_>>(),
                        );
                        blk -= &varx.d * &ui;
                    }
                    for j in 0..i {
                        let mut zr: Vec<usize> = (0..m).map(|c| rows.u(j as isize, c)).collect();
                        zr.extend((0..l).map(|c| rows.y(j as isize, c)));
                        let zj = pick(lmat, &zr);
                        blk -= &varx.xi[i - j - 1] * &zj;
                    }
                    yt.as_mut().subrows_mut(i * l, l).copy_from(&blk);
                }
                // CCA between ỹ_f and z_p
                let dp = zp.nrows();
                let t = lq_lower(vstack(zp.as_ref(), yt.as_ref()).as_ref());
                let t11 = t.as_ref().submatrix(0, 0, dp, dp);
                let t21 = t.as_ref().submatrix(dp, 0, f * l, dp);
                let tf = lq_lower(t.as_ref().submatrix(dp, 0, f * l, dp + f * l));
                let tf_inv = pinv(tf.as_ref(), 1e-10)?;
                // x = S^{-1/2} U^T (T_f^{-1} T21 T11^+) z_p
                let w = &tf_inv * t21 * pinv(t11, PINV_TOL)?;
                let target = &tf_inv * t21;
                (w, target)
            }
        };
        let (s, u) = crate::linalg::svd_left_seq("closed-loop weighted SVD", svd_target.as_ref())?;
        let smax = s.first().copied().unwrap_or(0.0);
        if !smax.is_finite() || smax <= 0.0 {
            return Err(SysidError::numerical(
                "closed-loop weighted SVD",
                "the past data carry no information about the outputs (zero outputs?)",
            ));
        }
        let rank = s.iter().filter(|&&x| x > 1e-12 * smax).count();
        Ok(Self {
            factor: factor.clone(),
            opts: opts.clone(),
            varx,
            rows,
            w,
            u,
            s,
            rank,
        })
    }

    /// Singular values of the weighted matrix, largest first (canonical correlations for
    /// SSARX).
    pub fn singular_values(&self) -> &[f64] {
        &self.s
    }

    /// Largest order: `min(f l, rank)`, and no more than the past dimension allows.
    pub fn max_order(&self) -> usize {
        let r = &self.rows;
        (r.f * r.l).min(self.rank).min(r.p * (r.m + r.l))
    }

    /// The order at the largest gap of the log singular values.
    pub fn auto_order(&self) -> usize {
        largest_log_gap(&self.s, self.max_order())
    }

    /// Estimated predictor Markov parameters `Ξ_1..Ξ_p` (each `l x (m + l)`).
    pub fn varx_coefficients(&self) -> &[Mat<f64>] {
        &self.varx.xi
    }

    /// Estimates A, B, C, D, K and the innovation covariance for `order`.
    pub fn fit(&self, order: usize) -> Result<Identified> {
        let r = self.rows;
        let (m, l) = (r.m, r.l);
        let n = order;
        if n == 0 {
            return Err(SysidError::invalid(
                "order",
                "the model order must be at least 1",
            ));
        }
        let max = self.max_order();
        if n > max {
            return Err(SysidError::OrderTooLarge {
                order: n,
                max,
                future: r.f,
                outputs: l,
            });
        }
        let lmat = self.factor.l();
        // state map on z_p: S_n^{-1/2} U_n^T W
        let mut ut = self.u.as_ref().subcols(0, n).transpose().to_owned();
        for i in 0..n {
            let sc = 1.0 / self.s[i].sqrt();
            for j in 0..ut.ncols() {
                ut[(i, j)] *= sc;
            }
        }
        let map = &ut * &self.w; // n x p(m + l)
        let x0 = &map * pick(lmat, &r.past(0));
        let x1 = &map * pick(lmat, &r.past(1));
        let y0 = pick(lmat, &(0..l).map(|c| r.y(0, c)).collect::<Vec<_>>());
        let u0 = pick(lmat, &(0..m).map(|c| r.u(0, c)).collect::<Vec<_>>());
        // y(t) = C x(t) + D u(t) + e(t)
        let (c, d) = if self.opts.feedthrough && m > 0 {
            let th = lstsq(vstack(x0.as_ref(), u0.as_ref()).as_ref(), y0.as_ref())?;
            (
                th.as_ref().subcols(0, n).to_owned(),
                th.as_ref().subcols(n, m).to_owned(),
            )
        } else {
            (lstsq(x0.as_ref(), y0.as_ref())?, Mat::zeros(l, m))
        };
        let e = &y0 - &c * &x0 - &d * &u0;
        // x(t+1) = A x(t) + B u(t) + K e(t)
        let reg = vstack(vstack(x0.as_ref(), u0.as_ref()).as_ref(), e.as_ref());
        let th = lstsq(reg.as_ref(), x1.as_ref())?;
        let a = th.as_ref().subcols(0, n).to_owned();
        let b = th.as_ref().subcols(n, m).to_owned();
        let k = th.as_ref().subcols(n + m, l).to_owned();
        let nn = self.factor.n_columns() as f64;
        let mut re = &e * e.transpose();
        for j in 0..l {
            for i in 0..l {
                re[(i, j)] /= nn;
            }
        }
        crate::linalg::symmetrize(&mut re);
        let q = &k * &re * k.transpose();
        let s = &k * &re;
        let (k, innovation_cov, predictor_stabilized) =
            match stable_predictor(a.as_ref(), c.as_ref(), k.as_ref(), re.as_ref()) {
                Some((k2, cov)) => (k2, cov, true),
                None => (k, re.clone(), false),
            };
        let sys = StateSpace::new(a, b, c, d).map_err(|_| {
            SysidError::numerical(
                "system matrices",
                "non-finite estimates; the data may be degenerate for this order and horizon",
            )
        })?;
        Ok(Identified {
            sys,
            k: Some(k),
            innovation_cov: Some(innovation_cov),
            q,
            r: re,
            s,
            stabilized: false,
            predictor_stabilized,
            kalman_regularization: 0.0,
            kalman_residual: 0.0,
        })
    }
}

/// The stabilising gain when the least-squares `K` leaves the predictor `A - K C` unstable
/// (a noise model `I + C (zI - A)^{-1} K` with zeros outside the unit circle): the Kalman
/// gain and innovation covariance of the same noise spectrum, `Q = K Re K^T`, `S = K Re`,
/// `R = Re`, whose stabilising Riccati solution reflects those zeros into the unit circle
/// (the minimum-phase spectral factor; Re grows by the reflected zeros' squared moduli).
/// `Q - S R^{-1} S^T` is zero for these covariances, where the doubling iteration stays at the
/// non-stabilising solution `P = 0`: a nudge of `1e-10` of `Q`'s scale (at least `1e-12` of
/// `Re`'s, mapped through `K`) makes the solution unique, an `O(1e-10)` change. `None` when the
/// predictor is stable already (or not finite), or no stabilising gain is found.
///
/// ```
/// use faer::mat;
/// use sysid_core::subspace::closed_loop::stable_predictor;
/// // H(z) = (z - 1.2) / (z - 0.5): its minimum-phase factor is (z - 1/1.2) / (z - 0.5),
/// // with the innovation variance 1.2^2 times larger
/// let (k, re) = stable_predictor(mat![[0.5]].as_ref(), mat![[1.0]].as_ref(),
///                                mat![[-0.7]].as_ref(), mat![[1.0]].as_ref()).unwrap();
/// assert!((k[(0, 0)] - (0.5 - 1.0 / 1.2)).abs() < 1e-6);
/// assert!((re[(0, 0)] - 1.44).abs() < 1e-6);
/// ```
pub fn stable_predictor(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    k: MatRef<'_, f64>,
    re: MatRef<'_, f64>,
) -> Option<(Mat<f64>, Mat<f64>)> {
    let n = a.nrows();
    let akc = a - k * c;
    let rho = crate::linalg::spectral_radius(akc.as_ref()).ok()?;
    if !rho.is_finite() || rho < 1.0 {
        return None;
    }
    let mut q = k * re * k.transpose();
    let scale = (0..n).map(|i| q[(i, i)]).sum::<f64>() / n.max(1) as f64;
    let floor = 1e-12 * (0..re.nrows()).map(|i| re[(i, i)]).sum::<f64>();
    let eps = 1e-10 * scale.max(floor).max(f64::MIN_POSITIVE);
    for i in 0..n {
        q[(i, i)] += eps;
    }
    let s = k * re;
    let sol = crate::riccati::kalman_gain(a, c, q.as_ref(), re, s.as_ref()).ok()?;
    Some((sol.k, sol.innovation_cov))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hankel::{Compressor, HankelLayout, QrCompressor};
    use crate::subspace::tests::Rng;

    /// x+ = A x + B u + K e, y = C x + e under u = r - 0.3 y; returns (u, y).
    fn closed_loop_data(n: usize, noise: f64, seed: u64) -> (Mat<f64>, Mat<f64>) {
        let mut rng = Rng(seed);
        let (a, b, c, k) = (
            [[1.5, -0.7], [1.0, 0.0]],
            [1.0, 0.0],
            [1.0, 0.5],
            [0.5, 0.2],
        );
        let mut x = [0.0, 0.0];
        let mut u = Mat::<f64>::zeros(n, 1);
        let mut y = Mat::<f64>::zeros(n, 1);
        for t in 0..n {
            let e = noise * rng.normal();
            let yt = c[0] * x[0] + c[1] * x[1] + e;
            let ut = rng.normal() - 0.3 * yt;
            u[(t, 0)] = ut;
            y[(t, 0)] = yt;
            let x0 = a[0][0] * x[0] + a[0][1] * x[1] + b[0] * ut + k[0] * e;
            let x1 = a[1][0] * x[0] + a[1][1] * x[1] + b[1] * ut + k[1] * e;
            x = [x0, x1];
        }
        (u, y)
    }

    fn factor(u: &Mat<f64>, y: &Mat<f64>, p: usize, f: usize) -> HankelFactor {
        let mut c = QrCompressor::new(HankelLayout::new(1, 1, p, f).unwrap());
        c.push(u.as_ref(), y.as_ref()).unwrap();
        c.finish().unwrap()
    }

    fn pole_error(sys: &StateSpace) -> f64 {
        // true poles 0.75 ± 0.3708i: compare the characteristic polynomial z^2 - 1.5 z + 0.7
        let a = &sys.a;
        let tr = a[(0, 0)] + a[(1, 1)];
        let det = a[(0, 0)] * a[(1, 1)] - a[(0, 1)] * a[(1, 0)];
        (tr - 1.5).abs().max((det - 0.7).abs())
    }

    #[test]
    fn pbsid_and_ssarx_are_consistent_under_feedback() {
        let (u, y) = closed_loop_data(20_000, 1.0, 7);
        let f = factor(&u, &y, 15, 5);
        for method in [ClosedLoopMethod::Pbsid, ClosedLoopMethod::Ssarx] {
            for reg in [VarxRegularization::None, VarxRegularization::Tc] {
                let opts = ClosedLoopOptions {
                    method,
                    regularization: reg,
                    feedthrough: false,
                };
                let cl = ClosedLoop::new(&f, &opts).unwrap();
                assert_eq!(cl.auto_order(), 2, "{method:?} {reg:?}");
                let id = cl.fit(2).unwrap();
                let err = pole_error(&id.sys);
                assert!(err < 0.03, "{method:?} {reg:?}: {err}");
                let k = id.k.unwrap();
                // K in the state basis: check the DC gain of the noise model instead
                assert!(k.norm_max().is_finite());
                let r = id.innovation_cov.unwrap()[(0, 0)];
                assert!(
                    (r - 1.0).abs() < 0.05,
                    "{method:?}: innovation variance {r}"
                );
            }
        }
    }

    #[test]
    fn bad_horizons_are_errors() {
        let (u, y) = closed_loop_data(500, 1.0, 1);
        let f = factor(&u, &y, 3, 6);
        assert!(ClosedLoop::new(&f, &ClosedLoopOptions::default()).is_err());
        assert!(ClosedLoopMethod::parse("nope").is_err());
    }
}
