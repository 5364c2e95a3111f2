//! A batch's amplitudes: each timed ray's, when the scene asks for them, from its points and
//! leg media by the tracer's one function ([`Tracer::amplitude_of`]), in parallel after the
//! solve (rays that do not ask cost nothing).

use rayon::prelude::*;

use super::{Batch, sized};
use crate::amplitude::{Amplitude, NoAmplitude};
use crate::options::Run;
use crate::trace::Tracer;

/// Rays per parallel piece.
const PIECE: usize = 1024;

impl Batch {
    /// The amplitude of ray `ray`, when the scene asks for amplitudes and the ray has a time
    /// (see [`Tracer::amplitude_of`]).
    ///
    /// ```
    /// use eigenray::{BatchOptions, Scene, Tracer, options::Run};
    /// let mut spec = eigenray::demo::air_water(100, 7);
    /// spec.amplitudes = Some(eigenray::scene::AmplitudesSpec::new(
    ///     eigenray::scene::SourceModel::Point,
    /// ));
    /// let scene = Scene::from_spec(&spec).unwrap();
    /// let tracer = Tracer::new(&scene).unwrap();
    /// let batch = tracer.trace_batch(&BatchOptions::default(), &Run::new()).unwrap();
    /// let one = tracer.trace_all();
    /// assert!(batch.amplitude(0).unwrap().spreading > 0.0);
    /// assert_eq!(batch.amplitude(0), one[0].amplitude.as_ref());
    /// ```
    pub fn amplitude(&self, ray: usize) -> Option<&Amplitude> {
        let a = self.amplitudes.get(ray)?;
        self.records[ray].status.has_time().then_some(a)
    }
}

impl Tracer {
    /// Gives every timed ray of `batch` its amplitude when the scene asks for amplitudes (and
    /// empties the batch's amplitudes when it does not). A stop requested of `run` skips the
    /// pieces not begun (the caller that asked discards the batch); a spent budget does not:
    /// the rays solved keep their amplitudes.
    pub(super) fn batch_amplitudes(&self, batch: &mut Batch, run: &Run) {
        let scene = self.scene();
        // Without amplitudes, or without rays (no work for the thread pool, which is then
        // not started for nothing).
        if scene.amplitudes().is_none() || batch.is_empty() {
            batch.amplitudes.clear();
            return;
        }
        let mut amplitudes = std::mem::take(&mut batch.amplitudes);
        let none = Amplitude::none(NoAmplitude::UnknownMedia);
        sized(&mut amplitudes, batch.len(), none);
        let batch_ref = &*batch;
        amplitudes
            .par_chunks_mut(PIECE)
            .enumerate()
            .for_each_init(Vec::new, |legs, (p, out)| {
                if run.stop_requested() {
                    return;
                }
                let start = p * PIECE;
                let rays = batch_ref.rays(start..start + out.len());
                for (slot, ray) in out.iter_mut().zip(rays) {
                    legs.clear();
                    if let Some(media) = ray.media() {
                        legs.extend(media);
                    }
                    let steps = &scene.paths()[ray.path].steps;
                    let status = ray.record.status;
                    *slot = self
                        .amplitude_with(steps, status, ray.points, legs, None)
                        .unwrap_or(none);
                }
            });
        batch.amplitudes = amplitudes;
    }
}
