//! The tracer's updates (`Tracer::set_source`, `set_receiver`, `set_interface_points`,
//! `set_medium_speed`, `set_medium_index`): after every update of a random sequence, the
//! tracer's rays are those of a tracer built afresh from the edited scene document, bit for
//! bit, and a refused update gives the document's own error and changes nothing; the edited
//! scene's document (`Scene::to_json`) reads back to the edited scene, bit for bit.

use eigenray::{BatchOptions, MediumSpec, Point, Scene, SceneError, SceneSpec, Tracer};

#[path = "support/rng.rs"]
mod rng;
use rng::SplitMix64;

/// Every result of a tracer in one string: `Debug` prints each `f64` so that it reads back to
/// the same bits, so equal strings are equal rays.
fn results(tracer: &Tracer, thorough: bool) -> String {
    let mut out = format!("{:?}", tracer.trace_all());
    out += &format!(
        "{:?}",
        tracer
            .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
            .unwrap()
            .to_rays()
    );
    if thorough {
        out += &format!(
            "{:?}",
            tracer.trace_stationary(&eigenray::options::Run::new())
        );
        if tracer.scene().search().is_some() {
            out += &format!("{:?}", tracer.search(&eigenray::options::Run::new()));
        }
    }
    out
}

/// A tracer built afresh from `spec`.
fn fresh(spec: &SceneSpec) -> Result<Tracer, SceneError> {
    Tracer::new(Scene::from_spec(spec)?)
}

/// One random update, applied to the spec and to the tracer.
enum Update {
    Source(usize, Point),
    Receiver(usize, Point),
    Interface(String, Vec<Point>),
    Speed(String, f64),
    Index(String, f64),
}

fn random_update(spec: &SceneSpec, rng: &mut SplitMix64) -> Update {
    let mut f = || rng.next_f64();
    let bbox = {
        let all: Vec<[f64; 2]> = spec
            .interfaces
            .values()
            .flat_map(|i| i.points.iter().copied())
            .chain(spec.sources.iter().copied())
            .chain(spec.receivers.list().unwrap().iter().copied())
            .collect();
        let lo = all
            .iter()
            .fold([f64::MAX; 2], |m, p| [m[0].min(p[0]), m[1].min(p[1])]);
        let hi = all
            .iter()
            .fold([f64::MIN; 2], |m, p| [m[0].max(p[0]), m[1].max(p[1])]);
        [lo, hi]
    };
    let anywhere = |f: &mut dyn FnMut() -> f64| {
        let [lo, hi] = bbox;
        let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
        Point::new(
            lo[0] - 0.1 * w + 1.2 * w * f(),
            lo[1] - 0.1 * h + 1.2 * h * f(),
        )
    };
    // Now and then a point exactly on an interface's vertex, or not finite.
    let awkward = |f: &mut dyn FnMut() -> f64, p: Point| -> Point {
        let u = f();
        if u < 0.06 {
            let iface: Vec<_> = spec.interfaces.values().collect();
            let i = iface[(f() * iface.len() as f64) as usize];
            let v = i.points[(f() * i.points.len() as f64) as usize];
            Point::new(v[0], v[1])
        } else if u < 0.08 {
            Point::new(f64::NAN, p.y)
        } else {
            p
        }
    };
    let pick = |u: f64, n: usize| ((u * n as f64) as usize).min(n - 1);
    match pick(f(), 5) {
        0 => {
            let k = pick(f(), spec.sources.len());
            let p = anywhere(&mut f);
            Update::Source(k, awkward(&mut f, p))
        }
        1 | 2 => {
            let k = pick(f(), spec.receivers.list().unwrap().len());
            let p = anywhere(&mut f);
            Update::Receiver(k, awkward(&mut f, p))
        }
        3 => {
            let names: Vec<&String> = spec.interfaces.keys().collect();
            let name = names[pick(f(), names.len())].clone();
            let points = &spec.interfaces[&name].points;
            let mut new: Vec<Point> = points.iter().map(|p| Point::new(p[0], p[1])).collect();
            let scale = (bbox[1][0] - bbox[0][0]).max(bbox[1][1] - bbox[0][1]);
            let j = pick(f(), new.len());
            let step = scale * if f() < 0.7 { 0.02 } else { 0.3 };
            let u = f();
            if u < 0.15 && new.len() > 3 {
                new.remove(j);
            } else if u < 0.3 {
                // A new vertex beside vertex j, towards the next one.
                let q = new[(j + 1) % new.len()];
                let m = new[j].lerp(q, 0.5);
                new.insert(
                    j + 1,
                    Point::new(m.x + step * (f() - 0.5), m.y + step * (f() - 0.5)),
                );
            } else {
                new[j] = Point::new(new[j].x + step * (f() - 0.5), new[j].y + step * (f() - 0.5));
            }
            Update::Interface(name, new)
        }
        _ => {
            let names: Vec<&String> = spec.media.keys().collect();
            let name = names[pick(f(), names.len())].clone();
            let v = if f() < 0.05 { -1.0 } else { 0.5 + 2.0 * f() };
            if f() < 0.5 {
                Update::Speed(name, v)
            } else {
                Update::Index(name, v)
            }
        }
    }
}

/// Applies `update` to a copy of `spec`.
fn edited(spec: &SceneSpec, update: &Update) -> SceneSpec {
    let mut spec = spec.clone();
    let xy = |p: &Point| [p.x, p.y];
    match update {
        Update::Source(k, p) => spec.sources[*k] = xy(p),
        Update::Receiver(k, p) => spec.receivers.points_mut()[*k] = xy(p),
        Update::Interface(name, pts) => {
            spec.interfaces.get_mut(name).unwrap().points = pts.iter().map(xy).collect();
        }
        Update::Speed(name, v) | Update::Index(name, v) => {
            let m = spec.media.get_mut(name).unwrap();
            let at = m.at;
            *m = MediumSpec {
                at,
                ..if matches!(update, Update::Speed(..)) {
                    MediumSpec::speed(*v)
                } else {
                    MediumSpec::index(*v)
                }
            };
        }
    }
    spec
}

/// Applies `update` to the tracer.
fn apply(tracer: &mut Tracer, update: &Update) -> Result<(), SceneError> {
    let scene = tracer.scene();
    match update {
        Update::Source(k, p) => tracer.set_source(*k, *p),
        Update::Receiver(k, p) => tracer.set_receiver(*k, *p),
        Update::Interface(name, pts) => {
            let i = scene.interface_index(name).unwrap();
            tracer.set_interface_points(i, pts)
        }
        Update::Speed(name, v) => {
            let m = scene.medium_index(name).unwrap();
            tracer.set_medium_speed(m, *v)
        }
        Update::Index(name, v) => {
            let m = scene.medium_index(name).unwrap();
            tracer.set_medium_index(m, *v)
        }
    }
}

/// `steps` random updates of `spec`'s tracer, each checked against a tracer built afresh.
/// Returns the numbers of updates accepted and refused.
fn random_updates(spec: SceneSpec, steps: usize, seed: u64) -> (usize, usize) {
    let mut rng = SplitMix64(seed);
    let mut spec = spec;
    let mut tracer = fresh(&spec).expect("a valid scene");
    let (mut accepted, mut refused) = (0, 0);
    // Accepted updates of each kind: sources, receivers, interfaces, media.
    let mut kinds = [0; 4];
    let kind = |u: &Update| match u {
        Update::Source(..) => 0,
        Update::Receiver(..) => 1,
        Update::Interface(..) => 2,
        Update::Speed(..) | Update::Index(..) => 3,
    };
    for step in 0..steps {
        let update = random_update(&spec, &mut rng);
        let candidate = edited(&spec, &update);
        let expected = fresh(&candidate);
        let before = results(&tracer, false);
        let got = apply(&mut tracer, &update);
        match (got, expected) {
            (Ok(()), Ok(expected)) => {
                accepted += 1;
                kinds[kind(&update)] += 1;
                spec = candidate;
                let thorough = step % 7 == 0;
                assert_eq!(
                    results(&tracer, thorough),
                    results(&expected, thorough),
                    "step {step}: the updated tracer differs from a fresh one"
                );
                // The edited scene's document reads back to it, bit for bit (`Debug` prints
                // every number so that it reads back to the same bits).
                let read = Scene::from_json(&tracer.scene().to_json()).expect("its document");
                assert_eq!(
                    format!("{read:?}"),
                    format!("{:?}", tracer.scene()),
                    "step {step}: the edited scene's document reads back to another scene"
                );
            }
            (Err(e), Err(expected)) => {
                refused += 1;
                assert_eq!(e.to_string(), expected.to_string(), "step {step}");
                assert_eq!(
                    results(&tracer, false),
                    before,
                    "step {step}: a refused update changed the tracer"
                );
            }
            (got, expected) => panic!(
                "step {step}: the update gives {got:?}, a fresh tracer {:?}",
                expected.map(|_| ())
            ),
        }
    }
    assert!(
        kinds.iter().all(|&n| n >= 5),
        "accepted of each kind: {kinds:?}"
    );
    (accepted, refused)
}

/// A bent surface between air and water, media given on two paths and looked up (across a
/// domain) on a third.
fn refraction() -> SceneSpec {
    let json = r#"{
        "media": { "air": { "speed": 1.0, "at": [0, 3] }, "water": { "speed": 0.75, "at": [0, -3] } },
        "domain": [[-6, -6], [6, 6]],
        "interfaces": {
            "surface": { "points": [[-6, 0], [-2, 0.3], [0, -0.2], [2, 0.25], [6, 0]] },
            "floor": { "points": [[-6, -4], [0, -4.5], [6, -4]] }
        },
        "sources": [[-1, 2], [1.5, 3]],
        "receivers": [[-4, -1], [-2, -2], [0, -1.5], [2, -3], [4, -2], [3, 1.5]],
        "paths": [
            { "name": "down", "steps": [{ "refract": "surface" }], "media": ["air", "water"] },
            { "name": "floor", "steps": [{ "refract": "surface" }, { "reflect": "floor" },
                { "refract": "surface" }], "media": ["air", "water", "water", "air"] },
            { "name": "looked up", "steps": [{ "refract": "surface" }] }
        ]
    }"#;
    SceneSpec::from_json(json).unwrap()
}

/// A room of four one-segment walls (the image method's plans), the air claimed by an `at`
/// point, with a search of every first-order reflection.
fn room() -> SceneSpec {
    let json = r#"{
        "media": { "air": { "speed": 343.0, "at": [3, 2] } },
        "interfaces": {
            "north": { "points": [[0, 4], [6, 4]] },
            "east": { "points": [[6, 0], [6, 4]] },
            "south": { "points": [[0, 0], [6, 0]] },
            "west": { "points": [[0, 0], [0, 4]] }
        },
        "sources": [[1.5, 1.2]],
        "receivers": [[4.5, 2.8], [3.8, 1.0], [2.2, 3.1], [5, 3.5]],
        "paths": [
            { "name": "direct", "steps": [], "media": ["air"] },
            { "name": "north", "steps": [{ "reflect": "north" }], "media": ["air", "air"] },
            { "name": "east then west", "steps": [{ "reflect": "east" }, { "reflect": "west" }] },
            { "name": "south", "steps": [{ "reflect": "south" }] }
        ],
        "search": { "max_steps": 1, "refract": false }
    }"#;
    SceneSpec::from_json(json).unwrap()
}

/// A closed lens of glass in air: the media from region lookup (glass `at` inside, air the
/// background), rays through both faces and off the front.
fn lens() -> SceneSpec {
    let arc: Vec<String> = (0..12)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 12.0;
            format!("[{}, {}]", 0.8 * t.cos(), 2.0 * t.sin())
        })
        .collect();
    let json = format!(
        r#"{{
        "media": {{ "air": {{ "index": 1.0 }}, "glass": {{ "index": 1.5, "at": [0, 0] }} }},
        "background": "air",
        "interfaces": {{
            "lens": {{ "points": [{}], "closed": true }},
            "screen": {{ "points": [[6, -3], [6, 3]] }}
        }},
        "sources": [[-5, 0.2]],
        "receivers": [[4, -1], [4, -0.3], [4, 0.4], [4, 1.1], [-4, 1.5]],
        "paths": [
            {{ "name": "direct", "steps": [] }},
            {{ "name": "through", "steps": [{{ "refract": "lens" }}, {{ "refract": "lens" }}] }},
            {{ "name": "off the front", "steps": [{{ "reflect": "lens" }}] }},
            {{ "name": "screen", "steps": [{{ "reflect": "screen" }}], "media": ["air", "air"] }}
        ]
    }}"#,
        arc.join(", ")
    );
    SceneSpec::from_json(&json).unwrap()
}

#[test]
fn updates_of_a_refraction_give_a_fresh_tracers_rays() {
    let (accepted, refused) = random_updates(refraction(), 150, 1);
    assert!(
        accepted >= 80 && refused >= 5,
        "{accepted} accepted, {refused} refused"
    );
}

#[test]
fn updates_of_a_room_give_a_fresh_tracers_rays() {
    let (accepted, refused) = random_updates(room(), 150, 2);
    assert!(
        accepted >= 80 && refused >= 5,
        "{accepted} accepted, {refused} refused"
    );
}

#[test]
fn updates_of_a_lens_with_regions_give_a_fresh_tracers_rays() {
    let (accepted, refused) = random_updates(lens(), 150, 3);
    assert!(
        accepted >= 80 && refused >= 5,
        "{accepted} accepted, {refused} refused"
    );
}

/// Moving every receiver at once (`set_receivers`: the blocks of a large map) gives the rays
/// of a tracer built afresh, whether the receivers' box shrinks, grows or shifts; a refused
/// point moves no receiver.
#[test]
fn moving_every_receiver_gives_a_fresh_tracers_rays() {
    for mut spec in [refraction(), room(), lens()] {
        let mut tracer = fresh(&spec).unwrap();
        for (scale, shift) in [(0.5, 0.0), (1.3, 0.25), (1.0, -0.2), (1.0, 0.0)] {
            let moved: Vec<[f64; 2]> = spec
                .receivers
                .list()
                .unwrap()
                .iter()
                .map(|p| [p[0] * scale + shift, p[1] * scale - shift])
                .collect();
            let points: Vec<Point> = moved.iter().map(|p| Point::new(p[0], p[1])).collect();
            tracer.set_receivers(&points).unwrap();
            spec.receivers = moved.into();
            assert_eq!(
                results(&tracer, true),
                results(&fresh(&spec).unwrap(), true)
            );
            let read = Scene::from_json(&tracer.scene().to_json()).unwrap();
            assert_eq!(format!("{read:?}"), format!("{:?}", tracer.scene()));
        }
        let before = results(&tracer, false);
        let mut bad: Vec<Point> = tracer
            .scene()
            .receivers()
            .iter()
            .map(|p| Point::new(p.x * 2.0, p.y))
            .collect();
        bad[2] = Point::new(0.0, f64::NAN);
        let e = tracer.set_receivers(&bad).unwrap_err();
        assert_eq!(
            e.to_string(),
            "receivers[2]: coordinates must be finite numbers"
        );
        let e = tracer.set_receivers(&bad[1..]).unwrap_err();
        assert_eq!(e.key, "receivers");
        assert_eq!(results(&tracer, false), before);
    }
}

/// The refusals a layout tool meets, with the document's keys.
#[test]
fn refused_updates_name_the_key() {
    let mut tracer = fresh(&refraction()).unwrap();
    let scene = tracer.scene();
    let surface = scene.interface_index("surface").unwrap();
    let water = scene.medium_index("water").unwrap();
    let e = |r: Result<(), SceneError>| r.unwrap_err().to_string();
    assert_eq!(
        e(tracer.set_receiver(9, Point::new(0.0, 0.0))),
        "receivers: index 9 is out of range (the scene has 6 receivers)"
    );
    assert_eq!(
        e(tracer.set_source(0, Point::new(-2.0, 0.3))),
        "sources[0]: lies exactly on interface `surface`, so it has no medium: move it off the \
         interface, or give every path its `media`"
    );
    let crossing = [
        Point::new(-6.0, 0.0),
        Point::new(0.0, -5.0),
        Point::new(6.0, 0.0),
    ];
    assert_eq!(
        e(tracer.set_interface_points(surface, &crossing)),
        "interfaces.floor.points: crosses interface `surface` (segment 0 crosses segment 0)"
    );
    let repeated = [
        Point::new(-6.0, 0.0),
        Point::new(1.0, 0.0),
        Point::new(1.0, 0.0),
    ];
    assert_eq!(
        e(tracer.set_interface_points(surface, &repeated)),
        "interfaces.surface.points[2]: point 2 repeats the point before it (zero-length segment)"
    );
    assert_eq!(
        e(tracer.set_medium_speed(water, 0.0)),
        "media.water.speed: must be a finite number > 0"
    );
    // The surface ends inside the domain: it no longer divides air from water.
    let short = [Point::new(-6.0, 0.0), Point::new(5.0, 0.0)];
    let got = e(tracer.set_interface_points(surface, &short));
    let mut spec = refraction();
    spec.interfaces.get_mut("surface").unwrap().points = vec![[-6.0, 0.0], [5.0, 0.0]];
    assert_eq!(got, fresh(&spec).err().unwrap().to_string());
    // None of these changed anything.
    assert_eq!(
        results(&tracer, true),
        results(&fresh(&refraction()).unwrap(), true)
    );
}

/// A tracer whose scene is shared (one `Arc`) edits a copy: the other keeps the old scene.
#[test]
fn a_shared_scene_is_copied_before_an_update() {
    let scene = std::sync::Arc::new(Scene::from_spec(&room()).unwrap());
    let mut a = Tracer::new(scene.clone()).unwrap();
    let b = Tracer::new(scene.clone()).unwrap();
    a.set_receiver(0, Point::new(1.0, 3.0)).unwrap();
    assert_eq!(a.scene().receivers()[0], Point::new(1.0, 3.0));
    assert_eq!(b.scene().receivers()[0], Point::new(4.5, 2.8));
    assert_eq!(scene.receivers()[0], Point::new(4.5, 2.8));
}
