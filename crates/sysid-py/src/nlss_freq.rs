//! Binding of `sysid_core::nlss::estimate_weighted`: the PNLSS (or decoupled PNLSS) fit on
//! the frequency-weighted simulation error of periodic records.

use crate::convert::slice_to_numpy;
use crate::nlss::{fit_options, records_data, Model, Structure};
use crate::search::{run, search_items};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::nlss::{self, LineWeights};

/// Frequency-weighted simulation-error fit of a PNLSS or decoupled PNLSS structure (the dict
/// `pnlss_estimate` takes) from `theta0`; records are `(u, y, skip)`, one
/// `(period, lines, weights)` per record (`weights`: `len(lines) x ny`, row-major). Returns
/// the optimiser's report and `theta`, as `pnlss_estimate`.
#[pyfunction]
#[pyo3(signature = (structure, records, weights, theta0, max_iter=100, tol=1e-8, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn pnlss_estimate_weighted<'py>(
    py: Python<'py>,
    structure: Structure,
    records: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    weights: Vec<(usize, Vec<usize>, Vec<f64>)>,
    theta0: PyReadonlyArray1<'_, f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = structure.model()?;
    let data = records_data(&records)?;
    let w: Vec<LineWeights> = weights
        .into_iter()
        .map(|(period, lines, weights)| LineWeights {
            period,
            lines,
            weights,
        })
        .collect();
    let th0 = crate::convert::vec1(&theta0);
    let opts = fit_options(max_iter, tol);
    let sol = run(py, &progress, |obs| match &m {
        Model::Pnlss(m) => nlss::estimate_weighted(m, &data, &w, &th0, &opts, obs),
        Model::Decoupled(m) => nlss::estimate_weighted_decoupled(m, &data, &w, &th0, &opts, obs),
    })?;
    let d = PyDict::new(py);
    search_items(&d, py, &sol)?;
    d.set_item("theta", slice_to_numpy(py, &sol.theta))?;
    Ok(d)
}

/// Registers the function.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pnlss_estimate_weighted, m)?)?;
    Ok(())
}
