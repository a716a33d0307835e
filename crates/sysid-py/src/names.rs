//! Bindings of `sysid_core::names`: the core's option names, so that Python checks an
//! option string where it is given without a list of its own.

use crate::errors::IntoPy;
use pyo3::prelude::*;

/// The canonical name of `value` for `option` (`"method"`, `"compressor"`, `"integrator"`,
/// ...), or the core's error (a `sysid.errors.DataError`) naming what the option accepts.
#[pyfunction]
pub fn option_name(option: &str, value: &str) -> PyResult<&'static str> {
    sysid_core::names::canonical(option, value).py()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(option_name, m)?)?;
    Ok(())
}
