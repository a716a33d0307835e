//! Bindings of `sysid_core::subspace`: weighted SVD, order choice and fits.

use crate::convert::{mat_to_numpy, slice_to_numpy, vec1, view};
use crate::errors::IntoPy;
use crate::hankel::PyHankelFactor;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::subspace::{
    bd_x0, checks, frequency, FitOptions, Identified, Method, Subspace, SubspaceOptions,
    SystemMatrices,
};
use sysid_core::StateSpace;

/// A dict with the system's A, B, C, D.
fn system_dict<'py>(py: Python<'py>, sys: &StateSpace) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (key, m) in [("A", &sys.a), ("B", &sys.b), ("C", &sys.c), ("D", &sys.d)] {
        d.set_item(key, mat_to_numpy(py, m))?;
    }
    Ok(d)
}

/// A fit as a dict: A, B, C, D, K, noise_cov (None without Kalman), Q, R, S, stabilized.
pub fn identified_dict<'py>(py: Python<'py>, id: &Identified) -> PyResult<Bound<'py, PyDict>> {
    let d = system_dict(py, &id.sys)?;
    d.set_item("K", id.k.as_ref().map(|k| mat_to_numpy(py, k)))?;
    d.set_item(
        "noise_cov",
        id.innovation_cov.as_ref().map(|k| mat_to_numpy(py, k)),
    )?;
    for (key, m) in [("Q", &id.q), ("R", &id.r), ("S", &id.s)] {
        d.set_item(key, mat_to_numpy(py, m))?;
    }
    d.set_item("stabilized", id.stabilized)?;
    d.set_item("predictor_stabilized", id.predictor_stabilized)?;
    d.set_item("kalman_regularization", id.kalman_regularization)?;
    d.set_item("kalman_residual", id.kalman_residual)?;
    Ok(d)
}

/// Weighted SVD of a compressed record for one method.
#[pyclass(name = "Subspace", module = "sysid._sysid", frozen)]
pub struct PySubspace {
    inner: Subspace,
}

#[pymethods]
impl PySubspace {
    #[new]
    fn new(py: Python<'_>, factor: &PyHankelFactor, method: &str) -> PyResult<Self> {
        let method: Method = method.parse().py()?;
        let f = factor.inner.clone();
        let inner = py
            .detach(|| Subspace::from_owned(f, &SubspaceOptions::with_method(method)))
            .py()?;
        Ok(Self { inner })
    }

    #[getter]
    fn singular_values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        slice_to_numpy(py, self.inner.singular_values())
    }

    #[getter]
    fn max_order(&self) -> usize {
        self.inner.max_order()
    }

    fn auto_order(&self) -> usize {
        self.inner.auto_order()
    }

    /// Returns a dict with A, B, C, D, K, noise_cov (None without Kalman), Q, R, S, stabilized.
    /// `matrices`: "shift", "states" or "auto" (`SystemMatrices`).
    #[pyo3(signature = (order, feedthrough, kalman, stable, matrices="shift"))]
    fn fit<'py>(
        &self,
        py: Python<'py>,
        order: usize,
        feedthrough: bool,
        kalman: bool,
        stable: bool,
        matrices: &str,
    ) -> PyResult<Bound<'py, PyDict>> {
        let mut opts = FitOptions::default();
        opts.feedthrough = feedthrough;
        opts.kalman = kalman;
        opts.stable = stable;
        opts.matrices = matrices.parse::<SystemMatrices>().py()?;
        let id = py.detach(|| self.inner.fit(order, &opts)).py()?;
        identified_dict(py, &id)
    }
}

/// B, D and an x0 per record by least squares on several records given A and C:
/// `(B, D, [x0, ...])`.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub fn estimate_bd_x0_records<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'_, f64>,
    c: PyReadonlyArray2<'_, f64>,
    us: Vec<PyReadonlyArray2<'_, f64>>,
    ys: Vec<PyReadonlyArray2<'_, f64>>,
    feedthrough: bool,
) -> PyResult<(
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Vec<Bound<'py, PyArray1<f64>>>,
)> {
    if us.len() != ys.len() {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "{} input records and {} output records: give one of each per experiment",
            us.len(),
            ys.len()
        )));
    }
    let (av, cv) = (view(&a), view(&c));
    let recs: Vec<_> = us
        .iter()
        .zip(&ys)
        .map(|(u, y)| (view(u), view(y)))
        .collect();
    let (b, d, x0) = crate::search::detach(py, || {
        bd_x0::estimate_bd_x0_records(av, cv, &recs, feedthrough)
    })?;
    Ok((
        mat_to_numpy(py, &b),
        mat_to_numpy(py, &d),
        x0.iter().map(|x| slice_to_numpy(py, x)).collect(),
    ))
}

/// Frequency-domain subspace identification from `G_k` (rows of `g_re`/`g_im`: the
/// row-major `l x m` response at `omega[k]`, rad/sample): dict with A, B, C, D and
/// singular_values. `order=None` takes the largest log gap.
#[pyfunction]
#[pyo3(signature = (omega, g_re, g_im, n_outputs, horizon, order=None, weights=None, feedthrough="zero"))]
#[allow(clippy::too_many_arguments)]
pub fn frd_subspace<'py>(
    py: Python<'py>,
    omega: PyReadonlyArray1<'_, f64>,
    g_re: PyReadonlyArray2<'_, f64>,
    g_im: PyReadonlyArray2<'_, f64>,
    n_outputs: usize,
    horizon: usize,
    order: Option<usize>,
    weights: Option<PyReadonlyArray1<'_, f64>>,
    feedthrough: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let ft = frequency::Feedthrough::parse(feedthrough).py()?;
    let om = vec1(&omega);
    let w = weights.as_ref().map(vec1);
    let (gr, gi) = (view(&g_re), view(&g_im));
    let l = n_outputs.max(1);
    let m = gr.ncols() / l;
    let to_mats = |g: faer::MatRef<'_, f64>| -> Vec<faer::Mat<f64>> {
        (0..g.nrows())
            .map(|k| faer::Mat::from_fn(l, m, |r, j| g[(k, r * m + j)]))
            .collect()
    };
    let (re, im) = (to_mats(gr), to_mats(gi));
    let id = py
        .detach(|| {
            let rr: Vec<_> = re.iter().map(|x| x.as_ref()).collect();
            let ii: Vec<_> = im.iter().map(|x| x.as_ref()).collect();
            frequency::identify_frd(&om, &rr, &ii, w.as_deref(), order, horizon, ft)
        })
        .py()?;
    let d = system_dict(py, &id.sys)?;
    d.set_item("singular_values", slice_to_numpy(py, &id.singular_values))?;
    Ok(d)
}

/// Frequency-domain subspace identification from one record's input and output DFTs
/// (rows: frequencies): dict with A, B, C, D and singular_values.
#[pyfunction]
#[pyo3(signature = (omega, u_re, u_im, y_re, y_im, horizon, order=None, weights=None, transient=true, feedthrough="zero"))]
#[allow(clippy::too_many_arguments)]
pub fn spectra_subspace<'py>(
    py: Python<'py>,
    omega: PyReadonlyArray1<'_, f64>,
    u_re: PyReadonlyArray2<'_, f64>,
    u_im: PyReadonlyArray2<'_, f64>,
    y_re: PyReadonlyArray2<'_, f64>,
    y_im: PyReadonlyArray2<'_, f64>,
    horizon: usize,
    order: Option<usize>,
    weights: Option<PyReadonlyArray1<'_, f64>>,
    transient: bool,
    feedthrough: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let ft = frequency::Feedthrough::parse(feedthrough).py()?;
    let om = vec1(&omega);
    let w = weights.as_ref().map(vec1);
    let (ur, ui, yr, yi) = (view(&u_re), view(&u_im), view(&y_re), view(&y_im));
    let id = py
        .detach(|| {
            frequency::identify_spectra(
                &om,
                ur,
                ui,
                yr,
                yi,
                w.as_deref(),
                order,
                horizon,
                transient,
                ft,
            )
        })
        .py()?;
    let d = system_dict(py, &id.sys)?;
    d.set_item("singular_values", slice_to_numpy(py, &id.singular_values))?;
    Ok(d)
}

/// The feedback test's regressions on a factor: `(rss_restricted, rss_full, rank_restricted,
/// rank_full, total)` (see `sysid_core::subspace::checks::feedback_regressions`).
#[pyfunction]
#[pyo3(signature = (factor, rtol=1e-9))]
#[allow(clippy::type_complexity)]
pub fn feedback_regressions<'py>(
    py: Python<'py>,
    factor: &PyHankelFactor,
    rtol: f64,
) -> PyResult<(
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    usize,
    usize,
    Bound<'py, PyArray1<f64>>,
)> {
    let f = &factor.inner;
    let r = py.detach(|| checks::feedback_regressions(f, rtol)).py()?;
    Ok((
        slice_to_numpy(py, &r.rss_restricted),
        slice_to_numpy(py, &r.rss_full),
        r.rank_restricted,
        r.rank_full,
        slice_to_numpy(py, &r.total),
    ))
}

/// Persistent-excitation order of the input read from a factor (see
/// `sysid_core::subspace::checks::excitation_order`).
#[pyfunction]
#[pyo3(signature = (factor, needed, tol=1e-9))]
pub fn excitation_order(
    py: Python<'_>,
    factor: &PyHankelFactor,
    needed: usize,
    tol: f64,
) -> PyResult<usize> {
    let f = &factor.inner;
    py.detach(|| checks::excitation_order(f, needed, tol)).py()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(feedback_regressions, m)?)?;
    m.add_function(wrap_pyfunction!(excitation_order, m)?)?;
    m.add_function(wrap_pyfunction!(spectra_subspace, m)?)?;
    m.add_class::<PySubspace>()?;
    m.add_function(wrap_pyfunction!(frd_subspace, m)?)?;
    m.add_function(wrap_pyfunction!(estimate_bd_x0_records, m)?)?;
    Ok(())
}
