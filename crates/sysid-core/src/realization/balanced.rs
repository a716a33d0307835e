//! Gramians, Hankel singular values and balanced truncation of stable discrete-time models.
//!
//! The controllability and observability gramians solve the discrete Lyapunov equations
//!
//! ```text
//! Wc = A Wc A^T + B B^T,      Wo = A^T Wo A + C^T C,
//! ```
//!
//! and the Hankel singular values are `sigma_i = sqrt(lambda_i(Wc Wo))`. The square-root
//! method (Laub et al. 1987) balances without forming `Wc Wo`: with factors `Wc = Lc Lc^T`,
//! `Wo = Lo Lo^T` and the SVD `Lo^T Lc = U Sigma V^T`, the transformation
//! `T = Lc V_r Sigma_r^{-1/2}`, `T^+ = Sigma_r^{-1/2} U_r^T Lo^T` gives the balanced model
//! `(T^+ A T, T^+ B, C T, D)` whose gramians both equal `diag(sigma_1..sigma_r)`. Keeping the
//! r largest sigma is balanced truncation, with the error bound
//! `||G - G_r||_inf <= 2 sum_{k>r} sigma_k`.

use crate::error::{Result, SysidError};
use crate::lyapunov::solve_discrete_lyapunov;
use crate::model::StateSpace;
use faer::{Mat, MatRef};

/// A balanced (possibly truncated) model with its transformation.
#[derive(Debug, Clone)]
pub struct Balanced {
    /// The balanced model of the requested order.
    pub model: StateSpace,
    /// All Hankel singular values of the original model, decreasing.
    pub hankel_singular_values: Vec<f64>,
    /// `T` (n x r): original state = T * balanced state (on the retained subspace).
    pub t: Mat<f64>,
    /// `T^+` (r x n): balanced state = T^+ * original state.
    pub t_inv: Mat<f64>,
    /// `2 sum` of the discarded Hankel singular values (bound on the H-infinity error).
    pub error_bound: f64,
}

/// Controllability and observability gramians `(Wc, Wo)` of a stable model.
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::gramians;
/// let sys = StateSpace::new(mat![[0.5]], mat![[1.0]], mat![[2.0]], mat![[0.0]]).unwrap();
/// let (wc, wo) = gramians(&sys).unwrap();
/// assert!((wc[(0, 0)] - 1.0 / 0.75).abs() < 1e-14);
/// assert!((wo[(0, 0)] - 4.0 / 0.75).abs() < 1e-14);
/// ```
pub fn gramians(sys: &StateSpace) -> Result<(Mat<f64>, Mat<f64>)> {
    let bb = &sys.b * sys.b.transpose();
    let cc = sys.c.transpose() * &sys.c;
    let wc = solve_discrete_lyapunov(sys.a.as_ref(), bb.as_ref())?;
    let wo = solve_discrete_lyapunov(sys.a.transpose(), cc.as_ref())?;
    Ok((wc, wo))
}

/// A square factor L with `L L^T = W` for a symmetric positive semi-definite W (negative
/// eigenvalues from round-off are set to zero).
fn psd_factor(w: MatRef<'_, f64>) -> Result<Mat<f64>> {
    let n = w.nrows();
    let (u, s) = crate::optim::symmetric_eigen(&w.to_owned(), "eigendecomposition of a gramian")?;
    Ok(Mat::from_fn(n, n, |i, j| u[(i, j)] * s[j].max(0.0).sqrt()))
}

struct SquareRoot {
    lc: Mat<f64>,
    lo: Mat<f64>,
    u: Mat<f64>,
    s: Vec<f64>,
    v: Mat<f64>,
}

fn square_root(sys: &StateSpace) -> Result<SquareRoot> {
    let (wc, wo) = gramians(sys)?;
    let lc = psd_factor(wc.as_ref())?;
    let lo = psd_factor(wo.as_ref())?;
    let prod = lo.transpose() * &lc;
    let (s, u, v) = crate::linalg::svd_both_seq("SVD in balancing", prod.as_ref())?;
    Ok(SquareRoot { lc, lo, u, s, v })
}

/// Hankel singular values of a stable model, decreasing.
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::hankel_singular_values;
/// let sys = StateSpace::new(mat![[0.5]], mat![[1.0]], mat![[2.0]], mat![[0.0]]).unwrap();
/// let hsv = hankel_singular_values(&sys).unwrap();
/// assert!((hsv[0] - 2.0 / 0.75).abs() < 1e-13);
/// ```
pub fn hankel_singular_values(sys: &StateSpace) -> Result<Vec<f64>> {
    crate::error::check_finite("A", sys.a.as_ref())?;
    if sys.n_states() == 0 {
        return Ok(vec![]);
    }
    Ok(square_root(sys)?.s)
}

/// Balanced truncation to `order` states (the `order` largest Hankel singular values).
///
/// Errors: an unstable model, an order of zero or above n, and an order that would keep a
/// zero Hankel singular value (a non-minimal part, which cannot be balanced).
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::balanced_truncation;
/// // a strong slow mode and a weak fast one
/// let sys = StateSpace::new(mat![[0.9, 0.0], [0.0, 0.1]], mat![[1.0], [0.01]],
///                           mat![[1.0, 0.01]], mat![[0.0]]).unwrap();
/// let red = balanced_truncation(&sys, 1).unwrap();
/// assert_eq!(red.model.n_states(), 1);
/// assert!((red.model.a[(0, 0)] - 0.9).abs() < 1e-3);
/// assert!(red.error_bound < 1e-3);
/// ```
pub fn balanced_truncation(sys: &StateSpace, order: usize) -> Result<Balanced> {
    let n = sys.n_states();
    if order == 0 || order > n {
        return Err(SysidError::invalid(
            "order",
            format!("the reduced order must be between 1 and the model's {n} states, got {order}"),
        ));
    }
    let sr = square_root(sys)?;
    let smax = sr.s[0];
    if sr.s[order - 1].is_nan() || sr.s[order - 1] <= smax * 1e-13 {
        let minimal = sr.s.iter().filter(|&&x| x > smax * 1e-13).count();
        return Err(SysidError::invalid(
            "order",
            format!(
                "the model has only {minimal} non-zero Hankel singular values (the rest of it is \
                 uncontrollable or unobservable), so {order} states cannot be balanced; \
                 truncate to order <= {minimal}"
            ),
        ));
    }
    let t = Mat::from_fn(n, order, |i, j| {
        let v = sr.v.col(j);
        (0..n).map(|k| sr.lc[(i, k)] * v[k]).sum::<f64>() / sr.s[j].sqrt()
    });
    let t_inv = Mat::from_fn(order, n, |i, j| {
        let u = sr.u.col(i);
        (0..n).map(|k| u[k] * sr.lo[(j, k)]).sum::<f64>() / sr.s[i].sqrt()
    });
    let a = &t_inv * &sys.a * &t;
    let b = &t_inv * &sys.b;
    let c = &sys.c * &t;
    let model = StateSpace::new(a, b, c, sys.d.clone())?;
    let error_bound = 2.0 * sr.s[order..].iter().sum::<f64>();
    Ok(Balanced {
        model,
        hankel_singular_values: sr.s,
        t,
        t_inv,
        error_bound,
    })
}

/// Balanced realisation keeping all n states (the model must be minimal).
///
/// ```
/// use faer::mat;
/// use sysid_core::StateSpace;
/// use sysid_core::realization::{balanced_realization, gramians};
/// let sys = StateSpace::new(mat![[0.5, 0.2], [0.0, 0.3]], mat![[1.0], [1.0]],
///                           mat![[1.0, -0.5]], mat![[0.0]]).unwrap();
/// let bal = balanced_realization(&sys).unwrap();
/// let (wc, wo) = gramians(&bal.model).unwrap();
/// assert!((wc[(0, 1)]).abs() < 1e-12 && (wc[(0, 0)] - wo[(0, 0)]).abs() < 1e-12);
/// ```
pub fn balanced_realization(sys: &StateSpace) -> Result<Balanced> {
    balanced_truncation(sys, sys.n_states())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::realization::testing::{markov_distance, random_system};

    #[test]
    fn balanced_gramians_are_equal_and_diagonal() {
        for (seed, (n, m, l)) in [(3, 1, 1), (6, 2, 3), (10, 3, 2)].iter().enumerate() {
            let sys = random_system(*n, *m, *l, 0.95, 40 + seed as u64);
            let bal = balanced_realization(&sys).unwrap();
            let (wc, wo) = gramians(&bal.model).unwrap();
            let hsv = &bal.hankel_singular_values;
            for i in 0..*n {
                for j in 0..*n {
                    let target = if i == j { hsv[i] } else { 0.0 };
                    assert!((wc[(i, j)] - target).abs() < 1e-9 * hsv[0], "case {seed}");
                    assert!((wo[(i, j)] - target).abs() < 1e-9 * hsv[0], "case {seed}");
                }
            }
            assert!(markov_distance(&bal.model, &sys, 50) < 1e-10);
        }
    }

    #[test]
    fn truncation_error_respects_the_bound() {
        let sys = random_system(8, 2, 2, 0.9, 77);
        let red = balanced_truncation(&sys, 4).unwrap();
        let h = sys.markov(400);
        let hr = red.model.markov(400);
        // the l1 norm of the impulse response error bounds the H-infinity error from above,
        // each Markov parameter's norm bounds it from below
        let worst = h
            .iter()
            .zip(&hr)
            .map(|(x, y)| (x - y).norm_l2())
            .fold(0.0, f64::max);
        assert!(worst <= red.error_bound * (1.0 + 1e-9));
    }

    #[test]
    fn unstable_or_nonminimal_models_are_errors() {
        let sys = StateSpace::new(
            faer::mat![[1.1]],
            faer::mat![[1.0]],
            faer::mat![[1.0]],
            faer::mat![[0.0]],
        )
        .unwrap();
        assert!(matches!(
            balanced_truncation(&sys, 1),
            Err(SysidError::InvalidArgument { .. })
        ));
        let nonmin = StateSpace::new(
            faer::mat![[0.5, 0.0], [0.0, 0.3]],
            faer::mat![[1.0], [0.0]],
            faer::mat![[1.0, 1.0]],
            faer::mat![[0.0]],
        )
        .unwrap();
        assert!(matches!(
            balanced_realization(&nonmin),
            Err(SysidError::InvalidArgument { .. })
        ));
        assert_eq!(balanced_truncation(&nonmin, 1).unwrap().model.n_states(), 1);
    }
}
