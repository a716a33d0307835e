//! Multi-input multi-output Hammerstein-Wiener models with a state-space linear block.
//!
//! ```text
//! w_j(t) = f_j(u_j(t); alpha_j)               per-input static nonlinearity
//! x(t+1) = A x(t) + B w(t)                     linear block (state space, x(0) = 0)
//! v(t)   = C x(t) + D w(t)                     (D = 0 without feedthrough)
//! y_i(t) = g_i(v_i(t); beta_i) + e_i(t)        per-output static nonlinearity
//! ```
//!
//! Parameters `theta = [alpha_1..alpha_m, vec(A), vec(B), vec(C), (vec(D)), beta_1..beta_p,
//! (y0_1..y0_p), (x0 of each record)]`
//! (matrices row-major), estimated by prediction error with the one optimiser
//! ([`crate::optim`]): the state sensitivities `S(t) = dx(t)/dtheta` run sample by sample
//! for the parameters that move the state only (`alpha`, `A`, `B`), once per sample for all
//! outputs, `S(t+1) = A S(t) + dA x(t) + dB w(t) + B dw(t)/dalpha`, and
//! `dy_i/dtheta = g_i'(v_i) (C S + dC x + D dw/dalpha + dD w)_i + dg_i/dbeta_i`; an estimated
//! initial state `x0` (the output is not affine in it through `g_i`, so it is searched with
//! the rest) has `S(0) = I` in its columns (`dx(t)/dx0 = A^t`); the rows are
//! folded into `J^T J` in blocks by one matrix product ([`NormalEquations::blocked`]), no
//! `N x p` array. The full state-space parametrisation is not identifiable (similarity transforms):
//! the Gauss-Newton products are formed over the identifiable columns in the modal
//! coordinates of `A` and mapped back exactly (module `modal`), so the search moves as over
//! the full parameters at a fraction of the cost; the poles and the nonlinearities, which are
//! identifiable, are what the tests check. The unit-gain normalisations of the
//! nonlinearities ([`Nonlinearity`]) put the gains in `B` and `C`.
//! The admissible set is `A` stable.

use faer::{Mat, MatRef};

use super::{check_start, Nonlinearity};
use crate::error::{Result, SysidError};
use crate::linalg::spectral_radius;
use crate::optim::{
    flush_tiny, minimize, Evaluation, Flow, Iteration, NormalEquations, Options, Problem, Solution,
    FLUSH_EVERY,
};

/// The structure of a MIMO Hammerstein-Wiener model with a state-space linear block.
#[derive(Debug, Clone)]
pub struct MimoHwStructure {
    /// Input nonlinearities, one per input.
    pub inputs: Vec<Nonlinearity>,
    /// Output nonlinearities, one per output.
    pub outputs: Vec<Nonlinearity>,
    /// State dimension of the linear block.
    pub order: usize,
    /// Whether the linear block has a direct term `D`.
    pub feedthrough: bool,
    /// Whether `theta` ends with one output offset per output, added to the output
    /// nonlinearities' values (`y_i = y0_i + g_i(v_i)`): the levels of the operating point.
    pub offsets: bool,
    /// The number of records whose initial state `x(0)` is estimated: `theta` ends (after
    /// the offsets) with one state (`order` entries) per record, in order; 0 when every
    /// record starts from rest.
    pub initial_states: usize,
}

/// Offsets of the parameter groups.
struct Layout {
    alpha: Vec<usize>,
    a: usize,
    b: usize,
    c: usize,
    d: usize,
    beta: Vec<usize>,
    offset: usize,
    x0: usize,
    total: usize,
}

impl MimoHwStructure {
    fn layout(&self) -> Layout {
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let mut off = 0;
        let alpha = self
            .inputs
            .iter()
            .map(|f| {
                off += f.n_params();
                off - f.n_params()
            })
            .collect();
        let a = off;
        let b = a + n * n;
        let c = b + n * m;
        let d = c + p * n;
        off = d + if self.feedthrough { p * m } else { 0 };
        let beta = self
            .outputs
            .iter()
            .map(|g| {
                off += g.n_params();
                off - g.n_params()
            })
            .collect();
        let x0 = off + if self.offsets { p } else { 0 };
        Layout {
            alpha,
            a,
            b,
            c,
            d,
            beta,
            offset: off,
            x0,
            total: x0 + self.initial_states * n,
        }
    }

    /// Total number of parameters.
    pub fn n_params(&self) -> usize {
        self.layout().total
    }

    /// The model's own parameters `[alpha, A, B, C, (D), beta, (offsets)]` (the initial
    /// states excluded).
    pub fn n_model(&self) -> usize {
        self.layout().x0
    }

    /// Record `k`'s initial state in `theta` (with [`Self::initial_states`]).
    pub fn initial_state<'a>(&self, theta: &'a [f64], k: usize) -> &'a [f64] {
        let at = self.layout().x0 + k * self.order;
        &theta[at..at + self.order]
    }

    /// Checks the definition.
    pub fn check(&self) -> Result<()> {
        if self.inputs.is_empty() || self.outputs.is_empty() || self.order == 0 {
            return Err(SysidError::invalid(
                "structure",
                "needs at least one input, one output and order >= 1",
            ));
        }
        for f in self.inputs.iter().chain(&self.outputs) {
            f.check()?;
        }
        Ok(())
    }

    /// The matrices `(A, B, C, D)` of the linear block at `theta`.
    pub fn matrices(&self, theta: &[f64]) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
        let l = self.layout();
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let a = Mat::from_fn(n, n, |r, c| theta[l.a + r * n + c]);
        let b = Mat::from_fn(n, m, |r, c| theta[l.b + r * m + c]);
        let c = Mat::from_fn(p, n, |r, k| theta[l.c + r * n + k]);
        let d = Mat::from_fn(p, m, |r, k| {
            if self.feedthrough {
                theta[l.d + r * m + k]
            } else {
                0.0
            }
        });
        (a, b, c, d)
    }

    /// Noise-free outputs `(N, p)` for inputs `u` `(N, m)` at `theta`, from rest.
    ///
    /// # Errors
    /// [`SysidError::Interrupted`] when stopped inside an [`crate::interrupt`] scope.
    pub fn simulate(&self, theta: &[f64], u: MatRef<'_, f64>) -> Result<Mat<f64>> {
        let mut y = Mat::<f64>::zeros(u.nrows(), self.outputs.len());
        self.run(theta, u, None, None, usize::MAX, |t, i, yhat, _| {
            y[(t, i)] = yhat
        })?;
        Ok(y)
    }

    /// Noise-free outputs `(N, p)` from the linear block's initial state `x0` (`order`
    /// entries; what [`Self::simulate`] takes as zero).
    ///
    /// # Errors
    /// [`SysidError::ShapeMismatch`] when `x0` has not `order` entries.
    ///
    /// # Example
    /// ```
    /// use faer::Mat;
    /// use sysid_core::hw::{mimo::MimoHwStructure, Nonlinearity};
    /// let s = MimoHwStructure { inputs: vec![Nonlinearity::Identity],
    ///     outputs: vec![Nonlinearity::Identity], order: 1, feedthrough: false, offsets: false,
    ///     initial_states: 0 };
    /// // x(t+1) = 0.5 x + w, v = x: from x0 = 2 with no input, 2, 1, 0.5
    /// let y = s.simulate_from(&[0.5, 1.0, 1.0], Mat::<f64>::zeros(3, 1).as_ref(), &[2.0])
    ///     .unwrap();
    /// assert_eq!((y[(0, 0)], y[(1, 0)], y[(2, 0)]), (2.0, 1.0, 0.5));
    /// ```
    pub fn simulate_from(&self, theta: &[f64], u: MatRef<'_, f64>, x0: &[f64]) -> Result<Mat<f64>> {
        if x0.len() != self.order {
            return Err(SysidError::ShapeMismatch {
                what: "x0".into(),
                expected: format!("{} entries (the linear block's order)", self.order),
                got: format!("{} entries", x0.len()),
            });
        }
        let mut y = Mat::<f64>::zeros(u.nrows(), self.outputs.len());
        self.run(theta, u, None, Some(x0), usize::MAX, |t, i, yhat, _| {
            y[(t, i)] = yhat
        })?;
        Ok(y)
    }

    /// The Jacobian columns of the parameters that move (all but those in `held`), in
    /// layout order: those that move the state (`alpha`, `A`, `B`) first, the records'
    /// initial states last.
    fn columns(&self, held: &[bool]) -> Vec<Column> {
        let l = self.layout();
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let mut cols = Vec::with_capacity(l.total);
        for (j, f) in self.inputs.iter().enumerate() {
            cols.extend((0..f.n_params()).map(|q| Column::Alpha(j, l.alpha[j] + q)));
        }
        cols.extend((0..n * n).map(|k| Column::A(k / n, k % n)));
        cols.extend((0..n * m).map(|k| Column::B(k / m, k % m)));
        cols.extend((0..p * n).map(|k| Column::C(k / n, k % n)));
        if self.feedthrough {
            cols.extend((0..p * m).map(|k| Column::D(k / m, k % m)));
        }
        for (i, g) in self.outputs.iter().enumerate() {
            cols.extend((0..g.n_params()).map(|q| Column::Beta(i, l.beta[i] + q)));
        }
        if self.offsets {
            cols.extend((0..p).map(Column::Offset));
        }
        for e in 0..self.initial_states {
            cols.extend((0..n).map(|k| Column::X0(e, k)));
        }
        debug_assert_eq!(cols.len(), l.total);
        cols.into_iter()
            .enumerate()
            .filter(|(k, _)| !held.get(*k).copied().unwrap_or(false))
            .map(|(_, c)| c)
            .collect()
    }

    /// Runs the model of record `record` from `x0` (`None`: from rest); `visit(t, output,
    /// yhat, d yhat / d theta)` per sample and output, the row over `cols`
    /// ([`Self::columns`]; empty when `cols` is `None`; the columns of other records' initial
    /// states zero). The state sensitivities `S` (`n x nd`, row-major) are carried for the
    /// `nd` columns that move the state only (`alpha`, `A`, `B`, this record's `x0`, whose
    /// `S(0)` is the identity), once per sample for all outputs; `A S` skips the zeros of `A`
    /// (the modal chart holds all but its blocks at zero).
    fn run(
        &self,
        theta: &[f64],
        u: MatRef<'_, f64>,
        cols: Option<&[Column]>,
        x0: Option<&[f64]>,
        record: usize,
        mut visit: impl FnMut(usize, usize, f64, &[f64]),
    ) -> Result<()> {
        let l = self.layout();
        let (n, m, p) = (self.order, self.inputs.len(), self.outputs.len());
        let (a, b, c, d) = self.matrices(theta);
        let cols = cols.unwrap_or(&[]);
        let q = cols.len();
        // the columns that move the state, in order (alpha first), and where they sit
        let moves = |c: &Column| c.moves_state() || matches!(*c, Column::X0(e, _) if e == record);
        let dyn_at: Vec<usize> = (0..q).filter(|&k| moves(&cols[k])).collect();
        let dyn_cols: Vec<Column> = dyn_at.iter().map(|&k| cols[k]).collect();
        let nd = dyn_at.len();
        let mut x = x0.map_or_else(|| vec![0.0; n], <[f64]>::to_vec);
        let mut xn = vec![0.0; n];
        let mut w = vec![0.0; m];
        // dw_j / dalpha_j and dg_i / dbeta_i, stored at their theta offsets
        let mut dw = vec![0.0; l.total];
        let mut dg = vec![0.0; l.total];
        let mut s = vec![0.0; n * nd];
        for (cn, col) in dyn_cols.iter().enumerate() {
            if let Column::X0(_, k) = *col {
                s[k * nd + cn] = 1.0; // dx(0) / dx0 = I
            }
        }
        let mut sn = vec![0.0; n * nd];
        let mut row = vec![0.0; q];
        let mut dyn_row = vec![0.0; nd];
        // the input parameters' columns, and per output the static columns it moves
        let alphas: Vec<(usize, usize, usize)> = dyn_cols
            .iter()
            .enumerate()
            .filter_map(|(cn, col)| match *col {
                Column::Alpha(j, at) if self.feedthrough => Some((cn, j, at)),
                _ => None,
            })
            .collect();
        let mut own: Vec<Vec<(usize, Column)>> = vec![Vec::new(); p];
        for (cn, col) in cols.iter().enumerate().filter(|(_, c)| !moves(c)) {
            if let Column::C(i, _) | Column::D(i, _) | Column::Beta(i, _) | Column::Offset(i) = *col
            {
                own[i].push((cn, *col));
            }
        }
        // per row of A, its non-zero entries
        let nz: Vec<Vec<(usize, f64)>> = (0..n)
            .map(|r| {
                (0..n)
                    .filter(|&k| a[(r, k)] != 0.0)
                    .map(|k| (k, a[(r, k)]))
                    .collect()
            })
            .collect();
        for t in 0..u.nrows() {
            if t % 4096 == 4095 {
                crate::interrupt::check()?; // Ctrl-C within a pass over a long record
            }
            for j in 0..m {
                let np = self.inputs[j].n_params();
                let a0 = l.alpha[j];
                w[j] = self.inputs[j]
                    .eval(&theta[a0..a0 + np], u[(t, j)], &mut dw[a0..a0 + np])
                    .0;
            }
            for i in 0..p {
                let v = (0..n).map(|k| c[(i, k)] * x[k]).sum::<f64>()
                    + (0..m).map(|j| d[(i, j)] * w[j]).sum::<f64>();
                let nb = self.outputs[i].n_params();
                let b0 = l.beta[i];
                let (g, gd) = self.outputs[i].eval(&theta[b0..b0 + nb], v, &mut dg[b0..b0 + nb]);
                let yhat = if self.offsets {
                    g + theta[l.offset + i]
                } else {
                    g
                };
                if q > 0 {
                    // dv_i = C_i S + dC_i x + D_i dw + dD_i w, times g_i'; + dg_i / dbeta_i
                    dyn_row.fill(0.0);
                    for k in 0..n {
                        let cik = c[(i, k)];
                        if cik != 0.0 {
                            for (rv, sv) in dyn_row.iter_mut().zip(&s[k * nd..(k + 1) * nd]) {
                                *rv += cik * sv;
                            }
                        }
                    }
                    for &(cn, j, at) in &alphas {
                        dyn_row[cn] += d[(i, j)] * dw[at];
                    }
                    dyn_row.iter_mut().for_each(|rv| *rv *= gd);
                    row.fill(0.0);
                    for (&at, &rv) in dyn_at.iter().zip(&dyn_row) {
                        row[at] = rv;
                    }
                    for &(cn, col) in &own[i] {
                        row[cn] = match col {
                            Column::C(_, k) => gd * x[k],
                            Column::D(_, j) => gd * w[j],
                            Column::Beta(_, at) => dg[at],
                            Column::Offset(_) => 1.0,
                            _ => 0.0,
                        };
                    }
                }
                visit(t, i, yhat, &row);
            }
            // state update and sensitivities: S(t+1) = A S + dA x + dB w + B dw/dalpha
            for r in 0..n {
                xn[r] = nz[r].iter().map(|&(k, akr)| akr * x[k]).sum::<f64>()
                    + (0..m).map(|j| b[(r, j)] * w[j]).sum::<f64>();
            }
            if nd > 0 {
                for r in 0..n {
                    let out = &mut sn[r * nd..(r + 1) * nd];
                    out.fill(0.0);
                    for &(k, ark) in &nz[r] {
                        for (ov, sv) in out.iter_mut().zip(&s[k * nd..(k + 1) * nd]) {
                            *ov += ark * sv;
                        }
                    }
                    for (ov, col) in out.iter_mut().zip(&dyn_cols) {
                        match *col {
                            Column::Alpha(j, at) => *ov += b[(r, j)] * dw[at],
                            _ => break, // alpha first, then A and B
                        }
                    }
                }
                for (cn, col) in dyn_cols.iter().enumerate() {
                    match *col {
                        Column::A(r, k) => sn[r * nd + cn] += x[k],
                        Column::B(r, j) => sn[r * nd + cn] += w[j],
                        _ => {}
                    }
                }
                std::mem::swap(&mut s, &mut sn);
            }
            std::mem::swap(&mut x, &mut xn);
            if t % FLUSH_EVERY == 0 {
                // a state (and sensitivities) no longer forced decays through the subnormal
                // numbers, slow on Intel processors (`optim::flush_tiny`)
                flush_tiny(&mut x);
                flush_tiny(&mut s);
            }
        }
        Ok(())
    }
}

/// A Jacobian column: what its parameter is (with its `theta` offset for the nonlinearities).
#[derive(Debug, Clone, Copy)]
enum Column {
    /// Parameter at `theta[at]` of input `j`'s nonlinearity.
    Alpha(usize, usize),
    /// `A[r, k]`.
    A(usize, usize),
    /// `B[r, j]`.
    B(usize, usize),
    /// `C[i, k]`.
    C(usize, usize),
    /// `D[i, j]`.
    D(usize, usize),
    /// Parameter at `theta[at]` of output `i`'s nonlinearity.
    Beta(usize, usize),
    /// Output `i`'s offset.
    Offset(usize),
    /// Entry `k` of record `e`'s initial state.
    X0(usize, usize),
}

impl Column {
    fn moves_state(&self) -> bool {
        matches!(self, Column::Alpha(..) | Column::A(..) | Column::B(..))
    }
}

/// The prediction-error problem of a MIMO Hammerstein-Wiener structure over several records.
pub struct MimoHwProblem<'a> {
    /// The structure.
    pub structure: MimoHwStructure,
    /// `(u (N, m), y (N, p))` records.
    pub records: Vec<(MatRef<'a, f64>, MatRef<'a, f64>)>,
}

impl Problem for MimoHwProblem<'_> {
    fn n_params(&self) -> usize {
        self.structure.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        if jacobian {
            if let Some(mut ev) = self.evaluate_modal(theta)? {
                // the cost at theta itself (the search compares it with its trial points)
                ev.cost = self.evaluate(theta, false)?.cost;
                return Ok(ev);
            }
        }
        let s = &self.structure;
        let cols = s.columns(&[]);
        let mut sums = NormalEquations::blocked(cols.len(), jacobian);
        for (e, (u, y)) in self.records.iter().enumerate() {
            let c = jacobian.then_some(cols.as_slice());
            let x0 = (s.initial_states > 0).then(|| s.initial_state(theta, e));
            s.run(theta, *u, c, x0, e, |t, i, yhat, jr| {
                sums.add(y[(t, i)] - yhat, Some(jr))
            })?;
        }
        Ok(sums.finish())
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        if !theta.iter().all(|v| v.is_finite()) {
            return false;
        }
        let (a, _, _, _) = self.structure.matrices(theta);
        matches!(spectral_radius(a.as_ref()), Ok(r) if r < 1.0)
    }

    /// Every output of every sample is a residual of the cost (for
    /// [`Options::tol_statistical`]).
    fn n_residuals(&self) -> Option<usize> {
        Some(
            self.records
                .iter()
                .map(|(_, y)| y.nrows() * y.ncols())
                .sum(),
        )
    }
}

/// Prediction-error estimate of a MIMO Hammerstein-Wiener model from `theta0` (for example
/// a linear state-space fit with identity-like nonlinearities).
pub fn estimate_mimo(
    structure: &MimoHwStructure,
    records: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    structure.check()?;
    check_start(
        structure.n_params(),
        theta0.len(),
        structure.initial_states,
        records.len(),
    )?;
    let (m, p) = (structure.inputs.len(), structure.outputs.len());
    for (u, y) in records {
        crate::error::check_io("u, y", *u, *y, m, p)?;
    }
    let mut problem = MimoHwProblem {
        structure: structure.clone(),
        records: records.to_vec(),
    };
    if !problem.admissible(theta0) {
        return Err(SysidError::invalid(
            "theta0",
            "the starting linear block is unstable or not finite; start from a stable fit",
        ));
    }
    minimize(&mut problem, theta0, options, observer)
}

mod modal;
#[cfg(test)]
mod tests;
