//! Leg media from region lookup: layers cut by open polylines in a domain box, and a lens.

use eigenray::{Ray, Reason, Status};
use serde_json::json;

use crate::common::*;

const TOL: f64 = 1e-12;

/// Three layers (`upper` above y = 1, `middle` down to y = −2, `lower` below) and a
/// rectangular `glass` lens `[−1, 1] × [−1, 0]` inside the middle layer.
fn layered_scene() -> eigenray::Scene {
    scene(&json!({
        "media": {
            "upper": { "speed": 1.0, "at": [0.0, 3.0] },
            "middle": { "speed": 0.6, "at": [-4.0, -0.5] },
            "lower": { "speed": 1.5, "at": [0.0, -4.0] },
            "glass": { "speed": 0.4, "at": [0.0, -0.5] }
        },
        "domain": [[-5.0, -5.0], [5.0, 5.0]],
        "interfaces": {
            "top": { "points": [[-5.0, 1.0], [5.0, 1.0]] },
            "bottom": { "points": [[-5.0, -2.0], [5.0, -2.0]] },
            "lens": { "points": [[-1.0, -1.0], [1.0, -1.0], [1.0, 0.0], [-1.0, 0.0]], "closed": true }
        },
        "sources": [[0.0, 3.0], [0.0, 0.5]],
        "receivers": [[2.5, -0.5], [0.4, -1.5], [1.0, 4.0], [3.0, -3.5], [1.5, -3.5]],
        "paths": [
            { "name": "down", "steps": [{ "refract": "top" }] },
            { "name": "lens", "steps": [{ "refract": "lens" }, { "refract": "lens" }] },
            { "name": "explicit", "steps": [{ "refract": "top" }], "media": ["upper", "middle"] },
            { "name": "direct", "steps": [] },
            { "name": "down2", "steps": [{ "refract": "top" }, { "refract": "bottom" }] }
        ]
    }))
}

/// The ray-parameter reference for flat legs `(height, speed)` from `s` to `r` with the
/// interactions at heights `ys`: time and points.
fn flat_reference(s: P, r: P, legs: &[(f64, f64)], ys: &[f64]) -> (f64, Vec<P>) {
    let offset = r[0] - s[0];
    let (_, dx) = ray_parameter(legs, offset.abs());
    let mut pts = vec![s];
    let mut x = s[0];
    for (d, &y) in dx.iter().zip(ys) {
        x += d * offset.signum();
        pts.push([x, y]);
    }
    pts.push(r);
    let slowness: Vec<f64> = legs.iter().map(|l| 1.0 / l.1).collect();
    (path_time(&pts, &slowness), pts)
}

fn check_ray(
    ray: &Ray,
    status: Status,
    want_time: f64,
    want_pts: &[P],
    media: &[usize],
    case: &str,
) -> f64 {
    assert_eq!(ray.status, status, "{case}: {ray:?}");
    let time = ray.time;
    let err = rel_err(time, want_time);
    assert!(
        err <= TOL,
        "{case}: time {time}, reference {want_time}, relative error {err:e}"
    );
    assert_eq!(ray.points.len(), want_pts.len(), "{case}: {ray:?}");
    for (got, want) in ray.points.iter().zip(want_pts) {
        assert!(
            dist(pt(*got), *want) <= 1e-9,
            "{case}: point {got:?}, reference {want:?}"
        );
    }
    assert_eq!(ray.media, media, "{case}: leg media");
    err
}

#[test]
fn media_from_regions() {
    let sc = layered_scene();
    let rays = trace_all(&sc);
    let ray = |s: usize, r: usize, p: usize| &rays[sc.ray_index(s, r, p)];
    let m = |name: &str| sc.medium_index(name).unwrap();
    let (upper, middle, lower, glass) = (m("upper"), m("middle"), m("lower"), m("glass"));
    let (w_up, w_mid) = (1.0, 1.0 / 0.6);
    let pts = |i: usize, j: usize| (pt(sc.sources()[i]), pt(sc.receivers()[j]));
    let mut max = 0.0f64;

    // Down through `top`: upper → middle, by Snell bisection.
    let (s, r) = pts(0, 0);
    let (x, want) = snell_reference(w_up, s[0], s[1] - 1.0, w_mid, r[0], 1.0 - r[1]);
    let reference = [s, [x, 1.0], r];
    max = max.max(check_ray(
        ray(0, 0, 0),
        Status::Converged,
        want,
        &reference,
        &[upper, middle],
        "down",
    ));
    // The same path with its media written out agrees.
    max = max.max(check_ray(
        ray(0, 0, 2),
        Status::Converged,
        want,
        &reference,
        &[upper, middle],
        "explicit",
    ));

    // Into the lens through its top edge and out through its bottom one.
    let (s, r) = pts(1, 1);
    let legs = [(s[1], 0.6), (1.0, 0.4), (-1.0 - r[1], 0.6)];
    let (want, reference) = flat_reference(s, r, &legs, &[0.0, -1.0]);
    assert!(
        reference[1..3].iter().all(|p| p[0].abs() < 1.0),
        "reference leaves the lens edges: {reference:?}"
    );
    max = max.max(check_ray(
        ray(1, 1, 1),
        Status::Converged,
        want,
        &reference,
        &[middle, glass, middle],
        "lens",
    ));

    // Through both layer interfaces, passing beside the lens (x > 1 at y = 0).
    let (s, r) = pts(0, 3);
    let legs = [(s[1] - 1.0, 1.0), (3.0, 0.6), (-2.0 - r[1], 1.5)];
    let (want, reference) = flat_reference(s, r, &legs, &[1.0, -2.0]);
    let (p, q) = (reference[1], reference[2]);
    assert!(
        lerp(p, q, 1.0 / 3.0)[0] > 1.0,
        "reference crosses the lens: {reference:?}"
    );
    max = max.max(check_ray(
        ray(0, 3, 4),
        Status::Converged,
        want,
        &reference,
        &[upper, middle, lower],
        "down2",
    ));

    // The same through the lens: the stationary path with the layer media, obstructed.
    let (s, r) = pts(0, 4);
    let legs = [(s[1] - 1.0, 1.0), (3.0, 0.6), (-2.0 - r[1], 1.5)];
    let (want, reference) = flat_reference(s, r, &legs, &[1.0, -2.0]);
    assert!(
        lerp(reference[1], reference[2], 1.0 / 3.0)[0].abs() < 1.0,
        "reference misses the lens"
    );
    let got = ray(0, 4, 4);
    max = max.max(check_ray(
        got,
        Status::Obstructed,
        want,
        &reference,
        &[upper, middle, lower],
        "down2 blocked",
    ));
    let lens = sc.interface_index("lens").unwrap();
    assert_eq!(
        got.reason,
        Some(Reason::Crosses {
            leg: 1,
            interface: lens
        }),
        "{got:?}"
    );

    // Direct rays: within one region converged, into another obstructed.
    let (s, r) = pts(0, 2);
    let want = w_up * dist(s, r);
    max = max.max(check_ray(
        ray(0, 2, 3),
        Status::Converged,
        want,
        &[s, r],
        &[upper],
        "direct upper",
    ));
    let (s, r) = pts(1, 0);
    assert!(
        s[1] + (r[1] - s[1]) * (1.0 - s[0]) / (r[0] - s[0]) > 0.0,
        "direct line clips the lens"
    );
    let want = w_mid * dist(s, r);
    max = max.max(check_ray(
        ray(1, 0, 3),
        Status::Converged,
        want,
        &[s, r],
        &[middle],
        "direct middle",
    ));
    for (i, j, what) in [
        (0, 0, "across top"),
        (1, 1, "through the lens"),
        (0, 3, "across both"),
    ] {
        let got = ray(i, j, 3);
        let (s, r) = pts(i, j);
        assert_eq!(got.status, Status::Obstructed, "direct {what}: {got:?}");
        let time = got.time;
        let w0 = if i == 0 { w_up } else { w_mid };
        assert!(
            rel_err(time, w0 * dist(s, r)) <= TOL,
            "direct {what}: time {time}"
        );
        assert_eq!(
            got.media,
            [if i == 0 { upper } else { middle }],
            "direct {what}: {got:?}"
        );
    }
    println!("regions: max relative time error {max:.2e}");
}
