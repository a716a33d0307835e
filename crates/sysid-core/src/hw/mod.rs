//! Hammerstein-Wiener models (single input, single output, several experiments; the MIMO
//! state-space form is in [`mimo`]).
//!
//! ```text
//! w(t) = f(u(t); alpha)                       static input nonlinearity
//! x(t) = B(q)/F(q) w(t - nk)                  linear block (output-error form)
//! y(t) = g(x(t); beta) + e(t)                 static output nonlinearity
//! ```
//!
//! Estimated by prediction error with the one optimiser ([`crate::optim`]): the residual is
//! `r = y - g(x)`, its Jacobian `-g'(x) dx/dtheta` and `-dg/dbeta`, where the sensitivities
//! of `x` are `1/F` filters of `B dw/dalpha`, `w(t - nk - k)` and `-x(t - k)`, run sample by
//! sample with a ring of the last `nf` values; `J^T J` and `J^T r` are accumulated per sample.
//! A record's initial state, when estimated ([`HwStructure::initial_states`]), is the short
//! polynomial `h` of `F x = B w(t - nk) + h` (what the samples before the record leave), its
//! sensitivity the `1/F` filter of a unit pulse at each of its lags.
//! The admissible set is `F` stable. Each nonlinearity has a normalisation so that the scale
//! of the signal between it and the linear block lives in `B` only: saturation and dead zone
//! have unit slope, the polynomial a unit linear term, the piecewise-linear map keeps its
//! value at its last breakpoint fixed. A sigmoid network has its first unit's amplitude
//! fixed: at the input at one (the scale of `w`); at the output, where it restricts the
//! curve rather than normalising a scale, at a value in the output's own units (the caller
//! passes the output's standard deviation, so that the model class does not depend on
//! the units the output is recorded in).

use crate::error::{Result, SysidError};

pub mod mimo;
use crate::optim::{
    minimize, Evaluation, Flow, Iteration, NormalEquations, Options, Problem, Solution,
};
use crate::polynomial::filter::is_stable;

/// A static nonlinearity with its free parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum Nonlinearity {
    /// `f(x) = x`.
    Identity,
    /// `clip(x, lower, upper)`; parameters `[lower, upper]`.
    Saturation,
    /// `x - upper` above `upper`, `x - lower` below `lower`, zero between; parameters
    /// `[lower, upper]`.
    DeadZone,
    /// `x + c_2 x^2 + ... + c_d x^d`; parameters `c_2..c_d`.
    Polynomial {
        /// Degree `d >= 2`.
        degree: usize,
    },
    /// Linear interpolation of values at fixed, increasing breakpoints (end segments
    /// extended); parameters the values at all breakpoints but the last (held at the last
    /// breakpoint itself).
    PiecewiseLinear {
        /// The breakpoints.
        breakpoints: Vec<f64>,
    },
    /// `c x + sum_k a_k tanh(b_k x + d_k)` with `a_1 = amplitude` fixed; parameters
    /// `[c, b_1, d_1, a_2, b_2, d_2, ...]`.
    Sigmoid {
        /// Number of units.
        units: usize,
        /// The first unit's fixed amplitude (one at the input).
        amplitude: f64,
    },
}

crate::names::option_names! { Nonlinearity, "nonlinearity", false, [
    ("identity", Nonlinearity::Identity), ("saturation", Nonlinearity::Saturation),
    ("deadzone", Nonlinearity::DeadZone), ("polynomial", Nonlinearity::Polynomial { degree: 2 }),
    ("pwl", Nonlinearity::PiecewiseLinear { breakpoints: Vec::new() }),
    ("sigmoid", Nonlinearity::Sigmoid { units: 1, amplitude: 1.0 }),
] }

impl Nonlinearity {
    /// The nonlinearity of kind `kind` with `n` (a polynomial's degree, a sigmoid network's
    /// units) and the breakpoints of a piecewise-linear one (for a sigmoid network: empty,
    /// or its first unit's fixed amplitude; the others ignore them).
    ///
    /// ```
    /// use sysid_core::hw::Nonlinearity;
    /// let p = Nonlinearity::from_spec("polynomial", 3, &[]).unwrap();
    /// assert_eq!(p, Nonlinearity::Polynomial { degree: 3 });
    /// let s = Nonlinearity::from_spec("sigmoid", 2, &[0.5]).unwrap();
    /// assert_eq!(s, Nonlinearity::Sigmoid { units: 2, amplitude: 0.5 });
    /// assert_eq!(s.n_params(), 6);
    /// assert!(Nonlinearity::from_spec("spline", 3, &[]).is_err());
    /// ```
    pub fn from_spec(kind: &str, n: usize, breakpoints: &[f64]) -> Result<Self> {
        Ok(match kind.parse()? {
            Nonlinearity::Polynomial { .. } => Nonlinearity::Polynomial { degree: n },
            Nonlinearity::PiecewiseLinear { .. } => Nonlinearity::PiecewiseLinear {
                breakpoints: breakpoints.to_vec(),
            },
            Nonlinearity::Sigmoid { .. } => Nonlinearity::Sigmoid {
                units: n,
                amplitude: breakpoints.first().copied().unwrap_or(1.0),
            },
            other => other,
        })
    }

    /// Number of free parameters.
    pub fn n_params(&self) -> usize {
        match self {
            Nonlinearity::Identity => 0,
            Nonlinearity::Saturation | Nonlinearity::DeadZone => 2,
            Nonlinearity::Polynomial { degree } => degree.saturating_sub(1),
            Nonlinearity::PiecewiseLinear { breakpoints } => breakpoints.len().saturating_sub(1),
            Nonlinearity::Sigmoid { units, .. } => 3 * units,
        }
    }

    /// Checks the definition.
    pub fn check(&self) -> Result<()> {
        match self {
            Nonlinearity::Polynomial { degree } if *degree < 2 => Err(SysidError::invalid(
                "nonlinearity",
                "a polynomial nonlinearity needs degree >= 2",
            )),
            Nonlinearity::PiecewiseLinear { breakpoints }
                if breakpoints.len() < 2
                    || breakpoints.windows(2).any(|w| w[1] <= w[0])
                    || breakpoints.iter().any(|b| !b.is_finite()) =>
            {
                Err(SysidError::invalid(
                    "breakpoints",
                    "need at least two finite, strictly increasing breakpoints",
                ))
            }
            Nonlinearity::Sigmoid { amplitude, .. }
                if !(amplitude.is_finite() && *amplitude != 0.0) =>
            {
                Err(SysidError::invalid(
                    "amplitude",
                    "a sigmoid network's fixed first amplitude must be finite and nonzero",
                ))
            }
            _ => Ok(()),
        }
    }

    /// Value, derivative in `x`, and (into `dp`) derivatives in the parameters.
    #[inline]
    pub fn eval(&self, p: &[f64], x: f64, dp: &mut [f64]) -> (f64, f64) {
        match self {
            Nonlinearity::Identity => (x, 1.0),
            Nonlinearity::Saturation => {
                let (lo, hi) = (p[0], p[1]);
                dp[0] = 0.0;
                dp[1] = 0.0;
                if x >= hi {
                    dp[1] = 1.0;
                    (hi, 0.0)
                } else if x <= lo {
                    dp[0] = 1.0;
                    (lo, 0.0)
                } else {
                    (x, 1.0)
                }
            }
            Nonlinearity::DeadZone => {
                let (lo, hi) = (p[0], p[1]);
                dp[0] = 0.0;
                dp[1] = 0.0;
                if x > hi {
                    dp[1] = -1.0;
                    (x - hi, 1.0)
                } else if x < lo {
                    dp[0] = -1.0;
                    (x - lo, 1.0)
                } else {
                    (0.0, 0.0)
                }
            }
            Nonlinearity::Polynomial { degree } => {
                let (mut v, mut d, mut xp) = (x, 1.0, x);
                for k in 2..=*degree {
                    let c = p[k - 2];
                    d += c * k as f64 * xp;
                    xp *= x;
                    v += c * xp;
                    dp[k - 2] = xp;
                }
                (v, d)
            }
            Nonlinearity::PiecewiseLinear { breakpoints: z } => {
                let k = z.len();
                let val = |i: usize| if i + 1 == k { z[k - 1] } else { p[i] };
                let s = match z.iter().position(|&b| x < b) {
                    None => k - 2,
                    Some(0) => 0,
                    Some(i) => i - 1,
                };
                let h = z[s + 1] - z[s];
                let lam = (x - z[s]) / h;
                dp.iter_mut().for_each(|d| *d = 0.0);
                if s < k - 1 {
                    dp[s] = 1.0 - lam;
                }
                if s + 1 < k - 1 {
                    dp[s + 1] = lam;
                }
                let v = (1.0 - lam) * val(s) + lam * val(s + 1);
                (v, (val(s + 1) - val(s)) / h)
            }
            Nonlinearity::Sigmoid { units, amplitude } => {
                let c = p[0];
                let (mut v, mut d) = (c * x, c);
                dp[0] = x;
                for k in 0..*units {
                    let a = if k == 0 { *amplitude } else { p[3 * k] };
                    let (b, o) = (p[3 * k + 1], p[3 * k + 2]);
                    let th = (b * x + o).tanh();
                    let sech2 = 1.0 - th * th;
                    v += a * th;
                    d += a * b * sech2;
                    if k > 0 {
                        dp[3 * k] = th;
                    }
                    dp[3 * k + 1] = a * x * sech2;
                    dp[3 * k + 2] = a * sech2;
                }
                (v, d)
            }
        }
    }
}

/// The structure of a Hammerstein-Wiener model.
#[derive(Debug, Clone)]
pub struct HwStructure {
    /// Input nonlinearity.
    pub input: Nonlinearity,
    /// Output nonlinearity.
    pub output: Nonlinearity,
    /// Number of `B` coefficients.
    pub nb: usize,
    /// Number of free `F` coefficients.
    pub nf: usize,
    /// Input delay.
    pub nk: usize,
    /// Whether `theta` ends with an output offset `y0`, added to the output nonlinearity's
    /// value (`y = y0 + g(x)`): the level of the operating point, estimated with the rest.
    pub offset: bool,
    /// The number of records whose linear block's initial state is estimated: `theta` ends
    /// (after `y0`) with one state of [`Self::n_initial`] entries per record, in order; 0
    /// when every record starts from rest.
    pub initial_states: usize,
}

impl HwStructure {
    /// Total parameters `[alpha, b, f, beta]`, then `y0` with [`Self::offset`], then the
    /// records' initial states ([`Self::initial_states`]).
    pub fn n_params(&self) -> usize {
        self.n_model() + self.initial_states * self.n_initial()
    }

    /// The model's own parameters `[alpha, b, f, beta, (y0)]` (the initial states excluded).
    pub fn n_model(&self) -> usize {
        self.input.n_params() + self.nb + self.nf + self.output.n_params() + self.offset as usize
    }

    /// Entries of a record's initial state: `max(nf, nk + nb - 1)`, the coefficients `h` of
    /// `F x = B w(t - nk) + h` acting on the first samples (what the samples before the
    /// record leave; SciPy's `lfilter(r_[zeros(nk), b], r_[1, f], w, zi=h)` state), as the
    /// polynomial estimators' initial conditions.
    pub fn n_initial(&self) -> usize {
        self.nf.max((self.nk + self.nb).saturating_sub(1))
    }

    /// Record `k`'s initial state in `theta` (with [`Self::initial_states`]).
    pub fn initial_state<'a>(&self, th: &'a [f64], k: usize) -> &'a [f64] {
        let (start, nh) = (self.n_model(), self.n_initial());
        &th[start + k * nh..start + (k + 1) * nh]
    }

    fn split<'a>(&self, th: &'a [f64]) -> (&'a [f64], &'a [f64], &'a [f64], &'a [f64]) {
        let na = self.input.n_params();
        let (alpha, rest) = th.split_at(na);
        let (b, rest) = rest.split_at(self.nb);
        let (f, rest) = rest.split_at(self.nf);
        (alpha, b, f, &rest[..self.output.n_params()])
    }

    /// The output offset `y0` at `theta` (0 without [`Self::offset`]).
    fn y0(&self, th: &[f64]) -> f64 {
        if self.offset {
            th[self.n_model() - 1]
        } else {
            0.0
        }
    }

    /// Noise-free output for input `u` at parameters `theta` (from rest).
    ///
    /// # Errors
    /// [`SysidError::Interrupted`] when stopped inside an [`crate::interrupt`] scope.
    pub fn simulate(&self, theta: &[f64], u: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; u.len()];
        self.run(theta, u, None, None, |t, yhat, _, _| out[t] = yhat)?;
        Ok(out)
    }

    /// Noise-free output from the linear block's initial state `h` ([`Self::n_initial`]
    /// entries: what [`Self::simulate`] takes as zero).
    ///
    /// # Errors
    /// [`SysidError::ShapeMismatch`] when `h` has not [`Self::n_initial`] entries;
    /// [`SysidError::Interrupted`] as [`Self::simulate`].
    ///
    /// ```
    /// use sysid_core::hw::{HwStructure, Nonlinearity};
    /// let s = HwStructure { input: Nonlinearity::Identity, output: Nonlinearity::Identity,
    ///                       nb: 1, nf: 1, nk: 1, offset: false, initial_states: 0 };
    /// // x(t) = 0.5 x(t - 1) + w(t - 1) + h(t): from h = [2] with no input, 2, 1, 0.5
    /// let y = s.simulate_from(&[1.0, -0.5], &[0.0; 3], &[2.0]).unwrap();
    /// assert_eq!(y, vec![2.0, 1.0, 0.5]);
    /// ```
    pub fn simulate_from(&self, theta: &[f64], u: &[f64], h: &[f64]) -> Result<Vec<f64>> {
        if h.len() != self.n_initial() {
            return Err(SysidError::ShapeMismatch {
                what: "h".into(),
                expected: format!("{} entries (max(nf, nk + nb - 1))", self.n_initial()),
                got: format!("{} entries", h.len()),
            });
        }
        let mut out = vec![0.0; u.len()];
        self.run(theta, u, None, Some(h), |t, yhat, _, _| out[t] = yhat)?;
        Ok(out)
    }

    /// The linear block's intermediate signals `(w, x)` for input `u`.
    pub fn intermediate(&self, theta: &[f64], u: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (alpha, b, f, _) = self.split(theta);
        let mut dp = vec![0.0; alpha.len()];
        let w: Vec<f64> = u
            .iter()
            .map(|&v| self.input.eval(alpha, v, &mut dp).0)
            .collect();
        let mut x = vec![0.0; u.len()];
        for t in 0..u.len() {
            let mut s = 0.0;
            for (k, bk) in b.iter().enumerate() {
                if t >= self.nk + k {
                    s += bk * w[t - self.nk - k];
                }
            }
            for (i, fi) in f.iter().enumerate() {
                if t > i {
                    s -= fi * x[t - 1 - i];
                }
            }
            x[t] = s;
        }
        (w, x)
    }

    /// Runs the model from the initial state `h` (`None`: from rest); `visit(t, yhat,
    /// jacobian row of yhat (if asked), _)` per sample, the row over the model's parameters
    /// ([`Self::n_model`]) and then, with `h`, over `h`'s entries.
    fn run(
        &self,
        theta: &[f64],
        u: &[f64],
        mut jac: Option<&mut Vec<f64>>,
        h: Option<&[f64]>,
        mut visit: impl FnMut(usize, f64, Option<&[f64]>, ()),
    ) -> Result<()> {
        let (alpha, b, f, beta) = self.split(theta);
        let y0 = self.y0(theta);
        let (na, nbeta) = (alpha.len(), beta.len());
        let n = u.len();
        let h = h.unwrap_or(&[]);
        let nh = h.len();
        let p = self.n_model() + nh;
        // the sensitivities run through 1/F: alpha, b, f, then h's entries
        let plin0 = na + self.nb + self.nf;
        let plin = plin0 + nh;
        let mut dpa = vec![0.0; na];
        let mut dpb = vec![0.0; nbeta];
        // w and dw/dalpha for every sample (n x (1 + na)); x history
        let mut w = vec![0.0; n];
        let mut dw = vec![0.0; n * na];
        for t in 0..n {
            w[t] = self.input.eval(alpha, u[t], &mut dpa).0;
            dw[t * na..(t + 1) * na].copy_from_slice(&dpa);
        }
        let mut x = vec![0.0; n];
        let ring = self.nf.max(1);
        let mut s_hist = vec![0.0; ring * plin]; // s(t-1-i) at slot (t-1-i) % ring
        let mut s = vec![0.0; plin];
        for t in 0..n {
            if t % 4096 == 4095 {
                crate::interrupt::check()?; // Ctrl-C within a pass over a long record
            }
            let mut xt = 0.0;
            for (k, bk) in b.iter().enumerate() {
                if t >= self.nk + k {
                    xt += bk * w[t - self.nk - k];
                }
            }
            for (i, fi) in f.iter().enumerate() {
                if t > i {
                    xt -= fi * x[t - 1 - i];
                }
            }
            if t < nh {
                xt += h[t];
            }
            x[t] = xt;
            let (g, gd) = self.output.eval(beta, xt, &mut dpb);
            let yhat = y0 + g;
            if let Some(row) = jac.as_deref_mut() {
                // sources of the 1/F filters
                s.iter_mut().for_each(|v| *v = 0.0);
                for (k, bk) in b.iter().enumerate() {
                    if t >= self.nk + k {
                        let tt = t - self.nk - k;
                        for j in 0..na {
                            s[j] += bk * dw[tt * na + j];
                        }
                        s[na + k] = w[tt];
                    }
                }
                for i in 0..self.nf {
                    if t > i {
                        s[na + self.nb + i] = -x[t - 1 - i];
                    }
                }
                if t < nh {
                    s[plin0 + t] = 1.0;
                }
                for (i, fi) in f.iter().enumerate() {
                    if t > i {
                        let slot = (t - 1 - i) % ring;
                        for j in 0..plin {
                            s[j] -= fi * s_hist[slot * plin + j];
                        }
                    }
                }
                let slot = t % ring;
                s_hist[slot * plin..(slot + 1) * plin].copy_from_slice(&s);
                row.clear();
                row.extend(s[..plin0].iter().map(|v| gd * v));
                row.extend_from_slice(&dpb);
                if self.offset {
                    row.push(1.0);
                }
                row.extend(s[plin0..].iter().map(|v| gd * v));
                debug_assert_eq!(row.len(), p);
                visit(t, yhat, Some(row), ());
            } else {
                visit(t, yhat, None, ());
            }
        }
        Ok(())
    }
}

/// The prediction-error problem of a Hammerstein-Wiener structure over several records.
pub struct HwProblem<'a> {
    /// The structure.
    pub structure: HwStructure,
    /// `(u, y)` records.
    pub records: Vec<(&'a [f64], &'a [f64])>,
}

impl Problem for HwProblem<'_> {
    fn n_params(&self) -> usize {
        self.structure.n_params()
    }

    fn evaluate(&mut self, theta: &[f64], jacobian: bool) -> Result<Evaluation> {
        let s = &self.structure;
        let mut sums = NormalEquations::blocked(self.n_params(), jacobian);
        let mut row = Vec::with_capacity(self.n_params());
        if s.initial_states == 0 {
            for (u, y) in &self.records {
                let jac = if jacobian { Some(&mut row) } else { None };
                s.run(theta, u, jac, None, |t, yhat, jr, _| {
                    sums.add(y[t] - yhat, jr)
                })?;
            }
            return Ok(sums.finish());
        }
        // each record's row: the model's columns, its own state's, zeros for the others'
        let (pm, nh) = (s.n_model(), s.n_initial());
        let mut full = vec![0.0; self.n_params()];
        for (k, (u, y)) in self.records.iter().enumerate() {
            let jac = if jacobian { Some(&mut row) } else { None };
            let at = pm + k * nh;
            s.run(
                theta,
                u,
                jac,
                Some(s.initial_state(theta, k)),
                |t, yhat, jr, _| {
                    let jr = jr.map(|jr| {
                        full[..pm].copy_from_slice(&jr[..pm]);
                        full[at..at + nh].copy_from_slice(&jr[pm..]);
                        &full[..]
                    });
                    sums.add(y[t] - yhat, jr)
                },
            )?;
        }
        Ok(sums.finish())
    }

    fn admissible(&mut self, theta: &[f64]) -> bool {
        let (_, _, f, _) = self.structure.split(theta);
        let mut a = vec![1.0];
        a.extend_from_slice(f);
        theta.iter().all(|v| v.is_finite()) && is_stable(&a)
    }

    /// Every sample of every record is a residual of the cost (for
    /// [`Options::tol_statistical`]).
    fn n_residuals(&self) -> Option<usize> {
        Some(self.records.iter().map(|(_, y)| y.len()).sum())
    }
}

/// The search's start and records agree: `theta0` has the structure's `n_params`, and the
/// initial states estimated are one per record or none (both estimators).
pub(crate) fn check_start(
    n_params: usize,
    theta0: usize,
    initial_states: usize,
    records: usize,
) -> Result<()> {
    if theta0 != n_params {
        return Err(SysidError::invalid(
            "theta0",
            format!("needs {n_params} parameters"),
        ));
    }
    if initial_states != 0 && initial_states != records {
        return Err(SysidError::invalid(
            "initial_states",
            format!("one initial state per record ({records}) or none, got {initial_states}"),
        ));
    }
    Ok(())
}

/// Prediction-error estimate of a Hammerstein-Wiener model from `theta0` (for example a
/// linear output-error fit with identity-like nonlinearities).
///
/// ```
/// use sysid_core::hw::{estimate, HwStructure, Nonlinearity};
/// use sysid_core::optim::Options;
/// // Hammerstein: saturation at +-0.5, then 0.5 q^-1 / (1 - 0.8 q^-1)
/// let s = HwStructure { input: Nonlinearity::Saturation, output: Nonlinearity::Identity,
///                       nb: 1, nf: 1, nk: 1, offset: false,
///                       initial_states: 0 };
/// let u: Vec<f64> = (0..400).map(|t| ((t * 7919 % 101) as f64 / 50.0) - 1.0).collect();
/// let y = s.simulate(&[-0.5, 0.5, 0.5, -0.8], &u).unwrap();
/// let sol = estimate(&s, &[(&u, &y)], &[-0.9, 0.9, 0.4, -0.7], &Options::default(),
///                    &mut |_| sysid_core::optim::Flow::Continue).unwrap();
/// assert!((sol.theta[3] + 0.8).abs() < 1e-6 && (sol.theta[1] - 0.5).abs() < 1e-6);
/// ```
pub fn estimate(
    structure: &HwStructure,
    records: &[(&[f64], &[f64])],
    theta0: &[f64],
    options: &Options,
    observer: &mut dyn FnMut(&Iteration) -> Flow,
) -> Result<Solution> {
    structure.input.check()?;
    structure.output.check()?;
    if structure.nb == 0 {
        return Err(SysidError::invalid("nb", "must be at least 1"));
    }
    check_start(
        structure.n_params(),
        theta0.len(),
        structure.initial_states,
        records.len(),
    )?;
    for (u, y) in records {
        crate::error::check_io(
            "u, y",
            faer::MatRef::from_column_major_slice(u, u.len(), 1),
            faer::MatRef::from_column_major_slice(y, y.len(), 1),
            1,
            1,
        )?;
    }
    let mut problem = HwProblem {
        structure: structure.clone(),
        records: records.to_vec(),
    };
    minimize(&mut problem, theta0, options, observer)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A saturation before a first-order block with a one-sample delay.
    fn saturation_first_order(offset: bool) -> HwStructure {
        HwStructure {
            input: Nonlinearity::Saturation,
            output: Nonlinearity::Identity,
            nb: 1,
            nf: 1,
            nk: 1,
            offset,
            initial_states: 0,
        }
    }

    /// The Gauss-Newton gradient equals the finite-difference gradient of the cost.
    #[test]
    fn gradient_matches_finite_differences() {
        let u: Vec<f64> = (0..300)
            .map(|t| (((t * 7919) % 211) as f64 / 105.0) - 1.0)
            .collect();
        let y: Vec<f64> = u.iter().map(|v| (2.0 * v).tanh() + 0.1 * v * v).collect();
        let nls = [
            (Nonlinearity::Saturation, vec![-0.613, 0.707]),
            (Nonlinearity::DeadZone, vec![-0.213, 0.117]),
            (Nonlinearity::Polynomial { degree: 3 }, vec![0.2, -0.1]),
            (
                Nonlinearity::PiecewiseLinear {
                    breakpoints: vec![-1.0, -0.2, 0.5, 1.0],
                },
                vec![-0.9, -0.3, 0.4],
            ),
            (
                Nonlinearity::Sigmoid {
                    units: 2,
                    amplitude: 1.0,
                },
                vec![0.3, 1.1, 0.1, 0.5, 0.7, -0.2],
            ),
            (
                Nonlinearity::Sigmoid {
                    units: 2,
                    amplitude: 0.6,
                },
                vec![0.3, 1.1, 0.1, 0.5, 0.7, -0.2],
            ),
        ];
        for (inp, pin) in &nls {
            for (out, pout) in [&nls[2], &nls[4], &nls[5]] {
                let s = HwStructure {
                    input: inp.clone(),
                    output: out.clone(),
                    nb: 2,
                    nf: 1,
                    nk: 1,
                    offset: true,
                    initial_states: 0,
                };
                let mut th = pin.clone();
                th.extend([0.4, 0.2, -0.6]);
                th.extend(pout.iter());
                th.push(0.3); // the output offset y0
                let mut pr = HwProblem {
                    structure: s,
                    records: vec![(&u, &y)],
                };
                let what = format!("{inp:?}/{out:?}");
                crate::optim::assert_gradient_matches_cost(&mut pr, &th, 1e-4, &what);
            }
        }
    }

    /// A Hammerstein record sitting at an output level (`y = 2.5 + L sat(u)`) is recovered
    /// exactly with the offset estimated, from a start at the output's mean.
    #[test]
    fn the_output_offset_is_estimated_with_the_rest() {
        let u: Vec<f64> = (0..400)
            .map(|t| ((t * 7919 % 101) as f64 / 50.0) - 1.0)
            .collect();
        let s = saturation_first_order(true);
        let truth = [-0.5, 0.5, 0.5, -0.8, 2.5];
        let y = s.simulate(&truth, &u).unwrap();
        let mean = y.iter().sum::<f64>() / y.len() as f64;
        let sol = estimate(
            &s,
            &[(&u, &y)],
            &[-0.9, 0.9, 0.4, -0.7, mean],
            &Options::default(),
            &mut |_| Flow::Continue,
        )
        .unwrap();
        for (a, b) in sol.theta.iter().zip(truth) {
            assert!((a - b).abs() < 1e-8, "{:?} vs {truth:?}", sol.theta);
        }
    }

    /// With the records' initial states estimated (two records; `nk + nb - 1 > nf`, so the
    /// state holds past inputs too), the Gauss-Newton gradient still equals the
    /// finite-difference one, the states' columns included.
    #[test]
    fn gradient_with_initial_states_matches_finite_differences() {
        let u: Vec<f64> = (0..200)
            .map(|t| (((t * 7919) % 211) as f64 / 105.0) - 1.0)
            .collect();
        let y: Vec<f64> = u.iter().map(|v| (2.0 * v).tanh() + 0.1 * v * v).collect();
        let (u2, y2): (Vec<f64>, Vec<f64>) = (u[50..].to_vec(), y[..150].to_vec());
        let s = HwStructure {
            input: Nonlinearity::Saturation,
            output: Nonlinearity::Polynomial { degree: 3 },
            nb: 2,
            nf: 2,
            nk: 2,
            offset: true,
            initial_states: 2,
        };
        assert_eq!(s.n_initial(), 3);
        let mut th = vec![-0.613, 0.707, 0.4, 0.2, -0.6, 0.25, 0.2, -0.1, 0.3];
        th.extend([0.5, -0.3, 0.2, -0.4, 0.1, 0.6]); // the two records' states
        assert_eq!(th.len(), s.n_params());
        let mut pr = HwProblem {
            structure: s,
            records: vec![(&u, &y), (&u2, &y2)],
        };
        crate::optim::assert_gradient_matches_cost(&mut pr, &th, 1e-5, "");
    }

    /// The initial state is SciPy's `lfilter` state of `B/F` with `nk` leading zeros: a
    /// record cut from a longer one is the longer one's continuation from the state the cut
    /// leaves, and the state recovered by the search (from rest) reproduces it.
    #[test]
    fn a_record_starting_mid_response_is_fitted_with_its_initial_state() {
        let u: Vec<f64> = (0..600)
            .map(|t| ((t * 7919 % 101) as f64 / 50.0) - 1.0)
            .collect();
        let mut s = HwStructure {
            input: Nonlinearity::Saturation,
            output: Nonlinearity::Identity,
            nb: 2,
            nf: 2,
            nk: 1,
            offset: false,
            initial_states: 0,
        };
        let truth = [-0.5, 0.5, 0.5, 0.3, -1.5, 0.7];
        let long = s.simulate(&truth, &u).unwrap();
        let (uc, yc) = (&u[100..], &long[100..]);
        // the state the first 100 samples leave: x(t) + f1 x(t-1) + f2 x(t-2) = b0 w(t-1) +
        // b1 w(t-2) at t = 100, 101, its terms before sample 100
        let w = |t: usize| u[t].clamp(-0.5, 0.5);
        let (b0, b1, f1, f2) = (0.5, 0.3, -1.5, 0.7);
        let h = [
            b0 * w(99) + b1 * w(98) - f1 * long[99] - f2 * long[98],
            b1 * w(99) - f2 * long[99],
        ];
        let from = s.simulate_from(&truth, uc, &h).unwrap();
        for (a, b) in from.iter().zip(yc) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        let start = [-0.6, 0.6, 0.45, 0.25, -1.4, 0.6];
        let zero = estimate(&s, &[(uc, yc)], &start, &Options::default(), &mut |_| {
            Flow::Continue
        })
        .unwrap();
        assert!((zero.theta[4] - f1).abs() > 1e-4, "{:?}", zero.theta);
        s.initial_states = 1;
        let mut th0 = start.to_vec();
        th0.extend([0.0, 0.0]);
        let sol = estimate(&s, &[(uc, yc)], &th0, &Options::default(), &mut |_| {
            Flow::Continue
        })
        .unwrap();
        for (a, b) in sol.theta.iter().zip(truth.iter().chain(&h)) {
            assert!((a - b).abs() < 1e-8 * (1.0 + b.abs()), "{:?}", sol.theta);
        }
    }

    /// A pass over a long record asks whether to stop every few thousand samples (see the
    /// MIMO structure's test of the same name).
    #[test]
    fn a_pass_stops_inside_the_record_when_asked() {
        let u: Vec<f64> = (0..20_000)
            .map(|t| (((t * 7919) % 211) as f64 / 105.0) - 1.0)
            .collect();
        let s = saturation_first_order(false);
        let th = [-0.5, 0.5, 0.5, -0.8];
        let y = s.simulate(&th, &u).unwrap();
        let mut pr = HwProblem {
            structure: s.clone(),
            records: vec![(&u, &y)],
        };
        for jacobian in [false, true] {
            let r = crate::interrupt::error_when_asked_to_stop(|| pr.evaluate(&th, jacobian));
            assert_eq!(r, Some(SysidError::Interrupted), "jacobian {jacobian}");
        }
        assert!(pr.evaluate(&th, true).is_ok());
    }
}
