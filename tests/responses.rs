//! Impulse responses and coherent pressure (`eigenray::response`, `"impulse_response"`,
//! `eigenray solve --ir`): each against the image method written out here, and the CLI's
//! files and refusals.

use std::f64::consts::PI;
use std::path::PathBuf;
use std::process::Command;

use eigenray::response::{ImpulseResponses, echoes_of_scene, pressure_into, transmission_loss};
use eigenray::{Scene, Tracer, amplitude::Complex64};

const BIN: &str = env!("CARGO_BIN_EXE_eigenray");

/// `eigenray solve SCENE ARGS…`.
fn solve(scene: &std::path::Path, args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(BIN)
        .arg("solve")
        .arg(scene)
        .args(args)
        .output()
        .unwrap()
}

/// A rectangle `w × h` of four absorbing walls (α = 0.19, so R = 0.9), source (1, 1),
/// receiver (3.3, 2.2), reflections up to `order`, amplitudes of a point source, responses at
/// 8 kHz for 0.1 s.
fn rectangle(order: usize) -> String {
    let walls = [
        ("bottom", [[0.0, 0.0], [5.0, 0.0]]),
        ("right", [[5.0, 0.0], [5.0, 4.0]]),
        ("top", [[5.0, 4.0], [0.0, 4.0]]),
        ("left", [[0.0, 4.0], [0.0, 0.0]]),
    ];
    let interfaces: Vec<String> = walls
        .iter()
        .map(|(name, p)| {
            format!(
                r#""{name}": {{"points": [[{}, {}], [{}, {}]], "reflection": {{"absorption": 0.19}}}}"#,
                p[0][0], p[0][1], p[1][0], p[1][1]
            )
        })
        .collect();
    format!(
        r#"{{"media": {{"air": {{"speed": 343}}}}, "background": "air",
        "interfaces": {{{}}},
        "sources": [[1, 1]], "receivers": [[3.3, 2.2]],
        "search": {{"max_steps": {order}, "refract": false}},
        "amplitudes": {{"source": "point", "frequency": 500}},
        "impulse_response": {{"rate": 8000, "duration": 0.1}}}}"#,
        interfaces.join(", ")
    )
}

/// The images of (1, 1) in the rectangle [0, 5] × [0, 4] up to `order` reflections: each
/// `(distance to (3.3, 2.2), reflections)`. In a rectangle every image is seen, unless its
/// path meets a corner, which no path to (3.3, 2.2) does to order 6 (checked in exact
/// rationals): x images 10i ± 1, y images 8j ± 1.
fn rectangle_images(order: usize) -> Vec<(f64, usize)> {
    let mut out = Vec::new();
    let n = order as i64 + 1;
    for i in -n..=n {
        for j in -n..=n {
            for (sx, fx) in [(1.0, 0i64), (-1.0, 1)] {
                for (sy, fy) in [(1.0, 0i64), (-1.0, 1)] {
                    // 10i + 1 is |2i| reflections away, 10i − 1 is |2i − 1|.
                    let rx = (2 * i - fx).unsigned_abs() as usize;
                    let ry = (2 * j - fy).unsigned_abs() as usize;
                    if rx + ry > order {
                        continue;
                    }
                    let x = 10.0 * i as f64 + sx;
                    let y = 8.0 * j as f64 + sy;
                    let d = ((x - 3.3f64).powi(2) + (y - 2.2f64).powi(2)).sqrt();
                    out.push((d, rx + ry));
                }
            }
        }
    }
    out
}

#[test]
fn the_rectangles_response_and_pressure_are_its_images() {
    let order = 4;
    let scene = Scene::from_json(&rectangle(order)).unwrap();
    let tracer = Tracer::new(&scene).unwrap();
    let echoes = echoes_of_scene(&tracer, &eigenray::options::Run::new()).unwrap();
    let images = rectangle_images(order);
    assert_eq!(echoes.len(), images.len(), "one echo per image");

    // The response against each image's pulse (amplitude 0.9^k / (4πd)) placed here.
    let options = scene.impulse_response().unwrap();
    let ir = ImpulseResponses::new(options, 1, 1);
    let ours = ir
        .render(echoes.iter().copied(), &eigenray::options::Run::new())
        .unwrap();
    let mut want = vec![0.0; ir.samples()];
    for &(d, k) in &images {
        let a = 0.9f64.powi(k as i32) / (4.0 * PI * d);
        let x = d / 343.0 * 8000.0;
        let whole = x.floor();
        for tap in 0..81 {
            let n = whole - 40.0 + tap as f64;
            if n >= 0.0 && (n as usize) < want.len() {
                let hann = 0.5 - 0.5 * (2.0 * PI * tap as f64 / 80.0).cos();
                let u = PI * (n - x);
                want[n as usize] += a * hann * if u == 0.0 { 1.0 } else { u.sin() / u };
            }
        }
    }
    let norm = want.iter().map(|v| v * v).sum::<f64>().sqrt();
    let err = ours
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    assert!(err / norm < 1e-12, "relative L2 error {:e}", err / norm);

    // The coherent pressure at 500 Hz against the sum over images.
    let mut p = [Complex64::new(0.0, 0.0)];
    pressure_into(
        echoes.iter().copied(),
        500.0,
        1,
        &eigenray::options::Run::new(),
        &mut p,
    );
    let k = 2.0 * PI * 500.0 / 343.0;
    let want: Complex64 = images
        .iter()
        .map(|&(d, r)| Complex64::from_polar(0.9f64.powi(r as i32) / (4.0 * PI * d), k * d))
        .sum();
    assert!(
        (p[0] - want).norm() < 1e-12 * want.norm(),
        "{} vs {want}",
        p[0]
    );
    let tl = transmission_loss(p[0]);
    assert!((tl + 20.0 * (want.norm() * 4.0 * PI).log10()).abs() < 1e-9);
}

struct Dir(PathBuf);

impl Dir {
    fn new(name: &str) -> Dir {
        let d =
            std::env::temp_dir().join(format!("eigenray-responses-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        Dir(d)
    }
}

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn the_cli_writes_the_responses_as_npy() {
    let dir = Dir::new("npy");
    let scene = dir.0.join("room.json");
    std::fs::write(&scene, rectangle(3)).unwrap();
    let out = dir.0.join("ir.npy");
    let run = solve(&scene, &["--ir".as_ref(), out.as_os_str()]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let bytes = std::fs::read(&out).unwrap();
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(
        header.contains("'descr': '<f8'") && header.contains("'shape': (1, 1, 800)"),
        "{header}"
    );
    let data: Vec<f64> = bytes[10 + header_len..]
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    let parsed = Scene::from_json(&rectangle(3)).unwrap();
    let tracer = Tracer::new(&parsed).unwrap();
    let ir = ImpulseResponses::new(parsed.impulse_response().unwrap(), 1, 1);
    let want = ir
        .render(
            echoes_of_scene(&tracer, &eigenray::options::Run::new()).unwrap(),
            &eigenray::options::Run::new(),
        )
        .unwrap();
    // Streamed as the search finds them: the collected sum up to the order of the sums.
    let peak = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(
        data.iter()
            .zip(&want)
            .all(|(a, b)| (a - b).abs() <= 1e-12 * peak)
    );
}

/// The `.npy` file of float64 numbers at `path`: its header's shape and its numbers.
fn read_npy(path: &std::path::Path) -> (String, Vec<f64>) {
    let bytes = std::fs::read(path).unwrap();
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    assert!(header.contains("'descr': '<f8'"), "{header}");
    let shape = header.split("'shape': ").nth(1).unwrap();
    let shape = shape[..=shape.find(')').unwrap()].to_string();
    let data = bytes[10 + header_len..]
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (shape, data)
}

/// Lloyd's mirror on a grid: a point source 25 deep under a pressure-release surface,
/// receivers on a grid of `nx × ny`, the direct and the surface-reflected paths, `mode`.
fn lloyd(mode: &str) -> String {
    format!(
        r#"{{"media": {{"water": {{"speed": 1500}}}}, "background": "water",
        "interfaces": {{"surface": {{"points": [[-5000, 0], [5000, 0]],
                                     "reflection": "pressure-release"}}}},
        "sources": [[0, -25]],
        "receivers": {{"grid": {{"x": [50, 1000, 20], "y": [-5, -95, 10]}}}},
        "search": {{"max_steps": 1, "refract": false}},
        "amplitudes": {{"source": "point", "frequency": 100}},
        "transmission_loss": {{"mode": "{mode}"}}}}"#
    )
}

#[test]
fn the_cli_writes_the_transmission_loss_as_npy() {
    let dir = Dir::new("tl");
    let scene = dir.0.join("lloyd.json");
    let k = 2.0 * std::f64::consts::PI * 100.0 / 1500.0;
    for mode in ["coherent", "incoherent"] {
        std::fs::write(&scene, lloyd(mode)).unwrap();
        let out = dir.0.join(format!("{mode}.npy"));
        let run = solve(&scene, &["--tl".as_ref(), out.as_os_str()]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(run.status.success(), "{stderr}");
        assert!(run.stdout.is_empty());
        assert!(
            stderr.contains("400 echoes summed, 0 timed paths without an amplitude"),
            "{stderr}"
        );
        let (shape, tl) = read_npy(&out);
        assert_eq!(shape, "(1, 20, 10)");
        for ix in 0..20 {
            for iy in 0..10 {
                let (x, y) = (50.0 + 50.0 * ix as f64, -5.0 - 10.0 * iy as f64);
                let r1 = (x * x + (y + 25.0) * (y + 25.0)).sqrt();
                let r2 = (x * x + (y - 25.0) * (y - 25.0)).sqrt();
                let want = if mode == "coherent" {
                    let p = eigenray::amplitude::Complex64::from_polar(1.0 / r1, k * r1)
                        - eigenray::amplitude::Complex64::from_polar(1.0 / r2, k * r2);
                    -20.0 * p.norm().log10()
                } else {
                    -10.0 * (1.0 / (r1 * r1) + 1.0 / (r2 * r2)).log10()
                };
                let got = tl[ix * 10 + iy];
                assert!((got - want).abs() < 1e-9, "{mode} {ix} {iy}: {got} {want}");
            }
        }
        // Listed (the arrivals written) and streamed give the same loss.
        let arrivals = dir.0.join("arrivals.json");
        let listed = dir.0.join("listed.npy");
        let run = solve(
            &scene,
            &[
                "--tl".as_ref(),
                listed.as_os_str(),
                "--arrivals".as_ref(),
                arrivals.as_os_str(),
            ],
        );
        assert!(run.status.success());
        let (_, again) = read_npy(&listed);
        assert!(tl.iter().zip(&again).all(|(a, b)| (a - b).abs() < 1e-9));
    }
    // Nothing arrives above the surface: +inf, never NaN.
    std::fs::write(
        &scene,
        lloyd("coherent").replace(r#""y": [-5, -95, 10]"#, r#""y": [5, -85, 10]"#),
    )
    .unwrap();
    let out = dir.0.join("above.npy");
    let run = solve(&scene, &["--tl".as_ref(), out.as_os_str()]);
    assert!(run.status.success());
    let (_, tl) = read_npy(&out);
    assert!(tl.iter().all(|v| !v.is_nan()));
    assert_eq!(tl.iter().filter(|v| **v == f64::INFINITY).count(), 20);
}

#[test]
fn bad_transmission_loss_requests_exit_2_and_write_nothing() {
    let dir = Dir::new("badtl");
    let scene = dir.0.join("lloyd.json");
    let no_frequency = lloyd("coherent")
        .replace(r#", "frequency": 100"#, "")
        .replace(r#","transmission_loss": {"mode": "coherent"}"#, "");
    let no_frequency = no_frequency.replace(
        r#",
        "transmission_loss": {"mode": "coherent"}"#,
        "",
    );
    let missing = dir.0.join("no-such-directory").join("tl.npy");
    let cases: [(String, std::path::PathBuf, &str); 4] = [
        (
            no_frequency,
            dir.0.join("tl.npy"),
            "--tl: the loss is at `amplitudes.frequency`",
        ),
        (
            lloyd("coherent"),
            dir.0.join("tl.txt"),
            "--tl: the file's name must end in .npy",
        ),
        (lloyd("coherent"), missing, "--tl: "),
        (lloyd("loud"), dir.0.join("tl.npy"), "transmission_loss"),
    ];
    for (text, out, message) in cases {
        std::fs::write(&scene, text).unwrap();
        let run = solve(&scene, &["--tl".as_ref(), out.as_os_str()]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{message}: {stderr}");
        assert!(run.stdout.is_empty());
        assert!(!out.exists());
    }
}

#[test]
fn bad_response_requests_exit_2_and_write_nothing() {
    let dir = Dir::new("bad");
    let scene = dir.0.join("room.json");
    let cases: [(String, &str, &str); 4] = [
        (
            rectangle(1).replace(
                r#""impulse_response": {"rate": 8000, "duration": 0.1}"#,
                r#""solver": {}"#,
            ),
            "ir.npy",
            "--ir: the scene has no `impulse_response`",
        ),
        (
            rectangle(1),
            "ir.txt",
            "--ir: the file's name must end in .npy or .wav",
        ),
        (
            rectangle(1).replace(r#""rate": 8000"#, r#""rate": 8000.5"#),
            "ir.wav",
            "impulse_response.rate: a WAV file needs a whole number",
        ),
        (
            rectangle(1).replace(r#""duration": 0.1"#, r#""duration": -1"#),
            "ir.npy",
            "impulse_response.duration",
        ),
    ];
    for (text, file, message) in cases {
        std::fs::write(&scene, text).unwrap();
        let out = dir.0.join(file);
        let run = solve(&scene, &["--ir".as_ref(), out.as_os_str()]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
        assert!(run.stdout.is_empty());
        assert!(!out.exists());
    }
    let no_amplitudes = rectangle(1).replace(
        r#""amplitudes": {"source": "point", "frequency": 500},"#,
        "",
    );
    let e = Scene::from_json(&no_amplitudes).unwrap_err();
    assert_eq!(e.key, "impulse_response");
}

#[test]
fn the_cli_draws_the_echogram_and_the_map() {
    let dir = Dir::new("charts");
    let scene = dir.0.join("room.json");
    std::fs::write(&scene, rectangle(2)).unwrap();
    let (echogram, map) = (dir.0.join("echo.svg"), dir.0.join("tl.svg"));
    let run = solve(
        &scene,
        &[
            "--echogram".as_ref(),
            echogram.as_os_str(),
            "--tl-map".as_ref(),
            map.as_os_str(),
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let echogram = std::fs::read_to_string(&echogram).unwrap();
    // One stem per image to order 2 (1 + 4 + 8), a legend entry per order.
    assert_eq!(
        echogram.matches("<circle").count(),
        rectangle_images(2).len()
    );
    for label in ["direct", "1 interaction", "2 interactions", "time (s)"] {
        assert!(echogram.contains(label), "{label}");
    }
    let map = std::fs::read_to_string(&map).unwrap();
    assert!(map.contains("transmission loss (dB)") && map.contains("at 500 Hz"));
    // A receiver the scene does not have, and a map without a frequency: exit 2.
    let run = solve(
        &scene,
        &["--echogram", "x.svg", "--receiver", "1"].map(std::ffi::OsStr::new),
    );
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("--receiver"));
    std::fs::write(&scene, rectangle(2).replace(r#", "frequency": 500"#, "")).unwrap();
    let run = solve(&scene, &["--tl-map", "x.svg"].map(std::ffi::OsStr::new));
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("amplitudes.frequency"));
}
