//! SplitMix64: the small reproducible generator of the tests' random cases (the same sequence
//! as the demo's jittered grids).

/// A SplitMix64 state.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

#[allow(
    dead_code,
    reason = "each test binary uses its own part of the generator"
)]
impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A uniform number in `[0, 1)`.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}
