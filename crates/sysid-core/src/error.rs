//! The one error type of sysid-core.
//!
//! Every fallible public function returns [`Result`]. Messages are written for the person who
//! called the library: they name the problem and the fix, because the binding crate passes
//! them on unchanged as the text of the Python exception.

use thiserror::Error;

/// What went wrong, with the data needed to explain it.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SysidError {
    /// A sample is NaN or infinite.
    #[error(
        "{what} has a non-finite value (NaN or Inf) at sample {sample}, channel {channel}; \
         interpolate or cut it out before identification"
    )]
    NonFinite {
        /// Which array ("u", "y", "markov", ...).
        what: &'static str,
        /// Row (time index) of the first offending value.
        sample: usize,
        /// Column (channel) of the first offending value.
        channel: usize,
    },
    /// The record is too short for what was asked of it.
    #[error("{}; {fix}", self.problem())]
    InsufficientData {
        /// What needed the samples.
        context: String,
        /// How many are needed.
        needed: usize,
        /// How many there are.
        got: usize,
        /// What the user can do.
        fix: &'static str,
    },
    /// Arrays whose shapes do not fit together.
    #[error("{what} has shape {got} but should have shape {expected}")]
    ShapeMismatch {
        /// Which argument.
        what: String,
        /// The expected shape, in words or numbers.
        expected: String,
        /// The shape received.
        got: String,
    },
    /// The input does not excite the system enough for the requested horizon.
    #[error("{}; {}", self.problem(), EXCITATION_REMEDY)]
    NotPersistentlyExciting {
        /// Numerical rank found.
        rank: usize,
        /// Rank needed (number of future-input rows).
        rows: usize,
        /// Relative tolerance used to decide the rank.
        tol: f64,
    },
    /// The regressors (or instruments) of a linear-regression estimator are rank deficient:
    /// the data do not determine the parameters.
    #[error("{}; {fix}", self.problem())]
    RegressorRank {
        /// The estimator (`"arx"`, `"iv4"`).
        estimator: &'static str,
        /// Numerical rank found.
        rank: usize,
        /// Number of regressor columns (parameters of one equation).
        columns: usize,
        /// Relative tolerance used to decide the rank.
        tol: f64,
        /// What may help.
        fix: &'static str,
    },
    /// The model order is larger than the data matrix supports.
    #[error(
        "order {order} is too large: with a future horizon of {future} and {outputs} output(s) \
         at most {max} states can be identified; choose order <= {max} or a longer horizon"
    )]
    OrderTooLarge {
        /// Requested order.
        order: usize,
        /// Largest admissible order.
        max: usize,
        /// Future horizon in use.
        future: usize,
        /// Number of outputs.
        outputs: usize,
    },
    /// An argument outside its valid range.
    #[error("invalid {name}: {reason}")]
    InvalidArgument {
        /// The argument's name.
        name: &'static str,
        /// What is wrong and what would be right.
        reason: String,
    },
    /// Two Hankel factors that cannot be combined.
    #[error("cannot merge compressed data: {reason}")]
    IncompatibleFactors {
        /// Why not.
        reason: String,
    },
    /// A numerical step failed (rank loss, non-convergence).
    #[error("numerical failure in {step}: {reason}")]
    Numerical {
        /// Which step.
        step: &'static str,
        /// What happened, and what may help.
        reason: String,
    },
    /// The discrete algebraic Riccati equation has no stabilising solution.
    #[error(
        "the Riccati equation for the Kalman gain has no stabilising solution ({reason}); \
         the noise covariances may be degenerate: fit with kalman=False or a different order"
    )]
    NoStabilizingSolution {
        /// Why the solver gave up.
        reason: String,
    },
    /// The computation was stopped from outside (Ctrl-C; see [`crate::interrupt`]).
    #[error("interrupted: the computation was stopped before it finished")]
    Interrupted,
}

/// Result with [`SysidError`].
pub type Result<T> = std::result::Result<T, SysidError>;

/// The fix for a data matrix with too few columns: a longer record or a smaller horizon,
/// and only a longer record once both horizons are at their smallest (2): a record of 57
/// samples with 7 channels was told to shrink a horizon that could not shrink.
///
/// ```
/// use sysid_core::error::horizon_fix;
/// assert!(horizon_fix(2, 2).contains("smallest"));
/// assert!(horizon_fix(10, 10).contains("smaller horizon"));
/// ```
pub fn horizon_fix(past: usize, future: usize) -> &'static str {
    if past <= 2 && future <= 2 {
        "use a longer record (the horizons are already at their smallest)"
    } else {
        "use a longer record or a smaller horizon"
    }
}

/// What [`SysidError::NotPersistentlyExciting`] suggests (its [`SysidError::remedy`]).
pub const EXCITATION_REMEDY: &str = "use a richer input (white noise, PRBS, multisine), a \
     shorter horizon, or remove constant input channels";

impl SysidError {
    /// The variant's name (`"NotPersistentlyExciting"`): the Python exception's `kind`, so
    /// that callers tell errors apart without reading their text.
    pub fn kind(&self) -> &'static str {
        match self {
            SysidError::NonFinite { .. } => "NonFinite",
            SysidError::InsufficientData { .. } => "InsufficientData",
            SysidError::ShapeMismatch { .. } => "ShapeMismatch",
            SysidError::NotPersistentlyExciting { .. } => "NotPersistentlyExciting",
            SysidError::RegressorRank { .. } => "RegressorRank",
            SysidError::OrderTooLarge { .. } => "OrderTooLarge",
            SysidError::InvalidArgument { .. } => "InvalidArgument",
            SysidError::IncompatibleFactors { .. } => "IncompatibleFactors",
            SysidError::Numerical { .. } => "Numerical",
            SysidError::NoStabilizingSolution { .. } => "NoStabilizingSolution",
            SysidError::Interrupted => "Interrupted",
        }
    }

    /// What may help, for the errors whose message ends in a separate remedy (the message is
    /// then `"{problem}; {remedy}"`, see [`SysidError::problem`]); `None` for the others.
    ///
    /// ```
    /// use sysid_core::SysidError;
    /// let e = SysidError::NotPersistentlyExciting { rank: 3, rows: 4, tol: 1e-9 };
    /// assert_eq!(e.to_string(), format!("{}; {}", e.problem(), e.remedy().unwrap()));
    /// ```
    pub fn remedy(&self) -> Option<&'static str> {
        match self {
            SysidError::NotPersistentlyExciting { .. } => Some(EXCITATION_REMEDY),
            SysidError::InsufficientData { fix, .. } | SysidError::RegressorRank { fix, .. } => {
                Some(fix)
            }
            _ => None,
        }
    }

    /// The message without its [`SysidError::remedy`] (the whole message when there is
    /// none): what a caller that knows a better remedy for its own data says first.
    pub fn problem(&self) -> String {
        match self {
            SysidError::NotPersistentlyExciting { rank, rows, tol } => format!(
                "the input is not persistently exciting: the {rows} rows of future inputs in \
                 the data matrix have numerical rank {rank} (relative tolerance {tol:.1e})"
            ),
            SysidError::InsufficientData {
                context,
                needed,
                got,
                ..
            } => format!("too few samples: {context} needs at least {needed} but got {got}"),
            SysidError::RegressorRank {
                estimator,
                rank,
                columns,
                tol,
                ..
            } => format!(
                "{estimator}: the {columns} regressor columns of each equation have numerical \
                 rank {rank} (relative tolerance {tol:.1e}), so the data do not determine the \
                 parameters"
            ),
            _ => self.to_string(),
        }
    }

    pub(crate) fn invalid(name: &'static str, reason: impl Into<String>) -> Self {
        SysidError::InvalidArgument {
            name,
            reason: reason.into(),
        }
    }

    pub(crate) fn numerical(step: &'static str, reason: impl Into<String>) -> Self {
        SysidError::Numerical {
            step,
            reason: reason.into(),
        }
    }
}

/// Largest matrix, in bytes, that sysid allocates for a size the caller chose (a horizon, a
/// number of lags, a chunk size): 4 GiB. Larger requests are refused with an error naming the
/// argument instead of aborting the process in the allocator.
pub const MAX_MATRIX_BYTES: usize = 1 << 32;

/// Checks that a `rows x cols` matrix of `f64` whose size comes from argument `name` can be
/// allocated: no overflow and at most [`MAX_MATRIX_BYTES`].
///
/// ```
/// use sysid_core::error::check_matrix_size;
/// assert!(check_matrix_size("horizon", 100, 100).is_ok());
/// assert!(check_matrix_size("horizon", usize::MAX, 2).is_err());
/// assert!(check_matrix_size("horizon", 1 << 20, 1 << 20).is_err());
/// ```
pub fn check_matrix_size(name: &'static str, rows: usize, cols: usize) -> Result<()> {
    let bytes = rows
        .checked_mul(cols)
        .and_then(|n| n.checked_mul(std::mem::size_of::<f64>()));
    match bytes {
        Some(b) if b <= MAX_MATRIX_BYTES => Ok(()),
        _ => Err(SysidError::invalid(
            name,
            format!(
                "it would need a {rows} x {cols} matrix ({}), more than the {} GiB limit; \
                 choose a smaller {name}",
                match bytes {
                    Some(b) => format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64),
                    None => "more memory than can be addressed".to_string(),
                },
                MAX_MATRIX_BYTES >> 30
            ),
        )),
    }
}

/// True when every value of `x` is finite: `v - v` is 0 for finite `v` and NaN otherwise,
/// summed in 8 independent lanes.
#[allow(clippy::eq_op)]
fn all_finite_slice(x: &[f64]) -> bool {
    let mut acc = [0.0f64; 8];
    let mut chunks = x.chunks_exact(8);
    for ch in &mut chunks {
        for (a, v) in acc.iter_mut().zip(ch) {
            *a += v - v;
        }
    }
    acc.iter().all(|a| *a == 0.0) && chunks.remainder().iter().all(|v| v.is_finite())
}

/// Checks that every entry of `x` is finite.
// `v - v` is the test: 0 for finite values, NaN for infinities and NaN
#[allow(clippy::eq_op)]
pub fn check_finite(what: &'static str, x: faer::MatRef<'_, f64>) -> Result<()> {
    // fast path: one sweep with no early exit, over contiguous memory in independent lanes
    // when the layout allows (vectorises); the slow loop below only runs to locate the first
    // bad value
    let (r, c) = (x.nrows(), x.ncols());
    let all_finite =
        if r > 1 && c > 0 && x.row_stride() == c as isize && (c == 1 || x.col_stride() == 1) {
            // SAFETY: row-major and contiguous (checked strides): r c values from the pointer
            all_finite_slice(unsafe { std::slice::from_raw_parts(x.as_ptr(), r * c) })
        } else if r > 0 && x.row_stride() == 1 {
            (0..c).all(|j| {
                // SAFETY: column j is r contiguous values (row stride 1)
                all_finite_slice(unsafe { std::slice::from_raw_parts(x.col(j).as_ptr(), r) })
            })
        } else {
            (0..c).all(|j| {
                x.col(j)
                    .iter()
                    .fold(0.0f64, |acc, v| acc + (v - v))
                    .is_finite()
            })
        };
    if all_finite {
        return Ok(());
    }
    for j in 0..x.ncols() {
        for i in 0..x.nrows() {
            if !x[(i, j)].is_finite() {
                return Err(SysidError::NonFinite {
                    what,
                    sample: i,
                    channel: j,
                });
            }
        }
    }
    Ok(())
}

/// Checks one experiment: `u` is `(N, m)` and `y` is `(N, l)` with the same `N` (not compared
/// when `m == 0`: an input-free record may pass an empty `u`), and every entry is finite.
/// `what` names the pair in the message ("u, y", "experiment 2 (u, y)", ...).
///
/// ```
/// use faer::Mat;
/// use sysid_core::error::check_io;
/// let (u, y) = (Mat::<f64>::zeros(10, 2), Mat::<f64>::zeros(10, 1));
/// assert!(check_io("u, y", u.as_ref(), y.as_ref(), 2, 1).is_ok());
/// let e = check_io("u, y", u.as_ref(), y.as_ref(), 1, 1).unwrap_err();
/// assert!(e.to_string().contains("(N, 1) and (N, 1)"));
/// let short = Mat::<f64>::zeros(9, 1);
/// assert!(check_io("u, y", u.as_ref(), short.as_ref(), 2, 1).is_err());
/// ```
pub fn check_io(
    what: &str,
    u: faer::MatRef<'_, f64>,
    y: faer::MatRef<'_, f64>,
    m: usize,
    l: usize,
) -> Result<()> {
    if u.ncols() != m || y.ncols() != l || (m > 0 && u.nrows() != y.nrows()) {
        return Err(SysidError::ShapeMismatch {
            what: what.to_string(),
            expected: format!("(N, {m}) and (N, {l})"),
            got: format!(
                "({}, {}) and ({}, {})",
                u.nrows(),
                u.ncols(),
                y.nrows(),
                y.ncols()
            ),
        });
    }
    check_finite("u", u)?;
    check_finite("y", y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_are_problem_then_remedy_as_before() {
        let pe = SysidError::NotPersistentlyExciting {
            rank: 3,
            rows: 10,
            tol: 1e-9,
        };
        assert_eq!(
            pe.to_string(),
            "the input is not persistently exciting: the 10 rows of future inputs in the data \
             matrix have numerical rank 3 (relative tolerance 1.0e-9); use a richer input \
             (white noise, PRBS, multisine), a shorter horizon, or remove constant input channels"
        );
        let short = SysidError::InsufficientData {
            context: "the horizon".into(),
            needed: 40,
            got: 12,
            fix: "use a longer record",
        };
        assert_eq!(
            short.to_string(),
            "too few samples: the horizon needs at least 40 but got 12; use a longer record"
        );
        let rank = SysidError::RegressorRank {
            estimator: "arx",
            rank: 2,
            columns: 3,
            tol: 1e-10,
            fix: "excite more",
        };
        assert_eq!(
            rank.to_string(),
            "arx: the 3 regressor columns of each equation have numerical rank 2 (relative \
             tolerance 1.0e-10), so the data do not determine the parameters; excite more"
        );
        for e in [&pe, &short, &rank] {
            assert_eq!(
                e.to_string(),
                format!("{}; {}", e.problem(), e.remedy().unwrap())
            );
        }
        let order = SysidError::OrderTooLarge {
            order: 5,
            max: 3,
            future: 3,
            outputs: 1,
        };
        assert_eq!(
            (order.kind(), order.remedy(), order.problem()),
            ("OrderTooLarge", None, order.to_string())
        );
    }
}
