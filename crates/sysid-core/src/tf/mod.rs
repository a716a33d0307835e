//! Continuous-time transfer functions `G(s) = B(s) / A(s) e^{-s tau}` identified from data.
//!
//! Two kernels, the rest (canonical realisations, sampling with ZOH/FOH, the output-error
//! refinement on sampled data) lives in the shared optimiser and the grey-box predictor:
//!
//! - [`gram`]: refined instrumental variables for continuous-time models (SRIVC, Young &
//!   Jakeman 1980) need the measured signals filtered by `s^k / A(s)` for `k = 0..n`. With
//!   the filter realised as a state-space model sampled exactly under the data's hold, one pass
//!   over the samples gives every filtered derivative at once (the states); the pass
//!   accumulates the Gram matrix `sum_t w_t w_t^T` of the vector `w_t = C x_t + D v_t` that
//!   stacks target, regressors and instruments, so no `N x p` matrix is ever stored.
//! - [`frequency`]: the weighted nonlinear least-squares fit of a rational model to a
//!   measured frequency response, `min sum_k |W_k (N(x_k)/D(x_k) e^{-w_k tau} - H_k)|^2`, a
//!   provider of the shared Gauss-Newton search ([`crate::optim`]) with the exact Jacobian.

pub mod frequency;
pub mod gram;
#[cfg(test)]
mod tests;

pub use frequency::{fit_frequency, FrequencyFit, Rational};
pub use gram::filtered_gram;
