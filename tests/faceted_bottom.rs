//! A faceted bottom: where two straight segments of a sloping shelf join, the specular points
//! of the two segments leave a gap, and a receiver in the gap has no specular bottom bounce at
//! all, only a path held at the joint (`vertex`, edge diffraction). The search's arrivals are
//! checked against an independent enumeration by the image method over every facet of every
//! bounce, and the held path against its time through the vertex.

use eigenray::options::Run;
use eigenray::{Point, Scene, Status, Tracer, amplitude::NoAmplitude};
use serde_json::json;

/// Sound speed of the water.
const SPEED: f64 = 1500.0;
/// The source, at 25 m on the axis.
const SOURCE: [f64; 2] = [0.0, -25.0];
/// The receiver, at 4 km and 25 m: in the gap of the one-bounce bottom reflections.
const RECEIVER: [f64; 2] = [4000.0, -25.0];
/// The joint of the shelf: flat at 80 m to 1.5 km, then sloping to 120 m at 5 km.
const JOINT: [f64; 2] = [1500.0, -80.0];

/// The shelf's bottom (a pressure-release surface above it).
fn shelf() -> Vec<[f64; 2]> {
    vec![[0.0, -80.0], JOINT, [5000.0, -120.0]]
}

/// The same water over a flat bottom at 80 m.
fn flat() -> Vec<[f64; 2]> {
    vec![[0.0, -80.0], [5000.0, -80.0]]
}

/// The scene: the surface, `bottom`, the source and the receiver, with `search`.
fn scene(bottom: &[[f64; 2]], search: serde_json::Value) -> Scene {
    let doc = json!({
        "media": { "water": { "speed": SPEED } },
        "background": "water",
        "interfaces": {
            "surface": { "points": [[0, 0], [5000, 0]], "reflection": "pressure-release" },
            "bottom": { "points": bottom }
        },
        "sources": [SOURCE], "receivers": [RECEIVER],
        "search": search,
        "amplitudes": { "source": "axisymmetric", "frequency": 100 }
    });
    let s = Scene::from_json(&doc.to_string()).unwrap();
    assert_eq!(s.interface_index("bottom"), Some(BOTTOM));
    assert_eq!(s.interface_index("surface"), Some(SURFACE));
    s
}

/// The interfaces' indices in the scene (in the order of their names).
const BOTTOM: usize = 0;
const SURFACE: usize = 1;

type P = [f64; 2];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dist(a: P, b: P) -> f64 {
    let d = sub(a, b);
    dot(d, d).sqrt()
}

/// `p` mirrored across the line through `a` and `b`.
fn mirror(p: P, (a, b): (P, P)) -> P {
    let t = sub(b, a);
    let u = dot(sub(p, a), t) / dot(t, t);
    let foot = [a[0] + u * t[0], a[1] + u * t[1]];
    [2.0 * foot[0] - p[0], 2.0 * foot[1] - p[1]]
}

/// Where the line from `p` to `q` meets the line through `a` and `b`: the fraction along
/// `a → b` (`None` when parallel).
fn meet(p: P, q: P, (a, b): (P, P)) -> Option<f64> {
    let (d, t) = (sub(q, p), sub(b, a));
    let den = cross(d, t);
    (den != 0.0).then(|| cross(d, sub(p, a)) / den)
}

/// Whether the segments `p q` and `a b` cross at a point inside both, each end of one more
/// than a micrometre from the other's line (an end of a leg on the facet it reflects off
/// touches, and does not cross).
fn crosses(p: P, q: P, a: P, b: P) -> bool {
    let side = |u: P, v: P, w: P| cross(sub(v, u), sub(w, u)) / dist(u, v);
    let apart = |x: f64, y: f64| (x > 1e-6 && y < -1e-6) || (x < -1e-6 && y > 1e-6);
    apart(side(p, q, a), side(p, q, b)) && apart(side(a, b, p), side(a, b, q))
}

/// One specular path by the image method.
#[derive(Debug)]
struct ImagePath {
    /// The interfaces in order (0 the bottom, 1 the surface).
    sequence: Vec<usize>,
    /// Travel time.
    time: f64,
}

/// Every specular path from `s` to `r` of at most `max_steps` reflections off the facets of
/// `bottom` and the surface (`y = 0`): every sequence, every choice of facet per bounce, the
/// image method, and a path kept where each point lies strictly inside its facet, both legs
/// at each point lie on the water's side of its facet, and no leg crosses a facet.
fn image_paths(s: P, r: P, bottom: &[P], max_steps: usize) -> Vec<ImagePath> {
    // In the scene's order of interfaces (by name): the bottom, then the surface.
    let facets: Vec<(P, P)> = bottom.windows(2).map(|w| (w[0], w[1])).collect();
    let surface = vec![([0.0, 0.0], [5000.0, 0.0])];
    let walls = [facets, surface];
    let every: Vec<(P, P)> = walls.iter().flatten().copied().collect();
    // The water lies above every facet and below the surface (by more than a micrometre:
    // a leg back to the line it left is no reflection).
    let water_side = |wall: usize, (a, b): (P, P), p: P| {
        let side = cross(sub(b, a), sub(p, a)) / dist(a, b);
        if wall == 0 { side > 1e-6 } else { side < -1e-6 }
    };
    let mut out = Vec::new();
    for k in 0..=max_steps {
        for code in 0..(1usize << k) {
            let sequence: Vec<usize> = (0..k).map(|i| (code >> i) & 1).collect();
            let choices: usize = sequence.iter().map(|&w| walls[w].len()).product();
            for choice in 0..choices {
                let mut c = choice;
                let lines: Vec<(P, P)> = sequence
                    .iter()
                    .map(|&w| {
                        let f = walls[w][c % walls[w].len()];
                        c /= walls[w].len();
                        f
                    })
                    .collect();
                // images[i]: the receiver mirrored across lines k−1, …, i.
                let mut images = vec![r; k + 1];
                for i in (0..k).rev() {
                    images[i] = mirror(images[i + 1], lines[i]);
                }
                let mut points = vec![s];
                let mut valid = true;
                for (i, &line) in lines.iter().enumerate() {
                    let prev = points[i];
                    let Some(u) =
                        meet(prev, images[i], line).filter(|u| *u > 1e-9 && *u < 1.0 - 1e-9)
                    else {
                        valid = false;
                        break;
                    };
                    let (a, b) = line;
                    points.push([a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])]);
                }
                if !valid {
                    continue;
                }
                points.push(r);
                for (i, &line) in lines.iter().enumerate() {
                    valid &= water_side(sequence[i], line, points[i])
                        && water_side(sequence[i], line, points[i + 2]);
                }
                for leg in points.windows(2) {
                    valid &= !every.iter().any(|&(a, b)| crosses(leg[0], leg[1], a, b));
                }
                if valid {
                    let length: f64 = points.windows(2).map(|w| dist(w[0], w[1])).sum();
                    out.push(ImagePath {
                        sequence: sequence.clone(),
                        time: length / SPEED,
                    });
                }
            }
        }
    }
    out.sort_by(|a, b| {
        (&a.sequence, a.time)
            .partial_cmp(&(&b.sequence, b.time))
            .unwrap()
    });
    out
}

/// The search's `converged` arrivals as (sequence, time), sorted as [`image_paths`].
fn converged(s: &Scene) -> Vec<(Vec<usize>, f64)> {
    let arrivals = Tracer::new(s)
        .unwrap()
        .search(&Run::new())
        .unwrap()
        .arrivals;
    let mut out: Vec<(Vec<usize>, f64)> = arrivals
        .iter()
        .filter(|a| a.arrival.status == Status::Converged)
        .map(|a| {
            (
                a.steps.iter().map(|s| s.interface).collect(),
                a.arrival.time,
            )
        })
        .collect();
    out.sort_by(|a, b| a.partial_cmp(b).unwrap());
    out
}

/// The one-bounce bottom reflection to 4 km: on neither facet does the image method put a
/// specular point (the flat facet's lies past the joint, the slope's before it), and the
/// search finds the bounce only as the path held at the joint, with the time through it.
#[test]
fn the_bounce_past_the_joint_is_held_at_the_vertex() {
    // Ground truth first: the image method's point on each facet's line lies off the facet.
    let bottom = shelf();
    for facet in bottom.windows(2) {
        let image = mirror(SOURCE, (facet[0], facet[1]));
        let u = meet(image, RECEIVER, (facet[0], facet[1])).unwrap();
        assert!(!(0.0..=1.0).contains(&u), "{facet:?}: {u}");
    }
    assert!(
        image_paths(SOURCE, RECEIVER, &bottom, 1)
            .iter()
            .all(|p| p.sequence != [BOTTOM])
    );

    let held = scene(&bottom, json!({ "max_steps": 1, "vertex": true }));
    let arrivals = Tracer::new(&held)
        .unwrap()
        .search(&Run::new())
        .unwrap()
        .arrivals;
    let bounces: Vec<_> = arrivals
        .iter()
        .filter(|a| a.steps.len() == 1 && a.steps[0].interface == BOTTOM)
        .collect();
    assert_eq!(bounces.len(), 1, "{bounces:#?}");
    let bounce = &bounces[0].arrival;
    assert_eq!(bounce.status, Status::Vertex);
    assert_eq!(bounce.points[1], Point::new(JOINT[0], JOINT[1]));
    let through_joint = (dist(SOURCE, JOINT) + dist(JOINT, RECEIVER)) / SPEED;
    assert!(
        (bounce.time - through_joint).abs() <= 1e-15 * through_joint,
        "{} against {through_joint}",
        bounce.time
    );
    // Edge diffraction: no ray-theory amplitude, and it says why.
    let amplitude = bounce.amplitude.unwrap();
    assert_eq!(amplitude.reason, Some(NoAmplitude::Vertex));

    // By default (no `vertex`) the search lists the specular paths only: no bottom bounce.
    let plain = scene(&bottom, json!({ "max_steps": 1 }));
    let found = converged(&plain);
    let sequences: Vec<_> = found.iter().map(|f| f.0.clone()).collect();
    assert_eq!(sequences, [vec![], vec![SURFACE]]);

    // Over a flat bottom the same bounce is specular, at the image method's time.
    let level = converged(&scene(&flat(), json!({ "max_steps": 1 })));
    let image = mirror(SOURCE, ([0.0, -80.0], [5000.0, -80.0]));
    let (sequence, time) = &level[1];
    assert_eq!(sequence, &[BOTTOM]);
    assert!((time - dist(image, RECEIVER) / SPEED).abs() <= 1e-15 * time);
}

/// Every specular path of up to 8 bounces, on the shelf and on the flat bottom, against the
/// image method over every facet of every bounce: the same paths at the same times. The shelf
/// has fewer: bounces whose specular points would straddle the joint are missing.
#[test]
fn the_specular_paths_are_those_of_the_image_method() {
    let max_steps = 8;
    let mut counts = Vec::new();
    for bottom in [shelf(), flat()] {
        let want = image_paths(SOURCE, RECEIVER, &bottom, max_steps);
        let got = converged(&scene(&bottom, json!({ "max_steps": max_steps })));
        assert_eq!(
            got.len(),
            want.len(),
            "{bottom:?}: {got:?}\nagainst\n{want:?}"
        );
        for ((sequence, time), w) in got.iter().zip(&want) {
            assert_eq!(sequence, &w.sequence, "{bottom:?}");
            assert!(
                (time - w.time).abs() <= 1e-14 * w.time,
                "{bottom:?}: {time} {w:?}"
            );
        }
        counts.push(got.len());
    }
    println!(
        "specular paths of up to {max_steps} bounces: shelf {}, flat {}",
        counts[0], counts[1]
    );
    assert!(counts[0] < counts[1], "{counts:?}");
}
