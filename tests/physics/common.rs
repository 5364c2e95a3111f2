//! Shared helpers: plain-`f64` geometry, a seeded generator, scene building, reference solvers.

use eigenray::demo::SplitMix64;
use eigenray::{Point, Ray, Scene, Tracer};
use serde_json::Value;

/// A point or vector as plain numbers, so that references do not use the library's geometry.
pub type P = [f64; 2];

pub fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1]]
}
pub fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}
pub fn scale(a: P, k: f64) -> P {
    [a[0] * k, a[1] * k]
}
pub fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
pub fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
pub fn norm(a: P) -> f64 {
    a[0].hypot(a[1])
}
pub fn dist(a: P, b: P) -> f64 {
    norm(sub(a, b))
}
pub fn unit(a: P) -> P {
    scale(a, 1.0 / norm(a))
}
pub fn lerp(a: P, b: P, t: f64) -> P {
    add(a, scale(sub(b, a), t))
}
/// The library's point as plain numbers.
pub fn pt(p: Point) -> P {
    [p.x, p.y]
}

/// Mirror image of `p` across the line through `a` and `b`.
pub fn reflect(p: P, a: P, b: P) -> P {
    let d = sub(b, a);
    let t = dot(sub(p, a), d) / dot(d, d);
    let foot = add(a, scale(d, t));
    sub(scale(foot, 2.0), p)
}

/// Where the lines `p–q` and `a–b` meet: `(t, u)` with `p + t (q − p) = a + u (b − a)`.
pub fn intersect(p: P, q: P, a: P, b: P) -> (f64, f64) {
    let r = sub(q, p);
    let s = sub(b, a);
    let den = cross(r, s);
    let ap = sub(a, p);
    (cross(ap, s) / den, cross(ap, r) / den)
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

/// `|got − want| / |want|`.
pub fn rel_err(got: f64, want: f64) -> f64 {
    ((got - want) / want).abs()
}

/// Σ slowness × leg length over consecutive points.
pub fn path_time(points: &[P], slowness: &[f64]) -> f64 {
    assert_eq!(points.len(), slowness.len() + 1);
    points
        .windows(2)
        .zip(slowness)
        .map(|(w, s)| s * dist(w[0], w[1]))
        .sum()
}

/// Root of an increasing function on `[lo, hi]` (`f(lo) ≤ 0 ≤ f(hi)`) by bisection, to the
/// last representable number.
pub fn bisect(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    assert!(lo <= hi);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return if f(lo).abs() <= f(hi).abs() { lo } else { hi };
        }
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// Snell's law on a flat interface in its own coordinates: the source is at `(a, h1)` above
/// (slowness `n1`), the receiver at `(b, −h2)` below (slowness `n2`). Returns the crossing `x`
/// solving `n1 (x−a)/√((x−a)²+h1²) = n2 (b−x)/√((b−x)²+h2²)` and the travel time.
pub fn snell_reference(n1: f64, a: f64, h1: f64, n2: f64, b: f64, h2: f64) -> (f64, f64) {
    let f = |x: f64| n1 * (x - a) / (x - a).hypot(h1) - n2 * (b - x) / (b - x).hypot(h2);
    let x = bisect(a.min(b), a.max(b), f);
    (x, n1 * (x - a).hypot(h1) + n2 * (b - x).hypot(h2))
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
