//! Hostile and careless input: every case ends in a right answer or a clear error, never in a
//! silent wrong answer, an abort, a panic or a hang.
//!
//! Command-line cases run the binary with a memory limit (`ulimit -v`) and a net for a hang
//! (killed after ten minutes; no answer depends on a clock), and check the exit status, the
//! first line of standard error and that nothing reached standard output. Library cases call
//! the API directly. `round2.rs` holds the second round of cases: work that must stay
//! bounded, memory, and answers that must not be wrong.

mod budgets;
mod proofs;
mod round2;
mod round3;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use eigenray::geom::{SegmentContact, segment_contact};
use eigenray::polyline::Polyline;
use eigenray::scene::MAX_ITERATIONS_LIMIT;
use eigenray::{Point, Scene, SceneSpec, SolverOptions, Status, Tracer, Workspace};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use serde_json::{Value, json};

const BIN: &str = env!("CARGO_BIN_EXE_eigenray");

/// The scene format's own example (air over water, a lens, three paths).
fn contract_example() -> Value {
    json!({
        "media": {"air": {"speed": 1.0}, "water": {"speed": 0.75, "at": [0.5, -0.5]}},
        "background": "air",
        "domain": [[-2.0, -3.0], [5.0, 3.0]],
        "interfaces": {
            "surface": {"points": [[-2.0, 0.0], [5.0, 0.0]]},
            "lens": {"points": [[3, 0.5], [4, 0.5], [4, 1.5]], "closed": true}
        },
        "sources": [[0.0, 1.0]],
        "receivers": [[1.0, -1.0], [0.5, -1.0]],
        "paths": [
            {"name": "transmitted", "steps": [{"refract": "surface"}]},
            {"name": "bounce", "steps": [{"reflect": "surface"}]},
            {"name": "explicit", "steps": [{"refract": "surface"}], "media": ["air", "water"]},
            {"name": "direct", "steps": []}
        ]
    })
}

/// A file in the temporary directory, removed when dropped.
struct TempFile(PathBuf);

impl TempFile {
    fn with(contents: impl AsRef<[u8]>) -> TempFile {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let path =
            std::env::temp_dir().join(format!("eigenray-hostile-{}-{n}.json", std::process::id()));
        std::fs::write(&path, contents).expect("write temp file");
        TempFile(path)
    }
    fn path(&self) -> &str {
        self.0.to_str().expect("UTF-8 temp path")
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// What a bounded run of the binary left.
struct Run {
    code: Option<i32>,
    stdout: Vec<u8>,
    stderr: String,
}

impl Run {
    fn first_line(&self) -> &str {
        self.stderr.lines().next().unwrap_or("")
    }
    /// Exit status 2, one message naming `key` on standard error, nothing on standard output.
    fn assert_refused(&self, key: &str) {
        assert_eq!(self.code, Some(2), "stderr: {}", self.stderr);
        assert!(self.stdout.is_empty(), "stdout: {:?}", self.stdout);
        assert!(!self.stderr.contains("panicked"), "stderr: {}", self.stderr);
        assert_eq!(self.stderr.lines().count(), 1, "stderr: {}", self.stderr);
        let want = format!("error: {key}");
        assert!(
            self.first_line().starts_with(&want),
            "first line {:?}, expected it to start with {want:?}",
            self.first_line()
        );
    }
}

/// How long a run of the binary may go before it is killed and the test fails: a net for a
/// hang, not a check of speed (every run here bounds its work, and takes seconds at most even
/// on a loaded machine); no test's answer depends on a clock otherwise.
const HANG_GUARD: Duration = Duration::from_secs(600);

/// Runs `eigenray ARGS` through `sh` (`redirect` is put after the command: redirections), with
/// at most 4 GB of address space; kills it after [`HANG_GUARD`].
fn run_bounded(args: &str, redirect: &str, stdin: Option<&[u8]>) -> Run {
    run_capped(4_000_000, args, redirect, stdin)
}

/// [`run_bounded`] with at most `kilobytes` of address space.
fn run_capped(kilobytes: u64, args: &str, redirect: &str, stdin: Option<&[u8]>) -> Run {
    let script = format!("ulimit -v {kilobytes}; exec {BIN} {args} {redirect}");
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(script)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn sh");
    if let Some(data) = stdin {
        let mut pipe = child.stdin.take().expect("stdin pipe");
        let data = data.to_vec();
        std::thread::spawn(move || {
            let _ = std::io::Write::write_all(&mut pipe, &data);
        });
    }
    let mut out = child.stdout.take().expect("stdout pipe");
    let mut err = child.stderr.take().expect("stderr pipe");
    let reader = std::thread::spawn(move || {
        let mut v = Vec::new();
        let _ = out.read_to_end(&mut v);
        v
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > HANG_GUARD {
            let _ = child.kill();
            let _ = child.wait();
            panic!("eigenray {args} still ran after {HANG_GUARD:?}: it hangs");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run {
        code: status.code(),
        stdout: reader.join().expect("stdout reader"),
        stderr: err_reader.join().expect("stderr reader"),
    }
}

/// `eigenray solve FILE` on `scene`, as [`run_bounded`].
fn solve_file(scene: &str) -> Run {
    let file = TempFile::with(scene);
    run_bounded(&format!("solve {}", file.path()), "", None)
}

/// The error of `Tracer::new` (a tracer is not `Debug`).
fn tracer_error(s: &Scene) -> eigenray::SceneError {
    match Tracer::new(s) {
        Ok(_) => panic!("Tracer::new accepted the scene"),
        Err(e) => e,
    }
}

fn scene(v: &Value) -> Result<Scene, eigenray::SceneError> {
    Scene::from_json(&v.to_string())
}

/// Statuses and times of every ray (`Tracer::trace_all`).
fn rays(scene: &Scene) -> Vec<(Status, Option<f64>)> {
    Tracer::new(scene)
        .expect("tracer")
        .trace_all()
        .into_iter()
        .map(|r| (r.status, r.status.has_time().then_some(r.time)))
        .collect()
}

/// `v` with every coordinate (interface points, sources, receivers, `at`, domain) mapped by
/// `f`.
fn map_coordinates(v: &Value, f: &dyn Fn(f64) -> f64) -> Value {
    fn points(v: &mut Value, f: &dyn Fn(f64) -> f64) {
        match v {
            Value::Array(a) if a.len() == 2 && a.iter().all(Value::is_number) => {
                for x in a.iter_mut() {
                    *x = json!(f(x.as_f64().expect("number")));
                }
            }
            Value::Array(a) => a.iter_mut().for_each(|x| points(x, f)),
            _ => {}
        }
    }
    let mut v = v.clone();
    for key in ["sources", "receivers", "domain"] {
        if let Some(x) = v.get_mut(key) {
            points(x, f);
        }
    }
    if let Some(Value::Object(m)) = v.get_mut("interfaces") {
        for i in m.values_mut() {
            points(&mut i["points"], f);
        }
    }
    if let Some(Value::Object(m)) = v.get_mut("media") {
        for medium in m.values_mut() {
            if let Some(at) = medium.get_mut("at") {
                points(at, f);
            }
        }
    }
    v
}

// ---------------------------------------------------------------------------------------
// 1. Ray counts that overflow; 7. batches beyond the machine's memory.

#[test]
fn batch_sizes_are_counted_at_validation() {
    // The overflow itself is tested on the private counting function (scene.rs): lists whose
    // lengths multiply beyond 2^64 take gigabytes to write. Here: the counts a batch relies on.
    let ok = scene(&contract_example()).expect("valid");
    let size = ok.batch_size();
    assert_eq!(size.rays, 8);
    assert_eq!(ok.num_rays(), 8);
    assert_eq!(size.points, 2 * (3 + 3 + 3 + 2));
    assert_eq!(size.legs, 2 * (2 + 2 + 2 + 1));
    assert_eq!(size.bytes(usize::MAX, 1, 1), None, "bytes overflow is None");
}

/// 10^4 sources × 10^4 receivers × 10^3 paths: 10^11 rays from a file of about 150 kB.
fn hundred_billion_rays() -> Value {
    let pts: Vec<Value> = (0..10_000).map(|i| json!([i as f64 * 1e-3, 1.0])).collect();
    let rec: Vec<Value> = (0..10_000)
        .map(|i| json!([i as f64 * 1e-3, -1.0]))
        .collect();
    let paths: Vec<Value> = (0..1000)
        .map(|_| json!({"steps": [], "media": ["air"]}))
        .collect();
    json!({"media": {"air": {"speed": 1.0}}, "sources": pts, "receivers": rec, "paths": paths})
}

#[test]
fn too_many_rays_for_memory_exit_2_saying_how_much() {
    let doc = hundred_billion_rays();
    let run = solve_file(&doc.to_string());
    run.assert_refused("paths: the batch needs about");
}

/// The library's batch: an error saying how much, not an abort, where the arrays cannot be
/// allocated (10^11 rays: terabytes).
#[test]
fn library_batch_too_big_for_memory_is_an_error() {
    let overcommit = std::fs::read_to_string("/proc/sys/vm/overcommit_memory").unwrap_or_default();
    if overcommit.trim() == "1" {
        // Every allocation succeeds there, to be killed on first use: nothing to test.
        eprintln!("skipped: the kernel overcommits every allocation");
        return;
    }
    let s = scene(&hundred_billion_rays()).expect("valid");
    let tracer = Tracer::new(&s).expect("tracer");
    let e = tracer
        .trace_batch(
            &eigenray::BatchOptions::default(),
            &eigenray::options::Run::new(),
        )
        .expect_err("terabytes");
    assert_eq!(e.key, "paths");
    assert!(
        e.message.contains("100000000000 rays") && e.message.contains("cannot be allocated"),
        "{e}"
    );
}

#[test]
fn long_path_times_many_receivers_exit_2_saying_how_much() {
    // A 100,000-step path × 10,000 receivers: about 16 GB of points (issue 19, item 7).
    let steps: Vec<Value> = (0..100_000).map(|_| json!({"reflect": "m"})).collect();
    let rec: Vec<Value> = (0..10_000).map(|i| json!([i as f64 * 1e-3, 1.0])).collect();
    let doc = json!({
        "media": {"air": {"speed": 1.0}},
        "interfaces": {"m": {"points": [[-1, 0], [11, 0]]}},
        "sources": [[0, 1]], "receivers": rec,
        "paths": [{"steps": steps, "media": vec!["air"; 100_001]}]
    });
    let run = solve_file(&doc.to_string());
    run.assert_refused("paths: the batch needs about");
    assert!(run.stderr.contains("points of 16 bytes"), "{}", run.stderr);
}

// ---------------------------------------------------------------------------------------
// 2. Far geometry and region lookup.

#[test]
fn distant_interface_does_not_change_region_lookup() {
    let base = contract_example();
    let want = rays(&scene(&base).expect("valid"));
    for far in [1e20, 1e43, 1e44, 1e60, 1e90] {
        let mut v = base.clone();
        v["interfaces"]["big"] = json!({"points": [[far, far], [2.0 * far, far]]});
        let got = rays(&scene(&v).unwrap_or_else(|e| panic!("far {far:e}: {e}")));
        assert_eq!(got, want, "an interface at {far:e} changed the rays");
    }
    // A tiny triangle beside an interface far away is a valid scene.
    let v = json!({
        "media": {"air": {"speed": 1.0}, "glass": {"speed": 0.5, "at": [1.2e-30, 1.2e-30]}},
        "background": "air",
        "interfaces": {
            "tri": {"points": [[1e-30, 1e-30], [2e-30, 1e-30], [1e-30, 2e-30]], "closed": true},
            "far": {"points": [[1e20, 0], [1e20, 1]]}
        },
        "sources": [[1.1e-30, 1.1e-30]], "receivers": [[3e-30, 3e-30]],
        "paths": [{"steps": []}]
    });
    let s = scene(&v).expect("a tiny triangle beside a far interface is valid");
    let t = Tracer::new(&s).expect("its regions build");
    assert_eq!(
        t.regions()
            .expect("regions")
            .medium_at(Point::new(1.2e-30, 1.2e-30)),
        s.medium_index("glass")
    );
}

#[test]
fn dynamic_range_beyond_region_lookup_is_refused_with_a_reason() {
    let mut v = contract_example();
    v["interfaces"]["big"] = json!({"points": [[1e100, 1e100], [2e99, 1e100]]});
    v["sources"] = json!([[1e-10, 1.0]]);
    let e = scene(&v).expect_err("1e-10 beside 1e100 is beyond 2^340");
    assert_eq!(e.key, "scene");
    assert!(e.message.contains("orders of magnitude"), "{e}");
    // With every path's media given no region lookup is needed: accepted.
    v["paths"] = json!([{"steps": [], "media": ["air"]}]);
    scene(&v).expect("no region lookup, no limit on the range");
}

// ---------------------------------------------------------------------------------------
// 3. Scales: refused below the accepted range, the same statuses within it.

#[test]
fn small_scales_are_refused_up_front() {
    for k in [1e-170, 1e-310, 1e-320] {
        let v = map_coordinates(&contract_example(), &|x| x * k);
        let e = scene(&v).expect_err("below 1e-100");
        assert!(e.message.contains("at least 1e-100"), "scale {k:e}: {e}");
    }
    let v = map_coordinates(&contract_example(), &|x| x * 1e200);
    let e = scene(&v).expect_err("beyond 1e100");
    assert!(e.message.contains("within ±1e100"), "{e}");
}

#[test]
fn contract_example_scaled_keeps_statuses_and_scales_times() {
    let base = contract_example();
    let want = rays(&scene(&base).expect("valid"));
    for k in [-99, -90, -50, -10, -1, 1, 10, 50, 90, 99] {
        let f = 10f64.powi(k);
        let v = map_coordinates(&base, &|x| x * f);
        let got = rays(&scene(&v).unwrap_or_else(|e| panic!("1e{k}: {e}")));
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g.0, w.0, "scale 1e{k}");
            if let (Some(a), Some(b)) = (g.1, w.1) {
                assert!(
                    ((a / f - b) / b).abs() < 1e-12,
                    "scale 1e{k}: {a} against {b}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// 4. The library: non-finite points, solver settings; 15. path indices.

#[test]
fn library_solve_refuses_non_finite_and_out_of_range_points() {
    let s = scene(&contract_example()).expect("valid");
    let bad = [
        Point::new(f64::NAN, f64::NAN),
        Point::new(f64::INFINITY, 0.0),
        Point::new(f64::MAX, 0.5),
        Point::new(-f64::MAX, -0.5),
    ];
    for p in bad {
        let e = s
            .check_solve(Point::new(0.0, 1.0), p, 0)
            .expect_err("bad receiver");
        assert_eq!(e.key, "receiver", "{p:?}");
        let e = s
            .check_solve(p, Point::new(0.0, 1.0), 0)
            .expect_err("bad source");
        assert_eq!(e.key, "source", "{p:?}");
        let t = Tracer::new(&s).expect("tracer");
        let solved = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            t.solve(Point::new(0.0, 1.0), p, 0, &mut Workspace::new())
        }));
        assert!(solved.is_err(), "{p:?} must be refused, not solved");
    }
    s.check_solve(Point::new(0.0, 1.0), Point::new(1.0, -1.0), 0)
        .expect("valid points");
    // A coordinate below the scene's smallest is zero to the scene: solved, not refused.
    s.check_solve(Point::new(1e-320, 1.0), Point::new(1.0, -1.0), 0)
        .expect("a tiny coordinate");
    let ray = Tracer::new(&s).expect("tracer").solve(
        Point::new(1e-320, 1.0),
        Point::new(1.0, -1.0),
        0,
        &mut Workspace::new(),
    );
    assert!(ray.status.has_time(), "{ray:?}");
}

#[test]
fn library_out_of_range_path_index_is_an_error() {
    let s = scene(&contract_example()).expect("valid");
    let e = s
        .check_solve(Point::new(0.0, 1.0), Point::new(1.0, -1.0), 4)
        .expect_err("4 paths");
    assert_eq!(e.key, "path");
    assert!(e.message.contains("out of range"), "{e}");
    let t = Tracer::new(&s).expect("tracer");
    let solved = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        t.solve(
            Point::new(0.0, 1.0),
            Point::new(1.0, -1.0),
            4,
            &mut Workspace::new(),
        )
    }));
    let msg = solved.expect_err("documented panic");
    let msg = msg.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(msg.contains("path: index 4 is out of range"), "{msg}");
}

#[test]
fn set_solver_validates_like_the_scene_document() {
    let mut s = scene(&contract_example()).expect("valid");
    let before = s.solver();
    for (tolerance, max_iterations, key) in [
        (-1.0, 100_000_000, "solver.tolerance"),
        (f64::INFINITY, 100, "solver.tolerance"),
        (f64::NAN, 100, "solver.tolerance"),
        (1.0, 100, "solver.tolerance"),
        (1e-12, MAX_ITERATIONS_LIMIT + 1, "solver.max_iterations"),
    ] {
        let e = s
            .set_solver(SolverOptions {
                tolerance,
                max_iterations,
                ..Default::default()
            })
            .expect_err("invalid");
        assert_eq!(e.key, key);
        assert_eq!(s.solver(), before, "left as it was");
    }
    // Zero iterations is allowed in the library: the solve returns its start.
    s.set_solver(SolverOptions {
        tolerance: 1e-12,
        max_iterations: 0,
        ..Default::default()
    })
    .expect("0 iterations");
}

// ---------------------------------------------------------------------------------------
// 5. Duplicate names; 6. `at` outside the domain.

#[test]
fn duplicate_names_are_refused() {
    let medium = r#"{"media": {"air": {"speed": 1.0}, "air": {"speed": 3.0}},
        "sources": [[0, 1]], "receivers": [[1, 1]], "paths": [{"steps": []}], "background": "air"}"#;
    let e = Scene::from_json(medium).expect_err("air twice");
    assert_eq!(e.key, "media");
    assert!(e.message.contains("`air` is given twice"), "{e}");
    let run = solve_file(medium);
    run.assert_refused("media: the name `air` is given twice");

    let interface = r#"{"media": {"air": {"speed": 1.0}},
        "interfaces": {"m": {"points": [[0, 0], [1, 0]]}, "m": {"points": [[0, 5], [1, 5]]}},
        "sources": [[0, 1]], "receivers": [[1, 1]], "paths": [{"steps": [], "media": ["air"]}]}"#;
    let e = Scene::from_json(interface).expect_err("m twice");
    assert_eq!(e.key, "interfaces");

    let path = r#"{"media": {"air": {"speed": 1.0}},
        "sources": [[0, 1]], "receivers": [[1, 1]],
        "paths": [{"name": "d", "steps": [], "media": ["air"]}, {"name": "d", "steps": [], "media": ["air"]}]}"#;
    let e = Scene::from_json(path).expect_err("path d twice");
    assert_eq!(e.key, "paths[1].name");
}

#[test]
fn at_outside_the_domain_is_refused() {
    let mut v = contract_example();
    v["media"]["water"]["at"] = json!([10.0, -0.5]);
    let e = scene(&v).expect_err("outside");
    assert_eq!(e.key, "media.water.at");
    assert!(e.message.contains("outside the domain"), "{e}");
    v["media"]["water"]["at"] = json!([5.0, -0.5]);
    let e = scene(&v).expect_err("on the edge");
    assert!(e.message.contains("edge of the domain"), "{e}");
}

// ---------------------------------------------------------------------------------------
// 8. Unbounded input.

#[test]
fn endless_input_stops_at_the_size_limit() {
    let run = run_bounded("solve /dev/zero", "", None);
    run.assert_refused("/dev/zero: larger than 256 MiB");
    let big = vec![b' '; (256 << 20) + 10];
    let run = run_bounded("solve -", "", Some(&big));
    run.assert_refused("<stdin>: larger than 256 MiB");
}

// ---------------------------------------------------------------------------------------
// 9. Validation in O(n log n).

/// `n` flat layers spanning a domain, and a path refracting through all of them.
fn layers(n: usize) -> String {
    let mut interfaces = serde_json::Map::new();
    let mut steps = Vec::new();
    for k in 0..n {
        let y = -(k as f64) - 0.5;
        interfaces.insert(format!("l{k}"), json!({"points": [[-10.0, y], [10.0, y]]}));
        steps.push(json!({"refract": format!("l{k}")}));
    }
    json!({
        "media": {"air": {"speed": 1.0}},
        "interfaces": interfaces,
        "sources": [], "receivers": [],
        "paths": [{"steps": steps, "media": vec!["air"; n + 1]}]
    })
    .to_string()
}

/// A path of 10^6 reflections over 100,000 interfaces (about 36 MB), no rays.
fn long_path() -> String {
    let n = 100_000;
    let mut text =
        String::from(r#"{"media": {"air": {"speed": 1.0}}, "background": "air", "interfaces": {"#);
    for k in 0..n {
        let sep = if k == 0 { "" } else { "," };
        let y = -(k as f64) - 0.5;
        text += &format!(r#"{sep}"l{k}": {{"points": [[-10.0, {y}], [10.0, {y}]]}}"#);
    }
    text += r#"}, "sources": [], "receivers": [], "paths": [{"steps": ["#;
    for k in 0..1_000_000 {
        let sep = if k == 0 { "" } else { "," };
        text += &format!(r#"{sep}{{"reflect": "l{}"}}"#, k % n);
    }
    text += r#"]}]}"#;
    text
}

/// `n` parallel diagonal segments whose boxes all overlap.
fn diagonals(n: usize) -> String {
    let mut interfaces = serde_json::Map::new();
    for k in 0..n {
        let x = k as f64;
        interfaces.insert(
            format!("d{k}"),
            json!({"points": [[x, 0.0], [x + n as f64, n as f64]]}),
        );
    }
    json!({"media": {"air": {"speed": 1.0}}, "interfaces": interfaces,
           "sources": [], "receivers": [], "paths": []})
    .to_string()
}

/// Large scenes validate and give a tracer (in O(n log n): a quadratic check of 10^5
/// interfaces would take minutes; the times are printed, not checked: `cargo test --profile
/// test-opt --test hostile large_scenes -- --nocapture`); a crossing hidden among 40,000
/// overlapping diagonals is found.
#[test]
fn large_scenes_validate_and_a_crossing_among_them_is_found() {
    for (name, text, interfaces) in [
        ("100,000 layers", layers(100_000), 100_000),
        ("40,000 overlapping diagonals", diagonals(40_000), 40_000),
        (
            "a 10^6-step path over 100,000 interfaces",
            long_path(),
            100_000,
        ),
    ] {
        let start = Instant::now();
        let scene = Scene::from_json(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
        let secs = start.elapsed().as_secs_f64();
        let start = Instant::now();
        drop(Tracer::new(&scene).expect("tracer"));
        let tracer = start.elapsed().as_secs_f64();
        eprintln!("{name}: validated in {secs:.3} s, tracer prepared in {tracer:.3} s");
        assert_eq!(scene.interfaces().len(), interfaces, "{name}");
    }
    // The diagonals with one crossing added: found.
    let mut v: Value = serde_json::from_str(&diagonals(40_000)).expect("json");
    v["interfaces"]["x"] = json!({"points": [[100.5, 100.0], [99.5, 101.0]]});
    let e = Scene::from_json(&v.to_string()).expect_err("crossing");
    assert!(e.message.contains("crosses"), "{e}");
}

/// [`diagonals`] with a background, a source, a receiver and a direct path by region lookup.
fn diagonals_with_lookup(n: usize) -> Value {
    let mut v: Value = serde_json::from_str(&diagonals(n)).expect("json");
    v["background"] = json!("air");
    v["sources"] = json!([[-5.0, 1.0]]);
    v["receivers"] = json!([[-5.0, 2.0]]);
    v["paths"] = json!([{"steps": []}]);
    v
}

#[test]
fn intertwined_interfaces_are_refused_for_region_lookup_at_once() {
    // 2,500 parallel diagonals (boxes all overlapping) with region lookup took 13 s to
    // triangulate, 5,000 took 3 minutes: refused before the triangulation starts.
    let run = solve_file(&diagonals_with_lookup(2500).to_string());
    run.assert_refused("interfaces: too many interface segments lie across each other");
    // 300 of them are triangulated.
    let s = scene(&diagonals_with_lookup(300)).expect("valid");
    assert_eq!(rays(&s), vec![(Status::Converged, Some(1.0))]);
}

/// Every forbidden contact between random segments on a small grid (many touches, overlaps
/// and collinear cases), by brute force.
fn brute_force_problem(lines: &[(Vec<Point>, bool)]) -> bool {
    let segs: Vec<(usize, usize, Point, Point)> = lines
        .iter()
        .enumerate()
        .flat_map(|(i, (pts, closed))| {
            let n = pts.len();
            let m = if *closed { n } else { n - 1 };
            (0..m).map(move |j| (i, j, pts[j], pts[(j + 1) % n]))
        })
        .collect();
    for (x, &(i, j, a0, a1)) in segs.iter().enumerate() {
        for &(k, l, b0, b1) in &segs[x + 1..] {
            let n = lines[i].0.len();
            let nseg = if lines[i].1 { n } else { n - 1 };
            let adjacent = i == k && (l == j + 1 || (lines[i].1 && j == 0 && l == nseg - 1));
            match segment_contact(a0, a1, b0, b1) {
                SegmentContact::Disjoint => {}
                SegmentContact::Touch if i != k || adjacent => {}
                _ => return true,
            }
        }
    }
    false
}

proptest! {
    #![proptest_config(Config { cases: 3000, rng_seed: RngSeed::Fixed(19), failure_persistence: None, ..Config::default() })]

    /// The sweep accepts exactly the interfaces that no two segments meet wrongly (compared
    /// with every pair, on a 5 × 5 grid where touches and collinear segments are common).
    #[test]
    fn crossing_sweep_agrees_with_brute_force(
        raw in prop::collection::vec((prop::collection::vec((0..5i32, 0..5i32), 2..5), any::<bool>()), 1..5)
    ) {
        let mut lines = Vec::new();
        let mut interfaces = serde_json::Map::new();
        for (n, (pts, closed)) in raw.iter().enumerate() {
            let pts: Vec<Point> = pts.iter().map(|&(x, y)| Point::new(x as f64, y as f64)).collect();
            if Polyline::new(pts.clone(), *closed).is_err() {
                continue;
            }
            interfaces.insert(format!("i{n}"), json!({
                "points": pts.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(), "closed": closed
            }));
            lines.push((pts, *closed));
        }
        let doc = json!({"media": {"air": {"speed": 1.0}}, "interfaces": interfaces,
                         "sources": [], "receivers": [], "paths": []});
        let got = Scene::from_json(&doc.to_string());
        prop_assert_eq!(got.is_err(), brute_force_problem(&lines), "{} {:?}", doc, got.err());
    }
}

// ---------------------------------------------------------------------------------------
// 10. Subnormal coordinates; 11. tiny triangles.

#[test]
fn subnormal_coordinates_are_refused_without_a_panic() {
    let text = r#"{"media":{"air":{"speed":1.0}},"background":"air","domain":[[-1e-320,-1e-320],[1e-320,1e-320]],"interfaces":{"s":{"points":[[-2e-320,0],[2e-320,0]]}},"sources":[[0,5e-321]],"receivers":[[0,-5e-321]],"paths":[{"steps":[]}]}"#;
    let run = solve_file(text);
    run.assert_refused("domain: a nonzero coordinate must be at least 1e-100");
}

#[test]
fn tiny_triangle_is_a_polygon_and_a_clear_refusal_in_a_scene() {
    let tri = vec![
        Point::new(1e-300, 1e-300),
        Point::new(2e-300, 1e-300),
        Point::new(1e-300, 2e-300),
    ];
    Polyline::new(tri, true).expect("not all on one line");
    let sub = vec![
        Point::new(1e-320, 1e-320),
        Point::new(2e-320, 1e-320),
        Point::new(1e-320, 2e-320),
    ];
    Polyline::new(sub, true).expect("subnormal, still not all on one line");
    let v = json!({"media": {"air": {"speed": 1.0}},
        "interfaces": {"t": {"points": [[1e-300, 1e-300], [2e-300, 1e-300], [1e-300, 2e-300]], "closed": true}},
        "sources": [], "receivers": [], "paths": []});
    let e = scene(&v).expect_err("below the coordinate range");
    assert_eq!(e.key, "interfaces.t.points[0]");
    assert!(e.message.contains("at least 1e-100"), "{e}");
}

// ---------------------------------------------------------------------------------------
// 13. Control characters; 14. closed standard output; 16. a source on an interface.

#[test]
fn control_characters_in_names_are_escaped() {
    let text = "{\"media\": {\"air\": {\"speed\": 1}}, \"sources\": [[0, 1]], \"receivers\": [[1, 1]], \
                \"paths\": [{\"steps\": [{\"reflect\": \"x\\u001b[2J\\u0007\\u2028\\u202e\"}]}]}";
    let e = Scene::from_json(text).expect_err("unknown interface");
    let shown = e.to_string();
    assert!(!shown.chars().any(|c| c.is_control()), "{shown:?}");
    assert!(
        shown.contains("x\\u{1b}[2J\\u{7}\\u{2028}\\u{202e}"),
        "{shown}"
    );
    let run = solve_file(text);
    run.assert_refused("paths[0].steps[0].reflect: unknown interface `x\\u{1b}[2J");
    assert!(!run.stderr.contains('\u{1b}'), "{:?}", run.stderr);
}

/// A standard output closed at start is reopened on `/dev/null` by the Rust runtime, which
/// cannot be told from a caller's own `/dev/null` opened for reading and writing (Python's
/// `subprocess.DEVNULL`): both succeed. An output that cannot be written exits 1.
#[test]
fn closed_or_null_stdout_succeeds_and_a_full_one_exits_1() {
    let file = TempFile::with(contract_example().to_string());
    for redirect in [">&-", ">/dev/null", "1<>/dev/null"] {
        let run = run_bounded(&format!("solve {}", file.path()), redirect, None);
        assert_eq!(run.code, Some(0), "{redirect}: {}", run.stderr);
        let run = run_bounded("demo --no-svg", redirect, None);
        assert_eq!(run.code, Some(0), "demo {redirect}: {}", run.stderr);
    }
    if Path::new("/dev/full").exists() {
        let run = run_bounded(&format!("solve {}", file.path()), ">/dev/full", None);
        assert_eq!(run.code, Some(1), "stderr: {}", run.stderr);
        assert!(run.first_line().starts_with("error:"), "{}", run.stderr);
    }
}

#[test]
fn source_on_an_interface_is_refused_naming_it() {
    let mut v = contract_example();
    v["sources"] = json!([[0.0, 1.0], [1.0, 0.0]]);
    let e = scene(&v).expect_err("source on the surface");
    assert_eq!(e.key, "sources[1]");
    assert!(
        e.message.contains("lies exactly on interface `surface`"),
        "{e}"
    );
    let run = solve_file(&v.to_string());
    run.assert_refused("sources[1]: lies exactly on interface `surface`");
    // On the domain's edge.
    v["sources"] = json!([[-2.0, 1.0]]);
    let e = scene(&v).expect_err("source on the edge");
    assert!(e.message.contains("edge of the domain"), "{e}");
    // With every path's media given, no medium is looked up: a valid scene.
    v["sources"] = json!([[1.0, 0.0]]);
    v["paths"] = json!([{"steps": [], "media": ["air"]}]);
    scene(&v).expect("no lookup");
}

// ---------------------------------------------------------------------------------------
// Issue 20: scenes that cannot mean what they say.

#[test]
fn open_surface_without_domain_is_refused_suggesting_a_domain() {
    let mut v = contract_example();
    v.as_object_mut().expect("object").remove("domain");
    v["interfaces"]
        .as_object_mut()
        .expect("object")
        .remove("lens");
    let run = solve_file(&v.to_string());
    run.assert_refused("background: `air` fills no region");
    assert!(run.stderr.contains("add a `domain`"), "{}", run.stderr);
    // Without a background, water would claim the whole plane: the refraction is refused.
    v.as_object_mut().expect("object").remove("background");
    v["sources"] = json!([[0.0, 1.0]]);
    let s = scene(&v).expect("valid document");
    let e = tracer_error(&s);
    assert_eq!(e.key, "paths[0].steps[0].refract");
    assert!(e.message.contains("add a `domain`"), "{e}");
}

#[test]
fn no_background_and_no_at_is_refused() {
    let v = json!({"media": {"air": {"speed": 1.0}},
        "interfaces": {"wall": {"points": [[0, 0], [1, 0]]}},
        "sources": [[0, 1]], "receivers": [[1, 1]], "paths": [{"steps": [{"reflect": "wall"}]}]});
    let run = solve_file(&v.to_string());
    run.assert_refused("paths[0].media: missing: path 0 takes its leg media from the regions");
}

#[test]
fn unused_medium_and_source_without_medium_are_refused() {
    // Water has no `at` and no path names it: it fills no region.
    let mut v = contract_example();
    v["media"]["water"]
        .as_object_mut()
        .expect("object")
        .remove("at");
    v["paths"] = json!([{"steps": [{"refract": "surface"}]}]);
    let s = scene(&v).expect("valid document");
    let e = tracer_error(&s);
    assert_eq!(e.key, "media.water");
    // A lens with glass inside and no background: a source outside has no medium.
    let v = json!({"media": {"glass": {"speed": 0.5, "at": [0.5, 0.2]}},
        "interfaces": {"lens": {"points": [[0, 0], [1, 0], [0.5, 1]], "closed": true}},
        "sources": [[3, 3]], "receivers": [[0.5, 0.3]], "paths": [{"steps": [{"refract": "lens"}]}]});
    let s = scene(&v).expect("valid document");
    let e = tracer_error(&s);
    assert_eq!(e.key, "sources[0]");
    assert!(e.message.contains("no medium fills"), "{e}");
}

#[test]
fn layered_scene_without_domain_hints_at_a_domain() {
    let v = json!({"media": {"air": {"speed": 1.0, "at": [0, 1]}, "bedrock": {"speed": 3.0, "at": [0, -1]}},
        "interfaces": {"top": {"points": [[-5, 0], [5, 0]]}},
        "sources": [[0, 1]], "receivers": [[0, -1]], "paths": [{"steps": [{"refract": "top"}]}]});
    let s = scene(&v).expect("valid document");
    let e = tracer_error(&s);
    assert!(
        e.message
            .contains("lies in the same region as media.air.at"),
        "{e}"
    );
    assert!(e.message.contains("add a `domain`"), "{e}");
}

// ---------------------------------------------------------------------------------------
// Scale invariance: random valid scenes scaled by 10^k across the accepted range.

/// A random layered scene: `n` flat or dipping layers across a domain, media by `at`, a
/// background, sources above and receivers below, and a few paths (direct, reflections,
/// refractions, and explicit media).
/// Layers `(depth jitter, dip)`, speeds, sources and receivers (fractions of their boxes).
type RawLayers = (Vec<(f64, f64)>, Vec<f64>, Vec<(f64, f64)>, Vec<(f64, f64)>);

fn layered(raw: &RawLayers) -> Value {
    let (layers, speeds, sources, receivers) = raw;
    let n = layers.len();
    let mut interfaces = serde_json::Map::new();
    let mut media = serde_json::Map::new();
    // Layer k crosses x = 0 at y in [-k - 0.65, -k - 0.35] and dips by at most 0.1.
    for (k, &(dy, dip)) in layers.iter().enumerate() {
        let y = -(k as f64) - 0.5 + 0.3 * (dy - 0.5);
        interfaces.insert(
            format!("l{k}"),
            json!({"points": [[-10.0, y - dip], [10.0, y + dip]]}),
        );
    }
    for k in 0..=n {
        let y = if k == 0 { 2.0 } else { -(k as f64) };
        media.insert(
            format!("m{k}"),
            json!({"speed": speeds[k % speeds.len()], "at": [0.0, y]}),
        );
    }
    media.insert("bg".into(), json!({"speed": 1.0}));
    let down: Vec<Value> = (0..n)
        .map(|k| json!({"refract": format!("l{k}")}))
        .collect();
    let paths = vec![
        json!({"steps": []}),
        json!({"steps": [{"reflect": "l0"}]}),
        json!({"steps": down}),
        json!({"steps": [{"refract": "l0"}], "media": ["m0", "m1"]}),
    ];
    json!({
        "media": media, "background": "bg",
        "domain": [[-10.0, -(n as f64) - 1.0], [10.0, 3.0]],
        "interfaces": interfaces,
        "sources": sources.iter().map(|&(x, y)| [-8.0 + 16.0 * x, 0.5 + 2.0 * y]).collect::<Vec<_>>(),
        "receivers": receivers.iter().map(|&(x, y)| [-8.0 + 16.0 * x, -(n as f64) - 0.1 - 0.8 * y]).collect::<Vec<_>>(),
        "paths": paths
    })
}

proptest! {
    #![proptest_config(Config { cases: 60, rng_seed: RngSeed::Fixed(0x5ca1e), failure_persistence: None, ..Config::default() })]

    /// Every status is the same and every time scales with the scene (to 1e-9: a power of
    /// ten rounds the coordinates), for scales from 1e-98 to 1e98; beyond the accepted range
    /// the scene is refused as a whole.
    #[test]
    fn scaled_scenes_keep_statuses_and_scale_times(
        raw in (
            prop::collection::vec((0.0..1.0f64, -0.1..0.1f64), 1..4),
            prop::collection::vec(0.3..3.0f64, 1..4),
            prop::collection::vec((0.0..1.0f64, 0.0..1.0f64), 1..3),
            prop::collection::vec((0.0..1.0f64, 0.0..1.0f64), 1..3),
        ),
        ks in prop::collection::vec(-98i32..=98, 4),
    ) {
        let base = layered(&raw);
        let want = rays(&scene(&base).map_err(|e| TestCaseError::fail(format!("{e}\n{base}")))?);
        for k in ks {
            let f = 10f64.powi(k);
            let v = map_coordinates(&base, &|x| x * f);
            let got = rays(&scene(&v).map_err(|e| TestCaseError::fail(format!("1e{k}: {e}")))?);
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                prop_assert_eq!(g.0, w.0, "ray {} at scale 1e{}\n{}", i, k, base);
                if let (Some(a), Some(b)) = (g.1, w.1) {
                    prop_assert!(((a / f - b) / b).abs() < 1e-9, "ray {} at 1e{}: {} against {}", i, k, a / f, b);
                }
            }
        }
        // Powers of two scale exactly: the same rays bit for bit, times scaled exactly.
        for j in [-300, -100, 100, 300] {
            let f = 2f64.powi(j);
            let v = map_coordinates(&base, &|x| x * f);
            let got = rays(&scene(&v).map_err(|e| TestCaseError::fail(format!("2^{j}: {e}")))?);
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                prop_assert_eq!(g.0, w.0, "ray {} at scale 2^{}\n{}", i, j, base);
                if let (Some(a), Some(b)) = (g.1, w.1) {
                    prop_assert!(((a / f - b) / b).abs() < 1e-12, "ray {} at 2^{}: {} against {}", i, j, a / f, b);
                }
            }
        }
        // Beyond the range: refused as a whole, not ray by ray.
        let v = map_coordinates(&base, &|x| x * 1e-120);
        prop_assert!(scene(&v).is_err());
    }
}

#[test]
fn spec_round_trip_keeps_unique_names() {
    // Serialising a spec and reading it back goes through the duplicate check unharmed.
    let s: SceneSpec = serde_json::from_value(contract_example()).expect("spec");
    let text = serde_json::to_string(&s).expect("serialise");
    Scene::from_json(&text).expect("valid");
}
