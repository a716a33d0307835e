//! The damped Gauss-Newton iteration of [`minimize`].

use super::boundary::{shape, Shaped};
use super::reduced::{reduce, Metric, Reduced, Solver};
use super::{Evaluation, Flow, GeodesicCounts, Iteration, Options, Problem, Solution, StopReason};
use crate::error::{Result, SysidError};
use faer::Mat;

/// Regularised cost, gradient and Gauss-Newton matrix at one point.
pub(super) struct Point {
    pub theta: Vec<f64>,
    pub cost: f64,
    /// Provider's own evaluation (without regularisation).
    pub raw: Evaluation,
    pub g: Vec<f64>,
    pub h: Mat<f64>,
}

impl Point {
    /// The Gauss-Newton diagonal's entry `i` when it is positive and finite (the square of
    /// Marquardt's scale of parameter `i`), else `None`.
    pub(super) fn diagonal(&self, i: usize) -> Option<f64> {
        let v = self.h[(i, i)];
        (v > 0.0 && v.is_finite()).then_some(v)
    }
}

/// Copies of the `p x p` normal equations a search holds at once: the evaluated point's and a
/// trial point's `J^T J`, the regularised and the reduced matrices, the eigenvectors and the
/// Cholesky factor.
const NORMAL_EQUATION_COPIES: usize = 6;

/// Checks, before a provider sizes anything by the parameter count, that the search's
/// normal equations fit in [`crate::error::MAX_MATRIX_BYTES`].
fn check_normal_equations(p: usize) -> Result<()> {
    let rows = p.saturating_mul(NORMAL_EQUATION_COPIES);
    crate::error::check_matrix_size("parameters", rows, p).map_err(|_| {
        SysidError::invalid(
            "parameters",
            format!(
                "the model has {p} parameters: the search's normal equations ({p} x {p}) and \
                 their working copies need {:.1} GiB, more than the {} GiB limit; use fewer \
                 parameters (lower orders, degrees, widths or branches)",
                rows as f64 * p as f64 * 8.0 / (1u64 << 30) as f64,
                crate::error::MAX_MATRIX_BYTES >> 30
            ),
        )
    })
}

fn check_options(p: usize, opt: &Options, theta0: &[f64]) -> Result<()> {
    check_normal_equations(p)?;
    if theta0.len() != p {
        return Err(SysidError::invalid(
            "theta0",
            format!(
                "has length {} but the problem has {p} parameters",
                theta0.len()
            ),
        ));
    }
    if let Some(i) = theta0.iter().position(|v| !v.is_finite()) {
        return Err(SysidError::invalid(
            "theta0",
            format!("entry {i} is not finite; start from finite parameters"),
        ));
    }
    for (name, v) in [("lower", &opt.lower), ("upper", &opt.upper)] {
        if let Some(v) = v {
            if v.len() != p {
                return Err(SysidError::invalid(
                    name,
                    format!(
                        "bounds have length {} but there are {p} parameters",
                        v.len()
                    ),
                ));
            }
        }
    }
    if let (Some(lo), Some(hi)) = (&opt.lower, &opt.upper) {
        if let Some(i) = (0..p).find(|&i| lo[i] > hi[i]) {
            return Err(SysidError::invalid(
                "lower",
                format!("lower bound {} exceeds upper bound {} at {i}", lo[i], hi[i]),
            ));
        }
    }
    if let Some(f) = &opt.fixed {
        if f.len() != p {
            return Err(SysidError::invalid(
                "fixed",
                format!("mask has length {} but there are {p} parameters", f.len()),
            ));
        }
    }
    if let Some(reg) = &opt.regularization {
        if !(reg.lambda >= 0.0 && reg.lambda.is_finite()) {
            return Err(SysidError::invalid(
                "regularization",
                format!("lambda must be finite and >= 0, got {}", reg.lambda),
            ));
        }
        if let Some(r) = &reg.r {
            if r.nrows() != p || r.ncols() != p {
                return Err(SysidError::invalid(
                    "regularization",
                    format!("R must be {p} x {p}, got {} x {}", r.nrows(), r.ncols()),
                ));
            }
        }
        if let Some(n) = &reg.nominal {
            if n.len() != p {
                return Err(SysidError::invalid(
                    "regularization",
                    format!(
                        "nominal has length {} but there are {p} parameters",
                        n.len()
                    ),
                ));
            }
        }
    }
    if opt.max_iter == 0 && opt.tol_cost < 0.0 {
        return Err(SysidError::invalid("tol_cost", "must be >= 0"));
    }
    Ok(())
}

/// Adds the regularisation term; returns (cost, g, h) with h empty when `raw` has none.
fn regularise(opt: &Options, theta: &[f64], raw: &Evaluation) -> (f64, Vec<f64>, Mat<f64>) {
    let p = theta.len();
    let mut cost = raw.cost;
    let mut g = raw.gradient.clone();
    let mut h = raw.gauss_newton.clone();
    if let Some(reg) = &opt.regularization {
        if reg.lambda > 0.0 {
            let d: Vec<f64> = (0..p)
                .map(|i| theta[i] - reg.nominal.as_ref().map_or(0.0, |n| n[i]))
                .collect();
            let rd: Vec<f64> = match &reg.r {
                Some(r) => (0..p)
                    .map(|i| (0..p).map(|j| r[(i, j)] * d[j]).sum())
                    .collect(),
                None => d.clone(),
            };
            cost += 0.5 * reg.lambda * d.iter().zip(&rd).map(|(a, b)| a * b).sum::<f64>();
            if !g.is_empty() {
                for i in 0..p {
                    g[i] += reg.lambda * rd[i];
                    for j in 0..p {
                        let rij = match &reg.r {
                            Some(r) => r[(i, j)],
                            None => f64::from(u8::from(i == j)),
                        };
                        h[(i, j)] += reg.lambda * rij;
                    }
                }
            }
        }
    }
    (cost, g, h)
}

pub(crate) fn prof(what: &str, t0: std::time::Instant) {
    if std::env::var_os("SYSID_PROFILE").is_some() {
        eprintln!("PROF {what} {:.6}", t0.elapsed().as_secs_f64());
    }
}

fn evaluate_point(
    problem: &mut dyn Problem,
    opt: &Options,
    theta: Vec<f64>,
    evals: &mut usize,
) -> Result<Point> {
    *evals += 1;
    let t0 = std::time::Instant::now();
    crate::interrupt::check()?;
    let raw = problem.evaluate(&theta, true)?;
    prof("full", t0);
    let p = theta.len();
    if raw.gradient.len() != p || raw.gauss_newton.nrows() != p || raw.gauss_newton.ncols() != p {
        return Err(SysidError::numerical(
            "optimiser",
            format!(
                "the provider returned a gradient of length {} and a {}x{} Gauss-Newton matrix for {p} parameters",
                raw.gradient.len(),
                raw.gauss_newton.nrows(),
                raw.gauss_newton.ncols()
            ),
        ));
    }
    let (cost, g, h) = regularise(opt, &theta, &raw);
    Ok(Point {
        theta,
        cost,
        raw,
        g,
        h,
    })
}

pub(super) fn project(opt: &Options, theta: &mut [f64]) {
    if let Some(lo) = &opt.lower {
        for (t, l) in theta.iter_mut().zip(lo) {
            *t = t.max(*l);
        }
    }
    if let Some(hi) = &opt.upper {
        for (t, u) in theta.iter_mut().zip(hi) {
            *t = t.min(*u);
        }
    }
}

fn at_bounds(opt: &Options, theta: &[f64]) -> Vec<usize> {
    (0..theta.len())
        .filter(|&i| {
            opt.lower.as_ref().is_some_and(|l| theta[i] <= l[i])
                || opt.upper.as_ref().is_some_and(|u| theta[i] >= u[i])
        })
        .collect()
}

/// The finite-difference step of the geodesic acceleration, as a fraction of the step
/// (Transtrum & Sethna 2012).
const GEODESIC_H: f64 = 0.1;

/// The largest `2 |a| / |v|` (acceleration against velocity, scaled norm) a trial may have:
/// above it the second-order term is too large for the expansion to hold, and the trial is
/// refused as a failed step would be (Transtrum & Sethna 2012 use 0.75).
const GEODESIC_ALPHA: f64 = 0.75;

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Minimises a [`Problem`] from `theta0` by damped Gauss-Newton steps.
///
/// The observer is called after every accepted step; returning [`Flow::Stop`] ends the
/// search at the current point. The start must be admissible and inside the bounds (it is
/// projected onto them). Only points that lower the cost are accepted.
///
/// ```
/// use sysid_core::optim::{minimize, Evaluation, Options, Problem, Flow};
/// use faer::Mat;
/// // Rosenbrock as least squares: r = (10 (y - x^2), 1 - x).
/// struct Rosen;
/// impl Problem for Rosen {
///     fn n_params(&self) -> usize { 2 }
///     fn evaluate(&mut self, t: &[f64], jac: bool) -> sysid_core::Result<Evaluation> {
///         let r = [10.0 * (t[1] - t[0] * t[0]), 1.0 - t[0]];
///         let j = [[-20.0 * t[0], 10.0], [-1.0, 0.0]];
///         let mut ev = Evaluation::cost_only(0.5 * (r[0] * r[0] + r[1] * r[1]));
///         if jac {
///             ev.gradient = (0..2).map(|a| j[0][a] * r[0] + j[1][a] * r[1]).collect();
///             ev.gauss_newton = Mat::from_fn(2, 2, |a, b| j[0][a] * j[0][b] + j[1][a] * j[1][b]);
///         }
///         Ok(ev)
///     }
/// }
/// let sol = minimize(&mut Rosen, &[-1.2, 1.0], &Options::default(), &mut |_| Flow::Continue).unwrap();
/// assert!((sol.theta[0] - 1.0).abs() < 1e-6 && (sol.theta[1] - 1.0).abs() < 1e-6);
/// ```
pub fn minimize(
    problem: &mut dyn Problem,
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    let p = problem.n_params();
    check_options(p, options, theta0)?;
    let mut theta = theta0.to_vec();
    project(options, &mut theta);
    if !problem.admissible(&theta) {
        return Err(SysidError::invalid(
            "theta0",
            "the starting point is not admissible (for a state-space model: the predictor is \
             unstable); stabilise the start first",
        ));
    }
    let mut evals = 0usize;
    let mut pt = evaluate_point(problem, options, theta, &mut evals)?;
    if !pt.cost.is_finite() {
        return Err(SysidError::numerical(
            "optimiser",
            "the cost at the starting point is not finite",
        ));
    }
    let fixed: Vec<bool> = options.fixed.clone().unwrap_or_else(|| vec![false; p]);
    let mut weighted_history = vec![pt.cost];
    let mut history = vec![problem.criterion().unwrap_or(pt.cost)];
    let mut mu = options.initial_damping.max(0.0);
    let mut iterations = 0usize;
    let mut condition = f64::NAN;
    // consecutive iterations whose Gauss-Newton matrix is reused from an earlier point
    let mut frozen = 0usize;
    let mut last_red: Option<Reduced> = None;
    // the same step problem in the plain metric's basis (a provider's basis, small problems)
    let mut last_alt: Option<Reduced> = None;
    // the metric of a provider's basis: plain until the search crawls (see `CRAWL_WINDOW`)
    let mut metric = Metric::Plain;
    let mut switched_at: Option<usize> = None;
    // the decrease of each accepted step (weighted cost)
    let mut gains: Vec<f64> = Vec::new();
    let mut geo = GeodesicCounts::default();
    let mut shortened = 0usize;
    let mut remaining = f64::NAN;
    let stop;
    loop {
        let capped = iterations >= options.max_iter;
        if capped && frozen > 0 && options.final_gauss_newton && options.max_iter > 0 {
            // the evaluation the end of the search makes anyway, made before the tests
            frozen = 0;
            pt = evaluate_point(problem, options, pt.theta, &mut evals)?;
        }
        // at the cap, the point's own Gauss-Newton matrix (formed when `final_gauss_newton`)
        // still answers the convergence tests below: a search that converged on its last
        // allowed iteration says so, not that it stopped short
        if capped && (options.max_iter == 0 || !options.final_gauss_newton || frozen > 0) {
            stop = StopReason::MaxIterations;
            break;
        }
        // Active set: parameters at a bound whose descent direction points outward.
        let bounds = at_bounds(options, &pt.theta);
        let mut blocked = fixed.clone();
        for &i in &bounds {
            let lo = options.lower.as_ref().is_some_and(|l| pt.theta[i] <= l[i]);
            // descent direction is -g
            if (lo && pt.g[i] > 0.0) || (!lo && pt.g[i] < 0.0) {
                blocked[i] = true;
            }
        }
        let stale = frozen > 0;
        // a chord step reuses the factorisation of the matrix it reuses
        let red = match last_red.take() {
            Some(mut r) if stale && r.blocked == blocked => {
                r.set_gradient(&pt.g);
                if matches!(r.solver, Solver::Cholesky { .. }) {
                    let t0 = std::time::Instant::now();
                    if r.orbit.is_none() {
                        if let Some(dirs) = problem.invariant_directions(&r.at)? {
                            r.orbit = r.scaled_basis(&dirs);
                        }
                    }
                    r.remove_orbit();
                    prof("chord-projection", t0);
                }
                r
            }
            _ => match reduce(problem, options, &pt, &blocked, metric) {
                Ok(r) => {
                    last_alt = None;
                    r
                }
                // the tests at the cap are a courtesy: a failure there ends as before
                Err(_) if capped => {
                    stop = StopReason::MaxIterations;
                    break;
                }
                Err(e) => return Err(e),
            },
        };
        if stale {
            if let Some(alt) = last_alt.as_mut().filter(|a| a.blocked == blocked) {
                alt.set_gradient(&pt.g);
            } else {
                last_alt = None;
            }
        } else if !capped
            && metric == Metric::Marquardt
            && red.basis_given
            && matches!(red.solver, Solver::Eigen { .. })
        {
            last_alt = reduce(problem, options, &pt, &blocked, Metric::Plain).ok();
        }
        let red = &*last_red.insert(red);
        condition = red.condition;
        let gnorm = red
            .gs
            .iter()
            .zip(&red.d)
            .map(|(g, d)| (g * d).abs())
            .fold(0.0, f64::max);
        let sigma2 = problem
            .n_residuals()
            .map(|nr| 2.0 * pt.raw.cost / nr.max(1) as f64);
        // the largest decrease a stopping test below could still call converged
        let mut threshold = options.tol_gradient * pt.cost;
        if let Some(s2) = sigma2.filter(|_| !stale) {
            threshold = threshold.max(options.tol_statistical * s2);
        }
        let t0 = std::time::Instant::now();
        let (dec, exact) = match red.decrease_lower_bound() {
            // neither test can stop: the solve is skipped (same iterates)
            Some(lb) if lb > threshold => (lb, false),
            _ => (red.gn_decrease(options.rank_tol), true),
        };
        prof("gn-decrease", t0);
        if red.gate > 0.0 && dec < red.gate && pt.cost > f64::MIN_POSITIVE {
            // no direction's decrease reaches `Options::significance` residual variances
            stop = StopReason::Statistical;
            break;
        }
        if pt.cost <= f64::MIN_POSITIVE || dec <= options.tol_gradient * pt.cost {
            stop = StopReason::GradientTolerance;
            break;
        }
        if !stale && sigma2.is_some_and(|s2| dec <= options.tol_statistical * s2) {
            stop = StopReason::Statistical;
            break;
        }
        if crawls(red, metric, stale, &gains, dec, sigma2) && spread(&pt, &blocked) > SPREAD {
            // the steps take a small part of what the Gauss-Newton model says is left, and
            // the parameters' effects differ by orders of magnitude: the plain basis mixes
            // them; from here on the basis is orthonormal in the search's own metric
            metric = Metric::Marquardt;
            switched_at = Some(iterations);
            last_red = None;
            continue;
        }
        if capped {
            // how far short of the minimum it stops: the exact decrease (solved here when
            // the bound skipped the solve above)
            remaining = sigma2.map_or(f64::NAN, |s2| {
                let exact_dec = if exact {
                    dec
                } else {
                    red.gn_decrease(options.rank_tol)
                };
                exact_dec / s2
            });
            stop = StopReason::MaxIterations;
            break;
        }
        let mut accepted: Option<(Vec<f64>, f64, f64, f64, f64, bool)> = None;
        // whether the admissible set shortened the accepted step
        let mut cut = false;
        for try_ in 0..60 {
            if stale && try_ > 0 {
                // a chord step gets one try at the current damping
                break;
            }
            let t0 = std::time::Instant::now();
            let v = red.step(mu, options.rank_tol);
            prof("solve", t0);
            // geodesic acceleration: the step v + a / 2, or v alone (no acceleration formed)
            let accel = if options.geodesic && !stale {
                let t0 = std::time::Instant::now();
                crate::interrupt::check()?;
                let gv = problem.geodesic_gradient(&pt.theta, &v, GEODESIC_H)?;
                prof("geodesic", t0);
                gv.filter(|g| g.len() == p && g.iter().all(|x| x.is_finite()))
                    .map(|gv| red.step_for(&gv, mu, options.rank_tol))
            } else {
                None
            };
            if let Some(a) = &accel {
                geo.formed += 1;
                let ratio = 2.0 * red.scaled_norm(a) / red.scaled_norm(&v);
                if std::env::var_os("SYSID_PROFILE").is_some() {
                    eprintln!("PROF geodesic mu {mu:e} ratio {ratio}");
                }
                if ratio.is_nan() || ratio > GEODESIC_ALPHA {
                    geo.refused += 1;
                    if mu > 1e10 {
                        break;
                    }
                    mu = (mu * 4.0).max(1e-12);
                    continue;
                }
            }
            let s: Vec<f64> = match &accel {
                Some(a) => (0..p).map(|i| v[i] + 0.5 * a[i]).collect(),
                None => v.clone(),
            };
            // a step that finds no decrease is tried again in the plain metric's basis (the
            // same Gauss-Newton step up to its similarity part, which the Marquardt metric
            // spreads into parameters of small effect: a gain error corrected through `A`
            // and `C`, or, noise-free, only linear convergence) before the damping is raised
            let turn = accel.is_none() && metric == Metric::Marquardt;
            let mut best: Option<(Shaped, f64)> = None;
            if let Some(sh) = shape(problem, options, &pt, s, &blocked, turn) {
                let c = trial_cost(problem, options, &sh.trial, &mut evals)?;
                best = Some((sh, c));
            }
            let descends = best.as_ref().is_some_and(|(_, c)| *c < pt.cost);
            if let (Some(alt), None, false) = (&last_alt, &accel, descends) {
                let other = alt.step(mu, options.rank_tol);
                if let Some(sh) = shape(problem, options, &pt, other, &blocked, turn) {
                    let c = trial_cost(problem, options, &sh.trial, &mut evals)?;
                    if c.is_finite() && best.as_ref().is_none_or(|(_, b)| !b.is_finite() || c < *b)
                    {
                        best = Some((sh, c));
                    }
                }
            }
            let Some((
                Shaped {
                    trial,
                    alpha,
                    halvings,
                    turned: turned_step,
                },
                cand_cost,
            )) = best
            else {
                if !stale {
                    mu = (mu * 10.0).max(1e-6);
                }
                continue;
            };
            // the trial is judged on its cost alone; the Jacobian is formed once accepted
            let actual = pt.cost - cand_cost;
            if cand_cost.is_finite() && actual > 0.0 {
                // predicted decrease of the (projected) step taken; with an acceleration,
                // of its velocity (the Gauss-Newton model has no second-order term)
                let st: Vec<f64> = match accel {
                    Some(_) => v.iter().map(|x| alpha * x).collect(),
                    None => (0..p).map(|i| trial[i] - pt.theta[i]).collect(),
                };
                let quad = curvature(&pt, &st);
                let lin: f64 = (0..p).map(|i| pt.g[i] * st[i]).sum();
                let pred = -(lin + 0.5 * quad);
                let rho = if pred > 0.0 { actual / pred } else { 0.0 };
                let used = mu;
                // the damping follows the Gauss-Newton model, not a reused one
                if !stale && rho > 0.75 {
                    mu /= 3.0;
                } else if !stale && rho < 0.25 {
                    mu = (mu * 2.0).max(1e-12);
                }
                if std::env::var_os("SYSID_PROFILE").is_some() {
                    eprintln!("PROF step mu {used:e} rho {rho} pred {pred:e} actual {actual:e} try {try_} halvings {halvings}");
                }
                accepted = Some((trial, cand_cost, used, rho, quad, accel.is_some()));
                cut = halvings > 0 || turned_step;
                break;
            }
            if std::env::var_os("SYSID_PROFILE").is_some() {
                eprintln!("PROF rejected mu {mu:e} actual {actual:e} halvings {halvings}");
            }
            if mu > 1e10 || stale {
                break;
            }
            mu = (mu * 4.0).max(1e-12);
        }
        let Some((trial, cand_cost, used, rho, quad, accelerated)) = accepted else {
            if stale {
                // the reused matrix found no descent: form it at this point and try again
                frozen = 0;
                pt = evaluate_point(problem, options, pt.theta, &mut evals)?;
                continue;
            }
            stop = StopReason::NoDescent;
            break;
        };
        geo.accepted += usize::from(accelerated);
        shortened += usize::from(cut);
        let step_norm = norm(&(0..p).map(|i| trial[i] - pt.theta[i]).collect::<Vec<_>>());
        // relative decrease under the same cost definition (before any re-weighting)
        let rel_decrease = (pt.cost - cand_cost) / pt.cost.abs().max(f64::MIN_POSITIVE);
        gains.push(pt.cost - cand_cost);
        iterations += 1;
        let t0 = std::time::Instant::now();
        problem.accepted(&trial)?;
        prof("accepted", t0);
        if !options.final_gauss_newton && iterations >= options.max_iter {
            // the search ends here and only the point is wanted: not evaluated again
            frozen = 0;
            let raw = Evaluation::cost_only(cand_cost);
            let (g, h) = (Vec::new(), Mat::zeros(0, 0));
            pt = Point {
                theta: trial,
                cost: cand_cost,
                raw,
                g,
                h,
            };
            weighted_history.push(cand_cost);
            let reported = problem.criterion().unwrap_or(cand_cost);
            history.push(reported);
            let info = Iteration {
                iteration: iterations,
                cost: reported,
                weighted_cost: cand_cost,
                step_norm,
                gradient_norm: gnorm,
                damping: used,
                theta: &pt.theta,
            };
            stop = match observer(&info) {
                Flow::Stop => StopReason::Cancelled,
                Flow::Continue => StopReason::MaxIterations,
            };
            break;
        }
        // profile trace: the gradient before the step, for the curvature along it
        let before = std::env::var_os("SYSID_PROFILE").map(|_| (pt.g.clone(), pt.theta.clone()));
        let mut chord = None;
        if frozen < options.reuse_gauss_newton && rho > 0.75 {
            let t0 = std::time::Instant::now();
            crate::interrupt::check()?;
            let go = problem.gradient_only(&trial)?;
            prof("gradient", t0);
            if let Some(mut raw) = go {
                evals += 1;
                raw.gauss_newton = pt.raw.gauss_newton.clone();
                let (cost, g, h) = regularise(options, &trial, &raw);
                chord = Some(Point {
                    theta: trial.clone(),
                    cost,
                    raw,
                    g,
                    h,
                });
            }
        }
        pt = match chord {
            Some(c) => {
                frozen += 1;
                c
            }
            None => {
                frozen = 0;
                evaluate_point(problem, options, trial, &mut evals)?
            }
        };
        if let Some((g0, t0)) = before {
            // s^T (g_new - g_old) / s^T H s: 1 where the Gauss-Newton model has the curvature
            // of the cost along the step, far from 1 where the neglected second-order term of
            // the Hessian (large residuals) or the model's own curvature dominates
            let sy: f64 = (0..p)
                .map(|i| (pt.theta[i] - t0[i]) * (pt.g[i] - g0[i]))
                .sum();
            eprintln!("PROF curvature {} chord {frozen}", sy / quad);
        }
        weighted_history.push(pt.cost);
        let reported = problem.criterion().unwrap_or(pt.cost);
        history.push(reported);
        let info = Iteration {
            iteration: iterations,
            cost: reported,
            weighted_cost: pt.cost,
            step_norm,
            gradient_norm: gnorm,
            damping: used,
            theta: &pt.theta,
        };
        if observer(&info) == Flow::Stop {
            stop = StopReason::Cancelled;
            break;
        }
        let small_step = step_norm <= options.tol_step * (options.tol_step + norm(&pt.theta));
        if (rel_decrease <= options.tol_cost || small_step) && stale {
            // a chord step met a stopping test: confirm with the Gauss-Newton matrix
            if frozen > 0 {
                frozen = 0;
                pt = evaluate_point(problem, options, pt.theta, &mut evals)?;
            }
            continue;
        }
        if rel_decrease <= options.tol_cost {
            stop = StopReason::CostTolerance;
            break;
        }
        if small_step {
            stop = StopReason::StepTolerance;
            break;
        }
    }
    if frozen > 0 {
        pt = evaluate_point(problem, options, pt.theta, &mut evals)?;
    }
    let active_bounds = at_bounds(options, &pt.theta);
    Ok(Solution {
        cost: *history.last().unwrap_or(&pt.cost),
        history,
        weighted_history,
        iterations,
        evaluations: evals,
        stop,
        gauss_newton: pt.raw.gauss_newton,
        gradient: pt.raw.gradient,
        condition,
        active_bounds,
        theta: pt.theta,
        geodesic: geo,
        shortened,
        remaining_decrease: remaining,
        metric_switched_at: switched_at,
    })
}

/// Accepted steps over which a crawl is judged ([`crawls`]).
const CRAWL_WINDOW: usize = 5;
/// A crawl: the last [`CRAWL_WINDOW`] steps together took less than this fraction of the
/// decrease the Gauss-Newton model says is still to go.
const CRAWL_FRACTION: f64 = 0.25;

/// Whether a search in a provider's basis, orthonormal in the parameters themselves, crawls:
/// its last [`CRAWL_WINDOW`] accepted steps took less than [`CRAWL_FRACTION`] of the decrease
/// `dec` its Gauss-Newton model predicts, while that decrease is worth more than a residual
/// variance (`sigma2`). On an unstable plant the parameters' effects differ by orders of
/// magnitude ([`spread`]), a basis orthonormal in them mixes them, and the damped steps crawl
/// (the search stopped at its cap short of the minimum by several residual variances); in
/// the search's own metric it converges. The switch is made only then: on the searches that
/// converge without it, the plain basis keeps the similarity part of each step smallest in
/// the parameters, and their ends do not move.
fn crawls(
    red: &Reduced,
    metric: Metric,
    stale: bool,
    gains: &[f64],
    dec: f64,
    sigma2: Option<f64>,
) -> bool {
    if metric != Metric::Plain || stale || !red.basis_given || gains.len() < CRAWL_WINDOW {
        return false;
    }
    let Some(s2) = sigma2 else {
        return false;
    };
    let recent: f64 = gains[gains.len() - CRAWL_WINDOW..].iter().sum();
    dec > s2 && recent < CRAWL_FRACTION * dec
}

/// The spread of the parameters' effects above which a crawling search changes its metric
/// ([`spread`]): six orders of magnitude. Measured where the crawl test fires: 1e6 to 4e12
/// on unstable plants (the warning audit's scenario), where the plain basis stopped searches
/// at their cap; 8e1 to 6e4 on the shipped records' fits and 3e5 on an aircraft's
/// ground-vibration record, where a switch moved searches into other local minima, worse on
/// validation data as often as better (`benches/results/pem_search.md`).
const SPREAD: f64 = 1e6;

/// The largest over the smallest square root of the Gauss-Newton diagonal (Marquardt's
/// scale) among the parameters that move and that the cost sees.
fn spread(pt: &Point, blocked: &[bool]) -> f64 {
    let (lo, hi) = (0..blocked.len())
        .filter(|&i| !blocked[i])
        .filter_map(|i| pt.diagonal(i).map(f64::sqrt))
        .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if lo.is_finite() {
        hi / lo
    } else {
        1.0
    }
}

/// `st^T H st` at `pt`.
fn curvature(pt: &Point, st: &[f64]) -> f64 {
    let p = st.len();
    (0..p)
        .map(|i| st[i] * (0..p).map(|j| pt.h[(i, j)] * st[j]).sum::<f64>())
        .sum()
}

/// The cost of a trial point (no Jacobian), counted as an evaluation.
fn trial_cost(
    problem: &mut dyn Problem,
    options: &Options,
    trial: &[f64],
    evals: &mut usize,
) -> Result<f64> {
    *evals += 1;
    let t0 = std::time::Instant::now();
    crate::interrupt::check()?;
    let raw = problem.evaluate(trial, false)?;
    prof("cost", t0);
    Ok(regularise(options, trial, &raw).0)
}
