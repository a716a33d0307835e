//! Multi-input multi-output Hammerstein-Wiener models with a state-space linear block.
//!
//! ```text
//! w_j(t) = f_j(u_j(t); alpha_j)               per-input static nonlinearity
//! x(t+1) = A x(t) + B w(t)                     linear block (state space, x(0) = 0)
//! v(t)   = C x(t) + D w(t)                     (D = 0 without feedthrough)
//! y_i(t) = g_i(v_i(t); beta_i) + e_i(t)        per-output static nonlinearity
//! ```
//!
//! Parameters `theta = [alpha_1..alpha_m, vec(A), vec(B), vec(C), (vec(D)), beta_1..beta_p]`
//! (matrices row-major), estimated by prediction error with the one optimiser
//! ([`crate::optim`]): the state sensitivities `S(t) = dx(t)/dtheta` (`n x P`) run
//! sample by sample, `S(t+1) = A S(t) + dA x(t) + dB w(t) + B dw(t)/dalpha`, and
//! `dy_i/dtheta = g_i'(v_i) (C S + dC x + D dw/dalpha + dD w)_i + dg_i/dbeta_i`. The full
//! state-space parametrisation is not identifiable (similarity transforms): the optimiser's
//! search basis takes the rank-deficient Gauss-Newton matrix, and the poles and the
//! nonlinearities, which are identifiable, are what the tests check. The unit-gain
//! normalisations of the nonlinearities ([`Nonlinearity`]) put the gains in `B` and `C`.
//! The admissible set is `A` stable.

use faer::{Mat, MatRef};

use super::Nonlinearity;
use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::optim::{
    minimize, Evaluation, Flow, Iteration, NormalEquations, Options, Problem, Solution,
};

/// The structure of a MIMO Hammerstein-Wiener model with a state-space linear block.
#[derive(Debug, Clone)]
pub struct MimoHwStructure {
    /// Input nonlinearities, one per input.
    pub inputs: Vec<Nonlinearity>,
    /// Output nonlinearities, one per output.
    pub outputs: Vec<Nonlinearity>,
    /// State dimension of the linear block.
    pub order: usize,
    /// Whether the linear block has a direct term `D`.
    pub feedthrough: bool,
}

/// Offsets of the parameter groups.
struct Layout {
    alpha: Vec<usize>,
    a: usize,
    b: usize,
    c: usize,
    d: usize,
    beta: Vec<usize>,
    total: usize,
}

impl MimoHwStructure {
    fn layout(&self) -> Layout {
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let mut off = 0;
        let alpha = self
            .inputs
            .iter()
            .map(|f| {
                off += f.n_params();
                off - f.n_params()
            })
            .collect();
        let a = off;
        let b = a + n * n;
        let c = b + n * m;
        let d = c + p * n;
        off = d + if self.feedthrough { p * m } else { 0 };
        let beta = self
            .outputs
            .iter()
            .map(|g| {
                off += g.n_params();
                off - g.n_params()
            })
            .collect();
        Layout {
            alpha,
            a,
            b,
            c,
            d,
            beta,
            total: off,
        }
    }

    /// Total number of parameters.
    pub fn n_params(&self) -> usize {
        self.layout().total
    }

    /// Checks the definition.
    pub fn check(&self) -> Result<()> {
        if self.inputs.is_empty() || self.outputs.is_empty() || self.order == 0 {
            return Err(SysidError::invalid(
                "structure",
                "needs at least one input, one output and order >= 1",
            ));
        }
        for f in self.inputs.iter().chain(&self.outputs) {
            f.check()?;
        }
        Ok(())
    }

    /// The matrices `(A, B, C, D)` of the linear block at `theta`.
    pub fn matrices(&self, theta: &[f64]) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
        let l = self.layout();
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let a = Mat::from_fn(n, n, |r, c| theta[l.a + r * n + c]);
        let b = Mat::from_fn(n, m, |r, c| theta[l.b + r * m + c]);
        let c = Mat::from_fn(p, n, |r, k| theta[l.c + r * n + k]);
        let d = Mat::from_fn(p, m, |r, k| {
            if self.feedthrough {
                theta[l.d + r * m + k]
            } else {
                0.0
            }
        });
        (a, b, c, d)
    }

    /// Noise-free outputs `(N, p)` for inputs `u` `(N, m)` at `theta`.
    pub fn simulate(&self, theta: &[f64], u: MatRef<'_, f64>) -> Mat<f64> {
        let mut y = Mat::<f64>::zeros(u.nrows(), self.outputs.len());
        self.run(theta, u, false, |t, i, yhat, _| y[(t, i)] = yhat);
        y
    }

    /// Runs the model; `visit(t, output, yhat, d yhat / d theta)` per sample and output (the
    /// row is empty unless `jacobian`).
    fn run(
        &self,
        theta: &[f64],
        u: MatRef<'_, f64>,
        jacobian: bool,
        mut visit: impl FnMut(usize, usize, f64, &[f64]),
    ) {
        let l = self.layout();
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let pp = l.total;
        let th = |k: usize| theta[k];
        let mut x = vec![0.0; n];
        let mut xn = vec![0.0; n];
        let mut w = vec![0.0; m];
        // dw_j / dalpha_j, stored per input at its alpha offset
        let mut dw = vec![0.0; pp];
        let mut s = if jacobian { vec![0.0; n * pp] } else { vec![] };
        let mut sn = if jacobian { vec![0.0; n * pp] } else { vec![] };
        let mut dv = vec![0.0; if jacobian { pp } else { 0 }];
        let mut row = vec![0.0; if jacobian { pp } else { 0 }];
        let mut dg = vec![0.0; pp];
        for t in 0..u.nrows() {
            for j in 0..m {
                let np = self.inputs[j].n_params();
                let a0 = l.alpha[j];
                w[j] = self.inputs[j]
                    .eval(&theta[a0..a0 + np], u[(t, j)], &mut dw[a0..a0 + np])
                    .0;
            }
            for i in 0..p {
                let mut v = 0.0;
                for k in 0..n {
                    v += th(l.c + i * n + k) * x[k];
                }
                if self.feedthrough {
                    for j in 0..m {
                        v += th(l.d + i * m + j) * w[j];
                    }
                }
                let nb = self.outputs[i].n_params();
                let b0 = l.beta[i];
                let (yhat, gd) = self.outputs[i].eval(&theta[b0..b0 + nb], v, &mut dg[b0..b0 + nb]);
                if jacobian {
                    // dv_i = C_i S + dC_i x + D_i dw + dD_i w
                    for k in 0..pp {
                        let mut acc = 0.0;
                        for r in 0..n {
                            acc += th(l.c + i * n + r) * s[r * pp + k];
                        }
                        dv[k] = acc;
                    }
                    for r in 0..n {
                        dv[l.c + i * n + r] += x[r];
                    }
                    if self.feedthrough {
                        for j in 0..m {
                            let dij = th(l.d + i * m + j);
                            let a0 = l.alpha[j];
                            for q in 0..self.inputs[j].n_params() {
                                dv[a0 + q] += dij * dw[a0 + q];
                            }
                            dv[l.d + i * m + j] += w[j];
                        }
                    }
                    for k in 0..pp {
                        row[k] = gd * dv[k];
                    }
                    for q in 0..nb {
                        row[b0 + q] += dg[b0 + q];
                    }
                }
                visit(t, i, yhat, &row);
            }
            // state update and sensitivities
            for r in 0..n {
                let mut acc = 0.0;
                for k in 0..n {
                    acc += th(l.a + r * n + k) * x[k];
                }
                for j in 0..m {
                    acc += th(l.b + r * m + j) * w[j];
                }
                xn[r] = acc;
            }
            if jacobian {
                for r in 0..n {
                    let out = &mut sn[r * pp..(r + 1) * pp];
                    out.iter_mut().for_each(|v| *v = 0.0);
                    for k in 0..n {
                        let a = th(l.a + r * n + k);
                        if a != 0.0 {
                            let src = &s[k * pp..(k + 1) * pp];
                            for q in 0..pp {
                                out[q] += a * src[q];
                            }
                        }
                    }
                    for k in 0..n {
                        out[l.a + r * n + k] += x[k];
                    }
                    for j in 0..m {
                        out[l.b + r * m + j] += w[j];
                        let brj = th(l.b + r * m + j);
                        let a0 = l.alpha[j];
                        for q in 0..self.inputs[j].n_params() {
                            out[a0 + q] += brj * dw[a0 + q];
                        }
                    }
                }
                std::mem::swap(&mut s, &mut sn);
            }
            std::mem::swap(&mut x, &mut xn);
        }
    }
}

/// The prediction-error problem of a MIMO Hammerstein-Wiener structure over several records.
pub struct MimoHwProblem<'a> {
    /// The structure.
    pub structure: MimoHwStructure,
    /// `(u (N, m), y (N, p))` records.
    pub records: Vec<(MatRef<'a, f64>, MatRef<'a, f64>)>,
}

impl Problem for MimoHwProblem<'_> {
    fn n_params(&self) -> usize {
        self.structure.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let mut sums = NormalEquations::new(self.n_params(), jacobian);
        for (u, y) in &self.records {
            self.structure.run(theta, *u, jacobian, |t, i, yhat, jr| {
                sums.add(y[(t, i)] - yhat, Some(jr))
            });
        }
        Ok(sums.finish())
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        if !theta.iter().all(|v| v.is_finite()) {
            return false;
        }
        let (a, _, _, _) = self.structure.matrices(theta);
        matches!(spectral_radius(a.as_ref()), Ok(r) if r < 1.0)
    }
}

/// Prediction-error estimate of a MIMO Hammerstein-Wiener model from `theta0` (for example
/// a linear state-space fit with identity-like nonlinearities).
pub fn estimate_mimo(
    structure: &MimoHwStructure,
    records: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    structure.check()?;
    if theta0.len() != structure.n_params() {
        return Err(SysidError::invalid(
            "theta0",
            format!("needs {} parameters", structure.n_params()),
        ));
    }
    let (m, p) = (structure.inputs.len(), structure.outputs.len());
    for (u, y) in records {
        crate::error::check_io("u, y", *u, *y, m, p)?;
    }
    let mut problem = MimoHwProblem {
        structure: structure.clone(),
        records: records.to_vec(),
    };
    if !problem.admissible(theta0) {
        return Err(SysidError::invalid(
            "theta0",
            "the starting linear block is unstable or not finite; start from a stable fit",
        ));
    }
    minimize(&mut problem, theta0, options, observer)
}

#[cfg(test)]
mod tests;
