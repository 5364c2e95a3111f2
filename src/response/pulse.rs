//! Band-limited fractional-delay pulses: where one arrival goes in a sampled response.

use num_complex::Complex64;

use std::f64::consts::PI;

/// The Hann-windowed sinc pulse of pyroomacoustics, and its Hilbert pair for the imaginary
/// part of an amplitude.
///
/// An arrival at `x` samples (any real number) with amplitude `a` adds, for each of the
/// `taps` samples `n = ⌊x⌋ − taps/2 … ⌊x⌋ + taps/2` (a window on whole samples, as
/// pyroomacoustics),
///
/// ```text
/// w[n − ⌊x⌋ + taps/2] · (Re a · sinc(n − x) + Im a · hil(n − x))
/// sinc(d) = sin(πd)/(πd),   hil(d) = (1 − cos πd)/(πd) = 2 sin²(πd/2)/(πd)
/// ```
///
/// with `w` the Hann window of `taps` points, zero at both ends (`np.hanning(taps)`). The two
/// pulses are the real and imaginary parts of the band-limited analytic pulse
/// `(1/π) ∫₀^π e^(iωd) dω`: with the time factor `e^(−iωt)`, a field `a · e^(iωT)` is the
/// real signal `Re a · δ(t − T) + Im a · 1/(π(t − T))`, band-limited to the Nyquist
/// frequency.
#[derive(Clone, Debug, PartialEq)]
pub struct FractionalDelay {
    /// The window, one weight per tap.
    window: Vec<f64>,
    /// Per tap, its whole offset `n` from the arrival's sample (`−taps/2 … taps/2`), as a
    /// float (exact).
    offsets: Vec<f64>,
}

impl FractionalDelay {
    /// The pulse of `taps` samples (odd, at least 1; 81 is pyroomacoustics' default).
    ///
    /// # Panics
    /// If `taps` is even (the pulse is centred on its arrival's sample).
    pub fn hann_sinc(taps: usize) -> FractionalDelay {
        assert!(
            taps % 2 == 1,
            "a fractional-delay pulse has an odd number of taps"
        );
        let window = if taps == 1 {
            vec![1.0]
        } else {
            let m = (taps - 1) as f64;
            (0..taps)
                .map(|k| 0.5 - 0.5 * (2.0 * PI * k as f64 / m).cos())
                .collect()
        };
        let half = (taps / 2) as f64;
        let offsets = (0..taps).map(|k| k as f64 - half).collect();
        FractionalDelay { window, offsets }
    }

    /// Taps of the pulse.
    pub fn taps(&self) -> usize {
        self.window.len()
    }

    /// Adds the pulse of an arrival at `position` samples with amplitude `amplitude` to
    /// `out` (sample `n` of `out` at position `n`); the parts before 0 or past the end are
    /// left out. Allocates nothing.
    ///
    /// One `sin_cos` per arrival, not one per tap: with `x = ⌊x⌋ + f` each tap's delay is
    /// `d = n − f` for a whole `n`, so `sin πd = −(−1)ⁿ sin πf` and `1 − cos πd` is
    /// `2 sin²(πf/2)` for even `n` and `2 cos²(πf/2)` for odd `n` (both without
    /// cancellation); `d` itself is the direct form's to the bit. Equal to the direct form
    /// (a sine per tap and pulse) per tap to round-off (its tests).
    pub fn add(&self, out: &mut [f64], position: f64, amplitude: Complex64) {
        if !position.is_finite() {
            return;
        }
        let half = (self.window.len() / 2) as f64;
        let whole = position.floor();
        let first = whole - half;
        // Whole taps that fall inside `out` (as floats: `position` may be far outside).
        let lo = (-first).max(0.0);
        let hi = (out.len() as f64 - first).min(self.window.len() as f64);
        if lo >= hi {
            return;
        }
        let (lo, hi) = (lo as usize, hi as usize);
        let start = (first + lo as f64) as usize;
        // The fraction (exact: `whole` is `position`'s floor), and the sines of the pulse.
        let f = position - whole;
        // sin(πf/2) and cos(πf/2), the smaller from the nearer end (exactly 1 − f), where
        // the argument's rounding is small against it.
        let (s, c) = if f <= 0.5 {
            (0.5 * PI * f).sin_cos()
        } else {
            let (c, s) = (0.5 * PI * (1.0 - f)).sin_cos();
            (s, c)
        };
        // sin πf, 1 − cos πf, 1 + cos πf.
        let (sine, even, odd) = (2.0 * s * c, 2.0 * s * s, 2.0 * c * c);
        let (re, im) = (amplitude.re, amplitude.im);
        // The numerators at even and odd taps.
        let (at_even, at_odd) = (im * even - re * sine, im * odd + re * sine);
        // Every tap's delay `d = n − f` is nonzero (`f` in (0, 1) or `n` nonzero) but the
        // arrival's own sample where `f` is 0: that tap is `re` (the limit of both pulses), so
        // the taps on either side of it go on without it.
        let (weights, offsets) = (&self.window[lo..hi], &self.offsets[lo..hi]);
        let slots = &mut out[start..start + (hi - lo)];
        let numerator = |k: usize| {
            if (lo + k + self.window.len() / 2).is_multiple_of(2) {
                [at_even, at_odd]
            } else {
                [at_odd, at_even]
            }
        };
        let centre = self.window.len() / 2;
        if f == 0.0 && (lo..hi).contains(&centre) {
            let c = centre - lo;
            let (before, rest) = slots.split_at_mut(c);
            add_taps(before, &weights[..c], &offsets[..c], f, numerator(0));
            rest[0] += weights[c] * re;
            let after = c + 1;
            add_taps(
                &mut rest[1..],
                &weights[after..],
                &offsets[after..],
                f,
                numerator(after),
            );
        } else {
            add_taps(slots, weights, offsets, f, numerator(0));
        }
    }
}

/// Adds `weights[k] · numerators[k mod 2] / (π (offsets[k] − f))` to each `slots[k]`: the taps
/// of [`FractionalDelay::add`] two at a time (each the same expression as one at a time, so
/// the same bits), `numerators` those of the first tap's parity and the next's.
#[inline(always)]
fn add_taps(slots: &mut [f64], weights: &[f64], offsets: &[f64], f: f64, numerators: [f64; 2]) {
    let mut slot_pairs = slots.chunks_exact_mut(2);
    let mut weight_pairs = weights.chunks_exact(2);
    let mut offset_pairs = offsets.chunks_exact(2);
    for ((s, w), o) in (&mut slot_pairs)
        .zip(&mut weight_pairs)
        .zip(&mut offset_pairs)
    {
        for j in 0..2 {
            let d = o[j] - f;
            s[j] += w[j] * (numerators[j] / (PI * d));
        }
    }
    let last = (
        slot_pairs.into_remainder(),
        weight_pairs.remainder(),
        offset_pairs.remainder(),
    );
    if let ([s], [w], [o]) = last {
        *s += *w * (numerators[0] / (PI * (*o - f)));
    }
}

/// `sin(πd)/(πd)`: 1 at 0, exactly 0 at the other whole numbers (the direct form, which
/// the tests hold `FractionalDelay::add` to).
#[cfg(test)]
fn sinc(d: f64) -> f64 {
    if d == 0.0 {
        1.0
    } else if d.fract() == 0.0 {
        0.0
    } else {
        (PI * d).sin() / (PI * d)
    }
}

/// The Hilbert transform of [`sinc`]: `(1 − cos πd)/(πd)`, written `2 sin²(πd/2)/(πd)` so that
/// it keeps its precision near 0: exactly 0 at even whole numbers, `2/(πd)` at odd ones (the
/// direct form, as [`sinc`]).
#[cfg(test)]
fn hilbert_sinc(d: f64) -> f64 {
    if d.fract() == 0.0 {
        if (d * 0.5).fract() == 0.0 {
            0.0
        } else {
            2.0 / (PI * d)
        }
    } else {
        let s = (0.5 * PI * d).sin();
        2.0 * s * s / (PI * d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(1/π) ∫₀^π e^(iωd) dω` by Simpson's rule on `n` intervals: the band-limited analytic
    /// pulse, independently of the closed forms.
    fn analytic_pulse(d: f64, n: usize) -> Complex64 {
        let h = PI / n as f64;
        let f = |w: f64| Complex64::new((w * d).cos(), (w * d).sin());
        let mut s = f(0.0) + f(PI);
        for j in 1..n {
            s += f(j as f64 * h) * if j % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * (h / 3.0) / PI
    }

    #[test]
    fn the_pulses_are_the_band_limited_analytic_pulse() {
        for &d in &[
            -40.3, -7.5, -1.0, -0.25, -1e-9, 0.0, 1e-12, 0.1, 0.5, 0.999, 3.0, 17.77,
        ] {
            let q = analytic_pulse(d, 20_000);
            assert!(
                (sinc(d) - q.re).abs() < 1e-12,
                "sinc({d}) {} vs {}",
                sinc(d),
                q.re
            );
            assert!(
                (hilbert_sinc(d) - q.im).abs() < 1e-12,
                "hil({d}) {} vs {}",
                hilbert_sinc(d),
                q.im
            );
        }
    }

    #[test]
    fn both_pulses_carry_unit_energy() {
        // Parseval: a band-limited unit pulse and its Hilbert transform each have energy 1 at
        // any fractional delay (the tails beyond ±N hold about 1/(π²N) of it).
        for &frac in &[0.0, 0.3, 0.5, 0.77] {
            let n = 200_000i64;
            let (mut e, mut eh) = (0.0, 0.0);
            for k in -n..=n {
                let d = k as f64 - frac;
                e += sinc(d) * sinc(d);
                eh += hilbert_sinc(d) * hilbert_sinc(d);
            }
            assert!((e - 1.0).abs() < 1e-5, "energy {e} at {frac}");
            assert!((eh - 1.0).abs() < 1e-5, "Hilbert energy {eh} at {frac}");
        }
    }

    #[test]
    fn a_whole_sample_arrival_is_one_sample_and_its_pair_is_odd() {
        let p = FractionalDelay::hann_sinc(81);
        let mut out = vec![0.0; 200];
        p.add(&mut out, 100.0, Complex64::new(0.5, 0.0));
        for (n, &v) in out.iter().enumerate() {
            let want = if n == 100 { 0.5 } else { 0.0 };
            assert!((v - want).abs() < 1e-15, "sample {n}: {v}");
        }
        let mut pair = vec![0.0; 200];
        p.add(&mut pair, 100.0, Complex64::new(0.0, 1.0));
        assert_eq!(pair[100], 0.0);
        for m in 1..=40 {
            assert!((pair[100 + m] + pair[100 - m]).abs() < 1e-15, "odd at {m}");
            // Odd offsets 2/(πm) windowed, even ones 0.
            let w = 0.5 - 0.5 * (2.0 * PI * (40 + m) as f64 / 80.0).cos();
            let want = if m % 2 == 1 {
                w * 2.0 / (PI * m as f64)
            } else {
                0.0
            };
            assert!(
                (pair[100 + m] - want).abs() < 1e-15,
                "{m}: {}",
                pair[100 + m]
            );
        }
        assert_eq!(pair.iter().filter(|v| **v != 0.0).count(), 40);
    }

    #[test]
    fn the_pulse_is_pyroomacoustics_fractional_delay_filter() {
        // pyroomacoustics.utilities.fractional_delay(t0) = np.hanning(81) *
        // np.sinc(np.arange(81) - 40 - t0), written out.
        let p = FractionalDelay::hann_sinc(81);
        let frac = 0.3125;
        let mut out = vec![0.0; 300];
        p.add(&mut out, 150.0 + frac, Complex64::new(1.0, 0.0));
        for k in 0..81 {
            let hann = 0.5 - 0.5 * (2.0 * PI * k as f64 / 80.0).cos();
            let x = k as f64 - 40.0 - frac;
            let want = hann * (PI * x).sin() / (PI * x);
            assert!((out[110 + k] - want).abs() < 1e-15, "tap {k}");
        }
        assert_eq!(out.iter().filter(|v| **v != 0.0).count(), 79);
    }

    /// The pulse of one `sin_cos` per arrival against the direct form (a `sin` per tap:
    /// `w · (Re a · sinc(d) + Im a · hil(d))`), at random fractional positions (whole ones,
    /// near-whole ones, far from 0) and complex amplitudes: every tap within 1e-14 of the
    /// amplitude's size (the peak of a pulse is about the amplitude).
    ///
    /// Mutants caught: the signs of the odd and even taps swapped, `1 − cos` for `1 + cos`.
    #[test]
    fn one_sine_per_arrival_is_the_direct_form() {
        let mut rng = crate::demo::SplitMix64(5);
        for taps in [1, 3, 81, 161] {
            let p = FractionalDelay::hann_sinc(taps);
            let half = (taps / 2) as f64;
            let mut worst = 0.0f64;
            for round in 0..400 {
                let base = [200.0, 1234.0, 31_999.0, 4.0e6][round % 4];
                let frac = match round % 5 {
                    0 => 0.0,
                    1 => 1e-13 * rng.next_f64(),
                    2 => 1.0 - 1e-13 * rng.next_f64(),
                    _ => rng.next_f64(),
                };
                let position = base + frac;
                let a = Complex64::new(2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0);
                let a = if round % 3 == 0 {
                    Complex64::new(a.re, 0.0)
                } else {
                    a
                };
                let n = (base as usize) + 2 * taps + 2;
                let mut out = vec![0.0; n];
                p.add(&mut out, position, a);
                let first = position.floor() - half;
                for k in 0..taps {
                    let d = first + k as f64 - position;
                    let want = p.window[k] * (a.re * sinc(d) + a.im * hilbert_sinc(d));
                    let got = out[first as usize + k];
                    let e = (got - want).abs() / a.norm();
                    worst = worst.max(e);
                }
            }
            assert!(worst <= 1e-14, "{taps} taps: {worst:e}");
        }
    }

    /// [`FractionalDelay::add`] one tap at a time, as it was written before its taps went
    /// two at a time: a whole counter, the numerator of the tap's parity, the arrival's own
    /// sample `re` where the delay is 0.
    fn add_tap_by_tap(p: &FractionalDelay, out: &mut [f64], position: f64, amplitude: Complex64) {
        let half = (p.window.len() / 2) as f64;
        let whole = position.floor();
        let first = whole - half;
        let lo = (-first).max(0.0);
        let hi = (out.len() as f64 - first).min(p.window.len() as f64);
        if !position.is_finite() || lo >= hi {
            return;
        }
        let (lo, hi) = (lo as usize, hi as usize);
        let start = (first + lo as f64) as usize;
        let f = position - whole;
        let (s, c) = if f <= 0.5 {
            (0.5 * PI * f).sin_cos()
        } else {
            let (c, s) = (0.5 * PI * (1.0 - f)).sin_cos();
            (s, c)
        };
        let (sine, even, odd) = (2.0 * s * c, 2.0 * s * s, 2.0 * c * c);
        let (re, im) = (amplitude.re, amplitude.im);
        let (at_even, at_odd) = (im * even - re * sine, im * odd + re * sine);
        for k in lo..hi {
            let n = k as i64 - half as i64;
            let d = n as f64 - f;
            let numerator = if n % 2 == 0 { at_even } else { at_odd };
            let value = if d == 0.0 { re } else { numerator / (PI * d) };
            out[start + k - lo] += p.window[k] * value;
        }
    }

    /// The taps two at a time are the taps one at a time, to the bit: whole and fractional
    /// positions, both ends of the response cutting the pulse at even and odd taps, pulses
    /// of 1, 3, 81 and 161 taps, each added onto a response already holding others.
    ///
    /// Mutants caught: the numerators' parity swapped, the arrival's own sample left out or
    /// taken twice, the last odd tap left out.
    #[test]
    fn taps_two_at_a_time_are_taps_one_at_a_time() {
        let mut rng = crate::demo::SplitMix64(39);
        for taps in [1, 3, 81, 161] {
            let p = FractionalDelay::hann_sinc(taps);
            let (mut pairs, mut single) = (vec![0.0; 300], vec![0.0; 300]);
            for round in 0..2_000 {
                let base = (rng.next_f64() * 380.0).floor() - 40.0;
                let frac = match round % 4 {
                    0 => 0.0,
                    1 => 1e-14 * rng.next_f64(),
                    _ => rng.next_f64(),
                };
                let a = Complex64::new(2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0);
                p.add(&mut pairs, base + frac, a);
                add_tap_by_tap(&p, &mut single, base + frac, a);
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&pairs), bits(&single), "{taps} taps, round {round}");
            }
        }
    }

    #[test]
    fn pulses_are_cut_at_both_ends() {
        let p = FractionalDelay::hann_sinc(81);
        let full = {
            let mut out = vec![0.0; 400];
            p.add(&mut out, 200.375, Complex64::new(1.0, -0.5));
            out
        };
        let mut early = vec![0.0; 30];
        p.add(&mut early, 10.375, Complex64::new(1.0, -0.5));
        assert_eq!(early[..], full[190..220]);
        let mut late = vec![0.0; 215];
        p.add(&mut late, 200.375, Complex64::new(1.0, -0.5));
        assert_eq!(late[..], full[..215]);
        for far in [-1e300, -41.0, 400.0 + 41.0, 1e300, f64::NAN] {
            let mut out = vec![0.0; 400];
            p.add(&mut out, far, Complex64::new(1.0, 1.0));
            assert!(out.iter().all(|&v| v == 0.0), "{far}");
        }
    }
}
