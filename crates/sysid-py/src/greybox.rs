//! Bindings of the grey-box estimators (`sysid_core::greybox`): Python callables become a
//! parameter map (linear structures) or an ODE model (nonlinear structures).

use crate::convert::{mat_to_numpy, slice_to_numpy, view};
use crate::errors::IntoPy;
use faer::{Mat, MatRef};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::greybox::ode::{
    self, Derivatives, Integrator, OdeJacobian, OdeModel, OdeOptions, OdeStructure,
};
use sysid_core::greybox::{self, LinearOptions};
use sysid_core::optim::{self, Flow, Iteration, ParameterMap};
use sysid_core::pem::{Focus, Lines};
use sysid_core::SysidError;

use crate::search::{observer, solution_items, Slot};

fn callback_failed(slot: &mut Slot, e: PyErr, what: &str) -> SysidError {
    let msg = format!("{what} raised: {e}");
    if slot.is_none() {
        *slot = Some(e);
    }
    SysidError::InvalidArgument {
        name: "callback",
        reason: msg,
    }
}

fn to_mat(obj: &Bound<'_, PyAny>) -> PyResult<Mat<f64>> {
    let a: PyReadonlyArray2<'_, f64> = obj.extract()?;
    Ok(view(&a).to_owned())
}

struct PyMap<'s> {
    f: Py<PyAny>,
    err: &'s mut Slot,
}

impl ParameterMap for PyMap<'_> {
    fn map(&mut self, p: &[f64], jac: bool) -> sysid_core::Result<(Vec<f64>, Option<Mat<f64>>)> {
        sysid_core::interrupt::check()?;
        Python::attach(|py| {
            let r = (|| -> PyResult<(Vec<f64>, Option<Mat<f64>>)> {
                let out = self.f.call1(py, (slice_to_numpy(py, p), jac))?;
                let (th, m): (PyReadonlyArray1<'_, f64>, Option<Bound<'_, PyAny>>) =
                    out.extract(py)?;
                let th: Vec<f64> = th.as_array().iter().copied().collect();
                let m = match m {
                    Some(m) if !m.is_none() => Some(to_mat(&m)?),
                    _ => None,
                };
                Ok((th, m))
            })();
            r.map_err(|e| callback_failed(self.err, e, "the grey-box structure function"))
        })
    }
}

struct PyOde<'s> {
    f: Py<PyAny>,
    h: Py<PyAny>,
    /// `(t, x, u, p) -> (f, df/dx, df/dp)` at one point (sensitivity equations).
    fd: Option<Py<PyAny>>,
    /// `(t, x, u, p) -> (h, dh/dx, dh/dp)` at one point.
    hd: Option<Py<PyAny>>,
    err: &'s mut Slot,
}

impl PyOde<'_> {
    fn call(
        &mut self,
        which: bool,
        t: f64,
        x: MatRef<'_, f64>,
        u: &[f64],
        p: MatRef<'_, f64>,
    ) -> sysid_core::Result<Mat<f64>> {
        Python::attach(|py| {
            let r = (|| -> PyResult<Mat<f64>> {
                let xa = Array2::from_shape_fn((x.nrows(), x.ncols()), |(i, j)| x[(i, j)])
                    .into_pyarray(py);
                let pa = Array2::from_shape_fn((p.nrows(), p.ncols()), |(i, j)| p[(i, j)])
                    .into_pyarray(py);
                let f = if which { &self.f } else { &self.h };
                let out = f.call1(py, (t, xa, slice_to_numpy(py, u), pa))?;
                to_mat(out.bind(py))
            })();
            r.map_err(|e| {
                callback_failed(
                    self.err,
                    e,
                    if which {
                        "the state equation f"
                    } else {
                        "the output equation h"
                    },
                )
            })
        })
    }
}

impl PyOde<'_> {
    fn derivatives(
        &mut self,
        which: bool,
        t: f64,
        x: &[f64],
        u: &[f64],
        p: &[f64],
    ) -> sysid_core::Result<Option<Derivatives>> {
        let Some(fun) = (if which { &self.fd } else { &self.hd }) else {
            return Ok(None);
        };
        Python::attach(|py| {
            let r = (|| -> PyResult<Derivatives> {
                let out = fun.call1(
                    py,
                    (
                        t,
                        slice_to_numpy(py, x),
                        slice_to_numpy(py, u),
                        slice_to_numpy(py, p),
                    ),
                )?;
                let (v, dx, dp): (Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyAny>) =
                    out.extract(py)?;
                Ok((to_mat(&v)?, to_mat(&dx)?, to_mat(&dp)?))
            })();
            r.map(Some).map_err(|e| {
                callback_failed(
                    self.err,
                    e,
                    if which {
                        "the derivatives of f"
                    } else {
                        "the derivatives of h"
                    },
                )
            })
        })
    }
}

impl OdeModel for PyOde<'_> {
    fn rhs(
        &mut self,
        t: f64,
        x: MatRef<'_, f64>,
        u: &[f64],
        p: MatRef<'_, f64>,
    ) -> sysid_core::Result<Mat<f64>> {
        sysid_core::interrupt::check()?; // Ctrl-C between calls of Python
        self.call(true, t, x, u, p)
    }
    fn output(
        &mut self,
        t: f64,
        x: MatRef<'_, f64>,
        u: &[f64],
        p: MatRef<'_, f64>,
    ) -> sysid_core::Result<Mat<f64>> {
        sysid_core::interrupt::check()?; // Ctrl-C between calls of Python
        self.call(false, t, x, u, p)
    }
    fn rhs_derivatives(
        &mut self,
        t: f64,
        x: &[f64],
        u: &[f64],
        p: &[f64],
    ) -> sysid_core::Result<Option<Derivatives>> {
        self.derivatives(true, t, x, u, p)
    }
    fn output_derivatives(
        &mut self,
        t: f64,
        x: &[f64],
        u: &[f64],
        p: &[f64],
    ) -> sysid_core::Result<Option<Derivatives>> {
        self.derivatives(false, t, x, u, p)
    }
}

/// The search options of the grey-box fits, from a dict with `max_iter` (other keys
/// missing take the defaults).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct SearchArgs {
    #[pyo3(default)]
    lower: Option<Vec<f64>>,
    #[pyo3(default)]
    upper: Option<Vec<f64>>,
    #[pyo3(default)]
    fixed: Option<Vec<bool>>,
    max_iter: usize,
    #[pyo3(default = 1e-10)]
    tol_cost: f64,
    #[pyo3(default = 1e-10)]
    tol_step: f64,
    #[pyo3(default = 1e-12)]
    tol_gradient: f64,
}

impl SearchArgs {
    fn options(args: Option<SearchArgs>) -> optim::Options {
        let a = args.unwrap_or(SearchArgs {
            lower: None,
            upper: None,
            fixed: None,
            max_iter: 100,
            tol_cost: 1e-10,
            tol_step: 1e-10,
            tol_gradient: 1e-12,
        });
        let mut o = optim::Options::default();
        o.max_iter = a.max_iter;
        o.tol_cost = a.tol_cost;
        o.tol_step = a.tol_step;
        o.tol_gradient = a.tol_gradient;
        o.lower = a.lower;
        o.upper = a.upper;
        o.fixed = a.fixed;
        o
    }
}

/// The integrator of an ODE model, from a dict with `integrator_name` (other keys missing
/// take the defaults).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub struct IntegrationArgs {
    integrator_name: String,
    #[pyo3(default = 1)]
    substeps: usize,
    #[pyo3(default = 1e-8)]
    rtol: f64,
    #[pyo3(default = 1e-10)]
    atol: f64,
}

/// How the Jacobian of an ODE model's outputs is formed, from a dict with `jacobian`.
#[derive(FromPyObject, Default)]
#[pyo3(from_item_all)]
pub struct JacobianArgs {
    jacobian: String,
    #[pyo3(default)]
    rhs_derivatives: Option<Py<PyAny>>,
    #[pyo3(default)]
    output_derivatives: Option<Py<PyAny>>,
    #[pyo3(default = 1e-6)]
    fd_step: f64,
}

/// An optional Python callable.
type Callback = Option<Py<PyAny>>;

/// An ODE model's structure: `(nx, p, free_p, x0, free_x0, typical)`.
type StructureArgs = (
    usize,
    Vec<f64>,
    Vec<usize>,
    Vec<Vec<f64>>,
    Vec<(usize, usize)>,
    Vec<f64>,
);

fn ode_structure((nx, p, free_p, x0, free_x0, typical): StructureArgs) -> OdeStructure {
    OdeStructure {
        nx,
        p,
        free_p,
        x0,
        free_x0,
        typical,
    }
}

/// The options of an ODE fit, simulation or Jacobian (search options left default), and the
/// derivative callables; the sensitivity equations need both.
fn ode_options(
    dt: f64,
    integration: Option<IntegrationArgs>,
    jacobian: Option<JacobianArgs>,
) -> PyResult<(OdeOptions, Callback, Callback)> {
    let i = integration.unwrap_or(IntegrationArgs {
        integrator_name: "rk4".into(),
        substeps: 1,
        rtol: 1e-8,
        atol: 1e-10,
    });
    let j = jacobian.unwrap_or(JacobianArgs {
        jacobian: "fd".into(),
        fd_step: 1e-6,
        ..Default::default()
    });
    let mut o = OdeOptions::default();
    o.dt = dt;
    o.integrator = Integrator::from_name(&i.integrator_name, i.substeps, i.rtol, i.atol).py()?;
    o.fd_step = j.fd_step;
    o.jacobian = j.jacobian.parse().py()?;
    let both = j.rhs_derivatives.is_some() && j.output_derivatives.is_some();
    if o.jacobian == OdeJacobian::Sensitivity && !both {
        return Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "jacobian",
            reason: "\"sensitivity\" needs rhs_derivatives and output_derivatives".into(),
        }));
    }
    Ok((o, j.rhs_derivatives, j.output_derivatives))
}

/// Runs `fit` with the GIL released, `structure` as its parameter map and `progress` as its
/// observer; a Python error raised in either callback is re-raised, a core error mapped.
fn with_map<T: Send>(
    py: Python<'_>,
    structure: Py<PyAny>,
    progress: &Option<Py<PyAny>>,
    fit: impl FnOnce(&mut dyn ParameterMap, &mut dyn FnMut(&Iteration) -> Flow) -> sysid_core::Result<T>
        + Send,
) -> PyResult<T> {
    let mut map_err: Slot = None;
    let mut obs_err: Slot = None;
    let result = crate::search::watch(py, || {
        let mut map = PyMap {
            f: structure,
            err: &mut map_err,
        };
        let mut obs = observer(progress, &mut obs_err);
        fit(&mut map, &mut obs)
    });
    if let Some(e) = map_err.or(obs_err) {
        return Err(e);
    }
    result?.py()
}

/// Estimates a linear grey-box structure; `structure(p, jac) -> (theta, dtheta/dp or None)`.
#[pyfunction]
#[pyo3(signature = (dims, experiments, structure, p0, *, focus="prediction", with_k=false,
    reweight=true, x0_params=vec![], search=None, progress=None, unbounded=false))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_linear<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    experiments: Vec<(PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, f64>)>,
    structure: Py<PyAny>,
    p0: Vec<f64>,
    focus: &str,
    with_k: bool,
    reweight: bool,
    x0_params: Vec<usize>,
    search: Option<SearchArgs>,
    progress: Option<Py<PyAny>>,
    unbounded: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let focus: Focus = focus.parse().py()?;
    let mut o = LinearOptions::default();
    o.unbounded = unbounded;
    o.focus = focus;
    o.with_k = with_k;
    o.reweight = reweight;
    o.x0_params = x0_params;
    o.optim = SearchArgs::options(search);
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y)| (view(u), view(y)))
        .collect();
    let r = with_map(py, structure, &progress, |map, obs| {
        greybox::linear(dims, &views, map, &p0, &o, obs)
    })?;
    let out = PyDict::new(py);
    out.set_item("p", slice_to_numpy(py, &r.p))?;
    out.set_item("theta", slice_to_numpy(py, &r.theta))?;
    fit_items(&out, py, &r.fit)?;
    Ok(out)
}

/// Fits a linear grey-box structure to frequency-response lines (periodic data, or an FRD
/// with its noise variance); `structure(p, jac) -> ((A, B, C, D) entries, dtheta/dp or None)`.
#[pyfunction]
#[pyo3(signature = (dims, omega, re, im, weight, structure, p0, *, search=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_frequency<'py>(
    py: Python<'py>,
    dims: (usize, usize, usize),
    omega: PyReadonlyArray1<'py, f64>,
    re: PyReadonlyArray2<'py, f64>,
    im: PyReadonlyArray2<'py, f64>,
    weight: PyReadonlyArray2<'py, f64>,
    structure: Py<PyAny>,
    p0: Vec<f64>,
    search: Option<SearchArgs>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let o = SearchArgs::options(search);
    let omega: Vec<f64> = omega.as_array().iter().copied().collect();
    let lines = Lines {
        omega: &omega,
        re: view(&re),
        im: view(&im),
        weight: view(&weight),
    };
    let r = with_map(py, structure, &progress, |map, obs| {
        greybox::frequency::linear_frequency(dims, &lines, map, &p0, &o, obs)
    })?;
    let out = PyDict::new(py);
    out.set_item("p", slice_to_numpy(py, &r.p))?;
    out.set_item("theta", slice_to_numpy(py, &r.theta))?;
    out.set_item("n_residuals", r.n_residuals)?;
    out.set_item("residual_scale", r.residual_scale)?;
    out.set_item("spectral_radius", r.spectral_radius)?;
    solution_items(&out, py, &r.solution, &r.covariance)?;
    Ok(out)
}

/// The error covariance, sample count, loss history, search report and covariance of a
/// determinant-criterion fit, as items of `out`.
fn fit_items(out: &Bound<'_, PyDict>, py: Python<'_>, fit: &greybox::CriterionFit) -> PyResult<()> {
    out.set_item(
        "innovation_covariance",
        mat_to_numpy(py, &fit.innovation_covariance),
    )?;
    out.set_item("n_samples", fit.n_samples)?;
    out.set_item("loss_history", fit.loss_history.clone())?;
    solution_items(out, py, &fit.solution, &fit.covariance)
}

/// Estimates a nonlinear grey-box model; `f(t, x, u, p)` and `h(t, x, u, p)` take `x` as
/// `(nx, K)` and `p` as `(np, K)` arrays (K perturbed columns) and return `(nx, K)`, `(l, K)`.
#[pyfunction]
#[pyo3(signature = (f, h, experiments, structure, dt, *, reweight=true, integration=None,
    jacobian=None, search=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_ode<'py>(
    py: Python<'py>,
    f: Py<PyAny>,
    h: Py<PyAny>,
    experiments: Vec<(PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, f64>)>,
    structure: StructureArgs,
    dt: f64,
    reweight: bool,
    integration: Option<IntegrationArgs>,
    jacobian: Option<JacobianArgs>,
    search: Option<SearchArgs>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let (mut o, rhs_derivatives, output_derivatives) = ode_options(dt, integration, jacobian)?;
    o.reweight = reweight;
    o.optim = SearchArgs::options(search);
    let st = ode_structure(structure);
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y)| (view(u), view(y)))
        .collect();
    let mut cb_err: Slot = None;
    let mut obs_err: Slot = None;
    let result = crate::search::watch(py, || {
        let mut model = PyOde {
            f,
            h,
            fd: rhs_derivatives,
            hd: output_derivatives,
            err: &mut cb_err,
        };
        let mut obs = observer(&progress, &mut obs_err);
        ode::estimate(&mut model, &views, st, &o, &mut obs)
    });
    if let Some(e) = cb_err.or(obs_err) {
        return Err(e);
    }
    let r = result?.py()?;
    let out = PyDict::new(py);
    out.set_item("theta", slice_to_numpy(py, &r.theta))?;
    out.set_item("rhs_calls", r.rhs_calls)?;
    fit_items(&out, py, &r.fit)?;
    Ok(out)
}

/// Simulates a nonlinear grey-box model (`f`, `h` as for [`greybox_ode`], called with K = 1).
#[pyfunction]
#[pyo3(signature = (f, h, u, nx, p, x0, dt, *, integration=None))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_ode_simulate<'py>(
    py: Python<'py>,
    f: Py<PyAny>,
    h: Py<PyAny>,
    u: PyReadonlyArray2<'py, f64>,
    nx: usize,
    p: Vec<f64>,
    x0: Vec<f64>,
    dt: f64,
    integration: Option<IntegrationArgs>,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let (o, _, _) = ode_options(dt, integration, None)?;
    let st = OdeStructure {
        nx,
        p,
        free_p: vec![],
        x0: vec![x0],
        free_x0: vec![],
        typical: vec![],
    };
    let uv = view(&u);
    let mut cb_err: Slot = None;
    let result = crate::search::watch(py, || {
        let mut model = PyOde {
            f,
            h,
            fd: None,
            hd: None,
            err: &mut cb_err,
        };
        ode::simulate(&mut model, uv, &st, 0, &o)
    });
    if let Some(e) = cb_err {
        return Err(e);
    }
    Ok(mat_to_numpy(py, &result?.py()?))
}

type JacobianOut<'py> = (
    Bound<'py, numpy::PyArray2<f64>>,
    Bound<'py, numpy::PyArray2<f64>>,
);

/// The simulated outputs of every experiment (stacked) and their derivatives with respect to
/// the free parameters and free initial-state entries (row `t l + i`), by forward
/// differences (`jacobian="fd"`) or the sensitivity equations (`"sensitivity"`).
#[pyfunction]
#[pyo3(signature = (f, h, inputs, structure, dt, *, integration=None, jacobian=None))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_ode_jacobian<'py>(
    py: Python<'py>,
    f: Py<PyAny>,
    h: Py<PyAny>,
    inputs: Vec<PyReadonlyArray2<'py, f64>>,
    structure: StructureArgs,
    dt: f64,
    integration: Option<IntegrationArgs>,
    jacobian: Option<JacobianArgs>,
) -> PyResult<JacobianOut<'py>> {
    let (o, rhs_derivatives, output_derivatives) = ode_options(dt, integration, jacobian)?;
    let st = ode_structure(structure);
    let views: Vec<_> = inputs.iter().map(|u| view(u)).collect();
    let mut cb_err: Slot = None;
    let result = crate::search::watch(py, || {
        let mut model = PyOde {
            f,
            h,
            fd: rhs_derivatives,
            hd: output_derivatives,
            err: &mut cb_err,
        };
        ode::jacobian(&mut model, &views, &st, &o)
    });
    if let Some(e) = cb_err {
        return Err(e);
    }
    let (y, j) = result?.py()?;
    Ok((mat_to_numpy(py, &y), mat_to_numpy(py, &j)))
}

type ExpmOut<'py> = (
    Bound<'py, numpy::PyArray2<f64>>,
    Vec<Bound<'py, numpy::PyArray2<f64>>>,
);

/// `exp(x)` and its Fréchet derivatives in the directions `dirs` (small matrices).
#[pyfunction]
pub fn expm_frechet<'py>(
    py: Python<'py>,
    x: PyReadonlyArray2<'py, f64>,
    dirs: Vec<PyReadonlyArray2<'py, f64>>,
) -> PyResult<ExpmOut<'py>> {
    let xv = view(&x);
    if xv.nrows() != xv.ncols() {
        return Err(pyo3::exceptions::PyValueError::new_err("x must be square"));
    }
    let ds: Vec<Mat<f64>> = dirs.iter().map(|d| view(d).to_owned()).collect();
    if ds
        .iter()
        .any(|d| d.nrows() != xv.nrows() || d.ncols() != xv.ncols())
    {
        return Err(pyo3::exceptions::PyValueError::new_err(
            "every direction must have the shape of x",
        ));
    }
    crate::errors::IntoPy::py(sysid_core::error::check_finite("x", xv))?;
    let (f, l) = sysid_core::greybox::expm::expm_frechet(xv, &ds);
    Ok((
        mat_to_numpy(py, &f),
        l.iter().map(|m| mat_to_numpy(py, m)).collect(),
    ))
}

/// Whether the data insist on an unconstrained fit over the one a stability bound kept
/// (`sysid_core::pem::insists`: the likelihood-ratio statistic against chi-square(1) at
/// 1 %): `(statistic, insist)`.
#[pyfunction]
#[pyo3(signature = (kept, free, n, l=1, det=false))]
pub fn stability_insists(kept: f64, free: f64, n: usize, l: usize, det: bool) -> (f64, bool) {
    sysid_core::pem::insists(kept, free, n, l, det)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(stability_insists, m)?)?;
    m.add_function(wrap_pyfunction!(expm_frechet, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_linear, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_frequency, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_ode, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_ode_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_ode_jacobian, m)?)?;
    Ok(())
}
