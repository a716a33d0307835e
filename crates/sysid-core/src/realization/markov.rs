//! Markov parameters from input/output records: least-squares FIR (optionally regularised
//! with a TC kernel) and OKID.
//!
//! **FIR.** `y(t) = sum_{k=0}^{n-1} h_k u(t-k) + e(t)` is linear in the Markov parameters and
//! is solved by least squares. A lightly damped system needs a long FIR, whose variance the
//! TC ("tuned-correlated") prior `E[h_k h_j] = c lambda^{max(k, j)}` tames (Chen, Ohlsson and
//! Ljung 2012; the default of MATLAB's `impulseest`): the estimate is the posterior mean
//! `theta = (Phi^T Phi + sigma^2 P^{-1})^{-1} Phi^T y`, with `(c, lambda)` per output chosen
//! by maximising the marginal likelihood and `sigma^2` from the unregularised residuals. With
//! the factor `P = c L L^T` (L upper triangular with the exact form of the TC kernel) and the
//! eigendecomposition of `L^T Phi^T Phi L`, each likelihood costs O(n m) once that is known.
//!
//! **OKID** (Juang, Phan, Horta and Longman 1993). With an observer gain G,
//! `x(t+1) = (A + G C) x + (B + G D) u - G y`, so `y(t) = D u(t) + sum_{k=1}^{p}
//! Ybar_k [u(t-k); y(t-k)]` holds once `(A + G C)^p` is negligible, for some G (for instance
//! the Kalman predictor's), which makes a short regression capture a lightly damped system.
//! The observer Markov parameters `Ybar_k = [C Abar^{k-1} (B + G D), -C Abar^{k-1} G] =
//! [Ybar_k^(1), Ybar_k^(2)]` give the system's by the recursion
//! `h_0 = D`, `h_k = Ybar_k^(1) + sum_{i=1}^{min(k,p)} Ybar_i^(2) h_{k-i}`, for as many k as
//! wanted (`Ybar_k^(1) = 0` beyond p).
//!
//! Both regressions accumulate the triangular factor of `[Phi Y]` chunk by chunk (no
//! normal equations), over any number of experiments, with channels scaled to unit variance.

use crate::error::{Result, SysidError};
use crate::linalg::pinv;
use faer::{Mat, MatRef};

/// Regularisation of the FIR least squares.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Regularization {
    /// Plain least squares.
    None,
    /// TC kernel `c lambda^{max(k, j)}`; `hyper = Some((c, lambda))` fixes the
    /// hyperparameters for every output (for inputs scaled to unit variance), `None` tunes
    /// them per output by marginal likelihood.
    Tc {
        /// Fixed `(scale c, decay lambda)`, or `None` to tune them.
        hyper: Option<(f64, f64)>,
    },
}

crate::names::option_names! { Regularization, "regularization", false, [
    ("none", Regularization::None), ("tc", Regularization::Tc { hyper: None }),
] }

impl Regularization {
    /// The regularisation named `name` (`"none"` or `"tc"`, with fixed `hyper` or tuned).
    ///
    /// ```
    /// use sysid_core::realization::Regularization;
    /// assert_eq!(Regularization::from_name("tc", None).unwrap(), Regularization::Tc { hyper: None });
    /// assert!(Regularization::from_name("ridge", None).is_err());
    /// ```
    pub fn from_name(name: &str, hyper: Option<(f64, f64)>) -> Result<Self> {
        Ok(match name.parse()? {
            Regularization::Tc { .. } => Regularization::Tc { hyper },
            other => other,
        })
    }
}

/// Options of [`fir`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct FirOptions {
    /// Number of Markov parameters estimated, `h_0 .. h_{length-1}`.
    pub length: usize,
    /// Estimate `h_0 = D`; if false (the default, as every sysid state-space estimator) it
    /// is fixed at zero (a strictly proper system).
    pub feedthrough: bool,
    /// Regularisation (default: TC with tuned hyperparameters).
    pub regularization: Regularization,
}

impl Default for FirOptions {
    fn default() -> Self {
        Self {
            length: 50,
            feedthrough: false,
            regularization: Regularization::Tc { hyper: None },
        }
    }
}

/// Markov parameters estimated by [`fir`].
#[derive(Debug, Clone)]
pub struct FirEstimate {
    /// `h_0 .. h_{length-1}`, each `l x m`.
    pub markov: Vec<Mat<f64>>,
    /// Per output: TC scale c (for unit-variance inputs); NaN without regularisation.
    pub scale: Vec<f64>,
    /// Per output: TC decay lambda; NaN without regularisation.
    pub decay: Vec<f64>,
    /// Per output: noise variance of the unregularised least-squares residuals.
    pub noise_variance: Vec<f64>,
    /// Number of regression equations (samples used).
    pub samples: usize,
    /// Standard deviation of each Markov parameter (same shapes as `markov`; zero for a
    /// `h_0` not estimated): least squares', or the TC posterior's with regularisation.
    pub std: Vec<Mat<f64>>,
}

/// Options of [`okid`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct OkidOptions {
    /// Observer order p: lags of inputs and outputs in the regression.
    pub observer_order: usize,
    /// Number of system Markov parameters returned, `h_0 .. h_{count-1}` (may exceed p).
    pub count: usize,
    /// Estimate `h_0 = D`; if false (the default) it is fixed at zero.
    pub feedthrough: bool,
    /// Without `feedthrough`: also solve the regression with `u(t)` from the same triangular
    /// factor (its columns last), for [`OkidEstimate::direct`]: a check of the record for
    /// a direct term at no second pass over the data.
    pub check_direct: bool,
}

impl Default for OkidOptions {
    fn default() -> Self {
        Self {
            observer_order: 20,
            count: 100,
            feedthrough: false,
            check_direct: false,
        }
    }
}

/// The regression with `u(t)` solved beside one without it ([`OkidOptions::check_direct`]).
#[derive(Debug, Clone)]
pub struct DirectTerm {
    /// Its estimate of `D = h_0`, `l x m`.
    pub d: Mat<f64>,
    /// Covariance of its residuals, `l x l`.
    pub residual_cov: Mat<f64>,
}

/// Markov parameters estimated by [`okid`].
#[derive(Debug, Clone)]
pub struct OkidEstimate {
    /// System Markov parameters `h_0 .. h_{count-1}`, each `l x m`.
    pub markov: Vec<Mat<f64>>,
    /// Observer Markov parameters `Ybar_1 .. Ybar_p`, each `l x (m + l)`.
    pub observer_markov: Vec<Mat<f64>>,
    /// Covariance of the regression residuals (the one-step prediction errors), `l x l`.
    pub residual_cov: Mat<f64>,
    /// Number of regression equations (samples used).
    pub samples: usize,
    /// With [`OkidOptions::check_direct`] (and no `feedthrough`): the regression with `u(t)`.
    pub direct: Option<DirectTerm>,
}

type Experiments<'a, 'b> = &'a [(MatRef<'b, f64>, MatRef<'b, f64>)];

/// Checks the experiments; returns (m, l) and per-channel standard deviations of u and y.
fn check_experiments(
    exps: Experiments<'_, '_>,
    lag: usize,
) -> Result<(usize, usize, Vec<f64>, Vec<f64>)> {
    if exps.is_empty() {
        return Err(SysidError::invalid("data", "no experiment given"));
    }
    let (m, l) = (exps[0].0.ncols(), exps[0].1.ncols());
    if m == 0 || l == 0 {
        return Err(SysidError::invalid(
            "data",
            "Markov parameters need at least one input and one output",
        ));
    }
    let mut su = vec![0.0; m];
    let mut sy = vec![0.0; l];
    let mut count = 0usize;
    for (e, (u, y)) in exps.iter().enumerate() {
        if u.ncols() != m || y.ncols() != l {
            return Err(SysidError::ShapeMismatch {
                what: format!("experiment {e}"),
                expected: format!("{m} input(s) and {l} output(s) like experiment 0"),
                got: format!("{} and {}", u.ncols(), y.ncols()),
            });
        }
        if u.nrows() != y.nrows() {
            return Err(SysidError::ShapeMismatch {
                what: format!("y of experiment {e}"),
                expected: format!("{} samples like u", u.nrows()),
                got: format!("{} samples", y.nrows()),
            });
        }
        if u.nrows() <= lag {
            return Err(SysidError::InsufficientData {
                context: format!("experiment {e} with {lag} lags"),
                needed: lag + 1,
                got: u.nrows(),
                fix: "use fewer lags (a shorter FIR or a lower observer order) or a longer record",
            });
        }
        crate::error::check_finite("u", *u)?;
        crate::error::check_finite("y", *y)?;
        for t in 0..u.nrows() {
            for i in 0..m {
                su[i] += u[(t, i)] * u[(t, i)];
            }
            for i in 0..l {
                sy[i] += y[(t, i)] * y[(t, i)];
            }
        }
        count += u.nrows();
    }
    let su: Vec<f64> = su.iter().map(|s| (s / count as f64).sqrt()).collect();
    let sy: Vec<f64> = sy.iter().map(|s| (s / count as f64).sqrt()).collect();
    if let Some(i) = su.iter().position(|&s| s.is_nan() || s <= 0.0) {
        return Err(SysidError::invalid(
            "u",
            format!("input {i} is identically zero; drop it"),
        ));
    }
    Ok((
        m,
        l,
        su,
        sy.iter().map(|&s| if s > 0.0 { s } else { 1.0 }).collect(),
    ))
}

/// Triangular factor R of `[Phi Y]` accumulated chunk by chunk, with the rows built by
/// `fill(u, y, t, row)` for `t = lag..N` of every experiment.
fn accumulate(
    exps: Experiments<'_, '_>,
    lag: usize,
    d: usize,
    ys: &[f64],
    fill: impl Fn(MatRef<'_, f64>, MatRef<'_, f64>, usize, &mut [f64]),
) -> Result<(Mat<f64>, usize)> {
    let l = exps[0].1.ncols();
    let w = d + l;
    let chunk = 4096usize.max(2 * w);
    let mut r = Mat::<f64>::zeros(0, w);
    let mut rows = 0usize;
    let mut buf = vec![0.0; d];
    for (u, y) in exps {
        let n = u.nrows();
        let mut t0 = lag;
        while t0 < n {
            crate::interrupt::check()?; // Ctrl-C between blocks of a long record
            let t1 = (t0 + chunk).min(n);
            let k = r.nrows();
            let mut block = Mat::<f64>::zeros(k + t1 - t0, w);
            block.as_mut().subrows_mut(0, k).copy_from(&r);
            for t in t0..t1 {
                fill(*u, *y, t, &mut buf);
                let row = k + t - t0;
                for (j, &v) in buf.iter().enumerate() {
                    block[(row, j)] = v;
                }
                for j in 0..l {
                    block[(row, d + j)] = y[(t, j)] / ys[j];
                }
            }
            rows += t1 - t0;
            r = crate::linalg::thin_r_seq(block.as_ref());
            t0 = t1;
        }
    }
    if r.nrows() < w {
        let mut full = Mat::<f64>::zeros(w, w);
        full.as_mut().subrows_mut(0, r.nrows()).copy_from(&r);
        r = full;
    }
    Ok((r, rows))
}

/// Least-squares FIR estimate of the Markov parameters, over one or more experiments.
///
/// ```
/// use faer::Mat;
/// use sysid_core::realization::{fir, FirOptions, Regularization};
/// // y(t) = u(t-1) + 0.5 u(t-2)
/// let n = 300;
/// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919 % 101) as f64 / 50.0) - 1.0);
/// let y = Mat::from_fn(n, 1, |t, _| {
///     (if t >= 1 { u[(t - 1, 0)] } else { 0.0 }) + (if t >= 2 { 0.5 * u[(t - 2, 0)] } else { 0.0 })
/// });
/// let mut opts = FirOptions::default();
/// opts.length = 5;
/// opts.regularization = Regularization::None;
/// let est = fir(&[(u.as_ref(), y.as_ref())], &opts).unwrap();
/// assert!((est.markov[1][(0, 0)] - 1.0).abs() < 1e-10);
/// assert!((est.markov[2][(0, 0)] - 0.5).abs() < 1e-10);
/// ```
pub fn fir(exps: Experiments<'_, '_>, opts: &FirOptions) -> Result<FirEstimate> {
    let n = opts.length;
    let k0 = usize::from(!opts.feedthrough);
    if n < 1 + k0 {
        return Err(SysidError::invalid(
            "length",
            format!("the FIR needs at least {} Markov parameters", 1 + k0),
        ));
    }
    let lag = n - 1;
    let (m, l, su, sy) = check_experiments(exps, lag)?;
    let nk = n - k0;
    let d = nk * m;
    let (r, rows) = accumulate(exps, lag, d, &sy, |u, _y, t, row| {
        for kk in 0..nk {
            for i in 0..m {
                row[kk * m + i] = u[(t - kk - k0, i)] / su[i];
            }
        }
    })?;
    if rows <= d {
        return Err(SysidError::InsufficientData {
            context: format!(
                "an FIR of {n} Markov parameters with {m} input(s) ({d} unknowns per output)"
            ),
            needed: d + 1 + lag,
            got: rows + lag,
            fix: "use a shorter FIR (or OKID) or a longer record",
        });
    }
    let r11 = r.submatrix(0, 0, d, d);
    let r12 = r.submatrix(0, d, d, l);
    let r22 = r.submatrix(d, d, l, l);
    let noise: Vec<f64> = (0..l)
        .map(|j| (0..l).map(|i| r22[(i, j)].powi(2)).sum::<f64>() / (rows - d) as f64)
        .collect();
    let (theta, scale, decay, var) = match opts.regularization {
        Regularization::None => {
            let inv = pinv(r11, 1e-12)?;
            let th = &inv * r12;
            // diag of sigma^2 (R11^T R11)^-1: the squared row norms of R11^-1
            let var = Mat::from_fn(d, l, |i, j| {
                noise[j] * (0..d).map(|k| inv[(i, k)].powi(2)).sum::<f64>()
            });
            (th, vec![f64::NAN; l], vec![f64::NAN; l], var)
        }
        Regularization::Tc { hyper } => tc_estimate(r.as_ref(), d, l, m, nk, rows, &noise, hyper)?,
    };
    let mut markov = vec![Mat::<f64>::zeros(l, m); n];
    let mut std = vec![Mat::<f64>::zeros(l, m); n];
    for kk in 0..nk {
        for j in 0..l {
            for i in 0..m {
                markov[kk + k0][(j, i)] = theta[(kk * m + i, j)] * sy[j] / su[i];
                std[kk + k0][(j, i)] = var[(kk * m + i, j)].max(0.0).sqrt() * sy[j] / su[i];
            }
        }
    }
    let noise_variance = noise.iter().zip(&sy).map(|(v, s)| v * s * s).collect();
    Ok(FirEstimate {
        markov,
        scale,
        decay,
        noise_variance,
        samples: rows,
        std,
    })
}

/// `L` with `L L^T` the TC kernel `lambda^{max(a, b)}` over `nk` lags, expanded over m inputs.
fn tc_factor(lambda: f64, nk: usize, m: usize) -> Mat<f64> {
    let dk: Vec<f64> = (0..nk)
        .map(|k| {
            if k + 1 < nk {
                lambda.powi(k as i32) * (1.0 - lambda)
            } else {
                lambda.powi(k as i32)
            }
        })
        .map(f64::sqrt)
        .collect();
    Mat::from_fn(nk * m, nk * m, |p, q| {
        let (a, i) = (p / m, p % m);
        let (b, j) = (q / m, q % m);
        if i == j && b >= a {
            dk[b]
        } else {
            0.0
        }
    })
}

struct TcSpectrum {
    lf: Mat<f64>,
    q: Mat<f64>,
    s: Vec<f64>,
    z: Mat<f64>, // Q^T Lf^T Phi^T Y, d x l
}

fn tc_spectrum(
    r11: MatRef<'_, f64>,
    r12: MatRef<'_, f64>,
    lambda: f64,
    nk: usize,
    m: usize,
) -> Result<TcSpectrum> {
    let lf = tc_factor(lambda, nk, m);
    let bm = r11 * &lf;
    // the SVD of B = R11 Lf, not the eigendecomposition of B^T B: the kernel's decay makes
    // B's columns span tens of decades, and B^T B's small eigenvalues (round-off of the
    // largest, 1e-16 of it) then decided the marginal likelihood: a 200-lag fit of a pole at
    // 0.99 chose a scale of 1e11 and returned Markov parameters 70 times the true peak
    let (sv, u, q) = crate::linalg::svd_both_seq("TC regularisation (SVD)", bm.as_ref())?;
    let d = sv.len();
    let s: Vec<f64> = (0..d).map(|i| sv[i] * sv[i]).collect();
    let ur = u.transpose() * r12;
    let z = Mat::from_fn(d, r12.ncols(), |i, j| sv[i] * ur[(i, j)]);
    Ok(TcSpectrum { lf, q, s, z })
}

/// Negative log marginal likelihood (up to a constant) of output j.
fn tc_nll(sp: &TcSpectrum, j: usize, c: f64, sigma2: f64, yy: f64, rows: usize) -> f64 {
    let d = sp.s.len();
    let mut logdet = 0.0;
    let mut quad = 0.0;
    for i in 0..d {
        let g = sigma2 + c * sp.s[i];
        logdet += g.ln();
        quad += sp.z[(i, j)].powi(2) / g;
    }
    (rows - d) as f64 * sigma2.ln() + logdet + (yy - c * quad) / sigma2
}

/// A TC fit: the coefficients `d x l`, per output the scale c and decay lambda, and the
/// posterior variance of each coefficient `d x l`.
type TcFit = (Mat<f64>, Vec<f64>, Vec<f64>, Mat<f64>);

#[allow(clippy::too_many_arguments)]
fn tc_estimate(
    r: MatRef<'_, f64>,
    d: usize,
    l: usize,
    m: usize,
    nk: usize,
    rows: usize,
    noise: &[f64],
    hyper: Option<(f64, f64)>,
) -> Result<TcFit> {
    let r11 = r.submatrix(0, 0, d, d);
    let r12 = r.submatrix(0, d, d, l);
    let yy: Vec<f64> = (0..l)
        .map(|j| (0..d + l).map(|i| r[(i, d + j)].powi(2)).sum::<f64>())
        .collect();
    let sigma2: Vec<f64> = noise.iter().map(|&v| v.max(1e-300)).collect();
    let mut choice = vec![(0.0, 0.0); l];
    match hyper {
        Some((c, lambda)) => {
            if !(c > 0.0 && c.is_finite() && lambda > 0.0 && lambda < 1.0) {
                return Err(SysidError::invalid(
                    "TC hyperparameters",
                    format!("need scale c > 0 and 0 < decay < 1, got c = {c}, decay = {lambda}"),
                ));
            }
            choice.iter_mut().for_each(|x| *x = (c, lambda));
        }
        None => {
            let mut best = vec![(f64::INFINITY, 0.0, 0.0); l];
            let grid = 30;
            for g in 0..grid {
                // Ctrl-C between the grid's SVDs; 1 - lambda log-spaced from 0.9 to 1e-4
                crate::interrupt::check()?;
                let frac = g as f64 / (grid - 1) as f64;
                let lambda = 1.0 - 10f64.powf(0.9f64.log10() * (1.0 - frac) + (-4.0) * frac);
                let sp = tc_spectrum(r11, r12, lambda, nk, m)?;
                let smax =
                    sp.s.iter()
                        .copied()
                        .fold(0.0, f64::max)
                        .max(f64::MIN_POSITIVE);
                for j in 0..l {
                    // log-scale search for c: coarse grid, then golden section around the best
                    let lo = (sigma2[j] / smax).ln() - 10.0;
                    let hi = (sigma2[j] / smax).ln() + 40.0;
                    let f = |lc: f64| tc_nll(&sp, j, lc.exp(), sigma2[j], yy[j], rows);
                    let pts = 51;
                    let mut bi = 0;
                    let mut bv = f64::INFINITY;
                    for k in 0..pts {
                        let v = f(lo + (hi - lo) * k as f64 / (pts - 1) as f64);
                        if v < bv {
                            bv = v;
                            bi = k;
                        }
                    }
                    let step = (hi - lo) / (pts - 1) as f64;
                    let (mut a, mut b) =
                        (lo + step * (bi as f64 - 1.0), lo + step * (bi as f64 + 1.0));
                    let phi = 0.5 * (5f64.sqrt() - 1.0);
                    for _ in 0..40 {
                        let x1 = b - phi * (b - a);
                        let x2 = a + phi * (b - a);
                        if f(x1) < f(x2) {
                            b = x2;
                        } else {
                            a = x1;
                        }
                    }
                    let lc = 0.5 * (a + b);
                    let v = f(lc).min(bv);
                    if v < best[j].0 {
                        best[j] = (v, lc.exp(), lambda);
                    }
                }
            }
            for j in 0..l {
                choice[j] = (best[j].1, best[j].2);
            }
        }
    }
    let mut theta = Mat::<f64>::zeros(d, l);
    let mut var = Mat::<f64>::zeros(d, l);
    let mut cache: Option<(f64, TcSpectrum)> = None;
    for j in 0..l {
        let (c, lambda) = choice[j];
        if cache
            .as_ref()
            .map(|(lam, _)| *lam != lambda)
            .unwrap_or(true)
        {
            cache = Some((lambda, tc_spectrum(r11, r12, lambda, nk, m)?));
        }
        let sp = &cache.as_ref().unwrap().1;
        // theta_j = c Lf Q (sigma^2 + c S)^{-1} z_j
        let w = Mat::from_fn(d, 1, |i, _| c * sp.z[(i, j)] / (sigma2[j] + c * sp.s[i]));
        let lq = &sp.lf * &sp.q;
        let th = &lq * w;
        for i in 0..d {
            theta[(i, j)] = th[(i, 0)];
            // posterior variance: diag of Lf Q diag(c sigma^2 / (sigma^2 + c S)) Q^T Lf^T
            var[(i, j)] = (0..d)
                .map(|k| lq[(i, k)].powi(2) * c * sigma2[j] / (sigma2[j] + c * sp.s[k]))
                .sum();
        }
    }
    let scale = choice.iter().map(|x| x.0).collect();
    let decay = choice.iter().map(|x| x.1).collect();
    Ok((theta, scale, decay, var))
}

/// OKID: observer and system Markov parameters from input/output data.
///
/// ```
/// use faer::Mat;
/// use sysid_core::realization::{okid, OkidOptions};
/// // y(t) = 0.9 y(t-1) + u(t-1): h_k = 0.9^{k-1}, far longer than the observer order
/// let n = 400;
/// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919 % 101) as f64 / 50.0) - 1.0);
/// let mut y = Mat::<f64>::zeros(n, 1);
/// for t in 1..n { y[(t, 0)] = 0.9 * y[(t - 1, 0)] + u[(t - 1, 0)]; }
/// let mut opts = OkidOptions::default();
/// opts.observer_order = 3;
/// opts.count = 30;
/// let est = okid(&[(u.as_ref(), y.as_ref())], &opts).unwrap();
/// assert!((est.markov[20][(0, 0)] - 0.9f64.powi(19)).abs() < 1e-9);
/// ```
pub fn okid(exps: Experiments<'_, '_>, opts: &OkidOptions) -> Result<OkidEstimate> {
    let p = opts.observer_order;
    if p == 0 {
        return Err(SysidError::invalid("observer_order", "must be at least 1"));
    }
    if opts.count == 0 {
        return Err(SysidError::invalid(
            "count",
            "ask for at least one Markov parameter",
        ));
    }
    let (m, l, su, sy) = check_experiments(exps, p)?;
    let v = m + l;
    // past regressors first, then u(t) (estimated, or only checked): the regression without
    // u(t) is the leading block of the same triangular factor
    let d0 = p * v;
    let with_now = opts.feedthrough || opts.check_direct;
    let d = d0 + usize::from(with_now) * m;
    let (r, rows) = accumulate(exps, p, d, &sy, |u, y, t, row| {
        for k in 1..=p {
            let base = (k - 1) * v;
            for i in 0..m {
                row[base + i] = u[(t - k, i)] / su[i];
            }
            for i in 0..l {
                row[base + m + i] = y[(t - k, i)] / sy[i];
            }
        }
        if with_now {
            for i in 0..m {
                row[d0 + i] = u[(t, i)] / su[i];
            }
        }
    })?;
    if rows <= d {
        return Err(SysidError::InsufficientData {
            context: format!("OKID with observer order {p} ({d} unknowns per output)"),
            needed: d + 1 + p,
            got: rows + p,
            fix: "lower the observer order or use a longer record",
        });
    }
    let y_cols = r.submatrix(0, d, d + l, l);
    // the regression on the first `k` columns: coefficients and residual covariance
    let solve = |k: usize| -> Result<(Mat<f64>, Mat<f64>)> {
        let theta = pinv(r.submatrix(0, 0, k, k), 1e-12)? * y_cols.subrows(0, k);
        let rest = y_cols.subrows(k, d + l - k);
        let mut cov = rest.transpose() * rest;
        for i in 0..l {
            for j in 0..l {
                cov[(i, j)] *= sy[i] * sy[j] / (rows - k) as f64;
            }
        }
        Ok((theta, cov))
    };
    let (theta, residual_cov) = solve(if opts.feedthrough { d } else { d0 })?;
    // unscale: coefficient of regressor x / s_x on output y / s_y
    let direct_d = |theta: &Mat<f64>| Mat::from_fn(l, m, |j, i| theta[(d0 + i, j)] * sy[j] / su[i]);
    let dmat = if opts.feedthrough {
        direct_d(&theta)
    } else {
        Mat::<f64>::zeros(l, m)
    };
    let direct = if opts.check_direct && !opts.feedthrough {
        let (full, cov) = solve(d)?;
        Some(DirectTerm {
            d: direct_d(&full),
            residual_cov: cov,
        })
    } else {
        None
    };
    let coef = |j: usize, col: usize, sx: f64| theta[(col, j)] * sy[j] / sx;
    let mut observer_markov = Vec::with_capacity(p);
    for k in 1..=p {
        let base = (k - 1) * v;
        observer_markov.push(Mat::from_fn(l, v, |j, i| {
            let sx = if i < m { su[i] } else { sy[i - m] };
            coef(j, base + i, sx)
        }));
    }
    let mut markov = Vec::with_capacity(opts.count);
    markov.push(dmat);
    for k in 1..opts.count {
        let mut h = if k <= p {
            observer_markov[k - 1].subcols(0, m).to_owned()
        } else {
            Mat::zeros(l, m)
        };
        for i in 1..=k.min(p) {
            h += observer_markov[i - 1].subcols(m, l) * &markov[k - i];
        }
        if h.norm_max().is_nan() || !h.norm_max().is_finite() {
            return Err(SysidError::numerical(
                "OKID Markov parameters",
                format!(
                    "the recursion overflowed at Markov parameter {k}: the identified model is \
                     unstable; ask for fewer Markov parameters, change the observer order, or \
                     low-pass and decimate data whose input leaves a band unexcited"
                ),
            ));
        }
        markov.push(h);
    }
    Ok(OkidEstimate {
        markov,
        observer_markov,
        residual_cov,
        samples: rows,
        direct,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::realization::testing::random_system;
    use crate::simulate::simulate;
    use crate::StateSpace;
    use rand::{rngs::StdRng, SeedableRng};
    use rand_distr::{Distribution, Normal};

    fn noisy_data(sys: &StateSpace, n: usize, noise: f64, seed: u64) -> (Mat<f64>, Mat<f64>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let g = Normal::new(0.0, 1.0).unwrap();
        let u = Mat::from_fn(n, sys.n_inputs(), |_, _| g.sample(&mut rng));
        let mut y = simulate(sys, u.as_ref(), None).unwrap();
        for t in 0..n {
            for j in 0..sys.n_outputs() {
                y[(t, j)] += noise * g.sample(&mut rng);
            }
        }
        (u, y)
    }

    fn markov_error(est: &[Mat<f64>], sys: &StateSpace) -> f64 {
        let h = sys.markov(est.len());
        let num: f64 = est
            .iter()
            .zip(&h)
            .map(|(a, b)| (a - b).squared_norm_l2())
            .sum();
        let den: f64 = h.iter().map(|b| b.squared_norm_l2()).sum();
        (num / den).sqrt()
    }

    #[test]
    fn noise_free_fir_and_okid_are_exact() {
        let sys = random_system(4, 2, 2, 0.6, 21);
        let (u, y) = noisy_data(&sys, 600, 0.0, 1);
        let fo = FirOptions {
            length: 60,
            regularization: Regularization::None,
            feedthrough: true, // random_system has a D
            ..Default::default()
        };
        let f = fir(&[(u.as_ref(), y.as_ref())], &fo).unwrap();
        assert!(markov_error(&f.markov, &sys) < 1e-8);
        let oo = OkidOptions {
            observer_order: 4,
            count: 80,
            feedthrough: true,
            ..Default::default()
        };
        let o = okid(&[(u.as_ref(), y.as_ref())], &oo).unwrap();
        assert!(markov_error(&o.markov, &sys) < 1e-8);
    }

    #[test]
    fn tc_regularisation_beats_plain_least_squares_on_short_noisy_records() {
        let sys = random_system(4, 1, 1, 0.9, 8);
        let mut wins = 0;
        for seed in 0..5 {
            let (u, y) = noisy_data(&sys, 250, 0.3, 100 + seed);
            let mut fo = FirOptions {
                length: 80,
                feedthrough: true,
                ..Default::default()
            };
            let tc = fir(&[(u.as_ref(), y.as_ref())], &fo).unwrap();
            fo.regularization = Regularization::None;
            let ls = fir(&[(u.as_ref(), y.as_ref())], &fo).unwrap();
            if markov_error(&tc.markov, &sys) < markov_error(&ls.markov, &sys) {
                wins += 1;
            }
            assert!(tc.decay[0] > 0.0 && tc.decay[0] < 1.0);
        }
        assert!(wins >= 4, "TC won {wins} of 5");
    }

    #[test]
    fn the_direct_term_check_is_the_regression_with_u_now_from_the_same_factor() {
        let sys = random_system(4, 2, 2, 0.6, 21); // it has a D
        let (u, y) = noisy_data(&sys, 900, 0.05, 3);
        let e = [(u.as_ref(), y.as_ref())];
        let base = OkidOptions {
            observer_order: 6,
            count: 30,
            ..Default::default()
        };
        let plain = okid(&e, &base).unwrap();
        let checked = okid(
            &e,
            &OkidOptions {
                check_direct: true,
                ..base.clone()
            },
        )
        .unwrap();
        let with_d = okid(
            &e,
            &OkidOptions {
                feedthrough: true,
                ..base.clone()
            },
        )
        .unwrap();
        assert!(plain.direct.is_none() && with_d.direct.is_none());
        let direct = checked.direct.as_ref().unwrap();
        assert!((&direct.d - &with_d.markov[0]).norm_max() < 1e-10 * with_d.markov[0].norm_max());
        assert!((&direct.residual_cov - &with_d.residual_cov).norm_max() < 1e-12);
        for (a, b) in plain.markov.iter().zip(&checked.markov) {
            assert!((a - b).norm_max() < 1e-10 * (1.0 + b.norm_max()));
        }
        assert!((&plain.residual_cov - &checked.residual_cov).norm_max() < 1e-12);
    }

    #[test]
    fn experiments_are_pooled() {
        let sys = random_system(3, 1, 2, 0.7, 9);
        let (u, y) = noisy_data(&sys, 800, 0.0, 4);
        let oo = OkidOptions {
            observer_order: 5,
            count: 20,
            feedthrough: true,
            ..Default::default()
        };
        let whole = okid(&[(u.as_ref(), y.as_ref())], &oo).unwrap();
        let parts = okid(
            &[
                (u.subrows(0, 400), y.subrows(0, 400)),
                (u.subrows(400, 400), y.subrows(400, 400)),
            ],
            &oo,
        )
        .unwrap();
        assert!(markov_error(&whole.markov, &sys) < 1e-8);
        assert!(markov_error(&parts.markov, &sys) < 1e-8);
        assert!(parts.samples + 5 == whole.samples);
    }

    #[test]
    fn bad_data_are_errors() {
        let u = Mat::<f64>::zeros(50, 1);
        let y = Mat::<f64>::zeros(50, 1);
        let oo = OkidOptions::default();
        assert!(okid(&[(u.as_ref(), y.as_ref())], &oo).is_err()); // zero input
        let mut u = Mat::from_fn(50, 1, |t, _| (t as f64).sin());
        let ob = OkidOptions {
            observer_order: 60,
            ..Default::default()
        };
        assert!(matches!(
            okid(&[(u.as_ref(), y.as_ref())], &ob),
            Err(SysidError::InsufficientData { .. })
        ));
        u[(3, 0)] = f64::NAN;
        assert!(matches!(
            fir(&[(u.as_ref(), y.as_ref())], &FirOptions::default()),
            Err(SysidError::NonFinite { .. })
        ));
    }
}
