//! Cooperative interruption of long computations (Ctrl-C).
//!
//! A caller that wants its computation stoppable runs it inside [`scope`] with a `poll`
//! function: while the scope lives, [`check`] on that thread asks `poll` at most once per
//! [`POLL_INTERVAL`] whether to stop (the Python binding asks the interpreter for a pending
//! signal there), and once `poll` has said yes every later [`check`] of the scope fails with
//! [`SysidError::Interrupted`]. Parallel sections hand the scope's [`Flag`] to their workers
//! ([`Flag::current`] before the section, [`Flag::check`] in each task); a worker's check
//! only reads the flag. A caller that cannot poll from inside the computation (the Python
//! binding: only the main thread sees signals, and it may be waiting on a parallel section)
//! runs it on another thread under [`Flag::enter`] and sets the flag itself.
//!
//! Outside any scope [`check`] is a thread-local read and never fails, so a Rust user of the
//! crate pays nothing. Long loops call `check()?` every few milliseconds of work (a block of
//! samples, an evaluation, a pass): the cost is a thread-local read and a clock read.
//!
//! ```
//! use sysid_core::interrupt::{check, scope};
//! use sysid_core::SysidError;
//!
//! // a computation of about 20 ms that checks between blocks
//! fn work() -> sysid_core::Result<usize> {
//!     let mut blocks = 0;
//!     for _ in 0..200 {
//!         check()?;
//!         blocks += 1;
//!         std::thread::sleep(std::time::Duration::from_micros(100));
//!     }
//!     Ok(blocks)
//! }
//! assert_eq!(work(), Ok(200)); // outside a scope nothing stops it
//! // a poll that says "stop" ends it at the first check after POLL_INTERVAL
//! assert_eq!(scope(|| true, work), Err(SysidError::Interrupted));
//! ```

use crate::error::{Result, SysidError};
use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Shortest time between two calls of a scope's `poll`.
pub const POLL_INTERVAL: Duration = Duration::from_millis(10);

thread_local! {
    static FLAG: RefCell<Option<Arc<AtomicBool>>> = const { RefCell::new(None) };
    static POLL: Cell<Option<fn() -> bool>> = const { Cell::new(None) };
    static NEXT: Cell<Option<Instant>> = const { Cell::new(None) };
}

/// The stop flag of the scope a thread works for (none outside a scope).
#[derive(Clone, Debug, Default)]
pub struct Flag(Option<Arc<AtomicBool>>);

impl Flag {
    /// A new flag, not set: the stop flag of a computation run with [`Flag::enter`] on
    /// another thread while its owner watches for a reason to stop (and then sets it).
    pub fn new() -> Flag {
        Flag(Some(Arc::new(AtomicBool::new(false))))
    }

    /// The flag of the current thread's scope, to hand to parallel workers.
    pub fn current() -> Flag {
        Flag(FLAG.with(|f| f.borrow().clone()))
    }

    /// Whether the scope has been asked to stop.
    pub fn is_set(&self) -> bool {
        self.0.as_ref().is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Asks every thread working for the scope to stop.
    pub fn set(&self) {
        if let Some(f) = &self.0 {
            f.store(true, Ordering::Relaxed);
        }
    }

    /// `Err(SysidError::Interrupted)` when the flag is set; on the scope's own thread (a
    /// sequential run, or the caller taking part in a parallel section) it also polls as
    /// [`check`] does. The check of a parallel section's tasks.
    pub fn check(&self) -> Result<()> {
        if self.is_set() {
            Err(SysidError::Interrupted)
        } else {
            check()
        }
    }

    /// Runs `f` with this flag as the thread's (a worker of a parallel section, or a thread
    /// computing for an owner that watches): its [`check`] calls read the flag, never poll.
    pub fn enter<R>(&self, f: impl FnOnce() -> R) -> R {
        let _restore = Restore::install(self.0.clone(), None);
        f()
    }
}

/// Puts back the thread's previous scope when dropped (also on panic).
struct Restore {
    flag: Option<Arc<AtomicBool>>,
    poll: Option<fn() -> bool>,
    next: Option<Instant>,
}

impl Restore {
    fn install(flag: Option<Arc<AtomicBool>>, poll: Option<fn() -> bool>) -> Restore {
        let prev_flag = FLAG.with(|f| f.replace(flag));
        let prev_poll = POLL.with(|p| p.replace(poll));
        let prev_next = NEXT.with(|n| n.replace(poll.map(|_| Instant::now() + POLL_INTERVAL)));
        Restore {
            flag: prev_flag,
            poll: prev_poll,
            next: prev_next,
        }
    }
}

impl Drop for Restore {
    fn drop(&mut self) {
        FLAG.with(|f| f.replace(self.flag.take()));
        POLL.with(|p| p.set(self.poll));
        NEXT.with(|n| n.set(self.next));
    }
}

/// Runs `f` as an interruptible computation: [`check`] inside it calls `poll` (at most once
/// per [`POLL_INTERVAL`]) and fails from the first `true` on. Scopes nest; the previous one
/// is restored when `f` returns or panics.
pub fn scope<R>(poll: fn() -> bool, f: impl FnOnce() -> R) -> R {
    let _restore = Restore::install(Some(Arc::new(AtomicBool::new(false))), Some(poll));
    f()
}

/// The error of `f` run in a scope whose poll says "stop", entered a little after the
/// scope's first poll interval (so the first [`check`] inside `f` polls): what a
/// computation that checks returns, `None` from one that never does (test helper).
#[cfg(test)]
pub(crate) fn error_when_asked_to_stop<T>(f: impl FnOnce() -> Result<T>) -> Option<SysidError> {
    scope(
        || true,
        || {
            std::thread::sleep(POLL_INTERVAL * 2);
            f().err()
        },
    )
}

/// Whether the current computation should stop (polls the scope when due).
pub fn requested() -> bool {
    match FLAG.with(|f| f.borrow().as_ref().map(|a| a.load(Ordering::Relaxed))) {
        None => false,
        Some(true) => true,
        Some(false) => {
            let Some(poll) = POLL.with(|p| p.get()) else {
                return false;
            };
            let now = Instant::now();
            if NEXT.with(|n| n.get()).is_some_and(|t| now < t) {
                return false;
            }
            NEXT.with(|n| n.set(Some(now + POLL_INTERVAL)));
            // no borrow is held here: `poll` may run code that opens a scope of its own
            if poll() {
                Flag::current().set();
                true
            } else {
                false
            }
        }
    }
}

/// `Err(SysidError::Interrupted)` when the current computation should stop.
pub fn check() -> Result<()> {
    if requested() {
        Err(SysidError::Interrupted)
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    fn yes() -> bool {
        true
    }

    fn no() -> bool {
        false
    }

    #[test]
    fn outside_a_scope_nothing_stops() {
        assert!(check().is_ok());
        assert!(!Flag::current().is_set());
    }

    #[test]
    fn poll_is_rate_limited_and_sticky() {
        scope(yes, || {
            // the first poll is due only after POLL_INTERVAL
            assert!(check().is_ok());
            std::thread::sleep(POLL_INTERVAL * 2);
            assert_eq!(check(), Err(SysidError::Interrupted));
            assert!(Flag::current().is_set());
        });
        assert!(check().is_ok());
    }

    #[test]
    fn scopes_nest_and_restore() {
        scope(no, || {
            let outer = Flag::current();
            scope(yes, || Flag::current().set());
            assert!(!outer.is_set());
            assert!(!Flag::current().is_set());
        });
    }

    #[test]
    fn workers_see_the_flag() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        scope(no, || {
            let flag = Flag::current();
            flag.set();
            let stopped: Vec<bool> = pool.install(|| {
                (0..8)
                    .into_par_iter()
                    .map(|_| flag.enter(|| check().is_err()))
                    .collect()
            });
            assert!(stopped.iter().all(|&s| s));
        });
    }

    #[test]
    fn panics_restore_the_previous_scope() {
        let r = std::panic::catch_unwind(|| scope(yes, || panic!("boom")));
        assert!(r.is_err());
        assert!(Flag::current().0.is_none());
    }
}
