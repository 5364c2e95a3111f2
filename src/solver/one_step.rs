//! The fast path for a path of one interaction, in registers: the steps and tests of the
//! multi-point fast path (`super::fast_newton`) written out for one unknown.

use super::{
    IterationState, NewtonOptions, NewtonWorkspace, Outcome, Solution, last_residual_gradient,
    pivot_inverse,
};
use crate::geom::Vec2;
use crate::problem::{Frame, OnePointEval, ProblemRef, finite, max_num, min_num};

/// The solver's fast path (`fast_newton`) for a path of one interaction, in registers: the same
/// steps and tests.
pub(super) fn fast_newton(
    g: &ProblemRef,
    ws: &mut NewtonWorkspace,
    opts: NewtonOptions,
    fast: &mut IterationState,
) -> Option<Solution> {
    // Called first in a solve: no step taken yet, the curvature on.
    debug_assert!(fast.iterations == 0 && fast.polishes == 0 && fast.curvature);
    let f = &Frame::new(g.line(0), ws.seg[0], g.source);
    let w = [g.slowness[0], g.slowness[1]];
    let (to_receiver, coord) = (g.receiver - g.source, g.coord());
    let mut it = OneStepNewton::start(ws.s[0], f, w, to_receiver, coord);
    let done = it.run(f, w, to_receiver, coord, opts);
    ws.s[0] = it.s;
    it.e.store(f, to_receiver, &mut ws.eval);
    fast.iterations = it.iterations;
    fast.polishes = it.polishes;
    fast.curvature = it.iterations == 0;
    fast.evaluated = true;
    done.map(|outcome| it.solution(outcome))
}

/// The fast path's iteration for one interaction as a state and its steps: the same tests in
/// the same order as the multi-point fast path, the same arithmetic, in registers.
/// [`OneStepNewton::run`] drives it, for a solve with a workspace ([`fast_newton`]) and for
/// the batches' one-interaction chains without one.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct OneStepNewton {
    /// The parameter.
    pub s: f64,
    /// The evaluation at `s`.
    pub e: OnePointEval,
    /// Newton steps taken.
    pub iterations: usize,
    /// Newton steps taken after the residual met the tolerance.
    pub polishes: usize,
}

/// What [`OneStepNewton::next`] decided.
#[derive(Clone, Copy, Debug)]
enum OneStepNext {
    /// The solve ends with this outcome.
    End(Outcome),
    /// The general loop must take over from here.
    General,
    /// Evaluate at `to` and [`accept`](OneStepNewton::accept) the step (`polish`: the residual
    /// already met the tolerance).
    Try { to: f64, polish: bool },
}

impl OneStepNewton {
    /// The state at the start parameter `s` on the segment `f`, before any step (its
    /// evaluation adds the curvature estimate, as the first one of a solve does).
    #[inline(always)]
    pub fn start(s: f64, f: &Frame, w: [f64; 2], to_receiver: Vec2, coord: f64) -> Self {
        OneStepNewton {
            s,
            e: ProblemRef::evaluate_single(s, f, w, to_receiver, coord, true),
            iterations: 0,
            polishes: 0,
        }
    }

    /// The tests at the present point, in the general loop's order.
    #[inline(always)]
    fn next(&self, f: &Frame, tol: f64, max_iterations: usize) -> OneStepNext {
        let (s, e) = (self.s, &self.e);
        if e.vanished {
            return OneStepNext::General;
        }
        let residual = e.rmax;
        if !finite(residual) || self.iterations >= max_iterations {
            return OneStepNext::End(Outcome::NotConverged);
        }
        // `thomas` on one row.
        let x = e.r * (1.0 / e.h);
        // `thomas`'s pivot test on one row (|h| > 1e-14 |h| is h ≠ 0 for a finite h).
        if !(finite(e.h) && e.h != 0.0 && finite(x)) {
            return OneStepNext::General;
        }
        let d = -x;
        if d.abs() <= 4.0 * f64::EPSILON * (s.abs() + e.len[0] + e.len[1]) {
            return OneStepNext::End(Outcome::Converged);
        }
        let to = s + d;
        let reach = min_num(max_num(e.len[0], e.len[1]), f.quarter);
        if !(to > f.lo && to < f.hi && d.abs() <= reach) {
            return OneStepNext::General;
        }
        let polish = residual <= tol;
        if polish && (d.abs() <= tol.sqrt() * (e.len[0] + e.len[1]) || self.polishes >= 2) {
            return OneStepNext::End(Outcome::Converged);
        }
        OneStepNext::Try { to, polish }
    }

    /// Takes the step to `to` evaluated as `trial` if it lowers the merit enough; `false` (and
    /// no change) hands over to the general loop.
    #[inline(always)]
    fn accept(&mut self, to: f64, polish: bool, trial: OnePointEval) -> bool {
        if !(finite(trial.phi) && trial.phi <= (1.0 - 1e-4) * self.e.phi) {
            return false;
        }
        self.polishes += polish as usize;
        self.iterations += 1;
        (self.s, self.e) = (to, trial);
        true
    }

    /// Steps from the present point until the solve ends (`Some`, with its outcome) or must
    /// be handed to the general loop (`None`).
    #[inline(always)]
    pub fn run(
        &mut self,
        f: &Frame,
        w: [f64; 2],
        to_receiver: Vec2,
        coord: f64,
        opts: NewtonOptions,
    ) -> Option<Outcome> {
        loop {
            match self.next(f, opts.tolerance, opts.max_iterations) {
                OneStepNext::Try { to, polish } => {
                    let trial = ProblemRef::evaluate_single(to, f, w, to_receiver, coord, false);
                    if !self.accept(to, polish, trial) {
                        return None;
                    }
                }
                OneStepNext::End(outcome) => return Some(outcome),
                OneStepNext::General => return None,
            }
        }
    }

    /// The solution at the present point, ended with `outcome`.
    #[inline(always)]
    pub fn solution(&self, outcome: Outcome) -> Solution {
        Solution {
            outcome,
            time: self.e.time,
            iterations: self.iterations,
            residual: self.e.rmax,
        }
    }
}

/// How a one-interaction solution moves with the receiver (see
/// [`receiver_sensitivity`](super::receiver_sensitivity)): the parameter moves by
/// `−z (g · ΔR)` when the receiver moves by `ΔR`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ReceiverSensitivity {
    /// `1 / H`.
    pub z: f64,
    /// `∂r/∂R`.
    pub g: Vec2,
}

/// [`ReceiverSensitivity`] of a one-interaction solution held in registers, with `t` the
/// tangent at the point and `w` the receiver leg's slowness.
#[inline(always)]
pub(crate) fn one_step_sensitivity(
    e: &OnePointEval,
    t: Vec2,
    w: f64,
) -> Option<ReceiverSensitivity> {
    let g = last_residual_gradient(t, e.u[1], e.len[1], w)?;
    Some(ReceiverSensitivity {
        z: pivot_inverse(e.h)?,
        g,
    })
}
