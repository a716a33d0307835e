//! Bindings of `sysid_core::subspace::recursive`: the forgetting, chunk-by-chunk factor.

use crate::convert::view;
use crate::errors::IntoPy;
use crate::hankel::PyHankelFactor;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use sysid_core::hankel::HankelLayout;
use sysid_core::subspace::recursive::RecursiveFactor;

/// A Hankel factor updated chunk by chunk with exponential forgetting.
#[pyclass(name = "RecursiveFactor", module = "sysid._sysid")]
pub struct PyRecursiveFactor {
    inner: RecursiveFactor,
}

#[pymethods]
impl PyRecursiveFactor {
    #[new]
    #[pyo3(signature = (n_inputs, n_outputs, past, future, forgetting=1.0))]
    fn new(
        n_inputs: usize,
        n_outputs: usize,
        past: usize,
        future: usize,
        forgetting: f64,
    ) -> PyResult<Self> {
        let layout = HankelLayout::new(n_inputs, n_outputs, past, future).py()?;
        Ok(Self {
            inner: RecursiveFactor::new(layout, forgetting).py()?,
        })
    }

    /// Appends a chunk `(u, y)` (the GIL is released).
    fn update(
        &mut self,
        py: Python<'_>,
        u: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let (uv, yv) = (view(&u), view(&y));
        // into a copy (a k x k triangle and the tail), kept only when complete: an interrupted
        // update leaves the factor as it was
        let mut next = self.inner.clone();
        crate::search::detach(py, || next.update(uv, yv))?;
        self.inner = next;
        Ok(())
    }

    /// The current factor.
    fn factor(&self) -> PyResult<PyHankelFactor> {
        Ok(PyHankelFactor {
            inner: self.inner.factor().py()?,
        })
    }

    #[getter]
    fn n_columns(&self) -> usize {
        self.inner.n_columns()
    }

    #[getter]
    fn effective_columns(&self) -> f64 {
        self.inner.effective_columns()
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRecursiveFactor>()?;
    Ok(())
}
