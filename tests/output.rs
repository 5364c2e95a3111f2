//! The output formats read back: every field of JSON, JSON Lines, CSV and `.npy` (with its name
//! tables) against the JSON document and against values worked out by hand.

use eigenray::scene::{Step, StepKind};
use eigenray::{
    Arrival, BatchOptions, Format, Point, Reason, Scene, SearchArrival, Status, Tracer,
    output::write_names, trace::Kink, write,
};
use serde_json::Value;

/// Media listed water first, so that file order and name order differ; a path name that CSV
/// must quote; paths with every status this geometry gives.
const SCENE: &str = r#"{
    "media": { "water": { "speed": 0.5 }, "air": { "speed": 1.0 } },
    "interfaces": {
        "surface": { "points": [[-10, 0], [10, 0]] },
        "short": { "points": [[5, -2], [6, -2]] }
    },
    "sources": [[0, 1]],
    "receivers": [[2, 1], [1, -1]],
    "paths": [
        { "name": "bounce, \"top\"", "steps": [{ "reflect": "surface" }], "media": ["air", "air"] },
        { "steps": [{ "refract": "surface" }], "media": ["air", "water"] },
        { "name": "direct", "steps": [], "media": ["air"] },
        { "name": "miss", "steps": [{ "reflect": "short" }], "media": ["air", "air"] }
    ]
}"#;

fn scene() -> Scene {
    Scene::from_json(SCENE).expect("valid scene")
}

/// The bytes of every ray of `scene` in `format`, written from a batch; the owned rays give
/// the same bytes.
fn written(scene: &Scene, format: Format) -> Vec<u8> {
    let tracer = Tracer::new(scene).expect("tracer");
    let batch = tracer
        .trace_batch(&BatchOptions::default(), &eigenray::options::Run::new())
        .unwrap();
    let mut out = Vec::new();
    write(scene, &batch, format, &mut out).expect("write");
    let mut owned = Vec::new();
    write(scene, &tracer.trace_all(), format, &mut owned).expect("write");
    assert_eq!(owned, out, "{format:?}: owned rays and batch differ");
    out
}

fn json_rays(scene: &Scene) -> Vec<Value> {
    let doc: Value = serde_json::from_slice(&written(scene, Format::Json)).expect("JSON");
    doc["rays"].as_array().expect("rays").clone()
}

/// The point where a ray from (0, 1) in speed 1 crosses y = 0 into speed 0.5 towards (1, −1),
/// by bisection on Snell's law (sin θ₁ / v₁ = sin θ₂ / v₂), and its time.
fn refraction_by_bisection() -> (f64, f64) {
    let f = |x: f64| x / x.hypot(1.0) - 2.0 * (1.0 - x) / (1.0 - x).hypot(1.0);
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    let x = 0.5 * (lo + hi);
    (x, x.hypot(1.0) + (1.0 - x).hypot(1.0) / 0.5)
}

fn ray(rays: &[Value], receiver: usize, path: usize) -> &Value {
    &rays[receiver * 4 + path]
}

fn points(v: &Value) -> Vec<[f64; 2]> {
    v.as_array()
        .expect("points")
        .iter()
        .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

#[test]
fn json_holds_the_values_worked_out_by_hand() {
    let rays = json_rays(&scene());
    assert_eq!(rays.len(), 8);
    for (i, r) in rays.iter().enumerate() {
        assert_eq!(r["source"], 0);
        assert_eq!(r["receiver"], i / 4);
        assert_eq!(r["path"], i % 4);
    }

    // The bounce to (2, 1): off (1, 0), two legs of √2 in air.
    let bounce = ray(&rays, 0, 0);
    assert_eq!(bounce["status"], "converged");
    assert_eq!(bounce["path_name"], "bounce, \"top\"");
    assert_eq!(bounce["media"], serde_json::json!(["air", "air"]));
    assert!(close(bounce["time"].as_f64().unwrap(), 2.0 * 2f64.sqrt()));
    let p = points(&bounce["points"]);
    assert_eq!(p.len(), 3);
    assert_eq!(p[0], [0.0, 1.0]);
    assert!(close(p[1][0], 1.0) && p[1][1].abs() < 1e-12, "{p:?}");
    assert_eq!(p[2], [2.0, 1.0]);
    assert!(bounce.get("reason").is_none());

    // The unnamed refraction to (1, −1): no `path_name`, media air then water.
    let refracted = ray(&rays, 1, 1);
    let (x, time) = refraction_by_bisection();
    assert_eq!(refracted["status"], "converged");
    assert!(refracted.get("path_name").is_none());
    assert_eq!(refracted["media"], serde_json::json!(["air", "water"]));
    assert!(close(refracted["time"].as_f64().unwrap(), time));
    let p = points(&refracted["points"]);
    assert!(close(p[1][0], x) && p[1][1] == 0.0, "{p:?} against x = {x}");
    assert_eq!(p[2], [1.0, -1.0]);

    // The direct ray to (2, 1) in air; to (1, −1) it crosses the surface.
    let direct = ray(&rays, 0, 2);
    assert_eq!(direct["status"], "converged");
    assert_eq!(direct["path_name"], "direct");
    assert_eq!(direct["media"], serde_json::json!(["air"]));
    assert_eq!(direct["time"].as_f64(), Some(2.0));
    let blocked = ray(&rays, 1, 2);
    assert_eq!(blocked["status"], "obstructed");
    assert!(close(blocked["time"].as_f64().unwrap(), 5f64.sqrt()));
    let reason = blocked["reason"].as_str().expect("reason");
    assert!(reason.contains("surface"), "{reason}");

    // No path: a reflection with its legs on two sides, a refraction with both ends above,
    // and the short mirror whose specular point lies beyond its end.
    for (receiver, path) in [(1, 0), (0, 1), (0, 3)] {
        let r = ray(&rays, receiver, path);
        assert_eq!(r["status"], "no_path", "{r}");
        assert!(r.get("time").is_none() && r.get("points").is_none(), "{r}");
        assert!(r["reason"].as_str().is_some_and(|s| !s.is_empty()), "{r}");
    }
}

#[test]
fn json_lines_hold_the_json_objects() {
    let scene = scene();
    let rays = json_rays(&scene);
    let text = String::from_utf8(written(&scene, Format::Jsonl)).unwrap();
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("one object per line"))
        .collect();
    assert_eq!(lines, rays);
}

/// One CSV record split into fields as RFC 4180 says (quoted fields, `""` for a quote).
fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (false, ',') => fields.push(String::new()),
            (false, '"') => quoted = true,
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                fields.last_mut().unwrap().push('"');
            }
            (true, '"') => quoted = false,
            (_, c) => fields.last_mut().unwrap().push(c),
        }
    }
    fields
}

#[test]
fn csv_holds_every_field_of_the_json() {
    let scene = scene();
    let rays = json_rays(&scene);
    let text = String::from_utf8(written(&scene, Format::Csv)).unwrap();
    let mut lines = text.lines();
    let header = [
        "source",
        "receiver",
        "path",
        "status",
        "time",
        "iterations",
        "residual",
        "points",
        "path_name",
        "media",
        "reason",
    ];
    assert_eq!(csv_fields(lines.next().unwrap()), header);
    let records: Vec<Vec<String>> = lines.map(csv_fields).collect();
    assert_eq!(records.len(), rays.len());
    for (f, r) in records.iter().zip(&rays) {
        assert_eq!(f.len(), header.len(), "{f:?}");
        let field = |name: &str| &f[header.iter().position(|h| *h == name).unwrap()];
        for key in ["source", "receiver", "path", "iterations"] {
            assert_eq!(
                field(key).parse::<u64>().ok(),
                r[key].as_u64(),
                "{key} of {r}"
            );
        }
        assert_eq!(field("status"), r["status"].as_str().unwrap());
        // Floats as the JSON prints them: the same shortest round-trip text.
        for key in ["time", "residual"] {
            match r.get(key) {
                Some(v) => assert_eq!(
                    field(key).parse::<f64>().unwrap().to_bits(),
                    v.as_f64().unwrap().to_bits(),
                    "{key} of {r}"
                ),
                None => assert_eq!(field(key), "", "{key} of {r}"),
            }
        }
        match r.get("points") {
            Some(p) => {
                let csv: Vec<[f64; 2]> = field("points")
                    .split(';')
                    .map(|xy| {
                        let (x, y) = xy.split_once(' ').expect("x y");
                        [x.parse().unwrap(), y.parse().unwrap()]
                    })
                    .collect();
                assert_eq!(csv, points(p), "points of {r}");
            }
            None => assert_eq!(field("points"), ""),
        }
        assert_eq!(field("path_name"), r["path_name"].as_str().unwrap_or(""));
        let media: Vec<&str> = r["media"]
            .as_array()
            .map(|m| m.iter().map(|n| n.as_str().unwrap()).collect())
            .unwrap_or_default();
        assert_eq!(field("media"), &media.join(";"));
        assert_eq!(field("reason"), r["reason"].as_str().unwrap_or(""));
    }
    // By hand: the bounce's name with its comma and quote, its x and y in that order, and the
    // refraction's media.
    let bounce = &records[0];
    assert_eq!(bounce[8], "bounce, \"top\"");
    assert!(
        bounce[7].starts_with("0.0 1.0;1.0 ") && bounce[7].ends_with(";2.0 1.0"),
        "{bounce:?}"
    );
    assert_eq!(records[5][9], "air;water");
    assert_eq!(records[5][8], "");
    assert!(records[6][10].contains("surface"), "{:?}", records[6]);
}

/// A `.npy` file taken apart: the header dictionary and the records.
struct Npy {
    header: String,
    records: Vec<Vec<u8>>,
}

fn read_npy(bytes: &[u8]) -> Npy {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + len) % 64, 0, "data aligned to 64 bytes");
    let header = String::from_utf8(bytes[10..10 + len].to_vec()).unwrap();
    // The record size from the header's own shapes: P points and L legs.
    let dim = |field: &str| -> usize {
        let at = header.find(field).expect(field) + field.len();
        let digits: String = header[at..]
            .chars()
            .skip_while(|c| !c.is_ascii_digit())
            .take_while(char::is_ascii_digit)
            .collect();
        digits.parse().unwrap()
    };
    let (p, l) = (dim("('points', '<f8', ("), dim("('media', '<u4', ("));
    let size = 3 * 4 + 1 + 4 + 8 + 8 + 16 * p + 4 * l;
    let data = &bytes[10 + len..];
    assert_eq!(data.len() % size, 0);
    Npy {
        header,
        records: data.chunks(size).map(<[u8]>::to_vec).collect(),
    }
}

fn u32_at(r: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(r[at..at + 4].try_into().unwrap())
}

fn f64_at(r: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(r[at..at + 8].try_into().unwrap())
}

#[test]
fn npy_and_its_name_tables_hold_every_field_of_the_json() {
    let scene = scene();
    let rays = json_rays(&scene);
    let npy = read_npy(&written(&scene, Format::Npy));
    assert!(
        npy.header.contains("('points', '<f8', (3, 2))"),
        "{}",
        npy.header
    );
    assert!(
        npy.header.contains("('media', '<u4', (2,))"),
        "{}",
        npy.header
    );
    assert!(npy.header.contains("'shape': (8,)"), "{}", npy.header);
    assert_eq!(npy.records.len(), rays.len());

    let mut names = Vec::new();
    write_names(&scene, &mut names).unwrap();
    let names: Value = serde_json::from_slice(&names).expect("names are JSON");
    // By hand: the documented tables, media in the order of their names.
    assert_eq!(
        names["status"],
        serde_json::json!([
            "converged",
            "vertex",
            "no_path",
            "obstructed",
            "not_converged"
        ])
    );
    assert_eq!(
        names["paths"],
        serde_json::json!(["bounce, \"top\"", null, "direct", "miss"])
    );
    assert_eq!(names["media"], serde_json::json!(["air", "water"]));
    assert_eq!(names["interfaces"], serde_json::json!(["short", "surface"]));
    assert_eq!(names["no_medium"], 4_294_967_295_u64);
    // The media order of the file is the scene's.
    let order: Vec<&str> = scene.media().iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names["media"], serde_json::json!(order));

    for (rec, r) in npy.records.iter().zip(&rays) {
        for (at, key) in [(0, "source"), (4, "receiver"), (8, "path")] {
            assert_eq!(Some(u64::from(u32_at(rec, at))), r[key].as_u64(), "{key}");
        }
        // The documented codes, written out by hand.
        let code = match r["status"].as_str().unwrap() {
            "converged" => 0,
            "vertex" => 1,
            "no_path" => 2,
            "obstructed" => 3,
            "not_converged" => 4,
            other => panic!("status {other}"),
        };
        assert_eq!(rec[12], code, "{r}");
        assert_eq!(names["status"][usize::from(rec[12])], r["status"]);
        assert_eq!(names["paths"][u32_at(rec, 8) as usize], r["path_name"]);
        assert_eq!(Some(u64::from(u32_at(rec, 13))), r["iterations"].as_u64());
        let (time, residual) = (f64_at(rec, 17), f64_at(rec, 25));
        match r["time"].as_f64() {
            Some(t) => assert_eq!(time.to_bits(), t.to_bits(), "{r}"),
            None => assert!(time.is_nan(), "{r}"),
        }
        match r["residual"].as_f64() {
            Some(v) => assert_eq!(residual.to_bits(), v.to_bits(), "{r}"),
            None => assert!(!residual.is_finite(), "{r}"),
        }
        let want = r.get("points").map(points).unwrap_or_default();
        for j in 0..3 {
            let (x, y) = (f64_at(rec, 33 + 16 * j), f64_at(rec, 41 + 16 * j));
            match want.get(j) {
                Some(&[wx, wy]) => assert_eq!([x, y], [wx, wy], "point {j} of {r}"),
                None => assert!(x.is_nan() && y.is_nan(), "point {j} of {r}"),
            }
        }
        let media: Vec<Value> = (0..2)
            .map(|j| u32_at(rec, 33 + 48 + 4 * j))
            .filter(|&m| m != 4_294_967_295)
            .map(|m| names["media"][m as usize].clone())
            .collect();
        assert_eq!(Value::Array(media), r["media"], "media of {r}");
    }
    // By hand: the refraction's legs are media 0 (air) and 1 (water); the direct ray has one
    // leg, its second entry the "no medium" mark.
    let refracted = &npy.records[5];
    assert_eq!([u32_at(refracted, 81), u32_at(refracted, 85)], [0, 1]);
    let direct = &npy.records[2];
    assert_eq!([u32_at(direct, 81), u32_at(direct, 85)], [0, u32::MAX]);
}

/// Media from region lookup (no path gives `media`): the names still reach every format.
#[test]
fn media_from_region_lookup_are_named() {
    let scene = Scene::from_json(
        r#"{
        "media": { "glass": { "index": 1.5, "at": [0, 0] }, "air": { "index": 1.0 } },
        "background": "air",
        "interfaces": { "lens": { "points": [[-1, -1], [1, -1], [1, 1], [-1, 1]], "closed": true } },
        "sources": [[-3, 0.2]], "receivers": [[3, -0.1]],
        "paths": [{ "name": "through", "steps": [{ "refract": "lens" }, { "refract": "lens" }] }]
    }"#,
    )
    .expect("valid scene");
    let rays = json_rays(&scene);
    assert_eq!(rays[0]["status"], "converged", "{}", rays[0]);
    assert_eq!(rays[0]["media"], serde_json::json!(["air", "glass", "air"]));
    let csv = String::from_utf8(written(&scene, Format::Csv)).unwrap();
    let fields = csv_fields(csv.lines().nth(1).unwrap());
    assert_eq!(fields[8], "through");
    assert_eq!(fields[9], "air;glass;air");
    let npy = read_npy(&written(&scene, Format::Npy));
    let legs: Vec<u32> = (0..3)
        .map(|j| u32_at(&npy.records[0], 97 + 4 * j))
        .collect();
    // air = 0, glass = 1: the scene's media in the order of their names.
    assert_eq!(legs, [0, 1, 0]);
}

/// A medium name that CSV must quote: the whole `media` field is quoted.
#[test]
fn csv_quotes_a_media_field_whose_names_need_it() {
    let scene = Scene::from_json(
        r#"{
        "media": { "air, dry": { "speed": 1 }, "water": { "speed": 0.5 } },
        "interfaces": { "surface": { "points": [[-10, 0], [10, 0]] } },
        "sources": [[0, 1]], "receivers": [[1, -1]],
        "paths": [{ "steps": [{ "refract": "surface" }], "media": ["air, dry", "water"] }]
    }"#,
    )
    .expect("valid scene");
    let csv = String::from_utf8(written(&scene, Format::Csv)).unwrap();
    let line = csv.lines().nth(1).unwrap();
    assert!(line.contains(",\"air, dry;water\","), "{line}");
    assert_eq!(csv_fields(line)[9], "air, dry;water");
}

/// A valley (a maximum-type kink at its bottom), a roof (a minimum-type kink at its apex) and
/// the direct ray, every stationary path of each (`"stationary": "all"`).
const EVERY: &str = include_str!("../fixtures/every_stationary.json");

fn stationary_written(format: Format) -> (Scene, eigenray::StationaryRays, Vec<u8>) {
    let scene = Scene::from_json(EVERY).expect("valid scene");
    let rays = Tracer::new(&scene)
        .expect("tracer")
        .trace_stationary(&eigenray::options::Run::new())
        .expect("at most 12 steps");
    let mut out = Vec::new();
    write(&scene, &rays, format, &mut out).expect("write");
    (scene, rays, out)
}

fn stationary_json() -> Vec<Value> {
    let (_, _, out) = stationary_written(Format::Json);
    let doc: Value = serde_json::from_slice(&out).expect("JSON");
    assert_eq!(doc.as_object().unwrap().len(), 1, "rays only: {doc}");
    doc["rays"].as_array().expect("rays").clone()
}

#[test]
fn every_stationary_path_is_one_entry_with_its_arrival_kink_and_completeness() {
    let rays = stationary_json();
    let (_, st, _) = stationary_written(Format::Json);
    assert_eq!(rays.len(), st.entries());
    // Triple order, then time; `arrival` counts within the triple from 0.
    let key = |r: &Value| {
        (
            r["source"].as_u64().unwrap(),
            r["receiver"].as_u64().unwrap(),
            r["path"].as_u64().unwrap(),
        )
    };
    for w in rays.windows(2) {
        if key(&w[0]) == key(&w[1]) {
            assert_eq!(w[1]["arrival"], w[0]["arrival"].as_u64().unwrap() + 1);
            assert!(w[0]["time"].as_f64() <= w[1]["time"].as_f64(), "{w:?}");
        } else {
            assert!(key(&w[0]) < key(&w[1]), "{w:?}");
            assert_eq!(w[1]["arrival"], 0);
        }
    }
    for r in &rays {
        assert_eq!(r["complete"], true, "{r}");
        let vertex = r["status"] == "vertex";
        assert_eq!(
            r.get("kink").is_some(),
            vertex,
            "kink on vertex entries only: {r}"
        );
    }
    // By hand, source 0 to receiver 0 off the valley: the two slopes' specular points, at
    // (±1.875, −0.75), each 2 × √11.25 = √45 away, then the bottom (0, −2), 2 × √16.25, a
    // maximum-type kink.
    let valley: Vec<&Value> = rays.iter().filter(|r| key(r) == (0, 0, 0)).collect();
    assert_eq!(valley.len(), 3);
    for (k, x) in [(0, -1.875), (1, 1.875)] {
        assert_eq!(valley[k]["status"], "converged");
        assert!(close(valley[k]["time"].as_f64().unwrap(), 45f64.sqrt()));
        let p = points(&valley[k]["points"]);
        assert!(close(p[1][0], x) && close(p[1][1], -0.75), "{p:?}");
    }
    assert_eq!(valley[2]["status"], "vertex");
    assert_eq!(valley[2]["kink"], "maximum");
    assert_eq!(points(&valley[2]["points"])[1], [0.0, -2.0]);
    assert!(close(
        valley[2]["time"].as_f64().unwrap(),
        2.0 * 16.25f64.sqrt()
    ));
    // Source 1 to receiver 1 off the roof: only its apex (10, 2), a minimum-type kink.
    let roof: Vec<&Value> = rays.iter().filter(|r| key(r) == (1, 1, 1)).collect();
    assert_eq!(roof.len(), 1);
    assert_eq!(roof[0]["status"], "vertex");
    assert_eq!(roof[0]["kink"], "minimum");
    assert!(close(
        roof[0]["time"].as_f64().unwrap(),
        2.0 * 4.25f64.sqrt()
    ));
    // Source 0 sees no reflection off the roof at receiver 0: one `no_path` entry, a proof.
    let none: Vec<&Value> = rays.iter().filter(|r| key(r) == (0, 0, 1)).collect();
    assert_eq!(none.len(), 1);
    assert_eq!(none[0]["status"], "no_path");
    assert_eq!(none[0]["arrival"], 0);
    assert!(none[0].get("time").is_none() && none[0].get("points").is_none());
    assert_eq!(none[0]["path_name"], "roof");
    assert_eq!(none[0]["media"], serde_json::json!(["air", "air"]));
    // JSON Lines: the same objects.
    let (_, _, jsonl) = stationary_written(Format::Jsonl);
    let lines: Vec<Value> = String::from_utf8(jsonl)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines, rays);
}

#[test]
fn an_incomplete_triple_says_so_on_every_entry_and_is_never_no_path() {
    let scene = Scene::from_json(EVERY).unwrap();
    let mut st = Tracer::new(&scene)
        .unwrap()
        .trace_stationary(&eigenray::options::Run::new())
        .unwrap();
    // As a search that reached its limit leaves them: the valley's triple with its first
    // arrival only, the roof's with none.
    st.triples[0].arrivals.truncate(1);
    st.triples[0].complete = false;
    st.triples[1].complete = false;
    assert!(st.triples[1].arrivals.is_empty());
    let mut out = Vec::new();
    write(&scene, &st, Format::Json, &mut out).unwrap();
    let doc: Value = serde_json::from_slice(&out).unwrap();
    let rays = doc["rays"].as_array().unwrap();
    assert_eq!(rays[0]["complete"], false);
    assert_eq!(rays[0]["status"], "converged");
    assert_eq!(rays[1]["path"], 1);
    assert_eq!(rays[1]["complete"], false);
    assert_eq!(rays[1]["status"], "not_converged");
    assert!(
        rays[1]["reason"].as_str().unwrap().contains("limit"),
        "{}",
        rays[1]
    );
    assert!(rays[2..].iter().all(|r| r["complete"] == true));
}

#[test]
fn csv_of_every_stationary_path_appends_arrival_kink_and_complete() {
    let rays = stationary_json();
    let (_, _, out) = stationary_written(Format::Csv);
    let text = String::from_utf8(out).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "source,receiver,path,status,time,iterations,residual,points,path_name,media,reason,\
         arrival,kink,complete"
    );
    let records: Vec<Vec<String>> = lines.map(csv_fields).collect();
    assert_eq!(records.len(), rays.len());
    for (f, r) in records.iter().zip(&rays) {
        assert_eq!(f.len(), 14, "{f:?}");
        assert_eq!(f[3], r["status"].as_str().unwrap());
        assert_eq!(f[11].parse::<u64>().ok(), r["arrival"].as_u64());
        assert_eq!(f[12], r["kink"].as_str().unwrap_or(""));
        assert_eq!(f[13], "true");
        match r["time"].as_f64() {
            Some(t) => assert_eq!(f[4].parse::<f64>().unwrap().to_bits(), t.to_bits()),
            None => assert_eq!(f[4], ""),
        }
    }
    assert!(records.iter().any(|f| f[12] == "maximum"));
    assert!(records.iter().any(|f| f[12] == "minimum"));
}

/// The header dictionary and the data of a `.npy` file.
fn npy_parts(bytes: &[u8]) -> (String, &[u8]) {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + len) % 64, 0, "data aligned to 64 bytes");
    let header = String::from_utf8(bytes[10..10 + len].to_vec()).unwrap();
    assert!(header.ends_with('\n'));
    (header, &bytes[10 + len..])
}

#[test]
fn npy_of_every_stationary_path_appends_arrival_kink_and_complete() {
    let rays = stationary_json();
    let (_, _, out) = stationary_written(Format::Npy);
    let (header, data) = npy_parts(&out);
    assert!(
        header.contains(
            "('points', '<f8', (3, 2)), ('media', '<u4', (2,)), ('arrival', '<u4'), \
             ('kink', '|u1'), ('complete', '|u1')]"
        ),
        "{header}"
    );
    assert!(header.contains(&format!("'shape': ({},)", rays.len())));
    // The rays' record (3 points, 2 legs), then 4 + 1 + 1 bytes.
    let size = 3 * 4 + 1 + 4 + 8 + 8 + 16 * 3 + 4 * 2 + 6;
    assert_eq!(data.len(), size * rays.len());
    for (rec, r) in data.chunks(size).zip(&rays) {
        assert_eq!(Some(u64::from(u32_at(rec, 8))), r["path"].as_u64());
        match r["time"].as_f64() {
            Some(t) => assert_eq!(f64_at(rec, 17).to_bits(), t.to_bits(), "{r}"),
            None => assert!(f64_at(rec, 17).is_nan()),
        }
        assert_eq!(
            Some(u64::from(u32_at(rec, 89))),
            r["arrival"].as_u64(),
            "{r}"
        );
        // The documented kink codes, by hand.
        let kink = match r["kink"].as_str() {
            None => 0,
            Some("minimum") => 1,
            Some("maximum") => 2,
            Some(other) => panic!("kink {other}"),
        };
        assert_eq!(rec[93], kink, "{r}");
        assert_eq!(
            eigenray::output::KINK_CODES[usize::from(rec[93])].map(|k| k.as_str()),
            r["kink"].as_str()
        );
        assert_eq!(rec[94], 1);
    }
}

/// Search arrivals built by hand, as the search gives them: the direct ray, then a vertex
/// arrival off the valley, then an obstructed one from an incomplete search.
fn hand_built_arrivals(scene: &Scene) -> Vec<SearchArrival> {
    let valley = scene.interface_index("valley").expect("valley");
    let roof = scene.interface_index("roof").expect("roof");
    let air = scene.medium_index("air").expect("air");
    let arrival = |status, time, points: Vec<Point>, kink, reason| Arrival {
        status,
        time,
        parameters: vec![0.0; points.len() - 2],
        segments: vec![0; points.len() - 2],
        media: vec![air; points.len() - 1],
        points,
        iterations: 2,
        reason,
        kink,
        residual: 1e-16,
        amplitude: None,
        turns: None,
        caustics: None,
        launch_angle: None,
    };
    vec![
        SearchArrival {
            source: 0,
            receiver: 0,
            steps: vec![],
            arrival: arrival(
                Status::Converged,
                1.0,
                vec![Point::new(-0.5, 2.0), Point::new(0.5, 2.0)],
                None,
                None,
            ),
            complete: true,
            heights: Vec::new(),
        },
        SearchArrival {
            source: 0,
            receiver: 0,
            steps: vec![Step {
                kind: StepKind::Reflect,
                interface: valley,
            }],
            arrival: arrival(
                Status::Vertex,
                2.0 * 16.25f64.sqrt(),
                vec![
                    Point::new(-0.5, 2.0),
                    Point::new(0.0, -2.0),
                    Point::new(0.5, 2.0),
                ],
                Some(Kink::Maximum),
                Some(Reason::AtVertex { step: 0 }),
            ),
            complete: true,
            heights: Vec::new(),
        },
        SearchArrival {
            source: 0,
            receiver: 1,
            steps: vec![
                Step {
                    kind: StepKind::Reflect,
                    interface: roof,
                },
                Step {
                    kind: StepKind::Refract,
                    interface: valley,
                },
            ],
            arrival: arrival(
                Status::Obstructed,
                20.5,
                vec![
                    Point::new(-0.5, 2.0),
                    Point::new(9.0, 1.0),
                    Point::new(1.5, -1.0),
                    Point::new(10.5, 4.0),
                ],
                None,
                Some(Reason::Crosses {
                    leg: 1,
                    interface: valley,
                }),
            ),
            complete: false,
            heights: Vec::new(),
        },
    ]
}

/// The arrival objects the JSON formats write for [`hand_built_arrivals`], worked out by hand.
fn hand_built_json() -> Value {
    serde_json::json!([
        { "source": 0, "receiver": 0, "steps": [], "media": ["air"], "status": "converged",
          "time": 1.0, "points": [[-0.5, 2.0], [0.5, 2.0]], "iterations": 2,
          "residual": 1e-16, "complete": true },
        { "source": 0, "receiver": 0, "steps": [{ "reflect": "valley" }],
          "media": ["air", "air"], "status": "vertex", "kink": "maximum",
          "time": 2.0 * 16.25f64.sqrt(), "points": [[-0.5, 2.0], [0.0, -2.0], [0.5, 2.0]],
          "iterations": 2, "residual": 1e-16, "reason": "step 0 is held on a polyline vertex",
          "complete": true },
        { "source": 0, "receiver": 1, "steps": [{ "reflect": "roof" }, { "refract": "valley" }],
          "media": ["air", "air", "air"], "status": "obstructed", "time": 20.5,
          "points": [[-0.5, 2.0], [9.0, 1.0], [1.5, -1.0], [10.5, 4.0]], "iterations": 2,
          "residual": 1e-16, "reason": "leg 1 crosses interface `valley`", "complete": false }
    ])
}

#[test]
fn search_arrivals_follow_the_rays_in_json_and_json_lines() {
    let (scene, st, _) = stationary_written(Format::Json);
    let arrivals = hand_built_arrivals(&scene);
    let want = hand_built_json();
    // JSON: a second top-level key.
    let mut out = Vec::new();
    write(
        &scene,
        eigenray::Document::from(&st).with_arrivals(&arrivals),
        Format::Json,
        &mut out,
    )
    .unwrap();
    let doc: Value = serde_json::from_slice(&out).expect("one JSON document");
    assert_eq!(doc["arrivals"], want);
    assert_eq!(doc["rays"].as_array().unwrap().len(), st.entries());
    let keys: Vec<&String> = doc.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["arrivals", "rays"]);
    // Without arrivals the document is the rays' alone, byte for byte.
    let mut alone = Vec::new();
    write(&scene, &st, Format::Json, &mut alone).unwrap();
    let mut none = Vec::new();
    write(&scene, &st, Format::Json, &mut none).unwrap();
    assert_eq!(none, alone);
    // An empty search is an empty list, not a missing key.
    let mut empty = Vec::new();
    write(
        &scene,
        eigenray::Document::from(&st).with_arrivals(&[]),
        Format::Json,
        &mut empty,
    )
    .unwrap();
    let doc: Value = serde_json::from_slice(&empty).unwrap();
    assert_eq!(doc["arrivals"], serde_json::json!([]));

    // JSON Lines: the rays' lines, then one marked line per arrival.
    let mut out = Vec::new();
    write(
        &scene,
        eigenray::Document::from(&st).with_arrivals(&arrivals),
        Format::Jsonl,
        &mut out,
    )
    .unwrap();
    let lines: Vec<Value> = String::from_utf8(out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let (rays, marked) = lines.split_at(st.entries());
    assert!(rays.iter().all(|r| r.get("kind").is_none()));
    for (line, want) in marked.iter().zip(want.as_array().unwrap()) {
        let mut line = line.clone();
        assert_eq!(
            line.as_object_mut().unwrap().remove("kind"),
            Some("arrival".into())
        );
        assert_eq!(&line, want);
    }
    assert_eq!(marked.len(), 3);
    // On their own: `{"arrivals": [...]}` and the marked lines.
    let mut own = Vec::new();
    write(&scene, &arrivals, Format::Json, &mut own).unwrap();
    assert_eq!(
        serde_json::from_slice::<Value>(&own).unwrap(),
        serde_json::json!({ "arrivals": want })
    );
    let mut own = Vec::new();
    write(&scene, &arrivals, Format::Jsonl, &mut own).unwrap();
    assert_eq!(String::from_utf8(own).unwrap().lines().count(), 3);
}

#[test]
fn csv_and_npy_refuse_arrivals_beside_the_rays_and_write_them_on_their_own() {
    let (scene, st, _) = stationary_written(Format::Json);
    let arrivals = hand_built_arrivals(&scene);
    for format in [Format::Csv, Format::Npy] {
        let mut out = Vec::new();
        let err = write(
            &scene,
            eigenray::Document::from(&st).with_arrivals(&arrivals),
            format,
            &mut out,
        )
        .unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidInput);
        assert!(err.to_string().contains("document of their own"), "{err}");
        assert!(out.is_empty(), "nothing half-written");
    }

    // CSV: a table of its own.
    let mut out = Vec::new();
    write(&scene, &arrivals, Format::Csv, &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    let lines: Vec<Vec<String>> = text.lines().map(csv_fields).collect();
    assert_eq!(
        lines[0],
        [
            "source",
            "receiver",
            "steps",
            "media",
            "status",
            "kink",
            "time",
            "points",
            "iterations",
            "residual",
            "reason",
            "complete"
        ]
    );
    assert_eq!(lines.len(), 4);
    assert_eq!(lines[1][2], "");
    assert_eq!(lines[1][3], "air");
    assert_eq!(lines[1][7], "-0.5 2.0;0.5 2.0");
    assert_eq!(lines[2][2], "reflect:valley");
    assert_eq!(lines[2][4], "vertex");
    assert_eq!(lines[2][5], "maximum");
    assert_eq!(lines[2][6].parse::<f64>().unwrap(), 2.0 * 16.25f64.sqrt());
    assert_eq!(lines[3][2], "reflect:roof;refract:valley");
    assert_eq!(lines[3][3], "air;air;air");
    assert_eq!(lines[3][10], "leg 1 crosses interface `valley`");
    assert_eq!(lines[3][11], "false");

    // `.npy`: records of their own, sized by the most steps (2 here: no `search` section).
    let mut out = Vec::new();
    write(&scene, &arrivals, Format::Npy, &mut out).unwrap();
    let (header, data) = npy_parts(&out);
    assert!(
        header.contains(
            "[('source', '<u4'), ('receiver', '<u4'), ('steps', '<u4'), \
             ('step_kind', '|u1', (2,)), ('step_interface', '<u4', (2,)), ('status', '|u1'), \
             ('kink', '|u1'), ('complete', '|u1'), ('iterations', '<u4'), ('time', '<f8'), \
             ('residual', '<f8'), ('points', '<f8', (4, 2)), ('media', '<u4', (3,))]"
        ),
        "{header}"
    );
    assert!(header.contains("'shape': (3,)"), "{header}");
    let size = 12 + 2 + 8 + 3 + 4 + 16 + 64 + 12;
    assert_eq!(data.len(), 3 * size);
    let recs: Vec<&[u8]> = data.chunks(size).collect();
    // By hand: interfaces in the order of their names (roof 0, valley 1).
    assert_eq!(u32_at(recs[0], 8), 0);
    assert_eq!(&recs[0][12..14], [255, 255]);
    assert_eq!(u32_at(recs[2], 8), 2);
    assert_eq!(&recs[2][12..14], [0, 1]);
    assert_eq!([u32_at(recs[2], 14), u32_at(recs[2], 18)], [0, 1]);
    assert_eq!([u32_at(recs[1], 14), u32_at(recs[1], 18)], [1, u32::MAX]);
    // status, kink, complete
    assert_eq!(recs[1][22..25], [1, 2, 1]);
    assert_eq!(recs[2][22..25], [3, 0, 0]);
    assert_eq!(u32_at(recs[1], 25), 2);
    assert_eq!(f64_at(recs[1], 29), 2.0 * 16.25f64.sqrt());
    assert_eq!(f64_at(recs[1], 37), 1e-16);
    // Points from byte 45: the direct ray's two, then NaN.
    assert_eq!([f64_at(recs[0], 45), f64_at(recs[0], 53)], [-0.5, 2.0]);
    assert_eq!([f64_at(recs[0], 61), f64_at(recs[0], 69)], [0.5, 2.0]);
    assert!(f64_at(recs[0], 77).is_nan() && f64_at(recs[0], 101).is_nan());
    // Media from byte 109: air is medium 0; the direct ray's one leg, then the mark.
    assert_eq!(
        [
            u32_at(recs[0], 109),
            u32_at(recs[0], 113),
            u32_at(recs[0], 117)
        ],
        [0, u32::MAX, u32::MAX]
    );
    assert_eq!(u32_at(recs[2], 117), 0);
}

/// The items of a CSV list cell: split at every `;` that is not escaped, each `\;` and `\\`
/// turned back into `;` and `\` (the reader the format documents, written here apart from
/// the writer).
fn csv_list(cell: &str) -> Vec<String> {
    let mut items = vec![String::new()];
    let mut chars = cell.chars();
    while let Some(c) = chars.next() {
        match c {
            '\\' => items.last_mut().unwrap().extend(chars.next()),
            ';' => items.push(String::new()),
            c => items.last_mut().unwrap().push(c),
        }
    }
    items
}

/// Names that a spreadsheet would run as formulas are written as text (`'` in front, quoted),
/// and names holding `;` or `\` survive the list columns: the rays' and the arrivals' CSV give
/// every name back.
#[test]
fn csv_names_are_safe_to_open_and_split() {
    let evil = "=HYPERLINK(\"http://x\";\"y\")";
    let semi = r"wa;ter\deep";
    let doc = serde_json::json!({
        "media": { evil: { "speed": 1.0 }, semi: { "speed": 0.75, "at": [0.5, -0.5] } },
        "background": evil,
        "domain": [[-2, -3], [5, 3]],
        "interfaces": { "@surface": { "points": [[-2, 0], [5, 0]] } },
        "sources": [[0, 1]], "receivers": [[1, -1]],
        "paths": [{ "name": "+bounce", "steps": [{ "refract": "@surface" }] }],
        "search": { "max_steps": 1 }
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let mut rays = Vec::new();
    write(&scene, &tracer.trace_all(), Format::Csv, &mut rays).unwrap();
    let text = String::from_utf8(rays).unwrap();
    let row = csv_fields(text.lines().nth(1).unwrap());
    // path_name and media: text cells that start with a formula character get a `'`.
    assert_eq!(row[8], "'+bounce");
    let media = row[9].strip_prefix('\'').expect("a formula-safe cell");
    assert_eq!(csv_list(media), [evil, semi]);
    for line in text.lines() {
        for cell in csv_fields(line) {
            assert!(!cell.starts_with(['=', '+', '@']), "{cell}");
        }
    }
    let arrivals = tracer
        .search(&eigenray::options::Run::new())
        .unwrap()
        .arrivals;
    let mut out = Vec::new();
    write(&scene, &arrivals, Format::Csv, &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    let row = csv_fields(text.lines().nth(1).unwrap());
    assert_eq!(csv_list(&row[2]), ["refract:@surface"]);
    assert_eq!(csv_list(row[3].strip_prefix('\'').unwrap()), [evil, semi]);
}
