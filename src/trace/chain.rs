//! Chains of rays: the rays of one path, one after another (a batch's work unit), each from
//! the last converged ray's solution moved with the receiver (a warm start) when the caller
//! says so, with the solver's kernel for the path chosen once per chain.
//!
//! The caller ([`ChainRays`]: the batch) says which ray comes next, whether it is warm-started,
//! and where each solved ray goes; [`Tracer::solve_chain`] chooses how the path's rays are
//! solved from its plan ([`PathPlan`](super::PathPlan)) and keeps the solutions the next starts are predicted
//! from ([`WarmStarts`]).

use std::ops::Range;

use super::{
    OneStepPath, OneStepStart, RayRecord, Start, Status, Tracer, Workspace, flat_status,
    given_param,
};
use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::problem::{Frame, coord};
use crate::scene::StepKind;
use crate::solver::{
    OneStepNewton, Outcome, ReceiverSensitivity, one_step_sensitivity, receiver_sensitivity,
};

/// One ray of a chain as its caller gives it: its ends, and whether it starts from the last
/// ray's solution.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChainLink {
    /// Source index.
    pub source: usize,
    /// Receiver index.
    pub receiver: usize,
    /// The receiver's position.
    pub here: Point,
    /// The receiver's move from the last ray's receiver.
    pub moved: Vec2,
    /// Whether the caller starts the ray from the last ray's solution (it converged, and its
    /// receiver is near); the chain still starts it from the default start where that is the
    /// better one ([`PathPlan::skips_warm_start`](super::PathPlan::skips_warm_start)).
    pub warm: bool,
}

/// The rays of a chain as its caller holds them: [`Tracer::solve_chain`] asks for each ray in
/// turn ([`link`](Self::link)) and hands it back solved ([`write()`](Self::write) or
/// [`write_one`](Self::write_one)) before it asks for the next.
pub(crate) trait ChainRays {
    /// Whether the caller warm-starts its rays at all (else the chain keeps no solutions).
    fn warm_starts(&self) -> bool;

    /// How many rays the chain holds.
    fn rays(&self) -> usize;

    /// Ray `i` of the chain.
    fn link(&mut self, i: usize) -> ChainLink;

    /// Ray `i` (at `link`) solved: its record, its points (meaningful only when the record has
    /// a time) and its leg media (one per leg when known, else fewer).
    fn write(
        &mut self,
        i: usize,
        link: &ChainLink,
        record: &RayRecord,
        points: &[Point],
        media: &[usize],
    );

    /// [`write()`](Self::write) for a ray of one interaction with its three points and two leg
    /// media.
    fn write_one(
        &mut self,
        i: usize,
        link: &ChainLink,
        record: &RayRecord,
        points: &[Point; 3],
        media: [usize; 2],
    );
}

/// The warm-start memory of one worker: per path, the last converged solution of its chain
/// and how it moves with the receiver ([`receiver_sensitivity`]), to predict the next
/// receiver's solution.
pub(crate) struct WarmStarts {
    /// Parameters of the last converged solution, per path (at the paths' parameter offsets).
    params: Vec<f64>,
    /// Their sensitivity `z` to the last residual.
    z: Vec<f64>,
    /// Per path: `∂rₖ₋₁/∂R`, or `None` (no prediction, the parameters as they are).
    g: Vec<Option<Vec2>>,
    /// The predicted start.
    guess: Vec<f64>,
    /// Scratch for the sensitivity solve.
    unit: Vec<f64>,
    cp: Vec<f64>,
}

impl WarmStarts {
    /// Memory for `paths` paths of `params` parameters in all.
    pub(crate) fn new(params: usize, paths: usize) -> WarmStarts {
        WarmStarts {
            params: vec![0.0; params],
            z: vec![0.0; params],
            g: vec![None; paths],
            guess: vec![0.0; params],
            unit: vec![0.0; params],
            cp: vec![0.0; params],
        }
    }

    /// Keeps the converged solution of path `p` in `ws` and its sensitivity.
    fn store(&mut self, p: usize, range: Range<usize>, ws: &Workspace) {
        let k = range.len();
        self.params[range.clone()].copy_from_slice(ws.parameters());
        self.g[p] = receiver_sensitivity(
            &ws.newton,
            &ws.ray.slowness,
            &mut self.z[range],
            &mut self.unit[..k],
            &mut self.cp[..k],
        );
    }

    /// [`store`](Self::store) for a one-interaction path whose solution `s` was solved without
    /// a workspace, with its sensitivity (`one_step_sensitivity`).
    fn store_one(&mut self, p: usize, at: usize, s: f64, sensitivity: Option<ReceiverSensitivity>) {
        self.params[at] = s;
        (self.z[at], self.g[p]) = match sensitivity {
            Some(sens) => (sens.z, Some(sens.g)),
            None => (0.0, None),
        };
    }

    /// The predicted start of path `p` for a receiver `moved` from the last one: the last
    /// solution moved by `−z (g · moved)` (a first-order continuation step).
    fn predict(&mut self, p: usize, range: Range<usize>, moved: Vec2) -> &[f64] {
        let guess = &mut self.guess[range.clone()];
        let (params, z) = (&self.params[range.clone()], &self.z[range]);
        match self.g[p] {
            Some(g) => {
                let shift = g.dot(moved);
                for ((out, &s), &zi) in guess.iter_mut().zip(params).zip(z) {
                    *out = s - zi * shift;
                }
            }
            None => guess.copy_from_slice(params),
        }
        guess
    }
}

/// What [`Tracer::one_step_chain`] needs of its path, looked up once.
#[derive(Clone, Copy)]
struct OneStepChain<'a> {
    one: &'a OneStepPath,
    p: usize,
    kind: StepKind,
    line: &'a Polyline,
}

/// A ray of [`Tracer::one_step_chain`] solved without the workspace: its record, points,
/// final iterate and segment.
struct OneStepRay {
    record: RayRecord,
    points: [Point; 3],
    newton: OneStepNewton,
    seg: usize,
}

impl Tracer {
    /// Solves the rays of `rays`, all of path `path`, one after another, each warm-started
    /// where the link says so (from the last converged ray's solution moved with the receiver,
    /// held in `warm` at `params`, the path's parameter offsets there) and solved again from
    /// the default start when that start does not converge: a batch's entry to the tracer.
    /// The path's plan decides once how its rays are solved: one-interaction paths in
    /// registers, without the workspace, the others ray by ray as one by one.
    #[inline(always)]
    pub(crate) fn solve_chain<R: ChainRays>(
        &self,
        path: usize,
        params: Range<usize>,
        rays: &mut R,
        warm: &mut WarmStarts,
        ws: &mut Workspace,
    ) {
        match self.plan_of(path).one_step() {
            Some(one) => self.one_step_chain(one, path, params.start, rays, warm, ws),
            None => self.path_chain(path, params, rays, warm, ws),
        }
    }

    /// Path `p`'s chain ray by ray, each starting from the last one's solution when the link
    /// says so.
    fn path_chain<R: ChainRays>(
        &self,
        p: usize,
        params: Range<usize>,
        rays: &mut R,
        warm: &mut WarmStarts,
        ws: &mut Workspace,
    ) {
        // Through parallel flat layers the default start is already the solution: a warm
        // start would leave a Newton step or two.
        let skip = self.plan_of(p).skips_warm_start(self.initial_guess());
        let warm_start = rays.warm_starts() && !skip;
        for b in 0..rays.rays() {
            let link = rays.link(b);
            let guess =
                (link.warm && warm_start).then(|| warm.predict(p, params.clone(), link.moved));
            let s = self.solve_ray(link.source, link.receiver, p, guess, ws);
            rays.write(b, &link, &s, ws.points(), ws.media());
            if s.status == Status::Converged && warm_start {
                warm.store(p, params.clone(), ws);
            }
        }
    }

    /// One ray from `guess` if given, else from the default start; a warm-started ray that
    /// does not converge is solved again from the default start.
    fn solve_ray(
        &self,
        source: usize,
        receiver: usize,
        p: usize,
        guess: Option<&[f64]>,
        ws: &mut Workspace,
    ) -> RayRecord {
        let start = guess.map_or(Start::Default, Start::Trial);
        let s = self.solve_indexed_start(source, receiver, p, start, ws);
        if guess.is_none() || s.status == Status::Converged {
            return s;
        }
        // The neighbour's path may lead elsewhere (off an end, onto a vertex): the
        // documented start decides.
        let cold = self.solve_indexed_start(source, receiver, p, Start::Default, ws);
        RayRecord {
            iterations: s.iterations + cold.iterations,
            ..cold
        }
    }

    /// [`path_chain`](Self::path_chain) for a one-interaction path (its parameter at `at` in
    /// `warm`), without the workspace: each ray's start, Newton steps ([`OneStepNewton`], the
    /// steps of one-by-one solving) and classification in registers. A ray that leaves this
    /// common case (no crossing or specular point to start from, a step leaving its segment,
    /// any status but `converged` after a warm start, no time) is solved one by one from the
    /// same start. A refraction at a one-segment interface goes through the flat kernel instead,
    /// never warm-started, as one by one.
    fn one_step_chain<R: ChainRays>(
        &self,
        one: &OneStepPath,
        p: usize,
        at: usize,
        rays: &mut R,
        warm: &mut WarmStarts,
        ws: &mut Workspace,
    ) {
        let scene = self.scene();
        let step = &scene.paths()[p].steps[0];
        let path = OneStepChain {
            one,
            p,
            kind: step.kind,
            line: &scene.interfaces()[step.interface].polyline,
        };
        // The last ray's segment: the first one tried for the next start.
        let mut seg = 0;
        // Off a flat mirror the default start is already the solution; at a flat interface
        // the kernel's steps from its own start cost less than a warm start saves.
        let flat = self.plan_of(p).flat();
        let skip = self.plan_of(p).skips_warm_start(self.initial_guess());
        let warm_start = rays.warm_starts() && !skip;
        let cx = self.context();
        for b in 0..rays.rays() {
            let link = rays.link(b);
            let guess =
                (link.warm && warm_start).then(|| warm.predict(p, at..at + 1, link.moved)[0]);
            let source = scene.sources()[link.source];
            let fast = match flat {
                // (Never warm-started.)
                Some(flat) => flat.solve(source, link.here).map(|sol| {
                    let points = [source, flat.point(sol.s), link.here];
                    let record = flat_status(&cx, flat, p, &points, sol);
                    (record, points, None)
                }),
                None => self
                    .one_step_fast(&path, source, link.here, guess, seg)
                    .map(|ray| (ray.record, ray.points, Some((ray.newton, ray.seg)))),
            };
            // A ray without a time goes one by one: where the start led to no stationary
            // path, the complete search answers.
            match fast.filter(|(record, _, _)| record.status.has_time()) {
                Some((record, points, newton)) => {
                    rays.write_one(b, &link, &record, &points, one.media);
                    let converged = record.status == Status::Converged;
                    if let Some((it, j)) = newton.filter(|_| converged && warm_start) {
                        let t = path.line.tangent(j);
                        let sens = one_step_sensitivity(&it.e, t, one.slowness[1]);
                        warm.store_one(p, at, it.s, sens);
                        seg = j;
                    }
                }
                None => {
                    let guess = guess.map(|g| [g]);
                    let guess = guess.as_ref().map(|g| &g[..]);
                    let s = self.solve_ray(link.source, link.receiver, p, guess, ws);
                    rays.write(b, &link, &s, ws.points(), ws.media());
                    if s.status == Status::Converged && warm_start {
                        warm.store(p, at..at + 1, ws);
                        seg = ws.newton.seg[0];
                    }
                }
            }
        }
    }

    /// One ray of [`one_step_chain`](Self::one_step_chain) from `guess` (else the crossing
    /// start), `hint` a segment to try first; `None` when the ray must be solved one by one.
    #[inline(always)]
    fn one_step_fast(
        &self,
        path: &OneStepChain,
        source: Point,
        receiver: Point,
        guess: Option<f64>,
        hint: usize,
    ) -> Option<OneStepRay> {
        let OneStepChain { one, p, kind, line } = *path;
        let at = match guess {
            Some(wanted) => given_param(line, wanted, hint),
            None => match one.crossing_start(kind, line, source, receiver) {
                OneStepStart::At(at) => at,
                _ => return None,
            },
        };
        let (s, j) = (at.s, at.seg);
        let (to_receiver, coord) = (receiver - source, coord(source, receiver));
        let f = &Frame::new(line, j, source);
        let mut it = OneStepNewton::start(s, f, one.slowness, to_receiver, coord);
        if it.run(f, one.slowness, to_receiver, coord, self.newton_options())
            != Some(Outcome::Converged)
        {
            return None;
        }
        let e = &it.e;
        let points = [source, line.point_on(j, it.s), receiver];
        let rel = [Vec2::default(), e.p, to_receiver];
        let sol = it.solution(Outcome::Converged);
        let sides = std::iter::once((kind, line.normal(j)));
        let record = self.classifier().free_points(
            self.scene(),
            p,
            sides,
            &rel,
            &e.len,
            e.vanish,
            &points,
            &[j],
            &sol,
        );
        if record.status != Status::Converged && guess.is_some() {
            return None;
        }
        Some(OneStepRay {
            record,
            points,
            newton: it,
            seg: j,
        })
    }
}
