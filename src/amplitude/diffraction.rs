//! Edge diffraction at a polyline vertex: the wedge a vertex makes, the Fresnel integral, and
//! the uniform (UTD) wedge coefficient of Kouyoumjian and Pathak (1974) for an edge normal to
//! the plane, written for the time factor `e^(−iωt)` (the complex conjugate of their
//! `e^(jωt)` form).
//!
//! A diffracted path is its pieces (the specular paths between the source, its vertices and
//! its receiver), each walked as a path of its own (`walk_piece`); its amplitude is the
//! incident amplitude at the first vertex × the wedge coefficient `D` × the spreading from the
//! vertex, piece after piece:
//!
//! - in the plane the wave leaves a vertex as a cylindrical wave, so the in-plane tube
//!   factors of the pieces multiply (`Π Gⱼ`, `G = 1/ℓ` for a straight leg);
//! - out of the plane (`point`, `axisymmetric`) the width runs on from the source through the
//!   vertices as through a specular path (`Y`, the whole path's), which gives
//!   `√(r₀ / (r (r + r₀)))` for one diffraction of a direct wave;
//! - the spreading is then that of `ray::finish`'s form with the tube `Π Gⱼ`, and
//!   the coefficient the product of the pieces' coefficients and of each vertex's `D` (which
//!   carries the units `length^½`).
//!
//! The transition function's distance parameter is `L = r₀ r / (r₀ + r)` with `r₀ = 1/G` of
//! the piece before the vertex and `r = 1/G` of the piece after it: the in-plane distances of
//! the incident wave's centre and of the receiver (unfolded through flat reflections). For
//! one diffraction this makes the total field continuous across every shadow and reflection
//! boundary.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use num_complex::Complex64;

use super::ray::{PathGeometry, out_of_plane_axisymmetric, positive_finite, walk_piece};
use super::{Amplitude, DiffractionCase, NoAmplitude};
use crate::geom::{Point, Vec2};
use crate::regions::Regions;
use crate::scene::{Amplitudes, Reflection, Scene, SourceModel, Step};

/// The wedge a polyline vertex makes, seen from one side: its first face's direction from the
/// vertex, and its exterior angle `α` (`nπ` in UTD's notation; 2π at an open end).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Wedge {
    /// The unit direction of face 0 from the vertex (angles are measured from it,
    /// counter-clockwise, through the exterior).
    pub face: Vec2,
    /// The exterior angle, in (0, 2π].
    pub angle: f64,
}

/// The counter-clockwise angle from unit vector `from` to vector `to`, in [0, 2π).
fn angle_from(from: Vec2, to: Vec2) -> f64 {
    let a = from.cross(to).atan2(from.dot(to));
    if a < 0.0 { a + TAU } else { a }
}

impl Wedge {
    /// The wedge of vertex `vertex` of `points` (a polyline's vertices, `closed` or not) on
    /// the side that holds the direction `toward` (from the vertex): at an open end the whole
    /// plane.
    pub(crate) fn at(points: &[Point], closed: bool, vertex: usize, toward: Vec2) -> Wedge {
        let n = points.len();
        let v = points[vertex];
        let prev = if vertex > 0 {
            Some(points[vertex - 1])
        } else if closed {
            Some(points[n - 1])
        } else {
            None
        };
        let next = if vertex + 1 < n {
            Some(points[vertex + 1])
        } else if closed {
            Some(points[0])
        } else {
            None
        };
        let unit = |p: Point| {
            let d = p - v;
            d * (1.0 / d.length())
        };
        match (prev, next) {
            (Some(a), Some(b)) => {
                let (ea, eb) = (unit(a), unit(b));
                let gamma = angle_from(ea, eb);
                if angle_from(ea, toward) <= gamma {
                    Wedge {
                        face: ea,
                        angle: gamma,
                    }
                } else {
                    Wedge {
                        face: eb,
                        angle: TAU - gamma,
                    }
                }
            }
            (Some(a), None) | (None, Some(a)) => Wedge {
                face: unit(a),
                angle: TAU,
            },
            (None, None) => Wedge {
                face: Vec2::new(1.0, 0.0),
                angle: TAU,
            },
        }
    }

    /// The angle of direction `d` from face 0 through the exterior, when `d` points into the
    /// exterior (within `slack` rad of it): in [0, α].
    pub(crate) fn angle_of(&self, d: Vec2, slack: f64) -> Option<f64> {
        let a = angle_from(self.face, d);
        if a <= self.angle {
            Some(a)
        } else if a >= TAU - slack {
            Some(0.0)
        } else if a <= self.angle + slack {
            Some(self.angle)
        } else {
            None
        }
    }
}

/// `∫_a^∞ e^(iτ²) dτ` for `a ≥ 0`, through the Fresnel integrals
/// `C(u) + i S(u) = ∫₀^u e^(iπt²/2) dt` at `u = a √(2/π)`: their power series for `u ≤ 1.5`,
/// and beyond, the continued fraction of the complement (evaluated by Lentz's method), which
/// keeps its relative accuracy where the integral is small. About 1e-15 relative.
pub fn fresnel_tail(a: f64) -> Complex64 {
    let u = a * (2.0 / PI).sqrt();
    let half = Complex64::new(0.5, 0.5);
    let scale = FRAC_PI_2.sqrt();
    if u <= 1.5 {
        // The series: C = Σ (−1)ᵏ (π/2)²ᵏ u⁴ᵏ⁺¹ / ((2k)! (4k+1)), S likewise with odd powers.
        let x = FRAC_PI_2 * u * u;
        let (mut c, mut s) = (0.0, 0.0);
        let mut term = u; // (π/2 u²)^j u / j!
        let mut j = 0u32;
        loop {
            let contribution = term / f64::from(2 * j + 1);
            match j % 4 {
                0 => c += contribution,
                1 => s += contribution,
                2 => c -= contribution,
                _ => s -= contribution,
            }
            j += 1;
            term *= x / f64::from(j);
            if term < 1e-17 * (c.abs() + s.abs()) || j > 200 {
                break;
            }
        }
        return (half - Complex64::new(c, s)) * scale;
    }
    // Complement: (1 + i)/2 · e^(iπu²/2) · h, h the continued fraction (Numerical Recipes'
    // `frenel`, kept as the complement).
    let pix2 = PI * u * u;
    let tiny = 1e-300;
    let mut b = Complex64::new(1.0, -pix2);
    let mut cc = Complex64::new(1.0 / tiny, 0.0);
    let mut d = b.inv();
    let mut h = d;
    let mut n = -1.0;
    for _ in 2..400 {
        n += 2.0;
        let a = -n * (n + 1.0);
        b += 4.0;
        d = (d * a + b).inv();
        cc = b + cc.inv() * a;
        let del = cc * d;
        h *= del;
        if (del.re - 1.0).abs() + del.im.abs() < 1e-16 {
            break;
        }
    }
    h *= Complex64::new(u, -u);
    half * Complex64::from_polar(1.0, 0.5 * pix2) * h * scale
}

/// The spacing of [`scaled_tail`]'s table of `h(a) = e^(−ia²) ∫_a^∞ e^(iτ²) dτ`.
const TAIL_STEP: f64 = 1.0 / 32.0;

/// Nodes of [`scaled_tail`]'s table: `a` from 0 to `√50` and a node beyond.
const TAIL_NODES: usize = 228;

/// `h(a) = e^(−ia²) ∫_a^∞ e^(iτ²) dτ` for `0 ≤ a ≤ 7.1`: the Taylor series about the nearest
/// node of a table (filled once from [`fresnel_tail`]), whose coefficients follow from
/// `h′ = −1 − 2ia h` (`h⁽ᵐ⁺¹⁾ = −2i (m h⁽ᵐ⁻¹⁾ + a h⁽ᵐ⁾)`); `h` does not oscillate, and
/// `|2a δ| ≤ 0.23` at `|δ| ≤ 1/64` makes ten or so terms reach round-off. Within
/// `3e-15 (1 + a²)` relative of [`fresnel_tail`] and of 20-digit values (the conditioning of `e^(ia²)`), several times
/// faster than its series and continued fraction.
fn scaled_tail(a: f64) -> Complex64 {
    static TABLE: std::sync::OnceLock<Vec<Complex64>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        (0..TAIL_NODES)
            .map(|j| {
                let a0 = j as f64 * TAIL_STEP;
                Complex64::from_polar(1.0, -a0 * a0) * fresnel_tail(a0)
            })
            .collect()
    });
    let j = ((a / TAIL_STEP).round() as usize).min(TAIL_NODES - 1);
    let a0 = j as f64 * TAIL_STEP;
    let d = a - a0;
    let minus_2i_d = Complex64::new(0.0, -2.0 * d);
    // tₘ = h⁽ᵐ⁾(a₀) δᵐ / m!: t₁ = (−1 − 2ia₀h)δ, tₘ₊₁ = −2iδ (δ tₘ₋₁ + a₀ tₘ)/(m + 1).
    let mut before = table[j];
    let mut term = (Complex64::new(0.0, -2.0 * a0) * before - 1.0) * d;
    let mut sum = before + term;
    for m in 1..40 {
        let next = minus_2i_d * (before * d + term * a0) / f64::from(m + 1);
        sum += next;
        before = term;
        term = next;
        if term.norm_sqr() + before.norm_sqr() < 1e-36 * sum.norm_sqr() {
            break;
        }
    }
    sum
}

/// The UTD transition function for `e^(−iωt)`: `F(X) = −2i √X e^(−iX) ∫_√X^∞ e^(iτ²) dτ`
/// (`X ≥ 0`; 1 far from the boundaries, `√(πX) e^(−iπ/4)` near them). From `X = 50` on, its
/// asymptotic series `Σ (2n − 1)!! (−i/2X)ⁿ`, whose terms fall below 1e-17 before they grow
/// there (most receivers lie far from the boundaries); below, `−2i √X h(√X)` with
/// `h(a) = e^(−ia²) ∫_a^∞ e^(iτ²) dτ` from a table and its Taylor series.
pub fn transition(x: f64) -> Complex64 {
    if x >= 50.0 {
        // The n-th term is (2n − 1)!!/(2X)ⁿ times (−i)ⁿ: its size a real recurrence, its
        // phase the n-th quarter turn.
        let (mut re, mut im) = (1.0, 0.0);
        let mut size = 1.0;
        for n in 1..60u32 {
            size *= f64::from(2 * n - 1) * (0.5 / x);
            match n % 4 {
                1 => im -= size,
                2 => re -= size,
                3 => im += size,
                _ => re += size,
            }
            if size < 1e-17 {
                break;
            }
        }
        return Complex64::new(re, im);
    }
    let a = x.max(0.0).sqrt();
    Complex64::new(0.0, -2.0 * a) * scaled_tail(a)
}

/// The faces' boundary condition.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Faces {
    /// `rigid` (Neumann: `∂p/∂n = 0`, the hard coefficient `D_h`).
    Rigid,
    /// `pressure-release` (Dirichlet: `p = 0`, the soft coefficient `D_s`).
    PressureRelease,
}

/// The UTD wedge coefficient `D(φ, φ′)` of a wedge of exterior angle `angle` (`nπ`) for a
/// wavenumber `k`, the distance parameter `l` (`L`), the incidence angle `phi_in` (`φ′`) and
/// the diffraction angle `phi` (`φ`), both from face 0 through the exterior:
///
/// `D = −e^(iπ/4) / (2n √(2πk)) [cot((π + β⁻)/2n) F(kL a⁺(β⁻)) + cot((π − β⁻)/2n) F(kL a⁻(β⁻))
///  ∓ (the same at β⁺)]`, `β∓ = φ ∓ φ′`, `a±(β) = 2 cos²((2nπN± − β)/2)` with `N±` the
/// integers nearest to `(β ± π)/(2nπ)`; `−` for pressure-release faces, `+` for rigid ones.
/// A term exactly on its boundary (`a = 0`) is its limit from the shadow side of that
/// boundary, `−2n √(πkL/2) e^(−iπ/4)`: ray theory lists no arrival exactly on a boundary (the
/// reflection there is held on the vertex, a `vertex` path without an amplitude; the direct
/// ray through the vertex touches the face), so the total field there is the shadow side's,
/// continuous with both sides.
pub fn wedge_coefficient(
    angle: f64,
    k: f64,
    l: f64,
    phi_in: f64,
    phi: f64,
    faces: Faces,
) -> Complex64 {
    let n = angle / PI;
    let term = |beta: f64, sign: f64| -> Complex64 {
        // sign +1: cot((π + β)/2n) F(kL a⁺(β)); −1: cot((π − β)/2n) F(kL a⁻(β)).
        let big_n = ((beta + sign * PI) / (2.0 * n * PI)).round();
        let half = (2.0 * n * PI * big_n - beta) / 2.0;
        let a = 2.0 * half.cos().powi(2);
        let arg = (PI + sign * beta) / (2.0 * n);
        let s = arg.sin();
        if s == 0.0 || a == 0.0 {
            // cot → 2n/ε, F → √(πkL/2) |ε| e^(−iπ/4): the shadow side's ε < 0 for each of
            // the four terms' boundaries (docs/method.md).
            return Complex64::from_polar(-2.0 * n * (PI * k * l / 2.0).sqrt(), -PI / 4.0);
        }
        transition(k * l * a) * (arg.cos() / s)
    };
    let minus = phi - phi_in;
    let plus = phi + phi_in;
    let incident = term(minus, 1.0) + term(minus, -1.0);
    let reflected = term(plus, 1.0) + term(plus, -1.0);
    let sum = match faces {
        Faces::Rigid => incident + reflected,
        Faces::PressureRelease => incident - reflected,
    };
    let front = -Complex64::from_polar(1.0, PI / 4.0) / (2.0 * n * (TAU * k).sqrt());
    front * sum
}

/// The faces of `interface` under the scene's amplitude settings, or why its vertices have
/// no coefficient.
fn faces_of(settings: &Amplitudes, interface: usize) -> Result<Faces, DiffractionCase> {
    match settings.reflection[interface] {
        Reflection::Fixed(1.0) => Ok(Faces::Rigid),
        Reflection::Fixed(-1.0) => Ok(Faces::PressureRelease),
        Reflection::Fixed(_) => Err(DiffractionCase::AbsorbingFace),
        Reflection::Media => Err(DiffractionCase::PenetrableFace),
    }
}

/// The amplitude of a `converged` diffracted path (`steps` with at least one `diffract`),
/// its points and leg media: the pieces' walks composed with each vertex's wedge coefficient.
pub(crate) fn of_diffracted(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Amplitude {
    match diffracted(scene, settings, regions, path) {
        Ok(a) => a,
        Err(reason) => Amplitude::none(reason),
    }
}

/// [`of_diffracted`], its failures as errors.
fn diffracted(
    scene: &Scene,
    settings: &Amplitudes,
    regions: Option<&Regions>,
    path: PathGeometry<'_>,
) -> Result<Amplitude, NoAmplitude> {
    let (steps, points, media) = (path.steps, path.points, path.media);
    let k = steps.len();
    if points.len() != k + 2 || media.len() != k + 1 {
        return Err(NoAmplitude::UnknownMedia);
    }
    let mut coefficient = Complex64::new(1.0, 0.0);
    let (mut tube, mut out_of_plane, mut attenuation_db) = (1.0, 0.0, 0.0);
    let (mut first_l0, mut first_w0) = (0.0, 0.0);
    // The previous piece's in-plane distance (1/G) and the index of the step that ends it.
    let mut before: Option<(f64, usize)> = None;
    let mut start = 0;
    for end in (0..k)
        .filter(|&i| steps[i].kind.vertex().is_some())
        .chain([k])
    {
        let piece = PathGeometry {
            steps: &steps[start..end],
            points: &points[start..end + 2],
            media: &media[start..end + 1],
            segments: path
                .segments
                .map(|s| &s[start.min(s.len())..end.min(s.len())]),
        };
        let walk = walk_piece(scene, settings, regions, piece).map_err(|r| shift(r, start))?;
        let r = 1.0 / walk.tube;
        if let Some((r0, i)) = before {
            coefficient *= vertex_coefficient(scene, settings, steps[i], i, points, media, r0, r)?;
        } else {
            (first_l0, first_w0) = (walk.l0, walk.w0);
        }
        coefficient *= walk.coefficient;
        tube *= walk.tube;
        out_of_plane += walk.out_of_plane * (first_w0 / walk.w0);
        attenuation_db += walk.attenuation_db;
        before = Some((r, end));
        start = end + 1;
    }
    let quarter = 0.25 / PI;
    let (out, scale) = match settings.source {
        SourceModel::Point => (out_of_plane, quarter),
        SourceModel::Axisymmetric => match out_of_plane_axisymmetric(points, first_l0)? {
            Some(y) => (y, quarter),
            None => (out_of_plane, quarter),
        },
        SourceModel::Line => {
            let k0 = 2.0 * PI * settings.frequency.unwrap_or(f64::NAN) * first_w0;
            (k0, 1.0 / (8.0 * PI).sqrt())
        }
    };
    let spreading = (tube / out).sqrt() * scale;
    if !positive_finite(spreading) {
        return Err(NoAmplitude::Caustic);
    }
    let mut size = spreading;
    if attenuation_db > 0.0 {
        size *= (attenuation_db * (-std::f64::consts::LN_10 / 20.0)).exp();
    }
    let value = match settings.source {
        SourceModel::Line => {
            let h = std::f64::consts::FRAC_1_SQRT_2 * size;
            coefficient * Complex64::new(h, h)
        }
        SourceModel::Point | SourceModel::Axisymmetric => coefficient * size,
    };
    Ok(Amplitude {
        value,
        spreading,
        coefficient,
        attenuation_db,
        reason: None,
    })
}

/// A piece's reason with its step and leg indices made the whole path's (`start` the index
/// of the piece's first step).
fn shift(r: NoAmplitude, start: usize) -> NoAmplitude {
    match r {
        NoAmplitude::ConvertedReflection { step } => {
            NoAmplitude::ConvertedReflection { step: step + start }
        }
        NoAmplitude::NoMediumAcross { step } => NoAmplitude::NoMediumAcross { step: step + start },
        NoAmplitude::Grazing { step } => NoAmplitude::Grazing { step: step + start },
        NoAmplitude::VanishedLeg { leg } => NoAmplitude::VanishedLeg { leg: leg + start },
        other => other,
    }
}

/// The wedge coefficient of diffraction step `i` (its point `points[i + 1]`), the incident
/// wave's in-plane distance `r0` and the receiver's (or the next vertex's) `r`.
#[expect(
    clippy::too_many_arguments,
    reason = "a step of a path, the path, and the two distances of its transition function"
)]
fn vertex_coefficient(
    scene: &Scene,
    settings: &Amplitudes,
    step: Step,
    i: usize,
    points: &[Point],
    media: &[usize],
    r0: f64,
    r: f64,
) -> Result<Complex64, NoAmplitude> {
    let why = |case| NoAmplitude::Diffraction { step: i, case };
    let faces = faces_of(settings, step.interface).map_err(why)?;
    let frequency = settings
        .frequency
        .ok_or(why(DiffractionCase::NoFrequency))?;
    let line = &scene.interfaces()[step.interface].polyline;
    let vertex = step.kind.vertex().unwrap_or(0);
    let here = points[i + 1];
    let (d_in, d_out) = (points[i] - here, points[i + 2] - here);
    let wedge = Wedge::at(line.vertices(), line.is_closed(), vertex, d_in);
    let (Some(phi_in), Some(phi)) = (wedge.angle_of(d_in, 0.0), wedge.angle_of(d_out, 1e-9)) else {
        return Err(why(DiffractionCase::IntoWedge));
    };
    let k = TAU * frequency * scene.media()[media[i + 1]].slowness;
    let l = r0 * r / (r0 + r);
    Ok(wedge_coefficient(wedge.angle, k, l, phi_in, phi, faces))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `∫_a^∞ e^(iτ²) dτ` by Simpson's rule along the ray `τ = a + t e^(iπ/4)` (where the
    /// integrand decays as `e^(−√2 a t − t²)`): an independent reference.
    fn tail_by_quadrature(a: f64) -> Complex64 {
        let dir = Complex64::from_polar(1.0, PI / 4.0);
        let f = |t: f64| {
            let tau = dir * t + a;
            (Complex64::new(0.0, 1.0) * tau * tau).exp() * dir
        };
        let (end, n) = (12.0, 200_000);
        let h = end / f64::from(n);
        let mut sum = f(0.0) + f(end);
        for j in 1..n {
            sum += f(f64::from(j) * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
        }
        sum * (h / 3.0)
    }

    #[test]
    fn fresnel_tail_matches_quadrature_and_tables() {
        for a in [0.0, 0.1, 0.5, 1.0, 1.4, 1.6, 2.0, 3.0, 5.0, 8.0] {
            let (got, want) = (fresnel_tail(a), tail_by_quadrature(a));
            assert!(
                (got - want).norm() <= 1e-12 * want.norm().max(1e-3),
                "{a}: {got} {want}"
            );
        }
        // C(1) + i S(1) (Abramowitz and Stegun, table 7.7).
        let u = 1.0;
        let whole = Complex64::new(0.5, 0.5) * FRAC_PI_2.sqrt();
        let cs = (whole - fresnel_tail(u * FRAC_PI_2.sqrt())) / FRAC_PI_2.sqrt();
        assert!((cs.re - 0.779_893_400_376_822_8).abs() < 1e-14, "{cs}");
        assert!((cs.im - 0.438_259_147_390_354_8).abs() < 1e-14, "{cs}");
        // The asymptotic series against the integral, on both sides of X = 50.
        for x in [40.0f64, 49.9, 50.0, 64.0, 150.0, 900.0] {
            let a: f64 = x.sqrt();
            let direct = Complex64::new(0.0, -2.0 * a)
                * Complex64::from_polar(1.0, -x)
                * tail_by_quadrature(a);
            assert!((transition(x) - direct).norm() < 1e-12, "{x}");
        }
        // Far out: F(X) → 1 − i/(2X).
        let x = 1e4;
        assert!((transition(x) - Complex64::new(1.0, -0.5 / x)).norm() < 1e-7);
        // Near 0: F(X) = √(πX) e^(−iπ/4) + 2iX + O(X^(3/2)).
        let x = 1e-10;
        let near = Complex64::from_polar((PI * x).sqrt(), -PI / 4.0);
        assert!((transition(x) - near - Complex64::new(0.0, 2.0 * x)).norm() < 1e-14);
    }

    /// The table's Taylor series against the series and continued fraction it replaces,
    /// between and on its nodes, up to √50 and on both sides of X = 50.
    #[test]
    fn the_tables_taylor_series_matches_the_fresnel_integral() {
        // h(a) from mpmath at 40 digits (its Fresnel integrals, e^(−ia²) and the complement).
        let reference = [
            (0.0, 0.626_657_068_657_750_2, 0.626_657_068_657_750_2),
            (0.1, 0.532_894_868_959_414, 0.621_025_928_868_818_4),
            (0.5, 0.270_513_580_162_214_16, 0.534_877_974_533_517_6),
            (1.0, 0.116_099_695_027_632_3, 0.404_762_740_873_704_4),
            (1.5, 0.053_253_857_939_103_69, 0.307_265_584_164_053_36),
            (1.88, 0.031_343_939_653_929_43, 0.254_943_802_138_972_6),
            (1.9312, 0.029_308_528_922_752_35, 0.249_029_745_806_527_84),
            (2.5, 0.014_829_725_912_150_605, 0.196_739_684_862_605_24),
            (3.3, 0.006_759_817_274_657_124, 0.150_616_728_759_011_25),
            (4.4, 0.002_906_592_561_407_478_6, 0.113_413_971_354_834_14),
            (5.5, 0.001_496_573_814_046_792_4, 0.090_835_274_509_753_26),
            (6.6, 0.000_867_872_764_422_090_3, 0.075_727_767_962_598_72),
            (7.07, 0.000_706_372_039_318_573_4, 0.070_700_202_246_839_41),
        ];
        for (a, re, im) in reference {
            let want = Complex64::new(re, im);
            let e = (scaled_tail(a) - want).norm() / want.norm();
            let old = Complex64::from_polar(1.0, -a * a) * fresnel_tail(a);
            let e_old = (old - want).norm() / want.norm();
            eprintln!("h({a}): table {e:.1e}, series or continued fraction {e_old:.1e}");
            assert!(e < 3e-15 * (1.0 + a * a), "{a}: {e:e}");
        }
        // Against the series and continued fraction it replaces, at 2001 points: within the
        // function's own conditioning (an error ε in a moves the phase of e^(ia²) by 2aε).
        for i in 0..=2000 {
            let a = 7.1 * f64::from(i) / 2000.0;
            let want = Complex64::from_polar(1.0, -a * a) * fresnel_tail(a);
            let e = (scaled_tail(a) - want).norm() / want.norm();
            assert!(e < 3e-15 * (1.0 + a * a), "{a}: {e:e}");
        }
        for x in [49.999f64, 50.0] {
            let a: f64 = x.sqrt();
            let direct =
                Complex64::new(0.0, -2.0 * a) * Complex64::from_polar(1.0, -x) * fresnel_tail(a);
            assert!((transition(x) - direct).norm() < 1e-14, "{x}");
        }
    }

    /// Far from the boundaries the UTD coefficient is Keller's: for a half-plane,
    /// `−e^(iπ/4) / (2√(2πk)) (sec((φ − φ′)/2) ∓ sec((φ + φ′)/2))`.
    #[test]
    fn half_plane_coefficient_is_kellers_far_from_the_boundaries() {
        let (k, l) = (50.0, 1e6);
        for (phi_in, phi) in [(0.7, 2.0), (1.0, 5.5), (2.5, 0.3)] {
            for (faces, sign) in [(Faces::Rigid, 1.0), (Faces::PressureRelease, -1.0)] {
                let d = wedge_coefficient(TAU, k, l, phi_in, phi, faces);
                let sec = |x: f64| 1.0 / x.cos();
                let keller = -Complex64::from_polar(1.0, PI / 4.0) / (2.0 * (TAU * k).sqrt())
                    * (sec((phi - phi_in) / 2.0) + sign * sec((phi + phi_in) / 2.0));
                assert!((d - keller).norm() < 1e-5 * keller.norm(), "{d} {keller}");
            }
        }
    }

    /// For an exterior angle π/N the image sum is exact: the coefficient vanishes.
    #[test]
    fn coefficient_vanishes_where_images_are_exact() {
        for big_n in [2.0, 3.0, 4.0] {
            let angle = PI / big_n;
            for (phi_in, phi) in [(0.1 * angle, 0.7 * angle), (0.45 * angle, 0.2 * angle)] {
                for faces in [Faces::Rigid, Faces::PressureRelease] {
                    let d = wedge_coefficient(angle, 30.0, 2.0, phi_in, phi, faces);
                    assert!(d.norm() < 1e-12, "{big_n} {d}");
                }
            }
        }
    }

    /// Exactly on a boundary (here the incident shadow boundary of a half-plane, β⁻ = π to
    /// the bit) the coefficient is its limit from the shadow side, where ray theory lists no
    /// arrival either: continuous with the shadow side, a whole jump away from the lit side.
    #[test]
    fn on_a_boundary_the_coefficient_is_the_shadow_sides_limit() {
        let (k, l, phi_in) = (20.0, 3.0, 1.0);
        let on = 1.0 + PI;
        assert_eq!(on - phi_in, PI);
        for faces in [Faces::Rigid, Faces::PressureRelease] {
            let d = |phi: f64| wedge_coefficient(TAU, k, l, phi_in, phi, faces);
            let (shadow, lit) = (d(on + 1e-9), d(on - 1e-9));
            assert!(
                (d(on) - shadow).norm() < 1e-6 * shadow.norm(),
                "{} {shadow}",
                d(on)
            );
            assert!((d(on) - lit).norm() > 0.5 * shadow.norm());
        }
    }

    #[test]
    fn wedges_take_the_side_of_the_incident_direction() {
        let pts = [
            Point::new(-1.0, 0.0),
            Point::new(0.0, 0.0),
            Point::new(0.0, 1.0),
        ];
        // From the lower left: the 270° side.
        let w = Wedge::at(&pts, false, 1, Vec2::new(-1.0, -1.0));
        assert!((w.angle - 1.5 * PI).abs() < 1e-15);
        // From the upper left: the 90° side.
        let w = Wedge::at(&pts, false, 1, Vec2::new(-1.0, 1.0));
        assert!((w.angle - FRAC_PI_2).abs() < 1e-15);
        assert!(w.angle_of(Vec2::new(1.0, -1.0), 1e-9).is_none());
        // An open end is a wedge of 2π.
        let w = Wedge::at(&pts, false, 0, Vec2::new(0.0, 1.0));
        assert_eq!(w.angle, TAU);
        assert!((w.angle_of(Vec2::new(-1.0, 0.0), 0.0).unwrap() - PI).abs() < 1e-15);
    }
}
