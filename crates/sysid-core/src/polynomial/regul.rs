//! Marginal likelihood of a regularised (kernel-prior) linear regression from its compressed
//! summary, for empirical-Bayes tuning of regularised ARX (`sysid.arxregul`).
//!
//! The regression `y = Phi theta + e`, `e ~ N(0, sigma^2 I_N)`, `theta ~ N(0, P)` is known
//! through the upper-triangular factor `[[R1, r], [0, rho]]` of `[Phi y]`
//! ([`crate::polynomial::arx::ArxCompressor::output_summary`]). With
//! `S = sigma^2 I_p + R1 P R1^T` (the matrix determinant lemma and Woodbury's identity on the
//! `N x N` covariance `Phi P Phi^T + sigma^2 I`):
//!
//! ```text
//! L = -2 log p(y) - N log 2 pi = rho^2 / sigma^2 + (N - p) log sigma^2 + r^T S^-1 r + log det S
//! dL/d eta_k = sum_ij G_ij (dP/d eta_k)_ij,   G = R1^T (S^-1 - a a^T) R1,   a = S^-1 r
//! dL/d sigma^2 = -rho^2 / sigma^4 + (N - p) / sigma^2 + tr(S^-1 - a a^T)
//! ```
//!
//! `P` is never inverted (TC and stable-spline kernels are badly conditioned for long blocks).
//! Cost `O(p^3)` per evaluation, independent of `N`.

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::Solve;
use faer::{Accum, Mat, MatRef, Par, Side};

use crate::error::{check_finite, Result, SysidError};

/// `a * b` on one thread (the matrices here are a few dozen rows: threads cost more than
/// they save, above all on a loaded machine).
fn mul(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut c = Mat::zeros(a.nrows(), b.ncols());
    matmul(c.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    c
}

/// Value, gradient with respect to the parameters of `dprior`, and derivative with respect to
/// `sigma2`, of `L` above (`gradient = false`: the value only, about half the work; the
/// gradient is then empty and the derivative NaN). Where round-off makes the formed `S`
/// indefinite, `S` is factored without being formed (eigen-factor of the prior, SVD of
/// `R1 L`); a factorisation that fails, or a value that is not finite, gives
/// `(inf, zeros, 0)`, so a line search backs off.
///
/// ```
/// use faer::Mat;
/// use sysid_core::polynomial::regul::marginal_likelihood;
/// // one parameter, Phi = [1, 1]^T, y = [1, 1]^T: R1 = sqrt 2, r = sqrt 2, rho = 0
/// let s = Mat::from_fn(2, 2, |i, j| if i == 0 { 2f64.sqrt() } else { 0.0 });
/// let p = Mat::from_fn(1, 1, |_, _| 1.0);
/// let (v, _, _) = marginal_likelihood(s.as_ref(), 2, p.as_ref(), &[], 1.0, false).unwrap();
/// // dense: Sigma = [[2, 1], [1, 2]], y^T Sigma^-1 y = 2/3, log det = log 3
/// assert!((v - (2.0 / 3.0 + 3f64.ln())).abs() < 1e-12);
/// ```
pub fn marginal_likelihood(
    summary: MatRef<'_, f64>,
    n_rows: usize,
    prior: MatRef<'_, f64>,
    dprior: &[MatRef<'_, f64>],
    sigma2: f64,
    gradient: bool,
) -> Result<(f64, Vec<f64>, f64)> {
    let p = check_summary_prior(summary, prior)?;
    if let Some(d) = dprior.iter().find(|d| d.nrows() != p || d.ncols() != p) {
        return Err(SysidError::ShapeMismatch {
            what: "prior derivative".into(),
            expected: format!("({p}, {p})"),
            got: format!("({}, {})", d.nrows(), d.ncols()),
        });
    }
    if !(sigma2 > 0.0 && sigma2.is_finite()) {
        return Err(SysidError::invalid(
            "sigma2",
            format!("the noise variance must be positive and finite, got {sigma2}"),
        ));
    }
    if n_rows <= p {
        return Err(SysidError::InsufficientData {
            context: format!("a marginal likelihood with {p} parameters"),
            needed: p + 1,
            got: n_rows,
            fix: "use a longer record or smaller orders",
        });
    }
    check_finite("summary", summary)?;
    check_finite("prior", prior)?;
    let r1 = summary.submatrix(0, 0, p, p);
    let r = summary.submatrix(0, p, p, 1);
    let rho = summary[(p, p)];
    let inf = Ok((f64::INFINITY, vec![0.0; dprior.len()], 0.0));
    let Some(sv) = solve_s(r1, prior, r, sigma2, gradient) else {
        return inf;
    };
    let a = &sv.a;
    let quad: f64 = (0..p).map(|i| r[(i, 0)] * a[(i, 0)]).sum();
    let value = rho * rho / sigma2 + (n_rows - p) as f64 * sigma2.ln() + quad + sv.logdet;
    if !value.is_finite() {
        return inf;
    }
    if !gradient {
        return Ok((value, Vec::new(), f64::NAN));
    }
    let Some((g, trace)) = sv.gradient else {
        return inf;
    };
    let grad = dprior
        .iter()
        .map(|d| {
            let mut acc = 0.0;
            for j in 0..p {
                for i in 0..p {
                    acc += g[(i, j)] * d[(i, j)];
                }
            }
            acc
        })
        .collect();
    let dsig = -rho * rho / (sigma2 * sigma2) + (n_rows - p) as f64 / sigma2 + trace;
    Ok((value, grad, dsig))
}

/// `log det S` and `a = S^-1 r` for `S = sigma2 I + R1 P R1^T`, and (`gradient`)
/// `G = R1^T (S^-1 - a a^T) R1` with `tr(S^-1 - a a^T)`.
pub(crate) struct SolvedS {
    pub(crate) logdet: f64,
    pub(crate) a: Mat<f64>,
    pub(crate) gradient: Option<(Mat<f64>, f64)>,
}

/// [`SolvedS`] by Cholesky of the formed `S`; where round-off makes it indefinite (a prior
/// far larger than the noise variance on nearly collinear regressors: a band-limited input
/// and many lags, where `R1 P R1^T` reaches 1e12 against `sigma2` = 1e-10), from the
/// eigen-factor `P = L L^T` and the SVD `R1 L = U diag(s) V^T`: `S = U diag(s^2 + sigma2)
/// U^T`, positive definite by construction. `None` only when a factorisation fails.
pub(crate) fn solve_s(
    r1: MatRef<'_, f64>,
    prior: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    sigma2: f64,
    gradient: bool,
) -> Option<SolvedS> {
    let p = r1.nrows();
    let mut s = mul(mul(r1, prior).as_ref(), r1.transpose());
    for i in 0..p {
        s[(i, i)] += sigma2;
    }
    if let Ok(llt) = s.llt(Side::Lower) {
        let l = llt.L();
        let logdet = (0..p).map(|i| 2.0 * l[(i, i)].ln()).sum();
        let a = llt.solve(r);
        let gradient = gradient.then(|| {
            let mut w = llt.solve(Mat::<f64>::identity(p, p));
            for i in 0..p {
                for j in 0..p {
                    w[(i, j)] -= a[(i, 0)] * a[(j, 0)];
                }
            }
            let trace = (0..p).map(|i| w[(i, i)]).sum();
            (mul(mul(r1.transpose(), w.as_ref()).as_ref(), r1), trace)
        });
        return Some(SolvedS {
            logdet,
            a,
            gradient,
        });
    }
    spectral_s(r1, prior, r, sigma2, gradient)
}

/// `L` with `P = L L^T` from the eigendecomposition of the symmetric part of `prior`
/// (eigenvalues below zero, round-off of a PSD kernel, taken as zero): no inverse of `P`,
/// which TC and stable-spline kernels make badly conditioned.
fn eigen_factor(prior: MatRef<'_, f64>) -> Result<Mat<f64>> {
    let p = prior.nrows();
    let sym = Mat::from_fn(p, p, |i, j| 0.5 * (prior[(i, j)] + prior[(j, i)]));
    let (u, w) = crate::optim::symmetric_eigen(&sym, "regularised ARX (prior eigendecomposition)")?;
    Ok(Mat::from_fn(p, p, |i, j| u[(i, j)] * w[j].max(0.0).sqrt()))
}

/// [`solve_s`] without forming `S`: from the eigen-factor of `P` and the SVD of `R1 L`.
pub(crate) fn spectral_s(
    r1: MatRef<'_, f64>,
    prior: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    sigma2: f64,
    gradient: bool,
) -> Option<SolvedS> {
    let p = r1.nrows();
    let l = eigen_factor(prior).ok()?;
    let (sv, u) =
        crate::linalg::svd_left_seq("regularised ARX (SVD)", mul(r1, l.as_ref()).as_ref()).ok()?;
    let d: Vec<f64> = (0..p).map(|i| sv[i] * sv[i] + sigma2).collect();
    let logdet = d.iter().map(|x| x.ln()).sum();
    let ur = u.transpose() * r;
    let a = &u * Mat::from_fn(p, 1, |i, _| ur[(i, 0)] / d[i]);
    // G from T = U^T R1 (rows along the near-null directions stay at round-off of R1, not
    // of R1^T S^-1 R1, whose entries reach 1 / sigma2 and cancel)
    let gradient = gradient.then(|| {
        let t = u.transpose() * r1;
        let b = t.transpose() * Mat::from_fn(p, 1, |i, _| ur[(i, 0)] / d[i]);
        let scaled = Mat::from_fn(p, p, |i, j| t[(i, j)] / d[i]);
        let mut g = mul(t.transpose(), scaled.as_ref());
        for i in 0..p {
            for j in 0..p {
                g[(i, j)] -= b[(i, 0)] * b[(j, 0)];
            }
        }
        let trace = d.iter().map(|x| 1.0 / x).sum::<f64>()
            - (0..p).map(|i| a[(i, 0)] * a[(i, 0)]).sum::<f64>();
        (g, trace)
    });
    Some(SolvedS {
        logdet,
        a,
        gradient,
    })
}

/// The regularised solution of the regression summarised by `summary` with the penalty
/// `lam theta^T P^-1 theta` (the posterior of the prior `N(0, P)` when `lam` is the noise
/// variance): `(theta, covariance, rss)` with `theta = P R1^T (lam I + R1 P R1^T)^-1 r`, the
/// posterior covariance `P - P R1^T (lam I + R1 P R1^T)^-1 R1 P` and the residual sum of
/// squares `rho^2 + |r - R1 theta|^2`.
///
/// Computed as `P = L L^T` (eigen-factor), `R1 L = U diag(s) V^T`:
/// `theta = L V diag(s / (s^2 + lam)) U^T r`, covariance `L V diag(lam / (s^2 + lam)) V^T L^T`:
/// positive semi-definite by construction, and `lam -> 0` tends to least squares on the
/// range of `P` without cancellation. With `lam = 0` a direction the data do not determine
/// (a singular value at round-off of the largest) is left at the prior's 0 with the prior's
/// variance: the minimum-norm least-squares solution, finite on rank-deficient data.
///
/// ```
/// use faer::Mat;
/// use sysid_core::polynomial::regul::regularized_solve;
/// // one parameter, Phi^T Phi = 4, Phi^T y = 4 (R1 = 2, r = 2): theta = 4 / (4 + lam / P)
/// let s = Mat::from_fn(2, 2, |i, j| if i == 0 { 2.0 } else if j == 1 { 1.0 } else { 0.0 });
/// let p = Mat::from_fn(1, 1, |_, _| 1.0);
/// let (th, cov, _) = regularized_solve(s.as_ref(), p.as_ref(), 4.0).unwrap();
/// assert!((th[0] - 0.5).abs() < 1e-12 && (cov[(0, 0)] - 0.5).abs() < 1e-12);
/// ```
pub fn regularized_solve(
    summary: MatRef<'_, f64>,
    prior: MatRef<'_, f64>,
    lam: f64,
) -> Result<(Vec<f64>, Mat<f64>, f64)> {
    let p = check_summary_prior(summary, prior)?;
    if !(lam >= 0.0 && lam.is_finite()) {
        return Err(SysidError::invalid(
            "lam",
            format!("must be a finite number >= 0, got {lam}"),
        ));
    }
    check_finite("summary", summary)?;
    check_finite("prior", prior)?;
    let r1 = summary.submatrix(0, 0, p, p);
    let r = summary.submatrix(0, p, p, 1);
    let rho = summary[(p, p)];
    let l = eigen_factor(prior)?;
    let m = mul(r1, l.as_ref());
    let (s, su, sv) = crate::linalg::svd_both_seq("regularised ARX (SVD)", m.as_ref())?;
    let lv = mul(l.as_ref(), sv.as_ref());
    let ur = su.transpose() * r;
    let k = s.len();
    // a direction the data do not determine (a zero singular value, or one at round-off of
    // the largest: noise-free data, or more parameters than the data support) keeps the
    // prior's value 0 and its whole variance when there is no penalty to decide it
    let s_max = (0..k).map(|i| s[i]).fold(0.0, f64::max);
    let tol = s_max * (p.max(1) as f64) * f64::EPSILON;
    let lost = |i: usize| s[i] <= tol && lam == 0.0;
    let coef = Mat::from_fn(k, 1, |i, _| {
        if lost(i) {
            0.0
        } else {
            s[i] / (s[i] * s[i] + lam) * ur[(i, 0)]
        }
    });
    let th = &lv * &coef;
    let theta: Vec<f64> = (0..p).map(|i| th[(i, 0)]).collect();
    let scaled = Mat::from_fn(p, k, |i, j| {
        lv[(i, j)]
            * if lost(j) {
                1.0
            } else {
                lam / (s[j] * s[j] + lam)
            }
    });
    let cov0 = mul(scaled.as_ref(), lv.transpose());
    let cov = Mat::from_fn(p, p, |i, j| 0.5 * (cov0[(i, j)] + cov0[(j, i)]));
    let fitted = r1 * &th;
    let rss = rho * rho
        + (0..p)
            .map(|i| (r[(i, 0)] - fitted[(i, 0)]).powi(2))
            .sum::<f64>();
    Ok((theta, cov, rss))
}

/// The number of parameters `p` when `summary` is `(p + 1) x (p + 1)` and `prior` `p x p`.
fn check_summary_prior(summary: MatRef<'_, f64>, prior: MatRef<'_, f64>) -> Result<usize> {
    let p = prior.nrows();
    if summary.nrows() != p + 1 || summary.ncols() != p + 1 || prior.ncols() != p {
        return Err(SysidError::ShapeMismatch {
            what: "summary, prior".into(),
            expected: format!("({0}, {0}) and ({1}, {1})", p + 1, p),
            got: format!(
                "({}, {}) and ({}, {})",
                summary.nrows(),
                summary.ncols(),
                prior.nrows(),
                prior.ncols()
            ),
        });
    }
    Ok(p)
}
