//! Criterion benchmarks: single rays (through uniform layers and through layers with a speed
//! gradient), a 100,000-segment reflector, batches, a ray's gradient, and argmin's solvers.
//!
//! `cargo bench` runs everything but the argmin comparison; `cargo bench --features argmin`
//! adds it. Every benchmark shares one short configuration ([`config`]) so that the whole run
//! takes a few minutes. A "single ray" iteration solves the next receiver of the scene in turn
//! (one thread, one reused `Workspace`), so the figure is a mean over many different rays.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use eigenray::{BatchOptions, Gradient, Point, Scene, Tracer, Workspace, demo};

/// The shared configuration: short warm-up and measurement, few samples.
fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(20)
}

fn scene(spec: &eigenray::SceneSpec) -> Scene {
    Scene::from_spec(spec).expect("valid benchmark scene")
}

/// Benchmarks `Tracer::solve` on path 0, one receiver after the other.
fn bench_rays(c: &mut Criterion, group: &str, name: &str, scene: &Scene) {
    let tracer = Tracer::new(scene).expect("tracer");
    let source: Point = scene.sources()[0];
    let receivers = scene.receivers();
    let mut ws = Workspace::new();
    let mut next = 0;
    c.benchmark_group(group)
        .throughput(Throughput::Elements(1))
        .bench_function(name, |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                black_box(tracer.solve(source, receivers[next], 0, &mut ws))
            })
        });
}

/// `scene` with the solver's residual tolerance set to `tolerance`.
fn with_tolerance(mut scene: Scene, tolerance: f64) -> Scene {
    scene
        .set_solver(eigenray::SolverOptions {
            tolerance,
            ..scene.solver()
        })
        .expect("valid solver options");
    scene
}

/// One ray through 1, 8 and 100 interactions: at the demo scenes' residual tolerance 1e-12
/// (the solution to round-off), and at 1e-6, which already gives travel times exact to 1e-12
/// (the time is stationary: its error is of second order; `tests/physics/benchmarks.rs`
/// checks it against the 40-digit references of `seed500` and `layers10`); and through 8 and
/// 100 dipping layers, where Newton steps remain.
fn single_ray(c: &mut Criterion) {
    let scenes = [
        ("1_interaction", demo::air_water(500, 1)),
        ("8_interactions", demo::layer_stack(8, 500)),
        ("100_interactions", demo::layer_stack(100, 500)),
    ];
    for (name, spec) in &scenes {
        bench_rays(c, "single_ray", name, &scene(spec));
    }
    for (name, spec) in &scenes {
        bench_rays(
            c,
            "single_ray_time_to_1e-12",
            name,
            &with_tolerance(scene(spec), 1e-6),
        );
    }
    // Through flat layers the default start is the solution. Dipping layers are the general
    // case: the start is approximate and Newton steps remain.
    for (name, spec) in [
        ("8_interactions", demo::dipping_stack(8, 500)),
        ("100_interactions", demo::dipping_stack(100, 500)),
    ] {
        bench_rays(c, "single_ray_dipping", name, &scene(&spec));
    }
}

/// One ray through the ten layers of `fixtures/bench/layers10.json` as they are and with
/// every medium's speed given the gradient `[0, -0.02]` (every leg a circular arc): the
/// issue's target is at most twice the uniform layers' time (`benches/gradient_instructions.sh`
/// counts the instructions of the two).
fn curved(c: &mut Criterion) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench/layers10.json");
    let text = std::fs::read_to_string(path).expect("the benchmark scene");
    let mut spec = eigenray::SceneSpec::from_json(&text).expect("a valid scene");
    bench_rays(c, "curved_layers10", "uniform", &scene(&spec));
    for medium in spec.media.values_mut() {
        medium.gradient = Some([0.0, -0.02]);
    }
    bench_rays(c, "curved_layers10", "speed_gradient", &scene(&spec));
}

/// One reflection off a sea floor digitised with 100,000 segments.
fn reflector(c: &mut Criterion) {
    bench_rays(
        c,
        "reflector",
        "100k_segments",
        &scene(&demo::sea_floor(100_000, 500)),
    );
}

/// `trace_batch` over 100,000 receivers of the air-over-water scene on 1 and 2 threads, into a
/// new batch and into a reused one.
fn batch(c: &mut Criterion) {
    const N: usize = 100_000;
    let scene = scene(&demo::air_water(N, 1));
    let tracer = Tracer::new(&scene).expect("tracer");
    let mut group = c.benchmark_group("batch_100k");
    group
        .throughput(Throughput::Elements(N as u64))
        .sample_size(10);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool");
        let name = format!("{threads}_thread{}", if threads == 1 { "" } else { "s" });
        group.bench_function(&name, |b| {
            b.iter(|| {
                pool.install(|| {
                    black_box(
                        tracer
                            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
                            .unwrap(),
                    )
                })
            })
        });
        // Into one reused batch (a layout tool tracing every change again).
        let mut reused = eigenray::Batch::default();
        group.bench_function(format!("{name}_reused"), |b| {
            b.iter(|| {
                let run = eigenray::options::Run::new();
                pool.install(|| {
                    tracer.trace_batch_into(&BatchOptions::default(), &run, &mut reused)
                })
                .expect("allocated before");
                black_box(reused.len())
            })
        });
    }
    group.finish();
}

/// eigenray's Newton solver against argmin's Gauss-Newton and BFGS on the same paths, from the
/// same start (eigenray's initial guess with the paraxial refinement, `InitialGuess::Paraxial`),
/// to the same relative residual, 1e-12.
#[cfg(feature = "argmin")]
fn versus_argmin(c: &mut Criterion) {
    use eigenray::argmin_bridge::{solve_bfgs, solve_gauss_newton};
    use eigenray::{InitialGuess, SolverOptions, problem::PathProblem};

    const TOL: f64 = 1e-12;
    for (name, spec) in [
        ("1_interaction", demo::air_water(500, 1)),
        ("8_interactions", demo::layer_stack(8, 500)),
    ] {
        let mut scene = scene(&spec);
        scene
            .set_solver(SolverOptions {
                tolerance: TOL,
                max_iterations: 100,
                ..SolverOptions::default()
            })
            .expect("valid solver options");
        let source = scene.sources()[0];
        let receivers = scene.receivers().to_vec();
        // The paraxial start (the solver stopped after 0 iterations): the default start of
        // these flat layers is their solution, which would leave no solver anything to do.
        let mut start = scene.clone();
        start
            .set_solver(SolverOptions {
                tolerance: TOL,
                max_iterations: 0,
                ..SolverOptions::default()
            })
            .expect("valid solver options");
        let guesses: Vec<Vec<f64>> = {
            let tracer = Tracer::new(&start)
                .expect("tracer")
                .with_initial_guess(InitialGuess::Paraxial);
            let mut ws = Workspace::new();
            receivers
                .iter()
                .map(|&r| {
                    tracer.solve(source, r, 0, &mut ws);
                    ws.parameters().to_vec()
                })
                .collect()
        };
        let problems: Vec<PathProblem> = receivers
            .iter()
            .map(|&r| PathProblem::new(&scene, 0, source, r).expect("media given"))
            .collect();
        let tracer = Tracer::new(&scene)
            .expect("tracer")
            .with_initial_guess(InitialGuess::Paraxial);
        let mut group = c.benchmark_group(format!("versus_argmin/{name}"));
        group.throughput(Throughput::Elements(1));
        let mut ws = Workspace::new();
        let mut next = 0;
        group.bench_function("eigenray_newton", |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                black_box(tracer.solve(source, receivers[next], 0, &mut ws))
            })
        });
        group.bench_function("argmin_gauss_newton", |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                black_box(solve_gauss_newton(&problems[next], &guesses[next], 100, TOL).ok())
            })
        });
        group.bench_function("argmin_bfgs", |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                black_box(solve_bfgs(&problems[next], &guesses[next], 200, TOL).ok())
            })
        });
        group.finish();
    }
}

/// The cost of a ray's gradient: `Tracer::solve` alone, followed by `Gradient::solved_into`
/// (reused, allocation-free), and `Tracer::solve_with_gradient` (one call), one receiver after
/// the other, for one
/// refraction (`demo::air_water`) and eight (`demo::layer_stack(8, …)`, `demo::dipping_stack`).
fn gradient(c: &mut Criterion) {
    let cases = [
        ("one_refraction", scene(&demo::air_water(10_000, 1))),
        ("stack8", scene(&demo::layer_stack(8, 2000))),
        ("dipping8", scene(&demo::dipping_stack(8, 2000))),
    ];
    for (name, scene) in &cases {
        let tracer = Tracer::new(scene).expect("tracer");
        let source = scene.sources()[0];
        let receivers = scene.receivers();
        let mut group = c.benchmark_group(format!("gradient/{name}"));
        group.throughput(Throughput::Elements(1));
        let mut ws = Workspace::new();
        let mut next = 0;
        group.bench_function("ray", |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                black_box(tracer.solve(source, receivers[next], 0, &mut ws))
            })
        });
        let mut g = Gradient::default();
        group.bench_function("ray_and_gradient", |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                let record = tracer.solve(source, receivers[next], 0, &mut ws);
                if record.status.has_time() {
                    black_box(g.solved_into(scene, 0, &ws).is_ok());
                }
                black_box(record)
            })
        });
        group.bench_function("ray_with_gradient", |b| {
            b.iter(|| {
                next = (next + 1) % receivers.len();
                let record =
                    tracer.solve_with_gradient(source, receivers[next], 0, &mut ws, &mut g);
                black_box(g.source);
                black_box(record.is_ok())
            })
        });
        group.finish();
    }
}

#[cfg(not(feature = "argmin"))]
fn versus_argmin(_c: &mut Criterion) {
    eprintln!("versus_argmin: skipped (run `cargo bench --features argmin` to include it)");
}

criterion_group! {
    name = benches;
    config = config();
    targets = single_ray, curved, reflector, batch, gradient, versus_argmin
}
criterion_main!(benches);
