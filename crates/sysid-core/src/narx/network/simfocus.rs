//! Refinement for free-run simulation (MATLAB's `Focus = "simulation"`): every parameter of
//! every output's nonlinearity (unit parameters and linear ones; for a tree partition the
//! leaves' affine coefficients, the partition fixed) minimises
//!
//! ```text
//! V = 1/2 sum_t |y(t) - ysim(t)|^2,    ysim(t) = F(z(t)),  z(t) from ysim(t-1..), u(t-nk..)
//! ```
//!
//! from measured initial outputs in each record. The Jacobian follows the recursion:
//!
//! ```text
//! d ysim_i(t) / d theta = dF_i/d theta_i + sum_v dF_i/dz_v / scale_v * d ysim_k(v)(t - lag_v) / d theta
//! ```
//!
//! over the lagged-output variables `v`, kept for the last `max_lag` samples, and the
//! normal equations are accumulated sample by sample.

use super::model::{NetworkNarx, Nonlinearity};
use crate::error::Result;
use crate::narx::regressors::{Record, Signal};
use crate::optim::{Evaluation, NormalEquations, Problem};

/// The simulation-error problem of a model over records (see the module docs).
pub struct SimFocus<'a> {
    model: NetworkNarx,
    records: &'a [Record<'a>],
    offsets: Vec<usize>,
    rows: usize,
}

fn n_own(nl: &Nonlinearity, nz: usize) -> usize {
    match nl {
        Nonlinearity::Network(n) => n.theta.len() + n.linear.len(),
        Nonlinearity::Tree(t) => t.nodes.len() * (nz + 1),
    }
}

/// Value of `nl` at `z`, its gradient with respect to its own parameters (`dth`) and to `z`.
fn value_grads(
    nl: &Nonlinearity,
    z: &[f64],
    dth: &mut [f64],
    dz: &mut [f64],
    tmp: &mut [f64],
) -> f64 {
    let nz = z.len();
    dth.iter_mut().for_each(|v| *v = 0.0);
    match nl {
        Nonlinearity::Network(n) => {
            let (dt, dl) = dth.split_at_mut(n.theta.len());
            dl[0] = 1.0;
            dl[1..=nz].copy_from_slice(z);
            dz.copy_from_slice(&n.linear[1..=nz]);
            let mut v = n.linear[0]
                + z.iter()
                    .zip(&n.linear[1..=nz])
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
            for (k, kind) in n.kinds.iter().enumerate() {
                let p = &n.theta[k * (nz + 1)..(k + 1) * (nz + 1)];
                let d = &mut dt[k * (nz + 1)..(k + 1) * (nz + 1)];
                let g = kind.value_grad(p, z, Some(d), Some(&mut tmp[..nz]));
                let a = n.linear[1 + nz + k];
                d.iter_mut().for_each(|x| *x *= a);
                for (o, w) in dz.iter_mut().zip(&tmp[..nz]) {
                    *o += a * w;
                }
                dl[1 + nz + k] = g;
                v += a * g;
            }
            v
        }
        Nonlinearity::Tree(t) => {
            let j = t.leaf(z);
            let c = &t.nodes[j].coefs;
            let d = &mut dth[j * (nz + 1)..(j + 1) * (nz + 1)];
            d[0] = 1.0;
            d[1..].copy_from_slice(z);
            dz.copy_from_slice(&c[1..]);
            c[0] + c[1..].iter().zip(z).map(|(a, b)| a * b).sum::<f64>()
        }
    }
}

impl<'a> SimFocus<'a> {
    /// The problem of `model` (its current parameters the start) over `records`.
    pub fn new(model: NetworkNarx, records: &'a [Record<'a>]) -> Result<Self> {
        let rows = model.spec.check_records(records)?;
        let nz = model.spec.n_vars();
        let mut offsets = vec![0];
        for nl in &model.outputs {
            offsets.push(offsets.last().copied().unwrap_or(0) + n_own(nl, nz));
        }
        let rows = rows * model_outputs(&offsets);
        Ok(Self {
            model,
            records,
            offsets,
            rows,
        })
    }

    /// The model's parameters, output after output (the search's coordinates).
    pub fn params(&self) -> Vec<f64> {
        let mut th = Vec::with_capacity(*self.offsets.last().unwrap_or(&0));
        for nl in &self.model.outputs {
            match nl {
                Nonlinearity::Network(n) => {
                    th.extend_from_slice(&n.theta);
                    th.extend_from_slice(&n.linear);
                }
                Nonlinearity::Tree(t) => t
                    .nodes
                    .iter()
                    .for_each(|nd| th.extend_from_slice(&nd.coefs)),
            }
        }
        th
    }

    /// The model at parameters `theta`.
    pub fn model_at(&self, theta: &[f64]) -> NetworkNarx {
        let mut m = self.model.clone();
        let nz = m.spec.n_vars();
        for (i, nl) in m.outputs.iter_mut().enumerate() {
            let own = &theta[self.offsets[i]..self.offsets[i + 1]];
            match nl {
                Nonlinearity::Network(n) => {
                    let k = n.theta.len();
                    n.theta.copy_from_slice(&own[..k]);
                    n.linear.copy_from_slice(&own[k..]);
                }
                Nonlinearity::Tree(t) => {
                    for (j, nd) in t.nodes.iter_mut().enumerate() {
                        nd.coefs
                            .copy_from_slice(&own[j * (nz + 1)..(j + 1) * (nz + 1)]);
                    }
                }
            }
        }
        m
    }
}

fn model_outputs(offsets: &[usize]) -> usize {
    offsets.len() - 1
}

impl Problem for SimFocus<'_> {
    fn n_params(&self) -> usize {
        *self.offsets.last().unwrap_or(&0)
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let m = self.model_at(theta);
        let (p, ny, nz, lag) = (
            self.n_params(),
            m.spec.n_outputs,
            m.spec.n_vars(),
            m.spec.max_lag,
        );
        let mut ne = NormalEquations::new(p, jacobian);
        let (mut x, mut z, mut tmp) = (vec![0.0; nz], vec![0.0; nz], vec![0.0; nz]);
        let mut dz = vec![0.0; nz];
        let width = self
            .offsets
            .windows(2)
            .map(|w| w[1] - w[0])
            .max()
            .unwrap_or(0);
        let mut dth = vec![0.0; width];
        let ring = lag + 1;
        let sp = if jacobian { p } else { 0 };
        let mut sens = vec![0.0; ring * ny * sp];
        let mut row = vec![0.0; sp];
        for r in self.records {
            let n = r.y.nrows();
            let mut ys = r.y.to_owned();
            sens.iter_mut().for_each(|v| *v = 0.0);
            for t in lag..n {
                {
                    let yr = ys.as_ref();
                    m.spec.fill_with(t, &mut x, |s, ch, tt| match s {
                        Signal::Output => yr[(tt, ch)],
                        _ => r.u[(tt, ch)],
                    });
                }
                m.standardise(&x, &mut z);
                let slot = t % ring;
                for i in 0..ny {
                    let (o0, o1) = (self.offsets[i], self.offsets[i + 1]);
                    let v = value_grads(&m.outputs[i], &z, &mut dth[..o1 - o0], &mut dz, &mut tmp);
                    if !v.is_finite() || v.abs() > 1e150 {
                        return Ok(Evaluation::cost_only(f64::INFINITY));
                    }
                    ys[(t, i)] = v;
                    if jacobian {
                        row.iter_mut().for_each(|s| *s = 0.0);
                        row[o0..o1].copy_from_slice(&dth[..o1 - o0]);
                        for (vi, var) in m.spec.vars.iter().enumerate() {
                            if var.signal != Signal::Output || t < lag + var.lag {
                                continue;
                            }
                            let w = dz[vi] / m.scale[vi];
                            if w == 0.0 {
                                continue;
                            }
                            let src = ((t - var.lag) % ring) * ny * p + var.channel * p;
                            for (o, s) in row.iter_mut().zip(&sens[src..src + p]) {
                                *o += w * s;
                            }
                        }
                        let dst = slot * ny * p + i * p;
                        sens[dst..dst + p].copy_from_slice(&row);
                    }
                    ne.add(r.y[(t, i)] - v, jacobian.then_some(&row[..]));
                }
            }
        }
        Ok(ne.finish())
    }

    fn n_residuals(&self) -> Option<usize> {
        Some(self.rows)
    }
}
