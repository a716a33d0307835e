//! Subspace identification on a compressed record.
//!
//! With the data matrix in the row order `[U_f; U_p; Y_p; Y_f]` (`W_p = [U_p; Y_p]`) and its
//! factor `L` partitioned accordingly,
//!
//! ```text
//!   [U_f]   [L11  0    0 ] [Q1^T]
//!   [W_p] = [L21  L22  0 ] [Q2^T]
//!   [Y_f]   [L31  L32  L33] [Q3^T]
//! ```
//!
//! every method takes the SVD of a weighted block of L ([`weighting`]):
//!
//! | method | matrix whose SVD is taken | reference |
//! |---|---|---|
//! | PO-MOESP | `L32` (Y_f projected on the past, future inputs removed) | Verhaegen 1994 |
//! | ordinary MOESP | `L22'` of the LQ of `[U_f; Y_f]` alone (no instruments) | Verhaegen & Dewilde 1992 |
//! | PI-MOESP | block of `Y_f` on `U_p` in the LQ of `[U_f; U_p; Y_f]` | Verhaegen & Dewilde 1992 |
//! | N4SID | `L32 L22^{-1} [L21 L22]` (oblique projection) | Van Overschee & De Moor 1994 |
//! | CVA | `T^{-1} L32`, `T T^T = L32 L32^T + L33 L33^T` | Larimore 1990 |
//!
//! The left singular vectors give the extended observability matrix `Γ_f`; the order is the
//! number of retained singular values ([`order`]); `A`, `C` come from its shift invariance,
//! `B`, `D` and the noise covariances from a least-squares regression on `L` and `K` from the
//! Riccati equation ([`system`]); or all four by least squares on the estimated state
//! sequence ([`SystemMatrices`]). `B`, `D` and `x0` can also be re-estimated on the data
//! given `A`, `C` ([`bd_x0`]). Nothing here depends on the record length.

pub mod bd_x0;
pub mod checks;
pub mod closed_loop;
pub mod frequency;
pub mod order;
pub mod recursive;
pub mod system;
pub mod weighting;

use crate::error::{Result, SysidError};
use crate::hankel::HankelFactor;
use crate::model::StateSpace;
use faer::Mat;

/// Weighting of the subspace method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Method {
    /// PO-MOESP: past inputs and outputs as instruments (consistent with process noise).
    #[default]
    Moesp,
    /// Ordinary MOESP: future inputs and outputs only, no instruments (output-error data).
    OrdinaryMoesp,
    /// PI-MOESP: past inputs as instruments.
    PiMoesp,
    /// N4SID with unit weights (oblique projection).
    N4sid,
    /// Canonical variate analysis.
    Cva,
}

crate::names::option_names! { Method, "method", true, [
    ("moesp", Method::Moesp), ("po-moesp", Method::Moesp), ("pomoesp", Method::Moesp),
    ("ordinary-moesp", Method::OrdinaryMoesp), ("moesp-ordinary", Method::OrdinaryMoesp),
    ("pi-moesp", Method::PiMoesp), ("n4sid", Method::N4sid), ("cva", Method::Cva),
] }

impl Method {
    /// Parses `"moesp" | "po-moesp" | "ordinary-moesp" | "pi-moesp" | "n4sid" | "cva"`
    /// (ASCII case ignored); the same as `name.parse()`.
    ///
    /// ```
    /// use sysid_core::subspace::Method;
    /// assert_eq!(Method::parse("N4SID").unwrap(), Method::N4sid);
    /// assert_eq!("po-moesp".parse::<Method>().unwrap(), Method::Moesp);
    /// ```
    pub fn parse(name: &str) -> Result<Self> {
        name.parse()
    }
}

/// How a fit takes the system matrices from the weighted SVD.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum SystemMatrices {
    /// A and C by the shift invariance of `Γ_f`; B, D by the least squares of Van Overschee
    /// & De Moor (1996, sec. 4.3.3); noise covariances from its residuals.
    #[default]
    Shift,
    /// A, B, C, D by least squares on the estimated state sequence, `x(t+1)` on `x(t)`,
    /// `u(t)` and `y(t)` on `x(t)`, `u(t)` (the states `Γ_f^+` times the oblique
    /// projection of the future outputs, one window and the next: Larimore 1990, Verhaegen
    /// & Verdult 2007, sec. 9.6); noise covariances from its residuals.
    States,
    /// [`SystemMatrices::Shift`], and where its A is unstable [`SystemMatrices::States`]
    /// when that one's A is stable.
    Auto,
}

crate::names::option_names! { SystemMatrices, "matrices", true, [
    ("shift", SystemMatrices::Shift), ("states", SystemMatrices::States),
    ("auto", SystemMatrices::Auto),
] }

/// Options of the weighted SVD.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct SubspaceOptions {
    /// Weighting.
    pub method: Method,
    /// Relative tolerance for the rank of the future-input block (persistent excitation).
    pub input_rank_tol: f64,
}

impl Default for SubspaceOptions {
    fn default() -> Self {
        Self {
            method: Method::Moesp,
            input_rank_tol: 1e-10,
        }
    }
}

impl SubspaceOptions {
    /// Options for a given method, other fields at their defaults.
    pub fn with_method(method: Method) -> Self {
        Self {
            method,
            ..Self::default()
        }
    }
}

/// Options of one fit.
#[derive(Debug, Clone)]
#[non_exhaustive]
pub struct FitOptions {
    /// Estimate D (otherwise D = 0, the default of every sysid state-space estimator, as
    /// MATLAB's).
    pub feedthrough: bool,
    /// Estimate the noise model: K from the Riccati equation and the innovation covariance.
    pub kalman: bool,
    /// Enforce a stable A when the least-squares estimate is not (Chui & Maciejowski 1996;
    /// with [`SystemMatrices::States`], the shift path with it replaces an unstable estimate).
    pub stable: bool,
    /// How A, B, C, D are estimated.
    pub matrices: SystemMatrices,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            feedthrough: false,
            kalman: true,
            stable: false,
            matrices: SystemMatrices::Shift,
        }
    }
}

/// An identified innovation-form model with its noise description.
#[derive(Debug, Clone)]
pub struct Identified {
    /// A, B, C, D.
    pub sys: StateSpace,
    /// Kalman predictor gain (n x l), when requested.
    pub k: Option<Mat<f64>>,
    /// Covariance of the innovations `C P C^T + R` (l x l), when K was requested.
    pub innovation_cov: Option<Mat<f64>>,
    /// State noise covariance Q (n x n) of the residuals.
    pub q: Mat<f64>,
    /// Output noise covariance R (l x l) of the residuals.
    pub r: Mat<f64>,
    /// Cross covariance S (n x l) of the residuals.
    pub s: Mat<f64>,
    /// True when stability enforcement changed A.
    pub stabilized: bool,
    /// True when the noise model's first estimate of K gave an unstable predictor
    /// `A - K C` and K was replaced by the stabilising Kalman gain of the estimated noise
    /// covariances (closed-loop methods, whose K comes from least squares).
    pub predictor_stabilized: bool,
    /// The relative shift of the noise covariances whose Riccati equation the Kalman gain
    /// solves (0: the covariances as estimated; see [`crate::riccati::kalman_gain`]).
    pub kalman_regularization: f64,
    /// Relative residual of that Riccati equation at the returned gain (at most `1e-9` unless
    /// the solvers stalled; see [`crate::riccati::KalmanSolution::residual`]); 0 without a
    /// Riccati solve.
    pub kalman_residual: f64,
}

/// The weighted SVD of a compressed record, ready to fit models of any order.
///
/// See the crate-level example.
#[derive(Debug, Clone)]
pub struct Subspace {
    factor: HankelFactor,
    method: Method,
    weighted: weighting::Weighted,
}

impl Subspace {
    /// Checks excitation and computes the weighted SVD of `factor` for `opts.method`.
    pub fn new(factor: &HankelFactor, opts: &SubspaceOptions) -> Result<Self> {
        Self::from_owned(factor.clone(), opts)
    }

    /// [`Subspace::new`] taking the factor by value (no copy of L).
    pub fn from_owned(factor: HankelFactor, opts: &SubspaceOptions) -> Result<Self> {
        let lay = factor.layout();
        if lay.future < 2 {
            return Err(SysidError::invalid(
                "future horizon",
                format!(
                    "must be >= 2 for the shift-invariance step (got {})",
                    lay.future
                ),
            ));
        }
        let k = lay.k();
        if factor.n_columns() < k {
            let w = lay.window();
            return Err(SysidError::InsufficientData {
                context: format!(
                    "a data matrix with {k} rows (horizons p={}, f={}, {} input(s), {} output(s))",
                    lay.past, lay.future, lay.n_inputs, lay.n_outputs
                ),
                needed: k + (w - 1) * factor.n_experiments().max(1),
                got: factor.n_columns() + (w - 1) * factor.n_experiments(),
                fix: crate::error::horizon_fix(lay.past, lay.future),
            });
        }
        weighting::check_excitation(&factor, opts.input_rank_tol)?;
        let weighted = weighting::weighted_svd(&factor, opts.method)?;
        Ok(Self {
            factor,
            method: opts.method,
            weighted,
        })
    }

    /// The weighting used.
    pub fn method(&self) -> Method {
        self.method
    }

    /// Singular values, largest first (SLICOT's convention: data not divided by sqrt(N);
    /// canonical correlations for CVA).
    pub fn singular_values(&self) -> &[f64] {
        &self.weighted.singular_values
    }

    /// Largest order the horizon allows: `(f - 1) l`, and no more than the numerical rank.
    pub fn max_order(&self) -> usize {
        let lay = self.factor.layout();
        ((lay.future - 1) * lay.n_outputs).min(self.weighted.rank)
    }

    /// The order at the largest gap of the log singular values (SLICOT IB01AD's rule).
    pub fn auto_order(&self) -> usize {
        order::largest_log_gap(self.singular_values(), self.max_order())
    }

    /// Estimates A, B, C, D (and K, noise covariances) for `order`.
    pub fn fit(&self, order: usize, opts: &FitOptions) -> Result<Identified> {
        let max = self.max_order();
        let lay = self.factor.layout();
        if order == 0 {
            return Err(SysidError::invalid(
                "order",
                "the model order must be at least 1",
            ));
        }
        if order > max {
            return Err(SysidError::OrderTooLarge {
                order,
                max,
                future: lay.future,
                outputs: lay.n_outputs,
            });
        }
        system::identify(&self.factor, &self.weighted, order, opts)
    }
}

#[cfg(test)]
pub(crate) mod tests;
