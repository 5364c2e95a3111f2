//! Instructions of rays that do not ask for amplitudes (`Tracer::solve`, one receiver after
//! the other), the same source at every commit compared: `ray_cost CASE REPS`.
//!
//! The cases: `one_refraction` and `layers10`, and the scenes of `benches/eigenray.rs`'s
//! single rays (`1_interaction`, `8_interactions`, `100_interactions`, the same at tolerance
//! 1e-6 with the suffix `_tol6`, `dipping8`, `dipping100`) and its digitised reflector
//! (`reflector100k`).
use std::hint::black_box;

use eigenray::{Scene, SceneSpec, Tracer, Workspace, demo};

/// The scene of a case and its solver tolerance (`None`: the scene's own).
fn case(name: &str) -> (SceneSpec, Option<f64>) {
    let (base, tolerance) = match name.strip_suffix("_tol6") {
        Some(base) => (base, Some(1e-6)),
        None => (name, None),
    };
    let spec = match base {
        "one_refraction" => demo::air_water(10_000, 1),
        "layers10" => demo::layer_stack(10, 2000),
        "1_interaction" => demo::air_water(500, 1),
        "8_interactions" => demo::layer_stack(8, 500),
        "100_interactions" => demo::layer_stack(100, 500),
        "dipping8" => demo::dipping_stack(8, 500),
        "dipping100" => demo::dipping_stack(100, 500),
        "reflector100k" => demo::sea_floor(100_000, 500),
        other => panic!("no case {other}"),
    };
    (spec, tolerance)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (spec, tolerance) = case(&args[0]);
    let reps: usize = args[1].parse().unwrap();
    let mut scene = Scene::from_spec(&spec).unwrap();
    if let Some(tolerance) = tolerance {
        let solver = eigenray::SolverOptions {
            tolerance,
            ..scene.solver()
        };
        scene.set_solver(solver).unwrap();
    }
    let tracer = Tracer::new(scene).unwrap();
    let scene = tracer.scene();
    let source = scene.sources()[0];
    let mut ws = Workspace::new();
    let start = std::time::Instant::now();
    for _ in 0..reps {
        for &receiver in scene.receivers() {
            black_box(tracer.solve(black_box(source), black_box(receiver), 0, &mut ws));
        }
    }
    let n = reps * scene.receivers().len();
    println!("{:.2}", start.elapsed().as_secs_f64() * 1e9 / n as f64);
    eprintln!("rays per repetition: {}", scene.receivers().len());
}
