//! A `profile` medium between flat horizontal reflecting walls (the ocean: a surface above,
//! a bottom below), against independent references: an isovelocity profile against the
//! uniform medium (the image method: the beam tree's search and the straight-leg solve), a
//! linear profile against the same medium given as a `gradient` (the arc kernel with a
//! reflect step), and the streaming search against the listed one.

use std::sync::Mutex;

use eigenray::options::Run;
use eigenray::{Scene, Status, Tracer};

/// A waveguide 100 deep: a pressure-release surface at 0, a `"media"` bottom at −100 over
/// mud, the water `water` (a JSON object), and `extra` keys.
fn guide(water: &str, extra: &str) -> Scene {
    Scene::from_json(&format!(
        r#"{{ "media": {{ "water": {water},
                         "mud": {{ "speed": 1700, "density": 1.8, "at": [0, -150] }},
                         "air": {{ "speed": 340, "density": 0.0012, "at": [0, 50] }} }},
             "domain": [[-3000, -300], [6000, 100]],
             "interfaces": {{
                 "surface": {{ "points": [[-3000, 0], [6000, 0]], "reflection": "pressure-release" }},
                 "bottom": {{ "points": [[-3000, -100], [6000, -100]], "reflection": "media" }} }},
             "sources": [[0, -30], [100, -85]],
             "receivers": [[1000, -70], [2500, -10], [-1500, -50.5], [100, -40]],
             "amplitudes": {{ "source": "point" }} {extra} }}"#
    ))
    .unwrap()
}

const ISO: &str = r#"{ "profile": [[0, 1500], [-100, 1500]], "at": [0, -50] }"#;
const UNIFORM: &str = r#"{ "speed": 1500, "at": [0, -50] }"#;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

/// An isovelocity profile (two knots, one speed) between the walls is the uniform medium:
/// its search lists exactly the image method's arrivals (the beam tree's), with times to
/// 1e-12 and amplitudes (a pressure-release surface, an angle-dependent `"media"` bottom)
/// to 1e-9; and prescribed paths give the same, in the default mode and with
/// `"stationary": "all"`.
#[test]
fn isovelocity_between_walls_is_the_image_method() {
    let search = r#", "search": { "max_steps": 6 }"#;
    let (iso, uniform) = (guide(ISO, search), guide(UNIFORM, search));
    let a = Tracer::new(&iso).unwrap().search(&Run::new()).unwrap();
    let b = Tracer::new(&uniform).unwrap().search(&Run::new()).unwrap();
    assert_eq!(a.arrivals.len(), b.arrivals.len());
    assert!(a.arrivals.len() > 50, "{}", a.arrivals.len());
    let (mut worst_t, mut worst_a) = (0.0f64, 0.0f64);
    for x in &a.arrivals {
        let y = b
            .arrivals
            .iter()
            .find(|y| (y.source, y.receiver, &y.steps) == (x.source, x.receiver, &x.steps))
            .unwrap_or_else(|| panic!("{:?} not in the image method's", x.steps));
        assert!(!x.complete);
        assert_eq!(x.arrival.turns, Some(0));
        assert_eq!(x.arrival.caustics, Some(0));
        worst_t = worst_t.max(rel(x.arrival.time, y.arrival.time));
        let (ax, ay) = (x.arrival.amplitude.unwrap(), y.arrival.amplitude.unwrap());
        worst_a = worst_a.max((ax.value - ay.value).norm() / ay.value.norm());
        for (p, q) in x.arrival.points.iter().zip(&y.arrival.points) {
            assert!((p.x - q.x).abs() < 1e-9 && p.y == q.y, "{p:?} {q:?}");
        }
    }
    println!(
        "isovelocity guide: {} arrivals, time {worst_t:e}, amplitude {worst_a:e}",
        a.arrivals.len()
    );
    assert!(worst_t < 1e-12 && worst_a < 1e-9, "{worst_t:e} {worst_a:e}");

    // Prescribed paths: each sequence of up to three reflections, default mode and all.
    let seqs = [
        r#"[{"reflect": "surface"}]"#,
        r#"[{"reflect": "bottom"}]"#,
        r#"[{"reflect": "surface"}, {"reflect": "bottom"}]"#,
        r#"[{"reflect": "bottom"}, {"reflect": "surface"}, {"reflect": "bottom"}]"#,
    ];
    let paths: Vec<String> = seqs
        .iter()
        .map(|s| format!(r#"{{ "steps": {s} }}"#))
        .collect();
    let extra = format!(r#", "paths": [{}]"#, paths.join(","));
    let (iso, uniform) = (guide(ISO, &extra), guide(UNIFORM, &extra));
    let (ti, tu) = (Tracer::new(&iso).unwrap(), Tracer::new(&uniform).unwrap());
    let (ri, ru) = (ti.trace_all(), tu.trace_all());
    assert_eq!(ri.len(), ru.len());
    for (x, y) in ri.iter().zip(&ru) {
        assert_eq!(x.status, y.status);
        if y.status == Status::Converged {
            assert!(rel(x.time, y.time) < 1e-12, "{} {}", x.time, y.time);
            let (ax, ay) = (x.amplitude.unwrap(), y.amplitude.unwrap());
            assert!((ax.value - ay.value).norm() < 1e-9 * ay.value.norm());
        }
    }
    for &s in iso.sources() {
        for &r in iso.receivers() {
            for k in 0..seqs.len() {
                let (mut a, mut b) = (Vec::new(), Vec::new());
                ti.stationary_paths(s, r, k, &Run::new(), &mut a).unwrap();
                tu.stationary_paths(s, r, k, &Run::new(), &mut b).unwrap();
                assert_eq!(a.len(), b.len(), "{s:?} {r:?} {k}");
                for (x, y) in a.iter().zip(&b) {
                    assert!(rel(x.time, y.time) < 1e-12);
                }
            }
        }
    }
}

/// A linear profile (c = 1500 + 0.017 depth) over a flat bottom: each ray with one bottom
/// reflection is the `gradient` medium's path with one reflect step (circular arcs, the arc
/// kernel's Newton solve), times to 1e-9 and the same reflection point.
#[test]
fn linear_profile_reflection_is_the_gradient_medium() {
    let make = |medium: &str| {
        Scene::from_json(&format!(
            r#"{{ "media": {{ "sea": {medium} }},
                 "interfaces": {{ "bottom": {{ "points": [[-20000, -1000], [40000, -1000]] }} }},
                 "sources": [[0, -300], [0, -900]],
                 "receivers": [[1000, -200], [5000, -800], [-8000, -500], [15000, -950], [300, -20]],
                 "paths": [{{ "steps": [{{ "reflect": "bottom" }}], "media": ["sea", "sea"] }}],
                 "solver": {{ "stationary": "all" }} }}"#
        ))
        .unwrap()
    };
    let profile = make(r#"{ "profile": [[0, 1500], [-1000, 1517]] }"#);
    let gradient = make(r#"{ "speed": 1500, "gradient": [0, -0.017] }"#);
    let (tp, tg) = (
        Tracer::new(&profile).unwrap(),
        Tracer::new(&gradient).unwrap(),
    );
    let mut worst = 0.0f64;
    let mut count = 0;
    for &s in profile.sources() {
        for &r in profile.receivers() {
            let (mut a, mut b) = (Vec::new(), Vec::new());
            tp.stationary_paths(s, r, 0, &Run::new(), &mut a).unwrap();
            tg.stationary_paths(s, r, 0, &Run::new(), &mut b).unwrap();
            let b: Vec<_> = b
                .into_iter()
                .filter(|x| x.status == Status::Converged)
                .collect();
            assert_eq!(a.len(), b.len(), "{s:?} {r:?}: {a:?} {b:?}");
            for (x, y) in a.iter().zip(&b) {
                worst = worst.max(rel(x.time, y.time));
                assert!(
                    (x.points[1] - y.points[1]).length() < 1e-6,
                    "{:?} {:?}",
                    x.points,
                    y.points
                );
                count += 1;
            }
        }
    }
    println!("linear profile, one reflection: {count} rays, time {worst:e}");
    assert!(count >= 8 && worst < 1e-9, "{count} {worst:e}");
}

/// The streaming search hands on the arrivals the listed one lists (count, times and
/// amplitudes bit for bit), and `max_time` bounds both.
#[test]
fn streamed_search_is_the_listed_one() {
    let scene = guide(ISO, r#", "search": { "max_steps": 8, "max_time": 1.2 }"#);
    let tracer = Tracer::new(&scene).unwrap();
    let listed = tracer.search(&Run::new()).unwrap().arrivals;
    assert!(
        listed
            .iter()
            .all(|a| a.arrival.time <= 1.2 && a.steps.len() <= 8)
    );
    let got = Mutex::new(Vec::new());
    let report = tracer
        .search_into(&Run::new(), &|a| {
            got.lock()
                .unwrap()
                .push((a.source, a.receiver, a.time, a.amplitude.unwrap().value))
        })
        .unwrap();
    let mut got = got.into_inner().unwrap();
    assert_eq!(report.arrivals as usize, listed.len());
    // (Arrivals of equal time, the mirror images of each other, come in either order.)
    let key = |x: &(usize, usize, f64, num_complex::Complex64)| {
        (x.0, x.1, x.2.to_bits(), x.3.re.to_bits(), x.3.im.to_bits())
    };
    let mut want: Vec<_> = listed
        .iter()
        .map(|l| {
            (
                l.source,
                l.receiver,
                l.arrival.time,
                l.arrival.amplitude.unwrap().value,
            )
        })
        .collect();
    got.sort_by_key(key);
    want.sort_by_key(key);
    assert_eq!(
        got.iter().map(key).collect::<Vec<_>>(),
        want.iter().map(key).collect::<Vec<_>>()
    );
}
