//! The nonlinear units of sigmoid and wavelet networks, with their derivatives.
//!
//! Every unit maps the standardised regressors `z` (length `nz`) to a scalar through
//! `nz + 1` parameters `p`:
//!
//! ```text
//! sigmoid:  g = 1 / (1 + exp(-s)),          s = w^T z + b,        p = [w, b]
//! wavelet:  g = (nz - r2) exp(-r2 / 2),     r2 = d^2 |z - c|^2,   p = [d, c]
//! scaling:  g = exp(-r2 / 2),               r2 = d^2 |z - c|^2,   p = [d, c]
//! ```
//!
//! (the wavelet is the radial "Mexican hat", the scaling function its Gaussian). The
//! derivatives with respect to `p` build the Jacobian of the network; those with respect to
//! `z` the sensitivities of a free-run simulation.

/// The kind of one unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitKind {
    /// Logistic sigmoid of a projection (ridge function).
    Sigmoid,
    /// Radial Mexican-hat wavelet with dilation and translation.
    Wavelet,
    /// Radial Gaussian scaling function with dilation and translation.
    Scaling,
}

impl UnitKind {
    /// The kind of code `k` (0 sigmoid, 1 wavelet, 2 scaling), as the bindings pass it.
    pub fn from_code(k: u8) -> Option<Self> {
        match k {
            0 => Some(UnitKind::Sigmoid),
            1 => Some(UnitKind::Wavelet),
            2 => Some(UnitKind::Scaling),
            _ => None,
        }
    }

    /// Number of parameters of a unit on `nz` regressors: `nz + 1`.
    pub fn n_params(self, nz: usize) -> usize {
        nz + 1
    }

    /// The unit's value at `z`.
    ///
    /// ```
    /// use sysid_core::narx::network::units::UnitKind;
    /// assert_eq!(UnitKind::Sigmoid.value(&[1.0, 0.0], &[0.0]), 0.5);
    /// assert_eq!(UnitKind::Wavelet.value(&[1.0, 0.0], &[0.0]), 1.0);
    /// ```
    #[inline]
    pub fn value(self, p: &[f64], z: &[f64]) -> f64 {
        self.value_grad(p, z, None, None)
    }

    /// The value, and when asked its gradients with respect to the parameters (`dp`,
    /// length `nz + 1`) and to the regressors (`dz`, length `nz`).
    #[inline]
    pub fn value_grad(
        self,
        p: &[f64],
        z: &[f64],
        dp: Option<&mut [f64]>,
        dz: Option<&mut [f64]>,
    ) -> f64 {
        let nz = z.len();
        match self {
            UnitKind::Sigmoid => {
                let s = p[nz] + p[..nz].iter().zip(z).map(|(w, v)| w * v).sum::<f64>();
                let g = logistic(s);
                let gp = g * (1.0 - g);
                if let Some(dp) = dp {
                    for (d, v) in dp.iter_mut().zip(z) {
                        *d = gp * v;
                    }
                    dp[nz] = gp;
                }
                if let Some(dz) = dz {
                    for (d, w) in dz.iter_mut().zip(&p[..nz]) {
                        *d = gp * w;
                    }
                }
                g
            }
            UnitKind::Wavelet | UnitKind::Scaling => {
                let d = p[0];
                let q: f64 = z.iter().zip(&p[1..]).map(|(v, c)| (v - c) * (v - c)).sum();
                let r2 = d * d * q;
                let e = (-0.5 * r2).exp();
                let (g, h) = if self == UnitKind::Wavelet {
                    let a = nz as f64 - r2;
                    (a * e, -e * (1.0 + 0.5 * a)) // h = dg / dr2
                } else {
                    (e, -0.5 * e)
                };
                if let Some(dp) = dp {
                    dp[0] = h * 2.0 * d * q;
                    for ((o, v), c) in dp[1..].iter_mut().zip(z).zip(&p[1..]) {
                        *o = -h * 2.0 * d * d * (v - c);
                    }
                }
                if let Some(dz) = dz {
                    for ((o, v), c) in dz.iter_mut().zip(z).zip(&p[1..]) {
                        *o = h * 2.0 * d * d * (v - c);
                    }
                }
                g
            }
        }
    }
}

/// `1 / (1 + exp(-s))` without overflow for large `|s|`.
#[inline]
pub fn logistic(s: f64) -> f64 {
    if s >= 0.0 {
        1.0 / (1.0 + (-s).exp())
    } else {
        let e = s.exp();
        e / (1.0 + e)
    }
}
