//! Responses that stream: every echo of a scene goes straight into its output the moment the
//! search finds it ([`Tracer::search_into`]), so no arrival and none of its points is kept.
//! The memory is the output plus the search's working set, whatever the number of echoes.

use std::f64::consts::PI;
use std::sync::Mutex;

use num_complex::Complex64;

use super::{Echo, EchoError, ImpulseResponses, echoes_of_rays, transmission_loss};
use crate::options::{Progress, Run};
use crate::output::RaySet;
use crate::scene::{StationaryMode, TransmissionLossMode};
use crate::search::StreamedArrival;
use crate::trace::{Status, Tracer};
use crate::{Amplitude, BatchOptions};

/// What a streamed response summed ([`echoes_of_scene_into`] and the responses over it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summed {
    /// Echoes summed: `converged` paths with an amplitude.
    pub echoes: u64,
    /// Timed paths that add nothing because they have no amplitude value (`vertex` and
    /// `obstructed` ones, or every one in a scene without `amplitudes`).
    pub without_amplitude: u64,
    /// (Source, receiver) pairs whose search stopped at a limit: their sums may miss
    /// echoes.
    pub incomplete_pairs: usize,
}

/// Whether a path that ended as `status` with `amplitude` has a time but no amplitude value.
fn timed_without_amplitude(status: Status, amplitude: Option<&Amplitude>) -> bool {
    matches!(
        status,
        Status::Converged | Status::Vertex | Status::Obstructed
    ) && !amplitude.is_some_and(Amplitude::has_value)
}

/// Every echo of `tracer`'s scene, as [`echoes_of_scene`](super::echoes_of_scene) finds
/// them, handed to `sink` instead of listed: the rays of its `paths` first (from the thread
/// that called, in ray order), then the arrivals of its `search` the moment the search
/// finds them (from its worker threads, in the order of [`Tracer::search_into`]: the echoes
/// of one (source, receiver) pair always in one order). The search keeps no arrival; the
/// `paths`' rays are a batch (one ray per triple) as before.
///
/// # Errors
/// As [`echoes_of_scene`](super::echoes_of_scene).
pub fn echoes_of_scene_into(
    tracer: &Tracer,
    run: &Run,
    sink: &(dyn Fn(Echo) + Sync),
) -> Result<Summed, EchoError> {
    let scene = tracer.scene();
    let mut summed = Summed::default();
    if !scene.paths().is_empty() {
        match scene.solver().stationary {
            StationaryMode::One => {
                let batch = tracer
                    .trace_batch(&BatchOptions::default(), run)
                    .map_err(EchoError::Batch)?;
                summed.without_amplitude += (0..batch.len())
                    .filter(|&i| {
                        timed_without_amplitude(batch.record(i).status, batch.amplitude(i))
                    })
                    .count() as u64;
                for e in echoes_of_rays(scene, RaySet::Batch(&batch)) {
                    summed.echoes += 1;
                    sink(e);
                }
            }
            StationaryMode::All => {
                let all = tracer
                    .trace_stationary(run)
                    .map_err(EchoError::Stationary)?;
                summed.without_amplitude += (all.triples.iter())
                    .flat_map(|t| &t.arrivals)
                    .filter(|a| timed_without_amplitude(a.status, a.amplitude.as_ref()))
                    .count() as u64;
                for e in echoes_of_rays(scene, RaySet::Stationary(&all)) {
                    summed.echoes += 1;
                    sink(e);
                }
            }
        }
    }
    if scene.search().is_some() {
        let without = std::sync::atomic::AtomicU64::new(0);
        let report = tracer
            .search_into(run, &|a: StreamedArrival| match Echo::of_streamed(&a) {
                Some(e) => sink(e),
                None => {
                    without.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                }
            })
            .map_err(EchoError::Search)?;
        let without = without.into_inner();
        summed.without_amplitude += without;
        summed.echoes += report.arrivals - without;
        summed.incomplete_pairs = report.incomplete_pairs;
    }
    Ok(summed)
}

/// A buffer of one row per source, each row behind its own lock: what the sink of a
/// streamed response adds into from the search's threads (a source's tree runs on one
/// thread, so its row is rarely contended).
struct Rows<'a, T> {
    rows: Vec<Mutex<&'a mut [T]>>,
    /// Numbers per (source, receiver).
    per_pair: usize,
    receivers: usize,
}

impl<'a, T> Rows<'a, T> {
    fn new(out: &'a mut [T], receivers: usize, per_pair: usize) -> Self {
        let row = (receivers * per_pair).max(1);
        Rows {
            rows: out.chunks_mut(row).map(Mutex::new).collect(),
            per_pair,
            receivers,
        }
    }

    /// Runs `f` on the numbers of `echo`'s pair, when it is one of the buffer's.
    fn with(&self, echo: &Echo, f: impl FnOnce(&mut [T])) {
        if echo.receiver >= self.receivers {
            return;
        }
        if let Some(row) = self.rows.get(echo.source) {
            let mut row = row.lock().unwrap_or_else(|e| e.into_inner());
            let start = echo.receiver * self.per_pair;
            f(&mut row[start..start + self.per_pair]);
        }
    }
}

/// The phase factor `e^(iωT)` at `frequency`, from the fractional part of `f · T` (as
/// [`pressure_into`](super::pressure_into)).
fn phase(frequency: f64, time: f64) -> Complex64 {
    Complex64::from_polar(1.0, 2.0 * PI * (frequency * time).fract())
}

/// The coherent pressure of every echo of `tracer`'s scene at `frequency` into `out` (one
/// per (source, receiver), source-major, as [`pressure_into`](super::pressure_into) gives
/// it), each echo added the moment it is found: nothing of it is kept. Each echo is a unit
/// of `run`'s work, asked before it is added. Equal to
/// [`pressure_into`](super::pressure_into) of [`echoes_of_scene`](super::echoes_of_scene)
/// up to the order of the sums (round-off).
///
/// # Errors
/// As [`echoes_of_scene`](super::echoes_of_scene).
///
/// # Panics
/// If `out` does not hold `sources × receivers` numbers.
pub fn pressure_of_scene_into(
    tracer: &Tracer,
    frequency: f64,
    run: &Run,
    out: &mut [Complex64],
) -> Result<Summed, EchoError> {
    let r = receivers(tracer, out.len());
    out.fill(Complex64::new(0.0, 0.0));
    let rows = Rows::new(out, r, 1);
    echoes_of_scene_into(tracer, run, &|e| {
        if run.keep_going(Progress::work(1)) {
            rows.with(&e, |p| p[0] += e.amplitude * phase(frequency, e.time));
        }
    })
}

/// The sum of `|a|²` over every echo of `tracer`'s scene into `out` (one per (source,
/// receiver), source-major): the incoherent intensity. Each echo as in
/// [`pressure_of_scene_into`].
///
/// # Errors
/// As [`echoes_of_scene`](super::echoes_of_scene).
///
/// # Panics
/// If `out` does not hold `sources × receivers` numbers.
pub fn intensity_of_scene_into(
    tracer: &Tracer,
    run: &Run,
    out: &mut [f64],
) -> Result<Summed, EchoError> {
    let r = receivers(tracer, out.len());
    out.fill(0.0);
    let rows = Rows::new(out, r, 1);
    echoes_of_scene_into(tracer, run, &|e| {
        if run.keep_going(Progress::work(1)) {
            rows.with(&e, |p| p[0] += e.amplitude.norm_sqr());
        }
    })
}

/// The transmission loss of every (source, receiver) of `tracer`'s scene at `frequency` into
/// `out` (dB, source-major), the echoes summed by `mode` as they are found:
/// [`transmission_loss`] of the coherent pressure, or `−10 log10(16π² Σ |a|²)` for the
/// incoherent sum. +∞ where no echo arrives (never NaN).
///
/// ```
/// use eigenray::{Scene, Tracer, options::Run};
/// use eigenray::response::transmission_loss_of_scene_into;
/// use eigenray::scene::TransmissionLossMode;
/// // Free field: 20 log10(r) dB at r = 10 and 100 from a point source.
/// let scene = Scene::from_json(r#"{
///     "media": { "w": { "speed": 1500 } }, "background": "w",
///     "sources": [[0, 0]], "receivers": [[10, 0], [0, 100]],
///     "search": { "max_steps": 0 },
///     "amplitudes": { "source": "point", "frequency": 100 }
/// }"#).unwrap();
/// let tracer = Tracer::new(&scene).unwrap();
/// let mut tl = [0.0; 2];
/// let mode = TransmissionLossMode::Coherent;
/// transmission_loss_of_scene_into(&tracer, 100.0, mode, &Run::new(), &mut tl).unwrap();
/// assert!((tl[0] - 20.0).abs() < 1e-12 && (tl[1] - 40.0).abs() < 1e-12);
/// ```
///
/// # Errors
/// As [`echoes_of_scene`](super::echoes_of_scene).
///
/// # Panics
/// If `out` does not hold `sources × receivers` numbers.
pub fn transmission_loss_of_scene_into(
    tracer: &Tracer,
    frequency: f64,
    mode: TransmissionLossMode,
    run: &Run,
    out: &mut [f64],
) -> Result<Summed, EchoError> {
    match mode {
        TransmissionLossMode::Coherent => {
            let mut p = vec![Complex64::new(0.0, 0.0); out.len()];
            let summed = pressure_of_scene_into(tracer, frequency, run, &mut p)?;
            for (tl, p) in out.iter_mut().zip(&p) {
                *tl = transmission_loss(*p);
            }
            Ok(summed)
        }
        TransmissionLossMode::Incoherent => {
            let summed = intensity_of_scene_into(tracer, run, out)?;
            for v in out.iter_mut() {
                *v = incoherent_loss(*v);
            }
            Ok(summed)
        }
    }
}

/// The transmission loss of an intensity `Σ |a|²`: `−10 log10(16π² Σ |a|²)` dB, the
/// coherent [`transmission_loss`] of one arrival of that size (+∞ at 0).
pub fn incoherent_loss(intensity: f64) -> f64 {
    -10.0 * (intensity * 16.0 * PI * PI).log10()
}

/// Receivers of `tracer`'s scene, its sources and receivers checked against a buffer of `len` numbers.
fn receivers(tracer: &Tracer, len: usize) -> usize {
    let scene = tracer.scene();
    let (s, r) = (scene.sources().len(), scene.receivers().len());
    assert_eq!(len, s * r, "response buffer of the wrong size");
    r
}

/// The room acoustic parameters of every (source, receiver) of a scene
/// ([`room_parameters_of_scene`]), source-major, and what was summed.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRoomParameters {
    /// One per (source, receiver), source-major.
    pub parameters: Vec<super::RoomParameters>,
    /// What the responses summed.
    pub summed: Summed,
}

/// The room acoustic parameters ([`room_parameters`](super::room_parameters)) of the
/// response of every (source, receiver) of `tracer`'s scene as `responses` renders it, time
/// zero at each pair's first arrival: the responses rendered as the search finds each echo
/// ([`ImpulseResponses::render_scene_into`]), nothing of an echo kept; the memory is the
/// responses'.
///
/// # Errors
/// As [`echoes_of_scene`](super::echoes_of_scene).
pub fn room_parameters_of_scene(
    tracer: &Tracer,
    responses: &ImpulseResponses,
    run: &Run,
) -> Result<SceneRoomParameters, EchoError> {
    let scene = tracer.scene();
    let pairs = scene.sources().len() * scene.receivers().len();
    let mut out = vec![0.0; responses.len()];
    let mut first = vec![f64::INFINITY; pairs];
    let taps = responses.pulse().taps() as u64;
    let rate = responses.rate();
    let summed = {
        let rows = Rows::new(&mut out, responses.receivers(), responses.samples());
        let firsts = Rows::new(&mut first, scene.receivers().len(), 1);
        echoes_of_scene_into(tracer, run, &|e| {
            if run.keep_going(Progress::work(taps)) {
                rows.with(&e, |r| responses.pulse().add(r, e.time * rate, e.amplitude));
                firsts.with(&e, |t| t[0] = t[0].min(e.time));
            }
        })?
    };
    let parameters = (0..pairs)
        .map(|k| {
            let (s, r) = (k / scene.receivers().len(), k % scene.receivers().len());
            let t0 = first[k].is_finite().then_some(first[k]);
            super::room_parameters(responses.response(&out, s, r), rate, t0)
        })
        .collect();
    Ok(SceneRoomParameters { parameters, summed })
}

impl ImpulseResponses {
    /// The responses of every echo of `tracer`'s scene into `out` (of [`len`](Self::len)
    /// numbers), each echo rendered the moment the search finds it: nothing of it is kept.
    /// Each echo's taps are units of `run`'s work, asked before it is added. Equal to
    /// [`render_into`](Self::render_into) of [`echoes_of_scene`](super::echoes_of_scene) up
    /// to the order of the sums (round-off).
    ///
    /// # Errors
    /// As [`echoes_of_scene`](super::echoes_of_scene).
    ///
    /// # Panics
    /// If `out` does not hold [`len`](Self::len) numbers.
    pub fn render_scene_into(
        &self,
        tracer: &Tracer,
        run: &Run,
        out: &mut [f64],
    ) -> Result<Summed, EchoError> {
        assert_eq!(
            out.len(),
            self.len(),
            "impulse-response buffer of the wrong size"
        );
        out.fill(0.0);
        let taps = self.pulse().taps() as u64;
        let rate = self.rate();
        let rows = Rows::new(out, self.receivers(), self.samples());
        echoes_of_scene_into(tracer, run, &|e| {
            if run.keep_going(Progress::work(taps)) {
                rows.with(&e, |r| self.pulse().add(r, e.time * rate, e.amplitude));
            }
        })
    }
}
