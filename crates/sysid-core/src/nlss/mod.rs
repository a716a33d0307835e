//! Nonlinear state-space models: polynomial (PNLSS) and neural.
//!
//! The polynomial nonlinear state-space model (Paduart et al., Automatica 2010) is
//!
//! ```text
//! x(t+1) = A x(t) + B u(t) + E zeta(x(t), u(t))
//!   y(t) = C x(t) + D u(t) + F eta(x(t), u(t))
//! ```
//!
//! where `zeta` and `eta` stack monomials of chosen total degrees (>= 2) in the states and/or
//! the inputs ([`Monomials`]). It is fitted on the simulation error with the shared optimiser
//! ([`crate::optim`]): the Jacobian comes from forward sensitivities `S(t) = dx(t)/dtheta`,
//!
//! ```text
//! S(t+1) = (A + E dzeta/dx) S(t) + d f/d theta |_x        dy/dtheta = (C + F deta/dx) S + d g/d theta |_x
//! ```
//!
//! propagated sample by sample, the rows of the Jacobian accumulated block by block into
//! `J^T J` and `J^T r` (no `N x p` array). A simulation whose state leaves a bound or turns
//! non-finite is reported as diverged: the cost is infinite and the search rejects the step.
//! [`Decoupled`] replaces the state equation's multivariate polynomial by a few univariate
//! polynomials of linear forms of `[x; u]` (far fewer parameters for many states). Both may
//! clamp the polynomials' arguments to a box (bounded simulation outside the fitted range).
//! For periodic records [`estimate_weighted`] fits the period-averaged simulation error
//! weighted on chosen DFT lines (the classic frequency-domain PNLSS cost).
//! [`neural`] holds the neural state-space model and its training.

mod decoupled;
mod freqweight;
mod monomials;
pub mod neural;
mod pnlss;
mod simulation;
#[cfg(test)]
mod tests;

pub use decoupled::{estimate_decoupled, Decoupled};
pub use freqweight::{estimate_weighted, estimate_weighted_decoupled, weighted_cost, LineWeights};
pub use monomials::{Monomials, Terms};
pub use pnlss::{estimate, Pnlss, PnlssData};
