//! # sysid-core
//!
//! Identification of linear state-space models
//!
//! ```text
//! x(t+1) = A x(t) + B u(t) + K e(t)
//!   y(t) = C x(t) + D u(t) + e(t)
//! ```
//!
//! from measured input/output records, on [faer].
//!
//! The architecture follows one idea: only the compression of the data into the small
//! triangular factor of the block-Hankel data matrix touches every sample
//! ([`hankel`]); everything else (weighting, SVD, order choice, system matrices, noise model)
//! works on matrices whose size depends on the horizon and the channel counts, never on the
//! record length ([`subspace`]).
//!
//! ```
//! use faer::Mat;
//! use sysid_core::hankel::{HankelLayout, QrCompressor, Compressor};
//! use sysid_core::subspace::{Subspace, SubspaceOptions, Method};
//!
//! // y(t) = 0.5 u(t-1): a first-order system, fed with a pseudo-random input.
//! let n = 400;
//! let mut u = Mat::<f64>::zeros(n, 1);
//! let mut seed = 1u64;
//! for t in 0..n {
//!     seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
//!     u[(t, 0)] = ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
//! }
//! let mut y = Mat::<f64>::zeros(n, 1);
//! for t in 1..n { y[(t, 0)] = 0.5 * u[(t - 1, 0)]; }
//!
//! let layout = HankelLayout::new(1, 1, 5, 5).unwrap();
//! let mut c = QrCompressor::new(layout);
//! c.push(u.as_ref(), y.as_ref()).unwrap();
//! let factor = c.finish().unwrap();
//! let sub = Subspace::new(&factor, &SubspaceOptions::default()).unwrap();
//! assert_eq!(sub.auto_order(), 1);
//! ```

#![warn(missing_docs)]
// Index loops mirror the formulas in numerical kernels; iterator chains would hide them.
#![allow(clippy::needless_range_loop)]

pub mod denormals;
pub mod error;
pub mod greybox;
pub mod hankel;
pub mod hw;
pub mod interrupt;
pub mod linalg;
pub mod model;
pub mod names;
pub mod narx;
pub mod nlss;
pub mod optim;
pub mod pem;
pub mod polynomial;
pub mod realization;
pub mod recursive;
pub mod stats;
pub mod subspace;
pub mod tf;

pub use error::{Result, SysidError};
pub use model::StateSpace;
// The model's equations live in `model/`; their old root paths stay valid.
pub use model::{lyapunov, riccati, simulate};
