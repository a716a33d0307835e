//! Per-channel statistics of records (one pass over the samples, for input checks).

use faer::MatRef;

/// Largest absolute value, mean and standard deviation (population, `1/N`) of each column
/// over the rows of all `parts` (experiments) taken in order.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelStats {
    /// `max_t |x_t|` per channel.
    pub abs_max: Vec<f64>,
    /// Mean per channel.
    pub mean: Vec<f64>,
    /// Standard deviation per channel, `sqrt(sum (x_t - mean)^2 / N)`.
    pub std: Vec<f64>,
}

/// Statistics of the columns of `parts` (all with the same number of columns).
///
/// The sums run sample by sample in order, the way NumPy reduces a C-ordered `(samples,
/// channels)` array along its first axis, so `mean` and `std` equal `x.mean(0)` and
/// `x.std(0)` of the concatenated record bit for bit in that layout. Two passes over the
/// data, no copy.
///
/// ```
/// use faer::mat;
/// use sysid_core::stats::channel_stats;
/// let x = mat![[1.0, -4.0], [3.0, 0.0]];
/// let s = channel_stats(&[x.as_ref()]);
/// assert_eq!(s.abs_max, vec![3.0, 4.0]);
/// assert_eq!(s.mean, vec![2.0, -2.0]);
/// assert_eq!(s.std, vec![1.0, 2.0]);
/// ```
pub fn channel_stats(parts: &[MatRef<'_, f64>]) -> ChannelStats {
    let c = parts.first().map_or(0, |p| p.ncols());
    let n: usize = parts.iter().map(|p| p.nrows()).sum();
    let mut abs_max = vec![0.0f64; c];
    let mut sum = vec![0.0f64; c];
    for p in parts {
        for t in 0..p.nrows() {
            for j in 0..c {
                let v = p[(t, j)];
                sum[j] += v;
                let a = v.abs();
                if a > abs_max[j] || a.is_nan() {
                    abs_max[j] = a;
                }
            }
        }
    }
    let nf = n as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / nf).collect();
    let mut ss = vec![0.0f64; c];
    for p in parts {
        for t in 0..p.nrows() {
            for j in 0..c {
                let d = p[(t, j)] - mean[j];
                ss[j] += d * d;
            }
        }
    }
    let std = ss.iter().map(|s| (s / nf).sqrt()).collect();
    ChannelStats { abs_max, mean, std }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    #[test]
    fn matches_a_two_pass_reference_over_several_parts() {
        let a = Mat::from_fn(50, 3, |i, j| ((i * 7 + j * 3) % 11) as f64 * 0.37 - 1.5);
        let b = Mat::from_fn(20, 3, |i, j| ((i * 5 + j) % 7) as f64 * -0.91 + 2.0);
        let s = channel_stats(&[a.as_ref(), b.as_ref()]);
        for j in 0..3 {
            let v: Vec<f64> = (0..50)
                .map(|i| a[(i, j)])
                .chain((0..20).map(|i| b[(i, j)]))
                .collect();
            let mean = v.iter().sum::<f64>() / 70.0;
            let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / 70.0;
            let big = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            assert_eq!(s.mean[j], mean);
            assert_eq!(s.std[j], var.sqrt());
            assert_eq!(s.abs_max[j], big);
        }
    }

    #[test]
    fn constant_channel_has_zero_spread() {
        let a = Mat::from_fn(1000, 1, |_, _| 0.1);
        let s = channel_stats(&[a.as_ref()]);
        assert_eq!(s.abs_max, vec![0.1]);
        // a sequential sum of 1000 values 0.1 is off by a few ulps: the spread is round-off
        assert!(s.std[0] < 1e-12 * 0.1);
    }
}
