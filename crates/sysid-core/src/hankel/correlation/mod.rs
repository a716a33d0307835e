//! The fast compressor: lagged correlation sums, the Gram matrix from its block-Hankel shift
//! structure, then Cholesky.
//!
//! With `z_t = [u_t; y_t]` (d = m + l channels), window `w = p + f` and `T = N - w + 1`
//! columns, the Gram matrix of the data matrix in natural order (block `a` = sample offset
//! `a`) is `G_ab = sum_{t<T} z_{t+a} z_{t+b}^T`. For `a <= b`, with `tau = b - a`,
//!
//! ```text
//! G_ab = S_tau - sum_{t<a} z_t z_{t+tau}^T - sum_{t=a+T}^{N-1-tau} z_t z_{t+tau}^T,
//! S_tau = sum_{t=0}^{N-1-tau} z_t z_{t+tau}^T,
//! ```
//!
//! so only the `w` lagged sums (`2 w d^2 N` flops, one GEMM per block of samples) touch every
//! sample; the corrections use the first and last `w - 1` samples of each experiment. Sums are
//! formed in centred, scaled coordinates `x = (z - c) / s` (shift `c` and power-of-two scale
//! `s` per channel, from the first chunk), together with the column sums `sum_t X_t`. With
//! `Ga = [[X X^T, X 1], [1^T X^T, T]] = La La^T` (Cholesky, well conditioned), the raw
//! data matrix `H = [diag(s) | c] [X; 1^T]` has `H H^T = (E La)(E La)^T`, `E = [diag(s) | c]`,
//! and `L` is the LQ triangle of the rows of `E La` permuted to the canonical order: the same
//! matrix the exact compressor factors, up to round-off.
//!
//! Samples are processed in blocks with fixed boundaries (in parallel with rayon); partial
//! sums of contiguous segments are combined pairwise in a fixed order (the cross terms between
//! neighbouring segments come from their boundary samples), so the result does not depend on
//! the number of threads.
//!
//! Stages, a file each: `segment.rs` (sums of one stretch of samples, and two stretches
//! joined), `gram.rs` (an experiment closed into the Gram matrix), `factor.rs` (Cholesky and
//! the LQ triangle of the raw data), `state.rs` (plain-data snapshots); the accumulator and
//! the compressor here.

mod factor;
mod gram;
mod segment;
mod state;

pub use state::CorrelationState;

use super::{check_chunk, check_shapes, Compressor, HankelFactor, HankelLayout};
use crate::error::{Result, SysidError};
use faer::{Mat, MatRef};
use rayon::prelude::*;
use segment::Segment;

/// Knobs of the correlation compressor.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct CorrelationOptions {
    /// Samples per block (the unit of parallel work and of the pairwise reduction); 0 picks
    /// `256 (p + f)` samples (the merges of neighbouring blocks then cost about 1 % of the
    /// lagged sums), fewer if the block would exceed 512 KB (but at least `64 (p + f)`
    /// samples), at least 256.
    pub block_rows: usize,
    /// Threshold on the smallest relative Cholesky pivot `min La_ii^2 / max Ga_ii` of the
    /// centred, scaled Gram matrix below which the result is flagged ill-conditioned (and,
    /// in [`compress_experiments`], recomputed by the exact compressor).
    pub min_relative_pivot: f64,
    /// Process blocks on the rayon thread pool (the result is the same either way).
    pub parallel: bool,
}

impl Default for CorrelationOptions {
    fn default() -> Self {
        Self {
            block_rows: 0,
            min_relative_pivot: 1e-10,
            parallel: true,
        }
    }
}

/// Lagged correlation sums of a record: a value that can be merged with the sums of the
/// samples that follow it (or of other experiments) and turned into a [`HankelFactor`].
///
/// All partial sums that are to be merged must share the shift and scale given to
/// [`CorrelationSums::new`]; this is what lets chunks of one record be summed on different
/// machines and combined afterwards.
///
/// ```
/// use faer::Mat;
/// use sysid_core::hankel::{CorrelationSums, HankelLayout};
/// let layout = HankelLayout::new(1, 1, 2, 2).unwrap();
/// let u = Mat::from_fn(60, 1, |i, _| ((i * 7919) % 13) as f64 - 6.0);
/// let y = Mat::from_fn(60, 1, |i, _| ((i * 104729) % 11) as f64 - 5.0);
/// let (c, s) = (vec![0.0, 0.0], vec![4.0, 4.0]);
/// let mut a = CorrelationSums::new(layout, c.clone(), s.clone()).unwrap();
/// a.push(u.as_ref().subrows(0, 25), y.as_ref().subrows(0, 25)).unwrap();
/// let mut b = CorrelationSums::new(layout, c, s).unwrap();
/// b.push(u.as_ref().subrows(25, 35), y.as_ref().subrows(25, 35)).unwrap();
/// let f = a.merge(&b).unwrap().into_factor(1e-10).unwrap();
/// assert_eq!(f.n_columns(), 60 - 4 + 1);
/// ```
#[derive(Debug, Clone)]
pub struct CorrelationSums {
    layout: HankelLayout,
    center: Vec<f64>,
    inv_scale: Vec<f64>,
    scale: Vec<f64>,
    /// k x k once an experiment with a complete window has closed, 0 x 0 before: a stream
    /// too short for the horizon is refused at the end without sizing it.
    gram: Mat<f64>,
    col_sum: Vec<f64>,
    n_columns: usize,
    n_experiments: usize,
    /// Pairwise reduction stack of the open experiment: (level, segment), in sample order.
    stack: Vec<(u32, Segment)>,
    open_samples: usize,
    block_rows: usize,
    parallel: bool,
}

impl CorrelationSums {
    /// Empty sums for `layout`, accumulated in coordinates `(z - center) / scale`.
    pub fn new(layout: HankelLayout, center: Vec<f64>, scale: Vec<f64>) -> Result<Self> {
        let d = layout.n_inputs + layout.n_outputs;
        if center.len() != d || scale.len() != d {
            return Err(SysidError::ShapeMismatch {
                what: "center/scale".into(),
                expected: format!("({d},) each (one per input and output channel)"),
                got: format!("({},) and ({},)", center.len(), scale.len()),
            });
        }
        if center.iter().any(|v| !v.is_finite())
            || scale.iter().any(|v| !v.is_finite() || *v <= 0.0)
        {
            return Err(SysidError::invalid(
                "center/scale",
                "must be finite, with positive scales",
            ));
        }
        let k = layout.k();
        let w = layout.window();
        Ok(Self {
            layout,
            inv_scale: scale.iter().map(|s| 1.0 / s).collect(),
            center,
            scale,
            gram: Mat::zeros(0, 0),
            col_sum: vec![0.0; k],
            n_columns: 0,
            n_experiments: 0,
            stack: vec![(0, Segment::empty(d, w))],
            open_samples: 0,
            block_rows: Self::auto_block_rows(&layout),
            parallel: true,
        })
    }

    /// Shift and power-of-two scale per channel estimated from a chunk (mean and standard
    /// deviation), as [`CorrelationCompressor`] does with the first chunk it receives.
    pub fn center_scale(u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> (Vec<f64>, Vec<f64>) {
        Self::center_scale_finite(u, y).0
    }

    /// [`CorrelationSums::center_scale`] and whether every value is finite, in the two
    /// vectorised passes of [`crate::stats::channel_stats`] (mean, then spread).
    fn center_scale_finite(u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> ((Vec<f64>, Vec<f64>), bool) {
        let mut center = Vec::new();
        let mut scale = Vec::new();
        let mut finite = true;
        for x in [u, y] {
            if x.ncols() == 0 {
                continue;
            }
            let st = crate::stats::channel_stats(&[x]);
            finite &= st.abs_max.iter().all(|v| v.is_finite());
            for (&mean, &sd) in st.mean.iter().zip(&st.std) {
                let (mean, var) = if x.nrows() == 0 {
                    (0.0, 0.0)
                } else {
                    (mean, sd * sd)
                };
                let spread = if var > 0.0 && var.is_finite() {
                    var.sqrt()
                } else {
                    mean.abs()
                };
                let e = if spread > 0.0 && spread.is_finite() {
                    spread.log2().round().clamp(-1000.0, 1000.0)
                } else {
                    0.0
                };
                center.push(if mean.is_finite() { mean } else { 0.0 });
                scale.push(2f64.powi(e as i32));
            }
        }
        ((center, scale), finite)
    }

    /// Sets the block size (0: automatic, see [`CorrelationOptions::block_rows`]) and whether
    /// blocks run in parallel (the sums do not depend on `parallel`; they depend on
    /// `block_rows` only through round-off).
    pub fn set_blocking(&mut self, block_rows: usize, parallel: bool) {
        self.block_rows = if block_rows == 0 {
            Self::auto_block_rows(&self.layout)
        } else {
            block_rows
        };
        self.parallel = parallel;
    }

    fn auto_block_rows(layout: &HankelLayout) -> usize {
        // each block boundary costs about w^2 d^2 / 2 scalar multiply-adds (the cross terms
        // of the merge) against 2 w d^2 vectorised ones per sample in the lagged sums:
        // 256 w samples per block keep the merges near 1 % of the time. The kernel reads the
        // block in place right after the copy into it: a block that fits a core's L2 cache
        // (512 KB here) measured 5-10 % faster at 8 x 8 than 1.3 MB ones, so fewer samples
        // when the block would exceed 512 KB, down to 64 w (merges near 3 %), at least 256
        let w = layout.window();
        let row = (layout.n_inputs + layout.n_outputs).max(1) * std::mem::size_of::<f64>();
        (256 * w).min((512usize << 10) / row).max(64 * w).max(256)
    }

    /// The layout.
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }

    /// Hankel columns of the closed experiments.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Closed experiments.
    pub fn n_experiments(&self) -> usize {
        self.n_experiments
    }

    /// Samples pushed into the open experiment.
    pub fn open_samples(&self) -> usize {
        self.open_samples
    }

    fn d(&self) -> usize {
        self.layout.n_inputs + self.layout.n_outputs
    }

    fn push_segment(&mut self, seg: Segment) {
        let (d, w) = (self.d(), self.layout.window());
        self.stack.push((0, seg));
        while self.stack.len() >= 2
            && self.stack[self.stack.len() - 1].0 == self.stack[self.stack.len() - 2].0
        {
            let (lb, b) = self.stack.pop().unwrap();
            let (_, a) = self.stack.pop().unwrap();
            self.stack.push((lb + 1, a.concat(&b, d, w)));
        }
    }

    fn collapse(&mut self) -> Segment {
        let (d, w) = (self.d(), self.layout.window());
        let mut acc: Option<Segment> = None;
        while let Some((_, s)) = self.stack.pop() {
            acc = Some(match acc {
                None => s,
                Some(later) => s.concat(&later, d, w),
            });
        }
        let seg = acc.unwrap_or_else(|| Segment::empty(d, w));
        self.stack.push((u32::MAX, seg.clone()));
        seg
    }

    /// Appends samples to the open experiment.
    pub fn push(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
        self.push_impl(u, y, true)
    }

    /// [`CorrelationSums::push`]; `check: false` when the caller has just checked the chunk
    /// (shapes and finite values) with [`check_chunk`].
    fn push_impl(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>, check: bool) -> Result<()> {
        let u = if self.layout.n_inputs == 0 {
            u.subrows(0, 0)
        } else {
            u
        };
        if check {
            check_chunk(&self.layout, u, y, self.open_samples)?;
        }
        let n = y.nrows();
        if n == 0 {
            return Ok(());
        }
        let (m, d, w) = (self.layout.n_inputs, self.d(), self.layout.window());
        let br = self.block_rows;
        let n_blocks = n.div_ceil(br);
        let (center, inv) = (self.center.clone(), self.inv_scale.clone());
        let block = |b: usize| {
            let s = b * br;
            let len = br.min(n - s);
            // w - 1 rows of zero padding after the block (see Segment::from_padded_rows)
            let mut x = vec![0.0; (len + w - 1) * d];
            // u has no rows when there are no inputs (output-only data)
            let ub = if m == 0 { u } else { u.subrows(s, len) };
            let yb = y.subrows(s, len);
            for (c, (cc, ic)) in center.iter().zip(&inv).enumerate() {
                let (src, col) = if c < m { (ub, c) } else { (yb, c - m) };
                let src = src.col(col);
                for (t, v) in src.iter().enumerate() {
                    x[t * d + c] = (v - cc) * ic;
                }
            }
            Segment::from_padded_rows(&x, len, d, w)
        };
        // batches bound the memory of pending segments; the sequence of segments pushed,
        // hence the result, does not depend on the batch size or the thread count
        const BATCH: usize = 32;
        // Ctrl-C: asked before every block, in every task
        let flag = crate::interrupt::Flag::current();
        let block = |b: usize| flag.check().map(|()| block(b));
        for b0 in (0..n_blocks).step_by(BATCH) {
            let b1 = (b0 + BATCH).min(n_blocks);
            let segs: Vec<Segment> = if self.parallel && b1 - b0 > 1 {
                (b0..b1).into_par_iter().map(block).collect::<Result<_>>()?
            } else {
                (b0..b1).map(block).collect::<Result<_>>()?
            };
            for s in segs {
                self.push_segment(s);
            }
        }
        self.open_samples += n;
        Ok(())
    }

    /// Sums of `self` followed by `other`: `other`'s samples continue `self`'s open
    /// experiment, and closed experiments add up. Both must share layout, shift and scale;
    /// if `self` has an open experiment, `other` must not contain closed ones (end the
    /// experiment first to join separate experiments).
    pub fn merge(&self, other: &CorrelationSums) -> Result<CorrelationSums> {
        if self.layout != other.layout {
            return Err(SysidError::IncompatibleFactors {
                reason: format!("layouts differ: {:?} vs {:?}", self.layout, other.layout),
            });
        }
        if self.center != other.center || self.scale != other.scale {
            return Err(SysidError::IncompatibleFactors {
                reason: "the partial sums use different shifts or scales; build every part with \
                         the same center and scale"
                    .into(),
            });
        }
        if self.open_samples > 0 && other.n_experiments > 0 {
            return Err(SysidError::IncompatibleFactors {
                reason: "the first operand has an open experiment and the second contains closed \
                         experiments; call end_experiment() on the first before merging"
                    .into(),
            });
        }
        let (d, w) = (self.d(), self.layout.window());
        let mut out = self.clone();
        let a = out.collapse();
        let b = other.clone().collapse();
        out.stack = vec![(0, a.concat(&b, d, w))];
        out.open_samples = self.open_samples + other.open_samples;
        out.gram = match (self.gram.nrows(), other.gram.nrows()) {
            (0, _) => other.gram.clone(),
            (_, 0) => self.gram.clone(),
            _ => &self.gram + &other.gram,
        };
        for (x, y) in out.col_sum.iter_mut().zip(&other.col_sum) {
            *x += y;
        }
        out.n_columns += other.n_columns;
        out.n_experiments += other.n_experiments;
        Ok(out)
    }
}

/// The fast streaming compressor (lagged correlation sums, then Cholesky).
///
/// Same interface and same result as [`QrCompressor`] up to round-off on well-conditioned
/// data, at `2 (p + f)(m + l)^2` flops per sample instead of `2 (p + f)^2 (m + l)^2`. The
/// shift and scale are taken from the first chunk pushed. Check
/// [`HankelFactor::source`]: when the Gram matrix is nearly singular (noise-free data, a
/// constant channel) the factor is flagged and small singular values are not resolved.
///
/// ```
/// use faer::Mat;
/// use sysid_core::hankel::{Compressor, CorrelationCompressor, FactorSource, HankelLayout};
/// let layout = HankelLayout::new(1, 1, 2, 2).unwrap();
/// let u = Mat::from_fn(80, 1, |i, _| ((i * 7919) % 13) as f64 - 6.0);
/// let y = Mat::from_fn(80, 1, |i, _| ((i * 104729) % 11) as f64 - 5.0);
/// let mut c = CorrelationCompressor::new(layout);
/// c.push(u.as_ref(), y.as_ref()).unwrap();
/// let f = c.finish().unwrap();
/// assert_eq!(f.n_columns(), 80 - 4 + 1);
/// assert_eq!(f.source(), FactorSource::Correlation);
/// ```
#[derive(Debug, Clone)]
pub struct CorrelationCompressor {
    layout: HankelLayout,
    options: CorrelationOptions,
    sums: Option<CorrelationSums>,
}

impl CorrelationCompressor {
    /// A compressor with default options.
    pub fn new(layout: HankelLayout) -> Self {
        Self::with_options(layout, CorrelationOptions::default())
    }

    /// A compressor with the given options.
    pub fn with_options(layout: HankelLayout, options: CorrelationOptions) -> Self {
        Self {
            layout,
            options,
            sums: None,
        }
    }

    /// The layout being compressed.
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }
}

impl Compressor for CorrelationCompressor {
    fn push(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
        if self.sums.is_none() {
            let u0 = if self.layout.n_inputs == 0 {
                u.subrows(0, 0)
            } else {
                u
            };
            // shapes here; finite values through the statistics' pass (the exact check,
            // which locates the first bad value, only when that pass saw one)
            check_shapes(&self.layout, u0, y)?;
            if y.nrows() == 0 {
                return Ok(());
            }
            let ((c, s), finite) = CorrelationSums::center_scale_finite(u0, y);
            if !finite {
                check_chunk(&self.layout, u0, y, 0)?;
            }
            let mut sums = CorrelationSums::new(self.layout, c, s)?;
            sums.set_blocking(self.options.block_rows, self.options.parallel);
            let out = sums.push_impl(u, y, false);
            self.sums = Some(sums);
            return out;
        }
        self.sums.as_mut().unwrap().push(u, y)
    }

    fn end_experiment(&mut self) -> Result<()> {
        match self.sums.as_mut() {
            Some(s) => s.end_experiment(),
            None => Ok(()),
        }
    }

    fn finish(self) -> Result<HankelFactor> {
        match self.sums {
            Some(s) => s.into_factor(self.options.min_relative_pivot),
            None => Err(SysidError::InsufficientData {
                context: "the correlation compressor".into(),
                needed: self.layout.window(),
                got: 0,
                fix: "push samples before finishing",
            }),
        }
    }
}
