//! One Gauss-Newton / Levenberg-Marquardt search for every prediction-error estimator.
//!
//! A [`Problem`] provides, at a parameter vector `theta`, the cost
//!
//! ```text
//! V(theta) = 1/2 r(theta)^T W r(theta)
//! ```
//!
//! and, when asked, the gradient `g = J^T W r` and the Gauss-Newton matrix `H = J^T W J`
//! (`J = dr/dtheta`). Providers accumulate `g` and `H` over blocks of samples, so no `N x p`
//! Jacobian is ever stored and memory does not depend on the record length.
//!
//! [`minimize`] takes damped Gauss-Newton steps
//!
//! ```text
//! (D^-1 H D^-1 + mu I) D s = -D^-1 g,      D = diag(H)^(1/2)        (Marquardt scaling)
//! ```
//!
//! restricted to the free directions: fixed parameters (a mask), parameters held at an active
//! bound, and, when the provider supplies one, a basis of admissible search directions (for
//! example the orthogonal complement of the similarity orbit of a state-space model, the
//! data-driven local coordinates of McKelvey, Helmersson & Ribarits 2004). The damping `mu`
//! follows the ratio of actual to predicted decrease (a trust region in the scaled norm). A
//! trial point outside the bounds is projected onto them; a trial point the provider calls
//! inadmissible (an unstable predictor, say) is never evaluated: the step is halved until it
//! is admissible. Only points that decrease the cost are accepted, so the search never
//! diverges.
//!
//! A search in a provider's basis that crawls (its last five steps together took less than a
//! quarter of the decrease its Gauss-Newton model still predicts, worth more than a residual
//! variance) while its parameters' effects span more than six orders of magnitude changes
//! that basis's metric from the parameters to Marquardt's
//! ([`Problem::search_basis`], [`Solution::metric_switched_at`]); from then on a step that
//! finds no decrease is tried again in the plain basis, and a step that would leave the
//! admissible set is first turned along its boundary when the provider measures it
//! ([`Problem::bound_margin`]).
//!
//! With [`Options::geodesic`] each damped step `v` gets the geodesic acceleration of
//! Transtrum & Sethna (2012), `a = -(H + mu D)^-1 J^T W r_vv` with the same damped matrix and
//! `J^T W r_vv` from [`Problem::geodesic_gradient`]; the trial is `theta + v + a/2`.
//!
//! Regularisation toward a nominal value (MATLAB's `Regularization.Lambda/R/Nominal`) adds
//! `lambda/2 (theta - nominal)^T R (theta - nominal)` to the cost.
//!
//! [`Reparameterized`] shows a problem in other parameters `p` through a map
//! `theta = phi(p)` and its Jacobian (the chain rule on `g` and `H`): grey-box models reuse the
//! state-space predictor this way.
//!
//! [`covariance`] turns the Gauss-Newton matrix at the optimum into the parameter covariance,
//! a pseudo-inverse restricted to the identifiable directions, and returns the directions
//! the data do not determine.

mod boundary;
mod covariance;
pub(crate) mod dense;
mod normal;
mod reduced;
mod reparam;
mod search;
#[cfg(test)]
mod tests;

/// Test support: a problem's Gauss-Newton gradient against the central finite differences
/// of its cost (step `1e-6`), parameter by parameter, to `tol (1 + |g|)`.
#[cfg(test)]
pub(crate) fn assert_gradient_matches_cost<P: Problem>(
    pr: &mut P,
    th: &[f64],
    tol: f64,
    what: &str,
) {
    let ev = pr.evaluate(th, true).unwrap();
    for a in 0..th.len() {
        let h = 1e-6;
        let (mut tp, mut tm) = (th.to_vec(), th.to_vec());
        tp[a] += h;
        tm[a] -= h;
        let fd = (pr.evaluate(&tp, false).unwrap().cost - pr.evaluate(&tm, false).unwrap().cost)
            / (2.0 * h);
        let g = ev.gradient[a];
        assert!(
            (fd - g).abs() < tol * (1.0 + g.abs()),
            "{what} param {a}: fd {fd} vs {g}"
        );
    }
}

pub use covariance::{covariance, residual_scale, Covariance};
pub(crate) use dense::{
    clear_upper, flush_tiny, flush_tiny_mat, gram_add, mirror_lower, small_par, symmetric_eigen,
    FLUSH_EVERY,
};
pub use normal::NormalEquations;
pub use reparam::{ParameterMap, Reparameterized};
pub use search::minimize;
pub(crate) use search::prof;

use crate::error::Result;
use faer::Mat;

/// What a provider returns at one parameter vector.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// `1/2 r^T W r` (without the regularisation term; the search adds it).
    pub cost: f64,
    /// `J^T W r`, length p (empty when the Jacobian was not asked for).
    pub gradient: Vec<f64>,
    /// `J^T W J`, p x p (0 x 0 when the Jacobian was not asked for).
    pub gauss_newton: Mat<f64>,
}

impl Evaluation {
    /// An evaluation carrying only the cost.
    pub fn cost_only(cost: f64) -> Self {
        Evaluation {
            cost,
            gradient: Vec::new(),
            gauss_newton: Mat::zeros(0, 0),
        }
    }
}

/// A residual provider the search can minimise.
///
/// ```
/// use faer::Mat;
/// use sysid_core::optim::{minimize, Evaluation, Options, Problem, Flow};
///
/// // Fit y = a + b t to three points: linear least squares, solved in one step.
/// struct Line;
/// impl Problem for Line {
///     fn n_params(&self) -> usize { 2 }
///     fn evaluate(&mut self, th: &[f64], jac: bool) -> sysid_core::Result<Evaluation> {
///         let data = [(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)];
///         let mut ev = Evaluation::cost_only(0.0);
///         if jac { ev.gradient = vec![0.0; 2]; ev.gauss_newton = Mat::zeros(2, 2); }
///         for (t, y) in data {
///             let r = th[0] + th[1] * t - y;
///             ev.cost += 0.5 * r * r;
///             if jac {
///                 let j = [1.0, t];
///                 for a in 0..2 {
///                     ev.gradient[a] += j[a] * r;
///                     for b in 0..2 { ev.gauss_newton[(a, b)] += j[a] * j[b]; }
///                 }
///             }
///         }
///         Ok(ev)
///     }
/// }
/// let sol = minimize(&mut Line, &[0.0, 0.0], &Options::default(), &mut |_| Flow::Continue).unwrap();
/// assert!((sol.theta[0] - 1.0).abs() < 1e-9 && (sol.theta[1] - 2.0).abs() < 1e-9);
/// ```
pub trait Problem {
    /// Number of parameters p.
    fn n_params(&self) -> usize;
    /// The cost at `theta`; with `jacobian`, also the gradient and the Gauss-Newton matrix.
    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation>;
    /// `false` when `theta` is outside the admissible set; the search then shortens its step.
    fn admissible(&mut self, _theta: &[f64]) -> bool {
        true
    }
    /// A basis (p x q) of the directions the search may move in at `theta`, or `None` for all
    /// of them, orthonormal in the metric `diag(scale)` (`diag(scale) T` orthonormal).
    /// Recomputed at every iterate. `scale` (p, positive) is all ones (the parameters
    /// themselves: the similarity part of each step is then smallest in them) until the
    /// search crawls with effects orders of magnitude apart; from then on it is the metric the search damps its steps in (`sqrt` of
    /// the Gauss-Newton matrix's diagonal: Marquardt's scaling), which keeps that damping
    /// what it is without the basis, where a basis orthonormal in `theta` mixes parameters
    /// whose effects differ by orders of magnitude (an unstable plant) and the damped steps
    /// crawl ([`Solution::metric_switched_at`]).
    fn search_basis(&mut self, _theta: &[f64], _scale: &[f64]) -> Result<Option<Mat<f64>>> {
        Ok(None)
    }
    /// Called after each accepted step, before the Jacobian is formed there; the provider may
    /// change the definition of its cost (for example re-estimate a noise weighting). Return
    /// `true` when it did (informational: the search evaluates the new point afterwards anyway).
    fn accepted(&mut self, _theta: &[f64]) -> Result<bool> {
        Ok(false)
    }
    /// The criterion the search reports (in [`Solution::history`], [`Solution::cost`] and to
    /// the observer) at the start and at the point last passed to [`Problem::accepted`], when
    /// it is not the cost itself: a provider that re-defines its cost between steps (a noise
    /// weighting re-estimated from the residuals, which makes the weighted cost `N l / 2` at
    /// every iterate) reports what those steps decrease (the determinant of the residual
    /// covariance). `None` (the default): the cost with regularisation. The weighted cost is
    /// reported beside it ([`Solution::weighted_history`], [`Iteration::weighted_cost`]).
    fn criterion(&self) -> Option<f64> {
        None
    }
    /// Cost and gradient at `theta` without the Gauss-Newton matrix (left empty), when the
    /// provider forms them much more cheaply than a full evaluation; `None` (the default) when
    /// it cannot. Used only with [`Options::reuse_gauss_newton`] `> 0`.
    fn gradient_only(&mut self, _theta: &[f64]) -> Result<Option<Evaluation>> {
        Ok(None)
    }
    /// Directions (p x r, any basis) along which the cost is invariant at `theta`, such as the
    /// similarity orbit of a fully parameterised state-space model: null directions of the
    /// Gauss-Newton matrix there. A chord step of a large problem (the matrix of an earlier
    /// point with the gradient of the current one) removes them from the current gradient,
    /// which is not orthogonal to them, before solving with the tiny damping floor.
    /// `None` (the default): there are none, or the provider does not say.
    fn invariant_directions(&mut self, _theta: &[f64]) -> Result<Option<Mat<f64>>> {
        Ok(None)
    }
    /// How far `theta` lies beyond the boundary of the admissible set ([`Problem::admissible`]):
    /// negative inside, a continuous function of `theta` (for a state-space predictor, the
    /// largest spectral radius the set bounds, less its limit). `None` (the default): the
    /// provider has no such function. A step that would leave the set is then turned along
    /// the boundary (its part along this function's gradient removed) before it is halved.
    fn bound_margin(&mut self, _theta: &[f64]) -> Option<f64> {
        None
    }
    /// The number of scalar residuals in the cost (for [`Options::tol_statistical`]);
    /// `None` (the default) when the provider does not say.
    fn n_residuals(&self) -> Option<usize> {
        None
    }
    /// For [`Options::geodesic`]: `J(theta)^T W r_vv`, the Jacobian at `theta` times the
    /// residuals' second directional derivative along `v`, `r_vv = d^2/dt^2 r(theta + t v)`
    /// at `t = 0`, by finite differences with the step `h v` (`h` about 0.1: `v` is a whole
    /// search step). The search turns it into the geodesic acceleration of the step.
    /// `None` (the default): the provider cannot form it (or the difference points are
    /// inadmissible); the search then takes the plain step.
    fn geodesic_gradient(
        &mut self,
        _theta: &[f64],
        _v: &[f64],
        _h: f64,
    ) -> Result<Option<Vec<f64>>> {
        Ok(None)
    }
}

/// Regularisation toward a nominal value: `lambda/2 (theta - nominal)^T R (theta - nominal)`.
#[derive(Debug, Clone)]
pub struct Regularization {
    /// Weight lambda (>= 0).
    pub lambda: f64,
    /// Symmetric positive semi-definite p x p weighting; `None` means the identity.
    pub r: Option<Mat<f64>>,
    /// The nominal value (length p); `None` means zero.
    pub nominal: Option<Vec<f64>>,
}

/// Options of [`minimize`]. Build with `Options::default()` and set fields.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct Options {
    /// Maximum number of accepted iterations.
    pub max_iter: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub tol_cost: f64,
    /// Stop when the step is shorter than `tol_step * (tol_step + |theta|)`.
    pub tol_step: f64,
    /// Stop when the Gauss-Newton predicted decrease `g^T H^+ g / 2` is below
    /// `tol_gradient * cost` (first-order optimality, independent of scaling).
    pub tol_gradient: f64,
    /// Stop at statistical convergence: when the Gauss-Newton predicted decrease is below
    /// `tol_statistical * sigma^2`, with `sigma^2 = 2 cost / n` the residual variance
    /// ([`Problem::n_residuals`] residuals). A decrease that small moves the estimate by
    /// `sqrt(2 tol_statistical)` standard deviations at most and changes no test on it.
    /// Zero (the default) switches it off, as does a provider that does not count residuals.
    pub tol_statistical: f64,
    /// Lower bounds (length p; `-inf` for none), or `None`.
    pub lower: Option<Vec<f64>>,
    /// Upper bounds (length p; `+inf` for none), or `None`.
    pub upper: Option<Vec<f64>>,
    /// `true` for parameters that never move (length p), or `None`.
    pub fixed: Option<Vec<bool>>,
    /// Regularisation toward a nominal value, or `None`.
    pub regularization: Option<Regularization>,
    /// Initial Levenberg-Marquardt damping in the scaled problem.
    pub initial_damping: f64,
    /// Eigenvalues of the scaled Gauss-Newton matrix below `rank_tol * max` are treated as
    /// zero when reporting its condition and solving for the step.
    pub rank_tol: f64,
    /// After a step whose Gauss-Newton model predicted the actual decrease well (ratio above
    /// 0.75), up to this many consecutive iterations reuse the last Gauss-Newton matrix with
    /// a fresh gradient from [`Problem::gradient_only`] (a chord step) instead of forming
    /// `J^T J` again. A poorer step, or a stopping test met after a chord step, forms it anew;
    /// the solution always carries the Gauss-Newton matrix at its own point. Default 0 (never).
    pub reuse_gauss_newton: usize,
    /// Up to this many free parameters the damped steps come from an eigendecomposition of
    /// the scaled Gauss-Newton matrix reduced to the search basis
    /// ([`Problem::search_basis`]). Above it (a state-space model of order 20 with 28 outputs
    /// has 1580 parameters) the basis and the eigendecomposition, each `O(p^3)`, are skipped:
    /// every damped step is one Cholesky solve of the scaled full matrix plus a tiny shift.
    /// Similarity directions, an exact null space of `J^T W J` orthogonal to the gradient,
    /// then stay out of the step by themselves (the complement is taken in the Marquardt
    /// metric); the condition number is not computed (NaN). Default 400.
    pub eigen_limit: usize,
    /// Levenberg-Marquardt with geodesic acceleration (Transtrum & Sethna 2012): each damped
    /// step `v` gets the second-order correction `a = -(H + mu D)^-1 J^T W r_vv` (the same
    /// damped matrix, the right-hand side from [`Problem::geodesic_gradient`]) and the trial
    /// is `theta + v + a / 2`, refused (the damping raised) when `2 |a| / |v| > 0.75` in the
    /// scaled norm. Not on chord steps; a provider without the hook takes plain steps.
    /// Default `false`.
    pub geodesic: bool,
    /// Form the gradient and Gauss-Newton matrix at the point a search stopped on by
    /// `max_iter` ([`Solution::gauss_newton`], [`Solution::gradient`]; no stopping test
    /// needs them there). Default `true`; `false` when only the parameters are wanted (a
    /// one-step fit of the initial states: they stay empty and the step costs one
    /// evaluation less).
    pub final_gauss_newton: bool,
    /// Steps only where the data support them: in the eigenbasis of the scaled Gauss-Newton
    /// matrix, a direction whose own Gauss-Newton decrease `(v_k^T g)^2 / (2 lam_k)` is below
    /// `significance * sigma^2` (`sigma^2 = 2 cost / n`, [`Problem::n_residuals`]) is left out
    /// of the step and of the predicted decrease: its component's estimate is smaller than
    /// `sqrt(2 significance)` of its own standard deviation. `1` is the Akaike criterion's
    /// price of a parameter (a direction is taken when it lowers `sum r^2 / sigma^2` by more
    /// than 2). Needs the eigendecomposition (problems above `eigen_limit` free parameters
    /// use it too when this is on) and a provider that counts its residuals. Default `0`
    /// (off).
    pub significance: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_iter: 100,
            tol_cost: 1e-7,
            tol_step: 1e-9,
            tol_gradient: 1e-9,
            tol_statistical: 0.0,
            lower: None,
            upper: None,
            fixed: None,
            regularization: None,
            initial_damping: 1e-4,
            rank_tol: 1e-13,
            reuse_gauss_newton: 0,
            eigen_limit: 400,
            geodesic: false,
            final_gauss_newton: true,
            significance: 0.0,
        }
    }
}

/// Why the search stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The relative cost decrease fell below `tol_cost`.
    CostTolerance,
    /// The step fell below `tol_step`.
    StepTolerance,
    /// The predicted decrease fell below `tol_gradient * cost` (or the cost is zero).
    GradientTolerance,
    /// The predicted decrease fell below `tol_statistical` residual variances.
    Statistical,
    /// No damping produced a decrease of the cost: a (local) minimum to working precision.
    NoDescent,
    /// `max_iter` iterations were taken.
    MaxIterations,
    /// The observer asked to stop.
    Cancelled,
}

impl StopReason {
    /// A short lower-case name ("cost tolerance", ...).
    pub fn as_str(self) -> &'static str {
        match self {
            StopReason::CostTolerance => "cost tolerance",
            StopReason::StepTolerance => "step tolerance",
            StopReason::GradientTolerance => "gradient tolerance",
            StopReason::Statistical => "statistical convergence",
            StopReason::NoDescent => "no further decrease",
            StopReason::MaxIterations => "maximum iterations",
            StopReason::Cancelled => "cancelled",
        }
    }
}

/// Reported to the observer after every accepted step.
#[derive(Debug, Clone)]
pub struct Iteration<'a> {
    /// Iteration number, from 1.
    pub iteration: usize,
    /// The reported criterion after the step ([`Problem::criterion`]; by default the cost
    /// with regularisation).
    pub cost: f64,
    /// The cost the search minimises after the step (with regularisation, and with the
    /// weighting of the new point when the provider re-weights).
    pub weighted_cost: f64,
    /// Euclidean norm of the step taken.
    pub step_norm: f64,
    /// Infinity norm of the (free, reduced) gradient before the step.
    pub gradient_norm: f64,
    /// Damping used for the accepted step.
    pub damping: f64,
    /// The parameters after the step (the point `cost` was evaluated at), borrowed from the
    /// search: an observer that copies some can return one of them when the last iterate
    /// fails a check the search cannot make (as `pnlss` does with its fading-memory check).
    pub theta: &'a [f64],
}

/// What the observer tells the search.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Go on.
    Continue,
    /// Stop now, keeping the current point.
    Stop,
}

/// The result of [`minimize`].
#[derive(Debug, Clone)]
pub struct Solution {
    /// The final parameters.
    pub theta: Vec<f64>,
    /// The reported criterion at the solution ([`Problem::criterion`]; by default the cost
    /// with regularisation).
    pub cost: f64,
    /// The reported criterion at the start and after each accepted iteration.
    pub history: Vec<f64>,
    /// The cost the search minimises (with regularisation) at the start and after each
    /// accepted iteration; equal to `history` unless the provider reports a criterion.
    pub weighted_history: Vec<f64>,
    /// Accepted iterations.
    pub iterations: usize,
    /// Cost evaluations (including rejected trials).
    pub evaluations: usize,
    /// Why it stopped.
    pub stop: StopReason,
    /// `J^T W J` at the solution (without regularisation), p x p.
    pub gauss_newton: Mat<f64>,
    /// `J^T W r` at the solution (without regularisation).
    pub gradient: Vec<f64>,
    /// Condition number of the scaled reduced Gauss-Newton matrix at the last iterate
    /// (infinite when singular; NaN above [`Options::eigen_limit`] free parameters).
    pub condition: f64,
    /// Indices of parameters at a bound at the solution.
    pub active_bounds: Vec<usize>,
    /// With [`Options::geodesic`]: accelerations formed ([`Problem::geodesic_gradient`]
    /// calls that returned one), accepted steps that carried one, and trials refused by the
    /// acceleration's size (`2 |a| / |v| > 0.75`).
    pub geodesic: GeodesicCounts,
    /// Accepted steps that the admissible set shortened ([`Problem::admissible`]): a search
    /// that keeps meeting its boundary (a pole held at the unit circle) moves slowly.
    pub shortened: usize,
    /// A search stopped at [`Options::max_iter`]: how far it stood from the minimum of its
    /// Gauss-Newton model, the predicted decrease `g^T H^+ g / 2` at the solution in
    /// residual variances (`2 cost / n`, [`Problem::n_residuals`]). Twice it is the squared
    /// distance to that minimum in standard deviations of the estimate (the Mahalanobis
    /// distance under `H / sigma^2`): below 1/8 the estimate would move by less than half a
    /// standard deviation. NaN for any other stop, or when the provider does not count its
    /// residuals or the point was not evaluated with its Jacobian.
    pub remaining_decrease: f64,
    /// The iteration at which the search's local coordinates changed to a basis orthonormal
    /// in its own (Marquardt) metric because its steps crawled while its parameters' effects
    /// spanned more than six orders of magnitude (`None`: they did not, or the provider gives
    /// no basis). See [`Problem::search_basis`].
    pub metric_switched_at: Option<usize>,
}

/// What geodesic acceleration did in one search ([`Solution::geodesic`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GeodesicCounts {
    /// Accelerations formed (each costs the provider its second-difference passes).
    pub formed: usize,
    /// Accepted steps that carried an acceleration.
    pub accepted: usize,
    /// Trials refused because the acceleration was too large against the step.
    pub refused: usize,
}
