//! Reference helpers shared by `tests/physics` and `tests/stability` (and
//! `examples/stability.rs`, through `#[path]`): plain-`f64` geometry, so that the references
//! do not use the library's geometry, and the 1-D reference solvers built on it.

/// A point or vector as plain numbers.
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
