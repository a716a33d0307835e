//! Plain-data snapshots of [`CorrelationSums`]: for saving, pickling, sending to a worker.

use super::{CorrelationSums, Segment};
use crate::error::{Result, SysidError};
use crate::hankel::HankelLayout;
use faer::Mat;

/// Plain-data snapshot of [`CorrelationSums`] (for saving, pickling, sending to a worker).
#[derive(Debug, Clone, PartialEq)]
pub struct CorrelationState {
    /// Channel counts and horizons.
    pub layout: HankelLayout,
    /// Per-channel shift `c` (inputs then outputs).
    pub center: Vec<f64>,
    /// Per-channel scale `s` (powers of two).
    pub scale: Vec<f64>,
    /// Gram matrix of closed experiments, natural order, centred and scaled: (w d) x (w d),
    /// or 0 x 0 while no closed experiment has a Hankel column (it is sized only then).
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

impl CorrelationSums {
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
        let gram_ok = (s.gram.nrows() == k && s.gram.ncols() == k)
            || (s.gram.nrows() == 0 && s.gram.ncols() == 0 && s.n_columns == 0);
        let ok = gram_ok
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
}
