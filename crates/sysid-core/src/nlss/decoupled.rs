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

use super::pnlss::flush;
use crate::error::{Result, SysidError};
use crate::optim::{minimize, Evaluation, Flow, Iteration, Options, Problem, Solution};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

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
}

#[derive(Clone, Copy)]
struct Off {
    b: usize,
    c: usize,
    d: usize,
    v: usize,
    w: usize,
    k: usize,
    e0: usize,
    f0: usize,
    p: usize,
}

/// One step's branch values: arguments (clamped), values and slopes.
struct Work {
    z: Vec<f64>,
    s: Vec<f64>,
    g: Vec<f64>,
    gp: Vec<f64>,
    xn: Vec<f64>,
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
        })
    }

    /// The model with the branch arguments clamped to `lo <= s <= hi` (one pair per branch).
    pub fn with_range(mut self, lo: Vec<f64>, hi: Vec<f64>) -> Result<Self> {
        let r = self.branches;
        if lo.len() != r || hi.len() != r {
            return Err(SysidError::invalid(
                "range",
                format!("needs {r} lower and upper bounds (one per branch)"),
            ));
        }
        if lo
            .iter()
            .zip(&hi)
            .any(|(a, b)| a.is_nan() || b.is_nan() || a > b)
        {
            return Err(SysidError::invalid(
                "range",
                "each lower bound must be a number not above its upper bound",
            ));
        }
        self.lo = lo;
        self.hi = hi;
        Ok(self)
    }

    fn off(&self) -> Off {
        let (n, m, l, r) = (self.nx, self.nu, self.ny, self.branches);
        let b = n * n;
        let c = b + n * m;
        let d = c + l * n;
        let v = d + l * m;
        let w = v + r * (n + m);
        let k = w + n * r;
        let e0 = k + r * self.degrees.len();
        let f0 = e0 + n;
        Off {
            b,
            c,
            d,
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

    fn work(&self) -> Work {
        let r = self.branches;
        Work {
            z: vec![0.0; self.nx + self.nu],
            s: vec![0.0; r],
            g: vec![0.0; r],
            gp: vec![0.0; r],
            xn: vec![0.0; self.nx],
        }
    }

    /// One step: output into `y`, next state into `w.xn`; `false` when the next state is
    /// non-finite or beyond the bound.
    fn step(&self, th: &[f64], o: Off, x: &[f64], u: &[f64], y: &mut [f64], w: &mut Work) -> bool {
        let (n, m, nz, nd) = (self.nx, self.nu, self.nx + self.nu, self.degrees.len());
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
            *yi = dot(&th[o.c + i * n..o.c + (i + 1) * n], x)
                + dot(&th[o.d + i * m..o.d + (i + 1) * m], u)
                + th[o.f0 + i];
        }
        let r = self.branches;
        let mut ok = true;
        for i in 0..n {
            let v = dot(&th[i * n..(i + 1) * n], x)
                + dot(&th[o.b + i * m..o.b + (i + 1) * m], u)
                + dot(&th[o.w + i * r..o.w + (i + 1) * r], &w.g)
                + th[o.e0 + i];
            ok &= v.is_finite() && v.abs() <= self.bound;
            w.xn[i] = v;
        }
        ok
    }

    fn check(&self, theta: &[f64], u: &[f64], y: Option<&[f64]>) -> Result<usize> {
        if theta.len() != self.n_params() {
            return Err(SysidError::invalid(
                "theta",
                format!("needs {} parameters, got {}", self.n_params(), theta.len()),
            ));
        }
        if self.nu == 0 || u.len() % self.nu != 0 {
            return Err(SysidError::invalid(
                "u",
                "needs at least one input; its length must be a multiple of the input count",
            ));
        }
        let n = u.len() / self.nu;
        if let Some(y) = y {
            if y.len() != n * self.ny {
                return Err(SysidError::invalid(
                    "y",
                    format!(
                        "needs {} x {} values to match u, got {}",
                        n,
                        self.ny,
                        y.len()
                    ),
                ));
            }
        }
        Ok(n)
    }

    /// Simulated outputs (`N x ny`) and states (`N x nx`), row-major, from `x0` (zero when
    /// `None`). A diverging simulation is an error naming the sample.
    pub fn simulate(
        &self,
        theta: &[f64],
        u: &[f64],
        x0: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let n = self.check(theta, u, None)?;
        let o = self.off();
        let (nx, nu, ny) = (self.nx, self.nu, self.ny);
        let mut x = x0.map_or(vec![0.0; nx], |v| v.to_vec());
        if x.len() != nx {
            return Err(SysidError::invalid("x0", format!("needs {nx} values")));
        }
        let (mut y, mut xs) = (vec![0.0; n * ny], vec![0.0; n * nx]);
        let mut w = self.work();
        for t in 0..n {
            xs[t * nx..(t + 1) * nx].copy_from_slice(&x);
            let (ut, yt) = (&u[t * nu..(t + 1) * nu], &mut y[t * ny..(t + 1) * ny]);
            if !self.step(theta, o, &x, ut, yt, &mut w) && t + 1 < n {
                return Err(SysidError::numerical(
                    "decoupled pnlss simulation",
                    format!(
                        "the state diverged (beyond {:e} or non-finite) at sample {}",
                        self.bound,
                        t + 1
                    ),
                ));
            }
            x.copy_from_slice(&w.xn);
        }
        Ok((y, xs))
    }

    /// `1/2 sum r^2` over the records, with gradient and Gauss-Newton matrix when asked; an
    /// infinite cost when a simulation diverges.
    pub fn cost(&self, theta: &[f64], data: &[super::PnlssData<'_>], jacobian: bool) -> Evaluation {
        let p = self.n_params();
        let mut ev = Evaluation::cost_only(0.0);
        if jacobian {
            ev.gradient = vec![0.0; p];
            ev.gauss_newton = Mat::zeros(p, p);
        }
        for d in data {
            if !self.record(theta, d, &mut ev, jacobian) {
                return Evaluation::cost_only(f64::INFINITY);
            }
        }
        if jacobian {
            let h = &mut ev.gauss_newton;
            for a in 0..p {
                for b in 0..a {
                    h[(b, a)] = h[(a, b)];
                }
            }
        }
        ev
    }

    fn record(&self, th: &[f64], d: &super::PnlssData<'_>, ev: &mut Evaluation, jac: bool) -> bool {
        const BLK: usize = 32;
        let o = self.off();
        let (nx, nu, ny, r, nd) = (self.nx, self.nu, self.ny, self.branches, self.degrees.len());
        let nz = nx + nu;
        let n = d.u.len() / nu;
        let mut w = self.work();
        let (mut x, mut yh) = (vec![0.0; nx], vec![0.0; ny]);
        let q = if jac { o.p } else { 0 };
        let (mut s, mut s2) = (Mat::<f64>::zeros(nx, q), Mat::<f64>::zeros(nx, q));
        let mut jb = Mat::<f64>::zeros(BLK * ny, q);
        let mut rb = Mat::<f64>::zeros(BLK * ny, 1);
        let mut aeff = Mat::<f64>::zeros(nx, nx);
        let mut rows = 0;
        for t in 0..n {
            let u = &d.u[t * nu..(t + 1) * nu];
            let ok = self.step(th, o, &x, u, &mut yh, &mut w);
            if t >= d.skip {
                for i in 0..ny {
                    let res = d.y[t * ny + i] - yh[i];
                    ev.cost += 0.5 * res * res;
                    if jac {
                        rb[(rows, 0)] = res;
                        for a in 0..o.p {
                            let mut v = 0.0;
                            for j in 0..nx {
                                v += th[o.c + i * nx + j] * s[(j, a)];
                            }
                            jb[(rows, a)] = v;
                        }
                        for j in 0..nx {
                            jb[(rows, o.c + i * nx + j)] += x[j];
                        }
                        for j in 0..nu {
                            jb[(rows, o.d + i * nu + j)] += u[j];
                        }
                        jb[(rows, o.f0 + i)] += 1.0;
                        rows += 1;
                    }
                }
                if jac && (rows == BLK * ny || t + 1 == n) {
                    flush(&mut jb, &rb, rows, ev);
                    rows = 0;
                }
            }
            if !ok && t + 1 < n {
                return false;
            }
            if jac && t + 1 < n {
                // A + W diag(g') V_x
                for i in 0..nx {
                    for j in 0..nx {
                        let mut v = th[i * nx + j];
                        for k in 0..r {
                            v += th[o.w + i * r + k] * w.gp[k] * th[o.v + k * nz + j];
                        }
                        aeff[(i, j)] = v;
                    }
                }
                matmul(
                    s2.as_mut(),
                    Accum::Replace,
                    aeff.as_ref(),
                    s.as_ref(),
                    1.0,
                    Par::Seq,
                );
                for i in 0..nx {
                    for j in 0..nx {
                        s2[(i, i * nx + j)] += x[j];
                    }
                    for j in 0..nu {
                        s2[(i, o.b + i * nu + j)] += u[j];
                    }
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
                std::mem::swap(&mut s, &mut s2);
            }
            x.copy_from_slice(&w.xn);
        }
        if jac && rows > 0 {
            flush(&mut jb, &rb, rows, ev);
        }
        ev.cost.is_finite()
    }
}

struct DecoupledProblem<'a> {
    model: &'a Decoupled,
    data: &'a [super::PnlssData<'a>],
}

impl Problem for DecoupledProblem<'_> {
    fn n_params(&self) -> usize {
        self.model.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        Ok(self.model.cost(theta, self.data, jacobian))
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
    data: &[super::PnlssData<'_>],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    if data.is_empty() {
        return Err(SysidError::invalid("data", "no records"));
    }
    for d in data {
        let n = model.check(theta0, d.u, Some(d.y))?;
        if n <= d.skip {
            return Err(SysidError::InsufficientData {
                context: "a decoupled pnlss record after its transient".into(),
                needed: d.skip + 1,
                got: n,
                fix: "use a longer record or a shorter transient",
            });
        }
        if d.u.iter().chain(d.y).any(|v| !v.is_finite()) {
            return Err(SysidError::invalid(
                "data",
                "has non-finite values (NaN or Inf)",
            ));
        }
    }
    if !model.cost(theta0, data, false).cost.is_finite() {
        return Err(SysidError::numerical(
            "decoupled pnlss",
            "the initial model's simulation diverges on the data; start from a stable linear \
             model",
        ));
    }
    let mut prob = DecoupledProblem { model, data };
    minimize(&mut prob, theta0, options, observer)
}
