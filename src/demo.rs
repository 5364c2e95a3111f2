//! Built-in scenes: the classic air-over-water refraction used by the demo and the tests.

use crate::scene::{InterfaceSpec, MediumSpec, PathSpec, SceneSpec, SolverSpec, StepSpec};

/// A small deterministic generator (SplitMix64) for jittered receiver grids.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

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

/// `n` receivers on a jittered grid over `[x0, x1] × [y0, y1]`: the box is cut into a grid of
/// about `n` cells (columns × rows ≥ n, the first `n` cells used) and each receiver is placed
/// uniformly at random inside its cell.
pub fn jittered_grid(n: usize, x: [f64; 2], y: [f64; 2], seed: u64) -> Vec<[f64; 2]> {
    if n == 0 {
        return Vec::new();
    }
    let aspect = (x[1] - x[0]) / (y[1] - y[0]);
    let cols = ((n as f64 * aspect).sqrt().round() as usize).clamp(1, n);
    let rows = n.div_ceil(cols);
    let (dx, dy) = ((x[1] - x[0]) / cols as f64, (y[1] - y[0]) / rows as f64);
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|i| {
            let (c, r) = (i % cols, i / cols);
            [
                x[0] + (c as f64 + rng.next_f64()) * dx,
                y[0] + (r as f64 + rng.next_f64()) * dy,
            ]
        })
        .collect()
}

/// The classic air-over-water scene: a flat interface `surface` on y = 0 from x = −1 to 2,
/// index 1.0 above (`air`) and 1.333 below (`water`), a source at (0, 1) and `receivers`
/// receivers on a jittered grid with x in [0, 1] and y in [−1, −0.2]; one path, `transmitted`,
/// refracting once with its leg media given.
///
/// ```
/// let spec = eigenray::demo::air_water(500, 1);
/// let scene = eigenray::Scene::from_spec(&spec).unwrap();
/// assert_eq!(scene.num_rays(), 500);
/// ```
pub fn air_water(receivers: usize, seed: u64) -> SceneSpec {
    let mut spec = SceneSpec {
        description: Some(
            "Air over water: index 1.0 above y = 0, 1.333 below; source (0, 1).".into(),
        ),
        ..SceneSpec::default()
    };
    spec.media.insert(
        "air".into(),
        MediumSpec {
            index: Some(1.0),
            ..MediumSpec::default()
        },
    );
    spec.media.insert(
        "water".into(),
        MediumSpec {
            index: Some(1.333),
            ..MediumSpec::default()
        },
    );
    spec.interfaces.insert(
        "surface".into(),
        InterfaceSpec {
            points: vec![[-1.0, 0.0], [2.0, 0.0]],
            closed: false,
        },
    );
    spec.sources = vec![[0.0, 1.0]];
    spec.receivers = jittered_grid(receivers, [0.0, 1.0], [-1.0, -0.2], seed);
    spec.paths = vec![PathSpec {
        name: Some("transmitted".into()),
        steps: vec![StepSpec::Refract("surface".into())],
        media: Some(vec!["air".into(), "water".into()]),
    }];
    spec.solver = Some(SolverSpec {
        tolerance: Some(1e-12),
        max_iterations: Some(50),
    });
    spec
}
