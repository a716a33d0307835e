//! Binding of `sysid_core::nlss::estimate_weighted`: the PNLSS (or decoupled PNLSS) fit on
//! the frequency-weighted simulation error of periodic records.

use crate::nlss::{fit_dict, fit_options, keeping, records_data, Model, Structure};
use crate::search::run;
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::nlss::{self, LineWeights};

/// Frequency-weighted simulation-error fit of a PNLSS or decoupled PNLSS structure (the dict
/// `pnlss_estimate` takes) from `theta0`; records are `(u, y, skip)`, one
/// `(period, lines, weights)` per record (`weights`: `len(lines) x ny`, row-major). Returns
/// the optimiser's report and `theta` (and `iterates` when asked), as `pnlss_estimate`.
#[pyfunction]
#[pyo3(signature = (structure, records, weights, theta0, max_iter=100, tol=1e-8, progress=None, iterates=false))]
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
    iterates: bool,
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
    let mut kept = Vec::new();
    let sol = run(py, &progress, |obs| {
        let obs = &mut keeping(obs, iterates, &mut kept);
        match &m {
            Model::Pnlss(m) => nlss::estimate_weighted(m, &data, &w, &th0, &opts, obs),
            Model::Decoupled(m) => {
                nlss::estimate_weighted_decoupled(m, &data, &w, &th0, &opts, obs)
            }
        }
    })?;
    fit_dict(py, &sol, iterates.then_some(kept))
}

/// Registers the function.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pnlss_estimate_weighted, m)?)?;
    Ok(())
}
