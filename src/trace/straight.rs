//! The start of a path whose every step is at an interface of one segment: refractions only
//! (flat or dipping layers) or reflections only (flat mirrors, the walls of a room), from
//! data prepared once per path.
//!
//! - **Refractions:** the crossings of `S → R` with the interfaces, one segment intersection
//!   each: the result of [`initial_guess`](super::initial_guess), bit for bit, without its
//!   search; anything else (a crossing off a segment, a leg along one) goes to it.
//! - **Reflections:** the image method. The source mirrored in each interface's line in turn,
//!   then the points back from the receiver towards each image: the specular points of the
//!   mirrors' lines, the solution itself when each lies inside its segment (the Newton solve
//!   only confirms it). Where one lies clearly beyond its segment's end, and every leg meets
//!   its mirror's line clearly between its ends, the path has no solution: `T` is convex in
//!   the parameters (a sum of lengths of affine functions of them), strictly so at a
//!   reflection, so those points are its one stationary point. Where a leg meets its mirror's
//!   line clearly outside the leg (the point it comes from and the image it aims at lie on
//!   one side: the leg would come from the mirror's back), and every leg before it, counted
//!   from the receiver, meets its line clearly, the path has no solution either: a path that
//!   reflects at every mirror on the side its legs come from unfolds into the straight line
//!   from the receiver to the last image, which crosses each mirror's line between the ends
//!   of its leg, and that line is the one drawn here. Anything else (a point near an end, a
//!   grazing leg) goes to the documented guess as before.

use super::Workspace;
use super::start::{PARALLEL, Placed, StepLines};
use crate::geom::{Point, Segment, Vec2};
use crate::polyline::{Polyline, point_between, segment_intersection};
use crate::problem::Frame;
use crate::problem::Pin;
use crate::scene::{Scene, Step, StepKind};

/// One interface of a [`StraightPath`]: its segment `p → q`, `e = q − p`, its length, and
/// the polyline's unit tangent.
#[derive(Clone, Copy, Debug)]
pub(super) struct StraightSegment {
    p: Point,
    q: Point,
    e: Vec2,
    len: f64,
    t: Vec2,
}

impl StraightSegment {
    fn of(line: &Polyline) -> StraightSegment {
        let Segment { start: p, end: q } = line.segment(0);
        // (An open polyline of one segment has no curvature estimate: `StraightSegment::frame`.)
        debug_assert_eq!(line.curvature(0), 0.0);
        StraightSegment {
            p,
            q,
            e: q - p,
            len: line.segment_length(0),
            t: line.tangent(0),
        }
    }

    /// The segment's length.
    #[inline(always)]
    pub(super) fn len(&self) -> f64 {
        self.len
    }

    /// The polyline's unit normal ([`Polyline::normal`]).
    #[inline(always)]
    pub(super) fn normal(&self) -> Vec2 {
        self.t.perp()
    }

    /// [`Frame::new`] of the polyline's segment relative to `origin`, bit for bit (the
    /// curvature estimate of an open polyline's end segments is zero).
    #[inline(always)]
    pub(super) fn frame(&self, origin: Point) -> Frame {
        Frame {
            a: self.p - origin,
            b: self.q - origin,
            t: self.t,
            lo: 0.0,
            hi: self.len,
            kappa: 0.0,
            quarter: f64::INFINITY,
        }
    }

    /// [`Polyline::point_on`] on the segment, bit for bit.
    #[inline(always)]
    pub(super) fn point_on(&self, s: f64) -> Point {
        point_between(self.p, self.q, self.t, 0.0, self.len, s)
    }

    /// `x` mirrored in the segment's line.
    #[inline(always)]
    fn mirror(&self, x: Point) -> Point {
        let n = self.e.perp() * (1.0 / self.len);
        x - n * (2.0 * n.dot(x - self.p))
    }

    /// Where `a → b` meets the segment's line: the parameter along the segment, and how
    /// (see [`Meet`]).
    #[inline(always)]
    fn meet(&self, a: Point, b: Point) -> (f64, Meet) {
        let d = b - a;
        let den = d.cross(self.e);
        let w = self.p - a;
        let (t, u) = (w.cross(self.e) / den, w.cross(d) / den);
        let angle = den.abs() > MARGIN * d.length() * self.len;
        let clear = t > MARGIN && t < 1.0 - MARGIN && angle;
        let meet = Meet {
            inside: t > 0.0 && t < 1.0 && u > 0.0 && u < 1.0,
            clear,
            beyond: clear && !(-MARGIN..=1.0 + MARGIN).contains(&u),
            apart: angle && !(-MARGIN..=1.0 + MARGIN).contains(&t),
        };
        (u * self.len, meet)
    }
}

impl StepLines for [StraightSegment] {
    #[inline(always)]
    fn tangent(&self, i: usize, _seg: usize) -> Vec2 {
        self[i].t
    }

    /// [`Polyline::clamp_param`] on an open polyline of one segment, bit for bit.
    #[inline(always)]
    fn place(&self, i: usize, s: f64, _seg: usize) -> Placed {
        let s = if s.is_finite() { s } else { 0.0 };
        Placed {
            s: s.clamp(0.0, self[i].len),
            seg: 0,
        }
    }
}

/// How far inside `(0, 1)` a fraction along `a → b` and outside `[0, 1]` a fraction along the
/// segment must be, and the sine of the angle between them must be, for a meeting to count
/// as clear or beyond the segment's end (the image method's round-off is a few ulps of that).
const MARGIN: f64 = 1e-9;

/// How a leg of the image method meets a mirror's line.
#[derive(Clone, Copy, Debug)]
struct Meet {
    /// Strictly inside the segment and strictly between the leg's ends.
    inside: bool,
    /// Clearly between the leg's ends, at a clear angle.
    clear: bool,
    /// Clear, and clearly beyond an end of the segment.
    beyond: bool,
    /// At a clear angle, and clearly outside the leg: both of its ends on one side of the line.
    apart: bool,
}

/// What a [`StraightPath`]'s start found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StraightStart {
    /// The start (for reflections, the solution).
    At,
    /// No path: the one stationary path through the mirrors' lines reflects at a point beyond
    /// the end of the mirror of step `step` (`T` is convex in the parameters and strictly so
    /// there, so no other stationary point exists). The parameters are at the segments' ends.
    Beyond {
        /// The step.
        step: usize,
    },
    /// No path: the leg to the mirror of step `step` meets that mirror's line clearly outside
    /// the leg, so no path reflects there on the side its legs come from (every leg after it
    /// meets its line clearly). The parameters are the specular points, kept on the segments.
    Apart {
        /// The step.
        step: usize,
    },
    /// Neither: the general guess applies.
    Unsure,
}

/// The image method's answer for a single reflection.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Specular {
    /// The specular point's parameter (at the segment's end when it lies beyond).
    pub s: f64,
    /// What it says.
    pub start: StraightStart,
}

/// The image method for a single reflection off `line` (a path that
/// [`StraightPath::exact`] holds for).
#[inline(always)]
pub(crate) fn specular_point(line: &Polyline, source: Point, receiver: Point) -> Specular {
    debug_assert!(line.num_segments() == 1 && !line.is_closed());
    let l = StraightSegment::of(line);
    let (s, meet) = l.meet(receiver, l.mirror(source));
    let start = if meet.inside {
        StraightStart::At
    } else if meet.beyond {
        StraightStart::Beyond { step: 0 }
    } else if meet.apart {
        StraightStart::Apart { step: 0 }
    } else {
        StraightStart::Unsure
    };
    Specular {
        s: s.clamp(0.0, l.len),
        start,
    }
}

/// A path whose every step refracts, or whose every step reflects, at an open interface of one
/// segment (reflections with one slowness on every leg).
#[derive(Debug)]
pub(crate) struct StraightPath {
    pub(super) lines: Box<[StraightSegment]>,
    kind: StepKind,
    /// Whether the segments are parallel (as `refraction_guess` takes them): for refractions,
    /// the ray-parameter start then solves the path up to round-off.
    pub(crate) parallel: bool,
    /// The legs' slownesses when the path's media are given (else empty).
    pub(super) slowness: Box<[f64]>,
}

impl StraightPath {
    /// The path's segments, if it is such a path.
    pub(crate) fn of(scene: &Scene, path: usize) -> Option<StraightPath> {
        let steps = &scene.paths()[path].steps;
        let polylines: Vec<_> = steps
            .iter()
            .map(|step| &scene.interfaces()[step.interface].polyline)
            .collect();
        let kind = steps.first()?.kind;
        let simple = |(step, line): (&Step, &&Polyline)| {
            step.kind == kind && line.num_segments() == 1 && !line.is_closed()
        };
        if !steps.iter().zip(&polylines).all(simple) {
            return None;
        }
        // The image method needs one slowness on every leg: so it is with media looked up (a
        // reflection keeps the medium), not always with media given (a converted wave).
        let media = scene.paths()[path].media.as_deref().unwrap_or(&[]);
        let slowness = |m: &usize| scene.media()[*m].slowness;
        let one_slowness = media.windows(2).all(|m| slowness(&m[0]) == slowness(&m[1]));
        if kind == StepKind::Reflect && !one_slowness {
            return None;
        }
        let lines = polylines
            .iter()
            .map(|line| StraightSegment::of(line))
            .collect();
        let m = polylines[0].tangent(0);
        let parallel = polylines
            .iter()
            .all(|line| line.tangent(0).dot(m).abs() >= 1.0 - PARALLEL);
        Some(StraightPath {
            lines,
            kind,
            parallel,
            slowness: media.iter().map(slowness).collect(),
        })
    }

    /// Whether the default start solves the path up to round-off wherever it applies, with
    /// `ray_parameter` (the refinement [`InitialGuess::RayParameter`](super::InitialGuess)):
    /// reflections (the image method), or refractions at two or more parallel interfaces (a
    /// single refraction keeps the paraxial start).
    pub(crate) fn exact(&self, ray_parameter: bool) -> bool {
        ray_parameter
            && match self.kind {
                StepKind::Reflect => true,
                StepKind::Refract => self.parallel && self.lines.len() > 1,
                StepKind::Diffract { .. } => false,
            }
    }

    /// Writes the start of a ray from `source` to `receiver` into `ws` (parameters, segments,
    /// pins and crossing fractions; `ws` sized for the path) where it applies (see the module):
    /// [`StraightStart::At`] when it did; [`StraightStart::Beyond`] or [`StraightStart::Apart`]
    /// when the path has no solution (reflections only); [`StraightStart::Unsure`] leaves the
    /// ray to `initial_guess`.
    /// Without `images` (`InitialGuess::Paraxial`), reflections are left to `initial_guess`.
    #[inline]
    pub(crate) fn start(
        &self,
        source: Point,
        receiver: Point,
        images: bool,
        ws: &mut Workspace,
    ) -> StraightStart {
        match self.kind {
            StepKind::Refract if self.crossings(source, receiver, ws) => StraightStart::At,
            StepKind::Reflect if images => self.images(source, receiver, ws),
            _ => StraightStart::Unsure,
        }
    }

    /// Whether the path's rays can take the kernel of a stack of parallel layers
    /// ([`Tracer::solve_stack`](super::Tracer)): two or more refractions at parallel
    /// interfaces, with the media given.
    pub(crate) fn stack(&self) -> bool {
        self.kind == StepKind::Refract
            && self.parallel
            && self.lines.len() > 1
            && self.slowness.len() == self.lines.len() + 1
    }

    /// The crossings of `source → receiver` with the interfaces (see the module) in `ws`,
    /// if it crosses every segment.
    #[inline(always)]
    pub(super) fn crossings(&self, source: Point, receiver: Point, ws: &mut Workspace) -> bool {
        let k = self.lines.len();
        let (t, s, seg, pin) = (
            &mut ws.start.crossing_t[..k],
            &mut ws.newton.s[..k],
            &mut ws.newton.seg[..k],
            &mut ws.newton.pin[..k],
        );
        for (i, line) in self.lines.iter().enumerate() {
            // The crossing and parameter of `Polyline::crossings_with_segment`.
            let Some((ti, u)) = segment_intersection(source, receiver, line.p, line.q) else {
                return false;
            };
            t[i] = ti;
            s[i] = 0.0 + u * line.len;
            seg[i] = 0;
            pin[i] = Pin::Free;
        }
        true
    }

    /// The image method (see the module).
    fn images(&self, source: Point, receiver: Point, ws: &mut Workspace) -> StraightStart {
        let k = self.lines.len();
        // The source's image in the first mirror, then that image's in the second, …
        let image = self.lines.iter().fold(source, |x, line| line.mirror(x));
        // … and back: the last point lies where the receiver sees the last image, and that
        // image mirrored back is the one the point before sees. Points beyond a segment's end
        // stay on its line: the path through the lines is stationary all the same.
        let (mut image, mut to) = (image, receiver);
        let (mut inside, mut clear, mut first_beyond, mut apart) = (true, true, None, None);
        for i in (0..k).rev() {
            let line = &self.lines[i];
            let (s, meet) = line.meet(to, image);
            if meet.apart && clear && apart.is_none() {
                apart = Some(i);
            }
            inside &= meet.inside;
            clear &= meet.clear;
            if meet.beyond {
                first_beyond = Some(i);
            }
            if !(inside || clear || apart.is_some()) {
                return StraightStart::Unsure;
            }
            // (A point beyond its segment's end is kept at that end: with no path, the
            // parameters of the ray are where it leaves.)
            ws.newton.s[i] = s.clamp(0.0, line.len);
            ws.newton.seg[i] = 0;
            ws.newton.pin[i] = Pin::Free;
            ws.start.crossing_t[i] = f64::NAN;
            to = line.p + line.e * (s / line.len);
            image = line.mirror(image);
        }
        match first_beyond {
            _ if inside => StraightStart::At,
            Some(step) if clear => StraightStart::Beyond { step },
            _ => apart.map_or(StraightStart::Unsure, |step| StraightStart::Apart { step }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{self, SplitMix64};
    use crate::trace::{Reason, Status, Tracer, initial_guess};

    /// Layers flat and dipping, some interfaces drawn right to left, far from the origin or
    /// not: wherever `S → R` crosses every segment, the start is `initial_guess`'s bit for
    /// bit, and elsewhere it leaves the ray to it.
    #[test]
    fn the_start_is_the_documented_one() {
        let mut specs = vec![demo::layer_stack(8, 3), demo::dipping_stack(8, 3)];
        let mut reversed = demo::layer_stack(5, 3);
        for (i, iface) in reversed.interfaces.values_mut().enumerate() {
            if i % 2 == 1 {
                iface.points.reverse();
            }
        }
        specs.push(reversed);
        let mut far = demo::dipping_stack(4, 3);
        for iface in far.interfaces.values_mut() {
            for p in &mut iface.points {
                *p = [p[0] + 3.0e6, p[1] - 1.0e5];
            }
        }
        specs.push(far);
        let mut rng = SplitMix64(7);
        for (n, spec) in specs.iter().enumerate() {
            let scene = Scene::from_spec(spec).unwrap();
            let flat = StraightPath::of(&scene, 0).expect("refractions at one-segment interfaces");
            assert_eq!(flat.parallel, n != 1 && n != 3, "scene {n}");
            let steps = &scene.paths()[0].steps;
            let k = steps.len();
            let b = crate::geom::Aabb::around(
                &scene
                    .interfaces()
                    .iter()
                    .flat_map(|i| i.polyline.vertices().to_vec())
                    .collect::<Vec<_>>(),
            );
            let (mut started, mut left) = (0, 0);
            for _ in 0..400 {
                let mut at = |y: f64| {
                    let x = b.min.x + (b.max.x - b.min.x) * (1.4 * rng.next_f64() - 0.2);
                    Point::new(x, y)
                };
                let (s, r) = (at(b.max.y + 1.0), at(b.min.y - 1.5));
                let (mut ws, mut reference) = (Workspace::new(), Workspace::new());
                ws.resize(k);
                reference.resize(k);
                initial_guess(&scene, steps, s, r, &mut reference);
                if flat.start(s, r, true, &mut ws) != StraightStart::At {
                    left += 1;
                    continue;
                }
                started += 1;
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let (nw, rw) = (&ws.newton, &reference.newton);
                assert_eq!(bits(&nw.s), bits(&rw.s), "scene {n}: {s:?} -> {r:?}");
                assert_eq!(
                    bits(&ws.start.crossing_t),
                    bits(&reference.start.crossing_t)
                );
                assert_eq!(nw.seg, rw.seg);
                assert_eq!(nw.pin, rw.pin);
            }
            assert!(
                started > 100 && left > 20,
                "scene {n}: {started} started, {left} left"
            );
        }
        // Refractions and a reflection, or an interface of two segments: not such a path.
        let mut mirror = demo::layer_stack(2, 3);
        let path = &mut mirror.paths[0];
        path.steps[1] = crate::scene::StepSpec::Reflect("L001".into());
        if let Some(media) = &mut path.media {
            media[2] = media[1].clone();
        }
        let mirror = Scene::from_spec(&mirror).unwrap();
        assert!(StraightPath::of(&mirror, 0).is_none());
        let wavy = Scene::from_spec(&demo::undulating_stack(2, 20, 3)).unwrap();
        assert!(StraightPath::of(&wavy, 0).is_none());
    }

    /// Two and three reflections between two tilted mirrors: where the start applies, each
    /// point lies inside its segment and reflects (equal angles), and the rays it leaves to
    /// the general guess are those whose specular points fall off a segment.
    #[test]
    fn images_give_the_specular_points() {
        let doc = r#"{
            "media": { "m": { "speed": 1.0 } },
            "interfaces": { "low": { "points": [[-1, 0], [2, 0.3]] },
                            "high": { "points": [[3, 3], [-0.5, 2.5]] } },
            "sources": [[0, 1]], "receivers": [[1, 1.5]],
            "paths": [{ "steps": [{ "reflect": "low" }, { "reflect": "high" }] },
                      { "steps": [{ "reflect": "high" }, { "reflect": "low" },
                                  { "reflect": "high" }] }]
        }"#;
        let scene = Scene::from_json(doc).unwrap();
        let mut rng = SplitMix64(11);
        for path in 0..2 {
            let straight = StraightPath::of(&scene, path).expect("reflections off segments");
            assert!(straight.exact(true) && !straight.exact(false) && !straight.parallel);
            let steps = &scene.paths()[path].steps;
            let k = steps.len();
            let lines: Vec<_> = steps
                .iter()
                .map(|s| &scene.interfaces()[s.interface].polyline)
                .collect();
            let (mut started, mut left) = (0, 0);
            for _ in 0..300 {
                let mut at = || Point::new(-2.0 + 5.0 * rng.next_f64(), 0.8 + 1.3 * rng.next_f64());
                let (s, r) = (at(), at());
                let mut ws = Workspace::new();
                ws.resize(k);
                if straight.start(s, r, true, &mut ws) != StraightStart::At {
                    left += 1;
                    continue;
                }
                started += 1;
                let mut pts = vec![s];
                for (i, line) in lines.iter().enumerate() {
                    assert!(ws.newton.s[i] > 0.0 && ws.newton.s[i] < line.length());
                    assert_eq!((ws.newton.seg[i], ws.newton.pin[i]), (0, Pin::Free));
                    pts.push(line.point_on(0, ws.newton.s[i]));
                }
                pts.push(r);
                for (i, line) in lines.iter().enumerate() {
                    let (a, b) = (pts[i + 1] - pts[i], pts[i + 2] - pts[i + 1]);
                    let t = line.tangent(0);
                    let law = a.dot(t) / a.length() - b.dot(t) / b.length();
                    assert!(
                        law.abs() <= 1e-13,
                        "path {path}, {s:?} -> {r:?}: point {i}, {law:e}"
                    );
                    let n = line.normal(0);
                    assert!(
                        a.dot(n) * b.dot(n) < 0.0,
                        "point {i} reflects from one side"
                    );
                }
            }
            assert!(
                started > 50 && left > 20,
                "path {path}: {started} started, {left} left"
            );
        }
    }

    /// The image method's starts and verdicts against the general guess and solve, on
    /// `room2d` (3,700 rays of orders 0 to 2) and on short mirrors at random: the same
    /// statuses and reasons' kinds (the image method's `BeyondEnd` where the general solve's
    /// complete search finds no path), times within 1e-12. Both of the image method's proofs
    /// (a point beyond an end; a leg from behind a mirror, in the room) decide many rays.
    #[test]
    fn images_agree_with_the_general_solve() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench/room2d.json");
        let room = Scene::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
        let mut rng = SplitMix64(5);
        let mut at = |x: f64, y: f64| [x + rng.next_f64(), y + rng.next_f64()];
        let (sources, receivers): (Vec<_>, Vec<_>) =
            (0..40).map(|_| (at(-1.0, 0.3), at(0.5, 0.6))).unzip();
        let doc = serde_json::json!({
            "media": { "m": { "speed": 1.0 } },
            "interfaces": { "a": { "points": [[-1.0, 0.0], [1.5, 0.2]] },
                            "b": { "points": [[2.0, 3.0], [-0.5, 2.6]] } },
            "sources": sources, "receivers": receivers,
            "paths": [{ "steps": [{ "reflect": "a" }], "media": ["m", "m"] },
                      { "steps": [{ "reflect": "a" }, { "reflect": "b" }], "media": ["m", "m", "m"] },
                      { "steps": [{ "reflect": "b" }, { "reflect": "a" }, { "reflect": "b" }],
                        "media": ["m", "m", "m", "m"] }]
        });
        let mirrors = Scene::from_json(&doc.to_string()).unwrap();
        for (name, scene) in [("room2d", room), ("mirrors", mirrors)] {
            let fast = Tracer::new(&scene).unwrap();
            // The general guess (no image method: every path here reflects) and solve.
            let general = Tracer::new(&scene)
                .unwrap()
                .with_initial_guess(crate::InitialGuess::Paraxial)
                .with_kernels(crate::trace::Kernels::GeneralOnly);
            let mut ws = Workspace::new();
            let (np, nr) = (scene.paths().len(), scene.receivers().len());
            let (mut decided, mut started, mut behind) = (0, 0, 0);
            for i in 0..scene.num_rays() {
                let (s, r, p) = (i / (np * nr), (i / np) % nr, i % np);
                let a = fast.trace(s, r, p, &mut ws);
                let b = general.trace(s, r, p, &mut ws);
                assert_eq!(a.status, b.status, "{name}: {a:?} vs {b:?}");
                // The image method's verdict is the complete search's, sooner.
                let kind = |r: &crate::Ray| {
                    let proof = |reason: &Reason| match reason {
                        Reason::BeyondEnd { .. } => Reason::NoStationaryPath,
                        other => *other,
                    };
                    r.reason
                        .as_ref()
                        .map(proof)
                        .map(|r| std::mem::discriminant(&r))
                };
                assert_eq!(kind(&a), kind(&b), "{name}: {a:?} vs {b:?}");
                if a.status.has_time() {
                    let (x, y) = (a.time, b.time);
                    assert!((x - y).abs() <= 1e-12 * y, "{name}: {a:?} vs {b:?}");
                }
                if a.iterations == 0 && a.points.len() > 2 {
                    started += 1;
                } else if a.iterations == 0 && a.status == Status::NoPath {
                    decided += 1;
                    behind += usize::from(a.reason == Some(Reason::NoStationaryPath));
                }
            }
            assert!(
                started > 100 && decided > behind + 100 && (behind > 100 || name == "mirrors"),
                "{name}: {started} started, {decided} decided, {behind} from behind"
            );
        }
    }
}
