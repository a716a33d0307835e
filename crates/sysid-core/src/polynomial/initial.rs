//! Initial conditions of the polynomial predictors (MATLAB's `InitialCondition`).
//!
//! From rest, the predictor `e = D/C (A y - sum_j B_j/F_j x_j)`, `x_j(t) = u_j(t - nk_j)`,
//! treats every sample before the record as zero. What those samples were enters the
//! difference equations as polynomials `h(q) = h[0] + h[1] q^-1 + ...` acting on the first
//! samples only:
//!
//! ```text
//! F_j w_j = B_j x_j + h_j,      v = A y - sum_j w_j,      C e = D v + h_e
//! ```
//!
//! * `h_j` (an input with an `F_j`) has `L_j = max(nf_j, nk_j + nb_j - 1)` coefficients: the
//!   state of `B_j q^-nk_j / F_j` (SciPy's `lfilter(r_[zeros(nk_j), b_j], r_[1, f_j], u_j,
//!   zi=h_j)`);
//! * `h_e` holds the rest: the pre-sample outputs of `A`, the pre-sample inputs of inputs
//!   without `F_j`, and the state of `D/C`, `L_e = max(nc, nd, L_v + nd)` coefficients with
//!   `L_v = max(na, nk_j + nb_j - 1 of the inputs without F_j)` (`L_v = 0`: `max(nc, nd)`).
//!   This is every pre-sample history's effect (exactly so when `nd = 0` or `L_v = 0`, as
//!   in ARMAX, OE and BJ; otherwise a space a little larger when `nc < L_v + nd`).
//!
//! The residual is affine in `h = [h_1.., h_e]`: `e = e_0 + Psi h`, the columns of `Psi` the
//! impulse responses of `-D/(C F_j)` (for `h_j`) and `1/C` (for `h_e`), delayed by `0, 1, ..`.
//! Estimating `h` with the parameters is eliminating it by least squares at every evaluation
//! (variable projection, Golub & Pereyra 1973): the residual is `P e_0`, `P = I - Q Q^T` with
//! `Q` an orthonormal basis of `Psi`'s columns (modified Gram-Schmidt, twice), and the
//! sensitivities `J` at the fitted `h` give the gradient `J^T e` exactly and the Gauss-Newton
//! matrix `J^T J - (J^T Q)(Q^T J)` (Kaufman 1975), the Schur complement of the joint
//! information of parameters and initial state: its inverse times `sigma^2` is the marginal
//! covariance of the parameters, the initial state a nuisance.
//!
//! `Auto` fits from rest first and then estimates when, at that fit, eliminating `h` lowers
//! the sum of squared errors by more than [`AUTO_FACTOR`] times what it lowers it by on
//! average when the true initial state is zero ([`chance_drop`]: `n_h sigma^2` for white
//! errors, `n_h` the initial coefficients of every experiment; more for coloured ones, from
//! the errors' autocovariances): for white errors a chi-square test of the initial state
//! being zero, passed by chance with probability 1 % (`n_h = 1`; the 99 % point of
//! chi-square with one degree of freedom) and below 0.2 % (`n_h >= 2`). When it does, the result is `Estimate`'s (searched from the same start).

use faer::Mat;

use super::filter::{conv, filter};
use super::pem::{MisoOrders, MisoPolys};
use crate::error::{Result, SysidError};

/// How the initial conditions of the predictor are set (MATLAB's `InitialCondition`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialCondition {
    /// From rest: every sample before the record is zero.
    Zero,
    /// Estimated with the parameters (eliminated by least squares at every evaluation).
    Estimate,
    /// From rest, unless estimating lowers the criterion materially (see the module notes).
    Auto,
}

impl InitialCondition {
    /// The names [`InitialCondition::parse`] accepts.
    pub const NAMES: [&'static str; 3] = ["auto", "zero", "estimate"];

    /// `"auto"`, `"zero"` or `"estimate"`; MATLAB's `"backcast"` is refused with the reason.
    pub fn parse(name: &str) -> Result<Self> {
        match name {
            "auto" => Ok(Self::Auto),
            "zero" => Ok(Self::Zero),
            "estimate" => Ok(Self::Estimate),
            "backcast" => Err(SysidError::invalid(
                "initial_condition",
                "'backcast' is not offered ('estimate' fits the initial state exactly by \
                 least squares); use 'auto', 'zero' or 'estimate'",
            )),
            other => Err(SysidError::invalid(
                "initial_condition",
                format!("must be 'auto', 'zero' or 'estimate', got {other:?}"),
            )),
        }
    }

    /// The name [`InitialCondition::parse`] reads.
    pub fn name(self) -> &'static str {
        match self {
            Self::Zero => "zero",
            Self::Estimate => "estimate",
            Self::Auto => "auto",
        }
    }
}

/// `Auto` estimates when the sum of squared errors drops by more than this many times what a
/// zero initial state lets it drop by on average ([`chance_drop`]).
pub const AUTO_FACTOR: f64 = 6.63;

/// With the initial states estimated, a cost below `0.5 |y|^2 ROUNDOFF^2` is an exact fit (the
/// search stops there: the rest is round-off, which would move the directions the data leave
/// undetermined, such as `C` of a noise-free ARMAX record).
pub const ROUNDOFF: f64 = 1e-14;

/// How many initial coefficients each polynomial of one experiment has.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// `L_j` per input (0 for an input without `F_j` or without `B_j`).
    pub input: Vec<usize>,
    /// `L_e`.
    pub noise: usize,
}

impl Layout {
    /// The layout of `orders` (see the module notes).
    pub fn new(o: &MisoOrders) -> Self {
        let lag = |j: usize| {
            if o.nb[j] == 0 {
                0
            } else {
                o.nk[j] + o.nb[j] - 1
            }
        };
        let input: Vec<usize> = (0..o.nb.len())
            .map(|j| {
                if o.nf[j] > 0 && o.nb[j] > 0 {
                    o.nf[j].max(lag(j))
                } else {
                    0
                }
            })
            .collect();
        let lv = (0..o.nb.len())
            .filter(|&j| o.nf[j] == 0)
            .map(lag)
            .fold(o.na, usize::max);
        let mut noise = o.nc.max(o.nd);
        if lv > 0 {
            noise = noise.max(lv + o.nd);
        }
        Self { input, noise }
    }

    /// Coefficients of one experiment's initial state.
    pub fn len(&self) -> usize {
        self.input.iter().sum::<usize>() + self.noise
    }

    /// `true` when there is no initial state (never for a structure with parameters).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The initial state of one experiment: `h_j` per input (empty without `F_j`) and `h_e`.
#[derive(Debug, Clone, PartialEq)]
pub struct InitialState {
    /// `h_j`, the initial coefficients of `F_j w_j = B_j x_j + h_j`.
    pub input: Vec<Vec<f64>>,
    /// `h_e`, the initial coefficients of `C e = D v + h_e`.
    pub noise: Vec<f64>,
}

impl InitialState {
    /// From rest.
    pub fn zeros(layout: &Layout) -> Self {
        Self {
            input: layout.input.iter().map(|&l| vec![0.0; l]).collect(),
            noise: vec![0.0; layout.noise],
        }
    }

    fn from_flat(layout: &Layout, h: &[f64]) -> Self {
        let mut at = 0;
        let mut take = |n: usize| {
            let s = h[at..at + n].to_vec();
            at += n;
            s
        };
        let input = layout.input.iter().map(|&l| take(l)).collect();
        let noise = take(layout.noise);
        Self { input, noise }
    }

    /// `(1 / a) h`: the response of the monic `a` to the pulses `h` at the start, `n` samples.
    pub(super) fn response(h: &[f64], a: &[f64], n: usize) -> Vec<f64> {
        let mut s = vec![0.0; n];
        let k = h.len().min(n);
        s[..k].copy_from_slice(&h[..k]);
        filter(&[1.0], a, &s)
    }
}

/// The least-squares initial state of one experiment at given polynomials.
pub(super) struct Projection {
    /// The fitted initial state.
    pub state: InitialState,
    /// An orthonormal basis (n x r) of the columns of `Psi`.
    pub q: Mat<f64>,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The columns of `Psi` (n samples each), in the order of [`InitialState::from_flat`].
fn columns(p: &MisoPolys, layout: &Layout, n: usize) -> Vec<Vec<f64>> {
    let mut imp = vec![0.0; n];
    if n > 0 {
        imp[0] = 1.0;
    }
    let mut cols = Vec::with_capacity(layout.len());
    let shifts = |g: Vec<f64>, l: usize, cols: &mut Vec<Vec<f64>>| {
        for i in 0..l {
            let mut c = vec![0.0; n];
            if i < n {
                c[i..].copy_from_slice(&g[..n - i]);
            }
            cols.push(c);
        }
    };
    for (j, &l) in layout.input.iter().enumerate() {
        if l > 0 {
            let g: Vec<f64> = filter(&p.d, &conv(&p.c, &p.f[j]), &imp)
                .into_iter()
                .map(|v| -v)
                .collect();
            shifts(g, l, &mut cols);
        }
    }
    if layout.noise > 0 {
        shifts(filter(&[1.0], &p.c, &imp), layout.noise, &mut cols);
    }
    cols
}

/// The initial state minimising `|e0 + Psi h|` and an orthonormal basis of `Psi`'s columns
/// (a column dependent on earlier ones to `1e-10` of its norm gets a zero coefficient).
pub(super) fn project(e0: &[f64], p: &MisoPolys, layout: &Layout) -> Projection {
    let n = e0.len();
    let cols = columns(p, layout, n);
    let nh = cols.len();
    let mut qs: Vec<Vec<f64>> = Vec::with_capacity(nh);
    let mut kept: Vec<usize> = Vec::with_capacity(nh);
    let mut r = vec![vec![0.0; nh]; nh]; // r[k][m]: Psi[:, kept[m]] = sum_k q_k r[k][m]
    for (col, psi) in cols.iter().enumerate() {
        let norm0 = dot(psi, psi).sqrt();
        if !(norm0 > 0.0 && norm0.is_finite()) {
            continue;
        }
        let mut v = psi.clone();
        let mut coef = vec![0.0; qs.len()];
        for _ in 0..2 {
            for (k, q) in qs.iter().enumerate() {
                let s = dot(q, &v);
                coef[k] += s;
                v.iter_mut().zip(q).for_each(|(vt, qt)| *vt -= s * qt);
            }
        }
        let nv = dot(&v, &v).sqrt();
        if nv.is_nan() || nv <= 1e-10 * norm0 {
            continue;
        }
        let m = kept.len();
        for (k, c) in coef.iter().enumerate() {
            r[k][m] = *c;
        }
        r[m][m] = nv;
        v.iter_mut().for_each(|x| *x /= nv);
        qs.push(v);
        kept.push(col);
    }
    let rank = kept.len();
    let z: Vec<f64> = qs.iter().map(|q| -dot(q, e0)).collect();
    let mut c = vec![0.0; rank];
    for m in (0..rank).rev() {
        let mut s = z[m];
        for k in m + 1..rank {
            s -= r[m][k] * c[k];
        }
        c[m] = s / r[m][m];
    }
    let mut h = vec![0.0; nh];
    for (m, &col) in kept.iter().enumerate() {
        h[col] = c[m];
    }
    let q = Mat::from_fn(n, rank, |t, k| qs[k][t]);
    Projection {
        state: InitialState::from_flat(layout, &h),
        q,
    }
}

/// What eliminating an initial state lowers the sum of squares by when the true state is
/// zero, on average: `trace(Q^T Sigma Q)` for errors of covariance `Sigma` (`n_h sigma^2` for
/// white ones). `Sigma` from the autocovariances `r(k)` of the errors `e` (with the state
/// eliminated), Bartlett-weighted up to lag `L = min(n/4, 2 sqrt(n))`, and `Q`'s own lagged
/// products: `sum_k w_k r(k) sum_t q(t) q(t+k)`, at least its white value `n_h r(0)` (the
/// lagged terms of white errors are noise). Coloured errors (an OE fit's are the
/// disturbance itself) put more of their power along the slow free responses than white
/// ones: with an AR(1) disturbance of pole 0.9 the white count fired on a quarter of records
/// that start at rest.
pub(super) fn chance_drop(e: &[f64], q: &Mat<f64>) -> f64 {
    let n = e.len();
    let lags = ((2.0 * (n as f64).sqrt()) as usize).min(n / 4);
    let mut total = 0.0;
    let mut white = 0.0;
    for k in 0..=lags {
        let r: f64 = (0..n - k).map(|t| e[t] * e[t + k]).sum::<f64>() / n as f64;
        let c: f64 = (0..q.ncols())
            .map(|j| (0..n - k).map(|t| q[(t, j)] * q[(t + k, j)]).sum::<f64>())
            .sum();
        let w = 1.0 - k as f64 / (lags + 1) as f64;
        if k == 0 {
            white = r * c;
        }
        total += if k == 0 { r * c } else { 2.0 * w * r * c };
    }
    total.max(white)
}

/// `Auto`'s rule: `cost_zero` and `cost_estimated` (half sums of squares, from rest and with
/// the initial state eliminated, at the same parameters) and `chance` ([`chance_drop`]
/// summed over the experiments); `true` when estimating lowers the sum of squares by more
/// than `AUTO_FACTOR chance` (and by more than round-off).
pub fn worth_estimating(cost_zero: f64, cost_estimated: f64, chance: f64) -> bool {
    let drop = cost_zero - cost_estimated;
    drop.is_finite() && drop > 1e-10 * cost_zero && 2.0 * drop > AUTO_FACTOR * chance
}
