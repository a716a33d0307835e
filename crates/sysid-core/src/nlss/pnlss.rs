//! The PNLSS model: simulation and the simulation-error problem with forward sensitivities.

use super::Monomials;
use crate::error::{Result, SysidError};
use crate::optim::{minimize, Evaluation, Flow, Iteration, Options, Problem, Solution};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

/// Structure of a PNLSS model; the parameters are `theta = [A, B, C, D, E, F]`, each
/// row-major (`E` is `nx x zeta.len()`, `F` is `ny x eta.len()`).
///
/// ```
/// use sysid_core::nlss::{Monomials, Pnlss, Terms};
/// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
/// let model = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1));
/// // x(t+1) = 0.5 x + u - 0.1 x^2, y = x
/// let theta = [0.5, 1.0, 1.0, 0.0, -0.1];
/// let (y, _) = model.simulate(&theta, &[1.0, 1.0, 0.0], None).unwrap();
/// assert_eq!(y, vec![0.0, 1.0, 1.4]);
/// ```
#[derive(Debug, Clone)]
pub struct Pnlss {
    /// States.
    pub nx: usize,
    /// Inputs.
    pub nu: usize,
    /// Outputs.
    pub ny: usize,
    /// Monomials of the state equation.
    pub zeta: Monomials,
    /// Monomials of the output equation.
    pub eta: Monomials,
    /// A simulation whose state exceeds this in absolute value has diverged.
    pub bound: f64,
    /// Lower ends of the box the monomials' arguments `z = [x; u]` are clamped to (empty:
    /// no clamping; see [`Pnlss::with_range`]).
    pub lo: Vec<f64>,
    /// Upper ends of that box.
    pub hi: Vec<f64>,
}

/// One record: inputs `u` (`N x nu` row-major), outputs `y` (`N x ny` row-major), and the
/// number of leading samples left out of the cost (the transient from the zero state).
#[derive(Debug, Clone, Copy)]
pub struct PnlssData<'a> {
    /// Inputs, row-major.
    pub u: &'a [f64],
    /// Outputs, row-major.
    pub y: &'a [f64],
    /// Leading samples not in the cost.
    pub skip: usize,
}

#[derive(Clone, Copy)]
struct Off {
    b: usize,
    c: usize,
    d: usize,
    e: usize,
    f: usize,
    p: usize,
}

/// Work buffers of one simulation step.
struct Work {
    z: Vec<f64>,
    ze: Vec<f64>,
    et: Vec<f64>,
    xn: Vec<f64>,
    /// Whether each state lies inside the box (its monomial derivatives count).
    free: Vec<bool>,
}

impl Pnlss {
    /// A model with the default divergence bound (1e8).
    pub fn new(nx: usize, nu: usize, ny: usize, zeta: Monomials, eta: Monomials) -> Self {
        Pnlss {
            nx,
            nu,
            ny,
            zeta,
            eta,
            bound: 1e8,
            lo: Vec::new(),
            hi: Vec::new(),
        }
    }

    /// The model with the monomials evaluated at `z = [x; u]` clamped to the box
    /// `lo <= z <= hi` (one bound per state and input): outside the region the polynomial
    /// was fitted on, the nonlinear terms stay at their boundary values instead of growing
    /// without bound, so a simulation cannot diverge through them. The linear part is not
    /// clamped.
    ///
    /// ```
    /// use sysid_core::nlss::{Monomials, Pnlss, Terms};
    /// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
    /// let m = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1))
    ///     .with_range(vec![-1.0, -10.0], vec![1.0, 10.0])
    ///     .unwrap();
    /// // x(t+1) = 0.5 x + u - 0.1 clamp(x, -1, 1)^2
    /// let (y, _) = m.simulate(&[0.5, 1.0, 1.0, 0.0, -0.1], &[3.0, 0.0], None).unwrap();
    /// assert_eq!(y, vec![0.0, 3.0]);
    /// let (y, _) = m.simulate(&[0.5, 1.0, 1.0, 0.0, -0.1], &[3.0, 0.0, 0.0], None).unwrap();
    /// assert!((y[2] - (1.5 - 0.1)).abs() < 1e-15);
    /// ```
    pub fn with_range(mut self, lo: Vec<f64>, hi: Vec<f64>) -> Result<Self> {
        let nz = self.nx + self.nu;
        if lo.len() != nz || hi.len() != nz {
            return Err(SysidError::invalid(
                "range",
                format!(
                    "needs {nz} lower and upper bounds (states then inputs), got {} and {}",
                    lo.len(),
                    hi.len()
                ),
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
        let (n, m, l) = (self.nx, self.nu, self.ny);
        let b = n * n;
        let c = b + n * m;
        let d = c + l * n;
        let e = d + l * m;
        let f = e + n * self.zeta.len();
        Off {
            b,
            c,
            d,
            e,
            f,
            p: f + l * self.eta.len(),
        }
    }

    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.off().p
    }

    fn work(&self) -> Work {
        Work {
            z: vec![0.0; self.nx + self.nu],
            ze: vec![0.0; self.zeta.len()],
            et: vec![0.0; self.eta.len()],
            xn: vec![0.0; self.nx],
            free: vec![true; self.nx],
        }
    }

    /// One step: the output at `x, u` into `y`, the next state into `w.xn`; `false` when the
    /// next state is non-finite or beyond the bound.
    fn step(&self, th: &[f64], o: Off, x: &[f64], u: &[f64], y: &mut [f64], w: &mut Work) -> bool {
        let (n, m) = (self.nx, self.nu);
        w.z[..n].copy_from_slice(x);
        w.z[n..].copy_from_slice(u);
        if !self.lo.is_empty() {
            for (k, v) in w.z.iter_mut().enumerate() {
                let c = v.clamp(self.lo[k], self.hi[k]);
                if k < n {
                    w.free[k] = c == *v;
                }
                *v = c;
            }
        }
        self.zeta.eval(&w.z, &mut w.ze);
        self.eta.eval(&w.z, &mut w.et);
        let (ne, nf) = (w.ze.len(), w.et.len());
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>();
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = dot(&th[o.c + i * n..o.c + (i + 1) * n], x)
                + dot(&th[o.d + i * m..o.d + (i + 1) * m], u)
                + dot(&th[o.f + i * nf..o.f + (i + 1) * nf], &w.et);
        }
        let mut ok = true;
        for i in 0..n {
            let v = dot(&th[i * n..(i + 1) * n], x)
                + dot(&th[o.b + i * m..o.b + (i + 1) * m], u)
                + dot(&th[o.e + i * ne..o.e + (i + 1) * ne], &w.ze);
            ok &= v.is_finite() && v.abs() <= self.bound;
            w.xn[i] = v;
        }
        ok
    }

    /// Checks `theta` and a record's shapes.
    fn check(&self, theta: &[f64], u: &[f64], y: Option<&[f64]>) -> Result<usize> {
        if theta.len() != self.n_params() {
            return Err(SysidError::invalid(
                "theta",
                format!("needs {} parameters, got {}", self.n_params(), theta.len()),
            ));
        }
        let nu = self.nu.max(1);
        let n = if self.nu == 0 {
            y.map_or(0, |y| y.len() / self.ny.max(1))
        } else {
            u.len() / nu
        };
        if self.nu > 0 && u.len() != n * self.nu {
            return Err(SysidError::invalid(
                "u",
                "length is not a multiple of the input count",
            ));
        }
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
            let ok = self.step(
                theta,
                o,
                &x,
                &u[t * nu..(t + 1) * nu],
                &mut y[t * ny..(t + 1) * ny],
                &mut w,
            );
            if !ok && t + 1 < n {
                return Err(SysidError::numerical(
                    "pnlss simulation",
                    format!(
                        "the state diverged (beyond {:e} or non-finite) at sample {}; the \
                         input leaves the range the model was estimated on",
                        self.bound,
                        t + 1
                    ),
                ));
            }
            x.copy_from_slice(&w.xn);
        }
        Ok((y, xs))
    }

    /// Sum of squares `1/2 sum r^2` over the records, its gradient and Gauss-Newton matrix
    /// (with `jacobian`); an infinite cost when a simulation diverges.
    pub fn cost(&self, theta: &[f64], data: &[PnlssData<'_>], jacobian: bool) -> Evaluation {
        let p = self.n_params();
        let mut ev = Evaluation::cost_only(0.0);
        if jacobian {
            ev.gradient = vec![0.0; p];
            ev.gauss_newton = Mat::zeros(p, p);
        }
        for d in data {
            if !self.record(theta, d, &mut ev, jacobian, &mut flush) {
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

    /// Adds one record to `ev`; `false` when the simulation diverged. Blocks of Jacobian rows
    /// (`d yhat / d theta`, in time order after the transient) and residuals go to `sink`
    /// ([`flush`] for the time-domain cost), which must clear the block's rows.
    pub(super) fn record(
        &self,
        th: &[f64],
        d: &PnlssData<'_>,
        ev: &mut Evaluation,
        jac: bool,
        sink: &mut Sink<'_>,
    ) -> bool {
        const BLK: usize = 32;
        let o = self.off();
        let (nx, nu, ny, p) = (self.nx, self.nu, self.ny, o.p);
        let (ne, nf) = (self.zeta.len(), self.eta.len());
        let n = d.u.len().checked_div(nu).unwrap_or(d.y.len() / ny);
        let mut w = self.work();
        let mut x = vec![0.0; nx];
        let mut yh = vec![0.0; ny];
        let q = if jac { p } else { 0 };
        let mut s = Mat::<f64>::zeros(nx, q);
        let mut s2 = Mat::<f64>::zeros(nx, q);
        let mut jb = Mat::<f64>::zeros(BLK * ny, q);
        let mut rb = Mat::<f64>::zeros(BLK * ny, 1);
        let (mut dze, mut det) = (vec![0.0; ne * nx], vec![0.0; nf * nx]);
        let mut aeff = Mat::<f64>::zeros(nx, nx);
        let mut rows = 0;
        for t in 0..n {
            let u = &d.u[t * nu..(t + 1) * nu];
            let ok = self.step(th, o, &x, u, &mut yh, &mut w);
            if jac {
                self.zeta.dx(&w.z, &mut dze);
                self.eta.dx(&w.z, &mut det);
                for j in (0..nx).filter(|&j| !w.free[j]) {
                    dze.iter_mut().skip(j).step_by(nx).for_each(|v| *v = 0.0);
                    det.iter_mut().skip(j).step_by(nx).for_each(|v| *v = 0.0);
                }
            }
            if t >= d.skip {
                for i in 0..ny {
                    let r = d.y[t * ny + i] - yh[i];
                    ev.cost += 0.5 * r * r;
                    if jac {
                        rb[(rows, 0)] = r;
                        self.output_row(th, o, i, &x, u, &w, &det, &s, &mut jb, rows);
                        rows += 1;
                    }
                }
                if jac && (rows == BLK * ny || t + 1 == n) {
                    sink(&mut jb, &rb, rows, ev);
                    rows = 0;
                }
            }
            if !ok && t + 1 < n {
                return false;
            }
            if jac && t + 1 < n {
                for i in 0..nx {
                    for j in 0..nx {
                        let mut v = th[i * nx + j];
                        for k in 0..ne {
                            v += th[o.e + i * ne + k] * dze[k * nx + j];
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
                    for j in 0..ne {
                        s2[(i, o.e + i * ne + j)] += w.ze[j];
                    }
                }
                std::mem::swap(&mut s, &mut s2);
            }
            x.copy_from_slice(&w.xn);
        }
        if jac && rows > 0 {
            sink(&mut jb, &rb, rows, ev);
        }
        ev.cost.is_finite()
    }

    /// Row `rows` of the block: `d yhat_i / d theta = (C + F deta/dx)_i S + direct terms`.
    #[allow(clippy::too_many_arguments)]
    fn output_row(
        &self,
        th: &[f64],
        o: Off,
        i: usize,
        x: &[f64],
        u: &[f64],
        w: &Work,
        det: &[f64],
        s: &Mat<f64>,
        jb: &mut Mat<f64>,
        row: usize,
    ) {
        let (nx, nu, nf) = (self.nx, self.nu, self.eta.len());
        let mut ceff = vec![0.0; nx];
        for j in 0..nx {
            ceff[j] = th[o.c + i * nx + j];
        }
        for k in 0..nf {
            let fk = th[o.f + i * nf + k];
            if fk != 0.0 {
                for j in 0..nx {
                    ceff[j] += fk * det[k * nx + j];
                }
            }
        }
        for a in 0..o.p {
            let mut v = 0.0;
            for j in 0..nx {
                v += ceff[j] * s[(j, a)];
            }
            jb[(row, a)] = v;
        }
        for j in 0..nx {
            jb[(row, o.c + i * nx + j)] += x[j];
        }
        for j in 0..nu {
            jb[(row, o.d + i * nu + j)] += u[j];
        }
        for k in 0..nf {
            jb[(row, o.f + i * nf + k)] += w.et[k];
        }
    }
}

/// Receives a block of Jacobian rows, residuals, the row count and the evaluation.
pub(super) type Sink<'a> = dyn FnMut(&mut Mat<f64>, &Mat<f64>, usize, &mut Evaluation) + 'a;

/// `H += Jb^T Jb` (lower triangle used later), `g -= Jb^T r` over the first `rows` rows,
/// then clears the block.
pub(super) fn flush(jb: &mut Mat<f64>, rb: &Mat<f64>, rows: usize, ev: &mut Evaluation) {
    let j = jb.as_ref().subrows(0, rows);
    let r = rb.as_ref().subrows(0, rows);
    matmul(
        ev.gauss_newton.as_mut(),
        Accum::Add,
        j.transpose(),
        j,
        1.0,
        Par::Seq,
    );
    let p = j.ncols();
    let mut g = Mat::<f64>::zeros(p, 1);
    matmul(g.as_mut(), Accum::Replace, j.transpose(), r, 1.0, Par::Seq);
    for a in 0..p {
        ev.gradient[a] -= g[(a, 0)];
    }
    jb.as_mut().subrows_mut(0, rows).fill(0.0);
}

struct PnlssProblem<'a> {
    model: &'a Pnlss,
    data: &'a [PnlssData<'a>],
}

impl Problem for PnlssProblem<'_> {
    fn n_params(&self) -> usize {
        self.model.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        Ok(self.model.cost(theta, self.data, jacobian))
    }
}

/// Fits the PNLSS parameters on the simulation error from `theta0` with the shared optimiser
/// (a step whose simulation diverges is rejected like one that raises the cost).
///
/// ```
/// use sysid_core::nlss::{estimate, Monomials, Pnlss, PnlssData, Terms};
/// use sysid_core::optim::{Flow, Options};
/// let zeta = Monomials::new(1, 1, Terms::States, &[2]).unwrap();
/// let model = Pnlss::new(1, 1, 1, zeta, Monomials::empty(1));
/// let truth = [0.5, 1.0, 1.0, 0.0, -0.1];
/// let u: Vec<f64> = (0..200).map(|t| ((t * 7919) % 13) as f64 / 13.0 - 0.5).collect();
/// let (y, _) = model.simulate(&truth, &u, None).unwrap();
/// let data = [PnlssData { u: &u, y: &y, skip: 0 }];
/// let sol = estimate(&model, &data, &[0.4, 1.0, 1.0, 0.0, 0.0], &Options::default(),
///                    &mut |_| Flow::Continue).unwrap();
/// // the state basis is free (x -> s x rescales B, C and E): compare the outputs
/// let (yh, _) = model.simulate(&sol.theta, &u, None).unwrap();
/// assert!(yh.iter().zip(&y).all(|(a, b)| (a - b).abs() < 1e-8));
/// ```
pub fn estimate(
    model: &Pnlss,
    data: &[PnlssData<'_>],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    estimate_checks(model, data, theta0)?;
    let mut prob = PnlssProblem { model, data };
    minimize(&mut prob, theta0, options, observer)
}

/// The checks of [`estimate`] (records, shapes, finite values, a transient shorter than the
/// record, a start whose simulation does not diverge); the start's time-domain cost.
pub(super) fn estimate_checks(
    model: &Pnlss,
    data: &[PnlssData<'_>],
    theta0: &[f64],
) -> Result<f64> {
    if data.is_empty() {
        return Err(SysidError::invalid("data", "no records"));
    }
    for d in data {
        let n = model.check(theta0, d.u, Some(d.y))?;
        if n <= d.skip {
            return Err(SysidError::InsufficientData {
                context: "a pnlss record after its transient".into(),
                needed: d.skip + 1,
                got: n,
                fix: "use a longer record or a shorter transient",
            });
        }
        for (name, a, w) in [("u", d.u, model.nu), ("y", d.y, model.ny)] {
            if let Some(k) = a.iter().position(|v| !v.is_finite()) {
                return Err(SysidError::NonFinite {
                    what: name,
                    sample: k / w.max(1),
                    channel: k % w.max(1),
                });
            }
        }
    }
    let start = model.cost(theta0, data, false);
    if !start.cost.is_finite() {
        return Err(SysidError::numerical(
            "pnlss",
            "the initial model's simulation diverges on the data; start from a stable linear \
             model (the BLA or a subspace model)",
        ));
    }
    Ok(start.cost)
}
