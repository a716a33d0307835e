//! Python bindings of sysid-core: numpy <-> faer conversion, GIL release, error mapping.
//! Nothing else lives here: algorithms belong to `sysid-core`, orchestration to `python/sysid`.
//!
//! Each binding file exposes `register(m)`; add one line below per file.

use pyo3::prelude::*;

mod closed_loop;
mod convert;
mod errors;
mod greybox;
mod hankel;
mod hw;
mod narx;
mod pem;
mod polynomial;
mod realization;
mod recursive;
mod search;
mod simulate;
mod stats;
mod streaming;
mod subspace;
// issue 27 (branch tfproc): transfer functions
mod tf;
// issue 29 (branch nlss)
mod nlss;
// issue 29 (branch pnlss): frequency-weighted PNLSS
mod nlss_freq;
// issue 27 (branch tsonline): online estimators
mod recursive_estimators;
// issue 27 (branch nlnet): network nonlinearities of nlarx
mod narx_network;
// issue 31 (branch rules): option names and stabilisation from the core
mod linalg;
mod names;

#[pymodule]
fn _sysid(m: &Bound<'_, PyModule>) -> PyResult<()> {
    search::note_main_thread();
    // every result the same on any number of threads (faer's own decompositions and solves
    // split their work by thread above a few hundred rows)
    sysid_core::linalg::reproducible_threads();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    hankel::register(m)?;
    simulate::register(m)?;
    streaming::register(m)?;
    subspace::register(m)?;
    closed_loop::register(m)?;
    recursive::register(m)?;
    realization::register(m)?;
    pem::register(m)?;
    polynomial::register(m)?;
    greybox::register(m)?;
    narx::register(m)?;
    hw::register(m)?;
    stats::register(m)?;
    // issue 27 (branch tfproc): transfer functions
    tf::register(m)?;
    // issue 29 (branch nlss)
    nlss::register(m)?;
    // issue 29 (branch pnlss)
    nlss_freq::register(m)?;
    // issue 27 (branch tsonline)
    recursive_estimators::register(m)?;
    // issue 27 (branch nlnet)
    narx_network::register(m)?;
    // issue 31 (branch rules)
    linalg::register(m)?;
    names::register(m)?;
    Ok(())
}
