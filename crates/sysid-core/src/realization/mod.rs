//! Realisation: state-space models from Markov parameters (impulse responses).
//!
//! The Markov parameters of `x(t+1) = A x + B u`, `y = C x + D u` are `h_0 = D` and
//! `h_k = C A^{k-1} B` (each `l x m`). Stacked in a block-Hankel matrix with `r` block rows
//! and `s` block columns,
//!
//! ```text
//! H_0 = [h_1 h_2 ... h_s; h_2 ...; ...; h_r ... h_{r+s-1}] = O_r C_s,
//! H_1 = (the same, shifted by one: h_{i+j+1})               = O_r A C_s,
//! ```
//!
//! with `O_r` the extended observability and `C_s` the extended controllability matrix. The
//! SVD `H_0 = U S V^T`, truncated to the order n, gives `O_r = U_n S_n^{1/2}` and
//! `C_s = S_n^{1/2} V_n^T`; then `C` is the first block row of `O_r`, `B` the first block
//! column of `C_s`, and A follows either from the shifted Hankel matrix,
//! `A = S_n^{-1/2} U_n^T H_1 V_n S_n^{-1/2}` (Ho and Kalman 1966; ERA, Juang and Pappa 1985),
//! or from the shift invariance of `O_r`, `O_r[l..] = O_r[..-l] A` in least squares (Kung
//! 1978). With exact Markov parameters the rank of `H_0` is the minimal order and every
//! variant returns the same system up to a change of basis; with noisy ones the singular
//! values show the order.
//!
//! Files: [`ho_kalman`] (Ho-Kalman and Kung), [`era`] (ERA with modal accuracy indicators),
//! [`markov`] (Markov parameters from input/output data: least-squares FIR with optional TC
//! regularisation, and OKID), [`balanced`] (gramians, Hankel singular values, balanced
//! truncation), [`modal`] (frequencies, damping ratios and mode shapes).

pub mod balanced;
pub mod era;
pub mod ho_kalman;
pub mod markov;
pub mod modal;

pub use balanced::{
    balanced_realization, balanced_truncation, gramians, hankel_singular_values, Balanced,
};
pub use era::{era, EraResult};
pub use ho_kalman::{ho_kalman, kung};
pub use markov::{
    fir, okid, DirectTerm, FirEstimate, FirOptions, OkidEstimate, OkidOptions, Regularization,
};
pub use modal::{modal_analysis, Mode};

use crate::error::{Result, SysidError};
use crate::model::StateSpace;
use faer::{Mat, MatRef};

/// Which realisation algorithm: Ho-Kalman, Kung or ERA.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RealizationMethod {
    /// [`ho_kalman`].
    HoKalman,
    /// [`kung`].
    Kung,
    /// [`era`].
    Era,
}

crate::names::option_names! { RealizationMethod, "method", false, [
    ("ho_kalman", RealizationMethod::HoKalman), ("kung", RealizationMethod::Kung),
    ("era", RealizationMethod::Era),
] }

/// Options shared by the realisation algorithms.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct RealizationOptions {
    /// Model order; `None` chooses it: the numerical rank of `H_0` (Ho-Kalman) or, Kung
    /// and ERA, its numerical rank on noise-free Markov parameters and the count of its
    /// singular values above the noise floor on noisy ones (`auto_order`).
    pub order: Option<usize>,
    /// Block rows r of the Hankel matrix; `None` splits the available parameters evenly.
    pub rows: Option<usize>,
    /// Block columns s of the Hankel matrix; `None` splits the available parameters evenly.
    pub cols: Option<usize>,
    /// Relative tolerance on the singular values of `H_0` for the numerical rank.
    pub rank_tol: f64,
    /// Largest order the automatic choice (Kung, ERA) considers; `None`: every one the
    /// Hankel matrix allows. OKID's Markov parameters follow its observer of `p` past samples,
    /// so their Hankel matrix has rank `p l` by construction: on noisy data the largest gap
    /// is the drop to round-off there (12 decades), not the system's order (a few decades
    /// earlier), and the automatic order of OKID's Markov parameters stops below `p l`.
    pub max_order: Option<usize>,
}

impl Default for RealizationOptions {
    fn default() -> Self {
        Self {
            order: None,
            rows: None,
            cols: None,
            rank_tol: 1e-8,
            max_order: None,
        }
    }
}

impl RealizationOptions {
    /// Options with a fixed order.
    pub fn with_order(order: usize) -> Self {
        Self {
            order: Some(order),
            ..Self::default()
        }
    }
}

/// A realised model with the evidence for its order.
#[derive(Debug, Clone)]
pub struct Realization {
    /// The realised system (`D = h_0`).
    pub model: StateSpace,
    /// Singular values of the block-Hankel matrix `H_0`, decreasing.
    pub singular_values: Vec<f64>,
    /// Block rows used.
    pub rows: usize,
    /// Block columns used.
    pub cols: usize,
}

/// Checks a sequence of Markov parameters (same shape, finite, at least `needed` of them).
pub(crate) fn check_markov(markov: &[Mat<f64>]) -> Result<(usize, usize)> {
    if markov.is_empty() {
        return Err(SysidError::InsufficientData {
            context: "realisation".into(),
            needed: 3,
            got: 0,
            fix: "pass the Markov parameters h_0 = D, h_1 = CB, h_2 = CAB, ...",
        });
    }
    let (l, m) = (markov[0].nrows(), markov[0].ncols());
    if l == 0 || m == 0 {
        return Err(SysidError::invalid(
            "markov",
            "Markov parameters need at least one output and one input",
        ));
    }
    for (k, h) in markov.iter().enumerate() {
        if h.nrows() != l || h.ncols() != m {
            return Err(SysidError::ShapeMismatch {
                what: format!("Markov parameter {k}"),
                expected: format!("({l}, {m}) like the first one"),
                got: format!("({}, {})", h.nrows(), h.ncols()),
            });
        }
        for j in 0..m {
            for i in 0..l {
                if !h[(i, j)].is_finite() {
                    return Err(SysidError::NonFinite {
                        what: "markov",
                        sample: k,
                        channel: i * m + j,
                    });
                }
            }
        }
    }
    Ok((l, m))
}

/// Block rows and columns to use: the requested ones, checked, or an even split of the
/// `count - 1` parameters after `h_0` (the shifted Hankel matrix needs `h_{r+s}`).
pub(crate) fn hankel_size(
    count: usize,
    rows: Option<usize>,
    cols: Option<usize>,
) -> Result<(usize, usize)> {
    let avail = count.saturating_sub(1);
    let (r, s) = match (rows, cols) {
        (Some(r), Some(s)) => (r, s),
        (Some(r), None) => (r, avail.saturating_sub(r)),
        (None, Some(s)) => (avail.saturating_sub(s), s),
        (None, None) => (avail.div_ceil(2), avail / 2),
    };
    if r == 0 || s == 0 || r + s > avail {
        return Err(SysidError::InsufficientData {
            context: format!(
                "a block-Hankel matrix with {} block rows and {} block columns (plus its shift)",
                r.max(1),
                s.max(1)
            ),
            needed: r.max(1) + s.max(1) + 1,
            got: count,
            fix:
                "pass more Markov parameters (h_0 = D included) or choose fewer block rows/columns",
        });
    }
    Ok((r, s))
}

/// The block-Hankel matrix `[h_{1+shift+i+j}]` with r block rows and s block columns.
pub(crate) fn block_hankel(markov: &[Mat<f64>], r: usize, s: usize, shift: usize) -> Mat<f64> {
    let (l, m) = (markov[0].nrows(), markov[0].ncols());
    Mat::from_fn(r * l, s * m, |i, j| {
        markov[1 + shift + i / l + j / m][(i % l, j % m)]
    })
}

/// `max` lowered to `max_order` when that is given (at least 1).
pub(crate) fn cap(max: usize, max_order: Option<usize>) -> usize {
    max_order.map_or(max, |c| max.min(c.max(1)))
}

/// The automatic order (Kung, ERA) among `1..=max` from the singular values `sv` of a Hankel
/// matrix of `shape` (rows, columns):
/// - when a candidate singular value is below `rank_tol` times the largest (noise-free
///   Markov parameters), the numerical rank;
/// - else (noisy ones) the count above the noise floor: Gavish and Donoho's (2014) optimal
///   hard threshold for a noise level estimated from the median singular value,
///   `omega(beta) median(s)` with `beta` the Hankel matrix's aspect ratio. It assumes most
///   of the candidates are noise; of the values above the floor, those that form a continuum
///   with it (no gap, [`noise_edge`]) are counted as noise too; when half of them or more
///   stand above the floor, or none (a Hankel matrix too small to show the floor), the
///   largest gap of `log10(s_k / s_{k+1})` decides;
/// - with `max_order` (OKID's Markov parameters, whose errors follow its observer and are not
///   independent), the largest gap below it.
pub(crate) fn auto_order(
    sv: &[f64],
    shape: (usize, usize),
    opts: &RealizationOptions,
    max: usize,
) -> usize {
    let max = cap(max, opts.max_order);
    if opts.max_order.is_some() || sv.is_empty() {
        return largest_gap(sv, max);
    }
    let candidates = &sv[..(max + 1).min(sv.len())];
    let floor = opts.rank_tol * sv[0];
    let rank = candidates.iter().filter(|&&s| s > floor).count();
    if rank < candidates.len() {
        return rank.clamp(1, max.max(1));
    }
    let (rows, cols) = shape;
    let beta = rows.min(cols) as f64 / rows.max(cols).max(1) as f64;
    let omega = 0.56 * beta.powi(3) - 0.95 * beta.powi(2) + 1.82 * beta + 1.43;
    let threshold = omega * median(candidates);
    let above = candidates.iter().filter(|&&s| s > threshold).count();
    if above == 0 || 2 * above >= candidates.len() {
        largest_gap(sv, max)
    } else {
        noise_edge(sv, above).clamp(1, max.max(1))
    }
}

/// Log gaps below which the next singular value counts as part of the noise continuum: a
/// gap of at least [`EDGE_MIN_GAP`] decades and [`EDGE_FACTOR`] times the median of the
/// [`EDGE_WINDOW`] gaps after it.
const EDGE_MIN_GAP: f64 = 0.05;
const EDGE_FACTOR: f64 = 5.0;
const EDGE_WINDOW: usize = 20;

/// The largest order `k <= above` whose singular value stands apart from the ones after it
/// (see the constants above), else `above`. Noise on Markov parameters is not independent
/// from entry to entry of a block-Hankel matrix (each value repeats along an anti-diagonal,
/// and the channel scaling gives the channels different noise levels), so the top of its
/// singular values spreads past the median-based threshold and the count above it grew with
/// the record: 2 x 2 Markov parameters of a 6-state system with 0.1 % noise gave orders
/// 8-66 from 400 of them and 12-187 from 1000. The values above the threshold that belong to
/// the noise form a continuum with it, with no gap.
fn noise_edge(sv: &[f64], above: usize) -> usize {
    let floor = sv.first().copied().unwrap_or(0.0) * 1e-15 + f64::MIN_POSITIVE;
    let gap = |k: usize| (sv[k - 1].max(floor) / sv[k].max(floor)).log10();
    for k in (1..=above.min(sv.len().saturating_sub(1))).rev() {
        let after: Vec<f64> = (k + 1..sv.len().min(k + 1 + EDGE_WINDOW))
            .map(gap)
            .collect();
        if after.is_empty() {
            return k;
        }
        if gap(k) >= EDGE_MIN_GAP.max(EDGE_FACTOR * median(&after)) {
            return k;
        }
    }
    above
}

/// Median of a non-empty slice.
fn median(x: &[f64]) -> f64 {
    let mut v = x.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let k = v.len() / 2;
    if v.len() % 2 == 1 {
        v[k]
    } else {
        0.5 * (v[k - 1] + v[k])
    }
}

/// Order with the largest drop of `log10(s_k / s_{k+1})`, among `1..=max`.
pub(crate) fn largest_gap(sv: &[f64], max: usize) -> usize {
    let floor = sv.first().copied().unwrap_or(0.0) * 1e-15 + f64::MIN_POSITIVE;
    let mut best = (1, f64::NEG_INFINITY);
    for k in 1..=max.min(sv.len().saturating_sub(1)) {
        let gap = (sv[k - 1].max(floor) / sv[k].max(floor)).log10();
        if gap > best.1 {
            best = (k, gap);
        }
    }
    best.0
}

/// Thin SVD of `H_0` split into the order-n factors `U_n`, `S_n`, `V_n` and all singular values.
pub(crate) struct HankelSvd {
    pub u: Mat<f64>,
    pub s: Vec<f64>,
    pub v: Mat<f64>,
}

pub(crate) fn hankel_svd(h0: MatRef<'_, f64>) -> Result<HankelSvd> {
    let (s, u, v) = crate::linalg::svd_both_seq("SVD of the Hankel matrix", h0)?;
    Ok(HankelSvd { u, s, v })
}

/// Checks the chosen order against the singular values (positive, within the Hankel size).
pub(crate) fn check_order(
    n: usize,
    sv: &[f64],
    r: usize,
    s: usize,
    l: usize,
    m: usize,
) -> Result<()> {
    let max = sv.len();
    if n == 0 || n > max {
        return Err(SysidError::invalid(
            "order",
            format!(
                "order {n} is not possible with a {r} x {s} block-Hankel matrix of {l}x{m} blocks \
                 (at most {max}); choose 1 <= order <= {max} or more block rows/columns"
            ),
        ));
    }
    if sv[n - 1].is_nan() || sv[n - 1] <= sv[0] * 1e-14 {
        return Err(SysidError::invalid(
            "order",
            format!(
                "the Hankel matrix has numerical rank below {n} (singular value {n} is {:.3e}, \
                 the largest {:.3e}); choose a lower order",
                sv[n - 1],
                sv[0]
            ),
        ));
    }
    Ok(())
}

/// Observability and controllability factors `O = U_n S^{1/2}`, `Cc = S^{1/2} V_n^T`.
pub(crate) fn factors(svd: &HankelSvd, n: usize) -> (Mat<f64>, Mat<f64>) {
    let rl = svd.u.nrows();
    let sm = svd.v.nrows();
    let obs = Mat::from_fn(rl, n, |i, j| svd.u[(i, j)] * svd.s[j].sqrt());
    let ctr = Mat::from_fn(n, sm, |i, j| svd.s[i].sqrt() * svd.v[(j, i)]);
    (obs, ctr)
}

/// `A = S^{-1/2} U_n^T H_1 V_n S^{-1/2}`.
pub(crate) fn a_from_shift(svd: &HankelSvd, h1: MatRef<'_, f64>, n: usize) -> Mat<f64> {
    let un = svd.u.subcols(0, n);
    let vn = svd.v.subcols(0, n);
    let core = un.transpose() * h1 * vn;
    Mat::from_fn(n, n, |i, j| {
        core[(i, j)] / (svd.s[i].sqrt() * svd.s[j].sqrt())
    })
}

#[cfg(test)]
pub(crate) mod testing {
    //! Random stable MIMO systems for the tests of this module.
    use crate::model::StateSpace;
    use faer::Mat;
    use rand::{rngs::StdRng, Rng, SeedableRng};

    /// A random system whose poles are placed in the annulus `0.3 <= |z| <= rmax`, complex
    /// pairs and a real pole when n is odd, mixed by a random similarity.
    pub fn random_system(n: usize, m: usize, l: usize, rmax: f64, seed: u64) -> StateSpace {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut a = Mat::<f64>::zeros(n, n);
        let mut i = 0;
        while i + 1 < n {
            let r: f64 = rng.random_range(0.3..rmax);
            let th: f64 = rng.random_range(0.2..2.8);
            a[(i, i)] = r * th.cos();
            a[(i, i + 1)] = r * th.sin();
            a[(i + 1, i)] = -r * th.sin();
            a[(i + 1, i + 1)] = r * th.cos();
            i += 2;
        }
        if i < n {
            a[(i, i)] = rng.random_range(-rmax..rmax);
        }
        let t = Mat::from_fn(
            n,
            n,
            |i, j| if i == j { 2.0 } else { 0.0 } + rng.random_range(-0.5..0.5),
        );
        let tinv = crate::linalg::pinv(t.as_ref(), 1e-14).unwrap();
        let a = &tinv * &a * &t;
        let b = Mat::from_fn(n, m, |_, _| rng.random_range(-1.0..1.0));
        let c = Mat::from_fn(l, n, |_, _| rng.random_range(-1.0..1.0));
        let d = Mat::from_fn(l, m, |_, _| rng.random_range(-1.0..1.0));
        StateSpace::new(a, b, c, d).unwrap()
    }

    /// Poles sorted by (re, im), for comparison between bases.
    pub fn sorted_poles(sys: &StateSpace) -> Vec<(f64, f64)> {
        let mut p = sys.poles().unwrap();
        p.sort_by(|x, y| {
            x.0.partial_cmp(&y.0)
                .unwrap()
                .then(x.1.partial_cmp(&y.1).unwrap())
        });
        p
    }

    /// Largest difference between two pole sets (each matched to its nearest).
    pub fn pole_distance(a: &StateSpace, b: &StateSpace) -> f64 {
        let pa = sorted_poles(a);
        let pb = sorted_poles(b);
        assert_eq!(pa.len(), pb.len());
        pa.iter()
            .map(|x| {
                pb.iter()
                    .map(|y| (x.0 - y.0).hypot(x.1 - y.1))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
    }

    /// Largest difference of the first `count` Markov parameters, relative to the largest.
    pub fn markov_distance(a: &StateSpace, b: &StateSpace, count: usize) -> f64 {
        let ha = a.markov(count);
        let hb = b.markov(count);
        let scale = ha.iter().map(|h| h.norm_max()).fold(0.0, f64::max);
        ha.iter()
            .zip(&hb)
            .map(|(x, y)| (x - y).norm_max())
            .fold(0.0, f64::max)
            / scale
    }
}

#[cfg(test)]
mod auto_order_tests {
    use super::*;

    fn order(sv: &[f64], shape: (usize, usize), max_order: Option<usize>) -> usize {
        let opts = RealizationOptions {
            max_order,
            ..RealizationOptions::default()
        };
        auto_order(sv, shape, &opts, sv.len() - 1)
    }

    #[test]
    fn rank_noise_floor_and_gap() {
        // noise-free: the numerical rank, whatever the spread of the strong values
        let exact = [1e3, 1.0, 0.5, 1e-12, 1e-13, 1e-14, 1e-15];
        assert_eq!(order(&exact, (7, 7), None), 3);
        // noisy: three values above a floor of forty near 1 (the largest gap is 1e3 -> 50)
        let mut noisy = vec![1e3, 50.0, 20.0];
        noisy.extend((0..40).map(|k| 1.2 - 0.01 * k as f64));
        assert_eq!(order(&noisy, (43, 43), None), 3);
        // too small to show a floor: the largest gap
        let short = [10.0, 9.0, 8.0, 7.0, 1.0, 0.9];
        assert_eq!(order(&short, (6, 6), None), 4);
        // OKID's cap: the largest gap below it
        assert_eq!(order(&noisy, (43, 43), Some(2)), 1);
    }

    #[test]
    fn noise_values_above_the_floor_without_a_gap_are_noise() {
        // six strong values, then a noise continuum whose top stands above the median-based
        // floor (as block-Hankel noise does): the order is 6, not the count above the floor
        let mut sv = vec![10.0, 8.0, 6.0, 4.0, 2.5, 2.4];
        sv.extend((0..200).map(|k| 0.3 * (-0.03 * k as f64).exp()));
        let threshold = 2.858 * median(&sv);
        assert!(sv.iter().filter(|&&s| s > threshold).count() > 60);
        assert_eq!(order(&sv, (206, 206), None), 6);
        // a weak mode with a clear gap below it stays (the largest gap, 8 -> 0.5, is ignored)
        let mut weak = vec![10.0, 8.0, 0.5, 0.45];
        weak.extend((0..200).map(|k| 0.1 * (-0.03 * k as f64).exp()));
        assert_eq!(order(&weak, (204, 204), None), 4);
    }
}
