//! Plane-wave reflection and transmission coefficients at a flat interface: fluid–fluid
//! pressure coefficients from the impedances ρc, and the Fresnel coefficients of the electric
//! field for `index` media, complex beyond the critical angle (time factor `e^(−iωt)`).

use num_complex::Complex64;

use crate::scene::{Amplitudes, Polarization, Waves};

/// The weights of the two cosines in a coefficient `(A cos θ₁ − B cos θ₂) / (A cos θ₁ + B cos
/// θ₂)` and the weight `N` of the transmission coefficient's numerator `2 N cos θ₁`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Weights {
    /// The weight of `cos θ₁`.
    pub a: f64,
    /// The weight of `cos θ₂`.
    pub b: f64,
    /// The weight of the transmission coefficient's numerator.
    pub n: f64,
}

impl Weights {
    /// The weights from medium `m1` (the ray's) to medium `m2` (across), of slownesses `s1`
    /// and `s2`: fluids `A = Z₂`, `B = Z₁`, `N = Z₂` with `Z = ρc`; optics, s: `A = n₁`,
    /// `B = n₂`, `N = n₁`; p: `A = n₂`, `B = n₁`, `N = n₁`.
    #[inline(always)]
    pub(crate) fn of(settings: &Amplitudes, [m1, m2]: [usize; 2], [s1, s2]: [f64; 2]) -> Weights {
        match (settings.waves, settings.polarization) {
            (Waves::Fluid, _) => {
                let z1 = settings.density[m1] / s1;
                let z2 = settings.density[m2] / s2;
                Weights {
                    a: z2,
                    b: z1,
                    n: z2,
                }
            }
            (Waves::Optics, Polarization::S) => Weights {
                a: s1,
                b: s2,
                n: s1,
            },
            (Waves::Optics, Polarization::P) => Weights {
                a: s2,
                b: s1,
                n: s1,
            },
        }
    }

    /// The reflection coefficient for `cos θ₁` and `cos θ₂` (real below the critical angle).
    #[inline(always)]
    pub(crate) fn reflection(self, cos1: f64, cos2: Complex64) -> Complex64 {
        let (a, b) = (self.a * cos1, cos2 * self.b);
        if cos2.im == 0.0 {
            return Complex64::new((a - b.re) / (a + b.re), 0.0);
        }
        let r = (a - b) / (a + b);
        if r.re.is_finite() && r.im.is_finite() {
            return r;
        }
        self.evanescent_scaled(cos1, cos2)
    }

    /// [`reflection`](Self::reflection) beyond the critical angle where its products
    /// overflow (media whose impedances and speeds differ by far more than any material's):
    /// the weights divided by the larger, then both terms by the larger term. Out of line;
    /// never taken where the direct form has a number.
    #[cold]
    #[inline(never)]
    fn evanescent_scaled(self, cos1: f64, cos2: Complex64) -> Complex64 {
        let big = self.a.max(self.b);
        let a = self.a / big * cos1;
        let b = cos2 * (self.b / big);
        let size = a.abs().max(b.re.abs()).max(b.im.abs());
        let (a, b) = (a / size, b / size);
        (a - b) / (a + b)
    }

    /// The transmission coefficient for `cos θ₁` and a real `cos θ₂` (a refracted ray).
    #[inline(always)]
    pub(crate) fn transmission(self, cos1: f64, cos2: f64) -> f64 {
        2.0 * self.n * cos1 / (self.a * cos1 + self.b * cos2)
    }
}

/// The plane-wave reflection coefficient of a wave in medium `m1` (slowness `s1`) against
/// medium `m2` (slowness `s2`) at the angle of incidence whose cosine is `cos1` (an extruded
/// room's wall, at its 3-D angle).
pub(crate) fn reflection_against(
    settings: &Amplitudes,
    [m1, m2]: [usize; 2],
    [s1, s2]: [f64; 2],
    cos1: f64,
) -> Complex64 {
    let weights = Weights::of(settings, [m1, m2], [s1, s2]);
    let sin1_squared = (1.0 - cos1 * cos1).max(0.0);
    weights.reflection(cos1, cos_across(s1 / s2, sin1_squared))
}

/// `cos θ₂` of the wave across an interface from `sin² θ₁` and the ratio of speeds `c₂/c₁`
/// (`s₁/s₂` of the slownesses): `√(1 − (c₂/c₁)² sin² θ₁)`, and beyond the critical angle
/// `+i √((c₂/c₁)² sin² θ₁ − 1)`.
#[inline]
pub(crate) fn cos_across(speed_ratio: f64, sin1_squared: f64) -> Complex64 {
    let q2 = speed_ratio * speed_ratio * sin1_squared;
    if q2 <= 1.0 {
        Complex64::new((1.0 - q2).sqrt(), 0.0)
    } else if q2 < f64::INFINITY {
        Complex64::new(0.0, (q2 - 1.0).sqrt())
    } else {
        // (c₂/c₁)² overflows (speeds 1e±100 apart): √(q² − 1) is q to every digit.
        Complex64::new(0.0, speed_ratio * sin1_squared.sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evanescent_cosines_are_positive_imaginary() {
        let c = cos_across(2.0, 0.5);
        assert_eq!(c.re, 0.0);
        assert!((c.im - 1.0).abs() < 1e-15);
        assert!((cos_across(0.5, 0.36).re - 0.91f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn beyond_the_critical_angle_the_reflection_is_total() {
        let w = Weights {
            a: 2.0,
            b: 1.5,
            n: 2.0,
        };
        let r = w.reflection(0.3, cos_across(1.8, 1.0 - 0.09));
        assert!((r.norm() - 1.0).abs() < 1e-15);
        // Below it, energy: R² + (B cos θ₂)/(A cos θ₁) T² = 1 for fluids (A = Z₂, B = Z₁).
        let (cos1, cos2) = (0.8, cos_across(1.1, 0.36).re);
        let (r, t) = (
            w.reflection(cos1, cos2.into()).re,
            w.transmission(cos1, cos2),
        );
        assert!((r * r + (w.b * cos2) / (w.a * cos1) * t * t - 1.0).abs() < 1e-15);
    }
}
