//! The common one-interaction ray without the general bookkeeping: a path of one reflection
//! or refraction with its leg media given. The start (the documented one) and, when the solve
//! ends with the point free and converged, the side and obstruction tests are written out for
//! one interaction; the solve itself and every other ending go through the general code. The
//! results are those of the general solve, bit for bit.

use super::{
    RaySummary, Reason, SIDE_MARGIN, Start, Status, Tracer, given_start, initial_guess,
    refraction_guess, warm_start,
};
use crate::geom::{Point, Vec2};
use crate::polyline::{Polyline, segment_intersection};
use crate::problem::{Eval, Geometry};
use crate::scene::{Scene, StepKind};
use crate::solver::{Outcome, Pin, Workspace, solve};

/// A path of one interaction whose leg media are given.
#[derive(Clone, Copy, Debug)]
pub(super) struct SinglePath {
    media: [usize; 2],
    slowness: [f64; 2],
}

impl SinglePath {
    /// The path's one-interaction data, if it is such a path.
    pub(super) fn of(scene: &Scene, path: usize) -> Option<SinglePath> {
        let spec = &scene.paths()[path];
        match (spec.steps.len(), spec.media.as_deref()) {
            (1, Some(&[m0, m1])) => Some(SinglePath {
                media: [m0, m1],
                slowness: [scene.media()[m0].slowness, scene.media()[m1].slowness],
            }),
            _ => None,
        }
    }
}

impl Tracer<'_> {
    /// Solves one-interaction path `path` (described by `sp`) from `start`: the summary, with
    /// the ray's points, parameters and media in `ws`, as the general solve gives them.
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
            let crossing = match step.kind {
                StepKind::Refract => nearest_crossing(line, source, receiver),
                StepKind::Reflect => None,
            };
            match crossing {
                Some((s, t, j)) => {
                    let s = line.wrap(s);
                    let j = line.segment_at_hint(s, j);
                    let (s, j) = paraxial(line, s, t, j, sp.slowness, receiver - source);
                    ws.s[0] = s;
                    ws.seg[0] = j;
                    ws.pin[0] = Pin::Free;
                }
                None => {
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
        let point = line.point_on(j, ws.s[0]);
        ws.points.clear();
        ws.points.extend_from_slice(&[source, point, receiver]);
        let (status, reason) = if !sides_hold(step.kind, line.normal(j), &ws.eval) {
            (Status::NoPath, Some(Reason::WrongSide { step: 0 }))
        } else if let Some((leg, interface)) = self.obstruction(path, ws) {
            (Status::Obstructed, Some(Reason::Crosses { leg, interface }))
        } else {
            (Status::Converged, None)
        };
        RaySummary {
            status,
            time: sol.time,
            iterations: sol.iterations,
            residual: sol.residual,
            reason,
        }
    }
}

/// Polylines of at most this many segments are searched segment by segment, without their
/// BVH.
const SHORT: usize = 8;

/// The crossing of `source → receiver` with `line` nearest the middle of it, as
/// [`initial_guess`] takes it: `(parameter, fraction along source → receiver, segment)`.
#[inline]
fn nearest_crossing(line: &Polyline, source: Point, receiver: Point) -> Option<(f64, f64, usize)> {
    let mut best: Option<(f64, f64, f64, usize)> = None;
    let mut take = |s: f64, t: f64, j: usize| {
        let d = (t - 0.5).abs();
        if best.is_none_or(|(_, bd, _, _)| d < bd) {
            best = Some((s, d, t, j));
        }
    };
    let n = line.num_segments();
    if n <= SHORT {
        for j in 0..n {
            let (p, q) = line.segment(j);
            if let Some((t, u)) = segment_intersection(source, receiver, p, q) {
                take(line.start(j) + u * line.segment_length(j), t, j);
            }
        }
    } else {
        line.crossings_with_segment(source, receiver, take);
    }
    best.map(|(s, _, t, j)| (s, t, j))
}

/// [`refraction_guess`] for one refraction whose interface `S → R` crosses at fraction `t`,
/// parameter `s` on segment `j`: the paraxial point, `w` the two slownesses and `d = R − S`.
#[inline]
fn paraxial(line: &Polyline, s: f64, t: f64, j: usize, w: [f64; 2], d: Vec2) -> (f64, usize) {
    if !(t > 0.0 && t < 1.0) {
        return (s, j);
    }
    let first = (t - 0.0) / w[0];
    let sum = 0.0 + first + (1.0 - t) / w[1];
    let tau = (0.0 + first) / sum;
    let s = line.clamp_param(s + (tau - t) * d.dot(line.tangent(j)));
    (s, line.segment_at_hint(s, j))
}

/// [`Tracer::wrong_side`] for the free point of a one-interaction path whose solve left `e`
/// (no leg vanished): whether its legs lie on the sides `kind` demands of the segment with
/// unit normal `n`.
#[inline]
fn sides_hold(kind: StepKind, n: Vec2, e: &Eval) -> bool {
    let rel = &e.rel[..3];
    let a = n.dot(rel[0] - rel[1]);
    let b = n.dot(rel[2] - rel[1]);
    let (la, lb) = (e.len[0], e.len[1]);
    let a = if a.abs() <= SIDE_MARGIN * la { 0.0 } else { a };
    let b = if b.abs() <= SIDE_MARGIN * lb { 0.0 } else { b };
    match kind {
        StepKind::Reflect => (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0),
        StepKind::Refract => (a > 0.0 && b < 0.0) || (a < 0.0 && b > 0.0),
    }
}
