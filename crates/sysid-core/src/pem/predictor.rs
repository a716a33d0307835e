//! The innovation predictor over several experiments: its parameter layout and the one
//! recursion every evaluation runs,
//!
//! ```text
//! e(t) = y(t) - C x(t) - D u(t),    x(t+1) = (A - K C) x(t) + (B - K D) u(t) + K y(t),
//! ```
//!
//! with the weighted errors `R^-1 e` (`R R^T = Lambda`) whose half squared norm is the cost.

use super::options::{
    bounded_radius, stable_within, Focus, InitialState, PemOptions, MARGINAL_RADIUS,
};
use crate::error::{check_finite, check_io, Result, SysidError};
use crate::linalg::determinant;
use crate::model::StateSpace;
use faer::{Mat, MatRef, Par, Side};

/// `(theta, Gram of the modal sensitivities, cross sums with the regressor, sum z z^T)`.
pub(super) type GramCache = (Vec<f64>, Mat<f64>, Mat<f64>, Mat<f64>);

/// The innovation predictor over several experiments, as an optimisation problem.
///
/// Parameter layout (row-major blocks): `A (n*n), B (n*m), C (l*n)`, then `D (l*m)` when
/// estimated, `K (n*l)` when estimated, then `x0` (n) of every experiment whose initial state
/// is estimated, in experiment order.
pub struct Predictor<'a> {
    pub(super) exps: Vec<(MatRef<'a, f64>, MatRef<'a, f64>)>,
    pub(super) n: usize,
    pub(super) m: usize,
    pub(super) l: usize,
    pub(super) est_d: bool,
    pub(super) est_k: bool,
    pub(super) enforce_stability: bool,
    /// The largest spectral radius admitted (1, or [`MARGINAL_RADIUS`] after
    /// [`Self::set_marginal`]).
    pub(super) radius_limit: f64,
    pub(super) d_fixed: Mat<f64>,
    pub(super) k_fixed: Mat<f64>,
    pub(super) x0_mode: Vec<InitialState>,
    pub(super) x0_off: Vec<Option<usize>>,
    pub(super) p: usize,
    /// `R^-1` with `R R^T = Lambda` (weighted residual `R^-1 e`).
    pub(super) rinv: Mat<f64>,
    floor: Vec<f64>,
    pub(super) reweight: bool,
    pub(super) local: bool,
    pub(super) block: usize,
    pub(super) n_samples: usize,
    pub(super) losses: Vec<f64>,
    /// Sensitivities are formed only for parameters `>= col_lo` (the others get zero rows and
    /// columns in the Gauss-Newton matrix): the initial-state-only pre-step sets it.
    pub(super) col_lo: usize,
    /// Form `J^T W J` through the predictor parameterisation (see `evaluate_structured`);
    /// `false` forms every Jacobian row (the reference path, kept for tests).
    pub(super) structured: bool,
    /// Within the structured path, use the modal coordinates of `A - K C` when well
    /// conditioned (`evaluate_modal`).
    pub(super) modal: bool,
    /// Within the modal path, carry only the first row of each complex pair's sensitivities
    /// (the second is its rotation); `false` carries both (the reference, kept for tests).
    pub(super) halve: bool,
    /// The weighting-independent sums of the last modal `J^T W J`: a re-weighted
    /// Gauss-Newton matrix at the same point (the covariance after an unweighted search)
    /// costs a gradient pass instead of a full one.
    pub(super) gram_cache: Option<GramCache>,
    /// Trial points refused only because `A` was unstable (the stability bound was active).
    pub(super) a_bound_hits: usize,
    /// The modal chart (see [`super::chart`]): the entries of `A` outside its blocks are
    /// held at zero and their sensitivities never formed; `None`: every entry moves.
    pub(super) chart: Option<super::chart::Chart>,
    /// `(theta, Lambda)` of the last trial's cost pass ([`Self::cost_keeping_covariance`]).
    pub(super) last_covariance: Option<(Vec<f64>, Mat<f64>)>,
    /// `(c, x)`: a gradient pass (`evaluate_structured`, `evaluate_modal` with `grad_only`)
    /// forms `J^T W (c e + x)` instead of `J^T W e`, `x` the substituted residuals of every
    /// sample in experiment order (`l` per sample); see `pem::geodesic`.
    pub(super) substitute: Option<(f64, Vec<f64>)>,
}

/// The model matrices at one parameter vector, with the predictor's `A - K C`, `B - K D`.
pub(super) struct Unpacked {
    pub a: Mat<f64>,
    pub b: Mat<f64>,
    pub c: Mat<f64>,
    pub d: Mat<f64>,
    pub k: Mat<f64>,
    pub x0: Vec<Vec<f64>>,
    pub abar: Mat<f64>,
    pub bbar: Mat<f64>,
}

/// Column offsets of the parameter blocks: `A, B, C` always, `D` and `K` when estimated.
#[derive(Clone, Copy)]
pub(super) struct Offsets {
    pub a: usize,
    pub b: usize,
    pub c: usize,
    pub d: Option<usize>,
    pub k: Option<usize>,
}

/// The predictor run sample by sample at one parameter vector: every evaluation path drives
/// this loop body (errors, weighting, state update) and adds its own sums.
pub(super) struct Filter {
    pub pm: Unpacked,
    pub rinv: Mat<f64>,
    /// The predictor's state, and the next one.
    pub x: Vec<f64>,
    xn: Vec<f64>,
    /// `e`, `R^-1 e` and `W e = R^-T R^-1 e` at the current sample.
    pub e: Vec<f64>,
    pub we: Vec<f64>,
    pub wz: Vec<f64>,
    /// `1/2 sum |R^-1 e|^2` so far.
    pub cost: f64,
    /// Row-major copies of `[C D]` (`l x (n + m)`), `[Abar Bbar K]` (`n x (n + m + l)`) and
    /// `R^-1` (`l x l`), and the current sample's `(x, u, y)`: the per-sample loops read
    /// contiguous memory without index checks.
    pub(super) cd: Vec<f64>,
    /// `[C D]` column-major.
    cd_cols: Vec<f64>,
    pub(super) abk: RowProduct,
    pub(super) rinv_rows: Vec<f64>,
    xuy: Vec<f64>,
    /// The sample whose `(x, u, y)` `xuy` holds (`x` moves only in [`Self::advance`] and
    /// [`Self::restart`]).
    loaded: Option<usize>,
}

/// `a` (`r x c`) beside `b` (`r x c2`) beside `k` (`r x c3`), row-major.
pub(super) fn rows_of(blocks: &[&Mat<f64>]) -> Vec<f64> {
    let r = blocks.first().map_or(0, |b| b.nrows());
    let mut out = Vec::with_capacity(r * blocks.iter().map(|b| b.ncols()).sum::<usize>());
    for i in 0..r {
        for b in blocks {
            out.extend((0..b.ncols()).map(|j| b[(i, j)]));
        }
    }
    out
}

/// A row-major matrix kept for products with vectors, `out = M x`: dense, or, when at most
/// half of its entries are non-zero (the modal chart's block-diagonal `A`: 2-3 entries of
/// each row of `[A B]`), only the non-zero entries of each row, in column order, every row
/// padded to the same width with zero entries (a fixed trip count). Every sum adds the same
/// non-zero terms in the same order as the dense loop; the skipped and padded terms are zero
/// times a finite number, which change no sum (a non-finite state makes the cost non-finite
/// either way).
pub(super) enum RowProduct {
    /// `cols` and the row-major entries.
    Dense(usize, Vec<f64>),
    /// At most [`COLUMN_ROWS`] rows, dense: `cols` and the column-major entries. The product
    /// runs column by column into an array of the rows' sums (registers, not memory): every
    /// row's sum still adds its columns in order, as [`Self::Dense`] does.
    Columns(usize, Vec<f64>),
    /// `width` and per row `width` pairs `(column, entry)`.
    Sparse(usize, Vec<(usize, f64)>),
}

impl RowProduct {
    /// From the row-major entries of a matrix with `cols` columns.
    pub fn new(rows: &[f64], cols: usize) -> Self {
        let nnz = rows.iter().filter(|v| **v != 0.0).count();
        if cols == 0 || 2 * nnz > rows.len() {
            let r = rows.len() / cols.max(1);
            if (1..=COLUMN_ROWS).contains(&r) {
                return RowProduct::Columns(cols, column_major(rows, r, cols));
            }
            return RowProduct::Dense(cols, rows.to_vec());
        }
        let width = rows
            .chunks_exact(cols)
            .map(|r| r.iter().filter(|v| **v != 0.0).count())
            .max()
            .unwrap_or(0);
        let mut entries = Vec::with_capacity(width * (rows.len() / cols));
        for row in rows.chunks_exact(cols) {
            let before = entries.len();
            entries.extend(
                row.iter()
                    .enumerate()
                    .filter(|e| *e.1 != 0.0)
                    .map(|(j, &v)| (j, v)),
            );
            entries.resize(before + width, (0, 0.0));
        }
        RowProduct::Sparse(width, entries)
    }

    /// `out = M x` (`x` as long as a row, `out` one entry per row).
    pub fn apply(&self, x: &[f64], out: &mut [f64]) {
        match self {
            RowProduct::Dense(cols, vals) => {
                for (o, row) in out.iter_mut().zip(vals.chunks_exact((*cols).max(1))) {
                    let mut a = 0.0;
                    for (c, v) in row.iter().zip(x) {
                        a += c * v;
                    }
                    *o = a;
                }
            }
            RowProduct::Columns(cols, vals) => match vals.len() / cols {
                1 => by_columns::<1>(vals, x, out),
                2 => by_columns::<2>(vals, x, out),
                3 => by_columns::<3>(vals, x, out),
                4 => by_columns::<4>(vals, x, out),
                5 => by_columns::<5>(vals, x, out),
                6 => by_columns::<6>(vals, x, out),
                7 => by_columns::<7>(vals, x, out),
                _ => by_columns::<8>(vals, x, out),
            },
            RowProduct::Sparse(width, entries) => match *width {
                1 => sparse_rows::<1>(entries, x, out),
                2 => sparse_rows::<2>(entries, x, out),
                3 => sparse_rows::<3>(entries, x, out),
                4 => sparse_rows::<4>(entries, x, out),
                w => {
                    for (o, row) in out.iter_mut().zip(entries.chunks_exact(w.max(1))) {
                        let mut a = 0.0;
                        for &(j, c) in row {
                            a += c * x[j];
                        }
                        *o = a;
                    }
                }
            },
        }
    }
}

/// The most rows of a [`RowProduct::Columns`].
const COLUMN_ROWS: usize = 8;

/// The column-major copy of `r x c` row-major entries.
fn column_major(rows: &[f64], r: usize, c: usize) -> Vec<f64> {
    let mut out = vec![0.0; r * c];
    for (i, row) in rows.chunks_exact(c.max(1)).enumerate() {
        for (j, &v) in row.iter().enumerate() {
            out[j * r + i] = v;
        }
    }
    out
}

/// `out = M x` for the `R x cols` column-major `M` (`out` has `R` entries).
fn by_columns<const R: usize>(vals: &[f64], x: &[f64], out: &mut [f64]) {
    let mut acc = [0.0; R];
    for (col, &v) in vals.chunks_exact(R).zip(x) {
        for (a, c) in acc.iter_mut().zip(col) {
            *a += c * v;
        }
    }
    out[..R].copy_from_slice(&acc);
}

/// `e = y - M xu` for the `R x cols` column-major `M`, column by column (each error's sum
/// subtracts its columns in order, as [`Filter::errors`] does row by row).
fn less_columns<const R: usize>(vals: &[f64], xu: &[f64], y: &[f64], e: &mut [f64]) {
    let mut acc = [0.0; R];
    acc.copy_from_slice(&y[..R]);
    for (col, &v) in vals.chunks_exact(R).zip(xu) {
        for (a, c) in acc.iter_mut().zip(col) {
            *a -= c * v;
        }
    }
    e[..R].copy_from_slice(&acc);
}

/// [`RowProduct::apply`] for rows of `W` entries (the loop over a row unrolled).
fn sparse_rows<const W: usize>(entries: &[(usize, f64)], x: &[f64], out: &mut [f64]) {
    for (o, row) in out.iter_mut().zip(entries.chunks_exact(W)) {
        let mut a = 0.0;
        for &(j, c) in row {
            a += c * x[j];
        }
        *o = a;
    }
}

impl Filter {
    pub fn new(pm: Unpacked, rinv: Mat<f64>) -> Self {
        let (n, m, l) = (pm.a.nrows(), pm.b.ncols(), pm.c.nrows());
        let cd = rows_of(&[&pm.c, &pm.d]);
        let cd_cols = column_major(&cd, l, n + m);
        let abk = RowProduct::new(&rows_of(&[&pm.abar, &pm.bbar, &pm.k]), n + m + l);
        let rinv_rows = rows_of(&[&rinv]);
        Filter {
            pm,
            rinv,
            x: vec![0.0; n],
            xn: vec![0.0; n],
            e: vec![0.0; l],
            we: vec![0.0; l],
            wz: vec![0.0; l],
            cost: 0.0,
            cd,
            cd_cols,
            abk,
            rinv_rows,
            xuy: vec![0.0; n + m + l],
            loaded: None,
        }
    }

    /// Starts experiment `ex` from its initial state (and clears the vector registers' upper
    /// halves that dense products before the per-sample loop left dirty: see
    /// [`clear_upper`](crate::optim::clear_upper)).
    pub fn restart(&mut self, ex: usize) {
        crate::optim::clear_upper();
        self.x.copy_from_slice(&self.pm.x0[ex]);
        self.loaded = None;
    }

    /// `(x, u(t), y(t))` into `xuy`.
    fn load(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>, t: usize) {
        if self.loaded == Some(t) {
            return;
        }
        self.loaded = Some(t);
        let n = self.x.len();
        let m = u.ncols();
        self.xuy[..n].copy_from_slice(&self.x);
        for (j, v) in self.xuy[n..n + m].iter_mut().enumerate() {
            *v = u[(t, j)];
        }
        for (j, v) in self.xuy[n + m..].iter_mut().enumerate() {
            *v = y[(t, j)];
        }
    }

    /// `e = y - C x - D u` at sample `t`.
    pub fn errors(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>, t: usize) {
        self.load(u, y, t);
        let w = self.x.len() + u.ncols();
        let (xu, yt) = self.xuy.split_at(w);
        match self.e.len() {
            1 => return less_columns::<1>(&self.cd_cols, xu, yt, &mut self.e),
            2 => return less_columns::<2>(&self.cd_cols, xu, yt, &mut self.e),
            3 => return less_columns::<3>(&self.cd_cols, xu, yt, &mut self.e),
            4 => return less_columns::<4>(&self.cd_cols, xu, yt, &mut self.e),
            _ => {}
        }
        for ((ei, row), &yi) in self.e.iter_mut().zip(self.cd.chunks_exact(w)).zip(yt) {
            let mut a = yi;
            for (c, v) in row.iter().zip(xu) {
                a -= c * v;
            }
            *ei = a;
        }
    }

    /// The weighed errors at sample `t` ([`Self::errors`], then [`Self::weigh`]), the step
    /// of every sensitivity pass; every 4096 samples it checks for Ctrl-C.
    pub fn weighed_errors(
        &mut self,
        u: MatRef<'_, f64>,
        y: MatRef<'_, f64>,
        t: usize,
    ) -> Result<()> {
        if t % 4096 == 4095 {
            crate::interrupt::check()?;
        }
        self.errors(u, y, t);
        self.weigh();
        Ok(())
    }

    /// `R^-1 e` (added to the cost) and `W e`.
    pub fn weigh(&mut self) {
        let l = self.e.len();
        let r = &self.rinv_rows;
        for i in 0..l {
            let mut a = 0.0;
            for (rv, ev) in r[i * l..i * l + i + 1].iter().zip(&self.e) {
                a += rv * ev;
            }
            self.we[i] = a;
            self.cost += 0.5 * a * a;
        }
        self.weigh_back();
    }

    /// `wz = R^-T we`: the weighted errors of the gradient from `we = R^-1 e` (or of the
    /// substituted residuals).
    fn weigh_back(&mut self) {
        let l = self.we.len();
        let r = &self.rinv_rows;
        for i in 0..l {
            let mut a = 0.0;
            for j in i..l {
                a += r[j * l + i] * self.we[j];
            }
            self.wz[i] = a;
        }
    }

    /// Replaces the weighted errors of the gradient (`wz`) by `W (c e + x)` (the cost and
    /// `e` are kept): a pass with substituted residuals.
    pub fn substitute(&mut self, c: f64, x: &[f64]) {
        let l = self.e.len();
        let r = &self.rinv_rows;
        for i in 0..l {
            let mut a = 0.0;
            for (j, rv) in r[i * l..i * l + i + 1].iter().enumerate() {
                a += rv * (c * self.e[j] + x[j]);
            }
            self.we[i] = a;
        }
        self.weigh_back();
    }

    /// `x <- (A - K C) x + (B - K D) u + K y` at sample `t`.
    pub fn advance(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>, t: usize) {
        self.load(u, y, t);
        self.abk.apply(&self.xuy, &mut self.xn);
        std::mem::swap(&mut self.x, &mut self.xn);
        if t % crate::optim::FLUSH_EVERY == 0 {
            // a state no longer forced (zero input, simulation) decays through the subnormal
            // numbers: zeroed first, as the sensitivities it forces are
            crate::optim::flush_tiny(&mut self.x);
        }
        self.loaded = None;
    }

    /// The cost, infinite when it is not finite (the search then rejects the point).
    pub fn finite_cost(&self) -> f64 {
        if self.cost.is_finite() {
            self.cost
        } else {
            f64::INFINITY
        }
    }
}

/// Sum of squares of every output channel over the experiments.
/// The share of each output's mean square added to its error variance in the search's
/// weighting ([`Predictor::reweight_at`]): keeps it finite on noise-free data.
const FLOOR_SHARE: f64 = 1e-12;

fn output_power(experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)], l: usize) -> Vec<f64> {
    let mut power = vec![0.0; l];
    for (_, y) in experiments {
        for (j, pj) in power.iter_mut().enumerate() {
            for t in 0..y.nrows() {
                *pj += y[(t, j)] * y[(t, j)];
            }
        }
    }
    power
}

/// One initial-state choice per experiment, checked.
fn x0_modes(opts: &PemOptions, count: usize, n: usize) -> Result<Vec<InitialState>> {
    let modes = match opts.x0.len() {
        1 => vec![opts.x0[0].clone(); count],
        k if k == count => opts.x0.clone(),
        k => {
            return Err(SysidError::invalid(
                "x0",
                format!(
                    "{k} initial-state choices for {count} experiments; give one or one per \
                     experiment"
                ),
            ))
        }
    };
    for s in &modes {
        if let InitialState::Given(v) = s {
            if v.len() != n || v.iter().any(|x| !x.is_finite()) {
                return Err(SysidError::invalid(
                    "x0",
                    format!("a given initial state must have {n} finite entries"),
                ));
            }
        }
    }
    Ok(modes)
}

/// The fixed Kalman gain: the start's for prediction, zero for simulation or when not given.
fn fixed_gain(focus: Focus, k0: Option<MatRef<'_, f64>>, n: usize, l: usize) -> Result<Mat<f64>> {
    match (focus, k0) {
        (Focus::Simulation, _) | (_, None) => Ok(Mat::zeros(n, l)),
        (_, Some(k)) => {
            if k.nrows() != n || k.ncols() != l {
                return Err(SysidError::ShapeMismatch {
                    what: "K".into(),
                    expected: format!("({n}, {l})"),
                    got: format!("({}, {})", k.nrows(), k.ncols()),
                });
            }
            check_finite("K", k)?;
            Ok(k.to_owned())
        }
    }
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
        for (e, (u, y)) in experiments.iter().enumerate() {
            check_io(&format!("experiment {e} (u, y)"), *u, *y, m, l)?;
            n_samples += y.nrows();
        }
        let x0_mode = x0_modes(opts, experiments.len(), n)?;
        let full = n * n + n * m + l * n;
        let needed = opts.free_parameters.unwrap_or(full);
        if n_samples * l < needed {
            return Err(SysidError::InsufficientData {
                context: "prediction-error refinement".into(),
                needed: needed.div_ceil(l.max(1)),
                got: n_samples,
                fix: if opts.free_parameters.is_some() {
                    "use a longer record or fewer free parameters"
                } else {
                    "use a longer record or a lower order"
                },
            });
        }
        let est_k = opts.focus.estimates_k(opts.estimate_k);
        let k_fixed = fixed_gain(opts.focus, k0, n, l)?;
        let mut p = full + if opts.estimate_d { l * m } else { 0 };
        p += if est_k { n * l } else { 0 };
        let mut x0_off = Vec::new();
        for s in &x0_mode {
            x0_off.push((*s == InitialState::Estimate).then_some(p));
            p += if *s == InitialState::Estimate { n } else { 0 };
        }
        let floor = output_power(experiments, l)
            .iter()
            .map(|f| (f / n_samples as f64).max(f64::MIN_POSITIVE) * FLOOR_SHARE)
            .collect();
        Ok(Predictor {
            exps: experiments.to_vec(),
            n,
            m,
            l,
            est_d: opts.estimate_d,
            est_k,
            enforce_stability: opts.enforce_stability == Some(true)
                || opts.focus == Focus::Simulation,
            radius_limit: 1.0,
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
            a_bound_hits: 0,
            chart: None,
            last_covariance: None,
            substitute: None,
        })
    }

    /// The parameter vector of a model (initial states: zero where estimated).
    pub fn pack(&self, sys: &StateSpace, k: MatRef<'_, f64>, x0: &[Vec<f64>]) -> Vec<f64> {
        let mut th = Vec::with_capacity(self.p);
        let push = |th: &mut Vec<f64>, m: MatRef<'_, f64>| {
            for i in 0..m.nrows() {
                th.extend((0..m.ncols()).map(|j| m[(i, j)]));
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

    pub(super) fn unpack(&self, th: &[f64]) -> Unpacked {
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
        let abar = &a - &k * &c;
        let bbar = &b - &k * &d;
        Unpacked {
            a,
            b,
            c,
            d,
            k,
            x0,
            abar,
            bbar,
        }
    }

    pub(super) fn offsets(&self) -> Offsets {
        let (n, m, l) = (self.n, self.m, self.l);
        let c = n * n + n * m;
        let d = self.est_d.then_some(c + l * n);
        let k = self
            .est_k
            .then_some(c + l * n + if self.est_d { l * m } else { 0 });
        Offsets {
            a: 0,
            b: n * n,
            c,
            d,
            k,
        }
    }

    /// Whether `theta` is inside the admissible set ([`stable_enough`]); a point refused only
    /// because `A` is unstable is counted in `a_bound_hits`.
    pub(super) fn is_admissible(&mut self, th: &[f64]) -> bool {
        let pm = self.unpack(th);
        let (a, k, c) = (pm.a.as_ref(), pm.k.as_ref(), pm.c.as_ref());
        let limit = self.radius_limit;
        if stable_within(a, k, c, self.enforce_stability, limit) {
            return true;
        }
        if self.enforce_stability && stable_within(a, k, c, false, limit) {
            self.a_bound_hits += 1;
        }
        false
    }

    /// How far the spectral radii the admissible set bounds (the predictor's `A - K C`, and
    /// `A` with the stability bound) exceed its limit: the larger of the two differences
    /// (`None` when nothing is bounded or an eigenvalue solve fails).
    pub(super) fn margin(&mut self, th: &[f64]) -> Option<f64> {
        if !self.radius_limit.is_finite() {
            return None;
        }
        let pm = self.unpack(th);
        let (a, k, c) = (pm.a.as_ref(), pm.k.as_ref(), pm.c.as_ref());
        let limit = self.radius_limit;
        let m = bounded_radius(a, k, c, self.enforce_stability)? - limit;
        m.is_finite().then_some(m)
    }

    /// Admit poles on the unit circle (to [`MARGINAL_RADIUS`]) from now on: a grey box whose
    /// start has a structural integrator.
    pub(crate) fn set_marginal(&mut self) {
        self.radius_limit = MARGINAL_RADIUS;
    }

    /// Admit any spectral radius from now on: a simulation search left free of the stability
    /// bound (the test whether the data insist on an unstable model).
    pub(crate) fn set_unbounded(&mut self) {
        self.radius_limit = f64::INFINITY;
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

    /// The weighted cost `1/2 sum |R^-1 e|^2` at `theta` (no Jacobian).
    pub(super) fn cost(&self, th: &[f64]) -> f64 {
        self.pass(th, false).0
    }

    /// [`Self::cost`], keeping the errors' covariance of the same pass: when the search
    /// accepts this trial, its loss (`det Lambda`) or new weighting needs no second pass.
    pub(super) fn cost_keeping_covariance(&mut self, th: &[f64]) -> f64 {
        let (cost, lam) = self.pass(th, true);
        self.last_covariance = lam.map(|lam| (th.to_vec(), lam));
        cost
    }

    /// One pass of the predictor at `theta`: the weighted cost and, with `covariance`, the
    /// errors' sample covariance.
    fn pass(&self, th: &[f64], covariance: bool) -> (f64, Option<Mat<f64>>) {
        let l = self.l;
        let mut f = Filter::new(self.unpack(th), self.rinv.clone());
        // lower triangle, row by row
        let mut lam = vec![0.0; if covariance { l * (l + 1) / 2 } else { 0 }];
        // products and sums only (crate::denormals), as the sensitivity passes
        let daz = crate::denormals::DenormalsAreZero::new();
        let done = super::pass::dense_pass(&mut f, &self.exps, &mut lam);
        for (ex, (u, y)) in self.exps.iter().enumerate().filter(|_| !done) {
            f.restart(ex);
            for t in 0..y.nrows() {
                f.errors(*u, *y, t);
                f.weigh();
                if covariance {
                    let mut k = 0;
                    for i in 0..l {
                        for j in 0..=i {
                            lam[k] += f.e[i] * f.e[j];
                            k += 1;
                        }
                    }
                }
                f.advance(*u, *y, t);
            }
        }
        drop(daz);
        let nf = self.n_samples as f64;
        let lam = covariance.then(|| {
            Mat::from_fn(l, l, |i, j| {
                let (a, b) = (i.max(j), i.min(j));
                lam[a * (a + 1) / 2 + b] / nf
            })
        });
        (f.finite_cost(), lam)
    }

    /// Prediction errors' sample covariance at `theta`.
    pub fn innovation_covariance(&self, th: &[f64]) -> Mat<f64> {
        match &self.last_covariance {
            Some((at, lam)) if at.as_slice() == th => lam.clone(),
            _ => self.pass(th, true).1.unwrap_or_else(|| Mat::zeros(0, 0)),
        }
    }

    /// `det(Lambda)` at `theta`: the maximum-likelihood loss.
    pub(super) fn loss(&self, th: &[f64]) -> f64 {
        determinant(&self.innovation_covariance(th))
    }

    /// Whether some output's mean square exceeds its error variance (the diagonal of `lam`)
    /// more than `ratio` times, read from the weighting floor (that mean square times
    /// [`FLOOR_SHARE`]); false when `lam` does not fit.
    pub(super) fn outputs_dwarf_errors(&self, lam: &Mat<f64>, ratio: f64) -> bool {
        lam.nrows() == self.l
            && (0..self.l).any(|i| self.floor[i] / FLOOR_SHARE > ratio * lam[(i, i)])
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
        self.weigh_by(&lam)
    }

    /// `rinv = L^-1` with `L L^T = lam` (the weighting `W = lam^-1`); an error, and nothing
    /// changed, when `lam` is not positive definite.
    pub(super) fn weigh_by(&mut self, lam: &Mat<f64>) -> Result<()> {
        let llt = lam.llt(Side::Lower).map_err(|_| {
            SysidError::numerical(
                "prediction-error weighting",
                "the prediction-error covariance is not positive definite",
            )
        })?;
        let mut rinv = Mat::<f64>::identity(self.l, self.l);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            llt.L(),
            rinv.as_mut(),
            Par::Seq,
        );
        self.rinv = rinv;
        Ok(())
    }
}
