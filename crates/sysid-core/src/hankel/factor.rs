//! The compressed summary of a record: the triangular factor of its block-Hankel matrix.

use super::HankelLayout;
use crate::error::{Result, SysidError};
use crate::linalg::lq_lower;
use faer::{Mat, MatRef};

/// The four block rows of the data matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Block {
    /// Future inputs U_f.
    UFuture,
    /// Past inputs U_p.
    UPast,
    /// Past outputs Y_p.
    YPast,
    /// Future outputs Y_f.
    YFuture,
}

/// How a [`HankelFactor`] was obtained, so that callers can report a fallback.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum FactorSource {
    /// Exact sequential QR ([`super::QrCompressor`]).
    Qr,
    /// Lagged correlation sums and Cholesky ([`super::CorrelationCompressor`]), well
    /// conditioned: agrees with the exact factor to round-off times the condition number.
    Correlation,
    /// The correlation Gram matrix was numerically singular or nearly so: the relative
    /// Cholesky pivot fell below the threshold (the Cholesky factor is kept, `clipped = 0`),
    /// or Cholesky failed and the factor was built from the eigendecomposition with the
    /// negative eigenvalues set to zero (`clipped > 0`). Singular values of the data matrix
    /// below about `sqrt(eps)` times the largest are not resolved: rerun with the exact QR
    /// compressor where they matter.
    CorrelationIllConditioned {
        /// Eigenvalues of the (centred, scaled) Gram matrix that were negative and clipped.
        clipped: usize,
        /// Smallest relative Cholesky pivot (`min L_ii^2 / max G_ii`, 0 when it failed).
        relative_pivot: f64,
    },
    /// The correlation path was ill-conditioned and the data, still in memory, were
    /// compressed again with the exact QR compressor.
    QrFallback {
        /// Smallest relative Cholesky pivot of the rejected correlation factor.
        relative_pivot: f64,
    },
}

crate::names::option_names! { FactorSource, "source", false, [
    ("qr", FactorSource::Qr), ("correlation", FactorSource::Correlation),
    ("correlation-ill-conditioned", FactorSource::CorrelationIllConditioned {
        clipped: 0, relative_pivot: 0.0 }),
    ("qr-fallback", FactorSource::QrFallback { relative_pivot: 0.0 }),
] }

impl FactorSource {
    /// The source named `name` (see [`FactorSource::name`]) with the recorded pivot.
    ///
    /// ```
    /// use sysid_core::hankel::FactorSource;
    /// let s = FactorSource::from_name("qr-fallback", 1e-9).unwrap();
    /// assert_eq!(s, FactorSource::QrFallback { relative_pivot: 1e-9 });
    /// ```
    pub fn from_name(name: &str, relative_pivot: f64) -> crate::error::Result<Self> {
        Ok(match name.parse()? {
            FactorSource::CorrelationIllConditioned { clipped, .. } => {
                FactorSource::CorrelationIllConditioned {
                    clipped,
                    relative_pivot,
                }
            }
            FactorSource::QrFallback { .. } => FactorSource::QrFallback { relative_pivot },
            other => other,
        })
    }

    /// Short name: `"qr"`, `"correlation"`, `"correlation-ill-conditioned"` or `"qr-fallback"`.
    pub fn name(&self) -> &'static str {
        match self {
            FactorSource::Qr => "qr",
            FactorSource::Correlation => "correlation",
            FactorSource::CorrelationIllConditioned { .. } => "correlation-ill-conditioned",
            FactorSource::QrFallback { .. } => "qr-fallback",
        }
    }

    fn rank(&self) -> u8 {
        match self {
            FactorSource::Qr => 0,
            FactorSource::Correlation => 1,
            FactorSource::QrFallback { .. } => 2,
            FactorSource::CorrelationIllConditioned { .. } => 3,
        }
    }
}

/// Lower-triangular `L` with `H H^T = L L^T`, the data's block-Hankel matrix H compressed.
///
/// It is a value: it can be merged with the factor of another experiment recorded with the
/// same layout ([`HankelFactor::merge`]), stored, and used for many orders and weightings.
#[derive(Debug, Clone, PartialEq)]
pub struct HankelFactor {
    layout: HankelLayout,
    l: Mat<f64>,
    n_columns: usize,
    n_experiments: usize,
    source: FactorSource,
    relative_pivot: Option<f64>,
}

impl HankelFactor {
    /// Wraps a factor computed elsewhere; `l` must be k x k and lower triangular.
    pub fn from_parts(
        layout: HankelLayout,
        l: Mat<f64>,
        n_columns: usize,
        n_experiments: usize,
    ) -> Result<Self> {
        let k = layout.k();
        if l.nrows() != k || l.ncols() != k {
            return Err(SysidError::ShapeMismatch {
                what: "L".into(),
                expected: format!("({k}, {k})"),
                got: format!("({}, {})", l.nrows(), l.ncols()),
            });
        }
        crate::error::check_finite("L", l.as_ref())?;
        for j in 0..k {
            for i in 0..j {
                if l[(i, j)] != 0.0 {
                    return Err(SysidError::invalid("L", "must be lower triangular"));
                }
            }
        }
        Ok(Self {
            layout,
            l,
            n_columns,
            n_experiments,
            source: FactorSource::Qr,
            relative_pivot: None,
        })
    }

    /// The same factor, recorded as obtained by `source`.
    pub fn with_source(mut self, source: FactorSource) -> Self {
        self.source = source;
        self
    }

    /// The same factor, with the smallest relative Cholesky pivot of the correlation path
    /// that produced (or was rejected for) it.
    pub fn with_relative_pivot(mut self, pivot: Option<f64>) -> Self {
        self.relative_pivot = pivot;
        self
    }

    /// Smallest relative Cholesky pivot `min La_ii^2 / max Ga_ii` of the centred, scaled
    /// Gram matrix when the correlation path was run (also when it was rejected for the
    /// exact path), `None` for the exact compressor alone. About `1 / cond(H)^2`: the
    /// correlation factor loses `eps / pivot` relative accuracy in its weakest direction.
    pub fn relative_pivot(&self) -> Option<f64> {
        match (self.relative_pivot, self.source) {
            (Some(p), _) => Some(p),
            (None, FactorSource::CorrelationIllConditioned { relative_pivot, .. })
            | (None, FactorSource::QrFallback { relative_pivot }) => Some(relative_pivot),
            _ => None,
        }
    }

    /// How the factor was obtained (exact QR, correlation, or a fallback).
    pub fn source(&self) -> FactorSource {
        self.source
    }

    /// The layout (channel counts and horizons).
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }

    /// The k x k lower-triangular factor.
    pub fn l(&self) -> MatRef<'_, f64> {
        self.l.as_ref()
    }

    /// Number of Hankel columns summarised (samples minus `p + f - 1` per experiment).
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Number of experiments summarised.
    pub fn n_experiments(&self) -> usize {
        self.n_experiments
    }

    /// Rows of L belonging to one block.
    pub fn rows(&self, b: super::Block) -> MatRef<'_, f64> {
        let (s, n) = self.layout.block(b);
        self.l.as_ref().subrows(s, n)
    }

    /// The factor of the concatenated experiments of `self` and `other`.
    pub fn merge(&self, other: &HankelFactor) -> Result<HankelFactor> {
        if self.layout != other.layout {
            return Err(SysidError::IncompatibleFactors {
                reason: format!("layouts differ: {:?} vs {:?}", self.layout, other.layout),
            });
        }
        let k = self.layout.k();
        let mut both = Mat::<f64>::zeros(k, 2 * k);
        both.as_mut().subcols_mut(0, k).copy_from(self.l.as_ref());
        both.as_mut().subcols_mut(k, k).copy_from(other.l.as_ref());
        Ok(HankelFactor {
            layout: self.layout,
            l: lq_lower(both.as_ref()),
            n_columns: self.n_columns + other.n_columns,
            n_experiments: self.n_experiments + other.n_experiments,
            source: if other.source.rank() > self.source.rank() {
                other.source
            } else {
                self.source
            },
            relative_pivot: match (self.relative_pivot(), other.relative_pivot()) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            },
        })
    }
}
