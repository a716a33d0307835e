//! Bindings of `sysid_core::hankel`: compression and the `HankelFactor` value.

use crate::convert::{to_numpy, view, view_nd};
use crate::errors::IntoPy;
use faer::MatRef;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use sysid_core::hankel::{Compressor, HankelFactor, HankelLayout, QrCompressor};
use sysid_core::{Result as CoreResult, SysidError};

/// Triangular factor of a block-Hankel data matrix (`H H^T = L L^T`).
#[pyclass(name = "HankelFactor", module = "sysid._sysid", frozen)]
#[derive(Clone)]
pub struct PyHankelFactor {
    pub inner: HankelFactor,
}

#[pymethods]
impl PyHankelFactor {
    #[getter]
    fn l<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_numpy(py, self.inner.l())
    }
    #[getter]
    fn n_columns(&self) -> usize {
        self.inner.n_columns()
    }
    #[getter]
    fn n_experiments(&self) -> usize {
        self.inner.n_experiments()
    }
    #[getter]
    fn n_inputs(&self) -> usize {
        self.inner.layout().n_inputs
    }
    #[getter]
    fn n_outputs(&self) -> usize {
        self.inner.layout().n_outputs
    }
    #[getter]
    fn past(&self) -> usize {
        self.inner.layout().past
    }
    #[getter]
    fn future(&self) -> usize {
        self.inner.layout().future
    }

    fn merge(&self, other: &PyHankelFactor) -> PyResult<PyHankelFactor> {
        Ok(PyHankelFactor {
            inner: self.inner.merge(&other.inner).py()?,
        })
    }

    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    fn from_parts(
        n_inputs: usize,
        n_outputs: usize,
        past: usize,
        future: usize,
        l: PyReadonlyArray2<'_, f64>,
        n_columns: usize,
        n_experiments: usize,
    ) -> PyResult<PyHankelFactor> {
        let layout = HankelLayout::new(n_inputs, n_outputs, past, future).py()?;
        let inner =
            HankelFactor::from_parts(layout, view(&l).to_owned(), n_columns, n_experiments).py()?;
        Ok(PyHankelFactor { inner })
    }

    /// Pickling support (for saving and for Dask).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let me = slf.get();
        let lay = me.inner.layout();
        let ctor = py.get_type::<PyHankelFactor>().getattr("from_parts")?;
        let args = (
            lay.n_inputs,
            lay.n_outputs,
            lay.past,
            lay.future,
            to_numpy(py, me.inner.l()),
            me.inner.n_columns(),
            me.inner.n_experiments(),
        );
        PyTuple::new(py, [ctor, args.into_pyobject(py)?.into_any()])
    }

    fn __repr__(&self) -> String {
        let lay = self.inner.layout();
        format!(
            "HankelFactor(n_inputs={}, n_outputs={}, past={}, future={}, k={}, n_columns={}, n_experiments={})",
            lay.n_inputs,
            lay.n_outputs,
            lay.past,
            lay.future,
            lay.k(),
            self.inner.n_columns(),
            self.inner.n_experiments()
        )
    }
}

/// Feeds every experiment to a compressor (GIL released by the caller).
pub fn compress_all<C: Compressor>(
    mut c: C,
    experiments: &[(MatRef<'_, f64>, MatRef<'_, f64>)],
) -> CoreResult<HankelFactor> {
    for (u, y) in experiments {
        c.push(*u, *y)?;
        c.end_experiment()?;
    }
    c.finish()
}

/// Compresses a list of `(u, y)` experiments into a `HankelFactor`.
#[pyfunction]
#[pyo3(signature = (experiments, past, future, chunk_rows=None, compressor="qr"))]
pub fn compress(
    py: Python<'_>,
    experiments: Vec<(PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>)>,
    past: usize,
    future: usize,
    chunk_rows: Option<usize>,
    compressor: &str,
) -> PyResult<PyHankelFactor> {
    if experiments.is_empty() {
        return Err(crate::errors::to_py(SysidError::InvalidArgument {
            name: "experiments",
            reason: "no data: give at least one (u, y) pair".into(),
        }));
    }
    let m = experiments[0].0.as_array().ncols();
    let l = experiments[0].1.as_array().ncols();
    let layout = HankelLayout::new(m, l, past, future).py()?;
    let views: Vec<(MatRef<'_, f64>, MatRef<'_, f64>)> = experiments
        .iter()
        .map(|(u, y)| (view_nd(u.as_array()), view_nd(y.as_array())))
        .collect();
    let result = match compressor {
        "qr" => py.detach(|| {
            let c = match chunk_rows {
                Some(r) => QrCompressor::with_chunk_rows(layout, r),
                None => QrCompressor::new(layout),
            };
            compress_all(c, &views)
        }),
        other => Err(SysidError::InvalidArgument {
            name: "compressor",
            reason: format!("unknown compressor {other:?}; available: \"qr\""),
        }),
    };
    Ok(PyHankelFactor {
        inner: result.py()?,
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyHankelFactor>()?;
    m.add_function(wrap_pyfunction!(compress, m)?)?;
    Ok(())
}
