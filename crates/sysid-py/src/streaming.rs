//! Bindings for streaming compression: a compressor object fed chunk by chunk, and the
//! mergeable, picklable `CorrelationSums` value (for Dask).

use crate::convert::{slice_to_numpy, to_numpy, vec1, view};
use crate::errors::{to_py, IntoPy};
use crate::hankel::PyHankelFactor;
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use sysid_core::hankel::{
    AnyCompressor, Compressor, CompressorKind, CorrelationState, CorrelationSums, HankelLayout,
};
use sysid_core::SysidError;

fn finished() -> PyErr {
    to_py(SysidError::InvalidArgument {
        name: "compressor",
        reason: "finish() was already called; create a new StreamingCompressor".into(),
    })
}

/// The layout, checked against the longest experiment when the caller knows it.
fn layout(
    m: usize,
    l: usize,
    past: usize,
    future: usize,
    longest: Option<usize>,
) -> PyResult<HankelLayout> {
    match longest {
        Some(n) => HankelLayout::for_record(m, l, past, future, n),
        None => HankelLayout::new(m, l, past, future),
    }
    .py()
}

/// A compressor fed chunk by chunk: `push(u, y)`, `end_experiment()`, `finish()`.
#[pyclass(name = "StreamingCompressor", module = "sysid._sysid")]
pub struct PyStreamingCompressor {
    inner: Option<AnyCompressor>,
    kind: &'static str,
    samples: usize,
}

#[pymethods]
impl PyStreamingCompressor {
    #[new]
    #[pyo3(signature = (n_inputs, n_outputs, past, future, compressor="qr", chunk_rows=None, longest=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        n_inputs: usize,
        n_outputs: usize,
        past: usize,
        future: usize,
        compressor: &str,
        chunk_rows: Option<usize>,
        longest: Option<usize>,
    ) -> PyResult<Self> {
        let layout = layout(n_inputs, n_outputs, past, future, longest)?;
        let kind = CompressorKind::parse(compressor, chunk_rows).py()?;
        kind.check_stream(&layout, longest).py()?;
        let inner = kind.build(layout);
        let kind = kind.name();
        Ok(Self {
            inner: Some(inner),
            kind,
            samples: 0,
        })
    }

    /// Appends a chunk `(u, y)` to the current experiment (the GIL is released).
    fn push(
        &mut self,
        py: Python<'_>,
        u: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let (uv, yv) = (view(&u), view(&y));
        let n = yv.nrows();
        // pushed into a copy (a k x k triangle and the tail), kept only when complete: an
        // interrupted push leaves the compressor as it was
        let mut next = self.inner.clone().ok_or_else(finished)?;
        crate::search::detach(py, || next.push(uv, yv))?;
        self.inner = Some(next);
        self.samples += n;
        Ok(())
    }

    /// Closes the current experiment; the next push starts a new one.
    fn end_experiment(&mut self) -> PyResult<()> {
        self.inner
            .as_mut()
            .ok_or_else(finished)?
            .end_experiment()
            .py()
    }

    /// Closes the last experiment and returns the `HankelFactor`.
    fn finish(&mut self, py: Python<'_>) -> PyResult<PyHankelFactor> {
        let inner = self.inner.take().ok_or_else(finished)?;
        let f = crate::search::detach(py, || inner.finish())?;
        Ok(PyHankelFactor { inner: f })
    }

    /// Samples pushed so far.
    #[getter]
    fn samples(&self) -> usize {
        self.samples
    }

    #[getter]
    fn compressor(&self) -> &'static str {
        self.kind
    }

    fn __repr__(&self) -> String {
        let state = if self.inner.is_some() {
            "open"
        } else {
            "finished"
        };
        format!(
            "StreamingCompressor(compressor={:?}, samples={}, {state})",
            self.kind, self.samples
        )
    }
}

/// Lagged correlation sums of a stretch of data: mergeable and picklable.
#[pyclass(name = "CorrelationSums", module = "sysid._sysid")]
#[derive(Clone)]
pub struct PyCorrelationSums {
    inner: CorrelationSums,
}

#[pymethods]
impl PyCorrelationSums {
    #[new]
    #[pyo3(signature = (n_inputs, n_outputs, past, future, center, scale, longest=None))]
    fn new(
        n_inputs: usize,
        n_outputs: usize,
        past: usize,
        future: usize,
        center: PyReadonlyArray1<'_, f64>,
        scale: PyReadonlyArray1<'_, f64>,
        longest: Option<usize>,
    ) -> PyResult<Self> {
        let layout = layout(n_inputs, n_outputs, past, future, longest)?;
        Ok(Self {
            inner: CorrelationSums::new(layout, vec1(&center), vec1(&scale)).py()?,
        })
    }

    /// Shift and power-of-two scale per channel (inputs then outputs) estimated from a chunk.
    #[staticmethod]
    fn center_scale<'py>(
        py: Python<'py>,
        u: PyReadonlyArray2<'py, f64>,
        y: PyReadonlyArray2<'py, f64>,
    ) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>) {
        let (c, s) = CorrelationSums::center_scale(view(&u), view(&y));
        (slice_to_numpy(py, &c), slice_to_numpy(py, &s))
    }

    /// Appends samples to the open experiment (the GIL is released).
    fn push(
        &mut self,
        py: Python<'_>,
        u: PyReadonlyArray2<'_, f64>,
        y: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<()> {
        let (uv, yv) = (view(&u), view(&y));
        // into a copy, kept only when complete (see StreamingCompressor.push)
        let mut next = self.inner.clone();
        crate::search::detach(py, || next.push(uv, yv))?;
        self.inner = next;
        Ok(())
    }

    /// Closes the open experiment.
    fn end_experiment(&mut self) -> PyResult<()> {
        self.inner.end_experiment().py()
    }

    /// Sums of `self` followed by `other` (a new object).
    fn merge(&self, other: &PyCorrelationSums) -> PyResult<PyCorrelationSums> {
        Ok(PyCorrelationSums {
            inner: self.inner.merge(&other.inner).py()?,
        })
    }

    /// The `HankelFactor` of everything summed (closing the open experiment of a copy).
    #[pyo3(signature = (min_relative_pivot=1e-10))]
    fn to_factor(&self, py: Python<'_>, min_relative_pivot: f64) -> PyResult<PyHankelFactor> {
        let s = self.inner.clone();
        let f = crate::search::detach(py, || s.into_factor(min_relative_pivot))?;
        Ok(PyHankelFactor { inner: f })
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
    fn open_samples(&self) -> usize {
        self.inner.open_samples()
    }

    #[staticmethod]
    #[allow(clippy::too_many_arguments)]
    fn _from_state(
        layout: (usize, usize, usize, usize),
        center: PyReadonlyArray1<'_, f64>,
        scale: PyReadonlyArray1<'_, f64>,
        gram: PyReadonlyArray2<'_, f64>,
        col_sum: PyReadonlyArray1<'_, f64>,
        counts: (usize, usize, usize),
        open_lag: PyReadonlyArray2<'_, f64>,
        open_vectors: (
            PyReadonlyArray1<'_, f64>,
            PyReadonlyArray1<'_, f64>,
            PyReadonlyArray1<'_, f64>,
        ),
    ) -> PyResult<PyCorrelationSums> {
        let layout = HankelLayout::new(layout.0, layout.1, layout.2, layout.3).py()?;
        let state = CorrelationState {
            layout,
            center: vec1(&center),
            scale: vec1(&scale),
            gram: view(&gram).to_owned(),
            col_sum: vec1(&col_sum),
            n_columns: counts.0,
            n_experiments: counts.1,
            open_samples: counts.2,
            open_lag: view(&open_lag).to_owned(),
            open_sum: vec1(&open_vectors.0),
            open_head: vec1(&open_vectors.1),
            open_tail: vec1(&open_vectors.2),
        };
        Ok(PyCorrelationSums {
            inner: CorrelationSums::from_state(state).py()?,
        })
    }

    /// Pickling support (Dask ships partial sums between processes).
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyTuple>> {
        let py = slf.py();
        let s = slf.borrow().inner.state();
        let ctor = py.get_type::<PyCorrelationSums>().getattr("_from_state")?;
        let lay = s.layout;
        let args = (
            (lay.n_inputs, lay.n_outputs, lay.past, lay.future),
            slice_to_numpy(py, &s.center),
            slice_to_numpy(py, &s.scale),
            to_numpy(py, s.gram.as_ref()),
            slice_to_numpy(py, &s.col_sum),
            (s.n_columns, s.n_experiments, s.open_samples),
            to_numpy(py, s.open_lag.as_ref()),
            (
                slice_to_numpy(py, &s.open_sum),
                slice_to_numpy(py, &s.open_head),
                slice_to_numpy(py, &s.open_tail),
            ),
        );
        PyTuple::new(py, [ctor, args.into_pyobject(py)?.into_any()])
    }

    fn __repr__(&self) -> String {
        let lay = self.inner.layout();
        format!(
            "CorrelationSums(n_inputs={}, n_outputs={}, past={}, future={}, n_columns={}, n_experiments={}, open_samples={})",
            lay.n_inputs,
            lay.n_outputs,
            lay.past,
            lay.future,
            self.inner.n_columns(),
            self.inner.n_experiments(),
            self.inner.open_samples()
        )
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyStreamingCompressor>()?;
    m.add_class::<PyCorrelationSums>()?;
    Ok(())
}
