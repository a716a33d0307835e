//! The simulation errors of an [`OdeModel`] as an optimisation [`Problem`]: the checked
//! data and structure, the columns of the perturbed trajectories, the run over every
//! experiment and the accumulation of the cost and the normal equations.

use super::{Integrator, OdeJacobian, OdeModel, OdeOptions, OdeStructure, Sink};
use crate::error::{Result, SysidError};
use crate::greybox::determinant;
use crate::optim::{Evaluation, Problem};
use faer::{Mat, MatRef, Side};

/// Simulation errors of an [`OdeModel`] as an optimisation problem.
pub struct OdeProblem<'a> {
    pub(super) model: &'a mut dyn OdeModel,
    pub(super) exps: Vec<(MatRef<'a, f64>, MatRef<'a, f64>)>,
    pub(super) st: OdeStructure,
    pub(super) opt: OdeOptions,
    pub(super) l: usize,
    pub(super) rinv: Mat<f64>,
    pub(super) losses: Vec<f64>,
    pub(super) n_samples: usize,
    pub(super) rhs_calls: usize,
    /// Step size carried between sample intervals by the adaptive integrator.
    pub(super) h_last: f64,
    /// The error covariance at the last evaluated point (saves a simulation per reweight).
    pub(super) last_cov: Option<(Vec<f64>, Mat<f64>)>,
    /// While sensitivities are integrated: the searched index of every sensitivity column.
    pub(super) sens_cols: Option<Vec<usize>>,
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

    pub(super) fn steps(&self, th: &[f64]) -> Vec<f64> {
        th.iter()
            .zip(&self.st.typical)
            .map(|(v, t)| self.opt.fd_step * v.abs().max(t.abs()).max(1e-300))
            .collect()
    }

    /// Columns for experiment `e`: (P, X0, list of searched indices the columns perturb).
    pub(super) fn columns(
        &self,
        th: &[f64],
        e: usize,
        jac: bool,
    ) -> (Mat<f64>, Mat<f64>, Vec<usize>) {
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

    /// Runs every experiment; `sink(e, t, residual, d yhat / d theta)` per sample
    /// (the derivative is `l x q`, empty without `jac`).
    pub(super) fn run(&mut self, th: &[f64], jac: bool, sink: &mut Sink<'_>) -> Result<bool> {
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
                    if !residual(y.row(t), &yh, &mut res) {
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
                if !residual(y.row(t), &yh, &mut res) {
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

    pub(super) fn reweight_at(&mut self, th: &[f64]) -> Result<()> {
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

impl Problem for OdeProblem<'_> {
    fn n_params(&self) -> usize {
        self.st.free_p.len() + self.st.free_x0.len()
    }

    /// Every output of every sample is one residual of the cost `0.5 sum |R^-1 e|^2` (for
    /// the distance from the minimum at a cap; the grey-box searches set no statistical stop).
    fn n_residuals(&self) -> Option<usize> {
        Some(self.n_samples * self.l)
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
        crate::optim::mirror_lower(&mut h);
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

/// `res = y(t) - yhat` (column 0 of `yh`, the nominal point); whether every entry is finite.
fn residual(y: faer::RowRef<'_, f64>, yh: &Mat<f64>, res: &mut [f64]) -> bool {
    let mut finite = true;
    for (i, r) in res.iter_mut().enumerate() {
        *r = y[i] - yh[(i, 0)];
        finite &= r.is_finite();
    }
    finite
}
