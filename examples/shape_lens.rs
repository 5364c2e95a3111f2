//! Shaping a lens so that a point source images onto a focus (Fermat's imaging condition:
//! every path from the source through the lens to the focus takes the same time), with
//! argmin's L-BFGS as the outer optimiser and the exact derivatives of the times with respect
//! to the back surface's vertices inside (`argmin_bridge::LensProfile`).
//!
//! A glass plate (index 1.5) with a flat front face 20 units from a point source starts flat at
//! the back too: it does not focus. L-BFGS moves the back surface's ten outer vertices (the
//! middle one keeps the thickness on the axis) until the paths through seventeen entry points
//! reach the focus, 20 units behind, at times as equal as a polyline of eleven vertices allows;
//! the objective is printed per iteration and the lens before and after drawn as an SVG (with
//! the lens magnified in an inset).
//!
//! `cargo run --release --features argmin --example shape_lens [OUT.svg]`

use argmin::core::observers::ObserverMode;
use argmin::core::{Executor, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use eigenray::argmin_bridge::LensProfile;
use eigenray::{Point, SceneSpec, Tracer, Workspace};
use nalgebra::DVector;

#[path = "support/objective.rs"]
mod objective;
#[path = "support/svg.rs"]
mod svg;

use objective::PrintObjective;

/// Vertices of the back surface, from the top down.
const VERTICES: usize = 11;
/// The back surface's height above and below the axis.
const HALF_HEIGHT: f64 = 2.2;
/// The lens's thickness (the back surface's `x` at the start, and on the axis throughout).
const THICKNESS: f64 = 0.6;

fn spec() -> Result<SceneSpec, serde_json::Error> {
    let points: Vec<[f64; 2]> = (0..VERTICES)
        .map(|i| {
            let y = HALF_HEIGHT - 2.0 * HALF_HEIGHT * i as f64 / (VERTICES - 1) as f64;
            [THICKNESS, y]
        })
        .collect();
    serde_json::from_value(serde_json::json!({
        "media": { "glass": { "index": 1.5 }, "air": { "index": 1.0 } },
        "interfaces": { "back": { "points": points } },
        "sources": [[0.0, 0.0]], "receivers": [[20.0 + THICKNESS, 0.0]],
        "paths": [{ "steps": [{ "refract": "back" }], "media": ["glass", "air"] }]
    }))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "shape_lens.svg".to_string());
    let source = Point::new(-20.0, 0.0);
    let focus = Point::new(20.0 + THICKNESS, 0.0);
    // More entry points than free vertices: a polyline cannot focus exactly, and L-BFGS finds
    // the polyline whose path times spread least.
    let entries: Vec<Point> = (0..17)
        .map(|i| Point::new(0.0, -2.0 + 0.25 * i as f64))
        .collect();
    let middle = VERTICES / 2;
    let free: Vec<usize> = (0..VERTICES).filter(|&v| v != middle).collect();
    // The objective (built twice: the optimiser takes the first).
    let lens = spec()?;
    let profile = || {
        LensProfile::new(
            lens.clone(),
            "back",
            free.clone(),
            0,
            source,
            1.0,
            entries.clone(),
            focus,
        )
    };
    let problem = profile()?;
    let flat = vec![THICKNESS; free.len()];
    let before = problem.misfit(&flat)?;
    let spread = |t: &[f64]| {
        t.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - t.iter().copied().fold(f64::INFINITY, f64::min)
    };
    println!(
        "flat back: path times spread over {:.3e} (source to focus {:.4})",
        spread(&before.times),
        before.times[8]
    );
    println!("iter     objective");
    println!("{:>4}  {:>12.5e}", "init", before.cost);
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-14)?
        .with_tolerance_cost(0.0)?;
    let started = std::time::Instant::now();
    let result = Executor::new(problem, solver)
        .configure(|s| s.param(DVector::from_vec(flat.clone())).max_iters(200))
        .add_observer(PrintObjective(|_| String::new()), ObserverMode::Always)
        .ctrlc(false)
        .run()?;
    let elapsed = started.elapsed();
    let state = result.state();
    let shaped = state
        .get_best_param()
        .expect("a best profile")
        .as_slice()
        .to_vec();
    let problem = profile()?;
    let after = problem.misfit(&shaped)?;
    println!(
        "shaped after {} iterations ({:.1} ms): path times spread over {:.3e} ({})",
        state.get_iter(),
        elapsed.as_secs_f64() * 1e3,
        spread(&after.times),
        state
            .get_termination_reason()
            .map_or("running", |r| r.text())
    );
    let profile: Vec<String> = shaped.iter().map(|x| format!("{x:.4}")).collect();
    println!(
        "back surface x (top to bottom, the middle fixed at {THICKNESS}): {}",
        profile.join(" ")
    );
    let svg = picture(&problem, &flat, &shaped, source, focus, &entries)?;
    std::fs::write(&out, svg)?;
    println!("wrote {out}");
    Ok(())
}

/// The lens before (grey, dashed) and after (blue), and the paths through the shaped lens.
fn picture(
    problem: &LensProfile,
    flat: &[f64],
    shaped: &[f64],
    source: Point,
    focus: Point,
    entries: &[Point],
) -> Result<String, Box<dyn std::error::Error>> {
    // The picture stretches y: the lens is thin and the distances long.
    let (x0, x1, y0, y1) = (-21.0, 22.0, -3.0, 3.0);
    let (sx, sy) = (24.0, 110.0);
    let canvas = svg::Canvas::new([x0, x1], [y0, y1], [sx, sy], 300.0);
    let px = |p: Point| canvas.px(p);
    let mut s = canvas.header();
    let line = |pts: &[Point], style: &str| canvas.polyline(pts, style);
    s += &line(
        &[Point::new(0.0, -HALF_HEIGHT), Point::new(0.0, HALF_HEIGHT)],
        "stroke=\"#3a7bd5\" stroke-width=\"2\"",
    );
    for (x, style) in [
        (flat, "stroke=\"#999\" stroke-dasharray=\"6 4\""),
        (shaped, "stroke=\"#3a7bd5\" stroke-width=\"2\""),
    ] {
        let scene = problem.scene(x)?;
        let back = scene.interfaces()[0].polyline.vertices().to_vec();
        s += &line(&back, style);
    }
    let scene = problem.scene(shaped)?;
    let tracer = Tracer::new(&scene)?;
    let mut ws = Workspace::new();
    for &p in entries {
        if tracer.solve(p, focus, 0, &mut ws).status.has_time() {
            let q = ws.points()[1];
            s += &line(&[source, p, q, focus], "stroke=\"#d0462c\"");
        }
    }
    // Below: the lens magnified, x five times as much as y.
    let (ix, iy, k) = (420.0, (y1 - y0) * sy + 40.0, 240.0);
    let inset = |p: Point| (ix + (p.x + 0.1) * k, iy + (2.3 - p.y) * k * 0.1 * 2.0);
    s += &format!(
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#ccc\"/>\n\
         <text x=\"{}\" y=\"{}\">the lens (x stretched 5× against y)</text>\n",
        ix - 10.0,
        iy - 20.0,
        0.9 * k + 20.0,
        4.6 * k * 0.2 + 30.0,
        ix,
        iy - 26.0
    );
    for (x, style) in [
        (flat, "stroke=\"#999\" stroke-dasharray=\"6 4\""),
        (shaped, "stroke=\"#3a7bd5\" stroke-width=\"2\""),
    ] {
        let scene = problem.scene(x)?;
        let mut back = scene.interfaces()[0].polyline.vertices().to_vec();
        back.insert(0, Point::new(0.0, HALF_HEIGHT));
        back.push(Point::new(0.0, -HALF_HEIGHT));
        back.push(Point::new(0.0, HALF_HEIGHT));
        s += &svg::polyline_through(back.iter().map(|&p| inset(p)), style);
    }
    for (p, label) in [(source, "source"), (focus, "focus")] {
        let (x, y) = px(p);
        s += &format!(
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\" fill=\"#222\"/>\n\
             <text x=\"{:.1}\" y=\"{:.1}\">{label}</text>\n",
            x - 20.0,
            y + 22.0
        );
    }
    s += "<text x=\"10\" y=\"20\">back surface shaped by L-BFGS for equal path times (flat \
          start dashed; y stretched 4.6×)</text>\n</svg>\n";
    Ok(s)
}
