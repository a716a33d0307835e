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

use super::{determinant, free_covariance};
use crate::error::{Result, SysidError};
use crate::optim::{self, Covariance, Evaluation, Flow, Iteration, Problem, Solution};
use faer::{Mat, MatRef, Side};

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
    /// Sample covariance of the simulation errors, l x l.
    pub innovation_covariance: Mat<f64>,
    /// What the search did.
    pub solution: Solution,
    /// Covariance of `theta` (`H^+` with `W = Lambda^-1`).
    pub covariance: Covariance,
    /// Number of samples.
    pub n_samples: usize,
    /// `det(Lambda)` at the start and after every accepted iteration.
    pub loss_history: Vec<f64>,
    /// Right-hand-side evaluations (calls, each on all columns; with sensitivities, calls
    /// of [`OdeModel::rhs_derivatives`] count too).
    pub rhs_calls: usize,
}

/// Simulation errors of an [`OdeModel`] as an optimisation problem.
pub struct OdeProblem<'a> {
    model: &'a mut dyn OdeModel,
    exps: Vec<(MatRef<'a, f64>, MatRef<'a, f64>)>,
    st: OdeStructure,
    opt: OdeOptions,
    l: usize,
    rinv: Mat<f64>,
    losses: Vec<f64>,
    n_samples: usize,
    rhs_calls: usize,
    /// Step size carried between sample intervals by the adaptive integrator.
    h_last: f64,
    /// The error covariance at the last evaluated point (saves a simulation per reweight).
    last_cov: Option<(Vec<f64>, Mat<f64>)>,
    /// While sensitivities are integrated: the searched index of every sensitivity column.
    sens_cols: Option<Vec<usize>>,
}

impl<'a> OdeProblem<'a> {
    /// Checks the data and builds the problem.
    pub fn new(
        model: &'a mut dyn OdeModel,
        experiments: &[(MatRef<'a, f64>, MatRef<'a, f64>)],
        structure: OdeStructure,
        options: OdeOptions,
    ) -> Result<Self> {
        if experiments.is_empty() {
            return Err(SysidError::invalid("data", "no experiment given"));
        }
        if structure.x0.len() != experiments.len() {
            return Err(SysidError::invalid(
                "x0",
                format!(
                    "{} initial states for {} experiments",
                    structure.x0.len(),
                    experiments.len()
                ),
            ));
        }
        if structure.x0.iter().any(|v| v.len() != structure.nx) {
            return Err(SysidError::invalid(
                "x0",
                "every initial state needs nx entries",
            ));
        }
        if structure.free_p.iter().any(|&i| i >= structure.p.len())
            || structure
                .free_x0
                .iter()
                .any(|&(e, i)| e >= experiments.len() || i >= structure.nx)
        {
            return Err(SysidError::invalid("structure", "free index out of range"));
        }
        if structure.typical.len() != structure.free_p.len() + structure.free_x0.len() {
            return Err(SysidError::invalid(
                "typical",
                "one entry per searched quantity",
            ));
        }
        if !(options.dt.is_finite() && options.dt > 0.0) {
            return Err(SysidError::invalid("dt", "must be a positive sample time"));
        }
        match options.integrator {
            Integrator::Rk4 { substeps: 0 } => {
                return Err(SysidError::invalid("substeps", "must be >= 1"))
            }
            Integrator::Adaptive { rtol, atol } if !(rtol > 0.0 && atol > 0.0) => {
                return Err(SysidError::invalid(
                    "tolerances",
                    "rtol and atol must be > 0",
                ))
            }
            _ => {}
        }
        let l = experiments[0].1.ncols();
        let m = experiments[0].0.ncols();
        let mut n_samples = 0;
        for (u, y) in experiments {
            if y.ncols() != l || u.ncols() != m || u.nrows() != y.nrows() {
                return Err(SysidError::invalid(
                    "data",
                    "every experiment needs the same channels and as many input as output samples",
                ));
            }
            crate::error::check_finite("u", *u)?;
            crate::error::check_finite("y", *y)?;
            n_samples += y.nrows();
        }
        let h0 = options.dt;
        Ok(OdeProblem {
            model,
            exps: experiments.to_vec(),
            st: structure,
            opt: options,
            l,
            rinv: Mat::identity(l, l),
            losses: Vec::new(),
            n_samples,
            rhs_calls: 0,
            h_last: h0,
            last_cov: None,
            sens_cols: None,
        })
    }

    /// The searched quantities at the structure's initial values.
    pub fn theta0(&self) -> Vec<f64> {
        let mut th: Vec<f64> = self.st.free_p.iter().map(|&i| self.st.p[i]).collect();
        th.extend(self.st.free_x0.iter().map(|&(e, i)| self.st.x0[e][i]));
        th
    }

    fn steps(&self, th: &[f64]) -> Vec<f64> {
        th.iter()
            .zip(&self.st.typical)
            .map(|(v, t)| self.opt.fd_step * v.abs().max(t.abs()).max(1e-300))
            .collect()
    }

    /// Columns for experiment `e`: (P, X0, list of searched indices the columns perturb).
    fn columns(&self, th: &[f64], e: usize, jac: bool) -> (Mat<f64>, Mat<f64>, Vec<usize>) {
        let nfp = self.st.free_p.len();
        let mut p = self.st.p.clone();
        for (k, &i) in self.st.free_p.iter().enumerate() {
            p[i] = th[k];
        }
        let mut x0 = self.st.x0[e].clone();
        for (k, &(ee, i)) in self.st.free_x0.iter().enumerate() {
            if ee == e {
                x0[i] = th[nfp + k];
            }
        }
        let mut cols: Vec<usize> = Vec::new();
        if jac {
            cols.extend(0..nfp);
            for (k, &(ee, _)) in self.st.free_x0.iter().enumerate() {
                if ee == e {
                    cols.push(nfp + k);
                }
            }
        }
        let kc = 1 + cols.len();
        if jac && self.opt.jacobian == OdeJacobian::Sensitivity {
            // x in column 0, S = dx/dtheta in the others: S(0) = e_i for a free x0 entry
            let pm = Mat::from_fn(p.len(), 1, |i, _| p[i]);
            let mut xm = Mat::zeros(self.st.nx, kc);
            for i in 0..self.st.nx {
                xm[(i, 0)] = x0[i];
            }
            for (c, &k) in cols.iter().enumerate() {
                if k >= nfp {
                    xm[(self.st.free_x0[k - nfp].1, c + 1)] = 1.0;
                }
            }
            return (pm, xm, cols);
        }
        let h = self.steps(th);
        let mut pm = Mat::from_fn(p.len(), kc, |i, _| p[i]);
        let mut xm = Mat::from_fn(self.st.nx, kc, |i, _| x0[i]);
        for (c, &k) in cols.iter().enumerate() {
            if k < nfp {
                pm[(self.st.free_p[k], c + 1)] += h[k];
            } else {
                xm[(self.st.free_x0[k - nfp].1, c + 1)] += h[k];
            }
        }
        (pm, xm, cols)
    }

    fn rhs(&mut self, t: f64, x: &Mat<f64>, u: &[f64], p: &Mat<f64>) -> Result<Mat<f64>> {
        if self.sens_cols.is_some() {
            return self.rhs_sensitivity(t, x, u, p);
        }
        self.rhs_calls += 1;
        let d = self.model.rhs(t, x.as_ref(), u, p.as_ref())?;
        if d.nrows() != x.nrows() || d.ncols() != x.ncols() {
            return Err(SysidError::invalid(
                "f",
                format!(
                    "returned a {}x{} array for {} states and {} columns",
                    d.nrows(),
                    d.ncols(),
                    x.nrows(),
                    x.ncols()
                ),
            ));
        }
        Ok(d)
    }

    /// `[f, f_x S + f_p]` for the state in column 0 and the sensitivities in the others.
    fn rhs_sensitivity(
        &mut self,
        t: f64,
        x: &Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
    ) -> Result<Mat<f64>> {
        self.rhs_calls += 1;
        let nx = x.nrows();
        let np = p.nrows();
        let xs: Vec<f64> = (0..nx).map(|i| x[(i, 0)]).collect();
        let ps: Vec<f64> = (0..np).map(|i| p[(i, 0)]).collect();
        let (f, fx, fp) = self
            .model
            .rhs_derivatives(t, &xs, u, &ps)?
            .ok_or_else(no_derivatives)?;
        check_derivatives("f", &f, &fx, &fp, nx, nx, np)?;
        let cols = self.sens_cols.as_ref().expect("sensitivity columns");
        let nfp = self.st.free_p.len();
        let mut out = &fx * x;
        for i in 0..nx {
            out[(i, 0)] = f[(i, 0)];
        }
        for (c, &k) in cols.iter().enumerate() {
            if k < nfp {
                let pi = self.st.free_p[k];
                for i in 0..nx {
                    out[(i, c + 1)] += fp[(i, pi)];
                }
            }
        }
        Ok(out)
    }

    /// Advances `x` over one sample interval `[t, t + dt]` with input `u` held.
    fn advance(&mut self, t: f64, x: &mut Mat<f64>, u: &[f64], p: &Mat<f64>) -> Result<()> {
        let dt = self.opt.dt;
        match self.opt.integrator {
            Integrator::Rk4 { substeps } => {
                let h = dt / substeps as f64;
                for s in 0..substeps {
                    let ts = t + s as f64 * h;
                    let k1 = self.rhs(ts, x, u, p)?;
                    let x2 = &*x + &k1 * (0.5 * h);
                    let k2 = self.rhs(ts + 0.5 * h, &x2, u, p)?;
                    let x3 = &*x + &k2 * (0.5 * h);
                    let k3 = self.rhs(ts + 0.5 * h, &x3, u, p)?;
                    let x4 = &*x + &k3 * h;
                    let k4 = self.rhs(ts + h, &x4, u, p)?;
                    *x = &*x + (&k1 + &k2 * 2.0 + &k3 * 2.0 + &k4) * (h / 6.0);
                }
                Ok(())
            }
            Integrator::Adaptive { rtol, atol } => self.dopri(t, x, u, p, rtol, atol),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn dopri(
        &mut self,
        t0: f64,
        x: &mut Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
        rtol: f64,
        atol: f64,
    ) -> Result<()> {
        const C: [f64; 7] = [0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
        const A: [[f64; 6]; 7] = [
            [0.0; 6],
            [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
            [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
            [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
            [
                19372.0 / 6561.0,
                -25360.0 / 2187.0,
                64448.0 / 6561.0,
                -212.0 / 729.0,
                0.0,
                0.0,
            ],
            [
                9017.0 / 3168.0,
                -355.0 / 33.0,
                46732.0 / 5247.0,
                49.0 / 176.0,
                -5103.0 / 18656.0,
                0.0,
            ],
            [
                35.0 / 384.0,
                0.0,
                500.0 / 1113.0,
                125.0 / 192.0,
                -2187.0 / 6784.0,
                11.0 / 84.0,
            ],
        ];
        // 5th-order weights are A[6] (with 0 for k7); error weights b5 - b4:
        const E: [f64; 7] = [
            71.0 / 57600.0,
            0.0,
            -71.0 / 16695.0,
            71.0 / 1920.0,
            -17253.0 / 339200.0,
            22.0 / 525.0,
            -1.0 / 40.0,
        ];
        let dt = self.opt.dt;
        let t_end = t0 + dt;
        let mut t = t0;
        let mut h = self.h_last.min(dt);
        let mut rejected = 0usize;
        while t < t_end - 1e-14 * dt {
            h = h.min(t_end - t);
            let mut k: Vec<Mat<f64>> = Vec::with_capacity(7);
            for s in 0..7 {
                let mut xs = x.clone();
                for (j, kj) in k.iter().enumerate() {
                    if A[s][j] != 0.0 {
                        xs += kj * (h * A[s][j]);
                    }
                }
                k.push(self.rhs(t + C[s] * h, &xs, u, p)?);
            }
            let mut xn = x.clone();
            for j in 0..6 {
                if A[6][j] != 0.0 {
                    xn += &k[j] * (h * A[6][j]);
                }
            }
            let mut err = 0.0f64;
            for c in 0..x.ncols() {
                let mut s = 0.0;
                for i in 0..x.nrows() {
                    let mut e = 0.0;
                    for j in 0..7 {
                        e += E[j] * k[j][(i, c)];
                    }
                    let sc = atol + rtol * x[(i, c)].abs().max(xn[(i, c)].abs());
                    s += (h * e / sc).powi(2);
                }
                err = err.max((s / x.nrows().max(1) as f64).sqrt());
            }
            if !err.is_finite() {
                return Err(SysidError::numerical(
                    "adaptive integrator",
                    "the state became non-finite; the parameters make the model blow up",
                ));
            }
            if err <= 1.0 {
                t += h;
                *x = xn;
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
                };
                self.h_last = h * fac;
                h *= fac;
            } else {
                rejected += 1;
                if rejected > 10_000 || h < 1e-12 * dt {
                    return Err(SysidError::numerical(
                        "adaptive integrator",
                        "the step size fell below 1e-12 of the sample time (a stiff or \
                         blowing-up model); use integrator=\"rk4\" with more substeps",
                    ));
                }
                h *= (0.9 * err.powf(-0.2)).clamp(0.1, 1.0);
            }
        }
        Ok(())
    }

    /// Runs every experiment; `sink(e, t, residual, d yhat / d theta)` per sample
    /// (the derivative is `l x q`, empty without `jac`).
    fn run(&mut self, th: &[f64], jac: bool, sink: &mut Sink<'_>) -> Result<bool> {
        let q = th.len();
        let h = self.steps(th);
        let l = self.l;
        let dt = self.opt.dt;
        let exps = self.exps.clone();
        self.sens_cols = None;
        for (e, (u, y)) in exps.iter().enumerate() {
            let (p, mut x, cols) = self.columns(th, e, jac);
            let sens = jac && self.opt.jacobian == OdeJacobian::Sensitivity;
            self.sens_cols = sens.then(|| cols.clone());
            let kc = x.ncols();
            let mut ut = vec![0.0; u.ncols()];
            let mut res = vec![0.0; l];
            let mut dy = Mat::<f64>::zeros(l, if jac { q } else { 0 });
            self.h_last = dt;
            for t in 0..y.nrows() {
                for j in 0..ut.len() {
                    ut[j] = u[(t, j)];
                }
                let time = t as f64 * dt;
                if sens {
                    let yh = self.sensitivity_output(time, &x, &ut, &p, &cols, &mut dy)?;
                    let mut finite = true;
                    for i in 0..l {
                        res[i] = y[(t, i)] - yh[(i, 0)];
                        finite &= res[i].is_finite();
                    }
                    if !finite {
                        return Ok(false);
                    }
                    sink(&res, &dy, &cols);
                    if t + 1 < y.nrows() {
                        self.advance(time, &mut x, &ut, &p)?;
                    }
                    continue;
                }
                let yh = self.model.output(time, x.as_ref(), &ut, p.as_ref())?;
                if yh.nrows() != l || yh.ncols() != kc {
                    return Err(SysidError::invalid(
                        "h",
                        format!(
                            "returned a {}x{} array for {l} outputs and {kc} columns",
                            yh.nrows(),
                            yh.ncols()
                        ),
                    ));
                }
                let mut finite = true;
                for i in 0..l {
                    res[i] = y[(t, i)] - yh[(i, 0)];
                    finite &= res[i].is_finite();
                }
                if !finite {
                    return Ok(false);
                }
                if jac {
                    for (c, &k) in cols.iter().enumerate() {
                        for i in 0..l {
                            dy[(i, k)] = (yh[(i, c + 1)] - yh[(i, 0)]) / h[k];
                        }
                    }
                }
                sink(&res, &dy, &cols);
                if t + 1 < y.nrows() {
                    self.advance(time, &mut x, &ut, &p)?;
                }
            }
            self.sens_cols = None;
        }
        Ok(true)
    }

    /// `h` at the state in column 0, and `dy/dtheta = h_x S + h_p` into `dy`.
    fn sensitivity_output(
        &mut self,
        t: f64,
        x: &Mat<f64>,
        u: &[f64],
        p: &Mat<f64>,
        cols: &[usize],
        dy: &mut Mat<f64>,
    ) -> Result<Mat<f64>> {
        let nx = x.nrows();
        let np = p.nrows();
        let l = self.l;
        let xs: Vec<f64> = (0..nx).map(|i| x[(i, 0)]).collect();
        let ps: Vec<f64> = (0..np).map(|i| p[(i, 0)]).collect();
        let (h, hx, hp) = self
            .model
            .output_derivatives(t, &xs, u, &ps)?
            .ok_or_else(no_derivatives)?;
        check_derivatives("h", &h, &hx, &hp, l, nx, np)?;
        let hs = &hx * x;
        let nfp = self.st.free_p.len();
        for (c, &k) in cols.iter().enumerate() {
            for i in 0..l {
                dy[(i, k)] = hs[(i, c + 1)]
                    + if k < nfp {
                        hp[(i, self.st.free_p[k])]
                    } else {
                        0.0
                    };
            }
        }
        Ok(h)
    }

    /// Sample covariance of the simulation errors at `theta`.
    pub fn error_covariance(&mut self, th: &[f64]) -> Result<Mat<f64>> {
        if let Some((t, c)) = &self.last_cov {
            if t.as_slice() == th {
                return Ok(c.clone());
            }
        }
        let l = self.l;
        let mut lam = Mat::<f64>::zeros(l, l);
        let ok = self.run(th, false, &mut |e, _, _| {
            for i in 0..l {
                for j in 0..l {
                    lam[(i, j)] += e[i] * e[j];
                }
            }
        })?;
        if !ok {
            return Err(SysidError::numerical(
                "nonlinear grey-box",
                "the simulation is not finite at these parameters",
            ));
        }
        Ok(lam * (1.0 / self.n_samples as f64))
    }

    fn reweight_at(&mut self, th: &[f64]) -> Result<()> {
        let l = self.l;
        let mut lam = self.error_covariance(th)?;
        self.losses.push(determinant(&lam));
        let tr = (0..l).map(|i| lam[(i, i)]).sum::<f64>() / l.max(1) as f64;
        for i in 0..l {
            lam[(i, i)] += 1e-12 * tr.max(f64::MIN_POSITIVE);
        }
        let llt = lam.llt(Side::Lower).map_err(|_| {
            SysidError::numerical(
                "simulation-error weighting",
                "the error covariance is not positive definite",
            )
        })?;
        let mut rinv = Mat::<f64>::identity(l, l);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            llt.L(),
            rinv.as_mut(),
            faer::Par::Seq,
        );
        self.rinv = rinv;
        Ok(())
    }
}

fn no_derivatives() -> SysidError {
    SysidError::invalid(
        "jacobian",
        "the sensitivity equations need the model's derivatives (df/dx, df/dp, dh/dx, \
         dh/dp); give them, or use finite differences",
    )
}

fn check_derivatives(
    what: &'static str,
    v: &Mat<f64>,
    dx: &Mat<f64>,
    dp: &Mat<f64>,
    rows: usize,
    nx: usize,
    np: usize,
) -> Result<()> {
    if v.nrows() != rows
        || v.ncols() != 1
        || dx.nrows() != rows
        || dx.ncols() != nx
        || dp.nrows() != rows
        || dp.ncols() != np
    {
        return Err(SysidError::invalid(
            what,
            format!(
                "its derivatives have shapes {}x{}, {}x{}, {}x{}; expected {rows}x1, \
                 {rows}x{nx} (d/dx) and {rows}x{np} (d/dp, every parameter)",
                v.nrows(),
                v.ncols(),
                dx.nrows(),
                dx.ncols(),
                dp.nrows(),
                dp.ncols()
            ),
        ));
    }
    Ok(())
}

impl Problem for OdeProblem<'_> {
    fn n_params(&self) -> usize {
        self.st.free_p.len() + self.st.free_x0.len()
    }

    fn evaluate(&mut self, th: &[f64], jacobian: bool) -> Result<Evaluation> {
        let q = th.len();
        let l = self.l;
        let rinv = self.rinv.clone();
        let mut cost = 0.0;
        let mut g = vec![0.0; if jacobian { q } else { 0 }];
        let mut h = Mat::<f64>::zeros(if jacobian { q } else { 0 }, if jacobian { q } else { 0 });
        let mut we = vec![0.0; l];
        let mut jw = Mat::<f64>::zeros(l, q);
        let mut lam = Mat::<f64>::zeros(l, l);
        let ok = self.run(th, jacobian, &mut |e, dy, cols| {
            for i in 0..l {
                for j in 0..l {
                    lam[(i, j)] += e[i] * e[j];
                }
            }
            for i in 0..l {
                let mut v = 0.0;
                for j in 0..=i {
                    v += rinv[(i, j)] * e[j];
                }
                we[i] = v;
                cost += 0.5 * v * v;
            }
            if jacobian {
                // weighted Jacobian rows -R^-1 dy (only the columns this experiment moves)
                for &k in cols {
                    for i in 0..l {
                        let mut v = 0.0;
                        for j in 0..=i {
                            v += rinv[(i, j)] * dy[(j, k)];
                        }
                        jw[(i, k)] = -v;
                    }
                }
                for (a, &ka) in cols.iter().enumerate() {
                    for i in 0..l {
                        g[ka] += jw[(i, ka)] * we[i];
                    }
                    for &kb in &cols[..=a] {
                        let mut s = 0.0;
                        for i in 0..l {
                            s += jw[(i, ka)] * jw[(i, kb)];
                        }
                        h[(ka, kb)] += s;
                    }
                }
            }
        });
        let ok = match ok {
            Ok(v) => v,
            Err(e) if !jacobian && matches!(e, SysidError::Numerical { .. }) => false,
            Err(e) => return Err(e),
        };
        if !ok || !cost.is_finite() {
            return Ok(Evaluation::cost_only(f64::INFINITY));
        }
        self.last_cov = Some((th.to_vec(), lam * (1.0 / self.n_samples as f64)));
        for i in 0..h.nrows() {
            for j in 0..i {
                h[(j, i)] = h[(i, j)];
            }
        }
        Ok(Evaluation {
            cost,
            gradient: g,
            gauss_newton: h,
        })
    }

    /// With the re-estimated weighting: `det(Lambda)` at the last accepted point (see
    /// [`crate::pem::Predictor`]'s).
    fn criterion(&self) -> Option<f64> {
        if self.opt.reweight {
            self.losses.last().copied()
        } else {
            None
        }
    }

    fn accepted(&mut self, th: &[f64]) -> Result<bool> {
        if self.opt.reweight {
            self.reweight_at(th)?;
            return Ok(true);
        }
        let lam = self.error_covariance(th)?;
        self.losses.push(determinant(&lam));
        Ok(false)
    }
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
    let q = th0.len();
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
    let fixed = options
        .optim
        .fixed
        .clone()
        .unwrap_or_else(|| vec![false; q]);
    let covariance = free_covariance(&h, &fixed)?;
    Ok(OdeResult {
        theta,
        innovation_covariance: lam,
        covariance,
        n_samples: prob.n_samples,
        loss_history: prob.losses.clone(),
        rhs_calls: prob.rhs_calls,
        solution,
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
