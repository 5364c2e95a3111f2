//! The curves of rays through a `profile` medium off sloping walls (`ray_curve`, which
//! `--svg` and Python's `curve` draw): sampled on the ray itself, checked from the samples
//! alone — within each leg the chords' Snell invariant `cos φ / c` (a chord of a circular
//! arc is parallel to the arc's tangent at its middle) is one number, at each reflection the
//! chords either side obey the law of reflection off the wall's segment, the curve's ends
//! and reflection points are the ray's, and `Σ ds / c` over the samples is the ray's time;
//! and the picture's polylines are these curves, not chords.

use eigenray::options::Run;
use eigenray::trace::ray_curve;
use eigenray::{Arrival, Point, Scene, Tracer};

fn example() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/profile_slope.json"
    ))
    .unwrap()
}

/// A waveguide with a flat surface at 0 and a bottom sloping from −95 m to −118 m at 2 km
/// and −125 m at 7 km, five knots, a source at 40 m depth and a receiver at 60 m, 5 km, two
/// bottom reflections (rays of 2 and 3 turning points, on both of the bottom's segments).
const TWO_BOUNCES: &str = r#"{
  "media": { "water": { "profile": [[20, 1521], [-30, 1512], [-70, 1496], [-130, 1493],
                                    [-230, 1506]] } },
  "background": "water",
  "interfaces": {
    "surface": { "points": [[-1000, 0], [7000, 0]], "reflection": "pressure-release" },
    "bottom": { "points": [[-1000, -95], [2000, -118], [7000, -125]], "reflection": "rigid" } },
  "sources": [[0, -40]], "receivers": [[5000, -60]],
  "paths": [{ "steps": [{ "reflect": "bottom" }, { "reflect": "bottom" }],
              "media": ["water", "water", "water"] }]
}"#;

/// The speed of piecewise-linear `knots` (descending `y`) at `y`, uniform beyond the ends.
fn speed(knots: &[[f64; 2]], y: f64) -> f64 {
    let n = knots.len();
    if y >= knots[0][0] {
        return knots[0][1];
    }
    if y <= knots[n - 1][0] {
        return knots[n - 1][1];
    }
    let i = knots.iter().position(|k| k[0] <= y).unwrap();
    let ([y0, c0], [y1, c1]) = (knots[i - 1], knots[i]);
    c0 + (c1 - c0) * (y - y0) / (y1 - y0)
}

/// The layer of `y` (how many knots lie at or above it).
fn layer(knots: &[[f64; 2]], y: f64) -> usize {
    knots.iter().filter(|k| k[0] >= y).count()
}

/// The circle a chord `c` inside one layer lies on where the layer has a slope `g`: the
/// ray there is a circle of radius `1/(p |g|)` centred where the layer's speed is 0, so the
/// centre is on the chord's bisector at that height. `None` in a uniform layer.
fn circle(knots: &[[f64; 2]], c: &[Point]) -> Option<(f64, Point)> {
    let (d, mid) = (c[1] - c[0], 0.5 * (c[0].y + c[1].y));
    let i = layer(knots, mid);
    if i == 0 || i == knots.len() || knots[i - 1][1] == knots[i][1] {
        return None;
    }
    let ([y0, c0], [y1, c1]) = (knots[i - 1], knots[i]);
    let g = (c1 - c0) / (y1 - y0);
    let yc = y0 - c0 / g;
    let t = (yc - mid) / d.x;
    Some((g, Point::new(0.5 * (c[0].x + c[1].x) - t * d.y, yc)))
}

/// The ray's unit direction at end `end` of the chord `c` (inside one layer): the circle's
/// tangent there, turned the chord's way; in a uniform layer the chord's.
fn direction(knots: &[[f64; 2]], c: &[Point], end: usize) -> eigenray::Vec2 {
    let d = c[1] - c[0];
    let along = match circle(knots, c) {
        None => d,
        Some((_, centre)) => {
            let t = (c[end] - centre).perp();
            if t.dot(d) < 0.0 { t * -1.0 } else { t }
        }
    };
    along * (1.0 / along.length())
}

/// The worst figures of a scene's curves.
#[derive(Default, Debug)]
struct Worst {
    /// Relative spread of the chords' `cos φ / c` within a leg.
    invariant: f64,
    /// The angle between a reflection's chords' mirror images, radians.
    reflection: f64,
    /// `|Σ ds / c − T| / T`.
    time: f64,
    /// The curves checked.
    curves: usize,
    /// The least, over the curves, of the farthest a curve's sample lies from its leg's
    /// chord, m.
    least_bulge: f64,
}

/// Checks the curves (`n` samples each) of every arrival of every path of `scene` (its
/// medium `water`'s knots `knots`).
fn check_curves(scene: &Scene, knots: &[[f64; 2]], n: usize) -> Worst {
    let tracer = Tracer::new(scene.clone()).unwrap();
    let mut worst = Worst {
        least_bulge: f64::INFINITY,
        ..Worst::default()
    };
    for path in 0..scene.paths().len() {
        let mut found: Vec<Arrival> = Vec::new();
        let (s, r) = (scene.sources()[0], scene.receivers()[0]);
        tracer
            .stationary_paths(s, r, path, &Run::new(), &mut found)
            .unwrap();
        for a in found.iter().filter(|a| a.status.has_time()) {
            let curve = ray_curve(scene, &a.points, &a.media, a.launch_angle, n).unwrap();
            assert_eq!(curve.len(), n);
            check_one(scene, knots, a, &curve, &mut worst);
            worst.curves += 1;
        }
    }
    worst
}

/// One arrival's curve against the checks of the module's head.
fn check_one(scene: &Scene, knots: &[[f64; 2]], a: &Arrival, curve: &[Point], w: &mut Worst) {
    assert_eq!(curve[0], a.points[0]);
    assert_eq!(curve[curve.len() - 1], a.points[a.points.len() - 1]);
    // Each reflection point is a sample; the legs are the runs between them.
    let mut cuts = vec![0];
    for q in &a.points[1..a.points.len() - 1] {
        let at = (cuts[cuts.len() - 1] + 1..curve.len())
            .find(|&i| curve[i] == *q)
            .unwrap_or_else(|| panic!("reflection {q:?} is not a sample"));
        cuts.push(at);
    }
    cuts.push(curve.len() - 1);
    // The time along the samples (midpoint rule on each chord).
    let time: f64 = curve
        .windows(2)
        .map(|c| c[0].distance(c[1]) / speed(knots, 0.5 * (c[0].y + c[1].y)))
        .sum();
    w.time = w.time.max((time - a.time).abs() / a.time);
    // `p` of a chord inside one layer: of its circle's radius, or its direction.
    let invariant = |c: &[Point]| match circle(knots, c) {
        None => {
            let d = c[1] - c[0];
            d.x.abs() / d.length() / speed(knots, 0.5 * (c[0].y + c[1].y))
        }
        Some((g, centre)) => 1.0 / (g.abs() * centre.distance(c[0])),
    };
    let mut bulge = 0.0f64;
    for leg in cuts.windows(2) {
        let samples = &curve[leg[0]..=leg[1]];
        assert!(samples.len() > 8, "{} samples on a leg", samples.len());
        let ps: Vec<f64> = samples
            .windows(2)
            .filter(|c| layer(knots, c[0].y) == layer(knots, c[1].y))
            .map(invariant)
            .collect();
        let (lo, hi) = ps
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), &p| (l.min(p), h.max(p)));
        assert!(ps.len() > samples.len() / 2, "{} chords", ps.len());
        w.invariant = w.invariant.max((hi - lo) / hi);
        // Not its chord: the leg's curve leaves the straight line between its ends.
        let (p, q) = (samples[0], samples[samples.len() - 1]);
        let off = samples
            .iter()
            .map(|x| ((q - p).cross(*x - p) / (q - p).length()).abs())
            .fold(0.0f64, f64::max);
        bulge = bulge.max(off);
    }
    assert!(
        bulge > 1.0,
        "the curve is {bulge} m from its chords at most"
    );
    w.least_bulge = w.least_bulge.min(bulge);
    // The law of reflection at each wall, from the chords either side.
    for &at in &cuts[1..cuts.len() - 1] {
        let q = curve[at];
        let line = scene
            .interfaces()
            .iter()
            .map(|i| &i.polyline)
            .min_by(|x, y| x.nearest(q).distance.total_cmp(&y.nearest(q).distance))
            .unwrap();
        let seg = line.nearest(q).seg;
        let n = line.tangent(seg).perp();
        let (into, away) = (
            direction(knots, &curve[at - 1..=at], 1),
            direction(knots, &curve[at..=at + 1], 0),
        );
        let mirrored = into - n * (2.0 * into.dot(n));
        w.reflection = w.reflection.max(mirrored.cross(away).abs());
    }
}

/// The example's rays and the two-bounce scene's: on their rays by every check.
#[test]
fn sloped_curves_lie_on_their_rays() {
    let example = Scene::from_json(&example()).unwrap();
    let example_knots = [
        [0.0, 1500.0],
        [-20.0, 1497.0],
        [-50.0, 1490.0],
        [-80.0, 1488.0],
        [-150.0, 1489.0],
    ];
    let a = check_curves(&example, &example_knots, 4000);
    let two = Scene::from_json(TWO_BOUNCES).unwrap();
    let knots = [
        [20.0, 1521.0],
        [-30.0, 1512.0],
        [-70.0, 1496.0],
        [-130.0, 1493.0],
        [-230.0, 1506.0],
    ];
    let b = check_curves(&two, &knots, 4000);
    println!("example: {a:?}\ntwo bounces: {b:?}");
    assert!(a.curves >= 3 && b.curves >= 3, "{a:?} {b:?}");
    for w in [a, b] {
        assert!(w.invariant < 1e-10, "{w:?}");
        assert!(w.reflection < 1e-10, "{w:?}");
        assert!(w.time < 1e-8, "{w:?}");
    }
}

/// `eigenray solve --svg` of the example: each ray's polyline, mapped back to the scene's
/// coordinates through its ends (the source and the receiver), has many points, passes
/// through the ray's reflection points (within 0.05 m), lies on the ray's curve from `ray_curve` (within 1 mm of its dense sampling) and
/// leaves the straight chords between the ray's points by metres: curves, not chords.
#[test]
fn the_svg_draws_sloped_rays_as_their_curves() {
    let dir = std::env::temp_dir().join(format!("eigenray-svg-slope-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("slope.svg");
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/profile_slope.json"
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_eigenray"))
        .args(["solve", file, "--svg"])
        .arg(&svg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let timed: Vec<&serde_json::Value> = (doc["rays"].as_array().unwrap().iter())
        .filter(|r| !r["time"].is_null())
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
    assert_eq!(lines.len(), timed.len());
    assert!(lines.len() >= 3, "{}", lines.len());
    let scene = Scene::from_json(&example()).unwrap();
    let (s, r) = ([0.0, -30.0], [3000.0, -60.0]);
    let (mut least_off, mut worst_on) = (f64::INFINITY, 0.0f64);
    for (pixels, ray) in lines.iter().zip(&timed) {
        assert!(pixels.len() > 64, "{}", pixels.len());
        let (p0, p1) = (pixels[0], pixels[pixels.len() - 1]);
        let world: Vec<Point> = pixels
            .iter()
            .map(|p| {
                Point::new(
                    s[0] + (p[0] - p0[0]) / (p1[0] - p0[0]) * (r[0] - s[0]),
                    s[1] + (p[1] - p0[1]) / (p1[1] - p0[1]) * (r[1] - s[1]),
                )
            })
            .collect();
        let points: Vec<Point> = serde_json::from_value::<Vec<[f64; 2]>>(ray["points"].clone())
            .unwrap()
            .into_iter()
            .map(|[x, y]| Point::new(x, y))
            .collect();
        let water = scene.medium_index("water").unwrap();
        let media: Vec<usize> = vec![water; points.len() - 1];
        let launch = ray["launch_angle"].as_f64();
        let dense = ray_curve(&scene, &points, &media, launch, 20_000).unwrap();
        let to_polyline = |q: Point, line: &[Point]| {
            line.windows(2)
                .map(|w| segment_distance(q, w[0], w[1]))
                .fold(f64::INFINITY, f64::min)
        };
        for q in &points {
            let near = (world.iter())
                .map(|w| w.distance(*q))
                .fold(f64::INFINITY, f64::min);
            assert!(near < 0.05, "{q:?}: {near}");
        }
        let mut off = 0.0f64;
        for w in &world {
            let on = to_polyline(*w, &dense);
            assert!(on < 1e-3, "{w:?} is {on} m off the ray's curve");
            worst_on = worst_on.max(on);
            off = off.max(to_polyline(*w, &points));
        }
        least_off = least_off.min(off);
    }
    println!(
        "the picture's rays: within {worst_on:.1e} m of their curves, each at least \
         {least_off:.1} m from its chords somewhere"
    );
    assert!(least_off > 5.0, "{least_off}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The distance from `p` to the segment `a–b`.
fn segment_distance(p: Point, a: Point, b: Point) -> f64 {
    let d = b - a;
    let t = ((p - a).dot(d) / d.dot(d)).clamp(0.0, 1.0);
    p.distance(a + d * t)
}
