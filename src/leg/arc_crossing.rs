//! Where a segment meets a circular arc of at most half a turn (a leg in a medium with a
//! speed gradient), exactly: from the circle's equation in the frame of the arc's chord,
//! written so that it becomes the chord's line as the curvature goes to zero.
//!
//! In that frame (origin the chord's middle, `x` along the chord, `y` to its left, `h` half
//! the chord, `κ` the signed curvature, `w = √(1 − κ²h²)` the cosine of half the turn), the
//! circle through the chord's ends is
//!
//! `F(x, y) = κ (x² + y² − h²) − 2 w y = 0`,
//!
//! the circle's own equation times `κ` (its centre is at `y = w/κ`): no division by `κ`, and
//! at `κ = 0` the chord's line `y = 0`. The arc is the part of that circle with `|x| ≤ h`
//! on the chord's bulging side, `κ y ≤ 0`; the circle's far side has `κ y ≥ 2w` there, so the
//! test `κ y ≤ w` tells the two apart with the widest gap (at a half turn, `w = 0`, they
//! meet only at the chord's ends). A segment `p + t e` meets the circle where the quadratic
//! `F(p + t e) = 0` has a root `t ∈ [0, 1]`; each root, in the numerically stable form,
//! is the meeting point's position to a few ulps of the chord and the segment (the gradient
//! of `F` has length 2 on the circle). A segment that a leg's end lies on meets the circle
//! there exactly: its other meeting point is found from the root at that end (the quadratic's
//! constant term vanishes), so rounding at the end cannot show a crossing next to it.

use crate::geom::{Aabb, Point, Vec2};

/// Which ends of a leg lie on a segment it is tested against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EndsOn {
    /// Neither end.
    Neither,
    /// The leg's start.
    Start,
    /// The leg's end.
    End,
    /// Both ends: the circle meets the segment's line there and nowhere else.
    Both,
}

/// A circular arc of at most half a turn from `a` to `b` with signed curvature `κ`
/// (positive: it turns left, so it bulges to the right of its chord), in its chord's frame
/// (see the module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ArcFrame {
    /// The chord's middle.
    middle: Point,
    /// The chord's unit direction.
    along: Vec2,
    /// Half the chord's length.
    half: f64,
    /// The signed curvature.
    curvature: f64,
    /// The cosine of half the turn, `√(1 − κ²h²)`.
    cos_half_turn: f64,
    /// The arc's greatest distance from its chord, `κ h² / (1 + w)` in size.
    sagitta: f64,
}

impl ArcFrame {
    /// The arc from `a` to `b` with signed curvature `curvature`; `None` when the ends
    /// coincide or a value is not finite. A curvature beyond a half turn over the chord
    /// (`|κ| h > 1`, by rounding) is taken as a half turn.
    pub(crate) fn new(a: Point, b: Point, curvature: f64) -> Option<ArcFrame> {
        let chord = b - a;
        let len = chord.length();
        if !(len > 0.0 && len.is_finite() && curvature.is_finite()) {
            return None;
        }
        let half = 0.5 * len;
        let z = (curvature * half).abs().min(1.0);
        let cos_half_turn = ((1.0 - z) * (1.0 + z)).sqrt();
        Some(ArcFrame {
            middle: a + chord * 0.5,
            along: chord * (1.0 / len),
            half,
            curvature,
            cos_half_turn,
            sagitta: z * half / (1.0 + cos_half_turn),
        })
    }

    /// A box holding the arc: that of the rectangle on the chord reaching to the sagitta on
    /// the arc's side, widened by rounding.
    pub(crate) fn bounding_box(&self) -> Aabb {
        let bulge = self.along.perp() * (-self.curvature.signum() * self.sagitta);
        let a = self.middle - self.along * self.half;
        let b = self.middle + self.along * self.half;
        let [c, d] = [a + bulge, b + bulge];
        let lo = Point::new(
            a.x.min(b.x).min(c.x).min(d.x),
            a.y.min(b.y).min(c.y).min(d.y),
        );
        let hi = Point::new(
            a.x.max(b.x).max(c.x).max(d.x),
            a.y.max(b.y).max(c.y).max(d.y),
        );
        let slack = 8.0
            * f64::EPSILON
            * (self.half + lo.x.abs().max(lo.y.abs()).max(hi.x.abs()).max(hi.y.abs()));
        Aabb {
            min: Point::new(lo.x - slack, lo.y - slack),
            max: Point::new(hi.x + slack, hi.y + slack),
        }
    }

    /// `v` (a displacement) in the chord's frame: along the chord, to its left.
    #[inline]
    fn local(&self, v: Vec2) -> Vec2 {
        Vec2::new(v.dot(self.along), self.along.cross(v))
    }

    /// Where the segment `p–q` (its ends included) meets the arc strictly inside, at a
    /// fraction of the chord in `(margin, 1 − margin)` from the start: the least such
    /// fraction, or `None`. `ends_on` says which of the leg's ends lie on the segment (see
    /// the module); a segment parallel to a straight arc's chord meets it nowhere, as
    /// `polyline::segment_intersection` has it.
    pub(crate) fn meets(&self, p: Point, q: Point, margin: f64, ends_on: EndsOn) -> Option<f64> {
        let (k, w, h) = (self.curvature, self.cos_half_turn, self.half);
        let (p, e) = (self.local(p - self.middle), self.local(q - p));
        let a = k * e.dot(e);
        let point = |t: f64| Vec2::new(p.x + t * e.x, p.y + t * e.y);
        let roots: [Option<Vec2>; 2] = match ends_on {
            EndsOn::Both => return None,
            EndsOn::Start | EndsOn::End => {
                // The line through the leg's end `s` (on the segment) meets the circle at `s`
                // and at `s + τ e`, `τ = −F′(s)·e / (κ |e|²)`.
                let s = Vec2::new(if ends_on == EndsOn::Start { -h } else { h }, 0.0);
                let tau = -2.0 * (k * s.x * e.x - w * e.y) / a;
                let x = s + e * tau;
                let t = (x - p).dot(e) / e.dot(e);
                [(0.0..=1.0).contains(&t).then_some(x), None]
            }
            EndsOn::Neither => {
                let b = 2.0 * (k * p.dot(e) - w * e.y);
                let c = k * (p.dot(p) - h * h) - 2.0 * w * p.y;
                quadratic_roots(a, b, c).map(|t| t.filter(|t| (0.0..=1.0).contains(t)).map(point))
            }
        };
        let inside = (0.5 - margin) * 2.0 * h;
        roots
            .into_iter()
            .flatten()
            .filter(|x| x.x.abs() < inside && k * x.y <= w)
            .map(|x| (x.x + h) / (2.0 * h))
            .min_by(f64::total_cmp)
    }
}

/// The real roots of `a t² + b t + c` (one when `a = 0`; none when `a = b = 0` or the
/// discriminant is negative), in the form that loses no digits to cancellation.
fn quadratic_roots(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
    if a == 0.0 {
        return [(b != 0.0).then(|| -c / b), None];
    }
    let disc = b * b - 4.0 * a * c;
    if disc.is_nan() || disc < 0.0 {
        return [None, None];
    }
    let s = -0.5 * (b + disc.sqrt().copysign(b));
    if s == 0.0 {
        // b = 0 and a c = 0: the double root 0.
        return [Some(0.0), None];
    }
    [Some(s / a), Some(c / s)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;
    use crate::polyline::segment_intersection;
    use std::f64::consts::PI;

    /// An arc given by its circle: centre, radius, start angle and signed sweep (positive:
    /// counter-clockwise, turning left), with the points it is sampled at.
    struct Circled {
        centre: Point,
        radius: f64,
        start: f64,
        sweep: f64,
    }

    impl Circled {
        fn at(&self, angle: f64) -> Point {
            self.centre + Vec2::new(angle.cos(), angle.sin()) * self.radius
        }
        fn ends(&self) -> [Point; 2] {
            [self.at(self.start), self.at(self.start + self.sweep)]
        }
        fn frame(&self) -> ArcFrame {
            let [a, b] = self.ends();
            ArcFrame::new(a, b, self.sweep.signum() / self.radius).unwrap()
        }
        /// The reference: the arc as `SAMPLES` chords, each tested as a straight segment;
        /// the least fraction of the chord `a–b` (projected) in `(margin, 1 − margin)`.
        fn sampled_meeting(&self, p: Point, q: Point, margin: f64) -> Option<f64> {
            const SAMPLES: usize = 4000;
            let [a, b] = self.ends();
            let d = b - a;
            let pts: Vec<Point> = (0..=SAMPLES)
                .map(|j| self.at(self.start + self.sweep * j as f64 / SAMPLES as f64))
                .collect();
            pts.windows(2)
                .filter_map(|w| {
                    let (t, _) = segment_intersection(w[0], w[1], p, q)?;
                    Some((w[0].lerp(w[1], t) - a).dot(d) / d.dot(d))
                })
                .filter(|&f| f > margin && f < 1.0 - margin)
                .min_by(f64::total_cmp)
        }
    }

    fn random_arc(rng: &mut SplitMix64) -> Circled {
        let radius = 0.2 * 10f64.powf(2.0 * rng.next_f64());
        let sweep = (2.0 * rng.next_f64() - 1.0) * PI;
        Circled {
            centre: Point::new(6.0 * rng.next_f64() - 3.0, 6.0 * rng.next_f64() - 3.0),
            radius,
            start: 2.0 * PI * rng.next_f64(),
            sweep,
        }
    }

    /// The reference's answer when every perturbation of the segment (moved across itself,
    /// each end moved along it) and of the margin by `delta` gives the same yes or no, with
    /// the spread of the fractions found; `None` for a case too close to call.
    fn robust_reference(
        arc: &Circled,
        p: Point,
        q: Point,
        margin: f64,
        delta: f64,
    ) -> Option<(Option<f64>, f64)> {
        let u = (q - p) * (1.0 / (q - p).length());
        let n = u.perp() * delta;
        let along = u * delta;
        let cases = [
            (p, q, margin),
            (p + n, q + n, margin),
            (p - n, q - n, margin),
            (p - along, q, margin),
            (p + along, q, margin),
            (p, q + along, margin),
            (p, q - along, margin),
            (p, q, margin + delta),
            (p, q, (margin - delta).max(0.0)),
        ];
        let found: Vec<Option<f64>> = cases
            .iter()
            .map(|&(p, q, m)| arc.sampled_meeting(p, q, m))
            .collect();
        if found.iter().any(|f| f.is_some() != found[0].is_some()) {
            return None;
        }
        let fs = found.iter().flatten();
        let spread = fs
            .clone()
            .fold(0.0f64, |s, f| s.max((f - found[0].unwrap()).abs()));
        Some((found[0], spread))
    }

    /// Checks the exact test against the reference where the reference is decided, and
    /// returns whether it was.
    fn agrees(arc: &Circled, p: Point, q: Point, margin: f64, ends_on: EndsOn) -> bool {
        let Some((want, spread)) = robust_reference(arc, p, q, margin, 1e-6 * arc.radius) else {
            return false;
        };
        let got = arc.frame().meets(p, q, margin, ends_on);
        match (got, want) {
            (Some(g), Some(w)) => assert!(
                (g - w).abs() <= spread + 1e-6,
                "fraction {g} against {w} (spread {spread})"
            ),
            (None, None) => {}
            _ => panic!(
                "exact {got:?}, sampled {want:?}: centre {:?} radius {} start {} sweep {} \
                 segment {p:?}–{q:?}",
                arc.centre, arc.radius, arc.start, arc.sweep
            ),
        }
        true
    }

    /// Random arcs (up to a half turn, radii 0.2 to 20) and random segments near them:
    /// the exact test finds a meeting where, and only where, 4000 chords of the arc do, at
    /// the same fraction of the chord, in every case the chords decide robustly.
    #[test]
    fn random_arcs_and_segments_match_dense_sampling() {
        let mut rng = SplitMix64(0xa4c);
        let (mut decided, mut met) = (0, 0);
        for i in 0..3000 {
            let arc = random_arc(&mut rng);
            let [a, b] = arc.ends();
            let mid = arc.at(arc.start + 0.5 * arc.sweep);
            let scale = (b - a).length().max(1e-3);
            let r = |rng: &mut SplitMix64| {
                let c = [a, b, mid][(rng.next_u64() % 3) as usize];
                c + Vec2::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5) * (2.0 * scale)
            };
            let (p, q) = (r(&mut rng), r(&mut rng));
            let margin = [1e-10, 0.05, 0.3][i % 3];
            if agrees(&arc, p, q, margin, EndsOn::Neither) {
                decided += 1;
                met += usize::from(arc.frame().meets(p, q, margin, EndsOn::Neither).is_some());
            }
        }
        assert!(
            decided > 2700 && met > 500 && decided - met > 500,
            "{decided} {met}"
        );
    }

    /// Segments through the arc's start or end in random directions, marked as the end's
    /// own: the exact test finds the other meeting point only, where the chords find one
    /// beyond the margin.
    #[test]
    fn segments_through_an_end_match_dense_sampling() {
        let mut rng = SplitMix64(0xe4d);
        let (mut decided, mut met) = (0, 0);
        for i in 0..2000 {
            let arc = random_arc(&mut rng);
            let [a, b] = arc.ends();
            let scale = (b - a).length().max(1e-3);
            let angle = 2.0 * PI * rng.next_f64();
            let dir = Vec2::new(angle.cos(), angle.sin());
            let (at, ends_on) = if i % 2 == 0 {
                (a, EndsOn::Start)
            } else {
                (b, EndsOn::End)
            };
            let p = at - dir * (scale * rng.next_f64());
            let q = at + dir * (2.0 * scale * rng.next_f64());
            if agrees(&arc, p, q, 1e-3, ends_on) {
                decided += 1;
                met += usize::from(arc.frame().meets(p, q, 1e-3, ends_on).is_some());
            }
        }
        assert!(
            decided > 1500 && met > 200 && decided - met > 200,
            "{decided} {met}"
        );
    }

    /// The arc from (−1, 0) to (1, 0) turning left on a circle of radius 2 (it bulges down to
    /// `y = √3 − 2`).
    fn bulging_down() -> ArcFrame {
        ArcFrame::new(Point::new(-1.0, 0.0), Point::new(1.0, 0.0), 0.5).unwrap()
    }

    /// A horizontal segment a hair inside the arc's lowest point meets it twice (the nearer
    /// to the start is reported), one a hair below it misses; so does a segment stopping a
    /// hair short of the arc, while one reaching a hair past it meets it.
    #[test]
    fn tangent_and_end_point_cases() {
        let arc = bulging_down();
        let apex = 3f64.sqrt() - 2.0;
        let hair = 1e-9;
        let across = |y: f64| {
            arc.meets(
                Point::new(-1.0, y),
                Point::new(1.0, y),
                1e-10,
                EndsOn::Neither,
            )
        };
        let inside = across(apex + hair).unwrap();
        // x where the circle is at that height: −√(4 − (√3 − y)²).
        let x = -(4.0 - (3f64.sqrt() - apex - hair).powi(2)).sqrt();
        // (Both are ill-conditioned this close to tangency: to about 1e-11.)
        assert!((inside - (x + 1.0) / 2.0).abs() < 1e-9, "{inside}");
        assert!(across(apex - hair).is_none());
        // A vertical segment from below to the arc at x = 0.5.
        let y = 3f64.sqrt() - (4.0f64 - 0.25).sqrt();
        let up = |to: f64| {
            arc.meets(
                Point::new(0.5, -1.0),
                Point::new(0.5, to),
                1e-10,
                EndsOn::Neither,
            )
        };
        assert_eq!(up(y + hair), Some(0.75));
        assert!(up(y - hair).is_none());
        // From above the chord: the far side of the circle is no part of the arc.
        let down = arc.meets(
            Point::new(0.5, 5.0),
            Point::new(0.5, 1.0),
            1e-10,
            EndsOn::Neither,
        );
        assert!(down.is_none());
        assert_eq!(
            arc.meets(
                Point::new(0.5, 5.0),
                Point::new(0.5, -5.0),
                1e-10,
                EndsOn::Neither
            ),
            Some(0.75)
        );
    }

    /// The chord's line through both ends meets the arc only there; a segment that is the
    /// start's own and leaves it below the chord meets the arc where the chords find; the
    /// margin leaves out meetings next to the ends.
    #[test]
    fn ends_on_the_segment() {
        let arc = bulging_down();
        let (l, r) = (Point::new(-3.0, 0.0), Point::new(3.0, 0.0));
        for ends_on in [EndsOn::Neither, EndsOn::Both, EndsOn::Start, EndsOn::End] {
            assert_eq!(arc.meets(l, r, 1e-10, ends_on), None, "{ends_on:?}");
        }
        // From (−1, 0) down at 15° (the arc leaves at 30°): the line through the start meets
        // the circle again where `τ² + τ (2√3 sin 15° − 2 cos 15°) = 0`, `τ = 4 sin 15°`, at
        // the arc's lowest point (0, √3 − 2): half the chord.
        let d = Vec2::new((PI / 12.0).cos(), -(PI / 12.0).sin());
        let (p, q) = (Point::new(-1.0, 0.0) - d, Point::new(-1.0, 0.0) + d * 3.0);
        let got = arc.meets(p, q, 1e-10, EndsOn::Start).unwrap();
        assert!((got - 0.5).abs() < 1e-15, "{got}");
        assert!(arc.meets(p, q, 0.5 - 1e-9, EndsOn::Start).is_some());
        assert!(arc.meets(p, q, 0.5 + 1e-12, EndsOn::Start).is_none());
        // Not marked as its own, the segment meets the circle at the start too (left out by
        // the margin) and at the same point.
        let unmarked = arc.meets(p, q, 1e-10, EndsOn::Neither).unwrap();
        assert!((unmarked - 0.5).abs() < 1e-15, "{unmarked}");
        // Down at 45°, below the arc from the start on: no meeting.
        let d = Vec2::new(1.0, -1.0) * std::f64::consts::FRAC_1_SQRT_2;
        let (p, q) = (Point::new(-1.0, 0.0) - d, Point::new(-1.0, 0.0) + d * 3.0);
        assert_eq!(arc.meets(p, q, 1e-10, EndsOn::Start), None);
        assert_eq!(arc.meets(p, q, 1e-10, EndsOn::Neither), None);
    }

    /// At zero curvature (and at curvatures far below a double's resolution of the chord)
    /// the arc is its chord: the exact test answers as the straight test does, on random
    /// segments.
    #[test]
    fn straight_limit_is_the_segment_test() {
        let mut rng = SplitMix64(0x57a);
        let r = |rng: &mut SplitMix64| {
            Point::new(4.0 * rng.next_f64() - 2.0, 4.0 * rng.next_f64() - 2.0)
        };
        let mut met = 0;
        for _ in 0..2000 {
            let (a, b, p, q) = (r(&mut rng), r(&mut rng), r(&mut rng), r(&mut rng));
            let straight = segment_intersection(a, b, p, q)
                .map(|(t, _)| t)
                .filter(|&t| t > 1e-10 && t < 1.0 - 1e-10);
            for k in [0.0, 1e-300, -1e-30] {
                let got = ArcFrame::new(a, b, k)
                    .unwrap()
                    .meets(p, q, 1e-10, EndsOn::Neither);
                assert_eq!(
                    got.is_some(),
                    straight.is_some(),
                    "{a:?} {b:?} {p:?} {q:?} {k}"
                );
                if let (Some(g), Some(s)) = (got, straight) {
                    assert!((g - s).abs() < 1e-9, "{g} {s}");
                }
            }
            met += usize::from(straight.is_some());
        }
        assert!(met > 200, "{met}");
    }

    /// The arcs of media with a speed gradient (their points from `ArcLeg::offset_at`, which
    /// `leg.rs` checks against an integration of the ray equations), in the frame built from
    /// their ends and curvature: a short segment across the chord through each point meets
    /// the arc there, and one beside it on either side, not.
    #[test]
    fn legs_of_linear_media_are_the_frames_arcs() {
        use crate::leg::{LegModel, Linear};
        let mut rng = SplitMix64(0x1a4);
        let mut checked = 0;
        for _ in 0..200 {
            let angle = 2.0 * PI * rng.next_f64();
            let m = Linear {
                speed: 1.0 + 3.0 * rng.next_f64(),
                gradient: Vec2::new(angle.cos(), angle.sin()) * (0.3 * rng.next_f64()),
                least_speed: 0.1,
            };
            let r = |rng: &mut SplitMix64| {
                Vec2::new(4.0 * rng.next_f64() - 2.0, 4.0 * rng.next_f64() - 2.0)
            };
            let (a, b) = (r(&mut rng), r(&mut rng));
            let Some(leg) = m.valid_leg(a.to_point(), b.to_point()) else {
                continue;
            };
            let frame = ArcFrame::new(a.to_point(), b.to_point(), leg.curvature()).unwrap();
            let u = leg.chord * (1.0 / leg.len);
            for j in 1..10 {
                let x = a + leg.offset_at(leg.arc_length() * j as f64 / 10.0);
                let want = (x - a).dot(u) / leg.len;
                let across = |shift: f64| {
                    let at = (x + u * shift).to_point();
                    frame.meets(
                        at - u.perp() * 0.01,
                        at + u.perp() * 0.01,
                        1e-10,
                        EndsOn::Neither,
                    )
                };
                let got = across(0.0).unwrap();
                assert!((got - want).abs() < 1e-12, "{got} {want}");
                // Beside the point along the chord, the short segment meets the arc beside it.
                let moved = across(1e-3 * leg.len).unwrap();
                assert!((moved - want - 1e-3).abs() < 1e-9, "{moved} {want}");
                // The segment moved off the arc (across it, beyond its 0.01) misses it.
                let off = x.to_point() + u.perp() * 0.02;
                assert!(
                    frame
                        .meets(
                            off - u.perp() * 0.005,
                            off + u.perp() * 0.005,
                            1e-10,
                            EndsOn::Neither
                        )
                        .is_none()
                );
            }
            checked += 1;
        }
        assert!(checked > 100, "{checked}");
    }

    /// A half turn (the semicircle over its chord) and a nearly straight arc: the box holds
    /// every sampled point of the arc.
    #[test]
    fn the_box_holds_the_arc() {
        let mut rng = SplitMix64(0xb0c);
        for _ in 0..500 {
            let mut arc = random_arc(&mut rng);
            if rng.next_f64() < 0.2 {
                arc.sweep = PI.copysign(arc.sweep);
            }
            let b = arc.frame().bounding_box();
            for j in 0..=100 {
                let p = arc.at(arc.start + arc.sweep * j as f64 / 100.0);
                assert!(b.contains(p), "{p:?} outside {b:?}");
            }
        }
    }
}
