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

    /// Root mean square of each input and each output over the samples the factor
    /// summarises, read from it: row `r` of `L` has the norm of row `r` of the data matrix,
    /// so a channel's mean square is its rows' squared norms averaged over the window's
    /// lags and divided by the number of columns. A channel that is zero throughout gets 1.
    ///
    /// ```
    /// use faer::Mat;
    /// use sysid_core::hankel::{compress_experiments, CompressorKind, HankelLayout};
    /// let u = Mat::<f64>::from_fn(200, 1, |t, _| if t % 2 == 0 { 2.0 } else { -2.0 });
    /// let y = Mat::<f64>::from_fn(200, 1, |t, _| 3.0 * (t as f64).sin());
    /// let lay = HankelLayout::new(1, 1, 3, 3).unwrap();
    /// let f = compress_experiments(lay, &[(u.as_ref(), y.as_ref())], CompressorKind::Qr { chunk_rows: None })
    ///     .unwrap();
    /// let (su, _) = f.channel_rms();
    /// assert!((su[0] - 2.0).abs() < 1e-12);
    /// ```
    pub fn channel_rms(&self) -> (Vec<f64>, Vec<f64>) {
        let lay = self.layout;
        let (m, l) = (lay.n_inputs, lay.n_outputs);
        let cols = self.n_columns.max(1) as f64;
        let row_sq = |r: usize| -> f64 {
            let row = self.l.as_ref().row(r);
            row.iter().map(|v| v * v).sum::<f64>()
        };
        let rms = |blocks: [(Block, usize); 2], width: usize| -> Vec<f64> {
            (0..width)
                .map(|c| {
                    let (mut sq, mut lags) = (0.0, 0usize);
                    for (b, n_lags) in blocks {
                        let (start, _) = lay.block(b);
                        for j in 0..n_lags {
                            sq += row_sq(start + j * width + c);
                            lags += 1;
                        }
                    }
                    let v = (sq / (lags.max(1) as f64 * cols)).sqrt();
                    if v.is_finite() && v > 0.0 {
                        v
                    } else {
                        1.0
                    }
                })
                .collect()
        };
        let (p, f) = (lay.past, lay.future);
        (
            rms([(Block::UPast, p), (Block::UFuture, f)], m),
            rms([(Block::YPast, p), (Block::YFuture, f)], l),
        )
    }

    /// The factor of the same record with input channel `c` divided by `input_scale[c]` and
    /// output channel `c` by `output_scale[c]`: the rows of `L` scaled and triangularised
    /// again (one LQ of a `k x k` matrix, no pass over the data).
    ///
    /// ```
    /// use faer::Mat;
    /// use sysid_core::hankel::{compress_experiments, CompressorKind, HankelLayout};
    /// let u = Mat::<f64>::from_fn(100, 1, |t, _| ((t * 7) % 5) as f64 - 2.0);
    /// let y = Mat::<f64>::from_fn(100, 1, |t, _| 1e3 * ((t * 3) % 7) as f64);
    /// let y2 = Mat::<f64>::from_fn(100, 1, |t, _| y[(t, 0)] / 1e3);
    /// let lay = HankelLayout::new(1, 1, 2, 2).unwrap();
    /// let kind = CompressorKind::Qr { chunk_rows: None };
    /// let big = compress_experiments(lay, &[(u.as_ref(), y.as_ref())], kind).unwrap();
    /// let small = compress_experiments(lay, &[(u.as_ref(), y2.as_ref())], kind).unwrap();
    /// let scaled = big.scaled(&[1.0], &[1e3]).unwrap();
    /// let gap = (scaled.l() * scaled.l().transpose() - small.l() * small.l().transpose()).norm_max();
    /// assert!(gap < 1e-9);
    /// ```
    pub fn scaled(&self, input_scale: &[f64], output_scale: &[f64]) -> Result<HankelFactor> {
        let lay = self.layout;
        for (what, s, n) in [
            ("input_scale", input_scale, lay.n_inputs),
            ("output_scale", output_scale, lay.n_outputs),
        ] {
            if s.len() != n {
                return Err(SysidError::ShapeMismatch {
                    what: what.into(),
                    expected: format!("{n} entries"),
                    got: format!("{} entries", s.len()),
                });
            }
            if s.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(SysidError::invalid(
                    what,
                    "every scale must be finite and positive",
                ));
            }
        }
        let (p, f) = (lay.past, lay.future);
        let mut l = self.l.clone();
        for (b, n_lags, scale) in [
            (Block::UFuture, f, input_scale),
            (Block::UPast, p, input_scale),
            (Block::YPast, p, output_scale),
            (Block::YFuture, f, output_scale),
        ] {
            let (start, _) = lay.block(b);
            let w = scale.len();
            for j in 0..n_lags {
                for (c, s) in scale.iter().enumerate() {
                    let r = start + j * w + c;
                    for v in l.as_mut().row_mut(r).iter_mut() {
                        *v /= s;
                    }
                }
            }
        }
        Ok(HankelFactor {
            layout: lay,
            l: lq_lower(l.as_ref()),
            n_columns: self.n_columns,
            n_experiments: self.n_experiments,
            source: self.source,
            relative_pivot: self.relative_pivot,
        })
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
