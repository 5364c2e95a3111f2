//! The common one-interaction ray without the general bookkeeping: a path of one reflection
//! or refraction with its leg media given. The start (the documented one) and, when the solve
//! ends with the point free and converged, the side and obstruction tests are written out for
//! one interaction; the solve itself and every other ending go through the general code. The
//! results are those of the general solve, bit for bit, except for a refraction at an
//! interface of one segment from the default start, which the flat kernel (`trace::flat`)
//! solves with steps of its own (the same status, times within 1e-12: tested there).

use super::flat::{FlatRefraction, FlatSolution};
use super::straight::{self, single_specular};
use super::{
    RaySummary, Reason, Start, Status, Tracer, failed, given_start, initial_guess, leg_sides,
    nearest_crossing, paraxial_one, refraction_guess, sides_suit, summary, warm_start,
};
use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::Geometry;
use crate::scene::{Scene, StepKind};
use crate::solver::{Outcome, Pin, Solution, Workspace, solve};

/// A path of one interaction whose leg media are given.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SinglePath {
    pub(crate) media: [usize; 2],
    pub(crate) slowness: [f64; 2],
    /// The kernel of a refraction at a flat interface of one segment ([`SinglePath::flat`]).
    flat: Option<FlatRefraction>,
}

impl SinglePath {
    /// The path's one-interaction data, if it is such a path.
    pub(crate) fn of(scene: &Scene, path: usize) -> Option<SinglePath> {
        let spec = &scene.paths()[path];
        match (spec.steps.len(), spec.media.as_deref()) {
            (1, Some(&[m0, m1])) => {
                let slowness = [scene.media()[m0].slowness, scene.media()[m1].slowness];
                let step = &spec.steps[0];
                let line = &scene.interfaces()[step.interface].polyline;
                Some(SinglePath {
                    media: [m0, m1],
                    slowness,
                    flat: (step.kind == StepKind::Refract)
                        .then(|| FlatRefraction::of(line, slowness, scene.solver()))
                        .flatten(),
                })
            }
            _ => None,
        }
    }
}

impl SinglePath {
    /// The flat-refraction kernel of the path, if it has one.
    #[inline(always)]
    pub(crate) fn flat(&self) -> Option<&FlatRefraction> {
        #[cfg(test)]
        if crate::solver::tests::FLAT_OFF.with(|c| c.get()) {
            return None;
        }
        self.flat.as_ref()
    }
}

impl Tracer<'_> {
    /// Solves one-interaction path `path` (described by `sp`) from `start`: the summary, with
    /// the ray's points, parameters and media in `ws`, as the general solve gives them. Out of
    /// line, so that the flat kernel's caller ([`Tracer::solve_inner`]) keeps a small stack
    /// frame.
    #[inline(never)]
    pub(super) fn solve_single_path(
        &self,
        sp: &SinglePath,
        source: Point,
        receiver: Point,
        path: usize,
        start: Start,
        ws: &mut Workspace,
    ) -> RaySummary {
        let scene = self.scene;
        let steps = &scene.paths()[path].steps[..1];
        let step = &steps[0];
        let line = &scene.interfaces()[step.interface].polyline;
        ws.resize(1);
        ws.slowness.clear();
        ws.slowness.extend_from_slice(&sp.slowness);
        let g = Geometry {
            scene,
            steps,
            slowness: &sp.slowness,
            source,
            receiver,
        };
        if let Start::Given(params) = start {
            given_start(scene, steps, params, ws);
        } else {
            match self.single_crossing_start(sp, path, step.kind, line, source, receiver) {
                Ok((s, j)) => {
                    ws.s[0] = s;
                    ws.seg[0] = j;
                    ws.pin[0] = Pin::Free;
                }
                Err(Some((step, s))) => {
                    // As the general path leaves it: no points, the parameter at the end.
                    ws.s[0] = s;
                    ws.seg[0] = 0;
                    ws.pin[0] = Pin::Free;
                    ws.points.clear();
                    ws.media.clear();
                    ws.media.extend_from_slice(&sp.media);
                    return failed(Status::NoPath, Reason::LeavesEnd { step });
                }
                Err(None) => {
                    initial_guess(scene, steps, source, receiver, ws);
                    refraction_guess(scene, steps, source, receiver, self.guess, ws);
                }
            }
            if let Start::Compare(guess) = start {
                warm_start(&g, guess, ws);
            }
        }
        let opts = scene.solver();
        let (outcome, sol) = solve(&g, ws, opts.tolerance, opts.max_iterations);
        ws.media.clear();
        ws.media.extend_from_slice(&sp.media);
        if outcome != Outcome::Converged || ws.pin[0] != Pin::Free || ws.eval.vanished > 0 {
            return self.classify(path, source, receiver, outcome, sol, ws);
        }
        let j = ws.seg[0];
        ws.points.clear();
        ws.points
            .extend_from_slice(&[source, line.point_on(j, ws.s[0]), receiver]);
        let (rel, len) = (&ws.eval.rel[..3], &ws.eval.len[..2]);
        self.single_status(
            path,
            step.kind,
            line.normal(j),
            j,
            &ws.points,
            rel,
            len,
            sol,
        )
    }

    /// The ray of a converged [`FlatRefraction::solve`]: its status (the obstruction test; its
    /// legs are on the sides a refraction demands, see [`Tracer::flat_status`]), with its
    /// parameter, points and media in `ws`.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray held in registers by its callers"
    )]
    #[inline(always)]
    pub(super) fn single_flat(
        &self,
        sp: &SinglePath,
        flat: &FlatRefraction,
        path: usize,
        source: Point,
        receiver: Point,
        sol: FlatSolution,
        ws: &mut Workspace,
    ) -> RaySummary {
        ws.resize(1);
        ws.s[0] = sol.s;
        ws.seg[0] = 0;
        ws.pin[0] = Pin::Free;
        let (summary, pts) = self.flat_status(flat, path, source, receiver, sol);
        ws.points.clear();
        ws.points.extend_from_slice(&pts);
        ws.media.clear();
        ws.media.extend_from_slice(&sp.media);
        summary
    }

    /// The status and points of the ray of a converged [`FlatRefraction::solve`].
    #[inline(always)]
    pub(crate) fn flat_status(
        &self,
        flat: &FlatRefraction,
        path: usize,
        source: Point,
        receiver: Point,
        sol: FlatSolution,
    ) -> (RaySummary, [Point; 3]) {
        let p = flat.point(sol.s);
        let pts = [source, p, receiver];
        // The kernel's clean case puts the source and the receiver clearly on either side of
        // the interface's line (`flat::CLEAR`, above `SIDE_MARGIN` and the points'
        // round-off): the side test always passes (checked in debug builds).
        debug_assert!({
            let rel = [Vec2::default(), p - source, receiver - source];
            let (a, b) = leg_sides(flat.normal(), 1.0, &rel, &sol.len);
            sides_suit(StepKind::Refract, a, b)
        });
        let summary = self.unobstructed_status(
            path,
            &pts,
            0,
            Solution {
                time: sol.time,
                iterations: sol.iterations,
                residual: sol.residual,
            },
        );
        (summary, pts)
    }

    /// The documented start of a one-interaction path when it is the crossing of `S → R` with
    /// the interface (a refraction that crosses it), moved to the paraxial point, or the image
    /// method's specular point (a reflection of path `p` off an interface of one segment, one
    /// slowness: [`Tracer::exact_start`]): `(s, segment)`. `Err(Some((0, s)))` when that
    /// specular point lies beyond the segment's end (no path; `s` the end), `Err(None)` when
    /// the general guess applies.
    #[inline(always)]
    pub(crate) fn single_crossing_start(
        &self,
        sp: &SinglePath,
        p: usize,
        kind: StepKind,
        line: &Polyline,
        source: Point,
        receiver: Point,
    ) -> Result<(f64, usize), Option<(usize, f64)>> {
        if kind == StepKind::Reflect {
            // The image method: a mirror of one segment, one slowness on both legs (not a
            // converted wave), and the default refinement.
            if !self.exact_start(p) {
                return Err(None);
            }
            return match single_specular(line, source, receiver) {
                (s, straight::Start::At) => Ok((s, 0)),
                (s, straight::Start::Beyond { step }) => Err(Some((step, s))),
                (_, straight::Start::Unsure) => Err(None),
            };
        }
        let (s, t, j) = nearest_crossing(line, source, receiver, 0.5).ok_or(None)?;
        let s = line.wrap(s);
        let j = line.segment_at_hint(s, j);
        Ok(paraxial_one(line, s, t, j, sp.slowness, receiver - source))
    }

    /// The status of a one-interaction ray whose solve ended converged with its point free:
    /// the side and obstruction tests of `classify`, written out for one interaction. `n` is
    /// the normal of the point's segment `j`, `pts` the source, the point and the receiver, `rel`
    /// the same relative to the source and `len` the two legs' lengths.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray held in registers by its callers"
    )]
    #[inline(always)]
    pub(crate) fn single_status(
        &self,
        path: usize,
        kind: StepKind,
        n: Vec2,
        j: usize,
        pts: &[Point],
        rel: &[Vec2],
        len: &[f64],
        sol: Solution,
    ) -> RaySummary {
        // `Tracer::wrong_side` for a free point with both legs there.
        let (a, b) = leg_sides(n, 1.0, rel, len);
        if !sides_suit(kind, a, b) {
            return RaySummary {
                status: Status::NoPath,
                reason: Some(Reason::WrongSide { step: 0 }),
                ..summary(sol)
            };
        }
        self.unobstructed_status(path, pts, j, sol)
    }

    /// [`single_status`](Self::single_status) after its side test: the obstruction test.
    #[inline(always)]
    fn unobstructed_status(
        &self,
        path: usize,
        pts: &[Point],
        j: usize,
        sol: Solution,
    ) -> RaySummary {
        let (status, reason) = match self.obstruction(path, pts, &[j]) {
            Some((leg, interface)) => {
                (Status::Obstructed, Some(Reason::Crosses { leg, interface }))
            }
            None => (Status::Converged, None),
        };
        RaySummary {
            status,
            reason,
            ..summary(sol)
        }
    }
}
