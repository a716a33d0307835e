//! Filtering by rational polynomials in `q^-1` and their stability, and the matrix
//! difference equation of a coupled MIMO ARX model (simulation and k-step prediction).

use faer::{Mat, MatRef};

use crate::error::{check_finite, Result, SysidError};

/// `y = B(q)/A(q) x` from rest, with `A` monic (`a[0] == 1`, or empty meaning `A = 1`).
///
/// ```
/// use sysid_core::polynomial::filter::filter;
/// let y = filter(&[1.0], &[1.0, -0.5], &[1.0, 0.0, 0.0]);
/// assert_eq!(y, vec![1.0, 0.5, 0.25]);
/// ```
pub fn filter(b: &[f64], a: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut y = vec![0.0; n];
    for t in 0..n {
        let mut s = 0.0;
        for (k, bk) in b.iter().enumerate() {
            if k > t {
                break;
            }
            s += bk * x[t - k];
        }
        for k in 1..a.len() {
            if k > t {
                break;
            }
            s -= a[k] * y[t - k];
        }
        y[t] = s;
    }
    y
}

/// Product of two polynomials (coefficient convolution).
pub fn conv(a: &[f64], b: &[f64]) -> Vec<f64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut c = vec![0.0; a.len() + b.len() - 1];
    for (i, ai) in a.iter().enumerate() {
        for (j, bj) in b.iter().enumerate() {
            c[i + j] += ai * bj;
        }
    }
    c
}

/// `c` without its trailing zero coefficients (at least one kept); `None` when an entry is
/// not finite.
fn trimmed(c: &[f64]) -> Option<Vec<f64>> {
    let mut p = c.to_vec();
    while p.len() > 1 && p[p.len() - 1] == 0.0 {
        p.pop();
    }
    p.iter().all(|v| v.is_finite()).then_some(p)
}

/// `true` when the monic polynomial `1 + a_1 z^-1 + ... + a_n z^-n` has all roots strictly
/// inside the unit circle (Schur-Cohn step-down: every reflection coefficient below one).
///
/// ```
/// use sysid_core::polynomial::filter::is_stable;
/// assert!(is_stable(&[1.0, -0.9]));
/// assert!(!is_stable(&[1.0, -1.1]));
/// ```
pub fn is_stable(a: &[f64]) -> bool {
    let Some(mut p) = trimmed(a) else {
        return false;
    };
    while p.len() > 1 {
        let n = p.len() - 1;
        let k = p[n] / p[0];
        if k.abs() >= 1.0 {
            return false;
        }
        let d = 1.0 - k * k;
        let q: Vec<f64> = (0..n).map(|i| (p[i] - k * p[n - i]) / d).collect();
        p = q;
    }
    true
}

/// `true` when the polynomial `c_0 + c_1 s + ... + c_n s^n` (ascending powers, `c_n != 0`)
/// has all roots strictly in the left half-plane (Hurwitz). The bilinear map `s = (z - 1) /
/// (z + 1)` takes the left half-plane onto the unit disc: the polynomial
/// `sum_k c_k (z - 1)^k (z + 1)^(n - k)` is tested by [`is_stable`]; a vanishing leading
/// coefficient there is a root at `s = 1`.
///
/// ```
/// use sysid_core::polynomial::filter::is_hurwitz;
/// assert!(is_hurwitz(&[2.0, 3.0, 1.0]));      // (s + 1)(s + 2)
/// assert!(!is_hurwitz(&[-2.0, 1.0, 1.0]));    // (s - 1)(s + 2)
/// assert!(!is_hurwitz(&[1.0, 0.0, 1.0]));     // s = +-j: on the axis
/// ```
pub fn is_hurwitz(c: &[f64]) -> bool {
    let Some(c) = trimmed(c) else {
        return false;
    };
    let n = c.len() - 1;
    // descending powers of z: sum_k c_k (z - 1)^k (z + 1)^(n - k)
    let mut p = vec![0.0; n + 1];
    for (k, &ck) in c.iter().enumerate() {
        let mut term = vec![ck];
        for _ in 0..k {
            term = conv(&term, &[1.0, -1.0]);
        }
        for _ in k..n {
            term = conv(&term, &[1.0, 1.0]);
        }
        for (pi, ti) in p.iter_mut().zip(&term) {
            *pi += ti;
        }
    }
    let scale = p.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if p[0].abs() <= 1e-14 * scale {
        return false;
    }
    let lead = p[0];
    is_stable(&p.iter().map(|v| v / lead).collect::<Vec<_>>())
}

/// Monic polynomial `[1, c...]` from its free coefficients.
pub fn monic(c: &[f64]) -> Vec<f64> {
    let mut v = Vec::with_capacity(c.len() + 1);
    v.push(1.0);
    v.extend_from_slice(c);
    v
}

/// The matrix difference equation of a (coupled) MIMO ARX model,
/// `y_i(t) = w_i(t) - sum_k sum_{l>=1} a[i][k][l-1] y_k(t - l)`, from rest.
///
/// `a[i][k]` holds the coefficients `a_1..` of output `k` in the equation of output `i`
/// (any lengths), `w` (`N x ny`) the input part `sum_j B_ij u_j(t - nk_ij)` of every output.
///
/// * `measured = None`: simulation (the model's own past outputs).
/// * `measured = Some((y, k))`: the `k`-step-ahead prediction `yhat(t | t - k)`: with
///   `P_0 = y` and `P_j(t) = w(t) - sum_{l>=1} A_l P_{max(j - l, 0)}(t - l)`, measured outputs
///   where they are known at `t - k` and shorter-range predictions where not (future
///   innovations have mean zero). `P_1` is the one-step predictor `y - e`.
///
/// Memory: `na + 1` arrays of `N x ny` (`na` the longest `A` entry), whatever `k`.
///
/// ```
/// use faer::Mat;
/// use sysid_core::polynomial::filter::arx_matrix_filter;
/// // y(t) = 0.5 y(t-1) + w(t): simulation of a unit pulse, then one-step prediction
/// let a = vec![vec![vec![-0.5]]];
/// let w = Mat::from_fn(3, 1, |t, _| if t == 0 { 1.0 } else { 0.0 });
/// let y = arx_matrix_filter(&a, w.as_ref(), None).unwrap();
/// assert_eq!((y[(1, 0)], y[(2, 0)]), (0.5, 0.25));
/// let meas = Mat::from_fn(3, 1, |_, _| 2.0);
/// let p = arx_matrix_filter(&a, w.as_ref(), Some((meas.as_ref(), 1))).unwrap();
/// assert_eq!((p[(0, 0)], p[(1, 0)]), (1.0, 1.0));
/// ```
pub fn arx_matrix_filter(
    a: &[Vec<Vec<f64>>],
    w: MatRef<'_, f64>,
    measured: Option<(MatRef<'_, f64>, usize)>,
) -> Result<Mat<f64>> {
    let (n, ny) = (w.nrows(), w.ncols());
    if a.len() != ny || a.iter().any(|row| row.len() != ny) {
        return Err(SysidError::ShapeMismatch {
            what: "A coefficients".into(),
            expected: format!("{ny} x {ny} polynomials (one per output pair)"),
            got: format!(
                "{} rows of lengths {:?}",
                a.len(),
                a.iter().map(Vec::len).collect::<Vec<_>>()
            ),
        });
    }
    if a.iter().flatten().flatten().any(|v| !v.is_finite()) {
        return Err(SysidError::invalid(
            "A coefficients",
            "contain NaN or infinity; re-estimate the model",
        ));
    }
    check_finite("w", w)?;
    let na = a.iter().flatten().map(Vec::len).max().unwrap_or(0);
    let Some((y, k)) = measured else {
        let mut out = Mat::<f64>::zeros(n, ny);
        for t in 0..n {
            for i in 0..ny {
                let mut s = w[(t, i)];
                for (kk, ak) in a[i].iter().enumerate() {
                    for lag in 1..=ak.len().min(t) {
                        s -= ak[lag - 1] * out[(t - lag, kk)];
                    }
                }
                out[(t, i)] = s;
            }
        }
        return Ok(out);
    };
    if y.nrows() != n || y.ncols() != ny {
        return Err(SysidError::ShapeMismatch {
            what: "y".into(),
            expected: format!("({n}, {ny}) like the input part"),
            got: format!("({}, {})", y.nrows(), y.ncols()),
        });
    }
    if k == 0 {
        return Err(SysidError::invalid("horizon", "must be at least 1"));
    }
    check_finite("y", y)?;
    // lags[l][(i, q)]: coefficient of y_q(t - l) in the equation of output i.
    let lags: Vec<Mat<f64>> = (0..=na)
        .map(|l| {
            Mat::from_fn(ny, ny, |i, q| {
                if l >= 1 && l <= a[i][q].len() {
                    a[i][q][l - 1]
                } else {
                    0.0
                }
            })
        })
        .collect();
    // ring[j % (na + 1)] holds P_j for the last na + 1 values of j (P_0 = y kept aside).
    let mut ring: Vec<Mat<f64>> = vec![Mat::zeros(0, 0); na + 1];
    let mut last = y.to_owned();
    for j in 1..=k.min(n.max(1)) {
        let mut p = w.to_owned();
        for lag in 1..=na.min(n.saturating_sub(1)) {
            let src = j.saturating_sub(lag);
            let prev: MatRef<'_, f64> = if src == 0 {
                y
            } else {
                ring[src % (na + 1)].as_ref()
            };
            let al = &lags[lag];
            for t in lag..n {
                for i in 0..ny {
                    let mut dot = 0.0;
                    for q in 0..ny {
                        dot += prev[(t - lag, q)] * al[(i, q)];
                    }
                    p[(t, i)] -= dot;
                }
            }
        }
        last = p.clone();
        ring[j % (na + 1)] = p;
    }
    Ok(last)
}
