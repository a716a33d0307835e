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
/// Two passes over the data (the mean, then the spread about it), no copy. Parts stored
/// row-major (a C-ordered `(samples, channels)` array) run through lanes of 8 samples that
/// the compiler vectorises, about the memory bandwidth; sums are then taken in a different
/// order than sample by sample, so `mean` and `std` agree with NumPy's `x.mean(0)`,
/// `x.std(0)` to round-off. Records with a non-finite value take the sample-by-sample loop
/// (NaN propagates into `abs_max`, as `abs(x).max(0)`).
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
    if c == 0 {
        // no channel: nothing to sum (and no lane of width zero to split the rows into)
        return ChannelStats {
            abs_max: Vec::new(),
            mean: Vec::new(),
            std: Vec::new(),
        };
    }
    let n: usize = parts.iter().map(|p| p.nrows()).sum();
    let nf = n as f64;
    let (mut abs_max, mut sum, mut finite) = (vec![0.0f64; c], vec![0.0f64; c], true);
    for p in parts {
        let (sum_p, max_p, fin_p) = match row_major(*p) {
            Some(x) => lane_sums(x, c, None),
            None => strided_sums(*p, None),
        };
        finite &= fin_p;
        for j in 0..c {
            sum[j] += sum_p[j];
            abs_max[j] = abs_max[j].max(max_p[j]);
        }
    }
    if !finite {
        return channel_stats_ordered(parts);
    }
    let mean: Vec<f64> = sum.iter().map(|s| s / nf).collect();
    let mut ss = vec![0.0f64; c];
    for p in parts {
        let (ss_p, _, _) = match row_major(*p) {
            Some(x) => lane_sums(x, c, Some(&mean)),
            None => strided_sums(*p, Some(&mean)),
        };
        for j in 0..c {
            ss[j] += ss_p[j];
        }
    }
    let std = ss.iter().map(|s| (s / nf).sqrt()).collect();
    ChannelStats { abs_max, mean, std }
}

/// The samples of `p` as one row-major slice, when they are stored so.
fn row_major<'a>(p: MatRef<'a, f64>) -> Option<&'a [f64]> {
    let (r, c) = (p.nrows(), p.ncols());
    if r == 0 || c == 0 {
        return Some(&[]);
    }
    let rows_ok = r == 1 || p.row_stride() == c as isize;
    let cols_ok = c == 1 || p.col_stride() == 1;
    if rows_ok && cols_ok {
        // SAFETY: the r c values are contiguous (checked strides) and live as long as `p`.
        Some(unsafe { std::slice::from_raw_parts(p.as_ptr(), r * c) })
    } else {
        None
    }
}

const LANES: usize = 8;

/// Per channel: the sum of `x` (or of `(x - mean)^2` when `mean` is given), `max |x|`, and
/// whether every value is finite; `x` row-major with `c` channels.
#[allow(clippy::eq_op)] // `v - v`: 0 for finite values, NaN otherwise
fn lane_sums(x: &[f64], c: usize, mean: Option<&[f64]>) -> (Vec<f64>, Vec<f64>, bool) {
    let width = LANES * c;
    let mut acc = vec![0.0f64; width];
    let mut big = vec![0.0f64; width];
    let mut bad = vec![0.0f64; width];
    let mut chunks = x.chunks_exact(width);
    match mean {
        None => {
            for ch in &mut chunks {
                for (((a, m), b), v) in acc.iter_mut().zip(&mut big).zip(&mut bad).zip(ch) {
                    *a += v;
                    let av = v.abs();
                    *m = if av > *m { av } else { *m };
                    *b += v - v; // NaN unless finite
                }
            }
        }
        Some(mu) => {
            let mus: Vec<f64> = (0..width).map(|k| mu[k % c]).collect();
            for ch in &mut chunks {
                for ((a, m), v) in acc.iter_mut().zip(&mus).zip(ch) {
                    let d = v - m;
                    *a += d * d;
                }
            }
        }
    }
    let (mut s, mut mx) = (vec![0.0f64; c], vec![0.0f64; c]);
    for k in 0..width {
        s[k % c] += acc[k];
        mx[k % c] = mx[k % c].max(big[k]);
    }
    let mut finite = bad.iter().all(|b| *b == 0.0);
    for row in chunks.remainder().chunks_exact(c) {
        for (j, v) in row.iter().enumerate() {
            accumulate(&mut s, &mut mx, &mut finite, j, *v, mean);
        }
    }
    (s, mx, finite)
}

/// One value of channel `j` into the sums: the value itself (with its magnitude and
/// finiteness) without `mean`, its squared deviation from `mean[j]` with it.
#[inline]
fn accumulate(
    s: &mut [f64],
    mx: &mut [f64],
    finite: &mut bool,
    j: usize,
    v: f64,
    mean: Option<&[f64]>,
) {
    match mean {
        None => {
            s[j] += v;
            mx[j] = mx[j].max(v.abs());
            *finite &= v.is_finite();
        }
        Some(mu) => s[j] += (v - mu[j]) * (v - mu[j]),
    }
}

/// [`lane_sums`] for any strides, column by column.
fn strided_sums(p: MatRef<'_, f64>, mean: Option<&[f64]>) -> (Vec<f64>, Vec<f64>, bool) {
    let c = p.ncols();
    let (mut s, mut mx, mut finite) = (vec![0.0f64; c], vec![0.0f64; c], true);
    for j in 0..c {
        for v in p.col(j).iter() {
            accumulate(&mut s, &mut mx, &mut finite, j, *v, mean);
        }
    }
    (s, mx, finite)
}

/// The sample-by-sample statistics (records with non-finite values).
fn channel_stats_ordered(parts: &[MatRef<'_, f64>]) -> ChannelStats {
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

/// Lagged products `R[tau][a][b] = sum_t x_a(t + tau) x_b(t)`, `tau = 0..=max_lag`, summed
/// over the experiments `parts` (no lag spans two; lags beyond an experiment add nothing).
///
/// Each part holds `n` samples of `d` channels row-major (`x[t d + a]`). The sums come
/// from [`lag_sums`](crate::hankel::lag_sums) read in place over the record, the last
/// `max_lag` samples through a small zero-padded copy: no copy of the record. Returned
/// row-major as `(max_lag + 1, d, d)`.
///
/// ```
/// use sysid_core::stats::lagged_products;
/// // one channel, x = [1, 2, 3]: R[0] = 14, R[1] = 2*1 + 3*2 = 8, R[2] = 3, R[3] = 0
/// let r = lagged_products(&[&[1.0, 2.0, 3.0][..]], 1, 3);
/// assert_eq!(r, vec![14.0, 8.0, 3.0, 0.0]);
/// ```
pub fn lagged_products(parts: &[&[f64]], d: usize, max_lag: usize) -> Vec<f64> {
    let mut r = vec![0.0; (max_lag + 1) * d * d];
    for x in parts {
        let n = x.len().checked_div(d).unwrap_or(0);
        if n == 0 {
            continue;
        }
        let w = max_lag.min(n - 1) + 1;
        let wd = w * d;
        let mut c = vec![0.0; d * wd];
        crate::hankel::lag_sums(x, n + 1 - w, d, w, &mut c);
        if w > 1 {
            let mut tail = vec![0.0; (2 * w - 2) * d];
            tail[..(w - 1) * d].copy_from_slice(&x[(n + 1 - w) * d..n * d]);
            crate::hankel::lag_sums(&tail, w - 1, d, w, &mut c);
        }
        for tau in 0..w {
            for a in 0..d {
                for b in 0..d {
                    r[(tau * d + a) * d + b] += c[b * wd + tau * d + a];
                }
            }
        }
    }
    r
}

#[cfg(test)]
mod tests {
    #[test]
    fn lagged_products_match_the_definition() {
        let (n, d, lag) = (37, 3, 6);
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let x: Vec<f64> = (0..n * d).map(|_| next()).collect();
        let short: Vec<f64> = (0..4 * d).map(|_| next()).collect();
        let r = super::lagged_products(&[&x, &short], d, lag);
        for tau in 0..=lag {
            for a in 0..d {
                for b in 0..d {
                    let mut want = 0.0;
                    for part in [&x, &short] {
                        let m = part.len() / d;
                        for t in 0..m.saturating_sub(tau) {
                            want += part[(t + tau) * d + a] * part[t * d + b];
                        }
                    }
                    let got = r[(tau * d + a) * d + b];
                    assert!(
                        (got - want).abs() < 1e-13,
                        "tau {tau} ({a}, {b}): {got} vs {want}"
                    );
                }
            }
        }
    }

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
            assert!((s.mean[j] - mean).abs() <= 1e-14 * mean.abs().max(1.0));
            assert!((s.std[j] - var.sqrt()).abs() <= 1e-14 * var.sqrt());
            assert_eq!(s.abs_max[j], big);
        }
    }

    #[test]
    fn no_channel_gives_empty_statistics() {
        let x = Mat::<f64>::zeros(10, 0);
        let s = channel_stats(&[x.as_ref()]);
        assert!(s.abs_max.is_empty() && s.mean.is_empty() && s.std.is_empty());
        assert!(channel_stats(&[]).mean.is_empty());
    }

    #[test]
    fn row_major_lanes_strided_and_nonfinite_paths_agree() {
        // 203 rows: 25 full lanes of 8 samples and a remainder of 3
        let a = Mat::from_fn(203, 3, |i, j| ((i * 13 + j * 5) % 17) as f64 * 0.29 - 2.0);
        let rm: Vec<f64> = (0..203)
            .flat_map(|i| (0..3).map(move |j| ((i * 13 + j * 5) % 17) as f64 * 0.29 - 2.0))
            .collect();
        let v = MatRef::from_row_major_slice(&rm, 203, 3);
        let (x, y) = (channel_stats(&[a.as_ref()]), channel_stats(&[v]));
        for j in 0..3 {
            assert!((x.mean[j] - y.mean[j]).abs() < 1e-14);
            assert!((x.std[j] - y.std[j]).abs() < 1e-14);
            assert_eq!(x.abs_max[j], y.abs_max[j]);
        }
        let mut bad = rm.clone();
        bad[3 * 100 + 1] = f64::NAN;
        let s = channel_stats(&[MatRef::from_row_major_slice(&bad, 203, 3)]);
        assert!(s.abs_max[1].is_nan() && s.mean[1].is_nan() && !s.mean[0].is_nan());
        bad[3 * 100 + 1] = f64::INFINITY;
        let s = channel_stats(&[MatRef::from_row_major_slice(&bad, 203, 3)]);
        assert!(s.abs_max[1].is_infinite() && s.abs_max[0].is_finite());
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
