//! Coherent pressure at one frequency, and the transmission loss it gives.

use std::f64::consts::PI;

use num_complex::Complex64;

use super::Echo;
use crate::options::{Progress, Run};

/// Sums `echoes` coherently at `frequency` into `out`, one complex pressure per (source,
/// receiver), source-major (`out[s · receivers + r]`): `p = Σ a · e^(iωT)` with `ω = 2πf`,
/// the time factor `e^(−iωt)` of the amplitudes. Echoes of other sources or receivers are
/// left out. Allocates nothing.
///
/// Each echo is an item and a unit of work of `run`, asked for before it is summed: once
/// `run` stops (a stop request, a spent budget) the echoes left are not summed.
///
/// The phase is taken from the fractional part of `f · T`, so it keeps its precision at
/// large `f · T`.
///
/// # Panics
/// If `out` does not hold `sources × receivers` numbers, with `receivers = out.len() /
/// sources`.
pub fn pressure_into(
    echoes: impl IntoIterator<Item = Echo>,
    frequency: f64,
    sources: usize,
    run: &Run,
    out: &mut [Complex64],
) {
    assert!(
        sources > 0 && out.len().is_multiple_of(sources),
        "pressure buffer of the wrong size"
    );
    let receivers = out.len() / sources;
    out.fill(Complex64::new(0.0, 0.0));
    for e in echoes {
        if e.source < sources && e.receiver < receivers {
            if !run.keep_going(Progress::items(1)) {
                return;
            }
            let cycles = (frequency * e.time).fract();
            let phase = Complex64::from_polar(1.0, 2.0 * PI * cycles);
            out[e.source * receivers + e.receiver] += e.amplitude * phase;
        }
    }
}

/// The transmission loss of a pressure `p` from a unit source: `−20 log10(|p| · 4π)` dB
/// (relative to the free field 1 unit of length from a point source; +∞ where `p` is 0).
pub fn transmission_loss(p: Complex64) -> f64 {
    -20.0 * (p.norm() * 4.0 * PI).log10()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn echo(receiver: usize, time: f64, amplitude: Complex64) -> Echo {
        Echo {
            source: 0,
            receiver,
            time,
            amplitude,
            order: 0,
            diffractions: 0,
            vertical_reflections: 0,
        }
    }

    #[test]
    fn lloyds_mirror_against_its_closed_form() {
        // Source at depth 5 under a pressure-release surface, receivers at depth 10: the
        // direct and surface-reflected arrivals against |e^(ikR₁)/R₁ − e^(ikR₂)/R₂| / (4π).
        let (c, f, zs, zr) = (1500.0, 150.0, 5.0, 10.0);
        let k = 2.0 * PI * f / c;
        let ranges: Vec<f64> = (1..200).map(|i| 5.0 * i as f64).collect();
        let mut echoes = Vec::new();
        for (i, &x) in ranges.iter().enumerate() {
            let r1 = (x * x + (zr - zs) * (zr - zs)).sqrt();
            let r2 = (x * x + (zr + zs) * (zr + zs)).sqrt();
            echoes.push(echo(i, r1 / c, Complex64::new(1.0 / (4.0 * PI * r1), 0.0)));
            echoes.push(echo(i, r2 / c, Complex64::new(-1.0 / (4.0 * PI * r2), 0.0)));
        }
        let mut p = vec![Complex64::new(0.0, 0.0); ranges.len()];
        pressure_into(echoes, f, 1, &Run::new(), &mut p);
        for (i, &x) in ranges.iter().enumerate() {
            let r1 = (x * x + (zr - zs) * (zr - zs)).sqrt();
            let r2 = (x * x + (zr + zs) * (zr + zs)).sqrt();
            let want = (Complex64::from_polar(1.0 / r1, k * r1)
                - Complex64::from_polar(1.0 / r2, k * r2))
                / (4.0 * PI);
            // Round-off of the phases, relative to one arrival's size.
            let one = 1.0 / (4.0 * PI * r1);
            assert!((p[i] - want).norm() < 1e-12 * one, "{x}");
            if want.norm() > 1e-3 * one {
                let tl = -20.0 * (want.norm() * 4.0 * PI).log10();
                assert!((transmission_loss(p[i]) - tl).abs() < 1e-6, "{x}");
            }
        }
    }

    #[test]
    fn one_metre_of_free_field_is_zero_db() {
        let p = Complex64::from_polar(1.0 / (4.0 * PI), 0.7);
        assert!(transmission_loss(p).abs() < 1e-14);
        assert_eq!(transmission_loss(Complex64::new(0.0, 0.0)), f64::INFINITY);
        let ten = Complex64::new(1.0 / (40.0 * PI), 0.0);
        assert!((transmission_loss(ten) - 20.0).abs() < 1e-12);
    }

    #[test]
    fn echoes_of_other_pairs_are_left_out() {
        let mut p = vec![Complex64::new(9.0, 9.0); 4];
        let echoes = [
            Echo {
                source: 1,
                receiver: 1,
                time: 0.0,
                amplitude: Complex64::new(1.0, 0.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
            Echo {
                source: 2,
                receiver: 0,
                time: 0.0,
                amplitude: Complex64::new(1.0, 0.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
            Echo {
                source: 0,
                receiver: 2,
                time: 0.0,
                amplitude: Complex64::new(1.0, 0.0),
                order: 0,
                diffractions: 0,
                vertical_reflections: 0,
            },
        ];
        pressure_into(echoes, 100.0, 2, &Run::new(), &mut p);
        assert_eq!(p[3], Complex64::new(1.0, 0.0));
        assert_eq!(p[..3], [Complex64::new(0.0, 0.0); 3]);
    }
}
