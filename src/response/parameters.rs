//! Room acoustic parameters of an impulse response (ISO 3382-1): the Schroeder decay curve,
//! the decay times `edt`, `t20` and `t30`, the clarities `c50` and `c80` and the definition
//! `d50`, with time zero at the first arrival.
//!
//! The decay curve is the backward integral of the squared response,
//! `L(t) = 10 log10(∫ₜ^∞ h² / ∫₀^∞ h²)` dB, summed sample by sample (nothing arrives before the
//! first arrival but its own pulse's leading half, so the sums may start at sample 0). A decay
//! time is the least-squares line through `L` over the samples from the first arrival whose
//! level lies within its range (0 to −10 dB for `edt`, −5 to −25 dB for `t20`, −5 to −35 dB
//! for `t30`), extrapolated to 60 dB: `−60 / slope`. The early energy of `c50`, `c80` and
//! `d50` is that of the samples before the first arrival plus 50 or 80 ms (the scene's time
//! unit taken as seconds), the late energy the rest: `c = 10 log10(early / late)`,
//! `d50 = early / total`.
//!
//! A value is `null` with a reason when the response cannot give it: a response that ends
//! before its range's lower level is reached with room to spare (the last tenth of the span
//! after the first arrival is not trusted: a truncated response's curve plunges there), a
//! range of fewer than [`MIN_FIT_SAMPLES`] samples (too sparse), no energy at all, or a
//! response shorter than 50 or 80 ms after its first arrival.

use serde::Serialize;

/// The fewest samples a decay time is fitted through.
pub const MIN_FIT_SAMPLES: usize = 8;

/// One parameter: its value, or why it has none.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoomParameter {
    /// The value (seconds for decay times, dB for clarities, a fraction for `d50`), or `None`.
    pub value: Option<f64>,
    /// Why it has no value, when it has none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

impl RoomParameter {
    fn value(v: f64) -> RoomParameter {
        RoomParameter {
            value: Some(v),
            reason: None,
        }
    }

    fn none(reason: impl Into<String>) -> RoomParameter {
        RoomParameter {
            value: None,
            reason: Some(reason.into()),
        }
    }
}

/// The room acoustic parameters of one impulse response.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RoomParameters {
    /// The first arrival's time: time zero of every parameter.
    pub first_arrival: Option<f64>,
    /// Early decay time (from the 0 to −10 dB range), s.
    pub edt: RoomParameter,
    /// Reverberation time from the −5 to −25 dB range, s.
    pub t20: RoomParameter,
    /// Reverberation time from the −5 to −35 dB range, s.
    pub t30: RoomParameter,
    /// Clarity at 50 ms, dB.
    pub c50: RoomParameter,
    /// Clarity at 80 ms, dB.
    pub c80: RoomParameter,
    /// Definition: the fraction of the energy within 50 ms.
    pub d50: RoomParameter,
}

/// The Schroeder decay curve of `response`, in dB relative to its total energy (`-inf`
/// where no energy is left; all NaN when the response has no energy).
pub fn schroeder_decay(response: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; response.len()];
    let mut sum = 0.0;
    for (o, h) in out.iter_mut().zip(response).rev() {
        sum += h * h;
        *o = sum;
    }
    let total = sum;
    for o in &mut out {
        *o = if total > 0.0 {
            10.0 * (*o / total).log10()
        } else {
            f64::NAN
        };
    }
    out
}

/// The parameters of `response`, sampled at `rate`, whose first arrival is at
/// `first_arrival` (`None`: nothing arrives).
pub fn room_parameters(response: &[f64], rate: f64, first_arrival: Option<f64>) -> RoomParameters {
    let none = |why: &str| RoomParameters {
        first_arrival,
        edt: RoomParameter::none(why),
        t20: RoomParameter::none(why),
        t30: RoomParameter::none(why),
        c50: RoomParameter::none(why),
        c80: RoomParameter::none(why),
        d50: RoomParameter::none(why),
    };
    let Some(t0) = first_arrival else {
        return none("no arrival reaches the receiver");
    };
    let energy: f64 = response.iter().map(|h| h * h).sum();
    if energy.is_nan() || energy <= 0.0 {
        return none("the response has no energy");
    }
    let decay = schroeder_decay(response);
    let start = ((t0 * rate).floor().max(0.0) as usize).min(response.len());
    let end = response.len() as f64 / rate;
    // The last tenth of the span after the first arrival is not trusted.
    let trusted = start + ((response.len() - start) * 9) / 10;
    let decay_time = |hi: f64, lo: f64| fit(&decay, rate, start, trusted, hi, lo);
    let split = |ms: f64| {
        let cut = t0 + ms / 1000.0;
        if cut > end {
            return None;
        }
        let n = ((cut * rate).ceil() as usize).min(response.len());
        let early: f64 = response[..n].iter().map(|h| h * h).sum();
        Some((early, energy - early))
    };
    let clarity = |ms: f64| match split(ms) {
        None => RoomParameter::none(format!(
            "the response ends {:.4} s after the first arrival, before {ms} ms",
            end - t0
        )),
        Some((_, late)) if late <= 0.0 => {
            RoomParameter::none(format!("no energy arrives after {ms} ms"))
        }
        Some((early, late)) => RoomParameter::value(10.0 * (early / late).log10()),
    };
    RoomParameters {
        first_arrival,
        edt: decay_time(0.0, -10.0),
        t20: decay_time(-5.0, -25.0),
        t30: decay_time(-5.0, -35.0),
        c50: clarity(50.0),
        c80: clarity(80.0),
        d50: match split(50.0) {
            None => RoomParameter::none(format!(
                "the response ends {:.4} s after the first arrival, before 50 ms",
                end - t0
            )),
            Some((early, _)) => RoomParameter::value(early / energy),
        },
    }
}

/// The decay time from the least-squares line through `decay` over the samples from `start`
/// whose level lies within `[lo, hi]` dB, when the curve reaches `lo` before `trusted`.
fn fit(decay: &[f64], rate: f64, start: usize, trusted: usize, hi: f64, lo: f64) -> RoomParameter {
    let Some(last) = (start..trusted).find(|&n| decay[n] < lo) else {
        let reached = decay[start..trusted.max(start)]
            .iter()
            .copied()
            .fold(0.0, f64::min);
        return RoomParameter::none(format!(
            "too short: its decay curve reaches only {reached:.1} dB (before the last tenth \
             of the response), not {lo} dB"
        ));
    };
    let (mut n, mut st, mut sl, mut stt, mut stl) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (k, &l) in decay.iter().enumerate().take(last).skip(start) {
        if l <= hi && l >= lo {
            let t = k as f64 / rate;
            n += 1.0;
            st += t;
            sl += l;
            stt += t * t;
            stl += t * l;
        }
    }
    if n < MIN_FIT_SAMPLES as f64 {
        return RoomParameter::none(format!(
            "too sparse: {n} samples of its decay curve lie from {hi} to {lo} dB (at least \
             {MIN_FIT_SAMPLES} needed)"
        ));
    }
    let slope = (n * stl - st * sl) / (n * stt - st * st);
    if slope.is_nan() || slope >= 0.0 {
        return RoomParameter::none("the decay curve does not fall over its range");
    }
    RoomParameter::value(-60.0 / slope)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An exponential decay of energy, `h² ∝ 10^(−6 t / T)`: every decay time is `T` (the
    /// curve's line exact up to the truncation at the end, far below the ranges here).
    #[test]
    fn an_exponential_decay_gives_its_decay_time() {
        let (rate, t60) = (8000.0, 0.5);
        let n = (3.0 * t60 * rate) as usize;
        let response: Vec<f64> = (0..n)
            .map(|k| 10f64.powf(-3.0 * (k as f64 / rate) / t60))
            .collect();
        let p = room_parameters(&response, rate, Some(0.0));
        for (what, v) in [("edt", &p.edt), ("t20", &p.t20), ("t30", &p.t30)] {
            let v = v.value.unwrap_or_else(|| panic!("{what}: {:?}", v.reason));
            assert!((v - t60).abs() < 1e-3 * t60, "{what}: {v}");
        }
        // C50: ∫₀^0.05 / ∫_0.05^∞ of 10^(−6t/T) = 10^(0.3/T) − 1 (truncation far below).
        let want = 10.0 * (10f64.powf(6.0 * 0.05 / t60) - 1.0).log10();
        let c50 = p.c50.value.unwrap();
        assert!((c50 - want).abs() < 0.05, "{c50} {want}");
    }

    #[test]
    fn a_short_or_empty_response_says_why() {
        let rate = 8000.0;
        let response: Vec<f64> = (0..400)
            .map(|k| 10f64.powf(-3.0 * (k as f64 / rate) / 2.0))
            .collect();
        let p = room_parameters(&response, rate, Some(0.0));
        assert!(p.t30.value.is_none() && p.t30.reason.as_ref().unwrap().contains("too short"));
        assert!(p.c80.value.is_none());
        let p = room_parameters(&[0.0; 10], rate, Some(0.0));
        assert!(p.edt.value.is_none());
        let p = room_parameters(&response, rate, None);
        assert!(p.d50.reason.as_ref().unwrap().contains("no arrival"));
    }
}
