//! Polynomial (transfer-function) models in the backward shift `q^-1`.
//!
//! For output `i`, the general multi-input single-output structure is
//!
//! ```text
//! A(q) y(t) = sum_j B_j(q) / F_j(q) u_j(t - nk_j) + C(q) / D(q) e(t)
//! ```
//!
//! with monic `A, C, D, F_j` (`1 + a_1 q^-1 + ... + a_na q^-na`) and `B_j = b_0 + ... +
//! b_{nb-1} q^{-nb+1}`. ARX is `C = D = F = 1`, ARMAX `D = F = 1`, output error (OE)
//! `A = C = D = 1`, Box-Jenkins (BJ) `A = 1`; AR and ARMA have no input.
//!
//! * [`arx`]: the least-squares ARX fit. One streaming pass triangularises the matrix
//!   `Z = [lags 0..L of every input and output]` (rows t = L..N-1 of every experiment) into the
//!   small factor `R` (`R^T R = Z^T Z`). Any sub-structure (orders <= L, delays, cross terms of
//!   a MIMO `A(q)`) is solved from the columns of `R` it selects: the QR of `R[:, S]` is that of
//!   `Z[:, S]`, so every order combination of a search costs O(k^3) and never touches the data
//!   again (`arxstruc`). Ridge or kernel regularisation `theta^T (lambda M^T M) theta` appends
//!   the rows `sqrt(lambda) M` before the small QR.
//! * [`filter`]: `B/A` filtering, simulation and stability (Schur-Cohn) of polynomials.
//! * [`pem`]: the prediction error `e = D/C (A y - sum B_j/F_j u_j)` and its sensitivities
//!   (each a filtered copy of `y`, `u`, `w_j = B_j/F_j u_j`, `e` or `v`, shifted), accumulated
//!   into `J^T J` in blocks of samples, as a [`crate::optim::Problem`]; predictor stability
//!   (`C`, `F_j` stable) is the admissible set. Starting values: least squares (ARX),
//!   Hannan-Rissanen (ARMAX, noise models), Steiglitz-McBride (OE).
//! * [`initial`]: the predictors' initial conditions (MATLAB's `InitialCondition`): each
//!   experiment's initial state eliminated by least squares at every evaluation of [`pem`]
//!   (variable projection), its Gauss-Newton matrix the Schur complement (the marginal
//!   covariance); `Auto` estimates it when that lowers the criterion beyond chance.
//! * [`start`]: the starting values of [`pem`]'s searches.
//! * [`regul`]: the marginal likelihood (value and gradient) of a kernel-prior regression from
//!   the compressed summary of [`arx`], for the empirical-Bayes tuning of regularised ARX.

pub mod arx;
pub mod filter;
pub mod initial;
pub mod iv;
pub mod pem;
pub mod regul;
pub mod start;

#[cfg(test)]
mod initial_tests;
#[cfg(test)]
mod tests;
