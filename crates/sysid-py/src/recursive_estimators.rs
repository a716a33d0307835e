//! Bindings of `sysid_core::recursive`: the online polynomial estimators.

use crate::convert::slice_to_numpy;
use crate::errors::IntoPy;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use sysid_core::recursive::{check_structure, Method, MethodSettings, Recursive, Structure};

/// What `run` returns: the prior predictions and, when stored, the parameter trajectory.
type RunOutput<'py> = (Bound<'py, PyArray1<f64>>, Option<Bound<'py, PyArray2<f64>>>);

/// An online estimator of a single-output polynomial model.
#[pyclass(name = "RecursiveEstimator", module = "sysid._sysid")]
#[derive(Clone)]
pub struct PyRecursiveEstimator {
    inner: Recursive,
}

#[pymethods]
impl PyRecursiveEstimator {
    #[new]
    #[pyo3(signature = (na, nb, nc, nd, nf, nk, method="forgetting", forgetting=1.0,
        process_noise=None, noise_variance=1.0, gain=1.0, bias=f64::EPSILON, theta0=None,
        p0=1e4, startup_forgetting=true))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        na: usize,
        nb: Vec<usize>,
        nc: usize,
        nd: usize,
        nf: Vec<usize>,
        nk: Vec<usize>,
        method: &str,
        forgetting: f64,
        process_noise: Option<PyReadonlyArray2<'_, f64>>,
        noise_variance: f64,
        gain: f64,
        bias: f64,
        theta0: Option<PyReadonlyArray1<'_, f64>>,
        p0: f64,
        startup_forgetting: bool,
    ) -> PyResult<Self> {
        let s = Structure {
            na,
            nb,
            nc,
            nd,
            nf,
            nk,
        };
        let p = check_structure(&s).py()?;
        let settings = MethodSettings {
            forgetting,
            process_noise: process_noise.map(|a| a.as_array().iter().copied().collect()),
            noise_variance,
            gain,
            bias,
        };
        let m = Method::from_name(method, p, &settings).py()?;
        let t0: Option<Vec<f64>> = theta0.map(|t| t.as_array().to_vec());
        let mut inner = Recursive::new(s, m, t0.as_deref(), Some(p0)).py()?;
        inner.set_startup_forgetting(startup_forgetting);
        Ok(Self { inner })
    }

    /// One sample; returns the prior prediction `yhat(t | t-1)`.
    fn step(&mut self, u: Vec<f64>, y: f64) -> PyResult<f64> {
        self.inner.step(&u, y).py()
    }

    /// A record (`u` C-contiguous `(n, m)`, `y` `(n,)`), the GIL released; returns
    /// `(yhat, thetas or None)`. Ctrl-C is checked every 65536 samples.
    #[pyo3(signature = (u, y, store_parameters=false))]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        u: PyReadonlyArray2<'py, f64>,
        y: PyReadonlyArray1<'py, f64>,
        store_parameters: bool,
    ) -> PyResult<RunOutput<'py>> {
        let (us, ys) = (u.as_slice()?, y.as_slice()?);
        let n = ys.len();
        let np = self.inner.n_params();
        sysid_core::error::check_matrix_size("record", n, if store_parameters { np } else { 1 })
            .py()?;
        let mut yhat = vec![0.0; n];
        let mut thetas = if store_parameters {
            vec![0.0; n * np]
        } else {
            Vec::new()
        };
        // run on a copy, kept only when complete: Ctrl-C (asked every 4096 samples, see
        // crate::search) leaves the estimator as it was
        let mut next = self.inner.clone();
        let done = crate::search::detach(py, || {
            let th = store_parameters.then_some(thetas.as_mut_slice());
            next.run(us, ys, &mut yhat, th, 1 << 12, &mut || {
                sysid_core::interrupt::requested()
            })
        })?;
        self.inner = next;
        debug_assert!(done == n);
        let yh = PyArray1::from_vec(py, yhat);
        let th = if store_parameters {
            Some(PyArray1::from_vec(py, thetas).reshape([n, np])?)
        } else {
            None
        };
        Ok((yh, th))
    }

    /// Current parameters `[a, b_j, c, d, f_j]` (a copy).
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        slice_to_numpy(py, self.inner.theta())
    }

    /// Sets the parameters.
    fn set_parameters(&mut self, theta: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        self.inner.set_theta(&theta.as_array().to_vec()).py()
    }

    /// Current `P` (a copy, p x p).
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let n = self.inner.n_params();
        slice_to_numpy(py, self.inner.covariance()).reshape([n, n])
    }

    /// Sets `P`.
    fn set_covariance(&mut self, p: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let a = p.as_array();
        let n = self.inner.n_params();
        if a.shape() != [n, n] {
            return Err(PyValueError::new_err(format!(
                "covariance has shape {:?} but should have shape ({n}, {n})",
                a.shape()
            )));
        }
        self.inner
            .set_covariance(&a.iter().copied().collect::<Vec<_>>())
            .py()
    }

    /// The regressor of the last sample.
    #[getter]
    fn regressor<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        slice_to_numpy(py, self.inner.regressor())
    }

    #[getter]
    fn samples(&self) -> usize {
        self.inner.samples()
    }

    #[getter]
    fn rejected(&self) -> usize {
        self.inner.rejected()
    }

    #[getter]
    fn n_parameters(&self) -> usize {
        self.inner.n_params()
    }

    /// Forgets the signal history (parameters and `P` kept).
    fn reset_history(&mut self) {
        self.inner.reset_history()
    }

    /// An independent copy (state included).
    fn copy(&self) -> Self {
        self.clone()
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRecursiveEstimator>()?;
    Ok(())
}
