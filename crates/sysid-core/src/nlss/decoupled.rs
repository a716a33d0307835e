//! The decoupled PNLSS model: the state equation's multivariate polynomial replaced by a sum
//! of univariate polynomials of linear forms of `z = [x; u]`,
//!
//! ```text
//! x(t+1) = A x + B u + W g(V z) + e0        y(t) = C x + D u + f0
//! g_k(s) = sum_d c_{k,d} s^d                 (d in the chosen degrees, each >= 2)
//! ```
//!
//! With `r` branches the nonlinear part has `r (nx + nu + nx + n_degrees)` parameters instead
//! of `nx` times the number of monomials, which grows as `(nx + nu)^degree`. Fitted on the
//! simulation error like [`super::Pnlss`], with forward sensitivities
//! `S(t+1) = (A + W diag(g'(s)) V_x) S(t) + df/dtheta`. The branch arguments `s` may be
//! clamped to a box (the branch then holds its boundary value and has no slope), which
//! bounds the simulation outside the range the model was fitted on.

use super::simulation::{self, check_range, NonlinearTerms};
use super::PnlssData;
use crate::error::{Result, SysidError};
use crate::optim::{Evaluation, Flow, Iteration, Options, Solution};
use faer::Mat;

/// Structure of a decoupled PNLSS model; the parameters are
/// `theta = [A, B, C, D, V, W, c, e0, f0]`, each row-major (`V` is `r x (nx + nu)`, `W` is
/// `nx x r`, `c` is `r x degrees.len()`).
///
/// ```
/// use sysid_core::nlss::Decoupled;
/// // x(t+1) = 0.5 x + u - 0.1 (x + u)^2 (one branch), y = x
/// let m = Decoupled::new(1, 1, 1, 1, vec![2]).unwrap();
/// let theta = [0.5, 1.0, 1.0, 0.0, 1.0, 1.0, -0.1, 1.0, 0.0, 0.0];
/// let (y, _) = m.simulate(&theta, &[1.0, 0.0, 0.0], None).unwrap();
/// assert!((y[1] - 0.9).abs() < 1e-15 && (y[2] - (0.45 - 0.081)).abs() < 1e-15);
/// ```
#[derive(Debug, Clone)]
pub struct Decoupled {
    /// States.
    pub nx: usize,
    /// Inputs.
    pub nu: usize,
    /// Outputs.
    pub ny: usize,
    /// Branches (univariate polynomials).
    pub branches: usize,
    /// Degrees of each branch polynomial.
    pub degrees: Vec<usize>,
    /// A simulation whose state exceeds this in absolute value has diverged.
    pub bound: f64,
    /// Lower ends of the branch arguments' box (empty: no clamping).
    pub lo: Vec<f64>,
    /// Upper ends of that box.
    pub hi: Vec<f64>,
    /// Whether a fit keeps the linear part's `A` stable (see [`Decoupled::with_stable_linear`]).
    pub stable_linear: bool,
}

#[derive(Clone, Copy)]
struct Off {
    v: usize,
    w: usize,
    k: usize,
    e0: usize,
    f0: usize,
    p: usize,
}

/// One step's branch values: arguments (clamped), values and slopes.
pub(super) struct Work {
    o: Off,
    z: Vec<f64>,
    s: Vec<f64>,
    g: Vec<f64>,
    gp: Vec<f64>,
}

impl Decoupled {
    /// A model with `branches` univariate polynomials of the given degrees (each in 2..9).
    pub fn new(
        nx: usize,
        nu: usize,
        ny: usize,
        branches: usize,
        mut degrees: Vec<usize>,
    ) -> Result<Self> {
        if let Some(d) = degrees.iter().find(|&&d| !(2..=9).contains(&d)) {
            return Err(SysidError::invalid(
                "degree",
                format!("branch degrees must lie in 2..9, got {d}"),
            ));
        }
        if branches == 0 || degrees.is_empty() {
            return Err(SysidError::invalid(
                "branches",
                "needs at least one branch and one degree",
            ));
        }
        degrees.sort_unstable();
        degrees.dedup();
        Ok(Decoupled {
            nx,
            nu,
            ny,
            branches,
            degrees,
            bound: 1e8,
            lo: Vec::new(),
            hi: Vec::new(),
            stable_linear: false,
        })
    }

    /// The model whose fits keep the spectral radius of the linear part's `A` below 1
    /// (as [`crate::nlss::Pnlss::with_stable_linear`]).
    ///
    /// ```
    /// use sysid_core::nlss::Decoupled;
    /// let m = Decoupled::new(2, 1, 1, 1, vec![2]).unwrap().with_stable_linear();
    /// assert!(m.stable_linear);
    /// ```
    pub fn with_stable_linear(mut self) -> Self {
        self.stable_linear = true;
        self
    }

    /// The model with the branch arguments clamped to `lo <= s <= hi` (one pair per branch).
    pub fn with_range(mut self, lo: Vec<f64>, hi: Vec<f64>) -> Result<Self> {
        check_range(&lo, &hi, self.branches, "one per branch")?;
        self.lo = lo;
        self.hi = hi;
        Ok(self)
    }

    fn off(&self) -> Off {
        let (n, m, l, r) = (self.nx, self.nu, self.ny, self.branches);
        let v = n * n + n * m + l * n + l * m;
        let w = v + r * (n + m);
        let k = w + n * r;
        let e0 = k + r * self.degrees.len();
        let f0 = e0 + n;
        Off {
            v,
            w,
            k,
            e0,
            f0,
            p: f0 + l,
        }
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.off().p
    }

    /// Simulated outputs (`N x ny`) and states (`N x nx`), row-major, from `x0` (zero when
    /// `None`). A diverging simulation is an error naming the sample.
    pub fn simulate(
        &self,
        theta: &[f64],
        u: &[f64],
        x0: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        simulation::simulate(self, theta, u, x0)
    }

    /// `1/2 sum r^2` over the records, with gradient and Gauss-Newton matrix when asked; an
    /// infinite cost when a simulation diverges.
    pub fn cost(&self, theta: &[f64], data: &[PnlssData<'_>], jacobian: bool) -> Evaluation {
        simulation::cost(self, theta, data, jacobian)
    }
}

impl NonlinearTerms for Decoupled {
    type Work = Work;
    const NAME: &'static str = "decoupled pnlss";
    const SIMULATION: &'static str = "decoupled pnlss simulation";
    const NEEDS_INPUTS: bool = true;

    fn dims(&self) -> (usize, usize, usize) {
        (self.nx, self.nu, self.ny)
    }

    fn n_params(&self) -> usize {
        self.off().p
    }

    fn bound(&self) -> f64 {
        self.bound
    }

    fn stable_linear(&self) -> bool {
        self.stable_linear
    }

    fn work(&self) -> Work {
        let r = self.branches;
        Work {
            o: self.off(),
            z: vec![0.0; self.nx + self.nu],
            s: vec![0.0; r],
            g: vec![0.0; r],
            gp: vec![0.0; r],
        }
    }

    /// `W g(V z) + e0` and `f0`, the branch arguments clamped to the box.
    fn add_nonlinear(
        &self,
        th: &[f64],
        x: &[f64],
        u: &[f64],
        w: &mut Work,
        y: &mut [f64],
        xn: &mut [f64],
    ) {
        let (n, nz, nd, o) = (self.nx, self.nx + self.nu, self.degrees.len(), w.o);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        w.z[..n].copy_from_slice(x);
        w.z[n..].copy_from_slice(u);
        for k in 0..self.branches {
            let s = dot(&th[o.v + k * nz..o.v + (k + 1) * nz], &w.z);
            let (sc, free) = if self.lo.is_empty() {
                (s, true)
            } else {
                let c = s.clamp(self.lo[k], self.hi[k]);
                (c, c == s)
            };
            let (mut g, mut gp) = (0.0, 0.0);
            for (j, &d) in self.degrees.iter().enumerate() {
                let ck = th[o.k + k * nd + j];
                let p = sc.powi(d as i32 - 1);
                g += ck * p * sc;
                gp += ck * d as f64 * p;
            }
            w.s[k] = sc;
            w.g[k] = g;
            w.gp[k] = if free { gp } else { 0.0 };
        }
        for (i, yi) in y.iter_mut().enumerate() {
            *yi += th[o.f0 + i];
        }
        let r = self.branches;
        for (i, v) in xn.iter_mut().enumerate() {
            *v += dot(&th[o.w + i * r..o.w + (i + 1) * r], &w.g);
            *v += th[o.e0 + i];
        }
    }

    /// The output equation is linear in the state.
    fn add_output_slope(&self, _th: &[f64], _i: usize, _w: &Work, _ceff: &mut [f64]) {}

    fn add_output_direct(&self, _th: &[f64], i: usize, w: &Work, jb: &mut Mat<f64>, row: usize) {
        jb[(row, w.o.f0 + i)] += 1.0;
    }

    /// `W diag(g') V_x`.
    fn add_state_slope(&self, th: &[f64], w: &Work, aeff: &mut Mat<f64>) {
        let (nx, nz, r, o) = (self.nx, self.nx + self.nu, self.branches, w.o);
        for i in 0..nx {
            for j in 0..nx {
                for k in 0..r {
                    aeff[(i, j)] += th[o.w + i * r + k] * w.gp[k] * th[o.v + k * nz + j];
                }
            }
        }
    }

    fn add_state_direct(&self, th: &[f64], _x: &[f64], w: &Work, s2: &mut Mat<f64>) {
        let (nx, nz, r, nd, o) = (
            self.nx,
            self.nx + self.nu,
            self.branches,
            self.degrees.len(),
            w.o,
        );
        for i in 0..nx {
            for k in 0..r {
                let wik = th[o.w + i * r + k];
                s2[(i, o.w + i * r + k)] += w.g[k];
                for (jd, &deg) in self.degrees.iter().enumerate() {
                    s2[(i, o.k + k * nd + jd)] += wik * w.s[k].powi(deg as i32);
                }
                let a = wik * w.gp[k];
                if a != 0.0 {
                    for j in 0..nz {
                        s2[(i, o.v + k * nz + j)] += a * w.z[j];
                    }
                }
            }
            s2[(i, o.e0 + i)] += 1.0;
        }
    }
}

/// Fits a decoupled PNLSS model on the simulation error from `theta0` with the shared
/// optimiser (a step whose simulation diverges is rejected).
///
/// ```
/// use sysid_core::nlss::{estimate_decoupled, Decoupled, PnlssData};
/// use sysid_core::optim::{Flow, Options};
/// let m = Decoupled::new(1, 1, 1, 1, vec![3]).unwrap();
/// let truth = [0.5, 1.0, 1.0, 0.0, 1.0, 0.0, -0.2, 1.0, 0.0, 0.0];
/// let u: Vec<f64> = (0..300).map(|t| ((t * 7919) % 13) as f64 / 13.0 - 0.5).collect();
/// let (y, _) = m.simulate(&truth, &u, None).unwrap();
/// let data = [PnlssData { u: &u, y: &y, skip: 0 }];
/// let start = [0.5, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
/// let sol = estimate_decoupled(&m, &data, &start, &Options::default(), &mut |_| Flow::Continue)
///     .unwrap();
/// let (yh, _) = m.simulate(&sol.theta, &u, None).unwrap();
/// assert!(yh.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-8));
/// ```
pub fn estimate_decoupled(
    model: &Decoupled,
    data: &[PnlssData<'_>],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    simulation::estimate(model, data, theta0, options, observer)
}
