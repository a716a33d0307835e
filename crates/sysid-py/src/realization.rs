//! Bindings of `sysid_core::realization` and `sysid_core::lyapunov`.
//!
//! Markov parameters cross the boundary stacked as a 2-D array `(count * l, m)`; the Python
//! layer reshapes them to `(count, l, m)`. Complex values travel as real and imaginary parts.

use crate::convert::{
    mat_to_numpy, slice_to_numpy, state_space as model, state_space_items, view, view_nd,
};
use crate::errors::IntoPy;
use faer::{Mat, MatRef};
use numpy::{PyArray1, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::realization::{
    self as rz, FirOptions, OkidOptions, Realization, RealizationOptions, Regularization,
};
use sysid_core::SysidError;

type Arr<'py> = Bound<'py, PyArray2<f64>>;

fn unstack(h: MatRef<'_, f64>, l: usize) -> PyResult<Vec<Mat<f64>>> {
    if l == 0 || h.nrows() % l != 0 {
        return Err(crate::errors::to_py(SysidError::ShapeMismatch {
            what: "stacked Markov parameters".into(),
            expected: format!("(count * {l}, m)"),
            got: format!("({}, {})", h.nrows(), h.ncols()),
        }));
    }
    Ok((0..h.nrows() / l)
        .map(|k| h.subrows(k * l, l).to_owned())
        .collect())
}

fn stack(h: &[Mat<f64>]) -> Mat<f64> {
    let (l, m) = h.first().map(|x| (x.nrows(), x.ncols())).unwrap_or((0, 0));
    Mat::from_fn(h.len() * l, m, |i, j| h[i / l][(i % l, j)])
}

fn options(
    order: Option<usize>,
    rows: Option<usize>,
    cols: Option<usize>,
    rank_tol: f64,
    max_order: Option<usize>,
) -> RealizationOptions {
    let mut o = RealizationOptions::default();
    o.order = order;
    o.rows = rows;
    o.cols = cols;
    o.rank_tol = rank_tol;
    o.max_order = max_order;
    o
}

fn realization_dict<'py>(py: Python<'py>, r: &Realization) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    state_space_items(&d, py, &r.model)?;
    d.set_item("singular_values", slice_to_numpy(py, &r.singular_values))?;
    d.set_item("rows", r.rows)?;
    d.set_item("cols", r.cols)?;
    Ok(d)
}

/// Ho-Kalman (`method="ho_kalman"`), Kung (`"kung"`) or ERA (`"era"`) realisation.
#[pyfunction]
#[pyo3(signature = (method, markov, noutputs, order=None, rows=None, cols=None, rank_tol=1e-8, max_order=None))]
#[allow(clippy::too_many_arguments)]
pub fn realize<'py>(
    py: Python<'py>,
    method: &str,
    markov: PyReadonlyArray2<'_, f64>,
    noutputs: usize,
    order: Option<usize>,
    rows: Option<usize>,
    cols: Option<usize>,
    rank_tol: f64,
    max_order: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let h = unstack(view(&markov), noutputs)?;
    let opts = options(order, rows, cols, rank_tol, max_order);
    match method.parse::<rz::RealizationMethod>().py()? {
        rz::RealizationMethod::HoKalman => {
            let r = py.detach(|| rz::ho_kalman(&h, &opts)).py()?;
            realization_dict(py, &r)
        }
        rz::RealizationMethod::Kung => {
            let r = py.detach(|| rz::kung(&h, &opts)).py()?;
            realization_dict(py, &r)
        }
        rz::RealizationMethod::Era => {
            let e = py.detach(|| rz::era(&h, &opts)).py()?;
            let d = realization_dict(py, &e.realization)?;
            let re: Vec<f64> = e.eigenvalues.iter().map(|z| z.re).collect();
            let im: Vec<f64> = e.eigenvalues.iter().map(|z| z.im).collect();
            d.set_item("eig_re", slice_to_numpy(py, &re))?;
            d.set_item("eig_im", slice_to_numpy(py, &im))?;
            d.set_item("mac", slice_to_numpy(py, &e.mac))?;
            d.set_item("mpc", slice_to_numpy(py, &e.mpc))?;
            Ok(d)
        }
    }
}

fn views<'a>(
    experiments: &'a [(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>)],
) -> Vec<(MatRef<'a, f64>, MatRef<'a, f64>)> {
    experiments
        .iter()
        .map(|(u, y)| (view_nd(u.as_array()), view_nd(y.as_array())))
        .collect()
}

/// Least-squares FIR estimate; `regularization` is "none" or "tc".
#[pyfunction]
#[pyo3(signature = (experiments, length, feedthrough=false, regularization="tc", hyper=None))]
pub fn fir<'py>(
    py: Python<'py>,
    experiments: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>)>,
    length: usize,
    feedthrough: bool,
    regularization: &str,
    hyper: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opts = FirOptions::default();
    opts.length = length;
    opts.feedthrough = feedthrough;
    opts.regularization = Regularization::from_name(regularization, hyper).py()?;
    let v = views(&experiments);
    let est = crate::search::detach(py, || rz::fir(&v, &opts))?; // Ctrl-C stops it
    let d = PyDict::new(py);
    d.set_item("markov", mat_to_numpy(py, &stack(&est.markov)))?;
    d.set_item("scale", slice_to_numpy(py, &est.scale))?;
    d.set_item("decay", slice_to_numpy(py, &est.decay))?;
    d.set_item("noise_variance", slice_to_numpy(py, &est.noise_variance))?;
    d.set_item("samples", est.samples)?;
    d.set_item("std", mat_to_numpy(py, &stack(&est.std)))?;
    Ok(d)
}

/// OKID: observer and system Markov parameters.
#[pyfunction]
#[pyo3(signature = (experiments, observer_order, count, feedthrough=false, check_direct=false))]
pub fn okid<'py>(
    py: Python<'py>,
    experiments: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>)>,
    observer_order: usize,
    count: usize,
    feedthrough: bool,
    check_direct: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opts = OkidOptions::default();
    opts.observer_order = observer_order;
    opts.count = count;
    opts.feedthrough = feedthrough;
    opts.check_direct = check_direct;
    let v = views(&experiments);
    let est = crate::search::detach(py, || rz::okid(&v, &opts))?;
    let d = PyDict::new(py);
    d.set_item("markov", mat_to_numpy(py, &stack(&est.markov)))?;
    d.set_item(
        "observer_markov",
        mat_to_numpy(py, &stack(&est.observer_markov)),
    )?;
    d.set_item("residual_cov", mat_to_numpy(py, &est.residual_cov))?;
    d.set_item("samples", est.samples)?;
    if let Some(direct) = &est.direct {
        d.set_item("direct", mat_to_numpy(py, &direct.d))?;
        d.set_item(
            "direct_residual_cov",
            mat_to_numpy(py, &direct.residual_cov),
        )?;
    }
    Ok(d)
}

/// Solution X of `X = A X A^T + Q`.
#[pyfunction]
pub fn solve_discrete_lyapunov<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    q: PyReadonlyArray2<'_, f64>,
) -> PyResult<Arr<'py>> {
    let (av, qv) = (view(&a), view(&q));
    let x = py
        .detach(|| sysid_core::lyapunov::solve_discrete_lyapunov(av, qv))
        .py()?;
    Ok(mat_to_numpy(py, &x))
}

/// Controllability and observability gramians `(Wc, Wo)`.
#[pyfunction]
pub fn gramians<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
) -> PyResult<(Arr<'py>, Arr<'py>)> {
    let sys = model(&a, &b, &c, &d)?;
    let (wc, wo) = py.detach(|| rz::gramians(&sys)).py()?;
    Ok((mat_to_numpy(py, &wc), mat_to_numpy(py, &wo)))
}

/// Hankel singular values, decreasing.
#[pyfunction]
pub fn hankel_singular_values<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let sys = model(&a, &b, &c, &d)?;
    let s = py.detach(|| rz::hankel_singular_values(&sys)).py()?;
    Ok(slice_to_numpy(py, &s))
}

/// Balanced truncation to `order` states (all of them if `None`).
#[pyfunction]
#[pyo3(signature = (a, b, c, d, order=None))]
pub fn balanced_truncation<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    b: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    d: PyReadonlyArray2<'_, f64>,
    order: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let sys = model(&a, &b, &c, &d)?;
    let r = order.unwrap_or(sys.n_states());
    let bal = py.detach(|| rz::balanced_truncation(&sys, r)).py()?;
    let out = PyDict::new(py);
    state_space_items(&out, py, &bal.model)?;
    out.set_item(
        "hankel_singular_values",
        slice_to_numpy(py, &bal.hankel_singular_values),
    )?;
    out.set_item("t", mat_to_numpy(py, &bal.t))?;
    out.set_item("t_inv", mat_to_numpy(py, &bal.t_inv))?;
    out.set_item("error_bound", bal.error_bound)?;
    Ok(out)
}

/// Modes of `(A, C)`: frequencies, damping ratios and mode shapes.
#[pyfunction]
pub fn modal_analysis<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    dt: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (av, cv) = (view(&a), view(&c));
    let modes = py.detach(|| rz::modal_analysis(av, cv, dt)).py()?;
    let l = cv.nrows();
    let k = modes.len();
    let col = |f: &dyn Fn(&rz::Mode) -> f64| modes.iter().map(f).collect::<Vec<f64>>();
    let out = PyDict::new(py);
    out.set_item("eig_re", slice_to_numpy(py, &col(&|m| m.eigenvalue.re)))?;
    out.set_item("eig_im", slice_to_numpy(py, &col(&|m| m.eigenvalue.im)))?;
    out.set_item("omega", slice_to_numpy(py, &col(&|m| m.omega)))?;
    out.set_item(
        "frequency_hz",
        slice_to_numpy(py, &col(&|m| m.frequency_hz)),
    )?;
    out.set_item("damping", slice_to_numpy(py, &col(&|m| m.damping)))?;
    out.set_item(
        "shape_re",
        mat_to_numpy(py, &Mat::from_fn(k, l, |i, j| modes[i].shape[j].re)),
    )?;
    out.set_item(
        "shape_im",
        mat_to_numpy(py, &Mat::from_fn(k, l, |i, j| modes[i].shape[j].im)),
    )?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(realize, m)?)?;
    m.add_function(wrap_pyfunction!(fir, m)?)?;
    m.add_function(wrap_pyfunction!(okid, m)?)?;
    m.add_function(wrap_pyfunction!(solve_discrete_lyapunov, m)?)?;
    m.add_function(wrap_pyfunction!(gramians, m)?)?;
    m.add_function(wrap_pyfunction!(hankel_singular_values, m)?)?;
    m.add_function(wrap_pyfunction!(balanced_truncation, m)?)?;
    m.add_function(wrap_pyfunction!(modal_analysis, m)?)?;
    Ok(())
}
