//! Integration tests of the `eigenray` command line: `solve`'s output, invalid scenes, the
//! demo.

use std::ffi::OsStr;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;

const BIN: &str = env!("CARGO_BIN_EXE_eigenray");

/// Snell's law for source (0, 1), receiver (1, −1), indices 1 and 1.333 across y = 0.
const SNELL_TIME: f64 = 2.601764023084769;

/// A file in the temporary directory, removed when dropped.
struct TempFile(PathBuf);

impl TempFile {
    /// A unique path (nothing written yet).
    fn path_only(name: &str) -> TempFile {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        TempFile(
            std::env::temp_dir().join(format!("eigenray-cli-{}-{n}-{name}", std::process::id())),
        )
    }
    fn with(name: &str, contents: impl AsRef<[u8]>) -> TempFile {
        let f = TempFile::path_only(name);
        std::fs::write(&f.0, contents).expect("write temp file");
        f
    }
    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

fn run<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    Command::new(BIN).args(args).output().expect("run eigenray")
}

fn text(bytes: &[u8]) -> &str {
    std::str::from_utf8(bytes).expect("UTF-8 output")
}

/// Runs `eigenray solve` on `scene` (written to a temp file); asserts success; returns the
/// document.
fn solve(scene: &str) -> Value {
    let file = TempFile::with("scene.json", scene);
    let out = run([OsStr::new("solve"), file.path().as_os_str()]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    assert!(out.stderr.is_empty(), "stderr: {}", text(&out.stderr));
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON document")
}

/// Checks the documented shape of every ray: count, order, indices, and `time`/`points`
/// present exactly for `converged`, `vertex` and `obstructed` (with steps + 2 points).
fn check_rays(doc: &Value, sources: usize, receivers: usize, steps: &[usize]) -> Vec<Value> {
    let rays = doc["rays"].as_array().expect("`rays` is an array").clone();
    assert_eq!(rays.len(), sources * receivers * steps.len());
    for (idx, ray) in rays.iter().enumerate() {
        let path = idx % steps.len();
        let receiver = (idx / steps.len()) % receivers;
        let source = idx / (steps.len() * receivers);
        assert_eq!(ray["source"], source, "ray {idx}");
        assert_eq!(ray["receiver"], receiver, "ray {idx}");
        assert_eq!(ray["path"], path, "ray {idx}");
        assert!(ray["iterations"].is_u64(), "ray {idx}: iterations");
        let status = ray["status"].as_str().expect("status is a string");
        assert!(
            [
                "converged",
                "vertex",
                "no_path",
                "obstructed",
                "not_converged"
            ]
            .contains(&status),
            "ray {idx}: status {status}"
        );
        let has_time = matches!(status, "converged" | "vertex" | "obstructed");
        assert_eq!(
            ray.get("time").is_some(),
            has_time,
            "ray {idx}: time with status {status}"
        );
        assert_eq!(
            ray.get("points").is_some(),
            has_time,
            "ray {idx}: points with status {status}"
        );
        if has_time {
            assert!(
                ray["time"]
                    .as_f64()
                    .is_some_and(|t| t.is_finite() && t > 0.0),
                "ray {idx}: time"
            );
            let points = ray["points"].as_array().expect("points is an array");
            assert_eq!(
                points.len(),
                steps[path] + 2,
                "ray {idx}: source, interactions, receiver"
            );
            for p in points {
                let p = p.as_array().expect("a point is an array");
                assert_eq!(p.len(), 2);
                assert!(p.iter().all(|c| c.as_f64().is_some_and(f64::is_finite)));
            }
        }
    }
    rays
}

fn point(v: &Value) -> [f64; 2] {
    [v[0].as_f64().expect("x"), v[1].as_f64().expect("y")]
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

const AIR_WATER: &str = r#"{
    "media": { "air": { "index": 1.0 }, "water": { "index": 1.333 } },
    "interfaces": { "surface": { "points": [[-1, 0], [2, 0]] } },
    "sources": [[0, 1]],
    "receivers": [[1, -1], [0.5, -1]],
    "paths": [
        { "name": "transmitted", "steps": [{ "refract": "surface" }], "media": ["air", "water"] },
        { "name": "bounce", "steps": [{ "reflect": "surface" }], "media": ["air", "air"] }
    ]
}"#;

/// The minimiser of `n1·√(x² + 1) + n2·√((1 − x)² + 1)` by bisection on its derivative.
fn snell_time(n1: f64, n2: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..200 {
        let x = 0.5 * (lo + hi);
        let d = n1 * x / (x * x + 1.0).sqrt() - n2 * (1.0 - x) / ((1.0 - x).powi(2) + 1.0).sqrt();
        if d > 0.0 { hi = x } else { lo = x }
    }
    let x = 0.5 * (lo + hi);
    (
        x,
        n1 * (x * x + 1.0).sqrt() + n2 * ((1.0 - x).powi(2) + 1.0).sqrt(),
    )
}

#[test]
fn solve_refraction_matches_snell_and_reflection_below_has_no_path() {
    let doc = solve(AIR_WATER);
    let rays = check_rays(&doc, 1, 2, &[1, 1]);
    let (x, t) = snell_time(1.0, 1.333);
    assert!(close(t, SNELL_TIME, 1e-14), "closed form {t}");

    // Ray 0: source 0, receiver (1, −1), transmitted.
    assert_eq!(rays[0]["status"], "converged");
    let time = rays[0]["time"].as_f64().expect("time");
    assert!(
        close(time, SNELL_TIME, 1e-12),
        "time {time} vs {SNELL_TIME}"
    );
    let pts: Vec<[f64; 2]> = rays[0]["points"]
        .as_array()
        .expect("points")
        .iter()
        .map(point)
        .collect();
    assert_eq!(pts[0], [0.0, 1.0]);
    assert_eq!(pts[2], [1.0, -1.0]);
    assert!(
        (pts[1][0] - x).abs() < 1e-9 && pts[1][1].abs() < 1e-12,
        "interaction {:?}",
        pts[1]
    );

    // Ray 1: the reflection with the receiver under the surface.
    assert_eq!(rays[1]["status"], "no_path");
    // Rays 2 and 3: receiver (0.5, −1).
    assert_eq!(rays[2]["status"], "converged");
    assert_eq!(rays[3]["status"], "no_path");
}

#[test]
fn batch_with_failures_writes_every_ray_in_order() {
    let scene = r#"{
        "media": { "air": { "index": 1.0 }, "water": { "index": 1.333 } },
        "interfaces": { "surface": { "points": [[-1, 0], [2, 0]] } },
        "sources": [[0, 1], [0.3, 2]],
        "receivers": [[1, -1], [0.5, 0.5], [3, -1]],
        "paths": [
            { "name": "transmitted", "steps": [{ "refract": "surface" }], "media": ["air", "water"] },
            { "name": "bounce", "steps": [{ "reflect": "surface" }], "media": ["air", "air"] },
            { "name": "direct", "steps": [], "media": ["air"] }
        ]
    }"#;
    let doc = solve(scene);
    let rays = check_rays(&doc, 2, 3, &[1, 1, 0]);
    // [source][receiver][path]
    let expected = [
        [
            ["converged", "no_path", "obstructed"], // (1, −1) under the surface
            ["no_path", "converged", "converged"],  // (0.5, 0.5) above it
            ["no_path", "no_path", "obstructed"],   // (3, −1): the refraction point is past x = 2
        ],
        [
            ["converged", "no_path", "obstructed"],
            ["no_path", "converged", "converged"],
            ["no_path", "no_path", "converged"], // the straight line passes beyond the end
        ],
    ];
    for (s, per_source) in expected.iter().enumerate() {
        for (r, per_receiver) in per_source.iter().enumerate() {
            for (p, status) in per_receiver.iter().enumerate() {
                let idx = (s * 3 + r) * 3 + p;
                assert_eq!(
                    rays[idx]["status"], *status,
                    "ray {idx}: source {s}, receiver {r}, path {p}"
                );
            }
        }
    }
    // Direct rays take the straight-line time; the bounce takes the mirror image's distance.
    let direct = rays[(3 + 2) * 3 + 2]["time"].as_f64().expect("time");
    assert!(
        close(direct, (2.7_f64.powi(2) + 9.0).sqrt(), 1e-12),
        "direct {direct}"
    );
    let bounce = rays[3 + 1]["time"].as_f64().expect("time");
    assert!(close(bounce, 2.5_f64.sqrt(), 1e-12), "bounce {bounce}");
}

#[test]
fn solve_reads_standard_input_and_writes_json_lines_and_npy() {
    let file = TempFile::with("scene.json", AIR_WATER);
    let from_file = run([OsStr::new("solve"), file.path().as_os_str()]);
    assert_eq!(from_file.status.code(), Some(0));

    let mut child = Command::new(BIN)
        .args(["solve", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn eigenray");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(AIR_WATER.as_bytes())
        .expect("write stdin");
    let from_stdin = child.wait_with_output().expect("wait");
    assert_eq!(
        from_stdin.status.code(),
        Some(0),
        "stderr: {}",
        text(&from_stdin.stderr)
    );
    assert_eq!(from_stdin.stdout, from_file.stdout);

    let lines = run([
        OsStr::new("solve"),
        OsStr::new("--format"),
        OsStr::new("jsonl"),
        file.path().as_os_str(),
    ]);
    assert_eq!(lines.status.code(), Some(0));
    let doc: Value = serde_json::from_slice(&from_file.stdout).expect("JSON");
    let rays = doc["rays"].as_array().expect("rays");
    let per_line: Vec<Value> = text(&lines.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object per line"))
        .collect();
    assert_eq!(&per_line, rays);

    // The .npy file: its header, then one 89-byte record per ray (3 points, 2 legs) whose
    // time is the JSON document's (NaN for a ray without one); `--names` writes the tables
    // that name its codes and indices.
    let names = TempFile::path_only("names.json");
    let npy = run([
        OsStr::new("solve"),
        OsStr::new("--format"),
        OsStr::new("npy"),
        OsStr::new("--names"),
        names.path().as_os_str(),
        file.path().as_os_str(),
    ]);
    assert_eq!(npy.status.code(), Some(0), "stderr: {}", text(&npy.stderr));
    let tables: Value =
        serde_json::from_str(&std::fs::read_to_string(names.path()).expect("names written"))
            .expect("names are JSON");
    assert_eq!(tables["media"], serde_json::json!(["air", "water"]));
    assert_eq!(tables["status"][2], "no_path");
    assert_eq!(
        tables["paths"],
        serde_json::json!(["transmitted", "bounce"])
    );
    let bytes = &npy.stdout;
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let data = &bytes[10 + u16::from_le_bytes([bytes[8], bytes[9]]) as usize..];
    assert_eq!(data.len(), rays.len() * 89);
    for (record, ray) in data.chunks(89).zip(rays) {
        let time = f64::from_le_bytes(record[17..25].try_into().expect("8 bytes"));
        match ray["time"].as_f64() {
            Some(t) => assert_eq!(time, t),
            None => assert!(time.is_nan()),
        }
    }
}

#[test]
fn solve_svg_option_draws_the_scene_and_keeps_stdout() {
    let file = TempFile::with("scene.json", AIR_WATER);
    let svg = TempFile::path_only("solve.svg");
    let plain = run([OsStr::new("solve"), file.path().as_os_str()]);
    let drawn = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--svg"),
        svg.path().as_os_str(),
    ]);
    assert_eq!(
        drawn.status.code(),
        Some(0),
        "stderr: {}",
        text(&drawn.stderr)
    );
    assert_eq!(drawn.stdout, plain.stdout);
    let picture = std::fs::read_to_string(svg.path()).expect("SVG written");
    assert!(picture.starts_with("<?xml") || picture.starts_with("<svg"));
    assert!(picture.contains("<polyline"));
    assert!(picture.trim_end().ends_with("</svg>"));

    // An SVG that cannot be written: refused before anything is solved (exit 2), nothing on
    // stdout.
    let bad = std::env::temp_dir()
        .join("eigenray-no-such-dir-for-cli-test")
        .join("x.svg");
    let out = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--svg"),
        bad.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    assert!(text(&out.stderr).starts_with("error: "));
}

#[test]
fn invalid_scenes_exit_2_and_name_the_key() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join("invalid");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("fixtures/invalid")
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 12, "only {} invalid scenes", scenes.len());
    let mut failures = Vec::new();
    for scene in &scenes {
        let key_file = scene.with_extension("key");
        let key = std::fs::read_to_string(&key_file)
            .unwrap_or_else(|_| panic!("{} has no .key", scene.display()));
        let key = key.trim();
        assert!(!key.is_empty(), "{} is empty", key_file.display());
        let out = run([OsStr::new("solve"), scene.as_os_str()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        let name = scene
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let ok = out.status.code() == Some(2)
            && out.stdout.is_empty()
            && stderr.starts_with("error: ")
            && stderr.ends_with('\n')
            && stderr.lines().count() == 1
            && stderr.contains(key);
        if !ok {
            failures.push(format!(
                "{name}: status {:?}, stdout {} bytes, expected key `{key}`, stderr: {stderr:?}",
                out.status.code(),
                out.stdout.len()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} invalid scenes:\n{}",
        failures.len(),
        scenes.len(),
        failures.join("\n")
    );
}

#[test]
fn missing_file_exits_2_and_names_the_path() {
    let missing = TempFile::path_only("missing.json");
    let out = run([OsStr::new("solve"), missing.path().as_os_str()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let stderr = text(&out.stderr);
    let expected = format!("error: {}: cannot read: ", missing.path().display());
    assert!(stderr.starts_with(&expected), "stderr: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "stderr: {stderr}");
}

#[test]
fn unreadable_inputs_exit_2() {
    // Not UTF-8.
    let binary = TempFile::with("binary.json", b"{\"media\": \xff\xfe}");
    let out = run([OsStr::new("solve"), binary.path().as_os_str()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains(&binary.path().display().to_string()) && stderr.contains("UTF-8"),
        "stderr: {stderr}"
    );
    assert_eq!(stderr.lines().count(), 1);

    // A directory.
    let out = run([OsStr::new("solve"), std::env::temp_dir().as_os_str()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    assert_eq!(text(&out.stderr).lines().count(), 1);
}

#[test]
fn usage_errors_exit_2() {
    for args in [
        &["solve"][..],
        &["frobnicate"],
        &["solve", "a.json", "--format", "xml"],
        &["demo", "--receivers", "-1"],
    ] {
        let out = run(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    let help = run(["--help"]);
    assert_eq!(help.status.code(), Some(0));
    assert!(text(&help.stdout).contains("solve"));
}

#[test]
fn demo_prints_a_summary_and_writes_an_svg() {
    let svg = TempFile::path_only("demo.svg");
    let out = run([
        OsStr::new("demo"),
        OsStr::new("--svg"),
        svg.path().as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 2, "stdout: {stdout}");
    assert!(
        lines[0].starts_with("demo: ") && lines[0].contains("500 rays"),
        "summary: {}",
        lines[0]
    );
    assert!(lines[0].contains("500 converged"), "summary: {}", lines[0]);
    assert_eq!(lines[1], format!("wrote {}", svg.path().display()));
    let picture = std::fs::read_to_string(svg.path()).expect("SVG written");
    assert!(picture.starts_with("<?xml") || picture.starts_with("<svg"));
    assert!(
        picture.matches("<polyline").count() >= 500,
        "one polyline per ray"
    );
    assert!(picture.trim_end().ends_with("</svg>"));
}

#[test]
fn demo_options_and_no_arguments() {
    let out = run(["demo", "--receivers", "7", "--seed", "3", "--no-svg"]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert_eq!(stdout.lines().count(), 1, "stdout: {stdout}");
    assert!(stdout.contains("7 rays"), "stdout: {stdout}");

    // No arguments: the demo, with its picture in the current directory.
    let dir = TempFile::path_only("demo-dir");
    std::fs::create_dir(dir.path()).expect("create dir");
    let out = Command::new(BIN)
        .current_dir(dir.path())
        .output()
        .expect("run eigenray");
    let svg = dir.path().join("eigenray-demo.svg");
    let written = std::fs::read_to_string(&svg);
    let _ = std::fs::remove_file(&svg);
    let _ = std::fs::remove_dir(dir.path());
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    assert!(text(&out.stdout).contains("500 rays"));
    assert!(text(&out.stdout).contains("wrote eigenray-demo.svg"));
    assert!(
        written
            .expect("eigenray-demo.svg written")
            .contains("<polyline")
    );
}

#[test]
fn closed_stdout_exits_quietly() {
    // Enough rays that the output cannot fit in a pipe's buffer.
    let receivers: Vec<String> = (0..4000)
        .map(|i| format!("[{}, -1]", f64::from(i) * 0.001))
        .collect();
    let scene = format!(
        r#"{{ "media": {{ "air": {{ "speed": 1 }} }}, "sources": [[0, 1]], "receivers": [{}],
              "paths": [{{ "steps": [], "media": ["air"] }}] }}"#,
        receivers.join(", ")
    );
    let file = TempFile::with("big.json", scene);
    let mut child = Command::new(BIN)
        .args([OsStr::new("solve"), file.path().as_os_str()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn eigenray");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = text(&out.stderr);
    assert!(!stderr.contains("panicked"), "stderr: {stderr}");
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(stderr.is_empty(), "stderr: {stderr}");
}

/// The README's worked scene is `examples/scenes/room.json`, and its output lines are what
/// `solve --format csv` prints for it.
#[test]
fn the_readme_room_is_the_example_file_and_its_output() {
    let root = env!("CARGO_MANIFEST_DIR");
    let readme = std::fs::read_to_string(format!("{root}/README.md")).expect("README");
    let block = |fence: &str| -> String {
        let start = readme.find(fence).expect(fence) + fence.len();
        readme[start..][..readme[start..].find("```").expect("closing fence")].to_string()
    };
    let shown: Value = serde_json::from_str(&block("```json\n")).expect("README scene");
    let path = format!("{root}/examples/scenes/room.json");
    let mut file: Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("room")).expect("JSON");
    file.as_object_mut().expect("object").remove("description");
    assert_eq!(shown, file);

    let out = run(["solve", path.as_str(), "--format", "csv"]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    let csv = text(&out.stdout);
    for line in block("```text\n").lines().filter(|l| *l != "…") {
        assert!(
            csv.lines().any(|l| l == line),
            "README line {line:?} not in\n{csv}"
        );
    }
}

/// docs/scene-format.md's example scene gives the output lines and name tables the page shows.
#[test]
fn the_format_page_shows_its_scene_output() {
    let root = env!("CARGO_MANIFEST_DIR");
    let page = std::fs::read_to_string(format!("{root}/docs/scene-format.md")).expect("page");
    // The first block of `fence` after `heading`.
    let block = |heading: &str, fence: &str| -> String {
        let at = page.find(heading).expect(heading);
        let start = at + page[at..].find(fence).expect(fence) + fence.len();
        page[start..][..page[start..].find("```").expect("closing fence")].to_string()
    };
    let scene = TempFile::with("format-page.json", block("## A scene", "```json\n"));
    let names = TempFile::path_only("format-page-names.json");
    let csv = run([
        OsStr::new("solve"),
        scene.path().as_os_str(),
        OsStr::new("--format"),
        OsStr::new("csv"),
        OsStr::new("--names"),
        names.path().as_os_str(),
    ]);
    assert_eq!(csv.status.code(), Some(0), "stderr: {}", text(&csv.stderr));
    let lines: Vec<&str> = text(&csv.stdout).lines().collect();
    for line in block("### `--format csv`", "```text\n").lines() {
        assert!(lines.contains(&line), "{line:?} not in {lines:?}");
    }
    let shown: Value =
        serde_json::from_str(&block("### `--names", "```json\n")).expect("names block");
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(names.path()).expect("names")).expect("JSON");
    assert_eq!(shown, written);

    let json = run([OsStr::new("solve"), scene.path().as_os_str()]);
    let doc: Value = serde_json::from_slice(&json.stdout).expect("JSON");
    let shown: Value =
        serde_json::from_str(&block("### `--format json`", "```json\n")).expect("rays block");
    let rays = shown["rays"].as_array().expect("rays");
    assert_eq!(&doc["rays"][0], &rays[0]);
    assert_eq!(&doc["rays"][1], &rays[1]);
}

/// A big demo draws a sample and says so, in a picture a viewer can open.
#[test]
fn a_big_demo_draws_a_sample() {
    let svg = TempFile::path_only("big-demo.svg");
    let out = run([
        OsStr::new("demo"),
        OsStr::new("--receivers"),
        OsStr::new("100000"),
        OsStr::new("--svg"),
        svg.path().as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    let picture = std::fs::read_to_string(svg.path()).expect("SVG written");
    assert!(picture.len() < 1_000_000, "{} bytes", picture.len());
    assert!(picture.contains("100,000 rays"), "title");
    assert!(
        picture.contains("2,000 of 100,000 rays drawn (a sample spread over all rays)"),
        "caption"
    );
    assert_eq!(
        picture.matches("<polyline").count(),
        2_000 + 1,
        "rays and the surface"
    );
}

/// A valley (a maximum-type kink), a roof (a minimum-type kink) and the direct ray, every
/// stationary path of each.
const EVERY: &str = include_str!("../fixtures/every_stationary.json");

#[test]
fn solve_lists_every_stationary_path_when_the_scene_asks() {
    let doc = solve(EVERY);
    let rays = doc["rays"].as_array().expect("rays");
    // 12 triples; the valley gives three paths to (0, 0) and one to (0, 1), (1, 0) (its
    // bottom is no kink path there: the leg to the far end leaves under the other slope);
    // the roof none to (0, 0) and the valley none to (1, 1): one `no_path` entry each.
    assert_eq!(rays.len(), 14, "{doc}");
    let first: Vec<(&str, Option<&str>)> = rays[..3]
        .iter()
        .map(|r| (r["status"].as_str().unwrap(), r["kink"].as_str()))
        .collect();
    assert_eq!(
        first,
        [
            ("converged", None),
            ("converged", None),
            ("vertex", Some("maximum"))
        ]
    );
    assert_eq!(
        rays.iter()
            .map(|r| r["arrival"].as_u64().unwrap())
            .collect::<Vec<_>>(),
        [0, 1, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]
    );
    let no_path: Vec<&Value> = rays.iter().filter(|r| r["status"] == "no_path").collect();
    assert_eq!(no_path.len(), 2);
    assert!(
        no_path
            .iter()
            .all(|r| r["arrival"] == 0 && r.get("time").is_none())
    );
    assert!(rays.iter().all(|r| r["complete"] == true));
    assert!(rays.iter().any(|r| r["kink"] == "minimum"));

    // The other formats: the same entries.
    let file = TempFile::with("every.json", EVERY);
    let csv = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--format"),
        OsStr::new("csv"),
    ]);
    assert_eq!(csv.status.code(), Some(0));
    let csv = text(&csv.stdout);
    assert!(csv.starts_with(
        "source,receiver,path,status,time,iterations,residual,points,path_name,media,reason,\
         arrival,kink,complete\n"
    ));
    assert_eq!(csv.lines().count(), 15);
    let jsonl = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--format"),
        OsStr::new("jsonl"),
    ]);
    assert_eq!(text(&jsonl.stdout).lines().count(), 14);
    let npy = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--format"),
        OsStr::new("npy"),
    ]);
    assert_eq!(npy.status.code(), Some(0));
    let len = u16::from_le_bytes([npy.stdout[8], npy.stdout[9]]) as usize;
    let header = String::from_utf8_lossy(&npy.stdout[10..10 + len]);
    assert!(header.contains("('arrival', '<u4'), ('kink', '|u1'), ('complete', '|u1')"));
    assert!(header.contains("'shape': (14,)"), "{header}");
}

#[test]
fn arrivals_without_a_search_section_exit_2() {
    let file = TempFile::with("every.json", EVERY);
    let target = TempFile::path_only("arrivals.csv");
    let out = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--arrivals"),
        target.path().as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let stderr = text(&out.stderr);
    assert!(
        stderr.starts_with("error: --arrivals: ") && stderr.contains("`search`"),
        "{stderr}"
    );
    assert!(!target.path().exists());
}

/// The SVG as XML: its `text` elements.
fn svg_texts(svg: &str) -> Vec<String> {
    let doc = roxmltree::Document::parse(svg).expect("well-formed SVG");
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| n.text().unwrap_or("").to_string())
        .collect()
}

#[test]
fn the_svg_draws_every_stationary_path_by_sequence_and_by_time() {
    let file = TempFile::with("every.json", EVERY);
    let svg = TempFile::path_only("every.svg");
    let out = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--svg"),
        svg.path().as_os_str(),
        OsStr::new("--svg-color"),
        OsStr::new("sequence"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let picture = std::fs::read_to_string(svg.path()).expect("SVG written");
    let texts = svg_texts(&picture);
    // 12 stationary paths (14 entries less the two `no_path`), by sequence: 4 direct, 5 off the
    // valley, 3 off the roof.
    for want in [
        "sequence (paths drawn)",
        "direct (4)",
        "reflect roof (3)",
        "reflect valley (5)",
    ] {
        assert!(texts.iter().any(|t| t == want), "{want} not in {texts:?}");
    }
    assert!(
        texts.iter().any(|t| t.starts_with(
            "12 of 12 stationary paths drawn (2 rays have no stationary path), coloured by step sequence"
        )),
        "{texts:?}"
    );
    assert!(
        texts
            .iter()
            .any(|t| t.contains("12 stationary paths of 12 rays"))
    );
    // 12 paths and the two interfaces.
    assert_eq!(picture.matches("<polyline").count(), 12 + 2);

    // By time: a colour bar with the range of the times, 1 to about 16.03.
    let out = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--svg"),
        svg.path().as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let texts = svg_texts(&std::fs::read_to_string(svg.path()).unwrap());
    assert!(texts.iter().any(|t| t == "travel time"), "{texts:?}");
    let ticks: Vec<f64> = texts.iter().filter_map(|t| t.parse().ok()).collect();
    assert!(ticks.contains(&1.0), "{ticks:?}");
    // The latest: off the valley's left slope from source 0 to receiver 1, the source's image
    // in the slope's line (−101/26, −40/13) to the receiver: √257 ≈ 16.03.
    assert!(ticks.contains(&16.03), "{ticks:?}");
}

/// Solves the first ```` ```json ```` block after `heading` in the document `doc` (a path in
/// the repository) with `--format FORMAT` and checks that the output is the first
/// ```` ```text ```` block after it, as the document shows it.
fn document_example_gives_its_output(doc: &str, heading: &str, file: &str, format: &str) {
    let root = env!("CARGO_MANIFEST_DIR");
    let page = std::fs::read_to_string(format!("{root}/{doc}")).expect(doc);
    let section = &page[page.find(heading).expect(heading)..];
    let block = |fence: &str| -> String {
        let start = section.find(fence).expect(fence) + fence.len();
        section[start..][..section[start..].find("```").expect("closing fence")].to_string()
    };
    let scene = TempFile::with(file, block("```json\n"));
    let out = run([
        OsStr::new("solve"),
        scene.path().as_os_str(),
        OsStr::new("--format"),
        OsStr::new(format),
    ]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    assert_eq!(text(&out.stdout), block("```text\n"), "{doc}: {heading}");
}

/// docs/scene-format.md's scene for `"stationary": "all"` gives the lines the page shows.
#[test]
fn the_format_page_shows_its_stationary_output() {
    document_example_gives_its_output(
        "docs/scene-format.md",
        "## Every stationary path",
        "format-page-every.json",
        "jsonl",
    );
}

/// The tour's every-stationary-path scene gives the CSV it shows.
#[test]
fn the_guide_valley_gives_its_output() {
    document_example_gives_its_output(
        "docs/guide.md",
        "## Every stationary path of a sequence",
        "valley.json",
        "csv",
    );
}

/// The tour's search scene gives the arrivals it shows.
#[test]
fn the_guide_square_room_gives_its_arrivals() {
    document_example_gives_its_output(
        "docs/guide.md",
        "## Automatic sequences: `search`",
        "square.json",
        "jsonl",
    );
}

/// Whether the segment `p`–`q` crosses the segment `a`–`b` (proper crossings: the test's
/// points are in general position).
fn segments_cross(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> bool {
    let side = |o: [f64; 2], u: [f64; 2], v: [f64; 2]| {
        (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    };
    side(p, q, a) * side(p, q, b) < 0.0 && side(a, b, p) * side(a, b, q) < 0.0
}

/// A search for direct arrivals only (`max_steps: 0`) past one opaque wall, 2 sources × 3
/// receivers: the pairs whose direct leg crosses the wall have no arrival.
const WALL: [[f64; 2]; 2] = [[-1.0, 0.5], [1.0, 0.5]];
const SEARCH_SOURCES: [[f64; 2]; 2] = [[0.0, 0.0], [5.0, 0.0]];
const SEARCH_RECEIVERS: [[f64; 2]; 3] = [[0.0, 1.0], [0.5, 2.0], [3.0, 0.0]];

/// How many pairs no arrival reaches is said on standard error, in every format and with
/// standard error not a terminal (a pipe here), and agrees with the pairs whose direct leg
/// the wall blocks (brute force) and with the pairs that have no entry in the output.
#[test]
fn a_search_says_how_many_pairs_no_arrival_reaches() {
    let scene = serde_json::json!({
        "media": { "air": { "speed": 1.0 } },
        "background": "air",
        "interfaces": { "wall": { "points": WALL } },
        "sources": SEARCH_SOURCES,
        "receivers": SEARCH_RECEIVERS,
        "search": { "max_steps": 0 }
    });
    let blocked: Vec<(usize, usize)> = (0..SEARCH_SOURCES.len())
        .flat_map(|s| (0..SEARCH_RECEIVERS.len()).map(move |r| (s, r)))
        .filter(|&(s, r)| segments_cross(SEARCH_SOURCES[s], SEARCH_RECEIVERS[r], WALL[0], WALL[1]))
        .collect();
    assert_eq!(blocked, [(0, 0), (0, 1)]);
    let file = TempFile::with("search-wall.json", scene.to_string());
    // CSV's arrivals are a table of their own: in a file of their own.
    let table = TempFile::path_only("search-wall-arrivals.csv");
    for format in ["jsonl", "csv", "json"] {
        let mut args = vec![
            OsStr::new("solve"),
            file.path().as_os_str(),
            OsStr::new("--format"),
            OsStr::new(format),
        ];
        if format == "csv" {
            args.extend([OsStr::new("--arrivals"), table.path().as_os_str()]);
        }
        let out = run(args);
        assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
        let stderr = text(&out.stderr);
        assert_eq!(stderr.lines().count(), 1, "{format}: {stderr}");
        assert!(
            stderr.starts_with("search: 4 arrivals")
                && stderr.trim_end().ends_with(
                    "; no arrival reaches 2 of the 6 source-receiver pairs \
                     (source 0 to receiver 0, source 0 to receiver 1)"
                ),
            "{format}: {stderr}"
        );
        // The output has entries for the other four pairs only.
        let arrivals_table;
        let stdout = if format == "csv" {
            arrivals_table = std::fs::read_to_string(table.path()).expect("arrivals written");
            &arrivals_table
        } else {
            text(&out.stdout)
        };
        let pairs: Vec<(u64, u64)> = match format {
            "jsonl" => stdout
                .lines()
                .map(|l| serde_json::from_str::<Value>(l).expect("a JSON line"))
                .map(|a| {
                    (
                        a["source"].as_u64().unwrap(),
                        a["receiver"].as_u64().unwrap(),
                    )
                })
                .collect(),
            "csv" => stdout
                .lines()
                .skip(1)
                .map(|l| {
                    let mut cells = l.split(',').map(|c| c.parse::<u64>().expect("an index"));
                    (cells.next().unwrap(), cells.next().unwrap())
                })
                .collect(),
            _ => serde_json::from_str::<Value>(stdout).expect("one JSON document")["arrivals"]
                .as_array()
                .expect("arrivals")
                .iter()
                .map(|a| {
                    (
                        a["source"].as_u64().unwrap(),
                        a["receiver"].as_u64().unwrap(),
                    )
                })
                .collect(),
        };
        assert_eq!(
            pairs,
            [(0, 2), (1, 0), (1, 1), (1, 2)],
            "{format}: {stdout}"
        );
    }
    // Every pair reached: the line says none, still.
    let mut open = scene.clone();
    open["interfaces"]["wall"]["points"] = serde_json::json!([[-1.0, -5.0], [1.0, -5.0]]);
    let file = TempFile::with("search-open.json", open.to_string());
    let out = run([
        OsStr::new("solve"),
        file.path().as_os_str(),
        OsStr::new("--format"),
        OsStr::new("jsonl"),
    ]);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    assert_eq!(text(&out.stdout).lines().count(), 6);
    assert!(
        text(&out.stderr)
            .trim_end()
            .ends_with("; no arrival reaches 0 of the 6 source-receiver pairs"),
        "{}",
        text(&out.stderr)
    );
}

/// Shallow water 100 deep (a pressure-release surface, a rigid bottom), a source 25 below the
/// surface, a receiver at 4,000 in range and one at 2,000; every arrival of up to 8 bounces,
/// with amplitudes at 100 Hz and impulse responses.
const SHALLOW: &str = r#"{
    "media": { "water": { "speed": 1500 } },
    "background": "water",
    "interfaces": {
        "surface": { "points": [[-10, 0], [5100, 0]], "reflection": "pressure-release" },
        "bottom": { "points": [[-10, -100], [5100, -100]] }
    },
    "sources": [[0, -25]],
    "receivers": [[4000, -50], [2000, -30]],
    "paths": [{ "name": "direct", "steps": [] }],
    "search": { "max_steps": 8, "refract": false },
    "amplitudes": { "source": "point", "frequency": 100 },
    "impulse_response": { "rate": 1000, "duration": 4 }
}"#;

/// Runs `eigenray solve SCENE` with `args`; asserts exit status 0.
fn solve_with(scene: &TempFile, args: &[&OsStr]) -> Output {
    let mut all = vec![OsStr::new("solve"), scene.path().as_os_str()];
    all.extend_from_slice(args);
    let out = run(all);
    assert_eq!(out.status.code(), Some(0), "stderr: {}", text(&out.stderr));
    out
}

/// A response output (`--ir`, `--echogram`, `--tl-map`) keeps standard output empty and says
/// on standard error what it wrote and what it did not; `--rays -` and `--arrivals -` bring
/// the rays and the arrivals back, exactly as a run without a response writes them.
#[test]
fn response_outputs_keep_stdout_empty_unless_asked() {
    let scene = TempFile::with("shallow.json", SHALLOW);
    let plain = solve_with(&scene, &[]);
    // The summary of a response run: its line that starts with `solve: ` (a search may say
    // more on lines of its own).
    let summary_of = |out: &Output| -> Option<String> {
        text(&out.stderr)
            .lines()
            .find(|l| l.starts_with("solve: "))
            .map(str::to_string)
    };
    assert_eq!(summary_of(&plain), None, "{}", text(&plain.stderr));
    let doc: Value = serde_json::from_slice(&plain.stdout).unwrap();
    assert_eq!(doc["rays"].as_array().unwrap().len(), 2);
    assert!(doc["arrivals"].as_array().unwrap().len() > 10);

    let (ir, echogram, map) = (
        TempFile::path_only("ir.npy"),
        TempFile::path_only("echo.svg"),
        TempFile::path_only("tl.svg"),
    );
    let options: [[&OsStr; 2]; 3] = [
        [OsStr::new("--ir"), ir.path().as_os_str()],
        [OsStr::new("--echogram"), echogram.path().as_os_str()],
        [OsStr::new("--tl-map"), map.path().as_os_str()],
    ];
    for [option, path] in options {
        let quiet = solve_with(&scene, &[option, path]);
        assert!(
            quiet.stdout.is_empty(),
            "{option:?}: {}",
            text(&quiet.stdout)
        );
        let summary = summary_of(&quiet).expect("a summary line");
        assert!(
            summary.starts_with("solve: 2 rays")
                && summary.contains("search arrivals")
                && summary.contains(&format!(
                    "wrote {} {}",
                    option.to_str().unwrap(),
                    Path::new(path).display()
                ))
                && summary
                    .contains("not written: the rays and the arrivals (--rays -, --arrivals -"),
            "{summary}"
        );
        assert!(
            std::fs::metadata(path).is_ok_and(|m| m.len() > 0),
            "{option:?} written"
        );

        // Asked for: the rays (with the arrivals beside them), as without a response.
        let both = solve_with(
            &scene,
            &[option, path, OsStr::new("--rays"), OsStr::new("-")],
        );
        assert_eq!(both.stdout, plain.stdout, "{option:?}");
        assert!(
            !text(&both.stderr).contains("not written"),
            "{}",
            text(&both.stderr)
        );
        let both = solve_with(
            &scene,
            &[
                option,
                path,
                OsStr::new("--rays"),
                OsStr::new("-"),
                OsStr::new("--arrivals"),
                OsStr::new("-"),
            ],
        );
        assert_eq!(both.stdout, plain.stdout, "{option:?}");
    }

    // The arrivals alone, and the rays to a file of their own.
    let rays = TempFile::path_only("rays.json");
    let arrivals_only = solve_with(
        &scene,
        &[
            OsStr::new("--echogram"),
            echogram.path().as_os_str(),
            OsStr::new("--arrivals"),
            OsStr::new("-"),
            OsStr::new("--rays"),
            rays.path().as_os_str(),
        ],
    );
    let shown: Value = serde_json::from_slice(&arrivals_only.stdout).unwrap();
    assert_eq!(shown.as_object().unwrap().len(), 1);
    assert_eq!(shown["arrivals"], doc["arrivals"]);
    let filed: Value = serde_json::from_slice(&std::fs::read(rays.path()).unwrap()).unwrap();
    assert_eq!(filed.as_object().unwrap().len(), 1);
    assert_eq!(filed["rays"], doc["rays"]);
    assert!(!text(&arrivals_only.stderr).contains("not written"));

    // CSV: the arrivals' table on standard output is the one `--arrivals FILE` writes.
    let table = TempFile::path_only("arrivals.csv");
    let csv = [OsStr::new("--format"), OsStr::new("csv")];
    let _ = solve_with(
        &scene,
        &[
            csv[0],
            csv[1],
            OsStr::new("--arrivals"),
            table.path().as_os_str(),
        ],
    );
    let piped = solve_with(
        &scene,
        &[
            csv[0],
            csv[1],
            OsStr::new("--tl-map"),
            map.path().as_os_str(),
            OsStr::new("--arrivals"),
            OsStr::new("-"),
        ],
    );
    assert_eq!(piped.stdout, std::fs::read(table.path()).unwrap());
    // Two tables cannot share standard output.
    let file = scene.path().as_os_str();
    let out = run([
        OsStr::new("solve"),
        file,
        csv[0],
        csv[1],
        OsStr::new("--rays"),
        OsStr::new("-"),
        OsStr::new("--arrivals"),
        OsStr::new("-"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    assert!(
        text(&out.stderr).starts_with("error: --format csv: "),
        "{}",
        text(&out.stderr)
    );
}

/// An output that cannot be written (`--ir`, `--echogram`, `--tl-map` as much as `--rays`,
/// `--arrivals`, `--svg` and `--names`) is refused before anything is solved or written:
/// exit status 2, the option and the path named, nothing on standard output, no other file.
#[test]
fn unwritable_outputs_are_refused_before_anything_is_written() {
    let scene = TempFile::with("shallow.json", SHALLOW);
    let missing = std::env::temp_dir().join(format!("eigenray-cli-missing-{}", std::process::id()));
    let written = TempFile::path_only("other.svg");
    for (option, name) in [
        ("--ir", "ir.npy"),
        ("--tl", "tl.npy"),
        ("--echogram", "e.svg"),
        ("--tl-map", "tl.svg"),
        ("--rays", "rays.json"),
        ("--arrivals", "arrivals.json"),
        ("--svg", "scene.svg"),
        ("--names", "names.json"),
    ] {
        let bad = missing.join(name);
        // Another output beside it, which must not be written either.
        let other = if option == "--echogram" {
            "--tl-map"
        } else {
            "--echogram"
        };
        let out = run([
            OsStr::new("solve"),
            scene.path().as_os_str(),
            OsStr::new(other),
            written.path().as_os_str(),
            OsStr::new(option),
            bad.as_os_str(),
        ]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{option}: {stderr}");
        assert!(out.stdout.is_empty(), "{option}");
        assert!(
            stderr.starts_with(&format!(
                "error: {option}: {}: cannot write: ",
                bad.display()
            )),
            "{stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(!written.path().exists(), "{option}: {other} written");
    }
    // A directory, and one file named by two options.
    let dir = std::env::temp_dir();
    let out = run([
        OsStr::new("solve"),
        scene.path().as_os_str(),
        OsStr::new("--tl-map"),
        dir.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).starts_with("error: --tl-map: ")
            && text(&out.stderr).contains("is a directory")
    );
    let out = run([
        OsStr::new("solve"),
        scene.path().as_os_str(),
        OsStr::new("--echogram"),
        written.path().as_os_str(),
        OsStr::new("--tl-map"),
        written.path().as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).starts_with("error: --tl-map: ")
            && text(&out.stderr).contains("also the file of --echogram"),
        "{}",
        text(&out.stderr)
    );
    assert!(!written.path().exists() && out.stdout.is_empty());
    // An existing file is checked without being changed.
    let kept = TempFile::with("kept.svg", "before");
    let out = run([
        OsStr::new("solve"),
        scene.path().as_os_str(),
        OsStr::new("--echogram"),
        kept.path().as_os_str(),
        OsStr::new("--source"),
        OsStr::new("7"),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(kept.path()).unwrap(), "before");
}

/// The texts of the elements of `class` in an SVG document.
fn texts_of_class(svg: &str, class: &str) -> Vec<String> {
    let doc = roxmltree::Document::parse(svg).expect("well-formed SVG");
    doc.descendants()
        .filter(|n| n.attribute("class") == Some(class))
        .map(|n| n.text().unwrap_or_default().to_string())
        .collect()
}

/// The echogram at 4 km starts just before the first arrival (2.667 s), or at 0 when asked;
/// the map names its axes in km and depth and draws the surface, the bottom and the source.
#[test]
fn the_charts_take_their_time_axis_and_named_axes() {
    let scene = TempFile::with("shallow.json", SHALLOW);
    let echogram = TempFile::path_only("echo.svg");
    let e = [OsStr::new("--echogram"), echogram.path().as_os_str()];
    let _ = solve_with(&scene, &e);
    let ticks = texts_of_class(&std::fs::read_to_string(echogram.path()).unwrap(), "x-tick");
    let first: f64 = ticks[0].parse().unwrap();
    assert!((2.5..2.7).contains(&first) || first == 2.7, "{ticks:?}");
    let _ = solve_with(&scene, &[e[0], e[1], OsStr::new("--echogram-from-zero")]);
    let ticks = texts_of_class(&std::fs::read_to_string(echogram.path()).unwrap(), "x-tick");
    assert_eq!(ticks[0], "0", "{ticks:?}");

    let map = TempFile::path_only("tl.svg");
    let _ = solve_with(
        &scene,
        &[
            OsStr::new("--tl-map"),
            map.path().as_os_str(),
            OsStr::new("--x-axis"),
            OsStr::new("range,km,0.001"),
            OsStr::new("--y-axis"),
            OsStr::new("depth,m,-1"),
        ],
    );
    let svg = std::fs::read_to_string(map.path()).unwrap();
    assert_eq!(texts_of_class(&svg, "x-title"), ["range (km)"]);
    assert_eq!(texts_of_class(&svg, "y-title"), ["depth (m)"]);
    // Depth ticks: positive, and growing down the picture.
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let depths: Vec<(f64, f64)> = doc
        .descendants()
        .filter(|n| n.attribute("class") == Some("y-tick"))
        .map(|n| {
            let depth: f64 = n.text().unwrap().parse().unwrap();
            (depth, n.attribute("y").unwrap().parse().unwrap())
        })
        .collect();
    assert!(depths.len() >= 3, "{depths:?}");
    assert!(
        depths.iter().all(|&(d, _)| d >= 0.0)
            && depths
                .windows(2)
                .all(|w| (w[0].0 < w[1].0) == (w[0].1 < w[1].1)),
        "{depths:?}"
    );
    for title in ["surface", "bottom", "bottom (bottom)", "source 0"] {
        assert!(
            doc.descendants().any(|n| n.text() == Some(title)),
            "{title}"
        );
    }
    // The scene picture takes the same axes; a bad one is refused naming its option.
    let picture = TempFile::path_only("scene.svg");
    let _ = solve_with(
        &scene,
        &[
            OsStr::new("--svg"),
            picture.path().as_os_str(),
            OsStr::new("--y-axis"),
            OsStr::new("depth,m,-1"),
        ],
    );
    let svg = std::fs::read_to_string(picture.path()).unwrap();
    assert_eq!(texts_of_class(&svg, "y-title"), ["depth (m)"]);
    for bad in ["range,km,0", "range,km,x", ",km"] {
        let out = run([
            OsStr::new("solve"),
            scene.path().as_os_str(),
            OsStr::new("--x-axis"),
            OsStr::new(bad),
        ]);
        assert_eq!(out.status.code(), Some(2), "{bad}");
        assert!(
            text(&out.stderr).contains("--x-axis"),
            "{}",
            text(&out.stderr)
        );
        assert!(out.stdout.is_empty());
    }
}

/// The room of `examples/scenes/room_orders.json` to 30 orders: every order's stems share one
/// colour, and the 31 orders' colours all differ ("20 interactions" is not "direct").
#[test]
fn a_room_echogram_of_30_orders_gives_each_order_its_colour() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join("scenes")
        .join("room_orders.json");
    let echogram = TempFile::path_only("room.svg");
    let out = run([
        OsStr::new("solve"),
        scene.as_os_str(),
        OsStr::new("--echogram"),
        echogram.path().as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    assert!(out.stdout.is_empty());
    let svg = std::fs::read_to_string(echogram.path()).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    let mut colours: std::collections::BTreeMap<String, std::collections::BTreeSet<String>> =
        Default::default();
    for stem in doc.descendants().filter(|n| n.has_tag_name("circle")) {
        let title = stem.children().find_map(|c| c.text()).unwrap();
        let order = title.rsplit(", ").next().unwrap().to_string();
        colours
            .entry(order)
            .or_default()
            .insert(stem.attribute("fill").unwrap().to_string());
    }
    assert_eq!(colours.len(), 31, "{:?}", colours.keys());
    assert!(colours.values().all(|c| c.len() == 1));
    let distinct: std::collections::BTreeSet<&String> =
        colours.values().flat_map(|c| c.iter()).collect();
    assert_eq!(distinct.len(), 31);
    assert_ne!(colours["direct"], colours["20 interactions"]);
    assert!(svg.contains(r#"class="order-bar""#));
    // A plane scene has no floor or ceiling to mark.
    assert!(!svg.contains("vertical"));
}

/// The extruded room of `examples/scenes/extruded_room.json`: the echogram marks each arrival
/// that reflects off the floor or the ceiling with a square (its title saying how many times),
/// every other one with a dot, exactly as the arrivals' own steps ("floor", "ceiling") count
/// them; a 2-D scene's echogram has no such mark (the other echogram tests are unchanged).
#[test]
fn an_extruded_room_echogram_marks_floor_and_ceiling_reflections() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join("scenes")
        .join("extruded_room.json");
    let echogram = TempFile::path_only("extruded.svg");
    let out = run([
        OsStr::new("solve"),
        scene.as_os_str(),
        OsStr::new("--echogram"),
        echogram.path().as_os_str(),
        OsStr::new("--arrivals"),
        OsStr::new("-"),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let doc: Value = serde_json::from_slice(&out.stdout).expect("JSON arrivals");
    // (time's bits, floor and ceiling steps) of each echo of source 0 at receiver 0.
    let mut expected: Vec<(u64, usize)> = (doc["arrivals"].as_array().unwrap().iter())
        .filter(|a| a["source"] == 0 && a["receiver"] == 0 && a["status"] == "converged")
        .filter(|a| !a["amplitude"].is_null())
        .map(|a| {
            let steps = a["steps"].as_array().unwrap();
            let vertical = (steps.iter())
                .filter(|s| s["reflect"] == "floor" || s["reflect"] == "ceiling")
                .count();
            (a["time"].as_f64().unwrap().to_bits(), vertical)
        })
        .collect();
    expected.sort_unstable();
    assert!(expected.iter().any(|e| e.1 == 0) && expected.iter().any(|e| e.1 >= 2));
    let svg = std::fs::read_to_string(echogram.path()).unwrap();
    let svg_doc = roxmltree::Document::parse(&svg).unwrap();
    let mut drawn: Vec<(u64, usize)> = Vec::new();
    for mark in svg_doc.descendants() {
        let vertical = mark.attribute("class") == Some("vertical");
        if !(vertical || mark.has_tag_name("circle")) {
            continue;
        }
        let title = mark.children().find_map(|c| c.text()).unwrap();
        let time: f64 = title.split(" s,").next().unwrap().parse().unwrap();
        let count = if vertical {
            let last = title.rsplit(", ").next().unwrap();
            let n = last.strip_suffix(" floor/ceiling").expect("its count");
            n.parse().unwrap()
        } else {
            0
        };
        drawn.push((time.to_bits(), count));
    }
    drawn.sort_unstable();
    assert_eq!(drawn, expected);
    assert!(svg.contains(r#"class="vertical-key""#));
}
