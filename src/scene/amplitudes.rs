//! The scene's amplitude keys (`media.*.density`, `media.*.attenuation`,
//! `interfaces.*.reflection`, `amplitudes`): their specs, constructors and validation.

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{InterfaceSpec, MediumSpec, Point, Scene, SceneError, SceneSpec, positive};

/// The largest attenuation a medium may have, in dB per unit length (given so, or per
/// wavelength at the scene's frequency): with coordinates within
/// [`MAX_COORDINATE`](super::MAX_COORDINATE), a path's attenuation in dB stays a finite
/// number, however many legs it has.
pub const MAX_ATTENUATION: f64 = 1e100;

/// What the scene's plane is a section of (`amplitudes.source`), which fixes how a ray tube
/// spreads out of the plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SourceModel {
    /// A point source in 3-D, the scene uniform along the third axis (a floor plan with tall
    /// walls, an extruded cross-section): `1/(4πR)` in a homogeneous medium.
    Point,
    /// The (range `x ≥ 0`, depth `y`) plane of a 3-D world symmetric about the axis `x = 0`,
    /// on which the source lies (BELLHOP's geometry): `1/(4πR)` in a homogeneous medium.
    Axisymmetric,
    /// A 2-D world with a line source: the far field of `(i/4) H₀⁽¹⁾(kR)` (needs a
    /// frequency).
    Line,
}

impl SourceModel {
    /// Its name in the scene document: `point`, `axisymmetric`, `line`.
    pub fn as_str(self) -> &'static str {
        match self {
            SourceModel::Point => "point",
            SourceModel::Axisymmetric => "axisymmetric",
            SourceModel::Line => "line",
        }
    }
}

/// The polarization of the Fresnel coefficients of `index` media (`amplitudes.polarization`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Polarization {
    /// The electric field perpendicular to the plane of incidence (TE), the default.
    #[default]
    S,
    /// The electric field in the plane of incidence (TM).
    P,
}

/// How an interface reflects (`interfaces.*.reflection`): `"rigid"` (the default),
/// `"pressure-release"`, `{"absorption": α}`, `{"coefficient": r}` or `"media"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReflectionSpec {
    /// `R = 1`.
    Rigid,
    /// `R = −1` (a sea surface).
    PressureRelease,
    /// `α` of the energy absorbed, independent of the angle (0 ≤ α ≤ 1): `R = √(1 − α)`, as
    /// pyroomacoustics.
    Absorption(f64),
    /// A real pressure coefficient `r` (−1 ≤ r ≤ 1).
    Coefficient(f64),
    /// The plane-wave coefficient between the ray's medium and the medium across the
    /// interface at the reflection point (region lookup).
    Media,
}

/// A medium's attenuation (`media.*.attenuation`): a number of dB per unit length, or
/// `{"db_per_wavelength": a}` as sediment tables give it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AttenuationSpec {
    /// dB per unit length, frequency independent (`"attenuation": 0.5`).
    DbPerLength(f64),
    /// dB per wavelength (`{"db_per_wavelength": a}`): `a·f/c` dB per unit length at the
    /// scene's `amplitudes.frequency` `f`, with the medium's speed `c` (`a·f·n` for a medium
    /// of index `n`, whose wavelength is `1/(n f)` with `c = 1`).
    DbPerWavelength(f64),
}

/// The object form of an attenuation, `{"db_per_wavelength": a}`.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PerWavelengthDocument {
    db_per_wavelength: f64,
}

/// An attenuation as the document writes it.
#[derive(Deserialize)]
#[serde(
    untagged,
    expecting = "expected a number (dB per unit length) or {\"db_per_wavelength\": a}"
)]
enum AttenuationDocument {
    Number(f64),
    PerWavelength(PerWavelengthDocument),
}

impl Serialize for AttenuationSpec {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match *self {
            AttenuationSpec::DbPerLength(a) => s.serialize_f64(a),
            AttenuationSpec::DbPerWavelength(a) => PerWavelengthDocument {
                db_per_wavelength: a,
            }
            .serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for AttenuationSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<AttenuationSpec, D::Error> {
        Ok(match AttenuationDocument::deserialize(d)? {
            AttenuationDocument::Number(a) => AttenuationSpec::DbPerLength(a),
            AttenuationDocument::PerWavelength(p) => {
                AttenuationSpec::DbPerWavelength(p.db_per_wavelength)
            }
        })
    }
}

/// The `amplitudes` section: ask every timed ray for its amplitude.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AmplitudesSpec {
    /// What the scene's plane is a section of.
    pub source: SourceModel,
    /// Frequency (Hz, with the scene's time unit s): needed for `line`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frequency: Option<f64>,
    /// The Fresnel coefficients' polarization for `index` media (default `s`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub polarization: Option<Polarization>,
}

impl AmplitudesSpec {
    /// Amplitudes for `source` (`{"source": "point"}`).
    pub fn new(source: SourceModel) -> AmplitudesSpec {
        AmplitudesSpec {
            source,
            frequency: None,
            polarization: None,
        }
    }

    /// The same with a frequency (`"frequency": 250`).
    pub fn frequency(self, frequency: f64) -> AmplitudesSpec {
        AmplitudesSpec {
            frequency: Some(frequency),
            ..self
        }
    }

    /// The same with a polarization (`"polarization": "p"`).
    pub fn polarization(self, polarization: Polarization) -> AmplitudesSpec {
        AmplitudesSpec {
            polarization: Some(polarization),
            ..self
        }
    }
}

impl MediumSpec {
    /// The same medium with a density (`"density": 1000`; default 1): with the speed, the
    /// impedance ρc.
    pub fn density(self, density: f64) -> MediumSpec {
        MediumSpec {
            density: Some(density),
            ..self
        }
    }

    /// The same medium with an attenuation in dB per unit length (`"attenuation": 0.5`;
    /// default 0).
    pub fn attenuation(self, db_per_length: f64) -> MediumSpec {
        MediumSpec {
            attenuation: Some(AttenuationSpec::DbPerLength(db_per_length)),
            ..self
        }
    }

    /// The same medium with an attenuation in dB per wavelength
    /// (`"attenuation": {"db_per_wavelength": 0.5}`), which needs the scene's
    /// `amplitudes.frequency`.
    pub fn attenuation_per_wavelength(self, db_per_wavelength: f64) -> MediumSpec {
        MediumSpec {
            attenuation: Some(AttenuationSpec::DbPerWavelength(db_per_wavelength)),
            ..self
        }
    }
}

impl InterfaceSpec {
    /// The same interface with a reflection law (`"reflection": "pressure-release"`).
    pub fn reflection(self, reflection: ReflectionSpec) -> InterfaceSpec {
        InterfaceSpec {
            reflection: Some(reflection),
            ..self
        }
    }
}

/// Which plane-wave coefficients the media take: all media of a scene that asks for
/// amplitudes have a `speed`, or all have an `index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Waves {
    /// `speed` media: fluid–fluid pressure coefficients from the impedances ρc.
    Fluid,
    /// `index` media: the Fresnel coefficients of the electric field.
    Optics,
}

/// A validated reflection law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reflection {
    /// A fixed real coefficient: 1 (`rigid`), −1 (`pressure-release`), `√(1 − α)`
    /// (`absorption`) or `r` (`coefficient`).
    Fixed(f64),
    /// The plane-wave coefficient against the medium across the interface.
    Media,
}

/// The validated amplitude settings of a scene that asks for them ([`Scene::amplitudes`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Amplitudes {
    /// What the plane is a section of.
    pub source: SourceModel,
    /// The frequency, when given (always for [`SourceModel::Line`]).
    pub frequency: Option<f64>,
    /// The Fresnel coefficients' polarization (`index` media).
    pub polarization: Polarization,
    /// Which coefficients the media take.
    pub waves: Waves,
    /// Each medium's density, in the order of [`Scene::media`] (1 where not given).
    pub density: Vec<f64>,
    /// Each medium's attenuation in dB per unit length (0 where not given; at
    /// [`frequency`](Self::frequency) where given per wavelength).
    pub attenuation: Vec<f64>,
    /// Each medium's attenuation in dB per wavelength where the document gives it so
    /// (`{"db_per_wavelength": a}`), else `None`: a change of the medium's speed changes its
    /// [`attenuation`](Self::attenuation).
    pub attenuation_per_wavelength: Vec<Option<f64>>,
    /// Whether some medium attenuates.
    pub attenuates: bool,
    /// Each interface's reflection law, in the order of [`Scene::interfaces`].
    pub reflection: Vec<Reflection>,
}

impl Scene {
    /// The amplitude settings, when the scene asks for amplitudes (`"amplitudes"`).
    pub fn amplitudes(&self) -> Option<&Amplitudes> {
        self.amplitudes.as_ref()
    }

    /// Refuses source `k` at `p` off the axis of an axisymmetric scene (the check of
    /// `sources[k]` that [`validate`] makes).
    pub(super) fn source_on_axis(&self, k: usize, p: Point) -> Result<(), SceneError> {
        match &self.amplitudes {
            Some(a) => on_axis(a.source, k, p),
            None => Ok(()),
        }
    }
}

/// A source of an axisymmetric scene must lie on the axis `x = 0`.
fn on_axis(source: SourceModel, k: usize, p: Point) -> Result<(), SceneError> {
    if source == SourceModel::Axisymmetric && p.x != 0.0 {
        return Err(SceneError::new(
            format!("sources[{k}]"),
            "lies off the axis x = 0 about which `amplitudes.source` \"axisymmetric\" turns the \
             scene: put the source at x = 0",
        ));
    }
    Ok(())
}

/// Each medium's density and attenuation, and which coefficients the media take (a scene's
/// media are of one kind: the scene's validation refuses a mix before this).
struct MediaAmplitudes {
    density: Vec<f64>,
    /// dB per unit length (at the frequency, where given per wavelength).
    attenuation: Vec<f64>,
    attenuation_per_wavelength: Vec<Option<f64>>,
    waves: Waves,
}

/// An attenuation at `key` as given: a finite number from 0 to [`MAX_ATTENUATION`], in
/// `unit`.
fn attenuation_value(key: String, a: f64, unit: &str) -> Result<f64, SceneError> {
    if !(a.is_finite() && a >= 0.0) {
        return Err(SceneError::new(
            key,
            format!("must be a finite number ≥ 0 ({unit})"),
        ));
    }
    if a > MAX_ATTENUATION {
        return Err(SceneError::new(
            key,
            format!(
                "must be at most {MAX_ATTENUATION:e} ({unit}; more would make a path's \
                 attenuation in dB overflow)"
            ),
        ));
    }
    Ok(a)
}

/// The dB per unit length of an attenuation of `a` dB per wavelength at `frequency` in a
/// medium of speed `value` (or of index `value`, when `index`): `a·f/c` (or `a·f·n`), refused
/// at `key` above [`MAX_ATTENUATION`].
pub(super) fn per_unit_length(
    key: impl FnOnce() -> String,
    a: f64,
    frequency: f64,
    index: bool,
    value: f64,
) -> Result<f64, SceneError> {
    let db = if index {
        a * frequency * value
    } else {
        a * frequency / value
    };
    if db.is_nan() || db > MAX_ATTENUATION {
        return Err(SceneError::new(
            key(),
            format!(
                "{a:e} dB per wavelength at {frequency:e} Hz is {db:e} dB per unit length in \
                 this medium, more than {MAX_ATTENUATION:e} (a path's attenuation in dB would \
                 overflow)"
            ),
        ));
    }
    Ok(db)
}

/// The media's amplitude keys, checked whether or not the scene asks for amplitudes; an
/// attenuation per wavelength is turned into dB per unit length at `frequency`, and refused
/// without one.
fn media_amplitudes(
    spec: &SceneSpec,
    frequency: Option<f64>,
) -> Result<MediaAmplitudes, SceneError> {
    let mut out = MediaAmplitudes {
        density: Vec::with_capacity(spec.media.len()),
        attenuation: Vec::with_capacity(spec.media.len()),
        attenuation_per_wavelength: Vec::with_capacity(spec.media.len()),
        waves: match spec.media.values().next() {
            Some(m) if m.index.is_some() => Waves::Optics,
            _ => Waves::Fluid,
        },
    };
    for (name, m) in &spec.media {
        let key = format!("media.{name}");
        out.density.push(match m.density {
            Some(d) => positive(format!("{key}.density"), d)?,
            None => 1.0,
        });
        let (db, per_wavelength) = match m.attenuation {
            None => (0.0, None),
            Some(AttenuationSpec::DbPerLength(a)) => (
                attenuation_value(format!("{key}.attenuation"), a, "dB per unit length")?,
                None,
            ),
            Some(AttenuationSpec::DbPerWavelength(a)) => {
                let at = format!("{key}.attenuation.db_per_wavelength");
                let a = attenuation_value(at.clone(), a, "dB per wavelength")?;
                let Some(f) = frequency else {
                    return Err(SceneError::new(
                        format!("{key}.attenuation"),
                        "is given per wavelength, which needs the frequency: give \
                         `amplitudes.frequency` (Hz), or the attenuation in dB per unit length",
                    ));
                };
                let (index, value) = match (m.index, m.speed) {
                    (Some(n), _) => (true, n),
                    (None, Some(c)) => (false, c),
                    // The scene's validation has refused a medium without either.
                    (None, None) => (false, f64::NAN),
                };
                (per_unit_length(|| at, a, f, index, value)?, Some(a))
            }
        };
        out.attenuation.push(db);
        out.attenuation_per_wavelength.push(per_wavelength);
    }
    Ok(out)
}

/// Each interface's reflection law (checked whether or not the scene asks for amplitudes);
/// a `media` law needs region lookup when amplitudes are asked for.
fn reflections(
    spec: &SceneSpec,
    asked: bool,
    needs_regions: bool,
) -> Result<Vec<Reflection>, SceneError> {
    let mut out = Vec::with_capacity(spec.interfaces.len());
    for (name, i) in &spec.interfaces {
        let key = format!("interfaces.{name}.reflection");
        let law = match i.reflection.unwrap_or(ReflectionSpec::Rigid) {
            ReflectionSpec::Rigid => Reflection::Fixed(1.0),
            ReflectionSpec::PressureRelease => Reflection::Fixed(-1.0),
            ReflectionSpec::Absorption(a) if (0.0..=1.0).contains(&a) => {
                Reflection::Fixed((1.0 - a).sqrt())
            }
            ReflectionSpec::Absorption(_) => {
                return Err(SceneError::new(
                    format!("{key}.absorption"),
                    "must be a number from 0 to 1 (the fraction of the energy absorbed)",
                ));
            }
            ReflectionSpec::Coefficient(r) if (-1.0..=1.0).contains(&r) => Reflection::Fixed(r),
            ReflectionSpec::Coefficient(_) => {
                return Err(SceneError::new(
                    format!("{key}.coefficient"),
                    "must be a number from -1 to 1 (a real pressure coefficient)",
                ));
            }
            ReflectionSpec::Media if asked && !needs_regions => {
                return Err(SceneError::new(
                    key,
                    "\"media\" takes the medium across the interface from region lookup, which \
                     this scene does not have (every path gives its `media`, there is no \
                     `search`, and no `background`, `at` or `domain` declares regions): give \
                     the law as a coefficient, or declare the regions (a `background`, or an \
                     `at` point per medium)",
                ));
            }
            ReflectionSpec::Media => Reflection::Media,
        };
        out.push(law);
    }
    Ok(out)
}

/// The amplitude settings of `spec` (`None` without an `amplitudes` section), every
/// amplitude key checked: densities and attenuations, reflection laws, the section's
/// frequency, the media of one kind, the sources of an axisymmetric scene on its axis.
///
/// # Errors
/// The first problem, at its key.
pub(super) fn validate(
    spec: &SceneSpec,
    sources: &[Point],
    needs_regions: bool,
) -> Result<Option<Amplitudes>, SceneError> {
    let frequency = match &spec.amplitudes {
        Some(a) => frequency_of(a)?,
        None => None,
    };
    let media = media_amplitudes(spec, frequency)?;
    let reflection = reflections(spec, spec.amplitudes.is_some(), needs_regions)?;
    let Some(a) = &spec.amplitudes else {
        return Ok(None);
    };
    let waves = media.waves;
    for (k, &p) in sources.iter().enumerate() {
        on_axis(a.source, k, p)?;
    }
    let attenuates = media.attenuation.iter().any(|&a| a > 0.0);
    Ok(Some(Amplitudes {
        source: a.source,
        frequency,
        polarization: a.polarization.unwrap_or_default(),
        waves,
        density: media.density,
        attenuation: media.attenuation,
        attenuation_per_wavelength: media.attenuation_per_wavelength,
        attenuates,
        reflection,
    }))
}

/// The section's frequency, checked: needed for a line source.
fn frequency_of(a: &AmplitudesSpec) -> Result<Option<f64>, SceneError> {
    match a.frequency {
        Some(f) => Ok(Some(positive("amplitudes.frequency".into(), f)?)),
        None if a.source == SourceModel::Line => Err(SceneError::new(
            "amplitudes.frequency",
            "missing: a line source's amplitude depends on the frequency (give it in Hz, \
             with the scene's time unit s)",
        )),
        None => Ok(None),
    }
}
