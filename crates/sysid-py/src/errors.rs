//! The one place where core errors become Python exceptions.
//!
//! The classes live in `sysid.errors` (Python), so that they can subclass both `SysidError`
//! and a builtin (`ValueError`, `ArithmeticError`).

use pyo3::prelude::*;
use pyo3::types::PyType;
use sysid_core::SysidError;

fn class_name(e: &SysidError) -> &'static str {
    match e {
        SysidError::NonFinite { .. } => "NonFiniteError",
        SysidError::InsufficientData { .. } => "InsufficientDataError",
        SysidError::ShapeMismatch { .. } => "ShapeError",
        SysidError::NotPersistentlyExciting { .. } => "ExcitationError",
        SysidError::RegressorRank { .. } => "ExcitationError",
        SysidError::OrderTooLarge { .. } => "OrderError",
        SysidError::InvalidArgument { .. } | SysidError::IncompatibleFactors { .. } => "DataError",
        SysidError::NoStabilizingSolution { .. } => "RiccatiError",
        SysidError::Numerical { .. } => "NumericalError",
        _ => "SysidError",
    }
}

/// Converts a core error into the matching `sysid.errors` exception, its message the core's
/// and its attributes `kind` (the variant's name), `problem` (the message without its
/// remedy) and `remedy` (what may help, or `None`): see `SysidError::remedy`.
pub fn to_py(e: SysidError) -> PyErr {
    if e == SysidError::Interrupted {
        // the signal handler's own exception when there is one (see `search::watch`)
        return crate::search::take_pending()
            .unwrap_or_else(|| pyo3::exceptions::PyKeyboardInterrupt::new_err(e.to_string()));
    }
    Python::attach(|py| {
        let msg = e.to_string();
        let err = match py
            .import("sysid.errors")
            .and_then(|m| m.getattr(class_name(&e)))
            .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from))
        {
            Ok(cls) => PyErr::from_type(cls, msg),
            Err(_) => return pyo3::exceptions::PyValueError::new_err(msg),
        };
        // the facts as data, so that Python re-words a message without parsing it
        let value = err.value(py);
        let set = value
            .setattr("kind", e.kind())
            .and_then(|_| value.setattr("problem", e.problem()))
            .and_then(|_| value.setattr("remedy", e.remedy()));
        match set {
            Ok(()) => err,
            Err(failed) => failed,
        }
    })
}

/// `Result<T, SysidError>` -> `PyResult<T>`.
pub trait IntoPy<T> {
    /// Maps the error with [`to_py`].
    fn py(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for Result<T, SysidError> {
    fn py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}
