//! What a ray's gradient costs beside the ray: `Tracer::solve` alone, followed by
//! `Gradient::solved_into`, and `Tracer::solve_with_gradient` (one call), one receiver after
//! the other, on one refraction (`demo::air_water`), eight flat layers
//! (`demo::layer_stack(8, …)`) and eight dipping layers (`demo::dipping_stack(8, …)`).
//!
//! - `cargo run --release --example gradient_cost` times the three ways in alternating
//!   rounds and prints the median nanoseconds per ray and the ratios to the ray alone, all
//!   measured in one run.
//! - `gradient_cost CASE WAY REPS` runs one way `REPS` times over the case's receivers and
//!   nothing else, for an instruction count: `benches/gradient_instructions.sh` runs it under
//!   callgrind at 1 and 3 repetitions and prints `(instructions(3) − instructions(1)) / (2 ×
//!   rays)`, the cost of one ray without the set-up.

use std::hint::black_box;
use std::time::Instant;

use eigenray::{Gradient, Scene, Tracer, Workspace, demo};

/// The cases: name and scene.
fn cases() -> Result<Vec<(&'static str, Scene)>, Box<dyn std::error::Error>> {
    Ok(vec![
        (
            "one_refraction",
            Scene::from_spec(&demo::air_water(10_000, 1))?,
        ),
        ("stack8", Scene::from_spec(&demo::layer_stack(8, 2000))?),
        ("dipping8", Scene::from_spec(&demo::dipping_stack(8, 2000))?),
    ])
}

/// How a ray is asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Way {
    /// `Tracer::solve`.
    Ray,
    /// `Tracer::solve`, then `Gradient::solved_into` when the ray has a time.
    RayThenGradient,
    /// `Tracer::solve_with_gradient`.
    WithGradient,
}

impl Way {
    const ALL: [Way; 3] = [Way::Ray, Way::RayThenGradient, Way::WithGradient];

    fn name(self) -> &'static str {
        match self {
            Way::Ray => "ray",
            Way::RayThenGradient => "ray_then_gradient",
            Way::WithGradient => "solve_with_gradient",
        }
    }
}

/// One pass over the scene's receivers from its first source, the way `way`; returns the rays
/// solved.
fn pass(tracer: &Tracer, way: Way, ws: &mut Workspace, g: &mut Gradient) -> usize {
    let scene = tracer.scene();
    let source = scene.sources()[0];
    for &receiver in scene.receivers() {
        let (s, r) = (black_box(source), black_box(receiver));
        match way {
            Way::Ray => {
                black_box(tracer.solve(s, r, 0, ws));
            }
            Way::RayThenGradient => {
                let record = tracer.solve(s, r, 0, ws);
                if record.status.has_time() {
                    black_box(g.solved_into(scene, 0, ws).is_ok());
                }
                black_box(record);
            }
            Way::WithGradient => {
                black_box(tracer.solve_with_gradient(s, r, 0, ws, g).is_ok());
                black_box(g.source);
            }
        }
    }
    scene.receivers().len()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut ws = Workspace::new();
    let mut g = Gradient::default();
    if let [case, way, reps] = args.as_slice() {
        let (_, scene) = cases()?
            .into_iter()
            .find(|(name, _)| name == case)
            .ok_or_else(|| format!("no case {case}: one_refraction, stack8 or dipping8"))?;
        let way = Way::ALL
            .into_iter()
            .find(|w| w.name() == way)
            .ok_or_else(|| {
                format!("no way {way}: ray, ray_then_gradient or solve_with_gradient")
            })?;
        let tracer = Tracer::new(scene)?;
        let mut rays = 0;
        for _ in 0..reps.parse::<usize>()? {
            rays += pass(&tracer, way, &mut ws, &mut g);
        }
        eprintln!(
            "rays per repetition: {}",
            rays / reps.parse::<usize>()?.max(1)
        );
        return Ok(());
    }
    if !args.is_empty() {
        return Err("usage: gradient_cost [CASE WAY REPS]".into());
    }
    const ROUNDS: usize = 201;
    println!("case            ray ns  +solved_into ns  ratio  solve_with_gradient ns  ratio");
    for (name, scene) in cases()? {
        let tracer = Tracer::new(scene)?;
        let mut times: [Vec<f64>; 3] = Default::default();
        for round in 0..ROUNDS {
            // A different way first in each round, so that none always runs warm.
            for k in 0..3 {
                let i = (round + k) % 3;
                let start = Instant::now();
                let rays = pass(&tracer, Way::ALL[i], &mut ws, &mut g);
                times[i].push(start.elapsed().as_secs_f64() * 1e9 / rays as f64);
            }
        }
        let [ray, then, with] = times.map(|mut t| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        });
        println!(
            "{name:<14} {ray:>7.1}  {then:>15.1}  {:>5.2}  {with:>22.1}  {:>5.2}",
            then / ray,
            with / ray
        );
    }
    Ok(())
}
