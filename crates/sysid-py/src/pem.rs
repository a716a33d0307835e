//! Bindings of the prediction-error refinement (`sysid_core::pem`).

use crate::convert::{
    mat_to_numpy, slice_to_numpy, state_space as model, state_space_items, vec1, view,
};
use crate::errors::IntoPy;
use crate::search::{run, solution_items};
use faer::MatRef;
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::optim::Regularization;
use sysid_core::pem::{self, FrequencyOptions, InitialState, Lines, PemOptions};

type Experiments<'py> = Vec<(PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, f64>)>;

/// The initial-state choices: `None` (zero), `"estimate"`, `"zero"` or an array, per entry.
fn x0_modes(list: Option<Vec<Option<Bound<'_, PyAny>>>>) -> PyResult<Vec<InitialState>> {
    let Some(list) = list else {
        return Ok(vec![InitialState::Estimate]);
    };
    let mut modes = Vec::new();
    for item in list {
        modes.push(match item {
            None => InitialState::Zero,
            Some(obj) => match obj.extract::<String>() {
                Ok(s) => s.parse().py()?,
                Err(_) => InitialState::Given(vec1(&obj.extract::<PyReadonlyArray1<'_, f64>>()?)),
            },
        });
    }
    Ok(modes)
}

/// The options every pem binding shares.
fn options(
    focus: &str,
    estimate_d: bool,
    estimate_k: bool,
    x0: Option<Vec<Option<Bound<'_, PyAny>>>>,
    reweight: bool,
    enforce_stability: Option<bool>,
) -> PyResult<PemOptions> {
    let mut o = PemOptions::default();
    o.focus = focus.parse().py()?;
    o.estimate_d = estimate_d;
    o.estimate_k = estimate_k;
    o.reweight = reweight;
    o.enforce_stability = enforce_stability;
    o.x0 = x0_modes(x0)?;
    Ok(o)
}

fn views<'a>(experiments: &'a Experiments<'_>) -> Vec<(MatRef<'a, f64>, MatRef<'a, f64>)> {
    experiments
        .iter()
        .map(|(u, y)| (view(u), view(y)))
        .collect()
}

/// Refines a state-space model by prediction-error minimisation; returns a dict.
#[pyfunction]
#[pyo3(signature = (a, b, c, d, k, experiments, *, focus="prediction", estimate_d=false,
    estimate_k=true, x0=None, reweight=true, local_coordinates=true, enforce_stability=None,
    max_iter=50, tol_cost=1e-6, tol_step=1e-9, tol_gradient=1e-9, reg_lambda=0.0, reg_r=None,
    reg_nominal=None, progress=None, geodesic=false))]
#[allow(clippy::too_many_arguments)]
pub fn pem_refine<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
    k: Option<PyReadonlyArray2<'_, f64>>,
    experiments: Experiments<'py>,
    focus: &str,
    estimate_d: bool,
    estimate_k: bool,
    x0: Option<Vec<Option<Bound<'py, PyAny>>>>,
    reweight: bool,
    local_coordinates: bool,
    enforce_stability: Option<bool>,
    max_iter: usize,
    tol_cost: f64,
    tol_step: f64,
    tol_gradient: f64,
    reg_lambda: f64,
    reg_r: Option<PyReadonlyArray2<'_, f64>>,
    reg_nominal: Option<PyReadonlyArray1<'_, f64>>,
    progress: Option<Py<PyAny>>,
    geodesic: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let sys = model(&a, &b, &c, &d)?;
    let mut o = options(
        focus,
        estimate_d,
        estimate_k,
        x0,
        reweight,
        enforce_stability,
    )?;
    o.local_coordinates = local_coordinates;
    o.optim.max_iter = max_iter;
    o.optim.tol_cost = tol_cost;
    o.optim.tol_step = tol_step;
    o.optim.tol_gradient = tol_gradient;
    o.optim.geodesic = geodesic;
    if reg_lambda != 0.0 {
        o.optim.regularization = Some(Regularization {
            lambda: reg_lambda,
            r: reg_r.as_ref().map(|r| view(r).to_owned()),
            nominal: reg_nominal.as_ref().map(vec1),
        });
    }
    let kv = k.as_ref().map(|k| view(k));
    let exps = views(&experiments);
    let r = run(py, &progress, |obs| pem::pem(&sys, kv, &exps, &o, obs))?;
    let out = PyDict::new(py);
    state_space_items(&out, py, &r.sys)?;
    out.set_item("k", mat_to_numpy(py, &r.k))?;
    let x0s: Vec<_> = r.x0.iter().map(|v| slice_to_numpy(py, v)).collect();
    out.set_item("x0", x0s)?;
    out.set_item(
        "innovation_covariance",
        mat_to_numpy(py, &r.innovation_covariance),
    )?;
    out.set_item("theta", slice_to_numpy(py, &r.theta))?;
    out.set_item("loss_history", r.loss_history.clone())?;
    out.set_item("spectral_radius", r.spectral_radius)?;
    solution_items(&out, py, &r.solution, &r.covariance)?;
    out.set_item("gauss_newton", mat_to_numpy(py, &r.solution.gauss_newton))?;
    out.set_item("n_samples", r.n_samples)?;
    Ok(out)
}

/// The criterion `pem_refine` would start from (initial states fitted), without a search.
#[pyfunction]
#[pyo3(signature = (a, b, c, d, k, experiments, *, focus="prediction", estimate_d=false,
    estimate_k=true, x0=None, reweight=true, enforce_stability=None))]
#[allow(clippy::too_many_arguments)]
pub fn pem_criterion<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
    k: Option<PyReadonlyArray2<'_, f64>>,
    experiments: Experiments<'py>,
    focus: &str,
    estimate_d: bool,
    estimate_k: bool,
    x0: Option<Vec<Option<Bound<'py, PyAny>>>>,
    reweight: bool,
    enforce_stability: Option<bool>,
) -> PyResult<f64> {
    let sys = model(&a, &b, &c, &d)?;
    let o = options(
        focus,
        estimate_d,
        estimate_k,
        x0,
        reweight,
        enforce_stability,
    )?;
    let kv = k.as_ref().map(|k| view(k));
    let exps = views(&experiments);
    crate::search::detach(py, || pem::criterion(&exps, &sys, kv, &o))
}

/// Refines a state-space model on the excited lines of periodic data (frequency domain);
/// returns a dict.
#[pyfunction]
#[pyo3(signature = (a, b, c, d, omega, re, im, weight, *, estimate_d=false, modal_chart=true,
    max_iter=50, tol_cost=1e-6, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn pem_frequency_refine<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
    omega: PyReadonlyArray1<'_, f64>,
    re: PyReadonlyArray2<'_, f64>,
    im: PyReadonlyArray2<'_, f64>,
    weight: PyReadonlyArray2<'_, f64>,
    estimate_d: bool,
    modal_chart: bool,
    max_iter: usize,
    tol_cost: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let sys = model(&a, &b, &c, &d)?;
    let mut o = FrequencyOptions::default();
    o.estimate_d = estimate_d;
    o.modal_chart = modal_chart;
    o.optim.max_iter = max_iter;
    o.optim.tol_cost = tol_cost;
    let omega = vec1(&omega);
    let lines = Lines {
        omega: &omega,
        re: view(&re),
        im: view(&im),
        weight: view(&weight),
    };
    let r = run(py, &progress, |obs| {
        pem::pem_frequency(&sys, &lines, &o, obs)
    })?;
    let out = PyDict::new(py);
    state_space_items(&out, py, &r.sys)?;
    out.set_item("theta", slice_to_numpy(py, &r.theta))?;
    out.set_item("spectral_radius", r.spectral_radius)?;
    out.set_item("n_residuals", r.n_residuals)?;
    out.set_item("residual_scale", r.residual_scale)?;
    out.set_item("modal", r.modal)?;
    solution_items(&out, py, &r.solution, &r.covariance)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pem_refine, m)?)?;
    m.add_function(wrap_pyfunction!(pem_criterion, m)?)?;
    m.add_function(wrap_pyfunction!(pem_frequency_refine, m)?)?;
    Ok(())
}
