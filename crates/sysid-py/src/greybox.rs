//! Bindings of the grey-box estimators (`sysid_core::greybox`): Python callables become a
//! parameter map (linear structures) or an ODE model (nonlinear structures).

use crate::convert::{mat_to_numpy, slice_to_numpy, view};
use crate::errors::IntoPy;
use faer::{Mat, MatRef};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::greybox::ode::{
    self, Derivatives, Integrator, OdeJacobian, OdeModel, OdeOptions, OdeStructure,
};
use sysid_core::greybox::{self, LinearOptions};
use sysid_core::optim::{self, ParameterMap};
use sysid_core::pem::Focus;
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

/// The integration options shared by the fit and the Jacobian (search options left default).
fn ode_options(dt: f64, integrator: Integrator, fd_step: f64, jacobian: OdeJacobian) -> OdeOptions {
    let mut o = OdeOptions::default();
    o.dt = dt;
    o.integrator = integrator;
    o.fd_step = fd_step;
    o.jacobian = jacobian;
    o
}

fn jacobian_kind(
    name: &str,
    fd: &Option<Py<PyAny>>,
    hd: &Option<Py<PyAny>>,
) -> PyResult<OdeJacobian> {
    match name {
        "fd" => Ok(OdeJacobian::FiniteDifference),
        "sensitivity" if fd.is_some() && hd.is_some() => Ok(OdeJacobian::Sensitivity),
        "sensitivity" => Err(PyValueError::new_err(
            "jacobian=\"sensitivity\" needs rhs_derivatives and output_derivatives",
        )),
        other => Err(PyValueError::new_err(format!(
            "jacobian must be \"fd\" or \"sensitivity\", got {other:?}"
        ))),
    }
}

#[allow(clippy::too_many_arguments)]
fn search_options(
    max_iter: usize,
    tol_cost: f64,
    tol_step: f64,
    tol_gradient: f64,
    lower: Option<Vec<f64>>,
    upper: Option<Vec<f64>>,
    fixed: Option<Vec<bool>>,
) -> optim::Options {
    let mut o = optim::Options::default();
    o.max_iter = max_iter;
    o.tol_cost = tol_cost;
    o.tol_step = tol_step;
    o.tol_gradient = tol_gradient;
    o.lower = lower;
    o.upper = upper;
    o.fixed = fixed;
    o
}

/// Estimates a linear grey-box structure; `structure(p, jac) -> (theta, dtheta/dp or None)`.
#[pyfunction]
#[pyo3(signature = (dims, experiments, structure, p0, *, focus="prediction", with_k=false,
    reweight=true, x0_params=vec![], lower=None, upper=None, fixed=None, max_iter=100,
    tol_cost=1e-10, tol_step=1e-10, tol_gradient=1e-12, progress=None))]
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
    lower: Option<Vec<f64>>,
    upper: Option<Vec<f64>>,
    fixed: Option<Vec<bool>>,
    max_iter: usize,
    tol_cost: f64,
    tol_step: f64,
    tol_gradient: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let focus: Focus = focus.parse().py()?;
    let mut o = LinearOptions::default();
    o.focus = focus;
    o.with_k = with_k;
    o.reweight = reweight;
    o.x0_params = x0_params;
    o.optim = search_options(
        max_iter,
        tol_cost,
        tol_step,
        tol_gradient,
        lower,
        upper,
        fixed,
    );
    let views: Vec<_> = experiments
        .iter()
        .map(|(u, y)| (view(u), view(y)))
        .collect();
    let mut map_err: Slot = None;
    let mut obs_err: Slot = None;
    let result = crate::search::watch(py, || {
        let mut map = PyMap {
            f: structure,
            err: &mut map_err,
        };
        let mut obs = observer(&progress, &mut obs_err);
        greybox::linear(dims, &views, &mut map, &p0, &o, &mut obs)
    });
    if let Some(e) = map_err.or(obs_err) {
        return Err(e);
    }
    let r = result?.py()?;
    let out = PyDict::new(py);
    out.set_item("p", slice_to_numpy(py, &r.p))?;
    out.set_item("theta", slice_to_numpy(py, &r.theta))?;
    out.set_item(
        "innovation_covariance",
        mat_to_numpy(py, &r.innovation_covariance),
    )?;
    out.set_item("n_samples", r.n_samples)?;
    out.set_item("loss_history", r.loss_history.clone())?;
    solution_items(&out, py, &r.solution, &r.covariance)?;
    Ok(out)
}

fn integrator(name: &str, substeps: usize, rtol: f64, atol: f64) -> PyResult<Integrator> {
    match name {
        "rk4" => Ok(Integrator::Rk4 { substeps }),
        "adaptive" => Ok(Integrator::Adaptive { rtol, atol }),
        other => Err(PyValueError::new_err(format!(
            "integrator must be \"rk4\" or \"adaptive\", got {other:?}"
        ))),
    }
}

/// Estimates a nonlinear grey-box model; `f(t, x, u, p)` and `h(t, x, u, p)` take `x` as
/// `(nx, K)` and `p` as `(np, K)` arrays (K perturbed columns) and return `(nx, K)`, `(l, K)`.
#[pyfunction]
#[pyo3(signature = (f, h, experiments, nx, p, free_p, x0, free_x0, typical, dt, *,
    integrator_name="rk4", substeps=1, rtol=1e-8, atol=1e-10, reweight=true, fd_step=1e-6,
    jacobian="fd", rhs_derivatives=None, output_derivatives=None,
    lower=None, upper=None, fixed=None, max_iter=100, tol_cost=1e-10, tol_step=1e-10,
    tol_gradient=1e-12, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_ode<'py>(
    py: Python<'py>,
    f: Py<PyAny>,
    h: Py<PyAny>,
    experiments: Vec<(PyReadonlyArray2<'py, f64>, PyReadonlyArray2<'py, f64>)>,
    nx: usize,
    p: Vec<f64>,
    free_p: Vec<usize>,
    x0: Vec<Vec<f64>>,
    free_x0: Vec<(usize, usize)>,
    typical: Vec<f64>,
    dt: f64,
    integrator_name: &str,
    substeps: usize,
    rtol: f64,
    atol: f64,
    reweight: bool,
    fd_step: f64,
    jacobian: &str,
    rhs_derivatives: Option<Py<PyAny>>,
    output_derivatives: Option<Py<PyAny>>,
    lower: Option<Vec<f64>>,
    upper: Option<Vec<f64>>,
    fixed: Option<Vec<bool>>,
    max_iter: usize,
    tol_cost: f64,
    tol_step: f64,
    tol_gradient: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut o = ode_options(
        dt,
        integrator(integrator_name, substeps, rtol, atol)?,
        fd_step,
        jacobian_kind(jacobian, &rhs_derivatives, &output_derivatives)?,
    );
    o.reweight = reweight;
    o.optim = search_options(
        max_iter,
        tol_cost,
        tol_step,
        tol_gradient,
        lower,
        upper,
        fixed,
    );
    let st = OdeStructure {
        nx,
        p,
        free_p,
        x0,
        free_x0,
        typical,
    };
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
    out.set_item(
        "innovation_covariance",
        mat_to_numpy(py, &r.innovation_covariance),
    )?;
    out.set_item("n_samples", r.n_samples)?;
    out.set_item("loss_history", r.loss_history.clone())?;
    out.set_item("rhs_calls", r.rhs_calls)?;
    solution_items(&out, py, &r.solution, &r.covariance)?;
    Ok(out)
}

/// Simulates a nonlinear grey-box model (`f`, `h` as for [`greybox_ode`], called with K = 1).
#[pyfunction]
#[pyo3(signature = (f, h, u, nx, p, x0, dt, *, integrator_name="rk4", substeps=1, rtol=1e-8,
    atol=1e-10))]
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
    integrator_name: &str,
    substeps: usize,
    rtol: f64,
    atol: f64,
) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
    let mut o = OdeOptions::default();
    o.dt = dt;
    o.integrator = integrator(integrator_name, substeps, rtol, atol)?;
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
#[pyo3(signature = (f, h, inputs, nx, p, free_p, x0, free_x0, typical, dt, *,
    integrator_name="rk4", substeps=1, rtol=1e-8, atol=1e-10, fd_step=1e-6, jacobian="fd",
    rhs_derivatives=None, output_derivatives=None))]
#[allow(clippy::too_many_arguments)]
pub fn greybox_ode_jacobian<'py>(
    py: Python<'py>,
    f: Py<PyAny>,
    h: Py<PyAny>,
    inputs: Vec<PyReadonlyArray2<'py, f64>>,
    nx: usize,
    p: Vec<f64>,
    free_p: Vec<usize>,
    x0: Vec<Vec<f64>>,
    free_x0: Vec<(usize, usize)>,
    typical: Vec<f64>,
    dt: f64,
    integrator_name: &str,
    substeps: usize,
    rtol: f64,
    atol: f64,
    fd_step: f64,
    jacobian: &str,
    rhs_derivatives: Option<Py<PyAny>>,
    output_derivatives: Option<Py<PyAny>>,
) -> PyResult<JacobianOut<'py>> {
    let o = ode_options(
        dt,
        integrator(integrator_name, substeps, rtol, atol)?,
        fd_step,
        jacobian_kind(jacobian, &rhs_derivatives, &output_derivatives)?,
    );
    let st = OdeStructure {
        nx,
        p,
        free_p,
        x0,
        free_x0,
        typical,
    };
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
        return Err(PyValueError::new_err("x must be square"));
    }
    let ds: Vec<Mat<f64>> = dirs.iter().map(|d| view(d).to_owned()).collect();
    if ds
        .iter()
        .any(|d| d.nrows() != xv.nrows() || d.ncols() != xv.ncols())
    {
        return Err(PyValueError::new_err(
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

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(expm_frechet, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_linear, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_ode, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_ode_simulate, m)?)?;
    m.add_function(wrap_pyfunction!(greybox_ode_jacobian, m)?)?;
    Ok(())
}
