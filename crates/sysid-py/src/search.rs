//! What every long computation of the bindings needs: the GIL released while it runs, Ctrl-C
//! seen within a few milliseconds ([`watch`], [`detach`]), the progress callback of the shared
//! optimiser (`sysid_core::optim`) as an observer ([`run`]), and the search's solution and
//! covariance as dict items.
//!
//! Interruption: the computation runs inside a [`sysid_core::interrupt::scope`] whose poll
//! asks the interpreter for pending signals (`PyErr_CheckSignals`, which runs the Python
//! handler: by default it raises `KeyboardInterrupt`). The core's loops call
//! `interrupt::check()` every few milliseconds of work; the first exception the handler
//! raises stops them and is re-raised here unchanged. Nothing keeps running: the core returns
//! only when every worker of its parallel sections has seen the flag.

use crate::convert::{mat_to_numpy, slice_to_numpy};
use crate::errors::IntoPy;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::cell::RefCell;
use sysid_core::interrupt::{self, Flag};
use sysid_core::optim::{self, Flow, Iteration};

thread_local! {
    /// The exception raised by the signal handler during the current computation.
    static PENDING: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

/// The scope's poll: runs pending signal handlers (on the main thread; elsewhere Python
/// reports none) and keeps the first exception they raise.
fn poll_signals() -> bool {
    Python::attach(|py| match py.check_signals() {
        Ok(()) => false,
        Err(e) => {
            PENDING.with(|p| {
                p.borrow_mut().get_or_insert(e);
            });
            true
        }
    })
}

/// The exception that interrupted the computation, if any (taken: asked once).
pub fn take_pending() -> Option<PyErr> {
    PENDING.with(|p| p.borrow_mut().take())
}

/// Runs `work` with the GIL released, interruptible: a signal handler's exception (Ctrl-C's
/// `KeyboardInterrupt`) raised meanwhile is returned instead of `work`'s value.
pub fn watch<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let out = py.detach(|| interrupt::scope(poll_signals, work));
    match take_pending() {
        Some(e) => Err(e),
        None => Ok(out),
    }
}

/// [`watch`] for a core computation: its error becomes the matching `sysid.errors` exception.
pub fn detach<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> sysid_core::Result<T> + Send,
) -> PyResult<T> {
    watch(py, work)?.py()
}

/// The first Python error raised inside a callback (re-raised after the search).
pub type Slot = Option<PyErr>;

/// Calls `progress(iteration, cost, step_norm, gradient_norm, damping)` after every
/// iteration; `False` returned stops the search, an exception stops it (and the rest of the
/// computation, through the interrupt flag) and lands in `slot`. An interrupt stops it too.
pub fn observer<'a>(
    progress: &'a Option<Py<PyAny>>,
    slot: &'a mut Slot,
) -> impl FnMut(&Iteration) -> Flow + 'a {
    move |it: &Iteration| -> Flow {
        if interrupt::requested() {
            return Flow::Stop;
        }
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
                    // whatever the core runs after this search (refits, candidates) stops too
                    Flag::current().set();
                    Flow::Stop
                }
            }
        })
    }
}

/// Runs `search` (a core estimator taking the observer) as [`watch`] does, `progress` as its
/// observer; a signal's exception or else the first exception raised by the callback is
/// re-raised, a core error becomes the matching `sysid.errors` exception.
pub fn run<T: Send>(
    py: Python<'_>,
    progress: &Option<Py<PyAny>>,
    search: impl FnOnce(&mut dyn FnMut(&Iteration) -> Flow) -> sysid_core::Result<T> + Send,
) -> PyResult<T> {
    let mut slot: Slot = None;
    let result = watch(py, || search(&mut observer(progress, &mut slot)));
    finish(result, slot)
}

/// The outcome of a watched search whose observer filled `slot`: the signal's exception,
/// else the callback's, else the core's result.
pub fn finish<T>(result: PyResult<sysid_core::Result<T>>, slot: Slot) -> PyResult<T> {
    let result = result?;
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
