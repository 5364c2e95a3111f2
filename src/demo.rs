//! Built-in scenes: the classic air-over-water refraction, layer stacks and a digitised sea floor.

use crate::scene::{InterfaceSpec, MediumSpec, PathSpec, SceneSpec, SolverSpec, StepSpec};

/// A small deterministic generator (SplitMix64) for jittered receiver grids.
#[derive(Clone, Debug)]
pub(crate) struct SplitMix64(pub(crate) u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// A uniform number in `[0, 1)`.
    pub(crate) fn next_f64(&mut self) -> f64 {
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
            reflection: None,
        },
    );
    spec.sources = vec![[0.0, 1.0]];
    spec.receivers = jittered_grid(receivers, [0.0, 1.0], [-1.0, -0.2], seed).into();
    spec.paths = vec![PathSpec {
        name: Some("transmitted".into()),
        steps: vec![StepSpec::Refract("surface".into())],
        media: Some(vec!["air".into(), "water".into()]),
    }];
    spec.solver = Some(SolverSpec {
        tolerance: Some(1e-12),
        max_iterations: Some(50),
        ..Default::default()
    });
    spec
}

/// Speeds of the media of [`layer_stack`], from the top down, repeated every 11 layers (those of
/// the benchmark scene `fixtures/bench/layers10.json`).
pub const LAYER_SPEEDS: [f64; 11] = [1.0, 1.25, 0.9, 1.6, 1.1, 2.0, 1.4, 0.8, 1.7, 1.2, 1.5];

/// `n` evenly spaced values from `a` to `b` inclusive (`[a]` when `n == 1`).
fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![a],
        _ => (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect(),
    }
}

/// A stack of `n_layers` flat horizontal interfaces with one path refracting down through all
/// of them: a path of `n_layers` interactions whose exact solution is known (one ray parameter
/// `p` solves `Σ hⱼ p vⱼ / √(1 − p² vⱼ²) = offset`), for benchmarks of the cost per interaction.
///
/// Interface `L…i` (names zero-padded, so name order is depth order) lies on `y = −i` for
/// `x ∈ [−W, W]` with `W = max(100, 10 n)`; medium `m…j` above interface `j` (and `m…n` below
/// the last) has speed [`LAYER_SPEEDS`]`[j % 11]`. The source is at `(0, 1)`, the `receivers`
/// receivers lie on `y = −n − 0.5` with `x` evenly spaced over `[−0.3 n, 0.9 n]` (offsets up to
/// about 0.9 of the depth). One path, `down`, refracts through `L…0`, …, `L…(n−1)` in order,
/// with its leg media given (so the scene builds no triangulation). `layer_stack(10, 1000)`
/// is the benchmark scene `layers10` up to the rounding of its receivers' coordinates.
///
/// ```
/// use eigenray::{Scene, Status, Tracer, Workspace};
/// let scene = Scene::from_spec(&eigenray::demo::layer_stack(8, 5)).unwrap();
/// assert_eq!(scene.paths()[0].steps.len(), 8);
/// let tracer = Tracer::new(&scene).unwrap();
/// let mut ws = Workspace::new();
/// let ray = tracer.solve_indexed_from(0, 4, 0, None, &mut ws);
/// assert_eq!(ray.status, Status::Converged);
/// assert_eq!(ws.points().len(), 10); // source, 8 refraction points, receiver
/// ```
///
/// # Panics
/// If `n_layers` is 0.
pub fn layer_stack(n_layers: usize, receivers: usize) -> SceneSpec {
    assert!(n_layers > 0, "a layer stack needs at least one interface");
    let n = n_layers;
    let width = n.to_string().len().max(3);
    let half = (10.0 * n as f64).max(100.0);
    let mut spec = SceneSpec {
        description: Some(format!(
            "{n} flat layers y = 0, -1, ..., -{} (x in [-{half}, {half}]); speeds {LAYER_SPEEDS:?} \
             repeating from the top; source (0, 1); receivers on y = -{n}.5; one path refracting \
             down through every interface.",
            n - 1
        )),
        ..SceneSpec::default()
    };
    let medium = |j: usize| format!("m{j:0width$}");
    let interface = |i: usize| format!("L{i:0width$}");
    for j in 0..=n {
        spec.media.insert(
            medium(j),
            MediumSpec {
                speed: Some(LAYER_SPEEDS[j % LAYER_SPEEDS.len()]),
                ..MediumSpec::default()
            },
        );
    }
    for i in 0..n {
        let y = -(i as f64);
        spec.interfaces.insert(
            interface(i),
            InterfaceSpec {
                points: vec![[-half, y], [half, y]],
                closed: false,
                reflection: None,
            },
        );
    }
    spec.sources = vec![[0.0, 1.0]];
    let y = -(n as f64) - 0.5;
    spec.receivers = linspace(-0.3 * n as f64, 0.9 * n as f64, receivers)
        .into_iter()
        .map(|x| [x, y])
        .collect::<Vec<_>>()
        .into();
    spec.paths = vec![PathSpec {
        name: Some("down".into()),
        steps: (0..n).map(|i| StepSpec::Refract(interface(i))).collect(),
        media: Some((0..=n).map(medium).collect()),
    }];
    spec.solver = Some(SolverSpec {
        tolerance: Some(1e-12),
        max_iterations: Some(100),
        ..Default::default()
    });
    spec
}

/// [`layer_stack`] with dipping interfaces: interface `i` turned about `x = 0` to the slope
/// `0.9 i / W` (`W` its half-width, so that neighbours never cross; the deepest dips about 5°),
/// and the receivers lowered to `y = −1.1 n − 0.5`. The layers are not parallel, so the start
/// is the paraxial one and Newton steps remain (benchmarks of the general case).
///
/// ```
/// let scene = eigenray::Scene::from_spec(&eigenray::demo::dipping_stack(8, 5)).unwrap();
/// let tracer = eigenray::Tracer::new(&scene).unwrap();
/// let rays = tracer.trace_all();
/// assert!(rays.iter().all(|r| r.status == eigenray::Status::Converged && r.iterations > 0));
/// ```
///
/// # Panics
/// If `n_layers` is 0.
pub fn dipping_stack(n_layers: usize, receivers: usize) -> SceneSpec {
    let mut spec = layer_stack(n_layers, receivers);
    for (i, iface) in spec.interfaces.values_mut().enumerate() {
        let (x0, x1, y) = (iface.points[0][0], iface.points[1][0], iface.points[0][1]);
        let slope = 0.9 * i as f64 / x1;
        iface.points = vec![[x0, y + slope * x0], [x1, y + slope * x1]];
    }
    for r in spec.receivers.points_mut() {
        r[1] = -1.1 * n_layers as f64 - 0.5;
    }
    spec.description = Some(format!(
        "{} flat layers turned about x = 0 (interface i to slope 0.9 i / W); receivers lowered \
         to y = -1.1 n - 0.5",
        n_layers
    ));
    spec
}

/// [`layer_stack`] with digitised undulating interfaces: interface `i` is
/// `y = −i + 0.3 sin(3 · 2π x / (2W) + i)` (`W` its half-width: three wavelengths across)
/// sampled at `segments + 1` evenly spaced `x`. Neighbours stay at least 0.4 apart. For an
/// even `segments` every interface has a vertex on `x = 0`, straight below the source: the
/// rays near the vertical cross a column of vertices, and some end held on vertices
/// (`vertex`), the nasty case of digitised horizons.
///
/// ```
/// use eigenray::Status;
/// let scene = eigenray::Scene::from_spec(&eigenray::demo::undulating_stack(8, 100, 50)).unwrap();
/// let rays = eigenray::Tracer::new(&scene).unwrap().trace_all();
/// assert!(rays.iter().all(|r| matches!(r.status, Status::Converged | Status::Vertex)));
/// ```
///
/// # Panics
/// If `n_layers` or `segments` is 0.
pub fn undulating_stack(n_layers: usize, segments: usize, receivers: usize) -> SceneSpec {
    assert!(segments > 0, "an interface needs at least one segment");
    let mut spec = layer_stack(n_layers, receivers);
    for (i, iface) in spec.interfaces.values_mut().enumerate() {
        let (x0, x1, y) = (iface.points[0][0], iface.points[1][0], iface.points[0][1]);
        iface.points = (0..=segments)
            .map(|j| {
                let x = x0 + (x1 - x0) * j as f64 / segments as f64;
                let phase = 3.0 * std::f64::consts::TAU * (x - x0) / (x1 - x0) + i as f64;
                [x, y + 0.3 * phase.sin()]
            })
            .collect();
    }
    spec.description = Some(format!(
        "{n_layers} layers y = -i + 0.3 sin(3 * 2 pi (x + W) / 2W + i), each digitised with \
         {segments} segments; source (0, 1); receivers on y = -{n_layers}.5"
    ));
    spec
}

/// The sea floor of [`sea_floor`]: `y = −2 + 0.1 sin(2π x / 5)` (km).
pub fn sea_floor_depth(x: f64) -> f64 {
    -2.0 + 0.1 * (2.0 * std::f64::consts::PI * x / 5.0).sin()
}

/// A digitised reflector with `segments` segments and one reflection path: the sea floor
/// `y =` [`sea_floor_depth`]`(x)` (a 2 km deep floor with 0.1 km undulations of 5 km
/// wavelength), sampled at `segments + 1` evenly spaced `x` over `[−10, 10]` km, under water of
/// speed 1.5 km/s. The source is at `(0, −0.01)`, the `receivers` receivers on `y = −0.01` with
/// `x` evenly spaced over `[0.1, 6]` km; one path, `bottom`, reflects off `floor` once.
///
/// The floor's radius of curvature (at least 6.3 km) exceeds the water depth, so every
/// receiver has exactly one reflection point: the cost of a ray measures the cost of finding
/// it on a polyline of `segments` segments (the tests of the solver's vertex handling and of
/// the `O(log M)` lookups). With few segments a reflection point may settle on a vertex
/// (status `vertex`).
///
/// ```
/// use eigenray::{Scene, Status, Tracer, Workspace};
/// let scene = Scene::from_spec(&eigenray::demo::sea_floor(10_000, 3)).unwrap();
/// assert_eq!(scene.interfaces()[0].polyline.num_segments(), 10_000);
/// let tracer = Tracer::new(&scene).unwrap();
/// let mut ws = Workspace::new();
/// assert_eq!(tracer.solve_indexed_from(0, 1, 0, None, &mut ws).status, Status::Converged);
/// ```
///
/// # Panics
/// If `segments` is 0.
pub fn sea_floor(segments: usize, receivers: usize) -> SceneSpec {
    assert!(segments > 0, "a reflector needs at least one segment");
    let mut spec = SceneSpec {
        description: Some(format!(
            "Sea floor y = -2 + 0.1 sin(2 pi x / 5) km digitised with {segments} segments over \
             x in [-10, 10]; water 1.5 km/s; source (0, -0.01); receivers on y = -0.01, x in \
             [0.1, 6]; one bottom reflection."
        )),
        ..SceneSpec::default()
    };
    spec.media.insert(
        "water".into(),
        MediumSpec {
            speed: Some(1.5),
            ..MediumSpec::default()
        },
    );
    spec.interfaces.insert(
        "floor".into(),
        InterfaceSpec {
            points: linspace(-10.0, 10.0, segments + 1)
                .into_iter()
                .map(|x| [x, sea_floor_depth(x)])
                .collect(),
            closed: false,
            reflection: None,
        },
    );
    spec.sources = vec![[0.0, -0.01]];
    spec.receivers = linspace(0.1, 6.0, receivers)
        .into_iter()
        .map(|x| [x, -0.01])
        .collect::<Vec<_>>()
        .into();
    spec.paths = vec![PathSpec {
        name: Some("bottom".into()),
        steps: vec![StepSpec::Reflect("floor".into())],
        media: Some(vec!["water".into(), "water".into()]),
    }];
    spec.solver = Some(SolverSpec {
        tolerance: Some(1e-12),
        max_iterations: Some(100),
        ..Default::default()
    });
    spec
}
