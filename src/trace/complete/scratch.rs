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
    /// The solve's state: parameters, segments, held points and the evaluation.
    pub(super) nw: NewtonWorkspace,
    /// The evaluation at a trial step.
    pub(super) trial: Eval,
    /// The parameters of a trial step.
    pub(super) s_try: Vec<f64>,
    /// The Newton step.
    pub(super) delta: Vec<f64>,
    /// The Hessian's diagonal, as the step solves it.
    pub(super) diag: Vec<f64>,
    /// The Hessian's off-diagonal, as the step solves it.
    pub(super) off: Vec<f64>,
    /// The step's right-hand side.
    pub(super) rhs: Vec<f64>,
    /// The tridiagonal solve's scratch.
    pub(super) cp: Vec<f64>,
    /// The places of the tuple or assignment being bounded.
    pub(super) places: Vec<Place>,
    /// The points of a classified path.
    pub(super) points: Vec<Point>,
    /// The legs' slownesses.
    pub(super) slowness: Vec<f64>,
    /// The tuples still to visit, `k` node indices each.
    pub(super) stack: Vec<u32>,
    /// The tuple being visited.
    pub(super) tuple: Vec<u32>,
    /// The segments of a leaf's assignment.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The scratch is sized for `k` points, and the thread gets the same one back: a search
    /// after the first allocates nothing.
    #[test]
    fn the_thread_keeps_its_scratch() {
        let first = with_scratch(|sc| {
            sc.resize(5);
            assert!(sc.nw.fits(5));
            for v in [&sc.s_try, &sc.delta, &sc.diag, &sc.off, &sc.rhs, &sc.cp] {
                assert_eq!(v.len(), 5);
            }
            assert_eq!((sc.tuple.len(), sc.segs.len()), (5, 5));
            sc.spare.push(Arrival::empty());
            std::ptr::from_ref(sc) as usize
        });
        let sc = take_scratch();
        assert_eq!(std::ptr::from_ref(&*sc) as usize, first);
        assert_eq!(sc.spare.len(), 1);
        give_back(sc);
        let again = with_scratch(|sc| {
            sc.spare.clear();
            std::ptr::from_ref(sc) as usize
        });
        assert_eq!(again, first);
    }
}
