//! Frequency-domain refinement on the excited lines of periodic data.
//!
//! With periodic excitation in steady state, the DFT of one period (averaged over periods)
//! is, at an excited line `k`, `Y_k = G(z_k) U_k + V_k` with `z_k = e^{j w_k}`, no transient
//! and no initial state. On the lines the frequency response `G_k` and the variance `s2_k` of
//! each entry are known from the periods (the best linear approximation, computed by the
//! caller), and the model
//!
//! ```text
//! G(z) = C (z I - A)^-1 B + D
//! ```
//!
//! is fitted by minimising `V = 1/2 sum_k sum_ij w_kij |G_ij(z_k) - G_kij|^2`, with
//! `w = 2 / s2` the weight of the real and imaginary parts (each carries half the variance):
//! the maximum-likelihood criterion of frequency-domain tools when the variances come from
//! the periods; for one input `|Y_k - G U_k|^2 / var(Y_k)` is the same sum.
//!
//! The search is the shared optimiser ([`crate::optim`]). With `R = (z I - A)^-1`,
//! `X = R B` and `Y = C R`, the Jacobian of one entry is
//!
//! ```text
//! dG_ij/dA_ab = Y_ia X_bj,    dG_ij/dB_aj = Y_ia,    dG_ij/dC_ia = X_aj,    dG_ij/dD_ij = 1,
//! ```
//!
//! its real and imaginary parts two residual rows; the rows of a block of lines are folded
//! into `J^T W J` by one matrix product. As in the time domain ([`super::chart`]) `A` is held
//! in its real modal form (1x1 and 2x2 blocks; the entries outside the blocks fixed at zero),
//! so `R` is block diagonal and the free parameters are `sum bs^2 + n (m + l) (+ l m)`; the
//! search moves in the complement of the similarities that keep the blocks (the local
//! coordinates of [`super::coordinates`]). Without a well-conditioned modal form the whole of
//! `A` is one block. The admissible set is a stable `A`.

use super::coordinates::{scaled_complement, similarity_tangent, Part};
use super::modal::modal_form;
use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::model::StateSpace;
use crate::optim::{self, Covariance, Evaluation, Flow, Iteration, Problem, Solution};
use faer::{c64, Mat, MatRef, Par};

/// Frequency-response data on the excited lines: `G_k` (`l x m`, entry `(i, j)` in column
/// `i m + j`) at the normalised frequency `omega[k]` (rad/sample, `z_k = e^{j omega_k}`)
/// with non-negative weights (inverse variances) of the same layout.
#[derive(Debug, Clone, Copy)]
pub struct Lines<'a> {
    /// Normalised angular frequencies in `[0, pi]`, one per line.
    pub omega: &'a [f64],
    /// Real parts of `G_k`, lines x `l m`.
    pub re: MatRef<'a, f64>,
    /// Imaginary parts of `G_k`, lines x `l m`.
    pub im: MatRef<'a, f64>,
    /// Weights `1 / s2` (zero leaves an entry out), lines x `l m`.
    pub weight: MatRef<'a, f64>,
}

/// Options of [`pem_frequency`]. Build with `FrequencyOptions::default()` and set fields.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct FrequencyOptions {
    /// Estimate `D` (`true`) or keep the start's (`false`, default).
    pub estimate_d: bool,
    /// Hold `A` in its real modal form (default `true`).
    pub modal_chart: bool,
    /// Options of the search.
    pub optim: optim::Options,
}

impl Default for FrequencyOptions {
    fn default() -> Self {
        FrequencyOptions {
            estimate_d: false,
            modal_chart: true,
            optim: optim::Options {
                max_iter: 50,
                tol_cost: 1e-6,
                tol_statistical: 1e-2,
                ..Default::default()
            },
        }
    }
}

/// The refined model and what the search did.
#[derive(Debug, Clone)]
pub struct FrequencyResult {
    /// The refined `(A, B, C, D)`, in the modal basis of the start when the chart was used.
    pub sys: StateSpace,
    /// All entries of `A, B, C` (row-major), then `D` when estimated.
    pub theta: Vec<f64>,
    /// What the search did (gradient and Gauss-Newton matrix over `theta`; the entries the
    /// chart holds have zero rows).
    pub solution: Solution,
    /// Covariance of `theta`: `s2 (J^T W J)^+` with `s2` the residual scale below.
    pub covariance: Covariance,
    /// Real residuals in the cost (twice the weighted entries over the lines).
    pub n_residuals: usize,
    /// `2 V / (n_residuals - rank)`: about 1 when the weights are the inverse noise variances
    /// and the model explains the lines; larger with model errors (nonlinear distortions).
    pub residual_scale: f64,
    /// Largest pole modulus of the refined `A`.
    pub spectral_radius: f64,
    /// Whether `A` was held in its modal form.
    pub modal: bool,
}

/// The fit of `G(z)` to the lines as an optimisation problem over the free parameters.
pub(crate) struct LineFit<'a> {
    lines: Lines<'a>,
    z: Vec<c64>,
    n: usize,
    m: usize,
    l: usize,
    /// (first state, size) of each block of `A`.
    blocks: Vec<(usize, usize)>,
    /// Index in the full layout of each free parameter.
    free: Vec<usize>,
    /// Free column of each full parameter.
    column: Vec<Option<usize>>,
    /// The full parameter vector (the held entries and, without `estimate_d`, `D`).
    full: Vec<f64>,
    d_fixed: Mat<f64>,
    estimate_d: bool,
    /// Search in the complement of the similarities that keep the blocks (the state-space
    /// parameterisation); `false` for a caller whose own parameters fix the basis.
    orbit: bool,
}

/// Lines per block of the Jacobian accumulation.
const BLOCK: usize = 128;

impl<'a> LineFit<'a> {
    /// The fit over every entry of `A, B, C, D` (row-major, the layout of the grey-box
    /// parameter map), `A` one block, no similarity orbit: for a caller that searches its
    /// own parameters through [`crate::optim::Reparameterized`]. Checks the lines.
    pub(crate) fn all_entries(lines: &Lines<'a>, n: usize, m: usize, l: usize) -> Result<Self> {
        check_lines(lines, l, m)?;
        let p = n * (n + m + l) + l * m;
        Ok(LineFit {
            lines: *lines,
            z: unit_circle(lines.omega),
            n,
            m,
            l,
            blocks: if n > 0 { vec![(0, n)] } else { Vec::new() },
            free: (0..p).collect(),
            column: (0..p).map(Some).collect(),
            full: vec![0.0; p],
            d_fixed: Mat::zeros(l, m),
            estimate_d: true,
            orbit: false,
        })
    }

    /// Real residuals in the cost: twice the weighted line entries.
    pub(crate) fn n_residuals_weighted(&self) -> usize {
        2 * self.n_weighted()
    }

    fn layout(&self) -> (usize, usize, usize) {
        let (n, m) = (self.n, self.m);
        (n * n, n * n + n * m, n * n + n * m + self.l * n)
    }

    fn expand(&self, th: &[f64]) -> Vec<f64> {
        let mut full = self.full.clone();
        for (c, &i) in self.free.iter().enumerate() {
            full[i] = th[c];
        }
        full
    }

    fn matrices(&self, th: &[f64]) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
        let full = self.expand(th);
        unpack(
            &full,
            self.n,
            self.m,
            self.l,
            self.estimate_d,
            &self.d_fixed,
        )
    }

    /// `X = R B` (n x m) and `Y = C R` (l x n) at `z`, block by block.
    fn resolvent_products(
        &self,
        a: &Mat<f64>,
        b: &Mat<f64>,
        c: &Mat<f64>,
        z: c64,
    ) -> (Mat<c64>, Mat<c64>) {
        let (n, m, l) = (self.n, self.m, self.l);
        let mut x = Mat::<c64>::zeros(n, m);
        let mut y = Mat::<c64>::zeros(l, n);
        for &(s, bs) in &self.blocks {
            let r = block_resolvent(a, s, bs, z);
            for i in 0..bs {
                for k in 0..bs {
                    let rik = r[(i, k)];
                    for j in 0..m {
                        x[(s + i, j)] += rik * b[(s + k, j)];
                    }
                    for o in 0..l {
                        y[(o, s + k)] += c[(o, s + i)] * rik;
                    }
                }
            }
        }
        (x, y)
    }

    /// Weighted residuals and, with `rows`, the Jacobian rows of lines `lo..hi` (two real
    /// rows per entry: real part, then imaginary part).
    fn residual_block(
        &self,
        th: &[f64],
        lo: usize,
        hi: usize,
        jac: Option<&mut Mat<f64>>,
    ) -> Vec<f64> {
        let (a, b, c, d) = self.matrices(th);
        let (m, l) = (self.m, self.l);
        let (ob, oc, od) = self.layout();
        let mut r = vec![0.0; (hi - lo) * l * m * 2];
        let mut jac = jac;
        for k in lo..hi {
            let (x, y) = self.resolvent_products(&a, &b, &c, self.z[k]);
            for i in 0..l {
                for j in 0..m {
                    let e = i * m + j;
                    let w = self.lines.weight[(k, e)].sqrt();
                    let mut g = c64::new(d[(i, j)], 0.0);
                    for s in 0..self.n {
                        g += c[(i, s)] * x[(s, j)];
                    }
                    let row = 2 * ((k - lo) * l * m + e);
                    let res = (g - c64::new(self.lines.re[(k, e)], self.lines.im[(k, e)])) * w;
                    r[row] = res.re;
                    r[row + 1] = res.im;
                    let Some(jm) = jac.as_deref_mut() else {
                        continue;
                    };
                    let mut put = |idx: usize, v: c64| {
                        if let Some(col) = self.column[idx] {
                            jm[(row, col)] += w * v.re;
                            jm[(row + 1, col)] += w * v.im;
                        }
                    };
                    for &(s, bs) in &self.blocks {
                        for p in s..s + bs {
                            for q in s..s + bs {
                                put(p * self.n + q, y[(i, p)] * x[(q, j)]);
                            }
                        }
                    }
                    for p in 0..self.n {
                        put(ob + p * m + j, y[(i, p)]);
                        put(oc + i * self.n + p, x[(p, j)]);
                    }
                    if self.estimate_d {
                        put(od + e, c64::new(1.0, 0.0));
                    }
                }
            }
        }
        r
    }

    /// Tangent vectors (free parameters x similarities) of the similarities `T = I + E_ab`
    /// that keep the blocks of `A`.
    fn orbit_tangent(&self, th: &[f64]) -> Mat<f64> {
        let (a, b, c, _) = self.matrices(th);
        let (ob, oc, _) = self.layout();
        let pairs: Vec<(usize, usize)> = self
            .blocks
            .iter()
            .flat_map(|&(s, bs)| (s..s + bs).flat_map(move |p| (s..s + bs).map(move |q| (p, q))))
            .collect();
        let mut tan = Mat::<f64>::zeros(self.free.len(), pairs.len());
        similarity_tangent(&a, &b, &c, &pairs, |col, part, idx, v| {
            let base = match part {
                Part::A => 0,
                Part::B => ob,
                Part::C => oc,
            };
            if let Some(f) = self.column[base + idx] {
                tan[(f, col)] += v;
            }
        });
        tan
    }

    fn n_weighted(&self) -> usize {
        let w = self.lines.weight;
        (0..w.nrows())
            .map(|k| (0..w.ncols()).filter(|&e| w[(k, e)] > 0.0).count())
            .sum()
    }
}

impl Problem for LineFit<'_> {
    fn n_params(&self) -> usize {
        self.free.len()
    }

    fn evaluate(&mut self, th: &[f64], jacobian: bool) -> Result<Evaluation> {
        let q = self.free.len();
        let nk = self.z.len();
        let mut ev = Evaluation::cost_only(0.0);
        if jacobian {
            ev.gradient = vec![0.0; q];
            ev.gauss_newton = Mat::zeros(q, q);
        }
        let mut lo = 0;
        while lo < nk {
            crate::interrupt::check()?;
            let hi = (lo + BLOCK).min(nk);
            let rows = (hi - lo) * self.l * self.m * 2;
            let mut jb = jacobian.then(|| Mat::<f64>::zeros(rows, q));
            let r = self.residual_block(th, lo, hi, jb.as_mut());
            ev.cost += 0.5 * r.iter().map(|v| v * v).sum::<f64>();
            if let Some(jb) = jb {
                // the calling thread for the small products of every iterate
                optim::gram_add(
                    ev.gauss_newton.as_mut(),
                    jb.as_ref(),
                    optim::small_par(rows, q),
                );
                for (c, gi) in ev.gradient.iter_mut().enumerate() {
                    *gi += (0..rows).map(|i| jb[(i, c)] * r[i]).sum::<f64>();
                }
            }
            lo = hi;
        }
        if jacobian {
            optim::mirror_lower(&mut ev.gauss_newton);
        }
        Ok(ev)
    }

    fn admissible(&mut self, th: &[f64]) -> bool {
        let (a, ..) = self.matrices(th);
        matches!(spectral_radius(a.as_ref()), Ok(r) if r < 1.0)
    }

    fn search_basis(&mut self, th: &[f64], scale: &[f64]) -> Result<Option<Mat<f64>>> {
        if !self.orbit {
            return Ok(None);
        }
        scaled_complement(&self.orbit_tangent(th), scale).map(Some)
    }

    fn invariant_directions(&mut self, th: &[f64]) -> Result<Option<Mat<f64>>> {
        if !self.orbit {
            return Ok(None);
        }
        Ok(Some(self.orbit_tangent(th)))
    }

    fn n_residuals(&self) -> Option<usize> {
        Some(2 * self.n_weighted())
    }
}

/// `z_k = e^{j omega_k}` of each line.
fn unit_circle(omega: &[f64]) -> Vec<c64> {
    omega.iter().map(|&w| c64::new(w.cos(), w.sin())).collect()
}

/// `(z I - A_bb)^-1` of the diagonal block `(s, bs)` of `a`.
fn block_resolvent(a: &Mat<f64>, s: usize, bs: usize, z: c64) -> Mat<c64> {
    let at = |i: usize, j: usize| c64::new(a[(s + i, s + j)], 0.0);
    match bs {
        1 => Mat::from_fn(1, 1, |_, _| c64::new(1.0, 0.0) / (z - at(0, 0))),
        2 => {
            let (p, q, r, t) = (z - at(0, 0), -at(0, 1), -at(1, 0), z - at(1, 1));
            let inv = c64::new(1.0, 0.0) / (p * t - q * r);
            let v = [[t * inv, -q * inv], [-r * inv, p * inv]];
            Mat::from_fn(2, 2, |i, j| v[i][j])
        }
        _ => {
            let m = Mat::from_fn(bs, bs, |i, j| {
                let d = if i == j { z } else { c64::new(0.0, 0.0) };
                d - at(i, j)
            });
            small_inverse(m)
        }
    }
}

/// The inverse of a small complex matrix: faer's partial-pivoting LU and its inverse, run
/// sequentially (`Par::Seq`: the global thread pool costs more than the work at the sizes of
/// a grey-box structure's `A`, once per line and evaluation).
fn small_inverse(mut m: Mat<c64>) -> Mat<c64> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::lu::partial_pivoting::{factor, inverse};
    let n = m.nrows();
    let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
    let req = factor::lu_in_place_scratch::<usize, c64>(n, n, Par::Seq, Default::default())
        .or(inverse::inverse_scratch::<usize, c64>(n, Par::Seq));
    let mut buf = MemBuffer::new(req);
    let stack = MemStack::new(&mut buf);
    let (_, p) = factor::lu_in_place(
        m.as_mut(),
        &mut perm,
        &mut perm_inv,
        Par::Seq,
        stack,
        Default::default(),
    );
    let mut out = Mat::zeros(n, n);
    inverse::inverse(out.as_mut(), m.as_ref(), m.as_ref(), p, Par::Seq, stack);
    out
}

/// `(A, B, C, D)` from the full parameter vector.
fn unpack(
    th: &[f64],
    n: usize,
    m: usize,
    l: usize,
    estimate_d: bool,
    d_fixed: &Mat<f64>,
) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
    let (ob, oc, od) = (n * n, n * n + n * m, n * n + n * m + l * n);
    let a = Mat::from_fn(n, n, |i, j| th[i * n + j]);
    let b = Mat::from_fn(n, m, |i, j| th[ob + i * m + j]);
    let c = Mat::from_fn(l, n, |i, j| th[oc + i * n + j]);
    let d = if estimate_d {
        Mat::from_fn(l, m, |i, j| th[od + i * m + j])
    } else {
        d_fixed.clone()
    };
    (a, b, c, d)
}

/// Checks the lines against the model's sizes.
fn check_lines(lines: &Lines<'_>, l: usize, m: usize) -> Result<()> {
    let nk = lines.omega.len();
    for (what, x) in [("re", lines.re), ("im", lines.im), ("weight", lines.weight)] {
        if x.nrows() != nk || x.ncols() != l * m {
            return Err(SysidError::ShapeMismatch {
                what: format!("lines.{what}"),
                expected: format!("({nk}, {}) (lines x outputs * inputs)", l * m),
                got: format!("({}, {})", x.nrows(), x.ncols()),
            });
        }
        crate::error::check_finite("lines", x)?;
    }
    if let Some(w) = lines
        .omega
        .iter()
        .find(|w| !(w.is_finite() && (0.0..=std::f64::consts::PI).contains(*w)))
    {
        return Err(SysidError::invalid(
            "omega",
            format!("line frequencies must lie in [0, pi] rad/sample, got {w}"),
        ));
    }
    let w = lines.weight;
    if (0..nk).any(|k| (0..l * m).any(|e| w[(k, e)] < 0.0)) {
        return Err(SysidError::invalid(
            "weight",
            "weights must be >= 0".to_string(),
        ));
    }
    Ok(())
}

/// Refines `start` by fitting its frequency response to `lines` (see the module notes).
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::model::StateSpace;
/// use sysid_core::pem::{pem_frequency, FrequencyOptions, Lines};
/// // lines of G(z) = 1 / (z - 0.5)
/// let omega: Vec<f64> = (1..20).map(|k| 0.15 * k as f64).collect();
/// let g: Vec<(f64, f64)> = omega.iter().map(|w| {
///     let (c, s) = (w.cos() - 0.5, w.sin());
///     (c / (c * c + s * s), -s / (c * c + s * s))
/// }).collect();
/// let re = Mat::from_fn(19, 1, |k, _| g[k].0);
/// let im = Mat::from_fn(19, 1, |k, _| g[k].1);
/// let w = Mat::from_fn(19, 1, |_, _| 1.0);
/// let lines = Lines { omega: &omega, re: re.as_ref(), im: im.as_ref(), weight: w.as_ref() };
/// let start = StateSpace::new(mat![[0.3]], mat![[0.8]], mat![[1.0]], mat![[0.0]]).unwrap();
/// let r = pem_frequency(&start, &lines, &FrequencyOptions::default(), &mut |_| {
///     sysid_core::optim::Flow::Continue
/// }).unwrap();
/// assert!((r.sys.a[(0, 0)] - 0.5).abs() < 1e-8);
/// ```
pub fn pem_frequency(
    start: &StateSpace,
    lines: &Lines<'_>,
    opts: &FrequencyOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<FrequencyResult> {
    let (n, m, l) = (start.n_states(), start.n_inputs(), start.n_outputs());
    check_lines(lines, l, m)?;
    let md = if opts.modal_chart && n > 1 {
        modal_form(start.a.as_ref())
    } else {
        None
    };
    let (a, b, c, blocks) = match &md {
        Some(md) => {
            let mut blocks: Vec<(usize, usize)> = md.block.clone();
            blocks.dedup();
            let a = Mat::from_fn(n, n, |i, j| {
                if md.block[i] == md.block[j] {
                    md.lam[(i, j)]
                } else {
                    0.0
                }
            });
            (a, &md.ti * &start.b, &start.c * &md.t, blocks)
        }
        None => (
            start.a.clone(),
            start.b.clone(),
            start.c.clone(),
            // all of A one block (none for a static model)
            if n > 0 { vec![(0, n)] } else { Vec::new() },
        ),
    };
    let p = n * (n + m + l) + usize::from(opts.estimate_d) * l * m;
    let mut full = Vec::with_capacity(p);
    full.extend((0..n * n).map(|i| a[(i / n, i % n)]));
    full.extend((0..n * m).map(|i| b[(i / m, i % m)]));
    full.extend((0..l * n).map(|i| c[(i / n, i % n)]));
    if opts.estimate_d {
        full.extend((0..l * m).map(|i| start.d[(i / m, i % m)]));
    }
    let in_block = |i: usize| {
        let (r, col) = (i / n, i % n);
        blocks
            .iter()
            .any(|&(s, bs)| (s..s + bs).contains(&r) && (s..s + bs).contains(&col))
    };
    let free: Vec<usize> = (0..p).filter(|&i| i >= n * n || in_block(i)).collect();
    let mut column = vec![None; p];
    for (f, &i) in free.iter().enumerate() {
        column[i] = Some(f);
    }
    let mut prob = LineFit {
        lines: *lines,
        z: unit_circle(lines.omega),
        n,
        m,
        l,
        blocks,
        free,
        column,
        full,
        d_fixed: start.d.clone(),
        estimate_d: opts.estimate_d,
        orbit: true,
    };
    let identifiable = n * (m + l) + usize::from(opts.estimate_d) * l * m;
    let n_res = 2 * prob.n_weighted();
    if n_res < identifiable {
        return Err(SysidError::InsufficientData {
            context: format!("an order-{n} model with {identifiable} identifiable parameters"),
            needed: identifiable,
            got: n_res,
            fix: "real residuals (twice the weighted line entries): lower the order or excite more lines",
        });
    }
    let theta0: Vec<f64> = prob.free.iter().map(|&i| prob.full[i]).collect();
    if !prob.admissible(&theta0) {
        return Err(SysidError::invalid(
            "start model",
            "A has a pole on or outside the unit circle; stabilise the start first".to_string(),
        ));
    }
    let mut sol = optim::minimize(&mut prob, &theta0, &opts.optim, observer)?;
    let cov = optim::covariance(sol.gauss_newton.as_ref(), 1.0, 1e-10)?;
    let scale = optim::residual_scale(sol.cost, n_res, cov.rank);
    let q = prob.free.len();
    let embed_vec = |v: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; p];
        for (f, &i) in prob.free.iter().enumerate() {
            out[i] = v[f];
        }
        out
    };
    let embed_mat = |h: &Mat<f64>, s: f64| -> Mat<f64> {
        let mut out = Mat::zeros(p, p);
        for a in 0..q {
            for b in 0..q {
                out[(prob.free[a], prob.free[b])] = s * h[(a, b)];
            }
        }
        out
    };
    let theta = prob.expand(&sol.theta);
    let (a, b, c, d) = unpack(&theta, n, m, l, opts.estimate_d, &prob.d_fixed);
    let unidentifiable = Mat::from_fn(p, cov.unidentifiable.ncols(), |i, j| {
        prob.column[i].map_or(0.0, |f| cov.unidentifiable[(f, j)])
    });
    let covariance = Covariance {
        covariance: embed_mat(&cov.covariance, scale),
        rank: cov.rank,
        unidentifiable,
        condition: cov.condition,
    };
    sol.gradient = embed_vec(&sol.gradient);
    sol.gauss_newton = embed_mat(&sol.gauss_newton, 1.0);
    sol.active_bounds = sol.active_bounds.iter().map(|&f| prob.free[f]).collect();
    sol.theta = theta.clone();
    let spectral = spectral_radius(a.as_ref())?;
    Ok(FrequencyResult {
        sys: StateSpace::new(a, b, c, d)?,
        theta,
        solution: sol,
        covariance,
        n_residuals: n_res,
        residual_scale: scale,
        spectral_radius: spectral,
        modal: md.is_some(),
    })
}

#[cfg(test)]
mod resolvent_tests {
    use super::block_resolvent;
    use faer::{c64, Mat};

    /// A 3 x 3 diagonal block (the case that goes through the LU) times its resolvent is the
    /// identity, with the block at an offset inside a larger `A`.
    #[test]
    fn a_three_by_three_block_resolvent_inverts_z_minus_a() {
        let a = Mat::from_fn(5, 5, |i, j| ((3 * i + 7 * j) % 5) as f64 * 0.1 - 0.2);
        let z = c64::new(0.3, 0.8);
        let r = block_resolvent(&a, 1, 3, z);
        for i in 0..3 {
            for j in 0..3 {
                let mut s = c64::new(0.0, 0.0);
                for k in 0..3 {
                    let zi = if i == k { z } else { c64::new(0.0, 0.0) };
                    s += (zi - c64::new(a[(1 + i, 1 + k)], 0.0)) * r[(k, j)];
                }
                let e = if i == j { 1.0 } else { 0.0 };
                assert!((s - c64::new(e, 0.0)).norm() < 1e-13, "{i},{j}: {s:?}");
            }
        }
    }
}
