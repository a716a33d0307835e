// Tests mirror how callers outside the crate set options (Options is non_exhaustive).
#![allow(clippy::field_reassign_with_default, clippy::type_complexity)]

use super::*;
use faer::prelude::Solve;
use faer::Mat;

/// Least squares on explicit residuals r(theta) with Jacobian J(theta).
struct Ls<F: FnMut(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)> {
    p: usize,
    f: F,
    admissible: Box<dyn FnMut(&[f64]) -> bool>,
    visited: Vec<Vec<f64>>,
    /// Provide `J^T r_vv` (central second differences) for geodesic acceleration.
    geodesic: bool,
}

impl<F: FnMut(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)> Problem for Ls<F> {
    fn n_params(&self) -> usize {
        self.p
    }
    fn evaluate(&mut self, th: &[f64], jac: bool) -> crate::Result<Evaluation> {
        self.visited.push(th.to_vec());
        let (r, j) = (self.f)(th);
        let mut ev = Evaluation::cost_only(0.5 * r.iter().map(|x| x * x).sum::<f64>());
        if jac {
            let p = self.p;
            ev.gradient = (0..p)
                .map(|a| (0..r.len()).map(|k| j[k][a] * r[k]).sum())
                .collect();
            ev.gauss_newton = Mat::from_fn(p, p, |a, b| {
                (0..r.len()).map(|k| j[k][a] * j[k][b]).sum::<f64>()
            });
        }
        Ok(ev)
    }
    fn admissible(&mut self, th: &[f64]) -> bool {
        (self.admissible)(th)
    }
    fn geodesic_gradient(
        &mut self,
        th: &[f64],
        v: &[f64],
        h: f64,
    ) -> crate::Result<Option<Vec<f64>>> {
        if !self.geodesic {
            return Ok(None);
        }
        let at = |s: f64| -> Vec<f64> { th.iter().zip(v).map(|(t, d)| t + s * h * d).collect() };
        let (r0, j) = (self.f)(th);
        let (rp, _) = (self.f)(&at(1.0));
        let (rm, _) = (self.f)(&at(-1.0));
        let rvv: Vec<f64> = (0..r0.len())
            .map(|k| (rp[k] - 2.0 * r0[k] + rm[k]) / (h * h))
            .collect();
        Ok(Some(
            (0..self.p)
                .map(|a| (0..r0.len()).map(|k| j[k][a] * rvv[k]).sum())
                .collect(),
        ))
    }
}

fn ls<F: FnMut(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)>(p: usize, f: F) -> Ls<F> {
    Ls {
        p,
        f,
        admissible: Box::new(|_| true),
        visited: Vec::new(),
        geodesic: false,
    }
}

fn rosen(t: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    (
        vec![10.0 * (t[1] - t[0] * t[0]), 1.0 - t[0]],
        vec![vec![-20.0 * t[0], 10.0], vec![-1.0, 0.0]],
    )
}

/// y = X theta with a fixed X (4 x 3).
fn linear(t: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let x = [
        [1.0, 0.5, -2.0],
        [0.0, 1.0, 3.0],
        [2.0, -1.0, 0.5],
        [1.0, 1.0, 1.0],
    ];
    let y = [1.0, -2.0, 0.3, 4.0];
    let r = (0..4)
        .map(|k| (0..3).map(|a| x[k][a] * t[a]).sum::<f64>() - y[k])
        .collect();
    (r, x.iter().map(|row| row.to_vec()).collect())
}

fn go(p: &mut dyn Problem, t0: &[f64], o: &Options) -> Solution {
    minimize(p, t0, o, &mut |_| Flow::Continue).unwrap()
}

#[test]
fn rosenbrock_converges() {
    let mut pr = ls(2, rosen);
    let sol = go(&mut pr, &[-1.2, 1.0], &Options::default());
    assert!((sol.theta[0] - 1.0).abs() < 1e-8, "{:?}", sol.theta);
    assert!((sol.theta[1] - 1.0).abs() < 1e-8);
    assert!(sol.cost < 1e-16);
    assert!(sol.history.windows(2).all(|w| w[1] < w[0]));
    assert_eq!(sol.history.len(), sol.iterations + 1);
}

#[test]
fn linear_least_squares_in_one_step() {
    let mut pr = ls(3, linear);
    let mut o = Options::default();
    o.initial_damping = 0.0;
    let sol = go(&mut pr, &[0.0; 3], &o);
    // reference: normal equations
    let (_, j) = linear(&[0.0; 3]);
    let x = Mat::from_fn(4, 3, |i, k| j[i][k]);
    let y = Mat::from_fn(4, 1, |i, _| [1.0, -2.0, 0.3, 4.0][i]);
    let xtx = x.transpose() * &x;
    let xty = x.transpose() * &y;
    let th = xtx.llt(faer::Side::Lower).unwrap().solve(&xty);
    for a in 0..3 {
        assert!((sol.theta[a] - th[(a, 0)]).abs() < 1e-12);
    }
    assert_eq!(sol.iterations, 1);
    assert!(sol.condition.is_finite() && sol.condition >= 1.0);
}

#[test]
fn bounds_are_respected_and_reported() {
    let mut pr = ls(3, linear);
    let mut o = Options::default();
    o.lower = Some(vec![f64::NEG_INFINITY, 0.0, f64::NEG_INFINITY]);
    o.upper = Some(vec![0.5, f64::INFINITY, f64::INFINITY]);
    o.tol_gradient = 1e-20;
    o.tol_cost = 1e-15;
    let unb = go(&mut ls(3, linear), &[0.0; 3], &Options::default());
    assert!(unb.theta[0] > 0.5, "the test needs an active upper bound");
    let sol = go(&mut pr, &[0.0; 3], &o);
    assert!(pr.visited.iter().all(|t| t[0] <= 0.5 && t[1] >= 0.0));
    assert!(sol.active_bounds.contains(&0));
    assert_eq!(sol.theta[0], 0.5);
    // with theta0 pinned at 0.5 the others solve the reduced least squares problem
    let mut fixed = o.clone();
    fixed.lower = None;
    fixed.upper = None;
    fixed.fixed = Some(vec![true, false, false]);
    let red = go(&mut ls(3, linear), &[0.5, 0.0, 0.0], &fixed);
    if !sol.active_bounds.contains(&1) {
        for a in 1..3 {
            assert!(
                (sol.theta[a] - red.theta[a]).abs() < 1e-7,
                "{:?} {:?} {:?} {:?}",
                sol.theta,
                red.theta,
                sol.stop,
                sol.history
            );
        }
    }
    assert!(sol.cost > unb.cost);
}

#[test]
fn fixed_parameters_never_move() {
    let mut pr = ls(2, rosen);
    let mut o = Options::default();
    o.fixed = Some(vec![false, true]);
    o.tol_gradient = 1e-20;
    o.tol_cost = 1e-15;
    let sol = go(&mut pr, &[-1.2, 0.7], &o);
    assert!(pr.visited.iter().all(|t| t[1] == 0.7));
    // min over x of 100 (0.7 - x^2)^2 + (1 - x)^2 lies near x = +sqrt(0.7) (from -1.2 maybe
    // the other local minimum): check stationarity instead
    let (r, j) = rosen(&sol.theta);
    let g0 = j[0][0] * r[0] + j[1][0] * r[1];
    assert!(g0.abs() < 1e-6, "{g0}");
}

#[test]
fn regularisation_pulls_toward_nominal() {
    let free = go(&mut ls(3, linear), &[0.0; 3], &Options::default());
    let nominal = vec![5.0, -5.0, 2.0];
    let mut last = f64::INFINITY;
    for lambda in [0.1, 1.0, 10.0, 1e6] {
        let mut o = Options::default();
        o.regularization = Some(Regularization {
            lambda,
            r: None,
            nominal: Some(nominal.clone()),
        });
        let sol = go(&mut ls(3, linear), &[0.0; 3], &o);
        let dist: f64 = (0..3).map(|a| (sol.theta[a] - nominal[a]).powi(2)).sum();
        assert!(
            dist < last,
            "distance to nominal must shrink as lambda grows"
        );
        last = dist;
        // exact solution of the regularised normal equations
        let (_, j) = linear(&[0.0; 3]);
        let x = Mat::from_fn(4, 3, |i, k| j[i][k]);
        let y = Mat::from_fn(4, 1, |i, _| [1.0, -2.0, 0.3, 4.0][i]);
        let a = x.transpose() * &x + Mat::<f64>::identity(3, 3) * faer::Scale(lambda);
        let b = x.transpose() * &y + Mat::from_fn(3, 1, |i, _| lambda * nominal[i]);
        let th = a.llt(faer::Side::Lower).unwrap().solve(&b);
        for k in 0..3 {
            assert!((sol.theta[k] - th[(k, 0)]).abs() < 1e-8 * (1.0 + th[(k, 0)].abs()));
        }
    }
    let d0: f64 = (0..3).map(|a| (free.theta[a] - nominal[a]).powi(2)).sum();
    assert!(last < 1e-6 * d0);
}

#[test]
fn inadmissible_region_never_entered() {
    // minimum of the linear problem lies at theta0 > 0.5; declare theta0 >= 0.4 inadmissible
    let unb = go(&mut ls(3, linear), &[0.0; 3], &Options::default());
    assert!(unb.theta[0] > 0.5);
    let mut pr = ls(3, linear);
    pr.admissible = Box::new(|t| t[0] < 0.4);
    let sol = go(&mut pr, &[0.0; 3], &Options::default());
    assert!(pr.visited.iter().all(|t| t[0] < 0.4));
    // the steps the boundary shortened are counted; the free search has none
    assert!(sol.shortened > 0 && sol.shortened <= sol.iterations && unb.shortened == 0);
    assert!(
        sol.theta[0] < 0.4
            && sol.cost
                < go(&mut ls(3, linear), &[0.0; 3], &{
                    let mut o = Options::default();
                    o.max_iter = 0;
                    o
                })
                .cost
    );
    // an inadmissible start is an error, not a search
    let mut bad = ls(3, linear);
    bad.admissible = Box::new(|t| t[0] < 0.4);
    assert!(
        minimize(&mut bad, &[1.0, 0.0, 0.0], &Options::default(), &mut |_| {
            Flow::Continue
        })
        .is_err()
    );
}

#[test]
fn observer_sees_every_iteration_and_can_cancel() {
    let mut seen = Vec::new();
    let sol = minimize(
        &mut ls(2, rosen),
        &[-1.2, 1.0],
        &Options::default(),
        &mut |it| {
            seen.push(it.cost);
            if it.iteration == 3 {
                Flow::Stop
            } else {
                Flow::Continue
            }
        },
    )
    .unwrap();
    assert_eq!(sol.stop, StopReason::Cancelled);
    assert_eq!(sol.iterations, 3);
    assert_eq!(seen, sol.history[1..].to_vec());
}

#[test]
fn observer_sees_the_point_of_each_iterate() {
    // each reported point has the reported cost; the last is the solution's point
    let mut seen: Vec<(Vec<f64>, f64)> = Vec::new();
    let sol = minimize(
        &mut ls(2, rosen),
        &[-1.2, 1.0],
        &Options::default(),
        &mut |it| {
            seen.push((it.theta.to_vec(), it.cost));
            Flow::Continue
        },
    )
    .unwrap();
    assert!(seen.len() > 3);
    for (theta, cost) in &seen {
        let (r, _) = rosen(theta);
        let c = 0.5 * r.iter().map(|v| v * v).sum::<f64>();
        assert!(
            (c - cost).abs() <= 1e-12 * cost.abs().max(1e-300),
            "{c} vs {cost}"
        );
    }
    assert_eq!(seen.last().unwrap().0, sol.theta);
}

#[test]
fn max_iter_and_bad_options() {
    let mut o = Options::default();
    o.max_iter = 2;
    let sol = go(&mut ls(2, rosen), &[-1.2, 1.0], &o);
    assert_eq!(sol.stop, StopReason::MaxIterations);
    assert_eq!(sol.iterations, 2);
    o.fixed = Some(vec![true]);
    assert!(minimize(&mut ls(2, rosen), &[0.0, 0.0], &o, &mut |_| Flow::Continue).is_err());
    assert!(minimize(
        &mut ls(2, rosen),
        &[f64::NAN, 0.0],
        &Options::default(),
        &mut |_| Flow::Continue
    )
    .is_err());
}

#[test]
fn a_search_that_converges_on_its_last_allowed_iteration_says_so() {
    // Rosenbrock ends on the gradient test, the chord problem (its last step a chord step,
    // whose matrix is formed at the cap) on the statistical one; capped at exactly the
    // iterations they need, both report that test, not the cap, at the same point
    let mut o = Options::default();
    o.tol_cost = 0.0;
    o.tol_step = 0.0;
    let free = go(&mut ls(2, rosen), &[-1.2, 1.0], &o);
    assert_eq!(free.stop, StopReason::GradientTolerance);
    o.max_iter = free.iterations;
    let capped = go(&mut ls(2, rosen), &[-1.2, 1.0], &o);
    assert_eq!(capped.stop, StopReason::GradientTolerance);
    assert_eq!(capped.theta, free.theta);
    o.max_iter = free.iterations - 1;
    assert_eq!(
        go(&mut ls(2, rosen), &[-1.2, 1.0], &o).stop,
        StopReason::MaxIterations
    );

    struct Noisy(Chord);
    impl Problem for Noisy {
        fn n_params(&self) -> usize {
            2
        }
        fn evaluate(&mut self, th: &[f64], jac: bool) -> crate::Result<Evaluation> {
            let mut ev = self.0.evaluate(th, jac)?;
            ev.cost += 1.0; // a residual floor: the statistical test can end the search
            Ok(ev)
        }
        fn gradient_only(&mut self, th: &[f64]) -> crate::Result<Option<Evaluation>> {
            let mut ev = self.0.gradient_only(th)?;
            if let Some(e) = ev.as_mut() {
                e.cost += 1.0;
            }
            Ok(ev)
        }
        fn n_residuals(&self) -> Option<usize> {
            Some(20)
        }
    }
    let mut o = Options::default();
    o.tol_cost = 0.0;
    o.tol_step = 0.0;
    o.tol_gradient = 0.0;
    o.tol_statistical = 1e-2;
    o.reuse_gauss_newton = 3;
    let run = |o: &Options| {
        let mut pr = Noisy(Chord { full: 0, grads: 0 });
        let s = go(&mut pr, &[1.0, 0.3], o);
        (s, pr.0.grads)
    };
    let (free, grads) = run(&o);
    assert_eq!(free.stop, StopReason::Statistical);
    assert!(grads > 0, "no chord step taken");
    o.max_iter = free.iterations;
    let (capped, _) = run(&o);
    assert_eq!(capped.stop, StopReason::Statistical);
    assert_eq!(capped.theta, free.theta);
    assert_eq!(capped.evaluations, free.evaluations);
}

/// Least squares whose minimum (2, 0.5) lies outside the unit disc, the admissible set, with
/// effects `k` apart, in a provider's basis (all directions: the search's crawl test
/// applies); with `margin`, the provider measures the disc's boundary (`|theta| - 1`).
struct Disc {
    margin: bool,
    /// The second residual's weight.
    k: f64,
}

/// [`Disc`]'s weight: effects seven orders of magnitude apart.
const DISC_K: f64 = 1e7;

impl Problem for Disc {
    fn n_params(&self) -> usize {
        2
    }
    fn evaluate(&mut self, t: &[f64], jac: bool) -> crate::Result<Evaluation> {
        let r = [t[0] - 2.0, self.k * (t[1] - 0.5)];
        let mut ev = Evaluation::cost_only(0.5 * (r[0] * r[0] + r[1] * r[1]));
        if jac {
            ev.gradient = vec![r[0], self.k * r[1]];
            ev.gauss_newton = Mat::from_fn(2, 2, |a, b| match (a, b) {
                (0, 0) => 1.0,
                (1, 1) => self.k * self.k,
                _ => 0.0,
            });
        }
        Ok(ev)
    }
    fn admissible(&mut self, t: &[f64]) -> bool {
        t[0].hypot(t[1]) < 1.0
    }
    fn bound_margin(&mut self, t: &[f64]) -> Option<f64> {
        self.margin.then(|| t[0].hypot(t[1]) - 1.0)
    }
    fn search_basis(&mut self, _t: &[f64], scale: &[f64]) -> crate::Result<Option<Mat<f64>>> {
        // every direction, orthonormal in the metric `diag(scale)`
        Ok(Some(Mat::from_fn(2, 2, |i, j| {
            if i == j {
                1.0 / scale[i]
            } else {
                0.0
            }
        })))
    }
    fn n_residuals(&self) -> Option<usize> {
        // residual variances far below the cost left at the boundary
        Some(1000)
    }
}

#[test]
fn a_search_that_crawls_along_the_admissible_sets_boundary_slides_along_it() {
    // halving alone keeps each step's direction: the search creeps along the circle towards
    // the constrained minimum (where the gradient points into the disc, normal to the
    // circle); once it crawls, its steps are turned along the boundary and it gets there
    let o = Options {
        max_iter: 30,
        tol_cost: 0.0,
        ..Options::default()
    };
    let turned = go(
        &mut Disc {
            margin: true,
            k: DISC_K,
        },
        &[0.0, 0.0],
        &o,
    );
    let halved = go(
        &mut Disc {
            margin: false,
            k: DISC_K,
        },
        &[0.0, 0.0],
        &o,
    );
    eprintln!(
        "turned {:?} {} {:?} {:?} halved {:?} {} {:?}",
        turned.theta,
        turned.iterations,
        turned.stop,
        turned.metric_switched_at,
        halved.theta,
        halved.iterations,
        halved.stop
    );
    // the constrained infimum: y = 1/2 (the heavy residual zero), x = sqrt(3)/2 on the circle
    let best = 0.5 * (0.75f64.sqrt() - 2.0).powi(2);
    assert!(turned.metric_switched_at.is_some());
    assert!(turned.theta[0].hypot(turned.theta[1]) > 1.0 - 1e-6);
    assert!(
        turned.cost < best * (1.0 + 1e-6),
        "{} {:?}",
        turned.cost,
        turned.theta
    );
    assert!(
        halved.cost > 10.0 * best,
        "{} {:?}",
        halved.cost,
        halved.theta
    );
    // effects of similar size (a factor 10): the same crawl keeps the plain basis
    let even = go(
        &mut Disc {
            margin: true,
            k: 10.0,
        },
        &[0.0, 0.0],
        &o,
    );
    assert!(even.metric_switched_at.is_none());
}

#[test]
fn search_basis_restricts_the_step() {
    // Only move along (1, 1)/sqrt2: the solution is the best point on that line.
    struct Along(Ls<fn(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)>);
    impl Problem for Along {
        fn n_params(&self) -> usize {
            3
        }
        fn evaluate(&mut self, t: &[f64], j: bool) -> crate::Result<Evaluation> {
            self.0.evaluate(t, j)
        }
        fn search_basis(&mut self, _t: &[f64], _s: &[f64]) -> crate::Result<Option<Mat<f64>>> {
            let s = 0.5f64.sqrt();
            Ok(Some(Mat::from_fn(3, 1, |i, _| if i < 2 { s } else { 0.0 })))
        }
    }
    let mut pr = Along(ls(3, linear));
    let sol = go(&mut pr, &[0.0; 3], &Options::default());
    assert!((sol.theta[0] - sol.theta[1]).abs() < 1e-14 && sol.theta[2] == 0.0);
    assert!(sol.iterations >= 1);
}

#[test]
fn covariance_matches_inverse_and_finds_null_space() {
    let (_, j) = linear(&[0.0; 3]);
    let x = Mat::from_fn(4, 3, |i, k| j[i][k]);
    let h = x.transpose() * &x;
    let c = covariance(h.as_ref(), 0.3, 1e-12).unwrap();
    assert_eq!(c.rank, 3);
    let prod = &c.covariance * &h;
    for i in 0..3 {
        for k in 0..3 {
            let e = if i == k { 0.3 } else { 0.0 };
            assert!((prod[(i, k)] - e).abs() < 1e-12);
        }
    }
    // duplicate a column: direction (1, -1, 0)-like is unidentifiable
    let x2 = Mat::from_fn(4, 3, |i, k| if k == 1 { 2.0 * j[i][0] } else { j[i][k] });
    let h2 = x2.transpose() * &x2;
    let c2 = covariance(h2.as_ref(), 1.0, 1e-10).unwrap();
    assert_eq!(c2.rank, 2);
    let v = c2.unidentifiable.col(0);
    // x2 v = 0
    let xv = &x2 * v;
    assert!(xv.norm_l2() < 1e-10);
    // a generalised inverse: H C H = H
    let hch = &h2 * &c2.covariance * &h2;
    assert!((&hch - &h2).norm_l2() < 1e-9 * h2.norm_l2());
}

/// A provider with cheap gradients: counts full and gradient-only evaluations.
struct Chord {
    full: usize,
    grads: usize,
}

impl Chord {
    /// Exponential fit r_k = a exp(-b t_k) - y_k (mildly nonlinear, zero residual).
    fn residuals(th: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let (a, b) = (th[0], th[1]);
        let mut r = Vec::new();
        let mut j = Vec::new();
        for k in 0..20 {
            let t = k as f64 * 0.1;
            let e = (-b * t).exp();
            r.push(a * e - 2.0 * (-0.7 * t).exp());
            j.push(vec![e, -a * t * e]);
        }
        (r, j)
    }
}

impl Problem for Chord {
    fn n_params(&self) -> usize {
        2
    }
    fn evaluate(&mut self, th: &[f64], jac: bool) -> crate::Result<Evaluation> {
        if jac {
            self.full += 1;
        }
        let mut inner = ls(2, Chord::residuals);
        inner.evaluate(th, jac)
    }
    fn gradient_only(&mut self, th: &[f64]) -> crate::Result<Option<Evaluation>> {
        self.grads += 1;
        let mut ev = ls(2, Chord::residuals).evaluate(th, true)?;
        ev.gauss_newton = Mat::zeros(0, 0);
        Ok(Some(ev))
    }
}

#[test]
fn chord_steps_reuse_the_gauss_newton_matrix_and_reach_the_same_minimum() {
    let mut o = Options::default();
    o.tol_cost = 0.0;
    o.tol_step = 0.0;
    o.tol_gradient = 1e-24;
    o.max_iter = 200;
    let mut plain = Chord { full: 0, grads: 0 };
    let a = go(&mut plain, &[1.0, 0.3], &o);
    o.reuse_gauss_newton = 3;
    let mut chord = Chord { full: 0, grads: 0 };
    let b = go(&mut chord, &[1.0, 0.3], &o);
    assert_eq!(plain.grads, 0);
    assert!(chord.grads > 0, "no chord step taken");
    // fewer Jacobians per iteration, same minimum, and the matrix returned is the one there
    assert!(
        (chord.full as f64) / (b.iterations as f64) < (plain.full as f64) / (a.iterations as f64)
    );
    for (x, y) in a.theta.iter().zip(&b.theta) {
        assert!((x - y).abs() < 1e-10, "{x} vs {y}");
    }
    assert!((b.theta[0] - 2.0).abs() < 1e-10 && (b.theta[1] - 0.7).abs() < 1e-10);
    let at = ls(2, Chord::residuals).evaluate(&b.theta, true).unwrap();
    assert!((&at.gauss_newton - &b.gauss_newton).norm_max() < 1e-12);
}

#[test]
fn cholesky_steps_reach_the_same_minimum() {
    // eigen_limit = 0 forces the large-problem path (one Cholesky solve per damped step)
    let mut o = Options::default();
    o.eigen_limit = 0;
    let sol = go(&mut ls(2, rosen), &[-1.2, 1.0], &o);
    assert!((sol.theta[0] - 1.0).abs() < 1e-8, "{:?}", sol.theta);
    assert!((sol.theta[1] - 1.0).abs() < 1e-8);
    assert!(sol.history.windows(2).all(|w| w[1] < w[0]));
    assert!(sol.condition.is_nan());
    let eig = go(&mut ls(3, linear), &[0.0; 3], &Options::default());
    let chol = go(&mut ls(3, linear), &[0.0; 3], &o);
    for a in 0..3 {
        assert!((eig.theta[a] - chol.theta[a]).abs() < 1e-9);
    }
    // bounds and fixed parameters hold on this path too
    let mut b = o.clone();
    b.upper = Some(vec![0.5, f64::INFINITY, f64::INFINITY]);
    b.fixed = Some(vec![false, false, true]);
    let mut pr = ls(3, linear);
    let s = go(&mut pr, &[0.0; 3], &b);
    assert!(pr.visited.iter().all(|t| t[0] <= 0.5 && t[2] == 0.0));
    assert_eq!(s.theta[0], 0.5);
}

/// Rosenbrock reporting `sqrt(2 cost)` (the residual norm) as its criterion, set in `accepted`.
struct Reporting {
    inner: Ls<fn(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)>,
    last: Option<f64>,
}

impl Problem for Reporting {
    fn n_params(&self) -> usize {
        2
    }
    fn evaluate(&mut self, th: &[f64], jac: bool) -> crate::Result<Evaluation> {
        self.inner.evaluate(th, jac)
    }
    fn accepted(&mut self, th: &[f64]) -> crate::Result<bool> {
        let c = self.inner.evaluate(th, false)?.cost;
        self.last = Some((2.0 * c).sqrt());
        Ok(false)
    }
    fn criterion(&self) -> Option<f64> {
        self.last
    }
}

#[test]
fn a_reported_criterion_replaces_the_cost_in_history_observer_and_result() {
    let th0 = [-1.2, 1.0];
    let mut prob = Reporting {
        inner: ls(2, rosen),
        last: None,
    };
    let c0 = prob.inner.evaluate(&th0, false).unwrap().cost;
    prob.last = Some((2.0 * c0).sqrt());
    let mut seen = Vec::new();
    let mut weighted = Vec::new();
    let sol = minimize(&mut prob, &th0, &Options::default(), &mut |it| {
        seen.push(it.cost);
        weighted.push(it.weighted_cost);
        Flow::Continue
    })
    .unwrap();
    assert!(sol.iterations > 3);
    assert_eq!(seen, sol.history[1..].to_vec());
    assert_eq!(weighted, sol.weighted_history[1..].to_vec());
    assert_eq!(sol.cost, *sol.history.last().unwrap());
    for (h, w) in sol.history.iter().zip(&sol.weighted_history) {
        assert!((h - (2.0 * w).sqrt()).abs() <= 1e-12 * (1.0 + h));
    }
}

/// A problem that must never be evaluated: its parameter count alone is refused.
struct Huge(usize);

impl Problem for Huge {
    fn n_params(&self) -> usize {
        self.0
    }
    fn evaluate(&mut self, _t: &[f64], _j: bool) -> crate::Result<Evaluation> {
        panic!("evaluated (and sized by the parameter count) before the count was checked")
    }
}

#[test]
fn parameter_counts_whose_normal_equations_cannot_fit_are_refused_first() {
    // 25 000 parameters: a 5 GB J^T J, which panicked in the allocator (pnlss)
    let p = 25_000;
    let e = minimize(
        &mut Huge(p),
        &vec![0.0; p],
        &Options::default(),
        &mut |_| Flow::Continue,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("25000 parameters") && e.contains("GiB limit"),
        "{e}"
    );
    let mut ok = ls(3, linear);
    assert!(minimize(&mut ok, &[0.0; 3], &Options::default(), &mut |_| {
        Flow::Continue
    })
    .is_ok());
}

/// Rosenbrock with a narrow curved valley: r = (1000 (y - x^2), 1 - x).
fn rosen1000(t: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    (
        vec![1000.0 * (t[1] - t[0] * t[0]), 1.0 - t[0]],
        vec![vec![-2000.0 * t[0], 1000.0], vec![-1.0, 0.0]],
    )
}

/// Geodesic acceleration (Transtrum & Sethna 2012) follows a narrow curved valley in far
/// fewer iterations than plain Levenberg-Marquardt, to the same minimum. A provider without
/// the hook runs exactly the plain search.
#[test]
fn geodesic_acceleration_takes_fewer_iterations() {
    let mut o = Options::default();
    o.max_iter = 500;
    o.tol_cost = 0.0;
    o.tol_step = 0.0;
    o.tol_gradient = 1e-24;
    type Case = (
        &'static str,
        fn(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>),
        Vec<f64>,
        Vec<f64>,
    );
    let cases: [Case; 2] = [
        ("rosenbrock", rosen1000, vec![-1.2, 1.0], vec![1.0, 1.0]),
        ("rosenbrock", rosen1000, vec![-3.0, -4.0], vec![1.0, 1.0]),
    ];
    for (name, f, start, truth) in cases {
        let mut plain = ls(start.len(), f);
        let ps = go(&mut plain, &start, &o);
        let mut hooked = ls(start.len(), f);
        hooked.geodesic = true;
        // off: the hook is never asked, the search is the plain one
        let off = go(&mut hooked, &start, &o);
        assert_eq!(off.theta, ps.theta, "{name}");
        assert_eq!(off.geodesic, GeodesicCounts::default());
        let mut og = o.clone();
        og.geodesic = true;
        let gs = go(&mut hooked, &start, &og);
        // without the hook the option changes nothing
        let mut nohook = ls(start.len(), f);
        let nh = go(&mut nohook, &start, &og);
        assert_eq!(nh.theta, ps.theta, "{name}");
        assert_eq!(nh.iterations, ps.iterations);
        assert_eq!(nh.geodesic, GeodesicCounts::default());
        eprintln!(
            "{name}: plain {} iterations ({} evaluations), geodesic {} ({}, {:?})",
            ps.iterations, ps.evaluations, gs.iterations, gs.evaluations, gs.geodesic
        );
        for (sol, what) in [(&ps, "plain"), (&gs, "geodesic")] {
            for (a, b) in sol.theta.iter().zip(&truth) {
                assert!((a - b).abs() < 1e-6, "{name} {what}: {:?}", sol.theta);
            }
        }
        assert!(gs.geodesic.accepted > 0, "{name}");
        assert!(
            2 * gs.iterations < ps.iterations,
            "{name}: {} vs {}",
            gs.iterations,
            ps.iterations
        );
    }
}

#[test]
fn a_capped_search_reports_how_far_it_stands_from_its_minimum() {
    // Rosenbrock's Jacobian is square and invertible: the Gauss-Newton step zeroes the
    // linearised residuals, so the predicted decrease is the whole cost, one residual
    // variance (2 cost / 2 residuals) exactly; any other stop reports NaN
    struct Counted<P: Problem>(P);
    impl<P: Problem> Problem for Counted<P> {
        fn n_params(&self) -> usize {
            self.0.n_params()
        }
        fn evaluate(&mut self, th: &[f64], jac: bool) -> crate::Result<Evaluation> {
            self.0.evaluate(th, jac)
        }
        fn n_residuals(&self) -> Option<usize> {
            Some(2)
        }
    }
    let mut o = Options::default();
    o.max_iter = 3;
    let capped = go(&mut Counted(ls(2, rosen)), &[-1.2, 1.0], &o);
    assert_eq!(capped.stop, StopReason::MaxIterations);
    assert!(
        (capped.remaining_decrease - 1.0).abs() < 1e-9,
        "{}",
        capped.remaining_decrease
    );
    let free = go(
        &mut Counted(ls(2, rosen)),
        &[-1.2, 1.0],
        &Options::default(),
    );
    assert_ne!(free.stop, StopReason::MaxIterations);
    assert!(free.remaining_decrease.is_nan());
    // a provider that does not count its residuals: unknown
    let uncounted = go(&mut ls(2, rosen), &[-1.2, 1.0], &o);
    assert!(uncounted.remaining_decrease.is_nan());
}

/// `Ls` counting its residuals (for the tests that need the residual variance).
struct Counted<F: FnMut(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)>(Ls<F>, usize);

impl<F: FnMut(&[f64]) -> (Vec<f64>, Vec<Vec<f64>>)> Problem for Counted<F> {
    fn n_params(&self) -> usize {
        self.0.n_params()
    }
    fn evaluate(&mut self, th: &[f64], jac: bool) -> crate::Result<Evaluation> {
        self.0.evaluate(th, jac)
    }
    fn n_residuals(&self) -> Option<usize> {
        Some(self.1)
    }
}

#[test]
fn significance_leaves_unsupported_directions_out_of_the_step() {
    // y = 1 + e: a level the data determine, and an alternating term (orthogonal to it) whose
    // least-squares coefficient is far inside its own standard deviation
    let n = 100;
    let e: Vec<f64> = (0..n).map(|k| (0.7 * k as f64).sin()).collect();
    let f = move |t: &[f64]| {
        let r = (0..n)
            .map(|k| t[0] + t[1] * if k % 2 == 0 { 1.0 } else { -1.0 } - 1.0 - e[k])
            .collect();
        let j = (0..n)
            .map(|k| vec![1.0, if k % 2 == 0 { 1.0 } else { -1.0 }])
            .collect();
        (r, j)
    };
    let fit = |significance: f64, eigen_limit: usize| {
        let mut o = Options::default();
        o.significance = significance;
        o.eigen_limit = eigen_limit;
        o.max_iter = 20;
        go(&mut Counted(ls(2, f.clone()), n), &[0.0, 0.0], &o).theta
    };
    let (ls_a, ls_b) = (fit(0.0, 400)[0], fit(0.0, 400)[1]);
    assert!(
        ls_b.abs() > 1e-4,
        "the alternating coefficient is not zero by itself: {ls_b}"
    );
    for limit in [400, 0] {
        let t = fit(1.0, limit);
        // the level moves from 0 to within its own standard deviation (0.07) of its
        // least-squares value (the search stops once no direction is worth one variance)
        assert!(
            (t[0] - ls_a).abs() < 0.05,
            "the level is still fitted: {t:?} ({ls_a})"
        );
        assert_eq!(
            t[1], 0.0,
            "the unsupported coefficient stays at its start: {t:?}"
        );
    }
}
