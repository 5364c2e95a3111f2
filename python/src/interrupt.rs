//! Long calls that Ctrl-C interrupts: the work runs on a thread of its own with the GIL
//! released, while the calling thread polls Python's signal handlers (and reports progress);
//! a `KeyboardInterrupt` there asks the work to stop (the library's `Run`) and is raised as
//! soon as it has.

use std::time::Duration;

use eigenray::options::Run;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// How often the calling thread looks at the signals (and reports progress).
const POLL: Duration = Duration::from_millis(20);

/// Runs `work` (which runs with `run`) on a thread of its own while this one polls the
/// signals every [`POLL`] and calls `tick` (with the GIL held: progress reports). A signal
/// handler's exception (`KeyboardInterrupt`) requests a stop of `run`, waits for the work to
/// end (it checks `run` before each piece of its work) and is returned; otherwise the work's
/// result.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    run: &Run,
    work: impl FnOnce() -> T + Send,
    mut tick: impl FnMut(),
) -> PyResult<T> {
    std::thread::scope(|scope| {
        let worker = scope.spawn(work);
        let mut interrupted = None;
        while !worker.is_finished() {
            py.detach(|| std::thread::sleep(POLL));
            if let Err(e) = py.check_signals() {
                run.request_stop();
                interrupted = Some(e);
                break;
            }
            tick();
        }
        let done = py.detach(|| worker.join());
        match (interrupted, done) {
            (Some(e), _) => Err(e),
            (None, Ok(out)) => Ok(out),
            (None, Err(_)) => Err(PyRuntimeError::new_err("the work panicked")),
        }
    })
}
