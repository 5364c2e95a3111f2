//! Every stationary path of one reflection off a digitised sea floor: time per ray of
//! `Tracer::stationary_paths` against the number of segments `M`.
//!
//! `cargo run --release --example stationary` prints, per `M`, the time per ray (one thread,
//! the hierarchy built before timing), the arrivals per ray and the tuples and solves the
//! search spent on each. Issue 18's target: at most 20 µs per ray at `M = 100,000`.

use std::time::Instant;

use eigenray::{Arrival, Scene, Status, Tracer, demo};

/// Receivers per scene.
const RECEIVERS: usize = 1000;

fn main() {
    let sizes: Vec<usize> = match std::env::args().nth(1) {
        Some(m) => vec![m.parse().expect("a number of segments")],
        None => vec![10, 100, 1_000, 10_000, 100_000, 1_000_000],
    };
    println!(
        "| M | µs per ray | arrivals per ray | converged | vertex | tuples per ray | solves per ray |"
    );
    println!("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for m in sizes {
        let scene = Scene::from_spec(&demo::sea_floor(m, RECEIVERS)).expect("the demo scene");
        let tracer = Tracer::new(&scene).expect("no regions");
        let source = scene.sources()[0];
        let mut out: Vec<Arrival> = Vec::new();
        // Builds the hierarchy (once per interface), outside the timing.
        tracer
            .stationary_paths(source, scene.receivers()[0], 0, &mut out)
            .expect("media given");
        let (mut arrivals, mut converged, mut vertex, mut tuples, mut solves) = (0, 0, 0, 0, 0);
        let mut rounds = 0;
        let start = Instant::now();
        while rounds == 0 || start.elapsed().as_secs_f64() < 0.5 {
            for &receiver in scene.receivers() {
                let search = tracer
                    .stationary_paths(source, receiver, 0, &mut out)
                    .expect("media given");
                assert!(search.complete);
                if rounds == 0 {
                    arrivals += out.len();
                    converged += out.iter().filter(|a| a.status == Status::Converged).count();
                    vertex += out.iter().filter(|a| a.status == Status::Vertex).count();
                    tuples += search.tuples;
                    solves += search.solves;
                }
            }
            rounds += 1;
        }
        let per_ray = start.elapsed().as_secs_f64() / (rounds * RECEIVERS) as f64;
        let n = RECEIVERS as f64;
        println!(
            "| {m} | {:.2} | {:.2} | {converged} | {vertex} | {:.1} | {:.1} |",
            per_ray * 1e6,
            arrivals as f64 / n,
            tuples as f64 / n,
            solves as f64 / n,
        );
    }
}
