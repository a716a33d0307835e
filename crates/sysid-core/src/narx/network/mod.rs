//! Network nonlinearities of NARX models (MATLAB's `sigmoidnet`, `wavenet`,
//! `treepartition` for `nlarx`).
//!
//! Output `i` is a nonlinear function of the standardised lagged variables
//! `z = (x(t) - shift) / scale` (the [`LagSpec`](super::regressors::LagSpec) regressors):
//!
//! ```text
//! unit network:    y_i(t) = d + l^T z + sum_k a_k g(z; p_k)       (sigmoid or wavelet units)
//! tree partition:  y_i(t) = c0_j + c_j^T z,   j = the leaf whose cell holds z
//! ```
//!
//! * [`units`]: the unit functions `g` and their derivatives.
//! * [`model`]: the model, its free-run simulation and k-step prediction.
//! * [`varpro`]: training of a unit network for one-step prediction by separable least
//!   squares (variable projection with Kaufman's Jacobian) on the shared optimiser
//!   ([`crate::optim`]); `d`, `l`, `a` are solved exactly at every step.
//! * [`simfocus`]: refinement of every parameter for free-run simulation, with the
//!   sensitivities of the simulated outputs propagated through the recursion.
//! * [`tree`]: greedy growth of a tree partition with exact affine fits in the leaves.

pub mod model;
pub mod simfocus;
pub mod tree;
pub mod units;
pub mod varpro;

#[cfg(test)]
mod tests;

use crate::error::{Result, SysidError};
use crate::optim::{minimize, Flow, Iteration, Options, Solution};
use model::UnitNetwork;
use units::UnitKind;

use super::regressors::{LagSpec, Record};

/// Trains the unit network of output `output` for one-step prediction from the unit
/// parameters `theta0` ([`varpro::VarPro`] on [`minimize`]); returns the network (its
/// linear parameters solved at the optimum) and the search's report.
///
/// ```
/// use faer::Mat;
/// use sysid_core::narx::network::{fit_prediction, units::UnitKind};
/// use sysid_core::narx::regressors::{LagSpec, Record};
/// use sysid_core::optim::{Flow, Options};
/// // y(t) = 0.5 y(t-1) + sigmoid(2 u(t-1))
/// let n = 300;
/// let u = Mat::from_fn(n, 1, |t, _| ((t * 7919) % 101) as f64 / 50.0 - 1.0);
/// let mut y = Mat::<f64>::zeros(n, 1);
/// for t in 1..n {
///     y[(t, 0)] = 0.5 * y[(t - 1, 0)] + 1.0 / (1.0 + (-2.0 * u[(t - 1, 0)]).exp());
/// }
/// let spec = LagSpec::new(1, 1, &[1], &[1], &[1], &[0]).unwrap();
/// let recs = [Record::new(u.as_ref(), y.as_ref())];
/// let (shift, scale) = (vec![0.0, 0.0], vec![1.0, 1.0]);
/// let (net, sol) = fit_prediction(&spec, &shift, &scale, &recs, 0, vec![UnitKind::Sigmoid],
///     &[0.1, 1.5, 0.1], &Options::default(), &mut |_| Flow::Continue).unwrap();
/// assert!(sol.cost < 1e-20 && (net.theta[1] - 2.0).abs() < 1e-6);
/// ```
#[allow(clippy::too_many_arguments)]
pub fn fit_prediction(
    spec: &LagSpec,
    shift: &[f64],
    scale: &[f64],
    records: &[Record<'_>],
    output: usize,
    kinds: Vec<UnitKind>,
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<(UnitNetwork, Solution)> {
    let mut problem = varpro::VarPro::new(spec, shift, scale, records, output, kinds)?;
    if theta0.len() != crate::optim::Problem::n_params(&problem) {
        return Err(SysidError::invalid(
            "theta0",
            format!(
                "needs {} unit parameters (nz + 1 per unit), got {}",
                crate::optim::Problem::n_params(&problem),
                theta0.len()
            ),
        ));
    }
    let sol = minimize(&mut problem, theta0, options, observer)?;
    Ok((problem.network(&sol.theta)?, sol))
}

/// Refines every parameter of `model` for free-run simulation ([`simfocus::SimFocus`] on
/// [`minimize`]); returns the refined model and the search's report.
pub fn fit_simulation(
    model: model::NetworkNarx,
    records: &[Record<'_>],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<(model::NetworkNarx, Solution)> {
    let mut problem = simfocus::SimFocus::new(model, records)?;
    let theta0 = problem.params();
    let sol = minimize(&mut problem, &theta0, options, observer)?;
    Ok((problem.model_at(&sol.theta), sol))
}
