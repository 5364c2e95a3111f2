//! Snell's law on one flat interface at random orientations, against a 1-D bisection.

use eigenray::Status;
use serde_json::json;

use crate::common::*;

/// Relative tolerance of every accuracy check here.
const TOL: f64 = 1e-12;

/// One refraction through the interface `p0–p1`: the medium above given as an index or a
/// speed, leg slownesses `w1`, `w2`.
fn refraction(p0: P, p1: P, s: P, r: P, w1: f64, w2: f64, as_speed: bool) -> eigenray::Scene {
    let medium = |w: f64| {
        if as_speed {
            json!({ "speed": 1.0 / w })
        } else {
            json!({ "index": w })
        }
    };
    scene(&json!({
        "media": { "one": medium(w1), "two": medium(w2) },
        "interfaces": { "flat": { "points": [p0, p1] } },
        "sources": [s], "receivers": [r],
        "paths": [{ "steps": [{ "refract": "flat" }], "media": ["one", "two"] }]
    }))
}

/// Errors of one solved refraction against the bisection reference:
/// `(snell residual, time vs its points, time vs reference, crossing position)`.
fn check_refraction(p0: P, p1: P, s: P, r: P, w1: f64, w2: f64, as_speed: bool) -> [f64; 4] {
    let sc = refraction(p0, p1, s, r, w1, w2, as_speed);
    // The slownesses the scene means: an index, or one over the speed written.
    let slowness = |w: f64| if as_speed { 1.0 / (1.0 / w) } else { w };
    let (n1, n2) = (slowness(w1), slowness(w2));
    let ray = &trace_all(&sc)[0];
    let case =
        format!("interface {p0:?}–{p1:?}, source {s:?}, receiver {r:?}, slowness {n1} / {n2}");
    assert_eq!(ray.status, Status::Converged, "{case}: {ray:?}");
    let pts: Vec<P> = ray.points.iter().map(|&p| pt(p)).collect();
    assert_eq!(pts.len(), 3, "{case}");
    // (Bit-exact end points are `end_points_are_the_given_ones`' business.)
    assert!(
        dist(pts[0], s) + dist(pts[2], r) <= 1e-14 * (norm(s) + norm(r)),
        "{case}: end points {pts:?}"
    );
    let x = pts[1];
    let t = unit(sub(p1, p0));
    let scale_len = dist(p0, p1);
    assert!(
        dist_to_line(x, p0, p1) <= TOL * scale_len,
        "{case}: {x:?} off the interface"
    );

    // Snell: n₁ sin θ₁ = n₂ sin θ₂, the sines being the tangential components of the legs.
    let sin1 = dot(unit(sub(x, s)), t);
    let sin2 = dot(unit(sub(r, x)), t);
    // Relative as the solver's tolerance is (scene format: `tolerance`, relative on the
    // stationarity residual |r| / (w₁ + w₂)).
    let snell = (n1 * sin1 - n2 * sin2).abs() / (n1 + n2);
    assert!(
        snell <= TOL,
        "{case}: n1 sin1 = {}, n2 sin2 = {}",
        n1 * sin1,
        n2 * sin2
    );

    let time = ray.time;
    let own = rel_err(time, path_time(&pts, &[n1, n2]));
    assert!(own <= TOL, "{case}: time {time} vs its points: {own:e}");

    // Independent reference in the interface's coordinates.
    let (a, b) = (dot(sub(s, p0), t), dot(sub(r, p0), t));
    let (h1, h2) = (cross(t, sub(s, p0)).abs(), cross(t, sub(r, p0)).abs());
    let (xr, tr) = snell_reference(n1, a, h1, n2, b, h2);
    let err = rel_err(time, tr);
    assert!(
        err <= TOL,
        "{case}: time {time}, reference {tr}, relative error {err:e}"
    );
    let pos = (dot(sub(x, p0), t) - xr).abs();
    assert!(
        pos <= 1e-9,
        "{case}: crossing at {} along the interface, reference {xr}",
        dot(sub(x, p0), t)
    );
    [snell, own, err, pos]
}

#[test]
fn classic_air_water() {
    let (s, r) = ([0.0, 1.0], [1.0, -1.0]);
    let (_, tr) = snell_reference(1.0, 0.0, 1.0, 1.333, 1.0, 1.0);
    assert!(
        rel_err(tr, 2.601764023084769) <= 1e-15,
        "bisection reference {tr}"
    );
    let e = check_refraction([-1.0, 0.0], [2.0, 0.0], s, r, 1.0, 1.333, false);
    let sc = refraction([-1.0, 0.0], [2.0, 0.0], s, r, 1.0, 1.333, false);
    let time = trace_all(&sc)[0].time;
    assert!(rel_err(time, 2.601764023084769) <= TOL, "time {time}");
    println!("snell classic: errors (snell, own time, reference time, position) = {e:?}");
}

#[test]
fn random_orientations_and_contrasts() {
    let mut rng = Rng::new(0x5EED_5E11);
    let mut max = [0.0f64; 4];
    let n = 300;
    for case in 0..n {
        let angle = rng.uniform(0.0, std::f64::consts::TAU);
        let offset = [rng.uniform(-10.0, 10.0), rng.uniform(-10.0, 10.0)];
        let n1 = rng.log_uniform(0.2, 5.0);
        let n2 = n1 * rng.log_uniform(0.1, 10.0);
        // Interface coordinates: the interface is the x axis, long enough for any crossing.
        let a = rng.uniform(-5.0, 5.0);
        let b = a + rng.uniform(-2.0, 2.0);
        let (h1, h2) = (rng.uniform(0.5, 3.0), rng.uniform(0.5, 3.0));
        let p0 = place([-30.0, 0.0], angle, offset);
        let p1 = place([30.0, 0.0], angle, offset);
        let s = place([a, h1], angle, offset);
        let r = place([b, -h2], angle, offset);
        let e = check_refraction(p0, p1, s, r, n1, n2, case % 2 == 1);
        for (m, v) in max.iter_mut().zip(e) {
            *m = m.max(v);
        }
    }
    println!(
        "snell random ({n} cases): max snell residual {:.2e}, time vs points {:.2e}, time vs bisection {:.2e}, crossing {:.2e}",
        max[0], max[1], max[2], max[3]
    );
}

#[test]
fn end_points_are_the_given_ones() {
    // A ray reports its source and receiver as given, bit for bit, however far from the origin.
    let mut rng = Rng::new(0xE2D5);
    let mut wrong = Vec::new();
    for _ in 0..100 {
        let angle = rng.uniform(0.0, std::f64::consts::TAU);
        let offset = [rng.uniform(-1e3, 1e3), rng.uniform(-1e3, 1e3)];
        let p0 = place([-30.0, 0.0], angle, offset);
        let p1 = place([30.0, 0.0], angle, offset);
        let s = place(
            [rng.uniform(-3.0, 3.0), rng.uniform(0.5, 3.0)],
            angle,
            offset,
        );
        let r = place(
            [rng.uniform(-3.0, 3.0), -rng.uniform(0.5, 3.0)],
            angle,
            offset,
        );
        let ray = &trace_all(&refraction(p0, p1, s, r, 1.0, 1.5, false))[0];
        assert_eq!(ray.status, eigenray::Status::Converged, "{ray:?}");
        let (gs, gr) = (pt(ray.points[0]), pt(*ray.points.last().unwrap()));
        if (gs, gr) != (s, r) {
            wrong.push(format!("given {s:?} → {r:?}, reported {gs:?} → {gr:?}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "{} of 100 rays misreport an end point, e.g. {}",
        wrong.len(),
        wrong[0]
    );
}
