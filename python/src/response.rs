//! `Tracer.impulse_response`, `Tracer.pressure` and `Tracer.transmission_loss`: what arrives
//! at each receiver, from every echo of the scene, as numpy arrays.

use eigenray::amplitude::Complex64;
use eigenray::options::Run;
use eigenray::response::{
    Echo, EchoError, ImpulseResponses, Summed, echoes_of_scene, pressure_of_scene_into,
    transmission_loss_of_scene_into,
};
use eigenray::scene::{ImpulseResponseOptions, ImpulseResponseSpec, TransmissionLossMode};
use eigenray::{Scene, Tracer};
use numpy::ndarray::{Array1, ArrayD, IxDyn};
use numpy::{IntoPyArray, PyArrayDyn};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{argument_error, scene_error};
use crate::interrupt::interruptible;

/// Every echo of the scene (its paths' rays and its search's arrivals), found with the GIL
/// released; refused, naming `amplitudes`, for a scene that does not ask for them.
fn scene_echoes(py: Python<'_>, tracer: &Tracer) -> PyResult<Vec<Echo>> {
    needs_amplitudes(py, tracer.scene())?;
    let run = Run::new();
    interruptible(py, &run, || echoes_of_scene(tracer, &run), || {})?
        .map_err(|e| argument_error(py, "scene", e.to_string()))
}

/// The response settings: the arguments where given (`rate` and `duration` together), else
/// the scene's `impulse_response`.
fn response_options(
    py: Python<'_>,
    scene: &Scene,
    rate: Option<f64>,
    duration: Option<f64>,
    taps: Option<usize>,
) -> PyResult<ImpulseResponseOptions> {
    match (rate, duration, scene.impulse_response()) {
        (Some(rate), Some(duration), _) => {
            let mut spec = ImpulseResponseSpec::new(rate, duration);
            spec.taps = taps;
            ImpulseResponseOptions::of_spec("impulse_response", &spec)
                .map_err(|e| scene_error(py, &e))
        }
        (None, None, Some(o)) => match taps {
            Some(t) => ImpulseResponseOptions::new("impulse_response", o.rate, o.samples, t)
                .map_err(|e| scene_error(py, &e)),
            None => Ok(*o),
        },
        (None, None, None) => Err(argument_error(
            py,
            "impulse_response",
            "the scene has no `impulse_response` section: pass rate= and duration=",
        )),
        _ => Err(argument_error(
            py,
            "impulse_response",
            "give rate= and duration= together (or neither, for the scene's settings)",
        )),
    }
}

/// See `Tracer.impulse_response`.
pub(crate) fn impulse_response<'py>(
    py: Python<'py>,
    tracer: &Tracer,
    rate: Option<f64>,
    duration: Option<f64>,
    taps: Option<usize>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let scene = tracer.scene();
    let options = response_options(py, scene, rate, duration, taps)?;
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    let responses = ImpulseResponses::new(&options, s, r);
    needs_amplitudes(py, scene)?;
    let too_large = || {
        PyMemoryError::new_err(format!(
            "impulse responses of {s} sources × {r} receivers × {} samples",
            options.samples
        ))
    };
    let mut data =
        buffer(responses.checked_len().ok_or_else(too_large)?, 0.0).ok_or_else(too_large)?;
    // Every echo rendered as the search finds it, on a thread of its own: Ctrl-C stops it.
    let run = Run::new();
    let summed = interruptible(
        py,
        &run,
        || responses.render_scene_into(tracer, &run, &mut data),
        || {},
    )?;
    summed_or_error(py, summed)?;
    let mut shape = grid_shape(scene);
    shape.push(options.samples);
    let array =
        ArrayD::from_shape_vec(IxDyn(&shape), data).expect("the responses fill their shape");
    Ok(array.into_pyarray(py))
}

/// `[sources, receivers]`, or `[sources, nx, ny]` for a scene whose receivers are a grid.
fn grid_shape(scene: &Scene) -> Vec<usize> {
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    match scene.receiver_grid().and_then(|g| g.shape()) {
        Some((nx, ny)) if nx * ny == r => vec![s, nx, ny],
        _ => vec![s, r],
    }
}

/// A buffer of `n` copies of `zero`, or `None` where it cannot be allocated.
fn buffer<T: Clone>(n: usize, zero: T) -> Option<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).ok()?;
    v.resize(n, zero);
    Some(v)
}

/// Refuses, naming `amplitudes`, a scene that does not ask for them.
fn needs_amplitudes(py: Python<'_>, scene: &Scene) -> PyResult<()> {
    if scene.amplitudes().is_none() {
        return Err(argument_error(
            py,
            "amplitudes",
            "the scene does not ask for amplitudes: add \"amplitudes\": {\"source\": \"point\"} \
             (or another source model)",
        ));
    }
    Ok(())
}

/// A streamed response's result, its error named as the scene's.
fn summed_or_error(py: Python<'_>, summed: Result<Summed, EchoError>) -> PyResult<Summed> {
    summed.map_err(|e| argument_error(py, "scene", e.to_string()))
}

/// The frequency: the argument, else the scene's `amplitudes.frequency`.
fn frequency_of(py: Python<'_>, scene: &Scene, frequency: Option<f64>) -> PyResult<f64> {
    let f = frequency.or_else(|| scene.amplitudes().and_then(|a| a.frequency));
    match f {
        Some(f) if f.is_finite() && f > 0.0 => Ok(f),
        Some(_) => Err(argument_error(
            py,
            "frequency",
            "must be a finite number > 0",
        )),
        None => Err(argument_error(
            py,
            "frequency",
            "pass frequency= (the scene's `amplitudes` gives none)",
        )),
    }
}

/// See `Tracer.pressure`: every echo summed as the search finds it.
pub(crate) fn pressure<'py>(
    py: Python<'py>,
    tracer: &Tracer,
    frequency: Option<f64>,
) -> PyResult<Bound<'py, PyArrayDyn<Complex64>>> {
    let scene = tracer.scene();
    needs_amplitudes(py, scene)?;
    let f = frequency_of(py, scene, frequency)?;
    let n = scene.sources().len() * scene.receivers().len();
    let mut p = buffer(n, Complex64::new(0.0, 0.0))
        .ok_or_else(|| PyMemoryError::new_err(format!("pressures of {n} pairs")))?;
    let run = Run::new();
    let summed = interruptible(
        py,
        &run,
        || pressure_of_scene_into(tracer, f, &run, &mut p),
        || {},
    )?;
    summed_or_error(py, summed)?;
    let array = ArrayD::from_shape_vec(IxDyn(&grid_shape(scene)), p).expect("one a pair");
    Ok(array.into_pyarray(py))
}

/// The mode of `Tracer.transmission_loss`: the argument, else the scene's, else coherent.
fn mode_of(py: Python<'_>, scene: &Scene, mode: Option<&str>) -> PyResult<TransmissionLossMode> {
    match mode {
        None => Ok(scene.transmission_loss().unwrap_or_default()),
        Some("coherent") => Ok(TransmissionLossMode::Coherent),
        Some("incoherent") => Ok(TransmissionLossMode::Incoherent),
        Some(other) => Err(argument_error(
            py,
            "mode",
            format!("must be \"coherent\" or \"incoherent\", not {other:?}"),
        )),
    }
}

/// See `Tracer.transmission_loss`: every echo summed as the search finds it.
pub(crate) fn transmission_loss_db<'py>(
    py: Python<'py>,
    tracer: &Tracer,
    frequency: Option<f64>,
    mode: Option<&str>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let scene = tracer.scene();
    needs_amplitudes(py, scene)?;
    let f = frequency_of(py, scene, frequency)?;
    let mode = mode_of(py, scene, mode)?;
    let n = scene.sources().len() * scene.receivers().len();
    let mut tl = buffer(n, 0.0)
        .ok_or_else(|| PyMemoryError::new_err(format!("transmission loss of {n} pairs")))?;
    let run = Run::new();
    let summed = interruptible(
        py,
        &run,
        || transmission_loss_of_scene_into(tracer, f, mode, &run, &mut tl),
        || {},
    )?;
    summed_or_error(py, summed)?;
    let array = ArrayD::from_shape_vec(IxDyn(&grid_shape(scene)), tl).expect("one a pair");
    Ok(array.into_pyarray(py))
}

/// See `Tracer.echoes`.
pub(crate) fn echoes<'py>(py: Python<'py>, tracer: &Tracer) -> PyResult<Bound<'py, PyDict>> {
    let echoes = scene_echoes(py, tracer)?;
    let d = PyDict::new(py);
    let column = |f: fn(&Echo) -> u32| Array1::from_iter(echoes.iter().map(f)).into_pyarray(py);
    d.set_item("source", column(|e| e.source as u32))?;
    d.set_item("receiver", column(|e| e.receiver as u32))?;
    d.set_item("order", column(|e| e.order as u32))?;
    d.set_item("diffractions", column(|e| e.diffractions as u32))?;
    d.set_item("vertical", column(|e| e.vertical_reflections as u32))?;
    d.set_item(
        "time",
        Array1::from_iter(echoes.iter().map(|e| e.time)).into_pyarray(py),
    )?;
    d.set_item(
        "amplitude",
        Array1::from_iter(echoes.iter().map(|e| e.amplitude)).into_pyarray(py),
    )?;
    Ok(d)
}

/// See `Tracer.room_parameters`.
pub(crate) fn room_parameters<'py>(
    py: Python<'py>,
    tracer: &Tracer,
    rate: Option<f64>,
    duration: Option<f64>,
) -> PyResult<Bound<'py, pyo3::types::PyList>> {
    let scene = tracer.scene();
    let options = response_options(py, scene, rate, duration, None)?;
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    let responses = ImpulseResponses::new(&options, s, r);
    needs_amplitudes(py, scene)?;
    if responses
        .checked_len()
        .and_then(|n| buffer(n, 0.0f64))
        .is_none()
    {
        return Err(PyMemoryError::new_err(format!(
            "impulse responses of {s} sources × {r} receivers × {} samples",
            options.samples
        )));
    }
    // The responses rendered as the search finds each echo, on a thread of its own: Ctrl-C
    // stops it.
    let run = Run::new();
    let found = interruptible(
        py,
        &run,
        || eigenray::response::room_parameters_of_scene(tracer, &responses, &run),
        || {},
    )?
    .map_err(|e| argument_error(py, "scene", e.to_string()))?;
    let out = pyo3::types::PyList::empty(py);
    for (k, p) in found.parameters.iter().enumerate() {
        let d = PyDict::new(py);
        d.set_item("source", k / r.max(1))?;
        d.set_item("receiver", k % r.max(1))?;
        d.set_item("first_arrival", p.first_arrival)?;
        for (name, v) in [
            ("edt", &p.edt),
            ("t20", &p.t20),
            ("t30", &p.t30),
            ("c50", &p.c50),
            ("c80", &p.c80),
            ("d50", &p.d50),
        ] {
            d.set_item(name, v.value)?;
            if let Some(why) = &v.reason {
                d.set_item(format!("{name}_reason"), why)?;
            }
        }
        out.append(d)?;
    }
    Ok(out)
}
