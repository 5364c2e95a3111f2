//! Instructions of rays that do not ask for amplitudes (`Tracer::solve`, one receiver after
//! the other), the same source at every commit compared: `ray_cost CASE REPS`.
use std::hint::black_box;

use eigenray::{Scene, Tracer, Workspace, demo};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let spec = match args[0].as_str() {
        "one_refraction" => demo::air_water(10_000, 1),
        "layers10" => demo::layer_stack(10, 2000),
        other => panic!("no case {other}"),
    };
    let reps: usize = args[1].parse().unwrap();
    let tracer = Tracer::new(Scene::from_spec(&spec).unwrap()).unwrap();
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
