//! Partial sums of one contiguous stretch of samples, and how two neighbouring stretches
//! combine (the cross terms come from the last `w - 1` samples of the first and the first
//! `w - 1` of the second).

use super::super::lagsum::lag_sums;
use faer::Mat;

/// Partial sums of one contiguous stretch of samples (inside one experiment).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Segment {
    pub(super) n: usize,
    /// d x (w d): block `tau` holds `sum x_t x_{t+tau}^T` over pairs inside the segment.
    pub(super) lag: Mat<f64>,
    pub(super) sum: Vec<f64>,
    /// First `min(n, w - 1)` samples, row-major.
    pub(super) head: Vec<f64>,
    /// Last `min(n, w - 1)` samples, row-major.
    pub(super) tail: Vec<f64>,
}

impl Segment {
    pub(super) fn empty(d: usize, w: usize) -> Self {
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
    pub(super) fn from_padded_rows(x: &[f64], n: usize, d: usize, w: usize) -> Self {
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
    pub(super) fn concat(&self, next: &Segment, d: usize, w: usize) -> Segment {
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
