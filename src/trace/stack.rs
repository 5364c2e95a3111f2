//! Refraction through a stack of parallel flat layers (two or more open interfaces of one
//! segment each, parallel, with the leg media given) from the default start: the general
//! code's own steps for the common case, without its bookkeeping.
//!
//! From the ray-parameter start (`refraction_guess`) such a ray is solved up to round-off,
//! and the general solve only confirms it: one evaluation, the Newton step's tests, then the
//! classification. The kernel takes the same steps on the same numbers (the solver's own
//! fast path, `solver::fast_newton_from`), with the per-path data prepared once
//! ([`StraightPath`]) instead of looked up per ray: the segments' frames from their end
//! points, the points from the segments, and the classification of a ray whose points are
//! all free and inside their segments with no vanished leg (the side and obstruction tests).
//! So where it returns, its ray is the general code's, bit for bit
//! (`tests/kernels.rs` and the tests below compare them).
//! Anything else (a point at a segment's end, a fast path that ends otherwise than
//! converged) goes to the general solve from the same start.

use super::classify::Sequence;
use super::start::{GradedLayer, graded_guess, layered_guess};
use super::straight::{StraightPath, StraightSegment};
use super::{Context, RayRecord, Workspace};
use crate::geom::Point;
use crate::problem::ProblemRef;
use crate::scene::StepKind;
use crate::solver::{Outcome, confirm_start, fast_newton_from, solve};

impl StraightPath {
    /// The ray of path `path` (described by `self`, a [`StraightPath::stack`]) from `source`
    /// to `receiver` from the default start, as the general solve gives it (record, and
    /// parameters, points and media in `ws`), or `None` outside the kernel's case (see the
    /// module).
    #[inline(always)]
    pub(super) fn solve_stack(
        &self,
        cx: &Context,
        path: usize,
        source: Point,
        receiver: Point,
        ws: &mut Workspace,
    ) -> Option<RayRecord> {
        let scene = cx.scene;
        let spec = &scene.paths()[path];
        let (steps, lines) = (&spec.steps[..], &self.lines[..]);
        let k = lines.len();
        // The start of the general solve: the crossings, then the ray parameter.
        ws.resize(k);
        if !self.crossings(source, receiver, ws) {
            return None;
        }
        ws.ray.slowness.clear();
        ws.ray.slowness.extend_from_slice(&self.slowness);
        layered_guess(lines, receiver - source, cx.guess, ws);
        // `layered_guess` clamps to the segments: a point at an end is the general solve's to
        // pin (or release).
        if !(0..k).all(|i| ws.newton.s[i] > 0.0 && ws.newton.s[i] < lines[i].len()) {
            return None;
        }
        let g = ProblemRef {
            scene,
            steps,
            slowness: &self.slowness,
            curved: &[],
            source,
            receiver,
        };
        // The solver's fast path on the frames kept for the path; an outcome other than
        // converged there (a step leaving a segment, a vanished leg, the iteration limit) is
        // the general solve's.
        let frames = lines.iter().map(|l| l.frame(source));
        let sol = fast_newton_from(&g, frames, &mut ws.newton, cx.newton)?;
        if sol.outcome != Outcome::Converged {
            return None;
        }
        ws.ray.media.clear();
        ws.ray
            .media
            .extend_from_slice(spec.media.as_deref().unwrap_or(&[]));
        let points = &mut ws.ray.points;
        points.clear();
        points.push(source);
        points.extend(
            lines
                .iter()
                .zip(&ws.newton.s[..k])
                .map(|(l, &s)| l.point_on(s)),
        );
        points.push(receiver);
        // The classification of free points inside their segments, no leg vanished.
        let nw = &ws.newton;
        let (rel, len) = (&nw.eval.rel[..k + 2], &nw.eval.len[..k + 1]);
        let sides = lines.iter().map(|l| (StepKind::Refract, l.normal()));
        Some(cx.classifier.free_points(
            scene,
            path,
            sides,
            rel,
            len,
            nw.eval.vanish,
            points,
            &nw.seg[..k],
            &sol,
        ))
    }
}

impl StraightPath {
    /// The ray of path `path` (described by `self`, a [`StraightPath::stack`]) in a scene with
    /// curved legs from `source` to `receiver` from the default start, as the general solve
    /// gives it (record, and parameters, points and media in `ws`), or `None` where the
    /// graded start does not apply (`trace::start::graded`; the general code then solves it
    /// from the uniform layers' start). The general code's own steps: the crossings from the
    /// segments kept here (`initial_guess`'s, bit for bit), the media given, the graded start
    /// on the same numbers ([`graded_start`](Self::graded_start)), the Newton solve and the
    /// classification; but where the start is the ray, the solve's first evaluation without
    /// the legs' Hessian blocks (`solver::confirm_start`, with [`layer_hessian`]: the general
    /// solve's verdict and numbers). Out of line: the uniform stack kernel's caller keeps its
    /// code.
    #[inline(never)]
    pub(super) fn solve_graded_stack(
        &self,
        cx: &Context,
        path: usize,
        source: Point,
        receiver: Point,
        ws: &mut Workspace,
    ) -> Option<RayRecord> {
        if !self.graded_start(cx, path, source, receiver, ws) {
            return None;
        }
        let scene = cx.scene;
        let steps = &scene.paths()[path].steps[..];
        let g = ProblemRef {
            scene,
            steps,
            slowness: &ws.ray.slowness,
            curved: &ws.ray.curved,
            source,
            receiver,
        };
        let hessian = layer_hessian(&self.lines, &ws.start.graded);
        let frames = self.lines.iter().map(|l| l.frame(source));
        if let Some(sol) = confirm_start(&g, frames, hessian, &mut ws.newton, cx.newton) {
            // The classification of free points on the kept segments.
            let points = &mut ws.ray.points;
            points.clear();
            points.push(source);
            let on = self.lines.iter().zip(&ws.newton.s[..self.lines.len()]);
            points.extend(on.map(|(l, &s)| l.point_on(s)));
            points.push(receiver);
            let normal = |i: usize| self.lines[i].normal();
            return Some(cx.classifier.graded_free_points(
                scene,
                path,
                normal,
                source,
                receiver,
                &sol,
                &ws.newton,
                &ws.ray.curved,
                points,
            ));
        }
        let sol = solve(&g, &mut ws.newton, cx.newton);
        let sequence = Sequence {
            steps,
            path: Some(path),
            curved: &ws.ray.curved,
        };
        let nw = &ws.newton;
        let points = &mut ws.ray.points;
        Some(
            cx.classifier
                .classify(scene, sequence, source, receiver, &sol, nw, points),
        )
    }

    /// The start of [`solve_graded_stack`](Self::solve_graded_stack) in `ws` (the crossings,
    /// the media, the legs' models and the graded start's parameters and layers): whether the
    /// graded start applies.
    #[inline(always)]
    fn graded_start(
        &self,
        cx: &Context,
        path: usize,
        source: Point,
        receiver: Point,
        ws: &mut Workspace,
    ) -> bool {
        let scene = cx.scene;
        let Some(media) = scene.paths()[path].media.as_deref() else {
            return false;
        };
        ws.resize(self.lines.len());
        if !self.crossings(source, receiver, ws) {
            return false;
        }
        ws.ray.media.clear();
        ws.ray.media.extend_from_slice(media);
        ws.ray.slowness.clear();
        ws.ray.slowness.extend_from_slice(&self.slowness);
        ws.ray.set_curved(scene, source);
        graded_guess(&self.lines[..], receiver - source, ws)
    }
}

/// The Hessian of the time along the interfaces at the graded start's ray through parallel
/// layers (`layers`, one per leg, at the start's `p`; `lines` the interfaces): row `i`'s
/// diagonal and its coupling to row `i + 1`. A leg's time as a function of its range `X`
/// across its layer has `∂T/∂X = p` and `∂²T/∂X² = 1 / (∂X/∂p)` (its
/// [`stiffness`](super::start::GradedLayer::stiffness)); moving point `i` along its
/// interface's tangent moves the ranges of its two legs by `±1` times as much, so `Hᵢᵢ` is the
/// sum of the two legs' and `Hᵢ,ᵢ₊₁` is `−(tᵢ · tᵢ₊₁)` times the leg between them: the legs'
/// Hessian blocks (`Leg::end_block`, `start_block`, `coupling`) at the start's ray, without
/// evaluating them.
pub(super) fn layer_hessian<'a>(
    lines: &'a [StraightSegment],
    layers: &'a [GradedLayer],
) -> impl Fn(usize) -> (f64, f64) + 'a {
    move |i| {
        let (before, after) = (layers[i].stiffness(), layers[i + 1].stiffness());
        let coupling = match lines.get(i + 1) {
            Some(next) => -lines[i].normal().dot(next.normal()) * after,
            None => 0.0,
        };
        (before + after, coupling)
    }
}

#[cfg(test)]
mod tests {
    use crate::Workspace;
    use crate::demo::{self, SplitMix64};
    use crate::geom::{Point, Vec2};
    use crate::scene::Scene;
    use crate::trace::test_support::kernels_agree;
    use crate::trace::{InitialGuess, Kernels, RayRecord, Status, Tracer};

    /// A stack of `n` parallel interfaces at random: any direction, some drawn the other way
    /// round, far from the origin or not, random thicknesses and speeds (contrasts up to 4:
    /// some rays beyond a critical angle), a short screen across some legs, and sources and
    /// receivers on either side, inside the stack or beyond the interfaces' ends.
    fn random_stack(rng: &mut SplitMix64, n: usize) -> Scene {
        let mut u = || rng.next_f64();
        let angle = std::f64::consts::TAU * u();
        let (t, nrm) = (
            Vec2::new(angle.cos(), angle.sin()),
            Vec2::new(-angle.sin(), angle.cos()),
        );
        let far = if u() < 0.3 { 2e5 } else { 0.0 };
        let o = Point::new(far + 10.0 * u(), -far + 10.0 * u());
        let half = 3.0 + 10.0 * u();
        let mut depth = 0.0;
        let mut interfaces = serde_json::Map::new();
        let (mut steps, mut media) = (Vec::new(), vec![serde_json::json!("m0")]);
        let mut speeds = serde_json::Map::new();
        speeds.insert("m0".into(), serde_json::json!({ "speed": 0.5 + 1.5 * u() }));
        for i in 0..n {
            depth += 0.2 + 2.0 * u();
            let c = o - nrm * depth;
            let (mut a, mut b) = (c - t * half, c + t * half);
            if u() < 0.3 {
                (a, b) = (b, a);
            }
            interfaces.insert(
                format!("L{i}"),
                serde_json::json!({ "points": [[a.x, a.y], [b.x, b.y]] }),
            );
            steps.push(serde_json::json!({ "refract": format!("L{i}") }));
            media.push(serde_json::json!(format!("m{}", i + 1)));
            speeds.insert(
                format!("m{}", i + 1),
                serde_json::json!({ "speed": 0.5 + 1.5 * u() }),
            );
        }
        // A screen across the first layer's legs, on one side of the stack.
        let s0 = o - nrm * 0.1 + t * (0.2 * half);
        interfaces.insert(
            "screen".into(),
            serde_json::json!({ "points": [[s0.x, s0.y], [s0.x - nrm.x * 0.05, s0.y - nrm.y * 0.05]] }),
        );
        let mut at = |above: bool| {
            let along = half * (2.6 * u() - 1.3);
            let across = if above {
                0.05 + 3.0 * u()
            } else {
                -depth - 0.05 - 3.0 * u()
            };
            let across = if u() < 0.1 { -depth * u() } else { across };
            let p = o + t * along + nrm * across;
            serde_json::json!([p.x, p.y])
        };
        let sources: Vec<_> = (0..3).map(|_| at(true)).collect();
        let receivers: Vec<_> = (0..40).map(|_| at(false)).collect();
        let doc = serde_json::json!({
            "media": speeds, "interfaces": interfaces,
            "sources": sources, "receivers": receivers,
            "paths": [{ "steps": steps, "media": media }],
        });
        Scene::from_json(&doc.to_string()).unwrap()
    }

    /// Every ray the kernel takes, against the general solve of the same ray (without any
    /// fast path): bit for bit. Returns how many it took, and how many ended obstructed.
    fn kernel_rays(scene: &Scene) -> (usize, usize) {
        let tracer = Tracer::new(scene).unwrap();
        let general_tracer = Tracer::new(scene)
            .unwrap()
            .with_kernels(Kernels::GeneralOnly);
        let Some(sp) = tracer.plan_of(0).stack() else {
            panic!("a stack");
        };
        let cx = tracer.context();
        let (mut ws, mut general) = (Workspace::new(), Workspace::new());
        let (mut taken, mut obstructed) = (0, 0);
        let bits = |r: &RayRecord| {
            (
                r.status,
                r.time.to_bits(),
                r.iterations,
                r.residual.to_bits(),
                r.reason,
            )
        };
        for &source in scene.sources() {
            for &receiver in scene.receivers() {
                let Some(ray) = sp.solve_stack(&cx, 0, source, receiver, &mut ws) else {
                    continue;
                };
                taken += 1;
                obstructed += usize::from(ray.status == Status::Obstructed);
                let reference = general_tracer.solve(source, receiver, 0, &mut general);
                assert_eq!(bits(&ray), bits(&reference), "{source:?} -> {receiver:?}");
                assert_eq!(ws.points(), general.points());
                assert_eq!(ws.parameters(), general.parameters());
                assert_eq!(ws.media(), general.media());
            }
        }
        (taken, obstructed)
    }

    #[test]
    fn the_kernel_takes_the_general_steps() {
        for (n, spec) in [
            (8, demo::layer_stack(8, 300)),
            (40, demo::layer_stack(40, 50)),
        ] {
            let scene = Scene::from_spec(&spec).unwrap();
            let (taken, _) = kernel_rays(&scene);
            assert_eq!(
                taken,
                scene.num_rays(),
                "layer_stack({n}): every ray is the clean case"
            );
        }
        let layers10 = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench/layers10.json");
        let scene = Scene::from_json(&std::fs::read_to_string(layers10).unwrap()).unwrap();
        let (taken, _) = kernel_rays(&scene);
        assert!(
            taken > scene.num_rays() / 2,
            "layers10: {taken} of {}",
            scene.num_rays()
        );
        let mut rng = SplitMix64(23);
        let (mut taken, mut obstructed, mut rays) = (0, 0, 0);
        for i in 0..60 {
            let scene = random_stack(&mut rng, 2 + i % 7);
            let (t, o) = kernel_rays(&scene);
            (taken, obstructed, rays) = (taken + t, obstructed + o, rays + scene.num_rays());
            // The rays it leaves, and the warm and given starts, through the general code.
            kernels_agree(&scene);
        }
        assert!(
            taken > rays / 3 && taken < rays && obstructed > 10,
            "{taken} of {rays} rays taken, {obstructed} obstructed"
        );
    }

    /// The graded stack kernel's Hessian from the start's layers ([`super::layer_hessian`])
    /// against the legs' Hessian blocks of the general evaluation at the same points (within
    /// 1e-6: the start's `∂X/∂p` are those of its last `p` evaluated, one step short of the
    /// root; the Hessian only sizes the Newton correction, which `CONFIRM_MARGIN` keeps 1e3
    /// times inside the general loop's bound), on
    /// `layer_stack(8, …)` with a random gradient across each layer (faster downward or
    /// upward, some zero) and on `layers10` with `[0, −0.02]`; and the confirmation without
    /// the blocks (`confirm_start`) taken for nearly every ray, with the general evaluation's
    /// time and residual.
    #[test]
    fn the_graded_hessian_is_the_legs_hessian() {
        use crate::problem::{Eval, ProblemRef};
        use crate::solver::confirm_start;
        use crate::trace::PathPlan;
        let layers10 = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench/layers10.json");
        let mut rng = SplitMix64(41);
        let mut specs = Vec::new();
        for _ in 0..4 {
            let mut spec = demo::layer_stack(8, 60);
            for m in spec.media.values_mut() {
                let g = if rng.next_f64() < 0.2 {
                    0.0
                } else {
                    0.05 * (rng.next_f64() - 0.3)
                };
                m.gradient = Some([0.0, g]);
            }
            specs.push(spec);
        }
        let mut spec =
            crate::SceneSpec::from_json(&std::fs::read_to_string(layers10).unwrap()).unwrap();
        for m in spec.media.values_mut() {
            m.gradient = Some([0.0, -0.02]);
        }
        specs.push(spec);
        let (mut tried, mut confirmed, mut worst) = (0, 0, 0.0f64);
        for spec in &specs {
            let scene = Scene::from_spec(spec).unwrap();
            let tracer = Tracer::new(&scene).unwrap();
            let PathPlan::GradedStack(sp) = tracer.plan_of(0) else {
                panic!("a graded stack");
            };
            let cx = tracer.context();
            let mut ws = Workspace::new();
            let k = sp.lines.len();
            let mut general = Eval::default();
            general.resize(k);
            for &source in scene.sources() {
                for &receiver in scene.receivers() {
                    if !sp.graded_start(&cx, 0, source, receiver, &mut ws) {
                        continue;
                    }
                    tried += 1;
                    let g = ProblemRef {
                        scene: &scene,
                        steps: &scene.paths()[0].steps,
                        slowness: &ws.ray.slowness,
                        curved: &ws.ray.curved,
                        source,
                        receiver,
                    };
                    let nw = &ws.newton;
                    g.evaluate(&nw.s, &nw.seg, &nw.pin, &mut general, true, false);
                    let hessian = super::layer_hessian(&sp.lines, &ws.start.graded);
                    for i in 0..k {
                        let (d, o) = hessian(i);
                        let scale = general.diag[i].abs();
                        assert!(
                            (d - general.diag[i]).abs() <= 1e-6 * scale,
                            "{i}: {d} {}",
                            general.diag[i]
                        );
                        let o_general = general.off.get(i).copied().unwrap_or(0.0);
                        assert!(
                            (o - o_general).abs() <= 1e-6 * scale,
                            "{i}: {o} {o_general}"
                        );
                        worst = worst.max((d - general.diag[i]).abs() / scale);
                    }
                    let frames = sp.lines.iter().map(|l| l.frame(source));
                    if let Some(sol) = confirm_start(&g, frames, hessian, &mut ws.newton, cx.newton)
                    {
                        confirmed += 1;
                        assert_eq!(sol.iterations, 0);
                        assert_eq!(sol.time.to_bits(), general.time.to_bits());
                        assert_eq!(sol.residual.to_bits(), general.rmax.to_bits());
                    }
                }
            }
        }
        assert!(
            tried > 400 && confirmed * 100 >= tried * 95,
            "{confirmed} of {tried} confirmed"
        );
        eprintln!("{confirmed} of {tried} confirmed; Hessian within {worst:.1e}");
    }

    /// The kernel is not taken from the paraxial start, nor for a path without its media.
    #[test]
    fn the_kernel_applies_to_its_case_only() {
        let stack = |t: &Tracer| t.plan_of(0).stack().is_some();
        let scene = Scene::from_spec(&demo::layer_stack(4, 3)).unwrap();
        assert!(stack(&Tracer::new(&scene).unwrap()));
        let paraxial = Tracer::new(&scene)
            .unwrap()
            .with_initial_guess(InitialGuess::Paraxial);
        assert!(!stack(&paraxial));
        let general = Tracer::new(&scene)
            .unwrap()
            .with_kernels(Kernels::GeneralOnly);
        assert!(!stack(&general));
        let mut spec = demo::layer_stack(4, 3);
        spec.paths[0].media = None;
        // Region lookup: the layers end on the domain's edges; each medium claims its layer.
        spec.domain = Some([[-100.0, -5.0], [100.0, 2.0]]);
        for (j, m) in spec.media.values_mut().enumerate() {
            m.at = Some([0.0, 0.5 - j as f64]);
        }
        let scene = Scene::from_spec(&spec).unwrap();
        assert!(!stack(&Tracer::new(&scene).unwrap()));
        let dipping = Scene::from_spec(&demo::dipping_stack(4, 3)).unwrap();
        assert!(!stack(&Tracer::new(&dipping).unwrap()));
    }
}
