//! Running sums of a least-squares cost for problems that produce one scalar residual at a
//! time (the Hammerstein-Wiener predictors, the simulation-focus network): the cost, the
//! gradient and the lower triangle of the Gauss-Newton matrix, mirrored once at the end.
//! [`NormalEquations::blocked`] buffers the Jacobian rows in blocks of [`BLOCK`] and folds
//! them in by one matrix product per block ([`gram_add`]) instead of rank-one updates: the
//! same sums, in another order of rounding (a nonconvex network fit, whose path that order
//! can move, keeps [`NormalEquations::new`]).

use super::{gram_add, small_par, Evaluation};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

/// Jacobian rows per block product.
const BLOCK: usize = 256;

/// Accumulates `1/2 sum r^2`, `J^T r` and `J^T J` residual by residual.
///
/// ```
/// use sysid_core::optim::NormalEquations;
/// let mut ne = NormalEquations::new(2, true);
/// ne.add(0.5, Some(&[1.0, 2.0])); // r = y - yhat, jr = d yhat / d theta
/// let ev = ne.finish();
/// assert_eq!(ev.cost, 0.125);
/// assert_eq!(ev.gradient, vec![-0.5, -1.0]);
/// assert_eq!(ev.gauss_newton[(0, 1)], 2.0);
/// ```
pub struct NormalEquations {
    cost: f64,
    gradient: Mat<f64>,
    gauss_newton: Mat<f64>,
    jacobian: bool,
    /// Buffered rows `jr`, one per column (p x BLOCK, each written contiguously), and
    /// residuals, `rows` of them filled.
    jt: Mat<f64>,
    rb: Mat<f64>,
    rows: usize,
    par: Par,
    blocked: bool,
}

impl NormalEquations {
    /// Empty sums for `p` parameters; without `jacobian` only the cost is kept. Every row
    /// is added as a rank-one update.
    pub fn new(p: usize, jacobian: bool) -> Self {
        Self::with(p, jacobian, false)
    }

    /// As [`Self::new`], the rows folded in blocks by one matrix product each: for long
    /// records and more than a few parameters, several times faster.
    ///
    /// ```
    /// use sysid_core::optim::NormalEquations;
    /// let (mut a, mut b) = (NormalEquations::new(2, true), NormalEquations::blocked(2, true));
    /// for t in 0..1000 {
    ///     let row = [1.0, t as f64 / 1000.0];
    ///     a.add(0.5 - row[1], Some(&row));
    ///     b.add(0.5 - row[1], Some(&row));
    /// }
    /// let (ea, eb) = (a.finish(), b.finish());
    /// assert!((ea.gauss_newton[(0, 1)] - eb.gauss_newton[(0, 1)]).abs() < 1e-9);
    /// assert!((ea.gradient[1] - eb.gradient[1]).abs() < 1e-9);
    /// ```
    pub fn blocked(p: usize, jacobian: bool) -> Self {
        Self::with(p, jacobian, true)
    }

    fn with(p: usize, jacobian: bool, blocked: bool) -> Self {
        let q = if jacobian { p } else { 0 };
        let b = if jacobian && blocked { BLOCK } else { 0 };
        NormalEquations {
            cost: 0.0,
            gradient: Mat::zeros(q, 1),
            gauss_newton: Mat::zeros(q, q),
            jacobian,
            jt: Mat::zeros(if b > 0 { q } else { 0 }, b),
            rb: Mat::zeros(b, 1),
            rows: 0,
            par: small_par(BLOCK, q),
            blocked,
        }
    }

    /// Adds the residual `r = y - yhat` whose Jacobian is `-jr` (`jr = d yhat / d theta`;
    /// ignored when the sums were made without the Jacobian).
    pub fn add(&mut self, r: f64, jr: Option<&[f64]>) {
        self.cost += 0.5 * r * r;
        let Some(jr) = jr.filter(|_| self.jacobian) else {
            return;
        };
        if !self.blocked {
            for (a, &ja) in jr.iter().enumerate() {
                if ja != 0.0 {
                    self.gradient[(a, 0)] -= ja * r;
                    for b in 0..=a {
                        self.gauss_newton[(a, b)] += ja * jr[b];
                    }
                }
            }
            return;
        }
        self.jt.col_as_slice_mut(self.rows).copy_from_slice(jr);
        self.rb[(self.rows, 0)] = r;
        self.rows += 1;
        if self.rows == BLOCK {
            self.flush();
        }
    }

    /// Folds the buffered rows into the sums.
    fn flush(&mut self) {
        if self.rows == 0 {
            return;
        }
        let jr = self.jt.as_ref().subcols(0, self.rows).transpose();
        gram_add(self.gauss_newton.as_mut(), jr, self.par);
        let rr = self.rb.as_ref().subrows(0, self.rows);
        matmul(
            self.gradient.as_mut(),
            Accum::Add,
            jr.transpose(),
            rr,
            -1.0,
            Par::Seq,
        );
        self.rows = 0;
    }

    /// The evaluation, with the Gauss-Newton matrix made symmetric from its lower triangle
    /// and a non-finite cost reported as infinite (the search then rejects the point).
    pub fn finish(mut self) -> Evaluation {
        self.flush();
        super::mirror_lower(&mut self.gauss_newton);
        Evaluation {
            cost: if self.cost.is_finite() {
                self.cost
            } else {
                f64::INFINITY
            },
            gradient: self.gradient.col_as_slice(0).to_vec(),
            gauss_newton: self.gauss_newton,
        }
    }
}
