//! Prediction-error providers for single-output polynomial structures (ARX, ARMAX, OE, BJ,
//! AR, ARMA), started from linear estimates and refined by [`crate::optim::minimize`].

use faer::{Mat, MatRef};

use super::filter::{conv, filter, is_stable, monic};
use crate::error::{check_io, Result, SysidError};
use crate::linalg::QrAccumulator;
use crate::optim::{minimize, Evaluation, Flow, Iteration, Options, Problem, Solution, StopReason};

/// Orders of `A y = sum B_j/F_j u_j(t-nk_j) + C/D e` for one output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MisoOrders {
    /// Order of A.
    pub na: usize,
    /// Coefficients of each B_j.
    pub nb: Vec<usize>,
    /// Order of C.
    pub nc: usize,
    /// Order of D.
    pub nd: usize,
    /// Order of each F_j.
    pub nf: Vec<usize>,
    /// Delay of each input.
    pub nk: Vec<usize>,
}

impl MisoOrders {
    /// Number of free parameters, laid out `[a, b_1.., b_m, c, d, f_1.., f_m]`.
    pub fn n_params(&self) -> usize {
        // saturating: absurd orders give usize::MAX, which every length check then refuses
        [self.na, self.nc, self.nd]
            .into_iter()
            .chain(self.nb.iter().copied())
            .chain(self.nf.iter().copied())
            .fold(0usize, |a, b| a.saturating_add(b))
    }
}

/// The polynomials of one output, split out of a parameter vector.
#[derive(Debug, Clone, PartialEq)]
pub struct MisoPolys {
    /// Monic A.
    pub a: Vec<f64>,
    /// B_j (b_0 first; applied to u_j(t - nk_j)).
    pub b: Vec<Vec<f64>>,
    /// Monic C.
    pub c: Vec<f64>,
    /// Monic D.
    pub d: Vec<f64>,
    /// Monic F_j.
    pub f: Vec<Vec<f64>>,
}

impl MisoOrders {
    /// Splits `theta` into polynomials.
    pub fn polys(&self, theta: &[f64]) -> MisoPolys {
        let mut i = 0;
        let mut take = |n: usize| {
            let s = theta[i..i + n].to_vec();
            i += n;
            s
        };
        let a = monic(&take(self.na));
        let b: Vec<Vec<f64>> = self.nb.iter().map(|&n| take(n)).collect();
        let c = monic(&take(self.nc));
        let d = monic(&take(self.nd));
        let f: Vec<Vec<f64>> = self.nf.iter().map(|&n| monic(&take(n))).collect();
        MisoPolys { a, b, c, d, f }
    }
}

/// A signal of several experiments: one vector per experiment.
type Sig = Vec<Vec<f64>>;

/// Residual `e`, equation error `v` and filtered inputs `w_j` of one experiment.
type Signals = (Vec<f64>, Vec<f64>, Vec<Vec<f64>>);

/// One experiment of a [`MisoProblem`]: the output and the delayed inputs.
struct Segment {
    y: Vec<f64>,
    x: Vec<Vec<f64>>,
}

/// Prediction-error problem of one output: residual `e = D/C (A y - sum B_j/F_j x_j)`,
/// `x_j(t) = u_j(t - nk_j)`, zero initial conditions. With several experiments the cost,
/// gradient and Gauss-Newton matrix are sums over the experiments, each filtered from rest
/// (no sample of one experiment enters a regressor of another).
pub struct MisoProblem {
    orders: MisoOrders,
    segs: Vec<Segment>,
    block: usize,
}

fn delayed(u: MatRef<'_, f64>, j: usize, nk: usize) -> Vec<f64> {
    let n = u.nrows();
    (0..n)
        .map(|t| if t >= nk { u[(t - nk, j)] } else { 0.0 })
        .collect()
}

fn shifted(s: &[f64], t: usize, k: usize) -> f64 {
    if t >= k {
        s[t - k]
    } else {
        0.0
    }
}

/// Checks one output's experiments against `orders`; returns the total sample count.
fn check_experiments(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    orders: &MisoOrders,
) -> Result<usize> {
    let Some(first) = experiments.first() else {
        return Err(SysidError::invalid(
            "experiments",
            "needs at least one (y, u) record",
        ));
    };
    let m = first.1.ncols();
    if orders.nb.len() != m || orders.nf.len() != m || orders.nk.len() != m {
        return Err(SysidError::invalid(
            "orders",
            format!("nb, nf and nk need one entry per input ({m})"),
        ));
    }
    for (y, u) in experiments {
        let yv = MatRef::from_column_major_slice(y, y.len(), 1);
        check_io("u, y", *u, yv, m, 1)?;
    }
    let p = orders.n_params();
    if p == 0 {
        return Err(SysidError::invalid(
            "orders",
            "the structure has no parameters",
        ));
    }
    let total: usize = experiments.iter().map(|e| e.0.len()).sum();
    let longest = experiments.iter().map(|e| e.0.len()).max().unwrap_or(0);
    let need = p.saturating_mul(2).saturating_add(2);
    if total < need || orders.nk.iter().any(|&k| k >= longest) {
        return Err(SysidError::InsufficientData {
            context: format!(
                "a polynomial model with {p} parameters and delays nk={:?}",
                orders.nk
            ),
            needed: need.max(orders.nk.iter().max().map_or(0, |k| k.saturating_add(1))),
            got: total,
            fix: "use a longer record or smaller orders",
        });
    }
    Ok(total)
}

impl MisoProblem {
    /// Output column `y` (length N) and inputs `u` (N x m).
    pub fn new(y: &[f64], u: MatRef<'_, f64>, orders: MisoOrders) -> Result<Self> {
        Self::new_multi(&[(y, u)], orders)
    }

    /// Several experiments `(y, u)` of the same output and inputs (lengths may differ).
    pub fn new_multi(
        experiments: &[(&[f64], MatRef<'_, f64>)],
        orders: MisoOrders,
    ) -> Result<Self> {
        check_experiments(experiments, &orders)?;
        let segs = experiments
            .iter()
            .map(|(y, u)| Segment {
                y: y.to_vec(),
                x: (0..u.ncols())
                    .map(|j| delayed(*u, j, orders.nk[j]))
                    .collect(),
            })
            .collect();
        Ok(Self {
            orders,
            segs,
            block: 128,
        })
    }

    /// Residuals and the intermediate signals `(e, v, w_j)` of one experiment.
    fn signals(seg: &Segment, p: &MisoPolys) -> Signals {
        let w: Vec<Vec<f64>> = (0..seg.x.len())
            .map(|j| filter(&p.b[j], &p.f[j], &seg.x[j]))
            .collect();
        let mut v = filter(&p.a, &[1.0], &seg.y);
        for wj in &w {
            for (vt, wt) in v.iter_mut().zip(wj) {
                *vt -= wt;
            }
        }
        let e = filter(&p.d, &p.c, &v);
        (e, v, w)
    }

    /// Residuals at `theta`, experiment after experiment (each from rest).
    pub fn residuals(&self, theta: &[f64]) -> Vec<f64> {
        let p = self.orders.polys(theta);
        self.segs
            .iter()
            .flat_map(|s| Self::signals(s, &p).0)
            .collect()
    }

    /// Adds one experiment's `J^T J` and `J^T e` (blocks of `self.block` rows) to `gn`, `grad`.
    fn accumulate(
        &self,
        seg: &Segment,
        p: &MisoPolys,
        signals: &Signals,
        gn: &mut Mat<f64>,
        grad: &mut [f64],
    ) {
        let (e, v, w) = signals;
        let o = &self.orders;
        let np = o.n_params();
        let n = seg.y.len();
        let nx = seg.x.len();
        let ya = filter(&p.d, &p.c, &seg.y);
        let cf: Vec<Vec<f64>> = p.f.iter().map(|f| conv(&p.c, f)).collect();
        let xf: Vec<Vec<f64>> = (0..nx).map(|j| filter(&p.d, &cf[j], &seg.x[j])).collect();
        let wf: Vec<Vec<f64>> = (0..nx)
            .map(|j| {
                if o.nf[j] > 0 {
                    filter(&p.d, &cf[j], &w[j])
                } else {
                    Vec::new()
                }
            })
            .collect();
        let ec = if o.nc > 0 {
            filter(&[1.0], &p.c, e)
        } else {
            Vec::new()
        };
        let vc = if o.nd > 0 {
            filter(&[1.0], &p.c, v)
        } else {
            Vec::new()
        };
        let mut jb = Mat::<f64>::zeros(self.block, np);
        let mut eb = Mat::<f64>::zeros(self.block, 1);
        let mut t0 = 0;
        while t0 < n {
            let rows = self.block.min(n - t0);
            for r in 0..rows {
                let t = t0 + r;
                let mut c = 0;
                for k in 1..=o.na {
                    jb[(r, c)] = shifted(&ya, t, k);
                    c += 1;
                }
                for j in 0..nx {
                    for k in 0..o.nb[j] {
                        jb[(r, c)] = -shifted(&xf[j], t, k);
                        c += 1;
                    }
                }
                for k in 1..=o.nc {
                    jb[(r, c)] = -shifted(&ec, t, k);
                    c += 1;
                }
                for k in 1..=o.nd {
                    jb[(r, c)] = shifted(&vc, t, k);
                    c += 1;
                }
                for j in 0..nx {
                    for k in 1..=o.nf[j] {
                        jb[(r, c)] = shifted(&wf[j], t, k);
                        c += 1;
                    }
                }
                eb[(r, 0)] = e[t];
            }
            let jr = jb.as_ref().subrows(0, rows);
            *gn += jr.transpose() * jr;
            let g = jr.transpose() * eb.as_ref().subrows(0, rows);
            for a in 0..np {
                grad[a] += g[(a, 0)];
            }
            t0 += rows;
        }
    }
}

impl Problem for MisoProblem {
    fn n_params(&self) -> usize {
        self.orders.n_params()
    }

    /// Every sample of every experiment is one residual of the cost `0.5 sum e^2` (for the
    /// distance from the minimum at a cap; this search has no statistical stop).
    fn n_residuals(&self) -> Option<usize> {
        Some(self.segs.iter().map(|s| s.y.len()).sum())
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        let p = self.orders.polys(theta);
        is_stable(&p.c) && p.f.iter().all(|f| is_stable(f))
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let o = &self.orders;
        let p = o.polys(theta);
        let sigs: Vec<_> = self.segs.iter().map(|s| Self::signals(s, &p)).collect();
        let cost = 0.5
            * sigs
                .iter()
                .map(|(e, _, _)| e.iter().map(|x| x * x).sum::<f64>())
                .sum::<f64>();
        if !cost.is_finite() {
            return Ok(Evaluation::cost_only(f64::INFINITY));
        }
        let mut ev = Evaluation::cost_only(cost);
        if !jacobian {
            return Ok(ev);
        }
        let np = o.n_params();
        let mut gn = Mat::<f64>::zeros(np, np);
        let mut grad = vec![0.0; np];
        for (seg, sig) in self.segs.iter().zip(&sigs) {
            self.accumulate(seg, &p, sig, &mut gn, &mut grad);
        }
        ev.gradient = grad;
        ev.gauss_newton = gn;
        Ok(ev)
    }
}

fn fmap(b: &[f64], a: &[f64], s: &Sig) -> Sig {
    s.iter().map(|x| filter(b, a, x)).collect()
}

/// Least squares of `target` on lagged signals: `regs` lists `(signal, first_lag, n_lags)`;
/// rows `t >= max(first_lag + n_lags)` of every experiment.
fn lagged_ls(target: &Sig, regs: &[(&Sig, usize, usize)]) -> Result<Vec<f64>> {
    let p: usize = regs.iter().map(|r| r.2).sum();
    if p == 0 {
        return Ok(Vec::new());
    }
    let start = regs.iter().map(|r| r.1 + r.2).max().unwrap_or(0);
    let mut acc = QrAccumulator::new(p + 1, 256);
    let mut row = vec![0.0; p + 1];
    for (ex, tgt) in target.iter().enumerate() {
        for t in start..tgt.len() {
            if t % 4096 == 0 {
                crate::interrupt::check()?; // Ctrl-C
            }
            let mut c = 0;
            for (s, first, nl) in regs {
                for k in *first..*first + *nl {
                    row[c] = s[ex][t - k];
                    c += 1;
                }
            }
            row[p] = tgt[t];
            acc.push_row(&row);
        }
    }
    let r = acc.finish();
    let dmax = (0..p).map(|d| r[(d, d)]).fold(0.0, f64::max);
    let mut th = vec![0.0; p];
    for d in (0..p).rev() {
        if r[(d, d)] <= 1e-13 * dmax {
            th[d] = 0.0;
            continue;
        }
        let mut v = r[(d, p)];
        for e in d + 1..p {
            v -= r[(d, e)] * th[e];
        }
        th[d] = v / r[(d, d)];
    }
    Ok(th)
}

/// Steiglitz-McBride for a single-input output-error model: returns `(b, f)`.
pub fn steiglitz_mcbride(
    y: &[f64],
    x: &[f64],
    nb: usize,
    nf: usize,
    iters: usize,
) -> Result<(Vec<f64>, Vec<f64>)> {
    steiglitz_mcbride_multi(&vec![y.to_vec()], &vec![x.to_vec()], nb, nf, iters)
}

/// [`steiglitz_mcbride`] over several experiments (each filtered from rest).
fn steiglitz_mcbride_multi(
    y: &Sig,
    x: &Sig,
    nb: usize,
    nf: usize,
    iters: usize,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut f = vec![0.0; nf];
    // The iterations need not converge (on a dryer record they cycle with period 6, the
    // last iterate just outside the unit circle): the start is the stable iterate whose
    // simulation fits best, not the last one.
    let mut best: Option<(f64, Vec<f64>, Vec<f64>)> = None;
    for _ in 0..iters.max(1) {
        let fp = monic(&f);
        let (yf, xf) = if is_stable(&fp) {
            (fmap(&[1.0], &fp, y), fmap(&[1.0], &fp, x))
        } else {
            (y.clone(), x.clone())
        };
        let th = lagged_ls(&yf, &[(&yf, 1, nf), (&xf, 0, nb)])?;
        let fnew: Vec<f64> = th[..nf].iter().map(|v| -v).collect();
        let bnew = th[nf..].to_vec();
        let change: f64 = fnew.iter().zip(&f).map(|(a, c)| (a - c).abs()).sum();
        let fm = monic(&fnew);
        if is_stable(&fm) {
            let sim = fmap(&bnew, &fm, x);
            let cost: f64 = y
                .iter()
                .zip(&sim)
                .map(|(ye, se)| {
                    ye.iter()
                        .zip(se)
                        .map(|(a, c)| (a - c) * (a - c))
                        .sum::<f64>()
                })
                .sum();
            if cost.is_finite() && best.as_ref().is_none_or(|(c, _, _)| cost < *c) {
                best = Some((cost, bnew.clone(), fnew.clone()));
            }
        }
        f = fnew;
        if change < 1e-12 {
            break;
        }
    }
    match best {
        Some((_, b, f)) => Ok((b, f)),
        None => {
            // no stable iterate: a finite impulse response (F = 1) by least squares
            let th = lagged_ls(y, &[(x, 0, nb)])?;
            Ok((th, vec![0.0; nf]))
        }
    }
}

fn stable_or_zero(c: Vec<f64>) -> Vec<f64> {
    if is_stable(&monic(&c)) {
        c
    } else {
        vec![0.0; c.len()]
    }
}

/// Sweeps of Gauss-Seidel over the inputs of a several-input output-error part: each input's
/// `B_j / F_j` by Steiglitz-McBride on what the other inputs' current parts leave of the
/// target (whose `F` stays stable), `GS_SWEEPS` times. The least-squares impulse responses
/// with `F = 1` (`b`, `f`) start it, and are returned instead when the sweeps do not lower the
/// simulation error: from `F = 1` the search settled in poor local minima on real
/// several-input records (four times the cost of an ARX-started search on a steam
/// generator, a pole of `F` on the unit circle on an industrial dryer).
fn gauss_seidel_start(
    target: &Sig,
    x: &[Sig],
    o: &MisoOrders,
    b: Vec<Vec<f64>>,
    f: Vec<Vec<f64>>,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let cost = |b: &[Vec<f64>], f: &[Vec<f64>]| -> f64 {
        minus_filtered(target, x, b, f)
            .iter()
            .map(|e| e.iter().map(|v| v * v).sum::<f64>())
            .sum()
    };
    let start = cost(&b, &f);
    let (mut b2, mut f2) = (b.clone(), f.clone());
    for _ in 0..GS_SWEEPS {
        for j in 0..x.len() {
            let mut others = b2.clone();
            others[j] = vec![0.0; o.nb[j]];
            let rest = minus_filtered(target, x, &others, &f2);
            match steiglitz_mcbride_multi(&rest, &x[j], o.nb[j], o.nf[j], 30) {
                Ok((bj, fj)) => {
                    b2[j] = bj;
                    f2[j] = fj;
                }
                Err(_) => return (b, f),
            }
        }
    }
    let swept = cost(&b2, &f2);
    if swept.is_finite() && swept < start && f2.iter().all(|fj| is_stable(&monic(fj))) {
        (b2, f2)
    } else {
        (b, f)
    }
}

/// Gauss-Seidel sweeps over the inputs of [`gauss_seidel_start`].
const GS_SWEEPS: usize = 3;

/// `target - sum_j B_j/F_j x_j` per experiment.
fn minus_filtered(target: &Sig, x: &[Sig], b: &[Vec<f64>], f: &[Vec<f64>]) -> Sig {
    let mut v = target.clone();
    for j in 0..x.len() {
        let fj = monic(&f[j]);
        for (ve, xe) in v.iter_mut().zip(&x[j]) {
            let w = filter(&b[j], &fj, xe);
            ve.iter_mut().zip(&w).for_each(|(vt, wt)| *vt -= wt);
        }
    }
    v
}

/// Starting parameters: ARX / Hannan-Rissanen for `A, B, C`; Steiglitz-McBride (one input) or
/// least squares with `F = 1` for OE parts; Hannan-Rissanen on the output-error residual for
/// the noise model `C/D` of Box-Jenkins structures.
pub fn initial_guess(y: &[f64], u: MatRef<'_, f64>, o: &MisoOrders) -> Result<Vec<f64>> {
    initial_guess_multi(&[(y, u)], o)
}

/// [`initial_guess`] from several experiments (every regression row inside one experiment).
pub fn initial_guess_multi(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    o: &MisoOrders,
) -> Result<Vec<f64>> {
    guess_multi(experiments, o, true)
}

/// [`initial_guess_multi`]; without `sweep`, the least-squares impulse responses with `F = 1`
/// start the output-error part of several inputs (no [`gauss_seidel_start`]).
fn guess_multi(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    o: &MisoOrders,
    sweep: bool,
) -> Result<Vec<f64>> {
    check_experiments(experiments, o)?;
    let m = experiments[0].1.ncols();
    let y: Sig = experiments.iter().map(|e| e.0.to_vec()).collect();
    let x: Vec<Sig> = (0..m)
        .map(|j| {
            experiments
                .iter()
                .map(|(_, u)| delayed(*u, j, o.nk[j]))
                .collect()
        })
        .collect();
    let n = experiments.iter().map(|e| e.0.len()).max().unwrap_or(0);
    let has_f = o.nf.iter().any(|&f| f > 0);
    let mut a = vec![0.0; o.na];
    let mut b: Vec<Vec<f64>> = o.nb.iter().map(|&k| vec![0.0; k]).collect();
    let mut f: Vec<Vec<f64>> = o.nf.iter().map(|&k| vec![0.0; k]).collect();
    let mut c = vec![0.0; o.nc];
    let mut d = vec![0.0; o.nd];
    // High-order ARX residual as an innovation estimate.
    let high = (o.na.max(o.nc).max(o.nd) + o.nf.iter().copied().max().unwrap_or(0) + 4)
        .min(n / 10)
        .max(1);
    let innov = |target: &Sig, xs: &[Sig], ar_only: bool| -> Result<Sig> {
        let mut regs: Vec<(&Sig, usize, usize)> = vec![(target, 1, high)];
        if !ar_only {
            for xj in xs {
                regs.push((xj, 0, high));
            }
        }
        let th = lagged_ls(target, &regs)?;
        let mut out = target.clone();
        for (ex, e) in out.iter_mut().enumerate() {
            for (t, et) in e.iter_mut().enumerate() {
                let mut s = 0.0;
                let mut c = 0;
                for (sig, first, nl) in &regs {
                    for k in *first..*first + *nl {
                        s += th[c] * shifted(&sig[ex], t, k);
                        c += 1;
                    }
                }
                *et -= s;
            }
        }
        Ok(out)
    };
    if !has_f {
        // A, B (and C, D if any) jointly: ARX or Hannan-Rissanen.
        let ehat = if o.nc > 0 || o.nd > 0 {
            innov(&y, &x, false)?
        } else {
            y.iter().map(|e| vec![0.0; e.len()]).collect()
        };
        let mut regs: Vec<(&Sig, usize, usize)> = vec![(&y, 1, o.na)];
        for j in 0..m {
            regs.push((&x[j], 0, o.nb[j]));
        }
        regs.push((&ehat, 1, o.nc));
        let th = lagged_ls(&y, &regs)?;
        a = th[..o.na].iter().map(|v| -v).collect();
        let mut i = o.na;
        for j in 0..m {
            b[j] = th[i..i + o.nb[j]].to_vec();
            i += o.nb[j];
        }
        c = stable_or_zero(th[i..i + o.nc].to_vec());
        if o.nd > 0 {
            // D from an AR fit of the equation error.
            let v = minus_filtered(&fmap(&monic(&a), &[1.0], &y), &x, &b, &f);
            let th = lagged_ls(&v, &[(&v, 1, o.nd)])?;
            d = th.iter().map(|t| -t).collect();
        }
    } else {
        let ya = fmap(&monic(&a), &[1.0], &y);
        if m == 1 {
            let (bb, ff) = steiglitz_mcbride_multi(&ya, &x[0], o.nb[0], o.nf[0], 30)?;
            b[0] = bb;
            f[0] = ff;
        } else {
            let regs: Vec<(&Sig, usize, usize)> = (0..m).map(|j| (&x[j], 0, o.nb[j])).collect();
            let th = lagged_ls(&ya, &regs)?;
            let mut i = 0;
            for j in 0..m {
                b[j] = th[i..i + o.nb[j]].to_vec();
                i += o.nb[j];
            }
            if sweep {
                (b, f) = gauss_seidel_start(&ya, &x, o, b, f);
            }
        }
        if o.nc > 0 || o.nd > 0 {
            let v = minus_filtered(&ya, &x, &b, &f);
            let ehat = innov(&v, &[], true)?;
            let th = lagged_ls(&v, &[(&v, 1, o.nd), (&ehat, 1, o.nc)])?;
            d = th[..o.nd].iter().map(|t| -t).collect();
            c = stable_or_zero(th[o.nd..].to_vec());
        }
    }
    let mut theta = a;
    for bj in b {
        theta.extend(bj);
    }
    theta.extend(c);
    theta.extend(d);
    for fj in f {
        theta.extend(fj);
    }
    Ok(theta)
}

/// Result of [`estimate`].
#[derive(Debug, Clone)]
pub struct MisoEstimate {
    /// The search's solution (theta, cost, iterations, stop reason, J^T J).
    pub solution: Solution,
    /// The starting point.
    pub theta0: Vec<f64>,
    /// Innovation variance estimate `2 cost / N`.
    pub noise_variance: f64,
    /// Parameter covariance `noise_variance * (J^T J)^+`.
    pub covariance: Mat<f64>,
}

/// Prediction-error estimate of one output's polynomial model, from `theta0` or (when `None`)
/// from [`initial_guess`].
pub fn estimate(
    y: &[f64],
    u: MatRef<'_, f64>,
    orders: MisoOrders,
    theta0: Option<&[f64]>,
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<MisoEstimate> {
    estimate_multi(&[(y, u)], orders, theta0, options, observer)
}

/// [`estimate`] from several experiments `(y, u)`: the cost is the sum of the experiments'
/// squared prediction errors, each experiment's predictor started from rest; the noise
/// variance is `2 cost / (total samples)` and the covariance `noise_variance (J^T J)^+` with
/// `J^T J` summed over the experiments.
pub fn estimate_multi(
    experiments: &[(&[f64], MatRef<'_, f64>)],
    orders: MisoOrders,
    theta0: Option<&[f64]>,
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<MisoEstimate> {
    let mut prob = MisoProblem::new_multi(experiments, orders.clone())?;
    let mut th0 = match theta0 {
        Some(t) => {
            if t.len() != orders.n_params() {
                return Err(SysidError::invalid(
                    "theta0",
                    format!(
                        "has {} entries but the structure has {}",
                        t.len(),
                        orders.n_params()
                    ),
                ));
            }
            t.to_vec()
        }
        None => initial_guess_multi(experiments, &orders)?,
    };
    if !prob.admissible(&th0) {
        if theta0.is_some() {
            return Err(SysidError::invalid(
                "theta0",
                "C or F is not stable at the start",
            ));
        }
        th0 = vec![0.0; orders.n_params()];
    }
    let mut solution = minimize(&mut prob, &th0, options, observer)?;
    // several inputs with an output-error part: the search also runs from the least-squares
    // impulse responses with F = 1, and the lower final cost is kept (neither start reaches
    // the better minimum on every record: the sweeps' start lowered a steam generator's cost
    // fourfold and raised a winding process's by a quarter)
    let several =
        experiments.first().is_some_and(|e| e.1.ncols() > 1) && orders.nf.iter().any(|&f| f > 0);
    if theta0.is_none() && several && solution.stop != StopReason::Cancelled {
        let alt = guess_multi(experiments, &orders, false)?;
        if alt != th0 && prob.admissible(&alt) {
            let other = minimize(&mut prob, &alt, options, observer)?;
            if other.cost < solution.cost * (1.0 - 1e-9) {
                solution = other;
                th0 = alt;
            }
        }
    }
    let n: usize = experiments.iter().map(|e| e.0.len()).sum();
    let noise_variance = 2.0 * solution.cost / n as f64;
    let cov = crate::optim::covariance(solution.gauss_newton.as_ref(), noise_variance, 1e-10)?;
    Ok(MisoEstimate {
        solution,
        theta0: th0,
        noise_variance,
        covariance: cov.covariance,
    })
}
