//! Bindings of `sysid_core::stats`: per-channel statistics of a record.

use crate::convert::{slice_to_numpy, view};
use crate::errors::IntoPy;
use numpy::{IntoPyArray, PyArray1, PyArray3, PyReadonlyArray2};
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
    if !views.is_empty() && views.iter().all(|v| v.nrows() == 0) {
        return Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "parts",
            reason: "no samples: statistics need at least one row".into(),
        }));
    }
    let s = py.detach(|| core_channel_stats(&views));
    Ok((
        slice_to_numpy(py, &s.abs_max),
        slice_to_numpy(py, &s.mean),
        slice_to_numpy(py, &s.std),
    ))
}

/// `R[tau, a, b] = sum_t x_a(t + tau) x_b(t)` for `tau = 0..=max_lag`, summed over the
/// C-contiguous `(samples, channels)` arrays `parts` (experiments; no lag spans two).
#[pyfunction]
pub fn lagged_products<'py>(
    py: Python<'py>,
    parts: Vec<PyReadonlyArray2<'_, f64>>,
    max_lag: usize,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let d = parts.first().map_or(0, |p| p.as_array().ncols());
    if parts.iter().any(|p| p.as_array().ncols() != d) {
        return Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "parts",
            reason: "every array needs the same number of columns".into(),
        }));
    }
    sysid_core::error::check_matrix_size("max_lag", max_lag.saturating_add(1), d * d).py()?;
    let slices: Vec<&[f64]> = parts
        .iter()
        .map(|p| p.as_slice())
        .collect::<Result<_, _>>()?;
    let r = py.detach(|| sysid_core::stats::lagged_products(&slices, d, max_lag));
    Ok(
        numpy::ndarray::Array3::from_shape_vec((max_lag + 1, d, d), r)
            .expect("lagged_products returns (max_lag + 1) d d values")
            .into_pyarray(py),
    )
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(channel_stats, m)?)?;
    m.add_function(wrap_pyfunction!(lagged_products, m)?)?;
    Ok(())
}
