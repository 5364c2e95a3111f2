//! Placing and tilting a reflector so that a listener hears its first reflection a prescribed
//! delay after the direct sound, with argmin's L-BFGS as the outer optimiser and the exact
//! derivatives of the reflection's time with respect to the reflector's vertices inside
//! (`argmin_bridge::ReflectorPlacement`).
//!
//! A 3 m panel hangs above a talker and a listener 6 m apart. Its first reflection reaches the
//! listener 9.6 ms after the direct sound; L-BFGS moves and tilts the panel (as little as it
//! can: a small weight on the change) until the delay is 15 ms. The objective is printed per
//! iteration and the layout before and after drawn as an SVG.
//!
//! `cargo run --release --features argmin --example place_reflector [OUT.svg]`

use argmin::core::observers::ObserverMode;
use argmin::core::{Executor, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use eigenray::argmin_bridge::{Placement, ReflectorPlacement};
use eigenray::{Point, Scene, SceneSpec, Tracer, Workspace};
use nalgebra::DVector;

#[path = "support/objective.rs"]
mod objective;
#[path = "support/svg.rs"]
mod svg;

use objective::PrintObjective;

const SCENE: &str = r#"{
    "media": { "air": { "speed": 343.0 } },
    "interfaces": { "panel": { "points": [[0, 5], [3, 5]] } },
    "sources": [[0, 1.5]], "receivers": [[6, 1.2]],
    "paths": [
        { "name": "direct", "steps": [], "media": ["air"] },
        { "name": "panel", "steps": [{ "reflect": "panel" }], "media": ["air", "air"] }
    ]
}"#;

const LENGTH: f64 = 3.0;
const DELAY: f64 = 0.015;
/// The weight of staying near the start (small: the delay first).
const WEIGHT: f64 = 1e-4;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "place_reflector.svg".to_string());
    let spec: SceneSpec = serde_json::from_str(SCENE)?;
    let (source, listener) = (Point::new(0.0, 1.5), Point::new(6.0, 1.2));
    let start = Placement {
        center: Point::new(2.2, 4.2),
        angle: 0.15,
    };
    let problem = ReflectorPlacement::new(
        spec, "panel", 1, 0, source, listener, LENGTH, DELAY, start, WEIGHT,
    )?;
    let before = problem.misfit(start)?;
    println!(
        "prescribed delay {:.2} ms; at the start {:.3} ms",
        DELAY * 1e3,
        before.delay * 1e3
    );
    println!("iter     objective  centre              angle");
    println!(
        "{:>4}  {:>12.5e}  ({:.5}, {:.5})  {:>8.4}°",
        "init",
        before.cost,
        start.center.x,
        start.center.y,
        start.angle.to_degrees()
    );
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-12)?
        .with_tolerance_cost(0.0)?;
    let started = std::time::Instant::now();
    let init = DVector::from_vec(vec![start.center.x, start.center.y, start.angle]);
    let result = Executor::new(problem, solver)
        .configure(|s| s.param(init).max_iters(100))
        .add_observer(
            PrintObjective(|p| format!("({:.5}, {:.5})  {:>8.4}°", p[0], p[1], p[2].to_degrees())),
            ObserverMode::Always,
        )
        .ctrlc(false)
        .run()?;
    let elapsed = started.elapsed();
    let state = result.state();
    let best = state.get_best_param().expect("a best placement");
    let placed = Placement {
        center: Point::new(best[0], best[1]),
        angle: best[2],
    };
    let spec: SceneSpec = serde_json::from_str(SCENE)?;
    let problem = ReflectorPlacement::new(
        spec, "panel", 1, 0, source, listener, LENGTH, DELAY, start, WEIGHT,
    )?;
    let after = problem.misfit(placed)?;
    println!(
        "placed at ({:.4}, {:.4}), tilted {:.3}°, after {} iterations ({:.1} ms): delay {:.6} ms \
         ({})",
        placed.center.x,
        placed.center.y,
        placed.angle.to_degrees(),
        state.get_iter(),
        elapsed.as_secs_f64() * 1e3,
        after.delay * 1e3,
        state
            .get_termination_reason()
            .map_or("running", |r| r.text())
    );
    let svg = picture(&problem, source, listener, start, placed)?;
    std::fs::write(&out, svg)?;
    println!("wrote {out}");
    Ok(())
}

/// The panel and its reflection before (grey, dashed) and after (red), the direct ray thin.
fn picture(
    problem: &ReflectorPlacement,
    source: Point,
    listener: Point,
    start: Placement,
    placed: Placement,
) -> Result<String, Box<dyn std::error::Error>> {
    let (x0, x1, y0, y1) = (-1.0, 7.0, 0.0, 8.0);
    let scale = 80.0;
    let canvas = svg::Canvas::new([x0, x1], [y0, y1], [scale, scale], 0.0);
    let px = |p: Point| canvas.px(p);
    let mut s = canvas.header();
    let line = |pts: &[Point], style: &str| canvas.polyline(pts, style);
    s += &line(&[source, listener], "stroke=\"#999\"");
    for (p, style, label) in [
        (start, "stroke=\"#999\" stroke-dasharray=\"6 4\"", "start"),
        (placed, "stroke=\"#d0462c\" stroke-width=\"1.5\"", "placed"),
    ] {
        let scene: Scene = problem.scene(p)?;
        let [a, b] = p.endpoints(LENGTH);
        s += &line(&[a, b], "stroke=\"#3a7bd5\" stroke-width=\"4\"");
        let misfit = problem.misfit(p)?;
        let (x, y) = px(b);
        s += &format!(
            "<text x=\"{:.1}\" y=\"{:.1}\">{label}: {:.2} ms</text>\n",
            x + 8.0,
            y,
            misfit.delay * 1e3
        );
        let tracer = Tracer::new(&scene)?;
        let mut ws = Workspace::new();
        if tracer.solve(source, listener, 1, &mut ws).status.has_time() {
            s += &line(ws.points(), style);
        }
    }
    for (p, label) in [(source, "talker"), (listener, "listener")] {
        let (x, y) = px(p);
        s += &format!(
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"6\" fill=\"#222\"/>\n\
             <text x=\"{:.1}\" y=\"{:.1}\">{label}</text>\n",
            x - 20.0,
            y + 24.0
        );
    }
    s += &format!(
        "<text x=\"10\" y=\"20\">a 3 m panel placed for a first reflection {} ms after the \
         direct sound</text>\n</svg>\n",
        DELAY * 1e3
    );
    Ok(s)
}
