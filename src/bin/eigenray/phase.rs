//! The phase factor `e^(2πi f T)` of the coherent sums (`--tl` coherent, `--tl-map`): one
//! echo's ([`unit_phase`]), and a batch's in straight loops ([`unit_phases`]), bit for bit
//! the same numbers.

use eigenray::amplitude::Complex64;

/// 1.5 · 2^52: a sum with it below 2^51 in size is rounded to an integer.
const ROUND: f64 = 6_755_399_441_055_744.0;

/// 2^51: quarter turns below it in size are rounded by a sum with [`ROUND`].
const NEAR: f64 = 2_251_799_813_685_248.0;

/// `e^(2πi · frac(turns))`, the phase factor of an echo at `turns = f · T` cycles: what
/// `Complex64::from_polar(1, 2π frac(turns))` gives, without its general range reduction
/// (nor the library calls of `fract` and `round` on a CPU without SSE4.1), and without a
/// branch on the quarter. `y = 4 · turns` (exact) is split exactly into its nearest integer
/// `q` (below 2^51, the sum with 1.5 · 2^52 rounds it there, ties to even, and the sum's
/// last bits are `q` modulo 4) and a rest `f = y − q`, `|f| ≤ 1/2` (a difference of two
/// numbers within a half of each other: no rounding); the sine and cosine of `π/2 · f` (at
/// most π/4) are fdlibm's kernels (within an ulp), turned by `q` quarter turns, exactly.
/// So each component is within about 2e-16 of the true phase factor of `2π · frac(turns)`
/// (`tests::the_phase_kernel_is_within_an_ulp_or_two_of_libm`).
#[inline]
pub(super) fn unit_phase(turns: f64) -> Complex64 {
    let y = 4.0 * turns;
    let (q, f) = if y.abs() < NEAR {
        let shifted = y + ROUND;
        (shifted.to_bits(), y - (shifted - ROUND))
    } else {
        // Beyond 2^51 quarter turns `y` is a multiple of 1/4 (of 2 above 2^53): `fract`
        // takes the fraction of the turns, exactly.
        let y = 4.0 * turns.fract();
        let r = y.round();
        (r as i64 as u64, y - r)
    };
    let t = std::f64::consts::FRAC_PI_2 * f;
    let (s, c) = (sin_kernel(t), cos_kernel(t));
    // Turned by `q` quarter turns: (c, s), (−s, c), (−c, −s), (s, −c), picked (not branched
    // on: the quarter is as good as random from one echo to the next).
    let turned = [c, -s, -c, s];
    let q = q as usize;
    Complex64::new(turned[q & 3], turned[q.wrapping_add(3) & 3])
}

/// The phase factors of a batch, `cos[i] + i·sin[i] = unit_phase(frequency · times[i])` bit
/// for bit, as straight loops over the batch that the compiler turns into vector
/// instructions: the quarter turn `q` picks and signs the kernels' sine and cosine by its
/// bits (as [`unit_phase`] picks them from a table), and the times beyond `NEAR / 4` quarter
/// turns (or not a number) are redone one at a time, after the batch. `cos` and `sin` are as
/// long as `times`.
#[inline(always)]
pub(super) fn unit_phases(frequency: f64, times: &[f64], cos: &mut [f64], sin: &mut [f64]) {
    let (cos, sin) = (&mut cos[..times.len()], &mut sin[..times.len()]);
    let mut far = false;
    for ((&t, c), s) in times.iter().zip(cos.iter_mut()).zip(sin.iter_mut()) {
        let y = 4.0 * (frequency * t);
        far |= !is_near(y);
        let p = near_phase(y);
        (*c, *s) = (p.re, p.im);
    }
    if far {
        for ((&t, c), s) in times.iter().zip(cos.iter_mut()).zip(sin.iter_mut()) {
            let turns = frequency * t;
            if !is_near(4.0 * turns) {
                let p = unit_phase(turns);
                (*c, *s) = (p.re, p.im);
            }
        }
    }
}

/// Whether `y` quarter turns are reduced by [`near_phase`] (below [`NEAR`] in size; not a
/// NaN).
#[inline(always)]
fn is_near(y: f64) -> bool {
    y.abs() < NEAR
}

/// [`unit_phase`] of `y / 4` turns for `|y| < NEAR`, without a branch or a table: the
/// quarter `q` (the last bits of `y + ROUND`) swaps the cosine and the sine when odd, and
/// flips the signs of the real part (`q` 1 or 2) and of the imaginary part (`q` 2 or 3),
/// exactly as the table `[c, −s, −c, s]` does. Beyond `NEAR` a number, not the phase.
#[inline(always)]
fn near_phase(y: f64) -> Complex64 {
    let shifted = y + ROUND;
    let q = shifted.to_bits();
    let t = std::f64::consts::FRAC_PI_2 * (y - (shifted - ROUND));
    let (c, s) = (cos_kernel(t).to_bits(), sin_kernel(t).to_bits());
    let odd = (q & 1).wrapping_neg();
    let (re, im) = ((c & !odd) | (s & odd), (s & !odd) | (c & odd));
    let re_sign = ((q ^ (q >> 1)) & 1) << 63;
    let im_sign = ((q >> 1) & 1) << 63;
    Complex64::new(f64::from_bits(re ^ re_sign), f64::from_bits(im ^ im_sign))
}

/// `sin t` for `|t| ≤ π/4`: fdlibm's `__kernel_sin` (its tail `y` zero), within one ulp.
#[inline(always)]
fn sin_kernel(t: f64) -> f64 {
    const S1: f64 = -0.16666666666666632;
    const S2: f64 = 0.00833333333332249;
    const S3: f64 = -0.0001984126982985795;
    const S4: f64 = 2.7557313707070068e-06;
    const S5: f64 = -2.5050760253406863e-08;
    const S6: f64 = 1.58969099521155e-10;
    let z = t * t;
    let w = z * z;
    let r = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    t + z * t * (S1 + z * r)
}

/// `cos t` for `|t| ≤ π/4`: fdlibm's `__kernel_cos` (its tail `y` zero), within one ulp.
#[inline(always)]
fn cos_kernel(t: f64) -> f64 {
    const C1: f64 = 0.0416666666666666;
    const C2: f64 = -0.001388888888887411;
    const C3: f64 = 2.480158728947673e-05;
    const C4: f64 = -2.7557314351390663e-07;
    const C5: f64 = 2.087572321298175e-09;
    const C6: f64 = -1.1359647557788195e-11;
    let z = t * t;
    let w = z * z;
    let r = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let one_less = 1.0 - hz;
    one_less + (((1.0 - one_less) - hz) + z * r)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The kernel against libm's `sin` and `cos` of the same reduced argument `2π r` (within
    /// 2.3e-16 a component: an ulp or two), and against `from_polar` of `2π frac(turns)`
    /// (within 1e-15: that argument's own rounding, up to 4.4e-16 rad near a full turn),
    /// over a million fractions spread over `[−3, 3000)` turns, the eighths of a turn and
    /// their neighbours.
    #[test]
    fn the_phase_kernel_is_within_an_ulp_or_two_of_libm() {
        let (mut kernel, mut polar) = (0.0f64, 0.0f64);
        let mut check = |turns: f64| {
            let got = unit_phase(turns);
            let want = Complex64::from_polar(1.0, std::f64::consts::TAU * turns.fract());
            polar = polar
                .max((got.re - want.re).abs())
                .max((got.im - want.im).abs());
            let x = turns.fract();
            let q = (4.0 * x).round();
            let t = std::f64::consts::TAU * (x - 0.25 * q);
            let quarter = Complex64::new(0.0, 1.0).powi((q as i32).rem_euclid(4));
            let exact = Complex64::new(t.cos(), t.sin()) * quarter;
            kernel = kernel
                .max((got.re - exact.re).abs())
                .max((got.im - exact.im).abs());
        };
        // A fixed linear congruential sequence: the same numbers every run.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..1_000_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            check(u * 3003.0 - 3.0);
        }
        for k in -8..=8 {
            let at = f64::from(k) / 8.0;
            for t in [at, at.next_up(), at.next_down(), 300.0 + at, -2.0 + at] {
                check(t);
            }
            // Four times the turns at and beyond 2^51 (the reduction's other way), and below.
            for big in [562_949_953_421_312.0, 1e15, 4_503_599_627_370_496.0] {
                for t in [big + at, big.next_down() + at, -big + at] {
                    check(t);
                }
            }
        }
        assert!(kernel <= 2.3e-16, "{kernel:e}");
        assert!(polar <= 1e-15, "{polar:e}");
        // Exact at the quarter turns, as `from_polar`'s multiples of π/2 are not.
        assert_eq!(unit_phase(0.25), Complex64::new(0.0, 1.0));
        assert_eq!(unit_phase(2.5), Complex64::new(-1.0, 0.0));
        assert_eq!(unit_phase(-0.75), Complex64::new(0.0, 1.0));
        assert!(unit_phase(f64::NAN).re.is_nan());
    }

    /// The batch's phase factors ([`unit_phases`]) against [`unit_phase`] one at a time, bit
    /// for bit (NaN's bits too), over a million times at random frequencies: spread times,
    /// the ties of the rounding (odd eighths of a turn, where `y` is half an integer), their
    /// neighbours, quarter turns at and beyond `NEAR` (the one-at-a-time way) and below,
    /// zeros, infinities and NaN, in batches of every length up to 300 (so the odd ends of
    /// the vector loops too).
    #[test]
    fn a_batch_of_phases_is_the_one_at_a_time_phases_bit_for_bit() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            state >> 11
        };
        let specials = [
            0.0,
            -0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            NEAR / 4.0,
            (NEAR / 4.0).next_down(),
            -NEAR / 4.0,
            1e300,
            f64::MIN_POSITIVE,
        ];
        let (mut checked, mut ties, mut far, mut length) = (0usize, 0usize, 0usize, 0usize);
        while checked < 1_000_000 {
            length = length % 300 + 1;
            let frequency = [1.0, 100.0, 3.0e3, 0.1 + (next() % 1000) as f64][next() as usize % 4];
            let times: Vec<f64> = (0..length)
                .map(|_| {
                    let u = next();
                    let unit = (u >> 8) as f64 / (1u64 << 45) as f64;
                    let turns = match u % 8 {
                        // Ties and their neighbours: odd eighths of a turn.
                        0 => (2 * ((u >> 20) % 20_001) as i64 - 19_999) as f64 / 8.0,
                        1 => ((2 * (u >> 20) + 1) as f64 / 8.0).next_up(),
                        2 => ((2 * (u >> 20) + 1) as f64 / 8.0).next_down(),
                        // Huge: around and beyond 2^49 turns (`y` at 2^51).
                        3 => (1u64 << (45 + u % 12)) as f64 * (1.0 + unit),
                        4 => specials[(u >> 20) as usize % specials.len()],
                        _ => (unit - 0.5) * 2e6,
                    };
                    turns / frequency
                })
                .collect();
            let (mut cos, mut sin) = (vec![0.0; length], vec![0.0; length]);
            unit_phases(frequency, &times, &mut cos, &mut sin);
            for (i, &t) in times.iter().enumerate() {
                let one = unit_phase(frequency * t);
                assert_eq!(
                    (cos[i].to_bits(), sin[i].to_bits()),
                    (one.re.to_bits(), one.im.to_bits()),
                    "time {t:e} at {frequency} Hz"
                );
                let y = 4.0 * (frequency * t);
                ties += usize::from(y.fract().abs() == 0.5);
                far += usize::from(!is_near(y));
            }
            checked += length;
        }
        // The sequence reaches both ways and the ties (not a test that cannot fail).
        assert!(ties > 10_000 && far > 10_000, "{ties} ties, {far} far");
    }
}
