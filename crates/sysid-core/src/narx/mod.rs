//! Nonlinear ARX / ARMAX (NARX, NARMAX) models with term selection.
//!
//! For output `i` the model is a linear combination of nonlinear terms of lagged signals,
//!
//! ```text
//! y_i(t) = sum_k theta_ik phi_k(x(t)) + e_i(t),
//! x(t) = [y(t-1) .. y(t-na), u(t-nk) .. u(t-nk-nb+1), e(t-1) .. e(t-ne)]
//! ```
//!
//! * [`regressors`]: the lagged variables `x(t)` of one or several experiments (MIMO).
//! * [`basis`]: the candidate terms `phi_k`: monomials of the lagged variables up to a degree
//!   (enumerated so that every monomial is its parent times one variable, one product per
//!   sample), or Gaussian radial basis functions plus the linear terms.
//! * [`frols`]: forward-regression orthogonal least squares (Billings): the term with the
//!   largest error reduction ratio `ERR = (w^T y)^2 / (w^T w y^T y)` of its component `w`
//!   orthogonal to the terms already chosen. The regressor matrix is never held: each step is
//!   one streaming pass over row blocks, generating the candidate columns and accumulating
//!   their inner products with the newly orthogonalised term (an explicit vector, computed
//!   per row from the chosen terms, as in classical Gram-Schmidt); the residual norms of all
//!   candidates are then updated by the projections. The final coefficients come from a
//!   streaming Householder QR of the chosen columns and the targets, so they are exact least
//!   squares whatever the conditioning of the selection path.
//! * [`simulate`]: free-run simulation, k-step prediction and residuals.
//! * [`network`]: sigmoid and wavelet networks and tree partitions on the same lagged
//!   variables, trained by separable least squares on the shared optimiser.

pub mod basis;
pub mod frols;
pub mod network;
pub mod regressors;
mod run;
pub mod simulate;

#[cfg(test)]
mod tests;
