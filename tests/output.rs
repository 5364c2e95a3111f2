//! The output formats read back: every field of JSON, JSON Lines, CSV and `.npy` (with its name
//! tables) against the JSON document and against values worked out by hand.

use eigenray::{BatchOptions, Format, Scene, Tracer, write_batch, write_names, write_rays};
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
    let batch = tracer.trace_batch(&BatchOptions::default());
    let mut out = Vec::new();
    write_batch(scene, &batch, format, &mut out).expect("write");
    let mut owned = Vec::new();
    write_rays(scene, &tracer.trace_all(), format, &mut owned).expect("write");
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
