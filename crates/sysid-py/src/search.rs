//! What every binding of the shared optimiser (`sysid_core::optim`) needs: the progress
//! callback as an observer, and the search's solution and covariance as dict items.

use crate::convert::{mat_to_numpy, slice_to_numpy};
use crate::errors::IntoPy;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sysid_core::optim::{self, Flow, Iteration};

/// The first Python error raised inside a callback (re-raised after the search).
pub type Slot = Option<PyErr>;

/// Calls `progress(iteration, cost, step_norm, gradient_norm, damping)` after every
/// iteration; `False` returned stops the search, an exception stops it and lands in `slot`.
pub fn observer<'a>(
    progress: &'a Option<Py<PyAny>>,
    slot: &'a mut Slot,
) -> impl FnMut(&Iteration) -> Flow + 'a {
    move |it: &Iteration| -> Flow {
        let Some(cb) = progress else {
            return Flow::Continue;
        };
        Python::attach(|py| {
            match cb.call1(
                py,
                (
                    it.iteration,
                    it.cost,
                    it.step_norm,
                    it.gradient_norm,
                    it.damping,
                ),
            ) {
                Ok(v) => {
                    if v.bind(py).is(&*pyo3::types::PyBool::new(py, false)) {
                        Flow::Stop
                    } else {
                        Flow::Continue
                    }
                }
                Err(e) => {
                    if slot.is_none() {
                        *slot = Some(e);
                    }
                    Flow::Stop
                }
            }
        })
    }
}

/// Runs `search` (a core estimator taking the observer) with the GIL released, `progress`
/// as its observer; the first exception raised by the callback is re-raised, a core error
/// becomes the matching `sysid.errors` exception.
pub fn run<T: Send>(
    py: Python<'_>,
    progress: &Option<Py<PyAny>>,
    search: impl FnOnce(&mut dyn FnMut(&Iteration) -> Flow) -> sysid_core::Result<T> + Send,
) -> PyResult<T> {
    let mut slot: Slot = None;
    let result = py.detach(|| search(&mut observer(progress, &mut slot)));
    if let Some(e) = slot {
        return Err(e);
    }
    result.py()
}

/// The optimiser's report and the parameter covariance, as items of `out`.
pub fn solution_items(
    out: &Bound<'_, PyDict>,
    py: Python<'_>,
    sol: &optim::Solution,
    cov: &optim::Covariance,
) -> PyResult<()> {
    out.set_item("covariance", mat_to_numpy(py, &cov.covariance))?;
    out.set_item("rank", cov.rank)?;
    out.set_item("unidentifiable", mat_to_numpy(py, &cov.unidentifiable))?;
    search_items(out, py, sol)
}

/// The optimiser's report alone (iterations, evaluations, `cost` and `history` of the
/// reported criterion, `weighted_history`, stop reason, condition, active bounds, gradient),
/// for bindings whose covariance is scaled their own way.
pub fn search_items(
    out: &Bound<'_, PyDict>,
    py: Python<'_>,
    sol: &optim::Solution,
) -> PyResult<()> {
    out.set_item("iterations", sol.iterations)?;
    out.set_item("evaluations", sol.evaluations)?;
    out.set_item("cost", sol.cost)?;
    out.set_item("history", sol.history.clone())?;
    out.set_item("weighted_history", sol.weighted_history.clone())?;
    out.set_item("stop", sol.stop.as_str())?;
    out.set_item("condition", sol.condition)?;
    out.set_item("active_bounds", sol.active_bounds.clone())?;
    out.set_item("gradient", slice_to_numpy(py, &sol.gradient))?;
    Ok(())
}
