//! `Tracer.impulse_response`, `Tracer.pressure` and `Tracer.transmission_loss`: what arrives
//! at each receiver, from every echo of the scene, as numpy arrays.

use eigenray::amplitude::Complex64;
use eigenray::options::Run;
use eigenray::response::{
    Echo, ImpulseResponses, echoes_of_scene, pressure_into, transmission_loss,
};
use eigenray::scene::ImpulseResponseOptions;
use eigenray::scene::ImpulseResponseSpec;
use eigenray::{Scene, Tracer};
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{argument_error, scene_error};
use crate::interrupt::interruptible;

/// Every echo of the scene (its paths' rays and its search's arrivals), found with the GIL
/// released; refused, naming `amplitudes`, for a scene that does not ask for them.
fn scene_echoes(py: Python<'_>, tracer: &Tracer) -> PyResult<Vec<Echo>> {
    if tracer.scene().amplitudes().is_none() {
        return Err(argument_error(
            py,
            "amplitudes",
            "the scene does not ask for amplitudes: add \"amplitudes\": {\"source\": \"point\"} \
             (or another source model)",
        ));
    }
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
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let scene = tracer.scene();
    let options = response_options(py, scene, rate, duration, taps)?;
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    let responses = ImpulseResponses::new(&options, s, r);
    let echoes = scene_echoes(py, tracer)?;
    // Rendered on a thread of its own too: Ctrl-C stops it between echoes.
    let run = Run::new();
    let data =
        interruptible(py, &run, || responses.render(echoes, &run), || {})?.map_err(|_| {
            PyMemoryError::new_err(format!(
                "impulse responses of {s} sources × {r} receivers × {} samples",
                options.samples
            ))
        })?;
    let array = Array3::from_shape_vec((s, r, options.samples), data)
        .expect("the responses fill their shape");
    Ok(array.into_pyarray(py))
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

/// The pressures of `Tracer.pressure`, `[sources, receivers]`.
fn pressures(
    py: Python<'_>,
    tracer: &Tracer,
    frequency: Option<f64>,
) -> PyResult<Array2<Complex64>> {
    let scene = tracer.scene();
    let f = frequency_of(py, scene, frequency)?;
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    let echoes = scene_echoes(py, tracer)?;
    let mut p = vec![Complex64::new(0.0, 0.0); s * r];
    if s > 0 {
        let run = Run::new();
        interruptible(
            py,
            &run,
            || pressure_into(echoes, f, s, &run, &mut p),
            || {},
        )?;
    }
    Ok(Array2::from_shape_vec((s, r), p).expect("one pressure a pair"))
}

/// See `Tracer.pressure`.
pub(crate) fn pressure<'py>(
    py: Python<'py>,
    tracer: &Tracer,
    frequency: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<Complex64>>> {
    Ok(pressures(py, tracer, frequency)?.into_pyarray(py))
}

/// See `Tracer.transmission_loss`.
pub(crate) fn transmission_loss_db<'py>(
    py: Python<'py>,
    tracer: &Tracer,
    frequency: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let tl = pressures(py, tracer, frequency)?.mapv(transmission_loss);
    Ok(tl.into_pyarray(py))
}

/// See `Tracer.echoes`.
pub(crate) fn echoes<'py>(py: Python<'py>, tracer: &Tracer) -> PyResult<Bound<'py, PyDict>> {
    let echoes = scene_echoes(py, tracer)?;
    let d = PyDict::new(py);
    let column = |f: fn(&Echo) -> u32| Array1::from_iter(echoes.iter().map(f)).into_pyarray(py);
    d.set_item("source", column(|e| e.source as u32))?;
    d.set_item("receiver", column(|e| e.receiver as u32))?;
    d.set_item("order", column(|e| e.order as u32))?;
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
