//! Python bindings of sysid-core: numpy <-> faer conversion, GIL release, error mapping.
use pyo3::prelude::*;

#[pymodule]
fn _sysid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
