//! What the refinement is asked to do ([`PemOptions`], [`Focus`], [`InitialState`]) and what
//! it returns ([`PemResult`]). The rules that follow from the focus (whether K is estimated,
//! which matrix must be stable) are decided here, once.

use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::model::StateSpace;
use crate::optim::{self, Covariance, Solution};
use faer::{Mat, MatRef};
use std::str::FromStr;

/// What the predictor's errors are; parses from `"prediction"` and `"simulation"`.
///
/// ```
/// use sysid_core::pem::Focus;
/// assert_eq!("simulation".parse::<Focus>().unwrap(), Focus::Simulation);
/// assert!("sim".parse::<Focus>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Focus {
    /// One-step-ahead prediction errors of the innovation form (K estimated or fixed).
    Prediction,
    /// Simulation errors (K = 0).
    Simulation,
}

impl Focus {
    /// Its name as the option string (`"prediction"`, `"simulation"`).
    pub fn as_str(self) -> &'static str {
        match self {
            Focus::Prediction => "prediction",
            Focus::Simulation => "simulation",
        }
    }

    /// Whether K is a parameter: only for prediction, and only when asked.
    pub fn estimates_k(self, requested: bool) -> bool {
        requested && self == Focus::Prediction
    }
}

/// `FromStr` for an option whose values are a fixed table of names: the error names the
/// option and what it accepts.
macro_rules! parse_from_table {
    ($ty:ty, $name:literal, $what:literal, [$(($key:literal, $val:expr)),+ $(,)?]) => {
        impl FromStr for $ty {
            type Err = SysidError;

            fn from_str(s: &str) -> Result<Self> {
                choose($name, s, &[$(($key, $val)),+], $what)
            }
        }
    };
}

parse_from_table! { Focus, "focus", "must be \"prediction\" or \"simulation\"",
[("prediction", Focus::Prediction), ("simulation", Focus::Simulation)] }

/// The value named `s` in `table`, or an error on option `name` saying `what` is allowed.
fn choose<T: Clone>(name: &'static str, s: &str, table: &[(&str, T)], what: &str) -> Result<T> {
    table
        .iter()
        .find(|(key, _)| *key == s)
        .map(|(_, v)| v.clone())
        .ok_or_else(|| SysidError::invalid(name, format!("{what}, got {s:?}")))
}

/// The initial state of one experiment; `"estimate"` and `"zero"` parse to the first two.
///
/// ```
/// use sysid_core::pem::InitialState;
/// assert_eq!("zero".parse::<InitialState>().unwrap(), InitialState::Zero);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum InitialState {
    /// Estimated with the other parameters (started at its least-squares value).
    Estimate,
    /// Zero.
    Zero,
    /// A given value (length n), not estimated.
    Given(Vec<f64>),
}

parse_from_table! { InitialState, "x0", "entries must be \"estimate\", \"zero\" or an array",
[("estimate", InitialState::Estimate), ("zero", InitialState::Zero)] }

/// Options of [`pem`](super::pem). Build with `PemOptions::default()` and set fields.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct PemOptions {
    /// Prediction (default) or simulation errors.
    pub focus: Focus,
    /// Estimate D (`true`) or keep it at its start value (`false`, default).
    pub estimate_d: bool,
    /// Estimate K (default) or keep it fixed at its start value (prediction focus only).
    pub estimate_k: bool,
    /// Initial state per experiment; a single entry applies to all. Default: estimated.
    pub x0: Vec<InitialState>,
    /// Re-estimate the weighting `W = Lambda^-1` between iterations (default `true`);
    /// `false` keeps `W = I`.
    pub reweight: bool,
    /// Search in data-driven local coordinates (default `true`).
    pub local_coordinates: bool,
    /// Keep `A` itself stable as well as the predictor (MATLAB's `EnforceStability`; always
    /// so for simulation focus, where the predictor is `A`). `None` (default): for prediction
    /// focus from a stable start, `A` is kept stable unless an unstable model fits
    /// significantly better (a likelihood-ratio test at the 1 % level, see
    /// [`pem`](super::pem), made only when the stable search converged, not when it stopped
    /// at `max_iter` or was cancelled); `Some(false)`: only the predictor is kept stable.
    pub enforce_stability: Option<bool>,
    /// Search in the modal chart where it applies (default `true`; see `pem::chart`: no
    /// Kalman gain, a well-conditioned modal form; the result returns in the start's basis).
    pub modal_chart: bool,
    /// Samples per block in the accumulation of the normal equations.
    pub block: usize,
    /// Options of the search (tolerances, iteration cap, regularisation, ...).
    pub optim: optim::Options,
    /// The free parameters of a structure that maps its own parameters to the matrices (a
    /// grey box, a transfer function): the record's size is checked against them instead
    /// of the full realisation's `n^2 + n m + l n`. `None` (default): the full realisation.
    pub free_parameters: Option<usize>,
}

impl Default for PemOptions {
    fn default() -> Self {
        let o = optim::Options {
            max_iter: 50,
            tol_cost: 1e-6,
            // J^T W J costs O(N min(l, n) p^2), the gradient O(N n^2 p): chord steps
            reuse_gauss_newton: 3,
            // stop once the expected decrease is a hundredth of a residual variance
            tol_statistical: 1e-2,
            ..Default::default()
        };
        PemOptions {
            focus: Focus::Prediction,
            estimate_d: false,
            estimate_k: true,
            x0: vec![InitialState::Estimate],
            reweight: true,
            local_coordinates: true,
            modal_chart: true,
            enforce_stability: None,
            block: 128,
            optim: o,
            free_parameters: None,
        }
    }
}

/// The admissible set of the search, decided once for every caller: the predictor
/// `A - K C` (which is `A` when `K = 0`, as for simulation) has all poles inside the unit
/// circle, and so does `A` when `enforce_stability`.
///
/// ```
/// use faer::mat;
/// use sysid_core::pem::stable_enough;
/// let a = mat![[1.1]];
/// let (k, c) = (mat![[0.5]], mat![[1.0]]);
/// assert!(stable_enough(a.as_ref(), k.as_ref(), c.as_ref(), false));
/// assert!(!stable_enough(a.as_ref(), k.as_ref(), c.as_ref(), true));
/// ```
pub fn stable_enough(
    a: MatRef<'_, f64>,
    k: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    enforce_stability: bool,
) -> bool {
    stable_within(a, k, c, enforce_stability, 1.0)
}

/// The spectral radius a search admits once its start sits on the unit circle: a structure
/// that fixes an integrator (a grey box's pole at `s = 0`, sampled to `z = 1` to round-off)
/// keeps it there, where the errors grow at most linearly.
pub(crate) const MARGINAL_RADIUS: f64 = 1.0 + 1e-9;

/// [`stable_enough`] with the spectral radii below `limit` instead of 1
/// ([`MARGINAL_RADIUS`] admits a structural integrator).
pub(crate) fn stable_within(
    a: MatRef<'_, f64>,
    k: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    enforce_stability: bool,
    limit: f64,
) -> bool {
    matches!(bounded_radius(a, k, c, enforce_stability), Some(r) if r < limit)
}

/// The largest spectral radius a search's admissible set bounds: the predictor's `A - K C`,
/// and with `enforce_stability` also `A`'s (a continuous function of the model: the margin
/// a step turned along the boundary follows); `None` when an eigenvalue solve fails or
/// gives NaN.
pub(crate) fn bounded_radius(
    a: MatRef<'_, f64>,
    k: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    enforce_stability: bool,
) -> Option<f64> {
    let radius = |m: MatRef<'_, f64>| spectral_radius(m).ok().filter(|r| !r.is_nan());
    let abar = a - crate::linalg::mul(k, c);
    let r = radius(abar.as_ref())?;
    if enforce_stability {
        return radius(a).map(|ra| ra.max(r));
    }
    Some(r)
}

/// The refined model and what the search did.
#[derive(Debug, Clone)]
pub struct PemResult {
    /// The refined (A, B, C, D).
    pub sys: StateSpace,
    /// The refined Kalman gain (zero for simulation focus).
    pub k: Mat<f64>,
    /// The initial state of each experiment (estimated, zero or given).
    pub x0: Vec<Vec<f64>>,
    /// Sample covariance of the prediction errors at the solution, l x l.
    pub innovation_covariance: Mat<f64>,
    /// The free parameters at the solution (layout in [`Predictor`](super::Predictor)).
    pub theta: Vec<f64>,
    /// What the search did.
    pub solution: Solution,
    /// Covariance of `theta` from the Gauss-Newton matrix with `W = Lambda^-1`.
    pub covariance: Covariance,
    /// Number of samples used.
    pub n_samples: usize,
    /// `det(Lambda)` (the maximum-likelihood loss, MATLAB's "loss function") at the start and
    /// after every accepted iteration.
    pub loss_history: Vec<f64>,
    /// Spectral radius of the refined `A` (above 1: an unstable model, allowed only for
    /// prediction focus without `enforce_stability`).
    pub spectral_radius: f64,
}
