//! Bindings of `sysid_core::nlss`: PNLSS monomials, simulation and estimation, and the
//! neural state-space training.
//!
//! A PNLSS structure crosses the boundary as `(nx, nu, ny, zeta, eta)`, the monomials as
//! lists of variable indices into `z = [x; u]`.

use crate::convert::slice_to_numpy;
use crate::errors::IntoPy;
use crate::search::{run, search_items};
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::nlss::{self, Monomials, Pnlss, PnlssData, Terms};
use sysid_core::optim::Options;
use sysid_core::SysidError;

type Terms2 = Vec<Vec<usize>>;

fn slice<'a>(a: &'a PyReadonlyArray2<'_, f64>, name: &'static str) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        crate::errors::to_py(SysidError::InvalidArgument {
            name,
            reason: "must be a C-contiguous float64 array".into(),
        })
    })
}

fn model(nx: usize, nu: usize, ny: usize, zeta: Terms2, eta: Terms2) -> PyResult<Pnlss> {
    Ok(Pnlss::new(
        nx,
        nu,
        ny,
        Monomials::from_terms(nx, nu, zeta).py()?,
        Monomials::from_terms(nx, nu, eta).py()?,
    ))
}

/// The monomials (index lists into `z = [x; u]`) of the given degrees in the variables
/// `terms` selects ("full", "states" or "inputs").
#[pyfunction]
pub fn pnlss_monomials(nx: usize, nu: usize, terms: &str, degrees: Vec<usize>) -> PyResult<Terms2> {
    let t = match terms {
        "full" => Terms::Full,
        "states" => Terms::States,
        "inputs" => Terms::Inputs,
        other => {
            return Err(crate::errors::to_py(SysidError::InvalidArgument {
                name: "terms",
                reason: format!("must be 'full', 'states' or 'inputs', got {other:?}"),
            }))
        }
    };
    Ok(Monomials::new(nx, nu, t, &degrees).py()?.terms().to_vec())
}

/// Simulated outputs and states (row-major `(N, ny)` and `(N, nx)` flattened) from `x0`.
#[pyfunction]
#[pyo3(signature = (nx, nu, ny, zeta, eta, theta, u, x0=None))]
#[allow(clippy::too_many_arguments)]
pub fn pnlss_simulate<'py>(
    py: Python<'py>,
    nx: usize,
    nu: usize,
    ny: usize,
    zeta: Terms2,
    eta: Terms2,
    theta: Vec<f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Option<Vec<f64>>,
) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
    let m = model(nx, nu, ny, zeta, eta)?;
    let us = slice(&u, "u")?;
    let (y, x) = py.detach(|| m.simulate(&theta, us, x0.as_deref())).py()?;
    Ok((slice_to_numpy(py, &y), slice_to_numpy(py, &x)))
}

/// Simulation-error fit from `theta0`; records are `(u, y, skip)`. Returns a dict with the
/// optimiser's report and `theta`.
#[pyfunction]
#[pyo3(signature = (nx, nu, ny, zeta, eta, records, theta0, max_iter=100, tol=1e-8, fixed=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn pnlss_estimate<'py>(
    py: Python<'py>,
    nx: usize,
    nu: usize,
    ny: usize,
    zeta: Terms2,
    eta: Terms2,
    records: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    theta0: PyReadonlyArray1<'_, f64>,
    max_iter: usize,
    tol: f64,
    fixed: Option<Vec<bool>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = model(nx, nu, ny, zeta, eta)?;
    let mut data = Vec::with_capacity(records.len());
    for (u, y, skip) in &records {
        data.push(PnlssData {
            u: slice(u, "u")?,
            y: slice(y, "y")?,
            skip: *skip,
        });
    }
    let th0 = crate::convert::vec1(&theta0);
    let mut opts = Options::default();
    opts.max_iter = max_iter;
    opts.tol_cost = tol;
    opts.tol_step = tol;
    opts.tol_gradient = tol * tol;
    opts.fixed = fixed;
    let sol = run(py, &progress, |obs| {
        nlss::estimate(&m, &data, &th0, &opts, obs)
    })?;
    let d = PyDict::new(py);
    search_items(&d, py, &sol)?;
    d.set_item("theta", slice_to_numpy(py, &sol.theta))?;
    Ok(d)
}

/// Registers the functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pnlss_monomials, m)?)?;
    m.add_function(wrap_pyfunction!(pnlss_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(pnlss_estimate, m)?)?;
    Ok(())
}
