//! The start of a path of refractions through straight interfaces of one segment each (flat
//! layers): the documented start without its search. The crossings of `S → R` with the
//! interfaces are one segment intersection each, from data prepared once per path; the result
//! is that of [`initial_guess`](super::initial_guess), bit for bit, and anything else (a
//! crossing off a segment, a leg along one) goes to it.

use super::PARALLEL;
use crate::geom::{Point, Vec2};
use crate::polyline::Polyline;
use crate::scene::{Scene, Step, StepKind};
use crate::solver::{Pin, Workspace};

/// One interface of a [`FlatPath`]: its segment `p → p + e` and that segment's length.
#[derive(Clone, Copy, Debug)]
struct Line {
    p: Point,
    e: Vec2,
    len: f64,
}

/// A path whose every step refracts at an open interface of one segment.
#[derive(Debug)]
pub(crate) struct FlatPath {
    lines: Box<[Line]>,
    /// Whether the segments are parallel (as `refraction_guess` takes them): the ray-parameter
    /// start then solves the path up to round-off.
    pub(crate) parallel: bool,
}

impl FlatPath {
    /// The path's segments, if it is such a path.
    pub(crate) fn of(scene: &Scene, path: usize) -> Option<FlatPath> {
        let steps = &scene.paths()[path].steps;
        let polylines: Vec<_> = steps
            .iter()
            .map(|step| &scene.interfaces()[step.interface].polyline)
            .collect();
        let simple = |(step, line): (&Step, &&Polyline)| {
            step.kind == StepKind::Refract && line.num_segments() == 1 && !line.is_closed()
        };
        if polylines.is_empty() || !steps.iter().zip(&polylines).all(simple) {
            return None;
        }
        let lines = polylines
            .iter()
            .map(|line| {
                let (p, q) = line.segment(0);
                Line {
                    p,
                    e: q - p,
                    len: line.segment_length(0),
                }
            })
            .collect();
        let m = polylines[0].tangent(0);
        let parallel = polylines
            .iter()
            .all(|line| line.tangent(0).dot(m).abs() >= 1.0 - PARALLEL);
        Some(FlatPath { lines, parallel })
    }

    /// Writes the documented start of a ray from `source` to `receiver` into `ws` (parameters,
    /// segments, pins and crossing fractions; `ws` sized for the path) when `S → R` crosses
    /// every segment: the same numbers as `initial_guess`, which the caller runs otherwise
    /// (`false`).
    #[inline]
    pub(crate) fn start(&self, source: Point, receiver: Point, ws: &mut Workspace) -> bool {
        let k = self.lines.len();
        let (t, s, seg, pin) = (
            &mut ws.crossing_t[..k],
            &mut ws.s[..k],
            &mut ws.seg[..k],
            &mut ws.pin[..k],
        );
        let d = receiver - source;
        for (i, line) in self.lines.iter().enumerate() {
            // `segment_intersection(source, receiver, p, q)` and the parameter
            // `crossings_with_segment` makes of it, operation for operation.
            let den = d.cross(line.e);
            let w = line.p - source;
            let (ti, u) = (w.cross(line.e) / den, w.cross(d) / den);
            if !((0.0..=1.0).contains(&ti) && (0.0..=1.0).contains(&u)) {
                return false;
            }
            t[i] = ti;
            s[i] = 0.0 + u * line.len;
            seg[i] = 0;
            pin[i] = Pin::Free;
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{self, SplitMix64};
    use crate::trace::initial_guess;

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
            let flat = FlatPath::of(&scene, 0).expect("refractions at one-segment interfaces");
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
                if !flat.start(s, r, &mut ws) {
                    left += 1;
                    continue;
                }
                started += 1;
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&ws.s), bits(&reference.s), "scene {n}: {s:?} -> {r:?}");
                assert_eq!(bits(&ws.crossing_t), bits(&reference.crossing_t));
                assert_eq!(ws.seg, reference.seg);
                assert_eq!(ws.pin, reference.pin);
            }
            assert!(
                started > 100 && left > 20,
                "scene {n}: {started} started, {left} left"
            );
        }
        // A reflection, or an interface of two segments: not such a path.
        let mut mirror = demo::layer_stack(2, 3);
        let path = &mut mirror.paths[0];
        path.steps[1] = crate::scene::StepSpec::Reflect("L001".into());
        if let Some(media) = &mut path.media {
            media[2] = media[1].clone();
        }
        let mirror = Scene::from_spec(&mirror).unwrap();
        assert!(FlatPath::of(&mirror, 0).is_none());
        let wavy = Scene::from_spec(&demo::undulating_stack(2, 20, 3)).unwrap();
        assert!(FlatPath::of(&wavy, 0).is_none());
    }
}
