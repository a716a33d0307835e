//! Bindings of `sysid_core::subspace::closed_loop`: PBSID-opt and SSARX on a compressed record.

use crate::convert::slice_to_numpy;
use crate::errors::IntoPy;
use crate::hankel::PyHankelFactor;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::subspace::closed_loop::{ClosedLoop, ClosedLoopOptions, VarxRegularization};

/// VARX and weighted SVD of a compressed record for PBSID-opt or SSARX.
#[pyclass(name = "ClosedLoopSubspace", module = "sysid._sysid", frozen)]
pub struct PyClosedLoop {
    inner: ClosedLoop,
}

#[pymethods]
impl PyClosedLoop {
    #[new]
    #[pyo3(signature = (factor, method, regularization="none", ridge=1e-3, feedthrough=false))]
    fn new(
        py: Python<'_>,
        factor: &PyHankelFactor,
        method: &str,
        regularization: &str,
        ridge: f64,
        feedthrough: bool,
    ) -> PyResult<Self> {
        let mut opts = ClosedLoopOptions::default();
        opts.method = method.parse().py()?;
        opts.regularization = VarxRegularization::from_name(regularization, ridge).py()?;
        opts.feedthrough = feedthrough;
        let f = factor.inner.clone();
        let inner = py.detach(|| ClosedLoop::new(&f, &opts)).py()?;
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

    /// Returns a dict with A, B, C, D, K, noise_cov, Q, R, S, stabilized (always False).
    fn fit<'py>(&self, py: Python<'py>, order: usize) -> PyResult<Bound<'py, PyDict>> {
        let id = py.detach(|| self.inner.fit(order)).py()?;
        crate::subspace::identified_dict(py, &id)
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyClosedLoop>()?;
    Ok(())
}
