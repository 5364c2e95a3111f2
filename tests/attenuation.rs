//! Attenuations and extreme media: `{"db_per_wavelength": a}` against the same scene written
//! in dB per unit length (a·f/c, or a·f·n for `index` media), its validation, its document and
//! its medium updates; attenuations too large for a path's decibels to stay a number are
//! refused at their key; media whose speeds and densities are 1e±100 apart give amplitudes
//! with a value (checked against closed forms) or with a reason, never a silent NaN.

use std::f64::consts::PI;

use eigenray::amplitude::Complex64;
use eigenray::{Amplitude, Point, Scene, Status, Tracer};

fn scene(json: &str) -> Scene {
    Scene::from_json(json).unwrap_or_else(|e| panic!("{e}"))
}

/// Every amplitude of every ray and search arrival of `s`, in order.
fn amplitudes(s: &Scene) -> Vec<Amplitude> {
    let tracer = Tracer::new(s).unwrap();
    let mut out: Vec<Amplitude> = tracer
        .trace_all()
        .iter()
        .filter_map(|r| r.amplitude)
        .collect();
    if s.search().is_some() {
        let arrivals = tracer
            .search(&eigenray::options::Run::new())
            .unwrap()
            .arrivals;
        out.extend(arrivals.iter().filter_map(|a| a.arrival.amplitude));
    }
    out
}

/// A layered shallow-water scene: water over a sediment, both attenuating as `water` and
/// `sediment` give it (each a JSON value), refractions, a `"media"` bottom bounce and a
/// search, at 250 Hz.
fn layered(water: &str, sediment: &str) -> String {
    format!(
        r#"{{ "media": {{ "water": {{ "speed": 1500, "density": 1, "attenuation": {water}, "at": [10, -5] }},
                        "sediment": {{ "speed": 1700, "density": 1.8, "attenuation": {sediment}, "at": [10, -150] }} }},
             "domain": [[-1, -300], [3001, 1]],
             "interfaces": {{ "surface": {{ "points": [[-1, 0], [3001, 0]], "reflection": "pressure-release" }},
                             "bottom": {{ "points": [[-1, -100], [1500, -110], [3001, -100]], "reflection": "media" }} }},
             "sources": [[0, -30]], "receivers": [[1000, -60], [2500, -200], [2900, -20]],
             "paths": [{{ "steps": [] }},
                       {{ "steps": [{{ "reflect": "bottom" }}] }},
                       {{ "steps": [{{ "refract": "bottom" }}] }},
                       {{ "steps": [{{ "reflect": "surface" }}, {{ "reflect": "bottom" }}] }}],
             "search": {{ "max_steps": 3, "refract": false }},
             "amplitudes": {{ "source": "axisymmetric", "frequency": 250 }} }}"#
    )
}

#[test]
fn an_attenuation_per_wavelength_is_a_times_f_over_c_per_unit_length() {
    let per_wavelength = scene(&layered(
        r#"{ "db_per_wavelength": 0.01 }"#,
        r#"{ "db_per_wavelength": 0.5 }"#,
    ));
    // The same attenuations in dB per unit length, written out: a·f/c.
    let (water, sediment) = (0.01 * 250.0 / 1500.0, 0.5 * 250.0 / 1700.0);
    let per_length = scene(&layered(&format!("{water:e}"), &format!("{sediment:e}")));
    let settings = per_wavelength.amplitudes().unwrap();
    // Media in the order of their names: the sediment, then the water.
    assert_eq!(settings.attenuation, [sediment, water]);
    assert_eq!(settings.attenuation_per_wavelength, [Some(0.5), Some(0.01)]);
    let (a, b) = (amplitudes(&per_wavelength), amplitudes(&per_length));
    assert!(a.len() > 10, "{}", a.len());
    // Every path with decibels (a value, or a converted reflection's) is attenuated.
    let with_db: Vec<_> = a.iter().filter(|x| !x.attenuation_db.is_nan()).collect();
    assert!(with_db.len() > 10, "{}", with_db.len());
    assert!(with_db.iter().all(|x| x.attenuation_db > 0.0));
    assert_eq!(a, b);

    // `index` media: the wavelength is 1/(n f), so a·f·n dB per unit length.
    let optics = |air: &str, glass: &str| {
        scene(&format!(
            r#"{{ "media": {{ "air": {{ "index": 1, "attenuation": {air} }},
                             "glass": {{ "index": 1.5, "attenuation": {glass} }} }},
                 "interfaces": {{ "face": {{ "points": [[-10, 0], [10, 0]] }} }},
                 "sources": [[0, 2]], "receivers": [[1, -3], [4, -1]],
                 "paths": [{{ "steps": [{{ "refract": "face" }}], "media": ["air", "glass"] }}],
                 "amplitudes": {{ "source": "point", "frequency": 3e-3 }} }}"#
        ))
    };
    let per_wavelength = optics("0", r#"{ "db_per_wavelength": 2 }"#);
    let per_length = optics("0", &format!("{:e}", 2.0 * 3e-3 * 1.5));
    let a = amplitudes(&per_wavelength);
    assert!(a.iter().all(|x| x.has_value() && x.attenuation_db > 0.0));
    assert_eq!(a, amplitudes(&per_length));
}

/// The key of the error of `json`.
fn refused(json: &str) -> String {
    match Scene::from_json(json) {
        Ok(_) => panic!("accepted: {json}"),
        Err(e) => {
            assert!(!e.message.is_empty());
            e.key
        }
    }
}

/// One medium `a` (its keys `medium`) and a direct path, with `extra` at the root.
fn one_medium(medium: &str, extra: &str) -> String {
    format!(
        r#"{{ "media": {{ "a": {{ "speed": 1500, {medium} }} }},
             "sources": [[0, 0]], "receivers": [[10, 0]],
             "paths": [{{ "steps": [], "media": ["a"] }}] {extra} }}"#
    )
}

#[test]
fn attenuations_are_refused_at_their_keys() {
    let asks = r#", "amplitudes": { "source": "point", "frequency": 100 }"#;
    let cases = [
        // Per wavelength without a frequency, or without amplitudes at all.
        (
            one_medium(
                r#""attenuation": { "db_per_wavelength": 0.5 }"#,
                r#", "amplitudes": { "source": "point" }"#,
            ),
            "media.a.attenuation",
        ),
        (
            one_medium(r#""attenuation": { "db_per_wavelength": 0.5 }"#, ""),
            "media.a.attenuation",
        ),
        // Even 0 per wavelength: the key asks for a frequency.
        (
            one_medium(r#""attenuation": { "db_per_wavelength": 0 }"#, ""),
            "media.a.attenuation",
        ),
        (
            one_medium(r#""attenuation": { "db_per_wavelength": -1 }"#, asks),
            "media.a.attenuation.db_per_wavelength",
        ),
        (
            one_medium(r#""attenuation": { "db_per_wavelength": 1e101 }"#, asks),
            "media.a.attenuation.db_per_wavelength",
        ),
        // 1e100 dB per wavelength at 100 Hz in 1500 m/s: 6.7e99 dB/m is allowed, but not
        // at 1e4 Hz (6.7e101).
        (
            one_medium(
                r#""attenuation": { "db_per_wavelength": 1e100 }"#,
                r#", "amplitudes": { "source": "point", "frequency": 1e4 }"#,
            ),
            "media.a.attenuation.db_per_wavelength",
        ),
        (
            one_medium(r#""attenuation": { "db_per_wavlength": 0.5 }"#, asks),
            "media.a.attenuation",
        ),
        (
            one_medium(
                r#""attenuation": { "db_per_wavelength": 0.5, "x": 1 }"#,
                asks,
            ),
            "media.a.attenuation",
        ),
        (
            one_medium(r#""attenuation": "0.5""#, asks),
            "media.a.attenuation",
        ),
        // dB per unit length: the hostile probe's 1e308, and anything above 1e100.
        (
            one_medium(r#""attenuation": 1e308"#, asks),
            "media.a.attenuation",
        ),
        (
            one_medium(r#""attenuation": 1.0000001e100"#, asks),
            "media.a.attenuation",
        ),
        (
            one_medium(r#""attenuation": -0.1"#, asks),
            "media.a.attenuation",
        ),
    ];
    for (json, key) in &cases {
        assert_eq!(&refused(json), key, "{json}");
    }
    for fine in [
        one_medium(r#""attenuation": { "db_per_wavelength": 1e100 }"#, asks),
        one_medium(r#""attenuation": 1e100"#, asks),
    ] {
        let s = Scene::from_json(&fine).unwrap_or_else(|e| panic!("{fine}: {e}"));
        if let Some(a) = s.amplitudes() {
            assert!(a.attenuation[0] <= 1e100);
        }
    }
}

/// The largest attenuation on the longest legs the coordinates allow: a path of 1e100 dB per
/// unit length over 4e100 units gives a finite number of decibels, and an amplitude of 0 that
/// says why (its `attenuation_db`), never a NaN or a null.
#[test]
fn the_largest_attenuation_gives_finite_decibels() {
    let s = scene(
        r#"{ "media": { "a": { "speed": 1, "attenuation": 1e100 } },
             "interfaces": { "wall": { "points": [[-1e100, -1e100], [1e100, -1e100]] } },
             "sources": [[-1e100, 1e100]], "receivers": [[1e100, 1e100]],
             "paths": [{ "steps": [], "media": ["a"] },
                       { "steps": [{ "reflect": "wall" }], "media": ["a", "a"] }],
             "amplitudes": { "source": "point" } }"#,
    );
    let rays = Tracer::new(&s).unwrap().trace_all();
    let direct = rays[0].amplitude.unwrap();
    let bounce = rays[1].amplitude.unwrap();
    assert_eq!(rays[1].status, Status::Converged);
    let want = [2e200, 1e100 * 2.0 * 1e100f64.hypot(2e100)];
    for (a, db) in [direct, bounce].iter().zip(want) {
        assert!(a.has_value(), "{a:?}");
        assert!(
            (a.attenuation_db - db).abs() <= 1e-14 * db,
            "{} {db}",
            a.attenuation_db
        );
        assert_eq!(a.value, Complex64::new(0.0, 0.0));
        assert!(a.spreading > 0.0 && a.spreading.is_finite());
    }
}

/// Media 1e±100 apart (the hostile probe's): `slow` of speed 1e-100 and density 1e100 above
/// `fast` of speed 1e100 and density 1e-100, both of impedance 1, a `"media"` interface
/// between them. Every timed ray's amplitude has a value or a reason; the values against the
/// closed forms of a flat interface (equal impedances: T = 1, and R from the cosines alone).
#[test]
fn media_1e200_apart_give_amplitudes_without_overflow() {
    let s = scene(
        r#"{ "media": { "slow": { "speed": 1e-100, "density": 1e100, "at": [0, 5] },
                        "fast": { "speed": 1e100, "density": 1e-100, "at": [0, -5] } },
             "domain": [[-10, -10], [10, 10]],
             "interfaces": { "face": { "points": [[-10, 0], [10, 0]], "reflection": "media" } },
             "sources": [[0, 1], [0, -2]],
             "receivers": [[3, 1], [0, -1], [3, -1], [-2, -3], [0, 1.5]],
             "paths": [{ "steps": [] }, { "steps": [{ "reflect": "face" }] },
                       { "steps": [{ "refract": "face" }] }],
             "amplitudes": { "source": "point" } }"#,
    );
    let rays = Tracer::new(&s).unwrap().trace_all();
    let find = |source: usize, receiver: usize, path: usize| {
        let ray = rays
            .iter()
            .find(|r| r.source == source && r.receiver == receiver && r.path == path)
            .unwrap();
        assert_eq!(ray.status, Status::Converged, "{ray:?}");
        ray.amplitude.unwrap()
    };
    let mut timed = 0;
    for ray in &rays {
        let Some(a) = ray.amplitude else { continue };
        timed += 1;
        if a.has_value() {
            let parts = [a.value.re, a.value.im, a.spreading, a.attenuation_db];
            assert!(parts.iter().all(|x| x.is_finite()), "{ray:?}");
            assert!(a.spreading > 0.0, "{ray:?}");
        } else {
            assert!(a.value.re.is_nan(), "{ray:?}");
        }
    }
    assert!(timed >= 5, "{timed}");
    let close = |a: Complex64, b: Complex64, what: &str| {
        let e = (a - b).norm() / b.norm();
        assert!(e <= 1e-13, "{what}: {a} against {b} ({e:e})");
    };
    let quarter = 0.25 / PI;
    // A reflection in the slow medium: beyond the critical angle at any incidence,
    // cos θ₂ = i·1e200·sin θ₁, so R = −1 to every digit.
    let length = Point::new(0.0, -1.0).distance(Point::new(3.0, 1.0));
    close(
        find(0, 0, 1).value,
        Complex64::new(-quarter / length, 0.0),
        "reflection, slow side",
    );
    // A reflection in the fast medium: cos θ₂ = 1, R = (cos θ₁ − 1)/(cos θ₁ + 1).
    let length = Point::new(0.0, 2.0).distance(Point::new(-2.0, -3.0));
    let cos1 = 5.0 / length;
    let r = (cos1 - 1.0) / (cos1 + 1.0);
    close(
        find(1, 3, 1).value,
        Complex64::new(r * quarter / length, 0.0),
        "reflection, fast side",
    );
    // Normal refraction, slow to fast: T = 1, and the tube widens by 1e200 over the fast leg
    // in and out of the plane: W = Y = ℓ₀ + 1e200 ℓ₁.
    let width = 1.0 + 1e200;
    close(
        find(0, 1, 2).value,
        Complex64::new(quarter / width, 0.0),
        "refraction, slow to fast",
    );
    // Oblique, slow to fast: the slow leg is normal (to 1e-200), cos θ₂ = 1/√10,
    // W = cos θ₂ + 1e200 ℓ₁ / cos θ₂ and Y = ℓ₀ + 1e200 ℓ₁ with ℓ₀ = 1, ℓ₁ = √10.
    let (l1, cos2) = (10f64.sqrt(), 1.0 / 10f64.sqrt());
    let (w, y) = (cos2 + 1e200 * l1 / cos2, 1.0 + 1e200 * l1);
    let t = 2.0 / (1.0 + cos2);
    close(
        find(0, 2, 2).value,
        Complex64::new(t * cos2.sqrt() * quarter / (w.sqrt() * y.sqrt()), 0.0),
        "refraction, oblique",
    );
    // Normal refraction, fast to slow: the slow leg adds 1e-200 of width: the field of a
    // source 2 away.
    close(
        find(1, 4, 2).value,
        Complex64::new(quarter / 2.0, 0.0),
        "refraction, fast to slow",
    );
}

/// `Scene::to_json` writes the attenuation as given (the object, not its dB per unit length),
/// and reads back to the same scene; the builder writes the same key.
#[test]
fn the_document_keeps_the_attenuation_as_given() {
    let s = scene(&layered("0.002", r#"{ "db_per_wavelength": 0.5 }"#));
    let json = s.to_json();
    assert!(
        json.contains(r#""attenuation":{"db_per_wavelength":0.5}"#),
        "{json}"
    );
    assert!(json.contains(r#""attenuation":0.002"#), "{json}");
    let again = scene(&json);
    assert_eq!(again.amplitudes(), s.amplitudes());
    assert_eq!(amplitudes(&again), amplitudes(&s));

    use eigenray::MediumSpec;
    let built = MediumSpec::speed(1700.0).attenuation_per_wavelength(0.5);
    let read: MediumSpec =
        serde_json::from_str(r#"{ "speed": 1700, "attenuation": { "db_per_wavelength": 0.5 } }"#)
            .unwrap();
    let text = |m: &MediumSpec| serde_json::to_string(m).unwrap();
    assert_eq!(text(&built), text(&read));
}

/// A change of speed (or index) moves an attenuation given per wavelength with it, on the
/// scene and on a tracer: the same amplitudes as a scene written with the new speed. A speed
/// that would push it past the limit is refused at the speed's key, the scene left as it was.
#[test]
fn medium_updates_move_an_attenuation_per_wavelength() {
    let per_wavelength = r#"{ "db_per_wavelength": 0.5 }"#;
    let mut s = scene(&layered("0.002", per_wavelength));
    let sediment = s.medium_index("sediment").unwrap();
    s.set_medium_speed(sediment, 1650.0).unwrap();
    let fresh = scene(&layered("0.002", per_wavelength).replace("1700", "1650"));
    assert_eq!(s.amplitudes(), fresh.amplitudes());
    assert_eq!(
        s.amplitudes().unwrap().attenuation[sediment],
        0.5 * 250.0 / 1650.0
    );
    assert_eq!(amplitudes(&s), amplitudes(&fresh));

    // The same through a tracer.
    let mut tracer = Tracer::new(scene(&layered("0.002", per_wavelength))).unwrap();
    tracer.set_medium_speed(sediment, 1650.0).unwrap();
    let want: Vec<_> = Tracer::new(&fresh).unwrap().trace_all();
    let got = tracer.trace_all();
    let pick = |rays: &[eigenray::Ray]| rays.iter().map(|r| r.amplitude).collect::<Vec<_>>();
    assert_eq!(pick(&got), pick(&want));

    // A dB per unit length does not follow the speed.
    let mut plain = scene(&layered("0.002", "0.07"));
    plain.set_medium_speed(sediment, 1650.0).unwrap();
    assert_eq!(plain.amplitudes().unwrap().attenuation[sediment], 0.07);

    // 1e100 dB per wavelength at 250 Hz: 2.5e101 dB per unit length at speed 1e2, refused.
    let mut edge =
        scene(&layered("0.002", r#"{ "db_per_wavelength": 1e100 }"#).replace("1700", "1e4"));
    let before = edge.to_json();
    let e = edge.set_medium_speed(sediment, 100.0).unwrap_err();
    assert_eq!(e.key, "media.sediment.speed", "{e}");
    assert_eq!(edge.to_json(), before);
    assert_eq!(edge.media()[sediment].slowness, 1e-4);

    // `index` media: a·f·n follows the index.
    let optics = |n: &str| {
        scene(&format!(
            r#"{{ "media": {{ "glass": {{ "index": {n}, "attenuation": {{ "db_per_wavelength": 2 }} }} }},
                 "sources": [[0, 2]], "receivers": [[1, -3]],
                 "paths": [{{ "steps": [], "media": ["glass"] }}],
                 "amplitudes": {{ "source": "point", "frequency": 3e-3 }} }}"#
        ))
    };
    let mut glass = optics("1.5");
    glass.set_medium_index(0, 1.7).unwrap();
    assert_eq!(glass.amplitudes(), optics("1.7").amplitudes());
}
