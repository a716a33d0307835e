//! Recursive subspace identification: the compressed factor updated chunk by chunk, with
//! exponential forgetting, in the least-squares framework of the subspace methods (the
//! factor L of `H H^T` is what a recursive least-squares solver propagates; Trnka & Havlena
//! 2005 for the recursive view, sliding-window and forgetting variants).
//!
//! Each new Hankel column `h(t)` enters the Gram matrix as `G ← λ G + h h^T`; in factored
//! form, the upper-triangular `R` (with `R^T R = G`) is re-triangularised with the new rows
//! by a blocked Householder QR of `[λ^{b/2} R; λ^{(b-1)/2} h_1^T; ...; h_b^T]`. The cost of an
//! update is `O(b k^2)` for b new columns (k rows of the data matrix), independent of how
//! much data came before; with `λ = 1` the factor equals the batch compression of all data
//! so far (to round-off).

use crate::error::{Result, SysidError};
use crate::hankel::{HankelFactor, HankelLayout};
use faer::{Mat, MatRef};

/// Checks, before anything is sized, that what an update holds at once fits in
/// [`crate::error::MAX_MATRIX_BYTES`]: the k x k triangle, a copy of it (a caller that keeps
/// the factor unchanged until an update completes, as the bindings do for Ctrl-C) and the
/// `(k + block_rows) x k` stack re-triangularised per block.
fn check_working_set(layout: &HankelLayout, block_rows: usize) -> Result<()> {
    let k = layout.k();
    let rows = k
        .checked_mul(3)
        .and_then(|r| r.checked_add(block_rows))
        .unwrap_or(usize::MAX);
    crate::error::check_matrix_size("horizon", rows, k).map_err(|_| {
        SysidError::invalid(
            "horizon",
            format!(
                "past={} and future={} with {} input(s) and {} output(s) give k = {k} rows; \
                 a recursive update holds the k x k factor, a copy and a ({} x {k}) block \
                 ({:.1} GiB), more than the {} GiB limit; use a horizon of a few times the \
                 expected order",
                layout.past,
                layout.future,
                layout.n_inputs,
                layout.n_outputs,
                k.saturating_add(block_rows),
                rows as f64 * k as f64 * 8.0 / (1u64 << 30) as f64,
                crate::error::MAX_MATRIX_BYTES >> 30
            ),
        )
    })
}

/// A streaming, forgetting compressor of one experiment.
#[derive(Debug, Clone)]
pub struct RecursiveFactor {
    layout: HankelLayout,
    forgetting: f64,
    r: Mat<f64>,
    tail_u: Mat<f64>,
    tail_y: Mat<f64>,
    n_columns: usize,
    weight: f64,
    block_rows: usize,
}

impl RecursiveFactor {
    /// A compressor with forgetting factor `forgetting` in (0, 1] (1: no forgetting).
    pub fn new(layout: HankelLayout, forgetting: f64) -> Result<Self> {
        if !(forgetting > 0.0 && forgetting <= 1.0) {
            return Err(SysidError::invalid(
                "forgetting",
                format!("must lie in (0, 1] (got {forgetting}); 1 keeps all data"),
            ));
        }
        let k = layout.k();
        let block_rows = crate::hankel::default_chunk_rows(k);
        check_working_set(&layout, block_rows)?;
        Ok(Self {
            layout,
            forgetting,
            // allocated with the first Hankel column: none before a window is complete
            r: Mat::zeros(0, 0),
            tail_u: Mat::zeros(0, layout.n_inputs),
            tail_y: Mat::zeros(0, layout.n_outputs),
            n_columns: 0,
            weight: 0.0,
            block_rows,
        })
    }

    /// The layout.
    pub fn layout(&self) -> &HankelLayout {
        &self.layout
    }

    /// Hankel columns seen so far.
    pub fn n_columns(&self) -> usize {
        self.n_columns
    }

    /// Effective number of columns `sum λ^age` (equals [`Self::n_columns`] without
    /// forgetting).
    pub fn effective_columns(&self) -> f64 {
        self.weight
    }

    /// Appends a chunk of samples (continuing the same experiment).
    pub fn update(&mut self, u: MatRef<'_, f64>, y: MatRef<'_, f64>) -> Result<()> {
        let lay = self.layout;
        let (m, l, w, k) = (lay.n_inputs, lay.n_outputs, lay.window(), lay.k());
        if u.ncols() != m || y.ncols() != l || (m > 0 && u.nrows() != y.nrows()) {
            return Err(SysidError::ShapeMismatch {
                what: "chunk".into(),
                expected: format!("(samples, {m}) inputs and (samples, {l}) outputs"),
                got: format!(
                    "{:?} and {:?}",
                    (u.nrows(), u.ncols()),
                    (y.nrows(), y.ncols())
                ),
            });
        }
        crate::error::check_finite("u", u)?;
        crate::error::check_finite("y", y)?;
        // the samples available: the tail (last w - 1) and the chunk
        let tl = self.tail_y.nrows();
        let total = tl + y.nrows();
        let mut bu = Mat::<f64>::zeros(total, m);
        let mut by = Mat::<f64>::zeros(total, l);
        bu.as_mut().subrows_mut(0, tl).copy_from(&self.tail_u);
        by.as_mut().subrows_mut(0, tl).copy_from(&self.tail_y);
        if m > 0 {
            bu.as_mut().subrows_mut(tl, u.nrows()).copy_from(u);
        }
        by.as_mut().subrows_mut(tl, y.nrows()).copy_from(y);
        let n_new = (total + 1).saturating_sub(w);
        let lam = self.forgetting;
        let mut col = vec![0.0; k];
        // sqrt(λ)^i for the rows of a block
        let half: Vec<f64> = (0..=self.block_rows.min(n_new.max(1)))
            .map(|i| lam.powf(i as f64 / 2.0))
            .collect();
        let mut start = 0;
        while start < n_new {
            crate::interrupt::check()?;
            let b = (n_new - start).min(self.block_rows);
            let mut stack = Mat::<f64>::zeros(k + b, k);
            let sr = half[b];
            if self.r.nrows() == 0 {
                self.r = Mat::zeros(k, k); // the first block: R = 0 so far
            }
            for j in 0..k {
                for i in 0..=j {
                    stack[(i, j)] = sr * self.r[(i, j)];
                }
            }
            for i in 0..b {
                lay.fill_column(bu.as_ref(), by.as_ref(), start + i, &mut col);
                let s = half[b - 1 - i];
                for j in 0..k {
                    stack[(k + i, j)] = s * col[j];
                }
            }
            // the compressors' sequential QR: the same bits for any thread count
            crate::linalg::qr_r_in_place(stack.as_mut());
            self.r.fill(0.0);
            for i in 0..k {
                for j in i..k {
                    self.r[(i, j)] = stack[(i, j)];
                }
            }
            self.weight =
                lam.powi(b as i32) * self.weight + (0..b).map(|i| lam.powi(i as i32)).sum::<f64>();
            self.n_columns += b;
            start += b;
        }
        let keep = total.min(w - 1);
        self.tail_u = bu.as_ref().subrows(total - keep, keep).to_owned();
        self.tail_y = by.as_ref().subrows(total - keep, keep).to_owned();
        Ok(())
    }

    /// The current factor (lower triangular L with `L L^T` the weighted Gram matrix); its
    /// column count is the effective one, rounded.
    pub fn factor(&self) -> Result<HankelFactor> {
        if self.n_columns == 0 {
            return Err(SysidError::InsufficientData {
                context: format!("a window of p + f = {} samples", self.layout.window()),
                needed: self.layout.window(),
                got: self.tail_y.nrows(),
                fix: "update with more samples first",
            });
        }
        let k = self.layout.k();
        let mut l = Mat::<f64>::zeros(k, k);
        for i in 0..k {
            let sign = if self.r[(i, i)] < 0.0 { -1.0 } else { 1.0 };
            for j in i..k {
                l[(j, i)] = sign * self.r[(i, j)];
            }
        }
        let cols = (self.weight.round() as usize).max(1);
        HankelFactor::from_parts(self.layout, l, cols, 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hankel::{Compressor, QrCompressor};

    #[test]
    fn without_forgetting_the_factor_equals_the_batch_one() {
        let n = 700;
        let u = Mat::from_fn(n, 1, |i, _| ((i * 7919) % 13) as f64 - 6.0);
        let y = Mat::from_fn(n, 2, |i, j| ((i * 104729 + j * 31) % 11) as f64 - 5.0);
        let lay = HankelLayout::new(1, 2, 4, 3).unwrap();
        let mut rec = RecursiveFactor::new(lay, 1.0).unwrap();
        let mut at = 0;
        for chunk in [3usize, 1, 50, 300, 346] {
            rec.update(u.as_ref().subrows(at, chunk), y.as_ref().subrows(at, chunk))
                .unwrap();
            at += chunk;
            if at < lay.window() {
                assert!(rec.factor().is_err());
                continue;
            }
            let mut c = QrCompressor::new(lay);
            c.push(u.as_ref().subrows(0, at), y.as_ref().subrows(0, at))
                .unwrap();
            let batch = c.finish().unwrap();
            let f = rec.factor().unwrap();
            assert_eq!(f.n_columns(), batch.n_columns());
            // compare L L^T (periodic test signals make L rank deficient, hence not unique)
            let g = f.l() * f.l().transpose();
            let gb = batch.l() * batch.l().transpose();
            let d = (&g - &gb).norm_max();
            assert!(d < 1e-10 * gb.norm_max(), "{at}: {d}");
        }
        assert!(RecursiveFactor::new(lay, 1.5).is_err());
    }

    #[test]
    fn the_whole_working_set_is_checked_before_sizing() {
        // k = 10 000: the triangle alone (0.8 GB) is allowed, an update's triangle, copy and
        // (5 k x k) stack (5.6 GB) are not
        let lay = HankelLayout::new(1, 1, 2500, 2500).unwrap();
        let e = RecursiveFactor::new(lay, 1.0).unwrap_err().to_string();
        assert!(e.contains("horizon") && e.contains("GiB limit"), "{e}");
        // below the limit the triangle waits for the first complete window
        let lay = HankelLayout::new(1, 1, 50, 50).unwrap();
        let mut rec = RecursiveFactor::new(lay, 1.0).unwrap();
        let (u, y) = (Mat::<f64>::zeros(60, 1), Mat::<f64>::zeros(60, 1));
        rec.update(u.as_ref(), y.as_ref()).unwrap();
        assert_eq!((rec.r.nrows(), rec.n_columns()), (0, 0));
        rec.update(u.as_ref(), y.as_ref()).unwrap();
        assert_eq!((rec.r.nrows(), rec.n_columns()), (lay.k(), 21));
    }
}
