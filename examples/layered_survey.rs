//! A seismic refraction-and-reflection survey over layered ground: a shot at the surface,
//! geophones every 100 m along it, and two flat layer boundaries. The layers are open lines
//! across a `domain` box, so region lookup knows which layer is where; each path reflects off
//! one boundary (down through the layers above it, back up the same way).
//!
//! Run with `cargo run --release --example layered_survey`.

use eigenray::{Scene, Status, Tracer};

const SCENE: &str = r#"{
    "description": "Two layers over a half-space; speeds in m/s, lengths in m.",
    "media": {
        "sand":      { "speed": 1800, "at": [0, -50] },
        "clay":      { "speed": 2400, "at": [0, -200] },
        "limestone": { "speed": 4000, "at": [0, -600] }
    },
    "domain": [[-100, -1000], [1100, 0.5]],
    "interfaces": {
        "top of clay":      { "points": [[-100, -120], [1100, -120]] },
        "top of limestone": { "points": [[-100, -300], [1100, -300]] }
    },
    "sources":   [[0, 0]],
    "receivers": [[100, 0], [200, 0], [300, 0], [400, 0], [500, 0],
                  [600, 0], [700, 0], [800, 0], [900, 0], [1000, 0]],
    "paths": [
        { "name": "direct", "steps": [] },
        { "name": "clay reflection", "steps": [{ "reflect": "top of clay" }] },
        { "name": "limestone reflection", "steps": [
            { "refract": "top of clay" }, { "reflect": "top of limestone" },
            { "refract": "top of clay" } ] }
    ]
}"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::from_json(SCENE)?;
    let tracer = Tracer::new(&scene)?;
    let rays = tracer.trace_all();
    let paths = scene.paths().len();

    print!("offset (m)");
    for p in scene.paths() {
        print!(" {:>22}", p.name.as_deref().unwrap_or("?"));
    }
    println!("\n{:>10} {:>22} {:>22} {:>22}", "", "ms", "ms", "ms");
    for (k, receiver) in scene.receivers().iter().enumerate() {
        print!("{:>10}", receiver.x);
        // Rays are numbered source-major, then receiver, then path.
        for ray in &rays[k * paths..(k + 1) * paths] {
            match ray.status {
                Status::Converged => print!(" {:>22.3}", ray.time * 1e3),
                _ => print!(" {:>22}", ray.status.as_str()),
            }
        }
        println!();
    }
    // The media of the deep reflection's legs, found by region lookup.
    let deep = &rays[2];
    let media: Vec<&str> = deep
        .media
        .iter()
        .map(|&m| scene.media()[m].name.as_str())
        .collect();
    println!("\nlimestone reflection legs: {}", media.join(" → "));
    Ok(())
}
