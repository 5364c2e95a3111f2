//! The amplitude of a path between two parallel walls from its unfolded line alone (no
//! points): the closed form of [`walk_reflections`](super::walk_reflections) where every
//! bounce on one wall meets it at one angle, the unfolded line's.
//!
//! A reflect-only path in one uniform medium is the straight line from the source's image,
//! so its tube's in-plane width is its unfolded length `L`, so is a point source's
//! out-of-plane width, the attenuation is `α L`, and each bounce takes its wall's
//! coefficient at the angle of incidence. Between two parallel walls that angle is the
//! same at every bounce, `cos θ = |across| / L`, `sin² θ = (along / L)²`: the coefficient is
//! `R₀ⁿ⁰ R₁ⁿ¹` of the two walls' coefficients and their numbers of bounces.

use num_complex::Complex64;

use super::super::coefficients::{Weights, cos_across};
use super::{Amplitude, Walk, finish_with};
use crate::regions::Regions;
use crate::scene::{Amplitudes, Reflection, Scene};

/// How near `(c₂/c₁)² sin² θ` may come to 1 (the critical angle) before the closed form
/// declines: there `cos θ₂ = √(1 − (c₂/c₁)² sin² θ)` turns the round-off of `sin² θ` (which
/// differs between the unfolded line and the walked legs by an ulp or so) into an error of
/// about `1e-16 / √|1 − (c₂/c₁)² sin² θ|` in the coefficient, up to 1e-8 at the critical
/// angle itself (hit exactly where the geometry is a Pythagorean triple of the speeds: 8,
/// 15 and 17 for 1500 and 1700 m/s); so within `1e-4` of it the walked form, to the bit.
const NEAR_CRITICAL: f64 = 1e-4;

/// One wall's coefficient as a function of the angle.
#[derive(Clone, Copy, Debug)]
enum Law {
    /// A fixed real coefficient.
    Fixed(f64),
    /// The plane-wave coefficient against one medium across, of these weights and speed
    /// ratio (`w_in / w_across`).
    Media { weights: Weights, ratio: f64 },
}

/// What the amplitudes of one source's paths between two parallel walls share: the walls'
/// laws, the medium's slowness and attenuation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Unfolded<'a> {
    settings: &'a Amplitudes,
    laws: [Law; 2],
    /// The medium's slowness and attenuation (dB per unit length).
    w0: f64,
    alpha: f64,
}

/// `z^n` by squaring (`n` small: the bounces on one wall).
#[inline]
fn power(z: Complex64, n: usize) -> Complex64 {
    if z.im == 0.0 {
        return Complex64::new(z.re.powi(n as i32), 0.0);
    }
    let (mut base, mut n, mut out) = (z, n, Complex64::new(1.0, 0.0));
    while n > 0 {
        if n & 1 == 1 {
            out *= base;
        }
        base *= base;
        n >>= 1;
    }
    out
}

impl<'a> Unfolded<'a> {
    /// The closed form for paths in medium `medium` between walls on interfaces
    /// `interfaces` (each one segment, the index 0), reached from `inside` (a point between
    /// them): `None` where it does not hold for every path, so that the caller weighs each
    /// path on its own: a `"media"` wall whose medium across is unknown or not one medium
    /// along the whole wall, a medium out of range, more bounces than an `i32`.
    pub(crate) fn new(
        scene: &Scene,
        settings: &'a Amplitudes,
        regions: Option<&Regions>,
        medium: usize,
        interfaces: [usize; 2],
        inside: crate::geom::Point,
    ) -> Option<Unfolded<'a>> {
        let w0 = scene.media().get(medium)?.slowness;
        let mut laws = [Law::Fixed(1.0); 2];
        for (law, &interface) in laws.iter_mut().zip(&interfaces) {
            *law = match *settings.reflection.get(interface)? {
                Reflection::Fixed(r) => Law::Fixed(r),
                Reflection::Media => {
                    let regions = regions?;
                    if regions.interface_sides(interface).len() != 1 {
                        return None;
                    }
                    let line = &scene.interfaces()[interface].polyline;
                    if line.num_segments() != 1 {
                        return None;
                    }
                    let a = line.segment(0).start;
                    let s = line.start(0) + (inside - a).dot(line.tangent(0));
                    let across = regions.medium_across(interface, 0, s, inside)?;
                    let w_across = scene.media().get(across)?.slowness;
                    Law::Media {
                        weights: Weights::of(settings, [medium, across], [w0, w_across]),
                        ratio: w0 / w_across,
                    }
                }
            };
        }
        Some(Unfolded {
            settings,
            laws,
            w0,
            alpha: settings.attenuation.get(medium).copied()?,
        })
    }

    /// The amplitude of the path of `hits` bounces on each wall whose unfolded line is
    /// `length` long, `along` the walls and `across` them (magnitudes); `axisymmetric` the
    /// out-of-plane width of an axisymmetric source (`range L / |Δx|`), unused otherwise.
    /// `None` where `checked` and a bounce lies within [`NEAR_CRITICAL`] of a `"media"`
    /// wall's critical angle: the caller then walks the path's points.
    #[inline]
    pub(crate) fn amplitude(
        &self,
        hits: [usize; 2],
        length: f64,
        along: f64,
        across: f64,
        axisymmetric: Option<f64>,
        checked: bool,
    ) -> Option<Amplitude> {
        let mut coefficient = Complex64::new(1.0, 0.0);
        if hits != [0, 0] {
            let cos_in = across / length;
            let sin = along / length;
            let sin2 = sin * sin;
            for (law, &n) in self.laws.iter().zip(&hits) {
                if n == 0 {
                    continue;
                }
                let r = match *law {
                    Law::Fixed(r) => Complex64::new(r, 0.0),
                    Law::Media { weights, ratio } => {
                        if checked && (ratio * ratio * sin2 - 1.0).abs() < NEAR_CRITICAL {
                            return None;
                        }
                        weights.reflection(cos_in, cos_across(ratio, sin2))
                    }
                };
                coefficient *= power(r, n);
            }
        }
        let walk = Walk {
            coefficient,
            tube_num: 1.0,
            tube_den: length,
            out_of_plane: length,
            attenuation_db: self.alpha * length,
            l0: f64::NAN,
            w0: self.w0,
            converted: None,
        };
        Some(finish_with(self.settings, &walk, axisymmetric))
    }
}
