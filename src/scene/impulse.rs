//! The scene's `impulse_response` key: its spec, constructor and validation.

use serde::{Deserialize, Serialize};

use super::{SceneError, SceneSpec};

/// The default pulse length in taps: pyroomacoustics' fractional-delay filter.
pub const DEFAULT_TAPS: usize = 81;

/// The longest pulse accepted (`impulse_response.taps`).
pub const MAX_TAPS: usize = 10_001;

/// The highest sampling rate accepted (`impulse_response.rate`, samples per second).
pub const MAX_RATE: f64 = 1e9;

/// The most samples per response accepted (`rate × duration`): beyond it a response alone
/// would outgrow any machine's memory.
pub const MAX_SAMPLES: usize = 1 << 32;

/// The `impulse_response` section: one response per (source, receiver), sampled at `rate`
/// for `duration` seconds from time 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImpulseResponseSpec {
    /// Samples per second (with the scene's time unit s).
    pub rate: f64,
    /// Length in seconds.
    pub duration: f64,
    /// Length of each arrival's pulse in samples, odd (default 81, as pyroomacoustics).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub taps: Option<usize>,
}

impl ImpulseResponseSpec {
    /// Responses sampled at `rate` for `duration` seconds, with the default pulse.
    pub fn new(rate: f64, duration: f64) -> ImpulseResponseSpec {
        ImpulseResponseSpec {
            rate,
            duration,
            taps: None,
        }
    }

    /// The same with pulses of `taps` samples (odd).
    pub fn taps(self, taps: usize) -> ImpulseResponseSpec {
        ImpulseResponseSpec {
            taps: Some(taps),
            ..self
        }
    }
}

/// The validated `impulse_response` settings ([`Scene::impulse_response`](super::Scene)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpulseResponseOptions {
    /// Samples per second.
    pub rate: f64,
    /// Samples per response: `rate × duration` rounded to the nearest whole number, at
    /// least 1. Sample `n` is at time `n / rate`.
    pub samples: usize,
    /// Taps of each arrival's pulse (odd).
    pub taps: usize,
}

impl ImpulseResponseOptions {
    /// Settings for `rate` samples per second, `samples` samples and pulses of `taps`, checked
    /// as the scene key is (`key` names them in errors).
    ///
    /// # Errors
    /// A rate that is not a finite number in (0, [`MAX_RATE`](crate::scene::MAX_RATE)], no samples or more than
    /// [`MAX_SAMPLES`](crate::scene::MAX_SAMPLES), or a tap count that is even or outside 1 ..= [`MAX_TAPS`](crate::scene::MAX_TAPS).
    pub fn new(
        key: &str,
        rate: f64,
        samples: usize,
        taps: usize,
    ) -> Result<ImpulseResponseOptions, SceneError> {
        if !(rate.is_finite() && rate > 0.0 && rate <= MAX_RATE) {
            return Err(SceneError::new(
                format!("{key}.rate"),
                format!("must be a finite number of samples per second in (0, {MAX_RATE:e}]"),
            ));
        }
        if samples == 0 || samples > MAX_SAMPLES {
            return Err(SceneError::new(
                format!("{key}.duration"),
                format!("gives {samples} samples at this rate: give 1 to {MAX_SAMPLES}"),
            ));
        }
        if taps.is_multiple_of(2) || taps > MAX_TAPS {
            return Err(SceneError::new(
                format!("{key}.taps"),
                format!("must be odd and at most {MAX_TAPS} (the pulse is centred on its arrival)"),
            ));
        }
        Ok(ImpulseResponseOptions {
            rate,
            samples,
            taps,
        })
    }

    /// The settings of `spec` (`key` names it in errors).
    ///
    /// # Errors
    /// As [`new`](Self::new), and a duration that is not a finite number > 0.
    pub fn of_spec(
        key: &str,
        spec: &ImpulseResponseSpec,
    ) -> Result<ImpulseResponseOptions, SceneError> {
        let d = spec.duration;
        if !(d.is_finite() && d > 0.0) {
            return Err(SceneError::new(
                format!("{key}.duration"),
                "must be a finite number of seconds > 0",
            ));
        }
        let rate = spec.rate;
        let samples = if rate.is_finite() && rate > 0.0 {
            // Saturates for products beyond usize, which `new` then refuses.
            ((d * rate).round() as usize).max(1)
        } else {
            1
        };
        Self::new(key, rate, samples, spec.taps.unwrap_or(DEFAULT_TAPS))
    }
}

/// Validates the scene's `impulse_response` section, which needs `amplitudes`.
pub(super) fn validate(spec: &SceneSpec) -> Result<Option<ImpulseResponseOptions>, SceneError> {
    let Some(ir) = &spec.impulse_response else {
        return Ok(None);
    };
    if spec.amplitudes.is_none() {
        return Err(SceneError::new(
            "impulse_response",
            "needs `amplitudes` (each arrival's pulse is scaled by its amplitude): add \
             \"amplitudes\": {\"source\": \"point\"} or another source model",
        ));
    }
    ImpulseResponseOptions::of_spec("impulse_response", ir).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key_of(rate: f64, duration: f64, taps: Option<usize>) -> String {
        let spec = ImpulseResponseSpec {
            rate,
            duration,
            taps,
        };
        ImpulseResponseOptions::of_spec("impulse_response", &spec)
            .unwrap_err()
            .key
    }

    #[test]
    fn samples_are_rate_times_duration() {
        let spec = ImpulseResponseSpec::new(16000.0, 0.1);
        let o = ImpulseResponseOptions::of_spec("ir", &spec).unwrap();
        assert_eq!((o.samples, o.taps), (1600, DEFAULT_TAPS));
        let tiny = ImpulseResponseSpec::new(10.0, 1e-9);
        assert_eq!(
            ImpulseResponseOptions::of_spec("ir", &tiny)
                .unwrap()
                .samples,
            1
        );
    }

    #[test]
    fn bad_settings_name_their_key() {
        assert_eq!(key_of(0.0, 1.0, None), "impulse_response.rate");
        assert_eq!(key_of(f64::NAN, 1.0, None), "impulse_response.rate");
        assert_eq!(key_of(1e10, 1.0, None), "impulse_response.rate");
        assert_eq!(key_of(48000.0, -1.0, None), "impulse_response.duration");
        assert_eq!(
            key_of(48000.0, f64::INFINITY, None),
            "impulse_response.duration"
        );
        assert_eq!(key_of(1e9, 1e9, None), "impulse_response.duration");
        assert_eq!(key_of(48000.0, 1.0, Some(80)), "impulse_response.taps");
        assert_eq!(
            key_of(48000.0, 1.0, Some(MAX_TAPS + 2)),
            "impulse_response.taps"
        );
    }
}
