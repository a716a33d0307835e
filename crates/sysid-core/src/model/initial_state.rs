//! Simulation errors with the initial state and per-output offsets fitted by least squares:
//! how a model is scored on a record it did not see (a held-out block, a validation record).
//!
//! Given the outputs `y` and a model's simulation from rest `ys` (both `N x l`), the residual
//! `r = y - ys` is fitted by `Phi(t) x0 + T theta_T`, where `Phi(t) = C A^t` is the free
//! response of the initial state and `T` holds per output a constant (and with `trend` a
//! straight line from -1 to 1); every output's rows are weighed by `1 / std(y_j)`, as the fit
//! % counts them. `Phi` of a block of samples is `M A^t0` with `M = [C; C A; ...]` of one
//! block (no `N l x n` array), and the blocks stop once `A^t0` is below round-off (`1e-17`):
//! a stable model's free response then adds nothing the sums can hold.
//!
//! Two solvers of one least-squares problem. The normal equations, summed block by block,
//! serve well-conditioned problems (column-scaled, their singular values within `1e10` of
//! each other), nearly every candidate. A model with a mode just outside the unit circle has
//! free responses that grow over the record, a regressor of condition 1e8 whose normal
//! equations (1e16) lose the fit (a held-out block scored 78.4 % where the least-squares fit
//! is 85.3 %): those rows are triangularised instead, streamed through the shared
//! [`QrAccumulator`] as `subspace::bd_x0` streams its regression. Either is solved by the
//! pseudo-inverse of its column-scaled matrix (`rtol = 1e-12`, the minimum-norm solution),
//! and the errors are formed in a second pass from the free response of the fitted state.

use crate::denormals::DenormalsAreZero;
use crate::error::{Result, SysidError};
use crate::linalg::{mul_seq, pinv, svd_seq, symmetrize, QrAccumulator};
use crate::optim::dense::symmetric_eigen;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

/// Samples per block of rows.
const BLOCK: usize = 64;
/// Blocks between two checks for Ctrl-C (16 384 samples).
const CHECK_EVERY: usize = 256;
/// The initial state's prior covariance is at least `FLOOR G^-1` in every direction (`G` the
/// weighted free responses' Gram): a direction the input does not drive is shrunk by
/// `FLOOR / (FLOOR + s^2)` of its least-squares value (`s^2` the weighted error variance,
/// the fit's `1 - fit` squared), nothing on noise-free data; basis- and units-free.
const FLOOR: f64 = 1e-6;
/// `A^t` below this (entrywise, `A^0 = I`) ends the free responses: their squares are below
/// round-off of the sums they would add to.
const NEGLIGIBLE: f64 = 1e-17;

/// Per output, `1 / std` of `y` over the record (1 for an output that stands still): the
/// standard deviation of `y / s` times `s`, with `s` a power of two near the output's largest
/// deviation, so that squares of very small or very large outputs neither underflow nor
/// overflow.
fn weights(y: MatRef<'_, f64>) -> Vec<f64> {
    let count = y.nrows() as f64;
    (0..y.ncols())
        .map(|j| {
            let col = y.col(j);
            let mean = col.iter().sum::<f64>() / count;
            let spread = col.iter().fold(0.0_f64, |m, &v| m.max((v - mean).abs()));
            let unit = if spread > 0.0 && spread.is_finite() {
                2f64.powi(spread.log2().floor() as i32 + 1)
            } else {
                1.0
            };
            let scaled_mean = col.iter().map(|&v| v / unit).sum::<f64>() / count;
            let var = col
                .iter()
                .map(|&v| (v / unit - scaled_mean).powi(2))
                .sum::<f64>()
                / count;
            let sd = var.sqrt() * unit;
            if sd > 0.0 {
                1.0 / sd
            } else {
                1.0
            }
        })
        .collect()
}

/// The simulation errors `y - ys` with the initial state (`x0` of `x(t+1) = A x`, seen
/// through `C`) and a constant per output (with `trend`, a constant and a slope) fitted by
/// weighted least squares; `None` when the simulation or the free responses are not finite
/// (a model that diverges on these data).
///
/// With `prior = Some(P)` (`n x n`, the covariance of the states the model's input drives),
/// the initial state is `x0 ~ N(0, P + FLOOR G^-1)` a priori: the fit minimises the weighted
/// squared errors plus `s^2 x0' (P + FLOOR G^-1)^-1 x0`, `s^2` the weighted error variance of
/// the fit without the prior (its residual degrees of freedom `N l - n - q`). A held-out
/// block then cannot spend its initial state on directions the model's input does not drive:
/// a mode with no input gain fits the block's noise only as far as the data outweigh the
/// prior. Without residual degrees of freedom the prior is not used.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::model::initial_state::fitted_errors;
/// let (a, c) = (mat![[0.5]], mat![[1.0]]);
/// // the output is the free response from x0 = 2 plus an offset of 3
/// let y = Mat::from_fn(20, 1, |t, _| 2.0 * 0.5f64.powi(t as i32) + 3.0);
/// let e = fitted_errors(a.as_ref(), c.as_ref(), y.as_ref(), Mat::zeros(20, 1).as_ref(), false, None)
///     .unwrap()
///     .unwrap();
/// assert!(e.col(0).iter().all(|v| v.abs() < 1e-12));
/// // noise-free: the prior changes nothing
/// let wide = mat![[10.0]];
/// let e = fitted_errors(a.as_ref(), c.as_ref(), y.as_ref(), Mat::zeros(20, 1).as_ref(), false,
///     Some(wide.as_ref())).unwrap().unwrap();
/// assert!(e.col(0).iter().all(|v| v.abs() < 1e-10));
/// ```
pub fn fitted_errors(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    ys: MatRef<'_, f64>,
    trend: bool,
    prior: Option<MatRef<'_, f64>>,
) -> Result<Option<Mat<f64>>> {
    let (count, l, n) = (y.nrows(), y.ncols(), a.nrows());
    if let Some(cov) = prior {
        if cov.nrows() != n || cov.ncols() != n {
            return Err(SysidError::ShapeMismatch {
                what: "the initial state's prior covariance".into(),
                got: format!("{}x{}", cov.nrows(), cov.ncols()),
                expected: format!("{n}x{n}"),
            });
        }
    }
    if a.ncols() != n || c.nrows() != l || c.ncols() != n {
        return Err(SysidError::ShapeMismatch {
            what: "A and C".into(),
            got: format!(
                "{}x{} and {}x{}",
                a.nrows(),
                a.ncols(),
                c.nrows(),
                c.ncols()
            ),
            expected: format!("{n}x{n} and {l}x{n}"),
        });
    }
    if ys.nrows() != count || ys.ncols() != l {
        return Err(SysidError::ShapeMismatch {
            what: "the simulated outputs".into(),
            got: format!("{}x{}", ys.nrows(), ys.ncols()),
            expected: format!("{count}x{l}"),
        });
    }
    if count == 0 {
        return Ok(Some(Mat::zeros(0, l)));
    }
    let r = Mat::from_fn(count, l, |t, j| y[(t, j)] - ys[(t, j)]);
    if r.col_iter().any(|col| col.iter().any(|v| !v.is_finite())) {
        return Ok(None);
    }
    let lines = Lines {
        tcols: if trend { 2 } else { 1 },
        count,
    };
    let w = weights(y);
    let free = FreeResponses::new(a, c);
    // subnormal operands read as zero in the block products only (crate::denormals), not
    // in the decompositions below
    let daz = DenormalsAreZero::new();
    let g = normal_equations(&free, &r, &w, &lines)?;
    drop(daz);
    let Some(g) = g else {
        return Ok(None);
    };
    if g.col_iter().any(|col| col.iter().any(|v| !v.is_finite())) {
        // free responses beyond 1e154 whose squares overflow: a model that diverges here
        return Ok(None);
    }
    let theta = match solve_normal(&g)? {
        Some(theta) => match prior {
            Some(cov) if n > 0 => {
                // the residual sum of squares of the least-squares solution: r'r - theta' X'r
                let p = g.ncols() - 1;
                let rss = g[(p, p)] - (0..p).map(|i| theta[i] * g[(i, p)]).sum::<f64>();
                with_prior(&g, rss, cov, count * l)?.unwrap_or(theta)
            }
            _ => theta,
        },
        None => {
            let Some(tri) = triangle(&free, &r, &w, &lines)? else {
                return Ok(None);
            };
            let theta = solve(&tri)?;
            match prior {
                Some(cov) if n > 0 => {
                    // the triangle's last diagonal entry is the residual norm; the prior
                    // makes the penalised equations well conditioned
                    let p = tri.ncols() - 1;
                    let rss = tri[(p, p)] * tri[(p, p)];
                    let g = mul_seq(tri.transpose(), tri.as_ref());
                    with_prior(&g, rss, cov, count * l)?.unwrap_or(theta)
                }
                _ => theta,
            }
        }
    };
    let q = lines.tcols * l;
    let mut e = r;
    for t in 0..count {
        for j in 0..l {
            e[(t, j)] -= (0..lines.tcols)
                .map(|k| lines.at(t, k) * theta[n + k * l + j])
                .sum::<f64>();
        }
    }
    debug_assert_eq!(theta.len(), n + q);
    // minus the free response of the fitted initial state, until it is below round-off
    let mut z: Vec<f64> = theta[..n].to_vec();
    let start = z.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut next = vec![0.0; n];
    for t in 0..count {
        if z.iter().all(|v| v.abs() <= NEGLIGIBLE * start) {
            break;
        }
        for j in 0..l {
            e[(t, j)] -= (0..n).map(|i| c[(j, i)] * z[i]).sum::<f64>();
        }
        for (i, v) in next.iter_mut().enumerate() {
            *v = (0..n).map(|k| a[(i, k)] * z[k]).sum();
        }
        std::mem::swap(&mut z, &mut next);
    }
    Ok(Some(e))
}

/// The offset (and line) columns: `T[t, 0] = 1`, `T[t, 1] = -1 + 2 t / (N - 1)`.
struct Lines {
    tcols: usize,
    count: usize,
}

impl Lines {
    fn at(&self, t: usize, k: usize) -> f64 {
        if k == 0 {
            1.0
        } else if self.count > 1 {
            -1.0 + 2.0 * t as f64 / (self.count - 1) as f64
        } else {
            -1.0
        }
    }
}

/// The free responses `Phi(t) = C A^t`, block by block of samples.
struct FreeResponses<'a> {
    a: MatRef<'a, f64>,
    /// Rows `(t, j)` of `C A^t` for `t < BLOCK`.
    m: Mat<f64>,
    /// `A^BLOCK`.
    step: Mat<f64>,
}

impl<'a> FreeResponses<'a> {
    fn new(a: MatRef<'a, f64>, c: MatRef<'a, f64>) -> Self {
        let (n, l) = (a.nrows(), c.nrows());
        let mut m = Mat::<f64>::zeros(BLOCK * l, n);
        m.as_mut().subrows_mut(0, l).copy_from(c);
        for t in 1..BLOCK {
            let next = mul_seq(m.as_ref().subrows((t - 1) * l, l), a);
            m.as_mut().subrows_mut(t * l, l).copy_from(next.as_ref());
        }
        let mut step = a.to_owned();
        let mut k = 1;
        while k < BLOCK {
            step = mul_seq(step.as_ref(), step.as_ref());
            k *= 2;
        }
        Self { a, m, step }
    }

    /// Calls `visit(t0, phi)` for each block from the start (`phi`: rows `(t, j)` of the
    /// block's `len` samples) until the record ends or `A^t0` is below round-off; the sample
    /// where they stopped, `None` when a free response is not finite.
    fn each(
        &self,
        count: usize,
        mut visit: impl FnMut(usize, MatRef<'_, f64>),
    ) -> Result<Option<usize>> {
        let n = self.a.nrows();
        let l = self.m.nrows() / BLOCK;
        if n == 0 {
            return Ok(Some(0));
        }
        let mut power = Mat::<f64>::identity(n, n);
        let mut phi = Mat::<f64>::zeros(BLOCK * l, n);
        let mut t0 = 0;
        while t0 < count {
            let rows = BLOCK.min(count - t0) * l;
            matmul(
                phi.as_mut().subrows_mut(0, rows),
                Accum::Replace,
                self.m.as_ref().subrows(0, rows),
                power.as_ref(),
                1.0,
                Par::Seq,
            );
            let block = phi.as_ref().subrows(0, rows);
            if block
                .col_iter()
                .any(|col| col.iter().any(|v| !v.is_finite()))
            {
                return Ok(None);
            }
            visit(t0, block);
            if (t0 / BLOCK) % CHECK_EVERY == CHECK_EVERY - 1 {
                crate::interrupt::check()?; // Ctrl-C within a long record
            }
            t0 += rows / l;
            if t0 >= count {
                break;
            }
            power = mul_seq(power.as_ref(), self.step.as_ref());
            let big = power.col_iter().fold(0.0_f64, |mx, col| {
                col.iter().fold(mx, |m, v| m.max(v.abs()))
            });
            if !big.is_finite() {
                return Ok(None);
            }
            if big < NEGLIGIBLE {
                break;
            }
        }
        Ok(Some(t0))
    }
}

/// The normal equations `[X r]^T [X r]` (`p x p`, `p = n + q + 1`) of the weighted rows
/// `[Phi(t) | T(t) | r(t)]` (columns: initial state, offsets and lines, residual); `None`
/// when a free response is not finite.
fn normal_equations(
    free: &FreeResponses<'_>,
    r: &Mat<f64>,
    w: &[f64],
    lines: &Lines,
) -> Result<Option<Mat<f64>>> {
    let (count, l, n) = (r.nrows(), r.ncols(), free.a.nrows());
    let q = lines.tcols * l;
    let p = n + q + 1;
    let mut g = Mat::<f64>::zeros(p, p);
    // the offsets', lines' and residual's sums over the whole record
    for j in 0..l {
        let w2 = w[j] * w[j];
        for ka in 0..lines.tcols {
            for kb in 0..lines.tcols {
                g[(n + ka * l + j, n + kb * l + j)] = w2
                    * (0..count)
                        .map(|t| lines.at(t, ka) * lines.at(t, kb))
                        .sum::<f64>();
            }
            g[(n + ka * l + j, p - 1)] =
                w2 * (0..count).map(|t| lines.at(t, ka) * r[(t, j)]).sum::<f64>();
        }
        g[(p - 1, p - 1)] += w2 * (0..count).map(|t| r[(t, j)] * r[(t, j)]).sum::<f64>();
    }
    // the initial state's rows and columns over the blocks where the free responses live
    let mut scaled = Mat::<f64>::zeros(BLOCK * l, n);
    let mut gxx = Mat::<f64>::zeros(n, n);
    let alive = free.each(count, |t0, phi| {
        let rows = phi.nrows();
        for row in 0..rows {
            let (t, j) = (t0 + row / l, row % l);
            for i in 0..n {
                let v = w[j] * phi[(row, i)];
                scaled[(row, i)] = v;
                for k in 0..lines.tcols {
                    g[(i, n + k * l + j)] += v * w[j] * lines.at(t, k);
                }
                g[(i, p - 1)] += v * w[j] * r[(t, j)];
            }
        }
        let sb = scaled.as_ref().subrows(0, rows);
        matmul(gxx.as_mut(), Accum::Add, sb.transpose(), sb, 1.0, Par::Seq);
    })?;
    if alive.is_none() {
        return Ok(None);
    }
    g.as_mut().submatrix_mut(0, 0, n, n).copy_from(gxx.as_ref());
    for i in 0..p {
        for k in 0..i {
            g[(i, k)] = g[(k, i)];
        }
    }
    Ok(Some(g))
}

/// The solution of the normal equations `g` (initial state first, `n` columns) with the
/// prior `x0 ~ N(0, Pi)`, `Pi = P + FLOOR G^-1` (`G` the initial state's block of `g`), the
/// penalty `s^2 x0' Pi^-1 x0` added ([`fitted_errors`]); `s^2` from `rss`, the residual sum of
/// squares without it. `Pi^-1 = G^(1/2) (G^(1/2) P G^(1/2) + FLOOR I)^-1 G^(1/2)` (on the state
/// scaled to unit free-response norms) needs no inverse of `G` or `P` (either may be
/// singular: a state the outputs do not see, a direction the input does not drive).
/// `None` without residual degrees of freedom (`rows` weighted rows in all) or when the
/// penalised equations cannot be solved.
fn with_prior(
    g: &Mat<f64>,
    rss: f64,
    cov: MatRef<'_, f64>,
    rows: usize,
) -> Result<Option<Vec<f64>>> {
    let p = g.ncols() - 1; // unknowns: n initial-state entries, then the lines
    let n = cov.nrows();
    if rows <= p || cov.ncols() != n {
        return Ok(None);
    }
    let s2 = rss.max(0.0) / (rows - p) as f64;
    if !s2.is_finite() || cov.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Ok(None);
    }
    // on the state scaled to unit free-response norms (x^ = D x), with S = G^^(1/2):
    // Pi^^-1 = S (S P^ S + FLOOR I)^-1 S, whose middle factor has eigenvalues >= FLOOR
    let d = column_norms(g, n);
    let gs = Mat::from_fn(n, n, |i, k| g[(i, k)] / (d[i] * d[k]));
    let (v, lam) = symmetric_eigen(&gs, "initial-state prior (free responses)")?;
    let root = Mat::from_fn(n, n, |i, k| {
        (0..n)
            .map(|j| v[(i, j)] * lam[j].max(0.0).sqrt() * v[(k, j)])
            .sum::<f64>()
    });
    let ps = Mat::from_fn(n, n, |i, k| cov[(i, k)] * d[i] * d[k]);
    let mut mid = mul_seq(mul_seq(root.as_ref(), ps.as_ref()).as_ref(), root.as_ref());
    symmetrize(&mut mid);
    for i in 0..n {
        mid[(i, i)] += FLOOR;
    }
    let (w, gam) = symmetric_eigen(&mid, "initial-state prior (penalty)")?;
    if gam
        .iter()
        .any(|&x| x.is_nan() || x <= 0.0 || !x.is_finite())
    {
        return Ok(None);
    }
    let inv = Mat::from_fn(n, n, |i, k| {
        (0..n).map(|j| w[(i, j)] * w[(k, j)] / gam[j]).sum::<f64>()
    });
    let hat = mul_seq(mul_seq(root.as_ref(), inv.as_ref()).as_ref(), root.as_ref());
    let mut penalty = Mat::from_fn(n, n, |i, k| hat[(i, k)] * d[i] * d[k]);
    symmetrize(&mut penalty);
    let mut g2 = g.clone();
    for i in 0..n {
        for k in 0..n {
            g2[(i, k)] += s2 * penalty[(i, k)];
        }
    }
    if g2.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
        return Ok(None);
    }
    solve_normal(&g2)
}

/// The norms of the first `count` columns behind the normal equations `g` (the square roots
/// of its diagonal), 1 for a zero or non-finite one: the column scaling of the solvers.
fn column_norms(g: &Mat<f64>, count: usize) -> Vec<f64> {
    (0..count)
        .map(|k| {
            let s = g[(k, k)].max(0.0).sqrt();
            if s > 0.0 && s.is_finite() {
                s
            } else {
                1.0
            }
        })
        .collect()
}

/// The minimum-norm solution of the normal equations' leading block against their last
/// column, columns scaled to unit norm first (free responses of slow and fast modes differ
/// by orders of magnitude) and singular values below `1e-12` of the largest dropped; `None`
/// when the scaled matrix is too ill-conditioned for normal equations (its singular values
/// spread by more than `1e10`: the regressor's by more than `1e5`).
fn solve_normal(g: &Mat<f64>) -> Result<Option<Vec<f64>>> {
    let p = g.ncols() - 1;
    let scale = column_norms(g, p);
    let gs = Mat::from_fn(p, p, |i, k| g[(i, k)] / (scale[i] * scale[k]));
    if p > 0 {
        let (sv, _, _) = svd_seq("initial-state fit (SVD)", gs.as_ref(), false, false)?;
        if sv[p - 1] < 1e-10 * sv[0] {
            return Ok(None);
        }
    }
    let rhs = Mat::from_fn(p, 1, |i, _| g[(i, p)] / scale[i]);
    let theta = mul_seq(pinv(gs.as_ref(), 1e-12)?.as_ref(), rhs.as_ref());
    Ok(Some((0..p).map(|k| theta[(k, 0)] / scale[k]).collect()))
}

/// The triangle `R` (`p x p`, `p = n + q + 1`) of the weighted rows `[Phi(t) | T(t) | r(t)]`
/// (the rows of [`normal_equations`]) through the shared [`QrAccumulator`]; `None` when a
/// free response is not finite. Past the free responses' end their columns are zero.
fn triangle(
    free: &FreeResponses<'_>,
    r: &Mat<f64>,
    w: &[f64],
    lines: &Lines,
) -> Result<Option<Mat<f64>>> {
    let (count, l, n) = (r.nrows(), r.ncols(), free.a.nrows());
    let q = lines.tcols * l;
    let p = n + q + 1;
    let mut acc = QrAccumulator::new(p, (8 * p).max(256));
    let mut row = vec![0.0; p];
    let push = |acc: &mut QrAccumulator, row: &mut [f64], t: usize, j: usize| {
        for k in 0..lines.tcols {
            row[n + k * l + j] = w[j] * lines.at(t, k);
        }
        row[p - 1] = w[j] * r[(t, j)];
        acc.push_row(row);
    };
    let alive = free.each(count, |t0, phi| {
        for k in 0..phi.nrows() {
            let (t, j) = (t0 + k / l, k % l);
            row.iter_mut().for_each(|v| *v = 0.0);
            for i in 0..n {
                row[i] = w[j] * phi[(k, i)];
            }
            push(&mut acc, &mut row, t, j);
        }
    })?;
    let Some(alive) = alive else {
        return Ok(None);
    };
    for t in alive..count {
        if t % (CHECK_EVERY * BLOCK) == 0 {
            crate::interrupt::check()?;
        }
        for j in 0..l {
            row.iter_mut().for_each(|v| *v = 0.0);
            push(&mut acc, &mut row, t, j);
        }
    }
    Ok(Some(acc.finish()))
}

/// The minimum-norm least-squares solution of the triangle's leading block against its
/// last column, columns scaled to unit norm first (free responses of slow and fast modes
/// differ by orders of magnitude) and singular values below `1e-12` of the largest dropped.
fn solve(tri: &Mat<f64>) -> Result<Vec<f64>> {
    let p = tri.ncols() - 1;
    let scale: Vec<f64> = (0..p)
        .map(|k| {
            let s = (0..=k)
                .map(|i| tri[(i, k)] * tri[(i, k)])
                .sum::<f64>()
                .sqrt();
            if s > 0.0 && s.is_finite() {
                s
            } else {
                1.0
            }
        })
        .collect();
    let rs = Mat::from_fn(p, p, |i, k| tri[(i, k)] / scale[k]);
    let rhs = Mat::from_fn(p, 1, |i, _| tri[(i, p)]);
    let theta = mul_seq(pinv(rs.as_ref(), 1e-12)?.as_ref(), rhs.as_ref());
    Ok((0..p).map(|k| theta[(k, 0)] / scale[k]).collect())
}
