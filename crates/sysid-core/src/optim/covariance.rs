//! Parameter covariance from the Gauss-Newton matrix, restricted to identifiable directions.

use crate::error::{Result, SysidError};
use faer::{Mat, MatRef};

/// The covariance of the parameters and what the data do not determine.
#[derive(Debug, Clone)]
pub struct Covariance {
    /// `scale * H^+` on the identifiable directions, p x p.
    pub covariance: Mat<f64>,
    /// Numerical rank of the Gauss-Newton matrix.
    pub rank: usize,
    /// Orthonormal basis (p x (p - rank)) of the directions the data do not determine.
    pub unidentifiable: Mat<f64>,
    /// Condition number of the Jacobi-scaled matrix on the identifiable directions.
    pub condition: f64,
}

/// The covariance `scale * H^+` of parameters estimated by minimising `1/2 r^T W r`, with
/// `H = J^T W J` the Gauss-Newton matrix at the optimum.
///
/// When `W` is the inverse of the noise covariance `scale` is 1; with `W = I` and white noise of
/// variance `sigma^2`, `scale = sigma^2`. The pseudo-inverse is taken after Jacobi scaling
/// (`D^-1 H D^-1`, `D = diag(H)^(1/2)`), dropping eigenvalues below `rtol` times the largest:
/// those directions (mapped back to the parameters and returned in `unidentifiable`) get zero
/// variance, so the caller can name them instead of reporting a huge number.
///
/// ```
/// use faer::mat;
/// use sysid_core::optim::covariance;
/// // Two parameters that only enter as their sum: one direction is not identifiable.
/// let h = mat![[1.0, 1.0], [1.0, 1.0]];
/// let c = covariance(h.as_ref(), 2.0, 1e-10).unwrap();
/// assert_eq!(c.rank, 1);
/// assert!((c.unidentifiable[(0, 0)] + c.unidentifiable[(1, 0)]).abs() < 1e-12);
/// ```
pub fn covariance(gauss_newton: MatRef<'_, f64>, scale: f64, rtol: f64) -> Result<Covariance> {
    let p = gauss_newton.nrows();
    if gauss_newton.ncols() != p {
        return Err(SysidError::ShapeMismatch {
            what: "gauss_newton".into(),
            expected: format!("({p}, {p})"),
            got: format!("({}, {})", p, gauss_newton.ncols()),
        });
    }
    if (0..p).any(|i| (0..p).any(|j| !gauss_newton[(i, j)].is_finite())) {
        // not the data's fault (they were checked on the way in): the search ended where
        // the model's sensitivities overflow
        return Err(SysidError::numerical(
            "covariance",
            "the Gauss-Newton matrix at the estimate is not finite: the model's sensitivities \
             overflow there (a search driven far from the data's scale, often by an offset \
             the model has no term for); remove the offsets (sysid.detrend) or give a start",
        ));
    }
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(SysidError::invalid(
            "scale",
            format!("must be finite and >= 0, got {scale}"),
        ));
    }
    if p == 0 {
        return Ok(Covariance {
            covariance: Mat::zeros(0, 0),
            rank: 0,
            unidentifiable: Mat::zeros(0, 0),
            condition: 1.0,
        });
    }
    let d: Vec<f64> = (0..p)
        .map(|i| {
            let v = gauss_newton[(i, i)];
            if v > 0.0 {
                v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let hs = Mat::from_fn(p, p, |i, j| {
        0.5 * (gauss_newton[(i, j)] + gauss_newton[(j, i)]) / (d[i] * d[j])
    });
    // on the calling thread for the small matrices of most models (see `small_par`)
    let (u, s) = super::dense::symmetric_eigen(&hs, "covariance (eigenvalues)")?;
    let lmax = (0..p).map(|i| s[i]).fold(0.0, f64::max);
    let keep: Vec<usize> = (0..p)
        .filter(|&i| s[i] > rtol * lmax && s[i] > 0.0)
        .collect();
    let drop: Vec<usize> = (0..p).filter(|i| !keep.contains(i)).collect();
    let lmin = keep.iter().map(|&i| s[i]).fold(f64::INFINITY, f64::min);
    // cov = (D^-1 U_k s_k^-1/2)(D^-1 U_k s_k^-1/2)^T * scale, one matrix product
    let f = Mat::from_fn(p, keep.len(), |i, j| {
        u[(i, keep[j])] / d[i] * (scale / s[keep[j]]).sqrt()
    });
    let mut cov = crate::linalg::mul(f.as_ref(), f.transpose());
    for i in 0..p {
        for j in 0..i {
            let m = 0.5 * (cov[(i, j)] + cov[(j, i)]);
            cov[(i, j)] = m;
            cov[(j, i)] = m;
        }
    }
    // Unidentifiable directions in parameter space: H D^-1 v = 0, orthonormalised.
    let mut null = Mat::from_fn(p, drop.len(), |i, j| u[(i, drop[j])] / d[i]);
    if null.ncols() > 0 {
        null = crate::linalg::thin_q_seq(null.as_ref());
    }
    Ok(Covariance {
        covariance: cov,
        rank: keep.len(),
        unidentifiable: null,
        condition: if keep.is_empty() {
            f64::INFINITY
        } else {
            lmax / lmin
        },
    })
}

/// The residual scale `s = 2 V / (n_residuals - rank)` that multiplies `(J^T W J)^+` when the
/// weights are inverse noise variances that are themselves estimated (from a few periods) or
/// the model does not explain the data exactly: about 1 when weights and model are right,
/// larger with estimated weights or model errors (the degrees of freedom are floored at 1).
/// The one rule for every weighted frequency-domain fit (`pem`, `greyest`, `tfest`, `oe`).
///
/// ```
/// use sysid_core::optim::residual_scale;
/// // cost 1/2 sum r^2 = 9 over 20 real residuals and 2 identifiable parameters: s = 1.
/// assert!((residual_scale(9.0, 20, 2) - 1.0).abs() < 1e-15);
/// assert_eq!(residual_scale(1.0, 2, 5), 2.0);
/// ```
pub fn residual_scale(cost: f64, n_residuals: usize, rank: usize) -> f64 {
    2.0 * cost / n_residuals.saturating_sub(rank).max(1) as f64
}
