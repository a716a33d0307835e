//! The discrete-time state-space model and the equations every family solves on it.
//!
//! ```text
//! x(t+1) = A x(t) + B u(t) + K e(t)
//!   y(t) = C x(t) + D u(t) + e(t),        E[e e^T] = Λ
//! ```
//!
//! [`StateSpace`] holds the deterministic part (A, B, C, D) and its Markov parameters
//! `h_0 = D`, `h_k = C A^{k-1} B`. The submodules are the model's own computations, shared by
//! every estimator that produces one:
//!
//! - [`simulate`]: `y = C x + D u` run forward (simulation), and the predictor
//!   `x̂(t+1) = A x̂ + B u + K (y - C x̂ - D u)` with its k-step-ahead form;
//! - [`initial_state`]: simulation errors with the initial state and output offsets fitted
//!   by least squares (a model scored on a record it did not see);
//! - [`lyapunov`]: the gramian equation `X = A X A^T + Q` (stable A), for covariances and
//!   balanced realisation;
//! - [`riccati`]: the filter Riccati equation
//!   `P = A P A^T + Q - (A P C^T + S)(C P C^T + R)^{-1}(A P C^T + S)^T` whose stabilising
//!   solution gives the innovation gain `K` and covariance `Λ = C P C^T + R`.
//!
//! They are also reachable at the crate root (`sysid_core::simulate`, `sysid_core::lyapunov`,
//! `sysid_core::riccati`), their paths before they were grouped here.

pub mod initial_state;
pub mod lyapunov;
pub mod riccati;
pub mod simulate;

use crate::error::{Result, SysidError};
use faer::{Mat, MatRef};

/// A discrete-time linear state-space model (the deterministic part of an identified model).
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// let sys = StateSpace::new(mat![[0.5]], mat![[1.0]], mat![[2.0]], mat![[0.0]]).unwrap();
/// let h = sys.markov(3);
/// assert_eq!(h[1][(0, 0)], 2.0);      // C B
/// assert_eq!(h[2][(0, 0)], 1.0);      // C A B
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    /// State matrix, n x n.
    pub a: Mat<f64>,
    /// Input matrix, n x m.
    pub b: Mat<f64>,
    /// Output matrix, l x n.
    pub c: Mat<f64>,
    /// Feed-through matrix, l x m.
    pub d: Mat<f64>,
}

fn shape(m: MatRef<'_, f64>) -> String {
    format!("({}, {})", m.nrows(), m.ncols())
}

impl StateSpace {
    /// Builds a model after checking that the shapes agree and every entry is finite.
    pub fn new(a: Mat<f64>, b: Mat<f64>, c: Mat<f64>, d: Mat<f64>) -> Result<Self> {
        let n = a.nrows();
        let mismatch =
            |what: &str, expected: String, got: MatRef<'_, f64>| SysidError::ShapeMismatch {
                what: what.to_string(),
                expected,
                got: shape(got),
            };
        if a.ncols() != n {
            return Err(mismatch("A", format!("({n}, {n})"), a.as_ref()));
        }
        if b.nrows() != n {
            return Err(mismatch("B", format!("({n}, m)"), b.as_ref()));
        }
        if c.ncols() != n {
            return Err(mismatch("C", format!("(l, {n})"), c.as_ref()));
        }
        if d.nrows() != c.nrows() || d.ncols() != b.ncols() {
            return Err(mismatch(
                "D",
                format!("({}, {})", c.nrows(), b.ncols()),
                d.as_ref(),
            ));
        }
        for (name, m) in [("A", &a), ("B", &b), ("C", &c), ("D", &d)] {
            crate::error::check_finite(name, m.as_ref())?;
        }
        Ok(Self { a, b, c, d })
    }

    /// Number of states n.
    pub fn n_states(&self) -> usize {
        self.a.nrows()
    }
    /// Number of inputs m.
    pub fn n_inputs(&self) -> usize {
        self.b.ncols()
    }
    /// Number of outputs l.
    pub fn n_outputs(&self) -> usize {
        self.c.nrows()
    }

    /// The first `count` Markov parameters `D, CB, CAB, ...` (each l x m).
    pub fn markov(&self, count: usize) -> Vec<Mat<f64>> {
        let mut out = Vec::with_capacity(count);
        if count == 0 {
            return out;
        }
        out.push(self.d.clone());
        let mut ab = self.b.clone(); // A^k B
        for _ in 1..count {
            out.push(&self.c * &ab);
            ab = &self.a * &ab;
        }
        out
    }

    /// Eigenvalues of A as (re, im) pairs.
    pub fn poles(&self) -> Result<Vec<(f64, f64)>> {
        crate::linalg::eigenvalues(self.a.as_ref())
    }
}
