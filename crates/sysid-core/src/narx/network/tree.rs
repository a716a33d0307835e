//! Tree partition: a piecewise-affine function on a binary partition of the regressor space,
//! grown greedily (a regression tree with affine leaves).
//!
//! Each cell holds the least-squares affine model `y = c0 + c^T z` of its samples. A cell is
//! split on one regressor at the threshold that minimises the summed residual sum of squares
//! of the two affine fits: for each regressor the samples are sorted and the Gram matrices
//! of `[1, z, y]` on either side of every split position follow from one running sum
//! (`O(n nz^3)` per cell and regressor), the threshold lying midway between neighbouring
//! values. Cells are split best first while the Bayesian information criterion
//!
//! ```text
//! BIC = n log(RSS / n) + k log(n),   k = leaves (nz + 1) + (leaves - 1)
//! ```
//!
//! decreases, no cell smaller than `min_leaf` samples arises, and at most `max_leaves`
//! leaves exist. The residual sums deciding a split and the leaf coefficients come from
//! Householder QR of the cell's samples (exact least squares); the Gram matrices only rank
//! the candidate positions.

use super::model::{TreeNode, TreePartition};
use super::varpro::{for_each_row, solve_triangular_ls};
use crate::error::{check_matrix_size, Result, SysidError};
use crate::linalg::QrAccumulator;
use crate::narx::regressors::{LagSpec, Record};

/// Options of [`fit_tree`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct TreeOptions {
    /// Largest number of leaves.
    pub max_leaves: usize,
    /// Fewest samples in a leaf (at least `nz + 2`).
    pub min_leaf: usize,
}

impl Default for TreeOptions {
    fn default() -> Self {
        TreeOptions {
            max_leaves: 16,
            min_leaf: 0,
        }
    }
}

impl TreeOptions {
    /// Options with `max_leaves` leaves at most and leaves of `min_leaf` samples at least
    /// (0: `max(10, 3 (nz + 1))`).
    pub fn new(max_leaves: usize, min_leaf: usize) -> Self {
        TreeOptions {
            max_leaves,
            min_leaf,
        }
    }
}

/// The grown tree and how it was grown.
#[derive(Debug, Clone)]
pub struct TreeFit {
    /// The tree.
    pub tree: TreePartition,
    /// Residual sum of squares after each accepted split (the first: one affine model).
    pub rss: Vec<f64>,
    /// Number of regression rows.
    pub n_rows: usize,
    /// Why growing stopped.
    pub stop: &'static str,
}

struct Cell {
    node: usize,
    idx: Vec<usize>,
    sse: f64,
    split: Option<(usize, f64, f64)>, // variable, threshold, exact sse of the two children
}

/// Grows the tree partition of output `output` on the records' standardised regressors;
/// `cancel()` is asked between splits (true stops with the tree so far).
pub fn fit_tree(
    spec: &LagSpec,
    shift: &[f64],
    scale: &[f64],
    records: &[Record<'_>],
    output: usize,
    options: &TreeOptions,
    cancel: &mut dyn FnMut() -> bool,
) -> Result<TreeFit> {
    let n = spec.check_records(records)?;
    let nz = spec.n_vars();
    check_matrix_size("regressors", n, nz + 1)?;
    if shift.len() != nz || scale.len() != nz || output >= spec.n_outputs {
        return Err(SysidError::invalid(
            "shift, scale, output",
            "do not fit the lags",
        ));
    }
    let min_leaf = if options.min_leaf == 0 {
        (3 * (nz + 1)).max(10)
    } else {
        options.min_leaf
    };
    if min_leaf < nz + 2 || options.max_leaves == 0 {
        return Err(SysidError::invalid(
            "min_leaf, max_leaves",
            format!(
                "need min_leaf >= {} (regressors + 2) and max_leaves >= 1",
                nz + 2
            ),
        ));
    }
    let mut data = Vec::with_capacity(n * (nz + 1));
    for_each_row(spec, shift, scale, records, output, |z, y| {
        data.extend_from_slice(z);
        data.push(y);
    })?;
    let yy: f64 = (0..n).map(|i| data[i * (nz + 1) + nz].powi(2)).sum();
    let tiny = 1e-20 * yy.max(f64::MIN_POSITIVE);
    let ctx = Ctx {
        data: &data,
        nz,
        min_leaf,
    };
    let (coefs, sse) = ctx.fit(&(0..n).collect::<Vec<_>>())?;
    let mut nodes = vec![TreeNode {
        var: 0,
        threshold: 0.0,
        children: None,
        coefs,
    }];
    let mut cells = vec![ctx.cell(0, (0..n).collect(), sse)?];
    let bic = |rss: f64, leaves: usize| {
        let k = (leaves * (nz + 1) + leaves - 1) as f64;
        n as f64 * (rss.max(tiny) / n as f64).ln() + k * (n as f64).ln()
    };
    let mut rss = vec![sse];
    let stop = loop {
        if cells.len() >= options.max_leaves {
            break "maximum leaves";
        }
        if cancel() {
            break "cancelled";
        }
        let best = cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.split.map(|s| (i, c.sse - s.2)))
            .max_by(|a, b| a.1.total_cmp(&b.1));
        let Some((i, gain)) = best else {
            break "no admissible split";
        };
        let total = *rss.last().unwrap_or(&0.0);
        if bic(total - gain, cells.len() + 1) >= bic(total, cells.len()) {
            break "information criterion";
        }
        let cell = cells.swap_remove(i);
        let (var, thr, _) = cell.split.expect("chosen for its split");
        let (li, ri): (Vec<usize>, Vec<usize>) = cell
            .idx
            .iter()
            .copied()
            .partition(|&j| data[j * (nz + 1) + var] <= thr);
        let (lc, ls) = ctx.fit(&li)?;
        let (rc, rs) = ctx.fit(&ri)?;
        let (l, r) = (nodes.len(), nodes.len() + 1);
        nodes[cell.node].var = var;
        nodes[cell.node].threshold = thr;
        nodes[cell.node].children = Some((l, r));
        for c in [lc, rc] {
            nodes.push(TreeNode {
                var: 0,
                threshold: 0.0,
                children: None,
                coefs: c,
            });
        }
        cells.push(ctx.cell(l, li, ls)?);
        cells.push(ctx.cell(r, ri, rs)?);
        rss.push(total - cell.sse + ls + rs);
    };
    Ok(TreeFit {
        tree: TreePartition { nodes },
        rss,
        n_rows: n,
        stop,
    })
}

struct Ctx<'a> {
    data: &'a [f64],
    nz: usize,
    min_leaf: usize,
}

impl Ctx<'_> {
    /// Exact least-squares affine fit of the samples `idx`: coefficients and residual sum
    /// of squares.
    fn fit(&self, idx: &[usize]) -> Result<(Vec<f64>, f64)> {
        let nz = self.nz;
        let mut acc = QrAccumulator::new(nz + 2, 256);
        let mut row = vec![0.0; nz + 2];
        for &j in idx {
            row[0] = 1.0;
            row[1..].copy_from_slice(&self.data[j * (nz + 1)..(j + 1) * (nz + 1)]);
            acc.push_row(&row);
        }
        let (c, half) = solve_triangular_ls(&acc.finish(), nz + 1)?;
        Ok((c, 2.0 * half))
    }

    fn cell(&self, node: usize, idx: Vec<usize>, sse: f64) -> Result<Cell> {
        let split = self.best_split(&idx)?;
        Ok(Cell {
            node,
            idx,
            sse,
            split,
        })
    }

    /// The best split of the samples `idx` (variable, threshold, exact children sse).
    fn best_split(&self, idx: &[usize]) -> Result<Option<(usize, f64, f64)>> {
        let (nz, m) = (self.nz, self.nz + 2);
        if idx.len() < 2 * self.min_leaf {
            return Ok(None);
        }
        let d = self.data;
        let mut total = vec![0.0; m * m];
        let mut row = vec![0.0; m];
        let load = |j: usize, row: &mut [f64]| {
            row[0] = 1.0;
            row[1..].copy_from_slice(&d[j * (nz + 1)..(j + 1) * (nz + 1)]);
        };
        for &j in idx {
            load(j, &mut row);
            rank_one(&mut total, &row, 1.0);
        }
        let mut best: Option<(usize, f64, f64)> = None;
        let (mut left, mut right) = (vec![0.0; m * m], vec![0.0; m * m]);
        let mut work = vec![0.0; m * m];
        let mut order = idx.to_vec();
        for v in 0..nz {
            let key = |j: usize| d[j * (nz + 1) + v];
            order.sort_by(|a, b| key(*a).total_cmp(&key(*b)));
            left.iter_mut().for_each(|x| *x = 0.0);
            for pos in 0..order.len() - 1 {
                // Ctrl-C: a scan of a large cell takes seconds
                if pos % 1024 == 0 {
                    crate::interrupt::check()?;
                }
                load(order[pos], &mut row);
                rank_one(&mut left, &row, 1.0);
                let nl = pos + 1;
                let (a, b) = (key(order[pos]), key(order[pos + 1]));
                if nl < self.min_leaf || order.len() - nl < self.min_leaf || a == b {
                    continue;
                }
                for ((r, t), l) in right.iter_mut().zip(&total).zip(&left) {
                    *r = t - l;
                }
                let s = gram_sse(&left, m, &mut work) + gram_sse(&right, m, &mut work);
                if best.is_none_or(|(_, _, bs)| s < bs) {
                    best = Some((v, 0.5 * (a + b), s));
                }
            }
        }
        let Some((v, thr, _)) = best else {
            return Ok(None);
        };
        let (li, ri): (Vec<usize>, Vec<usize>) = idx
            .iter()
            .copied()
            .partition(|&j| d[j * (nz + 1) + v] <= thr);
        let s = self.fit(&li)?.1 + self.fit(&ri)?.1;
        Ok(Some((v, thr, s)))
    }
}

#[inline]
fn rank_one(g: &mut [f64], row: &[f64], w: f64) {
    let m = row.len();
    for a in 0..m {
        let ra = w * row[a];
        for b in 0..=a {
            g[a * m + b] += ra * row[b];
        }
    }
}

/// Residual sum of squares of the least-squares fit whose Gram matrix of `[regressors, y]`
/// is `g` (lower triangle, `m x m`), by Cholesky with a tiny ridge.
fn gram_sse(g: &[f64], m: usize, l: &mut [f64]) -> f64 {
    let q = m - 1;
    let ridge = 1e-12 * (0..q).map(|i| g[i * m + i]).fold(0.0, f64::max);
    l.copy_from_slice(g);
    for i in 0..q {
        l[i * m + i] += ridge;
    }
    // Cholesky of the leading q x q block, extended to the last row: l[q, q]^2 is the sse
    for j in 0..m {
        let mut s = l[j * m + j];
        for k in 0..j {
            s -= l[j * m + k] * l[j * m + k];
        }
        if j == q {
            return s.max(0.0);
        }
        if s <= 0.0 {
            return f64::INFINITY;
        }
        let piv = s.sqrt();
        l[j * m + j] = piv;
        for i in (j + 1)..m {
            let mut t = l[i * m + j];
            for k in 0..j {
                t -= l[i * m + k] * l[j * m + k];
            }
            l[i * m + j] = t / piv;
        }
    }
    0.0
}
