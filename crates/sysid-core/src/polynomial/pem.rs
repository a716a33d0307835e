//! Prediction-error providers for single-output polynomial structures (ARX, ARMAX, OE, BJ,
//! AR, ARMA), started from linear estimates and refined by [`crate::optim::minimize`].

use faer::{Mat, MatRef};

use super::filter::{conv, filter, is_stable, monic};
use super::initial::{self, InitialCondition, InitialState, Layout};
use super::start::guess_multi;
pub use super::start::{initial_guess, initial_guess_multi, steiglitz_mcbride};
use crate::error::{check_io, Result, SysidError};
use crate::optim::{minimize, Evaluation, Flow, Iteration, Options, Problem, Solution, StopReason};

/// Orders of `A y = sum B_j/F_j u_j(t-nk_j) + C/D e` for one output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MisoOrders {
    /// Order of A.
    pub na: usize,
    /// Coefficients of each B_j.
    pub nb: Vec<usize>,
    /// Order of C.
    pub nc: usize,
    /// Order of D.
    pub nd: usize,
    /// Order of each F_j.
    pub nf: Vec<usize>,
    /// Delay of each input.
    pub nk: Vec<usize>,
}

impl MisoOrders {
    /// Number of free parameters, laid out `[a, b_1.., b_m, c, d, f_1.., f_m]`.
    pub fn n_params(&self) -> usize {
        // saturating: absurd orders give usize::MAX, which every length check then refuses
        [self.na, self.nc, self.nd]
            .into_iter()
            .chain(self.nb.iter().copied())
            .chain(self.nf.iter().copied())
            .fold(0usize, |a, b| a.saturating_add(b))
    }
}

/// The polynomials of one output, split out of a parameter vector.
#[derive(Debug, Clone, PartialEq)]
pub struct MisoPolys {
    /// Monic A.
    pub a: Vec<f64>,
    /// B_j (b_0 first; applied to u_j(t - nk_j)).
    pub b: Vec<Vec<f64>>,
    /// Monic C.
    pub c: Vec<f64>,
    /// Monic D.
    pub d: Vec<f64>,
    /// Monic F_j.
    pub f: Vec<Vec<f64>>,
}

impl MisoOrders {
    /// Splits `theta` into polynomials.
    pub fn polys(&self, theta: &[f64]) -> MisoPolys {
        let mut i = 0;
        let mut take = |n: usize| {
            let s = theta[i..i + n].to_vec();
            i += n;
            s
        };
        let a = monic(&take(self.na));
        let b: Vec<Vec<f64>> = self.nb.iter().map(|&n| take(n)).collect();
        let c = monic(&take(self.nc));
        let d = monic(&take(self.nd));
        let f: Vec<Vec<f64>> = self.nf.iter().map(|&n| monic(&take(n))).collect();
        MisoPolys { a, b, c, d, f }
    }
}

/// A signal of several experiments: one vector per experiment.
pub(super) type Sig = Vec<Vec<f64>>;

/// Residual `e`, equation error `v` and filtered inputs `w_j` of one experiment.
type Signals = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// One experiment of a [`MisoProblem`]: the output and the delayed inputs.
struct Segment {
    y: Vec<f64>,
    x: Vec<Vec<f64>>,
}

/// Prediction-error problem of one output: residual `e = D/C (A y - sum B_j/F_j x_j)`,
/// `x_j(t) = u_j(t - nk_j)`, zero initial conditions (or, after
/// [`MisoProblem::estimate_initial`], each experiment's initial state eliminated by least
/// squares: [`super::initial`]). With several experiments the cost, gradient and Gauss-Newton
/// matrix are sums over the experiments, each filtered from its own initial state (no sample
/// of one experiment enters a regressor of another).
pub struct MisoProblem {
    orders: MisoOrders,
    segs: Vec<Segment>,
    block: usize,
    layout: Option<Layout>,
    /// `0.5 |y|^2 ROUNDOFF^2`: with the initial states estimated, a cost below it is zero.
    floor: f64,
    /// Admit unstable `F` ([`free_search`]); `C` stays stable (the predictor).
    free_f: bool,
}

pub(super) fn delayed(u: MatRef<'_, f64>, j: usize, nk: usize) -> Vec<f64> {
    let n = u.nrows();
    (0..n)
        .map(|t| if t >= nk { u[(t - nk, j)] } else { 0.0 })
        .collect()
}

pub(super) fn shifted(s: &[f64], t: usize, k: usize) -> f64 {
    if t >= k {
        s[t - k]
    } else {
        0.0
    }
}

/// Checks one output's experiments against `orders`; returns the total sample count.
pub(super) fn check_experiments(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    orders: &MisoOrders,
) -> Result<usize> {
    let Some(first) = experiments.first() else {
        return Err(SysidError::invalid(
            "experiments",
            "needs at least one (y, u) record",
        ));
    };
    let m = first.1.ncols();
    if orders.nb.len() != m || orders.nf.len() != m || orders.nk.len() != m {
        return Err(SysidError::invalid(
            "orders",
            format!("nb, nf and nk need one entry per input ({m})"),
        ));
    }
    for (y, u) in experiments {
        let yv = MatRef::from_column_major_slice(y, y.len(), 1);
        check_io("u, y", *u, yv, m, 1)?;
    }
    let p = orders.n_params();
    if p == 0 {
        return Err(SysidError::invalid(
            "orders",
            "the structure has no parameters",
        ));
    }
    let total: usize = experiments.iter().map(|e| e.0.len()).sum();
    let longest = experiments.iter().map(|e| e.0.len()).max().unwrap_or(0);
    let need = p.saturating_mul(2).saturating_add(2);
    if total < need || orders.nk.iter().any(|&k| k >= longest) {
        return Err(SysidError::InsufficientData {
            context: format!(
                "a polynomial model with {p} parameters and delays nk={:?}",
                orders.nk
            ),
            needed: need.max(orders.nk.iter().max().map_or(0, |k| k.saturating_add(1))),
            got: total,
            fix: "use a longer record or smaller orders",
        });
    }
    Ok(total)
}

impl MisoProblem {
    /// Output column `y` (length N) and inputs `u` (N x m).
    pub fn new(y: &[f64], u: MatRef<'_, f64>, orders: MisoOrders) -> Result<Self> {
        Self::new_multi(&[(y, u)], orders)
    }

    /// Several experiments `(y, u)` of the same output and inputs (lengths may differ).
    pub fn new_multi(
        experiments: &[(&[f64], MatRef<'_, f64>)],
        orders: MisoOrders,
    ) -> Result<Self> {
        check_experiments(experiments, &orders)?;
        let energy: f64 = experiments
            .iter()
            .map(|(y, _)| y.iter().map(|v| v * v).sum::<f64>())
            .sum();
        let segs = experiments
            .iter()
            .map(|(y, u)| Segment {
                y: y.to_vec(),
                x: (0..u.ncols())
                    .map(|j| delayed(*u, j, orders.nk[j]))
                    .collect(),
            })
            .collect();
        Ok(Self {
            orders,
            segs,
            block: 128,
            layout: None,
            floor: 0.5 * energy * initial::ROUNDOFF * initial::ROUNDOFF,
            free_f: false,
        })
    }

    /// With `on`, every experiment's initial state is estimated (eliminated by least squares
    /// at every evaluation); without, the predictors start from rest.
    pub fn estimate_initial(&mut self, on: bool) {
        self.layout = on.then(|| Layout::new(&self.orders));
    }

    /// Initial coefficients of all experiments together (0 from rest).
    pub fn n_initial(&self) -> usize {
        self.layout
            .as_ref()
            .map_or(0, |l| l.len() * self.segs.len())
    }

    /// [`initial::chance_drop`] summed over the experiments at `theta` (state estimated).
    pub fn chance_drop(&self, theta: &[f64]) -> f64 {
        let p = self.orders.polys(theta);
        self.segs
            .iter()
            .map(|s| match self.solved(s, &p) {
                ((e, _, _), Some(pr)) => initial::chance_drop(&e, &pr.q),
                _ => 0.0,
            })
            .sum()
    }

    /// Each experiment's initial state at `theta` (zeros from rest).
    pub fn initial_states(&self, theta: &[f64]) -> Vec<InitialState> {
        let p = self.orders.polys(theta);
        let zero = InitialState::zeros(&Layout::new(&self.orders));
        self.segs
            .iter()
            .map(|s| match self.solved(s, &p) {
                (_, Some(pr)) => pr.state,
                _ => zero.clone(),
            })
            .collect()
    }

    /// One experiment's signals at its initial state (fitted, or zero) and the projection.
    fn solved(&self, seg: &Segment, p: &MisoPolys) -> (Signals, Option<initial::Projection>) {
        let s0 = Self::signals(seg, p, None);
        match &self.layout {
            Some(l) if s0.0.iter().all(|v| v.is_finite()) => {
                let pr = initial::project(&s0.0, p, l);
                (Self::signals(seg, p, Some(&pr.state)), Some(pr))
            }
            _ => (s0, None),
        }
    }

    /// Residuals and the intermediate signals `(e, v, w_j)` of one experiment, from rest or
    /// from the initial state `h`.
    fn signals(seg: &Segment, p: &MisoPolys, h: Option<&InitialState>) -> Signals {
        let n = seg.y.len();
        let w: Vec<Vec<f64>> = (0..seg.x.len())
            .map(|j| {
                let mut wj = filter(&p.b[j], &p.f[j], &seg.x[j]);
                if let Some(hj) = h.map(|h| &h.input[j]).filter(|hj| !hj.is_empty()) {
                    let free = InitialState::response(hj, &p.f[j], n);
                    wj.iter_mut().zip(&free).for_each(|(a, b)| *a += b);
                }
                wj
            })
            .collect();
        let mut v = filter(&p.a, &[1.0], &seg.y);
        for wj in &w {
            for (vt, wt) in v.iter_mut().zip(wj) {
                *vt -= wt;
            }
        }
        let mut e = filter(&p.d, &p.c, &v);
        if let Some(he) = h.map(|h| &h.noise).filter(|he| !he.is_empty()) {
            let free = InitialState::response(he, &p.c, n);
            e.iter_mut().zip(&free).for_each(|(a, b)| *a += b);
        }
        (e, v, w)
    }

    /// Residuals at `theta`, experiment after experiment (each from rest, or from its
    /// fitted initial state).
    pub fn residuals(&self, theta: &[f64]) -> Vec<f64> {
        let p = self.orders.polys(theta);
        self.segs
            .iter()
            .flat_map(|s| self.solved(s, &p).0 .0)
            .collect()
    }

    /// Adds one experiment's `J^T J` and `J^T e` (blocks of `self.block` rows) to `gn`, `grad`;
    /// with the basis `q` of its initial state's columns, `J^T J - (J^T q)(q^T J)`.
    fn accumulate(
        &self,
        seg: &Segment,
        p: &MisoPolys,
        signals: &Signals,
        q: Option<&Mat<f64>>,
        gn: &mut Mat<f64>,
        grad: &mut [f64],
    ) {
        let (e, v, w) = signals;
        let o = &self.orders;
        let np = o.n_params();
        let n = seg.y.len();
        let nx = seg.x.len();
        let ya = filter(&p.d, &p.c, &seg.y);
        let cf: Vec<Vec<f64>> = p.f.iter().map(|f| conv(&p.c, f)).collect();
        let xf: Vec<Vec<f64>> = (0..nx).map(|j| filter(&p.d, &cf[j], &seg.x[j])).collect();
        let wf: Vec<Vec<f64>> = (0..nx)
            .map(|j| {
                if o.nf[j] > 0 {
                    filter(&p.d, &cf[j], &w[j])
                } else {
                    Vec::new()
                }
            })
            .collect();
        let ec = if o.nc > 0 {
            filter(&[1.0], &p.c, e)
        } else {
            Vec::new()
        };
        let vc = if o.nd > 0 {
            filter(&[1.0], &p.c, v)
        } else {
            Vec::new()
        };
        let mut jb = Mat::<f64>::zeros(self.block, np);
        let mut eb = Mat::<f64>::zeros(self.block, 1);
        let mut jq = Mat::<f64>::zeros(np, q.map_or(0, |q| q.ncols()));
        let mut t0 = 0;
        while t0 < n {
            let rows = self.block.min(n - t0);
            for r in 0..rows {
                let t = t0 + r;
                let mut c = 0;
                for k in 1..=o.na {
                    jb[(r, c)] = shifted(&ya, t, k);
                    c += 1;
                }
                for j in 0..nx {
                    for k in 0..o.nb[j] {
                        jb[(r, c)] = -shifted(&xf[j], t, k);
                        c += 1;
                    }
                }
                for k in 1..=o.nc {
                    jb[(r, c)] = -shifted(&ec, t, k);
                    c += 1;
                }
                for k in 1..=o.nd {
                    jb[(r, c)] = shifted(&vc, t, k);
                    c += 1;
                }
                for j in 0..nx {
                    for k in 1..=o.nf[j] {
                        jb[(r, c)] = shifted(&wf[j], t, k);
                        c += 1;
                    }
                }
                eb[(r, 0)] = e[t];
            }
            let jr = jb.as_ref().subrows(0, rows);
            *gn += jr.transpose() * jr;
            let g = jr.transpose() * eb.as_ref().subrows(0, rows);
            for a in 0..np {
                grad[a] += g[(a, 0)];
            }
            if let Some(q) = q {
                jq += jr.transpose() * q.as_ref().subrows(t0, rows);
            }
            t0 += rows;
        }
        if jq.ncols() > 0 {
            *gn -= &jq * jq.transpose();
        }
    }
}

impl Problem for MisoProblem {
    fn n_params(&self) -> usize {
        self.orders.n_params()
    }

    /// Every sample of every experiment is one residual of the cost `0.5 sum e^2` (for the
    /// distance from the minimum at a cap; this search has no statistical stop).
    fn n_residuals(&self) -> Option<usize> {
        Some(self.segs.iter().map(|s| s.y.len()).sum())
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        let p = self.orders.polys(theta);
        is_stable(&p.c) && (self.free_f || p.f.iter().all(|f| is_stable(f)))
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let o = &self.orders;
        let p = o.polys(theta);
        let (sigs, qs): (Vec<_>, Vec<_>) = self.segs.iter().map(|s| self.solved(s, &p)).unzip();
        let mut cost = 0.5
            * sigs
                .iter()
                .map(|(e, _, _)| e.iter().map(|x| x * x).sum::<f64>())
                .sum::<f64>();
        if self.layout.is_some() && cost <= self.floor {
            cost = 0.0; // an exact fit: what is left is round-off, with no direction to follow
        }
        if !cost.is_finite() {
            return Ok(Evaluation::cost_only(f64::INFINITY));
        }
        let mut ev = Evaluation::cost_only(cost);
        if !jacobian {
            return Ok(ev);
        }
        let np = o.n_params();
        let mut gn = Mat::<f64>::zeros(np, np);
        let mut grad = vec![0.0; np];
        for ((seg, sig), pr) in self.segs.iter().zip(&sigs).zip(&qs) {
            let q = pr.as_ref().map(|pr| &pr.q);
            self.accumulate(seg, &p, sig, q, &mut gn, &mut grad);
        }
        ev.gradient = grad;
        ev.gauss_newton = gn;
        Ok(ev)
    }
}

/// Result of [`estimate`].
#[derive(Debug, Clone)]
pub struct MisoEstimate {
    /// The search's solution (theta, cost, iterations, stop reason, J^T J).
    pub solution: Solution,
    /// The starting point.
    pub theta0: Vec<f64>,
    /// Innovation variance estimate `2 cost / N`.
    pub noise_variance: f64,
    /// Parameter covariance `noise_variance * (J^T J)^+` (with the initial states estimated,
    /// `J^T J` is the Schur complement: the marginal covariance).
    pub covariance: Mat<f64>,
    /// How the initial conditions were set: `Zero` or `Estimate` (`Auto` has chosen).
    pub initial: InitialCondition,
    /// Each experiment's initial state (zeros from rest).
    pub initial_states: Vec<InitialState>,
    /// With `Auto`: the costs from rest and with the initial states eliminated at the fit from
    /// rest, which decided ([`initial::worth_estimating`]).
    pub auto_costs: Option<(f64, f64)>,
}

/// Prediction-error estimate of one output's polynomial model, from `theta0` or (when `None`)
/// from [`initial_guess`].
pub fn estimate(
    y: &[f64],
    u: MatRef<'_, f64>,
    orders: MisoOrders,
    theta0: Option<&[f64]>,
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<MisoEstimate> {
    estimate_multi(&[(y, u)], orders, theta0, options, observer)
}

/// [`estimate`] from several experiments `(y, u)`: the cost is the sum of the experiments'
/// squared prediction errors, each experiment's predictor started from rest; the noise
/// variance is `2 cost / (total samples)` and the covariance `noise_variance (J^T J)^+` with
/// `J^T J` summed over the experiments.
pub fn estimate_multi(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    orders: MisoOrders,
    theta0: Option<&[f64]>,
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<MisoEstimate> {
    let ic = InitialCondition::Zero;
    estimate_with(experiments, orders, theta0, ic, options, observer)
}

/// `theta` (named `name`) has one entry per parameter of `orders`.
fn check_length(name: &'static str, theta: &[f64], orders: &MisoOrders) -> Result<()> {
    if theta.len() != orders.n_params() {
        return Err(SysidError::invalid(
            name,
            format!(
                "has {} entries but the structure has {}",
                theta.len(),
                orders.n_params()
            ),
        ));
    }
    Ok(())
}

/// The search of one output's model from `theta` (a fit whose `F` was kept stable) with `F`
/// free to leave the unit circle, the initial conditions `Zero` or `Estimate` as that fit
/// chose: the criterion at `theta` and the free search's solution, for the test whether the
/// data insist on an unstable `F` ([`crate::pem::insists`]).
pub fn free_search(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    orders: MisoOrders,
    theta: &[f64],
    initial: InitialCondition,
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<(f64, Solution)> {
    check_length("theta", theta, &orders)?;
    let mut prob = MisoProblem::new_multi(experiments, orders)?;
    prob.estimate_initial(initial == InitialCondition::Estimate);
    prob.free_f = true;
    let kept = prob.evaluate(theta, false)?.cost;
    let solution = minimize(&mut prob, theta, options, observer)?;
    Ok((kept, solution))
}

/// [`estimate_multi`] with the initial conditions set by `initial` ([`super::initial`]):
/// `Estimate` eliminates each experiment's initial state at every evaluation; `Auto` searches
/// from rest and then, when [`initial::worth_estimating`] at that fit, again from it with the
/// initial states estimated.
pub fn estimate_with(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    orders: MisoOrders,
    theta0: Option<&[f64]>,
    initial: InitialCondition,
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<MisoEstimate> {
    let mut prob = MisoProblem::new_multi(experiments, orders.clone())?;
    prob.estimate_initial(initial == InitialCondition::Estimate);
    let mut th0 = match theta0 {
        Some(t) => {
            check_length("theta0", t, &orders)?;
            t.to_vec()
        }
        None => initial_guess_multi(experiments, &orders)?,
    };
    if !prob.admissible(&th0) {
        if theta0.is_some() {
            return Err(SysidError::invalid(
                "theta0",
                "C or F is not stable at the start",
            ));
        }
        th0 = vec![0.0; orders.n_params()];
    }
    let mut solution = minimize(&mut prob, &th0, options, observer)?;
    // several inputs with an output-error part: the search also runs from the least-squares
    // impulse responses with F = 1, and the lower final cost is kept (neither start reaches
    // the better minimum on every record: the sweeps' start lowered a steam generator's cost
    // fourfold and raised a winding process's by a quarter)
    let several =
        experiments.first().is_some_and(|e| e.1.ncols() > 1) && orders.nf.iter().any(|&f| f > 0);
    if theta0.is_none() && several && solution.stop != StopReason::Cancelled {
        let alt = guess_multi(experiments, &orders, false)?;
        if alt != th0 && prob.admissible(&alt) {
            let other = minimize(&mut prob, &alt, options, observer)?;
            if other.cost < solution.cost * (1.0 - 1e-9) {
                solution = other;
                th0 = alt;
            }
        }
    }
    let n: usize = experiments.iter().map(|e| e.0.len()).sum();
    let mut chosen = initial;
    let mut auto_costs = None;
    if initial == InitialCondition::Auto {
        chosen = InitialCondition::Zero;
        if solution.stop != StopReason::Cancelled {
            prob.estimate_initial(true);
            let with = prob.evaluate(&solution.theta, false)?.cost;
            let chance = prob.chance_drop(&solution.theta);
            prob.estimate_initial(false);
            if initial::worth_estimating(solution.cost, with, chance) {
                // what "estimate" gives, from the same start (the fit from rest carries the
                // transient's bias, in directions the data may not determine)
                let ic = InitialCondition::Estimate;
                let mut est = estimate_with(experiments, orders, theta0, ic, options, observer)?;
                est.auto_costs = Some((solution.cost, with));
                return Ok(est);
            }
            auto_costs = Some((solution.cost, with));
        }
    }
    let noise_variance = 2.0 * solution.cost / n as f64;
    let cov = crate::optim::covariance(solution.gauss_newton.as_ref(), noise_variance, 1e-10)?;
    let initial_states = prob.initial_states(&solution.theta);
    Ok(MisoEstimate {
        solution,
        theta0: th0,
        noise_variance,
        covariance: cov.covariance,
        initial: chosen,
        initial_states,
        auto_costs,
    })
}
