//! Flat mirrors against the image method: one, two and three reflections, and a finite end.
//! The tracer starts from the image method there too, so no Newton step is left.

use eigenray::{Reason, Status};
use serde_json::{Value, json};

use crate::common::*;

const TOL: f64 = 1e-12;

/// The image-method path from `s` to `r` off `mirrors` in order: the unfolded length, the
/// reflection points, and whether the path is valid (every point strictly inside its mirror
/// segment and between its neighbours on the unfolded line).
fn image_path(s: P, r: P, mirrors: &[(P, P)]) -> (f64, Vec<P>, bool) {
    let k = mirrors.len();
    // images[i]: the receiver reflected across mirrors k−1, …, i (the last one first).
    let mut images = vec![r; k + 1];
    for i in (0..k).rev() {
        images[i] = reflect(images[i + 1], mirrors[i].0, mirrors[i].1);
    }
    let mut points = Vec::with_capacity(k);
    let mut valid = true;
    let mut prev = s;
    for (i, &(a, b)) in mirrors.iter().enumerate() {
        let (t, u) = intersect(prev, images[i], a, b);
        valid &= t > 0.0 && t < 1.0 && u > 1e-9 && u < 1.0 - 1e-9;
        prev = lerp(a, b, u);
        points.push(prev);
    }
    (dist(s, images[0]), points, valid)
}

/// Solves every ray of `scene` (one medium of slowness `w`) and checks each against the image
/// method on `mirrors[path]`; returns the largest relative time error and the number of rays
/// checked (those whose image path is valid).
fn check_against_images(v: &Value, w: f64, mirrors: &[Vec<(P, P)>]) -> (f64, usize) {
    let sc = scene(v);
    let rays = trace_all(&sc);
    let (mut max, mut checked) = (0.0f64, 0);
    for ray in &rays {
        let s = pt(sc.sources()[ray.source]);
        let r = pt(sc.receivers()[ray.receiver]);
        let ms = &mirrors[ray.path];
        let (len, pts, valid) = image_path(s, r, ms);
        if !valid {
            continue;
        }
        checked += 1;
        let case = format!("source {s:?}, receiver {r:?}, mirrors {ms:?}");
        assert_eq!(ray.status, Status::Converged, "{case}: {ray:?}");
        // The start off one-segment mirrors is the image method's: no Newton step is left.
        assert_eq!(ray.iterations, 0, "{case}: {ray:?}");
        let time = ray.time;
        let err = rel_err(time, w * len);
        assert!(
            err <= TOL,
            "{case}: time {time}, image method {}, relative error {err:e}",
            w * len
        );
        assert_eq!(ray.points.len(), ms.len() + 2, "{case}");
        for (i, (&(a, b), q)) in ms.iter().zip(&pts).enumerate() {
            let got = pt(ray.points[i + 1]);
            assert!(
                dist_to_line(got, a, b) <= TOL * dist(a, b),
                "{case}: point {i} {got:?} off its mirror"
            );
            let u = fraction(got, a, b);
            assert!(
                u > 0.0 && u < 1.0,
                "{case}: point {i} {got:?} outside its mirror segment"
            );
            assert!(
                dist(got, *q) <= 1e-9,
                "{case}: point {i} {got:?}, image method {q:?}"
            );
        }
        max = max.max(err);
    }
    (max, checked)
}

/// A scene of named two-point mirrors, one medium of index `w`, and paths of reflections.
fn mirror_scene(
    mirrors: &[(&str, P, P)],
    w: f64,
    sources: &[P],
    receivers: &[P],
    paths: &[&[&str]],
) -> Value {
    let interfaces: serde_json::Map<String, Value> = mirrors
        .iter()
        .map(|(name, a, b)| (name.to_string(), json!({ "points": [a, b] })))
        .collect();
    let paths: Vec<Value> = paths
        .iter()
        .map(|steps| {
            let st: Vec<Value> = steps.iter().map(|m| json!({ "reflect": m })).collect();
            json!({ "steps": st, "media": vec!["m"; steps.len() + 1] })
        })
        .collect();
    json!({
        "media": { "m": { "index": w } },
        "interfaces": interfaces,
        "sources": sources, "receivers": receivers, "paths": paths
    })
}

#[test]
fn single_reflection_random_mirrors() {
    let mut rng = Rng::new(0x0111_22AA);
    let mut max = 0.0f64;
    let mut checked = 0;
    for _ in 0..200 {
        let angle = rng.uniform(0.0, std::f64::consts::TAU);
        let offset = [rng.uniform(-10.0, 10.0), rng.uniform(-10.0, 10.0)];
        let w = rng.log_uniform(0.2, 5.0);
        let a = rng.uniform(-5.0, 5.0);
        let b = a + rng.uniform(-4.0, 4.0);
        let p0 = place([-30.0, 0.0], angle, offset);
        let p1 = place([30.0, 0.0], angle, offset);
        let s = place([a, rng.uniform(0.3, 3.0)], angle, offset);
        let r = place([b, rng.uniform(0.3, 3.0)], angle, offset);
        let v = mirror_scene(&[("mirror", p0, p1)], w, &[s], &[r], &[&["mirror"]]);
        let (e, n) = check_against_images(&v, w, &[vec![(p0, p1)]]);
        max = max.max(e);
        checked += n;
    }
    assert_eq!(
        checked, 200,
        "every random single reflection has a valid image path"
    );
    println!("mirrors single: {checked} rays, max relative time error {max:.2e}");
}

#[test]
fn parallel_mirrors_two_and_three_bounces() {
    let (b0, b1) = ([-20.0, 0.0], [20.0, 0.0]);
    let (t0, t1) = ([20.0, 1.0], [-20.0, 1.0]);
    let sources = [[0.0, 0.3], [-1.0, 0.75]];
    let receivers = [[2.5, 0.6], [0.4, 0.2], [-3.0, 0.9], [6.0, 0.5], [0.0, 0.3]];
    let v = mirror_scene(
        &[("bottom", b0, b1), ("top", t0, t1)],
        1.5,
        &sources,
        &receivers,
        &[
            &["bottom", "top"],
            &["bottom", "top", "bottom"],
            &["top", "bottom", "top"],
        ],
    );
    let mirrors = [
        vec![(b0, b1), (t0, t1)],
        vec![(b0, b1), (t0, t1), (b0, b1)],
        vec![(t0, t1), (b0, b1), (t0, t1)],
    ];
    let (max, checked) = check_against_images(&v, 1.5, &mirrors);
    assert_eq!(
        checked,
        sources.len() * receivers.len() * 3,
        "all parallel-mirror paths are valid"
    );
    println!("mirrors parallel: {checked} rays, max relative time error {max:.2e}");
}

#[test]
fn wedge_two_and_three_bounces() {
    let alpha = 50f64.to_radians();
    let dir = [alpha.cos(), alpha.sin()];
    let (a0, a1) = ([0.2, 0.0], [8.0, 0.0]);
    let (c0, c1) = (scale(dir, 8.0), scale(dir, 0.2));
    let s = [3.0, 0.8];
    let mut rng = Rng::new(0x3ED6_E000);
    let receivers: Vec<P> = (0..60)
        .map(|_| {
            let (rad, phi) = (rng.uniform(1.0, 5.0), rng.uniform(0.1, 0.9) * alpha);
            [rad * phi.cos(), rad * phi.sin()]
        })
        .collect();
    let v = mirror_scene(
        &[("a", a0, a1), ("b", c0, c1)],
        1.0,
        &[s],
        &receivers,
        &[&["a", "b"], &["b", "a"], &["a", "b", "a"], &["b", "a", "b"]],
    );
    let (ma, mb) = ((a0, a1), (c0, c1));
    let mirrors = [
        vec![ma, mb],
        vec![mb, ma],
        vec![ma, mb, ma],
        vec![mb, ma, mb],
    ];
    let (max, checked) = check_against_images(&v, 1.0, &mirrors);
    // Count the three-bounce paths that exist, so that the test cannot pass on two-bounce ones.
    let triples = receivers
        .iter()
        .flat_map(|&r| {
            [
                image_path(s, r, &mirrors[2]).2,
                image_path(s, r, &mirrors[3]).2,
            ]
        })
        .filter(|&ok| ok)
        .count();
    assert!(
        checked >= 60 && triples >= 10,
        "too few valid wedge paths: {checked}, of them 3-bounce {triples}"
    );
    println!(
        "mirrors wedge: {checked} rays ({triples} with three bounces), max relative time error {max:.2e}"
    );
}

#[test]
fn reflection_point_beyond_finite_mirror_is_no_path() {
    // Image method: the source (2, 1) images to (2, −1); the line to (4, 1) meets y = 0 at
    // x = 3, beyond the mirror's end at x = 1.
    let (m0, m1, s, r) = ([0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [4.0, 1.0]);
    let (_, pts, valid) = image_path(s, r, &[(m0, m1)]);
    assert!(
        !valid && (pts[0][0] - 3.0).abs() < 1e-15,
        "reference {pts:?}"
    );
    let sc = scene(&mirror_scene(
        &[("short", m0, m1)],
        1.0,
        &[s],
        &[r],
        &[&["short"]],
    ));
    let ray = &trace_all(&sc)[0];
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert_eq!(ray.reason, Some(Reason::BeyondEnd { step: 0 }), "{ray:?}");
    assert!(ray.time.is_nan() && ray.points.is_empty(), "{ray:?}");
    // The image method decides it: `T` is convex in the mirror's parameter, and its one
    // stationary point on the mirror's line lies beyond the end.
    assert_eq!(ray.iterations, 0, "{ray:?}");

    // Two bounces between parallel mirrors where the top one is too short for the second.
    let (b0, b1, t0, t1) = ([-5.0, 0.0], [5.0, 0.0], [-5.0, 1.0], [0.5, 1.0]);
    let (s, r) = ([0.0, 0.5], [3.0, 0.5]);
    let (_, pts, valid) = image_path(s, r, &[(b0, b1), (t0, t1)]);
    assert!(!valid && pts[1][0] > 0.5, "reference {pts:?}");
    let v = mirror_scene(
        &[("bottom", b0, b1), ("top", t0, t1)],
        1.0,
        &[s],
        &[r],
        &[&["bottom", "top"]],
    );
    let ray = &trace_all(&scene(&v))[0];
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert_eq!(ray.reason, Some(Reason::BeyondEnd { step: 1 }), "{ray:?}");
    assert_eq!(ray.iterations, 0, "{ray:?}");
}

#[test]
fn two_reflections_in_a_row_off_one_flat_mirror_coincide() {
    // Off one flat mirror, a second reflection in a row has no path of its own: the image
    // method gives the single reflection, and the two points fall on one spot. The first pair
    // of steps that does is reported (legs between interactions only).
    let (m0, m1, n0, n1) = ([-5.0, 0.0], [5.0, 0.0], [-5.0, 3.0], [5.0, 3.0]);
    let v = mirror_scene(
        &[("m", m0, m1), ("n", n0, n1)],
        1.0,
        &[[-2.0, 1.0]],
        &[[2.0, 1.5]],
        &[&["m", "m"], &["m", "n", "n"], &["m", "n"]],
    );
    let rays = trace_all(&scene(&v));
    // The solve from the start ends with the repeated mirror's two points on one spot; the
    // complete search proves that the sequences have no path.
    for ray in &rays[..2] {
        assert_eq!(ray.status, Status::NoPath, "{ray:?}");
        assert_eq!(ray.reason, Some(Reason::NoStationaryPath), "{ray:?}");
    }
    // Without the repeated mirror the path exists: the image method's length.
    let (length, _, valid) = image_path([-2.0, 1.0], [2.0, 1.5], &[(m0, m1), (n0, n1)]);
    assert!(valid);
    let ray = &rays[2];
    assert_eq!(ray.status, Status::Converged, "{ray:?}");
    assert!(
        (ray.time - length).abs() <= TOL * length,
        "{ray:?} vs {length}"
    );
}

/// Legs that graze their mirror (1e-7 to 1e-6 rad over a thousand units): a straight mirror
/// meets a leg that ends on it only at that end, so no such leg is obstructed by its own
/// mirror, whatever round-off does to the intersection test (it made 32 of these 200 rays
/// `obstructed` before the obstruction test skipped a leg's own segments). Times against the
/// image method; the reflection point itself is ill-determined along so flat a path (the time
/// changes with its square), so it is only checked to lie on the mirror.
#[test]
fn grazing_reflections_are_not_obstructed_by_their_own_mirror() {
    let angle = 0.3;
    let at = |along: f64, height: f64| place([along, height], angle, [0.0, 0.0]);
    let (p0, p1) = (at(-10.0, 0.0), at(2000.0, 0.0));
    let s = at(0.0, 1e-4);
    let receivers: Vec<P> = (0..200)
        .map(|i| {
            at(
                1000.0 * (0.5 + 0.5 * i as f64 / 200.0),
                1e-4 * (1 + i % 7) as f64,
            )
        })
        .collect();
    let v = mirror_scene(&[("mirror", p0, p1)], 1.0, &[s], &receivers, &[&["mirror"]]);
    // The mirror as one segment (its legs can meet nothing else: no test at all) and as two
    // collinear ones (the far one is a candidate, and the leg's own segment is skipped at
    // each test).
    let mut two = v.clone();
    two["interfaces"]["mirror"]["points"] = json!([p0, at(1500.0, 0.0), p1]);
    let mut max = 0.0f64;
    for sc in [scene(&v), scene(&two)] {
        for ray in trace_all(&sc) {
            let r = pt(sc.receivers()[ray.receiver]);
            let (len, _, valid) = image_path(s, r, &[(p0, p1)]);
            assert!(valid, "receiver {r:?}: an image path");
            assert_eq!(ray.status, Status::Converged, "receiver {r:?}: {ray:?}");
            let err = rel_err(ray.time, len);
            assert!(
                err <= TOL,
                "receiver {r:?}: time {:?}, image method {len}",
                ray.time
            );
            let q = pt(ray.points[1]);
            assert!(
                dist_to_line(q, p0, p1) <= TOL * dist(p0, p1),
                "{q:?} off the mirror"
            );
            max = max.max(err);
        }
    }
    println!("mirrors grazing: 2 × 200 rays, max relative time error {max:.2e}");
}

/// A converted reflection (another speed on the way back, as a P wave reflecting as an S wave)
/// off one and off two flat mirrors: the image method does not hold, and the tracer must not
/// take it for the solution. Checked against the law of reflection with two slownesses,
/// `w₀ sin θ₀ = w₁ sin θ₁` at every point along its mirror, and the time of the points.
#[test]
fn converted_reflections_obey_the_law_with_two_slownesses() {
    let (low, high) = (([-20.0, 0.0], [20.0, 0.0]), ([20.0, 3.0], [-20.0, 3.5]));
    let v = json!({
        "media": { "p": { "speed": 1.7 }, "s": { "speed": 1.0 } },
        "interfaces": { "low": { "points": [low.0, low.1] },
                        "high": { "points": [high.0, high.1] } },
        "sources": [[-2.0, 1.0], [0.5, 2.0]],
        "receivers": [[3.0, 1.5], [-1.0, 2.2], [6.0, 0.4]],
        "paths": [
            { "steps": [{ "reflect": "low" }], "media": ["p", "s"] },
            { "steps": [{ "reflect": "low" }, { "reflect": "high" }], "media": ["p", "s", "s"] }
        ]
    });
    let sc = scene(&v);
    let w = |m: &str| if m == "p" { 1.0 / 1.7 } else { 1.0 };
    let legs: [&[f64]; 2] = [&[w("p"), w("s")], &[w("p"), w("s"), w("s")]];
    let mirrors: [&[(P, P)]; 2] = [&[low], &[low, high]];
    let rays = trace_all(&sc);
    assert_eq!(rays.len(), 12);
    for ray in &rays {
        assert_eq!(ray.status, Status::Converged, "{ray:?}");
        let p: Vec<P> = ray.points.iter().map(|&q| pt(q)).collect();
        let w = legs[ray.path];
        let time: f64 = p.windows(2).zip(w).map(|(l, w)| w * dist(l[0], l[1])).sum();
        assert!(rel_err(ray.time, time) <= TOL, "{ray:?}");
        for (i, &(a, b)) in mirrors[ray.path].iter().enumerate() {
            let t = unit(sub(b, a));
            let (arrive, leave) = (unit(sub(p[i + 1], p[i])), unit(sub(p[i + 2], p[i + 1])));
            let law = (w[i] * dot(arrive, t) - w[i + 1] * dot(leave, t)) / (w[i] + w[i + 1]);
            assert!(law.abs() <= TOL, "{ray:?}: point {i}, {law:e}");
        }
    }

    // Off a short mirror the image method's point (one slowness) lies beyond its end while the
    // converted ray's lies on it: the image method must not decide that ray.
    let (m0, m1, s, r) = ([2.0, 0.0], [4.0, 0.0], [-1.0, 1.0], [3.5, 1.0]);
    let (_, pts, valid) = image_path(s, r, &[(m0, m1)]);
    assert!(!valid && pts[0][0] < m0[0], "reference {pts:?}");
    let short = |media: [&str; 2]| {
        json!({
            "media": { "p": { "speed": 1.7 }, "s": { "speed": 1.0 } },
            "interfaces": { "short": { "points": [m0, m1] } },
            "sources": [s], "receivers": [r],
            "paths": [{ "steps": [{ "reflect": "short" }], "media": media }]
        })
    };
    let same = &trace_all(&scene(&short(["s", "s"])))[0];
    assert_eq!(same.status, Status::NoPath, "{same:?}");
    let ray = &trace_all(&scene(&short(["p", "s"])))[0];
    assert_eq!(ray.status, Status::Converged, "{ray:?}");
    let p: Vec<P> = ray.points.iter().map(|&q| pt(q)).collect();
    assert!(p[1][0] > m0[0] && p[1][0] < m1[0], "{ray:?}");
    let (arrive, leave) = (unit(sub(p[1], p[0])), unit(sub(p[2], p[1])));
    let (w0, w1) = (w("p"), w("s"));
    let law = (w0 * arrive[0] - w1 * leave[0]) / (w0 + w1);
    assert!(law.abs() <= TOL, "{ray:?}: {law:e}");
}
