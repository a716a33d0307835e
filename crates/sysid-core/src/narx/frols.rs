//! Forward-regression orthogonal least squares (FROLS) by streaming passes.
//!
//! Step `s` has chosen the terms `S` with orthonormal components `u_1..u_s` (each
//! `u_l = Phi_S T[:, l]`, `T` upper triangular). For every candidate `k` the state holds the
//! projections `q_lk = phi_k^T u_l`, the squared norm of its component orthogonal to `S`,
//! `|phi_k|^2 - sum_l q_lk^2`, and the cross product of that component with the target,
//! `phi_k^T y - sum_l q_lk z_l` (`z_l = u_l^T y`). The next term maximises the error
//! reduction ratio; its orthogonal component `w = phi_s - Phi_S T q_s` is then formed
//! explicitly, sample by sample, in one pass that accumulates `Phi^T w`, `w^T w` and `w^T y`
//! over row blocks (generated on the fly, never stored whole). Memory is
//! `O(n_candidates * (max_terms + outputs))` plus one block.

use faer::Mat;
use rayon::prelude::*;

use super::basis::{dot, Basis, Candidates, Term};
use super::regressors::{LagSpec, Record, Signal};
use crate::error::{Result, SysidError};
use crate::linalg::QrAccumulator;

/// Settings of [`frols`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct FrolsOptions {
    /// Largest number of terms per output.
    pub max_terms: usize,
    /// Stop when the unexplained fraction `1 - sum ERR` falls below this.
    pub err_tol: f64,
    /// A candidate whose orthogonal component keeps less than this fraction of its squared
    /// norm is treated as collinear with the chosen terms and skipped.
    pub collinear_tol: f64,
    /// Rows per generated block (0: chosen from the number of candidates).
    pub block_rows: usize,
    /// Process blocks on several threads.
    pub parallel: bool,
}

impl Default for FrolsOptions {
    fn default() -> Self {
        Self {
            max_terms: 10,
            err_tol: 1e-10,
            collinear_tol: 1e-9,
            block_rows: 0,
            parallel: true,
        }
    }
}

impl FrolsOptions {
    /// Options with a term budget.
    pub fn with_max_terms(max_terms: usize) -> Self {
        Self {
            max_terms,
            ..Self::default()
        }
    }
}

/// The terms chosen for one output, in the order chosen.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Candidate indices.
    pub terms: Vec<usize>,
    /// Error reduction ratio of each.
    pub err: Vec<f64>,
    /// Residual sum of squares after 0, 1, ... terms (`rss[0] = y^T y`).
    pub rss: Vec<f64>,
    /// Regression rows.
    pub n_rows: usize,
}

struct Sums {
    cross: Vec<f64>,
    sq: Vec<f64>,
    gram: Vec<f64>,
}

impl Sums {
    fn zeros(m: usize, np: usize, q: usize, sq: bool) -> Self {
        Self {
            cross: vec![0.0; m * np],
            sq: vec![0.0; if sq { m } else { 0 }],
            gram: vec![0.0; q * q],
        }
    }
    fn add(&mut self, o: &Sums) {
        for (a, b) in self.cross.iter_mut().zip(&o.cross) {
            *a += b;
        }
        for (a, b) in self.sq.iter_mut().zip(&o.sq) {
            *a += b;
        }
        for (a, b) in self.gram.iter_mut().zip(&o.gram) {
            *a += b;
        }
    }
}

/// `a > b` (false when either is NaN).
#[inline]
fn above(a: f64, b: f64) -> bool {
    a > b
}

/// Row blocks `(record, first row, length)` covering rows `max_lag..N` of every record.
fn blocks(spec: &LagSpec, records: &[Record<'_>], len: usize) -> Vec<(usize, usize, usize)> {
    let mut out = Vec::new();
    for (r, rec) in records.iter().enumerate() {
        let mut t = spec.max_lag;
        let n = rec.y.nrows();
        while t < n {
            let l = len.min(n - t);
            out.push((r, t, l));
            t += l;
        }
    }
    out
}

/// One pass over the data. `probes(record, t0, len, x)` returns a column-major
/// `len x (np + extra)` block; candidate columns are dotted with its first `np` columns and
/// its Gram matrix is accumulated whole.
#[allow(clippy::too_many_arguments)]
fn pass<F>(
    spec: &LagSpec,
    cands: &Candidates,
    records: &[Record<'_>],
    blocks: &[(usize, usize, usize)],
    parallel: bool,
    np: usize,
    q: usize,
    want_sq: bool,
    probes: &F,
) -> Result<Sums>
where
    F: Fn(&Record<'_>, usize, usize, &[f64]) -> Vec<f64> + Sync,
{
    let m = cands.len();
    let nv = spec.n_vars();
    // Ctrl-C: asked before every block, in every task
    let flag = crate::interrupt::Flag::current();
    let group = |bs: &[(usize, usize, usize)]| -> Result<Sums> {
        let mut s = Sums::zeros(m, np, q, want_sq);
        let maxlen = bs.iter().map(|b| b.2).max().unwrap_or(0);
        let mut x = vec![0.0; maxlen * nv];
        let mut scratch = vec![0.0; cands.accumulate_scratch_len(maxlen, np)];
        for &(r, t0, len) in bs {
            flag.check()?;
            let rec = &records[r];
            let x = &mut x[..len * nv];
            spec.fill_block(rec, t0, len, x);
            let p = probes(rec, t0, len, x);
            for a in 0..q {
                for b in 0..q {
                    s.gram[a * q + b] +=
                        dot(&p[a * len..(a + 1) * len], &p[b * len..(b + 1) * len]);
                }
            }
            let sc = &mut scratch[..cands.accumulate_scratch_len(len, np)];
            let sq = if want_sq { Some(&mut s.sq[..]) } else { None };
            cands.accumulate(x, len, &p, np, &mut s.cross, sq, sc);
        }
        Ok(s)
    };
    // fixed groups of blocks summed in order: the result does not depend on the threads
    const GROUP: usize = 16;
    let parts: Vec<Sums> = if parallel && blocks.len() > GROUP {
        blocks.par_chunks(GROUP).map(group).collect::<Result<_>>()?
    } else {
        blocks.chunks(GROUP).map(group).collect::<Result<_>>()?
    };
    let mut total = Sums::zeros(m, np, q, want_sq);
    for p in &parts {
        total.add(p);
    }
    Ok(total)
}

fn block_len(cands: &Candidates, opts: &FrolsOptions) -> usize {
    if opts.block_rows > 0 {
        return opts.block_rows;
    }
    let per_row = 8 * (cands.accumulate_scratch_len(1, 2) + cands.n_vars());
    ((2 << 20) / per_row).clamp(64, 4096)
}

struct State {
    q: Vec<Vec<f64>>,
    t: Vec<Vec<f64>>,
    res_sq: Vec<f64>,
    res_y: Vec<f64>,
    d: Vec<f64>,
    yy: f64,
    sel: Selection,
    pending: Option<(usize, Vec<f64>)>,
    excluded: Vec<bool>,
    done: bool,
}

/// FROLS term selection for every output from the same candidates (one pass per step, the
/// outputs' selections advance together). `forced[i]` lists candidates chosen first for
/// output `i`, in that order (for example the process terms when selecting noise terms).
///
/// ```
/// use faer::Mat;
/// use sysid_core::narx::basis::{Basis, Candidates, Term};
/// use sysid_core::narx::frols::{frols, FrolsOptions};
/// use sysid_core::narx::regressors::{LagSpec, Record};
/// let n = 300;
/// let u = Mat::from_fn(n, 1, |t, _| (((t * 7919) % 97) as f64 / 48.0) - 1.0);
/// let mut y = Mat::<f64>::zeros(n, 1);
/// for t in 1..n { y[(t, 0)] = 0.5 * y[(t - 1, 0)] + u[(t - 1, 0)] - 0.3 * y[(t - 1, 0)] * u[(t - 1, 0)]; }
/// let spec = LagSpec::new(1, 1, &[1], &[1], &[1], &[0]).unwrap();
/// let cands = Candidates::new(&Basis::Polynomial { degree: 2 }, spec.n_vars()).unwrap();
/// let rec = [Record::new(u.as_ref(), y.as_ref())];
/// let sel = frols(&spec, &cands, &rec, &[vec![]], &FrolsOptions::with_max_terms(4)).unwrap();
/// let mut chosen: Vec<_> = sel[0].terms.iter().map(|&k| cands.terms[k].clone()).collect();
/// chosen.sort_by_key(|t| format!("{t:?}"));
/// assert_eq!(chosen, vec![Term::Monomial(vec![0, 1]), Term::Monomial(vec![0]), Term::Monomial(vec![1])]);
/// ```
pub fn frols(
    spec: &LagSpec,
    cands: &Candidates,
    records: &[Record<'_>],
    forced: &[Vec<usize>],
    opts: &FrolsOptions,
) -> Result<Vec<Selection>> {
    let n_rows = spec.check_records(records)?;
    let (m, ny) = (cands.len(), spec.n_outputs);
    if cands.n_vars() != spec.n_vars() {
        return Err(SysidError::invalid(
            "basis",
            "the candidates were built for a different number of lagged variables",
        ));
    }
    if forced.len() != ny || forced.iter().flatten().any(|&k| k >= m) {
        return Err(SysidError::invalid(
            "forced",
            format!("needs one list per output ({ny}) of candidate indices below {m}"),
        ));
    }
    if opts.max_terms == 0 {
        return Err(SysidError::invalid("max_terms", "must be at least 1"));
    }
    let len = block_len(cands, opts);
    let bl = blocks(spec, records, len);
    // pass 0: |phi_k|^2, phi_k^T y_i, y^T y
    let targets = |rec: &Record<'_>, t0: usize, len: usize, _x: &[f64]| {
        let mut p = vec![0.0; len * ny];
        for i in 0..ny {
            for r in 0..len {
                p[i * len + r] = rec.y[(t0 + r, i)];
            }
        }
        p
    };
    let s0 = pass(
        spec,
        cands,
        records,
        &bl,
        opts.parallel,
        ny,
        ny,
        true,
        &targets,
    )?;
    let mut states: Vec<State> = (0..ny)
        .map(|i| {
            let yy = s0.gram[i * ny + i];
            State {
                q: vec![],
                t: vec![],
                res_sq: s0.sq.clone(),
                res_y: (0..m).map(|k| s0.cross[k * ny + i]).collect(),
                d: s0.sq.clone(),
                yy,
                sel: Selection {
                    terms: vec![],
                    err: vec![],
                    rss: vec![yy],
                    n_rows,
                },
                pending: None,
                excluded: vec![false; m],
                done: yy <= 0.0,
            }
        })
        .collect();
    if states.iter().all(|s| s.done) {
        return Err(SysidError::invalid(
            "y",
            "every output is identically zero over the regression rows; nothing to fit",
        ));
    }
    loop {
        // choose the next term of every active output
        for (i, st) in states.iter_mut().enumerate() {
            if st.done {
                continue;
            }
            let step = st.sel.terms.len();
            let choice = if step < forced[i].len() {
                let k = forced[i][step];
                if st.excluded[k] || st.res_sq[k] <= opts.collinear_tol * st.d[k] {
                    return Err(SysidError::invalid(
                        "forced",
                        format!("forced term {k} of output {i} is collinear with earlier ones"),
                    ));
                }
                Some(k)
            } else {
                let mut best = None;
                let mut best_err = 0.0;
                for k in 0..m {
                    if st.excluded[k] || !above(st.res_sq[k], opts.collinear_tol * st.d[k]) {
                        continue;
                    }
                    let e = st.res_y[k] * st.res_y[k] / (st.res_sq[k] * st.yy);
                    if e > best_err {
                        best_err = e;
                        best = Some(k);
                    }
                }
                best
            };
            let Some(s) = choice else {
                st.done = true;
                continue;
            };
            // w = phi_s - Phi_S c, c = T q_s
            let l = st.q.len();
            let mut c = vec![0.0; l];
            for (r, tr) in st.t.iter().enumerate() {
                let qs = st.q[r][s];
                for (mi, tv) in tr.iter().enumerate() {
                    c[mi] += qs * tv;
                }
            }
            st.pending = Some((s, c));
        }
        let active: Vec<usize> = (0..ny).filter(|&i| !states[i].done).collect();
        if active.is_empty() {
            break;
        }
        let na = active.len();
        let probe_terms: Vec<(Vec<usize>, Vec<f64>, usize)> = active
            .iter()
            .map(|&i| {
                let st = &states[i];
                let (s, c) = st.pending.clone().expect("set above");
                (st.sel.terms.clone(), c, s)
            })
            .collect();
        let probes = |rec: &Record<'_>, t0: usize, len: usize, x: &[f64]| {
            let nv = spec.n_vars();
            let mut p = vec![0.0; len * (na + ny)];
            let mut row = vec![0.0; nv];
            for r in 0..len {
                for v in 0..nv {
                    row[v] = x[v * len + r];
                }
                for (a, (sel, c, s)) in probe_terms.iter().enumerate() {
                    let mut w = cands.basis.eval(&cands.terms[*s], &row);
                    for (mi, &k) in sel.iter().enumerate() {
                        w -= c[mi] * cands.basis.eval(&cands.terms[k], &row);
                    }
                    p[a * len + r] = w;
                }
                for i in 0..ny {
                    p[(na + i) * len + r] = rec.y[(t0 + r, i)];
                }
            }
            p
        };
        let q = na + ny;
        let sums = pass(
            spec,
            cands,
            records,
            &bl,
            opts.parallel,
            na,
            q,
            false,
            &probes,
        )?;
        for (a, &i) in active.iter().enumerate() {
            let st = &mut states[i];
            let (s, c) = st.pending.take().expect("set above");
            let ww = sums.gram[a * q + a];
            if !above(ww, opts.collinear_tol * st.d[s]) || !ww.is_finite() {
                st.excluded[s] = true; // lost to rounding: try the next best
                continue;
            }
            let norm = ww.sqrt();
            let z = sums.gram[a * q + na + i] / norm;
            let row: Vec<f64> = (0..m).map(|k| sums.cross[k * na + a] / norm).collect();
            for k in 0..m {
                st.res_sq[k] -= row[k] * row[k];
                st.res_y[k] -= row[k] * z;
            }
            st.res_sq[s] = 0.0;
            st.excluded[s] = true;
            let mut tcol: Vec<f64> = c.iter().map(|v| -v / norm).collect();
            tcol.push(1.0 / norm);
            // T columns hold coefficients on the chosen terms in order; pad earlier ones
            st.t.push(tcol);
            st.q.push(row);
            st.sel.terms.push(s);
            st.sel.err.push(z * z / st.yy);
            let rss = (st.sel.rss.last().copied().unwrap_or(st.yy) - z * z).max(0.0);
            st.sel.rss.push(rss);
            if st.sel.terms.len() >= opts.max_terms.max(forced[i].len())
                || (st.sel.terms.len() >= forced[i].len() && rss <= opts.err_tol * st.yy)
            {
                st.done = true;
            }
        }
    }
    Ok(states.into_iter().map(|s| s.sel).collect())
}

/// The triangular factor `R` of `[Phi_S, y_i]` for each output's terms `terms[i]` (one
/// streaming Householder pass): least squares of any leading subset of the terms is
/// `R[..k, ..k] theta = R[..k, K]`, with residual sum of squares `sum_{r >= k} R[r, K]^2`.
pub fn fit(
    spec: &LagSpec,
    cands: &Candidates,
    records: &[Record<'_>],
    terms: &[Vec<usize>],
) -> Result<Vec<Mat<f64>>> {
    if terms.iter().flatten().any(|&k| k >= cands.len()) {
        return Err(SysidError::invalid("terms", "candidate index out of range"));
    }
    let terms: Vec<Vec<Term>> = terms
        .iter()
        .map(|t| t.iter().map(|&k| cands.terms[k].clone()).collect())
        .collect();
    fit_terms(spec, &cands.basis, records, &terms)
}

/// As [`fit`] for explicit terms (for example a NARMAX model's terms refitted on new
/// residuals).
pub fn fit_terms(
    spec: &LagSpec,
    basis: &Basis,
    records: &[Record<'_>],
    terms: &[Vec<Term>],
) -> Result<Vec<Mat<f64>>> {
    spec.check_records(records)?;
    basis.check(spec.n_lagged())?;
    if terms.len() != spec.n_outputs {
        return Err(SysidError::invalid(
            "terms",
            "needs one list of terms per output",
        ));
    }
    let nv = spec.n_vars();
    let mut accs: Vec<QrAccumulator> = terms
        .iter()
        .map(|t| QrAccumulator::new(t.len() + 1, 512.max(t.len() + 1)))
        .collect();
    let mut x = vec![0.0; nv];
    let mut row = Vec::new();
    for rec in records {
        for t in spec.max_lag..rec.y.nrows() {
            if t % 4096 == 0 {
                crate::interrupt::check()?;
            }
            spec.fill_with(t, &mut x, |s, ch, tt| match s {
                Signal::Output => rec.y[(tt, ch)],
                Signal::Input => rec.u[(tt, ch)],
                Signal::Noise => rec.e.expect("checked")[(tt, ch)],
                Signal::Custom => rec.c.expect("checked")[(tt, ch)],
            });
            for (i, ti) in terms.iter().enumerate() {
                row.clear();
                row.extend(ti.iter().map(|term| basis.eval(term, &x)));
                row.push(rec.y[(t, i)]);
                accs[i].push_row(&row);
            }
        }
    }
    Ok(accs.into_iter().map(|a| a.finish()).collect())
}

/// Coefficients of the first `k` terms from a factor of [`fit`] (`None` when the leading
/// block is singular).
pub fn solve_prefix(r: &Mat<f64>, k: usize) -> Option<Vec<f64>> {
    let kk = r.ncols() - 1;
    let mut th = vec![0.0; k];
    let scale = (0..kk).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
    for i in (0..k).rev() {
        let mut s = r[(i, kk)];
        for j in i + 1..k {
            s -= r[(i, j)] * th[j];
        }
        if !above(r[(i, i)].abs(), 1e-14 * scale) {
            return None;
        }
        th[i] = s / r[(i, i)];
    }
    Some(th)
}
