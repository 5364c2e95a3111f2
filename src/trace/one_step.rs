//! The common one-interaction ray without the general bookkeeping: a path of one reflection
//! or refraction with its leg media given ([`OneStepPath`]). The start (the documented one)
//! and, when the solve ends with the point free and converged, the classification of a free
//! point are written out for one interaction; the solve itself is the solver's, and every other
//! ending goes through the general classification. The results are those of the general
//! solve, bit for bit, except for a refraction at an interface of one segment from the default
//! start, which the flat kernel (`trace::flat`) solves with steps of its own (the same status,
//! times within 1e-12: tested there).

use super::flat::{FlatRefraction, FlatSolution};
use super::plan::OneStepPath;
use super::start::{
    Placed, given_start, initial_guess, nearest_crossing, paraxial_one, refraction_guess,
};
use super::straight::{StraightStart, specular_point};
use super::{Context, RayRecord, Reason, Sequence, Start, Status, Workspace};
use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::{Pin, ProblemRef};
use crate::scene::StepKind;
use crate::solver::{Outcome, Solution, solve};

/// Where the documented start of a one-interaction ray is, when it is not the general guess.
#[derive(Clone, Copy, Debug)]
pub(crate) enum OneStepStart {
    /// At this parameter and segment.
    At(Placed),
    /// The image method proves that there is no path (`reason`): its specular point lies
    /// beyond the segment's end, or the receiver sees the source's image from behind the
    /// mirror (`s` the specular point, kept on the segment).
    NoPath { s: f64, reason: Reason },
    /// The general guess applies.
    General,
}

impl OneStepPath {
    /// Solves one-interaction path `path` from `start`: the record, with the ray's points,
    /// parameters and media in `ws`, as the general solve gives them. Out of line, so that
    /// the flat kernel's caller keeps a small stack frame.
    #[inline(never)]
    pub(super) fn solve(
        &self,
        cx: &Context,
        path: usize,
        source: Point,
        receiver: Point,
        start: Start,
        ws: &mut Workspace,
    ) -> RayRecord {
        let scene = cx.scene;
        let steps = &scene.paths()[path].steps[..1];
        let step = &steps[0];
        let line = &scene.interfaces()[step.interface].polyline;
        ws.resize(1);
        ws.ray.slowness.clear();
        ws.ray.slowness.extend_from_slice(&self.slowness);
        let g = ProblemRef {
            scene,
            steps,
            slowness: &self.slowness,
            curved: &[],
            source,
            receiver,
        };
        if let Start::Given(params) | Start::Trial(params) = start {
            given_start(scene, steps, params, &mut ws.newton);
        } else {
            match self.crossing_start(step.kind, line, source, receiver) {
                OneStepStart::At(at) => {
                    ws.newton.s[0] = at.s;
                    ws.newton.seg[0] = at.seg;
                    ws.newton.pin[0] = Pin::Free;
                }
                OneStepStart::NoPath { s, reason } => {
                    // As the general path leaves it: no points, the parameter at the end.
                    ws.newton.s[0] = s;
                    ws.newton.seg[0] = 0;
                    ws.newton.pin[0] = Pin::Free;
                    ws.ray.points.clear();
                    ws.ray.media.clear();
                    ws.ray.media.extend_from_slice(&self.media);
                    return RayRecord::failed(Status::NoPath, reason);
                }
                OneStepStart::General => {
                    initial_guess(scene, steps, source, receiver, ws);
                    refraction_guess(scene, steps, source, receiver, cx.guess, ws);
                }
            }
        }
        let sol = solve(&g, &mut ws.newton, cx.newton);
        ws.ray.media.clear();
        ws.ray.media.extend_from_slice(&self.media);
        let nw = &ws.newton;
        if sol.outcome != Outcome::Converged || nw.pin[0] != Pin::Free || nw.eval.vanished > 0 {
            return cx.classifier.classify(
                scene,
                Sequence::of(scene, path),
                source,
                receiver,
                &sol,
                nw,
                &mut ws.ray.points,
            );
        }
        let j = nw.seg[0];
        let points = &mut ws.ray.points;
        points.clear();
        points.extend_from_slice(&[source, line.point_on(j, nw.s[0]), receiver]);
        let (rel, len) = (&nw.eval.rel[..3], &nw.eval.len[..2]);
        let sides = std::iter::once((step.kind, line.normal(j)));
        cx.classifier.free_points(
            scene,
            path,
            sides,
            rel,
            len,
            nw.eval.vanish,
            points,
            &[j],
            &sol,
        )
    }

    /// The ray of a converged [`FlatRefraction::solve`] (its legs are on the sides a
    /// refraction demands, see [`OneStepPath::flat_status`]), with its parameter, points and
    /// media in `ws`.
    #[expect(
        clippy::too_many_arguments,
        reason = "the parts of a ray held in registers by its callers"
    )]
    #[inline(always)]
    pub(super) fn flat_ray(
        &self,
        cx: &Context,
        flat: &FlatRefraction,
        path: usize,
        source: Point,
        receiver: Point,
        sol: FlatSolution,
        ws: &mut Workspace,
    ) -> RayRecord {
        ws.resize(1);
        ws.newton.s[0] = sol.s;
        ws.newton.seg[0] = 0;
        ws.newton.pin[0] = Pin::Free;
        let points = [source, flat.point(sol.s), receiver];
        ws.ray.points.clear();
        ws.ray.points.extend_from_slice(&points);
        ws.ray.media.clear();
        ws.ray.media.extend_from_slice(&self.media);
        flat_status(cx, flat, path, &points, sol)
    }

    /// The documented start of a one-interaction ray when it is the crossing of `S → R` with
    /// the interface (a refraction that crosses it), moved to the paraxial point, or the image
    /// method's specular point (a reflection off an interface of one segment, one slowness:
    /// [`OneStepPath::images`]).
    #[inline(always)]
    pub(crate) fn crossing_start(
        &self,
        kind: StepKind,
        line: &Polyline,
        source: Point,
        receiver: Point,
    ) -> OneStepStart {
        if kind == StepKind::Reflect {
            if !self.images {
                return OneStepStart::General;
            }
            let specular = specular_point(line, source, receiver);
            return match specular.start {
                StraightStart::At => OneStepStart::At(Placed {
                    s: specular.s,
                    seg: 0,
                }),
                StraightStart::Beyond { .. } => OneStepStart::NoPath {
                    s: specular.s,
                    reason: Reason::BeyondEnd { step: 0 },
                },
                StraightStart::Apart { .. } => OneStepStart::NoPath {
                    s: specular.s,
                    reason: Reason::NoStationaryPath,
                },
                StraightStart::Unsure => OneStepStart::General,
            };
        }
        let Some(c) = nearest_crossing(line, source, receiver, 0.5) else {
            return OneStepStart::General;
        };
        let s = line.wrap(c.s);
        let j = line.segment_at_hint(s, c.seg);
        OneStepStart::At(paraxial_one(
            line,
            s,
            c.t,
            j,
            self.slowness,
            receiver - source,
        ))
    }
}

/// The record of the ray of a converged [`FlatRefraction::solve`] through `points` (the source,
/// `flat.point(sol.s)` and the receiver).
#[inline(always)]
pub(crate) fn flat_status(
    cx: &Context,
    flat: &FlatRefraction,
    path: usize,
    points: &[Point; 3],
    sol: FlatSolution,
) -> RayRecord {
    let [source, p, receiver] = *points;
    // The kernel's clean case puts the source and the receiver clearly on either side of the
    // interface's line (`flat::CLEAR`, above `SIDE_MARGIN` and the points' round-off): the
    // side test always passes (checked in debug builds).
    debug_assert!({
        let rel = [Vec2::default(), p - source, receiver - source];
        let (a, b) = super::classify::leg_sides(flat.normal(), f64::INFINITY, &rel, &sol.len);
        super::classify::sides_suit(StepKind::Refract, a, b)
    });
    let solution = Solution {
        outcome: Outcome::Converged,
        time: sol.time,
        iterations: sol.iterations,
        residual: sol.residual,
    };
    cx.classifier
        .unobstructed(cx.scene, path, points, &[0], &solution)
}
