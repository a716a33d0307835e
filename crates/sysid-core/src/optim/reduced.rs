//! The step problem of one iterate of [`super::minimize`]: the Gauss-Newton matrix scaled and
//! reduced to the free directions, solved by an eigendecomposition (small problems) or by
//! Cholesky factorisations (large ones).

use super::dense::{small_par, symmetric_eigen};
use super::search::{prof, Point};
use super::{Options, Problem};
use crate::error::{Result, SysidError};
use faer::linalg::matmul::matmul;
use faer::prelude::Solve;
use faer::{Accum, Mat, Side};

/// How the damped steps are solved at one point.
pub(super) enum Solver {
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
pub(super) struct Reduced {
    /// Marquardt scaling (of z for `Eigen`, of theta for `Cholesky`).
    pub d: Vec<f64>,
    /// Scaled reduced gradient.
    pub gs: Vec<f64>,
    pub condition: f64,
    pub solver: Solver,
    /// The blocked parameters it was formed with.
    pub blocked: Vec<bool>,
    /// The point it was formed at.
    pub at: Vec<f64>,
    /// The scaled orthonormal basis of the invariant directions at `at`, once a chord step
    /// asked for it (every chord step from this matrix removes the same directions).
    pub orbit: Option<Mat<f64>>,
    /// The decrease (cost units) below which an eigendirection is left out of the steps
    /// ([`Options::significance`]; 0: none is).
    pub gate: f64,
    /// Whether the provider gave a search basis (then a second metric gives other steps).
    pub basis_given: bool,
    /// The metric that basis is orthonormal in.
    pub metric: Metric,
}

/// Smallest damping (relative to the largest eigenvalue) of a Cholesky solve: the similarity
/// directions of a state-space model are an exact null space of `J^T W J`, orthogonal to the
/// gradient, so a tiny shift leaves the step in their complement.
const CHOLESKY_FLOOR: f64 = 1e-10;

/// The metric a provider's search basis is orthonormal in ([`Problem::search_basis`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Metric {
    /// Marquardt's scaling (the Gauss-Newton diagonal): steps of parameters whose effects
    /// differ by orders of magnitude (an unstable plant's growing state) stay balanced.
    Marquardt,
    /// The parameters themselves: the similarity part of a step is the smallest in them,
    /// which keeps a step that corrects a gain from spreading into `A` and `C`.
    Plain,
}

pub(super) fn reduce(
    problem: &mut dyn Problem,
    opt: &Options,
    pt: &Point,
    blocked: &[bool],
    metric_kind: Metric,
) -> Result<Reduced> {
    let p = pt.theta.len();
    let n_free = blocked.iter().filter(|&&b| !b).count();
    let gate = significance_gate(&*problem, opt, pt);
    if n_free > opt.eigen_limit && gate == 0.0 {
        return Ok(reduce_cholesky(pt, blocked));
    }
    let t0 = std::time::Instant::now();
    // the basis's metric: Marquardt's is the full-space scaling of the Cholesky path
    let metric: Vec<f64> = match metric_kind {
        Metric::Marquardt => (0..p)
            .map(|i| pt.diagonal(i).map_or(1.0, f64::sqrt))
            .collect(),
        Metric::Plain => vec![1.0; p],
    };
    let basis = problem.search_basis(&pt.theta, &metric)?;
    prof("basis", t0);
    let t0 = std::time::Instant::now();
    let basis_given = basis.is_some();
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
    // Blocked parameters (fixed or at an active bound) never move, whatever the basis says;
    // in Marquardt's metric nor do those the cost does not see at this point (a zero column
    // of the Jacobian: a mode with B = C = 0 exactly), which such a basis would otherwise move
    // by rounding, to values the rank of the Gauss-Newton matrix no longer shows as idle.
    let idle: Vec<bool> = (0..p)
        .map(|i| {
            blocked[i] || (basis_given && metric_kind == Metric::Marquardt && pt.h[(i, i)] == 0.0)
        })
        .collect();
    if idle.iter().any(|&b| b) {
        for i in 0..p {
            if idle[i] {
                for j in 0..t.ncols() {
                    t[(i, j)] = 0.0;
                }
            }
        }
    }
    let q = t.ncols();
    let par = small_par(p, q);
    let mut ht = Mat::<f64>::zeros(p, q);
    matmul(
        ht.as_mut(),
        Accum::Replace,
        pt.h.as_ref(),
        t.as_ref(),
        1.0,
        par,
    );
    let mut hr = Mat::<f64>::zeros(q, q);
    matmul(
        hr.as_mut(),
        Accum::Replace,
        t.transpose(),
        ht.as_ref(),
        1.0,
        par,
    );
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
        let (u, s) = symmetric_eigen(&hs, "optimiser (eigenvalues of J^T J)")?;
        let lam: Vec<f64> = (0..q).map(|i| s[i].max(0.0)).collect();
        (u, lam)
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
        orbit: None,
        gate,
        basis_given,
        metric: metric_kind,
    };
    red.set_gradient(&pt.g);
    Ok(red)
}

/// [`Options::significance`] in cost units at `pt` (0 when off or the residuals are not
/// counted).
fn significance_gate(problem: &dyn Problem, opt: &Options, pt: &Point) -> f64 {
    match problem.n_residuals() {
        Some(n) if opt.significance > 0.0 && pt.raw.cost.is_finite() => {
            opt.significance * 2.0 * pt.raw.cost / n.max(1) as f64
        }
        _ => 0.0,
    }
}

/// The large-problem form of [`reduce`]: no basis and no eigendecomposition.
fn reduce_cholesky(pt: &Point, blocked: &[bool]) -> Reduced {
    let t0 = std::time::Instant::now();
    let p = pt.theta.len();
    let d: Vec<f64> = (0..p)
        .map(|i| {
            pt.diagonal(i)
                .filter(|_| !blocked[i])
                .map_or(1.0, f64::sqrt)
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
        orbit: None,
        gate: 0.0,
        basis_given: false,
        metric: Metric::Plain,
    };
    red.set_gradient(&pt.g);
    prof("reduce-cholesky", t0);
    red
}

impl Reduced {
    /// For a chord step of the Cholesky solver: removes from the scaled gradient its part
    /// along `orbit`, the directions in which the cost was invariant where the matrix was
    /// formed. They are null directions of that matrix, which the damping floor would
    /// otherwise amplify: the new gradient is not orthogonal to them.
    pub(super) fn remove_orbit(&mut self) {
        let Some(q) = &self.orbit else {
            return;
        };
        let g = Mat::from_fn(self.gs.len(), 1, |i, _| self.gs[i]);
        let c = q.transpose() * &g;
        let r = &g - q * &c;
        for (i, v) in self.gs.iter_mut().enumerate() {
            *v = r[(i, 0)];
        }
    }

    /// An orthonormal basis of `dirs` in the scaled coordinates (`None` when there is
    /// nothing to remove).
    pub(super) fn scaled_basis(&self, dirs: &Mat<f64>) -> Option<Mat<f64>> {
        if !matches!(self.solver, Solver::Cholesky { .. }) || dirs.nrows() != self.gs.len() {
            return None;
        }
        let ds = Mat::from_fn(dirs.nrows(), dirs.ncols(), |i, j| {
            if self.blocked[i] {
                0.0
            } else {
                self.d[i] * dirs[(i, j)]
            }
        });
        if ds.ncols() == 0 || !ds.norm_max().is_finite() {
            return None;
        }
        Some(crate::linalg::thin_q_seq(ds.as_ref()))
    }

    /// Sets the scaled reduced gradient from the full gradient `g` (also used to reuse the
    /// factorisation at a new point for a chord step).
    pub(super) fn set_gradient(&mut self, g: &[f64]) {
        self.gs = self.scaled_gradient(g);
    }

    /// A full-space gradient-like vector `g` (p) in the scaled reduced coordinates.
    fn scaled_gradient(&self, g: &[f64]) -> Vec<f64> {
        match &self.solver {
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
        }
    }

    /// The norm of a full-space step `s` in the scaled coordinates the damping measures
    /// (`|D z|` with `s = T z`).
    pub(super) fn scaled_norm(&self, s: &[f64]) -> f64 {
        let sq: f64 = match &self.solver {
            Solver::Eigen { t, .. } if self.metric == Metric::Plain => (0..t.ncols())
                .map(|j| {
                    let z: f64 = (0..t.nrows()).map(|i| t[(i, j)] * s[i]).sum();
                    (self.d[j] * z).powi(2)
                })
                .sum(),
            Solver::Eigen { t, .. } => {
                // z with s = T z: the basis is orthonormal in the problem's metric, not in
                // theta, so z solves the normal equations of T
                let q = t.ncols();
                let ts = t.transpose() * Mat::from_fn(s.len(), 1, |i, _| s[i]);
                let gram = t.transpose() * t;
                let z = match gram.llt(Side::Lower) {
                    Ok(f) => f.solve(&ts),
                    Err(_) => return f64::NAN,
                };
                (0..q).map(|j| (self.d[j] * z[(j, 0)]).powi(2)).sum()
            }
            Solver::Cholesky { .. } => (0..s.len())
                .filter(|&i| !self.blocked[i])
                .map(|i| (self.d[i] * s[i]).powi(2))
                .sum(),
        };
        sq.sqrt()
    }

    /// `-(H + mu D)^-1 g` for another right-hand side `g` (full space, p) with the damped
    /// matrix of [`Self::step`]: the geodesic acceleration from `J^T W r_vv`.
    pub(super) fn step_for(&self, g: &[f64], mu: f64, rank_tol: f64) -> Vec<f64> {
        self.solve(&self.scaled_gradient(g), mu, rank_tol)
    }

    /// `(hs + shift I)^-1 gs` by Cholesky, raising the shift until it factors.
    pub(super) fn cholesky_solve(hs: &Mat<f64>, gs: &[f64], mut shift: f64) -> Vec<f64> {
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

    /// The eigendirections a step may take: those whose own Gauss-Newton decrease along the
    /// gradient `gs` reaches [`Self::gate`] (all when it is 0).
    fn kept(&self, v: &Mat<f64>, lam: &[f64]) -> Vec<bool> {
        let q = lam.len();
        if self.gate <= 0.0 {
            return vec![true; q];
        }
        (0..q)
            .map(|k| {
                let proj: f64 = (0..q).map(|i| v[(i, k)] * self.gs[i]).sum();
                lam[k] > 0.0 && 0.5 * proj * proj / lam[k] >= self.gate
            })
            .collect()
    }

    /// Full-space step for damping `mu` (relative to the largest eigenvalue); `mu = 0` gives the
    /// Gauss-Newton step through the pseudo-inverse.
    pub(super) fn step(&self, mu: f64, rank_tol: f64) -> Vec<f64> {
        self.solve(&self.gs, mu, rank_tol)
    }

    /// The damped step for the scaled reduced gradient `gs`.
    fn solve(&self, gs: &[f64], mu: f64, rank_tol: f64) -> Vec<f64> {
        let (t, v, lam) = match &self.solver {
            Solver::Eigen { t, v, lam } => (t, v, lam),
            Solver::Cholesky { hs, lmax } => {
                let z = Self::cholesky_solve(hs, gs, mu.max(CHOLESKY_FLOOR) * lmax);
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
        let kept = self.kept(v, lam);
        let mut c = vec![0.0; q];
        for k in 0..q {
            let proj: f64 = (0..q).map(|i| v[(i, k)] * gs[i]).sum();
            let den = lam[k] + mu * lmax;
            if kept[k] && (lam[k] > rank_tol * lmax || mu > 0.0) {
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

    /// A lower bound of [`Self::gn_decrease`] that needs no solve, for the large problems
    /// whose every solve is a Cholesky factorisation (`None` for the eigendecomposition,
    /// where the decrease itself is cheap): the eigenvalues of the scaled matrix plus its
    /// shift are at most its trace plus the shift, so `g^T (H + c I)^-1 g >= |g|^2 / (tr H + c)`.
    pub(super) fn decrease_lower_bound(&self) -> Option<f64> {
        let Solver::Cholesky { hs, lmax } = &self.solver else {
            return None;
        };
        let trace: f64 = (0..hs.nrows()).map(|i| hs[(i, i)].max(0.0)).sum();
        let g2: f64 = self.gs.iter().map(|v| v * v).sum();
        let bound = 0.5 * g2 / (trace + CHOLESKY_FLOOR * lmax);
        bound.is_finite().then_some(bound)
    }

    /// Predicted decrease of the Gauss-Newton step (`g^T H^+ g / 2`, scaled reduced problem).
    pub(super) fn gn_decrease(&self, rank_tol: f64) -> f64 {
        let (v, lam) = match &self.solver {
            Solver::Eigen { v, lam, .. } => (v, lam),
            Solver::Cholesky { hs, lmax } => {
                let z = Self::cholesky_solve(hs, &self.gs, CHOLESKY_FLOOR * lmax);
                return 0.5 * z.iter().zip(&self.gs).map(|(a, b)| a * b).sum::<f64>();
            }
        };
        let q = lam.len();
        let lmax = lam.iter().copied().fold(0.0, f64::max);
        let kept = self.kept(v, lam);
        let mut s = 0.0;
        for k in 0..q {
            if kept[k] && lam[k] > rank_tol * lmax && lam[k] > 0.0 {
                let proj: f64 = (0..q).map(|i| v[(i, k)] * self.gs[i]).sum();
                s += proj * proj / lam[k];
            }
        }
        0.5 * s
    }
}
