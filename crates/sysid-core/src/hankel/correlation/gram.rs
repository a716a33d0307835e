//! Closing an experiment: its Hankel columns join the Gram matrix, from the lagged sums
//! minus the head and tail corrections of the module formula (`O(w^2 d^2)` work).

use super::{CorrelationSums, Segment};
use crate::error::{Result, SysidError};
use faer::Mat;

impl CorrelationSums {
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
        let k = self.layout.k();
        if self.gram.nrows() != k {
            self.gram = Mat::zeros(k, k);
        }
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
}
