//! numpy <-> faer without copies on the way in.
//!
//! Incoming arrays are viewed in place: `ArrayView2` strides (C order, Fortran order or any
//! slicing) become faer strides. Outgoing matrices are copied once into a new numpy array.

use faer::{Mat, MatRef};
use numpy::ndarray::{Array1, Array2, ArrayView1, ArrayView2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use sysid_core::StateSpace;

use crate::errors::IntoPy;

/// A faer view of a 2-D numpy array (no copy, any strides).
pub fn view<'a>(a: &'a PyReadonlyArray2<'_, f64>) -> MatRef<'a, f64> {
    view_nd(a.as_array())
}

/// A faer view of an ndarray view (no copy, any strides).
pub fn view_nd<'a>(a: ArrayView2<'a, f64>) -> MatRef<'a, f64> {
    let (r, c) = a.dim();
    let s = a.strides();
    // SAFETY: the pointer, shape and element strides come from a live ndarray view whose
    // lifetime bounds the returned MatRef.
    unsafe { MatRef::from_raw_parts(a.as_ptr(), r, c, s[0], s[1]) }
}

/// A 1-D numpy array as a Vec.
pub fn vec1(a: &PyReadonlyArray1<'_, f64>) -> Vec<f64> {
    let v: ArrayView1<'_, f64> = a.as_array();
    v.iter().copied().collect()
}

/// A faer matrix as a new numpy array.
pub fn to_numpy<'py>(py: Python<'py>, m: MatRef<'_, f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// An owned faer matrix as a new numpy array.
pub fn mat_to_numpy<'py>(py: Python<'py>, m: &Mat<f64>) -> Bound<'py, PyArray2<f64>> {
    to_numpy(py, m.as_ref())
}

/// A slice as a new 1-D numpy array.
pub fn slice_to_numpy<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    Array1::from(v.to_vec()).into_pyarray(py)
}

/// The matrices of `sys` as items `"a"`, `"b"`, `"c"`, `"d"` of `out`.
pub fn state_space_items(
    out: &Bound<'_, pyo3::types::PyDict>,
    py: Python<'_>,
    sys: &StateSpace,
) -> PyResult<()> {
    for (key, m) in [("a", &sys.a), ("b", &sys.b), ("c", &sys.c), ("d", &sys.d)] {
        out.set_item(key, mat_to_numpy(py, m))?;
    }
    Ok(())
}

/// A core `StateSpace` from four numpy matrices (shapes and finiteness checked by the core).
pub fn state_space(
    a: &PyReadonlyArray2<'_, f64>,
    b: &PyReadonlyArray2<'_, f64>,
    c: &PyReadonlyArray2<'_, f64>,
    d: &PyReadonlyArray2<'_, f64>,
) -> PyResult<StateSpace> {
    StateSpace::new(
        view(a).to_owned(),
        view(b).to_owned(),
        view(c).to_owned(),
        view(d).to_owned(),
    )
    .py()
}
