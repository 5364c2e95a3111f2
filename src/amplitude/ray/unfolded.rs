//! The amplitude of an image path from its unfolded line alone (no points): the closed form
//! of [`walk_reflections`](super::walk_reflections) where every bounce on one wall meets it at
//! one angle, the unfolded line's. It serves the two lattices of image sources: two parallel
//! walls (a waveguide, `trace/mirrors/waveguide.rs`: every bounce at one angle) and a
//! rectangular room (`trace/mirrors/shoebox.rs`: one angle on the x walls, another on the y
//! walls).
//!
//! A reflect-only path in one uniform medium is the straight line from the source's image,
//! so its tube's in-plane width is its unfolded length `L`, so is a point source's
//! out-of-plane width, the attenuation is `α L`, and each bounce takes its wall's
//! coefficient at the angle of incidence: the coefficient is `Π Rₖⁿᵏ` of the walls'
//! coefficients and their numbers of bounces.

use num_complex::Complex64;

use super::super::coefficients::{Weights, cos_across};
use super::{Amplitude, Walk, finish_with, medium_across};
use crate::geom::{Point, Vec2};
use crate::regions::Regions;
use crate::scene::{Amplitudes, Reflection, Scene, Step, StepKind};

/// How near `(c₂/c₁)² sin² θ` may come to 1 (the critical angle) before a checked closed
/// form declines: there `cos θ₂ = √(1 − (c₂/c₁)² sin² θ)` turns the round-off of `sin² θ`
/// (which differs between the unfolded line and the walked legs by an ulp or so) into an
/// error of about `1e-16 / √|1 − (c₂/c₁)² sin² θ|` in the coefficient, up to 1e-8 at the
/// critical angle itself (hit exactly where the geometry is a Pythagorean triple of the
/// speeds: 8, 15 and 17 for 1500 and 1700 m/s); so within `1e-4` of it the walked form.
const NEAR_CRITICAL: f64 = 1e-4;

/// One wall's coefficient as a function of the angle.
#[derive(Clone, Copy, Debug)]
enum Law {
    /// A fixed real coefficient.
    Fixed(f64),
    /// The plane-wave coefficient against one medium across, of these weights and ratio of
    /// the slownesses (`w_in / w_across`).
    Media { weights: Weights, ratio: f64 },
}

impl Law {
    /// The coefficient at the incidence cosine `cos_in` and squared sine `sin2`; `None`
    /// where `checked` and the angle lies within [`NEAR_CRITICAL`] of a critical angle.
    #[inline]
    fn at(self, cos_in: f64, sin2: f64, checked: bool) -> Option<Complex64> {
        match self {
            Law::Fixed(r) => Some(Complex64::new(r, 0.0)),
            Law::Media { weights, ratio } => {
                if checked && (ratio * ratio * sin2 - 1.0).abs() < NEAR_CRITICAL {
                    return None;
                }
                Some(weights.reflection(cos_in, cos_across(ratio, sin2)))
            }
        }
    }
}

/// `z^n` by squaring (a real `z` as [`real_power`] takes it).
#[inline]
fn power(z: Complex64, n: u64) -> Complex64 {
    if z.im == 0.0
        && let Ok(k) = u32::try_from(n)
    {
        return Complex64::new(real_power(z.re, k), 0.0);
    }
    by_squaring(z, Complex64::new(1.0, 0.0), n, |a, b| a * b)
}

/// `xⁿ` by squaring under the product `times` (`one` its unit): `out × x` where a bit of
/// `n` is set, `x × x` between bits, the products `powi` takes (compiler-builtins'
/// `__powidf2`), in line. Every power of this module is one: [`power`], [`real_power`],
/// [`real_powers`], and the lanes' ([`TreeLaws::merged_lanes`]).
#[inline(always)]
fn by_squaring<T: Copy>(mut x: T, one: T, mut n: u64, times: impl Fn(T, T) -> T) -> T {
    let mut out = one;
    loop {
        if n & 1 == 1 {
            out = times(out, x);
        }
        n >>= 1;
        if n == 0 {
            return out;
        }
        x = times(x, x);
    }
}

/// The incidence on one wall: `|cos θ|` and `sin² θ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Incidence {
    pub cos: f64,
    pub sin2: f64,
}

/// What the amplitudes of one source's image paths off `N` walls share: the walls' laws,
/// the medium's slowness and attenuation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct UnfoldedLaws<'a, const N: usize> {
    settings: &'a Amplitudes,
    laws: [Law; N],
    /// The medium's slowness and attenuation (dB per unit length).
    w0: f64,
    alpha: f64,
}

impl<'a, const N: usize> UnfoldedLaws<'a, N> {
    /// The laws of `walls` (each an interface and a segment) for paths in medium `medium`
    /// reached from `inside` (a point of the medium): `None` where the closed form does not
    /// hold for every path, so that the caller weighs each path on its own: a `"media"` wall
    /// whose medium across is unknown or not one medium along its whole interface, a medium
    /// or a wall out of range.
    pub(crate) fn new(
        scene: &Scene,
        settings: &'a Amplitudes,
        regions: Option<&Regions>,
        medium: usize,
        walls: [(usize, usize); N],
        inside: Point,
    ) -> Option<UnfoldedLaws<'a, N>> {
        let w0 = scene.media().get(medium)?.slowness;
        let mut laws = [Law::Fixed(1.0); N];
        for (law, (interface, seg)) in laws.iter_mut().zip(walls) {
            *law = match *settings.reflection.get(interface)? {
                Reflection::Fixed(r) => Law::Fixed(r),
                Reflection::Media => {
                    if regions?.interface_sides(interface).len() != 1 {
                        return None;
                    }
                    let line = &scene.interfaces().get(interface)?.polyline;
                    if seg >= line.num_segments() {
                        return None;
                    }
                    let s = line.segment(seg);
                    let middle = s.start + (s.end - s.start) * 0.5;
                    let step = Step {
                        kind: StepKind::Reflect,
                        interface,
                    };
                    let across = medium_across(regions, line, &step, seg, inside, middle)?;
                    let w_across = scene.media().get(across)?.slowness;
                    Law::Media {
                        weights: Weights::of(settings, [medium, across], [w0, w_across]),
                        ratio: w0 / w_across,
                    }
                }
            };
        }
        Some(UnfoldedLaws {
            settings,
            laws,
            w0,
            alpha: settings.attenuation.get(medium).copied()?,
        })
    }

    /// The amplitude of the image path `length` long with `reflections[k]` bounces off wall
    /// `k` (in the order of [`new`](Self::new)'s walls), each at `incidence[k]`;
    /// `axisymmetric` the out-of-plane width of an axisymmetric source (`range L / |Δx|`),
    /// unused otherwise. `None` where `checked` and a bounce lies within [`NEAR_CRITICAL`]
    /// of a `"media"` wall's critical angle: the caller then walks the path's points.
    #[inline]
    pub(crate) fn amplitude(
        &self,
        reflections: [u64; N],
        incidence: [Incidence; N],
        length: f64,
        axisymmetric: Option<f64>,
        checked: bool,
    ) -> Option<Amplitude> {
        let mut coefficient = Complex64::new(1.0, 0.0);
        for k in 0..N {
            if reflections[k] == 0 {
                continue;
            }
            let r = self.laws[k].at(incidence[k].cos, incidence[k].sin2, checked)?;
            coefficient *= power(r, reflections[k]);
        }
        let walk = Walk {
            coefficient,
            tube_num: 1.0,
            tube_den: length,
            out_of_plane: length,
            attenuation_db: self.alpha * length,
            l0: length,
            w0: self.w0,
            converted: None,
        };
        Some(finish_with(self.settings, &walk, || Ok(axisymmetric)))
    }
}

/// The bounces of an image path that meet their walls at one angle: `count` bounces off
/// interface `interface`, whose unit normal, mirrored into the frame of the path's last leg
/// (the unfolded line's), is `normal` (up to its sign; any vector where the interface's
/// coefficient does not depend on the angle). The bounce off wall `j` of `k` meets it at
/// the cosine `|d · m|` of the unfolded line's direction `d` against `m = Lₖ ⋯ Lⱼ₊₁ nⱼ`
/// (`Lᵢ` the mirroring in wall `i`'s line): the leg into wall `j` is `Lⱼ₊₁ ⋯ Lₖ d`, and
/// mirrorings keep dot products.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BounceGroup {
    pub interface: u32,
    pub count: u32,
    pub normal: Vec2,
}

/// One node's bounces as [`TreeLaws::node_amplitude`] takes them: the product of the
/// coefficients that do not depend on the angle, taken once for the node, and the groups
/// whose coefficient does, each with its law.
#[derive(Clone, Debug, Default)]
pub(crate) struct NodeBounces {
    /// The angle-free groups' coefficients' product (`None`: a group's interface is no
    /// wall, and the closed form declines).
    fixed: Option<Complex64>,
    angled: Vec<AngledGroup>,
    /// Whether the angled groups' coefficients may be merged into one quotient
    /// ([`TreeLaws::merged`]): at most [`MERGED_BOUNCES`] bounces, every group's weights
    /// positive and finite.
    merge: bool,
}

/// A group of bounces whose coefficient depends on the angle: its mirrored normal, its
/// number of bounces, its wall's weights and ratio of slownesses; for the merged form
/// ([`TreeLaws::merged`]) the weights scaled by one power of two so that the larger lies in
/// `[1, 2)`.
#[derive(Clone, Copy, Debug)]
struct AngledGroup {
    normal: Vec2,
    count: u32,
    weights: Weights,
    ratio: f64,
    scaled_a: f64,
    scaled_b: f64,
}

impl AngledGroup {
    /// The group of `g`'s bounces with its wall's `weights` and `ratio`, and whether its
    /// weights are positive, finite and scaled ([`TreeLaws::merged`] may take it).
    fn new(g: &BounceGroup, weights: Weights, ratio: f64) -> (AngledGroup, bool) {
        let big = weights.a.max(weights.b);
        let positive = |w: f64| w > 0.0 && w.is_finite();
        let scaled = positive(weights.a) && positive(weights.b) && big.is_normal();
        let scale = if big.is_normal() {
            inverse_binade(big)
        } else {
            1.0
        };
        let group = AngledGroup {
            normal: g.normal,
            count: g.count,
            weights,
            ratio,
            scaled_a: weights.a * scale,
            scaled_b: weights.b * scale,
        };
        (group, scaled)
    }
}

/// The most bounces a node's merged coefficient ([`TreeLaws::merged`]) takes.
const MERGED_BOUNCES: u32 = 50;

/// The range of each bounce's `a + b` in the merged coefficient ([`TreeLaws::merged`]; the
/// weights scaled to `[1, 2)`): outside it the path's groups are
/// taken one by one. With at most [`MERGED_BOUNCES`] bounces, every partial product of the
/// merged form's denominator then lies within `2^±850` and its numerator below it in size:
/// nothing overflows, nothing the quotient keeps underflows.
const MERGED_FACTOR: std::ops::RangeInclusive<f64> = (1.0 / 256.0)..=256.0;

/// What [`TreeLaws::merged`] finds.
enum Merged {
    /// The angled groups' coefficients' product.
    Coefficient(Complex64),
    /// A bounce within [`NEAR_CRITICAL`] of a critical angle: the path is walked.
    NearCritical,
    /// A bounce's factor outside [`MERGED_FACTOR`]: the groups are taken one by one.
    Apart,
}

/// How many paths [`TreeLaws::node_amplitudes`] takes at once.
pub(crate) const LANES: usize = 8;

/// What [`TreeLaws::merged_lanes`] finds for each of its paths: the merged coefficient, and
/// whether [`TreeLaws::merged`] finds the path [`Merged::NearCritical`] or [`Merged::Apart`].
struct MergedLanes {
    re: [f64; LANES],
    im: [f64; LANES],
    near: [bool; LANES],
    apart: [bool; LANES],
}

/// `2^-e` for the power of two `2^e ≤ x < 2^(e+1)` of a positive normal `x`, exactly.
#[inline(always)]
fn inverse_binade(x: f64) -> f64 {
    let e = (x.to_bits() >> 52) as i64 - 1023;
    f64::from_bits(((1023 - e) as u64) << 52)
}

/// `x^n` of a real `x` by squaring, as `powi` computes it (the same products, in line).
#[inline(always)]
fn real_power(x: f64, n: u32) -> f64 {
    by_squaring(x, 1.0, u64::from(n), |a, b| a * b)
}

/// Eight lanes of reals, and of complex numbers (real and imaginary parts).
type Lanes = [f64; LANES];
type ComplexLanes = (Lanes, Lanes);

/// Each lane's product, as `Complex64`'s multiplication takes it: `(a.re b.re − a.im b.im,
/// a.re b.im + a.im b.re)`.
#[inline(always)]
fn lanes_times((ar, ai): ComplexLanes, (br, bi): ComplexLanes) -> ComplexLanes {
    let (mut re, mut im) = ([0.0; LANES], [0.0; LANES]);
    for k in 0..LANES {
        re[k] = ar[k] * br[k] - ai[k] * bi[k];
        im[k] = ar[k] * bi[k] + ai[k] * br[k];
    }
    (re, im)
}

/// Each lane's two reals' products: `(a.0 b.0, a.1 b.1)`.
#[inline(always)]
fn lanes_both_times((a0, a1): ComplexLanes, (b0, b1): ComplexLanes) -> ComplexLanes {
    let (mut x, mut y) = ([0.0; LANES], [0.0; LANES]);
    for k in 0..LANES {
        x[k] = a0[k] * b0[k];
        y[k] = a1[k] * b1[k];
    }
    (x, y)
}

/// An axisymmetric source's path in closed form: the receiver's `|x|` and the first leg's
/// run along x over the unfolded line's (`|A₀ · d|`), whose out-of-plane width is
/// `|x| L / |A₀ · d|`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct AxisymmetricRun {
    pub receiver_x: f64,
    pub along: f64,
}

/// `(xⁿ, yⁿ)` of two reals, each as [`real_power`] takes it, in one loop.
#[inline(always)]
fn real_powers(x: f64, y: f64, n: u32) -> (f64, f64) {
    by_squaring((x, y), (1.0, 1.0), u64::from(n), |a, b| {
        (a.0 * b.0, a.1 * b.1)
    })
}

/// What the amplitudes of one source's image paths off any walls share (the beam tree's
/// [`UnfoldedLaws`]): each interface's law, the medium's slowness and attenuation.
#[derive(Clone, Debug)]
pub(crate) struct TreeLaws<'a> {
    settings: &'a Amplitudes,
    /// Per interface of the scene: its law, `None` where it is no wall of the tree.
    laws: Vec<Option<Law>>,
    /// The medium's slowness and attenuation (dB per unit length).
    w0: f64,
    alpha: f64,
}

impl<'a> TreeLaws<'a> {
    /// The laws of `walls` (each an interface and a segment) for paths in medium `medium`
    /// reached from `inside`, as [`UnfoldedLaws::new`] takes them (`None` where the closed
    /// form does not hold for every path).
    pub(crate) fn new(
        scene: &Scene,
        settings: &'a Amplitudes,
        regions: Option<&Regions>,
        medium: usize,
        walls: &[(usize, usize)],
        inside: Point,
    ) -> Option<TreeLaws<'a>> {
        let mut laws: Vec<Option<Law>> = vec![None; scene.interfaces().len()];
        for &(interface, seg) in walls {
            if laws.get(interface)?.is_some() {
                continue;
            }
            let one =
                UnfoldedLaws::new(scene, settings, regions, medium, [(interface, seg)], inside)?;
            laws[interface] = Some(one.laws[0]);
        }
        let w0 = scene.media().get(medium)?.slowness;
        Some(TreeLaws {
            settings,
            laws,
            w0,
            alpha: settings.attenuation.get(medium).copied()?,
        })
    }

    /// `groups` (one node's) prepared into `out` for [`node_amplitude`](Self::node_amplitude).
    pub(crate) fn prepare(&self, groups: &[BounceGroup], out: &mut NodeBounces) {
        out.angled.clear();
        let mut fixed = Complex64::new(1.0, 0.0);
        let (mut bounces, mut weighed) = (0u64, true);
        for g in groups {
            match self.laws.get(g.interface as usize).copied().flatten() {
                None => {
                    out.fixed = None;
                    return;
                }
                Some(Law::Fixed(r)) => fixed *= power(Complex64::new(r, 0.0), u64::from(g.count)),
                Some(Law::Media { weights, ratio }) => {
                    let (group, scaled) = AngledGroup::new(g, weights, ratio);
                    weighed &= scaled;
                    bounces += u64::from(g.count);
                    out.angled.push(group);
                }
            }
        }
        out.fixed = Some(fixed);
        out.merge = weighed && bounces <= u64::from(MERGED_BOUNCES);
    }

    /// The amplitude of the image path along `d` (the unfolded line, from the image to the
    /// receiver, `length` long) of the node whose bounce groups `node` holds
    /// ([`prepare`](Self::prepare)). `axisymmetric`: for an axisymmetric source, the
    /// receiver's `|x|` and the first leg's run along x over the unfolded line's, `|A₀ · d|`
    /// (the streamed tree's `TreePath::axes`), whose out-of-plane width is
    /// `|x| L / |A₀ · d|`. The angled groups' coefficients are merged into one quotient
    /// ([`merged`](Self::merged)), or, where that declines, each taken once and powered;
    /// the angle-free ones' product multiplies them. `None` where a bounce lies within
    /// [`NEAR_CRITICAL`] of a critical angle, or a group's interface is no wall: the caller
    /// then walks the path's points.
    #[inline]
    pub(crate) fn node_amplitude(
        &self,
        node: &NodeBounces,
        d: Vec2,
        length: f64,
        axisymmetric: Option<AxisymmetricRun>,
    ) -> Option<Amplitude> {
        let fixed = node.fixed?;
        let inv = 1.0 / length;
        let angled = match node.merge.then(|| Self::merged(node, d, inv)) {
            Some(Merged::Coefficient(c)) => c,
            Some(Merged::NearCritical) => return None,
            Some(Merged::Apart) | None => Self::groups_apart(node, d, inv)?,
        };
        Some(self.finished(fixed * angled, length, axisymmetric))
    }

    /// The amplitude of a path `length` long whose coefficients' product is `coefficient`
    /// ([`node_amplitude`](Self::node_amplitude)'s last step).
    #[inline(always)]
    fn finished(
        &self,
        coefficient: Complex64,
        length: f64,
        axisymmetric: Option<AxisymmetricRun>,
    ) -> Amplitude {
        // The tube `1 / (L · w)`, `w` the out-of-plane width: `L` for a point source, and
        // for an axisymmetric one `|x| L / |A₀ · d|`, i.e. `|A₀ · d| / (L² |x|)` (its
        // division, and `finish_with`'s, one).
        let (tube_num, tube_den, out) = match axisymmetric {
            Some(run) => (run.along, length * length, Some(run.receiver_x)),
            None => (1.0, length, None),
        };
        let walk = Walk {
            coefficient,
            tube_num,
            tube_den,
            out_of_plane: length,
            attenuation_db: self.alpha * length,
            l0: length,
            w0: self.w0,
            converted: None,
        };
        finish_with(self.settings, &walk, || Ok(out))
    }

    /// [`node_amplitude`](Self::node_amplitude) of up to [`LANES`] paths of one node at
    /// once, bit for bit: path `k` along `directions[k]`, `lengths[k]` long, with
    /// `axisymmetric[k]` for an axisymmetric source, its amplitude to `take(k, amplitude)`,
    /// in order, up to the first that has none (`node_amplitude`'s `None`), whose index it
    /// returns. The merged coefficients are taken for all of them together
    /// ([`merged_lanes`](Self::merged_lanes), the same operations on each path's numbers,
    /// in loops the compiler vectorises); a path whose merged form declines is taken on its
    /// own.
    #[inline(always)]
    pub(crate) fn node_amplitudes(
        &self,
        node: &NodeBounces,
        directions: &[Vec2],
        lengths: &[f64],
        axisymmetric: Option<&[AxisymmetricRun]>,
        mut take: impl FnMut(usize, Amplitude),
    ) -> Option<usize> {
        debug_assert!(directions.len() <= LANES && lengths.len() == directions.len());
        let n = directions.len().min(LANES);
        let run = |k: usize| axisymmetric.map(|runs| runs[k]);
        let (Some(fixed), true) = (node.fixed, node.merge) else {
            for k in 0..n {
                match self.node_amplitude(node, directions[k], lengths[k], run(k)) {
                    Some(amplitude) => take(k, amplitude),
                    None => return Some(k),
                }
            }
            return None;
        };
        if n == 0 {
            return None;
        }
        // The lanes past `n` repeat the first path (and are left out).
        let (mut dx, mut dy) = ([directions[0].x; LANES], [directions[0].y; LANES]);
        let mut inv = [1.0 / lengths[0]; LANES];
        for k in 0..n {
            dx[k] = directions[k].x;
            dy[k] = directions[k].y;
            inv[k] = 1.0 / lengths[k];
        }
        let merged = Self::merged_lanes(node, &dx, &dy, &inv);
        for k in 0..n {
            let amplitude = if merged.near[k] {
                None
            } else if merged.apart[k] {
                self.node_amplitude(node, directions[k], lengths[k], run(k))
            } else {
                let angled = Complex64::new(merged.re[k], merged.im[k]);
                Some(self.finished(fixed * angled, lengths[k], run(k)))
            };
            match amplitude {
                Some(amplitude) => take(k, amplitude),
                None => return Some(k),
            }
        }
        None
    }

    /// [`merged`](Self::merged) for [`LANES`] paths at once (`dx`, `dy`: their unfolded
    /// lines; `inv`: the inverses of their lengths): each group's bounce taken on every
    /// path, both forms (real and complex) with the other's factor 1 (exact: the same
    /// products as `merged` takes), powered in one loop over the count's bits. Per path
    /// the coefficient, and whether `merged` finds it [`Merged::NearCritical`] (`near`,
    /// whatever else) or [`Merged::Apart`] (`apart`).
    #[inline(always)]
    fn merged_lanes(
        node: &NodeBounces,
        dx: &[f64; LANES],
        dy: &[f64; LANES],
        inv: &[f64; LANES],
    ) -> MergedLanes {
        let (mut num, mut den) = ([1.0; LANES], [1.0; LANES]);
        let (mut pr, mut pi) = ([1.0; LANES], [0.0; LANES]);
        let (mut near, mut apart) = ([false; LANES], [false; LANES]);
        for g in &node.angled {
            // Each path's real factors `a ∓ b` (1 where complex) and complex `a + ib`
            // (1 where real).
            let (mut x, mut y) = ([1.0; LANES], [1.0; LANES]);
            let (mut zr, mut zi) = ([1.0; LANES], [0.0; LANES]);
            for k in 0..LANES {
                let d = Vec2::new(dx[k], dy[k]);
                let (c, s) = (d.dot(g.normal) * inv[k], d.cross(g.normal) * inv[k]);
                let q2 = g.ratio * g.ratio * (s * s);
                near[k] |= (q2 - 1.0).abs() < NEAR_CRITICAL;
                let a = g.scaled_a * c.abs();
                // `√(1 − q²)` or `√(q² − 1)`: the one difference up to its sign, exactly.
                let b = (1.0 - q2).abs().sqrt() * g.scaled_b;
                apart[k] |= !MERGED_FACTOR.contains(&(a + b));
                let real = q2 <= 1.0;
                x[k] = if real { a - b } else { 1.0 };
                y[k] = if real { a + b } else { 1.0 };
                zr[k] = if real { 1.0 } else { a };
                zi[k] = if real { 0.0 } else { b };
            }
            // `real_powers` and `power`, lane by lane; either left out where no path
            // needs it (its factors all 1: the same numbers).
            let n = u64::from(g.count);
            if x.iter().chain(&y).any(|&v| v != 1.0) {
                let ones = ([1.0; LANES], [1.0; LANES]);
                let powers = by_squaring((x, y), ones, n, lanes_both_times);
                (num, den) = lanes_both_times((num, den), powers);
            }
            if zr.iter().any(|&v| v != 1.0) || zi.iter().any(|&v| v != 0.0) {
                let one = ([1.0; LANES], [0.0; LANES]);
                (pr, pi) = lanes_times((pr, pi), by_squaring((zr, zi), one, n, lanes_times));
            }
        }
        let (mut re, mut im) = ([0.0; LANES], [0.0; LANES]);
        for k in 0..LANES {
            // `conj(P)² · num / (den |P|²)` as `merged` takes it.
            let (cr, ci) = (pr[k], -pi[k]);
            let (tr, ti) = (cr * cr - ci * ci, cr * ci + ci * cr);
            let bottom = den[k] * (pr[k] * pr[k] + pi[k] * pi[k]);
            re[k] = tr * num[k] / bottom;
            im[k] = ti * num[k] / bottom;
        }
        MergedLanes {
            re,
            im,
            near,
            apart,
        }
    }

    /// The angled groups' coefficients' product as one quotient, for `d` the unfolded line
    /// (`inv` the inverse of its length): with `a = A |cos θ₁|` and `b = B √(1 − q²)` (`q`
    /// the ratio of the slownesses times `sin θ₁`; the weights `A`, `B`), a real group's
    /// coefficient is `(a − b) / (a + b)`, and a complex one's (beyond the critical angle,
    /// `b = B √(q² − 1)`) `z̄ / z` with `z = a + ib`, so that the product is
    /// `Π (a − b)ⁿ · conj(P)² / (Π (a + b)ⁿ · |P|²)` with `P = Π zⁿ`: one division for the
    /// path. The cosines and `q²` are [`groups_apart`](Self::groups_apart)'s, each group's
    /// weights scaled by a power of two so that the larger lies in `[1, 2)` (exactly:
    /// `a` and `b` alike); so the same quotient as its product to round-off (a few ulps a
    /// bounce, `tests::the_merged_coefficient_is_the_groups_product`). [`Merged::Apart`]
    /// where a bounce's `a + b` leaves [`MERGED_FACTOR`].
    #[inline]
    fn merged(node: &NodeBounces, d: Vec2, inv: f64) -> Merged {
        let (mut num, mut den, mut p) = (1.0, 1.0, Complex64::new(1.0, 0.0));
        for g in &node.angled {
            let (c, s) = (d.dot(g.normal) * inv, d.cross(g.normal) * inv);
            let q2 = g.ratio * g.ratio * (s * s);
            if (q2 - 1.0).abs() < NEAR_CRITICAL {
                return Merged::NearCritical;
            }
            let a = g.scaled_a * c.abs();
            if q2 <= 1.0 {
                let b = (1.0 - q2).sqrt() * g.scaled_b;
                if !MERGED_FACTOR.contains(&(a + b)) {
                    return Merged::Apart;
                }
                let (top, bottom) = real_powers(a - b, a + b, g.count);
                num *= top;
                den *= bottom;
            } else {
                // `cos_across`'s `√(q² − 1)` where `q²` is finite.
                let b = (q2 - 1.0).sqrt() * g.scaled_b;
                if !MERGED_FACTOR.contains(&(a + b)) {
                    return Merged::Apart;
                }
                p *= power(Complex64::new(a, b), u64::from(g.count));
            }
        }
        let conj = Complex64::new(p.re, -p.im);
        let top = conj * conj * num;
        let bottom = den * p.norm_sqr();
        Merged::Coefficient(Complex64::new(top.re / bottom, top.im / bottom))
    }

    /// The angled groups' coefficients' product, each group's coefficient taken once and
    /// powered: the real ones' product first, then the complex ones'. `None` where a bounce
    /// lies within [`NEAR_CRITICAL`] of a critical angle.
    fn groups_apart(node: &NodeBounces, d: Vec2, inv: f64) -> Option<Complex64> {
        let mut coefficient = Complex64::new(1.0, 0.0);
        let mut real = 1.0;
        for g in &node.angled {
            let (c, s) = (d.dot(g.normal) * inv, d.cross(g.normal) * inv);
            let sin2 = s * s;
            let q2 = g.ratio * g.ratio * sin2;
            if (q2 - 1.0).abs() < NEAR_CRITICAL {
                return None;
            }
            if q2 <= 1.0 {
                // `Weights::reflection` with a real `cos θ₂`, as `cos_across` gives it.
                let (a, b) = (g.weights.a * c.abs(), (1.0 - q2).sqrt() * g.weights.b);
                real *= real_power((a - b) / (a + b), g.count);
            } else {
                let r = g.weights.reflection(c.abs(), cos_across(g.ratio, sin2));
                coefficient *= power(r, u64::from(g.count));
            }
        }
        Some(coefficient * real)
    }

    /// Whether the coefficient of `interface` depends on the angle (`false` also for an
    /// interface that is no wall).
    pub(crate) fn angled(&self, interface: usize) -> bool {
        matches!(self.laws.get(interface), Some(Some(Law::Media { .. })))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::amplitude::NoAmplitude;
    use crate::scene::{Polarization, SourceModel, Waves};

    /// Uniform numbers in `[0, 1)` from a linear congruential generator seeded `state`.
    fn uniform(mut state: u64) -> impl FnMut() -> f64 {
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// A random node of one to six angled groups (at most [`MERGED_BOUNCES`] bounces, as
    /// `prepare` has it): random normals, counts up to 12, weights whose ratio goes up to
    /// 1e6 either way, slownesses' ratios on both sides of 1.
    fn random_node(next: &mut impl FnMut() -> f64) -> NodeBounces {
        let groups = 1 + (next() * 6.0) as usize;
        let mut node = NodeBounces {
            fixed: Some(Complex64::new(1.0, 0.0)),
            angled: Vec::new(),
            merge: true,
        };
        let mut bounces = 0u32;
        for _ in 0..groups {
            let t = next() * std::f64::consts::TAU;
            let count = 1 + (next() * 12.0) as u32;
            let g = BounceGroup {
                interface: 0,
                count,
                normal: Vec2::new(t.cos(), t.sin()),
            };
            let scale = 10f64.powf(next() * 8.0 - 4.0);
            let weights = Weights {
                a: scale * 10f64.powf(next() * 6.0 - 3.0),
                b: scale * 10f64.powf(next() * 6.0 - 3.0),
                n: 1.0,
            };
            let (group, scaled) = AngledGroup::new(&g, weights, 0.6 + next() * 0.8);
            assert!(scaled);
            if bounces + count <= MERGED_BOUNCES {
                bounces += count;
                node.angled.push(group);
            }
        }
        node
    }

    /// The bits of an amplitude (every number, and the reason).
    fn bits(a: &Amplitude) -> ([u64; 6], Option<NoAmplitude>) {
        let numbers = [
            a.value.re,
            a.value.im,
            a.spreading,
            a.coefficient.re,
            a.coefficient.im,
            a.attenuation_db,
        ];
        (numbers.map(f64::to_bits), a.reason)
    }

    /// [`TreeLaws::node_amplitudes`] against [`TreeLaws::node_amplitude`] path by path, bit
    /// for bit: random nodes ([`random_node`]; some whose fixed factor is not 1, some not
    /// merged, some whose interface is no wall), one to eight paths each along random lines
    /// (some sharing an angle, so that a run declines part way), every source model, with
    /// and without attenuation. The same amplitudes, and the same first path without one.
    #[test]
    fn the_lanes_are_each_paths_amplitude_bit_for_bit() {
        let mut next = uniform(0x9e37_79b9_7f4a_7c15);
        let (mut taken, mut declined, mut apart, mut complex) = (0, 0, 0, 0);
        for source in [
            SourceModel::Point,
            SourceModel::Axisymmetric,
            SourceModel::Line,
        ] {
            for alpha in [0.0, 3e-3] {
                let settings = Amplitudes {
                    source,
                    frequency: Some(100.0),
                    polarization: Polarization::S,
                    waves: Waves::Fluid,
                    density: vec![1.0],
                    attenuation: vec![alpha],
                    attenuation_per_wavelength: vec![None],
                    attenuates: alpha > 0.0,
                    reflection: Vec::new(),
                };
                let laws = TreeLaws {
                    settings: &settings,
                    laws: Vec::new(),
                    w0: 1.0 / 1500.0,
                    alpha,
                };
                for _ in 0..8_000 {
                    let mut node = random_node(&mut next);
                    match (next() * 8.0) as u32 {
                        0 => node.merge = false,
                        1 => node.fixed = None,
                        2 => node.fixed = Some(Complex64::new(-0.7, 0.2)),
                        _ => {}
                    }
                    let n = 1 + (next() * LANES as f64) as usize;
                    let shared = next() * std::f64::consts::TAU;
                    let (mut directions, mut lengths, mut runs) = (vec![], vec![], vec![]);
                    for _ in 0..n {
                        let t = if next() < 0.3 {
                            shared
                        } else {
                            next() * std::f64::consts::TAU
                        };
                        let length = 10f64.powf(next() * 4.0);
                        directions.push(Vec2::new(t.cos(), t.sin()) * length);
                        lengths.push(length);
                        runs.push(AxisymmetricRun {
                            receiver_x: 10f64.powf(next() * 4.0),
                            along: next() * length,
                        });
                    }
                    let axisymmetric =
                        (source == SourceModel::Axisymmetric).then_some(runs.as_slice());
                    let run = |k: usize| axisymmetric.map(|r| r[k]);
                    let mut got = Vec::new();
                    let first_none =
                        laws.node_amplitudes(&node, &directions, &lengths, axisymmetric, |k, a| {
                            got.push((k, bits(&a)))
                        });
                    let mut want = Vec::new();
                    let mut want_none = None;
                    for k in 0..n {
                        let (d, l) = (directions[k], lengths[k]);
                        match laws.node_amplitude(&node, d, l, run(k)) {
                            Some(a) => {
                                complex += usize::from(a.coefficient.im != 0.0);
                                want.push((k, bits(&a)));
                            }
                            None => {
                                want_none = Some(k);
                                break;
                            }
                        }
                        if node.merge
                            && matches!(TreeLaws::merged(&node, d, 1.0 / l), Merged::Apart)
                        {
                            apart += 1;
                        }
                    }
                    assert_eq!(got, want);
                    assert_eq!(first_none, want_none);
                    taken += got.len();
                    declined += usize::from(first_none.is_some());
                }
            }
        }
        assert!(
            taken > 50_000 && declined > 2_000 && apart > 100 && complex > 5_000,
            "{taken} {declined} {apart} {complex}"
        );
    }

    /// The merged quotient against the groups' product, each group's coefficient taken and
    /// powered on its own, on random nodes: one to six groups (up to 50 bounces), random
    /// normals, lines and weights (their ratio up to 1e6 either way, so that some bounce's
    /// `a + b` leaves [`MERGED_FACTOR`] and the merged form declines: the groups are then
    /// taken apart), slownesses' ratios on both sides of 1 (bounces beyond the critical
    /// angle: complex coefficients). Where both give a number, they agree to a few ulps a
    /// bounce of the coefficient's size (the inputs `a ± b` are the same numbers, scaled by
    /// powers of two); where one declines near a critical angle, so does the other.
    #[test]
    fn the_merged_coefficient_is_the_groups_product() {
        let mut next = uniform(0x2545_f491_4f6c_dd1d);
        let (mut compared, mut complex, mut apart, mut critical) = (0, 0, 0, 0);
        for _ in 0..200_000 {
            let node = random_node(&mut next);
            let t = next() * std::f64::consts::TAU;
            let length = 10f64.powf(next() * 4.0);
            let d = Vec2::new(t.cos(), t.sin()) * length;
            let inv = 1.0 / d.dot(d).sqrt();
            let want = TreeLaws::groups_apart(&node, d, inv);
            match (TreeLaws::merged(&node, d, inv), want) {
                (Merged::Coefficient(got), Some(want)) => {
                    let n: u32 = node.angled.iter().map(|g| g.count).sum();
                    let tol = 4.0 * f64::from(n + 2) * f64::EPSILON * want.norm().max(1e-290);
                    assert!((got - want).norm() <= tol, "{got} vs {want} ({n} bounces)");
                    compared += 1;
                    complex += usize::from(want.im != 0.0);
                }
                (Merged::NearCritical, None) => critical += 1,
                (Merged::Apart, _) => apart += 1,
                (m, w) => panic!("{:?} vs {w:?}", matches!(m, Merged::NearCritical)),
            }
        }
        assert!(
            compared > 100_000 && complex > 10_000,
            "{compared} {complex}"
        );
        assert!(apart > 100 && critical > 20, "{apart} {critical}");
    }
}
