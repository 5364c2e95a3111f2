//! `Tracer.search`: the arrivals of a scene's automatic search, as a list of dicts.

use eigenray::options::Stop;
use eigenray::search::SearchLimits;
use eigenray::{Scene, SearchArrival, Tracer, scene_parts::StepKind};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::amplitude::RayAmplitude;
use crate::convert::{kink_name, medium_names, points_array};
use crate::error::argument_error;
use crate::interrupt::interruptible;

/// The arrivals of the scene's `search` of `tracer` (see `Tracer.search`), searched with the
/// GIL released on a thread of its own (Ctrl-C stops it).
pub(crate) fn search_list<'py>(py: Python<'py>, tracer: &Tracer) -> PyResult<Bound<'py, PyList>> {
    let stop = Stop::new();
    let limits = SearchLimits::default();
    let search = || tracer.search_with(&limits, &|_| {}, Some(&stop));
    let arrivals = interruptible(py, &stop, search, || {})?
        .map_err(|e| argument_error(py, "search", e.to_string()))?
        .arrivals;
    let scene = tracer.scene();
    let list = PyList::empty(py);
    for a in &arrivals {
        list.append(search_arrival(py, scene, a)?)?;
    }
    Ok(list)
}

/// One arrival of a search as a dict (`source`, `receiver`, `steps`, `media`, `status`, ...).
fn search_arrival<'py>(
    py: Python<'py>,
    scene: &Scene,
    a: &SearchArrival,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("source", a.source)?;
    d.set_item("receiver", a.receiver)?;
    let steps = PyList::empty(py);
    for step in &a.steps {
        let s = PyDict::new(py);
        let kind = match step.kind {
            StepKind::Reflect => "reflect",
            StepKind::Refract => "refract",
        };
        s.set_item(kind, &scene.interfaces()[step.interface].name)?;
        steps.append(s)?;
    }
    d.set_item("steps", steps)?;
    let arrival = &a.arrival;
    d.set_item("media", medium_names(scene, arrival.media.iter().copied()))?;
    d.set_item("status", arrival.status.as_str())?;
    d.set_item("time", arrival.time)?;
    d.set_item("points", points_array(py, &arrival.points))?;
    d.set_item("iterations", arrival.iterations)?;
    d.set_item("residual", arrival.residual)?;
    d.set_item("reason", arrival.reason.map(|r| r.describe(scene)))?;
    d.set_item("kink", kink_name(arrival.kink))?;
    d.set_item("complete", a.complete)?;
    RayAmplitude::new(scene.amplitudes().is_some(), arrival.amplitude.as_ref()).set_items(&d)?;
    Ok(d)
}
