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

/// `z^n` by squaring (a real `z` by `powi`).
#[inline]
fn power(z: Complex64, n: u64) -> Complex64 {
    if z.im == 0.0
        && let Ok(k) = i32::try_from(n)
    {
        return Complex64::new(z.re.powi(k), 0.0);
    }
    let (mut base, mut n, mut out) = (z, n, Complex64::new(1.0, 0.0));
    while n > 0 {
        if n & 1 == 1 {
            out *= base;
        }
        n >>= 1;
        if n > 0 {
            base *= base;
        }
    }
    out
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
}

/// A group of bounces whose coefficient depends on the angle: its mirrored normal, its
/// number of bounces, its wall's weights and ratio of slownesses.
#[derive(Clone, Copy, Debug)]
struct AngledGroup {
    normal: Vec2,
    count: u32,
    weights: Weights,
    ratio: f64,
}

/// `x^n` of a real `x` by squaring, as `powi` computes it (the same products, in line).
#[inline(always)]
fn real_power(x: f64, n: u32) -> f64 {
    let (mut base, mut n, mut out) = (x, n, 1.0);
    loop {
        if n & 1 == 1 {
            out *= base;
        }
        n >>= 1;
        if n == 0 {
            return out;
        }
        base *= base;
    }
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
        for g in groups {
            match self.laws.get(g.interface as usize).copied().flatten() {
                None => {
                    out.fixed = None;
                    return;
                }
                Some(Law::Fixed(r)) => fixed *= power(Complex64::new(r, 0.0), u64::from(g.count)),
                Some(Law::Media { weights, ratio }) => out.angled.push(AngledGroup {
                    normal: g.normal,
                    count: g.count,
                    weights,
                    ratio,
                }),
            }
        }
        out.fixed = Some(fixed);
    }

    /// The amplitude of the image path along `d` (the unfolded line, from the image to the
    /// receiver, `length` long) of the node whose bounce groups `node` holds
    /// ([`prepare`](Self::prepare)); `axisymmetric` as in [`UnfoldedLaws::amplitude`]. Each
    /// group's coefficient is taken once and powered; the angle-free ones' product comes
    /// first, then the real ones', then the complex ones'. `None` where a bounce lies within
    /// [`NEAR_CRITICAL`] of a critical angle, or a group's interface is no wall: the caller
    /// then walks the path's points.
    #[inline]
    pub(crate) fn node_amplitude(
        &self,
        node: &NodeBounces,
        d: Vec2,
        length: f64,
        axisymmetric: Option<f64>,
    ) -> Option<Amplitude> {
        let inv = 1.0 / length;
        let mut coefficient = node.fixed?;
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
        let walk = Walk {
            coefficient: coefficient * real,
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

    /// Whether the coefficient of `interface` depends on the angle (`false` also for an
    /// interface that is no wall).
    pub(crate) fn angled(&self, interface: usize) -> bool {
        matches!(self.laws.get(interface), Some(Some(Law::Media { .. })))
    }
}
