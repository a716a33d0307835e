//! Running sums of a least-squares cost for problems that produce one scalar residual at a
//! time (the Hammerstein-Wiener predictors): the cost, the gradient and the lower triangle of
//! the Gauss-Newton matrix, mirrored once at the end.

use super::Evaluation;
use faer::Mat;

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
    gradient: Vec<f64>,
    gauss_newton: Mat<f64>,
    jacobian: bool,
}

impl NormalEquations {
    /// Empty sums for `p` parameters; without `jacobian` only the cost is kept.
    pub fn new(p: usize, jacobian: bool) -> Self {
        let q = if jacobian { p } else { 0 };
        NormalEquations {
            cost: 0.0,
            gradient: vec![0.0; q],
            gauss_newton: Mat::zeros(q, q),
            jacobian,
        }
    }

    /// Adds the residual `r = y - yhat` whose Jacobian is `-jr` (`jr = d yhat / d theta`;
    /// ignored when the sums were made without the Jacobian).
    pub fn add(&mut self, r: f64, jr: Option<&[f64]>) {
        self.cost += 0.5 * r * r;
        let Some(jr) = jr.filter(|_| self.jacobian) else {
            return;
        };
        for (a, &ja) in jr.iter().enumerate() {
            if ja != 0.0 {
                self.gradient[a] -= ja * r;
                for b in 0..=a {
                    self.gauss_newton[(a, b)] += ja * jr[b];
                }
            }
        }
    }

    /// The evaluation, with the Gauss-Newton matrix made symmetric from its lower triangle
    /// and a non-finite cost reported as infinite (the search then rejects the point).
    pub fn finish(mut self) -> Evaluation {
        super::mirror_lower(&mut self.gauss_newton);
        Evaluation {
            cost: if self.cost.is_finite() {
                self.cost
            } else {
                f64::INFINITY
            },
            gradient: self.gradient,
            gauss_newton: self.gauss_newton,
        }
    }
}
