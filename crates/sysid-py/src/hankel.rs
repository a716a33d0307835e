//! Bindings of `sysid_core::hankel`: compression and the `HankelFactor` value.

use crate::convert::{to_numpy, view, view_nd};
use crate::errors::IntoPy;
use faer::MatRef;
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use sysid_core::hankel::{
    compress_experiments, CompressorKind, FactorSource, HankelFactor, HankelLayout,
};
use sysid_core::SysidError;

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

    /// How the factor was obtained: "qr", "correlation", "correlation-ill-conditioned" or
    /// "qr-fallback".
    #[getter]
    fn source(&self) -> &'static str {
        self.inner.source().name()
    }

    /// Smallest relative Cholesky pivot of the correlation path, also when it was rejected
    /// (None when only the exact path ran).
    #[getter]
    fn relative_pivot(&self) -> Option<f64> {
        self.inner.relative_pivot()
    }

    /// Root mean square of each input and output over the samples summarised.
    fn channel_rms(&self) -> (Vec<f64>, Vec<f64>) {
        self.inner.channel_rms()
    }

    /// The factor with every input divided by `input_scale` and output by `output_scale`.
    fn scaled(&self, input_scale: Vec<f64>, output_scale: Vec<f64>) -> PyResult<PyHankelFactor> {
        Ok(PyHankelFactor {
            inner: self.inner.scaled(&input_scale, &output_scale).py()?,
        })
    }

    fn merge(&self, other: &PyHankelFactor) -> PyResult<PyHankelFactor> {
        Ok(PyHankelFactor {
            inner: self.inner.merge(&other.inner).py()?,
        })
    }

    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (n_inputs, n_outputs, past, future, l, n_columns, n_experiments, source="qr", relative_pivot=None))]
    fn from_parts(
        n_inputs: usize,
        n_outputs: usize,
        past: usize,
        future: usize,
        l: PyReadonlyArray2<'_, f64>,
        n_columns: usize,
        n_experiments: usize,
        source: &str,
        relative_pivot: Option<f64>,
    ) -> PyResult<PyHankelFactor> {
        let layout = HankelLayout::new(n_inputs, n_outputs, past, future).py()?;
        let source = FactorSource::from_name(source, relative_pivot.unwrap_or(0.0)).py()?;
        let inner = HankelFactor::from_parts(layout, view(&l).to_owned(), n_columns, n_experiments)
            .py()?
            .with_source(source)
            .with_relative_pivot(relative_pivot);
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
            me.inner.source().name(),
            me.relative_pivot(),
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

/// Compresses a list of `(u, y)` experiments into a `HankelFactor`.
///
/// `compressor="auto"` (default) runs the fast correlation path and keeps it when its Gram
/// matrix is well conditioned (relative pivot >= AUTO_MIN_RELATIVE_PIVOT), else compresses
/// exactly (`factor.source == "qr-fallback"`); `"qr"` is exact (`chunk_rows` windows per QR
/// update); `"correlation"` is fast (`chunk_rows` samples per parallel block) and falls back
/// to the exact pass only when its Gram matrix is numerically singular (pivot < 1e-10).
#[pyfunction]
#[pyo3(signature = (experiments, past, future, chunk_rows=None, compressor="auto"))]
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
    let longest = experiments
        .iter()
        .map(|(_, y)| y.as_array().nrows())
        .max()
        .unwrap_or(0);
    let layout = HankelLayout::for_record(m, l, past, future, longest).py()?;
    let views: Vec<(MatRef<'_, f64>, MatRef<'_, f64>)> = experiments
        .iter()
        .map(|(u, y)| (view_nd(u.as_array()), view_nd(y.as_array())))
        .collect();
    let kind = CompressorKind::parse(compressor, chunk_rows).py()?;
    let result = crate::search::detach(py, || compress_experiments(layout, &views, kind));
    Ok(PyHankelFactor { inner: result? })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyHankelFactor>()?;
    m.add_function(wrap_pyfunction!(compress, m)?)?;
    m.add(
        "AUTO_MIN_RELATIVE_PIVOT",
        sysid_core::hankel::AUTO_MIN_RELATIVE_PIVOT,
    )?;
    Ok(())
}
