//! Grey-box models: a few named physical parameters instead of free matrix entries.
//!
//! [`linear`] estimates the parameters `p` of a linear structure `p -> (A, B, C, D, K, x0)`
//! (the sampled matrices; a continuous structure is discretised by the caller, which also
//! supplies the chain rule through the matrix exponential) by minimising the prediction (or
//! simulation) errors of the [`pem::Predictor`](crate::pem::Predictor) through an
//! [`optim::Reparameterized`] problem: the predictor's sensitivities with respect to the matrix
//! entries, accumulated blockwise over the samples, composed with the map's Jacobian
//! `dtheta/dp` once per iteration. Bounds and fixed parameters are the optimiser's.
//!
//! [`frequency`] fits the same structures to frequency-response lines (periodic data, or an
//! FRD with its noise variance), reusing the state-space fit's sensitivities to the matrix
//! entries through the same chain rule.
//!
//! [`ode`] estimates the parameters and initial states of a nonlinear state equation
//! `dx/dt = f(t, x, u, p)`, `y = h(t, x, u, p)` from its simulation errors, integrating all
//! finite-difference perturbations of the parameters together.

pub mod expm;
pub mod frequency;
pub mod ode;
#[cfg(test)]
mod tests;

use crate::error::{Result, SysidError};
use crate::model::StateSpace;
use crate::optim::{
    self, Covariance, Flow, Iteration, ParameterMap, Problem, Reparameterized, Solution,
};
use crate::pem::{Focus, InitialState, PemOptions, Predictor};
use faer::{Mat, MatRef};

/// Options of [`linear`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct LinearOptions {
    /// Prediction errors (with the structure's `K`) or simulation errors (`K = 0`).
    pub focus: Focus,
    /// Whether the inner parameters carry `K` (prediction focus with a noise model).
    pub with_k: bool,
    /// Re-estimate the weighting `W = Lambda^-1` between iterations (default `true`).
    pub reweight: bool,
    /// Indices of outer parameters that are free initial-state entries: fitted alone by one
    /// linear least-squares step before the search.
    pub x0_params: Vec<usize>,
    /// Options of the search (bounds and fixed mask in the outer parameters).
    pub optim: optim::Options,
    /// Let the model's `A` (simulation focus; the predictor's `A - K C` otherwise) leave the
    /// unit circle: a free search, for the test whether the data insist on an unstable model
    /// ([`crate::pem::insists`]). Default `false`: kept inside.
    pub unbounded: bool,
}

impl Default for LinearOptions {
    fn default() -> Self {
        LinearOptions {
            focus: Focus::Prediction,
            with_k: false,
            reweight: true,
            x0_params: Vec::new(),
            optim: optim::Options {
                max_iter: 100,
                tol_cost: 1e-10,
                ..Default::default()
            },
            unbounded: false,
        }
    }
}

/// What a fit on the determinant criterion reports besides its parameters (linear and ODE
/// grey-box models alike).
#[derive(Debug, Clone)]
pub struct CriterionFit {
    /// Sample covariance of the errors, l x l.
    pub innovation_covariance: Mat<f64>,
    /// What the search did.
    pub solution: Solution,
    /// Covariance of the searched parameters (`H^+` with `W = Lambda^-1`; fixed ones: zero
    /// rows and columns).
    pub covariance: Covariance,
    /// Number of samples.
    pub n_samples: usize,
    /// `det(Lambda)` at the start and after every accepted iteration.
    pub loss_history: Vec<f64>,
}

impl CriterionFit {
    /// The report of `solution`, its covariance from the Gauss-Newton matrix `h` at the
    /// solution (weighted by `Lambda^-1`) restricted to the parameters `fixed` leaves free
    /// (`None`: all).
    pub(crate) fn new(
        solution: Solution,
        h: &Mat<f64>,
        fixed: Option<&[bool]>,
        innovation_covariance: Mat<f64>,
        n_samples: usize,
        loss_history: Vec<f64>,
    ) -> Result<Self> {
        let all_free = vec![false; h.nrows()];
        let covariance = free_covariance(h, fixed.unwrap_or(&all_free))?;
        Ok(CriterionFit {
            innovation_covariance,
            solution,
            covariance,
            n_samples,
            loss_history,
        })
    }
}

/// The estimate of a linear grey-box structure.
#[derive(Debug, Clone)]
pub struct LinearResult {
    /// The outer parameters at the solution.
    pub p: Vec<f64>,
    /// The inner parameters `(A, B, C, D, [K], x0 per experiment)` at the solution.
    pub theta: Vec<f64>,
    /// Prediction-error covariance, search, covariance of `p`, samples, losses.
    pub fit: CriterionFit,
}

/// Estimates the parameters of a linear grey-box structure.
///
/// `map` gives, for outer parameters `p`, the inner vector
/// `theta = (A, B, C, D, [K], x0_1, ..., x0_E)` (row-major blocks; `K` when
/// `options.with_k`; one initial state per experiment) and `dtheta/dp`. `dims = (n, m, l)`.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::greybox::{linear, LinearOptions};
/// use sysid_core::optim::{Flow, ParameterMap};
/// use sysid_core::{StateSpace, simulate::simulate};
/// // x(t+1) = a x + u, y = x: one parameter a.
/// struct Map;
/// impl ParameterMap for Map {
///     fn map(&mut self, p: &[f64], jac: bool) -> sysid_core::Result<(Vec<f64>, Option<Mat<f64>>)> {
///         let th = vec![p[0], 1.0, 1.0, 0.0, 0.0];   // A, B, C, D, x0
///         let m = jac.then(|| Mat::from_fn(5, 1, |i, _| if i == 0 { 1.0 } else { 0.0 }));
///         Ok((th, m))
///     }
/// }
/// let truth = StateSpace::new(mat![[0.7]], mat![[1.0]], mat![[1.0]], mat![[0.0]]).unwrap();
/// let u = Mat::from_fn(100, 1, |t, _| ((t * 7919 % 13) as f64) - 6.0);
/// let y = simulate(&truth, u.as_ref(), None).unwrap();
/// let r = linear((1, 1, 1), &[(u.as_ref(), y.as_ref())], &mut Map, &[0.3],
///                &LinearOptions::default(), &mut |_| Flow::Continue).unwrap();
/// assert!((r.p[0] - 0.7).abs() < 1e-10);
/// ```
pub fn linear(
    dims: (usize, usize, usize),
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    map: &mut dyn ParameterMap,
    p0: &[f64],
    options: &LinearOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<LinearResult> {
    let (n, m, l) = dims;
    let np = p0.len();
    let start = StateSpace::new(
        Mat::zeros(n, n),
        Mat::zeros(n, m),
        Mat::zeros(l, n),
        Mat::zeros(l, m),
    )?;
    let po = PemOptions {
        focus: options.focus,
        estimate_d: true,
        estimate_k: options.with_k,
        x0: vec![InitialState::Estimate],
        reweight: options.reweight,
        local_coordinates: false,
        free_parameters: Some(np),
        ..Default::default()
    };
    if options.with_k && options.focus != Focus::Prediction {
        return Err(SysidError::invalid(
            "with_k",
            "a Kalman gain is only part of the prediction focus",
        ));
    }
    let k0 = Mat::<f64>::zeros(n, l);
    let mut pred = Predictor::new(&start, Some(k0.as_ref()), experiments, &po)?;
    if options.unbounded {
        pred.set_unbounded();
    }
    let q = pred.n_params();
    let (th0, _) = map.map(p0, false)?;
    if th0.len() != q {
        return Err(SysidError::invalid(
            "structure",
            format!(
                "the parameter map gives {} matrix entries, a model with n={n}, m={m}, l={l} \
                 and {} experiment(s) needs {q}",
                th0.len(),
                experiments.len()
            ),
        ));
    }
    if !pred.admissible(&th0) {
        // a structure's integrator (a pole at s = 0, sampled to z = 1 to round-off) is
        // physics, not a predictor about to diverge (MATLAB's DC-motor grey box): a start on
        // the unit circle admits the circle for the whole search
        pred.set_marginal();
    }
    if !pred.admissible(&th0) {
        return Err(SysidError::invalid(
            "initial parameters",
            match options.focus {
                Focus::Simulation => {
                    "the sampled A of the structure at the initial parameters \
                     has eigenvalues on or outside the unit circle (an unstable system cannot be \
                     fitted by simulation errors): start from stable values, or use \
                     focus=\"prediction\" with a stabilising K"
                }
                Focus::Prediction => {
                    "the predictor A - K C at the initial parameters is \
                     unstable: start from values that give a stable predictor"
                }
            },
        ));
    }
    let mut p = p0.to_vec();
    // free initial states first: the residual is linear in them, one Gauss-Newton step
    if !options.x0_params.is_empty() {
        let mut fixed = vec![true; np];
        for &i in &options.x0_params {
            if i >= np {
                return Err(SysidError::invalid("x0_params", "index out of range"));
            }
            fixed[i] = options.optim.fixed.as_ref().is_some_and(|f| f[i]);
        }
        let o = optim::Options {
            max_iter: 1,
            initial_damping: 0.0,
            tol_gradient: 0.0,
            final_gauss_newton: false,
            fixed: Some(fixed),
            ..Default::default()
        };
        let mut prob = Reparameterized::new(&mut pred, map, np);
        p = optim::minimize(&mut prob, &p, &o, &mut |_| Flow::Continue)?.theta;
    }
    let th = map.map(&p, false)?.0;
    pred.start_history(&th)?;
    let solution = {
        let mut prob = Reparameterized::new(&mut pred, map, np);
        optim::minimize(&mut prob, &p, &options.optim, observer)?
    };
    let p = solution.theta.clone();
    let (theta, _) = map.map(&p, false)?;
    let lam = pred.innovation_covariance(&theta);
    let loss_history = pred.losses().clone();
    let h = if options.reweight {
        solution.gauss_newton.clone()
    } else {
        pred.set_reweight(true);
        pred.reweight_at(&theta)?;
        let mut prob = Reparameterized::new(&mut pred, map, np);
        prob.evaluate(&p, true)?.gauss_newton
    };
    let fixed = options.optim.fixed.as_deref();
    let n = pred.n_samples();
    Ok(LinearResult {
        p,
        theta,
        fit: CriterionFit::new(solution, &h, fixed, lam, n, loss_history)?,
    })
}

/// The covariance `H^+` (W = Lambda^-1, scale 1) restricted to the free parameters, embedded
/// in the full parameter space (fixed parameters: zero rows and columns, never reported as
/// unidentifiable).
pub(crate) fn free_covariance(h: &Mat<f64>, fixed: &[bool]) -> Result<Covariance> {
    let np = fixed.len();
    let free: Vec<usize> = (0..np).filter(|&i| !fixed[i]).collect();
    let hf = Mat::from_fn(free.len(), free.len(), |i, j| h[(free[i], free[j])]);
    let c = optim::covariance(hf.as_ref(), 1.0, 1e-10)?;
    let mut cov = Mat::zeros(np, np);
    for (a, &i) in free.iter().enumerate() {
        for (b, &j) in free.iter().enumerate() {
            cov[(i, j)] = c.covariance[(a, b)];
        }
    }
    let k = c.unidentifiable.ncols();
    let mut null = Mat::zeros(np, k);
    for (a, &i) in free.iter().enumerate() {
        for j in 0..k {
            null[(i, j)] = c.unidentifiable[(a, j)];
        }
    }
    Ok(Covariance {
        covariance: cov,
        rank: c.rank,
        unidentifiable: null,
        condition: c.condition,
    })
}

pub(crate) use crate::linalg::determinant;
