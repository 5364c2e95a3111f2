//! One leg of a ray through a profile medium between two arbitrary points, as the leg model
//! has it ([`ProfileLeg`], [`ProfileLegModel`]): the ray of one branch (its first vertical
//! direction and its turning points) whose range is the ends' horizontal distance, and the
//! derivatives of its time with respect to its ends.
//!
//! With `p` the ray's horizontal slowness (signed as its horizontal direction), `X_p = ∂X/∂p`
//! (the range's derivative along the branch, ends fixed) and, at each end, the sine `s` of
//! the ray's angle with the horizontal, the speed `c`, its slope `c′ = dc/dy` on the ray's
//! side and the ray's vertical direction there (`first` at the start, `last` at the end):
//!
//! | quantity | value |
//! | --- | --- |
//! | `∇_b T` (arrival) | `(p, last · s_b / c_b)` |
//! | `−∇_a T` (departure) | `(p, first · s_a / c_a)` |
//! | `∇_b p`, `∇_a p` | `v_b / X_p`, `−v_a / X_p`, with `v = (1, −dir · p c / s)` |
//! | `tᵀ ∂²T/∂b² t` | `(v_b · t)² / X_p − last · c′_b t_y² / (c_b² s_b)` |
//! | `tᵀ ∂²T/∂a² t` | `(v_a · t)² / X_p + first · c′_a t_y² / (c_a² s_a)` |
//! | `t_aᵀ ∂²T/∂a∂b t_b` | `−(v_a · t_a)(v_b · t_b) / X_p` |
//!
//! (the vertical slowness `±√(c⁻² − p²)` moves with `p` and with the end's height; the
//! range moves with the end's height by `dir · p c / s`). A straight leg is `X_p = h c / s³`:
//! the blocks are `w (u × t)² / ℓ`; a leg in one linear layer is the `gradient` medium's arc.

use super::{Profile, ProfileRay, sine};
use crate::geom::{Aabb, Point, Vec2};
use crate::leg::{Leg, LegModel, box_gap};

/// Which ray of a profile joins a leg's two ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Branch {
    /// The first vertical direction (+1 up, −1 down).
    pub first: f64,
    /// The turning points.
    pub turns: u32,
    /// The horizontal slowness `|p|` the leg's ray is nearest (a branch with turns can hold
    /// several rays between two points, beside its caustics; a branch without turns has at
    /// most one, and this is not read).
    pub near: f64,
}

/// One leg of a ray in a profile medium ([`Profile::leg`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ProfileLeg {
    /// The travel time.
    pub time: f64,
    /// The horizontal slowness, signed as the ray's horizontal direction.
    pub p: f64,
    /// `∂X/∂p` along the branch, ends fixed.
    pub x_p: f64,
    /// The vertical direction at the start and at the end (+1 up).
    pub dirs: [f64; 2],
    /// The sines of the ray's angle with the horizontal at the ends (≥ 0).
    pub sines: [f64; 2],
    /// The speeds at the ends.
    pub speeds: [f64; 2],
    /// `dc/dy` at the ends, in the layer the ray leaves into and arrives from.
    pub slopes: [f64; 2],
    /// `∫ c ds` and the arc length.
    pub width: f64,
    pub arc: f64,
    /// The chord `b − a` and its length.
    pub chord: Vec2,
    pub len: f64,
    /// The turning points, and the caustics the tube from the start passes on the leg.
    pub turns: u32,
    pub caustics: u32,
}

impl ProfileLeg {
    /// The leg of `ray` from `a` to `b` in `profile`.
    pub fn of(profile: &Profile, ray: &ProfileRay, a: Vec2, b: Vec2) -> ProfileLeg {
        let chord = b - a;
        ProfileLeg {
            time: ray.sums.t,
            p: ray.p,
            x_p: ray.sums.x_p,
            dirs: [ray.first, ray.last],
            sines: ray.sines,
            speeds: ray.speeds,
            slopes: [
                profile.slope_toward(a.y, ray.first),
                profile.slope_toward(b.y, -ray.last),
            ],
            width: ray.sums.width,
            arc: ray.sums.arc,
            chord,
            len: chord.length(),
            turns: ray.turns,
            caustics: ray.caustics,
        }
    }

    /// The leg that joins nothing: its time infinite, its derivatives not numbers (a point
    /// the solver must step back from).
    fn missing(a: Vec2, b: Vec2) -> ProfileLeg {
        let chord = b - a;
        ProfileLeg {
            time: f64::INFINITY,
            p: f64::NAN,
            x_p: f64::NAN,
            dirs: [f64::NAN; 2],
            sines: [f64::NAN; 2],
            speeds: [f64::NAN; 2],
            chord,
            len: chord.length(),
            ..ProfileLeg::default()
        }
    }

    /// `v = (1, −dir · p c / s)` at end `i` (0 the start, 1 the end).
    #[inline]
    fn v(&self, i: usize) -> Vec2 {
        Vec2::new(1.0, -self.dirs[i] * self.p * self.speeds[i] / self.sines[i])
    }

    /// The branch this leg is the ray of.
    pub fn branch(&self) -> Branch {
        Branch {
            first: self.dirs[0],
            turns: self.turns,
            near: self.p.abs(),
        }
    }
}

impl Leg for ProfileLeg {
    #[inline]
    fn time(&self) -> f64 {
        self.time
    }
    #[inline]
    fn arrival(&self) -> Vec2 {
        Vec2::new(self.p, self.dirs[1] * self.sines[1] / self.speeds[1])
    }
    #[inline]
    fn departure(&self) -> Vec2 {
        Vec2::new(self.p, self.dirs[0] * self.sines[0] / self.speeds[0])
    }
    #[inline]
    fn direction_at_end(&self) -> Vec2 {
        Vec2::new(self.p * self.speeds[1], self.dirs[1] * self.sines[1])
    }
    #[inline]
    fn direction_at_start(&self) -> Vec2 {
        Vec2::new(self.p * self.speeds[0], self.dirs[0] * self.sines[0])
    }
    fn end_block(&self, t: Vec2) -> f64 {
        let vt = self.v(1).dot(t);
        let [_, c] = self.speeds;
        vt * vt / self.x_p - self.dirs[1] * self.slopes[1] * t.y * t.y / (c * c * self.sines[1])
    }
    fn start_block(&self, t: Vec2) -> f64 {
        let vt = self.v(0).dot(t);
        let [c, _] = self.speeds;
        vt * vt / self.x_p + self.dirs[0] * self.slopes[0] * t.y * t.y / (c * c * self.sines[0])
    }
    fn coupling(&self, ta: Vec2, tb: Vec2) -> f64 {
        -self.v(0).dot(ta) * self.v(1).dot(tb) / self.x_p
    }
    fn out_of_plane_width(&self, source_slowness: f64) -> f64 {
        source_slowness * self.width
    }
}

/// The legs of one branch of a profile medium ([`LegModel`]): positions relative to
/// `origin`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ProfileLegModel<'a> {
    /// The profile (without walls: a leg's ends are its reflections).
    pub profile: &'a Profile,
    /// Where the leg's positions are measured from.
    pub origin: Vec2,
    /// Which ray.
    pub branch: Branch,
}

impl PartialEq for ProfileLegModel<'_> {
    fn eq(&self, o: &Self) -> bool {
        std::ptr::eq(self.profile, o.profile) && self.origin == o.origin && self.branch == o.branch
    }
}

impl LegModel for ProfileLegModel<'_> {
    type Leg = ProfileLeg;

    fn leg(self, a: Vec2, b: Vec2) -> ProfileLeg {
        self.valid_leg(a.to_point(), b.to_point())
            .unwrap_or_else(|| ProfileLeg::missing(a, b))
    }

    fn valid_leg(self, a: Point, b: Point) -> Option<ProfileLeg> {
        let (a, b) = (a.to_vec2() + self.origin, b.to_vec2() + self.origin);
        let ray = self.profile.leg_ray(a, b, self.branch)?;
        let mut leg = ProfileLeg::of(self.profile, &ray, a, b);
        leg.chord = b - a;
        Some(leg)
    }

    fn least_time(self, from: Aabb, to: Aabb) -> f64 {
        box_gap(from, to) / self.profile.fastest_knot()
    }

    fn least_time_to(self, from: Aabb, to: Point) -> f64 {
        from.distance_sq(to).sqrt() / self.profile.fastest_knot()
    }

    fn along_at_ends(self, _chord_along: [f64; 2]) -> [f64; 2] {
        let w = self.greatest_slowness();
        [-w, w]
    }

    fn greatest_slowness(self) -> f64 {
        1.0 / self.profile.slowest_knot()
    }
}

impl Profile {
    /// The greatest and the least speed of the knots (the speed's range everywhere).
    pub(crate) fn fastest_knot(&self) -> f64 {
        self.c.iter().copied().fold(0.0, f64::max)
    }
    pub(crate) fn slowest_knot(&self) -> f64 {
        self.c.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// `dc/dy` in the layer entered from `y` going `dir` (+1 up; 0 beyond the end knots).
    pub(crate) fn slope_toward(&self, y: f64, dir: f64) -> f64 {
        let n = self.y.len();
        let i = if dir > 0.0 {
            self.y.partition_point(|&k| k <= y)
        } else {
            self.y.partition_point(|&k| k < y)
        };
        if i == 0 || i >= n {
            return 0.0;
        }
        (self.c[i] - self.c[i - 1]) / (self.y[i] - self.y[i - 1])
    }

    /// The ray of branch `(first, turns)` with ray parameter `p ≥ 0` (launch sine `sa`)
    /// from `a` to `b`, evaluated in full (`None` where the branch has none at `p`).
    fn ray_at(
        &self,
        a: Vec2,
        b: Vec2,
        p: f64,
        sa: f64,
        first: f64,
        turns: u32,
    ) -> Option<ProfileRay> {
        let mut caustics = 0;
        let sums =
            self.branch::<true>(p, sa, [a.y, b.y], first, turns, Some(&mut caustics), None)?;
        let last = if turns.is_multiple_of(2) {
            first
        } else {
            -first
        };
        let sign_x = if b.x < a.x { -1.0 } else { 1.0 };
        Some(ProfileRay {
            p: sign_x * p,
            first,
            turns,
            reflections: 0,
            caustics,
            sines: [sa, sine(p, self.speed_at(b.y))],
            speeds: [self.speed_at(a.y), self.speed_at(b.y)],
            last,
            sums,
        })
    }

    /// The ray of `branch` from `a` to `b` (no walls: this profile's own), `None` where the
    /// branch has none. Without turns the branch's range grows with `p`, so its one ray is
    /// found by bisection on the launch angle; with turns every root of the sampled branch
    /// (as [`arrivals`](Self::arrivals_within) finds them) is found and the one whose `|p|`
    /// is nearest `branch.near` kept. The time takes the first-order correction to the
    /// exact range (`dT = p dX`).
    pub(crate) fn leg_ray(&self, a: Vec2, b: Vec2, branch: Branch) -> Option<ProfileRay> {
        let Branch { first, turns, near } = branch;
        let dx = (b.x - a.x).abs();
        let ca = self.speed_at(a.y);
        if !(dx.is_finite() && a.y.is_finite() && b.y.is_finite()) {
            return None;
        }
        if dx == 0.0 {
            let toward = (b.y - a.y) * first > 0.0;
            return (turns == 0 && toward)
                .then(|| self.ray_at(a, b, 0.0, 1.0, first, 0))
                .flatten();
        }
        let at = |theta: f64| (theta.cos() / ca, theta.sin());
        let value = |theta: f64| {
            let (p, sa) = at(theta);
            let sums = self.branch::<false>(p, sa, [a.y, b.y], first, turns, None, None)?;
            Some(sums.x - dx)
        };
        let mut chosen: Option<f64> = None;
        if turns == 0 {
            if (b.y - a.y) * first <= 0.0 {
                return None;
            }
            // X falls as θ rises; a ray that turns before `b` counts as too shallow.
            let (mut lo, mut hi) = (0.0f64, std::f64::consts::FRAC_PI_2);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                match value(mid) {
                    Some(v) if v <= 0.0 => hi = mid,
                    _ => lo = mid,
                }
            }
            chosen = Some(hi);
        } else {
            let thetas = self.launch_angles(ca);
            let values: Vec<f64> = thetas
                .iter()
                .map(|&t| value(t).unwrap_or(f64::NAN))
                .collect();
            let mut best = f64::INFINITY;
            for j in 1..thetas.len() - 1 {
                let (v0, v1) = (values[j], values[j + 1]);
                if !(v0.is_finite() && v1.is_finite()) || (v0 > 0.0) == (v1 > 0.0) {
                    continue;
                }
                let theta = self.refine(
                    [thetas[j], thetas[j + 1]],
                    v0,
                    [a.y, b.y],
                    (first, turns),
                    dx,
                    ca,
                );
                let (p, _) = at(theta);
                let off = if near.is_finite() {
                    (p - near).abs()
                } else {
                    0.0
                };
                if off < best && value(theta).is_some_and(|v| v.abs() <= 1e-7 * dx.max(1.0)) {
                    (best, chosen) = (off, Some(theta));
                    if !near.is_finite() {
                        break;
                    }
                }
            }
        }
        let theta = chosen?;
        let (p, sa) = at(theta);
        let mut ray = self.ray_at(a, b, p, sa, first, turns)?;
        if (ray.sums.x - dx).abs() > 1e-7 * dx.max(1.0) {
            return None;
        }
        ray.sums.t += p * (dx - ray.sums.x);
        Some(ray)
    }
}

impl Profile {
    /// The free ray from `start` leaving in the unit direction `direction`, piece by piece
    /// (each inside one layer, ended by a knot or a turning point; one beyond the end knots
    /// ends at the bound of `heights` it heads for), each handed to `visit` until it returns
    /// `false`, the ray leaves `heights`, or `max_pieces` have been visited.
    pub(crate) fn march(
        &self,
        start: Vec2,
        direction: Vec2,
        heights: [f64; 2],
        max_pieces: usize,
        mut visit: impl FnMut(&super::RayPiece) -> bool,
    ) {
        use super::{PieceEnd, RayPiece, piece};
        let c0 = self.speed_at(start.y);
        let p = (direction.x.abs() / c0).min(1.0 / c0);
        let sx = if direction.x < 0.0 { -1.0 } else { 1.0 };
        let mut dir = if direction.y < 0.0 { -1.0 } else { 1.0 };
        let (mut x, mut y, mut s) = (start.x, start.y, direction.y.abs().min(1.0));
        for _ in 0..max_pieces {
            if !(heights[0]..=heights[1]).contains(&y) {
                return;
            }
            let c = self.speed_at(y);
            let bound = if dir > 0.0 { heights[1] } else { heights[0] };
            let (mut y_end, mut c_end, mut end_kind) = match self.next_knot(y, dir) {
                Some(i) if (self.y[i] - bound) * dir < 0.0 => {
                    (self.y[i], self.c[i], PieceEnd::Knot)
                }
                _ => (bound, self.speed_at(bound), PieceEnd::Target),
            };
            if p > 0.0 && c_end >= 1.0 / p && c_end != c {
                let slope = (c_end - c) / (y_end - y);
                y_end = y + (1.0 / p - c) / slope;
                c_end = 1.0 / p;
                end_kind = PieceEnd::Turn;
            }
            let s_end = if end_kind == PieceEnd::Turn {
                0.0
            } else {
                sine(p, c_end)
            };
            let part = piece::<false>(p, (y_end - y).abs(), c, c_end, s, s_end);
            let from = Vec2::new(x, y);
            x += sx * part.x;
            let run = RayPiece {
                start: from,
                end: Vec2::new(x, y_end),
                speeds: [c, c_end],
                sines: [s, s_end],
                p,
                sx,
                end_kind,
            };
            if !visit(&run) || end_kind == PieceEnd::Target || !x.is_finite() {
                return;
            }
            if end_kind == PieceEnd::Turn {
                dir = -dir;
            }
            (y, s) = (y_end, s_end);
        }
    }
}

impl super::RayPiece {
    /// Where the piece passes the height `y` (inside its range of heights, ends included):
    /// the closed-form range from its start.
    pub(crate) fn at_height(&self, y: f64) -> Option<Vec2> {
        let (lo, hi) = if self.start.y <= self.end.y {
            (self.start.y, self.end.y)
        } else {
            (self.end.y, self.start.y)
        };
        if !(lo..=hi).contains(&y) {
            return None;
        }
        if y == self.end.y {
            return Some(self.end);
        }
        let [c1, c2] = self.speeds;
        let f = if self.end.y == self.start.y {
            0.0
        } else {
            (y - self.start.y) / (self.end.y - self.start.y)
        };
        let c = c1 + (c2 - c1) * f;
        let part = super::piece::<false>(
            self.p,
            (y - self.start.y).abs(),
            c1,
            c,
            self.sines[0],
            sine(self.p, c),
        );
        Some(Vec2::new(self.start.x + self.sx * part.x, y))
    }

    /// The unit direction of the ray where it passes the height `y` of the piece.
    pub(crate) fn direction_at(&self, y: f64) -> Vec2 {
        let [c1, c2] = self.speeds;
        let f = if self.end.y == self.start.y {
            0.0
        } else {
            (y - self.start.y) / (self.end.y - self.start.y)
        };
        let c = c1 + (c2 - c1) * f.clamp(0.0, 1.0);
        let up = if self.end.y >= self.start.y {
            1.0
        } else {
            -1.0
        };
        let s = sine(self.p, c);
        Vec2::new(self.sx * self.p * c, up * s)
    }
}

#[cfg(test)]
#[path = "leg_tests.rs"]
mod tests;
