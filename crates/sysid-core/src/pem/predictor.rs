//! The innovation predictor as an [`optim::Problem`] and the [`pem`] driver.

use crate::error::{check_finite, check_io, Result, SysidError};
use crate::linalg::{determinant, spectral_radius};
use crate::model::StateSpace;
use crate::optim::{self, Covariance, Evaluation, Flow, Iteration, Problem, Solution};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self as tri, BlockStructure};
use faer::{Accum, Mat, MatRef, Par, Side};

/// What the predictor's errors are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Focus {
    /// One-step-ahead prediction errors of the innovation form (K estimated or fixed).
    Prediction,
    /// Simulation errors (K = 0).
    Simulation,
}

/// The initial state of one experiment.
#[derive(Debug, Clone, PartialEq)]
pub enum InitialState {
    /// Estimated with the other parameters (started at its least-squares value).
    Estimate,
    /// Zero.
    Zero,
    /// A given value (length n), not estimated.
    Given(Vec<f64>),
}

/// Options of [`pem`]. Build with `PemOptions::default()` and set fields.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct PemOptions {
    /// Prediction (default) or simulation errors.
    pub focus: Focus,
    /// Estimate D (`true`) or keep it at its start value (`false`, default).
    pub estimate_d: bool,
    /// Estimate K (default) or keep it fixed at its start value (prediction focus only).
    pub estimate_k: bool,
    /// Initial state per experiment; a single entry applies to all. Default: estimated.
    pub x0: Vec<InitialState>,
    /// Re-estimate the weighting `W = Lambda^-1` between iterations (default `true`);
    /// `false` keeps `W = I`.
    pub reweight: bool,
    /// Search in data-driven local coordinates (default `true`).
    pub local_coordinates: bool,
    /// Samples per block in the accumulation of the normal equations.
    pub block: usize,
    /// Options of the search (tolerances, iteration cap, regularisation, ...).
    pub optim: optim::Options,
}

impl Default for PemOptions {
    fn default() -> Self {
        let o = optim::Options {
            max_iter: 50,
            tol_cost: 1e-6,
            // J^T W J costs O(N min(l, n) p^2), the gradient O(N n^2 p): chord steps
            reuse_gauss_newton: 3,
            ..Default::default()
        };
        PemOptions {
            focus: Focus::Prediction,
            estimate_d: false,
            estimate_k: true,
            x0: vec![InitialState::Estimate],
            reweight: true,
            local_coordinates: true,
            block: 128,
            optim: o,
        }
    }
}

/// The refined model and what the search did.
#[derive(Debug, Clone)]
pub struct PemResult {
    /// The refined (A, B, C, D).
    pub sys: StateSpace,
    /// The refined Kalman gain (zero for simulation focus).
    pub k: Mat<f64>,
    /// The initial state of each experiment (estimated, zero or given).
    pub x0: Vec<Vec<f64>>,
    /// Sample covariance of the prediction errors at the solution, l x l.
    pub innovation_covariance: Mat<f64>,
    /// The free parameters at the solution (layout in [`Predictor`]).
    pub theta: Vec<f64>,
    /// What the search did.
    pub solution: Solution,
    /// Covariance of `theta` from the Gauss-Newton matrix with `W = Lambda^-1`.
    pub covariance: Covariance,
    /// Number of samples used.
    pub n_samples: usize,
    /// `det(Lambda)` (the maximum-likelihood loss, MATLAB's "loss function") at the start and
    /// after every accepted iteration.
    pub loss_history: Vec<f64>,
}

/// `(theta, Gram of the modal sensitivities, cross sums with the regressor, sum z z^T)`.
type GramCache = (Vec<f64>, Mat<f64>, Mat<f64>, Mat<f64>);

/// The innovation predictor over several experiments, as an optimisation problem.
///
/// Parameter layout (row-major blocks): `A (n*n), B (n*m), C (l*n)`, then `D (l*m)` when
/// estimated, `K (n*l)` when estimated, then `x0` (n) of every experiment whose initial state
/// is estimated, in experiment order.
pub struct Predictor<'a> {
    exps: Vec<(MatRef<'a, f64>, MatRef<'a, f64>)>,
    n: usize,
    m: usize,
    l: usize,
    focus: Focus,
    est_d: bool,
    est_k: bool,
    d_fixed: Mat<f64>,
    k_fixed: Mat<f64>,
    x0_mode: Vec<InitialState>,
    x0_off: Vec<Option<usize>>,
    p: usize,
    /// `R^-1` with `R R^T = Lambda` (weighted residual `R^-1 e`).
    rinv: Mat<f64>,
    floor: Vec<f64>,
    reweight: bool,
    local: bool,
    block: usize,
    n_samples: usize,
    losses: Vec<f64>,
    /// Sensitivities are formed only for parameters `>= col_lo` (the others get zero rows and
    /// columns in the Gauss-Newton matrix): the initial-state-only pre-step sets it.
    col_lo: usize,
    /// Form `J^T W J` through the predictor parameterisation (see [`Predictor::evaluate_structured`]);
    /// `false` forms every Jacobian row (the reference path, kept for tests).
    pub(super) structured: bool,
    /// Within the structured path, use the modal coordinates of `A - K C` when well
    /// conditioned ([`Predictor::evaluate_modal`]).
    pub(super) modal: bool,
    /// Within the modal path, carry only the first row of each complex pair's sensitivities
    /// (the second is its rotation, see [`Predictor::evaluate_modal`]); `false` carries both
    /// (the reference, kept for tests).
    pub(super) halve: bool,
    /// The weighting-independent sums of the last modal `J^T W J` (`theta`, Gram of the
    /// sensitivities, their cross sums with the regressor, `sum z z^T`): a re-weighted
    /// Gauss-Newton matrix at the same point (the covariance after an unweighted search)
    /// costs a gradient pass instead of a full one.
    gram_cache: Option<GramCache>,
}

struct Unpacked {
    a: Mat<f64>,
    b: Mat<f64>,
    c: Mat<f64>,
    d: Mat<f64>,
    k: Mat<f64>,
    x0: Vec<Vec<f64>>,
}

impl<'a> Predictor<'a> {
    /// Checks the data and builds the problem around a start model.
    pub fn new(
        start: &StateSpace,
        k0: Option<MatRef<'_, f64>>,
        experiments: &[(MatRef<'a, f64>, MatRef<'a, f64>)],
        opts: &PemOptions,
    ) -> Result<Self> {
        let (n, m, l) = (start.n_states(), start.n_inputs(), start.n_outputs());
        if experiments.is_empty() {
            return Err(SysidError::invalid("data", "no experiment given"));
        }
        if opts.block == 0 {
            return Err(SysidError::invalid("block", "must be >= 1"));
        }
        let mut n_samples = 0;
        let mut floor = vec![0.0; l];
        for (e, (u, y)) in experiments.iter().enumerate() {
            check_io(&format!("experiment {e} (u, y)"), *u, *y, m, l)?;
            n_samples += y.nrows();
            for j in 0..l {
                for t in 0..y.nrows() {
                    floor[j] += y[(t, j)] * y[(t, j)];
                }
            }
        }
        let x0_mode: Vec<InitialState> = match opts.x0.len() {
            1 => vec![opts.x0[0].clone(); experiments.len()],
            k if k == experiments.len() => opts.x0.clone(),
            k => {
                return Err(SysidError::invalid(
                    "x0",
                    format!(
                    "{k} initial-state choices for {} experiments; give one or one per experiment",
                    experiments.len()
                ),
                ))
            }
        };
        for s in &x0_mode {
            if let InitialState::Given(v) = s {
                if v.len() != n || v.iter().any(|x| !x.is_finite()) {
                    return Err(SysidError::invalid(
                        "x0",
                        format!("a given initial state must have {n} finite entries"),
                    ));
                }
            }
        }
        let needed = n * n + n * m + l * n;
        if n_samples * l < needed {
            return Err(SysidError::InsufficientData {
                context: "prediction-error refinement".into(),
                needed: needed.div_ceil(l.max(1)),
                got: n_samples,
                fix: "use a longer record or a lower order",
            });
        }
        let est_k = opts.estimate_k && opts.focus == Focus::Prediction;
        let k_fixed = match (opts.focus, k0) {
            (Focus::Simulation, _) | (_, None) => Mat::zeros(n, l),
            (_, Some(k)) => {
                if k.nrows() != n || k.ncols() != l {
                    return Err(SysidError::ShapeMismatch {
                        what: "K".into(),
                        expected: format!("({n}, {l})"),
                        got: format!("({}, {})", k.nrows(), k.ncols()),
                    });
                }
                check_finite("K", k)?;
                k.to_owned()
            }
        };
        let mut p = n * n + n * m + l * n;
        if opts.estimate_d {
            p += l * m;
        }
        if est_k {
            p += n * l;
        }
        let mut x0_off = Vec::new();
        for s in &x0_mode {
            if *s == InitialState::Estimate {
                x0_off.push(Some(p));
                p += n;
            } else {
                x0_off.push(None);
            }
        }
        for f in floor.iter_mut() {
            *f = (*f / n_samples as f64).max(f64::MIN_POSITIVE) * 1e-12;
        }
        Ok(Predictor {
            exps: experiments.to_vec(),
            n,
            m,
            l,
            focus: opts.focus,
            est_d: opts.estimate_d,
            est_k,
            d_fixed: start.d.clone(),
            k_fixed,
            x0_mode,
            x0_off,
            p,
            rinv: Mat::identity(l, l),
            floor,
            reweight: opts.reweight,
            local: opts.local_coordinates,
            block: opts.block,
            n_samples,
            losses: Vec::new(),
            col_lo: 0,
            structured: true,
            modal: true,
            halve: true,
            gram_cache: None,
        })
    }

    /// The parameter vector of a model (initial states: zero where estimated).
    pub fn pack(&self, sys: &StateSpace, k: MatRef<'_, f64>, x0: &[Vec<f64>]) -> Vec<f64> {
        let mut th = Vec::with_capacity(self.p);
        let push = |th: &mut Vec<f64>, m: MatRef<'_, f64>| {
            for i in 0..m.nrows() {
                for j in 0..m.ncols() {
                    th.push(m[(i, j)]);
                }
            }
        };
        push(&mut th, sys.a.as_ref());
        push(&mut th, sys.b.as_ref());
        push(&mut th, sys.c.as_ref());
        if self.est_d {
            push(&mut th, sys.d.as_ref());
        }
        if self.est_k {
            push(&mut th, k);
        }
        for (e, off) in self.x0_off.iter().enumerate() {
            if off.is_some() {
                th.extend_from_slice(&x0[e]);
            }
        }
        th
    }

    fn unpack(&self, th: &[f64]) -> Unpacked {
        let (n, m, l) = (self.n, self.m, self.l);
        let mut o = 0;
        let mut take = |r: usize, c: usize| {
            let mat = Mat::from_fn(r, c, |i, j| th[o + i * c + j]);
            o += r * c;
            mat
        };
        let a = take(n, n);
        let b = take(n, m);
        let c = take(l, n);
        let d = if self.est_d {
            take(l, m)
        } else {
            self.d_fixed.clone()
        };
        let k = if self.est_k {
            take(n, l)
        } else {
            self.k_fixed.clone()
        };
        let x0 = self
            .x0_mode
            .iter()
            .zip(&self.x0_off)
            .map(|(mode, off)| match (mode, off) {
                (_, Some(o)) => th[*o..*o + n].to_vec(),
                (InitialState::Given(v), None) => v.clone(),
                _ => vec![0.0; n],
            })
            .collect();
        Unpacked { a, b, c, d, k, x0 }
    }

    fn column_offsets(&self) -> (usize, usize, usize, Option<usize>, Option<usize>) {
        let (n, m, l) = (self.n, self.m, self.l);
        let ia = 0;
        let ib = n * n;
        let ic = ib + n * m;
        let mut next = ic + l * n;
        let id = if self.est_d {
            let v = next;
            next += l * m;
            Some(v)
        } else {
            None
        };
        let ik = if self.est_k { Some(next) } else { None };
        (ia, ib, ic, id, ik)
    }

    /// `det(Lambda)` at the start and after every accepted step (the maximum-likelihood loss).
    pub(crate) fn losses(&mut self) -> &mut Vec<f64> {
        &mut self.losses
    }

    /// Whether the weighting is re-estimated between steps; set it.
    pub(crate) fn set_reweight(&mut self, on: bool) {
        self.reweight = on;
    }

    /// Total number of samples over the experiments.
    pub(crate) fn n_samples(&self) -> usize {
        self.n_samples
    }

    /// Prediction errors' sample covariance at `theta`.
    pub fn innovation_covariance(&self, th: &[f64]) -> Mat<f64> {
        let l = self.l;
        let mut lam = Mat::<f64>::zeros(l, l);
        self.residual_pass(th, &mut |e: &[f64]| {
            for i in 0..l {
                for j in 0..=i {
                    lam[(i, j)] += e[i] * e[j];
                }
            }
        });
        let nf = self.n_samples as f64;
        Mat::from_fn(l, l, |i, j| {
            let (a, b) = if i >= j { (i, j) } else { (j, i) };
            lam[(a, b)] / nf
        })
    }

    fn residual_pass(&self, th: &[f64], f: &mut dyn FnMut(&[f64])) {
        let (n, m, l) = (self.n, self.m, self.l);
        let p = self.unpack(th);
        let abar = &p.a - &p.k * &p.c;
        let bbar = &p.b - &p.k * &p.d;
        let mut e = vec![0.0; l];
        let mut xn = vec![0.0; n];
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            let mut x = p.x0[ex].clone();
            for t in 0..y.nrows() {
                for i in 0..l {
                    let mut s = y[(t, i)];
                    for j in 0..n {
                        s -= p.c[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        s -= p.d[(i, j)] * u[(t, j)];
                    }
                    e[i] = s;
                }
                f(&e);
                for i in 0..n {
                    let mut s = 0.0;
                    for j in 0..n {
                        s += abar[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        s += bbar[(i, j)] * u[(t, j)];
                    }
                    for j in 0..l {
                        s += p.k[(i, j)] * y[(t, j)];
                    }
                    xn[i] = s;
                }
                std::mem::swap(&mut x, &mut xn);
            }
        }
    }

    /// Sets the weighting from the prediction errors at `theta`.
    pub(crate) fn reweight_at(&mut self, th: &[f64]) -> Result<()> {
        let l = self.l;
        let mut lam = self.innovation_covariance(th);
        // the criterion is the determinant of the covariance itself, not of the floored one
        self.losses.push(determinant(&lam));
        for i in 0..l {
            lam[(i, i)] += self.floor[i];
        }
        let llt = lam.llt(Side::Lower).map_err(|_| {
            SysidError::numerical(
                "prediction-error weighting",
                "the prediction-error covariance is not positive definite",
            )
        })?;
        let r = llt.L().to_owned();
        // invert the lower-triangular factor
        let mut rinv = Mat::<f64>::identity(l, l);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            r.as_ref(),
            rinv.as_mut(),
            Par::Seq,
        );
        self.rinv = rinv;
        Ok(())
    }
}

/// Sparse columns of `T = dphi/dtheta`, the derivative of the predictor parameters
/// `phi = (A - K C, B - K D, C, D, K, x0)` with respect to `theta = (A, B, C, D, K, x0)`
/// (both in the layout of [`Predictor`]): `(row, value)` pairs per column.
type SparseCols = Vec<Vec<(usize, f64)>>;

/// A real block-diagonal (modal) form `Lambda = T^-1 Abar T` with 1x1 and 2x2 blocks.
pub(super) struct Modal {
    t: Mat<f64>,
    ti: Mat<f64>,
    lam: Mat<f64>,
    /// For each state index: (first row, size) of its block.
    block: Vec<(usize, usize)>,
}

/// The modal form of `abar`, or `None` when its eigenvectors are ill-conditioned (then the
/// plain structured evaluation is used).
pub(super) fn modal_form(abar: MatRef<'_, f64>) -> Option<Modal> {
    use faer::linalg::solvers::DenseSolveCore;
    let n = abar.nrows();
    let eig = crate::realization::modal::eigen_decomposition(abar).ok()?;
    let mut t = Mat::<f64>::zeros(n, n);
    let mut lam = Mat::<f64>::zeros(n, n);
    let mut block = vec![(0usize, 0usize); n];
    let mut k = 0usize;
    let scale = 1.0 + eig.values.iter().map(|z| z.norm()).fold(0.0, f64::max);
    for (idx, z) in eig.values.iter().enumerate() {
        let v = eig.vectors.col(idx);
        if z.im.abs() <= 1e-13 * scale {
            if k >= n {
                return None;
            }
            // rotate the (complex) eigenvector to be real
            let mut big = 0usize;
            for i in 0..n {
                if v[i].norm() > v[big].norm() {
                    big = i;
                }
            }
            let ph = v[big].conj() * (1.0 / v[big].norm());
            for i in 0..n {
                t[(i, k)] = (v[i] * ph).re;
            }
            lam[(k, k)] = z.re;
            block[k] = (k, 1);
            k += 1;
        } else if z.im > 0.0 {
            if k + 1 >= n {
                return None;
            }
            for i in 0..n {
                t[(i, k)] = v[i].re;
                t[(i, k + 1)] = v[i].im;
            }
            lam[(k, k)] = z.re;
            lam[(k, k + 1)] = z.im;
            lam[(k + 1, k)] = -z.im;
            lam[(k + 1, k + 1)] = z.re;
            block[k] = (k, 2);
            block[k + 1] = (k, 2);
            k += 2;
        }
    }
    if k != n {
        return None;
    }
    let ti = t.partial_piv_lu().inverse();
    let norm1 = |m: &Mat<f64>| {
        (0..n)
            .map(|j| (0..n).map(|i| m[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let cond = norm1(&t) * norm1(&ti);
    if !cond.is_finite() || cond > 1e6 {
        return None;
    }
    let check = &ti * abar * &t - &lam;
    let anorm = abar.norm_max().max(1e-300);
    // NaN in the check counts as a failure
    let accurate = check.norm_max() <= 1e-11 * anorm * cond;
    if !accurate {
        return None;
    }
    Some(Modal { t, ti, lam, block })
}

impl Predictor<'_> {
    /// As [`Self::evaluate_structured`], with the state-moving parameters taken in the modal
    /// coordinates of `Abar` (`phi' = (T^-1 Abar T, T^-1 Bbar, C T, D, T^-1 K, T^-1 x0)`, a
    /// linear map of `phi` at the current point). There `Abar` is block diagonal, so the
    /// sensitivity of every state-moving parameter lives in one 1x1 or 2x2 block: `S` is
    /// stored compactly (`p_e <= 2 p_d` numbers per sample), its recursion costs `O(p_e)` and
    /// `sum S^T C^T W C S` comes from the Gram matrix of those numbers, `O(N p_e^2)` instead of
    /// `O(N min(l, n) p_d^2)`. The chain rule through `T` and the predictor map gives the
    /// result in `theta`.
    fn evaluate_modal(&mut self, th: &[f64], grad_only: bool, md: &Modal) -> Result<Evaluation> {
        let t_in = std::time::Instant::now();
        let (n, m, l, np) = (self.n, self.m, self.l, self.p);
        let pm = self.unpack(th);
        let abar = &pm.a - &pm.k * &pm.c;
        let bbar = &pm.b - &pm.k * &pm.d;
        let (ia, ib, ic, id, ik) = self.column_offsets();
        let blk = self.block;
        let cq = &pm.c * &md.t;
        // dynamic columns: (phi index, state row of the parameter, forcing kind)
        // kind: 0 = x'_j, 1 = u_j, 2 = y_j, 3 = initial state
        let mut dcols: Vec<(usize, usize, u8, usize)> = Vec::new();
        for i in 0..n {
            for j in 0..n {
                dcols.push((ia + i * n + j, i, 0, j));
            }
        }
        for i in 0..n {
            for j in 0..m {
                dcols.push((ib + i * m + j, i, 1, j));
            }
        }
        if let Some(ik) = ik {
            for i in 0..n {
                for j in 0..l {
                    dcols.push((ik + i * l + j, i, 2, j));
                }
            }
        }
        let mut x0_at = Vec::with_capacity(self.x0_off.len());
        for off in &self.x0_off {
            if let Some(o) = off {
                x0_at.push(Some(dcols.len()));
                for i in 0..n {
                    dcols.push((o + i, i, 3, 0));
                }
            } else {
                x0_at.push(None);
            }
        }
        let pd = dcols.len();
        // Carried sensitivities. A 2x2 block `[[a, b], [-b, a]]` commutes with the rotation
        // `R = [[0, -1], [1, 0]]`, and `R e_0 = e_1`: the sensitivity of a parameter in the
        // block's second row is `R` times that of the same parameter (same forcing, same
        // initial condition) in its first row, to the last bit. With `halve` only first rows
        // are carried (`twin`: the second-row column derived from it), so the recursion, the
        // Gram matrix and the cross sums cover `p_e / 2` numbers per complex pair column
        // instead of `p_e`: the Gram costs a quarter.
        let stride = |kind: u8| match kind {
            0 => n,
            1 => m,
            2 => l,
            _ => 1,
        };
        let mut carried: Vec<(usize, Option<usize>)> = Vec::with_capacity(pd);
        for (c, &(ph, i, kind, j)) in dcols.iter().enumerate() {
            let (b0, bs) = md.block[i];
            if self.halve && bs == 2 {
                if i == b0 + 1 {
                    continue;
                }
                let tw = c + stride(kind);
                debug_assert!(
                    dcols[tw].0 == ph + stride(kind)
                        && dcols[tw].1 == i + 1
                        && dcols[tw].2 == kind
                        && dcols[tw].3 == j
                );
                carried.push((c, Some(tw)));
            } else {
                carried.push((c, None));
            }
        }
        // offsets of the carried numbers; `at[c][q]` = (carried index, sign) of entry `q` of
        // the sensitivity block of column `c`
        let mut eoff = vec![0usize; carried.len() + 1];
        let mut at = vec![[(0usize, 0.0f64); 2]; pd];
        for (k, &(c, twin)) in carried.iter().enumerate() {
            let bs = md.block[dcols[c].1].1;
            eoff[k + 1] = eoff[k] + bs;
            for q in 0..bs {
                at[c][q] = (eoff[k] + q, 1.0);
            }
            if let Some(tw) = twin {
                // R s = (-s_1, s_0)
                at[tw] = [(eoff[k] + 1, -1.0), (eoff[k], 1.0)];
            }
        }
        let pe = eoff[carried.len()];
        let cached = if grad_only {
            None
        } else {
            self.gram_cache
                .take()
                .filter(|c| c.0.as_slice() == th && c.1.nrows() == pe)
        };
        // accumulate the sums (else they come from the cache, or are not needed)
        let acc = !grad_only && cached.is_none();
        let nz = n + m;
        let rinv = self.rinv.clone();
        let w = rinv.transpose() * &rinv;
        let wc = &w * &cq;
        let mq = cq.transpose() * &wc;
        let par = if pe >= 64 {
            faer::get_global_parallelism()
        } else {
            Par::Seq
        };
        let hp = if acc { pe } else { 0 };
        let mut gram = Mat::<f64>::zeros(hp, hp);
        let mut cross = Mat::<f64>::zeros(if acc { nz } else { 0 }, hp);
        let mut vbuf = Mat::<f64>::zeros(if acc { blk } else { 0 }, hp);
        let mut zbuf = Mat::<f64>::zeros(if acc { blk } else { 0 }, nz);
        let mut zz = Mat::<f64>::zeros(nz, nz);
        let mut gz = Mat::<f64>::zeros(l, nz);
        let mut gd = vec![0.0; pd];
        let mut sc = vec![0.0; pe];
        let mut sn = vec![0.0; pe];
        let mut cost = 0.0;
        let mut e = vec![0.0; l];
        let mut we = vec![0.0; l];
        let mut wz = vec![0.0; l];
        let mut v = vec![0.0; n];
        let mut z = vec![0.0; nz];
        let mut x = vec![0.0; n];
        let mut xn = vec![0.0; n];
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            x.copy_from_slice(&pm.x0[ex]);
            sc.fill(0.0);
            if let Some(c0) = x0_at[ex] {
                for i in 0..n {
                    let (b0, _) = md.block[i];
                    let (h, sg) = at[c0 + i][i - b0];
                    sc[h] = sg;
                }
            }
            let len = y.nrows();
            let mut row = 0usize;
            for t in 0..len {
                for i in 0..l {
                    let mut a = y[(t, i)];
                    for j in 0..n {
                        a -= pm.c[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        a -= pm.d[(i, j)] * u[(t, j)];
                    }
                    e[i] = a;
                }
                for i in 0..l {
                    let mut a = 0.0;
                    for j in 0..=i {
                        a += rinv[(i, j)] * e[j];
                    }
                    we[i] = a;
                    cost += 0.5 * a * a;
                }
                for i in 0..l {
                    let mut a = 0.0;
                    for j in i..l {
                        a += rinv[(j, i)] * we[j];
                    }
                    wz[i] = a;
                }
                // modal state x' = T^-1 x, regressor z = (x', u)
                for a in 0..n {
                    let mut acc = 0.0;
                    for b in 0..n {
                        acc += md.ti[(a, b)] * x[b];
                    }
                    z[a] = acc;
                }
                for j in 0..m {
                    z[n + j] = u[(t, j)];
                }
                for i in 0..l {
                    for j in 0..nz {
                        gz[(i, j)] += wz[i] * z[j];
                    }
                }
                for k in 0..n {
                    let mut a = 0.0;
                    for i in 0..l {
                        a += cq[(i, k)] * wz[i];
                    }
                    v[k] = a;
                }
                for (k, &(c, twin)) in carried.iter().enumerate() {
                    let (b0, bs) = md.block[dcols[c].1];
                    let o = eoff[k];
                    let mut a = 0.0;
                    for q in 0..bs {
                        a += sc[o + q] * v[b0 + q];
                    }
                    gd[c] -= a;
                    if let Some(tw) = twin {
                        gd[tw] -= sc[o] * v[b0 + 1] - sc[o + 1] * v[b0];
                    }
                }
                if acc {
                    for a in 0..nz {
                        for b in 0..=a {
                            zz[(a, b)] += z[a] * z[b];
                        }
                        zbuf[(row, a)] = z[a];
                    }
                    for q in 0..pe {
                        vbuf[(row, q)] = sc[q];
                    }
                }
                row += 1;
                // S'(t+1) = Lambda S' + F, blockwise
                for (k, &(c, _)) in carried.iter().enumerate() {
                    let (_, i, kind, j) = dcols[c];
                    let (b0, bs) = md.block[i];
                    let o = eoff[k];
                    for q in 0..bs {
                        let mut a = 0.0;
                        for r in 0..bs {
                            a += md.lam[(b0 + q, b0 + r)] * sc[o + r];
                        }
                        sn[o + q] = a;
                    }
                    let f = match kind {
                        0 => z[j],
                        1 => u[(t, j)],
                        2 => y[(t, j)],
                        _ => 0.0,
                    };
                    sn[o + (i - b0)] += f;
                }
                std::mem::swap(&mut sc, &mut sn);
                if !acc {
                    row = 0;
                } else if row == blk || t + 1 == len {
                    let vr = vbuf.as_ref().subrows(0, row);
                    tri::matmul(
                        gram.as_mut(),
                        BlockStructure::TriangularLower,
                        Accum::Add,
                        vr.transpose(),
                        BlockStructure::Rectangular,
                        vr,
                        BlockStructure::Rectangular,
                        1.0,
                        par,
                    );
                    matmul(
                        cross.as_mut(),
                        Accum::Add,
                        zbuf.as_ref().subrows(0, row).transpose(),
                        vr,
                        1.0,
                        par,
                    );
                    row = 0;
                }
                for i in 0..n {
                    let mut a = 0.0;
                    for j in 0..n {
                        a += abar[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        a += bbar[(i, j)] * u[(t, j)];
                    }
                    for j in 0..l {
                        a += pm.k[(i, j)] * y[(t, j)];
                    }
                    xn[i] = a;
                }
                std::mem::swap(&mut x, &mut xn);
            }
        }
        if !cost.is_finite() {
            cost = f64::INFINITY;
        }
        let stat = |i: usize, j: usize| -> Option<usize> {
            if j < n {
                Some(ic + i * n + j)
            } else {
                id.map(|d| d + i * m + (j - n))
            }
        };
        // gradient and Gauss-Newton matrix in phi'
        let mut g = vec![0.0; np];
        for i in 0..l {
            for j in 0..nz {
                if let Some(sij) = stat(i, j) {
                    g[sij] = -gz[(i, j)];
                }
            }
        }
        for (c, d) in dcols.iter().enumerate() {
            g[d.0] = gd[c];
        }
        crate::optim::prof("modal-loop", t_in);
        let t_in = std::time::Instant::now();
        // chain rule theta -> phi -> phi': J_theta = J_phi' M T with M the modal change of
        // basis (Kronecker blocks, applied by n x n products) and T the sparse predictor map
        let tmap = self.predictor_map(&pm);
        let gphi = self.modal_mt(md, &g);
        let gradient: Vec<f64> = tmap
            .iter()
            .map(|col| col.iter().map(|&(r, v)| v * gphi[r]).sum())
            .collect();
        if grad_only {
            return Ok(Evaluation {
                cost,
                gradient,
                gauss_newton: Mat::zeros(0, 0),
            });
        }
        if let Some(c) = cached {
            (gram, cross, zz) = (c.1, c.2, c.3);
        }
        let mut h = Mat::<f64>::zeros(np, np);
        // dynamic block: lower triangle (dcols' phi indices increase with c), column by
        // column so that the Gram matrix is read down its columns; mirrored after
        for c2 in 0..pd {
            let (b2, bs2) = md.block[dcols[c2].1];
            let col2 = dcols[c2].0;
            for c in c2..pd {
                let (b0, bs) = md.block[dcols[c].1];
                let mut acc = 0.0;
                for qa in 0..bs {
                    let (ra, sa) = at[c][qa];
                    for qb in 0..bs2 {
                        let (rb, sb) = at[c2][qb];
                        let gv = if ra >= rb {
                            gram[(ra, rb)]
                        } else {
                            gram[(rb, ra)]
                        };
                        acc += mq[(b0 + qa, b2 + qb)] * (sa * sb * gv);
                    }
                }
                h[(dcols[c].0, col2)] = acc;
            }
        }
        for c2 in 0..pd {
            for c in c2 + 1..pd {
                h[(dcols[c2].0, dcols[c].0)] = h[(dcols[c].0, dcols[c2].0)];
            }
        }
        for i in 0..l {
            for j in 0..nz {
                let Some(sij) = stat(i, j) else { continue };
                for i2 in 0..l {
                    for j2 in 0..nz {
                        let Some(s2j) = stat(i2, j2) else { continue };
                        let zjj = if j >= j2 { zz[(j, j2)] } else { zz[(j2, j)] };
                        h[(sij, s2j)] = w[(i, i2)] * zjj;
                    }
                }
                for (c, d) in dcols.iter().enumerate() {
                    let (b0, bs) = md.block[d.1];
                    let mut acc = 0.0;
                    for qa in 0..bs {
                        let (r, sg) = at[c][qa];
                        acc += wc[(i, b0 + qa)] * (sg * cross[(j, r)]);
                    }
                    h[(sij, d.0)] = acc;
                    h[(d.0, sij)] = acc;
                }
            }
        }
        crate::optim::prof("chain-assemble", t_in);
        let t_mt = std::time::Instant::now();
        // H_phi = M^T H' M = M^T (M^T H')^T (H' symmetric), column by column
        let z = self.modal_mt_cols(md, &h);
        drop(h);
        let hphi = self.modal_mt_cols(md, &z.transpose().to_owned());
        drop(z);
        crate::optim::prof("chain-modal", t_mt);
        let t_tm = std::time::Instant::now();
        // H_theta = T^T H_phi T with the sparse T
        let mut y = Mat::<f64>::zeros(np, np);
        for (c, tc) in tmap.iter().enumerate() {
            let yc = y.col_as_slice_mut(c);
            for &(r, v) in tc {
                for (a, b) in yc.iter_mut().zip(hphi.col_as_slice(r)) {
                    *a += v * b;
                }
            }
        }
        drop(hphi);
        let mut hth = Mat::<f64>::zeros(np, np);
        for c2 in 0..np {
            let yc = y.col_as_slice(c2);
            let hc = hth.col_as_slice_mut(c2);
            for (c1, tc) in tmap.iter().enumerate() {
                hc[c1] = tc.iter().map(|&(r, v)| v * yc[r]).sum();
            }
        }
        drop(y);
        // symmetrise in 64 x 64 tiles
        const TILE: usize = 64;
        for jb in (0..np).step_by(TILE) {
            for ib in (jb..np).step_by(TILE) {
                for j in jb..(jb + TILE).min(np) {
                    for i in ib.max(j + 1)..(ib + TILE).min(np) {
                        let a = 0.5 * (hth[(i, j)] + hth[(j, i)]);
                        hth[(i, j)] = a;
                        hth[(j, i)] = a;
                    }
                }
            }
        }
        crate::optim::prof("chain-predictor", t_tm);
        crate::optim::prof("modal-chain", t_in);
        self.gram_cache = Some((th.to_vec(), gram, cross, zz));
        Ok(Evaluation {
            cost,
            gradient,
            gauss_newton: hth,
        })
    }

    /// `M^T X` for every column of `X` ([`Self::modal_mt`] on contiguous slices: the inner
    /// loops run down columns of `T` and `T^-1`).
    fn modal_mt_cols(&self, md: &Modal, x: &Mat<f64>) -> Mat<f64> {
        let (n, m, l) = (self.n, self.m, self.l);
        let (ia, ib, ic, _, ik) = self.column_offsets();
        let mut out = x.clone();
        // column b of T, column i of T^-1
        let tcol: Vec<Vec<f64>> = (0..n)
            .map(|b| (0..n).map(|j| md.t[(j, b)]).collect())
            .collect();
        let ticol: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..n).map(|a| md.ti[(a, i)]).collect())
            .collect();
        // blocks T^-1 X (rows of the state): (offset, width)
        let mut left = vec![(ib, m)];
        if let Some(k0) = ik {
            left.push((k0, l));
        }
        for o in self.x0_off.iter().flatten() {
            left.push((*o, 1));
        }
        let mut tmp = vec![0.0; n * n];
        for c in 0..x.ncols() {
            let xs = x.col_as_slice(c);
            let os = out.col_as_slice_mut(c);
            // A: out[i, j] = sum_a Ti[a, i] sum_b X[a, b] T[j, b]
            tmp.fill(0.0);
            for a in 0..n {
                let row = &mut tmp[a * n..a * n + n];
                for (b, tb) in tcol.iter().enumerate() {
                    let s = xs[ia + a * n + b];
                    for (r, tv) in row.iter_mut().zip(tb) {
                        *r += s * tv;
                    }
                }
            }
            for (i, ti) in ticol.iter().enumerate() {
                let dst = &mut os[ia + i * n..ia + i * n + n];
                dst.fill(0.0);
                for (a, &s) in ti.iter().enumerate() {
                    for (d, v) in dst.iter_mut().zip(&tmp[a * n..a * n + n]) {
                        *d += s * v;
                    }
                }
            }
            for &(off, wd) in &left {
                for (i, ti) in ticol.iter().enumerate() {
                    let dst = &mut os[off + i * wd..off + i * wd + wd];
                    dst.fill(0.0);
                    for (a, &s) in ti.iter().enumerate() {
                        let src = &xs[off + a * wd..off + a * wd + wd];
                        for (d, v) in dst.iter_mut().zip(src) {
                            *d += s * v;
                        }
                    }
                }
            }
            // C: out[r, j] = sum_b X[r, b] T[j, b]; D unchanged
            for r in 0..l {
                let dst = &mut os[ic + r * n..ic + r * n + n];
                dst.fill(0.0);
                for (b, tb) in tcol.iter().enumerate() {
                    let s = xs[ic + r * n + b];
                    for (d, tv) in dst.iter_mut().zip(tb) {
                        *d += s * tv;
                    }
                }
            }
        }
        out
    }

    /// `M^T x` for the modal change of basis `phi' = M phi` (`phi' = (T^-1 Abar T, T^-1 Bbar,
    /// C T, D, T^-1 K, T^-1 x0)`, row-major blocks), by `n x n` products: `O(n^2 (n + m + l))`.
    fn modal_mt(&self, md: &Modal, x: &[f64]) -> Vec<f64> {
        let (n, m, l) = (self.n, self.m, self.l);
        let (ia, ib, ic, id, ik) = self.column_offsets();
        let mut out = x.to_vec();
        let (t, ti) = (&md.t, &md.ti);
        // A: out[i, j] = sum_ab Ti[a, i] X[a, b] T[j, b]
        let mut tmp = vec![0.0; n * n];
        for a in 0..n {
            for j in 0..n {
                let mut s = 0.0;
                for b in 0..n {
                    s += x[ia + a * n + b] * t[(j, b)];
                }
                tmp[a * n + j] = s;
            }
        }
        for i in 0..n {
            for j in 0..n {
                let mut s = 0.0;
                for a in 0..n {
                    s += ti[(a, i)] * tmp[a * n + j];
                }
                out[ia + i * n + j] = s;
            }
        }
        // blocks T^-1 X (rows of the state): B (n x m), K (n x l), each x0 (n x 1)
        let left = |out: &mut Vec<f64>, off: usize, cols: usize| {
            for i in 0..n {
                for j in 0..cols {
                    let mut s = 0.0;
                    for a in 0..n {
                        s += ti[(a, i)] * x[off + a * cols + j];
                    }
                    out[off + i * cols + j] = s;
                }
            }
        };
        left(&mut out, ib, m);
        if let Some(k0) = ik {
            left(&mut out, k0, l);
        }
        for o in self.x0_off.iter().flatten() {
            left(&mut out, *o, 1);
        }
        // C: out[r, j] = sum_b X[r, b] T[j, b]
        for r in 0..l {
            for j in 0..n {
                let mut s = 0.0;
                for b in 0..n {
                    s += x[ic + r * n + b] * t[(j, b)];
                }
                out[ic + r * n + j] = s;
            }
        }
        let _ = id; // D is unchanged
        out
    }

    /// Tangent vectors (p x n^2) of the similarity orbit at `theta`: `(A X - X A, -X B, C X, 0,
    /// -X K, -X x0)` for `X = E_ab`; `None` when local coordinates are off or inexact (a fixed
    /// non-zero `K` or a given non-zero `x0`).
    pub(super) fn similarity_tangent(&self, th: &[f64]) -> Option<Mat<f64>> {
        if !self.local {
            return None;
        }
        self.orbit_tangent(th)
    }

    /// The tangent of [`Self::similarity_tangent`] whether or not the search uses local
    /// coordinates.
    fn orbit_tangent(&self, th: &[f64]) -> Option<Mat<f64>> {
        if self.n == 0 {
            return None;
        }

        let pm = self.unpack(th);
        let (n, m, l) = (self.n, self.m, self.l);
        let k_ok = self.est_k || (0..n).all(|i| (0..l).all(|j| pm.k[(i, j)] == 0.0));
        let x0_ok = self
            .x0_mode
            .iter()
            .all(|s| !matches!(s, InitialState::Given(v) if v.iter().any(|&x| x != 0.0)));
        if !k_ok || !x0_ok {
            return None;
        }
        let (ia, ib, ic, _id, ik) = self.column_offsets();
        let mut tan = Mat::<f64>::zeros(self.p, n * n);
        for a in 0..n {
            for b in 0..n {
                let col = a * n + b;
                // δA = A E_ab - E_ab A
                for i in 0..n {
                    tan[(ia + i * n + b, col)] += pm.a[(i, a)];
                }
                for j in 0..n {
                    tan[(ia + a * n + j, col)] -= pm.a[(b, j)];
                }
                for j in 0..m {
                    tan[(ib + a * m + j, col)] -= pm.b[(b, j)];
                }
                for i in 0..l {
                    tan[(ic + i * n + b, col)] += pm.c[(i, a)];
                }
                if let Some(ik) = ik {
                    for j in 0..l {
                        tan[(ik + a * l + j, col)] -= pm.k[(b, j)];
                    }
                }
                for (ex, off) in self.x0_off.iter().enumerate() {
                    if let Some(o) = off {
                        tan[(o + a, col)] -= pm.x0[ex][b];
                    }
                }
            }
        }
        Some(tan)
    }

    fn modal_at(&self, th: &[f64]) -> Option<Modal> {
        let pm = self.unpack(th);
        let abar = &pm.a - &pm.k * &pm.c;
        modal_form(abar.as_ref())
    }

    fn predictor_map(&self, pm: &Unpacked) -> SparseCols {
        let (n, m, l) = (self.n, self.m, self.l);
        let (ia, ib, ic, id, ik) = self.column_offsets();
        let mut t: SparseCols = (0..self.p).map(|c| vec![(c, 1.0)]).collect();
        for r in 0..l {
            for i in 0..n {
                let kir = pm.k[(i, r)];
                if kir == 0.0 {
                    continue;
                }
                for j in 0..n {
                    t[ic + r * n + j].push((ia + i * n + j, -kir));
                }
                if let Some(id) = id {
                    for j in 0..m {
                        t[id + r * m + j].push((ib + i * m + j, -kir));
                    }
                }
            }
        }
        if let Some(ik) = ik {
            for i in 0..n {
                for r in 0..l {
                    let col = &mut t[ik + i * l + r];
                    for j in 0..n {
                        if pm.c[(r, j)] != 0.0 {
                            col.push((ia + i * n + j, -pm.c[(r, j)]));
                        }
                    }
                    for j in 0..m {
                        if pm.d[(r, j)] != 0.0 {
                            col.push((ib + i * m + j, -pm.d[(r, j)]));
                        }
                    }
                }
            }
        }
        t
    }

    /// Cost, `J^T W r` and `J^T W J` through the predictor parameterisation
    /// `phi = (Abar, Bbar, C, D, K, x0)` with `Abar = A - K C`, `Bbar = B - K D`.
    ///
    /// In `phi` the predictor's state depends on `Abar, Bbar, K, x0` only, so the columns of
    /// `C` and `D` have no state sensitivity: their Jacobian rows are `e_i (x) z(t)^T` with
    /// `z = (x, u)`, and their blocks of `J^T W J` are `W (x) sum z z^T` (static-static) and
    /// `sum_k (W C)_ik sum_t z_j(t) S_k(t)` (static-dynamic), `O(N n (n + m) p_d)` instead of
    /// `O(N l p^2)`. The dynamic block `sum S^T C^T W C S` is formed from `min(l, n)` rows per
    /// sample (`R^-1 C`, or the Cholesky factor of `C^T W C` when `l > n`). The result is
    /// mapped back to `theta` by the chain rule, `J_theta = J_phi T` ([`Self::predictor_map`]),
    /// so it equals the plain evaluation up to round-off. With `grad_only` the Gauss-Newton
    /// matrix is skipped (left empty): the sensitivities and the gradient cost `O(N n^2 p_d)`.
    fn evaluate_structured(&self, th: &[f64], grad_only: bool) -> Result<Evaluation> {
        let (n, m, l, np) = (self.n, self.m, self.l, self.p);
        let pm = self.unpack(th);
        let abar = &pm.a - &pm.k * &pm.c;
        let bbar = &pm.b - &pm.k * &pm.d;
        let (ia, ib, ic, id, ik) = self.column_offsets();
        let blk = self.block;
        // dynamic parameters (state sensitivity): Abar, Bbar, K, then each estimated x0
        let mut dcols: Vec<usize> = (ia..ia + n * n).chain(ib..ib + n * m).collect();
        let k_at = dcols.len();
        if let Some(ik) = ik {
            dcols.extend(ik..ik + n * l);
        }
        let mut x0_at = Vec::with_capacity(self.x0_off.len());
        for off in &self.x0_off {
            if let Some(o) = off {
                x0_at.push(Some(dcols.len()));
                dcols.extend(*o..*o + n);
            } else {
                x0_at.push(None);
            }
        }
        let pd = dcols.len();
        let nz = n + m;
        let rinv = self.rinv.clone();
        let w = rinv.transpose() * &rinv;
        let q = &rinv * &pm.c;
        let wc = &w * &pm.c;
        // rows whose Gram matrix is C^T W C
        let lt: Mat<f64> = if l > n {
            let g = q.transpose() * &q;
            match g.llt(Side::Lower) {
                Ok(f) => f.L().transpose().to_owned(),
                Err(_) => q.clone(),
            }
        } else {
            q.clone()
        };
        let r = lt.nrows();
        let par = if pd >= 64 {
            faer::get_global_parallelism()
        } else {
            Par::Seq
        };
        let hp = if grad_only { 0 } else { pd };
        let mut hd = Mat::<f64>::zeros(hp, hp);
        let mut gd = vec![0.0; pd];
        // rows k * nz + j: sum_t z_j(t) S_k(t)
        let mut cross = Mat::<f64>::zeros(if grad_only { 0 } else { n * nz }, hp);
        let mut zz = Mat::<f64>::zeros(nz, nz);
        // sum_t (W e)(t) z(t)^T
        let mut gz = Mat::<f64>::zeros(l, nz);
        let mut jb = Mat::<f64>::zeros(if grad_only { 0 } else { blk * r }, hp);
        let mut sbuf = Mat::<f64>::zeros(if grad_only { 0 } else { n * blk }, hp);
        let mut zbuf = Mat::<f64>::zeros(if grad_only { 0 } else { blk }, nz);
        let mut s = Mat::<f64>::zeros(n, pd);
        let mut s2 = s.clone();
        let mut cost = 0.0;
        let mut e = vec![0.0; l];
        let mut we = vec![0.0; l];
        let mut wz = vec![0.0; l];
        let mut v = vec![0.0; n];
        let mut z = vec![0.0; nz];
        let mut x = vec![0.0; n];
        let mut xn = vec![0.0; n];
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            x.copy_from_slice(&pm.x0[ex]);
            s.fill(0.0);
            if let Some(c0) = x0_at[ex] {
                for i in 0..n {
                    s[(i, c0 + i)] = 1.0;
                }
            }
            let len = y.nrows();
            let mut row = 0usize;
            for t in 0..len {
                for i in 0..l {
                    let mut a = y[(t, i)];
                    for j in 0..n {
                        a -= pm.c[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        a -= pm.d[(i, j)] * u[(t, j)];
                    }
                    e[i] = a;
                }
                for i in 0..l {
                    let mut a = 0.0;
                    for j in 0..=i {
                        a += rinv[(i, j)] * e[j];
                    }
                    we[i] = a;
                    cost += 0.5 * a * a;
                }
                // W e = R^-T R^-1 e
                for i in 0..l {
                    let mut a = 0.0;
                    for j in i..l {
                        a += rinv[(j, i)] * we[j];
                    }
                    wz[i] = a;
                }
                z[..n].copy_from_slice(&x);
                for j in 0..m {
                    z[n + j] = u[(t, j)];
                }
                for i in 0..l {
                    for j in 0..nz {
                        gz[(i, j)] += wz[i] * z[j];
                    }
                }
                if !grad_only {
                    for a in 0..nz {
                        for b in 0..=a {
                            zz[(a, b)] += z[a] * z[b];
                        }
                        zbuf[(row, a)] = z[a];
                    }
                }
                // dynamic gradient: -S^T C^T W e
                for k in 0..n {
                    let mut a = 0.0;
                    for i in 0..l {
                        a += pm.c[(i, k)] * wz[i];
                    }
                    v[k] = a;
                }
                for c in 0..pd {
                    let mut a = 0.0;
                    for k in 0..n {
                        a += s[(k, c)] * v[k];
                    }
                    gd[c] -= a;
                }
                if !grad_only {
                    for c in 0..pd {
                        for k in 0..n {
                            sbuf[(k * blk + row, c)] = s[(k, c)];
                        }
                    }
                    matmul(
                        jb.as_mut().subrows_mut(row * r, r),
                        Accum::Replace,
                        lt.as_ref(),
                        s.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                }
                row += 1;
                // S(t+1) = Abar S + F, F: e_i x_j (Abar), e_i u_j (Bbar), e_i y_j (K)
                matmul(
                    s2.as_mut(),
                    Accum::Replace,
                    abar.as_ref(),
                    s.as_ref(),
                    1.0,
                    Par::Seq,
                );
                for i in 0..n {
                    for j in 0..n {
                        s2[(i, i * n + j)] += x[j];
                    }
                    for j in 0..m {
                        s2[(i, n * n + i * m + j)] += u[(t, j)];
                    }
                    if ik.is_some() {
                        for j in 0..l {
                            s2[(i, k_at + i * l + j)] += y[(t, j)];
                        }
                    }
                }
                std::mem::swap(&mut s, &mut s2);
                if grad_only {
                    row = 0;
                } else if row == blk || t + 1 == len {
                    let jr = jb.as_ref().subrows(0, row * r);
                    tri::matmul(
                        hd.as_mut(),
                        BlockStructure::TriangularLower,
                        Accum::Add,
                        jr.transpose(),
                        BlockStructure::Rectangular,
                        jr,
                        BlockStructure::Rectangular,
                        1.0,
                        par,
                    );
                    let zr = zbuf.as_ref().subrows(0, row);
                    for k in 0..n {
                        matmul(
                            cross.as_mut().subrows_mut(k * nz, nz),
                            Accum::Add,
                            zr.transpose(),
                            sbuf.as_ref().subrows(k * blk, row),
                            1.0,
                            par,
                        );
                    }
                    row = 0;
                }
                for i in 0..n {
                    let mut a = 0.0;
                    for j in 0..n {
                        a += abar[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        a += bbar[(i, j)] * u[(t, j)];
                    }
                    for j in 0..l {
                        a += pm.k[(i, j)] * y[(t, j)];
                    }
                    xn[i] = a;
                }
                std::mem::swap(&mut x, &mut xn);
            }
        }
        if !cost.is_finite() {
            cost = f64::INFINITY;
        }
        // assemble J^T W J and J^T W r in phi
        let stat = |i: usize, j: usize| -> Option<usize> {
            if j < n {
                Some(ic + i * n + j)
            } else {
                id.map(|d| d + i * m + (j - n))
            }
        };
        let mut g = vec![0.0; np];
        for i in 0..l {
            for j in 0..nz {
                if let Some(sij) = stat(i, j) {
                    g[sij] = -gz[(i, j)];
                }
            }
        }
        let tmap = self.predictor_map(&pm);
        if grad_only {
            for a in 0..pd {
                g[dcols[a]] = gd[a];
            }
            return Ok(Evaluation {
                cost,
                gradient: tmap
                    .iter()
                    .map(|col| col.iter().map(|&(rw, val)| val * g[rw]).sum())
                    .collect(),
                gauss_newton: Mat::zeros(0, 0),
            });
        }
        let mut h = Mat::<f64>::zeros(np, np);
        for a in 0..pd {
            g[dcols[a]] = gd[a];
            for b in 0..=a {
                h[(dcols[a], dcols[b])] = hd[(a, b)];
                h[(dcols[b], dcols[a])] = hd[(a, b)];
            }
        }
        for i in 0..l {
            for j in 0..nz {
                let Some(sij) = stat(i, j) else { continue };
                for i2 in 0..l {
                    for j2 in 0..nz {
                        let Some(s2j) = stat(i2, j2) else { continue };
                        let zjj = if j >= j2 { zz[(j, j2)] } else { zz[(j2, j)] };
                        h[(sij, s2j)] = w[(i, i2)] * zjj;
                    }
                }
                for a in 0..pd {
                    let mut acc = 0.0;
                    for k in 0..n {
                        acc += wc[(i, k)] * cross[(k * nz + j, a)];
                    }
                    h[(sij, dcols[a])] = acc;
                    h[(dcols[a], sij)] = acc;
                }
            }
        }
        // back to theta: H = T^T H_phi T, g = T^T g_phi
        let mut ht = Mat::<f64>::zeros(np, np);
        for (c, col) in tmap.iter().enumerate() {
            for &(rw, val) in col {
                for i in 0..np {
                    ht[(i, c)] += val * h[(i, rw)];
                }
            }
        }
        let mut hth = Mat::<f64>::zeros(np, np);
        for cp in 0..np {
            for (c, col) in tmap.iter().enumerate() {
                let mut acc = 0.0;
                for &(rw, val) in col {
                    acc += val * ht[(rw, cp)];
                }
                hth[(c, cp)] = acc;
            }
        }
        for i in 0..np {
            for j in 0..i {
                let a = 0.5 * (hth[(i, j)] + hth[(j, i)]);
                hth[(i, j)] = a;
                hth[(j, i)] = a;
            }
        }
        let gradient = tmap
            .iter()
            .map(|col| col.iter().map(|&(rw, val)| val * g[rw]).sum())
            .collect();
        Ok(Evaluation {
            cost,
            gradient,
            gauss_newton: hth,
        })
    }
}

impl Problem for Predictor<'_> {
    fn n_params(&self) -> usize {
        self.p
    }

    fn evaluate(&mut self, th: &[f64], jacobian: bool) -> Result<Evaluation> {
        if jacobian && self.structured && self.col_lo == 0 && self.n > 0 {
            if self.modal {
                if let Some(md) = self.modal_at(th) {
                    crate::optim::prof("modal-yes", std::time::Instant::now());
                    return self.evaluate_modal(th, false, &md);
                }
            }
            crate::optim::prof("modal-no", std::time::Instant::now());
            return self.evaluate_structured(th, false);
        }
        let (n, m, l, np) = (self.n, self.m, self.l, self.p);
        let pm = self.unpack(th);
        let abar = &pm.a - &pm.k * &pm.c;
        let bbar = &pm.b - &pm.k * &pm.d;
        let (ia, ib, ic, id, ik) = self.column_offsets();
        let k_zero = (0..n).all(|i| (0..l).all(|j| pm.k[(i, j)] == 0.0));
        let blk = self.block;
        let mut cost = 0.0;
        let mut h = Mat::<f64>::zeros(if jacobian { np } else { 0 }, if jacobian { np } else { 0 });
        let mut g = Mat::<f64>::zeros(if jacobian { np } else { 0 }, 1);
        let lo = self.col_lo.min(np);
        let nc = np - lo;
        let mut jb = Mat::<f64>::zeros(if jacobian { blk * l } else { 0 }, nc);
        let mut rb = Mat::<f64>::zeros(if jacobian { blk * l } else { 0 }, 1);
        // sensitivities of the parameters lo..np only (column c <-> parameter lo + c)
        let mut s = Mat::<f64>::zeros(n, if jacobian { nc } else { 0 });
        let mut s2 = s.clone();
        let mut cs = Mat::<f64>::zeros(l, if jacobian { nc } else { 0 });
        let full = lo == 0;
        // the one product whose cost grows with p^2: faer's global parallelism, as the
        // compressors (results agree to round-off for any thread count)
        let par = if nc >= 64 {
            faer::get_global_parallelism()
        } else {
            Par::Seq
        };
        let mut e = vec![0.0; l];
        let mut we = vec![0.0; l];
        let mut x = vec![0.0; n];
        let mut xn = vec![0.0; n];
        let rinv = self.rinv.clone();
        for (ex, (u, y)) in self.exps.iter().enumerate() {
            x.copy_from_slice(&pm.x0[ex]);
            if jacobian {
                s.fill(0.0);
                if let Some(o) = self.x0_off[ex] {
                    if o >= lo {
                        for i in 0..n {
                            s[(i, o - lo + i)] = 1.0;
                        }
                    }
                }
            }
            let len = y.nrows();
            let mut row = 0usize;
            for t in 0..len {
                for i in 0..l {
                    let mut v = y[(t, i)];
                    for j in 0..n {
                        v -= pm.c[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        v -= pm.d[(i, j)] * u[(t, j)];
                    }
                    e[i] = v;
                }
                for i in 0..l {
                    let mut v = 0.0;
                    for j in 0..=i {
                        v += rinv[(i, j)] * e[j];
                    }
                    we[i] = v;
                    cost += 0.5 * v * v;
                }
                if jacobian {
                    // dŷ/dθ = C S + G
                    matmul(
                        cs.as_mut(),
                        Accum::Replace,
                        pm.c.as_ref(),
                        s.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                    for i in 0..l {
                        if !full {
                            break;
                        }
                        for j in 0..n {
                            cs[(i, ic + i * n + j)] += x[j];
                        }
                        if let Some(id) = id {
                            for j in 0..m {
                                cs[(i, id + i * m + j)] += u[(t, j)];
                            }
                        }
                    }
                    // weighted Jacobian rows: -R^-1 dŷ
                    matmul(
                        jb.as_mut().subrows_mut(row * l, l),
                        Accum::Replace,
                        rinv.as_ref(),
                        cs.as_ref(),
                        -1.0,
                        Par::Seq,
                    );
                    for i in 0..l {
                        rb[(row * l + i, 0)] = we[i];
                    }
                    row += 1;
                    // S(t+1) = Abar S + F
                    matmul(
                        s2.as_mut(),
                        Accum::Replace,
                        abar.as_ref(),
                        s.as_ref(),
                        1.0,
                        Par::Seq,
                    );
                    for i in 0..n {
                        if !full {
                            break;
                        }
                        for j in 0..n {
                            s2[(i, ia + i * n + j)] += x[j];
                        }
                        for j in 0..m {
                            s2[(i, ib + i * m + j)] += u[(t, j)];
                        }
                    }
                    if !k_zero && full {
                        for i in 0..l {
                            for j in 0..n {
                                let col = ic + i * n + j;
                                for r in 0..n {
                                    s2[(r, col)] -= pm.k[(r, i)] * x[j];
                                }
                            }
                            if let Some(id) = id {
                                for j in 0..m {
                                    let col = id + i * m + j;
                                    for r in 0..n {
                                        s2[(r, col)] -= pm.k[(r, i)] * u[(t, j)];
                                    }
                                }
                            }
                        }
                    }
                    if let (Some(ik), true) = (ik, full) {
                        for i in 0..n {
                            for j in 0..l {
                                s2[(i, ik + i * l + j)] += e[j];
                            }
                        }
                    }
                    std::mem::swap(&mut s, &mut s2);
                    if row == blk || t + 1 == len {
                        let rows = row * l;
                        let jr = jb.as_ref().subrows(0, rows);
                        // lower triangle of J^T J only (mirrored at the end)
                        tri::matmul(
                            h.as_mut().submatrix_mut(lo, lo, nc, nc),
                            BlockStructure::TriangularLower,
                            Accum::Add,
                            jr.transpose(),
                            BlockStructure::Rectangular,
                            jr,
                            BlockStructure::Rectangular,
                            1.0,
                            par,
                        );
                        matmul(
                            g.as_mut().subrows_mut(lo, nc),
                            Accum::Add,
                            jr.transpose(),
                            rb.as_ref().subrows(0, rows),
                            1.0,
                            Par::Seq,
                        );
                        row = 0;
                    }
                }
                for i in 0..n {
                    let mut v = 0.0;
                    for j in 0..n {
                        v += abar[(i, j)] * x[j];
                    }
                    for j in 0..m {
                        v += bbar[(i, j)] * u[(t, j)];
                    }
                    for j in 0..l {
                        v += pm.k[(i, j)] * y[(t, j)];
                    }
                    xn[i] = v;
                }
                std::mem::swap(&mut x, &mut xn);
            }
        }
        if !cost.is_finite() {
            cost = f64::INFINITY;
        }
        for i in 0..h.nrows() {
            for j in 0..i {
                h[(j, i)] = h[(i, j)];
            }
        }
        Ok(Evaluation {
            cost,
            gradient: (0..g.nrows()).map(|i| g[(i, 0)]).collect(),
            gauss_newton: h,
        })
    }

    fn admissible(&mut self, th: &[f64]) -> bool {
        let pm = self.unpack(th);
        let mat = match self.focus {
            Focus::Simulation => pm.a,
            Focus::Prediction => &pm.a - &pm.k * &pm.c,
        };
        matches!(spectral_radius(mat.as_ref()), Ok(r) if r < 1.0)
    }

    fn search_basis(&mut self, th: &[f64]) -> Result<Option<Mat<f64>>> {
        let Some(tan) = self.similarity_tangent(th) else {
            return Ok(None);
        };
        let svd = tan
            .svd()
            .map_err(|e| SysidError::numerical("local coordinates (SVD)", format!("{e:?}")))?;
        let sv = svd.S().column_vector();
        let smax = if sv.nrows() > 0 { sv[0] } else { 0.0 };
        let rank = (0..sv.nrows())
            .filter(|&i| sv[i] > 1e-10 * smax && sv[i] > 0.0)
            .count();
        let u = svd.U();
        Ok(Some(u.subcols(rank, self.p - rank).to_owned()))
    }

    fn invariant_directions(&mut self, th: &[f64]) -> Result<Option<Mat<f64>>> {
        Ok(self.orbit_tangent(th))
    }

    fn gradient_only(&mut self, th: &[f64]) -> Result<Option<Evaluation>> {
        if self.structured && self.col_lo == 0 && self.n > 0 {
            if self.modal {
                if let Some(md) = self.modal_at(th) {
                    return self.evaluate_modal(th, true, &md).map(Some);
                }
            }
            return self.evaluate_structured(th, true).map(Some);
        }
        Ok(None)
    }

    /// With the re-estimated weighting: `det(Lambda)` at the last accepted point (the
    /// weighted cost is `N l / 2` at every iterate; each accepted step lowers the determinant,
    /// since `tr(W_old Lambda_new) < l` and `det(W_old Lambda_new) <= (tr / l)^l`).
    fn criterion(&self) -> Option<f64> {
        if self.reweight {
            self.losses.last().copied()
        } else {
            None
        }
    }

    fn accepted(&mut self, th: &[f64]) -> Result<bool> {
        if self.reweight {
            self.reweight_at(th)?;
            return Ok(true);
        }
        let lam = self.innovation_covariance(th);
        self.losses.push(determinant(&lam));
        Ok(false)
    }
}

/// Refines a start model by minimising its prediction (or simulation) errors over one or more
/// experiments `(u, y)`, each `(N_e, m)` and `(N_e, l)`.
///
/// The start must give a stable predictor (A - K C, or A for simulation); `k0` is its Kalman
/// gain (zero when `None`). The observer sees every accepted iteration and may stop the search.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::{StateSpace, simulate::simulate};
/// use sysid_core::pem::{pem, PemOptions, Focus};
/// use sysid_core::optim::Flow;
/// let truth = StateSpace::new(mat![[0.8]], mat![[1.0]], mat![[0.5]], mat![[0.0]]).unwrap();
/// let u = Mat::from_fn(200, 1, |t, _| ((t * 7919 % 13) as f64) - 6.0);
/// let y = simulate(&truth, u.as_ref(), None).unwrap();
/// let start = StateSpace::new(mat![[0.6]], mat![[1.0]], mat![[0.4]], mat![[0.0]]).unwrap();
/// let mut o = PemOptions::default();
/// o.focus = Focus::Simulation;
/// let r = pem(&start, None, &[(u.as_ref(), y.as_ref())], &o, &mut |_| Flow::Continue).unwrap();
/// assert!((r.sys.a[(0, 0)] - 0.8).abs() < 1e-8);
/// ```
pub fn pem(
    start: &StateSpace,
    k0: Option<MatRef<'_, f64>>,
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    options: &PemOptions,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<PemResult> {
    let mut prob = Predictor::new(start, k0, experiments, options)?;
    let n = prob.n;
    let kmat = prob.k_fixed.clone();
    let k_start = match (options.focus, k0) {
        (Focus::Prediction, Some(k)) => k.to_owned(),
        _ => kmat,
    };
    let x0s: Vec<Vec<f64>> = prob
        .x0_mode
        .iter()
        .map(|s| match s {
            InitialState::Given(v) => v.clone(),
            _ => vec![0.0; n],
        })
        .collect();
    let mut theta = prob.pack(start, k_start.as_ref(), &x0s);
    if !prob.admissible(&theta) {
        return Err(SysidError::invalid(
            "start model",
            match options.focus {
                Focus::Simulation => "A of the start model is unstable: stabilise it first \
                     (for example reflect the unstable poles) or use focus=\"prediction\""
                    .to_string(),
                Focus::Prediction => "the predictor A - K C of the start model is unstable: \
                     stabilise it first or start from a Kalman gain of the model"
                    .to_string(),
            },
        ));
    }
    prob.rinv = Mat::identity(prob.l, prob.l);
    // Estimated initial states: least squares with everything else fixed (linear: one step).
    if prob.x0_off.iter().any(|o| o.is_some()) {
        let mut o = optim::Options {
            max_iter: 1,
            initial_damping: 0.0,
            tol_gradient: 0.0,
            ..Default::default()
        };
        let mut fixed = vec![true; prob.p];
        for off in prob.x0_off.iter().flatten() {
            for i in 0..n {
                fixed[off + i] = false;
            }
        }
        o.fixed = Some(fixed);
        let local = prob.local;
        prob.local = false;
        prob.col_lo = prob.x0_off.iter().flatten().copied().min().unwrap_or(0);
        let sol = optim::minimize(&mut prob, &theta, &o, &mut |_| Flow::Continue)?;
        prob.local = local;
        prob.col_lo = 0;
        theta = sol.theta;
    }
    prob.losses.clear();
    if prob.reweight {
        prob.reweight_at(&theta)?;
    } else {
        let lam = prob.innovation_covariance(&theta);
        prob.losses.push(determinant(&lam));
    }
    let t0 = std::time::Instant::now();
    let solution = optim::minimize(&mut prob, &theta, &options.optim, observer)?;
    crate::optim::prof("minimize", t0);
    let t_end = std::time::Instant::now();
    let theta = solution.theta.clone();
    let pm = prob.unpack(&theta);
    let lam = prob.innovation_covariance(&theta);
    // Covariance with W = Lambda^-1 (the maximum-likelihood weighting) at the solution.
    let loss_history = prob.losses.clone();
    let h = if prob.reweight {
        solution.gauss_newton.clone()
    } else {
        prob.reweight = true;
        prob.reweight_at(&theta)?;
        prob.evaluate(&theta, true)?.gauss_newton
    };
    crate::optim::prof("final-h", t_end);
    let t0 = std::time::Instant::now();
    let covariance = optim::covariance(h.as_ref(), 1.0, 1e-10)?;
    crate::optim::prof("covariance", t0);
    let mut solution = solution;
    if solution.condition.is_nan() {
        // a large search does not form the eigenvalues; those of the covariance say the same
        solution.condition = covariance.condition;
    }
    Ok(PemResult {
        sys: StateSpace::new(pm.a, pm.b, pm.c, pm.d)?,
        k: pm.k,
        x0: pm.x0,
        innovation_covariance: lam,
        theta,
        solution,
        covariance,
        n_samples: prob.n_samples,
        loss_history,
    })
}
