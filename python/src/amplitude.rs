//! Amplitudes in Python (a scene with `"amplitudes"`): the columns of a `Rays` or an
//! `Arrivals` (`amplitude`, `spreading`, `coefficient`, `attenuation_db`, and why an amplitude
//! has no value), the fields of a `Ray` and the keys of a search's arrival's dict. A missing amplitude is NaN, never 0.

use eigenray::Amplitude;
use eigenray::amplitudes::{Complex64, NoAmplitude};
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// A complex number that is not one (a missing amplitude or coefficient).
const NO_NUMBER: Complex64 = Complex64::new(f64::NAN, f64::NAN);

/// The amplitude columns of a `Table`, one entry per ray, while they are filled.
pub(crate) struct AmplitudeColumns {
    /// The complex amplitude of each ray.
    value: Vec<Complex64>,
    /// Its geometric spreading.
    spreading: Vec<f64>,
    /// The product of its coefficients.
    coefficient: Vec<Complex64>,
    /// Its attenuation, dB.
    attenuation_db: Vec<f64>,
    /// Why it has no value (`None` where it has one, or where the ray has no time).
    reason: Vec<Option<NoAmplitude>>,
}

impl AmplitudeColumns {
    /// The bytes of one ray's entries.
    pub(crate) const BYTES_PER_RAY: u64 =
        16 + 8 + 16 + 8 + std::mem::size_of::<Option<NoAmplitude>>() as u64;

    /// The columns of `rays` rays, every entry missing until written.
    pub(crate) fn new(rays: usize) -> AmplitudeColumns {
        AmplitudeColumns {
            value: vec![NO_NUMBER; rays],
            spreading: vec![f64::NAN; rays],
            coefficient: vec![NO_NUMBER; rays],
            attenuation_db: vec![f64::NAN; rays],
            reason: vec![None; rays],
        }
    }

    /// All its rows, for writing.
    pub(crate) fn rows(&mut self) -> AmplitudeRows<'_> {
        AmplitudeRows {
            value: &mut self.value,
            spreading: &mut self.spreading,
            coefficient: &mut self.coefficient,
            attenuation_db: &mut self.attenuation_db,
            reason: &mut self.reason,
        }
    }

    /// The columns as numpy arrays, and the reasons (worded when read).
    pub(crate) fn finish(self, py: Python<'_>) -> (AmplitudeArrays, Vec<Option<NoAmplitude>>) {
        let arrays = AmplitudeArrays {
            value: self.value.into_pyarray(py).unbind(),
            spreading: self.spreading.into_pyarray(py).unbind(),
            coefficient: self.coefficient.into_pyarray(py).unbind(),
            attenuation_db: self.attenuation_db.into_pyarray(py).unbind(),
        };
        (arrays, self.reason)
    }
}

/// The amplitude arrays of a `Rays`, shape `(n,)` each.
pub(crate) struct AmplitudeArrays {
    /// The complex amplitude (complex128).
    pub(crate) value: Py<PyArray1<Complex64>>,
    /// The geometric spreading (float64).
    pub(crate) spreading: Py<PyArray1<f64>>,
    /// The product of the coefficients (complex128).
    pub(crate) coefficient: Py<PyArray1<Complex64>>,
    /// The attenuation, dB (float64).
    pub(crate) attenuation_db: Py<PyArray1<f64>>,
}

/// Rows of the amplitude columns: one slice per column, all of the same rows.
pub(crate) struct AmplitudeRows<'a> {
    /// The complex amplitude of each ray.
    pub(crate) value: &'a mut [Complex64],
    /// Its geometric spreading.
    pub(crate) spreading: &'a mut [f64],
    /// The product of its coefficients.
    pub(crate) coefficient: &'a mut [Complex64],
    /// Its attenuation, dB.
    pub(crate) attenuation_db: &'a mut [f64],
    /// Why it has no value.
    pub(crate) reason: &'a mut [Option<NoAmplitude>],
}

impl AmplitudeRows<'_> {
    /// The rows before `k` and from `k` on.
    pub(crate) fn split_at(self, k: usize) -> (Self, Self) {
        let (value, value_b) = self.value.split_at_mut(k);
        let (spreading, spreading_b) = self.spreading.split_at_mut(k);
        let (coefficient, coefficient_b) = self.coefficient.split_at_mut(k);
        let (attenuation_db, attenuation_db_b) = self.attenuation_db.split_at_mut(k);
        let (reason, reason_b) = self.reason.split_at_mut(k);
        (
            AmplitudeRows {
                value,
                spreading,
                coefficient,
                attenuation_db,
                reason,
            },
            AmplitudeRows {
                value: value_b,
                spreading: spreading_b,
                coefficient: coefficient_b,
                attenuation_db: attenuation_db_b,
                reason: reason_b,
            },
        )
    }

    /// Row `i`: `amplitude` (`None` for a ray without a time: every number NaN).
    #[inline]
    pub(crate) fn write(&mut self, i: usize, amplitude: Option<&Amplitude>) {
        let a = amplitude.copied().unwrap_or(Amplitude {
            value: NO_NUMBER,
            spreading: f64::NAN,
            coefficient: NO_NUMBER,
            attenuation_db: f64::NAN,
            reason: None,
        });
        self.value[i] = a.value;
        self.spreading[i] = a.spreading;
        self.coefficient[i] = a.coefficient;
        self.attenuation_db[i] = a.attenuation_db;
        self.reason[i] = a.reason;
    }
}

/// The reasons of a `Rays`' amplitudes in words (`None` where an amplitude has a value or its
/// ray has no time): the command-line tool's `amplitude_reason`.
pub(crate) fn reason_words(reasons: &[Option<NoAmplitude>]) -> Vec<Option<String>> {
    reasons.iter().map(|r| r.map(|r| r.to_string())).collect()
}

/// The amplitude of one `Ray` as Python values: `None` each where the scene does not ask for
/// amplitudes; NaN where the ray has no time or its amplitude no value.
pub(crate) struct RayAmplitude {
    /// The complex amplitude.
    pub(crate) amplitude: Option<Complex64>,
    /// The geometric spreading.
    pub(crate) spreading: Option<f64>,
    /// The product of the coefficients.
    pub(crate) coefficient: Option<Complex64>,
    /// The attenuation, dB.
    pub(crate) attenuation_db: Option<f64>,
    /// Why the amplitude has no value.
    pub(crate) reason: Option<String>,
}

impl RayAmplitude {
    /// The amplitude of a ray of a scene that asks for amplitudes when `asked`: `amplitude`
    /// (`None` for a ray without a time).
    pub(crate) fn new(asked: bool, amplitude: Option<&Amplitude>) -> RayAmplitude {
        if !asked {
            return RayAmplitude {
                amplitude: None,
                spreading: None,
                coefficient: None,
                attenuation_db: None,
                reason: None,
            };
        }
        match amplitude {
            Some(a) => RayAmplitude {
                amplitude: Some(a.value),
                spreading: Some(a.spreading),
                coefficient: Some(a.coefficient),
                attenuation_db: Some(a.attenuation_db),
                reason: a.reason.map(|r| r.to_string()),
            },
            None => RayAmplitude {
                amplitude: Some(NO_NUMBER),
                spreading: Some(f64::NAN),
                coefficient: Some(NO_NUMBER),
                attenuation_db: Some(f64::NAN),
                reason: None,
            },
        }
    }

    /// Its keys in a dict (`amplitude`, `spreading`, `coefficient`, `attenuation_db`,
    /// `amplitude_reason`), when the scene asks for amplitudes.
    pub(crate) fn set_items(self, d: &Bound<'_, PyDict>) -> PyResult<()> {
        if self.amplitude.is_none() {
            return Ok(());
        }
        d.set_item("amplitude", self.amplitude)?;
        d.set_item("spreading", self.spreading)?;
        d.set_item("coefficient", self.coefficient)?;
        d.set_item("attenuation_db", self.attenuation_db)?;
        d.set_item("amplitude_reason", self.reason)
    }
}
