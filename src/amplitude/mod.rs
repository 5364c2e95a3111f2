//! Ray amplitudes (`"amplitudes"`): how much of the wave arrives along a solved ray, by ray
//! theory (the high-frequency asymptotic field), from its points and leg media alone.
//!
//! Within a leg `p √(W Y)` is constant, with `W` the ray tube's width in the plane and `Y` its
//! width out of the plane, both per unit take-off angle; at an interaction the field is
//! multiplied by the plane-wave coefficient and `W` by `cos θ₂ / cos θ₁` (refraction; a
//! reflection keeps it), `Y` is continuous; near the source `W = Y = R` and `p = 1/(4πR)`. The
//! impedances (and indices) of the energy flux cancel between the source and the receiver, so
//!
//! ```text
//! spreading = Π √(cos θ₂ / cos θ₁) / (4π √(W Y))            point, axisymmetric
//! spreading = Π √(cos θ₂ / cos θ₁) / √(8π k₀ W)              line (k₀ = 2π f w₀)
//! amplitude = spreading × Π coefficients × 10^(−dB/20)   (× e^(iπ/4) for line)
//! ```
//!
//! `W = |∂x⊥/∂φ₀|` is how far the receiver moves across the last leg per unit change of the
//! take-off angle: the inverse of how the first interaction point turns the first leg when
//! the receiver moves across the last one, the first component of one tridiagonal solve with
//! the Hessian of the time at the solved points (the implicit function theorem, as
//! `PointSensitivities` does; only its forward sweep is needed). `Y` is `w₀ Σ ℓⱼ / wⱼ`
//! (`point`: the out-of-plane slowness is conserved) or `x_R / |t₀ₓ|` (`axisymmetric`: the
//! ring of azimuths at range `x_R` over the cone of take-off directions).

mod coefficients;
pub(crate) use coefficients::reflection_against;
pub mod diffraction;
mod ray;

pub use num_complex::Complex64;

pub(crate) use diffraction::of_diffracted;
pub(crate) use ray::{
    AxisymmetricRun, BounceGroup, Incidence, LANES, NodeBounces, OnSegment, PathGeometry,
    ProfileReflection, TreeLaws, UnfoldedLaws, caustics_of_path, caustics_of_profile_legs, of_one,
    of_path, of_profile, of_profile_legs, of_straight_path,
};

/// The amplitude of one timed ray or arrival (the contract's `amplitude`, `spreading`,
/// `coefficient` and `attenuation_db`), or why it has none.
///
/// Where it has none ([`reason`](Self::reason) is `Some`), `value` and `coefficient` are NaN
/// (a missing amplitude is never 0), and so are `spreading` and `attenuation_db` except on a
/// converted reflection, whose geometry and media are known. Two amplitudes are equal when
/// every field is, NaN equal to NaN.
#[derive(Clone, Copy, Debug)]
pub struct Amplitude {
    /// The complex pressure (field) amplitude at the receiver for a unit source, without the
    /// travel-time phase `e^(iωT)`: `spreading × coefficient × 10^(−attenuation_db/20)`
    /// (× `e^(iπ/4)` for a line source).
    pub value: Complex64,
    /// The geometric spreading factor alone (> 0; `1/(4πR)` in a homogeneous medium for a
    /// point source).
    pub spreading: f64,
    /// The product of the path's reflection and transmission coefficients.
    pub coefficient: Complex64,
    /// The attenuation of the media along the path, in dB (≥ 0).
    pub attenuation_db: f64,
    /// Why the ray has no ray-theory amplitude, when it has none.
    pub reason: Option<NoAmplitude>,
}

impl Amplitude {
    /// No amplitude, for `reason`: every number NaN.
    pub fn none(reason: NoAmplitude) -> Amplitude {
        let nan = Complex64::new(f64::NAN, f64::NAN);
        Amplitude {
            value: nan,
            spreading: f64::NAN,
            coefficient: nan,
            attenuation_db: f64::NAN,
            reason: Some(reason),
        }
    }

    /// Whether it has a value (no [`reason`](Self::reason)).
    pub fn has_value(&self) -> bool {
        self.reason.is_none()
    }
}

/// Equal when every field is, NaN equal to NaN (an amplitude without a value).
impl PartialEq for Amplitude {
    fn eq(&self, o: &Self) -> bool {
        let same = |a: f64, b: f64| a == b || (a.is_nan() && b.is_nan());
        let same_c = |a: Complex64, b: Complex64| same(a.re, b.re) && same(a.im, b.im);
        same_c(self.value, o.value)
            && same(self.spreading, o.spreading)
            && same_c(self.coefficient, o.coefficient)
            && same(self.attenuation_db, o.attenuation_db)
            && self.reason == o.reason
    }
}

/// Why a timed ray has no ray-theory amplitude (`amplitude_reason` in the output).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NoAmplitude {
    /// A `vertex` path: an interaction held on a polyline vertex is edge diffraction, which
    /// needs diffraction coefficients.
    Vertex,
    /// An `obstructed` path: a leg crosses an interface that the path does not list, whose
    /// transmission ray theory would need.
    Obstructed,
    /// A reflection whose two legs lie in different media (a converted wave): no fluid
    /// coefficient (elastic coefficients are not modelled). Its spreading and attenuation
    /// are given.
    ConvertedReflection {
        /// Index of the step.
        step: usize,
    },
    /// A `"media"` reflection where no medium fills the region across the interface.
    NoMediumAcross {
        /// Index of the step.
        step: usize,
    },
    /// A leg meets its interface at grazing incidence (`cos θ = 0`).
    Grazing {
        /// Index of the step.
        step: usize,
    },
    /// A leg of zero length (an end on an interface).
    VanishedLeg {
        /// Index of the leg.
        leg: usize,
    },
    /// The ray tube has no width (a degenerate path): ray theory has no finite amplitude.
    Caustic,
    /// `axisymmetric`: the path reaches or crosses the axis after leaving the source, where
    /// every azimuth focuses (an axial caustic).
    OnAxis,
    /// `axisymmetric`: the source lies off the axis `x = 0`.
    SourceOffAxis,
    /// The leg media are not known, or not one per leg.
    UnknownMedia,
    /// A `diffract` step whose vertex has no wedge coefficient here (see [`DiffractionCase`]).
    Diffraction {
        /// Index of the step.
        step: usize,
        /// Which case it is.
        case: DiffractionCase,
    },
}

/// Why a diffracted path's vertex has no UTD wedge coefficient.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DiffractionCase {
    /// The interface's law is `"media"`: a penetrable (refracting) interface's vertex, whose
    /// coefficient needs the transmitted field inside the wedge.
    PenetrableFace,
    /// The interface's law absorbs (`absorption`, `coefficient`): an impedance wedge, whose
    /// coefficient needs Maliuzhinets' functions.
    AbsorbingFace,
    /// The scene gives no `amplitudes.frequency`: the coefficient depends on the wavenumber.
    NoFrequency,
    /// A leg leaves the vertex into the wedge's inside.
    IntoWedge,
}

impl DiffractionCase {
    /// The cases in the order of their codes (0, 1, …).
    pub const ALL: [DiffractionCase; 4] = [
        DiffractionCase::PenetrableFace,
        DiffractionCase::AbsorbingFace,
        DiffractionCase::NoFrequency,
        DiffractionCase::IntoWedge,
    ];

    /// Its words.
    pub fn describe(self) -> &'static str {
        match self {
            DiffractionCase::PenetrableFace => {
                "a penetrable (\"media\") interface's vertex: no coefficient for a refracting wedge"
            }
            DiffractionCase::AbsorbingFace => {
                "an absorbing face's vertex: no coefficient for an impedance wedge"
            }
            DiffractionCase::NoFrequency => "no `amplitudes.frequency`: the coefficient needs one",
            DiffractionCase::IntoWedge => "a leg leaves the vertex into the wedge",
        }
    }
}

impl NoAmplitude {
    /// The reasons in the order of their `.npy` `amplitude_reason` codes (1, 2, …; 0: none),
    /// with the step and leg indices 0.
    pub const CODES: [NoAmplitude; 11] = [
        NoAmplitude::Vertex,
        NoAmplitude::Obstructed,
        NoAmplitude::ConvertedReflection { step: 0 },
        NoAmplitude::NoMediumAcross { step: 0 },
        NoAmplitude::Grazing { step: 0 },
        NoAmplitude::VanishedLeg { leg: 0 },
        NoAmplitude::Caustic,
        NoAmplitude::OnAxis,
        NoAmplitude::SourceOffAxis,
        NoAmplitude::UnknownMedia,
        NoAmplitude::Diffraction {
            step: 0,
            case: DiffractionCase::PenetrableFace,
        },
    ];

    /// Its short name (the `.npy` names table): `vertex`, `obstructed`, `converted`,
    /// `no_medium_across`, `grazing`, `vanished_leg`, `caustic`, `on_axis`, `source_off_axis`,
    /// `unknown_media`, `diffraction`.
    pub fn name(self) -> &'static str {
        match self {
            NoAmplitude::Vertex => "vertex",
            NoAmplitude::Obstructed => "obstructed",
            NoAmplitude::ConvertedReflection { .. } => "converted",
            NoAmplitude::NoMediumAcross { .. } => "no_medium_across",
            NoAmplitude::Grazing { .. } => "grazing",
            NoAmplitude::VanishedLeg { .. } => "vanished_leg",
            NoAmplitude::Caustic => "caustic",
            NoAmplitude::OnAxis => "on_axis",
            NoAmplitude::SourceOffAxis => "source_off_axis",
            NoAmplitude::UnknownMedia => "unknown_media",
            NoAmplitude::Diffraction { .. } => "diffraction",
        }
    }

    /// Its `.npy` code: its place in [`CODES`](Self::CODES) plus 1.
    pub fn code(self) -> u8 {
        let place = Self::CODES.iter().position(|c| c.name() == self.name());
        place.map_or(0, |p| p as u8 + 1)
    }
}

impl std::fmt::Display for NoAmplitude {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoAmplitude::Vertex => f.write_str(
                "a vertex (edge-diffracted) path: its amplitude needs diffraction coefficients",
            ),
            NoAmplitude::Obstructed => {
                f.write_str("an obstructed path: a leg crosses an interface the path does not list")
            }
            NoAmplitude::ConvertedReflection { step } => write!(
                f,
                "step {step} reflects into another medium (a converted wave): no fluid \
                 coefficient"
            ),
            NoAmplitude::NoMediumAcross { step } => write!(
                f,
                "no medium fills the region across the interface of step {step} (its \
                 reflection law is \"media\")"
            ),
            NoAmplitude::Grazing { step } => {
                write!(
                    f,
                    "a leg meets step {step}'s interface at grazing incidence"
                )
            }
            NoAmplitude::VanishedLeg { leg } => {
                write!(f, "leg {leg} has zero length (an end lies on an interface)")
            }
            NoAmplitude::Caustic => f.write_str("the ray tube has no width (a caustic)"),
            NoAmplitude::OnAxis => f.write_str(
                "the path reaches or crosses the axis of symmetry after the source (an axial \
                 caustic)",
            ),
            NoAmplitude::SourceOffAxis => {
                f.write_str("the source lies off the axis x = 0 of an axisymmetric scene")
            }
            NoAmplitude::UnknownMedia => f.write_str("the leg media are not known"),
            NoAmplitude::Diffraction { step, case } => {
                write!(f, "diffraction at step {step}: {}", case.describe())
            }
        }
    }
}
