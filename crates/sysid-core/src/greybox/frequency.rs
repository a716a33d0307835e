//! Grey-box parameters fitted to frequency-response lines (periodic data, or an FRD with its
//! noise variance).
//!
//! On the excited lines of periodic data in steady state the sampled structure's response
//! `G(z_k) = C (z_k I - A)^-1 B + D` is compared with the measured `G_k`, each entry weighted
//! by its inverse noise variance (the criterion of [`crate::pem::pem_frequency`]). The
//! residuals and their sensitivities to every entry of `A, B, C, D` are the state-space fit's
//! (`pem::frequency`, all entries free, no similarity orbit); the structure's map
//! `theta = (A, B, C, D)(p)` with its Jacobian `dtheta/dp` turns them into the problem in the
//! physical parameters ([`Reparameterized`]), searched by the shared optimiser. The covariance
//! of `p` is `s (J_p^T W J_p)^+` with `s = 2 V / (residuals - rank)`: about 1 when the model
//! explains the lines and the weights are the inverse variances, larger (and so honest) with
//! model errors or variances estimated from few periods.

use super::free_covariance;
use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::optim::{
    self, Covariance, Flow, Iteration, ParameterMap, Problem, Reparameterized, Solution,
};
use crate::pem::frequency::LineFit;
use crate::pem::Lines;
use faer::Mat;

/// The estimate of a linear grey-box structure on frequency-response lines.
#[derive(Debug, Clone)]
pub struct FrequencyFit {
    /// The outer parameters at the solution.
    pub p: Vec<f64>,
    /// `(A, B, C, D)` at the solution (row-major blocks).
    pub theta: Vec<f64>,
    /// What the search did (in the outer parameters).
    pub solution: Solution,
    /// Covariance of `p`: `residual_scale (J^T W J)^+` on the free parameters (fixed ones:
    /// zero rows and columns).
    pub covariance: Covariance,
    /// Real residuals in the cost (twice the weighted line entries).
    pub n_residuals: usize,
    /// `2 V / (n_residuals - rank)`.
    pub residual_scale: f64,
    /// Largest pole modulus of the sampled `A` at the solution.
    pub spectral_radius: f64,
}

/// Fits the parameters `p` of a linear grey-box structure to `lines` (see the module notes).
///
/// `map` gives, for `p`, `theta = (A, B, C, D)` (row-major blocks of the sampled model) and
/// `dtheta/dp`; `dims = (n, m, l)`. The sampled `A` must be stable at `p0` (a periodic steady
/// state); the search keeps it so.
///
/// ```
/// use faer::Mat;
/// use sysid_core::greybox::frequency::linear_frequency;
/// use sysid_core::optim::{self, Flow, ParameterMap};
/// use sysid_core::pem::Lines;
/// // G(z) = 1 / (z - a): A = a, B = 1, C = 1, D = 0
/// struct Map;
/// impl ParameterMap for Map {
///     fn map(&mut self, p: &[f64], jac: bool) -> sysid_core::Result<(Vec<f64>, Option<Mat<f64>>)> {
///         let m = jac.then(|| Mat::from_fn(4, 1, |i, _| if i == 0 { 1.0 } else { 0.0 }));
///         Ok((vec![p[0], 1.0, 1.0, 0.0], m))
///     }
/// }
/// let omega: Vec<f64> = (1..20).map(|k| 0.15 * k as f64).collect();
/// let g: Vec<(f64, f64)> = omega.iter().map(|w| {
///     let (c, s) = (w.cos() - 0.5, w.sin());
///     (c / (c * c + s * s), -s / (c * c + s * s))
/// }).collect();
/// let re = Mat::from_fn(19, 1, |k, _| g[k].0);
/// let im = Mat::from_fn(19, 1, |k, _| g[k].1);
/// let w = Mat::from_fn(19, 1, |_, _| 1.0);
/// let lines = Lines { omega: &omega, re: re.as_ref(), im: im.as_ref(), weight: w.as_ref() };
/// let r = linear_frequency((1, 1, 1), &lines, &mut Map, &[0.2], &optim::Options::default(),
///                          &mut |_| Flow::Continue).unwrap();
/// assert!((r.p[0] - 0.5).abs() < 1e-10);
/// ```
pub fn linear_frequency(
    dims: (usize, usize, usize),
    lines: &Lines<'_>,
    map: &mut dyn ParameterMap,
    p0: &[f64],
    options: &optim::Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<FrequencyFit> {
    let (n, m, l) = dims;
    let np = p0.len();
    let mut fit = LineFit::all_entries(lines, n, m, l)?;
    let n_res = fit.n_residuals_weighted();
    let fixed = options.fixed.clone().unwrap_or_else(|| vec![false; np]);
    let n_free = fixed.iter().filter(|&&f| !f).count();
    if n_res < n_free {
        return Err(SysidError::InsufficientData {
            context: format!("a grey-box structure with {n_free} free parameters"),
            needed: n_free,
            got: n_res,
            fix: "real residuals (twice the weighted line entries): excite more lines or fix \
                  parameters",
        });
    }
    let (th0, _) = map.map(p0, false)?;
    if th0.len() != fit.n_params() {
        return Err(SysidError::invalid(
            "structure",
            format!(
                "the parameter map gives {} matrix entries, (A, B, C, D) with n={n}, m={m}, \
                 l={l} needs {}",
                th0.len(),
                fit.n_params()
            ),
        ));
    }
    if !fit.admissible(&th0) {
        return Err(SysidError::invalid(
            "initial parameters",
            "the sampled A of the structure at the initial parameters has eigenvalues on or \
             outside the unit circle: periodic data in steady state need a stable system; \
             start from values that give a stable model, or estimate in the time domain \
             (no periods=)",
        ));
    }
    let solution = {
        let mut prob = Reparameterized::new(&mut fit, map, np);
        optim::minimize(&mut prob, p0, options, observer)?
    };
    let (theta, _) = map.map(&solution.theta, false)?;
    let unit = free_covariance(&solution.gauss_newton, &fixed)?;
    let residual_scale = optim::residual_scale(solution.cost, n_res, unit.rank);
    let covariance = Covariance {
        covariance: &unit.covariance * faer::Scale(residual_scale),
        ..unit
    };
    let a = Mat::from_fn(n, n, |i, j| theta[i * n + j]);
    let spectral = if n > 0 {
        spectral_radius(a.as_ref())?
    } else {
        0.0
    };
    Ok(FrequencyFit {
        p: solution.theta.clone(),
        theta,
        solution,
        covariance,
        n_residuals: n_res,
        residual_scale,
        spectral_radius: spectral,
    })
}
