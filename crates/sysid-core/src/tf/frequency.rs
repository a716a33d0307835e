//! Weighted nonlinear least-squares fit of a rational model to frequency-response data.
//!
//! The model at the points `x_k` (`s = j omega` for continuous time, `z^-1 = e^{-j omega dt}`
//! for discrete time) is
//!
//! ```text
//! G_k(theta) = N(x_k) / D(x_k) * exp(-w_k tau),
//! D(x) = x^d0 + sum_i a_i x^{p_i},    N(x) = sum_i b_i x^{q_i},
//! ```
//!
//! with `theta = [a, b, tau]` and the cost `1/2 sum_k |W_k (G_k(theta) - H_k)|^2`. The
//! complex residual of each frequency counts as two real residuals; its derivatives are
//!
//! ```text
//! dG/da_i = -G x^{p_i} / D,    dG/db_i = x^{q_i} exp(-w tau) / D,    dG/dtau = -w G,
//! ```
//!
//! and the gradient and Gauss-Newton matrix are `Re(J^H r)` and `Re(J^H J)`. The search is
//! the shared one ([`crate::optim::minimize`]), the covariance the shared
//! [`crate::optim::covariance`], scaled by the variance of one real residual (given, or
//! estimated from the residuals as `2 V / (2 K - p)`).

use crate::error::{Result, SysidError};
use crate::optim::{self, Covariance, Evaluation, Flow, Iteration, Options, Problem, Solution};
use faer::{c64, Mat};

/// The structure of the rational model: evaluation points and polynomial powers.
#[derive(Debug, Clone)]
pub struct Rational {
    /// Points `x_k` at which the polynomials are evaluated.
    pub x: Vec<c64>,
    /// Delay variable `w_k` (the factor is `exp(-w_k tau)`); `j omega` in continuous time.
    pub w: Vec<c64>,
    /// Power `d0` of the fixed leading term of the denominator (coefficient 1).
    pub lead: usize,
    /// Powers `p_i` of the free denominator coefficients `a_i`.
    pub den: Vec<usize>,
    /// Powers `q_i` of the numerator coefficients `b_i`.
    pub num: Vec<usize>,
    /// Keep the denominator's roots stable during the search (MATLAB's `EnforceStability`):
    /// in the left half-plane of `x` when `lead > 0` (continuous time, `x = s`), inside the
    /// unit circle in `z` when `lead == 0` (discrete time, `x = z^-1`). The start must be
    /// stable then.
    pub stable: bool,
}

impl Rational {
    /// Number of parameters `len(a) + len(b) + 1` (the delay last).
    pub fn n_params(&self) -> usize {
        self.den.len() + self.num.len() + 1
    }

    fn max_power(&self) -> usize {
        self.den
            .iter()
            .chain(&self.num)
            .copied()
            .chain([self.lead])
            .max()
            .unwrap_or(0)
    }

    /// Whether the denominator at `theta` has its roots where [`Rational::stable`] asks.
    pub fn is_stable(&self, theta: &[f64]) -> bool {
        let mut c = vec![0.0; self.max_power() + 1];
        c[self.lead] += 1.0;
        for (i, &p) in self.den.iter().enumerate() {
            c[p] += theta[i];
        }
        if self.lead > 0 {
            crate::polynomial::filter::is_hurwitz(&c)
        } else {
            crate::polynomial::filter::is_stable(&c)
        }
    }

    /// The model's response at every point, for the parameters `theta`.
    pub fn response(&self, theta: &[f64]) -> Vec<c64> {
        let mut pw = vec![c64::new(1.0, 0.0); self.max_power() + 1];
        (0..self.x.len())
            .map(|k| self.terms(k, theta, &mut pw).0)
            .collect()
    }

    /// `(G, 1/D, exp(-w tau))` at point `k`; `pw` receives the powers of `x_k`.
    fn terms(&self, k: usize, theta: &[f64], pw: &mut [c64]) -> (c64, c64, c64) {
        let x = self.x[k];
        for i in 1..pw.len() {
            pw[i] = pw[i - 1] * x;
        }
        let na = self.den.len();
        let mut d = pw[self.lead];
        for (i, &p) in self.den.iter().enumerate() {
            d += pw[p] * theta[i];
        }
        let mut n = c64::new(0.0, 0.0);
        for (i, &q) in self.num.iter().enumerate() {
            n += pw[q] * theta[na + i];
        }
        let e = (-self.w[k] * theta[theta.len() - 1]).exp();
        let inv = c64::new(1.0, 0.0) / d;
        (n * inv * e, inv, e)
    }
}

struct FitProblem<'a> {
    model: &'a Rational,
    h: &'a [c64],
    weight: &'a [f64],
}

impl Problem for FitProblem<'_> {
    fn n_params(&self) -> usize {
        self.model.n_params()
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        !self.model.stable || self.model.is_stable(theta)
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let m = self.model;
        let p = m.n_params();
        let na = m.den.len();
        let mut ev = Evaluation::cost_only(0.0);
        if jacobian {
            ev.gradient = vec![0.0; p];
            ev.gauss_newton = Mat::zeros(p, p);
        }
        let mut pw = vec![c64::new(1.0, 0.0); m.max_power() + 1];
        let mut row = vec![c64::new(0.0, 0.0); p];
        for k in 0..m.x.len() {
            let (g, inv, e) = m.terms(k, theta, &mut pw);
            let wk = self.weight[k];
            let r = (g - self.h[k]) * wk;
            ev.cost += 0.5 * r.norm_sqr();
            if !jacobian {
                continue;
            }
            for (i, &pi) in m.den.iter().enumerate() {
                row[i] = -g * pw[pi] * inv * wk;
            }
            for (i, &qi) in m.num.iter().enumerate() {
                row[na + i] = pw[qi] * inv * e * wk;
            }
            row[p - 1] = -m.w[k] * g * wk;
            for a in 0..p {
                let ca = row[a].conj();
                ev.gradient[a] += (ca * r).re;
                for b in 0..=a {
                    ev.gauss_newton[(a, b)] += (ca * row[b]).re;
                }
            }
        }
        if jacobian {
            crate::optim::mirror_lower(&mut ev.gauss_newton);
        }
        if !ev.cost.is_finite() {
            return Err(SysidError::numerical(
                "frequency-domain fit",
                "the model's response is not finite (a pole on the frequency grid); start \
                 from another model or drop that frequency",
            ));
        }
        Ok(ev)
    }
}

/// The fit: the search's solution and the parameter covariance.
#[derive(Debug, Clone)]
pub struct FrequencyFit {
    /// What the search did, and the parameters `[a, b, tau]`.
    pub solution: Solution,
    /// Covariance of the parameters (zero rows for fixed ones).
    pub covariance: Covariance,
    /// The variance of one real residual used to scale the covariance.
    pub noise_variance: f64,
}

/// Fits `theta = [a, b, tau]` of `model` to the response `h` with weights `weight`.
///
/// `noise_variance`: the variance of the real and of the imaginary part of one weighted
/// residual when known (`1/2` when the weights are `1/std` of the complex response and that
/// std is exact), else `None`: the residual scale [`optim::residual_scale`] over the `2 k`
/// real residuals (what `tfest` and `oe` use, as `pem` and `greyest`).
///
/// ```
/// use faer::c64;
/// use sysid_core::optim::{Flow, Options};
/// use sysid_core::tf::{fit_frequency, Rational};
/// // G(s) = 2 / (s + 3) sampled at five frequencies, fitted from a = 1, b = 1.
/// let omega = [0.1, 0.5, 1.0, 3.0, 10.0];
/// let x: Vec<c64> = omega.iter().map(|&w| c64::new(0.0, w)).collect();
/// let h: Vec<c64> = x.iter().map(|&s| c64::new(2.0, 0.0) / (s + 3.0)).collect();
/// let model = Rational { x: x.clone(), w: x, lead: 1, den: vec![0], num: vec![0], stable: false };
/// let mut opts = Options::default();
/// opts.fixed = Some(vec![false, false, true]);
/// let fit = fit_frequency(&model, &h, &[1.0; 5], &[1.0, 1.0, 0.0], &opts, None,
///                         &mut |_| Flow::Continue).unwrap();
/// assert!((fit.solution.theta[0] - 3.0).abs() < 1e-9 && (fit.solution.theta[1] - 2.0).abs() < 1e-9);
/// ```
pub fn fit_frequency(
    model: &Rational,
    h: &[c64],
    weight: &[f64],
    theta0: &[f64],
    options: &Options,
    noise_variance: Option<f64>,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<FrequencyFit> {
    let k = model.x.len();
    for (what, len) in [
        ("w", model.w.len()),
        ("h", h.len()),
        ("weight", weight.len()),
    ] {
        if len != k {
            return Err(SysidError::ShapeMismatch {
                what: what.into(),
                expected: format!("({k},)"),
                got: format!("({len},)"),
            });
        }
    }
    if theta0.len() != model.n_params() {
        return Err(SysidError::ShapeMismatch {
            what: "theta0".into(),
            expected: format!("({},)", model.n_params()),
            got: format!("({},)", theta0.len()),
        });
    }
    if weight.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
        return Err(SysidError::invalid(
            "weight",
            "weights must be finite and >= 0",
        ));
    }
    if model.stable && !model.is_stable(theta0) {
        return Err(SysidError::invalid(
            "theta0",
            "the starting denominator is unstable while stability is enforced: start from a \
             stable model (reflect its unstable roots)",
        ));
    }
    let mut prob = FitProblem { model, h, weight };
    let solution = optim::minimize(&mut prob, theta0, options, observer)?;
    let mut gn = solution.gauss_newton.clone();
    if let Some(f) = &options.fixed {
        for (i, &fx) in f.iter().enumerate() {
            if fx {
                for j in 0..gn.ncols() {
                    gn[(i, j)] = 0.0;
                    gn[(j, i)] = 0.0;
                }
            }
        }
    }
    let unit = optim::covariance(gn.as_ref(), 1.0, 1e-12)?;
    let sigma2 =
        noise_variance.unwrap_or_else(|| optim::residual_scale(solution.cost, 2 * k, unit.rank));
    let covariance = Covariance {
        covariance: &unit.covariance * faer::Scale(sigma2),
        ..unit
    };
    Ok(FrequencyFit {
        solution,
        covariance,
        noise_variance: sigma2,
    })
}
