//! The exact compressor: the triangular factor updated by QR, block by block.
//!
//! Windows (Hankel columns) are numbered in the order they are pushed and grouped into
//! blocks of `block_windows` consecutive windows (boundaries fixed by that numbering, not by
//! the chunks pushed or the threads available). Each block is triangularised on its own:
//! its windows are written as rows below a running `R` (`R = L^T`, upper triangular) and the
//! stack is re-triangularised by Householder QR every `chunk_rows` rows. Complete blocks of a
//! push are compressed in parallel on the rayon pool; their k x k triangles are then merged
//! into the record's triangle one after the other, in block order. Every QR runs on one
//! thread, so the factor is bit-for-bit the same for any number of threads (and any way of
//! cutting the record into pushes). Cost `2 (k + c) k^2` flops per `c` windows plus about
//! `3 k^3` per block merge, memory `(k + c) k` doubles per thread, whatever the length.

use super::{check_chunk, Compressor, HankelFactor, HankelLayout};
use crate::error::{Result, SysidError};
use crate::linalg::{qr_r_in_place, QrAccumulator};
use faer::{Mat, MatRef};
use rayon::prelude::*;

/// Exact streaming compressor (block-wise QR updates merged in a fixed order).
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
    chunk_rows: usize,
    block_windows: usize,
    parallel: bool,
    /// Triangle of the closed blocks (None before the first block closes).
    r: Option<Mat<f64>>,
    /// The open block.
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

/// Blocks compressed concurrently per batch (bounds the memory of pending triangles).
const BATCH_BLOCKS: usize = 16;

/// Writes the window starting at sample `start` of (tail, chunk) into `col`.
#[allow(clippy::too_many_arguments)]
fn fill_window(
    layout: &HankelLayout,
    tail_u: MatRef<'_, f64>,
    tail_y: MatRef<'_, f64>,
    tl: usize,
    u: MatRef<'_, f64>,
    y: MatRef<'_, f64>,
    start: usize,
    col: &mut [f64],
) {
    let (m, l) = (layout.n_inputs, layout.n_outputs);
    let (p, f) = (layout.past, layout.future);
    let (uf, _) = layout.block(super::Block::UFuture);
    let (up, _) = layout.block(super::Block::UPast);
    let (yp, _) = layout.block(super::Block::YPast);
    let (yf, _) = layout.block(super::Block::YFuture);
    let sample_u = |s: usize, c: usize| {
        if s < tl {
            tail_u[(s, c)]
        } else {
            u[(s - tl, c)]
        }
    };
    let sample_y = |s: usize, c: usize| {
        if s < tl {
            tail_y[(s, c)]
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
}

/// The default number of windows per QR update for `k` rows of the data matrix,
/// `max(4 k, 512)`: the work matrix is `(k + chunk_rows) x k` (the recursive factor uses the
/// same blocks).
pub fn default_chunk_rows(k: usize) -> usize {
    k.saturating_mul(4).max(512)
}

impl QrCompressor {
    /// A compressor with the default chunk size ([`default_chunk_rows`], `max(4 k, 512)`
    /// windows per QR update), and blocks of 8 chunks.
    pub fn new(layout: HankelLayout) -> Self {
        Self::with_chunk_rows(layout, default_chunk_rows(layout.k()))
    }

    /// A compressor that re-triangularises after every `chunk_rows` windows (at least 1),
    /// with blocks of `8 chunk_rows` windows. The result does not depend on it beyond
    /// round-off.
    pub fn with_chunk_rows(layout: HankelLayout, chunk_rows: usize) -> Self {
        let k = layout.k();
        let w = layout.window();
        let chunk_rows = chunk_rows.max(1);
        Self {
            layout,
            chunk_rows,
            block_windows: 8 * chunk_rows,
            parallel: true,
            r: None,
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

    /// Whether complete blocks run on the rayon pool (default true). The factor is the same
    /// bit for bit either way.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// The layout being compressed.
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }

    /// Merges a block's triangle into the record's (in block order).
    fn merge_block(&mut self, rb: Mat<f64>) {
        match self.r.as_mut() {
            None => self.r = Some(rb),
            Some(r) => {
                let k = r.nrows();
                let mut both = Mat::<f64>::zeros(2 * k, k);
                both.as_mut().subrows_mut(0, k).copy_from(r.as_ref());
                both.as_mut().subrows_mut(k, k).copy_from(rb.as_ref());
                qr_r_in_place(both.as_mut());
                for j in 0..k {
                    for i in 0..k {
                        r[(i, j)] = if i <= j { both[(i, j)] } else { 0.0 };
                    }
                }
            }
        }
    }

    fn close_block(&mut self) {
        let k = self.layout.k();
        let acc = std::mem::replace(&mut self.acc, QrAccumulator::new(k, self.chunk_rows));
        if acc.n_rows() > 0 {
            self.merge_block(acc.finish());
        }
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
            let n_win = total - w + 1;
            let (layout, tl) = (self.layout, self.tail_len);
            let bw = self.block_windows;
            let mut next = 0;
            // 1. complete the open block, window by window
            if self.acc.n_rows() > 0 {
                let take = (bw - self.acc.n_rows()).min(n_win);
                for s in 0..take {
                    fill_window(
                        &layout,
                        self.tail_u.as_ref(),
                        self.tail_y.as_ref(),
                        tl,
                        u,
                        y,
                        s,
                        &mut self.column,
                    );
                    self.acc.push_row(&self.column);
                }
                next = take;
                if self.acc.n_rows() == bw {
                    self.close_block();
                }
            }
            // 2. whole blocks, each from scratch (in parallel), merged in block order
            let n_full = (n_win - next) / bw;
            let (k, cr) = (layout.k(), self.chunk_rows);
            // Ctrl-C: asked every `chunk_rows` windows, in every task
            let flag = crate::interrupt::Flag::current();
            for b0 in (0..n_full).step_by(BATCH_BLOCKS) {
                let b1 = (b0 + BATCH_BLOCKS).min(n_full);
                let (tu, ty) = (self.tail_u.as_ref(), self.tail_y.as_ref());
                let block = |b: usize| -> Result<Mat<f64>> {
                    let mut acc = QrAccumulator::new(k, cr);
                    let mut col = vec![0.0; k];
                    let first = next + b * bw;
                    for s in first..first + bw {
                        if (s - first) % cr == 0 {
                            flag.check()?;
                        }
                        fill_window(&layout, tu, ty, tl, u, y, s, &mut col);
                        acc.push_row(&col);
                    }
                    Ok(acc.finish())
                };
                let rs: Vec<Mat<f64>> = if self.parallel && b1 - b0 > 1 {
                    (b0..b1).into_par_iter().map(block).collect::<Result<_>>()?
                } else {
                    (b0..b1).map(block).collect::<Result<_>>()?
                };
                for rb in rs {
                    self.merge_block(rb);
                }
            }
            // 3. the rest opens a new block
            for s in (next + n_full * bw)..n_win {
                fill_window(
                    &layout,
                    self.tail_u.as_ref(),
                    self.tail_y.as_ref(),
                    tl,
                    u,
                    y,
                    s,
                    &mut self.column,
                );
                self.acc.push_row(&self.column);
            }
            self.n_columns += n_win;
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
        self.close_block();
        let r = self.r.take().expect("at least one window was pushed");
        let k = self.layout.k();
        let mut l = Mat::<f64>::zeros(k, k);
        for i in 0..k {
            let sign = if r[(i, i)] < 0.0 { -1.0 } else { 1.0 };
            for j in i..k {
                l[(j, i)] = sign * r[(i, j)];
            }
        }
        HankelFactor::from_parts(self.layout, l, self.n_columns, self.n_experiments)
    }
}
