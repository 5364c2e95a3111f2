//! What bounds a long call from outside its scene: its [`Run`] (a request to stop it, a
//! budget of work, the limits of its parts, and who hears of its progress), and the memory
//! and input size it may take ([`available_memory`], [`MAX_INPUT_BYTES`], [`read_limited`]).
//!
//! Every long call takes a `&Run` (a batch, every stationary path, one triple's stationary
//! paths, the search's beam trees and walks, the echoes of a scene, an impulse response's
//! rendering, a pressure's sum), and checks it through one seam, [`Run::keep_going`], before
//! each piece of its work: a work unit of a batch's rays, a block of a beam tree's beams, a
//! sequence of a walk, a tuple or solve of a complete search, an echo of a response. The
//! single-ray calls that take no `Run` ([`Tracer::solve`](crate::Tracer::solve) and its
//! kin, whose search where the start finds no path is bounded by
//! [`Limits::fallback_work`]) use the run their thread is [`within`](Run::within), if any.

use std::cell::RefCell;
use std::io::Read;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, LazyLock};

/// The work budget of the default mode's search of one ray, where its start leads to no
/// path (at most `solver.max_work`): 2^18 units, about 10 ms of one core, so that a batch
/// of many rays stays bounded; beyond it the ray is `not_converged` (`search_limit`). The
/// default of [`Limits::fallback_work`].
pub const FALLBACK_MAX_WORK: u64 = 1 << 18;

/// The largest `search.max_steps`: the depth of the beam tree (its stack holds one node per
/// step). The default of [`Limits::depth`].
pub const MAX_SEARCH_STEPS: usize = 1 << 16;

/// Beams one source's tree of a `search` may visit before it stops (its pairs then say
/// `complete: false`): the default of [`Limits::beams`]. At the tree's pace (tens of millions
/// of beams a second on one core) a few seconds.
pub const MAX_SEARCH_BEAMS: u64 = 1 << 28;

/// Arrivals a `search` may list before it stops (a few gigabytes of results): the default of
/// [`Limits::arrivals`].
pub const MAX_SEARCH_ARRIVALS: u64 = 1 << 24;

/// Tuples (and assignments solved) of the complete search of one sequence between one pair
/// of a `search`'s walk, beyond which it gives up and its pair says `complete: false`: the
/// default of [`Limits::walk_tuples`].
pub const MAX_WALK_TUPLES: usize = 1 << 20;

/// Bytes a `search`'s arrivals may hold at most ([`Limits::memory`]), whatever memory the
/// machine has: 16 GiB.
pub const MAX_SEARCH_MEMORY: u64 = 1 << 34;

/// Bytes a search's arrivals may hold where the memory available is not known: 2 GiB.
const UNKNOWN_MEMORY_SEARCH: u64 = 1 << 31;

/// Work done or about to be done, as a long call tells its [`Run`]
/// ([`keep_going`](Run::keep_going)) and the run its progress callback.
///
/// A unit of `work` is what the budget ([`Limits::work`]) counts: a ray solved by a batch, a
/// beam of a search's tree, a sequence visited by a search's walk, a work unit of a complete
/// search (a tuple of `k` points or a Newton step of an assignment of `k` points counts
/// `k + 1`, as `solver.max_work` counts them), a tap of an echo rendered into an impulse
/// response, an echo summed into a pressure. `items` count what a call's caller counts in
/// its progress bar: the rays of a batch, the triples of every stationary path, the pairs of
/// a search's walk, the echoes of a response.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Progress {
    /// Units of work.
    pub work: u64,
    /// Items begun.
    pub items: u64,
}

impl Progress {
    /// `work` units and no item.
    pub const fn work(work: u64) -> Progress {
        Progress { work, items: 0 }
    }

    /// `items` items of one unit each.
    pub const fn items(items: u64) -> Progress {
        Progress { work: items, items }
    }
}

/// What a long call may do: its budget over the whole call, and the limits of its parts
/// (each part that reaches its limit stops there and says it is not complete). The defaults
/// are the library's own limits; the scene's `solver.max_work` bounds each complete search
/// besides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Units of work over the whole call (see [`Progress`]); none by default (`u64::MAX`).
    /// A call that reaches it stops as a stop request stops it, its remaining work skipped
    /// and its results marked incomplete where they can say so.
    pub work: u64,
    /// Beams one source's tree of a search visits ([`MAX_SEARCH_BEAMS`]).
    pub beams: u64,
    /// Arrivals a search lists ([`MAX_SEARCH_ARRIVALS`]).
    pub arrivals: u64,
    /// Bytes the arrivals listed over a whole search (every source and pair) may hold, each
    /// counted with its points (`search::arrival_bytes`): a search of long paths stops here
    /// long before [`arrivals`](Self::arrivals). By default a quarter of the memory available
    /// ([`available_memory`]: what the machine has free, or less under an address-space
    /// limit), at most [`MAX_SEARCH_MEMORY`]: the rest is left to what the caller makes of
    /// the arrivals (written text, arrays, responses).
    pub memory: u64,
    /// Tuples (and assignments solved) of one complete search within a search's walk
    /// ([`MAX_WALK_TUPLES`]).
    pub walk_tuples: usize,
    /// Work of the search of a ray whose start finds no path, in the default mode
    /// ([`FALLBACK_MAX_WORK`], or `solver.max_work` when
    /// that is less).
    pub fallback_work: u64,
    /// Reflections a search's beam tree walks at most when `max_time` alone bounds it
    /// ([`MAX_SEARCH_STEPS`]).
    pub depth: usize,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            work: u64::MAX,
            beams: MAX_SEARCH_BEAMS,
            arrivals: MAX_SEARCH_ARRIVALS,
            memory: available_memory()
                .map_or(UNKNOWN_MEMORY_SEARCH, |have| have / 4)
                .min(MAX_SEARCH_MEMORY),
            walk_tuples: MAX_WALK_TUPLES,
            fallback_work: FALLBACK_MAX_WORK,
            depth: MAX_SEARCH_STEPS,
        }
    }
}

/// The control of one long call: a request to stop it (from another thread: a signal
/// handler's poll, a user interface), its [`Limits`] and budget, and a callback that hears of
/// its progress from the worker threads. Clones share the stop request and the work spent,
/// so a clone given to another thread stops the call.
///
/// A call that was stopped (asked to, or out of budget: [`stopped`](Run::stopped)) returns
/// soon after, its remaining work skipped; what it returns then says so where it can
/// (`complete: false` on a search's pairs and a stationary path's triples, rays a batch did
/// not write).
///
/// ```
/// use eigenray::options::{Progress, Run};
/// use std::sync::atomic::{AtomicU64, Ordering};
/// use std::sync::Arc;
/// let heard = Arc::new(AtomicU64::new(0));
/// let counter = heard.clone();
/// let run = Run::new()
///     .budget(10)
///     .on_progress(move |p: Progress| { counter.fetch_add(p.work, Ordering::Relaxed); });
/// assert!(run.keep_going(Progress::work(6)));
/// assert!(!run.keep_going(Progress::work(6))); // 12 > 10: refused, and the run stops
/// assert!(run.stopped() && !run.stop_requested());
/// assert_eq!((run.spent(), heard.load(Ordering::Relaxed)), (6, 6));
///
/// let run = Run::new();
/// let seen_by_workers = run.clone();
/// run.request_stop();
/// assert!(!seen_by_workers.keep_going(Progress::default()));
/// ```
#[derive(Clone, Default)]
pub struct Run {
    /// What the call may do.
    pub limits: Limits,
    progress: Option<Arc<dyn Fn(Progress) + Send + Sync>>,
    shared: Arc<Shared>,
}

/// What clones of a [`Run`] share.
#[derive(Debug, Default)]
struct Shared {
    /// A stop was requested.
    requested: AtomicBool,
    /// The budget refused work.
    exhausted: AtomicBool,
    /// Units of work spent.
    spent: AtomicU64,
    /// Items begun.
    items: AtomicU64,
}

impl std::fmt::Debug for Run {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Run")
            .field("limits", &self.limits)
            .field("progress", &self.progress.is_some())
            .field("shared", &self.shared)
            .finish()
    }
}

/// The run of the calls made without one: the default limits, never stopped.
static UNBOUNDED: LazyLock<Run> = LazyLock::new(Run::default);

impl Run {
    /// A run with the default [`Limits`], no budget and no progress callback.
    pub fn new() -> Run {
        Run::default()
    }

    /// A run that stops after `work` units of work ([`Limits::work`]).
    #[must_use]
    pub fn budget(mut self, work: u64) -> Run {
        self.limits.work = work;
        self
    }

    /// A run whose progress `f` hears of, from the worker threads, each time a call checks it
    /// ([`keep_going`](Run::keep_going)) with work that it lets it do.
    #[must_use]
    pub fn on_progress(mut self, f: impl Fn(Progress) + Send + Sync + 'static) -> Run {
        self.progress = Some(Arc::new(f));
        self
    }

    /// The run of the calls made without one (the default limits, never stopped).
    pub(crate) fn unbounded() -> &'static Run {
        &UNBOUNDED
    }

    /// Asks every call that runs with this run (or a clone) to stop.
    pub fn request_stop(&self) {
        self.shared.requested.store(true, Ordering::Relaxed);
    }

    /// Whether a stop was asked for ([`request_stop`](Run::request_stop)).
    pub fn stop_requested(&self) -> bool {
        self.shared.requested.load(Ordering::Relaxed)
    }

    /// Whether the run stopped its calls: a stop was asked for, or the budget refused work.
    pub fn stopped(&self) -> bool {
        self.stop_requested() || self.shared.exhausted.load(Ordering::Relaxed)
    }

    /// Units of work spent so far (counted only where the run has a budget or a progress
    /// callback).
    pub fn spent(&self) -> u64 {
        self.shared.spent.load(Ordering::Relaxed)
    }

    /// Items begun so far (rays, triples, pairs, echoes: see [`Progress`]), for a caller
    /// that polls the progress from another thread instead of hearing of it.
    pub fn items(&self) -> u64 {
        self.shared.items.load(Ordering::Relaxed)
    }

    /// The one test of a long call's control, before each piece of its work: whether it may
    /// do `next` (and then it is counted, and the progress callback hears of it). `false` once
    /// the run is stopped, or when `next.work` would take the work spent beyond the budget
    /// (the run is then stopped: nothing more is let through).
    #[inline]
    pub fn keep_going(&self, next: Progress) -> bool {
        if self.stopped() {
            return false;
        }
        if self.limits.work != u64::MAX || self.progress.is_some() {
            let spent = self.shared.spent.fetch_add(next.work, Ordering::Relaxed);
            if spent.saturating_add(next.work) > self.limits.work {
                self.shared.spent.fetch_sub(next.work, Ordering::Relaxed);
                self.shared.exhausted.store(true, Ordering::Relaxed);
                return false;
            }
        }
        if next.items > 0 {
            self.shared.items.fetch_add(next.items, Ordering::Relaxed);
        }
        if let Some(progress) = &self.progress {
            progress(next);
        }
        true
    }

    /// Runs `f` with this run as the run of the single-ray calls it makes on this thread
    /// ([`Tracer::solve`](crate::Tracer::solve), [`Tracer::trace`](crate::Tracer::trace) and
    /// their kin, whose search where the start finds no path then stops with it), then puts
    /// back the run that was there, also when `f` panics. Nested calls see their own run
    /// only; other threads never see it.
    pub fn within<R>(&self, f: impl FnOnce() -> R) -> R {
        /// Puts the previous run back when dropped (after `f`, or while a panic unwinds).
        struct Restore(Option<Run>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let before = self.0.take();
                CURRENT.with(|c| *c.borrow_mut() = before);
            }
        }
        let before = CURRENT.with(|c| c.replace(Some(self.clone())));
        let _restore = Restore(before);
        f()
    }
}

thread_local! {
    /// The run this thread's single-ray calls use ([`Run::within`]), if any.
    static CURRENT: RefCell<Option<Run>> = const { RefCell::new(None) };
}

/// Calls `f` with the run of this thread's single-ray calls ([`Run::within`]; without one,
/// the unbounded run).
pub(crate) fn with_current<R>(f: impl FnOnce(&Run) -> R) -> R {
    // A clone (no allocation), so that `f` may itself run something `within` a run.
    match CURRENT.with(|c| c.borrow().clone()) {
        Some(run) => f(&run),
        None => f(Run::unbounded()),
    }
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
    let info = read_proc_file("/proc/meminfo")?;
    let free = field(&info, "MemAvailable:")?.checked_mul(1024)?;
    // "unlimited" is no number: no limit (and then what the process maps is not read).
    let limit = read_proc_file("/proc/self/limits").and_then(|l| field(&l, "Max address space"));
    Some(match limit {
        Some(limit) => {
            let mapped = read_proc_file("/proc/self/status")
                .and_then(|s| field(&s, "VmSize:"))
                .map_or(0, |kb| kb.saturating_mul(1024));
            free.min(limit.saturating_sub(mapped))
        }
        None => free,
    })
}

/// The text of a small file of `/proc` (a few KiB), if it reads: into one buffer of a page
/// or two, a read or two, where `std::fs::read_to_string` asks for the size (`/proc` says 0)
/// and then reads 32 bytes, 32, 64, ... (a dozen system calls). The command-line tool looks
/// at the memory available several times a run.
fn read_proc_file(path: &str) -> Option<String> {
    let mut file = std::fs::File::open(path).ok()?;
    let mut text = vec![0u8; 4096];
    let mut len = 0;
    loop {
        if len == text.len() {
            text.resize(2 * len, 0);
        }
        match file.read(&mut text[len..]) {
            Ok(0) => break,
            Ok(n) => len += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return None,
        }
    }
    text.truncate(len);
    String::from_utf8(text).ok()
}

/// Whether `bytes` more would fit in the memory available ([`available_memory`]; where that is
/// unknown, yes: the allocation itself is then the test).
pub fn fits_in_memory(bytes: u64) -> bool {
    available_memory().is_none_or(|have| bytes <= have)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether this thread's single-ray calls would stop.
    fn stop_requested() -> bool {
        with_current(Run::stopped)
    }

    /// A job sees its own run, nested jobs theirs, a thread without one the unbounded run,
    /// and a run set for a call does not outlive it, also when the call panics.
    #[test]
    fn a_job_sees_its_own_run_and_no_other() {
        assert!(!stop_requested());
        let (a, b) = (Run::new(), Run::new());
        a.request_stop();
        a.within(|| {
            assert!(stop_requested());
            b.within(|| assert!(!stop_requested()));
            assert!(stop_requested());
            std::thread::spawn(|| assert!(!stop_requested()))
                .join()
                .unwrap();
        });
        assert!(!stop_requested());
        let call = std::panic::AssertUnwindSafe(|| a.within(|| panic!("a failing call")));
        let panicked = std::panic::catch_unwind(call);
        assert!(panicked.is_err());
        assert!(!stop_requested(), "the stop of a call that panicked leaked");
        b.within(|| {
            let call = std::panic::AssertUnwindSafe(|| a.within(|| panic!("a failing inner call")));
            let _ = std::panic::catch_unwind(call);
            assert!(
                !stop_requested(),
                "an inner call's stop leaked to the outer call"
            );
        });
    }

    /// A budget lets work through up to its units exactly, refuses the piece that would pass
    /// it, and stops the run; a stop request refuses everything, counted or not.
    #[test]
    fn a_budget_lets_through_at_most_its_units() {
        let run = Run::new().budget(10);
        assert!((0..10).all(|_| run.keep_going(Progress::work(1))));
        assert!(!run.stopped() && run.spent() == 10);
        assert!(!run.keep_going(Progress::work(1)));
        assert!(run.stopped() && !run.stop_requested());
        assert!(
            !run.keep_going(Progress::work(0)),
            "a stopped run lets nothing through"
        );
        assert_eq!(run.spent(), 10);
        let run = Run::new();
        assert!(run.keep_going(Progress::work(u64::MAX)));
        run.clone().request_stop();
        assert!(!run.keep_going(Progress::default()) && run.stop_requested());
    }

    /// A short input is read whole (an endless one is tested through the command line and
    /// the Python package: it takes the limit's 256 MiB).
    #[test]
    fn a_short_input_is_read_whole() {
        let small = read_limited(&mut &b"{}"[..]).unwrap();
        assert_eq!(small.as_deref(), Some(&b"{}"[..]));
    }

    /// A small file reads whole into its buffer, a file beyond the buffer's first page too
    /// (the buffer grows), byte for byte as `std::fs::read_to_string` reads them; a file
    /// that is not there, or not text, reads as nothing.
    #[test]
    fn a_proc_file_reads_as_the_standard_library_reads_it() {
        let dir = std::env::temp_dir().join(format!("eigenray-proc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for len in [0, 1, 4095, 4096, 4097, 10_000, 40_000] {
            let path = dir.join(format!("f{len}"));
            let text: String = (0..len).map(|i| (b'a' + (i % 26) as u8) as char).collect();
            std::fs::write(&path, &text).unwrap();
            let path = path.to_str().unwrap();
            assert_eq!(
                read_proc_file(path).as_deref(),
                Some(text.as_str()),
                "{len} bytes"
            );
        }
        let binary = dir.join("binary");
        std::fs::write(&binary, [0xff, 0xfe, 0x00]).unwrap();
        assert_eq!(read_proc_file(binary.to_str().unwrap()), None);
        assert_eq!(read_proc_file(dir.join("absent").to_str().unwrap()), None);
        let _ = std::fs::remove_dir_all(&dir);
        if cfg!(target_os = "linux") {
            let limits = std::fs::read_to_string("/proc/self/limits").unwrap();
            assert_eq!(read_proc_file("/proc/self/limits"), Some(limits));
        }
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
