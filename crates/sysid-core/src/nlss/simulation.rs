//! What the polynomial state-space models share: the linear part, the simulation loop, the
//! simulation-error cost with its forward sensitivities, and the checks, written once for any
//! model whose parameters start with `[A, B, C, D]` (row-major) and whose nonlinear terms are
//! added to
//!
//! ```text
//! x(t+1) = A x + B u + f_nl(x, u)        y(t) = C x + D u + g_nl(x, u)
//! S(t+1) = (A + d f_nl/dx) S + d x(t+1)/d theta |_x        dy/dtheta = (C + d g_nl/dx) S + d y/d theta |_x
//! ```
//!
//! A model supplies the nonlinear terms and their derivatives ([`NonlinearTerms`]); the
//! rest is here.

use super::PnlssData;
use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::optim::{
    gram_add, minimize, mirror_lower, Evaluation, Flow, Iteration, Options, Problem, Solution,
};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

/// Sizes and the nonlinear part of a state-space model fitted on the simulation error.
pub(super) trait NonlinearTerms {
    /// Per-step values kept for the sensitivities.
    type Work;
    /// The model's name in messages ("pnlss").
    const NAME: &'static str;
    /// The simulation's step in messages ("pnlss simulation").
    const SIMULATION: &'static str;
    /// Whether the model needs at least one input.
    const NEEDS_INPUTS: bool = false;

    /// States, inputs, outputs.
    fn dims(&self) -> (usize, usize, usize);
    /// Number of parameters.
    fn n_params(&self) -> usize;
    /// A state beyond this in absolute value has diverged.
    fn bound(&self) -> f64;
    /// Whether a fit keeps the linear part's `A` (the first `nx * nx` parameters, row-major)
    /// stable: [`linear_margin`] bounds the search's admissible set.
    fn stable_linear(&self) -> bool {
        false
    }
    /// Fresh work buffers.
    fn work(&self) -> Self::Work;
    /// Adds the nonlinear terms at `x, u` to `y` (holding `C x + D u`) and `xn` (holding
    /// `A x + B u`), keeping in `w` what the sensitivities need.
    fn add_nonlinear(
        &self,
        th: &[f64],
        x: &[f64],
        u: &[f64],
        w: &mut Self::Work,
        y: &mut [f64],
        xn: &mut [f64],
    );
    /// Derivatives of the last step's nonlinear terms, before the sensitivities read them.
    fn prepare_jacobian(&self, _w: &mut Self::Work) {}
    /// Adds `d g_nl,i / dx` to `ceff` (holding row `i` of `C`).
    fn add_output_slope(&self, th: &[f64], i: usize, w: &Self::Work, ceff: &mut [f64]);
    /// Adds the direct derivatives of output `i`'s nonlinear terms to row `row` of `jb`.
    fn add_output_direct(
        &self,
        th: &[f64],
        i: usize,
        w: &Self::Work,
        jb: &mut Mat<f64>,
        row: usize,
    );
    /// Adds `d f_nl / dx` to `aeff` (holding `A`).
    fn add_state_slope(&self, th: &[f64], w: &Self::Work, aeff: &mut Mat<f64>);
    /// Adds the direct derivatives of the next state's nonlinear terms to `s2`.
    fn add_state_direct(&self, th: &[f64], x: &[f64], w: &Self::Work, s2: &mut Mat<f64>);
}

/// Offsets of `B`, `C`, `D` in `theta` (`A` starts at 0).
fn linear_offsets(nx: usize, nu: usize, ny: usize) -> (usize, usize, usize) {
    let b = nx * nx;
    let c = b + nx * nu;
    (b, c, c + ny * nx)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(p, q)| p * q).sum::<f64>()
}

/// One step: the output at `x, u` into `y`, the next state into `xn`; `false` when the next
/// state is non-finite or beyond the bound.
#[allow(clippy::too_many_arguments)]
fn step<M: NonlinearTerms>(
    m: &M,
    th: &[f64],
    x: &[f64],
    u: &[f64],
    y: &mut [f64],
    xn: &mut [f64],
    w: &mut M::Work,
) -> bool {
    let (n, nu, ny) = m.dims();
    let (b, c, d) = linear_offsets(n, nu, ny);
    for (i, yi) in y.iter_mut().enumerate() {
        *yi = dot(&th[c + i * n..c + (i + 1) * n], x) + dot(&th[d + i * nu..d + (i + 1) * nu], u);
    }
    for (i, v) in xn.iter_mut().enumerate() {
        *v = dot(&th[i * n..(i + 1) * n], x) + dot(&th[b + i * nu..b + (i + 1) * nu], u);
    }
    m.add_nonlinear(th, x, u, w, y, xn);
    let bound = m.bound();
    xn.iter().all(|v| v.is_finite() && v.abs() <= bound)
}

/// Checks the range box of `count` bounds (`what` says which), as `with_range` takes it.
pub(super) fn check_range(lo: &[f64], hi: &[f64], count: usize, what: &str) -> Result<()> {
    if lo.len() != count || hi.len() != count {
        return Err(SysidError::invalid(
            "range",
            format!(
                "needs {count} lower and upper bounds ({what}), got {} and {}",
                lo.len(),
                hi.len()
            ),
        ));
    }
    if lo
        .iter()
        .zip(hi)
        .any(|(a, b)| a.is_nan() || b.is_nan() || a > b)
    {
        return Err(SysidError::invalid(
            "range",
            "each lower bound must be a number not above its upper bound",
        ));
    }
    Ok(())
}

/// Checks `theta` and a record's shapes; the number of samples.
fn check<M: NonlinearTerms>(m: &M, theta: &[f64], u: &[f64], y: Option<&[f64]>) -> Result<usize> {
    let (_, nu, ny) = m.dims();
    if theta.len() != m.n_params() {
        return Err(SysidError::invalid(
            "theta",
            format!("needs {} parameters, got {}", m.n_params(), theta.len()),
        ));
    }
    if M::NEEDS_INPUTS && nu == 0 {
        return Err(SysidError::invalid(
            "u",
            format!("a {} model needs at least one input", M::NAME),
        ));
    }
    // without inputs the record's length is the outputs'
    let n = u
        .len()
        .checked_div(nu)
        .unwrap_or_else(|| y.map_or(0, |y| y.len() / ny.max(1)));
    if nu > 0 && u.len() != n * nu {
        return Err(SysidError::invalid(
            "u",
            "length is not a multiple of the input count",
        ));
    }
    if let Some(y) = y {
        if y.len() != n * ny {
            return Err(SysidError::invalid(
                "y",
                format!("needs {} x {} values to match u, got {}", n, ny, y.len()),
            ));
        }
    }
    Ok(n)
}

/// Simulated outputs (`N x ny`) and states (`N x nx`), row-major, from `x0` (zero when
/// `None`); a diverging simulation is an error naming the sample.
pub(super) fn simulate<M: NonlinearTerms>(
    m: &M,
    theta: &[f64],
    u: &[f64],
    x0: Option<&[f64]>,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let n = check(m, theta, u, None)?;
    let (nx, nu, ny) = m.dims();
    let mut x = x0.map_or(vec![0.0; nx], |v| v.to_vec());
    if x.len() != nx {
        return Err(SysidError::invalid("x0", format!("needs {nx} values")));
    }
    let (mut y, mut xs) = (vec![0.0; n * ny], vec![0.0; n * nx]);
    let mut xn = vec![0.0; nx];
    let mut w = m.work();
    for t in 0..n {
        xs[t * nx..(t + 1) * nx].copy_from_slice(&x);
        let (ut, yt) = (&u[t * nu..(t + 1) * nu], &mut y[t * ny..(t + 1) * ny]);
        if !step(m, theta, &x, ut, yt, &mut xn, &mut w) && t + 1 < n {
            return Err(SysidError::numerical(
                M::SIMULATION,
                format!(
                    "the state diverged (beyond {:e} or non-finite) at sample {}; the input \
                     leaves the range the model was estimated on",
                    m.bound(),
                    t + 1
                ),
            ));
        }
        x.copy_from_slice(&xn);
    }
    Ok((y, xs))
}

/// `1/2 sum r^2` over the records, its gradient and Gauss-Newton matrix (with `jacobian`);
/// an infinite cost when a simulation diverges.
pub(super) fn cost<M: NonlinearTerms>(
    m: &M,
    theta: &[f64],
    data: &[PnlssData<'_>],
    jacobian: bool,
) -> Evaluation {
    let p = m.n_params();
    let mut ev = Evaluation::cost_only(0.0);
    if jacobian {
        ev.gradient = vec![0.0; p];
        ev.gauss_newton = Mat::zeros(p, p);
    }
    for d in data {
        if !record(m, theta, d, &mut ev, jacobian, &mut flush) {
            return Evaluation::cost_only(f64::INFINITY);
        }
    }
    if jacobian {
        mirror_lower(&mut ev.gauss_newton);
    }
    ev
}

/// Adds one record to `ev`; `false` when the simulation diverged (or the computation is to
/// stop: [`crate::interrupt::requested`], checked every 256 samples). Blocks of Jacobian rows
/// (`d yhat / d theta`, in time order after the transient) and residuals go to `sink`
/// ([`flush`] for the time-domain cost), which must clear the block's rows.
pub(super) fn record<M: NonlinearTerms>(
    m: &M,
    th: &[f64],
    d: &PnlssData<'_>,
    ev: &mut Evaluation,
    jac: bool,
    sink: &mut Sink<'_>,
) -> bool {
    const BLK: usize = 128;
    let (nx, nu, ny) = m.dims();
    let (ob, oc, od) = linear_offsets(nx, nu, ny);
    let p = m.n_params();
    let n = d.u.len().checked_div(nu).unwrap_or(d.y.len() / ny);
    // per-sample products of a few state rows: see `crate::denormals`
    let _daz = crate::denormals::DenormalsAreZero::new();
    let mut w = m.work();
    let (mut x, mut xn, mut yh) = (vec![0.0; nx], vec![0.0; nx], vec![0.0; ny]);
    let q = if jac { p } else { 0 };
    let (mut s, mut s2) = (Mat::<f64>::zeros(nx, q), Mat::<f64>::zeros(nx, q));
    let mut jb = Mat::<f64>::zeros(BLK * ny, q);
    let mut rb = Mat::<f64>::zeros(BLK * ny, 1);
    let mut aeff = Mat::<f64>::zeros(nx, nx);
    let mut ceff = vec![0.0; nx];
    let mut cm = Mat::<f64>::zeros(ny, nx);
    let mut rows = 0;
    for t in 0..n {
        if t % 256 == 255 && crate::interrupt::requested() {
            // Ctrl-C within a pass (seconds on a long record with a Jacobian of hundreds of
            // columns, 4 096 samples a quarter second): the pass ends as a diverged one
            // would, and the search's own check raises the interruption
            return false;
        }
        let u = &d.u[t * nu..(t + 1) * nu];
        let ok = step(m, th, &x, u, &mut yh, &mut xn, &mut w);
        if jac {
            m.prepare_jacobian(&mut w);
        }
        if t >= d.skip {
            if jac {
                // d yhat / d theta = (C + d g_nl/dx) S + direct terms, the ny rows at once
                for i in 0..ny {
                    ceff.copy_from_slice(&th[oc + i * nx..oc + (i + 1) * nx]);
                    m.add_output_slope(th, i, &w, &mut ceff);
                    for j in 0..nx {
                        cm[(i, j)] = ceff[j];
                    }
                }
                matmul(
                    jb.as_mut().subrows_mut(rows, ny),
                    Accum::Replace,
                    cm.as_ref(),
                    s.as_ref(),
                    1.0,
                    Par::Seq,
                );
            }
            for i in 0..ny {
                let r = d.y[t * ny + i] - yh[i];
                ev.cost += 0.5 * r * r;
                if jac {
                    rb[(rows, 0)] = r;
                    for j in 0..nx {
                        jb[(rows, oc + i * nx + j)] += x[j];
                    }
                    for j in 0..nu {
                        jb[(rows, od + i * nu + j)] += u[j];
                    }
                    m.add_output_direct(th, i, &w, &mut jb, rows);
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
                    aeff[(i, j)] = th[i * nx + j];
                }
            }
            m.add_state_slope(th, &w, &mut aeff);
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
                    s2[(i, ob + i * nu + j)] += u[j];
                }
            }
            m.add_state_direct(th, &x, &w, &mut s2);
            std::mem::swap(&mut s, &mut s2);
        }
        x.copy_from_slice(&xn);
    }
    if jac && rows > 0 {
        sink(&mut jb, &rb, rows, ev);
    }
    ev.cost.is_finite()
}

/// Receives a block of Jacobian rows, residuals, the row count and the evaluation.
pub(super) type Sink<'a> = dyn FnMut(&mut Mat<f64>, &Mat<f64>, usize, &mut Evaluation) + 'a;

/// `H += Jb^T Jb` (its lower triangle only: [`cost`] mirrors it), `g -= Jb^T r` over the
/// first `rows` rows, then clears the block.
pub(super) fn flush(jb: &mut Mat<f64>, rb: &Mat<f64>, rows: usize, ev: &mut Evaluation) {
    let j = jb.as_ref().subrows(0, rows);
    let r = rb.as_ref().subrows(0, rows);
    let p = j.ncols();
    gram_add(ev.gauss_newton.as_mut(), j, Par::Seq);
    let mut g = Mat::<f64>::zeros(p, 1);
    matmul(g.as_mut(), Accum::Replace, j.transpose(), r, 1.0, Par::Seq);
    for a in 0..p {
        ev.gradient[a] -= g[(a, 0)];
    }
    jb.as_mut().subrows_mut(0, rows).fill(0.0);
}

struct SimulationError<'a, M> {
    model: &'a M,
    data: &'a [PnlssData<'a>],
}

/// How far the spectral radius of the linear part's `A` (the first `nx * nx` parameters,
/// row-major) lies above 1 when the model keeps it stable; `None` when it does not, or when
/// the eigenvalue solve fails or gives NaN (then the point is not admissible).
pub(super) fn linear_margin<M: NonlinearTerms>(model: &M, theta: &[f64]) -> Option<f64> {
    let n = model.dims().0;
    if !model.stable_linear() || n == 0 || theta.len() < n * n {
        return None;
    }
    let a = faer::MatRef::from_row_major_slice(&theta[..n * n], n, n);
    spectral_radius(a)
        .ok()
        .filter(|r| !r.is_nan())
        .map(|r| r - 1.0)
}

/// Whether `theta` lies in the admissible set of a model that keeps its linear part stable
/// (always, for one that does not).
pub(super) fn linear_admissible<M: NonlinearTerms>(model: &M, theta: &[f64]) -> bool {
    !model.stable_linear() || linear_margin(model, theta).is_some_and(|m| m < 0.0)
}

impl<M: NonlinearTerms> Problem for SimulationError<'_, M> {
    fn n_params(&self) -> usize {
        self.model.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        Ok(cost(self.model, theta, self.data, jacobian))
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        linear_admissible(self.model, theta)
    }

    fn bound_margin(&mut self, theta: &[f64]) -> Option<f64> {
        linear_margin(self.model, theta)
    }

    /// The residuals the cost sums: every output of every sample after each record's
    /// transient (so that [`Options::tol_statistical`] can stop at statistical convergence).
    fn n_residuals(&self) -> Option<usize> {
        let ny = self.model.dims().2.max(1);
        Some(
            self.data
                .iter()
                .map(|d| (d.y.len() / ny).saturating_sub(d.skip) * ny)
                .sum(),
        )
    }
}

/// Checks the records and the start, then fits on the simulation error with the shared
/// optimiser (a step whose simulation diverges is rejected like one that raises the cost).
pub(super) fn estimate<M: NonlinearTerms>(
    model: &M,
    data: &[PnlssData<'_>],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    estimate_checks(model, data, theta0)?;
    let mut prob = SimulationError { model, data };
    minimize(&mut prob, theta0, options, observer)
}

/// The checks of [`estimate`] (records, shapes, finite values, a transient shorter than the
/// record, a start whose simulation does not diverge); the start's time-domain cost.
pub(super) fn estimate_checks<M: NonlinearTerms>(
    model: &M,
    data: &[PnlssData<'_>],
    theta0: &[f64],
) -> Result<f64> {
    if data.is_empty() {
        return Err(SysidError::invalid("data", "no records"));
    }
    let (_, nu, ny) = model.dims();
    for d in data {
        let n = check(model, theta0, d.u, Some(d.y))?;
        if n <= d.skip {
            return Err(SysidError::InsufficientData {
                context: format!("a {} record after its transient", M::NAME),
                needed: d.skip + 1,
                got: n,
                fix: "use a longer record or a shorter transient",
            });
        }
        for (name, a, w) in [("u", d.u, nu), ("y", d.y, ny)] {
            if let Some(k) = a.iter().position(|v| !v.is_finite()) {
                return Err(SysidError::NonFinite {
                    what: name,
                    sample: k / w.max(1),
                    channel: k % w.max(1),
                });
            }
        }
    }
    let start = cost(model, theta0, data, false).cost;
    if !start.is_finite() {
        return Err(SysidError::numerical(
            M::NAME,
            "the initial model's simulation diverges on the data; start from a stable linear \
             model (the BLA or a subspace model)",
        ));
    }
    Ok(start)
}
