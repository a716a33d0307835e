//! The four parameter updates of MATLAB's online estimators.

use crate::error::{Result, SysidError};

/// How the parameters follow the data.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Method {
    /// Recursive least squares with exponential forgetting `0 < lambda <= 1` (memory about
    /// `1 / (1 - lambda)` samples).
    Forgetting {
        /// The forgetting factor.
        lambda: f64,
    },
    /// The parameters as a random walk with covariance `R1` (p x p, row-major) observed with
    /// noise variance `R2`.
    Kalman {
        /// Process-noise covariance (row-major p x p).
        r1: Vec<f64>,
        /// Measurement-noise variance.
        r2: f64,
    },
    /// `theta += gamma psi eps / (bias + |psi|^2)`.
    NormalizedGradient {
        /// Adaptation gain.
        gamma: f64,
        /// Added to `|psi|^2` so that the step stays bounded when `psi` vanishes.
        bias: f64,
    },
    /// `theta += gamma psi eps`.
    Gradient {
        /// Adaptation gain.
        gamma: f64,
    },
}

crate::names::option_names! { Method, "method", false, [
    ("forgetting", Method::Forgetting { lambda: 1.0 }),
    ("kalman", Method::Kalman { r1: Vec::new(), r2: 1.0 }),
    ("normalized_gradient", Method::NormalizedGradient { gamma: 1.0, bias: f64::EPSILON }),
    ("gradient", Method::Gradient { gamma: 1.0 }),
] }

/// The settings of every [`Method`], of which [`Method::from_name`] takes those it needs.
#[derive(Debug, Clone, PartialEq)]
pub struct MethodSettings {
    /// Forgetting factor (`"forgetting"`).
    pub forgetting: f64,
    /// Process-noise covariance, row-major p x p (`"kalman"`; `None`: `0.1 I`).
    pub process_noise: Option<Vec<f64>>,
    /// Measurement-noise variance (`"kalman"`).
    pub noise_variance: f64,
    /// Adaptation gain (the gradient methods).
    pub gain: f64,
    /// Bias of the normalised gradient.
    pub bias: f64,
}

impl Method {
    /// The method named `name` for `p` parameters, with its settings from `s`.
    ///
    /// ```
    /// use sysid_core::recursive::{Method, MethodSettings};
    /// let s = MethodSettings { forgetting: 0.99, process_noise: None, noise_variance: 1.0,
    ///     gain: 1.0, bias: 0.0 };
    /// assert_eq!(Method::from_name("forgetting", 2, &s).unwrap(),
    ///            Method::Forgetting { lambda: 0.99 });
    /// assert!(Method::from_name("lms", 2, &s).is_err());
    /// ```
    pub fn from_name(name: &str, p: usize, s: &MethodSettings) -> Result<Self> {
        Ok(match name.parse()? {
            Method::Forgetting { .. } => Method::Forgetting {
                lambda: s.forgetting,
            },
            Method::Kalman { .. } => Method::Kalman {
                r1: s.process_noise.clone().unwrap_or_else(|| {
                    (0..p * p)
                        .map(|i| if i % (p + 1) == 0 { 0.1 } else { 0.0 })
                        .collect()
                }),
                r2: s.noise_variance,
            },
            Method::NormalizedGradient { .. } => Method::NormalizedGradient {
                gamma: s.gain,
                bias: s.bias,
            },
            Method::Gradient { .. } => Method::Gradient { gamma: s.gain },
        })
    }

    /// Checks the settings for `p` parameters.
    pub(super) fn check(&self, p: usize) -> Result<()> {
        let bad = |name: &'static str, why: String| Err(SysidError::invalid(name, why));
        match self {
            Method::Forgetting { lambda } if !(*lambda > 0.0 && *lambda <= 1.0) => bad(
                "forgetting",
                format!(
                    "the forgetting factor must be in (0, 1], got {lambda}; 0.98..0.999 is usual"
                ),
            ),
            Method::Kalman { r1, r2 } => {
                if r1.len() != p * p {
                    return Err(SysidError::ShapeMismatch {
                        what: "process_noise".into(),
                        expected: format!("({p}, {p})"),
                        got: format!("{} values", r1.len()),
                    });
                }
                if r1.iter().any(|v| !v.is_finite())
                    || (0..p).any(|i| r1[i * p + i] < 0.0)
                    || (0..p).any(|i| (0..i).any(|j| r1[i * p + j] != r1[j * p + i]))
                {
                    return bad(
                        "process_noise",
                        "must be a finite symmetric matrix with a non-negative diagonal".into(),
                    );
                }
                if !(r2.is_finite() && *r2 > 0.0) {
                    return bad(
                        "noise_variance",
                        format!("must be a finite number > 0, got {r2}"),
                    );
                }
                Ok(())
            }
            Method::NormalizedGradient { gamma, bias } => {
                if !(gamma.is_finite() && *gamma > 0.0) {
                    return bad("gain", format!("must be a finite number > 0, got {gamma}"));
                }
                if !(bias.is_finite() && *bias >= 0.0) {
                    return bad("bias", format!("must be a finite number >= 0, got {bias}"));
                }
                Ok(())
            }
            Method::Gradient { gamma } if !(gamma.is_finite() && *gamma > 0.0) => {
                bad("gain", format!("must be a finite number > 0, got {gamma}"))
            }
            _ => Ok(()),
        }
    }

    /// Whether the method carries a covariance `P`.
    pub fn uses_covariance(&self) -> bool {
        matches!(self, Method::Forgetting { .. } | Method::Kalman { .. })
    }
}

/// `theta += K eps` and the update of `P`; `false` (nothing changed) when the result would
/// not be finite.
pub(super) fn apply(
    method: &Method,
    theta: &mut [f64],
    p: &mut [f64],
    psi: &[f64],
    h: &mut [f64],
    eps: f64,
) -> bool {
    let n = theta.len();
    match method {
        Method::Forgetting { lambda } => covariance_update(theta, p, psi, h, eps, *lambda, None),
        Method::Kalman { r1, r2 } => covariance_update(theta, p, psi, h, eps, *r2, Some(r1)),
        Method::NormalizedGradient { gamma, bias } => {
            let nrm: f64 = psi.iter().map(|v| v * v).sum();
            let denom = bias + nrm;
            if denom <= 0.0 {
                return true; // psi = 0 and no bias: nothing to learn from this sample
            }
            gradient_step(theta, psi, gamma * eps / denom, n)
        }
        Method::Gradient { gamma } => gradient_step(theta, psi, gamma * eps, n),
    }
}

fn gradient_step(theta: &mut [f64], psi: &[f64], g: f64, n: usize) -> bool {
    if !(0..n).all(|i| (theta[i] + g * psi[i]).is_finite()) {
        return false;
    }
    for i in 0..n {
        theta[i] += g * psi[i];
    }
    true
}

/// `h = P psi`, `K = h / (s + psi^T h)`; forgetting (`r1` None, `s = lambda`):
/// `P <- (P - h h^T / denom) / lambda`; Kalman (`s = R2`): `P <- P - h h^T / denom + R1`.
/// Written entry by entry with `h_i h_j`, so a symmetric `P` stays exactly symmetric.
fn covariance_update(
    theta: &mut [f64],
    p: &mut [f64],
    psi: &[f64],
    h: &mut [f64],
    eps: f64,
    s: f64,
    r1: Option<&Vec<f64>>,
) -> bool {
    let n = theta.len();
    for i in 0..n {
        let row = &p[i * n..(i + 1) * n];
        h[i] = row.iter().zip(psi).map(|(a, b)| a * b).sum();
    }
    let denom = s + psi.iter().zip(h.iter()).map(|(a, b)| a * b).sum::<f64>();
    if !(denom.is_finite() && denom > 0.0) {
        return false;
    }
    let g = eps / denom;
    if !(0..n).all(|i| (theta[i] + g * h[i]).is_finite()) {
        return false;
    }
    for i in 0..n {
        theta[i] += g * h[i];
    }
    let inv = 1.0 / denom;
    match r1 {
        None => {
            let scale = 1.0 / s;
            for i in 0..n {
                let hi = h[i];
                let row = &mut p[i * n..(i + 1) * n];
                for (pij, hj) in row.iter_mut().zip(h.iter()) {
                    *pij = (*pij - (hi * hj) * inv) * scale;
                }
            }
        }
        Some(r1) => {
            for i in 0..n {
                let hi = h[i];
                let row = &mut p[i * n..(i + 1) * n];
                let q = &r1[i * n..(i + 1) * n];
                for ((pij, hj), qij) in row.iter_mut().zip(h.iter()).zip(q) {
                    *pij = *pij - (hi * hj) * inv + qij;
                }
            }
        }
    }
    true
}
