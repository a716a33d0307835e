//! Online (recursive) estimators of polynomial models, updated one sample at a time.
//!
//! The model of one output with `m` inputs is
//!
//! ```text
//! A(q) y(t) = sum_j B_j(q) / F_j(q) u_j(t - nk_j) + C(q) / D(q) e(t)
//! ```
//!
//! (ARX: `C = D = F = 1`; ARMAX: `D = F = 1`; OE: `A = C = D = 1`; BJ: `A = 1`). With the
//! noise-free outputs `w_j = B_j/F_j u_j(t - nk_j)`, the disturbance `v = A y - sum_j w_j` and
//! the innovations `e = D/C v` the model is a pseudo-linear regression
//!
//! ```text
//! y(t) = phi(t)^T theta + e(t),
//! phi(t) = [-y(t-1..na), u_j(t-nk_j..), e(t-1..nc), -v(t-1..nd), -w_j(t-1..nf_j)],
//! theta  = [a, b_j, c, d, f_j].
//! ```
//!
//! The recursive prediction-error method (Ljung & Soderstrom 1983) replaces `phi` by the
//! negative gradient of the prediction error, `psi = -d eps / d theta`: the `a` part is
//! `D/C` times its regressor, the `b_j` and `f_j` parts `D/(C F_j)` times theirs, the `c` and
//! `d` parts `1/C` times theirs; filtered with the current estimates. For ARX `psi = phi` and
//! the forgetting-factor update is exactly recursive least squares.
//!
//! Each sample: the prior prediction `yhat = phi^T theta`, the error `eps = y - yhat`, then
//! one of MATLAB's updates ([`Method`]):
//!
//! ```text
//! forgetting factor  K = P psi / (lambda + psi^T P psi),  P <- (P - K psi^T P) / lambda
//! Kalman filter      K = P psi / (R2 + psi^T P psi),      P <- P - K psi^T P + R1
//! normalised grad.   K = gamma psi / (bias + psi^T psi)
//! gradient           K = gamma psi
//! theta <- theta + K eps
//! ```
//!
//! and the signals `w`, `v`, `e` of that sample are recomputed with the updated estimates
//! (posterior values, as in recursive pseudo-linear regression) before they enter later
//! regressors. An update that would make a parameter or `P` non-finite is refused (the
//! sample still advances the histories) and counted in [`Recursive::rejected`].
//!
//! With filters (the prediction-error method) the forgetting factor starts below the one
//! asked for and tends to it, `lambda(t) = 0.99 lambda(t-1) + 0.01 lambda` from
//! `min(lambda, 0.95)` (Ljung & Soderstrom 1983; [`LAMBDA_START`]). The first updates, made
//! from the starting values with gradient filters far from the final ones, are then forgotten:
//! with a constant `lambda = 1` they stayed in `P` and in the estimate for good, and 1-4 % of
//! the estimates of a Monte Carlo study ended more than 4 standard deviations (`P` times the
//! noise variance) from the truth, so that `P` understated their spread 1.3-3 times.
//! `P` times the noise variance is then the estimate's covariance (to about 10 % from 600
//! samples on; with `lambda < 1`, about `P sigma^2 / (1 + lambda)`).

mod lagged;
#[cfg(test)]
mod tests;
mod update;

use crate::error::{Result, SysidError};
use lagged::{Iir, Lagged};
pub use update::{Method, MethodSettings};

/// Orders of the polynomial structure (single output, `nb.len()` inputs): the prediction-error
/// estimators' [`crate::polynomial::pem::MisoOrders`].
pub use crate::polynomial::pem::MisoOrders as Structure;

/// Longest delay line (input delay `nk` plus `nb` coefficients) an online estimator keeps
/// per input, in samples.
pub const MAX_DELAY_LINE: usize = 1 << 16;

/// Checks the lengths agree and the size is one an online estimator supports (delay lines
/// bounded by [`MAX_DELAY_LINE`], orders added with overflow checks); returns the number of
/// parameters.
///
/// ```
/// use sysid_core::recursive::{check_structure, Structure};
/// let s = Structure { na: 2, nb: vec![2], nc: 1, nd: 0, nf: vec![0], nk: vec![1] };
/// assert_eq!(check_structure(&s).unwrap(), 5);
/// ```
pub fn check_structure(s: &Structure) -> Result<usize> {
    let m = s.nb.len();
    if s.nf.len() != m || s.nk.len() != m {
        return Err(SysidError::invalid(
            "structure",
            format!(
                "nb, nf and nk need one entry per input; got {}, {} and {}",
                m,
                s.nf.len(),
                s.nk.len()
            ),
        ));
    }
    // orders as given can be anything: added with checks, the delays bounded (each input
    // keeps a delay line of nk + nb samples)
    for j in 0..m {
        let line = s.nk[j].checked_add(s.nb[j]);
        if line.is_none_or(|n| n > MAX_DELAY_LINE) {
            return Err(SysidError::invalid(
                "structure",
                format!(
                    "input {j}: delay nk={} with nb={} needs a delay line of more than \
                     {MAX_DELAY_LINE} samples, more than an online estimator keeps; shift \
                     the input by the delay before the estimator (u(t - nk)) or resample",
                    s.nk[j], s.nb[j]
                ),
            ));
        }
    }
    let p = [s.na, s.nc, s.nd]
        .into_iter()
        .chain(s.nb.iter().copied())
        .chain(s.nf.iter().copied())
        .try_fold(0usize, |acc, n| acc.checked_add(n));
    let Some(p) = p else {
        return Err(SysidError::invalid(
            "structure",
            "the orders add up to more parameters than can be counted; give orders of a \
             few times the expected dynamics"
                .to_string(),
        ));
    };
    if p == 0 {
        return Err(SysidError::invalid(
            "structure",
            "the model has no parameters; give at least one positive order".to_string(),
        ));
    }
    if p > 4096 {
        return Err(SysidError::invalid(
            "structure",
            format!("{p} parameters is more than an online estimator supports (4096)"),
        ));
    }
    Ok(p)
}

/// Whether the structure has filters (`C`, `D` or an `F_j`): the regressors are then
/// filtered and the update is a pseudo-linear regression.
fn filtered(s: &Structure) -> bool {
    s.nc + s.nd + s.nf.iter().sum::<usize>() > 0
}

/// An online estimator: parameters, covariance `P` and the regressor history.
///
/// ```
/// use sysid_core::recursive::{Method, Recursive, Structure};
/// // y(t) = 0.5 y(t-1) + u(t-1): recursive least squares recovers a = -0.5, b = 1.
/// let s = Structure { na: 1, nb: vec![1], nc: 0, nd: 0, nf: vec![0], nk: vec![1] };
/// let mut est = Recursive::new(s, Method::Forgetting { lambda: 1.0 }, None, Some(1e6)).unwrap();
/// let (mut y, mut u_prev, mut seed) = (0.0, 0.0, 7u64);
/// for _ in 0..200 {
///     seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
///     let u = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
///     y = 0.5 * y + u_prev;
///     est.step(&[u], y).unwrap();
///     u_prev = u;
/// }
/// assert!((est.theta()[0] + 0.5).abs() < 1e-4 && (est.theta()[1] - 1.0).abs() < 1e-4);
/// ```
#[derive(Debug, Clone)]
pub struct Recursive {
    s: Structure,
    method: Method,
    theta: Vec<f64>,
    /// `P`, row-major p x p (unused by the gradient methods).
    p: Vec<f64>,
    phi: Vec<f64>,
    psi: Vec<f64>,
    work: Vec<f64>,
    prev: Vec<f64>,
    y: Lagged,
    u: Vec<Lagged>,
    e: Lagged,
    v: Lagged,
    w: Vec<Lagged>,
    filt: Option<Filters>,
    samples: usize,
    rejected: usize,
    startup: bool,
}

/// The gradient filters of the prediction-error method and their output delay lines.
#[derive(Debug, Clone)]
struct Filters {
    y: Iir,
    u: Vec<Iir>,
    e: Iir,
    v: Iir,
    w: Vec<Iir>,
    yf: Lagged,
    uf: Vec<Lagged>,
    ef: Lagged,
    vf: Lagged,
    wf: Vec<Lagged>,
    cf: Vec<Vec<f64>>,
}

impl Recursive {
    /// A new estimator from rest: `theta0` (zeros by default) and `P0 = p0 I` (default 1e4).
    pub fn new(
        s: Structure,
        method: Method,
        theta0: Option<&[f64]>,
        p0: Option<f64>,
    ) -> Result<Self> {
        let np = check_structure(&s)?;
        method.check(np)?;
        let p0 = p0.unwrap_or(1e4);
        if !(p0.is_finite() && p0 > 0.0) {
            return Err(SysidError::invalid(
                "initial_covariance",
                format!("must be a finite number > 0, got {p0}"),
            ));
        }
        let mut p = vec![0.0; np * np];
        for i in 0..np {
            p[i * np + i] = p0;
        }
        let u: Vec<Lagged> = (0..s.nb.len())
            .map(|j| Lagged::new((s.nk[j] + s.nb[j]).max(1)))
            .collect();
        let w = s.nf.iter().map(|&n| Lagged::new(n.max(1))).collect();
        let filt = filtered(&s).then(|| Filters::new(&s));
        let mut est = Recursive {
            theta: vec![0.0; np],
            p,
            phi: vec![0.0; np],
            psi: vec![0.0; np],
            work: vec![0.0; np],
            prev: vec![0.0; np],
            y: Lagged::new(s.na),
            u,
            e: Lagged::new(s.nc),
            v: Lagged::new(s.nd),
            w,
            filt,
            samples: 0,
            rejected: 0,
            startup: true,
            method,
            s,
        };
        if let Some(t) = theta0 {
            est.set_theta(t)?;
        }
        Ok(est)
    }

    /// Whether the prediction-error method (`C`, `D` or an `F_j` in the structure, method
    /// [`Method::Forgetting`]) forgets its start-up ([`LAMBDA_START`]; on by default). Off, it
    /// runs with the constant factor, as the prediction-error method without a profile does:
    /// for starting values and `P` that are already right (a batch estimate and its
    /// covariance), which the start-up forgetting would discount.
    pub fn set_startup_forgetting(&mut self, on: bool) {
        self.startup = on;
    }

    /// Whether the start-up forgetting is on ([`Recursive::set_startup_forgetting`]).
    pub fn startup_forgetting(&self) -> bool {
        self.startup
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.theta.len()
    }

    /// The structure.
    pub fn structure(&self) -> &Structure {
        &self.s
    }

    /// The update method.
    pub fn method(&self) -> &Method {
        &self.method
    }

    /// Current parameters `[a, b_j, c, d, f_j]`.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// Current `P`, row-major p x p.
    pub fn covariance(&self) -> &[f64] {
        &self.p
    }

    /// The regressor `phi` of the last sample.
    pub fn regressor(&self) -> &[f64] {
        &self.phi
    }

    /// Samples processed.
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// Updates refused because they would have made the estimate non-finite.
    pub fn rejected(&self) -> usize {
        self.rejected
    }

    /// Replaces the parameters.
    pub fn set_theta(&mut self, t: &[f64]) -> Result<()> {
        if t.len() != self.theta.len() {
            return Err(SysidError::ShapeMismatch {
                what: "parameters".into(),
                expected: format!("({},)", self.theta.len()),
                got: format!("({},)", t.len()),
            });
        }
        if let Some(i) = t.iter().position(|v| !v.is_finite()) {
            return Err(SysidError::invalid(
                "parameters",
                format!("entry {i} is not finite; give finite starting values"),
            ));
        }
        self.theta.copy_from_slice(t);
        Ok(())
    }

    /// Replaces `P` (row-major p x p, symmetric positive semi-definite).
    pub fn set_covariance(&mut self, p: &[f64]) -> Result<()> {
        let n = self.theta.len();
        if p.len() != n * n {
            return Err(SysidError::ShapeMismatch {
                what: "covariance".into(),
                expected: format!("({n}, {n})"),
                got: format!("{} values", p.len()),
            });
        }
        for i in 0..n {
            if !(p[i * n + i].is_finite() && p[i * n + i] >= 0.0) {
                return Err(SysidError::invalid(
                    "covariance",
                    format!("diagonal entry {i} must be finite and >= 0"),
                ));
            }
            for j in 0..i {
                let (a, b) = (p[i * n + j], p[j * n + i]);
                if !(a.is_finite() && (a - b).abs() <= 1e-12 * (a.abs() + b.abs() + 1e-300)) {
                    return Err(SysidError::invalid(
                        "covariance",
                        format!("must be finite and symmetric; entries ({i}, {j}) and ({j}, {i}) differ"),
                    ));
                }
            }
        }
        // store the symmetric part exactly, so the updates keep it symmetric
        for i in 0..n {
            for j in 0..=i {
                let s = 0.5 * (p[i * n + j] + p[j * n + i]);
                self.p[i * n + j] = s;
                self.p[j * n + i] = s;
            }
        }
        Ok(())
    }

    /// Processes one sample (inputs `u` at time t, output `y` at time t); returns the prior
    /// one-step prediction `yhat(t | t-1)`.
    pub fn step(&mut self, u: &[f64], y: f64) -> Result<f64> {
        if u.len() != self.u.len() {
            return Err(SysidError::ShapeMismatch {
                what: "u".into(),
                expected: format!("{} value(s) per sample", self.u.len()),
                got: format!("{}", u.len()),
            });
        }
        if !y.is_finite() || u.iter().any(|v| !v.is_finite()) {
            return Err(SysidError::NonFinite {
                what: if y.is_finite() { "u" } else { "y" },
                sample: self.samples,
                channel: u.iter().position(|v| !v.is_finite()).unwrap_or(0),
            });
        }
        Ok(self.advance(u, y))
    }

    /// One sample, inputs already checked.
    fn advance(&mut self, u: &[f64], y: f64) -> f64 {
        for (line, &uj) in self.u.iter_mut().zip(u) {
            line.push(uj);
        }
        self.build_phi();
        let yhat = dot(&self.phi, &self.theta);
        let eps = y - yhat;
        if let Some(f) = &mut self.filt {
            f.gradient(&self.s, &self.theta, &self.u, &mut self.psi);
        } else {
            self.psi.copy_from_slice(&self.phi);
        }
        let filtered = self.filt.is_some();
        if filtered {
            self.prev.copy_from_slice(&self.theta);
        }
        let profiled = match (&self.method, filtered) {
            (Method::Forgetting { lambda }, true) if self.startup => Some(Method::Forgetting {
                lambda: start_up_forgetting(*lambda, self.samples),
            }),
            _ => None,
        };
        let ok = update::apply(
            profiled.as_ref().unwrap_or(&self.method),
            &mut self.theta,
            &mut self.p,
            &self.psi,
            &mut self.work,
            eps,
        );
        if !ok {
            self.rejected += 1;
        } else if filtered {
            self.project_stable();
        }
        self.posterior(y);
        self.samples += 1;
        yhat
    }

    /// Processes a record: `u` row-major `n x m`, `y` of length n; writes the prior
    /// predictions into `yhat` and, when given, the parameters after each sample into
    /// `thetas` (row-major `n x p`). Stops early (returning the samples done) when
    /// `interrupted()` says so; it is asked every `check_every` samples.
    pub fn run(
        &mut self,
        u: &[f64],
        y: &[f64],
        yhat: &mut [f64],
        mut thetas: Option<&mut [f64]>,
        check_every: usize,
        interrupted: &mut dyn FnMut() -> bool,
    ) -> Result<usize> {
        let (n, m, np) = (y.len(), self.u.len(), self.theta.len());
        if u.len() != n * m || yhat.len() != n {
            return Err(SysidError::ShapeMismatch {
                what: "u".into(),
                expected: format!("({n}, {m})"),
                got: format!("{} values", u.len()),
            });
        }
        if let Some(t) = &thetas {
            if t.len() != n * np {
                return Err(SysidError::ShapeMismatch {
                    what: "parameter trajectory".into(),
                    expected: format!("({n}, {np})"),
                    got: format!("{} values", t.len()),
                });
            }
        }
        check_record(u, y, m, self.samples)?;
        let every = check_every.max(1);
        for t in 0..n {
            if t % every == 0 && t > 0 && interrupted() {
                return Ok(t);
            }
            yhat[t] = self.advance(&u[t * m..(t + 1) * m], y[t]);
            if let Some(th) = thetas.as_deref_mut() {
                th[t * np..(t + 1) * np].copy_from_slice(&self.theta);
            }
        }
        Ok(n)
    }

    fn build_phi(&mut self) {
        let s = &self.s;
        let mut k = 0;
        for i in 0..s.na {
            self.phi[k] = -self.y.get(i);
            k += 1;
        }
        for (j, line) in self.u.iter().enumerate() {
            for i in 0..s.nb[j] {
                self.phi[k] = line.get(s.nk[j] + i);
                k += 1;
            }
        }
        for i in 0..s.nc {
            self.phi[k] = self.e.get(i);
            k += 1;
        }
        for i in 0..s.nd {
            self.phi[k] = -self.v.get(i);
            k += 1;
        }
        for (j, line) in self.w.iter().enumerate() {
            for i in 0..s.nf[j] {
                self.phi[k] = -line.get(i);
                k += 1;
            }
        }
    }

    /// Keeps the filters of the gradient (`C`, `F_j`) stable: a step that moves a root of
    /// either outside the unit circle is halved (up to 20 times; then the update is refused
    /// and counted in [`Recursive::rejected`]), as the projection of the recursive
    /// prediction-error method (Ljung & Soderstrom 1983) does.
    fn project_stable(&mut self) {
        for _ in 0..20 {
            if self.filters_stable() {
                return;
            }
            for (t, p) in self.theta.iter_mut().zip(&self.prev) {
                *t = 0.5 * (*t + p);
            }
        }
        if !self.filters_stable() {
            self.theta.copy_from_slice(&self.prev);
            self.rejected += 1;
        }
    }

    fn filters_stable(&mut self) -> bool {
        let s = &self.s;
        let ic = s.na + s.nb.iter().sum::<usize>();
        if !stable(&self.theta[ic..ic + s.nc], &mut self.work) {
            return false;
        }
        let mut of = ic + s.nc + s.nd;
        for &n in &s.nf {
            if !stable(&self.theta[of..of + n], &mut self.work) {
                return false;
            }
            of += n;
        }
        true
    }

    /// Posterior `w_j`, `v`, `e` of this sample (updated estimates) into the histories.
    fn posterior(&mut self, y: f64) {
        let s = &self.s;
        let th = &self.theta;
        let (ia, ib) = (0, s.na);
        let ic = ib + s.nb.iter().sum::<usize>();
        let (id, ifp) = (ic + s.nc, ic + s.nc + s.nd);
        let mut ay = y;
        for i in 0..s.na {
            ay += th[ia + i] * self.y.get(i);
        }
        let (mut ob, mut of) = (ib, ifp);
        let mut wsum = 0.0;
        for j in 0..self.u.len() {
            let mut wj = 0.0;
            for i in 0..s.nb[j] {
                wj += th[ob + i] * self.u[j].get(s.nk[j] + i);
            }
            for i in 0..s.nf[j] {
                wj -= th[of + i] * self.w[j].get(i);
            }
            ob += s.nb[j];
            of += s.nf[j];
            wsum += wj;
            self.w[j].push(wj);
        }
        let v = ay - wsum;
        let mut e = v;
        for i in 0..s.nd {
            e += th[id + i] * self.v.get(i);
        }
        for i in 0..s.nc {
            e -= th[ic + i] * self.e.get(i);
        }
        if let Some(f) = &mut self.filt {
            f.push(s, th, y, v, e, &self.w);
        }
        self.y.push(y);
        self.v.push(v);
        self.e.push(e);
    }

    /// Clears the signal histories (the parameters and `P` are kept): the next sample is
    /// treated as the first of a new record.
    pub fn reset_history(&mut self) {
        self.y.clear();
        self.u.iter_mut().for_each(Lagged::clear);
        self.e.clear();
        self.v.clear();
        self.w.iter_mut().for_each(Lagged::clear);
        if filtered(&self.s) {
            self.filt = Some(Filters::new(&self.s));
        }
    }
}

/// The start-up forgetting of the prediction-error method (Ljung & Soderstrom 1983):
/// `lambda(t) = LAMBDA_RATE lambda(t-1) + (1 - LAMBDA_RATE) lambda` from
/// `lambda(0) = min(lambda, LAMBDA_START)`, which tends to the factor `lambda` asked for.
pub const LAMBDA_START: f64 = 0.95;
/// See [`LAMBDA_START`].
pub const LAMBDA_RATE: f64 = 0.99;

/// The forgetting factor of sample `t` of the prediction-error method with start-up
/// forgetting ([`LAMBDA_START`]): it forgets the first samples' updates, made with the
/// starting values and the gradient filters they give, which with `lambda = 1` would otherwise
/// stay in `P` and in the estimate for good.
fn start_up_forgetting(lambda: f64, t: usize) -> f64 {
    let start = lambda.min(LAMBDA_START);
    if t > 10_000 {
        return lambda; // 0.99^10000 = 2e-44
    }
    lambda - (lambda - start) * LAMBDA_RATE.powi(t as i32)
}

fn check_record(u: &[f64], y: &[f64], m: usize, offset: usize) -> Result<()> {
    if let Some(t) = y.iter().position(|v| !v.is_finite()) {
        return Err(SysidError::NonFinite {
            what: "y",
            sample: offset + t,
            channel: 0,
        });
    }
    if let Some(i) = u.iter().position(|v| !v.is_finite()) {
        return Err(SysidError::NonFinite {
            what: "u",
            sample: offset + i / m.max(1),
            channel: i % m.max(1),
        });
    }
    Ok(())
}

/// Whether `1 + c_1 q^-1 + .. + c_n q^-n` has all its roots strictly inside the unit
/// circle (Schur-Cohn step-down: every reflection coefficient below 1 in magnitude).
fn stable(c: &[f64], work: &mut [f64]) -> bool {
    let n = c.len();
    if n == 0 {
        return true;
    }
    let a = &mut work[..n];
    a.copy_from_slice(c);
    for m in (1..=n).rev() {
        let k = a[m - 1];
        if k.is_nan() || k.abs() >= 1.0 {
            return false;
        }
        let den = 1.0 - k * k;
        for i in 0..(m - 1) / 2 + (m - 1) % 2 {
            let j = m - 2 - i;
            let (ai, aj) = (a[i], a[j]);
            a[i] = (ai - k * aj) / den;
            a[j] = (aj - k * ai) / den;
        }
    }
    true
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl Filters {
    fn new(s: &Structure) -> Self {
        let m = s.nb.len();
        Filters {
            y: Iir::new(s.nd, s.nc),
            u: (0..m).map(|j| Iir::new(s.nd, s.nc + s.nf[j])).collect(),
            e: Iir::new(0, s.nc),
            v: Iir::new(0, s.nc),
            w: (0..m).map(|j| Iir::new(s.nd, s.nc + s.nf[j])).collect(),
            yf: Lagged::new(s.na),
            uf: (0..m).map(|j| Lagged::new(s.nk[j] + s.nb[j])).collect(),
            ef: Lagged::new(s.nc),
            vf: Lagged::new(s.nd),
            wf: s.nf.iter().map(|&n| Lagged::new(n)).collect(),
            cf: (0..m).map(|j| vec![0.0; s.nc + s.nf[j]]).collect(),
        }
    }

    /// Filters this sample's inputs into their lines (they do not depend on the update) and
    /// forms `psi` from the filtered delay lines.
    fn gradient(&mut self, s: &Structure, th: &[f64], u: &[Lagged], psi: &mut [f64]) {
        self.update_cf(s, th);
        let (_, d) = coefficient_slices(s, th);
        for j in 0..u.len() {
            let uf = self.u[j].step(u[j].get(0), d, &self.cf[j]);
            self.uf[j].push(uf);
        }
        let mut k = 0;
        for i in 0..s.na {
            psi[k] = -self.yf.get(i);
            k += 1;
        }
        for j in 0..s.nb.len() {
            for i in 0..s.nb[j] {
                psi[k] = self.uf[j].get(s.nk[j] + i);
                k += 1;
            }
        }
        for i in 0..s.nc {
            psi[k] = self.ef.get(i);
            k += 1;
        }
        for i in 0..s.nd {
            psi[k] = -self.vf.get(i);
            k += 1;
        }
        for j in 0..s.nf.len() {
            for i in 0..s.nf[j] {
                psi[k] = -self.wf[j].get(i);
                k += 1;
            }
        }
    }

    /// The denominators `C F_j` with the current estimates.
    fn update_cf(&mut self, s: &Structure, th: &[f64]) {
        let (c, _) = coefficient_slices(s, th);
        let mut of = s.na + s.nb.iter().sum::<usize>() + s.nc + s.nd;
        for j in 0..s.nf.len() {
            let f = &th[of..of + s.nf[j]];
            of += s.nf[j];
            let out = &mut self.cf[j];
            // (1 + c q^-1 ..)(1 + f q^-1 ..) without the leading 1
            for (k, o) in out.iter_mut().enumerate() {
                let deg = k + 1;
                let mut acc = 0.0;
                if deg <= c.len() {
                    acc += c[deg - 1];
                }
                if deg <= f.len() {
                    acc += f[deg - 1];
                }
                for a in 1..deg {
                    let b = deg - a;
                    if a <= c.len() && b <= f.len() {
                        acc += c[a - 1] * f[b - 1];
                    }
                }
                *o = acc;
            }
        }
    }

    /// Filters this sample's signals (posterior values, updated estimates) into the lines.
    fn push(&mut self, s: &Structure, th: &[f64], y: f64, v: f64, e: f64, w: &[Lagged]) {
        self.update_cf(s, th);
        let (c, d) = coefficient_slices(s, th);
        let yf = self.y.step(y, d, c);
        self.yf.push(yf);
        for j in 0..w.len() {
            let wf = self.w[j].step(w[j].get(0), d, &self.cf[j]);
            self.wf[j].push(wf);
        }
        let ef = self.e.step(e, &[], c);
        self.ef.push(ef);
        let vf = self.v.step(v, &[], c);
        self.vf.push(vf);
    }
}

fn coefficient_slices<'a>(s: &Structure, th: &'a [f64]) -> (&'a [f64], &'a [f64]) {
    let ic = s.na + s.nb.iter().sum::<usize>();
    (&th[ic..ic + s.nc], &th[ic + s.nc..ic + s.nc + s.nd])
}
