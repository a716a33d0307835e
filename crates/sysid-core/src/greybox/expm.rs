//! The matrix exponential and its Fréchet derivatives, for sampling continuous structures.
//!
//! `exp(X)` by scaling and squaring of the Taylor series: `X / 2^s` with norm at most 1/2,
//! the series to degree 20 (truncation below `1e-25` relative), then `s` squarings. The
//! Fréchet derivative `L(X, E)` in a direction `E` is the upper-right block of the
//! exponential of `[[X, E], [0, X]]`, computed by the same recursion on the pair
//! `(exp, L)`: squaring `(F, L) -> (F F, F L + L F)`, so every direction costs a few products
//! of the small matrix.

use faer::{Mat, MatRef};

/// `exp(x)` and the Fréchet derivatives `L(x, e)` for every `e` in `dirs`.
///
/// ```
/// use faer::mat;
/// use sysid_core::greybox::expm::expm_frechet;
/// let (f, l) = expm_frechet(mat![[0.0, 1.0], [0.0, 0.0]].as_ref(), &[mat![[1.0, 0.0], [0.0, 0.0]]]);
/// assert!((f[(0, 1)] - 1.0).abs() < 1e-15);
/// // d/dt exp([[t, 1], [0, 0]]) at t = 0: [[1, 1/2], [0, 0]]
/// assert!((l[0][(0, 0)] - 1.0).abs() < 1e-14 && (l[0][(0, 1)] - 0.5).abs() < 1e-14);
/// ```
pub fn expm_frechet(x: MatRef<'_, f64>, dirs: &[Mat<f64>]) -> (Mat<f64>, Vec<Mat<f64>>) {
    let n = x.nrows();
    let norm = (0..n)
        .map(|i| (0..n).map(|j| x[(i, j)].abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut s = 0i32;
    while norm / 2f64.powi(s) > 0.5 && s < 1000 {
        s += 1;
    }
    let c = 1.0 / 2f64.powi(s);
    let xs = x.to_owned() * c;
    let es: Vec<Mat<f64>> = dirs.iter().map(|e| e * c).collect();
    // Taylor: F = sum X^k / k!, L = sum_k 1/k! sum_{j<k} X^j E X^(k-1-j), by Horner:
    // F_k = I + X F_{k+1} / k  and  L_k = (E F_{k+1} + X L_{k+1}) / k
    let id = Mat::<f64>::identity(n, n);
    let mut f = id.clone();
    let mut l: Vec<Mat<f64>> = dirs.iter().map(|_| Mat::zeros(n, n)).collect();
    for k in (1..=20).rev() {
        let kf = k as f64;
        for (li, e) in l.iter_mut().zip(&es) {
            *li = (e * &f + &xs * &*li) * (1.0 / kf);
        }
        f = &id + &xs * &f * (1.0 / kf);
    }
    for _ in 0..s {
        for li in l.iter_mut() {
            *li = &f * &*li + &*li * &f;
        }
        f = &f * &f;
    }
    (f, l)
}
