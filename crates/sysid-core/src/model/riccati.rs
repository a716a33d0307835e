//! The discrete algebraic Riccati equation of the steady-state Kalman predictor.
//!
//! For `x(t+1) = A x + w`, `y = C x + v` with `E[w w^T] = Q`, `E[v v^T] = R`, `E[w v^T] = S`,
//! the stabilising solution P of
//!
//! ```text
//! P = A P A^T + Q - (A P C^T + S)(C P C^T + R)^{-1}(A P C^T + S)^T
//! ```
//!
//! gives the innovation-form gain `K = (A P C^T + S)(C P C^T + R)^{-1}` and the innovation
//! covariance `C P C^T + R`; `A - K C` has all eigenvalues inside the unit circle.
//!
//! The cross term is removed first (`Ā = A - S R^{-1} C`, `Q̄ = Q - S R^{-1} S^T`), then the
//! structure-preserving doubling algorithm (Chu, Fan and Lin 2005) converges quadratically to
//! the stabilising solution when one exists. The solution is checked: if `A - K C` is not
//! stable, or the iteration does not converge, [`SysidError::NoStabilizingSolution`] is
//! returned rather than a wrong gain.

use crate::error::{Result, SysidError};
use crate::linalg::{spectral_radius, symmetrize};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::{Mat, MatRef};

/// Solution of the predictor Riccati equation.
#[derive(Debug, Clone)]
pub struct KalmanSolution {
    /// State error covariance P (n x n).
    pub p: Mat<f64>,
    /// Innovation-form (predictor) gain K (n x l).
    pub k: Mat<f64>,
    /// Innovation covariance `C P C^T + R` (l x l).
    pub innovation_cov: Mat<f64>,
    /// Doubling iterations used.
    pub iterations: usize,
}

/// Solves the predictor DARE for (A, C, Q, R, S).
///
/// ```
/// use faer::mat;
/// use sysid_core::riccati::kalman_gain;
/// // scalar random walk observed in noise
/// let s = kalman_gain(mat![[1.0]].as_ref(), mat![[1.0]].as_ref(), mat![[1.0]].as_ref(),
///                     mat![[1.0]].as_ref(), mat![[0.0]].as_ref()).unwrap();
/// let p = (1.0 + 5f64.sqrt()) / 2.0;            // P = P + 1 - P^2 / (P + 1)
/// assert!((s.p[(0, 0)] - p).abs() < 1e-12);
/// ```
pub fn kalman_gain(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    q: MatRef<'_, f64>,
    r: MatRef<'_, f64>,
    s: MatRef<'_, f64>,
) -> Result<KalmanSolution> {
    let n = a.nrows();
    let l = c.nrows();
    let fail = |reason: String| SysidError::NoStabilizingSolution { reason };
    let checks: [(&'static str, MatRef<'_, f64>, usize, usize); 5] = [
        ("A", a, n, n),
        ("C", c, l, n),
        ("Q", q, n, n),
        ("R", r, l, l),
        ("S", s, n, l),
    ];
    for (what, m, rows, cols) in checks {
        if m.nrows() != rows || m.ncols() != cols {
            return Err(SysidError::ShapeMismatch {
                what: what.into(),
                expected: format!("({rows}, {cols})"),
                got: format!("({}, {})", m.nrows(), m.ncols()),
            });
        }
        crate::error::check_finite(what, m)?;
    }
    let r_llt = r
        .llt(faer::Side::Lower)
        .map_err(|_| fail("the output noise covariance R is not positive definite".into()))?;
    let rinv_c = r_llt.solve(c); // R^{-1} C
    let rinv_st = r_llt.solve(s.transpose()); // R^{-1} S^T
    let abar = a - s * &rinv_c; // A - S R^{-1} C
    let mut h = q - s * &rinv_st; // Q - S R^{-1} S^T
    symmetrize(&mut h);
    let mut g = c.transpose() * &rinv_c; // C^T R^{-1} C
    symmetrize(&mut g);
    // SDA in the "control" form with F = Ā^T
    let mut ak = abar.transpose().to_owned();
    let eye = Mat::<f64>::identity(n, n);
    let mut iterations = 0;
    let mut converged = n == 0;
    for it in 0..200 {
        iterations = it + 1;
        let w = &eye + &g * &h;
        let lu = w.partial_piv_lu();
        let winv_a = lu.solve(&ak); // W^{-1} A_k
        let winv_g = lu.solve(&g); // W^{-1} G_k
        let h_new = &h + ak.transpose() * &h * &winv_a;
        let g_new = &g + &ak * &winv_g * ak.transpose();
        let a_new = &ak * &winv_a;
        let diff = (&h_new - &h).norm_l2();
        let scale = h_new.norm_l2().max(1e-300);
        h = h_new;
        g = g_new;
        symmetrize(&mut h);
        symmetrize(&mut g);
        ak = a_new;
        if !h.norm_l2().is_finite() {
            return Err(fail("the doubling iteration diverged".into()));
        }
        if diff <= 1e-14 * scale || ak.norm_l2() < 1e-300 {
            converged = true;
            break;
        }
    }
    if !converged {
        return Err(fail(format!(
            "no convergence after {iterations} doubling steps"
        )));
    }
    let p = h;
    let cp = c * &p;
    let mut innov = &cp * c.transpose() + r;
    symmetrize(&mut innov);
    let apct_s = a * cp.transpose() + s; // A P C^T + S
    let innov_llt = innov.llt(faer::Side::Lower).map_err(|_| {
        fail("the innovation covariance C P C^T + R is not positive definite".into())
    })?;
    let k = innov_llt.solve(apct_s.transpose()).transpose().to_owned();
    let rho = spectral_radius((a - &k * c).as_ref())?;
    if rho.is_nan() || rho >= 1.0 {
        return Err(fail(format!(
            "the predictor A - K C has spectral radius {rho:.6} >= 1"
        )));
    }
    let _ = innov_llt.inverse();
    Ok(KalmanSolution {
        p,
        k,
        innovation_cov: innov,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::mat;

    #[test]
    fn satisfies_the_riccati_equation_with_cross_term() {
        let a = mat![[0.9, 0.2, 0.0], [-0.1, 0.7, 0.3], [0.0, 0.0, 0.5]];
        let c = mat![[1.0, 0.0, 1.0], [0.0, 1.0, 0.5]];
        let q = mat![[0.5, 0.1, 0.0], [0.1, 0.3, 0.05], [0.0, 0.05, 0.2]];
        let r = mat![[0.4, 0.1], [0.1, 0.3]];
        let s = mat![[0.05, 0.0], [0.0, 0.02], [0.01, 0.01]];
        let sol = kalman_gain(a.as_ref(), c.as_ref(), q.as_ref(), r.as_ref(), s.as_ref()).unwrap();
        let p = &sol.p;
        let apct_s = &a * p * c.transpose() + &s;
        let rhs = &a * p * a.transpose() + &q - &sol.k * apct_s.transpose();
        assert!((p - &rhs).norm_max() < 1e-12 * p.norm_max());
        assert!(spectral_radius((&a - &sol.k * &c).as_ref()).unwrap() < 1.0);
    }

    #[test]
    fn mismatched_shapes_are_errors_not_panics() {
        let a = mat![[0.5, 0.0], [0.0, 0.5]];
        let q = mat![[1.0, 0.0], [0.0, 1.0]];
        let r = mat![[1.0]];
        let s = mat![[0.0], [0.0]];
        let c_bad = mat![[1.0, 0.0, 0.0]];
        assert!(matches!(
            kalman_gain(
                a.as_ref(),
                c_bad.as_ref(),
                q.as_ref(),
                r.as_ref(),
                s.as_ref()
            ),
            Err(SysidError::ShapeMismatch { .. })
        ));
        let a_bad = mat![[0.5, 0.0]];
        let c = mat![[1.0, 0.0]];
        assert!(matches!(
            kalman_gain(
                a_bad.as_ref(),
                c.as_ref(),
                q.as_ref(),
                r.as_ref(),
                s.as_ref()
            ),
            Err(SysidError::ShapeMismatch { .. })
        ));
    }

    #[test]
    fn unstable_undetectable_mode_has_no_stabilizing_solution() {
        // an unstable mode invisible in y: no gain can stabilise A - K C
        let a = mat![[1.5, 0.0], [0.0, 0.5]];
        let c = mat![[0.0, 1.0]];
        let q = mat![[1.0, 0.0], [0.0, 1.0]];
        let r = mat![[1.0]];
        let s = mat![[0.0], [0.0]];
        assert!(matches!(
            kalman_gain(a.as_ref(), c.as_ref(), q.as_ref(), r.as_ref(), s.as_ref()),
            Err(SysidError::NoStabilizingSolution { .. })
        ));
    }
}
