//! What bounds a long call from outside its scene: a request to stop it ([`Stop`]), and the
//! memory and input size it may take ([`available_memory`], [`MAX_INPUT_BYTES`],
//! [`read_limited`]).
//!
//! A stop request reaches the work through one seam: a long call (a batch, every stationary
//! path, a search) runs each of its parallel jobs [`within`] its `Stop`, and the one place
//! where work is spent checks it: the complete search's budget test (`Search::over_budget`,
//! per tuple, bound and solve, with the `Stop` it took from [`current`]), which the default
//! mode's fallback, every stationary path and the search all go through; the parallel loops
//! also skip the jobs they have not begun once asked. So a call stops within one tuple of any
//! search, and one work unit of fast rays.

use std::cell::RefCell;
use std::io::Read;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A request to stop a long call, shared between the caller and the call's workers: the
/// caller (another thread, a signal handler's poll) calls [`request`](Stop::request); the
/// call returns soon after, its remaining work skipped (its results are then incomplete:
/// the caller that asked to stop should discard them).
///
/// ```
/// use eigenray::options::Stop;
/// let stop = Stop::new();
/// let seen_by_workers = stop.clone();
/// assert!(!seen_by_workers.requested());
/// stop.request();
/// assert!(seen_by_workers.requested());
/// ```
#[derive(Clone, Debug, Default)]
pub struct Stop(Arc<AtomicBool>);

impl Stop {
    /// A request not yet made.
    pub fn new() -> Stop {
        Stop::default()
    }

    /// Asks every call that runs with this `Stop` (or a clone) to stop.
    pub fn request(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether a stop was asked for.
    pub fn requested(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Runs `f` with this `Stop` as the stop request of the library calls it makes on this
    /// thread (a ray's search where its start finds no path, every stationary path of one
    /// triple): they stop soon after it is requested. The calls that work in parallel take
    /// their `Stop` as an argument instead ([`BatchOptions::stop`](crate::BatchOptions),
    /// [`Tracer::trace_stationary_with`](crate::Tracer::trace_stationary_with),
    /// [`Tracer::search_with`](crate::Tracer::search_with)).
    pub fn run<R>(&self, f: impl FnOnce() -> R) -> R {
        within(Some(self), f)
    }
}

thread_local! {
    /// The `Stop` of the job this thread runs, if it has one.
    static CURRENT: RefCell<Option<Stop>> = const { RefCell::new(None) };
}

/// Runs `f` on this thread with `stop` as the stop request of its work ([`stop_requested`]),
/// then puts back what was there.
pub(crate) fn within<R>(stop: Option<&Stop>, f: impl FnOnce() -> R) -> R {
    let Some(stop) = stop else { return f() };
    let before = CURRENT.with(|c| c.replace(Some(stop.clone())));
    let out = f();
    CURRENT.with(|c| *c.borrow_mut() = before);
    out
}

/// The `Stop` of the job this thread runs (see [`within`]), for a search to keep.
pub(crate) fn current() -> Option<Stop> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Whether the job this thread runs was asked to stop.
#[cfg(test)]
pub(crate) fn stop_requested() -> bool {
    CURRENT.with(|c| c.borrow().as_ref().is_some_and(Stop::requested))
}

/// The largest scene text read (256 MiB): the command-line tool and the Python package stop
/// reading beyond it.
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// At most [`MAX_INPUT_BYTES`] of `reader` (one byte more is read, to know that it is
/// exceeded): `None` when there is more, whatever the reader (an endless `/dev/zero` is read
/// no further).
///
/// # Errors
/// The reader's.
pub fn read_limited(reader: &mut dyn Read) -> std::io::Result<Option<Vec<u8>>> {
    let mut buf = Vec::new();
    reader.take(MAX_INPUT_BYTES + 1).read_to_end(&mut buf)?;
    Ok((buf.len() as u64 <= MAX_INPUT_BYTES).then_some(buf))
}

/// Memory available to a new allocation, in bytes, if known: Linux's `MemAvailable`, or less
/// where the process's address space is limited (`ulimit -v`): the limit less what the process
/// already maps. The command-line tool refuses a run that needs more before it starts; the
/// Python package raises `MemoryError`.
pub fn available_memory() -> Option<u64> {
    let field = |text: &str, key: &str| -> Option<u64> {
        let line = text.lines().find(|l| l.starts_with(key))?;
        line[key.len()..].split_whitespace().next()?.parse().ok()
    };
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let free = field(&info, "MemAvailable:")?.checked_mul(1024)?;
    let limit = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|l| field(&l, "Max address space"));
    let mapped = std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| field(&s, "VmSize:"))
        .map_or(0, |kb| kb.saturating_mul(1024));
    Some(match limit {
        Some(limit) => free.min(limit.saturating_sub(mapped)),
        None => free,
    })
}

/// Whether `bytes` more would fit in the memory available ([`available_memory`]; where that is
/// unknown, yes: the allocation itself is then the test).
pub fn fits_in_memory(bytes: u64) -> bool {
    available_memory().is_none_or(|have| bytes <= have)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A job sees its own `Stop`, nested jobs theirs, and a thread without one sees none.
    #[test]
    fn a_job_sees_its_own_stop() {
        assert!(!stop_requested() && current().is_none());
        let (a, b) = (Stop::new(), Stop::new());
        a.request();
        within(Some(&a), || {
            assert!(stop_requested());
            within(Some(&b), || assert!(!stop_requested()));
            assert!(stop_requested());
            within(None, || assert!(stop_requested()));
            std::thread::spawn(|| assert!(!stop_requested()))
                .join()
                .unwrap();
        });
        assert!(!stop_requested());
    }

    /// A short input is read whole (an endless one is tested through the command line and
    /// the Python package: it takes the limit's 256 MiB).
    #[test]
    fn a_short_input_is_read_whole() {
        let small = read_limited(&mut &b"{}"[..]).unwrap();
        assert_eq!(small.as_deref(), Some(&b"{}"[..]));
    }

    /// On Linux the available memory is known and positive; a petabyte never fits.
    #[test]
    fn memory_is_known_on_linux() {
        if cfg!(target_os = "linux") {
            assert!(available_memory().is_some_and(|b| b > 0));
            assert!(!fits_in_memory(1 << 50));
        }
        assert!(fits_in_memory(0));
    }
}
