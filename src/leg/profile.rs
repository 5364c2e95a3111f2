//! A medium whose speed is piecewise linear in `y` and constant in `x` (BELLHOP's `'C'`
//! profile, `y` up): every ray between two points of it, in the ray-parameter form.
//!
//! In such a medium the horizontal slowness `p = cos θ / c` is conserved along a ray, so a
//! ray is fixed by `p`, its first vertical direction and its number of turning points (its
//! *branch*). Inside one linear layer the ray is a circular arc, and each quantity of a piece
//! of it between heights `y₁` and `y₂` (speeds `c₁`, `c₂`, `sᵢ = √(1 − p²cᵢ²)` the sines of
//! the angles with the horizontal) has a closed form written without a division by the
//! layer's gradient or by `p`, so a uniform layer and a vertical ray are the same formulas:
//!
//! | quantity | piece from `y₁` to `y₂` (`h = |y₂ − y₁|`) |
//! | --- | --- |
//! | range `X` | `h p (c₁ + c₂) / (s₁ + s₂)` |
//! | `∫ c ds = X / p` | `h (c₁ + c₂) / (s₁ + s₂)` |
//! | time `T = (atanh s₁ − atanh s₂) / g` | `h (c₁ + c₂)(1 + s₁s₂) / ((s₁ + s₂)(c₁² + c₂² − p²c₁²c₂²)) · atanh(q)/q` |
//! | arc length | `h (c₁ + c₂) / (c₂s₁ + c₁s₂) · asin(z)/z` |
//! | `∂X/∂p`, both ends fixed | `X / (p s₁ s₂)` |
//! | `∂X/∂p`, one end a turning point | `−1 / (s |g| p²)` (`s` at the other end) |
//! | `−∂T/∂c` of a speed raised everywhere, `A = ∫ \|dy\| / (c² s)` | `h (c₁ + c₂) / (c₁ c₂ (c₂s₁ + c₁s₂))` |
//!
//! with `q = (c₂² − c₁²)(1 + s₁s₂) / ((s₁ + s₂)(c₁² + c₂² − p²c₁²c₂²))` and
//! `z = p (c₂² − c₁²) / (c₂s₁ + c₁s₂)`. A turning point is where `c = 1/p` (`s = 0`): the same
//! formulas with `s₂ = 0`. Beyond the end knots the speed is that of the nearest knot (a
//! uniform layer, where no ray turns).
//!
//! Between two points, the rays of a branch are the roots of `X(p) = Δx`; `X` is not
//! monotone on a branch with turns (caustics), so [`Profile::arrivals`] samples the launch
//! angle and refines every sign change by bisection. A caustic the ray tube passes is a zero
//! of `Q ∝ sin θ · ∂X/∂p` (the prefix's `∂X/∂p` at fixed end): inside one linear layer `Q` is
//! linear in `sin θ`, which is monotone along the arc, so `Q` has at most one zero per layer
//! traversal and its sign at the knots and at the receiver counts them exactly.
//!
//! The derivatives of a ray's time with respect to the knots' speeds, its ends held, are
//! the partials at fixed `p` of `τ = T − pX = ∫ √(c⁻² − p²) |dy|` (the time is stationary in
//! the ray): each piece shares `−A` between its layer's two knots by their hat functions,
//! in closed form ([`piece_knot_derivatives`], [`Profile::knot_derivatives`]).

use crate::geom::Vec2;

mod leg;

pub(crate) use leg::{Branch, ProfileLeg, ProfileLegModel};

/// A speed profile: knots `(y, c)` in increasing `y` (the scene's order reversed), and
/// the flat horizontal reflecting walls that bound it, if any.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Profile {
    /// Heights of the knots, increasing.
    y: Vec<f64>,
    /// Speeds at the knots.
    c: Vec<f64>,
    /// The walls: a ray that reaches one before it turns reflects there.
    walls: Walls,
}

/// The flat horizontal walls of a waveguide (a surface above, a bottom below): a ray that
/// reaches one before its turning point reflects there, which acts as a turning point at
/// that height with the ray's angle there (no caustic of its own).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Walls {
    /// The height of the upper wall.
    pub top: Option<f64>,
    /// The height of the lower wall.
    pub bottom: Option<f64>,
}

impl Walls {
    /// The wall met going in direction `dir` (+1 up) from `y`, strictly beyond it.
    fn ahead(&self, y: f64, dir: f64) -> Option<f64> {
        let w = if dir > 0.0 { self.top } else { self.bottom }?;
        ((w - y) * dir > 0.0).then_some(w)
    }
}

/// One turning point or reflection of a ray ([`Profile::events`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Event {
    /// Where: the horizontal distance from the start (≥ 0) and the height.
    pub x: f64,
    pub y: f64,
    /// A reflection at a wall (`true`) or a turning point.
    pub wall: bool,
    /// At a wall: the sine of the ray's angle with the horizontal there, and the speed.
    pub sine: f64,
    pub speed: f64,
}

/// What an enumeration of rays between walls keeps ([`Profile::arrivals_within`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    /// The most reflections.
    pub reflections: u32,
    /// The latest time.
    pub time: f64,
}

/// The most turning points and reflections searched on one ray between walls.
pub(crate) const MAX_EVENTS: u32 = 400;

/// The sums over the pieces of a ray (or of one of its runs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct RaySums {
    /// Horizontal range.
    pub x: f64,
    /// Travel time.
    pub t: f64,
    /// `∫ c ds`.
    pub width: f64,
    /// Arc length.
    pub arc: f64,
    /// `∂X/∂p` (ends fixed, turning points moving with `p`).
    pub x_p: f64,
}

impl RaySums {
    fn add(&mut self, o: RaySums) {
        self.x += o.x;
        self.t += o.t;
        self.width += o.width;
        self.arc += o.arc;
        self.x_p += o.x_p;
    }
}

/// One ray between two points of a profile: its branch, its ray parameter and its sums.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ProfileRay {
    /// The horizontal slowness, signed as the ray's horizontal direction.
    pub p: f64,
    /// The first vertical direction (+1 up, −1 down).
    pub first: f64,
    /// The number of turning points (reflections at walls not counted).
    pub turns: u32,
    /// The number of reflections at walls.
    pub reflections: u32,
    /// The number of caustics the ray tube passes (zeros of `Q`).
    pub caustics: u32,
    /// The sine of the angle with the horizontal at the start and at the end (≥ 0).
    pub sines: [f64; 2],
    /// The speeds at the start and at the end.
    pub speeds: [f64; 2],
    /// The last vertical direction (+1 up, −1 down).
    pub last: f64,
    /// Time, range, `∫ c ds`, arc length and `∂X/∂p`.
    pub sums: RaySums,
}

impl ProfileRay {
    /// The unit direction at the start.
    pub fn direction_at_start(&self) -> Vec2 {
        let [ca, _] = self.speeds;
        Vec2::new(self.p * ca, self.first * self.sines[0])
    }
    /// The unit direction at the end.
    pub fn direction_at_end(&self) -> Vec2 {
        let [_, cb] = self.speeds;
        Vec2::new(self.p * cb, self.last * self.sines[1])
    }
    /// `c_s ‖∂²T/∂a∂b‖ = c_s / (|∂X/∂p| s_a s_b)`: the inverse of the tube's in-plane width
    /// per unit turn of the take-off direction, times the source's speed over the
    /// source's slowness as the amplitude's sweep has it (`1 / W`).
    pub fn inverse_width(&self) -> f64 {
        let [sa, sb] = self.sines;
        self.speeds[0] / (self.sums.x_p.abs() * sa * sb)
    }
}

/// What [`Profile::arrivals`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ProfileArrivals {
    /// The rays, by time.
    pub rays: Vec<ProfileRay>,
    /// Whether the branches were searched up to the most turns a ray can have there (not a
    /// proof: two roots closer than the sampling can be missed).
    pub every_branch: bool,
}

/// The launch angles sampled on each branch ([`Profile::arrivals`]).
pub(crate) const PROFILE_SAMPLES: usize = 4096;

/// The most turning points searched on one leg.
pub(crate) const MAX_TURNS: u32 = 200;

/// `atanh(q) / q` for `|q| < 1`, without loss near 0.
fn atanh_over(q: f64) -> f64 {
    let q = q.abs();
    if q < 1e-3 {
        let q2 = q * q;
        1.0 + q2 * (1.0 / 3.0 + q2 * (1.0 / 5.0 + q2 / 7.0))
    } else {
        q.atanh() / q
    }
}

/// What a piece of a ray gives the derivatives of its time with respect to its layer's
/// knots ([`piece_knot_derivatives`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PieceKnotSums {
    /// `A = ∫ |dy| / (c² s)`: minus `∂T/∂c` for a speed raised by one everywhere.
    pub a: f64,
    /// `R = (T − c̄ A) / (c₂ − c₁)` (`c̄` the mean of the ends' speeds): how the weight
    /// moves toward the faster end.
    pub r: f64,
    /// The piece's time `T` (the module's closed form).
    pub t: f64,
}

/// `A` and `R` of a piece of a ray (height `h ≥ 0`, speeds `c₁`, `c₂`, sines `s₁`, `s₂` at
/// its ends) in closed form without a division by the layer's gradient. With
/// `ψ = atanh s` (so `p c = sech ψ`, and `T = (ψ₁ − ψ₂)/g`):
///
/// ```text
/// A = h (c₁ + c₂) / (c₁ c₂ (c₂ s₁ + c₁ s₂))
/// δ = ψ₁ − ψ₂ = atanh q,   q and w = q/(c₂ − c₁) as in the time (T = h w atanh(q)/q)
/// K = 1/cosh² ψ̄ = 2 p² c₁ c₂ / (1 + s₁ s₂ + p² c₁ c₂)      (ψ̄ the mean of ψ₁, ψ₂)
/// Φ = (K sinh²(δ/2)/δ² − (sinh δ − δ)/δ³) / (1 + K sinh²(δ/2))
/// R = h Φ (w atanh(q)/q)³ (c₂ − c₁)
/// ```
///
/// (`T − c̄ A = (δ − sinh δ / (1 + K sinh²(δ/2))) / g`), the two ratios of `δ` by their
/// series below 0.1.
pub(crate) fn piece_knot_derivatives(
    p: f64,
    h: f64,
    [c1, c2]: [f64; 2],
    [s1, s2]: [f64; 2],
) -> PieceKnotSums {
    let a = h * (c1 + c2) / (c1 * c2 * (c2 * s1 + c1 * s2));
    let m = c1 * c1 + c2 * c2 - p * p * c1 * c1 * c2 * c2;
    let w = (c1 + c2) * (1.0 + s1 * s2) / ((s1 + s2) * m);
    let q = (c2 - c1) * w;
    let ratio = atanh_over(q);
    let delta = q * ratio;
    let pc2 = p * p * c1 * c2;
    let k = 2.0 * pc2 / (1.0 + s1 * s2 + pc2);
    let half = (0.5 * delta).sinh();
    let d2 = delta * delta;
    // sinh²(δ/2)/δ² = (cosh δ − 1)/(2δ²) and (sinh δ − δ)/δ³, by their series near 0.
    let (even, odd) = if delta.abs() < 0.1 {
        (
            0.25 + d2 * (1.0 / 48.0 + d2 * (1.0 / 1440.0 + d2 * (1.0 / 80640.0 + d2 / 7257600.0))),
            1.0 / 6.0
                + d2 * (1.0 / 120.0
                    + d2 * (1.0 / 5040.0 + d2 * (1.0 / 362880.0 + d2 / 39916800.0))),
        )
    } else {
        (half * half / d2, (delta.sinh() - delta) / (d2 * delta))
    };
    let phi = (k * even - odd) / (1.0 + k * half * half);
    let wr = w * ratio;
    PieceKnotSums {
        a,
        r: h * phi * wr * wr * wr * (c2 - c1),
        t: h * wr,
    }
}

/// `√(1 − p²c²)`, 0 at and beyond a turning point.
#[inline]
fn sine(p: f64, c: f64) -> f64 {
    let pc = p * c;
    ((1.0 - pc) * (1.0 + pc)).max(0.0).sqrt()
}

/// The sums of one piece of a ray in one linear layer (see the module), `h ≥ 0`; `x_p` is
/// left to the caller (it depends on which ends are turning points). Without `FULL`, only
/// the range and `∫ c ds` (the sampling's and the refinement's: no transcendental call).
fn piece<const FULL: bool>(p: f64, h: f64, c1: f64, c2: f64, s1: f64, s2: f64) -> RaySums {
    let den = s1 + s2;
    let width = h * (c1 + c2) / den;
    if !FULL {
        return RaySums {
            x: p * width,
            width,
            ..RaySums::default()
        };
    }
    let m = c1 * c1 + c2 * c2 - p * p * c1 * c1 * c2 * c2;
    let q = (c2 * c2 - c1 * c1) * (1.0 + s1 * s2) / (den * m);
    let t = h * (c1 + c2) * (1.0 + s1 * s2) / (den * m) * atanh_over(q);
    let across = c2 * s1 + c1 * s2;
    let z = p * (c2 * c2 - c1 * c1) / across;
    let arc = h * (c1 + c2) / across * super::asin_over(z.abs());
    RaySums {
        x: p * width,
        t,
        width,
        arc,
        x_p: 0.0,
    }
}

/// The range of a ray of horizontal slowness `p ≥ 0` across one linear layer of thickness
/// `h` with speeds `c₁`, `c₂` at its faces, without a turning point (`p c < 1` at both), and
/// its derivative in `p` (both ends fixed): [`piece`]'s range and the module's `∂X/∂p =
/// X / (p s₁ s₂)`, written `∫ c ds / (s₁ s₂)` (no division by `p`). The start of a ray
/// through flat layers with vertical gradients (`trace::start`) sums them.
#[inline]
pub(crate) fn layer_range(p: f64, h: f64, [c1, c2]: [f64; 2]) -> LayerRange {
    let (s1, s2) = (sine(p, c1), sine(p, c2));
    let part = piece::<false>(p, h, c1, c2, s1, s2);
    LayerRange {
        x: part.x,
        x_p: part.width / (s1 * s2),
    }
}

/// [`layer_range`]'s result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LayerRange {
    /// The horizontal range across the layer.
    pub x: f64,
    /// Its derivative in the ray parameter.
    pub x_p: f64,
}

/// Where a run ends: at its target height, or at a turning point.
#[derive(Clone, Copy, Debug)]
enum RunEnd {
    /// At the target.
    Target,
    /// At a turning point, at this height.
    Turn(f64),
    /// At a wall, at this height, with this sine there.
    Wall(f64, f64),
}

/// A run of a ray: its sums and where it ended.
#[derive(Clone, Copy, Debug)]
struct Run {
    sums: RaySums,
    end: RunEnd,
}

/// The ranges of the runs every branch's ray at one `p` is made of ([`Profile::parts`]).
#[derive(Clone, Copy, Debug)]
struct Parts {
    /// From `a` to `b` without a turn.
    direct: Option<f64>,
    /// From `a` up to its upper turning point, and down to its lower one.
    first_up: Option<f64>,
    first_down: Option<f64>,
    /// From one turning point to the other.
    full: Option<f64>,
    /// From the upper turning point down to `b`, and from the lower one up to `b`.
    from_hi: Option<f64>,
    from_lo: Option<f64>,
    /// The direction from `a` to `b`'s height.
    toward: f64,
    /// Whether the upper and the lower event are reflections at walls.
    hi_wall: bool,
    lo_wall: bool,
}

impl Parts {
    fn none() -> Parts {
        Parts {
            direct: None,
            first_up: None,
            first_down: None,
            full: None,
            from_hi: None,
            from_lo: None,
            toward: 1.0,
            hi_wall: false,
            lo_wall: false,
        }
    }

    /// The reflections of the branch `(first, events)`: its events alternate between the
    /// upper and the lower one.
    fn reflections(&self, first: f64, events: u32) -> u32 {
        let upper = if first > 0.0 {
            events.div_ceil(2)
        } else {
            events / 2
        };
        u32::from(self.hi_wall) * upper + u32::from(self.lo_wall) * (events - upper)
    }

    /// The range of the branch `(first, turns)`.
    fn range(&self, first: f64, turns: u32) -> Option<f64> {
        if turns == 0 {
            return if first == self.toward {
                self.direct
            } else {
                None
            };
        }
        let start = if first > 0.0 {
            self.first_up
        } else {
            self.first_down
        }?;
        // The last run leaves the turning point reached going `first · (−1)^(turns − 1)`.
        let last_up = if turns % 2 == 1 {
            first > 0.0
        } else {
            first < 0.0
        };
        let end = if last_up { self.from_hi } else { self.from_lo }?;
        let middle = if turns >= 2 {
            self.full? * f64::from(turns - 1)
        } else {
            0.0
        };
        Some(start + middle + end)
    }
}

impl Profile {
    /// The profile of the knots `[y, c]`, `y` strictly decreasing (validated by the scene).
    pub fn new(knots: &[[f64; 2]]) -> Profile {
        Profile {
            y: knots.iter().rev().map(|k| k[0]).collect(),
            c: knots.iter().rev().map(|k| k[1]).collect(),
            walls: Walls::default(),
        }
    }

    /// The profile between `walls` (the points a ray joins lie between them).
    pub fn with_walls(mut self, walls: Walls) -> Profile {
        self.walls = walls;
        self
    }

    /// The greatest speed between the walls (or over the knots where there is none).
    fn fastest(&self) -> f64 {
        let mut c = self.c.iter().copied().fold(0.0, f64::max);
        for w in [self.walls.top, self.walls.bottom].into_iter().flatten() {
            c = c.max(self.speed_at(w));
        }
        c
    }

    /// The speed at height `y`.
    pub fn speed_at(&self, y: f64) -> f64 {
        let n = self.y.len();
        if y <= self.y[0] {
            return self.c[0];
        }
        if y >= self.y[n - 1] {
            return self.c[n - 1];
        }
        let i = self.y.partition_point(|&k| k <= y).clamp(1, n - 1) - 1;
        let (y0, y1) = (self.y[i], self.y[i + 1]);
        let (c0, c1) = (self.c[i], self.c[i + 1]);
        c0 + (c1 - c0) * ((y - y0) / (y1 - y0))
    }

    /// The index of the first knot strictly beyond `y` in the direction `dir` (`None`:
    /// the uniform speed beyond the end knot reaches to infinity).
    fn next_knot(&self, y: f64, dir: f64) -> Option<usize> {
        if dir > 0.0 {
            let i = self.y.partition_point(|&k| k <= y);
            (i < self.y.len()).then_some(i)
        } else {
            let i = self.y.partition_point(|&k| k < y);
            i.checked_sub(1)
        }
    }

    /// A run from `y0` (sine `s0` there, which the caller may know better than
    /// `√(1 − p²c²)`; 0 at a turning point) in the direction `dir` until `target` (`None`:
    /// until the ray turns). `None` when it turns before its target, or never turns when
    /// asked to. `crossings` receives `(∂X/∂p so far in this run, direction)` at each knot
    /// the run crosses.
    fn run<const FULL: bool>(
        &self,
        p: f64,
        y0: f64,
        s0: f64,
        dir: f64,
        target: Option<f64>,
        mut crossings: Option<&mut Vec<f64>>,
    ) -> Option<Run> {
        let inv = 1.0 / p;
        let mut sums = RaySums::default();
        let (mut y, mut c, mut s) = (y0, self.speed_at(y0), s0);
        let starts_turned = s0 == 0.0;
        let mut first = true;
        loop {
            let next = self.next_knot(y, dir);
            // The piece ends at the next knot, the target, or the turning point.
            let (mut y_end, mut c_end) = match next {
                Some(i) => (self.y[i], self.c[i]),
                None => (dir * f64::INFINITY, c),
            };
            let mut at_target = false;
            let mut at_wall = false;
            if let Some(w) = self.walls.ahead(y, dir)
                && (w - y_end) * dir <= 0.0
            {
                (y_end, c_end) = (w, self.speed_at(w));
                at_wall = true;
            }
            if let Some(t) = target
                && (t - y_end) * dir <= 0.0
            {
                (y_end, c_end) = (t, self.speed_at(t));
                at_target = true;
                at_wall = false;
            }
            // Does the ray turn in this piece? (speed reaches 1/p)
            if c_end >= inv && p > 0.0 && c_end != c {
                if target.is_some() && at_target && c_end == inv {
                    // Turns exactly at the target: not a ray of this branch.
                    return None;
                }
                if target.is_some() {
                    return None;
                }
                let slope = (c_end - c) / (y_end - y);
                let y_turn = y + (inv - c) / slope;
                let h = (y_turn - y).abs();
                let mut part = piece::<FULL>(p, h, c, inv, s, 0.0);
                // (A layer is monotone in speed: a run turns at most once in it.)
                part.x_p = -1.0 / (s * slope.abs() * p * p);
                sums.add(part);
                return Some(Run {
                    sums,
                    end: RunEnd::Turn(y_turn),
                });
            }
            if !y_end.is_finite() {
                // Uniform to infinity without a target: never turns.
                return None;
            }
            let s_end = sine(p, c_end);
            let h = (y_end - y).abs();
            let mut part = piece::<FULL>(p, h, c, c_end, s, s_end);
            part.x_p = if first && starts_turned {
                let slope = (c_end - c) / (y_end - y);
                -1.0 / (s_end * slope.abs() * p * p)
            } else {
                part.width / (s * s_end)
            };
            sums.add(part);
            if at_target {
                return Some(Run {
                    sums,
                    end: RunEnd::Target,
                });
            }
            if at_wall {
                if target.is_some() {
                    // The target lies beyond the wall.
                    return None;
                }
                return Some(Run {
                    sums,
                    end: RunEnd::Wall(y_end, s_end),
                });
            }
            if let Some(out) = crossings.as_deref_mut() {
                out.push(sums.x_p);
            }
            (y, c, s) = (y_end, c_end, s_end);
            first = false;
        }
    }

    /// The ray of branch `(first, turns)` with ray parameter `p ≥ 0` (launch sine `sa` at
    /// `ya`) to the height `yb`: its sums, `None` where the branch has no ray at this `p`.
    /// With `caustics`, also counts the caustics (the sign changes of `Q`).
    #[expect(
        clippy::too_many_arguments,
        reason = "a branch's ray parameter, ends, shape and what to record of it"
    )]
    fn branch<const FULL: bool>(
        &self,
        p: f64,
        sa: f64,
        [ya, yb]: [f64; 2],
        first: f64,
        turns: u32,
        caustics: Option<&mut u32>,
        mut events: Option<&mut Vec<Event>>,
    ) -> Option<RaySums> {
        let mut sums = RaySums::default();
        let mut crossings = Vec::new();
        let mut signs: Vec<f64> = Vec::new();
        let detail = caustics.is_some();
        // `sense`: the vertical direction in the picture unfolded at the walls (a
        // reflection turns the ray but not its tube).
        let (mut y, mut s, mut dir, mut sense) = (ya, sa, first, first);
        for k in 0..=turns {
            let target = (k == turns).then_some(yb);
            crossings.clear();
            let run = self.run::<FULL>(p, y, s, dir, target, detail.then_some(&mut crossings))?;
            if detail {
                for x in &crossings {
                    signs.push(sense * (sums.x_p + x));
                }
            }
            sums.add(run.sums);
            match run.end {
                RunEnd::Target => {}
                RunEnd::Turn(at) => {
                    (y, s) = (at, 0.0);
                    dir = -dir;
                    sense = -sense;
                    if let Some(out) = events.as_deref_mut() {
                        out.push(Event {
                            x: sums.x,
                            y: at,
                            wall: false,
                            sine: 0.0,
                            speed: 1.0 / p,
                        });
                    }
                }
                RunEnd::Wall(at, s_wall) => {
                    (y, s) = (at, s_wall);
                    dir = -dir;
                    if let Some(out) = events.as_deref_mut() {
                        out.push(Event {
                            x: sums.x,
                            y: at,
                            wall: true,
                            sine: s_wall,
                            speed: self.speed_at(at),
                        });
                    }
                }
            }
        }
        if let Some(count) = caustics {
            // The last direction is `sense`.
            signs.push(sense * sums.x_p);
            let mut previous = first;
            *count = 0;
            for q in signs {
                if q != 0.0 && q.signum() != previous {
                    *count += 1;
                    previous = q.signum();
                }
            }
        }
        Some(sums)
    }

    /// The ranges of the runs that make up every branch's ray at `p` (launch sine `sa`).
    fn parts(&self, p: f64, sa: f64, ya: f64, yb: f64) -> Parts {
        let x = |r: Option<Run>| r.map(|r| r.sums.x);
        let toward = if yb >= ya { 1.0 } else { -1.0 };
        let up = self.run::<false>(p, ya, sa, 1.0, None, None);
        let down = self.run::<false>(p, ya, sa, -1.0, None, None);
        // Each event's height, its sine there (0 at a turning point) and whether it is a
        // wall.
        let turn = |r: Option<Run>| match r?.end {
            RunEnd::Turn(at) => Some((at, 0.0, false)),
            RunEnd::Wall(at, s) => Some((at, s, true)),
            RunEnd::Target => None,
        };
        let (hi, lo) = (turn(up), turn(down));
        let (first_up, first_down) = (x(up), x(down));
        // Three runs, the rest from differences along the duct (the sampling's signs only:
        // the refinement evaluates each branch in full).
        let full = first_up.zip(first_down).map(|(u, d)| u + d);
        let from_hi =
            hi.and_then(|(hi, s, _)| x(self.run::<false>(p, hi, s, -1.0, Some(yb), None)));
        let from_lo = match (lo, full, from_hi) {
            (Some(_), Some(full), Some(h)) => Some(full - h),
            (Some(_), Some(_), None) => None,
            (Some((lo, s, _)), None, _) => x(self.run::<false>(p, lo, s, 1.0, Some(yb), None)),
            (None, ..) => None,
        };
        let direct = match (toward > 0.0, first_up, from_hi, first_down, from_lo) {
            (true, Some(u), Some(h), ..) if yb >= ya => Some(u - h).filter(|&d| d >= 0.0),
            (false, _, _, Some(d), Some(l)) => Some(d - l).filter(|&v| v >= 0.0),
            (true, Some(_), None, ..) | (false, _, _, Some(_), None) => None,
            _ => x(self.run::<false>(p, ya, sa, toward, Some(yb), None)),
        };
        Parts {
            direct,
            first_up,
            first_down,
            full,
            from_hi,
            from_lo,
            toward,
            hi_wall: hi.is_some_and(|h| h.2),
            lo_wall: lo.is_some_and(|l| l.2),
        }
    }

    /// [`arrivals`](Self::arrivals), remembered per thread for the last profile and pair
    /// asked (the default mode's solve, its amplitude and its written turns ask for the same
    /// pair in turn): keyed by the knots and the points themselves, so never stale.
    pub fn arrivals_cached(&self, a: Vec2, b: Vec2) -> ProfileArrivals {
        self.arrivals_within_cached(a, b, None)
    }

    /// [`arrivals_within`](Self::arrivals_within), remembered per thread as
    /// [`arrivals_cached`](Self::arrivals_cached) is (keyed by the bounds too).
    pub fn arrivals_within_cached(
        &self,
        a: Vec2,
        b: Vec2,
        bounds: Option<Bounds>,
    ) -> ProfileArrivals {
        type Key = (Profile, Vec2, Vec2, Option<Bounds>);
        thread_local! {
            static LAST: std::cell::RefCell<Option<(Key, ProfileArrivals)>> =
                const { std::cell::RefCell::new(None) };
        }
        LAST.with(|last| {
            if let Some(((p, la, lb, bd), found)) = &*last.borrow()
                && p == self
                && *la == a
                && *lb == b
                && *bd == bounds
            {
                return found.clone();
            }
            let found = self.arrivals_within(a, b, bounds);
            *last.borrow_mut() = Some(((self.clone(), a, b, bounds), found.clone()));
            found
        })
    }

    /// Every ray from `a` to `b` (up to [`MAX_TURNS`] turning points), by time: for each
    /// branch, the launch angle sampled at [`PROFILE_SAMPLES`] points (and where the ray turns at a
    /// knot or grazes a wall) and every sign change of
    /// `X − Δx` refined by bisection, each ray then evaluated in full ([`ProfileRay`]).
    #[cfg(test)]
    pub fn arrivals(&self, a: Vec2, b: Vec2) -> ProfileArrivals {
        self.arrivals_within(a, b, None)
    }

    /// The turning points and reflections of `ray` from `a` to `b`, in order (their `x`
    /// the distance from `a`, unsigned).
    pub fn events(&self, ray: &ProfileRay, a: Vec2, b: Vec2) -> Vec<Event> {
        let mut out = Vec::new();
        let events = ray.turns + ray.reflections;
        self.branch::<false>(
            ray.p.abs(),
            ray.sines[0],
            [a.y, b.y],
            ray.first,
            events,
            None,
            Some(&mut out),
        );
        out
    }

    /// [`arrivals`](Self::arrivals), or with `bounds` (a profile between walls) every ray
    /// with at most `bounds.reflections` reflections arriving by `bounds.time`, each branch
    /// (first direction and number of events, turning points and reflections together)
    /// searched as long as one of its sampled rays lies within the bounds (at most
    /// [`MAX_EVENTS`] events; `every_branch` says whether that cap was left untouched).
    pub fn arrivals_within(&self, a: Vec2, b: Vec2, bounds: Option<Bounds>) -> ProfileArrivals {
        let dx = b.x - a.x;
        let sign_x = if dx < 0.0 { -1.0 } else { 1.0 };
        let dx = dx.abs();
        let (ca, cb) = (self.speed_at(a.y), self.speed_at(b.y));
        let mut out = ProfileArrivals {
            rays: Vec::new(),
            every_branch: true,
        };
        let make = |p: f64, sa: f64, first: f64, turns: u32| -> Option<ProfileRay> {
            let mut caustics = 0;
            let mut events = Vec::new();
            let sums = self.branch::<true>(
                p,
                sa,
                [a.y, b.y],
                first,
                turns,
                Some(&mut caustics),
                Some(&mut events),
            )?;
            let reflections = events.iter().filter(|e| e.wall).count() as u32;
            let last = if turns & 1 == 0 { first } else { -first };
            Some(ProfileRay {
                p: sign_x * p,
                first,
                turns: turns - reflections,
                reflections,
                caustics,
                sines: [sa, sine(p, cb)],
                speeds: [ca, cb],
                last,
                sums,
            })
        };
        let within = |r: &ProfileRay| {
            bounds.is_none_or(|bd| r.reflections <= bd.reflections && r.sums.t <= bd.time)
        };
        if dx == 0.0 {
            // A vertical ray (p = 0) on the direct branch, or between walls each number of
            // reflections.
            let Some(bd) = bounds else {
                if b.y != a.y {
                    let first = if b.y > a.y { 1.0 } else { -1.0 };
                    out.rays.extend(make(0.0, 1.0, first, 0));
                }
                return out;
            };
            for events in 0..=MAX_EVENTS.min(bd.reflections) {
                let mut any = false;
                for first in [1.0, -1.0] {
                    if events == 0 && (b.y - a.y) * first <= 0.0 {
                        continue;
                    }
                    if let Some(ray) = make(0.0, 1.0, first, events)
                        && ray.turns == 0
                        && within(&ray)
                    {
                        any = true;
                        out.rays.push(ray);
                    }
                }
                if !any && events > 0 {
                    break;
                }
            }
            out.rays.sort_by(|x, y| x.sums.t.total_cmp(&y.sums.t));
            return out;
        }
        // Launch angles θ ∈ (0, π/2] at a: p = cos θ / c_a, s_a = sin θ.
        let thetas = self.launch_angles(ca);
        let (n, angle) = (thetas.len() - 1, |j: usize| thetas[j]);
        let at = |theta: f64| (theta.cos() / ca, theta.sin());
        let parts: Vec<Parts> = (0..=n)
            .map(|j| {
                let (p, sa) = at(angle(j));
                if j == 0 {
                    Parts::none()
                } else {
                    self.parts(p, sa, a.y, b.y)
                }
            })
            .collect();
        let least_cycle = parts
            .iter()
            .filter_map(|q| q.full)
            .fold(f64::INFINITY, f64::min);
        let most = if bounds.is_some() {
            MAX_EVENTS
        } else if least_cycle > 0.0 {
            ((dx / least_cycle).floor() + 2.0).min(MAX_TURNS as f64) as u32
        } else {
            MAX_TURNS
        };
        out.every_branch = most < MAX_TURNS;
        let slowest_time = 1.0 / (self.fastest() * self.fastest());
        for turns in 0..=most {
            if let Some(bd) = bounds
                && turns > 1
            {
                // A branch is searched while one of its samples could still be within the
                // bounds: its range not beyond the pair's, its reflections (with a margin
                // for a root past a sample where the ray turns instead) and a lower bound
                // of its time (∫ c ds / c_max²) within them. Each grows with the events.
                let open = (1..=n).any(|j| {
                    let (p, _) = at(angle(j));
                    let q = &parts[j];
                    [1.0, -1.0].into_iter().any(|first| {
                        q.range(first, turns).is_some_and(|x| {
                            x <= dx * (1.0 + 1e-6)
                                && q.reflections(first, turns) <= bd.reflections.saturating_add(2)
                                && 0.9 * (x / p) * slowest_time <= bd.time
                        })
                    })
                });
                if !open {
                    out.every_branch = true;
                    break;
                }
                if turns == most {
                    out.every_branch = false;
                }
            }
            for first in [1.0, -1.0] {
                let value = |q: &Parts| q.range(first, turns).map_or(f64::NAN, |x| x - dx);
                for j in 1..n {
                    let (v0, v1) = (value(&parts[j]), value(&parts[j + 1]));
                    if !(v0.is_finite() && v1.is_finite()) || (v0 > 0.0) == (v1 > 0.0) {
                        continue;
                    }
                    let bracket = [angle(j), angle(j + 1)];
                    let theta = self.refine(bracket, v0, [a.y, b.y], (first, turns), dx, ca);
                    let (p, sa) = at(theta);
                    // A sign change across a jump of X (where the turning point jumps past
                    // a local maximum of the speed) is no root: its miss stays.
                    if let Some(mut ray) = make(p, sa, first, turns)
                        && (ray.sums.x - dx).abs() <= 1e-7 * dx.max(1.0)
                        && within(&ray)
                    {
                        // The first-order correction of the time to the exact range
                        // (dT = p dX along the family of rays from a).
                        ray.sums.t += p * (dx - ray.sums.x);
                        out.rays.push(ray);
                    }
                }
            }
        }
        out.rays.sort_by(|x, y| x.sums.t.total_cmp(&y.sums.t));
        out
    }

    /// The launch angle of the root of `X − dx` on branch `(first, events)` inside the
    /// bracket `[lo, hi]` (`v_lo` its value at `lo`): Newton on the angle (dX/dθ = −X_p sin θ
    /// / c_a), bisecting where a step would leave the bracket.
    fn refine(
        &self,
        [mut lo, mut hi]: [f64; 2],
        mut v_lo: f64,
        ends: [f64; 2],
        (first, events): (f64, u32),
        dx: f64,
        ca: f64,
    ) -> f64 {
        let mut theta = 0.5 * (lo + hi);
        for _ in 0..100 {
            let (p, sa) = (theta.cos() / ca, theta.sin());
            let Some(sums) = self.branch::<false>(p, sa, ends, first, events, None, None) else {
                break;
            };
            let v = sums.x - dx;
            if v == 0.0 || hi - lo <= 4.0 * f64::EPSILON * hi {
                break;
            }
            if (v > 0.0) == (v_lo > 0.0) {
                (lo, v_lo) = (theta, v);
            } else {
                hi = theta;
            }
            let step = theta + v / (sums.x_p * sa / ca);
            let next = if step > lo && step < hi && step.is_finite() {
                step
            } else {
                0.5 * (lo + hi)
            };
            if next == theta {
                break;
            }
            theta = next;
        }
        theta
    }

    /// The launch angles [`arrivals_within`](Self::arrivals_within) samples from a point of
    /// speed `ca`: an even grid of [`PROFILE_SAMPLES`] steps over `[0, π/2]`, and the angles
    /// whose ray turns exactly at a knot or grazes a wall, where `X` has a kink (a pair of
    /// roots can sit in the dip beside one, closer together than the grid's step).
    fn launch_angles(&self, ca: f64) -> Vec<f64> {
        let mut thetas: Vec<f64> = (0..=PROFILE_SAMPLES)
            .map(|j| std::f64::consts::FRAC_PI_2 * j as f64 / PROFILE_SAMPLES as f64)
            .collect();
        let walls = [self.walls.top, self.walls.bottom];
        let wall_speeds = walls.into_iter().flatten().map(|w| self.speed_at(w));
        for c in self.c.iter().copied().chain(wall_speeds) {
            if c > ca {
                let theta = (ca / c).acos();
                if theta > 0.0 && theta < std::f64::consts::FRAC_PI_2 {
                    thetas.push(theta);
                }
            }
        }
        thetas.sort_by(f64::total_cmp);
        thetas.dedup();
        thetas
    }

    /// `∂T/∂cₖ` of every knot (in this profile's order, increasing `y`) of `ray` from height
    /// `ya` to `yb`, the ray's ends (and its walls) held: at fixed ends the time is
    /// stationary in the ray, so this is the partial of `τ = T − pX` at fixed `p`,
    /// `−∫ wₖ(y) |dy| / (c² s)` summed over the ray's pieces (`wₖ` the knot's hat function;
    /// the turning points move with `cₖ` but add nothing: `s = 0` there), one
    /// [`piece_knot_derivatives`] per piece.
    pub fn knot_derivatives(&self, ray: &ProfileRay, ya: f64, yb: f64) -> Vec<f64> {
        let n = self.y.len();
        let mut out = vec![0.0; n];
        let p = ray.p.abs();
        let (mut y, mut dir, mut s) = (ya, ray.first, ray.sines[0]);
        let events = ray.turns + ray.reflections;
        for k in 0..=events {
            let last = k == events;
            loop {
                let c = self.speed_at(y);
                let (mut y_end, mut c_end) = match self.next_knot(y, dir) {
                    Some(i) => (self.y[i], self.c[i]),
                    None => (dir * f64::INFINITY, c),
                };
                let mut end_here = false;
                let mut at_wall = false;
                if let Some(w) = self.walls.ahead(y, dir)
                    && (w - y_end) * dir <= 0.0
                {
                    (y_end, c_end) = (w, self.speed_at(w));
                    at_wall = true;
                }
                if last && (yb - y_end) * dir <= 0.0 {
                    (y_end, c_end) = (yb, self.speed_at(yb));
                    end_here = true;
                    at_wall = false;
                }
                let turning = !end_here && p > 0.0 && c_end >= 1.0 / p && c_end != c;
                let s_end = if turning {
                    let slope = (c_end - c) / (y_end - y);
                    y_end = y + (1.0 / p - c) / slope;
                    c_end = 1.0 / p;
                    0.0
                } else {
                    sine(p, c_end)
                };
                if !y_end.is_finite() {
                    // (Not a ray of this profile: uniform to infinity.)
                    return out;
                }
                self.add_piece_knot_derivatives(p, [y, y_end], [c, c_end], [s, s_end], &mut out);
                (y, s) = (y_end, s_end);
                if turning || at_wall {
                    dir = -dir;
                    break;
                }
                if end_here {
                    return out;
                }
            }
        }
        out
    }

    /// Adds the knot derivatives of one piece of a ray between heights `ys` (speeds `cs`,
    /// sines `ss`), all in one layer, to `out`: a layer's two knots share `−A` (`A =
    /// ∫ |dy| / (c² s)`) by the hat functions, through the piece's mean fraction of the layer
    /// and `R` ([`piece_knot_derivatives`]); a piece beyond the end knots (uniform) gives
    /// its `−A` to the end knot.
    fn add_piece_knot_derivatives(
        &self,
        p: f64,
        ys: [f64; 2],
        cs: [f64; 2],
        ss: [f64; 2],
        out: &mut [f64],
    ) {
        let h = (ys[1] - ys[0]).abs();
        if h == 0.0 {
            return;
        }
        let n = self.y.len();
        let sums = piece_knot_derivatives(p, h, cs, ss);
        let mid = 0.5 * (ys[0] + ys[1]);
        if mid <= self.y[0] {
            out[0] -= sums.a;
            return;
        }
        if mid >= self.y[n - 1] {
            out[n - 1] -= sums.a;
            return;
        }
        let i = self.y.partition_point(|&k| k <= mid).clamp(1, n - 1) - 1;
        let (y0, y1) = (self.y[i], self.y[i + 1]);
        let [t1, t2] = ys.map(|y| (y - y0) / (y1 - y0));
        let mean = 0.5 * (t1 + t2);
        let odd = sums.r * (t2 - t1);
        out[i + 1] -= odd + mean * sums.a;
        out[i] -= (1.0 - mean) * sums.a - odd;
    }

    /// Points along `ray` from `a`: each piece's ends and `per_piece − 1` points inside it
    /// (equal steps of the speed), for the obstruction test.
    pub fn curve(&self, ray: &ProfileRay, a: Vec2, b: Vec2, per_piece: usize) -> Vec<Vec2> {
        let per = per_piece.max(1);
        let mut out = vec![a];
        for run in self.pieces(ray, a, b) {
            let (p, y, y_end) = (run.p, run.start.y, run.end.y);
            let ([c, c_end], s) = (run.speeds, run.sines[0]);
            let turning = run.end_kind == PieceEnd::Turn;
            for j in 1..=per {
                let f = j as f64 / per as f64;
                // Equal steps of the speed (of the angle along an arc, to first order).
                let (yj, cj) = (y + (y_end - y) * f, c + (c_end - c) * f);
                let sj = if turning && j == per {
                    0.0
                } else {
                    sine(p, cj)
                };
                let part = piece::<true>(p, (yj - y).abs(), c, cj, s, sj);
                out.push(Vec2::new(run.start.x + run.sx * part.x, yj));
            }
        }
        out
    }

    /// The pieces of `ray` from `a` to `b`, in order: each inside one layer (a circular arc,
    /// or a straight line), ended by a knot, a turning point, a wall or `b`'s height on the
    /// last run. Each piece's end is the next one's start (its `x` the sum of the pieces'
    /// closed-form ranges: the last end lies on `b` to the ray's own refinement).
    pub fn pieces(&self, ray: &ProfileRay, a: Vec2, b: Vec2) -> Vec<RayPiece> {
        let p = ray.p.abs();
        let sx = if ray.p < 0.0 { -1.0 } else { 1.0 };
        let mut out = Vec::new();
        let (mut x, mut y, mut dir) = (a.x, a.y, ray.first);
        let mut s = ray.sines[0];
        let events = ray.turns + ray.reflections;
        for k in 0..=events {
            let last = k == events;
            loop {
                let c = self.speed_at(y);
                let next = self.next_knot(y, dir);
                let (mut y_end, mut c_end) = match next {
                    Some(i) => (self.y[i], self.c[i]),
                    None => (dir * 1e300, c),
                };
                let mut end_kind = PieceEnd::Knot;
                if let Some(w) = self.walls.ahead(y, dir)
                    && (w - y_end) * dir <= 0.0
                {
                    (y_end, c_end) = (w, self.speed_at(w));
                    end_kind = PieceEnd::Wall;
                }
                let yb = last.then_some(b.y);
                if let Some(t) = yb
                    && (t - y_end) * dir <= 0.0
                {
                    (y_end, c_end) = (t, self.speed_at(t));
                    end_kind = PieceEnd::Target;
                }
                if end_kind != PieceEnd::Target && c_end >= 1.0 / p && p > 0.0 && c_end != c {
                    let slope = (c_end - c) / (y_end - y);
                    y_end = y + (1.0 / p - c) / slope;
                    c_end = 1.0 / p;
                    end_kind = PieceEnd::Turn;
                }
                if y_end.abs() >= 1e300 {
                    // Into the uniform speed beyond the end knots without a turn: no ray
                    // of `ray`'s branch (never for a ray the profile found).
                    return out;
                }
                // (At a turning point the sine is 0, not `sine(p, 1/p)`'s rounding: that
                // moved the range after each turn by ~1e-8 of the arc's radius.)
                let s_end = if end_kind == PieceEnd::Turn {
                    0.0
                } else {
                    sine(p, c_end)
                };
                let part = piece::<true>(p, (y_end - y).abs(), c, c_end, s, s_end);
                let start = Vec2::new(x, y);
                x += sx * part.x;
                y = y_end;
                out.push(RayPiece {
                    start,
                    end: Vec2::new(x, y),
                    speeds: [c, c_end],
                    sines: [s, s_end],
                    p,
                    sx,
                    end_kind,
                });
                s = s_end;
                match end_kind {
                    PieceEnd::Turn | PieceEnd::Wall => {
                        dir = -dir;
                        break;
                    }
                    PieceEnd::Target => return out,
                    PieceEnd::Knot => {}
                }
            }
        }
        out
    }
}

/// What ends a [`RayPiece`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PieceEnd {
    /// A knot, crossed.
    Knot,
    /// A turning point.
    Turn,
    /// A wall, where the ray reflects.
    Wall,
    /// The end's height on the ray's last run: the ray's end.
    Target,
}

/// One piece of a ray inside one layer of a profile ([`Profile::pieces`]): a circular arc
/// (a straight line in a uniform layer or along a vertical ray), monotone in height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RayPiece {
    /// Where it starts and where it ends.
    pub start: Vec2,
    pub end: Vec2,
    /// The speeds at its ends.
    pub speeds: [f64; 2],
    /// The sines of the ray's angle with the horizontal at its ends (0 at a turning point).
    pub sines: [f64; 2],
    /// The horizontal slowness (≥ 0) and the ray's horizontal direction (±1).
    pub p: f64,
    pub sx: f64,
    /// What ends it.
    pub end_kind: PieceEnd,
}

impl RayPiece {
    /// Its arc length (the closed form of the module's table).
    pub fn arc_length(&self) -> f64 {
        let ([c1, c2], [s1, s2]) = (self.speeds, self.sines);
        let h = (self.end.y - self.start.y).abs();
        piece::<true>(self.p, h, c1, c2, s1, s2).arc
    }

    /// The point of the piece at the fraction `f` of its arc length from its start (its
    /// ends at 0 and 1): the ray's angle with the horizontal `φ` (`cos φ = p c`) turns
    /// evenly along an arc, so the point's height is where `cos φ` is the one at
    /// `φ₁ + f (φ₂ − φ₁)`, and its `x` the closed-form range from the start to that height:
    /// the point lies on the ray whatever the rounding of its height.
    pub fn at(&self, f: f64) -> Vec2 {
        if f <= 0.0 || f >= 1.0 {
            return self.at_angles(f, [0.0; 2]);
        }
        self.at_angles(f, self.angles())
    }

    /// The ray's angles with the horizontal at its ends (`φ₁`, `φ₂` of [`RayPiece::at`]).
    pub fn angles(&self) -> [f64; 2] {
        let ([c1, c2], [s1, s2], p) = (self.speeds, self.sines, self.p);
        [s1.atan2(p * c1), s2.atan2(p * c2)]
    }

    /// [`RayPiece::at`] given the piece's [`RayPiece::angles`] `[phi1, phi2]` (the same
    /// point, for many fractions of one piece without their arctangents each time).
    pub fn at_angles(&self, f: f64, [phi1, phi2]: [f64; 2]) -> Vec2 {
        if f <= 0.0 {
            return self.start;
        }
        if f >= 1.0 {
            return self.end;
        }
        let ([c1, c2], [s1, s2], p) = (self.speeds, self.sines, self.p);
        let turn = phi2 - phi1;
        // The fraction of the height: (cos φ − cos φ₁) / (cos φ₂ − cos φ₁), in products of
        // sines (no cancellation); a straight piece (a uniform layer, a vertical ray, or one
        // that barely turns) in equal steps of height.
        let t = if turn.abs() < 1e-9 {
            f
        } else {
            let phi = phi1 + f * turn;
            ((0.5 * (phi + phi1)).sin() * (0.5 * f * turn).sin())
                / ((0.5 * (phi2 + phi1)).sin() * (0.5 * turn).sin())
        };
        let t = t.clamp(0.0, 1.0);
        let y = self.start.y + (self.end.y - self.start.y) * t;
        let c = c1 + (c2 - c1) * t;
        let s = if t == 1.0 { s2 } else { sine(p, c) };
        let part = piece::<false>(p, (y - self.start.y).abs(), c1, c, s1, s);
        Vec2::new(self.start.x + self.sx * part.x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::leg::{Leg, LegModel, Linear};

    /// The time and range of the ray of parameter `p` from `y1` to `y2` (monotone, no turn)
    /// by Simpson's rule on `dy / (c s)` and `p c dy / s`, the reference: `n` intervals.
    fn quadrature(profile: &Profile, p: f64, y1: f64, y2: f64, n: usize) -> (f64, f64) {
        let h = (y2 - y1) / n as f64;
        let (mut t, mut x) = (0.0, 0.0);
        for i in 0..=n {
            let y = y1 + h * i as f64;
            let c = profile.speed_at(y);
            let s = (1.0 - p * p * c * c).sqrt();
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            t += w / (c * s);
            x += w * p * c / s;
        }
        (t * h.abs() / 3.0, x * h.abs() / 3.0)
    }

    /// One layer's piece against Simpson quadrature, across knots.
    #[test]
    fn pieces_match_quadrature() {
        let profile = Profile::new(&[[0.0, 1500.0], [-300.0, 1480.0], [-1000.0, 1520.0]]);
        for p in [0.0, 1e-4, 5e-4, 6.5e-4] {
            let s = sine(p, profile.speed_at(-50.0));
            let run = profile
                .run::<true>(p, -50.0, s, -1.0, Some(-900.0), None)
                .unwrap();
            // Simpson per layer (the speed's kink at the knot).
            let (t1, x1) = quadrature(&profile, p, -50.0, -300.0, 20000);
            let (t2, x2) = quadrature(&profile, p, -300.0, -900.0, 20000);
            assert!((run.sums.t - (t1 + t2)).abs() < 1e-12 * run.sums.t, "{p}");
            assert!(
                (run.sums.x - (x1 + x2)).abs() < 1e-9 * (1.0 + run.sums.x),
                "{p}"
            );
        }
    }

    /// A piece's `A = ∫ |dy| / (c² s)` and `R = ∫ (u − ½) |dy| / (c² s)` (`u` the fraction
    /// from its first end; `R = (T − c̄A)/(c₂ − c₁)` as a closed form) and its time against
    /// Simpson's rule over the piece, for steep, gentle, near-vertical and near-horizontal
    /// rays and layers down to a speed change of 1e-9 (no 1/g blow-up: the errors stay
    /// below 1e-13 of `A`).
    #[test]
    fn piece_knot_sums_match_quadrature() {
        let simpson = |f: &dyn Fn(f64) -> f64, n: usize| {
            let mut sum = 0.0;
            for i in 0..=n {
                let u = i as f64 / n as f64;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                sum += w * f(u);
            }
            sum / (3.0 * n as f64)
        };
        for (p, h, c1, c2) in [
            (6.0e-4, 300.0, 1500.0, 1480.0),
            (6.0e-4, 300.0, 1480.0, 1500.0),
            (0.0, 100.0, 1500.0, 1600.0),
            (1e-5, 2000.0, 1520.0, 1490.0),
            (6.6e-4, 50.0, 1500.0, 1500.0 + 1e-9),
            (3e-4, 1000.0, 1500.0, 1500.0 - 1e-6),
            (6.6e-4, 80.0, 1505.0, 1510.0),
        ] {
            let (s1, s2) = (sine(p, c1), sine(p, c2));
            let got = piece_knot_derivatives(p, h, [c1, c2], [s1, s2]);
            let c = |u: f64| c1 + u * (c2 - c1);
            let f = |u: f64| h / (c(u) * c(u) * sine(p, c(u)));
            let a = simpson(&f, 20000);
            let r = simpson(&|u| (u - 0.5) * f(u), 20000);
            let t = simpson(&|u| c(u) * f(u), 20000);
            let what = format!("{p} {h} {c1} {c2}: {got:?} {a} {r} {t}");
            assert!((got.a - a).abs() < 1e-13 * a, "{what}");
            assert!((got.r - r).abs() < 1e-13 * a, "{what}");
            assert!((got.t - t).abs() < 1e-13 * t, "{what}");
            let full = piece::<true>(p, h, c1, c2, s1, s2);
            assert!((got.t - full.t).abs() < 1e-14 * t, "{what}");
        }
        // A uniform layer: `R` is zero, `A` is `h / (c² s)`.
        let got = piece_knot_derivatives(5e-4, 10.0, [1500.0; 2], [sine(5e-4, 1500.0); 2]);
        assert_eq!(got.r, 0.0);
        let a = 10.0 / (1500.0 * 1500.0 * sine(5e-4, 1500.0));
        assert!((got.a - a).abs() < 1e-15 * a);
    }

    /// `∂X/∂p` of a branch with a turn against a central difference.
    #[test]
    fn range_derivative_matches_differences() {
        let profile = Profile::new(&[[0.0, 1500.0], [-300.0, 1480.0], [-1000.0, 1520.0]]);
        let (ya, yb) = (-100.0, -200.0);
        let ca = profile.speed_at(ya);
        for theta in [0.05f64, 0.1, 0.15] {
            let p = theta.cos() / ca;
            let x = |p: f64| {
                let s = sine(p, ca);
                profile
                    .branch::<true>(p, s, [ya, yb], -1.0, 1, None, None)
                    .unwrap()
            };
            let h = 1e-10;
            let fd = (x(p + h).x - x(p - h).x) / (2.0 * h);
            let exact = x(p).x_p;
            assert!(
                (fd - exact).abs() < 1e-5 * exact.abs(),
                "{theta}: {fd} {exact}"
            );
        }
    }

    /// A one-layer profile (and beyond its knots, where the ray does not go) is a `gradient`
    /// medium: the one arc between two points, its time to 1e-13.
    #[test]
    fn one_layer_is_the_gradient_medium() {
        let profile = Profile::new(&[[0.0, 1500.0], [-5000.0, 1585.0]]);
        let linear = Linear {
            speed: 1500.0,
            gradient: Vec2::new(0.0, -0.017),
            least_speed: 1500.0,
        };
        for (a, b) in [
            (Vec2::new(0.0, -100.0), Vec2::new(5000.0, -300.0)),
            (Vec2::new(0.0, -100.0), Vec2::new(-3000.0, -2000.0)),
            (Vec2::new(0.0, -2000.0), Vec2::new(20000.0, -2000.0)),
            (Vec2::new(0.0, -2000.0), Vec2::new(0.0, -100.0)),
        ] {
            let found = profile.arrivals(a, b);
            assert_eq!(found.rays.len(), 1, "{a:?} {b:?}");
            let ray = found.rays[0];
            let arc = linear.leg(a, b);
            let rel = (ray.sums.t - arc.time()).abs() / arc.time();
            assert!(rel < 1e-13, "{a:?} {b:?}: {rel:e}");
            let d = ray.direction_at_start() - arc.direction_at_start();
            assert!(d.length() < 1e-9, "{d:?}");
        }
    }

    /// The design note's caustic example: a uniform layer (200 m, 1500 m/s) over
    /// c = 1500 + 0.1 (depth − 200), surface to surface over 10 km: two rays of the branch
    /// (down, one turn), 6.672526446116 s past the caustic and 6.628258089353 s before it.
    #[test]
    fn caustic_example() {
        let profile = Profile::new(&[[0.0, 1500.0], [-200.0, 1500.0], [-5200.0, 2000.0]]);
        let found = profile.arrivals(Vec2::new(0.0, 0.0), Vec2::new(10000.0, 0.0));
        let times: Vec<f64> = found.rays.iter().map(|r| r.sums.t).collect();
        assert_eq!(times.len(), 2, "{times:?}");
        assert!((times[0] - 6.628258089353).abs() < 1e-11, "{times:?}");
        assert!((times[1] - 6.672526446116).abs() < 1e-11, "{times:?}");
        let caustics: Vec<u32> = found.rays.iter().map(|r| r.caustics).collect();
        assert_eq!(caustics, [0, 1]);
        assert!(found.rays.iter().all(|r| r.turns == 1 && r.first < 0.0));
        // The horizontal slowness is conserved: cos θ / c at the end is p.
        for r in &found.rays {
            let end = r.direction_at_end();
            assert!((end.x / r.speeds[1] - r.p).abs() < 1e-15 * r.p && end.y > 0.0);
        }
    }

    /// An isovelocity profile between two walls: exactly the image method's arrivals, each
    /// with its reflections, times to 1e-12, the reflection points on the walls.
    #[test]
    fn isovelocity_between_walls_is_the_image_method() {
        let (top, bottom, c) = (0.0, -100.0, 1500.0);
        let profile = Profile::new(&[[top, c], [bottom, c]]).with_walls(Walls {
            top: Some(top),
            bottom: Some(bottom),
        });
        for (a, b) in [
            (Vec2::new(0.0, -30.0), Vec2::new(1000.0, -70.0)),
            (Vec2::new(0.0, -50.0), Vec2::new(-400.0, -50.5)),
            (Vec2::new(10.0, -1.0), Vec2::new(5010.0, -99.0)),
            (Vec2::new(0.0, -20.0), Vec2::new(0.0, -60.0)),
        ] {
            let k = 7u32;
            let found = profile.arrivals_within(
                a,
                b,
                Some(Bounds {
                    reflections: k,
                    time: f64::INFINITY,
                }),
            );
            // Images of the receiver: 2m·H ± y_b (H = top − bottom), reflections counted
            // by the walls the unfolded path crosses.
            let h = top - bottom;
            let mut images = Vec::new();
            for m in -10i32..=10 {
                for sign in [1.0, -1.0] {
                    let y = 2.0 * f64::from(m) * h + sign * (b.y - bottom) + bottom;
                    let (lo, hi) = if y > a.y { (a.y, y) } else { (y, a.y) };
                    // Walls at bottom + j H, j integer, strictly between.
                    let count = (((hi - bottom) / h).ceil() - ((lo - bottom) / h).floor() - 1.0)
                        .max(0.0) as u32;
                    if count <= k {
                        images.push(((b.x - a.x).hypot(y - a.y) / c, count));
                    }
                }
            }
            images.sort_by(|x, y| x.0.total_cmp(&y.0));
            assert_eq!(found.rays.len(), images.len(), "{a:?} {b:?}");
            for (r, (t, n)) in found.rays.iter().zip(&images) {
                assert!(
                    (r.sums.t - t).abs() <= 1e-12 * t,
                    "{a:?} {b:?}: {} {t}",
                    r.sums.t
                );
                assert_eq!(r.reflections, *n);
                assert_eq!((r.turns, r.caustics), (0, 0));
                for e in profile.events(r, a, b) {
                    assert!(e.wall && (e.y == top || e.y == bottom));
                }
            }
        }
    }

    /// Random profiles and points, ends on knots and beyond the end knots, vertical and
    /// same-height pairs included: no panic, and every ray listed lands on its receiver
    /// (its range within 1e-6 of the pair's) with a finite, positive time at least the
    /// straight line's at the greatest speed.
    #[test]
    fn random_profiles_give_rays_that_land() {
        let mut rng = crate::demo::SplitMix64(0x40);
        let mut rays = 0;
        for case in 0..400 {
            let n = 2 + (rng.next_f64() * 6.0) as usize;
            let mut y = 0.0;
            let knots: Vec<[f64; 2]> = (0..n)
                .map(|_| {
                    let k = [y, 1400.0 + 200.0 * rng.next_f64()];
                    y -= 50.0 + 1000.0 * rng.next_f64();
                    k
                })
                .collect();
            let profile = Profile::new(&knots);
            let depth = -y;
            let mut point = |j: usize| {
                let y = match (case + j) % 4 {
                    0 => knots[(rng.next_f64() * n as f64) as usize % n][0],
                    1 => 200.0 - (depth + 400.0) * rng.next_f64(),
                    _ => -depth * rng.next_f64(),
                };
                Vec2::new(20000.0 * rng.next_f64() - 10000.0, y)
            };
            let a = point(0);
            let mut b = point(1);
            if case % 10 == 3 {
                b.x = a.x;
            }
            if case % 10 == 7 {
                b.y = a.y;
            }
            let fastest = knots.iter().map(|k| k[1]).fold(0.0, f64::max);
            for r in profile.arrivals(a, b).rays {
                rays += 1;
                assert!(
                    (r.sums.x - (b.x - a.x).abs()).abs() < 1e-6,
                    "{a:?} {b:?} {r:?}"
                );
                assert!(
                    r.sums.t.is_finite() && r.sums.t >= (b - a).length() / fastest * (1.0 - 1e-12)
                );
            }
        }
        assert!(rays > 20, "{rays}");
    }
}
