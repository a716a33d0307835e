//! Bindings of simulation, prediction and the Kalman gain.

use crate::convert::{mat_to_numpy, state_space as model, vec1, view};
use crate::errors::IntoPy;
use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use sysid_core::model::initial_state;
use sysid_core::{riccati, simulate as sim};

/// Simulates `x(t+1) = A x + B u, y = C x + D u`; returns `(N, l)`.
#[pyfunction]
#[pyo3(signature = (a, b, c, d, u, x0=None))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
    u: PyReadonlyArray2<'_, f64>,
    x0: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let sys = model(&a, &b, &c, &d)?;
    let x0 = x0.as_ref().map(vec1);
    let uv = view(&u);
    let y = py.detach(|| sim::simulate(&sys, uv, x0.as_deref())).py()?;
    Ok(mat_to_numpy(py, &y))
}

/// `horizon`-step-ahead Kalman predictions; returns `(N, l)`.
#[pyfunction]
#[pyo3(signature = (a, b, c, d, k, u, y, x0=None, horizon=1))]
#[allow(clippy::too_many_arguments)]
pub fn predict<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
    k: PyReadonlyArray2<'_, f64>,
    u: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    x0: Option<PyReadonlyArray1<'_, f64>>,
    horizon: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let sys = model(&a, &b, &c, &d)?;
    let x0 = x0.as_ref().map(vec1);
    let (kv, uv, yv) = (view(&k), view(&u), view(&y));
    let out = py
        .detach(|| sim::predict(&sys, kv, uv, yv, x0.as_deref(), horizon))
        .py()?;
    Ok(mat_to_numpy(py, &out))
}

/// Simulation errors `y - ys` with the initial state and per-output offsets (or lines)
/// fitted by least squares (the initial state with the prior factor `prior`, when given);
/// `None` when the model diverges on these data.
#[pyfunction]
#[pyo3(signature = (a, c, y, ys, trend=false, prior=None))]
pub fn fitted_errors<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    y: PyReadonlyArray2<'_, f64>,
    ys: PyReadonlyArray2<'_, f64>,
    trend: bool,
    prior: Option<PyReadonlyArray2<'_, f64>>,
) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
    let (av, cv, yv, sv) = (view(&a), view(&c), view(&y), view(&ys));
    let pv = prior.as_ref().map(|p| view(p));
    // GIL released, Ctrl-C seen within milliseconds (the core checks between blocks)
    let e = crate::search::detach(py, || {
        initial_state::fitted_errors(av, cv, yv, sv, trend, pv)
    })?;
    Ok(e.map(|e| mat_to_numpy(py, &e)))
}

/// Stabilising solution of the predictor Riccati equation: `(K, P, innovation_cov)`.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn kalman_gain<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    q: PyReadonlyArray2<'_, f64>,
    r: PyReadonlyArray2<'_, f64>,
    s: PyReadonlyArray2<'_, f64>,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
)> {
    let sol = riccati::kalman_gain(view(&a), view(&c), view(&q), view(&r), view(&s)).py()?;
    Ok((
        mat_to_numpy(py, &sol.k),
        mat_to_numpy(py, &sol.p),
        mat_to_numpy(py, &sol.innovation_cov),
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(predict, m)?)?;
    m.add_function(wrap_pyfunction!(kalman_gain, m)?)?;
    m.add_function(wrap_pyfunction!(fitted_errors, m)?)?;
    Ok(())
}
