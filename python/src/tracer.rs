//! `Tracer`: a prepared scene and everything asked of it, each call converting its arguments,
//! calling the library and converting the result (the work is in the other modules).

use std::sync::{Arc, Mutex, PoisonError, RwLock, RwLockReadGuard, RwLockWriteGuard, TryLockError};

use eigenray::amplitude::Complex64;
use eigenray::options::Run;
use eigenray::output::columns::{Entry, Schema};
use eigenray::{
    Arrival, Gradient, Point, PointSensitivities, Scene, SceneError, Tracer, Workspace,
    batch::BatchScratch,
};
use numpy::PyArrayDyn;
use pyo3::exceptions::{PyIndexError, PyKeyError, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};

use crate::arrivals::PyArrivals;
use crate::convert::{named_index, point_arg, points_arg};
use crate::error::{argument_error, check_memory, scene_error};
use crate::gradient::PyGradient;
use crate::gradients::PyGradients;
use crate::interrupt::interruptible;
use crate::progress::{Progress, Reports};
use crate::ray::PyRay;
use crate::rays::PyRays;
use crate::response;
use crate::scene::PyScene;
use crate::search::search_arrivals;
use crate::sensitivities::PyPointSensitivities;
use crate::table::{Table, pairs_table, stationary_table, width};
use crate::trace::trace_rays;

/// Traces the rays of a scene. `Tracer(scene)` prepares it once (region lookup, segment
/// hierarchies); every call after that reuses it.
///
/// Calls from several Python threads at once run side by side: the tracer is shared (read)
/// by every call and changed (`set_*`) only between them; each call takes the scratch it
/// reuses if no other call holds it, else works with its own.
#[pyclass(module = "eigenray", name = "Tracer", frozen)]
pub(crate) struct PyTracer {
    /// The library's tracer, which owns its scene: read by the calls, written by `set_*`.
    tracer: RwLock<Tracer>,
    /// What the next `trace` reuses (the rays in solving order, for receivers solved in a
    /// spatial order).
    scratch: Mutex<BatchScratch>,
    /// What the one-ray calls reuse.
    workspace: Mutex<Workspace>,
    /// The last `stationary_paths`' arrivals (reused).
    arrivals: Mutex<Vec<Arrival>>,
    /// The last `gradient`'s derivatives (reused).
    gradient: Mutex<Gradient>,
}

/// The value in `lock` if no other call holds it, else a fresh one (a call never waits for
/// another's scratch, nor fails for it); given back to the lock at the end if it came from it.
fn scratch<T: Default, R>(lock: &Mutex<T>, f: impl FnOnce(&mut T) -> R) -> R {
    match lock.try_lock() {
        Ok(mut held) => f(&mut held),
        Err(TryLockError::Poisoned(poisoned)) => f(&mut poisoned.into_inner()),
        Err(TryLockError::WouldBlock) => f(&mut T::default()),
    }
}

impl PyTracer {
    /// The tracer, for a call that reads it (several at once).
    fn read(&self) -> RwLockReadGuard<'_, Tracer> {
        self.tracer.read().unwrap_or_else(PoisonError::into_inner)
    }

    /// The tracer, for a call that changes it: waits (the GIL released) for the calls that
    /// read it to end.
    fn write(&self, py: Python<'_>) -> RwLockWriteGuard<'_, Tracer> {
        loop {
            match self.tracer.try_write() {
                Ok(tracer) => return tracer,
                Err(TryLockError::Poisoned(poisoned)) => return poisoned.into_inner(),
                Err(TryLockError::WouldBlock) => {
                    py.detach(|| std::thread::sleep(std::time::Duration::from_millis(1)));
                }
            }
        }
    }
}

/// The index of a path of `scene` given by name or index (`None`: path 0).
fn path_index(py: Python<'_>, scene: &Scene, path: Option<&Bound<'_, PyAny>>) -> PyResult<usize> {
    let Some(path) = path else { return Ok(0) };
    if let Ok(name) = path.extract::<&str>() {
        return scene
            .paths()
            .iter()
            .position(|p| p.name.as_deref() == Some(name))
            .ok_or_else(|| PyKeyError::new_err(format!("no path is named `{name}`")));
    }
    let index: i64 = path
        .extract()
        .map_err(|_| argument_error(py, "path", "needs a path index or a path name"))?;
    usize::try_from(index)
        .ok()
        .filter(|&i| i < scene.paths().len())
        .ok_or_else(|| {
            PyIndexError::new_err(format!(
                "path index {index} is out of range (the scene has {} paths)",
                scene.paths().len()
            ))
        })
}

/// The arguments of a one-ray call on `scene`: a source, a receiver and a path (index or
/// name, default 0), checked for a ray.
fn ray_arguments(
    py: Python<'_>,
    scene: &Scene,
    source: &Bound<'_, PyAny>,
    receiver: &Bound<'_, PyAny>,
    path: Option<&Bound<'_, PyAny>>,
) -> PyResult<(Point, Point, usize)> {
    let path = path_index(py, scene, path)?;
    let (source, receiver) = checked_points(py, scene, source, receiver, path)?;
    Ok((source, receiver, path))
}

/// A source and a receiver from Python points, checked for a ray of path `path` of `scene`.
fn checked_points(
    py: Python<'_>,
    scene: &Scene,
    source: &Bound<'_, PyAny>,
    receiver: &Bound<'_, PyAny>,
    path: usize,
) -> PyResult<(Point, Point)> {
    let source = point_arg(py, "source", source)?;
    let receiver = point_arg(py, "receiver", receiver)?;
    scene
        .check_solve(source, receiver, path)
        .map_err(|e| scene_error(py, &e))?;
    Ok((source, receiver))
}

/// Bytes a vertex of an interface costs a tracer (the polyline, the segment index, the
/// hierarchy and the region lookup's triangulation; generous).
const BYTES_PER_VERTEX: u64 = 512;

#[pymethods]
impl PyTracer {
    #[new]
    fn new(py: Python<'_>, scene: &Bound<'_, PyScene>) -> PyResult<PyTracer> {
        let shared = Arc::clone(&scene.get().scene);
        let tracer = py.detach(|| Tracer::new(shared));
        let tracer = tracer.map_err(|e| scene_error(py, &e))?;
        Ok(PyTracer {
            tracer: RwLock::new(tracer),
            scratch: Mutex::default(),
            workspace: Mutex::default(),
            arrivals: Mutex::default(),
            gradient: Mutex::default(),
        })
    }

    /// The tracer's scene.
    #[getter]
    fn scene(&self) -> PyScene {
        PyScene {
            scene: Arc::new(self.read().scene().clone()),
        }
    }

    /// Pickling (`multiprocessing`, joblib, Dask, Ray): the tracer as its scene, edits
    /// included (`set_*`); unpickling prepares a tracer of it again (`Tracer(scene)`), which
    /// gives the same rays bit for bit.
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyType>, (PyScene,))> {
        let py = slf.py();
        Ok((py.get_type::<PyTracer>(), (slf.get().scene(),)))
    }

    /// Every ray of the scene, in parallel (the GIL released), as numpy arrays (`Rays`).
    /// Ctrl-C stops it (`KeyboardInterrupt`); `MemoryError` when the arrays would not fit.
    ///
    /// `warm_start`: start each receiver from its neighbour's solution (see the library's
    /// `BatchOptions::warm_start`). `progress`: `True` for a tqdm bar, or a callable
    /// `progress(done, total)` called from the calling thread. `out`: the `Rays` of an
    /// earlier `trace()` of this many rays, rewritten in place and returned (a loop then
    /// allocates its arrays once).
    #[pyo3(signature = (*, warm_start = true, progress = None, out = None))]
    fn trace(
        &self,
        py: Python<'_>,
        warm_start: bool,
        progress: Option<&Bound<'_, PyAny>>,
        out: Option<Bound<'_, PyRays>>,
    ) -> PyResult<Py<PyRays>> {
        let tracer = self.read();
        scratch(&self.scratch, |scratch| {
            trace_rays(py, &tracer, scratch, warm_start, progress, out)
        })
    }

    /// Every stationary path of every ray of the scene (not only the one the default start
    /// reaches), in parallel with the GIL released, as `Rays` with `arrival`, `kink` and
    /// `complete`: one entry per stationary path, ordered by time within its triple, and one
    /// `no_path` (a proof) or `not_converged` entry per triple that has none. Ctrl-C stops it.
    /// `progress`: as `trace`'s, counting the triples searched.
    #[pyo3(signature = (*, progress = None))]
    fn trace_stationary(
        &self,
        py: Python<'_>,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyRays> {
        let tracer = self.read();
        let scene = tracer.scene();
        let total = scene.num_rays();
        check_memory(
            &format!("trace_stationary: {total} rays"),
            Table::bytes(total, width(scene), false, &Schema::of(scene)),
        )?;
        let progress = Progress::new(py, progress, total)?;
        let run = Run::new();
        let mut reports = Reports::new(progress.as_ref(), &run, total);
        let rays = interruptible(
            py,
            &run,
            || tracer.trace_stationary(&run),
            || reports.poll(),
        )?
        .map_err(|e| scene_error(py, &e.into()))?;
        reports.finish()?;
        let table = py.detach(|| stationary_table(scene, &rays));
        let rays = table.finish(py, scene);
        *rays.scene.lock().unwrap_or_else(PoisonError::into_inner) = Some(tracer.shared_scene());
        Ok(rays)
    }

    /// One ray of path `path` (index or name) between any two points.
    #[pyo3(signature = (source, receiver, path = None))]
    fn solve(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyRay> {
        let tracer = self.read();
        let scene = tracer.scene();
        let (source, receiver, path) = ray_arguments(py, scene, source, receiver, path)?;
        scratch(&self.workspace, |ws| {
            let record = tracer.solve(source, receiver, path, ws);
            let entry = Entry::solved(&tracer, path, &record, ws);
            Ok(PyRay::from_record(
                py,
                &tracer.shared_scene(),
                &record,
                ws.points(),
                ws.media(),
                &entry,
            ))
        })
    }

    /// The travel time of one ray (NaN without one): `solve` without building a `Ray`.
    #[pyo3(signature = (source, receiver, path = None))]
    fn time(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<f64> {
        let tracer = self.read();
        let scene = tracer.scene();
        let (source, receiver, path) = ray_arguments(py, scene, source, receiver, path)?;
        Ok(scratch(&self.workspace, |ws| {
            tracer.solve(source, receiver, path, ws).time
        }))
    }

    /// The complex amplitude of one ray of path `path` (index or name) between any two points
    /// (NaN without one: no time, or no ray-theory amplitude, as on a `vertex` path), for a
    /// scene with `"amplitudes"`: `solve` without building a `Ray`, the call of a loop over
    /// receivers (the library's `Tracer::solve_with_amplitude`). `Ray.amplitude` of `solve`
    /// is the same number, with its parts and the reason it has none.
    #[pyo3(signature = (source, receiver, path = None))]
    fn amplitude(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Complex64> {
        let tracer = self.read();
        let scene = tracer.scene();
        if scene.amplitudes().is_none() {
            return Err(argument_error(
                py,
                "amplitudes",
                "the scene does not ask for amplitudes: give it an \"amplitudes\" section \
                 ({\"source\": \"point\"}, \"axisymmetric\" or \"line\")",
            ));
        }
        let (source, receiver, path) = ray_arguments(py, scene, source, receiver, path)?;
        let mut amplitude = None;
        scratch(&self.workspace, |ws| {
            tracer.solve_with_amplitude(source, receiver, path, ws, &mut amplitude);
        });
        let none = Complex64::new(f64::NAN, f64::NAN);
        Ok(amplitude.map_or(none, |a| a.value))
    }

    /// Solves one ray of path `path` between any two points and returns the derivatives of
    /// its time (`Gradient`): exact for the path as found (the envelope theorem at the solved
    /// points), so they agree with differences of re-solved times. For a layout loop: move
    /// things with the `set_*` calls, ask again.
    #[pyo3(signature = (source, receiver, path = None))]
    fn gradient(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyGradient> {
        let tracer = self.read();
        let scene = tracer.scene();
        let (source, receiver, path) = ray_arguments(py, scene, source, receiver, path)?;
        scratch(&self.workspace, |ws| {
            scratch(&self.gradient, |gradient| {
                let record = tracer
                    .solve_with_gradient(source, receiver, path, ws, gradient)
                    .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
                let gradient = record.status.has_time().then_some(&*gradient);
                PyGradient::new(py, scene, &record, gradient)
            })
        })
    }

    /// Solves one ray of path `path` between any two points and returns how its points move
    /// with every parameter its time depends on (`PointSensitivities`): by the implicit
    /// function theorem, one tridiagonal solve with the converged Hessian per parameter; for
    /// users who need where a ray lands (on a detector, on a wall) rather than when. Raises
    /// `RuntimeError` at a caustic, where the points do not move smoothly.
    #[pyo3(signature = (source, receiver, path = None))]
    fn point_sensitivities(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyPointSensitivities> {
        let tracer = self.read();
        let scene = tracer.scene();
        let (source, receiver, path) = ray_arguments(py, scene, source, receiver, path)?;
        scratch(&self.workspace, |ws| {
            let record = tracer.solve(source, receiver, path, ws);
            if !record.status.has_time() {
                return PyPointSensitivities::new(py, scene, &record, None);
            }
            let sens = PointSensitivities::of_solved(scene, path, ws)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            PyPointSensitivities::new(py, scene, &record, Some(&sens))
        })
    }

    /// The derivatives of the times of `rays` (from `trace`, `trace_stationary` or
    /// `solve_pairs` of this tracer), as `Gradients`: one row per ray, computed from each ray's
    /// points and leg media in parallel with the GIL released, the same numbers as
    /// `gradient` and the command-line tool's `"derivatives": true`.
    fn gradients(&self, py: Python<'_>, rays: &Bound<'_, PyRays>) -> PyResult<PyGradients> {
        PyGradients::of_rays(py, self.read().scene(), rays.get())
    }

    /// Rays of path `path` between `sources[i]` and `receivers[i]` (arrays of shape `(n, 2)`),
    /// in parallel with the GIL released, as `Rays` (their `source` and `receiver` hold `i`).
    /// Ctrl-C stops it; `MemoryError` when the rays would not fit.
    #[pyo3(signature = (sources, receivers, path = None))]
    fn solve_pairs(
        &self,
        py: Python<'_>,
        sources: &Bound<'_, PyAny>,
        receivers: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyRays> {
        let tracer = self.read();
        let scene = tracer.scene();
        let path = path_index(py, scene, path)?;
        // Each pair: its two points, and its ray's row of the table.
        let per_row =
            32 + Table::bytes(1, width(scene), false, &Schema::of(scene)).unwrap_or(u64::MAX);
        let sources = points_arg(py, "sources", sources, per_row)?;
        let receivers = points_arg(py, "receivers", receivers, 16)?;
        if sources.len() != receivers.len() {
            return Err(argument_error(
                py,
                "receivers",
                format!(
                    "has {} points where sources has {}",
                    receivers.len(),
                    sources.len()
                ),
            ));
        }
        for (i, (&s, &r)) in sources.iter().zip(&receivers).enumerate() {
            scene.check_solve(s, r, path).map_err(|e| {
                let key = format!("{}s[{i}]", e.key);
                scene_error(py, &SceneError::new(key, e.message))
            })?;
        }
        let run = Run::new();
        let table = interruptible(
            py,
            &run,
            || pairs_table(&tracer, &sources, &receivers, path, &run),
            || {},
        )?;
        let rays = table.finish(py, scene);
        *rays.scene.lock().unwrap_or_else(PoisonError::into_inner) = Some(tracer.shared_scene());
        Ok(rays)
    }

    /// Every stationary path of path `path` between two points, ordered by time (a `Ray`
    /// each, with its `arrival` index and, on `vertex` paths, its `kink`). Returns the list
    /// and whether the search was complete (with `True`, an empty list proves there is none).
    /// Ctrl-C stops it.
    #[pyo3(signature = (source, receiver, path = None))]
    fn stationary_paths(
        &self,
        py: Python<'_>,
        source: &Bound<'_, PyAny>,
        receiver: &Bound<'_, PyAny>,
        path: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<(Vec<PyRay>, bool)> {
        let tracer = self.read();
        let scene = tracer.scene();
        let (source, receiver, path) = ray_arguments(py, scene, source, receiver, path)?;
        scratch(&self.arrivals, |out| {
            let run = Run::new();
            let search = interruptible(
                py,
                &run,
                || tracer.stationary_paths(source, receiver, path, &run, out),
                || {},
            )?
            .map_err(|e| scene_error(py, &e.into()))?;
            let shared = tracer.shared_scene();
            let rays = out
                .iter()
                .enumerate()
                .map(|(i, a)| PyRay::from_arrival(py, &shared, i, a))
                .collect();
            Ok((rays, search.complete))
        })
    }

    /// Moves source `index` to `point`, checked as `sources[index]` of a scene file (a
    /// refused move leaves the tracer as it was). Cheap: nothing is rebuilt.
    fn set_source(&self, py: Python<'_>, index: usize, point: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = point_arg(py, &format!("sources[{index}]"), point)?;
        self.write(py)
            .set_source(index, p)
            .map_err(|e| scene_error(py, &e))
    }

    /// Moves receiver `index` to `point`, checked as `receivers[index]`. Cheap.
    fn set_receiver(&self, py: Python<'_>, index: usize, point: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = point_arg(py, &format!("receivers[{index}]"), point)?;
        self.write(py)
            .set_receiver(index, p)
            .map_err(|e| scene_error(py, &e))
    }

    /// Moves every receiver: `points` of shape `(n, 2)`, `n` the scene's receivers. All or
    /// nothing: a refused point raises, naming `receivers[i]`, and leaves every receiver
    /// where it was. Costs time in proportion to the receivers (a map computed in blocks
    /// moves one tracer from block to block).
    fn set_receivers(&self, py: Python<'_>, points: &Bound<'_, PyAny>) -> PyResult<()> {
        let points = points_arg(py, "receivers", points, 16)?;
        let mut tracer = self.write(py);
        tracer
            .set_receivers(&points)
            .map_err(|e| scene_error(py, &e))
    }

    /// Gives interface `interface` (a name or an index) new vertices, `points` of shape
    /// `(n, 2)`, checked as `interfaces.NAME.points` of a scene file (a refused change leaves
    /// the tracer as it was). Rebuilds what depends on the interfaces. `MemoryError` when
    /// that would not fit.
    fn set_interface_points(
        &self,
        py: Python<'_>,
        interface: &Bound<'_, PyAny>,
        points: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (index, name) = {
            let tracer = self.read();
            let scene = tracer.scene();
            let index = named_index(py, "interface", interface, scene.interfaces().len(), |n| {
                scene.interface_index(n)
            })?;
            (index, scene.interfaces()[index].name.clone())
        };
        let key = format!("interfaces.{name}.points");
        let points = points_arg(py, &key, points, BYTES_PER_VERTEX)?;
        self.write(py)
            .set_interface_points(index, &points)
            .map_err(|e| scene_error(py, &e))
    }

    /// Gives medium `medium` (a name or an index) the speed `speed`.
    fn set_medium_speed(
        &self,
        py: Python<'_>,
        medium: &Bound<'_, PyAny>,
        speed: f64,
    ) -> PyResult<()> {
        let mut tracer = self.write(py);
        let index = medium_index(py, tracer.scene(), medium)?;
        tracer
            .set_medium_speed(index, speed)
            .map_err(|e| scene_error(py, &e))
    }

    /// Gives medium `medium` (a name or an index) the refractive index `index`.
    fn set_medium_index(
        &self,
        py: Python<'_>,
        medium: &Bound<'_, PyAny>,
        index: f64,
    ) -> PyResult<()> {
        let mut tracer = self.write(py);
        let medium = medium_index(py, tracer.scene(), medium)?;
        tracer
            .set_medium_index(medium, index)
            .map_err(|e| scene_error(py, &e))
    }

    /// The scene's `search` (its `"search"` section): every arrival per (source, receiver),
    /// ordered by time, as `Arrivals`: numpy arrays (`source`, `receiver`, `time`, `order`,
    /// `status`, `points`, the steps as `step_interface` and `step_kind`, `media`, ...; with
    /// `"amplitudes"` also `amplitude`, `spreading`, `coefficient`, `attenuation_db` and
    /// `amplitude_reason`). `len`, indexing and iteration give each arrival as a dict with
    /// `source`, `receiver`, `steps` (as in the scene: `{"reflect": name}`), `media`,
    /// `status`, `time`, `points`, `iterations`, `complete`, ... (`to_dicts()`: all of them).
    /// Ctrl-C stops it; `MemoryError` when the arrays would not fit.
    fn search(&self, py: Python<'_>) -> PyResult<PyArrivals> {
        search_arrivals(py, &self.read())
    }

    /// Every arrival that reaches a receiver with an amplitude (each `converged` ray of the
    /// scene's paths and arrival of its search), as a dict of numpy arrays: `source`,
    /// `receiver`, `order` (interactions, uint32), `diffractions` (of those, the diffractions
    /// at vertices, uint32), `vertical` (of those, the floor and ceiling reflections of an
    /// extruded scene, uint32; 0 in a plane one), `time` (float64) and `amplitude`
    /// (complex128): what `impulse_response`, `pressure` and `eigenray.plotting.echogram` sum.
    fn echoes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        response::echoes(py, &self.read())
    }

    /// The impulse response of every (source, receiver), as float64 `[sources, receivers,
    /// samples]` (sample `n` at time `n / rate`): every `converged` ray and search arrival
    /// with an amplitude placed as a Hann-windowed sinc pulse of `taps` samples (default 81,
    /// as pyroomacoustics) centred on its time, scaled by its amplitude (its imaginary part
    /// by the pulse's Hilbert pair), rendered as the search finds it (`[sources, nx, ny,
    /// samples]` for a receiver grid). `rate` and `duration` default to the scene's
    /// `impulse_response`. Needs `amplitudes`.
    #[pyo3(signature = (rate=None, duration=None, taps=None))]
    fn impulse_response<'py>(
        &self,
        py: Python<'py>,
        rate: Option<f64>,
        duration: Option<f64>,
        taps: Option<usize>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        response::impulse_response(py, &self.read(), rate, duration, taps)
    }

    /// The room acoustic parameters (ISO 3382-1) of the impulse response of every (source,
    /// receiver), as a list of dicts (source-major): `source`, `receiver`, `first_arrival`
    /// (time zero), `edt`, `t20`, `t30` (s), `c50`, `c80` (dB) and `d50`, each `None` where
    /// the response is too short or too sparse, with `<name>_reason` saying why. `rate` and
    /// `duration` default to the scene's `impulse_response`. Needs `amplitudes`.
    #[pyo3(signature = (rate=None, duration=None))]
    fn room_parameters<'py>(
        &self,
        py: Python<'py>,
        rate: Option<f64>,
        duration: Option<f64>,
    ) -> PyResult<Bound<'py, pyo3::types::PyList>> {
        response::room_parameters(py, &self.read(), rate, duration)
    }

    /// The coherent pressure of every (source, receiver) at `frequency` (default: the
    /// scene's `amplitudes.frequency`), complex128 `[sources, receivers]` (`[sources, nx,
    /// ny]` for a receiver grid): the sum over echoes of `amplitude · e^(iωT)`, each added as
    /// the search finds it. Needs `amplitudes`.
    #[pyo3(signature = (frequency=None))]
    fn pressure<'py>(
        &self,
        py: Python<'py>,
        frequency: Option<f64>,
    ) -> PyResult<Bound<'py, PyArrayDyn<Complex64>>> {
        response::pressure(py, &self.read(), frequency)
    }

    /// The transmission loss in dB of every (source, receiver) at `frequency` (see
    /// `pressure`), float64 `[sources, receivers]` (`[sources, nx, ny]` for a receiver
    /// grid); `inf` where nothing arrives. `mode`: `"coherent"` (`−20 log10(|p| · 4π)`) or
    /// `"incoherent"` (`−10 log10(16π² Σ |a|²)`), default the scene's
    /// `transmission_loss.mode`, else coherent. The echoes are summed as the search finds
    /// them: none is kept. Ctrl-C stops it.
    #[pyo3(signature = (frequency=None, mode=None))]
    fn transmission_loss<'py>(
        &self,
        py: Python<'py>,
        frequency: Option<f64>,
        mode: Option<&str>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        response::transmission_loss_db(py, &self.read(), frequency, mode)
    }
}

/// The index of a medium of `scene` given by name or index.
fn medium_index(py: Python<'_>, scene: &Scene, medium: &Bound<'_, PyAny>) -> PyResult<usize> {
    named_index(py, "medium", medium, scene.media().len(), |name| {
        scene.medium_index(name)
    })
}
