//! Bindings of `sysid_core::stats`: per-channel statistics of a record.

use crate::convert::{slice_to_numpy, view};
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use sysid_core::stats::channel_stats as core_channel_stats;
use sysid_core::SysidError;

/// `(abs_max, mean, std)` per column over the rows of all arrays (experiments) in order:
/// equal to NumPy's `abs(x).max(0)`, `x.mean(0)`, `x.std(0)` of the C-ordered concatenation.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn channel_stats<'py>(
    py: Python<'py>,
    parts: Vec<PyReadonlyArray2<'_, f64>>,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
)> {
    let views: Vec<_> = parts.iter().map(view).collect();
    if let Some(c) = views.first().map(|v| v.ncols()) {
        if views.iter().any(|v| v.ncols() != c) {
            return Err(crate::errors::to_py(SysidError::InvalidArgument {
                name: "parts",
                reason: "every array needs the same number of columns".into(),
            }));
        }
    }
    let s = py.detach(|| core_channel_stats(&views));
    Ok((
        slice_to_numpy(py, &s.abs_max),
        slice_to_numpy(py, &s.mean),
        slice_to_numpy(py, &s.std),
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(channel_stats, m)?)?;
    Ok(())
}
