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
use sysid_core::nlss::neural::{self, EpochReport, NeuralSs, Segment, TrainOptions};
use sysid_core::nlss::{self, Decoupled, Monomials, Pnlss, PnlssData, Terms};
use sysid_core::optim::{Flow, Options};
use sysid_core::SysidError;

pub(crate) type Terms2 = Vec<Vec<usize>>;
type Pair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);
type Owned = Vec<(Vec<f64>, Vec<f64>, usize)>;
type Records<'a> = [(PyReadonlyArray2<'a, f64>, PyReadonlyArray2<'a, f64>, usize)];

pub(crate) fn slice<'a>(
    a: &'a PyReadonlyArray2<'_, f64>,
    name: &'static str,
) -> PyResult<&'a [f64]> {
    a.as_slice().map_err(|_| {
        crate::errors::to_py(SysidError::InvalidArgument {
            name,
            reason: "must be a C-contiguous float64 array".into(),
        })
    })
}

pub(crate) type Range = Option<(Vec<f64>, Vec<f64>)>;

pub(crate) fn model(
    nx: usize,
    nu: usize,
    ny: usize,
    zeta: Terms2,
    eta: Terms2,
    range: Range,
) -> PyResult<Pnlss> {
    let m = Pnlss::new(
        nx,
        nu,
        ny,
        Monomials::from_terms(nx, nu, zeta).py()?,
        Monomials::from_terms(nx, nu, eta).py()?,
    );
    match range {
        Some((lo, hi)) => Ok(m.with_range(lo, hi).py()?),
        None => Ok(m),
    }
}

/// The monomials (index lists into `z = [x; u]`) of the given degrees in the variables
/// `terms` selects ("full", "states" or "inputs").
#[pyfunction]
pub fn pnlss_monomials(nx: usize, nu: usize, terms: &str, degrees: Vec<usize>) -> PyResult<Terms2> {
    let t: Terms = terms.parse().py()?;
    Ok(Monomials::new(nx, nu, t, &degrees).py()?.terms().to_vec())
}

/// Simulated outputs and states (row-major `(N, ny)` and `(N, nx)` flattened) from `x0`;
/// `range = (lo, hi)` clamps the monomials' arguments `[x; u]`.
#[pyfunction]
#[pyo3(signature = (nx, nu, ny, zeta, eta, theta, u, x0=None, range=None))]
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
    range: Range,
) -> PyResult<Pair<'py>> {
    let m = model(nx, nu, ny, zeta, eta, range)?;
    let us = slice(&u, "u")?;
    let (y, x) = py.detach(|| m.simulate(&theta, us, x0.as_deref())).py()?;
    Ok((slice_to_numpy(py, &y), slice_to_numpy(py, &x)))
}

/// Simulation-error fit from `theta0`; records are `(u, y, skip)`. Returns a dict with the
/// optimiser's report and `theta`; `range` as in [`pnlss_simulate`].
#[pyfunction]
#[pyo3(signature = (nx, nu, ny, zeta, eta, records, theta0, max_iter=100, tol=1e-8, fixed=None, progress=None, range=None))]
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
    m.add_function(wrap_pyfunction!(decoupled_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(decoupled_estimate, m)?)?;
    register_neural(m)
}

fn decoupled(
    dims: (usize, usize, usize),
    branches: usize,
    degrees: Vec<usize>,
    range: Range,
) -> PyResult<Decoupled> {
    let m = Decoupled::new(dims.0, dims.1, dims.2, branches, degrees).py()?;
    match range {
        Some((lo, hi)) => Ok(m.with_range(lo, hi).py()?),
        None => Ok(m),
    }
}

/// Decoupled PNLSS simulation: outputs and states (row-major, flattened) from `x0`;
/// `range = (lo, hi)` clamps the branch arguments.
#[pyfunction]
#[pyo3(signature = (dims, branches, degrees, theta, u, x0=None, range=None))]
#[allow(clippy::too_many_arguments)]
pub fn decoupled_simulate<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    branches: usize,
    degrees: Vec<usize>,
    theta: Vec<f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Option<Vec<f64>>,
    range: Range,
) -> PyResult<Pair<'py>> {
    let m = decoupled(dims, branches, degrees, range)?;
    let us = slice(&u, "u")?;
    let (y, x) = py.detach(|| m.simulate(&theta, us, x0.as_deref())).py()?;
    Ok((slice_to_numpy(py, &y), slice_to_numpy(py, &x)))
}

/// Decoupled PNLSS simulation-error fit from `theta0`; records are `(u, y, skip)`.
#[pyfunction]
#[pyo3(signature = (dims, branches, degrees, records, theta0, max_iter=100, tol=1e-8, progress=None, range=None))]
#[allow(clippy::too_many_arguments)]
pub fn decoupled_estimate<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    branches: usize,
    degrees: Vec<usize>,
    records: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    theta0: PyReadonlyArray1<'_, f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    range: Range,
) -> PyResult<Bound<'py, PyDict>> {
    let m = decoupled(dims, branches, degrees, range)?;
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
    let sol = run(py, &progress, |obs| {
        nlss::estimate_decoupled(&m, &data, &th0, &opts, obs)
    })?;
    let d = PyDict::new(py);
    search_items(&d, py, &sol)?;
    d.set_item("theta", slice_to_numpy(py, &sol.theta))?;
    Ok(d)
}

fn neural_model(
    dims: (usize, usize, usize),
    f_hidden: Vec<usize>,
    g_hidden: Option<Vec<usize>>,
    h_hidden: Vec<usize>,
    lags: usize,
) -> NeuralSs {
    NeuralSs::new(
        dims.0,
        dims.1,
        dims.2,
        &f_hidden,
        g_hidden.as_deref(),
        &h_hidden,
        lags,
    )
}

/// Neural state-space simulation from `x0` (row-major `(N, ny)` flattened).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn neural_ss_simulate<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    f_hidden: Vec<usize>,
    g_hidden: Option<Vec<usize>>,
    h_hidden: Vec<usize>,
    lags: usize,
    params: PyReadonlyArray1<'_, f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Vec<f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = neural_model(dims, f_hidden, g_hidden, h_hidden, lags);
    let p = crate::convert::vec1(&params);
    let us = slice(&u, "u")?;
    let y = py.detach(|| m.simulate(&p, us, &x0)).py()?;
    Ok(slice_to_numpy(py, &y))
}

/// The encoder's state at sample `t` of a record.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn neural_ss_encode<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    f_hidden: Vec<usize>,
    g_hidden: Option<Vec<usize>>,
    h_hidden: Vec<usize>,
    lags: usize,
    params: PyReadonlyArray1<'_, f64>,
    u: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    t: usize,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = neural_model(dims, f_hidden, g_hidden, h_hidden, lags);
    let p = crate::convert::vec1(&params);
    let x = m.encode(&p, slice(&u, "u")?, slice(&y, "y")?, t).py()?;
    Ok(slice_to_numpy(py, &x))
}

/// Trains from `params0`; `train` and `val` are `(u, y, at)` records. `progress(epoch,
/// validation, train)` after every epoch (`False` stops). Returns a dict.
#[pyfunction]
#[pyo3(signature = (dims, f_hidden, g_hidden, h_hidden, lags, params0, train, val, epochs=200, batch=16, horizon=100, learning_rate=1e-3, patience=20, seed=0, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn neural_ss_train<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    f_hidden: Vec<usize>,
    g_hidden: Option<Vec<usize>>,
    h_hidden: Vec<usize>,
    lags: usize,
    params0: PyReadonlyArray1<'_, f64>,
    train: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    val: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, usize)>,
    epochs: usize,
    batch: usize,
    horizon: usize,
    learning_rate: f64,
    patience: usize,
    seed: u64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = neural_model(dims, f_hidden, g_hidden, h_hidden, lags);
    let seg = |v: &Records<'_>| -> PyResult<Owned> {
        v.iter()
            .map(|(u, y, at)| Ok((slice(u, "u")?.to_vec(), slice(y, "y")?.to_vec(), *at)))
            .collect()
    };
    let (tr, va) = (seg(&train)?, seg(&val)?);
    let p0 = crate::convert::vec1(&params0);
    let mut opts = TrainOptions::default();
    opts.epochs = epochs;
    opts.batch = batch.max(1);
    opts.horizon = horizon;
    opts.learning_rate = learning_rate;
    opts.patience = patience;
    opts.seed = seed;
    let mut slot: Option<PyErr> = None;
    let res = crate::search::watch(py, || {
        let ts: Vec<Segment<'_>> = tr
            .iter()
            .map(|(u, y, at)| Segment { u, y, at: *at })
            .collect();
        let vs: Vec<Segment<'_>> = va
            .iter()
            .map(|(u, y, at)| Segment { u, y, at: *at })
            .collect();
        neural::train(&m, &p0, &ts, &vs, &opts, &mut |r: &EpochReport| {
            Python::attach(|py| {
                let out = match &progress {
                    Some(cb) => cb
                        .call1(py, (r.epoch, r.validation, r.train))
                        .map(|v| v.bind(py).is(&*pyo3::types::PyBool::new(py, false))),
                    None => Ok(false),
                };
                match out {
                    Ok(true) => Flow::Stop,
                    Ok(false) => Flow::Continue,
                    Err(e) => {
                        slot.get_or_insert(e);
                        Flow::Stop
                    }
                }
            })
        })
    });
    let r = crate::search::finish(res, slot)?;
    let d = PyDict::new(py);
    d.set_item("params", slice_to_numpy(py, &r.params))?;
    d.set_item("validation", r.validation)?;
    d.set_item("train", r.train)?;
    d.set_item("best_epoch", r.best_epoch)?;
    d.set_item("stop", r.stop)?;
    d.set_item("diverged", r.diverged)?;
    Ok(d)
}

/// Parameter count of a neural state-space structure.
#[pyfunction]
pub fn neural_ss_n_params(
    dims: (usize, usize, usize),
    f_hidden: Vec<usize>,
    g_hidden: Option<Vec<usize>>,
    h_hidden: Vec<usize>,
    lags: usize,
) -> usize {
    neural_model(dims, f_hidden, g_hidden, h_hidden, lags).n_params()
}

/// Registers the neural state-space functions.
pub fn register_neural(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(neural_ss_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(neural_ss_encode, m)?)?;
    m.add_function(wrap_pyfunction!(neural_ss_train, m)?)?;
    m.add_function(wrap_pyfunction!(neural_ss_n_params, m)?)?;
    Ok(())
}
