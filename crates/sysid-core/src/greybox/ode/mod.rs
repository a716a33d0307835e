//! Nonlinear grey-box models: `dx/dt = f(t, x, u, p)`, `y = h(t, x, u, p)`, simulation errors.
//!
//! The free parameters are some entries of `p` and some initial-state entries of each
//! experiment. The Jacobian of the simulated outputs is taken either by forward differences,
//! all perturbed trajectories integrated together, or (with [`OdeJacobian::Sensitivity`])
//! by the forward sensitivity equations `dS/dt = f_x S + f_p`, `S(0) = dx0/dtheta`,
//! `dy/dtheta = h_x S + h_p`, integrated beside the states by the same integrator: the
//! sensitivities ride as extra columns of the state matrix, so the same Runge-Kutta stages
//! serve both (for the fixed-step RK4 this is exactly the derivative of the discrete
//! simulation). For forward differences the model is evaluated on `K` columns at once
//! (`x` is `nx x K`, `p` is `np x K`, column 0 the nominal point), so a vectorised
//! right-hand side costs one call per integrator stage for the whole Jacobian. The input is
//! held constant over each sample interval (zero-order hold). Integrators: classical
//! Runge-Kutta with a fixed number of sub-steps per sample, or Dormand-Prince 5(4) with error
//! control over all columns. The cost is `1/2 sum_t e^T W e` with `W = Lambda^-1` re-estimated
//! between iterations (the determinant criterion), as for the linear predictor.
//!
//! Files: this one (the model trait, options, structure, result and the three entry points
//! [`estimate`], [`simulate`], [`jacobian`]), `problem` (the checked problem, the run over
//! the experiments, the cost and normal equations), `integrate` (the integrators and the
//! sensitivity equations).

use super::{determinant, CriterionFit};
use crate::error::{Result, SysidError};
use crate::optim::{self, Flow, Iteration, Problem};
use faer::{Mat, MatRef};

mod integrate;
mod problem;

pub use problem::OdeProblem;

/// What [`OdeProblem::run`] reports per sample: residual, `d yhat / d theta`, moved columns.
type Sink<'a> = dyn FnMut(&[f64], &Mat<f64>, &[usize]) + 'a;

/// The model equations evaluated on `K` columns at once.
pub trait OdeModel {
    /// `dx/dt` (`nx x K`) at time `t` for states `x` (`nx x K`), input `u` (length m) and
    /// parameters `p` (`np x K`).
    fn rhs(
        &mut self,
        t: f64,
        x: MatRef<'_, f64>,
        u: &[f64],
        p: MatRef<'_, f64>,
    ) -> Result<Mat<f64>>;
    /// The outputs (`l x K`).
    fn output(
        &mut self,
        t: f64,
        x: MatRef<'_, f64>,
        u: &[f64],
        p: MatRef<'_, f64>,
    ) -> Result<Mat<f64>>;
    /// `(f, df/dx, df/dp)` at one point (`nx x 1`, `nx x nx`, `nx x np`), for the
    /// sensitivity equations; `None` (the default) when the model has no derivatives.
    fn rhs_derivatives(
        &mut self,
        _t: f64,
        _x: &[f64],
        _u: &[f64],
        _p: &[f64],
    ) -> Result<Option<Derivatives>> {
        Ok(None)
    }
    /// `(h, dh/dx, dh/dp)` at one point (`l x 1`, `l x nx`, `l x np`); `None` by default.
    fn output_derivatives(
        &mut self,
        _t: f64,
        _x: &[f64],
        _u: &[f64],
        _p: &[f64],
    ) -> Result<Option<Derivatives>> {
        Ok(None)
    }
}

/// A function value and its derivatives with respect to the state and the parameters:
/// `(value (k x 1), d/dx (k x nx), d/dp (k x np))`.
pub type Derivatives = (Mat<f64>, Mat<f64>, Mat<f64>);

/// How the Jacobian of the simulated outputs is formed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OdeJacobian {
    /// Forward differences, all perturbed trajectories integrated together (default).
    #[default]
    FiniteDifference,
    /// Forward sensitivity equations with the model's
    /// [`OdeModel::rhs_derivatives`] and [`OdeModel::output_derivatives`].
    Sensitivity,
}

/// How the state equation is integrated between samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Integrator {
    /// Classical fourth-order Runge-Kutta with this many equal steps per sample interval.
    Rk4 {
        /// Steps per sample (>= 1).
        substeps: usize,
    },
    /// Dormand-Prince 5(4) with error control (relative and absolute tolerance).
    Adaptive {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance.
        atol: f64,
    },
}

crate::names::option_names! { OdeJacobian, "jacobian", false, [
    ("fd", OdeJacobian::FiniteDifference), ("sensitivity", OdeJacobian::Sensitivity),
] }

crate::names::option_names! { Integrator, "integrator", false, [
    ("rk4", Integrator::Rk4 { substeps: 1 }),
    ("adaptive", Integrator::Adaptive { rtol: 1e-8, atol: 1e-10 }),
] }

impl Integrator {
    /// The integrator named `name` (`"rk4"` with `substeps`, `"adaptive"` with `rtol`,
    /// `atol`).
    ///
    /// ```
    /// use sysid_core::greybox::ode::Integrator;
    /// let i = Integrator::from_name("rk4", 4, 1e-8, 1e-10).unwrap();
    /// assert_eq!(i, Integrator::Rk4 { substeps: 4 });
    /// assert!(Integrator::from_name("euler", 1, 1e-8, 1e-10).is_err());
    /// ```
    pub fn from_name(name: &str, substeps: usize, rtol: f64, atol: f64) -> Result<Self> {
        Ok(match name.parse()? {
            Integrator::Rk4 { .. } => Integrator::Rk4 { substeps },
            Integrator::Adaptive { .. } => Integrator::Adaptive { rtol, atol },
        })
    }
}

/// Options of [`estimate`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct OdeOptions {
    /// Sample time of the data.
    pub dt: f64,
    /// The integrator.
    pub integrator: Integrator,
    /// Re-estimate the weighting `W = Lambda^-1` between iterations (default `true`).
    pub reweight: bool,
    /// Relative forward-difference step (times `max(|theta_k|, typical_k)`).
    pub fd_step: f64,
    /// Forward differences or sensitivity equations.
    pub jacobian: OdeJacobian,
    /// Options of the search (bounds and fixed mask in the free parameters).
    pub optim: optim::Options,
}

impl Default for OdeOptions {
    fn default() -> Self {
        OdeOptions {
            dt: 1.0,
            integrator: Integrator::Rk4 { substeps: 1 },
            reweight: true,
            fd_step: 1e-6,
            jacobian: OdeJacobian::FiniteDifference,
            optim: optim::Options {
                max_iter: 100,
                tol_cost: 1e-10,
                ..Default::default()
            },
        }
    }
}

/// What is estimated: which parameters and which initial-state entries are free.
#[derive(Debug, Clone)]
pub struct OdeStructure {
    /// Number of states.
    pub nx: usize,
    /// All parameters at their initial (or fixed) values.
    pub p: Vec<f64>,
    /// Indices into `p` of the parameters that are searched.
    pub free_p: Vec<usize>,
    /// The initial state of every experiment (initial or fixed values).
    pub x0: Vec<Vec<f64>>,
    /// `(experiment, state)` of the initial-state entries that are searched.
    pub free_x0: Vec<(usize, usize)>,
    /// A typical magnitude per searched quantity (length `free_p + free_x0`), for the
    /// difference steps.
    pub typical: Vec<f64>,
}

/// The estimate of a nonlinear grey-box model.
#[derive(Debug, Clone)]
pub struct OdeResult {
    /// The searched quantities (free parameters, then free initial-state entries).
    pub theta: Vec<f64>,
    /// Simulation-error covariance, search, covariance of `theta`, samples, losses.
    pub fit: CriterionFit,
    /// Right-hand-side evaluations (calls, each on all columns; with sensitivities, calls
    /// of [`OdeModel::rhs_derivatives`] count too).
    pub rhs_calls: usize,
}

/// Estimates the free parameters and initial states of a nonlinear grey-box model from the
/// simulation errors over one or more experiments `(u, y)`.
///
/// ```
/// use faer::{Mat, MatRef};
/// use sysid_core::greybox::ode::{estimate, OdeModel, OdeOptions, OdeStructure};
/// use sysid_core::optim::Flow;
/// // dx/dt = -a x + u, y = x, with a = 2 to be found from a = 1.
/// struct M;
/// impl OdeModel for M {
///     fn rhs(&mut self, _t: f64, x: MatRef<'_, f64>, u: &[f64], p: MatRef<'_, f64>)
///         -> sysid_core::Result<Mat<f64>> {
///         Ok(Mat::from_fn(1, x.ncols(), |_, c| -p[(0, c)] * x[(0, c)] + u[0]))
///     }
///     fn output(&mut self, _t: f64, x: MatRef<'_, f64>, _u: &[f64], _p: MatRef<'_, f64>)
///         -> sysid_core::Result<Mat<f64>> { Ok(x.to_owned()) }
/// }
/// let u = Mat::from_fn(200, 1, |t, _| if (t / 20) % 2 == 0 { 1.0 } else { -1.0 });
/// // data from the same integrator at a = 2
/// let st = OdeStructure { nx: 1, p: vec![2.0], free_p: vec![], x0: vec![vec![0.0]],
///                         free_x0: vec![], typical: vec![] };
/// let mut o = OdeOptions::default();
/// o.dt = 0.05;
/// let y = sysid_core::greybox::ode::simulate(&mut M, u.as_ref(), &st, 0, &o).unwrap();
/// let st = OdeStructure { p: vec![1.0], free_p: vec![0], typical: vec![1.0], ..st };
/// let r = estimate(&mut M, &[(u.as_ref(), y.as_ref())], st, &o, &mut |_| Flow::Continue)
///     .unwrap();
/// assert!((r.theta[0] - 2.0).abs() < 1e-6);
/// ```
pub fn estimate(
    model: &mut dyn OdeModel,
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    structure: OdeStructure,
    options: &OdeOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<OdeResult> {
    let mut prob = OdeProblem::new(model, experiments, structure, options.clone())?;
    let th0 = prob.theta0();
    if options.reweight {
        prob.reweight_at(&th0)?;
    } else {
        let lam = prob.error_covariance(&th0)?;
        prob.losses.push(determinant(&lam));
    }
    let solution = optim::minimize(&mut prob, &th0, &options.optim, observer)?;
    let theta = solution.theta.clone();
    let lam = prob.error_covariance(&theta)?;
    let h = if options.reweight {
        solution.gauss_newton.clone()
    } else {
        prob.opt.reweight = true;
        prob.reweight_at(&theta)?;
        prob.losses.pop();
        prob.evaluate(&theta, true)?.gauss_newton
    };
    let fixed = options.optim.fixed.as_deref();
    let fit = CriterionFit::new(
        solution,
        &h,
        fixed,
        lam,
        prob.n_samples,
        prob.losses.clone(),
    )?;
    Ok(OdeResult {
        theta,
        fit,
        rhs_calls: prob.rhs_calls,
    })
}

/// Simulates experiment input `u` with the structure's parameters and experiment `e`'s
/// initial state; returns the outputs (`N x l`).
pub fn simulate(
    model: &mut dyn OdeModel,
    u: MatRef<'_, f64>,
    structure: &OdeStructure,
    e: usize,
    options: &OdeOptions,
) -> Result<Mat<f64>> {
    // probe the output size on the initial state
    let p = Mat::from_fn(structure.p.len(), 1, |i, _| structure.p[i]);
    let x0 = structure
        .x0
        .get(e)
        .ok_or_else(|| SysidError::invalid("experiment", "index out of range"))?;
    let ut: Vec<f64> = (0..u.ncols())
        .map(|j| if u.nrows() > 0 { u[(0, j)] } else { 0.0 })
        .collect();
    let xm = Mat::from_fn(structure.nx, 1, |i, _| x0[i]);
    let l = model.output(0.0, xm.as_ref(), &ut, p.as_ref())?.nrows();
    let y = Mat::<f64>::zeros(u.nrows(), l);
    let st = OdeStructure {
        free_p: Vec::new(),
        free_x0: Vec::new(),
        typical: Vec::new(),
        x0: vec![x0.clone()],
        ..structure.clone()
    };
    let mut out = Mat::<f64>::zeros(u.nrows(), l);
    {
        let exps = [(u, y.as_ref())];
        let mut prob = OdeProblem::new(model, &exps, st, options.clone())?;
        let mut t = 0usize;
        let ok = prob.run(&[], false, &mut |r, _, _| {
            for i in 0..l {
                out[(t, i)] = -r[i];
            }
            t += 1;
        })?;
        if !ok {
            return Err(SysidError::numerical(
                "nonlinear grey-box simulation",
                "the simulated output is not finite",
            ));
        }
    }
    Ok(out)
}

/// The simulated outputs of every experiment (stacked, `N x l`) at the structure's values
/// and their derivatives with respect to the searched quantities (free parameters, then
/// free initial-state entries): `d yhat[t, i] / d theta_k` in row `t l + i`, column `k`,
/// by the method of `options.jacobian`.
///
/// ```
/// use faer::{Mat, MatRef};
/// use sysid_core::greybox::ode::{jacobian, Derivatives, OdeJacobian, OdeModel, OdeOptions,
///                                 OdeStructure};
/// // dx/dt = -a x + u, y = x: the sensitivity s = dx/da obeys ds/dt = -a s - x.
/// struct M;
/// impl OdeModel for M {
///     fn rhs(&mut self, _t: f64, x: MatRef<'_, f64>, u: &[f64], p: MatRef<'_, f64>)
///         -> sysid_core::Result<Mat<f64>> {
///         Ok(Mat::from_fn(1, x.ncols(), |_, c| -p[(0, c)] * x[(0, c)] + u[0]))
///     }
///     fn output(&mut self, _t: f64, x: MatRef<'_, f64>, _u: &[f64], _p: MatRef<'_, f64>)
///         -> sysid_core::Result<Mat<f64>> { Ok(x.to_owned()) }
///     fn rhs_derivatives(&mut self, _t: f64, x: &[f64], u: &[f64], p: &[f64])
///         -> sysid_core::Result<Option<Derivatives>> {
///         Ok(Some((Mat::from_fn(1, 1, |_, _| -p[0] * x[0] + u[0]),
///                  Mat::from_fn(1, 1, |_, _| -p[0]), Mat::from_fn(1, 1, |_, _| -x[0]))))
///     }
///     fn output_derivatives(&mut self, _t: f64, x: &[f64], _u: &[f64], _p: &[f64])
///         -> sysid_core::Result<Option<Derivatives>> {
///         Ok(Some((Mat::from_fn(1, 1, |_, _| x[0]), Mat::from_fn(1, 1, |_, _| 1.0),
///                  Mat::zeros(1, 1))))
///     }
/// }
/// let u = Mat::from_fn(50, 1, |_, _| 1.0);
/// let st = OdeStructure { nx: 1, p: vec![2.0], free_p: vec![0], x0: vec![vec![0.0]],
///                         free_x0: vec![], typical: vec![1.0] };
/// let mut o = OdeOptions::default();
/// o.dt = 0.05;
/// o.jacobian = OdeJacobian::Sensitivity;
/// let (y, j) = jacobian(&mut M, &[u.as_ref()], &st, &o).unwrap();
/// // x(t) = (1 - e^{-a t}) / a, dx/da = t e^{-a t} / a - (1 - e^{-a t}) / a^2
/// let t: f64 = 49.0 * 0.05;
/// let exact = t * (-2.0 * t).exp() / 2.0 - (1.0 - (-2.0 * t).exp()) / 4.0;
/// assert!((j[(49, 0)] - exact).abs() < 1e-6 && y.nrows() == 50);
/// ```
pub fn jacobian(
    model: &mut dyn OdeModel,
    inputs: &[MatRef<'_, f64>],
    structure: &OdeStructure,
    options: &OdeOptions,
) -> Result<(Mat<f64>, Mat<f64>)> {
    if inputs.is_empty() {
        return Err(SysidError::invalid("data", "no experiment given"));
    }
    let p = Mat::from_fn(structure.p.len(), 1, |i, _| structure.p[i]);
    let x0 = structure
        .x0
        .first()
        .ok_or_else(|| SysidError::invalid("x0", "one initial state per experiment"))?;
    let u0 = inputs[0];
    let ut: Vec<f64> = (0..u0.ncols())
        .map(|j| if u0.nrows() > 0 { u0[(0, j)] } else { 0.0 })
        .collect();
    let xm = Mat::from_fn(structure.nx, 1, |i, _| x0.get(i).copied().unwrap_or(0.0));
    let l = model.output(0.0, xm.as_ref(), &ut, p.as_ref())?.nrows();
    let ys: Vec<Mat<f64>> = inputs.iter().map(|u| Mat::zeros(u.nrows(), l)).collect();
    let exps: Vec<_> = inputs
        .iter()
        .zip(&ys)
        .map(|(u, y)| (*u, y.as_ref()))
        .collect();
    let n: usize = inputs.iter().map(|u| u.nrows()).sum();
    let mut prob = OdeProblem::new(model, &exps, structure.clone(), options.clone())?;
    let th = prob.theta0();
    let q = th.len();
    let mut yhat = Mat::<f64>::zeros(n, l);
    let mut jac = Mat::<f64>::zeros(n * l, q);
    let mut t = 0usize;
    let ok = prob.run(&th, true, &mut |r, dy, cols| {
        for i in 0..l {
            yhat[(t, i)] = -r[i];
            for &k in cols {
                jac[(t * l + i, k)] = dy[(i, k)];
            }
        }
        t += 1;
    })?;
    if !ok {
        return Err(SysidError::numerical(
            "nonlinear grey-box simulation",
            "the simulated output is not finite",
        ));
    }
    Ok((yhat, jac))
}
