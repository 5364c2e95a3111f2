//! Occlusion for the beam tree (`mirrors.rs`): the part of a child wall that a beam's rays
//! can reach without crossing an interface on the way, where obstructed paths are not listed.
//!
//! A node's legs leave its window (a part of its wall; at the root, the source) along rays
//! from its image `I`. A child wall `w` is reached at `x = w(t)` by the leg from the window to
//! `x`, which lies in the region `R` ahead of `I`, beyond the window's line and before `w`'s
//! line. An interface segment `o` whose part inside `R` (shrunk by a margin `m` from every
//! side of `R` and from `o`'s ends) projects from `I` onto `w`'s line over `(t₀, t₁)` hides
//! every `x` strictly inside that interval less the margin: the ray from `I` to such an `x`
//! meets that part of `o` at a point at least `m` from both ends of the leg and strictly
//! inside `o`, so the classifier (whose margin at a leg's ends is [`END_MARGIN`] of the leg,
//! far less than `m`) calls the path obstructed. The child's range is shrunk from its ends
//! past every hidden interval that covers an end (the hull of its visible parts), and a range
//! hidden whole prunes the child. No visible point is cut: every shadow is a subset of the
//! true one, by margins far above the images' round-off.
//!
//! One more rule closes the gap the margins leave at a corner that `o` shares with `w`
//! ([`Corner`]): where the image and `w`'s other end lie strictly on opposite sides of `o`'s
//! line, `o` runs from the corner to the legs' side of `w`'s line and the corner lies beyond
//! the window's line, a leg that reaches `w` near the corner crosses `o` near it, so the
//! shadow runs on to the corner. (Within [`END_MARGIN`] of a leg's end, the classifier would
//! not see that crossing; exact geometry, which this follows, does.)
//!
//! [`END_MARGIN`]: super::classify::END_MARGIN

use crate::geom::{Aabb, Point, Vec2, orient};
use crate::scene::{Scene, SegmentRef};

/// `m`, the occlusion's margin, as a multiple of the beam tests' position margin.
pub(crate) const OCCLUSION_MARGIN: f64 = 1000.0;

/// A wall seen by the occlusion: segment `p → q` with its unit normal.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Target {
    pub own: SegmentRef,
    pub p: Point,
    pub q: Point,
    pub n: Vec2,
}

impl Target {
    fn e(&self) -> Vec2 {
        self.q - self.p
    }
    fn at(&self, t: f64) -> Point {
        self.p + self.e() * t
    }
}

/// Every interface segment of a scene, as occluders.
#[derive(Clone, Debug)]
pub(crate) struct Occluders {
    /// Ends and name of each segment, with its box.
    segments: Vec<(Point, Point, SegmentRef, Aabb)>,
    /// Per segment, per end: whether another segment ends there too (a joint).
    joints: Vec<[bool; 2]>,
}

impl Occluders {
    /// The work of one [`unhidden`](Self::unhidden), in the units of `solver.max_work`: one
    /// per segment it weighs.
    pub(crate) fn work(&self) -> u64 {
        self.segments.len() as u64
    }

    /// Every segment: its ends and its name.
    pub(crate) fn each(&self) -> impl Iterator<Item = (Point, Point, SegmentRef)> + '_ {
        self.segments.iter().map(|&(c, d, own, _)| (c, d, own))
    }
}

/// Where a node's legs start: on rays from its image, beyond a line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Window {
    /// The node's image (the source at the root).
    pub image: Point,
    /// Legs start where `normal · (z − origin) ≥ 0`: beyond the window's line; `None` at the
    /// root, where they start at the source.
    pub start: Option<(Vec2, Point)>,
    /// The window's wall ([`SegmentRef::NONE`] at the root): never its own occluder.
    pub own: SegmentRef,
    /// A box that holds the window (at the root, the source).
    pub bounds: Aabb,
}

/// A half-plane `normal · (z − origin) ≥ m`.
#[derive(Clone, Copy, Debug)]
struct Side {
    normal: Vec2,
    origin: Point,
}

impl Occluders {
    /// Every segment of every interface of `scene`.
    pub(crate) fn new(scene: &Scene) -> Occluders {
        let mut segments = Vec::new();
        for (i, interface) in scene.interfaces().iter().enumerate() {
            let line = &interface.polyline;
            for j in 0..line.num_segments() {
                let s = line.segment(j);
                let own = SegmentRef {
                    interface: i as u32,
                    segment: j as u32,
                };
                segments.push((s.start, s.end, own, Aabb::from_points(s.start, s.end)));
            }
        }
        let mut ends: Vec<(u64, u64)> = segments
            .iter()
            .flat_map(|&(c, d, _, _)| [c, d])
            .map(|p| (p.x.to_bits(), p.y.to_bits()))
            .collect();
        ends.sort_unstable();
        let shared = |p: Point| {
            let key = (p.x.to_bits(), p.y.to_bits());
            ends.partition_point(|&e| e < key) + 1 < ends.partition_point(|&e| e <= key)
        };
        let joints = segments
            .iter()
            .map(|&(c, d, _, _)| [shared(c), shared(d)])
            .collect();
        Occluders { segments, joints }
    }

    /// The part of `range` (fractions along `wall`) that the legs from `window` may reach
    /// unobstructed: `range` shrunk past the hidden intervals that cover its ends; `None` when
    /// all of it is hidden. `m` is the module's margin; `shadows` is scratch.
    pub(crate) fn unhidden(
        &self,
        window: &Window,
        wall: &Target,
        range: [f64; 2],
        m: f64,
        shadows: &mut Vec<[f64; 2]>,
    ) -> Option<[f64; 2]> {
        let i = window.image;
        let h = wall.n.dot(i - wall.p);
        // An image too near the wall's line: no occlusion.
        if h.abs().partial_cmp(&(2.0 * m)) != Some(std::cmp::Ordering::Greater) {
            return Some(range);
        }
        let toward = wall.n * h.signum();
        let ahead = Side {
            normal: toward * -1.0,
            origin: i,
        };
        let sides = [
            // Before the wall's line.
            Side {
                normal: toward,
                origin: wall.p,
            },
            ahead,
            // Beyond the window's line (at the root, ahead of the source).
            window
                .start
                .map_or(ahead, |(normal, origin)| Side { normal, origin }),
        ];
        let (x_lo, x_hi) = (wall.at(range[0]), wall.at(range[1]));
        let legs = window.bounds.union(Aabb::from_points(x_lo, x_hi));
        shadows.clear();
        for (&(c, d, own, bbox), &joints) in self.segments.iter().zip(&self.joints) {
            if own == wall.own || own == window.own || !bbox.overlaps(legs) {
                continue;
            }
            if let Some(mut s) = shadow(c, d, joints, &sides, i, wall, m) {
                let corner = Corner { window, wall, m };
                if range[0] == 0.0 {
                    corner.extend(c, d, wall.p, wall.q, &mut s[0], -1.0);
                }
                if range[1] == 1.0 {
                    corner.extend(c, d, wall.q, wall.p, &mut s[1], 2.0);
                }
                shadows.push(s);
            }
        }
        shrink(range, shadows)
    }
}

impl Occluders {
    /// The part of `range` (fractions along `wall`) that no leg from `window` to it crosses
    /// an interface on the way, by the classifier's test: `range` shrunk past every shadow
    /// widened by `m` (each a superset of the true one, where [`unhidden`]'s are subsets);
    /// `None` where a shadow lies inside what is left (the visible part is then no one
    /// interval), where all of it is hidden, where the image lies within `2 m` of the wall's
    /// line, or where an occluder passes so near the image that its projection is
    /// ill-conditioned. What the beam tree's certain beams (`mirrors/grid.rs`) clip their
    /// windows with.
    ///
    /// Every point `z` where a leg crosses an occluder lies beyond the window's line, before
    /// the wall's line and ahead of the image (on the wall's side of the line through it
    /// parallel to the wall); the part of the occluder there, widened by `m`, projects from
    /// the image over the shadow. Only points at least `2 m` ahead are projected; a point
    /// nearer (`a` ahead, `w` along the wall from the image) reaches the wall's line `w |h| / a`
    /// along it, beyond the wall's span unless `|w| ≤ 2 m W / |h|` (`W` the span's farthest
    /// end from the image along the wall), so an occluder farther than `2 m (1 + W / |h|)`
    /// from the image loses nothing to that cut, and a nearer one gives `None`.
    ///
    /// [`unhidden`]: Self::unhidden
    pub(crate) fn clear(
        &self,
        window: &Window,
        wall: &Target,
        range: [f64; 2],
        m: f64,
        shadows: &mut Vec<[f64; 2]>,
    ) -> Option<[f64; 2]> {
        let i = window.image;
        let h = wall.n.dot(i - wall.p);
        if h.abs().partial_cmp(&(2.0 * m)) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let toward = wall.n * h.signum();
        let along = wall.e() * (1.0 / wall.e().length());
        let span = along.dot(wall.p - i).abs().max(along.dot(wall.q - i).abs());
        let near = 2.0 * m * (1.0 + span / h.abs()) + m;
        // Each side with the offset its value must reach: widened by `m` but ahead.
        let ahead = (
            Side {
                normal: toward * -1.0,
                origin: i,
            },
            2.0 * m,
        );
        let before = (
            Side {
                normal: toward,
                origin: wall.p,
            },
            -m,
        );
        let beyond = window
            .start
            .map_or(ahead, |(normal, origin)| (Side { normal, origin }, -m));
        let sides = [ahead, before, beyond];
        let (x_lo, x_hi) = (wall.at(range[0]), wall.at(range[1]));
        let grow = Vec2::new(2.0 * m, 2.0 * m);
        let legs = window.bounds.union(Aabb::from_points(x_lo, x_hi));
        let legs = Aabb::from_points(legs.min - grow, legs.max + grow);
        shadows.clear();
        for &(c, d, own, bbox) in &self.segments {
            if own == wall.own || own == window.own || !bbox.overlaps(legs) {
                continue;
            }
            let distance = segment_distance(i, c, d);
            if distance.partial_cmp(&near) != Some(std::cmp::Ordering::Greater) {
                return None;
            }
            if let Some(s) = widened_shadow(c, d, &sides, i, wall, m) {
                shadows.push(s);
            }
        }
        let [lo, hi] = shrink(range, shadows)?;
        let inside = shadows.iter().any(|s| s[1] > lo && s[0] < hi);
        (!inside).then_some([lo, hi])
    }
}

/// The interval of `wall` (fractions) that occluder `c–d`'s part inside the region `sides`
/// bound (each side's value at least its offset), extended by `m` past both its ends, hides
/// from `image`, widened by `m`; `None` where that part is empty.
fn widened_shadow(
    c: Point,
    d: Point,
    sides: &[(Side, f64); 3],
    image: Point,
    wall: &Target,
    m: f64,
) -> Option<[f64; 2]> {
    let od = d - c;
    let len = od.length();
    if len.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let (mut lo, mut hi) = (-m / len, 1.0 + m / len);
    for (side, offset) in sides {
        let fc = side.normal.dot(c - side.origin) - offset;
        let fd = side.normal.dot(d - side.origin) - offset;
        if fc >= 0.0 && fd >= 0.0 {
            continue;
        }
        if !(fc >= 0.0 || fd >= 0.0) {
            return None;
        }
        // The root, moved outward by its round-off.
        let u = fc / (fc - fd);
        if fc < 0.0 {
            lo = lo.max(u - 4.0 * f64::EPSILON);
        } else {
            hi = hi.min(u + 4.0 * f64::EPSILON);
        }
        if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
            return None;
        }
    }
    let e = wall.e();
    let project = |z: Point| {
        let v = z - image;
        (image - wall.p).cross(v) / e.cross(v)
    };
    let (t0, t1) = (project(c + od * lo), project(c + od * hi));
    let margin = m / e.length();
    Some([t0.min(t1) - margin, t0.max(t1) + margin])
}

/// The distance from `x` to the segment `a–b`.
#[inline(always)]
pub(super) fn segment_distance(x: Point, a: Point, b: Point) -> f64 {
    let e = b - a;
    let ee = e.dot(e);
    if ee > 0.0 {
        let t = ((x - a).dot(e) / ee).clamp(0.0, 1.0);
        x.distance(a + e * t)
    } else {
        x.distance(a)
    }
}

/// The rule at a corner of the child wall shared with an occluder (see the module).
struct Corner<'a> {
    window: &'a Window,
    wall: &'a Target,
    m: f64,
}

impl Corner<'_> {
    /// Moves the shadow's end `end` to `to` (past the wall's end `v`) where occluder `c–d`
    /// meets the wall at `v` and hides it up to there; `other` is the wall's other end.
    fn extend(&self, c: Point, d: Point, v: Point, other: Point, end: &mut f64, to: f64) {
        let far = if c == v {
            d
        } else if d == v {
            c
        } else {
            return;
        };
        let (w, window) = (self.wall, self.window);
        let i = window.image;
        let (image_side, wall_side) = (orient(v, far, i), orient(v, far, other));
        let clear = image_side.abs() > self.m * (far - v).length();
        let opposite = image_side * wall_side < 0.0;
        let legs_side = orient(w.p, w.q, far) * orient(w.p, w.q, i) > 0.0;
        let beyond = window
            .start
            .is_none_or(|(normal, origin)| normal.dot(v - origin) > self.m);
        if clear && opposite && legs_side && beyond {
            *end = to;
        }
    }
}

/// The hidden interval `(t₀, t₁)` of `wall` (fractions) behind occluder `c–d`'s part inside
/// the region `sides` bound (each `≥ m`), seen from `image`; `None` when that part is empty
/// or its shadow vanishes under the margins. The part keeps `m` from each end of the
/// occluder but a joint (`joints`: an end where another segment ends too), where a leg that
/// passes near the end crosses one of the two segments there: the shadows of a polyline's
/// consecutive segments (or of two walls meeting at a corner) then join, without a gap of
/// rays through the corner.
fn shadow(
    c: Point,
    d: Point,
    joints: [bool; 2],
    sides: &[Side; 3],
    image: Point,
    wall: &Target,
    m: f64,
) -> Option<[f64; 2]> {
    let od = d - c;
    let len = od.length();
    if len.partial_cmp(&(2.0 * m)) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    // Strictly inside the occluder: `m` from its free ends.
    let mut lo = if joints[0] { 0.0 } else { m / len };
    let mut hi = if joints[1] { 1.0 } else { 1.0 - m / len };
    for side in sides {
        let fc = side.normal.dot(c - side.origin) - m;
        let fd = side.normal.dot(d - side.origin) - m;
        if fc >= 0.0 && fd >= 0.0 {
            continue;
        }
        if !(fc >= 0.0 || fd >= 0.0) {
            return None;
        }
        // The root, moved inward by its round-off.
        let u = fc / (fc - fd);
        if fc < 0.0 {
            lo = lo.max(u + 4.0 * f64::EPSILON);
        } else {
            hi = hi.min(u - 4.0 * f64::EPSILON);
        }
        if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
            return None;
        }
    }
    let e = wall.e();
    let project = |z: Point| {
        let v = z - image;
        (image - wall.p).cross(v) / e.cross(v)
    };
    let (t0, t1) = (project(c + od * lo), project(c + od * hi));
    let margin = m / e.length();
    let (s0, s1) = (t0.min(t1) + margin, t0.max(t1) - margin);
    (s0 < s1).then_some([s0, s1])
}

/// `range` shrunk from each end past the open intervals of `shadows` that cover it; `None`
/// when nothing is left.
fn shrink(range: [f64; 2], shadows: &mut [[f64; 2]]) -> Option<[f64; 2]> {
    if shadows.is_empty() {
        return Some(range);
    }
    let [mut lo, mut hi] = range;
    shadows.sort_unstable_by(|x, y| x[0].total_cmp(&y[0]));
    for s in shadows.iter() {
        if s[0] < lo && s[1] > lo {
            lo = s[1];
        }
    }
    shadows.sort_unstable_by(|x, y| y[1].total_cmp(&x[1]));
    for s in shadows.iter() {
        if s[1] > hi && s[0] < hi {
            hi = s[0];
        }
    }
    (lo <= hi).then_some([lo, hi])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall from (0, 0) to (4, 0) seen from (2, 2) (the root) behind a segment from (1, 1)
    /// to (3, 1): the shadow is the middle half of the wall, less the margins, so a range
    /// inside it is hidden, and a range reaching past it is cut back to its visible end.
    #[test]
    fn a_segment_hides_its_shadow() {
        let wall = Target {
            own: SegmentRef {
                interface: 0,
                segment: 0,
            },
            p: Point::new(0.0, 0.0),
            q: Point::new(4.0, 0.0),
            n: Vec2::new(0.0, 1.0),
        };
        let (c, d) = (Point::new(1.0, 1.0), Point::new(3.0, 1.0));
        let occluders = Occluders {
            segments: vec![(
                c,
                d,
                SegmentRef {
                    interface: 1,
                    segment: 0,
                },
                Aabb::from_points(c, d),
            )],
            joints: vec![[false; 2]],
        };
        let image = Point::new(2.0, 2.0);
        let window = Window {
            image,
            start: None,
            own: SegmentRef::NONE,
            bounds: Aabb::from_points(image, image),
        };
        let m = 1e-9;
        let mut shadows = Vec::new();
        // The occluder projects from (2, 2) onto y = 0 over x ∈ (0, 4): all of the wall.
        assert_eq!(
            occluders.unhidden(&window, &wall, [0.3, 0.7], m, &mut shadows),
            None
        );
        // From higher up, (2, 3): x ∈ (0.5, 3.5), fractions (0.125, 0.875).
        let window = Window {
            image: Point::new(2.0, 3.0),
            bounds: Aabb::from_points(Point::new(2.0, 3.0), Point::new(2.0, 3.0)),
            ..window
        };
        let r = occluders
            .unhidden(&window, &wall, [0.5, 1.0], m, &mut shadows)
            .unwrap();
        assert!((r[0] - 0.875).abs() < 1e-6 && r[1] == 1.0, "{r:?}");
        let r = occluders
            .unhidden(&window, &wall, [0.0, 0.1], m, &mut shadows)
            .unwrap();
        assert_eq!(r, [0.0, 0.1]);
    }

    /// An occluder that meets the wall at its end and comes from behind the image's view
    /// hides the wall up to that end.
    #[test]
    fn a_wall_behind_a_corner_is_hidden_to_the_corner() {
        // Wall along y = 0 from (0, 0) to (2, 0); an occluder from (0, 0) up to (0, 2) (the
        // corner shared); the image at (-1, 1), left of the occluder's line, the wall's other
        // end right of it: every leg to the wall crosses the occluder.
        let wall = Target {
            own: SegmentRef {
                interface: 0,
                segment: 0,
            },
            p: Point::new(0.0, 0.0),
            q: Point::new(2.0, 0.0),
            n: Vec2::new(0.0, 1.0),
        };
        let (c, d) = (Point::new(0.0, 0.0), Point::new(0.0, 2.0));
        let occluders = Occluders {
            segments: vec![(
                c,
                d,
                SegmentRef {
                    interface: 0,
                    segment: 1,
                },
                Aabb::from_points(c, d),
            )],
            joints: vec![[false; 2]],
        };
        let image = Point::new(-1.0, 1.0);
        let window = Window {
            image,
            start: None,
            own: SegmentRef::NONE,
            bounds: Aabb::from_points(image, image),
        };
        let mut shadows = Vec::new();
        assert_eq!(
            occluders.unhidden(&window, &wall, [0.0, 1.0], 1e-9, &mut shadows),
            None
        );
        // Seen from the right of the occluder's line, nothing is hidden.
        let image = Point::new(1.0, 1.0);
        let window = Window {
            image,
            bounds: Aabb::from_points(image, image),
            ..window
        };
        assert_eq!(
            occluders.unhidden(&window, &wall, [0.0, 1.0], 1e-9, &mut shadows),
            Some([0.0, 1.0])
        );
    }
}
