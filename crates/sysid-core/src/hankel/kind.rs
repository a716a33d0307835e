//! The choice of compressor: by value ([`CompressorKind`]) or by name, built into one
//! streaming object ([`AnyCompressor`]) or run over in-memory experiments
//! ([`compress_experiments`], with the exact fallback of the fast compressor).

use super::{
    Compressor, CorrelationCompressor, CorrelationOptions, FactorSource, HankelFactor,
    HankelLayout, QrCompressor,
};
use crate::error::{Result, SysidError};
use faer::MatRef;

/// Which compressor to use.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum CompressorKind {
    /// Exact sequential QR, with an optional number of windows per QR update.
    Qr {
        /// Windows per QR update (`None`: the default).
        chunk_rows: Option<usize>,
    },
    /// Lagged correlation sums; in [`compress_experiments`] it falls back to the exact QR
    /// pass when the Gram matrix is ill-conditioned, recorded as [`FactorSource::QrFallback`].
    Correlation(CorrelationOptions),
    /// The default: the correlation path when its Gram matrix is well enough conditioned
    /// for the factor to match the exact one (smallest relative Cholesky pivot at least
    /// [`AUTO_MIN_RELATIVE_PIVOT`]), else the exact QR pass (in [`compress_experiments`];
    /// recorded as [`FactorSource::QrFallback`]). The pivot is recorded either way.
    Auto(CorrelationOptions),
}

/// Threshold on the smallest relative Cholesky pivot of the centred, scaled Gram matrix
/// above which the `"auto"` compressor keeps the correlation factor. The correlation
/// factor's relative error in its weakest direction is about `c eps / pivot` (c ~ 10-100
/// from the summation), so `1e-6` keeps it below about `1e-8` there (measured: error ~ eps / pivot on nearly collinear inputs) and far smaller in the
/// directions that carry the model; the accuracy suite (tests/test_compressor_accuracy.py)
/// checks Markov parameters within `1e-8` of the exact path.
pub const AUTO_MIN_RELATIVE_PIVOT: f64 = 1e-6;

crate::names::option_names! { CompressorKind, "compressor", false, [
    ("auto", CompressorKind::Auto(CorrelationOptions {
        min_relative_pivot: AUTO_MIN_RELATIVE_PIVOT,
        ..CorrelationOptions::default()
    })),
    ("qr", CompressorKind::Qr { chunk_rows: None }),
    ("correlation", CompressorKind::Correlation(CorrelationOptions::default())),
] }

impl CompressorKind {
    /// Parses `"auto"`, `"qr"` or `"correlation"`; `chunk_rows` sets the windows per QR update or the
    /// samples per block of the correlation sums.
    ///
    /// ```
    /// use sysid_core::hankel::CompressorKind;
    /// assert_eq!(CompressorKind::parse("qr", Some(64)).unwrap(), CompressorKind::Qr { chunk_rows: Some(64) });
    /// assert!(CompressorKind::parse("svd", None).is_err());
    /// ```
    pub fn parse(name: &str, chunk_rows: Option<usize>) -> Result<Self> {
        Ok(match (name.parse()?, chunk_rows) {
            (CompressorKind::Qr { .. }, rows) => CompressorKind::Qr { chunk_rows: rows },
            (CompressorKind::Correlation(mut o), Some(r)) => {
                o.block_rows = r.max(1);
                CompressorKind::Correlation(o)
            }
            (CompressorKind::Auto(mut o), Some(r)) => {
                o.block_rows = r.max(1);
                CompressorKind::Auto(o)
            }
            (kind, None) => kind,
        })
    }

    /// The name [`CompressorKind::parse`] accepts for this kind.
    pub fn name(&self) -> &'static str {
        match self {
            CompressorKind::Qr { .. } => "qr",
            CompressorKind::Correlation(_) => "correlation",
            CompressorKind::Auto(_) => "auto",
        }
    }

    /// Checks that the work memory of this kind for `layout` (the QR work matrix of
    /// `(k + chunk_rows) x k`) can be allocated (correlation blocks are bounded by the data).
    ///
    /// ```
    /// use sysid_core::hankel::{CompressorKind, HankelLayout};
    /// let layout = HankelLayout::new(1, 1, 10, 10).unwrap();
    /// assert!(CompressorKind::parse("qr", Some(1 << 50)).unwrap().check(&layout).is_err());
    /// assert!(CompressorKind::parse("qr", Some(256)).unwrap().check(&layout).is_ok());
    /// ```
    pub fn check(&self, layout: &HankelLayout) -> Result<()> {
        let k = layout.k();
        let rows = match self {
            CompressorKind::Qr {
                chunk_rows: Some(0),
            } => {
                return Err(SysidError::invalid(
                    "chunk_rows",
                    "must be a positive integer, got 0",
                ))
            }
            CompressorKind::Qr {
                chunk_rows: Some(r),
            } => k.checked_add(*r),
            // "auto" may fall back to the exact pass with the default window count
            CompressorKind::Qr { chunk_rows: None } | CompressorKind::Auto(_) => {
                k.checked_add(super::default_chunk_rows(k))
            }
            // a block never holds more samples than the chunk pushed: bounded by the data
            CompressorKind::Correlation(_) => return Ok(()),
        };
        match rows {
            Some(r) => crate::error::check_matrix_size("chunk_rows", r, k),
            None => crate::error::check_matrix_size("chunk_rows", usize::MAX, k),
        }
    }

    /// Checks a compression before anything is sized: the window against the longest
    /// experiment when the caller knows it ([`super::check_window`]: arrays, files and Dask
    /// arrays know their lengths, a generator does not), then the work memory
    /// ([`CompressorKind::check`]). Without `longest` the record is checked at `finish`;
    /// until a first window is complete the exact compressor allocates no work matrix, and
    /// until an experiment with one closes the correlation compressor no Gram matrix.
    ///
    /// ```
    /// use sysid_core::hankel::{CompressorKind, HankelLayout};
    /// let layout = HankelLayout::new(1, 1, 2000, 2000).unwrap();
    /// let qr = CompressorKind::parse("qr", None).unwrap();
    /// assert!(qr.check_stream(&layout, Some(500)).is_err());
    /// assert!(qr.check_stream(&layout, Some(10_000)).is_ok());
    /// assert!(qr.check_stream(&layout, None).is_ok());
    /// ```
    pub fn check_stream(&self, layout: &HankelLayout, longest: Option<usize>) -> Result<()> {
        if let Some(n) = longest {
            super::check_window(layout.past, layout.future, n)?;
        }
        self.check(layout)
    }

    /// A streaming compressor of this kind for `layout`.
    pub fn build(self, layout: HankelLayout) -> AnyCompressor {
        match self {
            CompressorKind::Qr {
                chunk_rows: Some(r),
            } => AnyCompressor::Qr(QrCompressor::with_chunk_rows(layout, r)),
            CompressorKind::Qr { chunk_rows: None } => AnyCompressor::Qr(QrCompressor::new(layout)),
            CompressorKind::Correlation(opts) | CompressorKind::Auto(opts) => {
                AnyCompressor::Correlation(CorrelationCompressor::with_options(layout, opts))
            }
        }
    }
}

/// Either compressor behind one type (for callers that choose at run time).
#[derive(Debug, Clone)]
pub enum AnyCompressor {
    /// The exact compressor.
    Qr(QrCompressor),
    /// The fast compressor.
    Correlation(CorrelationCompressor),
}

impl Compressor for AnyCompressor {
    fn push(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
        match self {
            AnyCompressor::Qr(c) => c.push(u, y),
            AnyCompressor::Correlation(c) => c.push(u, y),
        }
    }

    fn end_experiment(&mut self) -> Result<()> {
        match self {
            AnyCompressor::Qr(c) => c.end_experiment(),
            AnyCompressor::Correlation(c) => c.end_experiment(),
        }
    }

    fn finish(self) -> Result<HankelFactor> {
        match self {
            AnyCompressor::Qr(c) => c.finish(),
            AnyCompressor::Correlation(c) => c.finish(),
        }
    }
}

/// Compresses in-memory experiments `(u, y)` with the chosen compressor.
///
/// ```
/// use faer::Mat;
/// use sysid_core::hankel::{compress_experiments, CompressorKind, CorrelationOptions, HankelLayout};
/// let layout = HankelLayout::new(1, 1, 3, 3).unwrap();
/// let u = Mat::from_fn(200, 1, |i, _| ((i * 7919) % 13) as f64 - 6.0);
/// let y = Mat::from_fn(200, 1, |i, _| ((i * 104729) % 11) as f64 - 5.0);
/// let kind = CompressorKind::Correlation(CorrelationOptions::default());
/// let f = compress_experiments(layout, &[(u.as_ref(), y.as_ref())], kind).unwrap();
/// assert_eq!(f.n_columns(), 200 - 6 + 1);
/// ```
pub fn compress_experiments(
    layout: HankelLayout,
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
    kind: CompressorKind,
) -> Result<HankelFactor> {
    let longest = experiments
        .iter()
        .map(|(_, y)| y.nrows())
        .max()
        .unwrap_or(0);
    kind.check_stream(&layout, Some(longest))?;
    let run = |kind: CompressorKind| -> Result<HankelFactor> {
        let mut c = kind.build(layout);
        for (u, y) in experiments {
            c.push(*u, *y)?;
            c.end_experiment()?;
        }
        c.finish()
    };
    if let CompressorKind::Auto(_) = kind {
        // fewer Hankel columns than rows: the Gram matrix is singular, the exact path it is
        let w = layout.window();
        let cols: usize = experiments
            .iter()
            .map(|(_, y)| (y.nrows() + 1).saturating_sub(w))
            .sum();
        if cols < layout.k() {
            return Ok(run(CompressorKind::Qr { chunk_rows: None })?
                .with_source(FactorSource::QrFallback {
                    relative_pivot: 0.0,
                })
                .with_relative_pivot(Some(0.0)));
        }
    }
    let f = run(kind)?;
    match f.source() {
        // the data are in memory: redo the exact pass rather than keep a degraded factor
        FactorSource::CorrelationIllConditioned { relative_pivot, .. } => {
            Ok(run(CompressorKind::Qr { chunk_rows: None })?
                .with_source(FactorSource::QrFallback { relative_pivot })
                .with_relative_pivot(Some(relative_pivot)))
        }
        _ => Ok(f),
    }
}
