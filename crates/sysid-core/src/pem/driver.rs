//! The predictor as an [`optim::Problem`], the [`pem`] driver and the cheap [`criterion`] of
//! a given model.
//!
//! What the driver guarantees: the result's criterion is never above its start's (the start
//! is returned when the search could not improve on it); with simulation focus or
//! `enforce_stability = Some(true)` the model is stable; with the default
//! (`enforce_stability = None`) a prediction-focus model is stable unless an unstable one is
//! better by a likelihood-ratio test at the 1 % level, and [`PemResult::spectral_radius`]
//! says which.

use super::options::{Focus, InitialState, PemOptions, PemResult};
use super::predictor::Predictor;
use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::model::StateSpace;
use crate::optim::{self, Evaluation, Flow, Iteration, Problem, StopReason};
use faer::{Mat, MatRef};

/// The 99 % quantile of chi-square with one degree of freedom: the likelihood-ratio bound
/// an unstable model must pass to be preferred over the stable one.
const CHI2_1_99: f64 = 6.635;

/// Spectral radius of `A` at or above this after a search kept `A` stable, or a trial step
/// refused for an unstable `A`: the bound was (nearly) active, so the unconstrained search
/// is tried as well.
const NEAR_BOUNDARY: f64 = 0.999;

impl Problem for Predictor<'_> {
    fn n_params(&self) -> usize {
        self.p
    }

    fn evaluate(&mut self, th: &[f64], jacobian: bool) -> Result<Evaluation> {
        if !jacobian {
            return Ok(Evaluation::cost_only(self.cost_keeping_covariance(th)));
        }
        if !(self.structured && self.col_lo == 0 && self.n > 0) {
            return self.evaluate_rows(th);
        }
        match self.modal.then(|| self.modal_at(th)).flatten() {
            Some(md) => self.evaluate_modal(th, false, &md),
            None => self.evaluate_structured(th, false),
        }
    }

    fn n_residuals(&self) -> Option<usize> {
        Some(self.n_samples * self.l)
    }

    fn geodesic_gradient(&mut self, th: &[f64], v: &[f64], h: f64) -> Result<Option<Vec<f64>>> {
        self.second_difference_gradient(th, v, h)
    }

    fn admissible(&mut self, th: &[f64]) -> bool {
        self.is_admissible(th)
    }

    fn bound_margin(&mut self, th: &[f64]) -> Option<f64> {
        self.margin(th)
    }

    fn search_basis(&mut self, th: &[f64], scale: &[f64]) -> Result<Option<Mat<f64>>> {
        self.local_basis(th, scale)
    }

    fn invariant_directions(&mut self, th: &[f64]) -> Result<Option<Mat<f64>>> {
        Ok(self.orbit_tangent(th))
    }

    fn gradient_only(&mut self, th: &[f64]) -> Result<Option<Evaluation>> {
        if !(self.structured && self.col_lo == 0 && self.n > 0) {
            return Ok(None);
        }
        match self.modal.then(|| self.modal_at(th)).flatten() {
            Some(md) => self.evaluate_modal(th, true, &md).map(Some),
            None => self.evaluate_structured(th, true).map(Some),
        }
    }

    /// With the re-estimated weighting: `det(Lambda)` at the last accepted point (the
    /// weighted cost is `N l / 2` at every iterate; each accepted step lowers the determinant,
    /// since `tr(W_old Lambda_new) < l` and `det(W_old Lambda_new) <= (tr / l)^l`).
    fn criterion(&self) -> Option<f64> {
        self.reweight.then(|| self.losses.last().copied()).flatten()
    }

    fn accepted(&mut self, th: &[f64]) -> Result<bool> {
        if self.reweight {
            self.reweight_at(th)?;
            return Ok(true);
        }
        let loss = self.loss(th);
        self.losses.push(loss);
        Ok(false)
    }
}

impl Predictor<'_> {
    /// Starts the loss history at `theta`: the weighting from its errors when re-weighting
    /// (`W = I` otherwise) and `det(Lambda)` there.
    pub(crate) fn start_history(&mut self, th: &[f64]) -> Result<()> {
        self.losses.clear();
        self.rinv = Mat::identity(self.l, self.l);
        if self.reweight {
            return self.reweight_at(th);
        }
        let loss = self.loss(th);
        self.losses.push(loss);
        Ok(())
    }

    /// The criterion the search decreases at `theta` with the current weighting:
    /// `det(Lambda)` when re-weighting, `1/2 sum |e|^2` otherwise.
    fn criterion_at(&self, th: &[f64]) -> f64 {
        if self.reweight {
            self.loss(th)
        } else {
            self.cost(th)
        }
    }

    /// The start's parameters with estimated initial states at their least-squares values
    /// (the residual is linear in them: one Gauss-Newton step with the rest fixed).
    fn start_theta(
        &mut self,
        start: &StateSpace,
        k0: Option<MatRef<'_, f64>>,
        focus: Focus,
    ) -> Result<Vec<f64>> {
        let k_start = match (focus, k0) {
            (Focus::Prediction, Some(k)) => k.to_owned(),
            _ => self.k_fixed.clone(),
        };
        let x0s: Vec<Vec<f64>> = self
            .x0_mode
            .iter()
            .map(|s| match s {
                InitialState::Given(v) => v.clone(),
                _ => vec![0.0; self.n],
            })
            .collect();
        let theta = self.pack(start, k_start.as_ref(), &x0s);
        if !self.is_admissible(&theta) {
            return Err(SysidError::invalid(
                "start model",
                match (focus, self.enforce_stability) {
                    (Focus::Simulation, _) => {
                        "A of the start model is unstable: stabilise it first (for example \
                         reflect the unstable poles) or use focus=\"prediction\""
                    }
                    (Focus::Prediction, true) => {
                        "A or the predictor A - K C of the start model is unstable and \
                         enforce_stability is set: stabilise the start first"
                    }
                    (Focus::Prediction, false) => {
                        "the predictor A - K C of the start model is unstable: stabilise it \
                         first or start from a Kalman gain of the model"
                    }
                },
            ));
        }
        self.rinv = Mat::identity(self.l, self.l);
        Ok(self.x0_least_squares(&theta)?.map_or(theta, |(th, _)| th))
    }

    /// `theta` with the estimated initial states at their least-squares values for the rest
    /// of it (the residual is linear in them: one Gauss-Newton step with the rest fixed, under
    /// the current weighting) and that step's `(step norm, gradient norm, damping)` when it
    /// was taken; `None` without estimated initial states.
    #[allow(clippy::type_complexity)]
    fn x0_least_squares(
        &mut self,
        theta: &[f64],
    ) -> Result<Option<(Vec<f64>, Option<(f64, f64, f64)>)>> {
        let Some(lo) = self.x0_off.iter().flatten().copied().min() else {
            return Ok(None);
        };
        let mut fixed = vec![true; self.p];
        fixed[lo..].iter_mut().for_each(|f| *f = false);
        let o = optim::Options {
            max_iter: 1,
            initial_damping: 0.0,
            tol_gradient: 0.0,
            final_gauss_newton: false,
            fixed: Some(fixed),
            ..Default::default()
        };
        let local = self.local;
        self.local = false;
        self.col_lo = lo;
        let mut step = None;
        let sol = optim::minimize(self, theta, &o, &mut |it| {
            step = Some((it.step_norm, it.gradient_norm, it.damping));
            Flow::Continue
        });
        self.local = local;
        self.col_lo = 0;
        Ok(Some((sol?.theta, step)))
    }
}

/// The initial states of a finished search solved for exactly (least squares, the rest of
/// its parameters held), as one more iteration when one is left: a search that stops on a
/// tolerance can leave them short of their optimum where they move the errors over the whole
/// record (a mode held at the stability bound: on an aircraft's ground-vibration record the
/// exact states lowered the final cost by 6 %). The observer sees it as any iteration. When
/// it lowers the criterion by more than the cost tolerance and iterations are left, the
/// search goes on from there. Not with regularisation (its optimum is not the least-squares
/// one), initial states held fixed, nor after a search stopped at its cap or cancelled.
fn polish_x0(
    prob: &mut Predictor<'_>,
    mut sol: optim::Solution,
    options: &PemOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<optim::Solution> {
    let lo = prob
        .x0_off
        .iter()
        .flatten()
        .copied()
        .min()
        .unwrap_or(prob.p);
    let held = |f: &Vec<bool>| f.get(lo..).is_some_and(|x0| x0.iter().any(|&x| x));
    if matches!(sol.stop, StopReason::Cancelled | StopReason::MaxIterations)
        || sol.iterations >= options.optim.max_iter
        || options.optim.regularization.is_some()
        || options.optim.fixed.as_ref().is_some_and(held)
    {
        return Ok(sol);
    }
    let (losses, rinv) = (prob.losses.len(), prob.rinv.clone());
    let before = prob.criterion_at(&sol.theta);
    let Some((theta, Some((step_norm, gradient_norm, damping)))) =
        prob.x0_least_squares(&sol.theta)?
    else {
        return Ok(sol);
    };
    let after = prob.criterion_at(&theta);
    // a NaN criterion counts as no gain
    let gained = after < before - 1e-12 * before.abs();
    if !gained {
        prob.losses.truncate(losses);
        prob.rinv = rinv;
        return Ok(sol);
    }
    let weighted = prob.evaluate(&theta, false)?.cost;
    sol.theta = theta;
    sol.cost = after;
    sol.history.push(after);
    sol.weighted_history.push(weighted);
    sol.iterations += 1;
    sol.evaluations += 2; // the states' Jacobian and their step's trial
    sol.gauss_newton = Mat::zeros(0, 0);
    let flow = observer(&Iteration {
        iteration: sol.iterations,
        cost: after,
        weighted_cost: weighted,
        step_norm,
        gradient_norm,
        damping,
        theta: &sol.theta,
    });
    if flow == Flow::Stop {
        sol.stop = StopReason::Cancelled;
        return Ok(sol);
    }
    let left = options.optim.max_iter - sol.iterations;
    let gain = (before - after) / before.abs().max(f64::MIN_POSITIVE);
    if left == 0 || gain <= options.optim.tol_cost {
        return Ok(sol);
    }
    let mut o = options.optim.clone();
    o.max_iter = left;
    let done = sol.iterations;
    let more = optim::minimize(prob, &sol.theta, &o, &mut |it| {
        observer(&Iteration {
            iteration: done + it.iteration,
            ..it.clone()
        })
    })?;
    Ok(merge(sol, more))
}

/// One search from `theta` (the history started there); the start is kept when the search
/// ends above it.
fn search(
    prob: &mut Predictor<'_>,
    theta: &[f64],
    options: &PemOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<optim::Solution> {
    prob.start_history(theta)?;
    let start = prob.losses.last().copied().unwrap_or(f64::INFINITY);
    let start_cost = prob.criterion_at(theta);
    let sol = optim::minimize(prob, theta, &options.optim, observer)?;
    let mut sol = polish_x0(prob, sol, options, observer)?;
    let worse = if prob.reweight {
        prob.criterion_at(&sol.theta) > start
    } else {
        prob.criterion_at(&sol.theta) > start_cost
    };
    if worse {
        // never worse than the start: return it (its Gauss-Newton matrix is formed below)
        sol.theta = theta.to_vec();
        sol.stop = StopReason::NoDescent;
        sol.cost = sol.history[0];
        sol.gauss_newton = Mat::zeros(0, 0);
    }
    Ok(sol)
}

/// The likelihood-ratio statistic of an unconstrained criterion `free` against a constrained
/// one `kept` over `n` samples and `l` outputs (`det` criteria: `N ln(kept / free)`; sums of
/// squares: `N l ln(kept / free)`).
fn likelihood_ratio(kept: f64, free: f64, n: usize, l: usize, det: bool) -> f64 {
    let scale = if det { n } else { n * l } as f64;
    scale * (kept / free).ln()
}

/// Whether the data insist on the unconstrained fit (criterion `free`) over the one a
/// stability bound kept (`kept`), over `n` samples and `l` outputs (`det`: determinant
/// criteria, else sums of squares): the likelihood-ratio statistic and whether it exceeds
/// the 99 % quantile of chi-square with one degree of freedom (the 1 % level). The rule of
/// [`pem`]'s default stability choice, and of the estimators that keep their model stable
/// and warn when the data insist (`tfest`, `oe`).
///
/// ```
/// use sysid_core::pem::insists;
/// let (lr, yes) = insists(1.02, 1.0, 1000, 1, false);
/// assert!(yes && (lr - 1000.0 * 1.02f64.ln()).abs() < 1e-12);
/// assert!(!insists(1.001, 1.0, 1000, 1, false).1);
/// ```
pub fn insists(kept: f64, free: f64, n: usize, l: usize, det: bool) -> (f64, bool) {
    let lr = likelihood_ratio(kept, free, n, l, det);
    (lr, lr > CHI2_1_99)
}

/// Refines a start model by minimising its prediction (or simulation) errors over one or more
/// experiments `(u, y)`, each `(N_e, m)` and `(N_e, l)`.
///
/// The start must give a stable predictor (A - K C, or A for simulation); `k0` is its Kalman
/// gain (zero when `None`). The observer sees every accepted iteration and may stop the search.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::{StateSpace, simulate::simulate};
/// use sysid_core::pem::{pem, PemOptions, Focus};
/// use sysid_core::optim::Flow;
/// let truth = StateSpace::new(mat![[0.8]], mat![[1.0]], mat![[0.5]], mat![[0.0]]).unwrap();
/// let u = Mat::from_fn(200, 1, |t, _| ((t * 7919 % 13) as f64) - 6.0);
/// let y = simulate(&truth, u.as_ref(), None).unwrap();
/// let start = StateSpace::new(mat![[0.6]], mat![[1.0]], mat![[0.4]], mat![[0.0]]).unwrap();
/// let mut o = PemOptions::default();
/// o.focus = Focus::Simulation;
/// let r = pem(&start, None, &[(u.as_ref(), y.as_ref())], &o, &mut |_| Flow::Continue).unwrap();
/// assert!((r.sys.a[(0, 0)] - 0.8).abs() < 1e-8);
/// ```
pub fn pem(
    start: &StateSpace,
    k0: Option<MatRef<'_, f64>>,
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    options: &PemOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<PemResult> {
    match super::chart::modal_start(start, k0, options, experiments.len()) {
        Some((sys, chart, md)) => {
            let mut prob = Predictor::new(&sys, k0, experiments, options)?;
            let layout = Predictor::new(&sys, k0, experiments, options)?;
            prob.chart = Some(chart);
            let mask = prob.chart_mask();
            let mut charted = options.clone();
            let fixed = charted
                .optim
                .fixed
                .get_or_insert_with(|| vec![false; mask.len()]);
            if fixed.len() == mask.len() {
                fixed.iter_mut().zip(&mask).for_each(|(f, &h)| *f |= h);
            }
            let r = pem_from(prob, &sys, k0, &charted, observer)?;
            Ok(super::chart::to_start_basis(&layout, &md, r))
        }
        None => {
            let prob = Predictor::new(start, k0, experiments, options)?;
            pem_from(prob, start, k0, options, observer)
        }
    }
}

/// [`pem`] from a built problem.
fn pem_from(
    mut prob: Predictor<'_>,
    start: &StateSpace,
    k0: Option<MatRef<'_, f64>>,
    options: &PemOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<PemResult> {
    let auto = options.enforce_stability.is_none() && options.focus == Focus::Prediction;
    let a_stable = matches!(spectral_radius(start.a.as_ref()), Ok(r) if r < 1.0);
    // the default keeps A stable from a stable start; an unstable start is searched freely
    prob.enforce_stability = prob.enforce_stability || (auto && a_stable);
    let theta = prob.start_theta(start, k0, options.focus)?;
    let mut solution = search(&mut prob, &theta, options, observer)?;
    let mut losses = prob.losses.clone();
    let rho = |prob: &Predictor<'_>, th: &[f64]| {
        spectral_radius(prob.unpack(th).a.as_ref()).unwrap_or(f64::INFINITY)
    };
    let active = prob.a_bound_hits > 0 || rho(&prob, &solution.theta) >= NEAR_BOUNDARY;
    // the test compares two minima: a stable search stopped at its cap (or by the observer)
    // has not reached its own, and the free search from there lowers the cost by going on,
    // not by leaving the unit circle (the order-12 `ssest` of an aircraft structure's
    // ground-vibration record passed it that way with a pole at 1.0015); A stays stable
    let converged = !matches!(
        solution.stop,
        StopReason::MaxIterations | StopReason::Cancelled
    );
    if auto && a_stable && active && converged {
        // the bound was active: does an unstable model fit significantly better?
        prob.enforce_stability = false;
        let kept = solution.theta.clone();
        let free = search(&mut prob, &kept, options, observer)?;
        let (ck, cf) = (prob.criterion_at(&kept), prob.criterion_at(&free.theta));
        let (_, insist) = insists(ck, cf, prob.n_samples, prob.l, prob.reweight);
        if insist && rho(&prob, &free.theta) >= 1.0 {
            solution = merge(solution, free);
            losses.extend(prob.losses.iter().skip(1));
        } else {
            prob.enforce_stability = true;
        }
    }
    finish(prob, solution, losses)
}

/// At most this many multiply-adds (`N l p^2`) for the Gauss-Newton matrix at the end of a
/// search formed from every Jacobian row in `theta` (a few seconds).
const EXACT_ROWS_BUDGET: f64 = 2e10;

/// An output's mean square over its error variance beyond which the end of a search weighs
/// by the error covariance itself and forms its Gauss-Newton matrix from every row. The
/// structured matrix is formed in the predictor parameters and mapped to `theta`
/// (`normal::matrix_to_theta`), which cancels columns of the outputs' size into ones of the
/// errors' size after squaring them: about `log10` of this ratio of its 16 digits go (an
/// unstable model's growing state: 1e18 and more; a good fit of a clean record: 1e2 to 1e4).
/// Beyond it, too, the search's weighting floor ([`Predictor::reweight_at`]) exceeds 1e-6 of
/// the error variance, and every standard deviation would carry it (by 7e4 on a record whose
/// output grew by 1.03^800).
const OUTPUT_SHARE: f64 = 1e6;

/// Whether the Gauss-Newton matrix at the end of a search may be formed from every row: the
/// structured path formed it (the reference path forms every row already), the similarity
/// orbit is the whole of `K`'s too (`K` estimated or zero), within [`EXACT_ROWS_BUDGET`].
fn rows_allowed(prob: &Predictor<'_>) -> bool {
    let p = prob.p;
    let work = (prob.n_samples * prob.l) as f64 * (p * p) as f64;
    prob.n > 0
        && prob.structured
        && prob.col_lo == 0
        && (prob.est_k || prob.k_fixed.norm_max() == 0.0)
        && work <= EXACT_ROWS_BUDGET
}

/// The Gauss-Newton matrix at `theta` from every Jacobian row in `theta`.
fn exact_rows(prob: &mut Predictor<'_>, theta: &[f64]) -> Result<Mat<f64>> {
    let lo = prob.col_lo;
    prob.col_lo = 0;
    let ev = prob.evaluate_rows(theta);
    prob.col_lo = lo;
    Ok(ev?.gauss_newton)
}

/// `first` followed by `second` (started at `first`'s end): one report of both searches.
fn merge(first: optim::Solution, mut second: optim::Solution) -> optim::Solution {
    let mut history = first.history;
    history.extend(second.history.iter().skip(1));
    let mut weighted = first.weighted_history;
    weighted.extend(second.weighted_history.iter().skip(1));
    second.history = history;
    second.weighted_history = weighted;
    second.iterations += first.iterations;
    second.evaluations += first.evaluations;
    second.shortened += first.shortened;
    second.metric_switched_at = first
        .metric_switched_at
        .or(second.metric_switched_at.map(|k| k + first.iterations));
    second
}

/// The result at the solution, with the covariance from `W = Lambda^-1`.
fn finish(
    mut prob: Predictor<'_>,
    mut solution: optim::Solution,
    loss_history: Vec<f64>,
) -> Result<PemResult> {
    let t_finish = std::time::Instant::now();
    let theta = solution.theta.clone();
    let pm = prob.unpack(&theta);
    let lam = prob.innovation_covariance(&theta);
    let rows = rows_allowed(&prob);
    // outputs many orders above their errors: weighed by the errors' covariance itself, the
    // matrix from every row (see OUTPUT_SHARE)
    let dwarfed = prob.outputs_dwarf_errors(&lam, OUTPUT_SHARE) && prob.weigh_by(&lam).is_ok();
    let h = if dwarfed {
        prob.reweight = true;
        if rows {
            exact_rows(&mut prob, &theta)?
        } else {
            prob.evaluate(&theta, true)?.gauss_newton
        }
    } else if prob.reweight && solution.gauss_newton.nrows() == prob.p {
        solution.gauss_newton.clone()
    } else {
        prob.reweight = true;
        prob.reweight_at(&theta)?;
        prob.evaluate(&theta, true)?.gauss_newton
    };
    let t0 = std::time::Instant::now();
    let mut covariance = optim::covariance(h.as_ref(), 1.0, 1e-10)?;
    let mut h = h;
    let (n, p) = (prob.n, prob.p);
    // a rank test that missed the p - n^2 directions the orbit leaves, or a diagonal entry
    // J^T W J cannot have: the structured matrix lost its digits another way
    let odd = h.nrows() == p
        && (covariance.rank != p.saturating_sub(n * n) || (0..p).any(|i| h[(i, i)] <= 0.0));
    if rows && !dwarfed && odd {
        if let Ok(exact) = exact_rows(&mut prob, &theta) {
            if let Ok(c) = optim::covariance(exact.as_ref(), 1.0, 1e-10) {
                covariance = c;
                h = exact;
            }
        }
    }
    crate::optim::prof("covariance", t0);
    if solution.condition.is_nan() {
        // a large search does not form the eigenvalues; those of the covariance say the same
        solution.condition = covariance.condition;
    }
    // the matrix the covariance came from, for a caller's own test of it
    solution.gauss_newton = h;
    let radius = spectral_radius(pm.a.as_ref())?;
    crate::optim::prof("finish", t_finish);
    Ok(PemResult {
        sys: StateSpace::new(pm.a, pm.b, pm.c, pm.d)?,
        k: pm.k,
        x0: pm.x0,
        innovation_covariance: lam,
        theta,
        solution,
        covariance,
        n_samples: prob.n_samples,
        loss_history,
        spectral_radius: radius,
    })
}

/// The criterion [`pem`] would start from for `model` on the data, without searching: the initial
/// states fitted by least squares (where estimated), then `det(Lambda)` when `options.reweight`
/// (the maximum-likelihood loss) or `1/2 sum |e|^2` otherwise. One pass for the states and one
/// for the criterion: cheap enough to score many candidate models.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::{StateSpace, simulate::simulate};
/// use sysid_core::pem::{criterion, PemOptions, Focus};
/// let truth = StateSpace::new(mat![[0.8]], mat![[1.0]], mat![[0.5]], mat![[0.0]]).unwrap();
/// let u = Mat::from_fn(200, 1, |t, _| ((t * 7919 % 13) as f64) - 6.0);
/// let y = simulate(&truth, u.as_ref(), None).unwrap();
/// let mut o = PemOptions::default();
/// o.focus = Focus::Simulation;
/// o.reweight = false;
/// let c = criterion(&[(u.as_ref(), y.as_ref())], &truth, None, &o).unwrap();
/// assert!(c < 1e-20);
/// ```
pub fn criterion(
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    model: &StateSpace,
    k: Option<MatRef<'_, f64>>,
    options: &PemOptions,
) -> Result<f64> {
    let mut prob = Predictor::new(model, k, experiments, options)?;
    prob.enforce_stability = options.enforce_stability == Some(true);
    prob.enforce_stability |= options.focus == Focus::Simulation;
    let theta = prob.start_theta(model, k, options.focus)?;
    Ok(prob.criterion_at(&theta))
}
