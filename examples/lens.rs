//! A glass lens in air, built in code rather than read from JSON: its two faces are two
//! interfaces (digitised circular arcs that meet at the lens's rim), a point source on the
//! axis and receivers in a column behind the lens. Each ray refracts into the glass at the
//! front face and out at the back face; the path gives its legs' media, so the scene needs no
//! region lookup.
//!
//! The receivers stand beyond the focus (about 13.3 from the lens), where the picture is
//! inverted: a receiver below the axis is reached through the upper half of the lens. The
//! outer receivers would need a ray through the glass beyond the rim, so they have no path.
//!
//! Run with `cargo run --release --example lens`.

use eigenray::{InterfaceSpec, MediumSpec, PathSpec, Scene, StepSpec, Tracer};

/// The two faces of a biconvex lens: circular arcs of `radius` meeting at (0, ±half_height),
/// each of `n` segments, from the top down.
fn biconvex(radius: f64, half_height: f64, n: usize) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
    // Each arc's centre lies on the axis, at the distance that puts the arc through the rim.
    let c = (radius * radius - half_height * half_height).sqrt();
    let a = (half_height / radius).asin();
    let arc = |centre: f64, from: f64, to: f64| -> Vec<[f64; 2]> {
        (0..=n)
            .map(|i| {
                let t = from + (to - from) * i as f64 / n as f64;
                [centre + radius * t.cos(), radius * t.sin()]
            })
            .collect()
    };
    let pi = std::f64::consts::PI;
    // The front face bulges to the left (its centre on the right), the back face to the right.
    (arc(c, pi - a, pi + a), arc(-c, a, -a))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (front, back) = biconvex(5.0, 2.0, 24);
    let scene = Scene::builder()
        .medium("air", MediumSpec::index(1.0))
        .medium("glass", MediumSpec::index(1.5))
        .interface("front face", InterfaceSpec::open(front))
        .interface("back face", InterfaceSpec::open(back))
        .source([-8.0, 0.0])
        .receivers((0..5).map(|k| [20.0, -1.0 + 0.5 * k as f64]))
        .path(
            PathSpec::new([
                StepSpec::refract("front face"),
                StepSpec::refract("back face"),
            ])
            .named("through the lens")
            .media(["air", "glass", "air"]),
        )
        .build()?;
    let tracer = Tracer::new(&scene)?;

    // Optical path length: time with c = 1 (index × length).
    println!("receiver      y   status      time   enters at          leaves at");
    for ray in tracer.trace_all() {
        let y = scene.receivers()[ray.receiver].y;
        // (A ray without a time has no points.)
        let t = ray.time;
        match ray.points.as_slice() {
            [_, a, b, _] => println!(
                "{:>8} {y:>6.2}   {:<10} {t:>6.4}   ({:.4}, {:+.4})  ({:.4}, {:+.4})",
                ray.receiver,
                ray.status.as_str(),
                a.x,
                a.y,
                b.x,
                b.y
            ),
            _ => println!("{:>8} {y:>6.2}   {}", ray.receiver, ray.status),
        }
    }
    Ok(())
}
