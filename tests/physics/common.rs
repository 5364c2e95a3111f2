//! Shared helpers: plain-`f64` geometry, a seeded generator, scene building, reference solvers.

use eigenray::{Point, Ray, Scene, Tracer};
use serde_json::Value;

#[path = "../support/rng.rs"]
mod rng;
use rng::SplitMix64;

#[path = "../support/reference.rs"]
mod reference;
pub use reference::*;

/// The library's point as plain numbers.
pub fn pt(p: Point) -> P {
    [p.x, p.y]
}

/// The fraction along `a–b` of the foot of `p` on the line through them.
pub fn fraction(p: P, a: P, b: P) -> f64 {
    let d = sub(b, a);
    dot(sub(p, a), d) / dot(d, d)
}

/// Distance from `p` to the line through `a` and `b`.
pub fn dist_to_line(p: P, a: P, b: P) -> f64 {
    cross(sub(b, a), sub(p, a)).abs() / dist(a, b)
}

/// `p` rotated by `angle` about the origin, then moved by `offset`.
pub fn place(p: P, angle: f64, offset: P) -> P {
    let (s, c) = angle.sin_cos();
    [
        offset[0] + c * p[0] - s * p[1],
        offset[1] + s * p[0] + c * p[1],
    ]
}

/// A fixed-seed generator.
pub struct Rng(SplitMix64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(SplitMix64(seed))
    }
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.0.next_f64()
    }
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.uniform(lo.ln(), hi.ln()).exp()
    }
}

/// A validated scene from a JSON value (panics with the scene error).
pub fn scene(v: &Value) -> Scene {
    Scene::from_json(&v.to_string()).unwrap_or_else(|e| panic!("invalid test scene: {e}\n{v}"))
}

/// Every ray of a scene.
pub fn trace_all(scene: &Scene) -> Vec<Ray> {
    Tracer::new(scene).expect("tracer").trace_all()
}

/// Flat layers: the legs' vertical extents `h` and speeds `v`; the ray parameter `p`
/// (horizontal slowness, `sin θⱼ = p vⱼ`) with `Σ hⱼ tan θⱼ = x`, by bisection on
/// `[0, 1 / max v)`. Returns `p` and the horizontal extent of every leg.
pub fn ray_parameter(legs: &[(f64, f64)], x: f64) -> (f64, Vec<f64>) {
    assert!(x >= 0.0);
    let vmax = legs.iter().map(|l| l.1).fold(0.0, f64::max);
    let dx = |p: f64, (h, v): (f64, f64)| {
        let s = p * v;
        let c2 = 1.0 - s * s;
        if c2 <= 0.0 {
            f64::INFINITY
        } else {
            h * s / c2.sqrt()
        }
    };
    let total = |p: f64| legs.iter().map(|&l| dx(p, l)).sum::<f64>() - x;
    let p = bisect(0.0, 1.0 / vmax, total);
    (p, legs.iter().map(|&l| dx(p, l)).collect())
}
