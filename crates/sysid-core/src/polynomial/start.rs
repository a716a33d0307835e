//! Starting values of the polynomial prediction-error searches ([`super::pem`]): least squares
//! (ARX), Hannan-Rissanen (ARMAX, noise models), Steiglitz-McBride (OE), Gauss-Seidel sweeps
//! over the inputs of a several-input OE part.

use faer::MatRef;

use super::filter::{filter, is_stable, monic};
use super::pem::{check_experiments, delayed, shifted, MisoOrders, Sig};
use crate::error::Result;
use crate::linalg::QrAccumulator;

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
pub(super) fn guess_multi(
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
