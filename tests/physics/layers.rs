//! Flat horizontal layer stacks against the ray-parameter solution.

use eigenray::Status;
use serde_json::{Value, json};

use crate::common::*;

const TOL: f64 = 1e-12;

/// A random stack: `n` interfaces, the thickness of every leg's layer (the first from the
/// source down to interface 1, the last from interface `n` down to the receivers) and `n + 1`
/// speeds.
struct Stack {
    /// Leg heights `h₀ … hₙ`.
    h: Vec<f64>,
    /// Layer speeds `v₀ … vₙ`.
    v: Vec<f64>,
}

impl Stack {
    fn random(n: usize, seed: u64) -> Stack {
        let mut rng = Rng::new(seed);
        let h = (0..=n).map(|_| rng.uniform(0.2, 1.5)).collect();
        let v = (0..=n).map(|_| rng.uniform(0.5, 3.0)).collect();
        Stack { h, v }
    }
    fn n(&self) -> usize {
        self.h.len() - 1
    }
    /// Height of interface `j` (1-based): interface 1 at y = 0, the others below.
    fn y(&self, j: usize) -> f64 {
        -self.h[1..j].iter().sum::<f64>()
    }
    /// The scene: interfaces `i1 … in`, media `L0 … Ln`, one path `steps` with `media`.
    fn scene(&self, source: P, receivers: &[P], steps: Vec<Value>, media: Vec<String>) -> Value {
        let n = self.n();
        let interfaces: serde_json::Map<String, Value> = (1..=n)
            .map(|j| {
                (
                    format!("i{j}"),
                    json!({ "points": [[-200.0, self.y(j)], [200.0, self.y(j)]] }),
                )
            })
            .collect();
        let media_spec: serde_json::Map<String, Value> = self
            .v
            .iter()
            .enumerate()
            .map(|(j, v)| (format!("L{j}"), json!({ "speed": v })))
            .collect();
        json!({
            "media": media_spec, "interfaces": interfaces,
            "sources": [source], "receivers": receivers,
            "paths": [{ "steps": steps, "media": media }]
        })
    }
}

/// Checks every ray against the ray-parameter reference for legs `(height, speed)` whose
/// interaction points lie at heights `ys`; returns the largest relative time error and the
/// largest horizontal position error.
fn check(v: &Value, legs: &[(f64, f64)], ys: &[f64]) -> (f64, f64) {
    let sc = scene(v);
    let rays = trace_all(&sc);
    let (mut max_t, mut max_x) = (0.0f64, 0.0f64);
    for ray in &rays {
        let s = pt(sc.sources()[ray.source]);
        let r = pt(sc.receivers()[ray.receiver]);
        let offset = r[0] - s[0];
        let (p, dx) = ray_parameter(legs, offset.abs());
        let mut pts = vec![s];
        let mut x = s[0];
        for (d, &y) in dx.iter().zip(ys) {
            x += d * offset.signum();
            pts.push([x, y]);
        }
        pts.push(r);
        let slowness: Vec<f64> = legs.iter().map(|l| 1.0 / l.1).collect();
        // Time along the reference points between the true end points: stationary, so the
        // reference's own rounding enters only to second order.
        let t_ref = path_time(&pts, &slowness);
        // The closed form Σ h / (v cos θ), as a check on the reference itself.
        let t_closed: f64 = legs
            .iter()
            .map(|&(h, v)| h / (v * (1.0 - (p * v).powi(2)).sqrt()))
            .sum();
        let case = format!("source {s:?}, receiver {r:?}, p = {p}");
        assert!(
            rel_err(t_closed, t_ref) <= 1e-13,
            "{case}: reference {t_ref} vs closed form {t_closed}"
        );

        assert_eq!(ray.status, Status::Converged, "{case}: {ray:?}");
        let time = ray.time;
        let err = rel_err(time, t_ref);
        assert!(
            err <= TOL,
            "{case}: time {time}, reference {t_ref}, relative error {err:e}"
        );
        assert_eq!(ray.points.len(), pts.len(), "{case}");
        for (i, (got, want)) in ray.points.iter().zip(&pts).enumerate() {
            let ex = (got.x - want[0]).abs();
            assert!(
                ex <= 1e-9,
                "{case}: point {i} at x = {}, reference {}",
                got.x,
                want[0]
            );
            assert!(
                (got.y - want[1]).abs() <= 1e-12,
                "{case}: point {i} at y = {}, interface at {}",
                got.y,
                want[1]
            );
            max_x = max_x.max(ex);
        }
        max_t = max_t.max(err);
    }
    (max_t, max_x)
}

fn down_through(n: usize, seed: u64) -> (f64, f64) {
    let st = Stack::random(n, seed);
    let source = [0.0, st.h[0]];
    let depth = st.y(n) - st.h[n];
    let total: f64 = st.h.iter().sum();
    let receivers: Vec<P> = [-2.5, -0.7, 0.0, 1e-3, 0.3, 1.0, 1.8, 3.0]
        .iter()
        .map(|f| [f * total, depth])
        .collect();
    let steps = (1..=n)
        .map(|j| json!({ "refract": format!("i{j}") }))
        .collect();
    let media = (0..=n).map(|j| format!("L{j}")).collect();
    let legs: Vec<(f64, f64)> = st.h.iter().copied().zip(st.v.iter().copied()).collect();
    let ys: Vec<f64> = (1..=n).map(|j| st.y(j)).collect();
    check(&st.scene(source, &receivers, steps, media), &legs, &ys)
}

#[test]
fn five_layers_down() {
    let (t, x) = down_through(5, 0x1A7E_0005);
    println!("layers 5 down: max relative time error {t:.2e}, max |Δx| {x:.2e}");
}

#[test]
fn ten_layers_down() {
    let (t, x) = down_through(10, 0x1A7E_0010);
    println!("layers 10 down: max relative time error {t:.2e}, max |Δx| {x:.2e}");
}

/// Down through interfaces 1 … n−1, reflected off interface n, back up to receivers above
/// interface 1 (some at the source's height: the symmetric case).
fn down_and_up(n: usize, seed: u64) -> (f64, f64) {
    let st = Stack::random(n, seed);
    let source = [0.0, st.h[0]];
    let mut receivers = Vec::new();
    for f in [0.0, 0.4, 1.5, -2.0, 4.0] {
        receivers.push([f * 2.0, st.h[0]]);
    }
    let r_height = 0.37;
    for f in [0.5, -3.0] {
        receivers.push([f, r_height]);
    }
    let mut steps: Vec<Value> = (1..n)
        .map(|j| json!({ "refract": format!("i{j}") }))
        .collect();
    steps.push(json!({ "reflect": format!("i{n}") }));
    steps.extend((1..n).rev().map(|j| json!({ "refract": format!("i{j}") })));
    let mut media: Vec<String> = (0..n).map(|j| format!("L{j}")).collect();
    media.extend((0..n).rev().map(|j| format!("L{j}")));
    let mut ys: Vec<f64> = (1..=n).map(|j| st.y(j)).collect();
    ys.extend((1..n).rev().map(|j| st.y(j)));
    let v = st.scene(source, &receivers, steps, media);
    let mut max = (0.0f64, 0.0f64);
    // One scene per receiver height: the last leg's height differs.
    for (rs, h_last) in [(&receivers[..5], st.h[0]), (&receivers[5..], r_height)] {
        let mut v = v.clone();
        v["receivers"] = json!(rs);
        let mut legs: Vec<(f64, f64)> = (0..n).map(|j| (st.h[j], st.v[j])).collect();
        legs.extend((1..n).rev().map(|j| (st.h[j], st.v[j])));
        legs.push((h_last, st.v[0]));
        let (t, x) = check(&v, &legs, &ys);
        max = (max.0.max(t), max.1.max(x));
    }
    max
}

#[test]
fn down_reflect_up() {
    let (t4, x4) = down_and_up(4, 0xD0_0004);
    let (t6, x6) = down_and_up(6, 0xD0_0006);
    println!(
        "layers down-reflect-up: max relative time error {:.2e}, max |Δx| {:.2e}",
        t4.max(t6),
        x4.max(x6)
    );
}
