//! Block-Hankel compression: the only step that touches every sample.
//!
//! For a record of `m` inputs and `l` outputs, a past horizon `p` and a future horizon `f`,
//! each window of `w = p + f` consecutive samples starting at time t gives one column of the
//! block-Hankel data matrix
//!
//! ```text
//!        [ U_f ]   u(t+p) ... u(t+w-1)        (f m rows)
//!    H = [ U_p ]   u(t)   ... u(t+p-1)        (p m rows)
//!        [ Y_p ]   y(t)   ... y(t+p-1)        (p l rows)
//!        [ Y_f ]   y(t+p) ... y(t+w-1)        (f l rows)
//! ```
//!
//! (this row order is the one in which SLICOT's MOESP results are reproduced), with `k =
//! (p + f)(m + l)` rows and one column per window. A column never spans two experiments.
//! Compression keeps only the lower-triangular `L` (k x k) of the LQ factorisation
//! `H = L Q^T`, equivalently `H H^T = L L^T`; Q is never formed. Every subspace method needs
//! only L. The data are not divided by the square root of the number of columns (SLICOT's
//! convention).
//!
//! Compressors implement [`Compressor`]: push chunks of samples, mark the end of an
//! experiment, finish into a [`HankelFactor`]. [`QrCompressor`] is exact (sequential QR
//! updates, as SLICOT does with sequential data batches); [`CorrelationCompressor`] is fast
//! (lagged correlation sums, the Gram matrix `H H^T` filled from its block-Hankel shift
//! structure, then Cholesky), with a reported fallback when `H H^T` is numerically singular.

mod correlation;
mod factor;
mod kind;
mod lagsum;
mod qr;

pub use correlation::{
    CorrelationCompressor, CorrelationOptions, CorrelationState, CorrelationSums,
};
pub use factor::{Block, FactorSource, HankelFactor};
pub use kind::{compress_experiments, AnyCompressor, CompressorKind, AUTO_MIN_RELATIVE_PIVOT};
pub use lagsum::lag_sums;
pub use qr::{default_chunk_rows, QrCompressor};

use crate::error::{Result, SysidError};
use faer::MatRef;

/// Shape of the block-Hankel data matrix: channel counts and horizons.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HankelLayout {
    /// Number of inputs m (may be 0 for output-only data).
    pub n_inputs: usize,
    /// Number of outputs l (at least 1).
    pub n_outputs: usize,
    /// Past horizon p (block rows of past data).
    pub past: usize,
    /// Future horizon f (block rows of future data).
    pub future: usize,
}

/// Checks that a window of `past + future` samples fits in the longest experiment
/// (`longest` samples), before anything is sized from the horizons: a horizon too large for
/// the record is [`SysidError::InsufficientData`] naming the largest horizon the record allows,
/// whatever the data matrix would have cost. Zero horizons are left to [`HankelLayout::new`].
///
/// ```
/// use sysid_core::hankel::check_window;
/// assert!(check_window(5, 5, 100).is_ok());
/// let e = check_window(1 << 40, 1, 100).unwrap_err().to_string();
/// assert!(e.contains("horizon <= 50"), "{e}");
/// let e = check_window(2, 2, 3).unwrap_err().to_string();
/// assert!(e.contains("smallest subspace window") && e.ends_with("give a longer record"), "{e}");
/// ```
pub fn check_window(past: usize, future: usize, longest: usize) -> Result<()> {
    if past == 0 || future == 0 {
        return Ok(());
    }
    let w = past.saturating_add(future);
    if w <= longest {
        return Ok(());
    }
    if past <= 2 && future <= 2 {
        // the smallest horizons: nothing to shrink, only the record to lengthen
        return Err(SysidError::InsufficientData {
            context: format!(
                "the smallest subspace window (horizons past={past} + future={future}, {w} \
                 samples in one experiment)"
            ),
            needed: w,
            got: longest,
            fix: "give a longer record",
        });
    }
    Err(SysidError::InsufficientData {
        context: format!(
            "the horizon past={past} + future={future} (past/future: a window of {w} samples, \
             too large for this record; the longest experiment allows horizon <= {})",
            (longest / 2).max(1)
        ),
        needed: w,
        got: longest,
        fix: "choose a smaller horizon (a few times the expected order) or give a longer record",
    })
}

impl HankelLayout {
    /// Checks the window against the longest experiment ([`check_window`]) and then builds the
    /// layout ([`HankelLayout::new`]), so a horizon too large for the record is reported as such
    /// before the data-matrix size limit is looked at.
    pub fn for_record(
        n_inputs: usize,
        n_outputs: usize,
        past: usize,
        future: usize,
        longest: usize,
    ) -> Result<Self> {
        check_window(past, future, longest)?;
        Self::new(n_inputs, n_outputs, past, future)
    }

    /// Checks and builds a layout.
    pub fn new(n_inputs: usize, n_outputs: usize, past: usize, future: usize) -> Result<Self> {
        if n_outputs == 0 {
            return Err(SysidError::invalid(
                "outputs",
                "at least one output channel is needed",
            ));
        }
        if past == 0 || future == 0 {
            return Err(SysidError::invalid(
                "horizon",
                format!("past and future horizons must be >= 1 (got past={past}, future={future})"),
            ));
        }
        let d = n_inputs.checked_add(n_outputs);
        let k = past
            .checked_add(future)
            .and_then(|w| d.and_then(|d| w.checked_mul(d)));
        let Some(k) = k else {
            return Err(SysidError::invalid(
                "horizon",
                format!(
                    "past={past} and future={future} are far too large (the data matrix \
                     would have more rows than can be counted); use a horizon of a few times \
                     the expected order"
                ),
            ));
        };
        crate::error::check_matrix_size("horizon", k, k).map_err(|_| {
            SysidError::invalid(
                "horizon",
                format!(
                    "past={past} and future={future} with {n_inputs} input(s) and \
                     {n_outputs} output(s) give a {k} x {k} data matrix ({:.1} GiB), more \
                     than the {} GiB limit; use a horizon of a few times the expected order",
                    (k as f64).powi(2) * 8.0 / (1u64 << 30) as f64,
                    crate::error::MAX_MATRIX_BYTES >> 30
                ),
            )
        })?;
        Ok(Self {
            n_inputs,
            n_outputs,
            past,
            future,
        })
    }

    /// Samples per Hankel column, `p + f`.
    pub fn window(&self) -> usize {
        self.past + self.future
    }

    /// Number of rows of the data matrix, `(p + f)(m + l)`.
    pub fn k(&self) -> usize {
        self.window() * (self.n_inputs + self.n_outputs)
    }

    /// Row range (start, length) of a block in the canonical row order.
    pub fn block(&self, b: Block) -> (usize, usize) {
        let (m, l, p, f) = (self.n_inputs, self.n_outputs, self.past, self.future);
        match b {
            Block::UFuture => (0, f * m),
            Block::UPast => (f * m, p * m),
            Block::YPast => ((f + p) * m, p * l),
            Block::YFuture => ((f + p) * m + p * l, f * l),
        }
    }

    /// Samples one experiment must have to give at least one Hankel column.
    pub fn min_samples(&self) -> usize {
        self.window()
    }

    /// Writes the data-matrix column of the window starting at sample `t` of (u, y) into
    /// `out` (length k), in the canonical row order.
    pub fn fill_column(&self, u: MatRef<'_, f64>, y: MatRef<'_, f64>, t: usize, out: &mut [f64]) {
        let (m, l, p, f) = (self.n_inputs, self.n_outputs, self.past, self.future);
        let (uf, _) = self.block(Block::UFuture);
        let (up, _) = self.block(Block::UPast);
        let (yp, _) = self.block(Block::YPast);
        let (yf, _) = self.block(Block::YFuture);
        for j in 0..p {
            for c in 0..m {
                out[up + j * m + c] = u[(t + j, c)];
            }
            for c in 0..l {
                out[yp + j * l + c] = y[(t + j, c)];
            }
        }
        for j in 0..f {
            for c in 0..m {
                out[uf + j * m + c] = u[(t + p + j, c)];
            }
            for c in 0..l {
                out[yf + j * l + c] = y[(t + p + j, c)];
            }
        }
    }
}

/// Anything that turns streamed samples into a [`HankelFactor`].
///
/// Chunks are `(samples x channels)` views; consecutive pushes continue the same experiment
/// until [`Compressor::end_experiment`] is called. Memory does not grow with the number of
/// samples pushed.
pub trait Compressor {
    /// Appends samples to the current experiment.
    fn push(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()>;
    /// Closes the current experiment: the next push starts a new one, and no Hankel column
    /// spans the boundary.
    fn end_experiment(&mut self) -> Result<()>;
    /// Closes the last experiment and returns the factor.
    fn finish(self) -> Result<HankelFactor>;
}

/// Checks a chunk against a layout: matching lengths, channel counts and finite values.
pub(crate) fn check_chunk(
    layout: &HankelLayout,
    u: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    offset: usize,
) -> Result<()> {
    check_shapes(layout, u, y)?;
    let shift = |e: SysidError| match e {
        SysidError::NonFinite {
            what,
            sample,
            channel,
        } => SysidError::NonFinite {
            what,
            sample: sample + offset,
            channel,
        },
        other => other,
    };
    crate::error::check_finite("u", u).map_err(shift)?;
    crate::error::check_finite("y", y).map_err(shift)?;
    Ok(())
}

/// The shape part of [`check_chunk`]: channel counts and matching lengths.
pub(crate) fn check_shapes(
    layout: &HankelLayout,
    u: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
) -> Result<()> {
    if u.ncols() != layout.n_inputs {
        return Err(SysidError::ShapeMismatch {
            what: "u".into(),
            expected: format!("(samples, {})", layout.n_inputs),
            got: format!("({}, {})", u.nrows(), u.ncols()),
        });
    }
    if y.ncols() != layout.n_outputs {
        return Err(SysidError::ShapeMismatch {
            what: "y".into(),
            expected: format!("(samples, {})", layout.n_outputs),
            got: format!("({}, {})", y.nrows(), y.ncols()),
        });
    }
    if u.nrows() != y.nrows() && layout.n_inputs > 0 {
        return Err(SysidError::ShapeMismatch {
            what: "u".into(),
            expected: format!(
                "({}, {}) (as many samples as y)",
                y.nrows(),
                layout.n_inputs
            ),
            got: format!("({}, {})", u.nrows(), u.ncols()),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests;

#[cfg(test)]
mod correlation_tests;

#[cfg(test)]
mod lagsum_tests;
