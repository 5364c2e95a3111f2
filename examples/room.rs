//! A room's early reflections: the direct sound and the four first-order wall reflections from
//! one loudspeaker to three listening positions, sorted by arrival time.
//!
//! Run with `cargo run --release --example room`. The scene is `examples/scenes/room.json`;
//! `cargo run --release -- solve examples/scenes/room.json --svg room.svg --colour-by path`
//! draws it.

use eigenray::{Scene, Tracer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scene = Scene::from_json(include_str!("scenes/room.json"))?;
    let tracer = Tracer::new(&scene)?;
    let rays = tracer.trace_all();

    for (k, receiver) in scene.receivers().iter().enumerate() {
        println!("receiver {k} at ({}, {}):", receiver.x, receiver.y);
        // This receiver's rays that exist, earliest first.
        let mut arrivals: Vec<_> = rays
            .iter()
            .filter(|r| r.receiver == k)
            .filter(|r| r.status.has_time())
            .map(|r| (r.time, r))
            .collect();
        arrivals.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (time, ray) in arrivals {
            let name = scene.paths()[ray.path].name.as_deref().unwrap_or("?");
            // The points run source, reflection point(s), receiver.
            let via = match ray.points.get(1..ray.points.len() - 1) {
                Some([p]) => format!(" off ({:.3}, {:.3})", p.x, p.y),
                _ => String::new(),
            };
            println!("  {:>7.3} ms  {name:<11} {}{via}", time * 1e3, ray.status);
        }
    }
    Ok(())
}
