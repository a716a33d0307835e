//! The exact compressor: the triangular factor updated by QR, chunk by chunk.
//!
//! Windows (Hankel columns) are written as rows of a work matrix below the current `R`
//! (`R = L^T`, upper triangular); when `chunk_rows` rows are pending, the stack `[R; rows]`
//! is re-triangularised by Householder QR. Cost `2 (k + c) k^2` flops per `c` columns, memory
//! `(k + c) k` doubles, whatever the record length.

use super::{check_chunk, Compressor, HankelFactor, HankelLayout};
use crate::error::{Result, SysidError};
use crate::linalg::QrAccumulator;
use faer::{Mat, MatRef};

/// Exact streaming compressor (sequential QR updates).
///
/// ```
/// use faer::Mat;
/// use sysid_core::hankel::{Compressor, HankelLayout, QrCompressor};
/// let layout = HankelLayout::new(1, 1, 2, 2).unwrap();
/// let u = Mat::from_fn(50, 1, |i, _| ((i * 7919) % 13) as f64 - 6.0);
/// let y = Mat::from_fn(50, 1, |i, _| ((i * 104729) % 11) as f64 - 5.0);
/// let mut c = QrCompressor::new(layout);
/// c.push(u.as_ref().subrows(0, 20), y.as_ref().subrows(0, 20)).unwrap();
/// c.push(u.as_ref().subrows(20, 30), y.as_ref().subrows(20, 30)).unwrap();
/// let f = c.finish().unwrap();
/// assert_eq!(f.n_columns(), 50 - 4 + 1);
/// ```
#[derive(Debug, Clone)]
pub struct QrCompressor {
    layout: HankelLayout,
    acc: QrAccumulator,
    tail_u: Mat<f64>,
    tail_y: Mat<f64>,
    tail_len: usize,
    exp_samples: usize,
    n_columns: usize,
    n_experiments: usize,
    total_samples: usize,
    column: Vec<f64>,
}

impl QrCompressor {
    /// A compressor with the default chunk size, `max(4 k, 512)` windows per QR update.
    pub fn new(layout: HankelLayout) -> Self {
        let k = layout.k();
        Self::with_chunk_rows(layout, (4 * k).max(512))
    }

    /// A compressor that re-triangularises after every `chunk_rows` windows (at least 1).
    /// The result does not depend on it beyond round-off.
    pub fn with_chunk_rows(layout: HankelLayout, chunk_rows: usize) -> Self {
        let k = layout.k();
        let w = layout.window();
        Self {
            layout,
            acc: QrAccumulator::new(k, chunk_rows),
            tail_u: Mat::zeros(w, layout.n_inputs),
            tail_y: Mat::zeros(w, layout.n_outputs),
            tail_len: 0,
            exp_samples: 0,
            n_columns: 0,
            n_experiments: 0,
            total_samples: 0,
            column: vec![0.0; k],
        }
    }

    /// The layout being compressed.
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }

    fn take_window(&mut self, start: usize, u: MatRef<'_, f64>, y: MatRef<'_, f64>) {
        let (m, l) = (self.layout.n_inputs, self.layout.n_outputs);
        let (p, f) = (self.layout.past, self.layout.future);
        let tl = self.tail_len;
        let (uf, _) = self.layout.block(super::Block::UFuture);
        let (up, _) = self.layout.block(super::Block::UPast);
        let (yp, _) = self.layout.block(super::Block::YPast);
        let (yf, _) = self.layout.block(super::Block::YFuture);
        let col = &mut self.column;
        let sample_u = |s: usize, c: usize| {
            if s < tl {
                self.tail_u[(s, c)]
            } else {
                u[(s - tl, c)]
            }
        };
        let sample_y = |s: usize, c: usize| {
            if s < tl {
                self.tail_y[(s, c)]
            } else {
                y[(s - tl, c)]
            }
        };
        for j in 0..p {
            for c in 0..m {
                col[up + j * m + c] = sample_u(start + j, c);
            }
            for c in 0..l {
                col[yp + j * l + c] = sample_y(start + j, c);
            }
        }
        for j in 0..f {
            for c in 0..m {
                col[uf + j * m + c] = sample_u(start + p + j, c);
            }
            for c in 0..l {
                col[yf + j * l + c] = sample_y(start + p + j, c);
            }
        }
        self.acc.push_row(col);
        self.n_columns += 1;
    }
}

impl Compressor for QrCompressor {
    fn push(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
        let u = if self.layout.n_inputs == 0 {
            u.subrows(0, 0)
        } else {
            u
        };
        check_chunk(&self.layout, u, y, self.exp_samples)?;
        let n_new = y.nrows();
        let w = self.layout.window();
        let total = self.tail_len + n_new;
        if total >= w {
            for start in 0..=(total - w) {
                self.take_window(start, u, y);
            }
        }
        // keep the last w - 1 samples as the new tail
        let keep = total.min(w - 1);
        let first = total - keep;
        let mut nu = Mat::<f64>::zeros(w, self.layout.n_inputs);
        let mut ny = Mat::<f64>::zeros(w, self.layout.n_outputs);
        for s in 0..keep {
            let src = first + s;
            for c in 0..self.layout.n_inputs {
                nu[(s, c)] = if src < self.tail_len {
                    self.tail_u[(src, c)]
                } else {
                    u[(src - self.tail_len, c)]
                };
            }
            for c in 0..self.layout.n_outputs {
                ny[(s, c)] = if src < self.tail_len {
                    self.tail_y[(src, c)]
                } else {
                    y[(src - self.tail_len, c)]
                };
            }
        }
        self.tail_u = nu;
        self.tail_y = ny;
        self.tail_len = keep;
        self.exp_samples += n_new;
        self.total_samples += n_new;
        Ok(())
    }

    fn end_experiment(&mut self) -> Result<()> {
        if self.exp_samples == 0 {
            return Ok(());
        }
        let w = self.layout.window();
        if self.exp_samples < w {
            return Err(SysidError::InsufficientData {
                context: format!(
                    "experiment {} with a window of p + f = {} samples",
                    self.n_experiments + 1,
                    w
                ),
                needed: w,
                got: self.exp_samples,
                fix: "drop the short experiment or use a smaller horizon",
            });
        }
        self.n_experiments += 1;
        self.exp_samples = 0;
        self.tail_len = 0;
        Ok(())
    }

    fn finish(mut self) -> Result<HankelFactor> {
        self.end_experiment()?;
        if self.n_columns == 0 {
            return Err(SysidError::InsufficientData {
                context: format!("a window of p + f = {} samples", self.layout.window()),
                needed: self.layout.window(),
                got: self.total_samples,
                fix: "push data before finishing, or use a smaller horizon",
            });
        }
        let l = self.acc.finish().transpose().to_owned();
        HankelFactor::from_parts(self.layout, l, self.n_columns, self.n_experiments)
    }
}
