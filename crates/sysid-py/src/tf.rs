//! Bindings of `sysid_core::tf`: the SRIVC Gram matrix and the frequency-domain fit.

use crate::convert::{mat_to_numpy, slice_to_numpy, view};
use crate::search::{run, solution_items};
use faer::c64;
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::optim::Options;
use sysid_core::tf::{self, Rational};

/// `sum_{t >= skip} w_t w_t^T`, `w_t = cw x_t + dw v_t`, `x_{t+1} = ad x_t + bd v_t` (GIL
/// released).
#[pyfunction]
#[pyo3(signature = (ad, bd, cw, dw, v, skip=0))]
pub fn tf_filtered_gram<'py>(
    py: Python<'py>,
    ad: PyReadonlyArray2<'py, f64>,
    bd: PyReadonlyArray2<'py, f64>,
    cw: PyReadonlyArray2<'py, f64>,
    dw: PyReadonlyArray2<'py, f64>,
    v: PyReadonlyArray2<'py, f64>,
    skip: usize,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let (ad, bd, cw, dw, v) = (view(&ad), view(&bd), view(&cw), view(&dw), view(&v));
    let g = crate::search::detach(py, || tf::filtered_gram(ad, bd, cw, dw, v, skip))?;
    Ok(mat_to_numpy(py, &g))
}

fn complex(re: &PyReadonlyArray1<'_, f64>, im: &PyReadonlyArray1<'_, f64>) -> Vec<c64> {
    re.as_array()
        .iter()
        .zip(im.as_array().iter())
        .map(|(&a, &b)| c64::new(a, b))
        .collect()
}

/// Weighted nonlinear least-squares fit of `N(x)/D(x) exp(-w tau)` to `h` (complex arrays as
/// `(re, im)` pairs); returns the search report, `theta`, `covariance`, `noise_variance`.
/// `stable`: keep the denominator's roots stable (the start must be).
#[pyfunction]
#[pyo3(signature = (x, w, h, weight, lead, den, num, theta0, *, fixed=None, lower=None,
    upper=None, noise_variance=None, max_iter=100, tol=1e-10, progress=None, stable=false))]
#[allow(clippy::too_many_arguments)]
pub fn tf_fit_frequency<'py>(
    py: Python<'py>,
    x: (PyReadonlyArray1<'py, f64>, PyReadonlyArray1<'py, f64>),
    w: (PyReadonlyArray1<'py, f64>, PyReadonlyArray1<'py, f64>),
    h: (PyReadonlyArray1<'py, f64>, PyReadonlyArray1<'py, f64>),
    weight: Vec<f64>,
    lead: usize,
    den: Vec<usize>,
    num: Vec<usize>,
    theta0: Vec<f64>,
    fixed: Option<Vec<bool>>,
    lower: Option<Vec<f64>>,
    upper: Option<Vec<f64>>,
    noise_variance: Option<f64>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    stable: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let model = Rational {
        x: complex(&x.0, &x.1),
        w: complex(&w.0, &w.1),
        lead,
        den,
        num,
        stable,
    };
    let h = complex(&h.0, &h.1);
    let mut o = Options::default();
    o.max_iter = max_iter;
    o.tol_cost = tol;
    o.tol_step = tol;
    o.tol_gradient = tol;
    o.fixed = fixed;
    o.lower = lower;
    o.upper = upper;
    let fit = run(py, &progress, |obs| {
        tf::fit_frequency(&model, &h, &weight, &theta0, &o, noise_variance, obs)
    })?;
    let out = PyDict::new(py);
    out.set_item("theta", slice_to_numpy(py, &fit.solution.theta))?;
    out.set_item("noise_variance", fit.noise_variance)?;
    solution_items(&out, py, &fit.solution, &fit.covariance)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(tf_filtered_gram, m)?)?;
    m.add_function(wrap_pyfunction!(tf_fit_frequency, m)?)?;
    Ok(())
}
