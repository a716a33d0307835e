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

use super::lagsum::lag_sums;
use super::{
    check_chunk, check_shapes, Block, Compressor, FactorSource, HankelFactor, HankelLayout,
};
use crate::error::{Result, SysidError};
use crate::linalg::{cholesky_lower_seq, lq_lower, lq_lower_rank_one};
use faer::{Mat, MatRef, Side};
use rayon::prelude::*;

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

/// Partial sums of one contiguous stretch of samples (inside one experiment).
#[derive(Debug, Clone, PartialEq)]
struct Segment {
    n: usize,
    /// d x (w d): block `tau` holds `sum x_t x_{t+tau}^T` over pairs inside the segment.
    lag: Mat<f64>,
    sum: Vec<f64>,
    /// First `min(n, w - 1)` samples, row-major.
    head: Vec<f64>,
    /// Last `min(n, w - 1)` samples, row-major.
    tail: Vec<f64>,
}

impl Segment {
    fn empty(d: usize, w: usize) -> Self {
        Segment {
            n: 0,
            lag: Mat::zeros(d, w * d),
            sum: vec![0.0; d],
            head: vec![],
            tail: vec![],
        }
    }

    /// Sums of `n` row-major samples, the first `n d` entries of `x`, which holds `w - 1`
    /// rows of zeros after them: with that padding one product over the overlapping Hankel
    /// view ([`lag_sums`], read in place) forms every lagged sum, the pairs near the end of the block included (the padded
    /// products are exact zeros).
    fn from_padded_rows(x: &[f64], n: usize, d: usize, w: usize) -> Self {
        debug_assert_eq!(x.len(), (n + w - 1) * d);
        debug_assert!(x[n * d..].iter().all(|v| *v == 0.0));
        // row-major d x (w d) sums, then into the column-major lag matrix
        let wd = w * d;
        let mut rm = vec![0.0; d * wd];
        lag_sums(x, n, d, w, &mut rm);
        let lag = Mat::from_fn(d, wd, |i, c| rm[i * wd + c]);
        let x = &x[..n * d];
        let mut sum = vec![0.0; d];
        for t in 0..n {
            for (s, v) in sum.iter_mut().zip(&x[t * d..(t + 1) * d]) {
                *s += v;
            }
        }
        let b = n.min(w - 1);
        Segment {
            n,
            lag,
            sum,
            head: x[..b * d].to_vec(),
            tail: x[(n - b) * d..].to_vec(),
        }
    }

    /// Sums of the samples of `self` followed by those of `next`.
    fn concat(&self, next: &Segment, d: usize, w: usize) -> Segment {
        if self.n == 0 {
            return next.clone();
        }
        if next.n == 0 {
            return self.clone();
        }
        let mut lag = &self.lag + &next.lag;
        let tail_rows = self.tail.len() / d.max(1);
        for tau in 1..w {
            for i in 1..=tau.min(self.n) {
                let j = tau - i;
                if j >= next.n {
                    continue;
                }
                let a = &self.tail[(tail_rows - i) * d..(tail_rows - i + 1) * d];
                let b = &next.head[j * d..(j + 1) * d];
                add_outer(&mut lag, tau * d, a, b);
            }
        }
        let n = self.n + next.n;
        let keep = n.min(w - 1) * d;
        let mut head = self.head.clone();
        head.extend_from_slice(&next.head);
        head.truncate(keep);
        let mut tail = self.tail.clone();
        tail.extend_from_slice(&next.tail);
        let tail = tail[tail.len() - keep..].to_vec();
        let sum = self.sum.iter().zip(&next.sum).map(|(a, b)| a + b).collect();
        Segment {
            n,
            lag,
            sum,
            head,
            tail,
        }
    }
}

#[inline]
fn add_outer(lag: &mut Mat<f64>, col0: usize, a: &[f64], b: &[f64]) {
    for (j, bj) in b.iter().enumerate() {
        let col = &mut lag.col_as_slice_mut(col0 + j)[..a.len()];
        for (c, ai) in col.iter_mut().zip(a) {
            *c += ai * bj;
        }
    }
}

/// Plain-data snapshot of [`CorrelationSums`] (for saving, pickling, sending to a worker).
#[derive(Debug, Clone, PartialEq)]
pub struct CorrelationState {
    /// Channel counts and horizons.
    pub layout: HankelLayout,
    /// Per-channel shift `c` (inputs then outputs).
    pub center: Vec<f64>,
    /// Per-channel scale `s` (powers of two).
    pub scale: Vec<f64>,
    /// Gram matrix of closed experiments, natural order, centred and scaled: (w d) x (w d).
    pub gram: Mat<f64>,
    /// Column sums `sum_t X_t` of closed experiments (w d).
    pub col_sum: Vec<f64>,
    /// Hankel columns of closed experiments.
    pub n_columns: usize,
    /// Closed experiments.
    pub n_experiments: usize,
    /// Samples of the open (not yet ended) experiment.
    pub open_samples: usize,
    /// Lagged sums of the open experiment, d x (w d).
    pub open_lag: Mat<f64>,
    /// Channel sums of the open experiment.
    pub open_sum: Vec<f64>,
    /// First `min(open_samples, w - 1)` samples of the open experiment, row-major.
    pub open_head: Vec<f64>,
    /// Last `min(open_samples, w - 1)` samples of the open experiment, row-major.
    pub open_tail: Vec<f64>,
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
            gram: Mat::zeros(k, k),
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

    /// Closes the open experiment: its Hankel columns join the Gram matrix.
    pub fn end_experiment(&mut self) -> Result<()> {
        let seg = self.collapse();
        let (d, w) = (self.d(), self.layout.window());
        self.stack.clear();
        self.stack.push((0, Segment::empty(d, w)));
        self.open_samples = 0;
        if seg.n == 0 {
            return Ok(());
        }
        if seg.n < w {
            return Err(SysidError::InsufficientData {
                context: format!(
                    "experiment {} with a window of p + f = {w} samples",
                    self.n_experiments + 1
                ),
                needed: w,
                got: seg.n,
                fix: "drop the short experiment or use a smaller horizon",
            });
        }
        let t_cols = seg.n - w + 1;
        let (head, tail) = (&seg.head, &seg.tail);
        let k = self.gram.nrows();
        // G_ab = S_tau - H_a(tau) - T_a(tau) with H_a = sum_{t<a} z_t z_{t+tau}^T (head rows,
        // accumulated for increasing a) and T_a = sum_{a<=q<=w-2-tau} of the tail rows
        // (accumulated for decreasing a): O(w^2 d^2) work, every partial sum a plain sum
        let dd = d * d;
        let mut tails = vec![0.0; w * dd];
        let mut heads = vec![0.0; dd];
        let add_outer_rows = |acc: &mut [f64], a: &[f64], b: &[f64]| {
            for (j, bj) in b.iter().enumerate() {
                for (c, ai) in acc[j * d..(j + 1) * d].iter_mut().zip(a) {
                    *c += ai * bj;
                }
            }
        };
        let mut acc = vec![0.0; dd];
        for tau in 0..w {
            let na = w - tau;
            acc.fill(0.0);
            for a in (0..na).rev() {
                if a + tau + 2 <= w {
                    let (ra, rb) = (
                        &tail[a * d..(a + 1) * d],
                        &tail[(a + tau) * d..(a + tau + 1) * d],
                    );
                    add_outer_rows(&mut acc, ra, rb);
                }
                tails[a * dd..(a + 1) * dd].copy_from_slice(&acc);
            }
            heads.fill(0.0);
            for a in 0..na {
                let b = a + tau;
                let t_a = &tails[a * dd..(a + 1) * dd];
                for j in 0..d {
                    let lag_col = seg.lag.col_as_slice(tau * d + j);
                    for i in 0..d {
                        let v = lag_col[i] - heads[j * d + i] - t_a[j * d + i];
                        let (r, c) = (a * d + i, b * d + j);
                        debug_assert!(r < k && c < k);
                        self.gram.col_as_slice_mut(c)[r] += v;
                        if a != b {
                            self.gram.col_as_slice_mut(r)[c] += v;
                        }
                    }
                }
                if a + 1 < na {
                    let (ra, rb) = (&head[a * d..(a + 1) * d], &head[b * d..(b + 1) * d]);
                    add_outer_rows(&mut heads, ra, rb);
                }
            }
        }
        for a in 0..w {
            for i in 0..d {
                let mut v = seg.sum[i];
                for t in 0..a {
                    v -= head[t * d + i];
                }
                for q in a..(w - 1) {
                    v -= tail[q * d + i];
                }
                self.col_sum[a * d + i] += v;
            }
        }
        self.n_columns += t_cols;
        self.n_experiments += 1;
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
        out.gram = &self.gram + &other.gram;
        for (x, y) in out.col_sum.iter_mut().zip(&other.col_sum) {
            *x += y;
        }
        out.n_columns += other.n_columns;
        out.n_experiments += other.n_experiments;
        Ok(out)
    }

    /// A plain-data snapshot.
    pub fn state(&self) -> CorrelationState {
        let seg = self.clone().collapse();
        CorrelationState {
            layout: self.layout,
            center: self.center.clone(),
            scale: self.scale.clone(),
            gram: self.gram.clone(),
            col_sum: self.col_sum.clone(),
            n_columns: self.n_columns,
            n_experiments: self.n_experiments,
            open_samples: seg.n,
            open_lag: seg.lag,
            open_sum: seg.sum,
            open_head: seg.head,
            open_tail: seg.tail,
        }
    }

    /// Rebuilds sums from a snapshot, checking its shapes.
    pub fn from_state(s: CorrelationState) -> Result<Self> {
        let mut out = Self::new(s.layout, s.center, s.scale)?;
        let (d, w, k) = (out.d(), s.layout.window(), s.layout.k());
        let b = s.open_samples.min(w - 1) * d;
        let ok = s.gram.nrows() == k
            && s.gram.ncols() == k
            && s.col_sum.len() == k
            && s.open_lag.nrows() == d
            && s.open_lag.ncols() == w * d
            && s.open_sum.len() == d
            && s.open_head.len() == b
            && s.open_tail.len() == b;
        if !ok {
            return Err(SysidError::invalid(
                "state",
                "the correlation-sum arrays do not fit the layout",
            ));
        }
        out.gram = s.gram;
        out.col_sum = s.col_sum;
        out.n_columns = s.n_columns;
        out.n_experiments = s.n_experiments;
        out.open_samples = s.open_samples;
        out.stack = vec![(
            0,
            Segment {
                n: s.open_samples,
                lag: s.open_lag,
                sum: s.open_sum,
                head: s.open_head,
                tail: s.open_tail,
            },
        )];
        Ok(out)
    }

    /// Closes the open experiment and factors the Gram matrix of the raw data.
    ///
    /// The result is flagged [`FactorSource::CorrelationIllConditioned`] when the smallest
    /// relative Cholesky pivot of the centred, scaled Gram matrix is below
    /// `min_relative_pivot`, or when Cholesky fails (then the factor comes from the
    /// eigendecomposition with negative eigenvalues set to zero).
    pub fn into_factor(mut self, min_relative_pivot: f64) -> Result<HankelFactor> {
        self.end_experiment()?;
        let (m, l, p) = (
            self.layout.n_inputs,
            self.layout.n_outputs,
            self.layout.past,
        );
        let (d, w, k) = (m + l, self.layout.window(), self.layout.k());
        if self.n_columns < k {
            return Err(SysidError::InsufficientData {
                context: format!(
                    "a data matrix with {k} rows (horizons p={}, f={}, {m} input(s), {l} output(s))",
                    p, self.layout.future
                ),
                needed: k + (w - 1) * self.n_experiments.max(1),
                got: self.n_columns + (w - 1) * self.n_experiments,
                fix: "use a longer record or a smaller horizon",
            });
        }
        // rows of the data matrix from natural order (sample offset a, channel c) to the
        // canonical order [U_f; U_p; Y_p; Y_f], with the shift and scale of each row
        let (uf, _) = self.layout.block(Block::UFuture);
        let (up, _) = self.layout.block(Block::UPast);
        let (yp, _) = self.layout.block(Block::YPast);
        let (yf, _) = self.layout.block(Block::YFuture);
        let mut perm = vec![0usize; k];
        let (mut s_rows, mut c_rows) = (vec![0.0; k], vec![0.0; k]);
        for a in 0..w {
            for c in 0..d {
                let dst = match (c < m, a < p) {
                    (true, true) => up + a * m + c,
                    (true, false) => uf + (a - p) * m + c,
                    (false, true) => yp + a * l + (c - m),
                    (false, false) => yf + (a - p) * l + (c - m),
                };
                perm[a * d + c] = dst;
                s_rows[dst] = self.scale[c];
                c_rows[dst] = self.center[c];
            }
        }
        // augmented Gram matrix [[X X^T, X 1], [1^T X^T, T]], rows and columns in canonical
        // order (the constant row last)
        let mut ga = Mat::<f64>::zeros(k + 1, k + 1);
        for j in 0..k {
            let col = self.gram.col_as_slice(j);
            let dst = ga.col_as_slice_mut(perm[j]);
            for (i, v) in col.iter().enumerate() {
                dst[perm[i]] = *v;
            }
        }
        for i in 0..k {
            ga[(perm[i], k)] = self.col_sum[i];
            ga[(k, perm[i])] = self.col_sum[i];
        }
        ga[(k, k)] = self.n_columns as f64;
        let max_diag = (0..=k).map(|i| ga[(i, i)]).fold(0.0, f64::max);
        let (la, source, pivot, triangular) = match cholesky_lower_seq(ga.as_ref()) {
            Some(la) => {
                let min_piv = (0..=k)
                    .map(|i| la[(i, i)] * la[(i, i)])
                    .fold(f64::INFINITY, f64::min);
                let rel = if max_diag > 0.0 {
                    min_piv / max_diag
                } else {
                    0.0
                };
                let src = if rel >= min_relative_pivot {
                    FactorSource::Correlation
                } else {
                    FactorSource::CorrelationIllConditioned {
                        clipped: 0,
                        relative_pivot: rel,
                    }
                };
                (la, src, rel, true)
            }
            None => {
                let evd = ga.self_adjoint_eigen(Side::Lower).map_err(|e| {
                    SysidError::numerical(
                        "correlation compressor (eigendecomposition)",
                        format!("{e:?}"),
                    )
                })?;
                let s = evd.S().column_vector();
                let v = evd.U();
                let clipped = (0..=k).filter(|&i| s[i] < 0.0).count();
                let f = Mat::from_fn(k + 1, k + 1, |i, j| v[(i, j)] * s[j].max(0.0).sqrt());
                (
                    f,
                    FactorSource::CorrelationIllConditioned {
                        clipped,
                        relative_pivot: 0.0,
                    },
                    0.0,
                    false,
                )
            }
        };
        // L: the LQ triangle of E La with E = [diag(s) | c]; when La is the Cholesky factor,
        // E La = [diag(s) La_11 | 0] + c La_k (triangular plus rank one)
        let l_mat = if triangular {
            let t = Mat::from_fn(
                k,
                k,
                |i, j| {
                    if j <= i {
                        s_rows[i] * la[(i, j)]
                    } else {
                        0.0
                    }
                },
            );
            let r: Vec<f64> = (0..=k).map(|j| la[(k, j)]).collect();
            lq_lower_rank_one(t.as_ref(), &c_rows, &r)
        } else {
            let h = Mat::from_fn(k, k + 1, |i, j| {
                s_rows[i] * la[(i, j)] + c_rows[i] * la[(k, j)]
            });
            lq_lower(h.as_ref())
        };
        Ok(
            HankelFactor::from_parts(self.layout, l_mat, self.n_columns, self.n_experiments)?
                .with_source(source)
                .with_relative_pivot(Some(pivot)),
        )
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
