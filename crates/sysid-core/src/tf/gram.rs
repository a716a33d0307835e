//! The Gram matrix of filtered signals, for the SRIVC normal equations.
//!
//! A discrete state-space filter `x_{t+1} = Ad x_t + Bd v_t` driven by the columns of `v`
//! (`N x q`: the signals, and their shifted copies for fractional delays) has the outputs
//! `w_t = Cw x_t + Dw v_t` (`r` of them). [`filtered_gram`] returns
//!
//! ```text
//! G = sum_{t >= skip} w_t w_t^T            (r x r)
//! ```
//!
//! accumulated in blocks of samples (a partial sum per block, then added), so round-off does
//! not grow with the record length and the result does not depend on threads.

use crate::error::{check_finite, Result, SysidError};
use faer::{Mat, MatRef};

const BLOCK: usize = 512;

fn shape(what: &str, got: (usize, usize), expected: (usize, usize)) -> Result<()> {
    if got != expected {
        return Err(SysidError::ShapeMismatch {
            what: what.into(),
            expected: format!("({}, {})", expected.0, expected.1),
            got: format!("({}, {})", got.0, got.1),
        });
    }
    Ok(())
}

/// `sum_{t >= skip} w_t w_t^T` with `w_t = cw x_t + dw v_t`, `x_{t+1} = ad x_t + bd v_t`,
/// `x_0 = 0`.
///
/// ```
/// use faer::mat;
/// use sysid_core::tf::filtered_gram;
/// // a pure gain (no state): w_t = [v_t, 2 v_t], so G = sum v^2 [[1, 2], [2, 4]]
/// let v = mat![[1.0], [2.0]];
/// let g = filtered_gram(
///     faer::Mat::<f64>::zeros(0, 0).as_ref(), faer::Mat::<f64>::zeros(0, 1).as_ref(),
///     faer::Mat::<f64>::zeros(2, 0).as_ref(), mat![[1.0], [2.0]].as_ref(), v.as_ref(), 0,
/// ).unwrap();
/// assert_eq!(g[(1, 1)], 20.0);
/// ```
pub fn filtered_gram(
    ad: MatRef<'_, f64>,
    bd: MatRef<'_, f64>,
    cw: MatRef<'_, f64>,
    dw: MatRef<'_, f64>,
    v: MatRef<'_, f64>,
    skip: usize,
) -> Result<Mat<f64>> {
    let (nx, q, r) = (ad.nrows(), v.ncols(), cw.nrows());
    shape("ad", (ad.nrows(), ad.ncols()), (nx, nx))?;
    shape("bd", (bd.nrows(), bd.ncols()), (nx, q))?;
    shape("cw", (cw.nrows(), cw.ncols()), (r, nx))?;
    shape("dw", (dw.nrows(), dw.ncols()), (r, q))?;
    for (name, m) in [("ad", ad), ("bd", bd), ("cw", cw), ("dw", dw), ("v", v)] {
        check_finite(name, m)?;
    }
    let n = v.nrows();
    let mut total = Mat::<f64>::zeros(r, r);
    let mut part = Mat::<f64>::zeros(r, r);
    let mut x = vec![0.0; nx];
    let mut xn = vec![0.0; nx];
    let mut w = vec![0.0; r];
    let mut vt = vec![0.0; q];
    for t in 0..n {
        if t % 4096 == 0 {
            crate::interrupt::check()?; // Ctrl-C
        }
        for (k, e) in vt.iter_mut().enumerate() {
            *e = v[(t, k)];
        }
        if t >= skip {
            for (i, wi) in w.iter_mut().enumerate() {
                let mut s = 0.0;
                for (j, xj) in x.iter().enumerate() {
                    s += cw[(i, j)] * xj;
                }
                for (k, vk) in vt.iter().enumerate() {
                    s += dw[(i, k)] * vk;
                }
                *wi = s;
            }
            for j in 0..r {
                let wj = w[j];
                for i in j..r {
                    part[(i, j)] += w[i] * wj;
                }
            }
            if (t - skip + 1) % BLOCK == 0 {
                flush(&mut total, &mut part);
            }
        }
        for (i, e) in xn.iter_mut().enumerate() {
            let mut s = 0.0;
            for (j, xj) in x.iter().enumerate() {
                s += ad[(i, j)] * xj;
            }
            for (k, vk) in vt.iter().enumerate() {
                s += bd[(i, k)] * vk;
            }
            *e = s;
        }
        std::mem::swap(&mut x, &mut xn);
    }
    flush(&mut total, &mut part);
    for j in 0..r {
        for i in 0..j {
            total[(i, j)] = total[(j, i)];
        }
    }
    Ok(total)
}

fn flush(total: &mut Mat<f64>, part: &mut Mat<f64>) {
    let r = total.nrows();
    for j in 0..r {
        for i in j..r {
            total[(i, j)] += part[(i, j)];
            part[(i, j)] = 0.0;
        }
    }
}
