//! From the centred, scaled Gram matrix to the LQ triangle of the raw data matrix:
//! Cholesky of `Ga` (eigendecomposition when it fails), the shift and scale put back, rows
//! permuted to the canonical order.

use super::CorrelationSums;
use crate::error::{Result, SysidError};
use crate::hankel::{Block, FactorSource, HankelFactor};
use crate::linalg::{cholesky_lower_seq, lq_lower, lq_lower_rank_one};
use faer::Mat;

impl CorrelationSums {
    /// Closes the open experiment and factors the Gram matrix of the raw data.
    ///
    /// The result is flagged [`FactorSource::CorrelationIllConditioned`] when the smallest
    /// relative Cholesky pivot of the centred, scaled Gram matrix is below
    /// `min_relative_pivot`, or when Cholesky fails (then the factor comes from the
    /// eigendecomposition with negative eigenvalues set to zero).
    pub fn into_factor(mut self, min_relative_pivot: f64) -> Result<HankelFactor> {
        let (m, l, p) = (
            self.layout.n_inputs,
            self.layout.n_outputs,
            self.layout.past,
        );
        let (d, w, k) = (m + l, self.layout.window(), self.layout.k());
        // too few columns in all: refused before the open experiment is closed (which sizes
        // the k x k Gram matrix); an open experiment shorter than a window is refused by
        // end_experiment
        let open = self.open_samples;
        let (cols, exps) = (
            self.n_columns + (open + 1).saturating_sub(w),
            self.n_experiments + usize::from(open > 0),
        );
        if (open == 0 || open >= w) && cols < k {
            return Err(SysidError::InsufficientData {
                context: format!(
                    "a data matrix with {k} rows (horizons p={}, f={}, {m} input(s), {l} output(s))",
                    p, self.layout.future
                ),
                needed: k + (w - 1) * exps.max(1),
                got: cols + (w - 1) * exps,
                fix: crate::error::horizon_fix(p, self.layout.future),
            });
        }
        self.end_experiment()?;
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
                let (v, s) = crate::optim::symmetric_eigen(
                    &ga,
                    "correlation compressor (eigendecomposition)",
                )?;
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
