//! Sampled impulse responses: every echo placed as a fractional-delay pulse.

use std::collections::TryReserveError;

use super::{Echo, FractionalDelay};
use crate::options::{Progress, Run};
use crate::scene::ImpulseResponseOptions;

/// The layout and pulse of a set of impulse responses, one per (source, receiver): it
/// renders echoes into a buffer of `sources × receivers × samples` numbers, source-major
/// (`out[(s · receivers + r) · samples + n]` is sample `n`, at time `n / rate`, of the
/// response from source `s` at receiver `r`), as the `.npy` file's `[sources, receivers,
/// samples]` array.
///
/// ```
/// use eigenray::amplitude::Complex64;
/// use eigenray::options::Run;
/// use eigenray::response::{Echo, ImpulseResponses};
/// use eigenray::scene::ImpulseResponseSpec;
/// use eigenray::scene::ImpulseResponseOptions;
///
/// let spec = ImpulseResponseSpec::new(1000.0, 0.05); // 50 samples
/// let options = ImpulseResponseOptions::of_spec("impulse_response", &spec).unwrap();
/// let ir = ImpulseResponses::new(&options, 1, 2);
/// let a = Complex64::new(0.5, 0.0);
/// let echo = Echo { source: 0, receiver: 1, time: 0.02, amplitude: a, order: 0, diffractions: 0, vertical_reflections: 0 };
/// let mut out = vec![0.0; ir.len()];
/// ir.render_into([echo], &Run::new(), &mut out);
/// assert_eq!(ir.response(&out, 0, 1)[20], 0.5); // on a whole sample: that sample alone
/// assert!(ir.response(&out, 0, 0).iter().all(|&v| v == 0.0));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ImpulseResponses {
    rate: f64,
    samples: usize,
    sources: usize,
    receivers: usize,
    pulse: FractionalDelay,
}

impl ImpulseResponses {
    /// Responses with the settings `options`, for `sources` sources and `receivers`
    /// receivers.
    pub fn new(
        options: &ImpulseResponseOptions,
        sources: usize,
        receivers: usize,
    ) -> ImpulseResponses {
        ImpulseResponses {
            rate: options.rate,
            samples: options.samples,
            sources,
            receivers,
            pulse: FractionalDelay::hann_sinc(options.taps),
        }
    }

    /// Samples per second.
    pub fn rate(&self) -> f64 {
        self.rate
    }
    /// Samples per response.
    pub fn samples(&self) -> usize {
        self.samples
    }
    /// Sources.
    pub fn sources(&self) -> usize {
        self.sources
    }
    /// Receivers.
    pub fn receivers(&self) -> usize {
        self.receivers
    }
    /// The pulse each echo is placed as.
    pub fn pulse(&self) -> &FractionalDelay {
        &self.pulse
    }

    /// Numbers in the whole buffer (`sources × receivers × samples`), or `None` where that
    /// overflows.
    pub fn checked_len(&self) -> Option<usize> {
        self.sources
            .checked_mul(self.receivers)?
            .checked_mul(self.samples)
    }

    /// Numbers in the whole buffer (`sources × receivers × samples`).
    ///
    /// # Panics
    /// Where that overflows (see [`checked_len`](Self::checked_len)).
    pub fn len(&self) -> usize {
        self.checked_len()
            .expect("sources × receivers × samples overflows")
    }

    /// Whether the buffer is empty (no sources or no receivers).
    pub fn is_empty(&self) -> bool {
        self.sources == 0 || self.receivers == 0
    }

    /// Writes the responses of `echoes` into `out` (of [`len`](Self::len) numbers): each
    /// echo adds its pulse, centred on `time × rate`, scaled by its amplitude, to the response
    /// of its (source, receiver); the rest is 0. Echoes of other sources or receivers, and
    /// parts of pulses outside the responses, are left out. Allocates nothing.
    ///
    /// Each echo is an item of `run`, and its pulse's taps units of its work, asked for
    /// before it is added: once `run` stops (a stop request, a spent budget) the echoes left
    /// are not rendered.
    ///
    /// # Panics
    /// If `out` does not hold [`len`](Self::len) numbers.
    pub fn render_into(&self, echoes: impl IntoIterator<Item = Echo>, run: &Run, out: &mut [f64]) {
        assert_eq!(
            out.len(),
            self.len(),
            "impulse-response buffer of the wrong size"
        );
        out.fill(0.0);
        let taps = self.pulse.taps() as u64;
        for e in echoes {
            if e.source < self.sources && e.receiver < self.receivers {
                if !run.keep_going(Progress {
                    work: taps,
                    items: 1,
                }) {
                    return;
                }
                let start = (e.source * self.receivers + e.receiver) * self.samples;
                let response = &mut out[start..start + self.samples];
                self.pulse.add(response, e.time * self.rate, e.amplitude);
            }
        }
    }

    /// The responses of `echoes` in a new buffer (see [`render_into`](Self::render_into)).
    ///
    /// # Errors
    /// When the buffer cannot be allocated (or its size overflows).
    pub fn render(
        &self,
        echoes: impl IntoIterator<Item = Echo>,
        run: &Run,
    ) -> Result<Vec<f64>, TryReserveError> {
        let mut out = Vec::new();
        // An overflowing size asks for more than any allocator gives.
        out.try_reserve_exact(self.checked_len().unwrap_or(usize::MAX))?;
        out.resize(self.len(), 0.0);
        self.render_into(echoes, run, &mut out);
        Ok(out)
    }

    /// The response from `source` at `receiver` within a rendered buffer.
    pub fn response<'a>(&self, out: &'a [f64], source: usize, receiver: usize) -> &'a [f64] {
        let start = (source * self.receivers + receiver) * self.samples;
        &out[start..start + self.samples]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;

    fn options(rate: f64, samples: usize, taps: usize) -> ImpulseResponseOptions {
        ImpulseResponseOptions::new("ir", rate, samples, taps).unwrap()
    }

    #[test]
    fn echoes_go_to_their_own_response() {
        let ir = ImpulseResponses::new(&options(100.0, 64, 21), 2, 3);
        assert_eq!(ir.len(), 2 * 3 * 64);
        let echoes = [
            Echo {
                source: 1,
                receiver: 2,
                time: 0.25,
                amplitude: Complex64::new(2.0, 0.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
            Echo {
                source: 0,
                receiver: 0,
                time: 0.101,
                amplitude: Complex64::new(0.0, 1.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
            Echo {
                source: 0,
                receiver: 0,
                time: 0.101,
                amplitude: Complex64::new(0.0, -1.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
            // Not in these responses: left out.
            Echo {
                source: 2,
                receiver: 0,
                time: 0.1,
                amplitude: Complex64::new(1.0, 0.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
        ];
        let mut out = vec![f64::NAN; ir.len()];
        ir.render_into(echoes, &Run::new(), &mut out);
        let r12 = ir.response(&out, 1, 2);
        assert_eq!(r12[25], 2.0);
        assert_eq!(r12.iter().filter(|v| **v != 0.0).count(), 1);
        // Two opposite echoes cancel to round-off; every other response is 0.
        assert!(ir.response(&out, 0, 0).iter().all(|v| v.abs() < 1e-15));
        let rest = [(0, 1), (0, 2), (1, 0), (1, 1)];
        for (s, r) in rest {
            assert!(ir.response(&out, s, r).iter().all(|&v| v == 0.0), "{s} {r}");
        }
    }

    #[test]
    fn a_response_is_the_sum_of_its_pulses() {
        let ir = ImpulseResponses::new(&options(8000.0, 400, 81), 1, 1);
        let echoes: Vec<Echo> = (0..5)
            .map(|k| Echo {
                source: 0,
                receiver: 0,
                time: 0.001 + 0.0071 * k as f64,
                amplitude: Complex64::new(1.0 / (k + 1) as f64, 0.3 * k as f64 - 0.5),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            })
            .collect();
        let out = ir.render(echoes.iter().copied(), &Run::new()).unwrap();
        let mut sum = vec![0.0; 400];
        for e in &echoes {
            let mut one = vec![0.0; 400];
            ir.pulse().add(&mut one, e.time * 8000.0, e.amplitude);
            for (s, o) in sum.iter_mut().zip(&one) {
                *s += o;
            }
        }
        for (a, b) in out.iter().zip(&sum) {
            assert!((a - b).abs() < 1e-15);
        }
        assert!(out.iter().any(|&v| v != 0.0));
    }

    #[test]
    fn an_impossible_buffer_is_an_error() {
        let ir = ImpulseResponses::new(&options(1.0, 1 << 32, 1), usize::MAX / 2, 3);
        assert_eq!(ir.checked_len(), None);
        assert!(ir.render([], &Run::new()).is_err());
    }
}
