//! What a search reuses from one triple to the next on each thread.

use crate::geom::Point;
use crate::problem::Eval;
use crate::solver::NewtonWorkspace;

use super::place::Place;
use super::result::Arrival;

/// What a search reuses from one triple to the next (per thread): the solve's state and
/// scratch, the tuples' stack.
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) nw: NewtonWorkspace,
    pub(super) trial: Eval,
    pub(super) s_try: Vec<f64>,
    pub(super) delta: Vec<f64>,
    pub(super) diag: Vec<f64>,
    pub(super) off: Vec<f64>,
    pub(super) rhs: Vec<f64>,
    pub(super) cp: Vec<f64>,
    pub(super) places: Vec<Place>,
    pub(super) points: Vec<Point>,
    pub(super) slowness: Vec<f64>,
    pub(super) stack: Vec<u32>,
    pub(super) tuple: Vec<u32>,
    pub(super) segs: Vec<usize>,
    /// Arrivals no longer listed, whose vectors the next ones reuse.
    pub(super) spare: Vec<Arrival>,
}

impl Scratch {
    /// Sized for paths of `k` interactions.
    pub(super) fn resize(&mut self, k: usize) {
        if !self.nw.fits(k) {
            self.nw.resize_to(k);
        }
        self.trial.resize(k);
        for v in [
            &mut self.s_try,
            &mut self.delta,
            &mut self.diag,
            &mut self.off,
            &mut self.rhs,
            &mut self.cp,
        ] {
            v.resize(k, 0.0);
        }
        self.tuple.resize(k, 0);
        self.segs.resize(k, 0);
    }
}

thread_local! {
    /// Each thread's scratch, taken by a search and given back at its end.
    static SCRATCH: std::cell::Cell<Option<Box<Scratch>>> = const { std::cell::Cell::new(None) };
}

/// This thread's scratch, taken for a search (made on first use); [`give_back`] returns it.
pub(super) fn take_scratch() -> Box<Scratch> {
    SCRATCH.with(|c| c.take()).unwrap_or_default()
}

/// Returns `sc` to this thread, for its next search.
pub(super) fn give_back(sc: Box<Scratch>) {
    SCRATCH.with(|c| c.set(Some(sc)));
}

/// Runs `f` on this thread's scratch (made on first use).
pub(super) fn with_scratch<R>(f: impl FnOnce(&mut Scratch) -> R) -> R {
    let mut sc = take_scratch();
    let r = f(&mut sc);
    give_back(sc);
    r
}
