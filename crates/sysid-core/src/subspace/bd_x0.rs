//! B, D and the initial state by least squares on the data, given A and C.
//!
//! The output of the model is linear in `x0`, `vec(B)` and `vec(D)`:
//!
//! ```text
//! y(t) = C A^t x0 + sum_{τ<t} C A^{t-1-τ} B u(τ) + D u(t)
//!      = C A^t x0 + C Z_t vec(B) + (u(t)^T ⊗ I_l) vec(D),
//! ```
//!
//! where `Z_{t+1} = A Z_t + u(t)^T ⊗ I_n` (n x n m) carries the sensitivities of the state
//! to the entries of B (the Kronecker-product regression of the seed slides and of SLICOT
//! IB01CD). The regressor rows stream through a [`QrAccumulator`], so memory does not grow
//! with the record length; one pass, `O(N n^2 m)` flops.

use crate::error::{check_finite, Result, SysidError};
use crate::linalg::{pinv, QrAccumulator};
use faer::{Mat, MatRef};

/// `(B, D, x0)` minimising the simulation error of `(A, B, C, D)` from `x0` on `(u, y)`.
/// With `feedthrough = false`, D is fixed at zero.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::subspace::bd_x0::estimate_bd_x0;
/// use sysid_core::{StateSpace, simulate::simulate};
/// let sys = StateSpace::new(mat![[0.8]], mat![[0.5]], mat![[2.0]], mat![[0.1]]).unwrap();
/// let u = Mat::from_fn(50, 1, |t, _| ((t * 37) % 11) as f64 - 5.0);
/// let y = simulate(&sys, u.as_ref(), Some(&[3.0])).unwrap();
/// let (b, d, x0) = estimate_bd_x0(sys.a.as_ref(), sys.c.as_ref(), u.as_ref(), y.as_ref(), true).unwrap();
/// assert!((b[(0, 0)] - 0.5).abs() < 1e-10 && (d[(0, 0)] - 0.1).abs() < 1e-10);
/// assert!((x0[0] - 3.0).abs() < 1e-9);
/// ```
pub fn estimate_bd_x0(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    u: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    feedthrough: bool,
) -> Result<(Mat<f64>, Mat<f64>, Vec<f64>)> {
    let (b, d, mut x0) = estimate_bd_x0_records(a, c, &[(u, y)], feedthrough)?;
    Ok((b, d, x0.remove(0)))
}

/// `(B, D, [x0 of each record])` minimising the simulation error of `(A, B, C, D)` over
/// several records (experiments), each simulated from its own initial state: one `B`, `D`
/// for all, an `x0` per record. With `feedthrough = false`, D is fixed at zero. Records
/// may differ in length; each must have the same input and output channels.
///
/// ```
/// use faer::{mat, Mat};
/// use sysid_core::subspace::bd_x0::estimate_bd_x0_records;
/// use sysid_core::{StateSpace, simulate::simulate};
/// let sys = StateSpace::new(mat![[0.8]], mat![[0.5]], mat![[2.0]], mat![[0.1]]).unwrap();
/// let u1 = Mat::from_fn(40, 1, |t, _| ((t * 37) % 11) as f64 - 5.0);
/// let u2 = Mat::from_fn(30, 1, |t, _| ((t * 17) % 7) as f64 - 3.0);
/// let y1 = simulate(&sys, u1.as_ref(), Some(&[3.0])).unwrap();
/// let y2 = simulate(&sys, u2.as_ref(), Some(&[-1.0])).unwrap();
/// let recs = [(u1.as_ref(), y1.as_ref()), (u2.as_ref(), y2.as_ref())];
/// let (b, d, x0) = estimate_bd_x0_records(sys.a.as_ref(), sys.c.as_ref(), &recs, true).unwrap();
/// assert!((b[(0, 0)] - 0.5).abs() < 1e-10 && (d[(0, 0)] - 0.1).abs() < 1e-10);
/// assert!((x0[0][0] - 3.0).abs() < 1e-9 && (x0[1][0] + 1.0).abs() < 1e-9);
/// ```
#[allow(clippy::type_complexity)]
pub fn estimate_bd_x0_records(
    a: MatRef<'_, f64>,
    c: MatRef<'_, f64>,
    records: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    feedthrough: bool,
) -> Result<(Mat<f64>, Mat<f64>, Vec<Vec<f64>>)> {
    let (n, l) = (a.nrows(), c.nrows());
    if c.ncols() != n || a.ncols() != n {
        return Err(SysidError::invalid("A, C", "A must be n x n and C l x n"));
    }
    let Some(&(u0, _)) = records.first() else {
        return Err(SysidError::invalid("records", "give at least one record"));
    };
    let m = u0.ncols();
    let mut total = 0usize;
    for (k, &(u, y)) in records.iter().enumerate() {
        if u.ncols() != m || y.ncols() != l || y.nrows() != u.nrows() {
            return Err(SysidError::ShapeMismatch {
                what: format!("record {k}"),
                expected: format!("u ({}, {m}) and y ({}, {l})", u.nrows(), u.nrows()),
                got: format!(
                    "u ({}, {}), y ({}, {})",
                    u.nrows(),
                    u.ncols(),
                    y.nrows(),
                    y.ncols()
                ),
            });
        }
        check_finite("u", u)?;
        check_finite("y", y)?;
        total += y.nrows();
    }
    let e = records.len();
    let nx = n * e;
    let nb = n * m;
    let nd = if feedthrough { l * m } else { 0 };
    let p = nx + nb + nd;
    if total * l < p {
        return Err(SysidError::InsufficientData {
            context: format!(
                "estimating B, D and {e} initial state(s) ({p} unknowns) from {l} output(s)"
            ),
            needed: p.div_ceil(l),
            got: total,
            fix: "use a longer record",
        });
    }
    let af: Vec<f64> = (0..n * n).map(|i| a[(i / n, i % n)]).collect();
    let mut acc = QrAccumulator::new(p + 1, (8 * (p + 1)).max(256));
    let mut row = vec![0.0; p + 1];
    let mut z = vec![0.0; n * nb]; // Z_t, row-major n x (n m)
    let mut zn = vec![0.0; n * nb];
    for (k, &(u, y)) in records.iter().enumerate() {
        let mut ca = c.to_owned(); // C A^t (l x n)
        z.iter_mut().for_each(|v| *v = 0.0);
        for t in 0..y.nrows() {
            if t % 4096 == 4095 {
                crate::interrupt::check()?; // Ctrl-C within a long record
            }
            for i in 0..l {
                row.iter_mut().for_each(|v| *v = 0.0);
                for j in 0..n {
                    row[n * k + j] = ca[(i, j)];
                }
                // C Z_t, row i
                for col in 0..nb {
                    let mut s = 0.0;
                    for r in 0..n {
                        s += c[(i, r)] * z[r * nb + col];
                    }
                    row[nx + col] = s;
                }
                if feedthrough {
                    // vec(D) column-major: index i + l * j
                    for j in 0..m {
                        row[nx + nb + i + l * j] = u[(t, j)];
                    }
                }
                row[p] = y[(t, i)];
                acc.push_row(&row);
            }
            // Z_{t+1} = A Z_t + u(t)^T ⊗ I_n ; vec(B) column-major: entry (r, j) at r + n j
            for r in 0..n {
                for col in 0..nb {
                    let mut s = 0.0;
                    for q in 0..n {
                        s += af[r * n + q] * z[q * nb + col];
                    }
                    zn[r * nb + col] = s;
                }
                for j in 0..m {
                    zn[r * nb + r + n * j] += u[(t, j)];
                }
            }
            std::mem::swap(&mut z, &mut zn);
            ca = &ca * a;
            if t % crate::optim::FLUSH_EVERY == 0 {
                // C A^t decays through the subnormal numbers, slow on Intel processors
                crate::optim::flush_tiny_mat(&mut ca);
            }
            if !ca.norm_max().is_finite() {
                return Err(SysidError::numerical(
                    "initial-state regression",
                    "C A^t overflowed: A is unstable over this record length",
                ));
            }
        }
    }
    let r = acc.finish();
    let r11 = r.as_ref().submatrix(0, 0, p, p);
    let r12 = r.as_ref().submatrix(0, p, p, 1);
    let theta = pinv(r11, 1e-12)? * r12;
    let x0: Vec<Vec<f64>> = (0..e)
        .map(|k| (0..n).map(|i| theta[(n * k + i, 0)]).collect())
        .collect();
    let mut b = Mat::<f64>::zeros(n, m);
    for j in 0..m {
        for i in 0..n {
            b[(i, j)] = theta[(nx + i + n * j, 0)];
        }
    }
    let mut d = Mat::<f64>::zeros(l, m);
    if feedthrough {
        for j in 0..m {
            for i in 0..l {
                d[(i, j)] = theta[(nx + nb + i + l * j, 0)];
            }
        }
    }
    Ok((b, d, x0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{simulate::simulate, StateSpace};
    use faer::mat;

    /// The pass over the record asks whether to stop every few thousand samples (Ctrl-C
    /// waited for the whole pass, over a second on 200 000 samples), and over a long record
    /// `C A^t` decays to zero (flushed before it turns subnormal) with the estimate exact.
    #[test]
    fn a_long_record_stops_when_asked_and_is_exact_to_its_end() {
        let sys = StateSpace::new(
            mat![[0.5, 0.2], [0.0, 0.3]],
            mat![[1.0], [0.5]],
            mat![[1.0, -1.0]],
            mat![[0.2]],
        )
        .unwrap();
        let u = Mat::from_fn(20_000, 1, |t, _| ((t * 37) % 11) as f64 - 5.0);
        let y = simulate(&sys, u.as_ref(), Some(&[3.0, -1.0])).unwrap();
        let (a, c) = (sys.a.as_ref(), sys.c.as_ref());
        let r = crate::interrupt::error_when_asked_to_stop(|| {
            estimate_bd_x0(a, c, u.as_ref(), y.as_ref(), true)
        });
        assert_eq!(r, Some(SysidError::Interrupted));
        let (b, d, x0) = estimate_bd_x0(a, c, u.as_ref(), y.as_ref(), true).unwrap();
        assert!((&b - &sys.b).norm_max() < 1e-10 && (&d - &sys.d).norm_max() < 1e-10);
        assert!((x0[0] - 3.0).abs() < 1e-9 && (x0[1] + 1.0).abs() < 1e-9);
    }
}
