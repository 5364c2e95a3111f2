//! A ray's curve (`eigenray::trace::ray_curve`, the points `--svg` and Python's `curve`
//! draw) against independent references: a `profile` medium's rays against an RK4
//! integration of the ray equations from their launch angles (the samples at their arc
//! lengths), the legs of a linear profile between walls and of a `gradient` medium against
//! the circle through each leg's ends whose centre lies where the speed is 0, the picture's
//! polylines against the integrated rays, and the errors.

use std::process::Command;

use eigenray::options::Run;
use eigenray::trace::{CurveError, ray_curve};
use eigenray::{Point, Scene, Tracer};

/// A sound channel: the speed's minimum at −1000.
const CHANNEL: [[f64; 2]; 3] = [[0.0, 1520.0], [-1000.0, 1490.0], [-3000.0, 1530.0]];

/// Layer `i` of `knots` (0 above the first knot, `n` below the last, both of the end
/// knot's speed; else between knots `i − 1` and `i`): its speed at `y` (its line extended
/// beyond it), its slope, and its span `[bottom, top]`.
fn layer(knots: &[[f64; 2]], i: usize, y: f64) -> (f64, f64, [f64; 2]) {
    let n = knots.len();
    if i == 0 {
        return (knots[0][1], 0.0, [knots[0][0], f64::INFINITY]);
    }
    if i == n {
        return (knots[n - 1][1], 0.0, [f64::NEG_INFINITY, knots[n - 1][0]]);
    }
    let ([y0, c0], [y1, c1]) = (knots[i - 1], knots[i]);
    let slope = (c1 - c0) / (y1 - y0);
    (c0 + slope * (y - y0), slope, [y1, y0])
}

/// The layer a ray at height `y` going up (`up`) or down is in: at a knot, the one it
/// enters.
fn layer_of(knots: &[[f64; 2]], y: f64, up: bool) -> usize {
    let above = knots.iter().filter(|k| k[0] > y).count();
    let at_knot = knots.iter().any(|k| k[0] == y);
    above + usize::from(at_knot && !up)
}

/// One classical RK4 step of size `h` from `u` of the ray equations in arc length,
/// `(x, y, θ)` with `θ′ = −c′(y) cos θ / c`, in layer `i`'s speed (one smooth line).
fn rk4_plain(knots: &[[f64; 2]], i: usize, u: [f64; 3], h: f64) -> [f64; 3] {
    let rhs = |u: [f64; 3]| {
        let (c, dc, _) = layer(knots, i, u[1]);
        [u[2].cos(), u[2].sin(), -dc * u[2].cos() / c]
    };
    let add =
        |u: [f64; 3], k: [f64; 3], f: f64| [u[0] + f * k[0], u[1] + f * k[1], u[2] + f * k[2]];
    let k1 = rhs(u);
    let k2 = rhs(add(u, k1, 0.5 * h));
    let k3 = rhs(add(u, k2, 0.5 * h));
    let k4 = rhs(add(u, k3, h));
    let mut out = u;
    for j in 0..3 {
        out[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    out
}

/// `steps` RK4 steps of size `h` from `u`, each in the speed of the layer the ray is in: a
/// step that leaves its layer is cut where it reaches the knot (by bisection on its size),
/// and goes on in the next layer from there (the speed's slope jumps at a knot: a step
/// across it would be of first order).
fn rk4(knots: &[[f64; 2]], mut u: [f64; 3], h: f64, steps: usize) -> [f64; 3] {
    for _ in 0..steps {
        let mut left = h;
        while left > 0.0 {
            let i = layer_of(knots, u[1], u[2].sin() >= 0.0);
            let (_, _, [bottom, top]) = layer(knots, i, u[1]);
            let inside = |v: [f64; 3]| v[1] >= bottom && v[1] <= top;
            let v = rk4_plain(knots, i, u, left);
            if inside(v) {
                u = v;
                break;
            }
            let edge = if v[1] > top { top } else { bottom };
            let (mut lo, mut hi) = (0.0, left);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if inside(rk4_plain(knots, i, u, mid)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            // To the knot, on into the next layer from there.
            u = rk4_plain(knots, i, u, hi);
            u[1] = edge;
            left -= hi;
        }
    }
    u
}

/// The arc length at which the ray from `u` (going +x) reaches `x = end` (steps of `h`,
/// the last one found by bisection).
fn arc_length_to(knots: &[[f64; 2]], mut u: [f64; 3], end: f64, h: f64) -> f64 {
    let mut s = 0.0;
    loop {
        let next = rk4(knots, u, h, 1);
        if next[0] >= end {
            let (mut lo, mut hi) = (0.0, h);
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if rk4(knots, u, mid, 1)[0] >= end {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return s + 0.5 * (lo + hi);
        }
        (u, s) = (next, s + h);
    }
}

fn scene(json: &str) -> Scene {
    Scene::from_json(json).unwrap()
}

/// Every ray of a sound channel (three at 15 km, four at 30 km, turning up to three times,
/// with caustics) sampled at 301 points: the first the source, the last the receiver; every
/// sample within 1e-6 m of
/// an RK4 integration of the ray equations from the ray's launch angle, stepped to the
/// sample's arc length (`j L / 300`, `L` the integrated ray's arc length to the receiver's
/// range): the samples are on the ray and evenly spaced along it.
#[test]
fn profile_curves_lie_on_the_integrated_ray() {
    let knots = serde_json::to_string(&CHANNEL).unwrap();
    let s = scene(&format!(
        r#"{{ "media": {{ "sea": {{ "profile": {knots} }} }},
             "sources": [[0, -800]], "receivers": [[15000, -1200], [30000, -1100]],
             "paths": [{{ "steps": [], "media": ["sea"] }}] }}"#
    ));
    let tracer = Tracer::new(&s).unwrap();
    let (mut rays, mut worst, mut most_turns) = (0, 0.0f64, 0);
    for &r in s.receivers() {
        let mut arrivals = Vec::new();
        tracer
            .stationary_paths(s.sources()[0], r, 0, &Run::new(), &mut arrivals)
            .unwrap();
        assert!(arrivals.len() >= 3, "{}", arrivals.len());
        for a in &arrivals {
            let n = 301;
            let curve = ray_curve(&s, &a.points, &a.media, a.launch_angle, n).unwrap();
            assert_eq!(curve.len(), n);
            assert_eq!((curve[0], curve[n - 1]), (a.points[0], a.points[1]));
            let theta = a.launch_angle.unwrap();
            let start = [a.points[0].x, a.points[0].y, theta];
            let length = arc_length_to(&CHANNEL, start, r.x, 0.25);
            let step = length / (n - 1) as f64;
            let substeps = (step / 0.25).ceil() as usize;
            let mut u = start;
            for (j, p) in curve.iter().enumerate().skip(1) {
                u = rk4(&CHANNEL, u, step / substeps as f64, substeps);
                let off = ((p.x - u[0]).powi(2) + (p.y - u[1]).powi(2)).sqrt();
                worst = worst.max(off);
                assert!(off < 1e-6, "ray {theta} sample {j}: {p:?} {u:?}: {off}");
            }
            rays += 1;
            most_turns = most_turns.max(a.turns.unwrap());
        }
    }
    println!("{rays} rays (up to {most_turns} turns): worst distance to RK4 {worst:.2e} m");
    assert!(rays >= 7 && most_turns >= 3, "{rays} {most_turns}");
}

/// The point `(xc, yc)` equidistant from `a` and `b` on the line `y = yc`, and its distance.
fn circle(a: Point, b: Point, yc: f64) -> (f64, f64) {
    let xc =
        ((b.x * b.x - a.x * a.x) + (b.y - yc).powi(2) - (a.y - yc).powi(2)) / (2.0 * (b.x - a.x));
    (xc, ((a.x - xc).powi(2) + (a.y - yc).powi(2)).sqrt())
}

/// A linear profile between a surface and a bottom (one layer: each leg between reflections
/// one circle, whose centre lies where `c = 0`, turning points and all): every search
/// arrival with up to 3 reflections sampled at 200 points passes through its source, its
/// reflection points and its receiver as samples, in order, and every sample lies on its
/// leg's circle to 1e-9 of the radius, in order along it.
#[test]
fn walled_profile_legs_are_circles_through_their_reflections() {
    let s = scene(
        r#"{ "media": {
               "water": { "profile": [[0, 1500], [-100, 1480]], "at": [0, -50] },
               "mud": { "speed": 1700, "at": [0, -150] }, "air": { "speed": 340, "at": [0, 50] } },
             "domain": [[-3000, -300], [6000, 100]],
             "interfaces": {
               "surface": { "points": [[-3000, 0], [6000, 0]] },
               "bottom": { "points": [[-3000, -100], [6000, -100]] } },
             "sources": [[0, -30]], "receivers": [[2500, -70], [-1500, -10]],
             "search": { "max_steps": 3 } }"#,
    );
    let report = Tracer::new(&s).unwrap().search(&Run::new()).unwrap();
    // c = 1500 + 0.2 y: 0 at y = −7500.
    let yc = -7500.0;
    let (mut checked, mut worst) = (0, 0.0f64);
    for a in &report.arrivals {
        let pts = &a.arrival.points;
        let n = 200;
        let curve = ray_curve(&s, pts, &a.arrival.media, a.arrival.launch_angle, n).unwrap();
        assert_eq!(curve.len(), n);
        // Each point is a sample, in order.
        let mut at = Vec::new();
        for p in pts {
            let from = at.last().map_or(0, |&i| i + 1);
            let i = from
                + curve[from..]
                    .iter()
                    .position(|q| q == p)
                    .expect("a point is a sample");
            at.push(i);
        }
        assert_eq!((at[0], at[at.len() - 1]), (0, n - 1));
        for (leg, w) in at.windows(2).enumerate() {
            let (xc, radius) = circle(pts[leg], pts[leg + 1], yc);
            let mut last = f64::NEG_INFINITY;
            let sx = (pts[leg + 1].x - pts[leg].x).signum();
            for q in &curve[w[0]..=w[1]] {
                let off = ((q.x - xc).powi(2) + (q.y - yc).powi(2)).sqrt() - radius;
                worst = worst.max(off.abs() / radius);
                assert!(off.abs() < 1e-9 * radius, "{q:?}: {off}");
                assert!(q.x * sx >= last, "{q:?} back along x");
                last = q.x * sx;
            }
        }
        checked += 1;
    }
    println!("{checked} arrivals: worst distance to the circles {worst:.1e} of the radius");
    assert!(checked >= 8, "{checked}");
    assert!(report.arrivals.iter().any(|a| a.steps.len() == 3));
}

/// A reflection in a `gradient` medium (`c = 1500 − 0.05 y`): both legs' samples on their
/// circles (centre where `c = 0`) to 1e-9 of the radius, evenly spaced along each (equal
/// angles at the centre, to 1e-9), the reflection point a sample.
#[test]
fn gradient_legs_are_arcs_evenly_sampled() {
    let s = scene(
        r#"{ "media": { "sea": { "speed": 1500, "gradient": [0, -0.05] } },
             "interfaces": { "floor": { "points": [[-100, -2000], [9000, -2000]] } },
             "sources": [[0, -100]], "receivers": [[7000, -400]],
             "paths": [{ "steps": [{ "reflect": "floor" }], "media": ["sea", "sea"] }] }"#,
    );
    let ray = &Tracer::new(&s).unwrap().trace_all()[0];
    assert_eq!(ray.points.len(), 3);
    let curve = ray_curve(&s, &ray.points, &ray.media, None, 101).unwrap();
    let at = curve.iter().position(|q| *q == ray.points[1]).unwrap();
    let yc = 1500.0 / 0.05;
    for (a, b, samples) in [
        (ray.points[0], ray.points[1], &curve[..=at]),
        (ray.points[1], ray.points[2], &curve[at..]),
    ] {
        assert!(samples.len() >= 30, "{}", samples.len());
        let (xc, radius) = circle(a, b, yc);
        let angles: Vec<f64> = samples
            .iter()
            .map(|q| {
                let off = ((q.x - xc).powi(2) + (q.y - yc).powi(2)).sqrt() - radius;
                assert!(off.abs() < 1e-9 * radius, "{q:?}: {off}");
                (q.y - yc).atan2(q.x - xc)
            })
            .collect();
        let step = (angles[angles.len() - 1] - angles[0]) / (angles.len() - 1) as f64;
        for (j, w) in angles.windows(2).enumerate() {
            assert!(
                ((w[1] - w[0]) - step).abs() < 1e-9 * step.abs(),
                "{j}: {w:?} {step}"
            );
        }
    }
}

/// Straight legs are their chords; too few samples, a ray without points and a launch
/// angle no ray of the profile has are refused, naming why.
#[test]
fn straight_legs_and_refusals() {
    let s = scene(
        r#"{ "media": { "air": { "speed": 340 } },
             "interfaces": { "wall": { "points": [[-10, 0], [10, 0]] } },
             "sources": [[0, 1]], "receivers": [[4, 3]],
             "paths": [{ "steps": [{ "reflect": "wall" }], "media": ["air", "air"] }] }"#,
    );
    let ray = &Tracer::new(&s).unwrap().trace_all()[0];
    let curve = ray_curve(&s, &ray.points, &ray.media, None, 5).unwrap();
    let at = curve.iter().position(|q| *q == ray.points[1]).unwrap();
    assert!(at > 0 && at < 4);
    for q in &curve {
        let leg = if q.x <= ray.points[1].x { 0 } else { 1 };
        let (a, b) = (ray.points[leg], ray.points[leg + 1]);
        let cross = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        assert!(cross.abs() < 1e-12, "{q:?}");
    }
    assert_eq!(
        ray_curve(&s, &ray.points, &ray.media, None, 2),
        Err(CurveError::TooFewSamples { n: 2, least: 3 })
    );
    let nan = [Point::new(0.0, 1.0), Point::new(f64::NAN, 0.0)];
    assert_eq!(ray_curve(&s, &nan, &[], None, 10), Err(CurveError::Points));
    let p = scene(
        r#"{ "media": { "sea": { "profile": [[0, 1520], [-1000, 1490], [-3000, 1530]] } },
             "sources": [[0, -500]], "receivers": [[8000, -500]],
             "paths": [{ "steps": [], "media": ["sea"] }] }"#,
    );
    let ray = &Tracer::new(&p).unwrap().trace_all()[0];
    assert!(ray_curve(&p, &ray.points, &ray.media, None, 50).is_ok());
    let err = ray_curve(&p, &ray.points, &ray.media, Some(1.2), 50).unwrap_err();
    assert_eq!(
        err,
        CurveError::NoProfileRay {
            medium: "sea".into()
        }
    );
    assert!(err.to_string().contains("\"sea\""), "{err}");
}

/// `eigenray solve --svg` of a sound channel with `"stationary": "all"`: each ray's
/// polyline, mapped back to the scene's coordinates through its ends (the source and the
/// receiver), lies within 0.01 m of the RK4 ray from the launch angle the JSON gives for it
/// (15 km of range), has many points, and the turning ones leave their
/// chord by hundreds of metres.
#[test]
fn the_svg_draws_profile_rays_as_their_curves() {
    let knots = serde_json::to_string(&CHANNEL).unwrap();
    let json = format!(
        r#"{{ "media": {{ "sea": {{ "profile": {knots} }} }},
             "sources": [[0, -800]], "receivers": [[15000, -1200]],
             "solver": {{ "stationary": "all" }},
             "paths": [{{ "steps": [], "media": ["sea"] }}] }}"#
    );
    let dir = std::env::temp_dir().join(format!("eigenray-svg-profile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (file, svg) = (dir.join("channel.json"), dir.join("channel.svg"));
    std::fs::write(&file, json).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .arg("--svg")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let angles: Vec<f64> = doc["rays"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["launch_angle"].as_f64().unwrap())
        .collect();
    let text = std::fs::read_to_string(&svg).unwrap();
    let rays = text.split(r#"<g class="rays""#).nth(1).unwrap();
    let rays = &rays[..rays.find("</g>").unwrap()];
    let lines: Vec<Vec<[f64; 2]>> = rays
        .split(r#"<polyline points=""#)
        .skip(1)
        .map(|l| {
            l[..l.find('"').unwrap()]
                .split(' ')
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    [x.parse().unwrap(), y.parse().unwrap()]
                })
                .collect()
        })
        .collect();
    assert_eq!(lines.len(), angles.len());
    assert!(lines.len() >= 3, "{}", lines.len());
    let (s, r) = ([0.0, -800.0], [15000.0, -1200.0]);
    let mut worst = 0.0f64;
    let mut bulges = 0;
    for (pixels, theta) in lines.iter().zip(&angles) {
        assert!(pixels.len() > 50, "{}", pixels.len());
        let (p0, p1) = (pixels[0], pixels[pixels.len() - 1]);
        let world = |p: [f64; 2]| {
            [
                s[0] + (p[0] - p0[0]) / (p1[0] - p0[0]) * (r[0] - s[0]),
                s[1] + (p[1] - p0[1]) / (p1[1] - p0[1]) * (r[1] - s[1]),
            ]
        };
        // The integrated ray, densely (1 m steps).
        let mut u = [s[0], s[1], *theta];
        let mut dense = vec![[u[0], u[1]]];
        while u[0] < r[0] + 10.0 {
            u = rk4(&CHANNEL, u, 1.0, 1);
            dense.push([u[0], u[1]]);
        }
        let mut chord_off = 0.0f64;
        for p in pixels {
            let [x, y] = world(*p);
            let near = dense
                .windows(2)
                .map(|w| segment_distance([x, y], w[0], w[1]))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(near);
            assert!(near < 0.01, "ray at {theta}: ({x}, {y}) is {near} m off");
            let chord_y = s[1] + (x - s[0]) / (r[0] - s[0]) * (r[1] - s[1]);
            chord_off = chord_off.max((y - chord_y).abs());
        }
        bulges += usize::from(chord_off > 200.0);
    }
    println!(
        "{} polylines: worst distance to the RK4 rays {worst:.2e} m",
        lines.len()
    );
    assert!(bulges >= 2, "{bulges}");
    std::fs::remove_dir_all(&dir).ok();
}

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// `eigenray solve --svg` of a search in a linear profile between walls (`c = 1500 + 0.2 y`):
/// each arrival's polyline, mapped back through its ends (the source and the receiver),
/// passes through the arrival's reflection points (within 1e-3 m) and lies on its legs'
/// circles (centre where `c = 0`, within 1e-3 m): the picture draws the search's curved
/// arrivals with their launch angles.
#[test]
fn the_svg_draws_walled_arrivals_through_their_reflections() {
    let json = r#"{ "media": {
       "water": { "profile": [[0, 1500], [-100, 1480]], "at": [0, -50] },
       "mud": { "speed": 1700, "at": [0, -150] }, "air": { "speed": 340, "at": [0, 50] } },
     "domain": [[-3000, -300], [6000, 100]],
     "interfaces": {
       "surface": { "points": [[-3000, 0], [6000, 0]] },
       "bottom": { "points": [[-3000, -100], [6000, -100]] } },
     "sources": [[0, -30]], "receivers": [[2500, -70]],
     "search": { "max_steps": 3 } }"#;
    let dir = std::env::temp_dir().join(format!("eigenray-svg-walled-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (file, svg) = (dir.join("walled.json"), dir.join("walled.svg"));
    std::fs::write(&file, json).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .arg("solve")
        .arg(&file)
        .arg("--svg")
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let arrivals: Vec<Vec<[f64; 2]>> = doc["arrivals"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| serde_json::from_value(a["points"].clone()).unwrap())
        .collect();
    let text = std::fs::read_to_string(&svg).unwrap();
    let rays = text.split(r#"<g class="rays""#).nth(1).unwrap();
    let rays = &rays[..rays.find("</g>").unwrap()];
    let lines: Vec<Vec<[f64; 2]>> = rays
        .split(r#"<polyline points=""#)
        .skip(1)
        .map(|l| {
            l[..l.find('"').unwrap()]
                .split(' ')
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    [x.parse().unwrap(), y.parse().unwrap()]
                })
                .collect()
        })
        .collect();
    assert_eq!(lines.len(), arrivals.len());
    assert!(arrivals.iter().any(|a| a.len() == 5), "{arrivals:?}");
    let (s, r) = ([0.0, -30.0], [2500.0, -70.0]);
    for (pixels, points) in lines.iter().zip(&arrivals) {
        assert!(pixels.len() > 64, "{}", pixels.len());
        let (p0, p1) = (pixels[0], pixels[pixels.len() - 1]);
        let world: Vec<[f64; 2]> = pixels
            .iter()
            .map(|p| {
                [
                    s[0] + (p[0] - p0[0]) / (p1[0] - p0[0]) * (r[0] - s[0]),
                    s[1] + (p[1] - p0[1]) / (p1[1] - p0[1]) * (r[1] - s[1]),
                ]
            })
            .collect();
        for q in points {
            let near = world
                .iter()
                .map(|w| (w[0] - q[0]).hypot(w[1] - q[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(near < 1e-3, "{q:?}: {near}");
        }
        let circles: Vec<(f64, f64)> = points
            .windows(2)
            .map(|w| {
                let (a, b) = (Point::new(w[0][0], w[0][1]), Point::new(w[1][0], w[1][1]));
                circle(a, b, -7500.0)
            })
            .collect();
        for w in &world {
            let off = circles
                .iter()
                .map(|(xc, radius)| ((w[0] - xc).hypot(w[1] + 7500.0) - radius).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(off < 1e-3, "{w:?}: {off}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
