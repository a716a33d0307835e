//! Bindings of `sysid_core::linalg`: the small matrix rules the Python layer asks the core.

use crate::convert::{mat_to_numpy, view};
use crate::errors::IntoPy;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

/// `a` with its eigenvalues on or outside the unit circle reflected to `shrink / conj(z)`.
#[pyfunction]
#[pyo3(signature = (a, shrink=0.99))]
pub fn reflect_unstable_poles<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'py, f64>,
    shrink: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let av = view(&a);
    let out = py
        .detach(|| sysid_core::linalg::reflect_unstable_poles(av, shrink))
        .py()?;
    Ok(mat_to_numpy(py, &out))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(reflect_unstable_poles, m)?)?;
    Ok(())
}
