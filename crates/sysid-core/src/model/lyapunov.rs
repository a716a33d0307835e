//! The discrete Lyapunov (Stein) equation `X = A X A^T + Q`.
//!
//! For a stable A (spectral radius below one) the unique solution is the convergent series
//! `X = sum_k A^k Q (A^T)^k`. Smith's doubling sums it in `O(log)` squarings:
//!
//! ```text
//! X_0 = Q, A_0 = A;   X_{j+1} = X_j + A_j X_j A_j^T,   A_{j+1} = A_j^2
//! ```
//!
//! so that `X_j` holds the first `2^j` terms. The iteration stops when the added term is below
//! a relative tolerance of the sum. An A with an eigenvalue on or outside the unit circle has
//! no such solution (the gramians diverge) and is reported as an error, never as a number.

use crate::error::{Result, SysidError};
use crate::linalg::{spectral_radius, symmetrize};
use faer::{Mat, MatRef};

/// Solves `X = A X A^T + Q` for a stable A by Smith's doubling.
///
/// Errors: A not square or Q of another size ([`SysidError::ShapeMismatch`]), non-finite
/// entries, A with spectral radius `>= 1` ([`SysidError::InvalidArgument`]) and
/// non-convergence ([`SysidError::Numerical`]).
///
/// ```
/// use faer::mat;
/// use sysid_core::lyapunov::solve_discrete_lyapunov;
/// // x(t+1) = 0.5 x(t) + w(t), var(w) = 1  =>  var(x) = 1 / (1 - 0.25)
/// let x = solve_discrete_lyapunov(mat![[0.5]].as_ref(), mat![[1.0]].as_ref()).unwrap();
/// assert!((x[(0, 0)] - 4.0 / 3.0).abs() < 1e-14);
/// ```
pub fn solve_discrete_lyapunov(a: MatRef<'_, f64>, q: MatRef<'_, f64>) -> Result<Mat<f64>> {
    let n = a.nrows();
    if a.ncols() != n {
        return Err(SysidError::ShapeMismatch {
            what: "A".into(),
            expected: "square".into(),
            got: format!("({}, {})", a.nrows(), a.ncols()),
        });
    }
    if q.nrows() != n || q.ncols() != n {
        return Err(SysidError::ShapeMismatch {
            what: "Q".into(),
            expected: format!("({n}, {n})"),
            got: format!("({}, {})", q.nrows(), q.ncols()),
        });
    }
    crate::error::check_finite("A", a)?;
    crate::error::check_finite("Q", q)?;
    if n == 0 {
        return Ok(Mat::zeros(0, 0));
    }
    let rho = spectral_radius(a)?;
    if rho >= 1.0 - 1e-12 {
        return Err(SysidError::invalid(
            "A",
            format!(
                "the model is not stable (spectral radius {rho:.6} >= 1), so its gramians and \
                 Hankel singular values do not exist; reduce only stable models, or split off \
                 the unstable part first"
            ),
        ));
    }
    let mut x = q.to_owned();
    symmetrize(&mut x);
    let mut ak = a.to_owned();
    let tol = 64.0 * f64::EPSILON;
    for _ in 0..200 {
        let term = &ak * &x * ak.transpose();
        x += &term;
        let size = x.norm_l1().max(f64::MIN_POSITIVE);
        if term.norm_l1() <= tol * size {
            symmetrize(&mut x);
            crate::error::check_finite("Lyapunov solution", x.as_ref())?;
            return Ok(x);
        }
        ak = &ak * &ak;
    }
    Err(SysidError::numerical(
        "discrete Lyapunov equation",
        format!("Smith doubling did not converge (spectral radius {rho:.12}, too close to 1)"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{rngs::StdRng, Rng, SeedableRng};

    fn random(n: usize, m: usize, rng: &mut StdRng) -> Mat<f64> {
        Mat::from_fn(n, m, |_, _| rng.random_range(-1.0..1.0))
    }

    #[test]
    fn residual_is_tiny_for_random_stable_matrices() {
        let mut rng = StdRng::seed_from_u64(7);
        for n in [1, 2, 5, 17, 40] {
            let mut a = random(n, n, &mut rng);
            let rho = spectral_radius(a.as_ref()).unwrap();
            a *= faer::Scale(0.97 / rho);
            let b = random(n, 2, &mut rng);
            let q = &b * b.transpose();
            let x = solve_discrete_lyapunov(a.as_ref(), q.as_ref()).unwrap();
            let res = &a * &x * a.transpose() + &q - &x;
            assert!(res.norm_max() < 1e-11 * x.norm_max(), "n = {n}");
        }
    }

    #[test]
    fn unstable_and_bad_shapes_are_errors() {
        let a = faer::mat![[1.0, 0.1], [0.0, 0.5]];
        let q = Mat::<f64>::identity(2, 2);
        assert!(matches!(
            solve_discrete_lyapunov(a.as_ref(), q.as_ref()),
            Err(SysidError::InvalidArgument { .. })
        ));
        let q3 = Mat::<f64>::identity(3, 3);
        assert!(matches!(
            solve_discrete_lyapunov(a.as_ref(), q3.as_ref()),
            Err(SysidError::ShapeMismatch { .. })
        ));
    }
}
