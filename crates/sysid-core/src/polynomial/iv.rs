//! Instrumental variables: the four-stage IV4 method for single-input single-output ARX
//! structures `A(q) y = B(q) u(t - nk) + v` (Ljung, System Identification, 1999, sec. 15.3).

use faer::linalg::solvers::Solve;

use super::filter::{filter, monic};
use crate::error::{Result, SysidError};

/// Solves `sum z(t) phi(t)^T theta = sum z(t) y(t)` (rows from `start`), where
/// `phi(t) = [-y(t-1..na), u(t-nk..nk+nb-1)]` and `z(t)` the same with `x` in place of `y`
/// and `r` in place of `u`. Accumulated sample by sample into p x p sums.
fn iv_solve(
    y: &[f64],
    u: &[f64],
    x: &[f64],
    r: &[f64],
    na: usize,
    nb: usize,
    nk: usize,
) -> Result<Vec<f64>> {
    let p = na + nb;
    let start = na.max(nk + nb);
    let mut m = vec![0.0; p * p];
    let mut v = vec![0.0; p];
    let mut phi = vec![0.0; p];
    let mut z = vec![0.0; p];
    for t in start..y.len() {
        for k in 0..na {
            phi[k] = -y[t - 1 - k];
            z[k] = -x[t - 1 - k];
        }
        for k in 0..nb {
            phi[na + k] = u[t - nk - k];
            z[na + k] = r[t - nk - k];
        }
        for a in 0..p {
            for b in 0..p {
                m[a * p + b] += z[a] * phi[b];
            }
            v[a] += z[a] * y[t];
        }
    }
    let mat = faer::Mat::from_fn(p, p, |a, b| m[a * p + b]);
    let rhs = faer::Mat::from_fn(p, 1, |a, _| v[a]);
    let s = mat
        .singular_values()
        .map_err(|e| SysidError::numerical("iv4", format!("{e:?}")))?;
    if s.is_empty() || s[s.len() - 1] <= 1e-12 * s[0] {
        return Err(SysidError::NotPersistentlyExciting {
            rank: 0,
            rows: p,
            tol: 1e-12,
        });
    }
    let sol = mat.partial_piv_lu().solve(&rhs);
    Ok((0..p).map(|a| sol[(a, 0)]).collect())
}

fn split(theta: &[f64], na: usize) -> (Vec<f64>, Vec<f64>) {
    (monic(&theta[..na]), theta[na..].to_vec())
}

fn delayed(x: &[f64], nk: usize) -> Vec<f64> {
    (0..x.len())
        .map(|t| if t >= nk { x[t - nk] } else { 0.0 })
        .collect()
}

/// IV4 estimate `[a_1..a_na, b_0..b_{nb-1}]` of `A y = B u(t-nk) + v`. With `reference`
/// (closed-loop data), the instruments are built from the reference instead of the input.
///
/// ```
/// use sysid_core::polynomial::{filter::filter, iv::iv4};
/// let u: Vec<f64> = (0..400).map(|t| ((t * 7919 % 17) as f64) - 8.0).collect();
/// let mut x = vec![0.0; 400];
/// x[1..].copy_from_slice(&u[..399]);
/// let y = filter(&[1.0], &[1.0, -0.5], &x);
/// let th = iv4(&y, &u, 1, 1, 1, None).unwrap();
/// assert!((th[0] + 0.5).abs() < 1e-8 && (th[1] - 1.0).abs() < 1e-8);
/// ```
pub fn iv4(
    y: &[f64],
    u: &[f64],
    na: usize,
    nb: usize,
    nk: usize,
    reference: Option<&[f64]>,
) -> Result<Vec<f64>> {
    if u.len() != y.len() || reference.is_some_and(|r| r.len() != y.len()) {
        return Err(SysidError::invalid(
            "u",
            "u, y (and reference) need equal lengths",
        ));
    }
    if nb == 0 {
        return Err(SysidError::invalid("nb", "iv4 needs nb >= 1"));
    }
    let p = na.saturating_add(nb);
    let need = p.saturating_add(nk).saturating_mul(4).saturating_add(10);
    if y.len() < need {
        return Err(SysidError::InsufficientData {
            context: format!("iv4 with {p} parameters (na={na}, nb={nb}, nk={nk})"),
            needed: need,
            got: y.len(),
            fix: "use a longer record or smaller orders",
        });
    }
    let r = reference.unwrap_or(u);
    // Stage 1: least squares (instruments = regressors), or reference-lag IV in closed loop.
    let th1 = if reference.is_some() {
        let rl = delayed(r, nb + nk);
        iv_solve(y, u, &rl, r, na, nb, nk)?
    } else {
        iv_solve(y, u, y, u, na, nb, nk)?
    };
    // Stage 2: instruments from the simulated noise-free output of stage 1.
    let (a1, b1) = split(&th1, na);
    let x1 = filter(&b1, &a1, &delayed(r, nk));
    let th2 = iv_solve(y, u, &x1, r, na, nb, nk)?;
    // Stage 3: AR model L of the equation error, order na + nb.
    let (a2, b2) = split(&th2, na);
    let ay = filter(&a2, &[1.0], y);
    let bu = filter(&b2, &[1.0], &delayed(u, nk));
    let w: Vec<f64> = ay.iter().zip(&bu).map(|(a, b)| a - b).collect();
    let nl = na + nb;
    let zero = vec![0.0; w.len()];
    let lth = iv_solve(&w, &zero, &w, &zero, nl, 0, 0).unwrap_or_else(|_| vec![0.0; nl]);
    let l = monic(&lth);
    // Stage 4: prefiltered IV with instruments from the stage-2 model.
    let x2 = filter(&b2, &a2, &delayed(r, nk));
    let (yf, uf, xf, rf) = (
        filter(&l, &[1.0], y),
        filter(&l, &[1.0], u),
        filter(&l, &[1.0], &x2),
        filter(&l, &[1.0], r),
    );
    let th = iv_solve(&yf, &uf, &xf, &rf, na, nb, nk)?;
    Ok(th)
}
