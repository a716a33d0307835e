//! The damped Gauss-Newton iteration of [`minimize`].

use super::{Evaluation, Flow, Iteration, Options, Problem, Solution, StopReason};
use crate::error::{Result, SysidError};
use faer::prelude::Solve;
use faer::{Mat, Side};

/// Regularised cost, gradient and Gauss-Newton matrix at one point.
struct Point {
    theta: Vec<f64>,
    cost: f64,
    /// Provider's own evaluation (without regularisation).
    raw: Evaluation,
    g: Vec<f64>,
    h: Mat<f64>,
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
        eprintln!("PROF {what} {:.3}", t0.elapsed().as_secs_f64());
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

fn project(opt: &Options, theta: &mut [f64]) {
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

/// How the damped steps are solved at one point.
enum Solver {
    /// Eigenpairs `(v, lam)` of the scaled reduced Gauss-Newton matrix `D^-1 T^T H T D^-1`,
    /// with `T` (p x q) the search basis: theta = theta_k + T z.
    Eigen {
        t: Mat<f64>,
        v: Mat<f64>,
        lam: Vec<f64>,
    },
    /// Large problems: the scaled full-space matrix `D^-1 H D^-1` (rows and columns of blocked
    /// parameters replaced by the identity) and an estimate of its largest eigenvalue; every
    /// damped step is one Cholesky solve.
    Cholesky { hs: Mat<f64>, lmax: f64 },
}

/// The reduced step problem at a point.
struct Reduced {
    /// Marquardt scaling (of z for `Eigen`, of theta for `Cholesky`).
    d: Vec<f64>,
    /// Scaled reduced gradient.
    gs: Vec<f64>,
    condition: f64,
    solver: Solver,
    /// The blocked parameters it was formed with.
    blocked: Vec<bool>,
    /// The point it was formed at.
    at: Vec<f64>,
}

/// Smallest damping (relative to the largest eigenvalue) of a Cholesky solve: the similarity
/// directions of a state-space model are an exact null space of `J^T W J`, orthogonal to the
/// gradient, so a tiny shift leaves the step in their complement.
const CHOLESKY_FLOOR: f64 = 1e-10;

fn reduce(
    problem: &mut dyn Problem,
    opt: &Options,
    pt: &Point,
    blocked: &[bool],
) -> Result<Reduced> {
    let p = pt.theta.len();
    let n_free = blocked.iter().filter(|&&b| !b).count();
    if n_free > opt.eigen_limit {
        return Ok(reduce_cholesky(pt, blocked));
    }
    let t0 = std::time::Instant::now();
    let basis = problem.search_basis(&pt.theta)?;
    prof("basis", t0);
    let t0 = std::time::Instant::now();
    let mut t = match basis {
        Some(b) => {
            if b.nrows() != p {
                return Err(SysidError::numerical(
                    "optimiser",
                    format!("search basis has {} rows for {p} parameters", b.nrows()),
                ));
            }
            b
        }
        None => {
            let free: Vec<usize> = (0..p).filter(|&i| !blocked[i]).collect();
            Mat::from_fn(p, free.len(), |i, j| f64::from(u8::from(free[j] == i)))
        }
    };
    // Blocked parameters (fixed or at an active bound) never move, whatever the basis says.
    if blocked.iter().any(|&b| b) {
        for i in 0..p {
            if blocked[i] {
                for j in 0..t.ncols() {
                    t[(i, j)] = 0.0;
                }
            }
        }
    }
    let q = t.ncols();
    let ht = &pt.h * &t;
    let hr = t.transpose() * &ht;
    let d: Vec<f64> = (0..q)
        .map(|i| {
            let v = hr[(i, i)];
            if v > 0.0 && v.is_finite() {
                v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let mut hs = Mat::from_fn(q, q, |i, j| hr[(i, j)] / (d[i] * d[j]));
    for i in 0..q {
        for j in 0..i {
            let m = 0.5 * (hs[(i, j)] + hs[(j, i)]);
            hs[(i, j)] = m;
            hs[(j, i)] = m;
        }
    }
    prof("reduce-products", t0);
    let t0 = std::time::Instant::now();
    let (v, lam) = if q == 0 {
        (Mat::zeros(0, 0), Vec::new())
    } else {
        let e = hs.self_adjoint_eigen(Side::Lower).map_err(|e| {
            SysidError::numerical("optimiser (eigenvalues of J^T J)", format!("{e:?}"))
        })?;
        let s = e.S().column_vector();
        let lam: Vec<f64> = (0..q).map(|i| s[i].max(0.0)).collect();
        (e.U().to_owned(), lam)
    };
    prof("reduce-eigen", t0);
    let lmax = lam.iter().copied().fold(0.0, f64::max);
    let lmin = lam.iter().copied().fold(f64::INFINITY, f64::min);
    let condition = if q == 0 {
        1.0
    } else if lmin > opt.rank_tol * lmax && lmin > 0.0 {
        lmax / lmin
    } else {
        f64::INFINITY
    };
    let mut red = Reduced {
        d,
        gs: Vec::new(),
        condition,
        solver: Solver::Eigen { t, v, lam },
        blocked: blocked.to_vec(),
        at: pt.theta.clone(),
    };
    red.set_gradient(&pt.g);
    Ok(red)
}

/// The large-problem form of [`reduce`]: no basis and no eigendecomposition.
fn reduce_cholesky(pt: &Point, blocked: &[bool]) -> Reduced {
    let t0 = std::time::Instant::now();
    let p = pt.theta.len();
    let d: Vec<f64> = (0..p)
        .map(|i| {
            let v = pt.h[(i, i)];
            if v > 0.0 && v.is_finite() && !blocked[i] {
                v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let hs = Mat::from_fn(p, p, |i, j| {
        if blocked[i] || blocked[j] {
            f64::from(u8::from(i == j))
        } else {
            0.5 * (pt.h[(i, j)] + pt.h[(j, i)]) / (d[i] * d[j])
        }
    });
    // largest eigenvalue by power iteration (deterministic start; an estimate from below,
    // enough to scale the damping)
    let mut x = Mat::from_fn(p, 1, |_, _| 1.0 / (p.max(1) as f64).sqrt());
    let mut lmax = 1.0;
    for _ in 0..12 {
        let y = &hs * &x;
        let ny = y.norm_l2();
        if !(ny > 0.0 && ny.is_finite()) {
            break;
        }
        lmax = ny;
        x = y * faer::Scale(1.0 / ny);
    }
    let mut red = Reduced {
        d,
        gs: Vec::new(),
        condition: f64::NAN,
        solver: Solver::Cholesky { hs, lmax },
        blocked: blocked.to_vec(),
        at: pt.theta.clone(),
    };
    red.set_gradient(&pt.g);
    prof("reduce-cholesky", t0);
    red
}

impl Reduced {
    /// For a chord step of the Cholesky solver: removes from the scaled gradient its part
    /// along the directions `dirs` (p x r) in which the cost was invariant where the matrix
    /// was formed. They are null directions of that matrix, which the damping floor would
    /// otherwise amplify: the new gradient is not orthogonal to them.
    fn remove_directions(&mut self, dirs: &Mat<f64>) {
        if !matches!(self.solver, Solver::Cholesky { .. }) || dirs.nrows() != self.gs.len() {
            return;
        }
        let ds = Mat::from_fn(dirs.nrows(), dirs.ncols(), |i, j| {
            if self.blocked[i] {
                0.0
            } else {
                self.d[i] * dirs[(i, j)]
            }
        });
        if ds.ncols() == 0 || !ds.norm_max().is_finite() {
            return;
        }
        let q = ds.qr().compute_thin_Q();
        let g = Mat::from_fn(self.gs.len(), 1, |i, _| self.gs[i]);
        let c = q.transpose() * &g;
        let r = &g - &q * &c;
        for (i, v) in self.gs.iter_mut().enumerate() {
            *v = r[(i, 0)];
        }
    }

    /// Sets the scaled reduced gradient from the full gradient `g` (also used to reuse the
    /// factorisation at a new point for a chord step).
    fn set_gradient(&mut self, g: &[f64]) {
        self.gs = match &self.solver {
            Solver::Eigen { t, .. } => {
                let q = t.ncols();
                (0..q)
                    .map(|j| (0..t.nrows()).map(|i| t[(i, j)] * g[i]).sum::<f64>() / self.d[j])
                    .collect()
            }
            Solver::Cholesky { .. } => (0..g.len())
                .map(|i| {
                    if self.blocked[i] {
                        0.0
                    } else {
                        g[i] / self.d[i]
                    }
                })
                .collect(),
        };
    }

    /// `(hs + shift I)^-1 gs` by Cholesky, raising the shift until it factors.
    fn cholesky_solve(hs: &Mat<f64>, gs: &[f64], mut shift: f64) -> Vec<f64> {
        let p = gs.len();
        for _ in 0..12 {
            let mut a = hs.clone();
            for i in 0..p {
                a[(i, i)] += shift;
            }
            if let Ok(f) = a.llt(Side::Lower) {
                let b = Mat::from_fn(p, 1, |i, _| gs[i]);
                let z = f.solve(&b);
                let z: Vec<f64> = (0..p).map(|i| z[(i, 0)]).collect();
                if z.iter().all(|v| v.is_finite()) {
                    return z;
                }
            }
            if std::env::var_os("SYSID_PROFILE").is_some() {
                eprintln!("PROF chol-retry {shift:e}");
            }
            shift = (shift * 100.0).max(f64::MIN_POSITIVE);
        }
        vec![0.0; p]
    }

    /// Full-space step for damping `mu` (relative to the largest eigenvalue); `mu = 0` gives the
    /// Gauss-Newton step through the pseudo-inverse.
    fn step(&self, mu: f64, rank_tol: f64) -> Vec<f64> {
        let (t, v, lam) = match &self.solver {
            Solver::Eigen { t, v, lam } => (t, v, lam),
            Solver::Cholesky { hs, lmax } => {
                let z = Self::cholesky_solve(hs, &self.gs, mu.max(CHOLESKY_FLOOR) * lmax);
                return (0..z.len()).map(|i| -z[i] / self.d[i]).collect();
            }
        };
        let q = lam.len();
        let p = t.nrows();
        let lmax = lam
            .iter()
            .copied()
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut c = vec![0.0; q];
        for k in 0..q {
            let proj: f64 = (0..q).map(|i| v[(i, k)] * self.gs[i]).sum();
            let den = lam[k] + mu * lmax;
            if lam[k] > rank_tol * lmax || mu > 0.0 {
                c[k] = -proj / den;
            }
        }
        let mut z = vec![0.0; q];
        for i in 0..q {
            z[i] = (0..q).map(|k| v[(i, k)] * c[k]).sum::<f64>() / self.d[i];
        }
        (0..p)
            .map(|i| (0..q).map(|j| t[(i, j)] * z[j]).sum())
            .collect()
    }

    /// Predicted decrease of the Gauss-Newton step (`g^T H^+ g / 2`, scaled reduced problem).
    fn gn_decrease(&self, rank_tol: f64) -> f64 {
        let (v, lam) = match &self.solver {
            Solver::Eigen { v, lam, .. } => (v, lam),
            Solver::Cholesky { hs, lmax } => {
                let z = Self::cholesky_solve(hs, &self.gs, CHOLESKY_FLOOR * lmax);
                return 0.5 * z.iter().zip(&self.gs).map(|(a, b)| a * b).sum::<f64>();
            }
        };
        let q = lam.len();
        let lmax = lam.iter().copied().fold(0.0, f64::max);
        let mut s = 0.0;
        for k in 0..q {
            if lam[k] > rank_tol * lmax && lam[k] > 0.0 {
                let proj: f64 = (0..q).map(|i| v[(i, k)] * self.gs[i]).sum();
                s += proj * proj / lam[k];
            }
        }
        0.5 * s
    }
}

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
    let stop;
    loop {
        if iterations >= options.max_iter {
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
                    if let Some(dirs) = problem.invariant_directions(&r.at)? {
                        r.remove_directions(&dirs);
                    }
                    prof("chord-projection", t0);
                }
                r
            }
            _ => reduce(problem, options, &pt, &blocked)?,
        };
        let red = &*last_red.insert(red);
        condition = red.condition;
        let gnorm = red
            .gs
            .iter()
            .zip(&red.d)
            .map(|(g, d)| (g * d).abs())
            .fold(0.0, f64::max);
        let dec = red.gn_decrease(options.rank_tol);
        if pt.cost <= f64::MIN_POSITIVE || dec <= options.tol_gradient * pt.cost {
            stop = StopReason::GradientTolerance;
            break;
        }
        let sigma2 = problem
            .n_residuals()
            .map(|nr| 2.0 * pt.raw.cost / nr.max(1) as f64);
        if !stale && sigma2.is_some_and(|s2| dec <= options.tol_statistical * s2) {
            stop = StopReason::Statistical;
            break;
        }
        let mut accepted: Option<(Vec<f64>, f64, f64, f64)> = None;
        for try_ in 0..60 {
            if stale && try_ > 0 {
                // a chord step gets one try at the current damping
                break;
            }
            let s = red.step(mu, options.rank_tol);
            let mut alpha = 1.0;
            let mut trial: Vec<f64> = (0..p).map(|i| pt.theta[i] + s[i]).collect();
            project(options, &mut trial);
            let mut ok = problem.admissible(&trial);
            let mut halvings = 0;
            while !ok && halvings < 30 {
                alpha *= 0.5;
                halvings += 1;
                trial = (0..p).map(|i| pt.theta[i] + alpha * s[i]).collect();
                project(options, &mut trial);
                ok = problem.admissible(&trial);
            }
            if !ok {
                if !stale {
                    mu = (mu * 10.0).max(1e-6);
                }
                continue;
            }
            // the trial is judged on its cost alone; the Jacobian is formed once accepted
            evals += 1;
            let t0 = std::time::Instant::now();
            crate::interrupt::check()?;
            let raw = problem.evaluate(&trial, false)?;
            prof("cost", t0);
            let cand_cost = regularise(options, &trial, &raw).0;
            let actual = pt.cost - cand_cost;
            if cand_cost.is_finite() && actual > 0.0 {
                // predicted decrease of the (projected) step taken
                let st: Vec<f64> = (0..p).map(|i| trial[i] - pt.theta[i]).collect();
                let mut quad = 0.0;
                for i in 0..p {
                    let hs: f64 = (0..p).map(|j| pt.h[(i, j)] * st[j]).sum();
                    quad += st[i] * hs;
                }
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
                    eprintln!("PROF step mu {used:e} rho {rho} pred {pred:e} actual {actual:e} try {try_}");
                }
                accepted = Some((trial, cand_cost, used, rho));
                break;
            }
            if mu > 1e10 || stale {
                break;
            }
            mu = (mu * 4.0).max(1e-12);
        }
        let Some((trial, cand_cost, used, rho)) = accepted else {
            if stale {
                // the reused matrix found no descent: form it at this point and try again
                frozen = 0;
                pt = evaluate_point(problem, options, pt.theta, &mut evals)?;
                continue;
            }
            stop = StopReason::NoDescent;
            break;
        };
        let step_norm = norm(&(0..p).map(|i| trial[i] - pt.theta[i]).collect::<Vec<_>>());
        // relative decrease under the same cost definition (before any re-weighting)
        let rel_decrease = (pt.cost - cand_cost) / pt.cost.abs().max(f64::MIN_POSITIVE);
        iterations += 1;
        let t0 = std::time::Instant::now();
        problem.accepted(&trial)?;
        prof("accepted", t0);
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
    })
}
