//! Order choice from singular values.

/// Index n (1-based order) maximising `log s_n - log s_{n+1}` for `n <= max_order`
/// (SLICOT IB01AD with a negative tolerance). Singular values are floored at
/// `1e-15 * s_1` so that exact zeros give a finite, very large gap.
///
/// ```
/// use sysid_core::subspace::order::largest_log_gap;
/// assert_eq!(largest_log_gap(&[69.9, 15.0, 3.67, 1.97, 0.30, 0.21], 5), 4);
/// ```
pub fn largest_log_gap(sv: &[f64], max_order: usize) -> usize {
    if sv.is_empty() || max_order == 0 {
        return 0;
    }
    let floor = sv[0].abs() * 1e-15 + f64::MIN_POSITIVE;
    let lg = |x: f64| x.max(floor).ln();
    let last = max_order.min(sv.len().saturating_sub(1));
    if last == 0 {
        return 1;
    }
    let mut best = 1;
    let mut gap = f64::NEG_INFINITY;
    for n in 1..=last {
        let g = lg(sv[n - 1]) - lg(sv[n]);
        if g > gap {
            gap = g;
            best = n;
        }
    }
    best
}
