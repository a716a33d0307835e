//! Bindings of `sysid_core::polynomial`: ARX by streaming QR, order search, filtering and the
//! prediction-error estimate of single-output polynomial structures.

use crate::convert::{mat_to_numpy, slice_to_numpy, view_nd};
use crate::errors::IntoPy;
use crate::search::{run, search_items};
use numpy::{PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use sysid_core::optim::Options;
use sysid_core::polynomial::arx::{ArxCompressor, ArxOrders};
use sysid_core::polynomial::filter;
use sysid_core::polynomial::initial::{InitialCondition, InitialState};
use sysid_core::polynomial::iv::{self, IvRecord};
use sysid_core::polynomial::pem::{self, MisoOrders};

type Experiments<'a> = Vec<(PyReadonlyArray2<'a, f64>, PyReadonlyArray2<'a, f64>)>;

/// Least-squares ARX of every output; `reg_factor` M gives the penalty `lam |M theta|^2` of
/// each output's equation.
#[pyfunction]
#[pyo3(signature = (experiments, na, nb, nk, lam=0.0, reg_factor=None))]
pub fn arx_fit<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    na: Vec<Vec<usize>>,
    nb: Vec<Vec<usize>>,
    nk: Vec<Vec<usize>>,
    lam: f64,
    reg_factor: Option<PyReadonlyArray2<'_, f64>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let max_lag = orders_max_lag(&na, &nb, &nk);
    let orders = ArxOrders { na, nb, nk };
    let m = reg_factor.as_ref().map(|r| view_nd(r.as_array()));
    let ny = experiments.first().map_or(0, |e| e.1.as_array().ncols());
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y)| (view_nd(u.as_array()), view_nd(y.as_array())))
        .collect();
    let fits = py
        .detach(|| -> sysid_core::Result<Vec<_>> {
            let c = compress_core(&views, max_lag)?;
            let r = c.factor();
            (0..ny)
                .map(|i| c.solve_with_factor(r.as_ref(), i, &orders, lam, m))
                .collect()
        })
        .py()?;
    fits.iter()
        .map(|f| {
            let d = PyDict::new(py);
            d.set_item("a", f.a.clone())?;
            d.set_item("b", f.b.clone())?;
            d.set_item("theta", slice_to_numpy(py, &f.theta))?;
            d.set_item("loss", f.loss)?;
            d.set_item("unscaled_cov", mat_to_numpy(py, &f.unscaled_cov))?;
            d.set_item("n_rows", f.n_rows)?;
            Ok(d)
        })
        .collect()
}

/// The largest lag a structure needs: `na`, and `nk + nb - 1` of every channel (at least 1).
fn orders_max_lag(na: &[Vec<usize>], nb: &[Vec<usize>], nk: &[Vec<usize>]) -> usize {
    na.iter()
        .flatten()
        .copied()
        .chain(
            nb.iter()
                .flatten()
                .zip(nk.iter().flatten())
                .map(|(b, k)| b.saturating_add(*k).saturating_sub(1)),
        )
        .max()
        .unwrap_or(0)
        .max(1)
}

/// Per output, the compressed regression `[[R11, r], [0, rho]]` (`(p+1) x (p+1)`, upper
/// triangular) of `[Phi_i y_i]` and the number of regression rows: the summaries a regularised
/// ARX fit and its marginal likelihood are computed from.
#[pyfunction]
pub fn arx_summary<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    na: Vec<Vec<usize>>,
    nb: Vec<Vec<usize>>,
    nk: Vec<Vec<usize>>,
) -> PyResult<Vec<(Bound<'py, numpy::PyArray2<f64>>, usize)>> {
    let max_lag = orders_max_lag(&na, &nb, &nk);
    let orders = ArxOrders { na, nb, nk };
    let ny = experiments.first().map_or(0, |e| e.1.as_array().ncols());
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y)| (view_nd(u.as_array()), view_nd(y.as_array())))
        .collect();
    let (sums, rows) = py
        .detach(|| -> sysid_core::Result<_> {
            let c = compress_core(&views, max_lag)?;
            let r = c.factor();
            let s = (0..ny)
                .map(|i| c.output_summary(r.as_ref(), i, &orders))
                .collect::<sysid_core::Result<Vec<_>>>()?;
            Ok((s, c.n_rows()))
        })
        .py()?;
    Ok(sums.iter().map(|s| (mat_to_numpy(py, s), rows)).collect())
}

/// Simulation (`y = None`) or `horizon`-step prediction of a coupled MIMO ARX model from its
/// `A` coefficients `a[i][k]` and input part `w` (`N x ny`).
#[pyfunction]
#[pyo3(signature = (a, w, y=None, horizon=1))]
pub fn arx_matrix_filter<'py>(
    py: Python<'py>,
    a: Vec<Vec<Vec<f64>>>,
    w: PyReadonlyArray2<'_, f64>,
    y: Option<PyReadonlyArray2<'_, f64>>,
    horizon: usize,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let wv = view_nd(w.as_array());
    let yv = y.as_ref().map(|y| view_nd(y.as_array()));
    let out = py
        .detach(|| filter::arx_matrix_filter(&a, wv, yv.map(|y| (y, horizon))))
        .py()?;
    Ok(mat_to_numpy(py, &out))
}

fn compress_core(
    experiments: &[(faer::MatRef<'_, f64>, faer::MatRef<'_, f64>)],
    max_lag: usize,
) -> sysid_core::Result<ArxCompressor> {
    let (nu, ny) = experiments
        .first()
        .map(|(u, y)| (u.ncols(), y.ncols()))
        .unwrap_or((0, 0));
    let mut c = ArxCompressor::new(nu, ny, max_lag)?;
    for (u, y) in experiments {
        c.push(*u, *y)?;
    }
    Ok(c)
}

/// Loss of every ARX structure in the ranges from one compression: rows `[na, nb, nk, loss, np]`.
#[pyfunction]
pub fn arx_struc<'py>(
    py: Python<'py>,
    experiments: Experiments<'_>,
    na_range: Vec<usize>,
    nb_range: Vec<usize>,
    nk_range: Vec<usize>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let max_lag = na_range
        .iter()
        .copied()
        .chain(nb_range.iter().flat_map(|b| {
            nk_range
                .iter()
                .map(move |k| b.saturating_add(*k).saturating_sub(1))
        }))
        .max()
        .unwrap_or(1)
        .max(1);
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y)| (view_nd(u.as_array()), view_nd(y.as_array())))
        .collect();
    let rows = crate::search::detach(py, || {
        compress_core(&views, max_lag)?.arxstruc(&na_range, &nb_range, &nk_range)
    })?;
    let m = faer::Mat::from_fn(rows.len(), 5, |i, j| rows[i][j]);
    Ok(mat_to_numpy(py, &m))
}

/// `B(q)/A(q) x` from rest (A monic).
#[pyfunction]
pub fn poly_filter<'py>(
    py: Python<'py>,
    b: Vec<f64>,
    a: Vec<f64>,
    x: PyReadonlyArray1<'_, f64>,
) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
    let xs = x.as_slice()?.to_vec();
    let y = py.detach(|| filter::filter(&b, &a, &xs));
    Ok(slice_to_numpy(py, &y))
}

type MisoExperiments<'a> = Vec<(PyReadonlyArray1<'a, f64>, PyReadonlyArray2<'a, f64>)>;

/// The outputs (copied: they may be strided) of `experiments`.
fn outputs(experiments: &MisoExperiments<'_>) -> Vec<Vec<f64>> {
    experiments
        .iter()
        .map(|(y, _)| y.as_array().to_vec())
        .collect()
}

/// `(y, u)` views of `experiments`, the outputs from [`outputs`].
fn miso_views<'a>(
    ys: &'a [Vec<f64>],
    experiments: &'a MisoExperiments<'_>,
) -> Vec<(&'a [f64], faer::MatRef<'a, f64>)> {
    ys.iter()
        .zip(experiments)
        .map(|(y, (_, u))| (y.as_slice(), view_nd(u.as_array())))
        .collect()
}

/// Each experiment's initial state as `{"input": [h_j..], "noise": h_e}`.
fn states_list<'py>(py: Python<'py>, states: &[InitialState]) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for s in states {
        let d = PyDict::new(py);
        let inputs: Vec<_> = s.input.iter().map(|h| slice_to_numpy(py, h)).collect();
        d.set_item("input", inputs)?;
        d.set_item("noise", slice_to_numpy(py, &s.noise))?;
        out.append(d)?;
    }
    Ok(out)
}

/// Prediction-error estimate of one output: `A y = sum B_j/F_j u_j(t-nk_j) + C/D e`, from
/// one or several experiments `(y, u)` (the cost summed over them, each from rest or, by
/// `initial_condition` `"estimate"` or `"auto"`, from its estimated initial state).
/// The initial condition, orders and search options of one output's polynomial search
/// (`[na, nc, nd]`, then `nb`, `nf`, `nk` per input).
fn miso_setup(
    [na, nc, nd]: [usize; 3],
    nb: Vec<usize>,
    nf: Vec<usize>,
    nk: Vec<usize>,
    max_iter: usize,
    tol: f64,
    initial_condition: &str,
) -> PyResult<(InitialCondition, MisoOrders, Options)> {
    let ic = InitialCondition::parse(initial_condition).py()?;
    let orders = MisoOrders {
        na,
        nb,
        nc,
        nd,
        nf,
        nk,
    };
    let mut opts = Options::default();
    opts.max_iter = max_iter;
    opts.tol_gradient = tol;
    opts.tol_step = tol;
    Ok((ic, orders, opts))
}

#[pyfunction]
#[pyo3(signature = (experiments, na, nb, nc, nd, nf, nk, theta0=None, max_iter=100, tol=1e-9, progress=None, initial_condition="zero"))]
#[allow(clippy::too_many_arguments)]
pub fn polynomial_pem<'py>(
    py: Python<'py>,
    experiments: MisoExperiments<'_>,
    na: usize,
    nb: Vec<usize>,
    nc: usize,
    nd: usize,
    nf: Vec<usize>,
    nk: Vec<usize>,
    theta0: Option<Vec<f64>>,
    max_iter: usize,
    tol: f64,
    progress: Option<Py<PyAny>>,
    initial_condition: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let (ic, orders, opts) =
        miso_setup([na, nc, nd], nb, nf, nk, max_iter, tol, initial_condition)?;
    let ys = outputs(&experiments);
    let exps = miso_views(&ys, &experiments);
    let est = run(py, &progress, |obs| {
        pem::estimate_with(&exps, orders, theta0.as_deref(), ic, &opts, obs)
    })?;
    let d = PyDict::new(py);
    search_items(&d, py, &est.solution)?;
    d.set_item("theta", slice_to_numpy(py, &est.solution.theta))?;
    d.set_item("theta0", slice_to_numpy(py, &est.theta0))?;
    d.set_item("noise_variance", est.noise_variance)?;
    d.set_item("covariance", mat_to_numpy(py, &est.covariance))?;
    d.set_item("initial_condition", est.initial.name())?;
    d.set_item("initial_states", states_list(py, &est.initial_states)?)?;
    d.set_item("auto_costs", est.auto_costs)?;
    Ok(d)
}

/// One output's search from `theta` with `F` free to leave the unit circle
/// (`sysid_core::polynomial::pem::free_search`): the search's items, `theta` and `kept_cost`
/// (the criterion at the start).
#[pyfunction]
#[pyo3(signature = (experiments, na, nb, nc, nd, nf, nk, theta, initial_condition="zero", max_iter=100, tol=1e-9))]
#[allow(clippy::too_many_arguments)]
pub fn polynomial_free_search<'py>(
    py: Python<'py>,
    experiments: MisoExperiments<'_>,
    na: usize,
    nb: Vec<usize>,
    nc: usize,
    nd: usize,
    nf: Vec<usize>,
    nk: Vec<usize>,
    theta: Vec<f64>,
    initial_condition: &str,
    max_iter: usize,
    tol: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (ic, orders, opts) =
        miso_setup([na, nc, nd], nb, nf, nk, max_iter, tol, initial_condition)?;
    let ys = outputs(&experiments);
    let exps = miso_views(&ys, &experiments);
    let (kept, sol) = run(py, &None, |obs| {
        pem::free_search(&exps, orders, &theta, ic, &opts, obs)
    })?;
    let d = PyDict::new(py);
    search_items(&d, py, &sol)?;
    d.set_item("kept_cost", kept)?;
    d.set_item("theta", slice_to_numpy(py, &sol.theta))?;
    Ok(d)
}

/// The name of an `initial_condition` (`"auto"`, `"zero"`, `"estimate"`), checked by the core
/// (a `DataError` naming the allowed values otherwise).
#[pyfunction]
pub fn initial_condition_name(name: &str) -> PyResult<&'static str> {
    InitialCondition::parse(name).map(|ic| ic.name()).py()
}

/// The prediction errors of one output's polynomial model at `theta`, every experiment's after
/// another, from rest (`"zero"`) or from each experiment's least-squares initial state
/// (`"estimate"`); and those initial states.
#[pyfunction]
#[pyo3(signature = (experiments, na, nb, nc, nd, nf, nk, theta, initial_condition="zero"))]
#[allow(clippy::too_many_arguments)]
pub fn polynomial_residuals<'py>(
    py: Python<'py>,
    experiments: MisoExperiments<'_>,
    na: usize,
    nb: Vec<usize>,
    nc: usize,
    nd: usize,
    nf: Vec<usize>,
    nk: Vec<usize>,
    theta: Vec<f64>,
    initial_condition: &str,
) -> PyResult<(Bound<'py, numpy::PyArray1<f64>>, Bound<'py, PyList>)> {
    let ic = InitialCondition::parse(initial_condition).py()?;
    if ic == InitialCondition::Auto {
        return Err(sysid_core::SysidError::InvalidArgument {
            name: "initial_condition",
            reason: "'auto' chooses during a search: give 'zero' or 'estimate'".into(),
        })
        .py();
    }
    let ys = outputs(&experiments);
    let exps = miso_views(&ys, &experiments);
    let orders = MisoOrders {
        na,
        nb,
        nc,
        nd,
        nf,
        nk,
    };
    let (e, states) = py
        .detach(|| -> sysid_core::Result<_> {
            let mut prob = pem::MisoProblem::new_multi(&exps, orders.clone())?;
            if theta.len() != orders.n_params() {
                return Err(sysid_core::SysidError::InvalidArgument {
                    name: "theta",
                    reason: format!(
                        "has {} entries but the structure has {}",
                        theta.len(),
                        orders.n_params()
                    ),
                });
            }
            prob.estimate_initial(ic == InitialCondition::Estimate);
            Ok((prob.residuals(&theta), prob.initial_states(&theta)))
        })
        .py()?;
    Ok((slice_to_numpy(py, &e), states_list(py, &states)?))
}

type IvExperiments<'a> = Vec<(
    PyReadonlyArray2<'a, f64>,
    PyReadonlyArray2<'a, f64>,
    Option<PyReadonlyArray2<'a, f64>>,
)>;

/// IV4 estimate of a MIMO ARX structure from experiments `(u, y, reference or None)`: per
/// output a dict with `theta` (`[a_i1.., .., b_i1.., ..]`), `covariance`, `noise_variance`.
#[pyfunction]
pub fn iv4<'py>(
    py: Python<'py>,
    experiments: IvExperiments<'_>,
    na: Vec<Vec<usize>>,
    nb: Vec<Vec<usize>>,
    nk: Vec<Vec<usize>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let recs = iv_records(&experiments);
    let orders = ArxOrders { na, nb, nk };
    let fit = py.detach(|| iv::iv4_multi(&recs, &orders)).py()?;
    fit_dicts(py, &fit)
}

/// IV estimate with given instruments (MATLAB's `ivx`) from experiments `(u, y, reference
/// or None)` and one instrument array `x` (N x ny) per experiment: per output a dict as
/// [`iv4`]'s.
#[pyfunction]
pub fn ivx<'py>(
    py: Python<'py>,
    experiments: IvExperiments<'_>,
    x: Vec<PyReadonlyArray2<'_, f64>>,
    na: Vec<Vec<usize>>,
    nb: Vec<Vec<usize>>,
    nk: Vec<Vec<usize>>,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let recs = iv_records(&experiments);
    let xs: Vec<_> = x.iter().map(|a| view_nd(a.as_array())).collect();
    let orders = ArxOrders { na, nb, nk };
    let fit = py.detach(|| iv::ivx_multi(&recs, &xs, &orders)).py()?;
    fit_dicts(py, &fit)
}

/// The core's view of the experiments `(u, y, reference or None)`.
fn iv_records<'a>(experiments: &'a IvExperiments<'_>) -> Vec<IvRecord<'a>> {
    experiments
        .iter()
        .map(|(u, y, r)| IvRecord {
            u: view_nd(u.as_array()),
            y: view_nd(y.as_array()),
            r: r.as_ref().map(|r| view_nd(r.as_array())),
        })
        .collect()
}

/// Per output, `theta`, `covariance` and `noise_variance` of an IV fit.
fn fit_dicts<'py>(py: Python<'py>, fit: &iv::Iv4Fit) -> PyResult<Vec<Bound<'py, PyDict>>> {
    (0..fit.theta.len())
        .map(|i| {
            let d = PyDict::new(py);
            d.set_item("theta", slice_to_numpy(py, &fit.theta[i]))?;
            d.set_item("covariance", mat_to_numpy(py, &fit.covariance[i]))?;
            d.set_item("noise_variance", fit.noise_variance[i])?;
            Ok(d)
        })
        .collect()
}

/// `-2 log p(y) - N log 2 pi` of a kernel-prior regression from its summary, with the
/// gradient over `dprior` and the derivative with respect to `sigma2`
/// (`sysid_core::polynomial::regul::marginal_likelihood`).
#[pyfunction]
#[pyo3(signature = (summary, n_rows, prior, dprior, sigma2, gradient=true))]
pub fn arx_marginal_likelihood(
    py: Python<'_>,
    summary: PyReadonlyArray2<'_, f64>,
    n_rows: usize,
    prior: PyReadonlyArray2<'_, f64>,
    dprior: Vec<PyReadonlyArray2<'_, f64>>,
    sigma2: f64,
    gradient: bool,
) -> PyResult<(f64, Vec<f64>, f64)> {
    let s = view_nd(summary.as_array());
    let pr = view_nd(prior.as_array());
    let ds: Vec<_> = dprior.iter().map(|d| view_nd(d.as_array())).collect();
    py.detach(|| {
        sysid_core::polynomial::regul::marginal_likelihood(s, n_rows, pr, &ds, sigma2, gradient)
    })
    .py()
}

/// `(theta, covariance, rss)` of [`arx_regularized_solve`].
type Solved<'py> = (
    Bound<'py, numpy::PyArray1<f64>>,
    Bound<'py, numpy::PyArray2<f64>>,
    f64,
);

/// The regularised (posterior) solution `(theta, covariance, rss)` of a summarised
/// regression with penalty `lam theta^T prior^-1 theta`
/// (`sysid_core::polynomial::regul::regularized_solve`).
#[pyfunction]
pub fn arx_regularized_solve<'py>(
    py: Python<'py>,
    summary: PyReadonlyArray2<'_, f64>,
    prior: PyReadonlyArray2<'_, f64>,
    lam: f64,
) -> PyResult<Solved<'py>> {
    let s = view_nd(summary.as_array());
    let pr = view_nd(prior.as_array());
    let (th, cov, rss) = py
        .detach(|| sysid_core::polynomial::regul::regularized_solve(s, pr, lam))
        .py()?;
    Ok((slice_to_numpy(py, &th), mat_to_numpy(py, &cov), rss))
}

/// Registers the functions of this file.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(arx_fit, m)?)?;
    m.add_function(wrap_pyfunction!(arx_struc, m)?)?;
    m.add_function(wrap_pyfunction!(arx_summary, m)?)?;
    m.add_function(wrap_pyfunction!(arx_matrix_filter, m)?)?;
    m.add_function(wrap_pyfunction!(arx_marginal_likelihood, m)?)?;
    m.add_function(wrap_pyfunction!(arx_regularized_solve, m)?)?;
    m.add_function(wrap_pyfunction!(poly_filter, m)?)?;
    m.add_function(wrap_pyfunction!(polynomial_pem, m)?)?;
    m.add_function(wrap_pyfunction!(polynomial_residuals, m)?)?;
    m.add_function(wrap_pyfunction!(polynomial_free_search, m)?)?;
    m.add_function(wrap_pyfunction!(initial_condition_name, m)?)?;
    m.add_function(wrap_pyfunction!(iv4, m)?)?;
    m.add_function(wrap_pyfunction!(ivx, m)?)?;
    Ok(())
}
