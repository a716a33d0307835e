//! Filtering by rational polynomials in `q^-1` and their stability.

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

/// `true` when the monic polynomial `1 + a_1 z^-1 + ... + a_n z^-n` has all roots strictly
/// inside the unit circle (Schur-Cohn step-down: every reflection coefficient below one).
///
/// ```
/// use sysid_core::polynomial::filter::is_stable;
/// assert!(is_stable(&[1.0, -0.9]));
/// assert!(!is_stable(&[1.0, -1.1]));
/// ```
pub fn is_stable(a: &[f64]) -> bool {
    let mut p: Vec<f64> = a.to_vec();
    while p.len() > 1 && p[p.len() - 1] == 0.0 {
        p.pop();
    }
    if p.iter().any(|v| !v.is_finite()) {
        return false;
    }
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

/// Monic polynomial `[1, c...]` from its free coefficients.
pub fn monic(c: &[f64]) -> Vec<f64> {
    let mut v = Vec::with_capacity(c.len() + 1);
    v.push(1.0);
    v.extend_from_slice(c);
    v
}
