//! Locating a source from arrival times at several receivers: an inversion, as in seismology
//! or acoustic localisation, with argmin's L-BFGS as the outer optimiser and eigenray's rays
//! and their exact derivatives inside (`argmin_bridge::SourceLocation`).
//!
//! A source in the air above an undulating water surface is heard by six hydrophones below
//! it. From a wrong first guess, L-BFGS moves the source until the predicted refracted arrival
//! times match the observed ones; the objective is printed per iteration and the layout before
//! and after is drawn as an SVG.
//!
//! `cargo run --release --features argmin --example locate_source [OUT.svg]`

use argmin::core::observers::ObserverMode;
use argmin::core::{Executor, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use eigenray::argmin_bridge::{ObservedArrival, SourceLocation};
use eigenray::{Point, Scene, Tracer, Workspace};
use nalgebra::DVector;

#[path = "support/objective.rs"]
mod objective;
#[path = "support/svg.rs"]
mod svg;

use objective::PrintObjective;

const SCENE: &str = r#"{
    "media": { "air": { "speed": 343.0 }, "water": { "speed": 1480.0 } },
    "interfaces": { "surface": { "points": [[-60, 0], [-30, 1.5], [-10, -1], [10, 1.2], [30, -0.8], [60, 0]] } },
    "sources": [[0, 10]],
    "receivers": [[-25, -12], [-12, -20], [0, -8], [8, -25], [20, -15], [32, -10]],
    "paths": [{ "name": "refracted", "steps": [{ "refract": "surface" }], "media": ["air", "water"] }]
}"#;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "locate_source.svg".to_string());
    let scene = Scene::from_json(SCENE)?;
    let tracer = Tracer::new(&scene)?;
    let truth = Point::new(7.0, 14.0);
    let guess = Point::new(-20.0, 4.0);
    // The observations: the refracted arrival at each hydrophone from the true source.
    let mut ws = Workspace::new();
    let mut observed = Vec::new();
    for &receiver in scene.receivers() {
        let ray = tracer.solve(truth, receiver, 0, &mut ws);
        assert!(ray.status.has_time(), "every hydrophone hears the source");
        observed.push(ObservedArrival {
            receiver,
            path: 0,
            time: ray.time,
        });
    }
    let problem = SourceLocation::new(&tracer, observed);
    let before = problem.misfit(guess)?;
    println!(
        "true source ({}, {}), first guess ({}, {})",
        truth.x, truth.y, guess.x, guess.y
    );
    println!("iter     objective  source");
    println!(
        "{:>4}  {:>12.5e}  ({:.6}, {:.6})",
        "init", before.cost, guess.x, guess.y
    );
    let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7)
        .with_tolerance_grad(1e-16)?
        .with_tolerance_cost(0.0)?;
    let started = std::time::Instant::now();
    let result = Executor::new(problem, solver)
        .configure(|s| {
            s.param(DVector::from_vec(vec![guess.x, guess.y]))
                .max_iters(100)
        })
        .add_observer(
            PrintObjective(|p| format!("({:.6}, {:.6})", p[0], p[1])),
            ObserverMode::Always,
        )
        .ctrlc(false)
        .run()?;
    let elapsed = started.elapsed();
    let state = result.state();
    let best = state.get_best_param().expect("a best source");
    let found = Point::new(best[0], best[1]);
    println!(
        "found ({:.9}, {:.9}) after {} iterations, {} ray solves per evaluation, {:.1} ms: \
         {:.2e} from the truth ({})",
        found.x,
        found.y,
        state.get_iter(),
        scene.receivers().len(),
        elapsed.as_secs_f64() * 1e3,
        (found - truth).length(),
        state
            .get_termination_reason()
            .map_or("running", |r| r.text())
    );
    let svg = picture(&scene, &tracer, guess, found, truth)?;
    std::fs::write(&out, svg)?;
    println!("wrote {out}");
    Ok(())
}

/// The layout before (rays from the first guess, grey) and after (rays from the found source,
/// blue), the true source as a ring.
fn picture(
    scene: &Scene,
    tracer: &Tracer,
    guess: Point,
    found: Point,
    truth: Point,
) -> Result<String, Box<dyn std::error::Error>> {
    let (x0, x1, y0, y1) = (-45.0, 45.0, -30.0, 20.0);
    let scale = 10.0;
    let canvas = svg::Canvas::new([x0, x1], [y0, y1], [scale, scale], 0.0);
    let px = |p: Point| canvas.px(p);
    let mut s = canvas.header();
    let polyline = |pts: &[Point], style: &str| canvas.polyline(pts, style);
    for i in scene.interfaces() {
        s += &polyline(
            i.polyline.vertices(),
            "stroke=\"#3a7bd5\" stroke-width=\"2\"",
        );
    }
    let mut ws = Workspace::new();
    for (source, style) in [
        (guess, "stroke=\"#999\" stroke-dasharray=\"6 4\""),
        (found, "stroke=\"#d0462c\" stroke-width=\"1.5\""),
    ] {
        for &r in scene.receivers() {
            if tracer.solve(source, r, 0, &mut ws).status.has_time() {
                s += &polyline(ws.points(), style);
            }
        }
    }
    for &r in scene.receivers() {
        let (x, y) = px(r);
        s += &format!(
            "<rect x=\"{}\" y=\"{}\" width=\"8\" height=\"8\" fill=\"#222\"/>\n",
            x - 4.0,
            y - 4.0
        );
    }
    for (p, fill, label) in [
        (guess, "#999", "first guess"),
        (found, "#d0462c", "found by L-BFGS"),
    ] {
        let (x, y) = px(p);
        s += &format!(
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"5\" fill=\"{fill}\"/>\n\
             <text x=\"{:.1}\" y=\"{:.1}\">{label}</text>\n",
            x + 8.0,
            y - 8.0
        );
    }
    let (x, y) = px(truth);
    s += &format!(
        "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"9\" fill=\"none\" stroke=\"#222\"/>\n\
         <text x=\"{:.1}\" y=\"{:.1}\">true source</text>\n\
         <text x=\"10\" y=\"20\">air (343 m/s) over water (1480 m/s): source located from six \
         refracted arrival times</text>\n</svg>\n",
        x + 12.0,
        y + 16.0
    );
    Ok(s)
}
