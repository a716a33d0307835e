//! Binding of `sysid_core::nlss::estimate_weighted`: the PNLSS fit on the frequency-weighted
//! simulation error of periodic records.

use crate::convert::slice_to_numpy;
use crate::nlss::{model, slice, Range, Terms2};
use crate::search::{run, search_items};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::nlss::{self, LineWeights, PnlssData};
use sysid_core::optim::Options;

/// Frequency-weighted simulation-error fit from `theta0`; records are `(u, y, skip)`, one
/// `(period, lines, weights)` per record (`weights`: `len(lines) x ny`, row-major). Returns
/// the optimiser's report and `theta`, as `pnlss_estimate`.
#[pyfunction]
#[pyo3(signature = (nx, nu, ny, zeta, eta, records, weights, theta0, max_iter=100, tol=1e-8, progress=None, range=None))]
#[allow(clippy::too_many_arguments)]
pub fn pnlss_estimate_weighted<'py>(
    py: Python<'py>,
    nx: usize,
    nu: usize,
    ny: usize,
    zeta: Terms2,
    eta: Terms2,
    records: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    weights: Vec<(usize, Vec<usize>, Vec<f64>)>,
    theta0: PyReadonlyArray1<'_, f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    range: Range,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model(nx, nu, ny, zeta, eta, range)?;
    let mut data = Vec::with_capacity(records.len());
    for (u, y, skip) in &records {
        data.push(PnlssData {
            u: slice(u, "u")?,
            y: slice(y, "y")?,
            skip: *skip,
        });
    }
    let w: Vec<LineWeights> = weights
        .into_iter()
        .map(|(period, lines, weights)| LineWeights {
            period,
            lines,
            weights,
        })
        .collect();
    let th0 = crate::convert::vec1(&theta0);
    let mut opts = Options::default();
    opts.max_iter = max_iter;
    opts.tol_cost = tol;
    opts.tol_step = tol;
    opts.tol_gradient = tol * tol;
    let sol = run(py, &progress, |obs| {
        nlss::estimate_weighted(&m, &data, &w, &th0, &opts, obs)
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
