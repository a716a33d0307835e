//! Separable least squares (variable projection) for one output's unit network, focus on
//! one-step prediction.
//!
//! The prediction `yhat = Phi(theta) c` is linear in `c = [d, l, a]` (offset, linear term,
//! output weights) and nonlinear in the unit parameters `theta`. For each `theta` the best
//! `c` is a linear least-squares solution, so the search runs on `theta` alone (Golub &
//! Pereyra) with the projected residual `r(theta) = (I - Phi Phi^+) y`:
//!
//! ```text
//! V(theta) = 1/2 |r|^2,   gradient = -D^T r,   H = D^T P D   (Kaufman's Gauss-Newton)
//! D = d(Phi c)/d theta at fixed c,   P = I - Phi Phi^+
//! ```
//!
//! The gradient is exact (`r` is orthogonal to the columns of `Phi`); Kaufman's matrix drops
//! the second-order term of the projector's derivative. Two streaming passes over the
//! records, each a [`QrAccumulator`]: `[Phi, y]` gives `c` and the cost by a
//! rank-revealing solve of the small triangular factor; `[Phi, D]` gives `H` as the
//! trailing block's `R22^T R22 = D^T P D`. No `N x p` matrix is stored.

use faer::Mat;

use super::model::UnitNetwork;
use super::units::UnitKind;
use crate::error::{Result, SysidError};
use crate::linalg::{mul_seq, pinv, QrAccumulator};
use crate::narx::regressors::{LagSpec, Record, Signal};
use crate::optim::{Evaluation, Problem};

/// Rows buffered between re-triangularisations of the streaming QR.
const CHUNK: usize = 256;

/// Singular values of the linear part below this fraction of the largest are dropped.
const RTOL: f64 = 1e-12;

/// The separable prediction-error problem of output `output` (see the module docs).
pub struct VarPro<'a> {
    spec: &'a LagSpec,
    shift: &'a [f64],
    scale: &'a [f64],
    records: &'a [Record<'a>],
    output: usize,
    kinds: Vec<UnitKind>,
    rows: usize,
}

impl<'a> VarPro<'a> {
    /// The problem of output `output` with units `kinds` on the records' lagged variables,
    /// standardised by `shift` and `scale`.
    pub fn new(
        spec: &'a LagSpec,
        shift: &'a [f64],
        scale: &'a [f64],
        records: &'a [Record<'a>],
        output: usize,
        kinds: Vec<UnitKind>,
    ) -> Result<Self> {
        let rows = spec.check_records(records)?;
        if output >= spec.n_outputs {
            return Err(SysidError::invalid("output", "no such output channel"));
        }
        if shift.len() != spec.n_vars() || scale.len() != spec.n_vars() {
            return Err(SysidError::invalid(
                "shift, scale",
                "one value per regressor",
            ));
        }
        Ok(Self {
            spec,
            shift,
            scale,
            records,
            output,
            kinds,
            rows,
        })
    }

    fn nz(&self) -> usize {
        self.spec.n_vars()
    }

    /// Number of linear parameters `1 + nz + n_units`.
    pub fn n_linear(&self) -> usize {
        1 + self.nz() + self.kinds.len()
    }

    fn for_rows(&self, f: impl FnMut(&[f64], f64)) -> Result<()> {
        for_each_row(
            self.spec,
            self.shift,
            self.scale,
            self.records,
            self.output,
            f,
        )
    }

    /// Writes the row `[1, z, g_1(z), ..]` of `Phi` into `row[..n_linear]` and, with `dp`,
    /// the unit gradients (`n_units x (nz + 1)`, unit after unit) into `dp`.
    #[inline]
    fn phi_row(&self, theta: &[f64], z: &[f64], row: &mut [f64], mut dp: Option<&mut [f64]>) {
        let nz = z.len();
        row[0] = 1.0;
        row[1..=nz].copy_from_slice(z);
        for (k, kind) in self.kinds.iter().enumerate() {
            let p = &theta[k * (nz + 1)..(k + 1) * (nz + 1)];
            let d = dp
                .as_deref_mut()
                .map(|d| &mut d[k * (nz + 1)..(k + 1) * (nz + 1)]);
            row[1 + nz + k] = kind.value_grad(p, z, d, None);
        }
    }

    /// The best linear parameters at `theta` and the cost `1/2 |r|^2` there.
    pub fn linear_at(&self, theta: &[f64]) -> Result<(Vec<f64>, f64)> {
        let q = self.n_linear();
        let mut acc = QrAccumulator::new(q + 1, CHUNK);
        let mut row = vec![0.0; q + 1];
        self.for_rows(|z, y| {
            self.phi_row(theta, z, &mut row, None);
            row[q] = y;
            acc.push_row(&row);
        })?;
        solve_triangular_ls(&acc.finish(), q)
    }

    /// The network of output `output` at `theta` (its linear parameters solved for).
    pub fn network(&self, theta: &[f64]) -> Result<UnitNetwork> {
        let (linear, cost) = self.linear_at(theta)?;
        if !cost.is_finite() {
            return Err(SysidError::numerical(
                "network least squares",
                "the units' values are not finite at these parameters",
            ));
        }
        Ok(UnitNetwork {
            kinds: self.kinds.clone(),
            theta: theta.to_vec(),
            linear,
        })
    }
}

impl Problem for VarPro<'_> {
    fn n_params(&self) -> usize {
        self.kinds.len() * (self.nz() + 1)
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let (c, cost) = self.linear_at(theta)?;
        if !jacobian || !cost.is_finite() {
            return Ok(Evaluation::cost_only(cost));
        }
        let (q, p, nz) = (self.n_linear(), self.n_params(), self.nz());
        let mut acc = QrAccumulator::new(q + p, CHUNK);
        let mut row = vec![0.0; q + p];
        let mut gradient = vec![0.0; p];
        self.for_rows(|z, y| {
            let (phi, d) = row.split_at_mut(q);
            self.phi_row(theta, z, phi, Some(d));
            let res = y - phi.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>();
            for k in 0..self.kinds.len() {
                let a = c[1 + nz + k];
                for v in &mut d[k * (nz + 1)..(k + 1) * (nz + 1)] {
                    *v *= a;
                }
            }
            for (g, dv) in gradient.iter_mut().zip(d.iter()) {
                *g -= dv * res;
            }
            acc.push_row(&row);
        })?;
        let r = acc.finish();
        let r22 = r.as_ref().submatrix(q, q, p, p);
        let gauss_newton: Mat<f64> = mul_seq(r22.transpose(), r22);
        Ok(Evaluation {
            cost,
            gradient,
            gauss_newton,
        })
    }

    fn n_residuals(&self) -> Option<usize> {
        Some(self.rows)
    }
}

/// From the triangular factor `R` (`(q + 1) x (q + 1)`) of `[Phi, y]`: the minimum-norm
/// least-squares `c` (singular values of `R11` below `1e-12` of the largest dropped) and
/// `1/2 |y - Phi c|^2`; an infinite cost when the factor is not finite.
pub(crate) fn solve_triangular_ls(r: &Mat<f64>, q: usize) -> Result<(Vec<f64>, f64)> {
    let r11 = r.as_ref().submatrix(0, 0, q, q);
    let qy: Vec<f64> = (0..q).map(|i| r[(i, q)]).collect();
    if !qy.iter().all(|v| v.is_finite()) || !r11.norm_max().is_finite() || !r[(q, q)].is_finite() {
        return Ok((vec![f64::NAN; q], f64::INFINITY));
    }
    let pi = pinv(r11, RTOL)?;
    let c: Vec<f64> = (0..q)
        .map(|i| (0..q).map(|j| pi[(i, j)] * qy[j]).sum())
        .collect();
    let mut miss = r[(q, q)] * r[(q, q)];
    for i in 0..q {
        let fit: f64 = (i..q).map(|j| r[(i, j)] * c[j]).sum();
        miss += (qy[i] - fit) * (qy[i] - fit);
    }
    Ok((c, 0.5 * miss))
}

/// Calls `f(z, y)` for every regression row of the records: the standardised lagged
/// variables `z = (x - shift) / scale` and the target `y_output(t)`, `t >= max_lag`; stops
/// on Ctrl-C (asked every 4096 rows).
pub(crate) fn for_each_row(
    spec: &LagSpec,
    shift: &[f64],
    scale: &[f64],
    records: &[Record<'_>],
    output: usize,
    mut f: impl FnMut(&[f64], f64),
) -> Result<()> {
    let nz = spec.n_vars();
    let (mut x, mut z) = (vec![0.0; nz], vec![0.0; nz]);
    for r in records {
        for t in spec.max_lag..r.y.nrows() {
            if t % 4096 == 0 {
                crate::interrupt::check()?;
            }
            spec.fill_with(t, &mut x, |s, ch, tt| match s {
                Signal::Output => r.y[(tt, ch)],
                _ => r.u[(tt, ch)],
            });
            for (((o, v), s), c) in z.iter_mut().zip(&x).zip(shift).zip(scale) {
                *o = (v - s) / c;
            }
            f(&z, r.y[(t, output)]);
        }
    }
    Ok(())
}
