//! The cost pass of the predictor ([`Predictor::pass`](super::predictor::Predictor)) for a
//! few states, with the state held in registers.
//!
//! The pass is latency bound: each sample's state is a sum over the previous one. The general
//! [`Filter`] keeps the state in memory and copies it per sample; here, for `N <= 8` states
//! known at compile time and a dense `[Abar Bbar K]`, the state is an array the compiler keeps
//! in registers. Every sum adds the same terms in the same order as [`Filter::errors`],
//! [`Filter::weigh`] and [`Filter::advance`]: the cost and the covariance are the same to the
//! last bit.

use super::predictor::{Filter, RowProduct};
use faer::MatRef;

/// Runs `f` over the experiments from their initial states, adding each sample's `e e^T`
/// (lower triangle, row by row) to `lam` when it is not empty; `false` (nothing done) when the
/// kernel does not apply (more than 8 states, or a sparse `[Abar Bbar K]`).
pub(super) fn dense_pass(
    f: &mut Filter,
    exps: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    lam: &mut [f64],
) -> bool {
    match f.x.len() {
        1 => run::<1>(f, exps, lam),
        2 => run::<2>(f, exps, lam),
        3 => run::<3>(f, exps, lam),
        4 => run::<4>(f, exps, lam),
        5 => run::<5>(f, exps, lam),
        6 => run::<6>(f, exps, lam),
        7 => run::<7>(f, exps, lam),
        8 => run::<8>(f, exps, lam),
        _ => false,
    }
}

fn run<const N: usize>(
    f: &mut Filter,
    exps: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    lam: &mut [f64],
) -> bool {
    let RowProduct::Columns(cols, abk) = &f.abk else {
        return false;
    };
    let l = f.e.len();
    let w = *cols;
    if abk.len() != N * w {
        return false;
    }
    // the columns of u and y after the N state columns
    let ml = w - N;
    let m = ml - l;
    let (cd, r) = (&f.cd, &f.rinv_rows);
    let mut uy = vec![0.0; ml];
    let (mut e, mut we) = (vec![0.0; l], vec![0.0; l]);
    // [Abar Bbar K] by columns of N entries: each column adds to every row at once (the
    // state's sums still run over the columns in order)
    let (ax, buy) = abk.split_at(N * N);
    let mut cost = f.cost;
    // the dense products before left the vector registers' upper halves dirty
    crate::optim::clear_upper();
    for (ex, (u, y)) in exps.iter().enumerate() {
        let mut x = [0.0; N];
        x.copy_from_slice(&f.pm.x0[ex]);
        for t in 0..y.nrows() {
            for (j, v) in uy[..m].iter_mut().enumerate() {
                *v = u[(t, j)];
            }
            for (j, v) in uy[m..].iter_mut().enumerate() {
                *v = y[(t, j)];
            }
            // e = y - C x - D u ([`Filter::errors`])
            for ((ei, row), &yi) in e.iter_mut().zip(cd.chunks_exact(N + m)).zip(&uy[m..]) {
                let mut a = yi;
                for (c, v) in row[..N].iter().zip(&x) {
                    a -= c * v;
                }
                for (c, v) in row[N..].iter().zip(&uy[..m]) {
                    a -= c * v;
                }
                *ei = a;
            }
            // R^-1 e and the cost ([`Filter::weigh`])
            for i in 0..l {
                let mut a = 0.0;
                for (rv, ev) in r[i * l..i * l + i + 1].iter().zip(&e) {
                    a += rv * ev;
                }
                we[i] = a;
                cost += 0.5 * a * a;
            }
            if !lam.is_empty() {
                let mut k = 0;
                for i in 0..l {
                    for j in 0..=i {
                        lam[k] += e[i] * e[j];
                        k += 1;
                    }
                }
            }
            // x <- [Abar Bbar K] (x, u, y) ([`Filter::advance`])
            let mut xn = [0.0; N];
            for (col, &v) in ax.chunks_exact(N).zip(&x) {
                for (o, c) in xn.iter_mut().zip(col) {
                    *o += c * v;
                }
            }
            for (col, &v) in buy.chunks_exact(N).zip(&uy) {
                for (o, c) in xn.iter_mut().zip(col) {
                    *o += c * v;
                }
            }
            x = xn;
            if t % crate::optim::FLUSH_EVERY == 0 {
                crate::optim::flush_tiny(&mut x); // as [`Filter::advance`]
            }
        }
        f.x.copy_from_slice(&x);
    }
    f.cost = cost;
    true
}
