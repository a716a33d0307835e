//! Modal analysis of a discrete-time model: natural frequencies, damping ratios, mode shapes.
//!
//! Each eigenvalue `z = exp(s dt)` of A maps to the continuous-time pole `s = ln(z) / dt`
//! (principal logarithm, so frequencies are below the Nyquist frequency `pi / dt`), with
//! natural frequency `omega_n = |s|` rad/s (`omega_n / 2 pi` Hz), damped frequency `Im s` and
//! damping ratio `zeta = -Re(s) / |s|`. The mode shape is `C psi` for the eigenvector psi,
//! scaled so that its entry of largest modulus is 1 (a real, positive reference).

use crate::error::{Result, SysidError};
use faer::{c64, Mat, MatRef};

/// Eigenvalues, eigenvectors and the inverse of the eigenvector matrix of a real matrix.
pub(crate) struct EigenDecomposition {
    pub values: Vec<c64>,
    pub vectors: Mat<c64>,
    pub inverse: Mat<c64>,
}

pub(crate) fn eigen_decomposition(a: MatRef<'_, f64>) -> Result<EigenDecomposition> {
    let n = a.nrows();
    if n == 0 {
        return Ok(EigenDecomposition {
            values: vec![],
            vectors: Mat::zeros(0, 0),
            inverse: Mat::zeros(0, 0),
        });
    }
    let (values, vectors) = crate::linalg::eigen(a)
        .map_err(|e| SysidError::numerical("eigendecomposition of A", format!("{e:?}")))?;
    let inverse = crate::linalg::inverse(vectors.as_ref());
    let check = crate::linalg::mul(inverse.as_ref(), vectors.as_ref());
    let mut err = 0.0f64;
    for j in 0..n {
        for i in 0..n {
            let target = if i == j { 1.0 } else { 0.0 };
            err = err.max((check[(i, j)] - c64::new(target, 0.0)).norm());
        }
    }
    let norm = |m: &Mat<c64>| {
        (0..n)
            .map(|j| (0..n).map(|i| m[(i, j)].norm()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    let cond = norm(&vectors) * norm(&inverse);
    // f64::max skips NaN: a singular eigenvector matrix (a defective A) inverts to NaN,
    // which neither the residual nor the norms above would show
    let nan = (0..n).any(|j| {
        (0..n).any(|i| !inverse[(i, j)].re.is_finite() || !inverse[(i, j)].im.is_finite())
    });
    if nan || !err.is_finite() || err > 1e-6 || cond.is_nan() || cond >= 1e12 {
        return Err(SysidError::numerical(
            "eigendecomposition of A",
            "A is defective or nearly so (repeated poles without a full set of eigenvectors); \
             modal quantities are not defined for it",
        ));
    }
    Ok(EigenDecomposition {
        values,
        vectors,
        inverse,
    })
}

/// One mode of a discrete-time model.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Discrete-time eigenvalue z.
    pub eigenvalue: c64,
    /// Continuous-time equivalent `s = ln(z) / dt` (1/s); `-inf` for `z = 0`.
    pub s: c64,
    /// Natural frequency in rad/s (infinite for `z = 0`, a pure delay).
    pub omega: f64,
    /// Natural frequency in Hz.
    pub frequency_hz: f64,
    /// Damping ratio (1 for a positive real pole and for `z = 0`, negative for an unstable
    /// mode).
    pub damping: f64,
    /// Mode shape `C psi`, one entry per output, largest entry scaled to 1.
    pub shape: Vec<c64>,
}

/// The continuous-time equivalent `s = ln(z) / dt` of a discrete pole, its natural frequency
/// `|s|` (rad/s) and damping ratio `-Re(s) / |s|`. A pole at `z = 0` (a pure delay,
/// infinitely fast) has `s = -inf`, infinite frequency and damping 1, as `sysid.damp` and
/// MATLAB's `damp` report it (not the `ln(f64::MIN_POSITIVE) / dt` of a clamped modulus, a
/// finite frequency above Nyquist).
fn continuous_mode(z: c64, dt: f64) -> (c64, f64, f64) {
    let r = z.norm();
    if r == 0.0 {
        return (c64::new(f64::NEG_INFINITY, 0.0), f64::INFINITY, 1.0);
    }
    let s = c64::new(r.ln(), z.im.atan2(z.re)) / dt;
    let omega = s.norm();
    let damping = if omega > 0.0 { -s.re / omega } else { 1.0 };
    (s, omega, damping)
}

/// Modes of `(A, C)` with sample time `dt`, one per real eigenvalue and one per complex pair
/// (the member with positive imaginary part), sorted by natural frequency.
///
/// ```
/// use faer::mat;
/// use sysid_core::realization::modal_analysis;
/// // a 10 Hz mode with 2 % damping, sampled at 1 kHz
/// let dt = 1e-3;
/// let (w, z) = (2.0 * std::f64::consts::PI * 10.0, 0.02);
/// let (re, im) = (-z * w * dt, w * (1.0 - z * z).sqrt() * dt);
/// let (r, th) = (re.exp(), im);
/// let a = mat![[r * th.cos(), r * th.sin()], [-r * th.sin(), r * th.cos()]];
/// let modes = modal_analysis(a.as_ref(), mat![[1.0, 0.0]].as_ref(), dt).unwrap();
/// assert_eq!(modes.len(), 1);
/// assert!((modes[0].frequency_hz - 10.0).abs() < 1e-9);
/// assert!((modes[0].damping - 0.02).abs() < 1e-9);
/// ```
pub fn modal_analysis(a: MatRef<'_, f64>, c: MatRef<'_, f64>, dt: f64) -> Result<Vec<Mode>> {
    let n = a.nrows();
    if a.ncols() != n || c.ncols() != n {
        return Err(SysidError::ShapeMismatch {
            what: "A and C".into(),
            expected: "A (n, n) and C (l, n)".into(),
            got: format!(
                "A ({}, {}), C ({}, {})",
                a.nrows(),
                a.ncols(),
                c.nrows(),
                c.ncols()
            ),
        });
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SysidError::invalid(
            "dt",
            format!("the sample time must be positive and finite, got {dt}"),
        ));
    }
    crate::error::check_finite("A", a)?;
    crate::error::check_finite("C", c)?;
    let eig = eigen_decomposition(a)?;
    let l = c.nrows();
    let cc = Mat::from_fn(l, n, |i, j| c64::new(c[(i, j)], 0.0));
    let shapes = &cc * &eig.vectors;
    let mut modes = Vec::new();
    for (i, &z) in eig.values.iter().enumerate() {
        if z.im < 0.0
            && eig
                .values
                .iter()
                .any(|w| (w.conj() - z).norm() <= 1e-12 * (1.0 + z.norm()))
        {
            continue; // the partner with positive imaginary part represents the pair
        }
        let (s, omega, damping) = continuous_mode(z, dt);
        let mut shape: Vec<c64> = (0..l).map(|k| shapes[(k, i)]).collect();
        if let Some(big) = shape
            .iter()
            .copied()
            .max_by(|x, y| x.norm().partial_cmp(&y.norm()).unwrap())
        {
            if big.norm() > 0.0 {
                for v in shape.iter_mut() {
                    *v /= big;
                }
            }
        }
        modes.push(Mode {
            eigenvalue: z,
            s,
            omega,
            frequency_hz: omega / (2.0 * std::f64::consts::PI),
            damping,
            shape,
        });
    }
    modes.sort_by(|x, y| {
        x.omega
            .partial_cmp(&y.omega)
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    Ok(modes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_diagonal_modes_are_recovered() {
        // two modes, 5 Hz (1 %) and 40 Hz (5 %), plus a real pole at 0.5, dt = 2 ms
        let dt = 2e-3;
        let mut a = Mat::<f64>::zeros(5, 5);
        for (k, (f, z)) in [(5.0f64, 0.01f64), (40.0, 0.05)].iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let r = (-z * w * dt).exp();
            let th = w * (1.0f64 - z * z).sqrt() * dt;
            a[(2 * k, 2 * k)] = r * th.cos();
            a[(2 * k, 2 * k + 1)] = r * th.sin();
            a[(2 * k + 1, 2 * k)] = -r * th.sin();
            a[(2 * k + 1, 2 * k + 1)] = r * th.cos();
        }
        a[(4, 4)] = 0.5;
        let c = Mat::from_fn(2, 5, |i, j| (i + 2 * j) as f64 * 0.1 + 0.05);
        let modes = modal_analysis(a.as_ref(), c.as_ref(), dt).unwrap();
        assert_eq!(modes.len(), 3);
        assert!(
            (modes[0].frequency_hz - 5.0).abs() < 1e-9 && (modes[0].damping - 0.01).abs() < 1e-9
        );
        assert!(
            (modes[1].frequency_hz - 40.0).abs() < 1e-9 && (modes[1].damping - 0.05).abs() < 1e-9
        );
        assert!((modes[2].damping - 1.0).abs() < 1e-12);
        assert!((modes[2].omega - 0.5f64.ln().abs() / dt).abs() < 1e-9);
        for m in &modes {
            let big = m.shape.iter().map(|z| z.norm()).fold(0.0, f64::max);
            assert!((big - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn pole_at_zero_is_infinitely_fast_with_damping_one() {
        // z = 0 (a delay state) beside z = 0.5, dt = 0.1: the delay has no finite frequency
        // (it read 7083.96 rad/s, ln(f64::MIN_POSITIVE) / dt, above Nyquist)
        let a = faer::mat![[0.0, 0.0], [1.0, 0.5]];
        let c = faer::mat![[0.0, 1.0]];
        let modes = modal_analysis(a.as_ref(), c.as_ref(), 0.1).unwrap();
        assert_eq!(modes.len(), 2);
        assert!((modes[0].omega - 0.5f64.ln().abs() / 0.1).abs() < 1e-12);
        let delay = &modes[1];
        assert_eq!(delay.eigenvalue.norm(), 0.0);
        assert!(delay.omega.is_infinite() && delay.frequency_hz.is_infinite());
        assert_eq!(delay.damping, 1.0);
        assert_eq!(delay.s.re, f64::NEG_INFINITY);
        assert_eq!(delay.s.im, 0.0);
    }

    #[test]
    fn defective_matrix_is_an_error() {
        let a = faer::mat![[0.5, 1.0], [0.0, 0.5]];
        let c = faer::mat![[1.0, 0.0]];
        assert!(matches!(
            modal_analysis(a.as_ref(), c.as_ref(), 1.0),
            Err(SysidError::Numerical { .. })
        ));
    }

    #[test]
    fn bad_sample_time_is_an_error() {
        let a = Mat::<f64>::identity(1, 1) * faer::Scale(0.5);
        let c = Mat::<f64>::identity(1, 1);
        assert!(modal_analysis(a.as_ref(), c.as_ref(), 0.0).is_err());
        assert!(modal_analysis(a.as_ref(), c.as_ref(), f64::NAN).is_err());
    }
}
