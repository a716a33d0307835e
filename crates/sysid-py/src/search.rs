//! What every long computation of the bindings needs: the GIL released while it runs, Ctrl-C
//! seen within a few milliseconds ([`watch`], [`detach`]), the progress callback of the shared
//! optimiser (`sysid_core::optim`) as an observer ([`run`]), and the search's solution and
//! covariance as dict items.
//!
//! Interruption: the computation runs on a helper thread under a [`Flag`] of
//! `sysid_core::interrupt` while the calling (main) thread, with the GIL released, asks the
//! interpreter for pending signals every 10 ms (`PyErr_CheckSignals`, which runs the Python
//! handler: by default it raises `KeyboardInterrupt`). The first exception a handler raises
//! sets the flag; the core's loops call `interrupt::check()` every few milliseconds of work,
//! in every thread of their parallel sections, and return; the exception is re-raised here
//! unchanged. The helper is joined before returning: no thread keeps running.

use crate::convert::{mat_to_numpy, slice_to_numpy};
use crate::errors::IntoPy;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use sysid_core::interrupt::{self, Flag};
use sysid_core::optim::{self, Flow, Iteration};

thread_local! {
    /// The exception raised by a signal handler during the current computation (for
    /// `errors::to_py` of `SysidError::Interrupted`).
    static PENDING: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

/// Runs pending signal handlers (on the main thread; elsewhere Python reports none) and
/// keeps the first exception they raise; on another thread, the stop its Python caller set
/// for it (`sysid._progress.stopped_by`: Ctrl-C seen by the main thread) raises
/// `KeyboardInterrupt` the same way.
fn poll_signals() -> bool {
    Python::attach(
        |py| match py.check_signals().and_then(|()| stop_requested(py)) {
            Ok(()) => false,
            Err(e) => {
                PENDING.with(|p| {
                    p.borrow_mut().get_or_insert(e);
                });
                true
            }
        },
    )
}

/// The thread that imported the module: Python's main thread, where signals arrive.
static MAIN_THREAD: std::sync::OnceLock<std::thread::ThreadId> = std::sync::OnceLock::new();

/// Remembers the importing thread as the main one (called once, by the module's init).
pub fn note_main_thread() {
    let _ = MAIN_THREAD.set(std::thread::current().id());
}

/// `Err(KeyboardInterrupt)` once `sysid._progress.stop_requested()` says this thread's work
/// is to stop; `Ok` otherwise, on the main thread (which its signals stop), and when the
/// bindings are used without the package (the module or function not found). Any other
/// exception is returned, not dropped.
fn stop_requested(py: Python<'_>) -> PyResult<()> {
    if MAIN_THREAD.get() == Some(&std::thread::current().id()) {
        return Ok(()); // the main thread is stopped by its signals alone
    }
    let found = py
        .import("sysid._progress")
        .and_then(|m| m.getattr("stop_requested"));
    let f = match found {
        Ok(f) => f,
        Err(e)
            if e.is_instance_of::<pyo3::exceptions::PyImportError>(py)
                || e.is_instance_of::<pyo3::exceptions::PyAttributeError>(py) =>
        {
            return Ok(())
        }
        Err(e) => return Err(e),
    };
    if f.call0()?.is_truthy()? {
        Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(
            "stopped: Ctrl-C reached the main thread while this fit ran on another",
        ))
    } else {
        Ok(())
    }
}

/// The exception that interrupted the computation, if any (taken: asked once).
pub fn take_pending() -> Option<PyErr> {
    PENDING.with(|p| p.borrow_mut().take())
}

/// Stack of the helper thread (the size of a main thread's).
const STACK: usize = 8 << 20;

/// Runs `work` on a helper thread under a fresh flag while this thread polls for signals
/// every [`interrupt::POLL_INTERVAL`] (a panic of `work` is resumed here). Should no thread
/// be had, `work` runs here and polls from inside (its own `interrupt::check` calls).
fn run_watched<T: Send>(work: impl FnOnce() -> T + Send) -> T {
    let flag = Flag::new();
    let owner = std::thread::current();
    let job = Mutex::new(Some(work));
    let take = || job.lock().ok().and_then(|mut j| j.take());
    // set by the helper when its work is done, before it wakes this thread: waiting on
    // `is_finished` instead raced with the helper's exit (woken before the helper had ended,
    // this thread parked again for a whole poll interval, 10 ms on every short call)
    let done = AtomicBool::new(false);
    let spawned = std::thread::scope(|s| {
        let handle = std::thread::Builder::new()
            .name("sysid-compute".into())
            .stack_size(STACK)
            .spawn_scoped(s, || {
                let out = take().map(|w| flag.enter(w));
                done.store(true, Ordering::Release);
                owner.unpark();
                out
            })
            .ok()?;
        // (`is_finished` too: a helper that panicked never sets `done`)
        while !done.load(Ordering::Acquire) && !handle.is_finished() {
            std::thread::park_timeout(interrupt::POLL_INTERVAL);
            if !flag.is_set() && !done.load(Ordering::Acquire) && poll_signals() {
                flag.set();
            }
        }
        match handle.join() {
            Ok(out) => out,
            Err(panic) => std::panic::resume_unwind(panic),
        }
    });
    match spawned {
        Some(out) => out,
        None => {
            let work = take().expect("the job runs once");
            interrupt::scope(poll_signals, work)
        }
    }
}

/// Runs `work` with the GIL released, interruptible: a signal handler's exception (Ctrl-C's
/// `KeyboardInterrupt`) raised meanwhile is returned instead of `work`'s value.
pub fn watch<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    let out = py.detach(|| run_watched(work));
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
    let geo = PyDict::new(py);
    geo.set_item("formed", sol.geodesic.formed)?;
    geo.set_item("accepted", sol.geodesic.accepted)?;
    geo.set_item("refused", sol.geodesic.refused)?;
    out.set_item("geodesic", geo)?;
    out.set_item("shortened", sol.shortened)?;
    out.set_item("remaining_decrease", sol.remaining_decrease)?;
    out.set_item("metric_switched_at", sol.metric_switched_at)?;
    Ok(())
}
