//! Pickling (`multiprocessing`, `concurrent.futures`, joblib, Dask, Ray): a `Scene` and a
//! `Tracer` as the scene's JSON document (the library's `Scene::to_json`, which reads back to
//! the same scene bit for bit), a `Rays` as its arrays, its names and its reasons as codes.

use std::sync::{Arc, Mutex};

use eigenray::amplitude::{DiffractionCase, NoAmplitude};
use eigenray::trace::Threshold;
use eigenray::{Reason, Scene};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::columns::QuantityArrays;
use crate::convert::status_names;
use crate::error::check_memory;
use crate::rays_data::{PyRays, Reasons};

/// The rules with a threshold, by their code in a pickled `Rays`.
const THRESHOLDS: [Threshold; 4] = [
    Threshold::VanishedLeg,
    Threshold::ShortLeg,
    Threshold::Grazing,
    Threshold::Side,
];

/// A reason as three numbers: its kind (1, 2, …) and its indices (0 where it has none).
fn reason_code(r: Reason) -> [u64; 3] {
    let n = |i: usize| i as u64;
    match r {
        Reason::LeavesEnd { step } => [1, n(step), 0],
        Reason::WrongSide { step } => [2, n(step), 0],
        Reason::AtVertex { step } => [3, n(step), 0],
        Reason::Crosses { leg, interface } => [4, n(leg), n(interface)],
        Reason::NoMedium { leg } => [5, n(leg), 0],
        Reason::MediaUnsettled => [6, 0, 0],
        Reason::Coincident { step } => [7, n(step), 0],
        Reason::IterationLimit => [8, 0, 0],
        Reason::BeyondEnd { step } => [9, n(step), 0],
        Reason::NoStationaryPath => [10, 0, 0],
        Reason::SearchLimit => [11, 0, 0],
        Reason::Undecided { rule } => {
            let code = THRESHOLDS.iter().position(|&t| t == rule);
            [12, n(code.expect("every rule has a code")), 0]
        }
        Reason::AtEnd { step } => [13, n(step), 0],
    }
}

/// The reason of [`reason_code`]'s numbers.
fn reason_of(code: [u64; 3]) -> Option<Reason> {
    let [kind, a, b] = code;
    let (a, b) = (usize::try_from(a).ok()?, usize::try_from(b).ok()?);
    Some(match kind {
        1 => Reason::LeavesEnd { step: a },
        2 => Reason::WrongSide { step: a },
        3 => Reason::AtVertex { step: a },
        4 => Reason::Crosses {
            leg: a,
            interface: b,
        },
        5 => Reason::NoMedium { leg: a },
        6 => Reason::MediaUnsettled,
        7 => Reason::Coincident { step: a },
        8 => Reason::IterationLimit,
        9 => Reason::BeyondEnd { step: a },
        10 => Reason::NoStationaryPath,
        11 => Reason::SearchLimit,
        12 => Reason::Undecided {
            rule: *THRESHOLDS.get(a)?,
        },
        13 => Reason::AtEnd { step: a },
        _ => return None,
    })
}

/// Why an amplitude has none, as three numbers: its `.npy` code, its index, 0.
fn no_amplitude_code(r: NoAmplitude) -> [u64; 3] {
    let index = match r {
        NoAmplitude::ConvertedReflection { step }
        | NoAmplitude::NoMediumAcross { step }
        | NoAmplitude::Grazing { step } => step,
        NoAmplitude::VanishedLeg { leg } => leg,
        NoAmplitude::Diffraction { step, case } => {
            let place = DiffractionCase::ALL.iter().position(|&c| c == case);
            return [u64::from(r.code()), step as u64, place.unwrap_or(0) as u64];
        }
        NoAmplitude::Vertex
        | NoAmplitude::Obstructed
        | NoAmplitude::Caustic
        | NoAmplitude::OnAxis
        | NoAmplitude::SourceOffAxis
        | NoAmplitude::UnknownMedia => 0,
    };
    [u64::from(r.code()), index as u64, 0]
}

/// The reason of [`no_amplitude_code`]'s numbers.
fn no_amplitude_of(code: [u64; 3]) -> Option<NoAmplitude> {
    let place = usize::try_from(code[0]).ok()?.checked_sub(1)?;
    let i = usize::try_from(code[1]).ok()?;
    Some(match *NoAmplitude::CODES.get(place)? {
        NoAmplitude::ConvertedReflection { .. } => NoAmplitude::ConvertedReflection { step: i },
        NoAmplitude::NoMediumAcross { .. } => NoAmplitude::NoMediumAcross { step: i },
        NoAmplitude::Grazing { .. } => NoAmplitude::Grazing { step: i },
        NoAmplitude::VanishedLeg { .. } => NoAmplitude::VanishedLeg { leg: i },
        NoAmplitude::Diffraction { .. } => NoAmplitude::Diffraction {
            step: i,
            case: *DiffractionCase::ALL.get(usize::try_from(code[2]).ok()?)?,
        },
        other => other,
    })
}

/// The entries of `items` that are not `None`: their rows and their codes, three a row.
fn sparse<T: Copy>(items: &[Option<T>], code: impl Fn(T) -> [u64; 3]) -> (Vec<i64>, Vec<u64>) {
    let (mut rows, mut codes) = (Vec::new(), Vec::new());
    for (i, item) in items.iter().enumerate() {
        if let Some(r) = item {
            rows.push(i as i64);
            codes.extend(code(*r));
        }
    }
    (rows, codes)
}

/// [`sparse`]'s rows and codes under `KEY_rows` (`(k,)`) and `KEY_codes` (`(k, 3)`).
fn set_sparse(
    d: &Bound<'_, PyDict>,
    key: &str,
    (rows, codes): (Vec<i64>, Vec<u64>),
) -> PyResult<()> {
    let py = d.py();
    let codes = Array2::from_shape_vec((rows.len(), 3), codes).expect("three numbers a row");
    d.set_item(format!("{key}_rows"), rows.into_pyarray(py))?;
    d.set_item(format!("{key}_codes"), codes.into_pyarray(py))
}

/// `n` entries, `None` but at the rows of [`sparse`]'s arrays under `key`.
fn dense<T: Copy>(
    state: &Bound<'_, PyDict>,
    key: &str,
    n: usize,
    of: impl Fn([u64; 3]) -> Option<T>,
) -> PyResult<Vec<Option<T>>> {
    let rows: Bound<'_, PyArray1<i64>> = item(state, &format!("{key}_rows"))?;
    let codes: Bound<'_, PyArray2<u64>> = item(state, &format!("{key}_codes"))?;
    let (rows, codes) = (rows.to_vec()?, codes.to_owned_array());
    let bad = || PyValueError::new_err(format!("Rays state: bad `{key}` codes"));
    if codes.dim() != (rows.len(), 3) {
        return Err(bad());
    }
    // (A broadcast state holds many rows in little memory: these entries are allocated.)
    let bytes = (n as u64).checked_mul(std::mem::size_of::<Option<T>>() as u64);
    check_memory(&format!("Rays state: {n} rays"), bytes)?;
    let mut out = vec![None; n];
    for (row, code) in rows.iter().zip(codes.rows()) {
        let entry = usize::try_from(*row)
            .ok()
            .and_then(|i| out.get_mut(i))
            .ok_or_else(bad)?;
        *entry = Some(of([code[0], code[1], code[2]]).ok_or_else(bad)?);
    }
    Ok(out)
}

/// The value under `key` of a pickled state, as a `T`.
fn item<'py, T>(state: &Bound<'py, PyDict>, key: &str) -> PyResult<T>
where
    T: for<'a> FromPyObject<'a, 'py>,
{
    let value = state
        .get_item(key)?
        .ok_or_else(|| PyValueError::new_err(format!("Rays state: no `{key}`")))?;
    value.extract::<T>().map_err(|e| {
        let e: PyErr = e.into();
        PyValueError::new_err(format!("Rays state: `{key}`: {e}"))
    })
}

/// The state of `rays` that [`rays_of_state`] reads back: its arrays (shared, not copied:
/// pickling copies them), its names, and its reasons as sparse codes.
pub(crate) fn rays_state<'py>(py: Python<'py>, rays: &PyRays) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("source", &rays.source)?;
    d.set_item("receiver", &rays.receiver)?;
    d.set_item("path", &rays.path)?;
    d.set_item("status", &rays.status)?;
    d.set_item("time", &rays.time)?;
    d.set_item("points", &rays.points)?;
    d.set_item("num_points", &rays.num_points)?;
    d.set_item("media", &rays.media)?;
    d.set_item("iterations", &rays.iterations)?;
    d.set_item("residual", &rays.residual)?;
    d.set_item("path_names", &rays.path_names)?;
    d.set_item("media_names", &rays.media_names)?;
    d.set_item("arrival", &rays.arrival)?;
    d.set_item("kink", &rays.kink)?;
    d.set_item("complete", &rays.complete)?;
    rays.quantities.set_items(&d)?;
    // The scene (for the rays' curves), as its document.
    let scene = py.detach(|| rays.scene.lock().ok()?.as_ref().map(|s| s.to_json()));
    d.set_item("scene", scene)?;
    // The GIL released while waiting, as the `reason` getter does: a `trace(out=...)` of
    // these rays in another thread holds the lock through its batch.
    let reasons = py.detach(|| {
        let reasons = rays.reasons.lock().ok()?;
        Some((
            reasons.interfaces.clone(),
            sparse(&reasons.codes, reason_code),
            reasons
                .whys
                .iter()
                .map(|w| (w.column.name, sparse(&w.reasons, no_amplitude_code)))
                .collect::<Vec<_>>(),
        ))
    });
    let (interfaces, codes, whys) =
        reasons.ok_or_else(|| PyValueError::new_err("the rays' reasons are poisoned"))?;
    d.set_item("interfaces", interfaces)?;
    set_sparse(&d, "reason", codes)?;
    for (name, why) in whys {
        set_sparse(&d, name, why)?;
    }
    Ok(d)
}

/// The scene of a pickled state (its document under `"scene"`; `None` for none).
fn scene_of_state(state: &Bound<'_, PyDict>) -> PyResult<Option<Arc<Scene>>> {
    let Some(text) = state.get_item("scene")?.filter(|v| !v.is_none()) else {
        return Ok(None);
    };
    let text: String = text.extract()?;
    let scene = Scene::from_json(&text)
        .map_err(|e| PyValueError::new_err(format!("Rays state: `scene`: {e}")))?;
    Ok(Some(Arc::new(scene)))
}

/// The `Rays` of a state of [`rays_state`], its arrays checked for their types and lengths.
///
/// # Errors
/// `ValueError` for a state that is not one.
pub(crate) fn rays_of_state(state: &Bound<'_, PyDict>) -> PyResult<PyRays> {
    let time: Bound<'_, PyArray1<f64>> = item(state, "time")?;
    let n = time.len();
    let points: Bound<'_, PyArray3<f64>> = item(state, "points")?;
    let media: Bound<'_, PyArray2<i32>> = item(state, "media")?;
    let width = points.shape()[1];
    let shapes_agree =
        points.shape() == [n, width, 2] && width >= 2 && media.shape() == [n, width - 1];
    if !shapes_agree {
        return Err(PyValueError::new_err(
            "Rays state: `points` and `media` do not fit the rays",
        ));
    }
    /// A column of `n` entries.
    fn column<'py, T: numpy::Element + 'static>(
        state: &Bound<'py, PyDict>,
        key: &str,
        n: usize,
    ) -> PyResult<Py<PyArray1<T>>> {
        let a: Bound<'py, PyArray1<T>> = item(state, key)?;
        if a.len() != n {
            return Err(PyValueError::new_err(format!(
                "Rays state: `{key}` has {} entries for {n} rays",
                a.len()
            )));
        }
        Ok(a.unbind())
    }
    let optional =
        |key: &str| -> PyResult<bool> { Ok(state.get_item(key)?.is_some_and(|v| !v.is_none())) };
    let (quantities, whys) = QuantityArrays::of_state(
        state,
        |key| column(state, key, n),
        |key| column(state, key, n),
        |key| dense(state, key, n, no_amplitude_of),
    )?;
    let codes = dense(state, "reason", n, reason_of)?;
    let any = codes.iter().any(Option::is_some);
    let stationary = optional("arrival")?;
    let kink: Option<Vec<Option<String>>> = if stationary {
        Some(item(state, "kink")?)
    } else {
        None
    };
    if kink.as_ref().is_some_and(|k| k.len() != n) {
        return Err(PyValueError::new_err(
            "Rays state: `kink` does not fit the rays",
        ));
    }
    Ok(PyRays {
        source: column(state, "source", n)?,
        receiver: column(state, "receiver", n)?,
        path: column(state, "path", n)?,
        status: column(state, "status", n)?,
        time: time.unbind(),
        points: points.unbind(),
        num_points: column(state, "num_points", n)?,
        media: media.unbind(),
        iterations: column(state, "iterations", n)?,
        residual: column(state, "residual", n)?,
        scene: Mutex::new(scene_of_state(state)?),
        reasons: Mutex::new(Reasons {
            codes,
            any,
            interfaces: item(state, "interfaces")?,
            whys,
        }),
        status_names: status_names(),
        path_names: item(state, "path_names")?,
        media_names: item(state, "media_names")?,
        arrival: stationary
            .then(|| column(state, "arrival", n))
            .transpose()?,
        kink,
        complete: stationary
            .then(|| column(state, "complete", n))
            .transpose()?,
        quantities,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every reason, each index its own nonzero number (so that an index read back as 0, or
    /// as another field, shows).
    const REASONS: [Reason; 13] = [
        Reason::LeavesEnd { step: 3 },
        Reason::WrongSide { step: 1 },
        Reason::AtVertex { step: 7 },
        Reason::Crosses {
            leg: 2,
            interface: 5,
        },
        Reason::NoMedium { leg: 4 },
        Reason::MediaUnsettled,
        Reason::Coincident { step: 6 },
        Reason::IterationLimit,
        Reason::BeyondEnd { step: 8 },
        Reason::NoStationaryPath,
        Reason::SearchLimit,
        Reason::Undecided {
            rule: Threshold::Side,
        },
        Reason::AtEnd { step: 9 },
    ];

    /// Every reason reads back from its code as itself, every rule of `Undecided` too; the
    /// kinds are 1 to 13, one a reason (13 is `AtEnd`); 0 and 14 are no reason.
    #[test]
    fn every_reason_reads_back() {
        let reasons = REASONS
            .into_iter()
            .chain(THRESHOLDS.map(|rule| Reason::Undecided { rule }));
        for r in reasons {
            assert_eq!(reason_of(reason_code(r)), Some(r));
        }
        let mut kinds: Vec<u64> = REASONS.iter().map(|&r| reason_code(r)[0]).collect();
        kinds.sort_unstable();
        assert_eq!(kinds, (1..=13).collect::<Vec<u64>>());
        assert_eq!(reason_of([13, 4, 0]), Some(Reason::AtEnd { step: 4 }));
        assert_eq!(reason_of([0, 0, 0]), None);
        assert_eq!(reason_of([14, 0, 0]), None);
        assert_eq!(reason_of([12, THRESHOLDS.len() as u64, 0]), None);
    }

    /// Every reason for no amplitude reads back from its code as itself, its step or leg
    /// index included (each a different nonzero number: a converted reflection at step 3
    /// comes back at step 3); its kind is its place in `NoAmplitude::CODES`, plus 1; 0 and
    /// one past the table are no reason.
    #[test]
    fn every_reason_for_no_amplitude_reads_back() {
        let reasons = [
            NoAmplitude::Vertex,
            NoAmplitude::Obstructed,
            NoAmplitude::ConvertedReflection { step: 3 },
            NoAmplitude::NoMediumAcross { step: 5 },
            NoAmplitude::Grazing { step: 7 },
            NoAmplitude::VanishedLeg { leg: 2 },
            NoAmplitude::Caustic,
            NoAmplitude::OnAxis,
            NoAmplitude::SourceOffAxis,
            NoAmplitude::UnknownMedia,
            NoAmplitude::Diffraction {
                step: 4,
                case: DiffractionCase::IntoWedge,
            },
        ];
        assert_eq!(reasons.len(), NoAmplitude::CODES.len());
        for (k, r) in reasons.into_iter().enumerate() {
            let code = no_amplitude_code(r);
            assert_eq!(code[0], k as u64 + 1, "{r:?}");
            assert_eq!(NoAmplitude::CODES[k].name(), r.name());
            assert_eq!(no_amplitude_of(code), Some(r));
        }
        assert_eq!(
            no_amplitude_of([3, 11, 0]),
            Some(NoAmplitude::ConvertedReflection { step: 11 })
        );
        assert_eq!(no_amplitude_of([0, 0, 0]), None);
        let past = NoAmplitude::CODES.len() as u64 + 1;
        assert_eq!(no_amplitude_of([past, 0, 0]), None);
    }
}
