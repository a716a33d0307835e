//! Bindings of `sysid_core::hw`: Hammerstein-Wiener prediction-error estimate and simulation.
//!
//! A nonlinearity crosses the boundary as `(kind, n, breakpoints)`: kind `"identity"`,
//! `"saturation"`, `"deadzone"`, `"polynomial"` (n = degree), `"pwl"` (breakpoints) or
//! `"sigmoid"` (n = units).

use crate::convert::{mat_to_numpy, slice_to_numpy, vec1, view};
use crate::errors::IntoPy;
use crate::search::{run, search_items};
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::hw::mimo::{self, MimoHwStructure};
use sysid_core::hw::{self, HwStructure, Nonlinearity};
use sysid_core::optim::{covariance, Options, Solution};
use sysid_core::SysidError;

type Nl = (String, usize, Vec<f64>);
type Signals<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

fn nl(spec: &Nl) -> PyResult<Nonlinearity> {
    let (kind, n, bp) = spec;
    Nonlinearity::from_spec(kind, *n, bp).py()
}

fn structure(
    input: &Nl,
    output: &Nl,
    (nb, nf, nk): (usize, usize, usize),
    offset: bool,
    initial_states: usize,
) -> PyResult<HwStructure> {
    let s = HwStructure {
        input: nl(input)?,
        output: nl(output)?,
        nb,
        nf,
        nk,
        offset,
        initial_states,
    };
    s.input.check().py()?;
    s.output.check().py()?;
    Ok(s)
}

/// The search options of both estimators: `tol` for the cost, step and gradient tests.
fn options(max_iter: usize, tol: f64) -> Options {
    let mut opts = Options::default();
    opts.max_iter = max_iter;
    opts.tol_gradient = tol;
    opts.tol_step = tol;
    opts.tol_cost = tol;
    // statistical convergence, as pem's searches
    opts.tol_statistical = 1e-2;
    opts
}

/// Prediction-error estimate from `theta0`; returns a dict (theta, cost, history,
/// iterations, stop, covariance). With `offset`, `theta` ends with the output offset; with
/// `initial_state`, then with each record's initial state (`max(nf, nk + nb - 1)` entries),
/// and the covariance is the marginal one of the model's parameters (the states a
/// nuisance). `covariance` is None where the Gauss-Newton matrix at the estimate is not
/// finite (the search's sensitivities overflow there): the estimate stands without it.
#[pyfunction]
#[pyo3(signature = (records, input, output, nb, nf, nk, theta0, max_iter=100, tol=1e-10, progress=None, offset=false, initial_state=false))]
#[allow(clippy::too_many_arguments)]
pub fn hw_estimate<'py>(
    py: Python<'py>,
    records: Vec<(PyReadonlyArray1<'_, f64>, PyReadonlyArray1<'_, f64>)>,
    input: Nl,
    output: Nl,
    nb: usize,
    nf: usize,
    nk: usize,
    theta0: Vec<f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    offset: bool,
    initial_state: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let states = if initial_state { records.len() } else { 0 };
    let s = structure(&input, &output, (nb, nf, nk), offset, states)?;
    let data: Vec<(Vec<f64>, Vec<f64>)> = records.iter().map(|(u, y)| (vec1(u), vec1(y))).collect();
    let refs: Vec<(&[f64], &[f64])> = data.iter().map(|(u, y)| (&u[..], &y[..])).collect();
    let opts = options(max_iter, tol);
    let sol = run(py, &progress, |obs| {
        hw::estimate(&s, &refs, &theta0, &opts, obs)
    })?;
    let n: usize = data.iter().map(|d| d.0.len()).sum();
    result(py, &sol, n, s.n_model())
}

/// The estimate's dict: the search's items, `theta`, the noise variance (`2 cost / (n - p)`
/// over `n` residuals) and the marginal covariance of the model's `pm` parameters (the
/// leading block of the joint one; None where the Gauss-Newton matrix is not finite: the
/// estimate stands, without).
fn result<'py>(
    py: Python<'py>,
    sol: &Solution,
    n: usize,
    pm: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let var = 2.0 * sol.cost / (n.saturating_sub(sol.theta.len()).max(1)) as f64;
    let cov = covariance(sol.gauss_newton.as_ref(), var, 1e-10)
        .ok()
        .map(|c| c.covariance.as_ref().submatrix(0, 0, pm, pm).to_owned());
    let d = PyDict::new(py);
    search_items(&d, py, sol)?;
    d.set_item("theta", slice_to_numpy(py, &sol.theta))?;
    d.set_item("noise_variance", var)?;
    match cov {
        Some(c) => d.set_item("covariance", mat_to_numpy(py, &c))?,
        None => d.set_item("covariance", py.None())?,
    }
    Ok(d)
}

/// Simulated output and the intermediate signals `(y, w, x)`.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn hw_simulate<'py>(
    py: Python<'py>,
    input: Nl,
    output: Nl,
    nb: usize,
    nf: usize,
    nk: usize,
    theta: Vec<f64>,
    u: PyReadonlyArray1<'_, f64>,
) -> PyResult<Signals<'py>> {
    let s = structure(&input, &output, (nb, nf, nk), false, 0)?;
    if theta.len() != s.n_params() {
        return Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "theta",
            reason: format!("needs {} parameters", s.n_params()),
        }));
    }
    let u = vec1(&u);
    let (y, (w, x)) = py.detach(|| (s.simulate(&theta, &u), s.intermediate(&theta, &u)));
    let y = y.map_err(crate::errors::to_py)?;
    Ok((
        slice_to_numpy(py, &y),
        slice_to_numpy(py, &w),
        slice_to_numpy(py, &x),
    ))
}

fn mimo_structure(
    inputs: &[Nl],
    outputs: &[Nl],
    order: usize,
    feedthrough: bool,
    offsets: bool,
    initial_states: usize,
) -> PyResult<MimoHwStructure> {
    let s = MimoHwStructure {
        inputs: inputs.iter().map(nl).collect::<PyResult<_>>()?,
        outputs: outputs.iter().map(nl).collect::<PyResult<_>>()?,
        order,
        feedthrough,
        offsets,
        initial_states,
    };
    s.check().py()?;
    Ok(s)
}

/// MIMO Hammerstein-Wiener (state-space linear block) prediction-error estimate from
/// `theta0`; returns a dict (theta, cost, history, iterations, stop, noise_variance,
/// covariance). With `offsets`, `theta` ends with one output offset per output; with
/// `initial_state`, then with each record's initial state (`order` entries), and the
/// covariance is the marginal one of the model's parameters (the states a nuisance). The
/// similarity directions of the free `A, B, C` are not determined: the covariance is the
/// pseudo-inverse's, zero along them. `covariance` is None where the Gauss-Newton matrix
/// at the estimate is not finite.
#[pyfunction]
#[pyo3(signature = (records, inputs, outputs, order, feedthrough, theta0, max_iter=100, tol=1e-10, progress=None, offsets=false, initial_state=false))]
#[allow(clippy::too_many_arguments)]
pub fn hw_mimo_estimate<'py>(
    py: Python<'py>,
    records: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>)>,
    inputs: Vec<Nl>,
    outputs: Vec<Nl>,
    order: usize,
    feedthrough: bool,
    theta0: Vec<f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    offsets: bool,
    initial_state: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let states = if initial_state { records.len() } else { 0 };
    let s = mimo_structure(&inputs, &outputs, order, feedthrough, offsets, states)?;
    let refs: Vec<_> = records.iter().map(|(u, y)| (view(u), view(y))).collect();
    let opts = options(max_iter, tol);
    let sol = run(py, &progress, |obs| {
        mimo::estimate_mimo(&s, &refs, &theta0, &opts, obs)
    })?;
    let n: usize = refs.iter().map(|(_, y)| y.nrows() * y.ncols()).sum();
    result(py, &sol, n, s.n_model())
}

/// Simulated outputs `(N, p)` of a MIMO Hammerstein-Wiener model from rest, or from the
/// linear block's state `x0`.
#[pyfunction]
#[pyo3(signature = (inputs, outputs, order, feedthrough, theta, u, x0=None))]
#[allow(clippy::too_many_arguments)]
pub fn hw_mimo_simulate<'py>(
    py: Python<'py>,
    inputs: Vec<Nl>,
    outputs: Vec<Nl>,
    order: usize,
    feedthrough: bool,
    theta: Vec<f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Option<Vec<f64>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let s = mimo_structure(&inputs, &outputs, order, feedthrough, false, 0)?;
    if theta.len() != s.n_params() {
        return Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "theta",
            reason: format!("needs {} parameters", s.n_params()),
        }));
    }
    let uv = view(&u);
    if uv.ncols() != s.inputs.len() {
        return Err(crate::errors::to_py(SysidError::ShapeMismatch {
            what: "u".into(),
            expected: format!("(N, {})", s.inputs.len()),
            got: format!("({}, {})", uv.nrows(), uv.ncols()),
        }));
    }
    let y = match x0 {
        None => py.detach(|| s.simulate(&theta, uv)),
        Some(x0) => py.detach(|| s.simulate_from(&theta, uv, &x0)),
    }
    .map_err(crate::errors::to_py)?;
    Ok(mat_to_numpy(py, &y))
}

/// Registers the functions of this file.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(hw_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(hw_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(hw_mimo_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(hw_mimo_simulate, m)?)?;
    Ok(())
}
