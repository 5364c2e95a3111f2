//! The leg model: what a ray does between two consecutive points of its path, in one medium.
//!
//! A path is a chain of legs, each joining two points (the source, interaction points, the
//! receiver) inside one medium. Everything the solver, the amplitude and the searches need of
//! a leg is a function of its two end points `a`, `b` and its medium, and comes from here:
//!
//! | quantity | [`Leg`] / [`LegModel`] | uniform medium ([`Uniform`], [`StraightLeg`]) |
//! | --- | --- | --- |
//! | time `T(a, b)` | [`Leg::time`] | `w ℓ` |
//! | gradient: `∇_b T`, `−∇_a T` (slowness vectors at the ends) | [`Leg::arrival`], [`Leg::departure`] | `w u`, `w u` |
//! | unit directions at the ends | [`Leg::direction_at_end`], [`Leg::direction_at_start`] | `u`, `u` |
//! | Hessian blocks along tangents: `tᵀ ∂²T/∂b² t`, `tᵀ ∂²T/∂a² t`, `t_aᵀ ∂²T/∂a∂b t_b` | [`Leg::end_block`], [`Leg::start_block`], [`Leg::coupling`] | `w (u × t)² / ℓ`, the same, `−w (u × t_a)(u × t_b) / ℓ` |
//! | tube width out of the plane, `w₀ ∫ c ds` | [`Leg::out_of_plane_width`] | `ℓ w₀ / w` |
//! | validity (a leg exists between the ends) | [`LegModel::valid_leg`] | `ℓ` positive and finite |
//! | lower bound on `T` between two boxes | [`LegModel::least_time`], [`LegModel::least_time_to`] | `w` × the boxes' distance |
//! | the slowness at the ends from the chord's direction (bounds) | [`LegModel::along_at_ends`], [`LegModel::greatest_slowness`] | `w u`, `w` |
//!
//! (`ℓ = |b − a|`, `u = (b − a)/ℓ`, `w` the slowness.) The path's time is the sum of its legs'
//! times; its residual at point `i` is `(arrival of leg i − departure of leg i + 1) · tᵢ`; its
//! tridiagonal Hessian has `Hᵢᵢ = end_block(leg i, tᵢ) + start_block(leg i + 1, tᵢ)` and
//! `Hᵢ,ᵢ₊₁ = coupling(leg i + 1, tᵢ, tᵢ₊₁)` (`problem.rs`). Every leg depends on its two ends
//! only, so the Hessian stays tridiagonal for any leg model.
//!
//! The uniform medium, whose legs are straight, is the one model so far. A medium with a
//! speed gradient (circular arcs in a medium whose speed is linear in position;
//! `design/curved-rays.md` of the team's notes) is a second [`LegModel`]: its legs' times
//! `(2/g) asinh(g ℓ / (2 √(c_a c_b)))` and their derivatives in closed form, its validity the
//! test that the arc stays inside its medium, its bound the time at the medium's greatest
//! speed. Each caller's formulas are written with [`Leg`]'s methods, so the caller stays as it
//! is; the calls are static (the model is a type, every method inlined), so the uniform
//! medium's arithmetic is the code's before the seam, operation for operation.
//!
//! Two places are the uniform medium's own and say so: the image method of the beam tree
//! (`trace/mirrors.rs`: straight legs in one medium, [`Uniform::time_along`],
//! [`Uniform::reach`]) and the one-interaction closed form of the amplitude
//! (`amplitude/ray.rs`, [`Uniform::leg_across`]); a medium with a gradient takes the general
//! forms there (the walk over sequences; the amplitude's sweep).

use crate::geom::{Aabb, Point, Vec2};

mod arc_crossing;
pub(crate) mod profile;

pub(crate) use arc_crossing::{ArcFrame, EndsOn};

/// One leg of a ray in one medium, evaluated from its two end points (see the module).
pub(crate) trait Leg: Copy {
    /// The travel time along the leg.
    fn time(&self) -> f64;
    /// `∇_b T`: the slowness vector with which the leg arrives at its end `b`.
    fn arrival(&self) -> Vec2;
    /// `−∇_a T`: the slowness vector with which the leg leaves its start `a`.
    fn departure(&self) -> Vec2;
    /// The unit direction of the leg at its end.
    fn direction_at_end(&self) -> Vec2;
    /// The unit direction of the leg at its start.
    fn direction_at_start(&self) -> Vec2;
    /// `tᵀ (∂²T/∂b²) t`: the Hessian block of the end along the unit vector `t`.
    fn end_block(&self, t: Vec2) -> f64;
    /// `tᵀ (∂²T/∂a²) t`: the Hessian block of the start along the unit vector `t`.
    fn start_block(&self, t: Vec2) -> f64;
    /// `t_aᵀ (∂²T/∂a∂b) t_b`: the block that couples the start (along `ta`) and the end
    /// (along `tb`).
    fn coupling(&self, ta: Vec2, tb: Vec2) -> f64;
    /// `w₀ ∫ c ds` along the leg, `w₀` the slowness at the source: what the leg adds to the
    /// out-of-plane width of a point source's tube (the out-of-plane slowness is conserved).
    fn out_of_plane_width(&self, source_slowness: f64) -> f64;
}

/// A leg read in place (the solver's evaluation keeps its legs and reads each several
/// times): the same numbers, without a copy.
impl<L: Leg> Leg for &L {
    #[inline(always)]
    fn time(&self) -> f64 {
        (**self).time()
    }
    #[inline(always)]
    fn arrival(&self) -> Vec2 {
        (**self).arrival()
    }
    #[inline(always)]
    fn departure(&self) -> Vec2 {
        (**self).departure()
    }
    #[inline(always)]
    fn direction_at_end(&self) -> Vec2 {
        (**self).direction_at_end()
    }
    #[inline(always)]
    fn direction_at_start(&self) -> Vec2 {
        (**self).direction_at_start()
    }
    #[inline(always)]
    fn end_block(&self, t: Vec2) -> f64 {
        (**self).end_block(t)
    }
    #[inline(always)]
    fn start_block(&self, t: Vec2) -> f64 {
        (**self).start_block(t)
    }
    #[inline(always)]
    fn coupling(&self, ta: Vec2, tb: Vec2) -> f64 {
        (**self).coupling(ta, tb)
    }
    #[inline(always)]
    fn out_of_plane_width(&self, source_slowness: f64) -> f64 {
        (**self).out_of_plane_width(source_slowness)
    }
}

/// A medium's model of the legs through it (see the module).
pub(crate) trait LegModel: Copy {
    /// An evaluated leg.
    type Leg: Leg;
    /// The leg from `a` to `b` (positions relative to one origin, the same for every leg of a
    /// path), evaluated whatever the ends: a leg of zero length has zero direction and zero
    /// inverse length (the solver judges vanished legs by their length).
    fn leg(self, a: Vec2, b: Vec2) -> Self::Leg;
    /// The leg from `a` to `b` if one exists between them in this medium (`None`: no leg, for
    /// a straight leg one of zero or non-finite length).
    fn valid_leg(self, a: Point, b: Point) -> Option<Self::Leg>;
    /// A lower bound on the time of every leg from a point of `from` to a point of `to`.
    fn least_time(self, from: Aabb, to: Aabb) -> f64;
    /// A lower bound on the time of every leg from a point of `from` to the point `to`.
    fn least_time_to(self, from: Aabb, to: Point) -> f64;
    /// The range of `p · t` (`p` the slowness vector at either end of a leg) over the legs
    /// whose chords' unit directions `u` have `u · t` in `chord_along` (the complete search's
    /// residual bounds).
    fn along_at_ends(self, chord_along: [f64; 2]) -> [f64; 2];
    /// The greatest size of the slowness vector at a leg's ends.
    fn greatest_slowness(self) -> f64;
}

/// A uniform medium: one slowness, straight legs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Uniform {
    /// The slowness (1 / speed).
    pub slowness: f64,
}

/// A straight leg in a [`Uniform`] medium.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct StraightLeg {
    /// The medium's slowness.
    pub slowness: f64,
    /// The unit direction from the start to the end (zero for a leg of zero length).
    pub u: Vec2,
    /// The length.
    pub len: f64,
    /// `1 / len` (zero for a leg of zero length).
    pub inv_len: f64,
}

impl Uniform {
    /// The uniform medium of slowness `slowness`.
    #[inline(always)]
    pub fn new(slowness: f64) -> Uniform {
        Uniform { slowness }
    }

    /// The straight leg along `d` (its end minus its start), its length by [`length`] where
    /// the squares are plain, else `hypot` (the solver's general evaluation).
    #[inline(always)]
    pub fn leg_along(self, d: Vec2) -> StraightLeg {
        let l = length(d);
        let il = inverse(l);
        StraightLeg {
            slowness: self.slowness,
            // `inverse` gives 0 for a zero-length leg, whose `d` is zero: `u` is then zero too.
            u: d * il,
            len: l,
            inv_len: il,
        }
    }

    /// The straight leg along `d` with a plain square root and reciprocal, and whether its
    /// squared length was a normal number below 1e300 (otherwise the leg's numbers are not to
    /// be used: the caller falls back to [`Uniform::leg_along`]). The solver's fast passes.
    #[inline(always)]
    pub fn leg_plain(self, d: Vec2) -> (StraightLeg, bool) {
        let l2 = d.x * d.x + d.y * d.y;
        let plain = (f64::MIN_POSITIVE..1e300).contains(&l2);
        let l = l2.sqrt();
        let il = 1.0 / l;
        let leg = StraightLeg {
            slowness: self.slowness,
            u: d * il,
            len: l,
            inv_len: il,
        };
        (leg, plain)
    }

    /// The leg `d` against the unit normal `n` of the segment it meets (`None` for a leg of
    /// zero or non-finite length): the uniform medium's one-interaction form of the amplitude,
    /// whose cosines with the normal are the legs' own (straight legs). The cosine's square is
    /// `(d · n)² / |d|²`: its division runs beside the square root, not after it.
    #[inline(always)]
    pub fn leg_across(d: Vec2, n: Vec2) -> Option<LegAcross> {
        let l2 = d.x * d.x + d.y * d.y;
        let across = d.dot(n);
        if (f64::MIN_POSITIVE..1e300).contains(&l2) {
            let cos_squared = across * across / l2;
            Some(LegAcross {
                length: l2.sqrt(),
                across,
                cos_squared,
            })
        } else {
            leg_across_unusual(d, across)
        }
    }

    /// The time of a straight path of length `length` through the medium (the image method's
    /// paths: every leg in this one medium).
    #[inline(always)]
    pub fn time_along(self, length: f64) -> f64 {
        self.slowness * length
    }

    /// The length of the longest straight path within the time `time` (infinite for no bound).
    #[inline]
    pub fn reach(self, time: f64) -> f64 {
        time / self.slowness
    }

    /// [`Leg::out_of_plane_width`] of a leg of length `len` in a uniform medium of slowness
    /// `w`, for a source of slowness `w0`: `ℓ w₀ / w`.
    #[inline(always)]
    fn out_of_plane(len: f64, w0: f64, w: f64) -> f64 {
        len * (w0 / w)
    }
}

impl LegModel for Uniform {
    type Leg = StraightLeg;

    #[inline(always)]
    fn leg(self, a: Vec2, b: Vec2) -> StraightLeg {
        self.leg_along(b - a)
    }

    #[inline(always)]
    fn valid_leg(self, a: Point, b: Point) -> Option<StraightLeg> {
        let d = b - a;
        let l2 = d.x * d.x + d.y * d.y;
        // The common leg without `hypot`: a squared length that neither underflows nor
        // overflows.
        let l = if (f64::MIN_POSITIVE..1e300).contains(&l2) {
            l2.sqrt()
        } else {
            length_unusual(d)?
        };
        let inv = 1.0 / l;
        Some(StraightLeg {
            slowness: self.slowness,
            u: d * inv,
            len: l,
            inv_len: inv,
        })
    }

    #[inline]
    fn least_time(self, from: Aabb, to: Aabb) -> f64 {
        self.slowness * box_gap(from, to)
    }

    #[inline]
    fn least_time_to(self, from: Aabb, to: Point) -> f64 {
        self.slowness * from.distance_sq(to).sqrt()
    }

    #[inline]
    fn along_at_ends(self, [lo, hi]: [f64; 2]) -> [f64; 2] {
        [self.slowness * lo, self.slowness * hi]
    }

    #[inline]
    fn greatest_slowness(self) -> f64 {
        self.slowness
    }
}

impl Leg for StraightLeg {
    #[inline(always)]
    fn time(&self) -> f64 {
        self.slowness * self.len
    }
    #[inline(always)]
    fn arrival(&self) -> Vec2 {
        self.u * self.slowness
    }
    #[inline(always)]
    fn departure(&self) -> Vec2 {
        self.u * self.slowness
    }
    #[inline(always)]
    fn direction_at_end(&self) -> Vec2 {
        self.u
    }
    #[inline(always)]
    fn direction_at_start(&self) -> Vec2 {
        self.u
    }
    // The blocks take `u · t⊥` (= −(u × t) exactly, rounding being symmetric: the same
    // bits once squared or multiplied in pairs), the form a caller that has the normal
    // `t⊥` shares with its cosines.
    #[inline(always)]
    fn end_block(&self, t: Vec2) -> f64 {
        let c = self.u.dot(t.perp());
        self.slowness * c * c * self.inv_len
    }
    #[inline(always)]
    fn start_block(&self, t: Vec2) -> f64 {
        let c = self.u.dot(t.perp());
        self.slowness * c * c * self.inv_len
    }
    #[inline(always)]
    fn coupling(&self, ta: Vec2, tb: Vec2) -> f64 {
        -self.slowness * self.u.dot(ta.perp()) * self.u.dot(tb.perp()) * self.inv_len
    }
    #[inline(always)]
    fn out_of_plane_width(&self, source_slowness: f64) -> f64 {
        Uniform::out_of_plane(self.len, source_slowness, self.slowness)
    }
}

impl StraightLeg {
    /// [`Leg::coupling`] written as `−t_b · (t_a − u (u · t_a)) w / ℓ` (the projection of `t_a`
    /// across the leg): the same number to round-off, in the order of the amplitude's sweep,
    /// which keeps it so that amplitudes stay as they were bit for bit.
    #[inline(always)]
    pub fn coupling_projected(&self, ta: Vec2, tb: Vec2) -> f64 {
        let u = self.u;
        -tb.dot(ta - u * u.dot(ta)) * (self.slowness * self.inv_len)
    }
}

/// A straight leg against the unit normal of a segment ([`Uniform::leg_across`]): its length,
/// its component along the normal, and the square of its cosine with the normal.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LegAcross {
    /// The leg's length.
    pub length: f64,
    /// `d · n`.
    pub across: f64,
    /// `(d · n)² / |d|²`.
    pub cos_squared: f64,
}

/// [`Uniform::leg_across`] for a leg of zero, tiny or huge length, out of line.
#[cold]
#[inline(never)]
fn leg_across_unusual(d: Vec2, across: f64) -> Option<LegAcross> {
    let length = length_unusual(d)?;
    let cos = across / length;
    Some(LegAcross {
        length,
        across,
        cos_squared: cos * cos,
    })
}

/// The length of a leg of zero, tiny or huge length (`None` for zero or non-finite), out of
/// line.
#[cold]
#[inline(never)]
fn length_unusual(d: Vec2) -> Option<f64> {
    let l = d.length();
    (l > 0.0 && l.is_finite()).then_some(l)
}

/// `|d|`: a plain square root where the squares neither overflow nor lose precision to
/// underflow, `hypot` otherwise.
#[inline(always)]
pub(crate) fn length(d: Vec2) -> f64 {
    let l2 = d.x * d.x + d.y * d.y;
    // (`is_normal` for a sum of squares, as two compares.)
    if (f64::MIN_POSITIVE..1e300).contains(&l2) {
        l2.sqrt()
    } else {
        d.length()
    }
}

/// `1/ℓ`, with a zero-length leg contributing nothing (its direction is undefined).
#[inline(always)]
fn inverse(l: f64) -> f64 {
    if l > 0.0 { 1.0 / l } else { 0.0 }
}

/// Distance between two boxes (0 where they overlap).
#[inline]
fn box_gap(a: Aabb, b: Aabb) -> f64 {
    let dx = (a.min.x - b.max.x).max(b.min.x - a.max.x).max(0.0);
    let dy = (a.min.y - b.max.y).max(b.min.y - a.max.y).max(0.0);
    dx.hypot(dy)
}

/// A medium whose speed is linear in position, `c(p) = speed + gradient · p` (`p` relative
/// to the origin of the leg's ends): its legs are circular arcs (`design/curved-rays.md`).
///
/// Every formula below is written in `y = g ℓ / (2 √(c_a c_b))` (`g = |gradient|`), with no
/// division by `g`: at a gradient of zero they are the straight leg's (to rounding), and near
/// it they lose no digits (the textbook `acosh(1 + 2y²) / g` gives 0 at `g = 1e-9`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Linear {
    /// The speed at the origin.
    pub speed: f64,
    /// The speed's gradient (speed per length).
    pub gradient: Vec2,
    /// The least speed where the medium is used (the scene's extent): the residual bounds'
    /// greatest slowness.
    pub least_speed: f64,
}

/// A circular arc in a [`Linear`] medium, evaluated from its two ends.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ArcLeg {
    /// The travel time.
    pub time: f64,
    /// The speed at the start and at the end.
    pub speeds: [f64; 2],
    /// The chord `b − a`.
    pub chord: Vec2,
    /// The chord's length.
    pub len: f64,
    /// The medium's gradient.
    pub gradient: Vec2,
    /// `T′ A = 1 / (ℓ √(c_a c_b) √(1 + y²))` (the factor of the first derivatives).
    first: f64,
    /// `−T″ A² = (1 + 2y²) / (ℓ³ √(c_a c_b) (1 + y²)^{3/2})`.
    second: f64,
    /// `−∇_a T`.
    departure: Vec2,
    /// `∇_b T`.
    arrival: Vec2,
}

/// `asinh(y) / y` for `y ≥ 0`, without loss near 0 (its series below 1e-3).
#[inline]
pub(crate) fn asinh_over(y: f64) -> f64 {
    if y < 1e-3 {
        let y2 = y * y;
        1.0 - y2 * (1.0 / 6.0 - y2 * (3.0 / 40.0 - y2 * (5.0 / 112.0)))
    } else {
        y.asinh() / y
    }
}

/// [`asinh_over`] given `y² ` and `s = √(1 + y²)` (an arc's own): `asinh y = ln(1 + y + y² /
/// (1 + s))`, by `ln_1p` (the standard `asinh` computes that root again, by `hypot`).
#[inline]
fn asinh_over_given(y: f64, y2: f64, s: f64) -> f64 {
    if y < 1e-3 {
        asinh_over(y)
    } else {
        (y + y2 / (1.0 + s)).ln_1p() / y
    }
}

/// `asin(z) / z` for `0 ≤ z ≤ 1`, without loss near 0.
#[inline]
fn asin_over(z: f64) -> f64 {
    if z < 1e-3 {
        let z2 = z * z;
        1.0 + z2 * (1.0 / 6.0 + z2 * (3.0 / 40.0 + z2 * (5.0 / 112.0)))
    } else {
        z.min(1.0).asin() / z
    }
}

/// `sin(x) / x`, without loss near 0.
#[inline]
fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-3 {
        let x2 = x * x;
        1.0 - x2 / 6.0 * (1.0 - x2 / 20.0)
    } else {
        x.sin() / x
    }
}

impl Linear {
    /// The speed at `p` (relative to the origin).
    #[inline]
    pub fn speed_at(self, p: Vec2) -> f64 {
        self.speed + self.gradient.dot(p)
    }

    /// The same medium with its positions relative to `origin` (given relative to the old
    /// origin).
    #[inline]
    pub fn shifted(self, origin: Vec2) -> Linear {
        Linear {
            speed: self.speed_at(origin),
            ..self
        }
    }

    /// The greatest speed over the corners of `b` (the greatest over the box: the speed is
    /// linear).
    fn greatest_speed(self, b: Aabb) -> f64 {
        let c = |x: f64, y: f64| self.speed_at(Vec2::new(x, y));
        c(b.min.x, b.min.y)
            .max(c(b.max.x, b.min.y))
            .max(c(b.min.x, b.max.y))
            .max(c(b.max.x, b.max.y))
    }

    /// The least time of a leg of chord length at least `len` between ends of speeds at most
    /// `ca`, `cb` (the time grows with the chord and falls with the speeds at the ends).
    fn least_time_between(self, len: f64, ca: f64, cb: f64) -> f64 {
        if !(ca > 0.0 && cb > 0.0) {
            return 0.0;
        }
        let root = (ca * cb).sqrt();
        let y = self.gradient.length() * len / (2.0 * root);
        (len / root * asinh_over(y)).max(0.0)
    }
}

impl LegModel for Linear {
    type Leg = ArcLeg;

    #[inline]
    fn leg(self, a: Vec2, b: Vec2) -> ArcLeg {
        let (ca, cb) = (self.speed_at(a), self.speed_at(b));
        let d = b - a;
        let len = length(d);
        let g = self.gradient;
        if len.is_nan() || len <= 0.0 {
            return ArcLeg {
                speeds: [ca, cb],
                gradient: g,
                ..ArcLeg::default()
            };
        }
        let cacb = ca * cb;
        let root = cacb.sqrt();
        let y2 = g.dot(g) * len * len / (4.0 * cacb);
        let y = y2.sqrt();
        let s = (1.0 + y2).sqrt();
        let time = len / root * asinh_over_given(y, y2, s);
        let first = 1.0 / (len * root * s);
        let second = (1.0 + 2.0 * y2) / (len * len * len * root * s * s * s);
        let l2 = len * len;
        ArcLeg {
            time,
            speeds: [ca, cb],
            chord: d,
            len,
            gradient: g,
            first,
            second,
            departure: (d + g * (l2 / (2.0 * ca))) * first,
            arrival: (d - g * (l2 / (2.0 * cb))) * first,
        }
    }

    #[inline]
    fn valid_leg(self, a: Point, b: Point) -> Option<ArcLeg> {
        let leg = self.leg(a.to_vec2(), b.to_vec2());
        let [ca, cb] = leg.speeds;
        (leg.len > 0.0 && leg.len.is_finite() && ca > 0.0 && cb > 0.0 && leg.time.is_finite())
            .then_some(leg)
    }

    fn least_time(self, from: Aabb, to: Aabb) -> f64 {
        let (ca, cb) = (self.greatest_speed(from), self.greatest_speed(to));
        self.least_time_between(box_gap(from, to), ca, cb)
    }

    fn least_time_to(self, from: Aabb, to: Point) -> f64 {
        let (ca, cb) = (self.greatest_speed(from), self.speed_at(to.to_vec2()));
        self.least_time_between(from.distance_sq(to).sqrt(), ca, cb)
    }

    fn along_at_ends(self, _chord_along: [f64; 2]) -> [f64; 2] {
        // An arc's ends turn away from its chord: only the slowness's size bounds them.
        let w = self.greatest_slowness();
        [-w, w]
    }

    fn greatest_slowness(self) -> f64 {
        1.0 / self.least_speed
    }
}

/// `(asinh(y)/y − 1/√(1 + y²)) / y²` for `y ≥ 0`, without loss near 0 (its series below
/// 1e-2): the factor of an arc's time's derivative by its gradient's size, over `y`.
#[inline]
fn asinh_gap(y: f64) -> f64 {
    let y2 = y * y;
    if y < 1e-2 {
        1.0 / 3.0 - y2 * (3.0 / 10.0 - y2 * (15.0 / 56.0 - y2 * (35.0 / 144.0)))
    } else {
        (asinh_over(y) - 1.0 / (1.0 + y2).sqrt()) / y2
    }
}

impl ArcLeg {
    /// The derivatives of the leg's time by its medium's speed at the origin `c₀` and by its
    /// gradient `G` (`c(p) = c₀ + G · p`), its ends `a`, `b` held (relative to that origin):
    /// with `T = (2/g) asinh(y)`, `∂T/∂c_a = −ℓ² T′A / (2 c_a)` (and so for `b`), `∂T/∂c₀`
    /// their sum, and `∂T/∂G = −ℓ³ k(y) G / (4 c_a c_b √(c_a c_b)) + a ∂T/∂c_a + b ∂T/∂c_b`
    /// with `k` [`asinh_gap`]: no division by `g` (at `G = 0`, `−ℓ (a + b) / (2 c₀²)`). Zero
    /// for a vanished leg.
    pub fn medium_derivatives(&self, a: Vec2, b: Vec2) -> (f64, Vec2) {
        if self.len.is_nan() || self.len <= 0.0 {
            return (0.0, Vec2::default());
        }
        let [ca, cb] = self.speeds;
        let l2 = self.len * self.len;
        let (dca, dcb) = (-l2 * self.first / (2.0 * ca), -l2 * self.first / (2.0 * cb));
        let p = ca * cb;
        let root = p.sqrt();
        let y = self.gradient.length() * self.len / (2.0 * root);
        let along = -(l2 * self.len) / (4.0 * p * root) * asinh_gap(y);
        (dca + dcb, self.gradient * along + a * dca + b * dcb)
    }

    /// `v_a = −d − ℓ² G / (2 c_a)` and `v_b = d − ℓ² G / (2 c_b)`: `∇X / A` at the ends.
    #[inline]
    fn v(&self) -> [Vec2; 2] {
        let l2 = self.len * self.len;
        let [ca, cb] = self.speeds;
        [
            (self.chord + self.gradient * (l2 / (2.0 * ca))) * -1.0,
            self.chord - self.gradient * (l2 / (2.0 * cb)),
        ]
    }

    /// The arc's signed curvature (positive: it turns left), `−(G · n⊥) / c` at its start.
    #[inline]
    pub fn curvature(&self) -> f64 {
        let d0 = self.direction_at_start();
        -self.gradient.dot(d0.perp()) / self.speeds[0]
    }

    /// The arc's length.
    pub fn arc_length(&self) -> f64 {
        let z = 0.5 * self.len * self.curvature().abs();
        self.len * asin_over(z)
    }

    /// The point at arc length `s` from the start, relative to the start (a ray's sampled
    /// curve, `trace::curve`; the tests' check of an arc's points).
    pub fn offset_at(&self, s: f64) -> Vec2 {
        let d0 = self.direction_at_start();
        let k = self.curvature();
        let half = sinc(0.5 * k * s);
        d0 * (s * sinc(k * s)) + d0.perp() * (0.5 * k * s * s * half * half)
    }
}

impl Leg for ArcLeg {
    #[inline]
    fn time(&self) -> f64 {
        self.time
    }
    #[inline]
    fn arrival(&self) -> Vec2 {
        self.arrival
    }
    #[inline]
    fn departure(&self) -> Vec2 {
        self.departure
    }
    #[inline]
    fn direction_at_end(&self) -> Vec2 {
        self.arrival * self.speeds[1]
    }
    #[inline]
    fn direction_at_start(&self) -> Vec2 {
        self.departure * self.speeds[0]
    }
    fn end_block(&self, t: Vec2) -> f64 {
        let [_, vb] = self.v();
        let [_, cb] = self.speeds;
        let (dt, gt) = (self.chord.dot(t), self.gradient.dot(t));
        let m = t.dot(t) - 2.0 * dt * gt / cb + self.len * self.len * gt * gt / (cb * cb);
        -self.second * vb.dot(t) * vb.dot(t) + self.first * m
    }
    fn start_block(&self, t: Vec2) -> f64 {
        let [va, _] = self.v();
        let [ca, _] = self.speeds;
        let (dt, gt) = (self.chord.dot(t), self.gradient.dot(t));
        let m = t.dot(t) + 2.0 * dt * gt / ca + self.len * self.len * gt * gt / (ca * ca);
        -self.second * va.dot(t) * va.dot(t) + self.first * m
    }
    fn coupling(&self, ta: Vec2, tb: Vec2) -> f64 {
        let [va, vb] = self.v();
        let [ca, cb] = self.speeds;
        let (d, g) = (self.chord, self.gradient);
        let m = -ta.dot(tb) - d.dot(tb) * g.dot(ta) / ca
            + g.dot(tb) * d.dot(ta) / cb
            + self.len * self.len * g.dot(ta) * g.dot(tb) / (2.0 * ca * cb);
        -self.second * va.dot(ta) * vb.dot(tb) + self.first * m
    }
    fn out_of_plane_width(&self, source_slowness: f64) -> f64 {
        // ∫ c ds = ℓ c(arc's middle) = ℓ c(chord's middle) / cos(half the turn), and
        // sin(half the turn) = ℓ κ / 2 (κ the curvature).
        let [ca, cb] = self.speeds;
        let z = 0.5 * self.len * self.curvature();
        let cos = (1.0 - z * z).max(0.0).sqrt();
        source_slowness * self.len * 0.5 * (ca + cb) / cos
    }
}

/// The model of one leg's medium when a path may hold curved legs: [`Uniform`],
/// [`Linear`] or one branch of a profile ([`profile::ProfileLegModel`], borrowing its
/// profile: a path through a profile medium whose reflections are not all on flat
/// horizontal walls), chosen per leg.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum LegMedium<'a> {
    /// A uniform medium.
    Uniform(Uniform),
    /// A medium whose speed is linear in position.
    Linear(Linear),
    /// One branch of a profile medium.
    Profile(profile::ProfileLegModel<'a>),
}

/// A leg of a [`LegMedium`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum AnyLeg {
    /// A straight leg.
    Straight(StraightLeg),
    /// A circular arc.
    Arc(ArcLeg),
    /// A ray of a profile medium.
    Profile(profile::ProfileLeg),
}

impl AnyLeg {
    /// The chord's length.
    #[inline]
    pub fn len(&self) -> f64 {
        match self {
            AnyLeg::Straight(l) => l.len,
            AnyLeg::Arc(l) => l.len,
            AnyLeg::Profile(l) => l.len,
        }
    }

    /// The unit direction of the chord (zero for a leg of zero length).
    #[inline]
    pub fn chord_direction(&self) -> Vec2 {
        match self {
            AnyLeg::Straight(l) => l.u,
            AnyLeg::Arc(l) if l.len > 0.0 => l.chord * (1.0 / l.len),
            AnyLeg::Profile(l) if l.len > 0.0 => l.chord * (1.0 / l.len),
            AnyLeg::Arc(_) | AnyLeg::Profile(_) => Vec2::default(),
        }
    }

    /// The arc, if the leg is one.
    #[inline]
    pub fn arc(&self) -> Option<&ArcLeg> {
        match self {
            AnyLeg::Arc(l) => Some(l),
            AnyLeg::Straight(_) | AnyLeg::Profile(_) => None,
        }
    }

    /// The profile's ray, if the leg is one.
    #[inline]
    pub fn profile(&self) -> Option<&profile::ProfileLeg> {
        match self {
            AnyLeg::Profile(l) => Some(l),
            AnyLeg::Straight(_) | AnyLeg::Arc(_) => None,
        }
    }

    /// The length along the leg: a straight leg's, an arc's, a profile ray's.
    #[inline]
    pub fn arc_length(&self) -> f64 {
        match self {
            AnyLeg::Straight(l) => l.len,
            AnyLeg::Arc(l) => l.arc_length(),
            AnyLeg::Profile(l) => l.arc,
        }
    }
}

macro_rules! either {
    ($self:expr, $l:ident => $e:expr) => {
        match $self {
            AnyLeg::Straight($l) => $e,
            AnyLeg::Arc($l) => $e,
            AnyLeg::Profile($l) => $e,
        }
    };
}

impl Leg for AnyLeg {
    #[inline]
    fn time(&self) -> f64 {
        either!(self, l => l.time())
    }
    #[inline]
    fn arrival(&self) -> Vec2 {
        either!(self, l => l.arrival())
    }
    #[inline]
    fn departure(&self) -> Vec2 {
        either!(self, l => l.departure())
    }
    #[inline]
    fn direction_at_end(&self) -> Vec2 {
        either!(self, l => l.direction_at_end())
    }
    #[inline]
    fn direction_at_start(&self) -> Vec2 {
        either!(self, l => l.direction_at_start())
    }
    #[inline]
    fn end_block(&self, t: Vec2) -> f64 {
        either!(self, l => l.end_block(t))
    }
    #[inline]
    fn start_block(&self, t: Vec2) -> f64 {
        either!(self, l => l.start_block(t))
    }
    #[inline]
    fn coupling(&self, ta: Vec2, tb: Vec2) -> f64 {
        either!(self, l => l.coupling(ta, tb))
    }
    #[inline]
    fn out_of_plane_width(&self, source_slowness: f64) -> f64 {
        either!(self, l => l.out_of_plane_width(source_slowness))
    }
}

impl LegModel for LegMedium<'_> {
    type Leg = AnyLeg;

    #[inline]
    fn leg(self, a: Vec2, b: Vec2) -> AnyLeg {
        match self {
            LegMedium::Uniform(m) => AnyLeg::Straight(m.leg(a, b)),
            LegMedium::Profile(m) => AnyLeg::Profile(m.leg(a, b)),
            LegMedium::Linear(m) => AnyLeg::Arc(m.leg(a, b)),
        }
    }
    #[inline]
    fn valid_leg(self, a: Point, b: Point) -> Option<AnyLeg> {
        match self {
            LegMedium::Uniform(m) => m.valid_leg(a, b).map(AnyLeg::Straight),
            LegMedium::Linear(m) => m.valid_leg(a, b).map(AnyLeg::Arc),
            LegMedium::Profile(m) => m.valid_leg(a, b).map(AnyLeg::Profile),
        }
    }
    fn least_time(self, from: Aabb, to: Aabb) -> f64 {
        match self {
            LegMedium::Uniform(m) => m.least_time(from, to),
            LegMedium::Linear(m) => m.least_time(from, to),
            LegMedium::Profile(m) => m.least_time(from, to),
        }
    }
    fn least_time_to(self, from: Aabb, to: Point) -> f64 {
        match self {
            LegMedium::Uniform(m) => m.least_time_to(from, to),
            LegMedium::Linear(m) => m.least_time_to(from, to),
            LegMedium::Profile(m) => m.least_time_to(from, to),
        }
    }
    fn along_at_ends(self, chord_along: [f64; 2]) -> [f64; 2] {
        match self {
            LegMedium::Uniform(m) => m.along_at_ends(chord_along),
            LegMedium::Linear(m) => m.along_at_ends(chord_along),
            LegMedium::Profile(m) => m.along_at_ends(chord_along),
        }
    }
    fn greatest_slowness(self) -> f64 {
        match self {
            LegMedium::Uniform(m) => m.greatest_slowness(),
            LegMedium::Linear(m) => m.greatest_slowness(),
            LegMedium::Profile(m) => m.greatest_slowness(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::SplitMix64;

    /// The unit vector at angle `a`.
    fn unit(a: f64) -> Vec2 {
        Vec2::new(a.cos(), a.sin())
    }

    /// A random point in [−5, 5]².
    fn point(rng: &mut SplitMix64) -> Vec2 {
        Vec2::new(10.0 * rng.next_f64() - 5.0, 10.0 * rng.next_f64() - 5.0)
    }

    /// The time of the straight leg from `a` to `b` at slowness `w`, the reference: the
    /// distance times the slowness.
    fn reference_time(w: f64, a: Vec2, b: Vec2) -> f64 {
        w * (b - a).length()
    }

    /// The leg's time, gradient and Hessian blocks against central finite differences of the
    /// reference time, on random legs and directions: the gradient to 1e-7, the blocks to
    /// 1e-5 (relative to the leg's scale `w` and `w / ℓ`).
    #[test]
    fn derivatives_match_finite_differences() {
        let mut rng = SplitMix64(0x1e9);
        let h = 1e-5;
        let mut checked = 0;
        for _ in 0..500 {
            let (a, b) = (point(&mut rng), point(&mut rng));
            let w = 0.2 + 3.0 * rng.next_f64();
            let leg = Uniform::new(w).leg(a, b);
            if leg.len < 1.0 {
                continue;
            }
            assert!((leg.time() - reference_time(w, a, b)).abs() <= 1e-14 * leg.time());
            let (ta, tb) = (unit(7.0 * rng.next_f64()), unit(7.0 * rng.next_f64()));
            let t = |da: f64, db: f64| reference_time(w, a + ta * da, b + tb * db);
            // First derivatives along ta and tb.
            let d_end = (t(0.0, h) - t(0.0, -h)) / (2.0 * h);
            let d_start = (t(h, 0.0) - t(-h, 0.0)) / (2.0 * h);
            assert!((leg.arrival().dot(tb) - d_end).abs() < 1e-7 * w, "{d_end}");
            assert!(
                (-leg.departure().dot(ta) - d_start).abs() < 1e-7 * w,
                "{d_start}"
            );
            // Second derivatives.
            let h2 = 1e-3;
            let t2 = |da: f64, db: f64| reference_time(w, a + ta * da, b + tb * db);
            let dd_end = (t2(0.0, h2) - 2.0 * t2(0.0, 0.0) + t2(0.0, -h2)) / (h2 * h2);
            let dd_start = (t2(h2, 0.0) - 2.0 * t2(0.0, 0.0) + t2(-h2, 0.0)) / (h2 * h2);
            let dd_mixed =
                (t2(h2, h2) - t2(h2, -h2) - t2(-h2, h2) + t2(-h2, -h2)) / (4.0 * h2 * h2);
            let scale = w / leg.len;
            assert!(
                (leg.end_block(tb) - dd_end).abs() < 1e-5 * scale,
                "{dd_end}"
            );
            assert!(
                (leg.start_block(ta) - dd_start).abs() < 1e-5 * scale,
                "{dd_start}"
            );
            assert!(
                (leg.coupling(ta, tb) - dd_mixed).abs() < 1e-5 * scale,
                "{dd_mixed}"
            );
            let projected = leg.coupling_projected(ta, tb);
            assert!((projected - leg.coupling(ta, tb)).abs() < 1e-13 * scale);
            // The directions at the ends are the slowness vectors over the slowness, unit.
            assert!((leg.direction_at_end().length() - 1.0).abs() < 1e-15);
            assert!((leg.arrival().length() - w).abs() < 1e-14 * w);
            checked += 1;
        }
        assert!(checked > 300, "{checked} legs checked");
    }

    /// The gradient is the slowness vector: its size is the slowness (the eikonal equation)
    /// and it points along the leg, at both ends.
    #[test]
    fn the_gradient_is_the_slowness_vector() {
        let leg = Uniform::new(2.0).leg(Vec2::new(1.0, 1.0), Vec2::new(4.0, 5.0));
        assert_eq!(leg.len, 5.0);
        assert_eq!(leg.time(), 10.0);
        for p in [leg.arrival(), leg.departure()] {
            assert!((p - Vec2::new(1.2, 1.6)).length() < 1e-15, "{p:?}");
        }
        // Across the leg the blocks are w / ℓ; along it zero.
        let across = Vec2::new(-0.8, 0.6);
        assert!((leg.end_block(across) - 0.4).abs() < 1e-15);
        assert!(leg.end_block(Vec2::new(0.6, 0.8)).abs() < 1e-15);
        assert!((leg.coupling(across, across) + 0.4).abs() < 1e-15);
        // The out-of-plane width: ℓ c (w₀ = 1).
        assert_eq!(leg.out_of_plane_width(1.0), 2.5);
    }

    /// The residual bounds' view of a leg: for random legs and tangents, the slowness vector
    /// at either end along `t` lies in `along_at_ends` of the chord's `u · t` (here exactly
    /// the slowness times it), and its size is at most `greatest_slowness`.
    #[test]
    fn the_slowness_at_the_ends_is_bounded_by_the_chord() {
        let mut rng = SplitMix64(0xa10e);
        for _ in 0..1000 {
            let (a, b) = (point(&mut rng), point(&mut rng));
            let m = Uniform::new(0.1 + 4.0 * rng.next_f64());
            let leg = m.leg(a, b);
            if leg.len == 0.0 {
                continue;
            }
            let t = unit(7.0 * rng.next_f64());
            let chord = (b - a) * (1.0 / (b - a).length());
            let along = chord.dot(t);
            let [lo, hi] = m.along_at_ends([along - 1e-12, along + 1e-12]);
            for p in [leg.arrival(), leg.departure()] {
                let x = p.dot(t);
                assert!(lo <= x && x <= hi, "{x} outside [{lo}, {hi}]");
                assert!(p.length() <= m.greatest_slowness() * (1.0 + 1e-15));
            }
        }
    }

    /// A leg of zero length: zero direction and inverse length, no valid leg; a leg of
    /// tiny or huge length through `hypot`.
    #[test]
    fn degenerate_legs() {
        let m = Uniform::new(1.0);
        let zero = m.leg(Vec2::new(1.0, 2.0), Vec2::new(1.0, 2.0));
        assert_eq!(
            (zero.len, zero.inv_len, zero.u),
            (0.0, 0.0, Vec2::default())
        );
        let p = Point::new(1.0, 2.0);
        assert!(m.valid_leg(p, p).is_none());
        assert!(m.valid_leg(p, Point::new(f64::INFINITY, 0.0)).is_none());
        let origin = Point::new(0.0, 0.0);
        let tiny = m.valid_leg(origin, Point::new(1e-160, 0.0)).expect("a leg");
        assert!(tiny.len > 0.0 && (tiny.u.x - 1.0).abs() < 1e-15);
        let huge = m.leg(Vec2::new(-1e200, 0.0), Vec2::new(1e200, 0.0));
        assert_eq!(huge.len, 2e200);
        let (_, plain) = m.leg_plain(Vec2::new(1e200, 0.0));
        assert!(!plain);
        let (leg, plain) = m.leg_plain(Vec2::new(3.0, 4.0));
        assert!(plain);
        assert_eq!(leg, m.leg_along(Vec2::new(3.0, 4.0)));
    }

    /// The lower bounds hold every leg between random points of two random boxes, and
    /// are reached by the boxes' nearest points.
    #[test]
    fn the_least_time_bounds_every_leg() {
        let mut rng = SplitMix64(0xb0c5);
        for _ in 0..300 {
            let corner = |rng: &mut SplitMix64| {
                let (p, q) = (point(rng), point(rng));
                Aabb::from_points(p.to_point(), (p + (q - p) * 0.3).to_point())
            };
            let (from, to) = (corner(&mut rng), corner(&mut rng));
            let m = Uniform::new(0.5 + rng.next_f64());
            let bound = m.least_time(from, to);
            assert!(bound >= 0.0);
            let at = |b: Aabb, rng: &mut SplitMix64| {
                Point::new(
                    b.min.x + rng.next_f64() * (b.max.x - b.min.x),
                    b.min.y + rng.next_f64() * (b.max.y - b.min.y),
                )
            };
            for _ in 0..20 {
                let (a, b) = (at(from, &mut rng), at(to, &mut rng));
                let leg = m.leg(a.to_vec2(), b.to_vec2());
                assert!(
                    leg.time() >= bound * (1.0 - 1e-12),
                    "{} < {bound}",
                    leg.time()
                );
                assert!(leg.time() >= m.least_time_to(from, b) * (1.0 - 1e-12));
            }
            // The nearest points, axis by axis: the facing ends where the boxes' ranges are
            // apart, one shared coordinate where they overlap. The bound is their leg's time.
            let nearest = |a: [f64; 2], b: [f64; 2]| {
                if a[1] < b[0] {
                    (a[1], b[0])
                } else if b[1] < a[0] {
                    (a[0], b[1])
                } else {
                    (a[0].max(b[0]), a[0].max(b[0]))
                }
            };
            let (xa, xb) = nearest([from.min.x, from.max.x], [to.min.x, to.max.x]);
            let (ya, yb) = nearest([from.min.y, from.max.y], [to.min.y, to.max.y]);
            let leg = m.leg(Vec2::new(xa, ya), Vec2::new(xb, yb));
            assert!(
                (leg.time() - bound).abs() <= 1e-14 * (1.0 + bound),
                "{} {bound}",
                leg.time()
            );
        }
    }

    /// The arc leg of a medium `c = c0 + G · p` from `a` to `b`.
    fn arc(c0: f64, g: [f64; 2], a: [f64; 2], b: [f64; 2]) -> ArcLeg {
        let m = Linear {
            speed: c0,
            gradient: Vec2::new(g[0], g[1]),
            least_speed: 1.0,
        };
        m.leg(Vec2::new(a[0], a[1]), Vec2::new(b[0], b[1]))
    }

    /// The ray equations `dx/ds = c p`, `dp/ds = −∇c / c²` of a medium `c = c0 + G · x`,
    /// integrated by RK4 from `x` along the unit direction `d` over the arc length `s` in `n`
    /// steps: the end point, the time and `∫ c ds` (trapezoids on the steps). An oracle
    /// independent of the closed forms.
    fn shoot(c0: f64, g: Vec2, x: Vec2, d: Vec2, s: f64, n: usize) -> (Vec2, f64, f64) {
        // State: position, slowness vector, time, ∫ c ds.
        type State = (Vec2, Vec2, f64, f64);
        let c = |x: Vec2| c0 + g.dot(x);
        let f = |(x, p, _, _): State| {
            let cx = c(x);
            (p * cx, g * (-1.0 / (cx * cx)), 1.0 / cx, cx)
        };
        let step = |a: State, k: State, h: f64| {
            (a.0 + k.0 * h, a.1 + k.1 * h, a.2 + k.2 * h, a.3 + k.3 * h)
        };
        let h = s / n as f64;
        let mut y: State = (x, d * (1.0 / c(x)), 0.0, 0.0);
        for _ in 0..n {
            let k1 = f(y);
            let k2 = f(step(y, k1, h / 2.0));
            let k3 = f(step(y, k2, h / 2.0));
            let k4 = f(step(y, k3, h));
            y = step(
                step(step(step(y, k1, h / 6.0), k2, h / 3.0), k3, h / 3.0),
                k4,
                h / 6.0,
            );
        }
        (y.0, y.2, y.3)
    }

    /// The design note's leg times (its §3 table, checked there against quadrature and a ray
    /// integration), to 1e-14.
    #[test]
    fn arc_times_match_the_design_note() {
        let cases = [
            (
                1500.0,
                [0.0, 0.017],
                [0.0, 100.0],
                [5000.0, 300.0],
                3.328012692238152,
            ),
            (
                1500.0,
                [0.0, 0.017],
                [0.0, 100.0],
                [20000.0, 100.0],
                13.289_955_753_698_13,
            ),
            (
                2000.0,
                [0.3, 0.8],
                [0.0, 0.0],
                [3000.0, -1000.0],
                1.448755408206392,
            ),
            (
                340.0,
                [0.0, -0.5],
                [0.0, 0.0],
                [30.0, 5.0],
                0.089775546767277,
            ),
        ];
        for (c0, g, a, b, t) in cases {
            let leg = arc(c0, g, a, b);
            assert!((leg.time() - t).abs() <= 1e-14 * t, "{} {t}", leg.time());
            // The eikonal equation at both ends: c |∇T| = 1.
            let [ca, cb] = leg.speeds;
            assert!((leg.arrival().length() * cb - 1.0).abs() < 1e-14);
            assert!((leg.departure().length() * ca - 1.0).abs() < 1e-14);
        }
    }

    /// An RK4 integration of the ray equations from the start along the leg's departure
    /// direction, over the leg's arc length, lands on its end (to 1e-9 of the chord), takes
    /// its time (1e-10) and its `∫ c ds` (1e-9), and arrives along its arrival direction; the
    /// arc's points ([`ArcLeg::offset_at`]) lie on the integrated ray.
    #[test]
    fn arcs_are_rays() {
        let mut rng = SplitMix64(0xa4c);
        let mut checked = 0;
        for _ in 0..40 {
            let c0 = 300.0 + 2000.0 * rng.next_f64();
            let g = unit(7.0 * rng.next_f64()) * (1.5 * rng.next_f64());
            let (a, b) = (point(&mut rng) * 200.0, point(&mut rng) * 200.0);
            let m = Linear {
                speed: c0,
                gradient: g,
                least_speed: 1.0,
            };
            let leg = m.leg(a, b);
            if leg.len < 10.0 || leg.speeds[0] < 100.0 || leg.speeds[1] < 100.0 {
                continue;
            }
            let s = leg.arc_length();
            let (end, time, width) = shoot(c0, g, a, leg.direction_at_start(), s, 4000);
            assert!(
                (end - b).length() < 1e-9 * leg.len,
                "{:?} {b:?} {:?} {c0} {g:?} {a:?} k={} s={}",
                end,
                leg.speeds,
                leg.curvature(),
                s
            );
            assert!(
                (time - leg.time()).abs() < 1e-10 * leg.time(),
                "{time} {} {:?} {c0} {g:?} {a:?} {b:?}",
                leg.time(),
                leg.speeds
            );
            let w0 = 1.0 / leg.speeds[0];
            let closed = leg.out_of_plane_width(w0) / w0;
            assert!((width - closed).abs() < 1e-9 * closed, "{width} {closed}");
            let (mid, _, _) = shoot(c0, g, a, leg.direction_at_start(), 0.3 * s, 1000);
            assert!((a + leg.offset_at(0.3 * s) - mid).length() < 1e-9 * leg.len);
            // Where it arrives: the direction the ray has at its end.
            let (near, _, _) = shoot(c0, g, a, leg.direction_at_start(), s - 1e-3, 4000);
            let d = (end - near) * (1.0 / (end - near).length());
            assert!((d - leg.direction_at_end()).length() < 1e-6);
            checked += 1;
        }
        assert!(checked >= 10, "{checked}");
    }

    /// The arc's gradient and Hessian blocks against central finite differences of its
    /// time, on random legs, gradients (down to zero) and directions.
    #[test]
    fn arc_medium_derivatives_match_finite_differences() {
        let (a, b) = (Vec2::new(-300.0, 120.0), Vec2::new(2500.0, -400.0));
        for (c0, g) in [
            (1500.0, Vec2::new(0.0, -0.1)),
            (2000.0, Vec2::new(0.3, 0.6)),
            (1500.0, Vec2::new(1e-9, -2e-9)),
            (1500.0, Vec2::new(0.0, 0.0)),
        ] {
            let time = |c0: f64, g: Vec2| {
                Linear {
                    speed: c0,
                    gradient: g,
                    least_speed: 1.0,
                }
                .leg(a, b)
                .time
            };
            let leg = Linear {
                speed: c0,
                gradient: g,
                least_speed: 1.0,
            }
            .leg(a, b);
            let (dc, dg) = leg.medium_derivatives(a, b);
            let h = 1e-3;
            let fd_c = (time(c0 + h, g) - time(c0 - h, g)) / (2.0 * h);
            assert!((dc - fd_c).abs() < 1e-9 * fd_c.abs(), "{dc} {fd_c}");
            let hg = 1e-6;
            for (e, d) in [(Vec2::new(hg, 0.0), dg.x), (Vec2::new(0.0, hg), dg.y)] {
                let fd = (time(c0, g + e) - time(c0, g - e)) / (2.0 * hg);
                assert!((d - fd).abs() < 1e-6 * fd.abs(), "{g:?}: {d} {fd}");
            }
        }
    }

    #[test]
    fn arc_derivatives_match_finite_differences() {
        let mut rng = SplitMix64(0xd1ff);
        let mut checked = 0;
        for n in 0..400 {
            let c0 = 2.0 + 3.0 * rng.next_f64();
            let size = [0.0, 1e-12, 1e-6, 0.05, 0.2][n % 5];
            let g = unit(7.0 * rng.next_f64()) * size;
            let m = Linear {
                speed: c0,
                gradient: g,
                least_speed: 1.0,
            };
            let (a, b) = (point(&mut rng), point(&mut rng));
            let leg = m.leg(a, b);
            if leg.len < 1.0 || leg.speeds[0] < 0.5 || leg.speeds[1] < 0.5 {
                continue;
            }
            let (ta, tb) = (unit(7.0 * rng.next_f64()), unit(7.0 * rng.next_f64()));
            let t = |da: f64, db: f64| m.leg(a + ta * da, b + tb * db).time();
            let h = 1e-5;
            let d_end = (t(0.0, h) - t(0.0, -h)) / (2.0 * h);
            let d_start = (t(h, 0.0) - t(-h, 0.0)) / (2.0 * h);
            let w = 1.0 / c0;
            assert!((leg.arrival().dot(tb) - d_end).abs() < 1e-8 * w, "{d_end}");
            assert!((-leg.departure().dot(ta) - d_start).abs() < 1e-8 * w);
            let h2 = 1e-3;
            let dd_end = (t(0.0, h2) - 2.0 * t(0.0, 0.0) + t(0.0, -h2)) / (h2 * h2);
            let dd_start = (t(h2, 0.0) - 2.0 * t(0.0, 0.0) + t(-h2, 0.0)) / (h2 * h2);
            let dd_mixed = (t(h2, h2) - t(h2, -h2) - t(-h2, h2) + t(-h2, -h2)) / (4.0 * h2 * h2);
            let scale = w / leg.len;
            assert!(
                (leg.end_block(tb) - dd_end).abs() < 1e-5 * scale,
                "{dd_end}"
            );
            assert!((leg.start_block(ta) - dd_start).abs() < 1e-5 * scale);
            assert!((leg.coupling(ta, tb) - dd_mixed).abs() < 1e-5 * scale);
            checked += 1;
        }
        assert!(checked > 150, "{checked}");
    }

    /// `asinh(y)/y` from the arc's own `√(1 + y²)` against the standard `asinh` (and its
    /// series), over `y` from 1e-6 to 1e6: within 4 ulps.
    #[test]
    fn asinh_from_the_arcs_root_is_asinh() {
        let mut rng = SplitMix64(7);
        for _ in 0..20000 {
            let y = 10f64.powf(12.0 * rng.next_f64() - 6.0);
            let y2 = y * y;
            let got = super::asinh_over_given(y, y2, (1.0 + y2).sqrt());
            let want = asinh_over(y);
            assert!(
                (got - want).abs() <= 4.0 * f64::EPSILON * want,
                "{y}: {got} {want}"
            );
        }
    }

    /// Near-zero gradients give the straight leg's numbers to rounding (no `1/g`): at
    /// `g = 1e-9` the textbook `acosh(1 + 2y²) / g` gives 0.
    #[test]
    fn tiny_gradients_are_straight() {
        let (a, b) = (Vec2::new(0.0, 100.0), Vec2::new(5000.0, 300.0));
        let straight = Uniform::new(1.0 / 1500.0).leg(a, b);
        for g in [1e-9, 1e-12, 1e-15] {
            let m = Linear {
                speed: 1500.0,
                gradient: Vec2::new(0.0, g / 1000.0),
                least_speed: 1.0,
            };
            let leg = m.leg(a, b);
            let rel = |x: f64, y: f64| (x - y).abs() / y.abs().max(1e-300);
            assert!(rel(leg.time(), straight.time()) < 1e-9, "{g}");
            assert!((leg.arrival() - straight.arrival()).length() < 1e-9 / 1500.0);
            let t = Vec2::new(0.6, 0.8);
            assert!(rel(leg.end_block(t), straight.end_block(t)) < 1e-9);
            assert!(rel(leg.coupling(t, t), straight.coupling(t, t)) < 1e-9);
            assert!(
                rel(
                    leg.out_of_plane_width(1.0),
                    straight.out_of_plane_width(1.0)
                ) < 1e-9
            );
        }
        let textbook = (1.0f64 + 2.0 * (1e-9f64 * 5004.0 / 3000.0).powi(2)).acosh() / 1e-9;
        assert_eq!(textbook, 0.0);
    }

    /// The lower bounds hold for arcs between random points of random boxes.
    #[test]
    fn arc_least_time_bounds_every_leg() {
        let mut rng = SplitMix64(0xb0c6);
        for _ in 0..300 {
            let corner = |rng: &mut SplitMix64| {
                let (p, q) = (point(rng), point(rng));
                Aabb::from_points(p.to_point(), (p + (q - p) * 0.3).to_point())
            };
            let (from, to) = (corner(&mut rng), corner(&mut rng));
            let m = Linear {
                speed: 4.0,
                gradient: unit(7.0 * rng.next_f64()) * 0.3,
                least_speed: 1.0,
            };
            let bound = m.least_time(from, to);
            let at = |b: Aabb, rng: &mut SplitMix64| {
                Point::new(
                    b.min.x + rng.next_f64() * (b.max.x - b.min.x),
                    b.min.y + rng.next_f64() * (b.max.y - b.min.y),
                )
            };
            for _ in 0..20 {
                let (a, b) = (at(from, &mut rng), at(to, &mut rng));
                let leg = m.leg(a.to_vec2(), b.to_vec2());
                assert!(leg.time() >= bound * (1.0 - 1e-12));
                assert!(leg.time() >= m.least_time_to(from, b) * (1.0 - 1e-12));
                for p in [leg.arrival(), leg.departure()] {
                    assert!(p.length() <= m.greatest_slowness());
                }
            }
        }
    }
}
