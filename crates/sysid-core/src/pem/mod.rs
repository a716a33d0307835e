//! Prediction-error refinement of state-space models.
//!
//! The innovation-form model `x(t+1) = A x + B u + K e`, `y = C x + D u + e` gives the
//! one-step predictor
//!
//! ```text
//! x(t+1) = (A - K C) x(t) + (B - K D) u(t) + K y(t),    ŷ(t) = C x(t) + D u(t)
//! ```
//!
//! whose errors `e(t) = y(t) - ŷ(t)` over all experiments define the cost
//! `V = 1/2 sum_t e^T W e`, with `W` the inverse of the innovation covariance re-estimated after
//! every accepted step (so the search minimises `det(sum e e^T)`, the maximum-likelihood
//! criterion for Gaussian innovations). With `focus = Simulation`, `K = 0` and the predictor is
//! the simulation.
//!
//! The parameters are all entries of `A, B, C` (row-major), then `D` (when free), `K` (when
//! estimated) and the initial state of every experiment whose `x0` is estimated. The
//! sensitivities `S(t) = dx(t)/dtheta` obey `S(t+1) = (A - K C) S(t) + F(t)`, with `F` the
//! direct derivative of the right-hand side (for `K_ij` it is the innovation `e_j(t)` in row
//! `i`); `dŷ/dtheta = C S + G`. The Jacobian rows of a block of samples are formed and folded
//! into `J^T W J` and `J^T W r` by one matrix product, so memory does not depend on N.
//!
//! A fully parameterised model is only determined up to a change of state basis. The search
//! moves in the orthogonal complement of the tangent space of the similarity orbit
//! `{(T^-1 A T, T^-1 B, C T, D, T^-1 K, T^-1 x0)}` at the current iterate (data-driven local
//! coordinates, McKelvey, Helmersson & Ribarits 2004), whose tangent vectors for `T = I + X`
//! are `(A X - X A, -X B, C X, 0, -X K, -X x0)`. This is exact when every quantity the
//! similarity moves is a parameter or zero; with a fixed non-zero `K` or a given non-zero `x0`
//! the search uses all directions (the damped Gauss-Newton step is minimum-norm anyway).
//! Without a Kalman gain the search moves in the modal chart instead (module `chart`): `A` in its
//! real block-diagonal form with the entries outside the blocks held at zero, so that the
//! Gauss-Newton products are formed over about `n (m + l + 2)` parameters rather than
//! `n (n + m + l)`.
//! Stability of the predictor (of `A - K C`, or of `A` when simulating) is the admissible
//! set: the search never evaluates an unstable predictor.
//!
//! Periodic data in steady state are fitted on their excited lines instead
//! ([`pem_frequency`], module `frequency`): `G(z) = C (zI - A)^-1 B + D` against the averaged
//! frequency response, weighted by the inverse noise variance from the periods.

mod chart;
mod coordinates;
mod driver;
pub(crate) mod frequency;
#[cfg(test)]
mod frequency_tests;
mod geodesic;
#[cfg(test)]
mod geodesic_tests;
mod modal;
mod normal;
mod options;
mod pass;
mod predictor;
mod rows;
mod sensitivities;
#[cfg(test)]
mod tests;

pub(crate) use coordinates::{similarity_tangent, Part};
pub use driver::{criterion, insists, pem};
pub use frequency::{pem_frequency, FrequencyOptions, FrequencyResult, Lines};
pub(crate) use modal::{modal_form, modal_mt_cols, StateBlocks};
pub use options::{stable_enough, Focus, InitialState, PemOptions, PemResult};
pub use predictor::Predictor;
