//! Paths of reflections through a `profile` medium off sloping walls (a sloping bottom, a
//! bottom of two segments): each leg the profile's ray between its ends, the path stationary
//! in its reflection points, against independent references — the image method where the
//! profile is isovelocity (times and amplitudes), the `gradient` medium's arcs where the
//! profile is one linear layer, and a Munk profile's knots stepped finer.

use eigenray::options::Run;
use eigenray::{Arrival, Scene, Status, Tracer};

type P = [f64; 2];

/// A waveguide: a flat pressure-release surface at 0 and a rigid bottom `bottom` (points),
/// the medium `medium` (a JSON object), one source and one receiver, the paths `paths`.
fn scene(medium: &str, bottom: &str, source: P, receiver: P, paths: &str) -> Scene {
    Scene::from_json(&format!(
        r#"{{ "media": {{ "water": {medium} }},
             "interfaces": {{
               "surface": {{ "points": [[-500, 0], [12000, 0]], "reflection": "pressure-release" }},
               "bottom": {{ "points": {bottom}, "reflection": "rigid" }} }},
             "sources": [{source:?}], "receivers": [{receiver:?}],
             "paths": {paths},
             "amplitudes": {{ "source": "point" }} }}"#
    ))
    .unwrap()
}

/// Every stationary path of path `path` of the scene's one pair, by time.
fn arrivals(scene: &Scene, path: usize) -> Vec<Arrival> {
    let tracer = Tracer::new(scene).unwrap();
    let mut out = Vec::new();
    tracer
        .stationary_paths(
            scene.sources()[0],
            scene.receivers()[0],
            path,
            &Run::new(),
            &mut out,
        )
        .unwrap();
    out.retain(|a| a.status == Status::Converged);
    out
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

/// `p` mirrored in the line through `a` and `b`.
fn mirror(p: P, a: P, b: P) -> P {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2;
    let f = [a[0] + t * d[0], a[1] + t * d[1]];
    [2.0 * f[0] - p[0], 2.0 * f[1] - p[1]]
}

/// The image method: every path from `s` to `r` reflecting off the segments `walls[i]`
/// chosen per step from `choices[i]`, each reflection inside its segment; its unfolded
/// length and its reflection points.
fn images(s: P, r: P, choices: &[Vec<(P, P)>]) -> Vec<(f64, Vec<P>)> {
    let k = choices.len();
    let mut out = Vec::new();
    let mut index = vec![0usize; k];
    loop {
        let walls: Vec<(P, P)> = (0..k).map(|i| choices[i][index[i]]).collect();
        // Images of the receiver, last wall first.
        let mut img = vec![r; k + 1];
        for i in (0..k).rev() {
            img[i] = mirror(img[i + 1], walls[i].0, walls[i].1);
        }
        let length = ((img[0][0] - s[0]).powi(2) + (img[0][1] - s[1]).powi(2)).sqrt();
        let mut from = s;
        let mut points = Vec::new();
        let mut inside = true;
        for i in 0..k {
            let (a, b) = walls[i];
            let (p, q) = (from, img[i]);
            // Where p–q meets the line a–b, and where along a–b.
            let d = [q[0] - p[0], q[1] - p[1]];
            let e = [b[0] - a[0], b[1] - a[1]];
            let den = d[0] * e[1] - d[1] * e[0];
            let t = ((a[0] - p[0]) * e[1] - (a[1] - p[1]) * e[0]) / den;
            let u = ((a[0] - p[0]) * d[1] - (a[1] - p[1]) * d[0]) / den;
            inside &= (0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u);
            let x = [p[0] + t * d[0], p[1] + t * d[1]];
            points.push(x);
            from = x;
        }
        if inside {
            out.push((length, points));
        }
        let mut i = 0;
        loop {
            if i == k {
                out.sort_by(|x, y| x.0.total_cmp(&y.0));
                return out;
            }
            index[i] += 1;
            if index[i] < choices[i].len() {
                break;
            }
            index[i] = 0;
            i += 1;
        }
    }
}

/// Two knots of one speed over a sloping bottom and over a bottom of two segments: every
/// path the image method has (each reflection inside its segment), no other, times to
/// 1e-12, reflection points to 1e-9 of the range, amplitudes (spreading 1/(4πL), the
/// surface's −1) to 1e-10.
#[test]
fn isovelocity_over_a_sloping_bottom_is_the_image_method() {
    let c = 1500.0;
    let surface = ([-500.0, 0.0], [12000.0, 0.0]);
    let (s, r) = ([0.0, -30.0], [2000.0, -60.0]);
    let bottoms: [&[P]; 2] = [
        &[[-500.0, -100.0], [12000.0, -130.0]],
        &[[-500.0, -100.0], [900.0, -125.0], [12000.0, -110.0]],
    ];
    let paths = r#"[{ "steps": [{ "reflect": "bottom" }] },
        { "steps": [{ "reflect": "surface" }, { "reflect": "bottom" }] },
        { "steps": [{ "reflect": "bottom" }, { "reflect": "surface" }] },
        { "steps": [{ "reflect": "bottom" }, { "reflect": "surface" }, { "reflect": "bottom" }] }]"#;
    let walls = [
        vec!["bottom"],
        vec!["surface", "bottom"],
        vec!["bottom", "surface"],
        vec!["bottom", "surface", "bottom"],
    ];
    let (mut checked, mut worst_t, mut worst_a) = (0, 0.0f64, 0.0f64);
    for bottom in bottoms {
        let text = format!("{bottom:?}");
        let sc = scene(
            r#"{ "profile": [[0, 1500], [-200, 1500]], "at": [0, -50] }"#,
            &text,
            s,
            r,
            paths,
        );
        let segments: Vec<(P, P)> = bottom.windows(2).map(|w| (w[0], w[1])).collect();
        for (path, names) in walls.iter().enumerate() {
            let choices: Vec<Vec<(P, P)>> = names
                .iter()
                .map(|n| {
                    if *n == "surface" {
                        vec![surface]
                    } else {
                        segments.clone()
                    }
                })
                .collect();
            let want = images(s, r, &choices);
            let got = arrivals(&sc, path);
            assert_eq!(got.len(), want.len(), "{text} path {path}: {got:?}");
            for (a, (length, points)) in got.iter().zip(&want) {
                let t = length / c;
                assert!(rel(a.time, t) <= 1e-12, "{text} {path}: {} {t}", a.time);
                for (p, q) in a.points[1..a.points.len() - 1].iter().zip(points) {
                    assert!((p.x - q[0]).abs().max((p.y - q[1]).abs()) <= 1e-9 * 2000.0);
                }
                let amp = a.amplitude.as_ref().unwrap().value;
                let sign = if names.iter().filter(|n| **n == "surface").count() % 2 == 1 {
                    -1.0
                } else {
                    1.0
                };
                let want_amp = sign / (4.0 * std::f64::consts::PI * length);
                (worst_t, worst_a) = (
                    worst_t.max(rel(a.time, t)),
                    worst_a.max(rel(amp.re, want_amp)),
                );
                assert!(
                    rel(amp.re, want_amp) <= 1e-10 && amp.im.abs() <= 1e-10 * want_amp.abs(),
                    "{amp} {want_amp}"
                );
                assert_eq!((a.turns, a.caustics), (Some(0), Some(0)));
                checked += 1;
            }
        }
    }
    eprintln!("{checked} image paths: times {worst_t:.1e}, amplitudes {worst_a:.1e} relative");
    assert!(checked >= 8, "{checked}");
}

/// One linear layer over a sloping bottom of two segments is the `gradient` medium (exact
/// arcs): the same arrivals of each path, times to 1e-12.
#[test]
fn one_layer_over_a_sloping_bottom_is_the_gradient_medium() {
    let bottom = "[[-500, -800], [4000, -1000], [12000, -900]]";
    let (s, r) = ([0.0, -300.0], [7000.0, -500.0]);
    let paths = r#"[{ "steps": [{ "reflect": "bottom" }] },
        { "steps": [{ "reflect": "surface" }, { "reflect": "bottom" }] }]"#;
    let profile = scene(
        r#"{ "profile": [[0, 1500], [-1000, 1517]], "at": [0, -50] }"#,
        bottom,
        s,
        r,
        paths,
    );
    let gradient = scene(
        r#"{ "speed": 1500, "gradient": [0, -0.017], "at": [0, -50] }"#,
        bottom,
        s,
        r,
        paths,
    );
    let (mut checked, mut worst) = (0, 0.0f64);
    for path in 0..2 {
        let (a, b) = (arrivals(&profile, path), arrivals(&gradient, path));
        assert_eq!(a.len(), b.len(), "path {path}: {a:?} {b:?}");
        for (x, y) in a.iter().zip(&b) {
            worst = worst.max(rel(x.time, y.time));
            assert!(
                rel(x.time, y.time) <= 1e-12,
                "{path}: {} {}",
                x.time,
                y.time
            );
            for (p, q) in x.points.iter().zip(&y.points) {
                assert!(p.distance(*q) <= 1e-6, "{p:?} {q:?}");
            }
            checked += 1;
        }
    }
    eprintln!("{checked} arrivals as arcs: times {worst:.1e} relative");
    assert!(checked >= 2, "{checked}");
}

/// A Munk profile over a bottom sloping from 4000 to 4300 and back to 3800, 10 km: with the
/// knots 200, 100 and 50 m apart the arrivals of a bottom reflection are the same rays, and
/// their times change only as the piecewise-linear profile does (to second order in the
/// step: each halving at least halves the change, and the last is below 1 ms).
#[test]
fn munk_over_a_sloping_bottom_converges_with_the_knots() {
    let munk = |step: usize| {
        let knots: Vec<String> = (0..=5000)
            .step_by(step)
            .map(|z| {
                let e = 2.0 * (z as f64 - 1300.0) / 1300.0;
                let c = 1500.0 * (1.0 + 0.00737 * (e - 1.0 + (-e).exp()));
                format!("[{}, {c}]", -(z as f64))
            })
            .collect();
        format!(
            r#"{{ "profile": [{}], "at": [0, -1000] }}"#,
            knots.join(", ")
        )
    };
    let bottom = "[[-500, -4000], [5000, -4300], [12000, -3800]]";
    let paths = r#"[{ "steps": [{ "reflect": "bottom" }] }]"#;
    let times: Vec<Vec<f64>> = [200, 100, 50]
        .iter()
        .map(|&step| {
            let sc = scene(
                &munk(step),
                bottom,
                [0.0, -1000.0],
                [10000.0, -1500.0],
                paths,
            );
            arrivals(&sc, 0).iter().map(|a| a.time).collect()
        })
        .collect();
    assert!(!times[0].is_empty());
    assert!(times.iter().all(|t| t.len() == times[0].len()), "{times:?}");
    for (j, ((t0, t1), t2)) in times[0].iter().zip(&times[1]).zip(&times[2]).enumerate() {
        let (d1, d2) = ((t0 - t1).abs(), (t1 - t2).abs());
        eprintln!("arrival {j}: {t2:.9} s; 200 → 100 m knots {d1:.2e} s, 100 → 50 m {d2:.2e} s");
        assert!(d2 <= 0.5 * d1 && d2 < 1e-3, "{j}: {d1:e} {d2:e}");
    }
}

/// A sequence of walls: their names, and per step the segments it may reflect off.
type Sequence = (Vec<&'static str>, Vec<Vec<(P, P)>>);

/// Every sequence of `n` walls or fewer off a flat surface and the bottom's segments (no two
/// surfaces in a row): per step, the segments it may reflect off, and the names.
fn sequences(n: usize, surface: (P, P), bottom: &[(P, P)]) -> Vec<Sequence> {
    let mut out = vec![(Vec::new(), Vec::new())];
    let mut last: Vec<Sequence> = vec![(Vec::new(), Vec::new())];
    for _ in 0..n {
        let mut next = Vec::new();
        for (names, choices) in &last {
            for wall in ["surface", "bottom"] {
                if wall == "surface" && names.last() == Some(&"surface") {
                    continue;
                }
                let (mut names, mut choices) = (names.clone(), choices.clone());
                names.push(wall);
                choices.push(if wall == "surface" {
                    vec![surface]
                } else {
                    bottom.to_vec()
                });
                next.push((names, choices));
            }
        }
        out.extend(next.iter().cloned());
        last = next;
    }
    out
}

/// The search off a sloping bottom (and a bottom of two segments: a valley) in an
/// isovelocity profile is the image method: every image path of up to `max_steps` walls
/// (each reflection inside its segment; the water is convex, so none is obstructed), and,
/// with `max_time` alone, every image path arriving by then; no other arrival, the same
/// walls, times to 1e-12, reflection points to 1e-9 of the range.
#[test]
fn search_over_a_sloping_bottom_is_the_image_method() {
    let c = 1500.0;
    let surface = ([-500.0, 0.0], [12000.0, 0.0]);
    let bottoms: [&[P]; 2] = [
        &[[-500.0, -100.0], [12000.0, -130.0]],
        &[[-500.0, -100.0], [900.0, -125.0], [12000.0, -110.0]],
    ];
    let pairs: [(P, P); 3] = [
        ([0.0, -30.0], [2000.0, -60.0]),
        ([0.0, -30.0], [-400.0, -90.0]),
        ([100.0, -80.0], [4000.0, -15.0]),
    ];
    let (mut checked, mut worst) = (0, 0.0f64);
    for bottom in bottoms {
        let segments: Vec<(P, P)> = bottom.windows(2).map(|w| (w[0], w[1])).collect();
        for (s, r) in pairs {
            for search in [r#"{ "max_steps": 3 }"#, "MAX_TIME"] {
                // The time bound: the direct path's time plus 2.5 %.
                let direct = ((r[0] - s[0]).powi(2) + (r[1] - s[1]).powi(2)).sqrt() / c;
                let limit = (search == "MAX_TIME").then_some(direct * 1.025);
                let search = match limit {
                    Some(t) => format!(r#"{{ "max_time": {t:e} }}"#),
                    None => search.to_string(),
                };
                let text = format!("{bottom:?}");
                let sc = scene(
                    r#"{ "profile": [[0, 1500], [-200, 1500]], "at": [0, -50] }"#,
                    &text,
                    s,
                    r,
                    &format!(r#"[], "search": {search}"#),
                );
                let depth = if limit.is_some() { 12 } else { 3 };
                let mut want: Vec<(f64, Vec<&str>, Vec<P>)> = Vec::new();
                for (names, choices) in sequences(depth, surface, &segments) {
                    for (length, points) in images(s, r, &choices) {
                        // Two reflections in a row off one segment's line: no path (the
                        // image method's degenerate solution, both points one).
                        let twice = points.windows(2).any(|w| {
                            (w[0][0] - w[1][0]).abs().max((w[0][1] - w[1][1]).abs()) < 1e-6
                        });
                        if twice {
                            continue;
                        }
                        let t = length / c;
                        if limit.is_none_or(|l| t <= l) {
                            // The deepest sequences arrive after the bound.
                            assert!(names.len() < depth || limit.is_none(), "{names:?}");
                            want.push((t, names.clone(), points));
                        }
                    }
                }
                want.sort_by(|a, b| a.0.total_cmp(&b.0));
                let tracer = Tracer::new(&sc).unwrap();
                let got = tracer.search(&Run::new()).unwrap().arrivals;
                let what = format!("{text} {s:?} {r:?} {search}");
                assert_eq!(got.len(), want.len(), "{what}: {got:?}\n{want:?}");
                for (a, (t, names, points)) in got.iter().zip(&want) {
                    let walls: Vec<&str> = a
                        .steps
                        .iter()
                        .map(|st| sc.interfaces()[st.interface].name.as_str())
                        .collect();
                    assert_eq!(&walls, names, "{what}");
                    assert!(
                        rel(a.arrival.time, *t) <= 1e-12,
                        "{what}: {} {t}",
                        a.arrival.time
                    );
                    worst = worst.max(rel(a.arrival.time, *t));
                    let pts = &a.arrival.points;
                    for (p, q) in pts[1..pts.len() - 1].iter().zip(points) {
                        assert!((p.x - q[0]).abs().max((p.y - q[1]).abs()) <= 1e-9 * 4000.0);
                    }
                    assert!(!a.complete);
                    checked += 1;
                }
            }
        }
    }
    eprintln!("{checked} image paths found by the search: times {worst:.1e} relative");
    assert!(checked >= 60, "{checked}");
}

/// The search off a sloping bottom within its limits: `solver.max_work` stops each pair's
/// fan (fewer arrivals, each one of the full search's, the work reported within the limit
/// and one ray's overshoot), a run's budget stops it, a stop asked for before it lists
/// nothing; the path route's shooting (`stationary: all`) stops at `solver.max_work` too.
#[test]
fn the_search_over_a_slope_keeps_to_its_limits() {
    let bottom = "[[-500, -100], [900, -125], [12000, -110]]";
    let (s, r) = ([0.0, -30.0], [2000.0, -60.0]);
    let medium = r#"{ "profile": [[0, 1500], [-50, 1490], [-200, 1500]], "at": [0, -50] }"#;
    let full = scene(medium, bottom, s, r, r#"[], "search": { "max_steps": 3 }"#);
    let all = Tracer::new(&full).unwrap().search(&Run::new()).unwrap();
    assert!(all.arrivals.len() >= 6, "{:?}", all.arrivals);
    assert!(all.work > 400_000, "{}", all.work);
    let limited = scene(
        medium,
        bottom,
        s,
        r,
        r#"[], "search": { "max_steps": 3 }, "solver": { "max_work": 200000 }"#,
    );
    let some = Tracer::new(&limited).unwrap().search(&Run::new()).unwrap();
    assert!(some.work >= 200_000 && some.work < 220_000, "{}", some.work);
    assert!(some.arrivals.len() < all.arrivals.len());
    for a in &some.arrivals {
        assert!(
            all.arrivals
                .iter()
                .any(|b| b.steps == a.steps && rel(a.arrival.time, b.arrival.time) <= 1e-12),
            "{a:?}"
        );
    }
    let budget = Run::new().budget(100);
    let few = Tracer::new(&full).unwrap().search(&budget).unwrap();
    assert!(few.arrivals.len() < all.arrivals.len() && budget.stopped());
    let stopped = Run::new();
    stopped.request_stop();
    let none = Tracer::new(&full).unwrap().search(&stopped).unwrap();
    assert!(none.arrivals.is_empty());
    // The path route: a bottom reflection, all its arrivals, then within a small budget.
    let path = r#"[{ "steps": [{ "reflect": "bottom" }] }], "solver": { "max_work": 1000 }"#;
    let small = scene(medium, bottom, s, r, path);
    let unlimited = scene(
        medium,
        bottom,
        s,
        r,
        r#"[{ "steps": [{ "reflect": "bottom" }] }]"#,
    );
    assert!(!arrivals(&unlimited, 0).is_empty());
    assert!(arrivals(&small, 0).is_empty());
}

/// Where a reflection point crosses a vertex of the bottom, the ray's depth at the receiver
/// jumps, so one depth is reached once from each segment, within one step of the shooting's
/// grid of launch angles. BELLHOP (A-New-BellHope, `benches/bellhop_slope.py`) traced both
/// rays of each pair below through `examples/scenes/profile_slope.json`'s water and bottom:
/// at (3000, −20) the `sb` rays launched 4.9947° and 4.8960° above the horizontal (its
/// −4.9947° and −4.8960°: its angles are positive down), at (3000, −95) the `sbsbsbsb`
/// rays 17.2253° and 17.0435° above it, the second of each reflecting off
/// the bottom just past its vertex at 2 km. Both are found, converged, at BELLHOP's launch
/// angles to its printed digits, by the path's shooting and by the search's fan.
///
/// Mutants caught: neighbouring shots off different segments left unbracketed, in the
/// path's shooting and in the fan (one of each pair found).
#[test]
fn rays_reflecting_past_a_vertex_of_the_bottom_are_found() {
    let example: serde_json::Value =
        serde_json::from_str(include_str!("../examples/scenes/profile_slope.json")).unwrap();
    for (receiver, path, degrees) in [
        ([3000.0, -20.0], "sb", [4.9947, 4.8960]),
        ([3000.0, -95.0], "sbsbsbsb", [17.2253, 17.0435]),
    ] {
        let mut json = example.clone();
        json["receivers"] = serde_json::json!([receiver]);
        let steps: Vec<_> = path
            .chars()
            .map(|c| {
                let wall = if c == 's' { "surface" } else { "bottom" };
                serde_json::json!({ "reflect": wall })
            })
            .collect();
        json["paths"] = serde_json::json!([{ "name": path, "steps": steps }]);
        let scene = Scene::from_json(&json.to_string()).unwrap();
        let found = arrivals(&scene, 0);
        assert_eq!(found.len(), 2, "{path} at {receiver:?}: {found:?}");
        let mut angles: Vec<f64> = found
            .iter()
            .map(|a| a.launch_angle.expect("a launch angle").to_degrees())
            .collect();
        angles.sort_by(|a, b| b.total_cmp(a));
        for (got, want) in angles.iter().zip(degrees) {
            assert!(
                (got - want).abs() < 1e-4,
                "{path}: {got}° against BELLHOP's {want}°"
            );
        }
        // The search's fan (every sequence up to the path's length) finds both as well.
        json.as_object_mut().unwrap().remove("paths");
        json["solver"].as_object_mut().unwrap().remove("stationary");
        json["search"] = serde_json::json!({ "max_steps": path.len() });
        let search = Scene::from_json(&json.to_string()).unwrap();
        let report = Tracer::new(&search).unwrap().search(&Run::new()).unwrap();
        let surface = search.interface_index("surface").unwrap();
        let listed = (report.arrivals.iter())
            .filter(|a| {
                let walls: String = (a.steps.iter())
                    .map(|s| if s.interface == surface { 's' } else { 'b' })
                    .collect();
                walls == path
            })
            .count();
        assert_eq!(listed, 2, "the search's {path} arrivals at {receiver:?}");
    }
}
