//! What a ray's gradient costs beside the ray: `Tracer::solve` alone, followed by
//! `Gradient::solved_into`, and `Tracer::solve_with_gradient` (one call), one receiver after
//! the other, on one refraction (`demo::air_water`), eight flat layers
//! (`demo::layer_stack(8, …)`) and eight dipping layers (`demo::dipping_stack(8, …)`). Two
//! more cases give what a medium with a speed gradient costs against a uniform one: the
//! benchmark scene `fixtures/bench/layers10.json` as it is (`layers10`) and with every
//! medium given `"gradient": [0, -0.02]` (`layers10_speed_gradient`: every leg an arc).
//!
//! - `cargo run --release --example gradient_cost` times the three ways in alternating
//!   rounds and prints the median nanoseconds per ray and the ratios to the ray alone, all
//!   measured in one run; then one ray of `layers10_speed_gradient` against one of
//!   `layers10`, the two in alternating rounds, and their ratio.
//! - `gradient_cost CASE WAY REPS` runs one way `REPS` times over the case's receivers and
//!   nothing else, for an instruction count: `benches/gradient_instructions.sh` runs it under
//!   callgrind at 1 and 3 repetitions and prints `(instructions(3) − instructions(1)) / (2 ×
//!   rays)`, the cost of one ray without the set-up.

use std::hint::black_box;
use std::time::Instant;

use eigenray::{Gradient, Scene, SceneSpec, Tracer, Workspace, demo};

/// The cases: name and scene.
fn cases() -> Result<Vec<(&'static str, Scene)>, Box<dyn std::error::Error>> {
    Ok(vec![
        (
            "one_refraction",
            Scene::from_spec(&demo::air_water(10_000, 1))?,
        ),
        ("stack8", Scene::from_spec(&demo::layer_stack(8, 2000))?),
        ("dipping8", Scene::from_spec(&demo::dipping_stack(8, 2000))?),
        ("layers10", Scene::from_spec(&layers10(None)?)?),
        (
            "layers10_speed_gradient",
            Scene::from_spec(&layers10(Some(SPEED_GRADIENT))?)?,
        ),
    ])
}

/// The speed gradient given to every medium of `layers10_speed_gradient` (speed per unit
/// length, growing downward).
const SPEED_GRADIENT: [f64; 2] = [0.0, -0.02];

/// The benchmark scene `fixtures/bench/layers10.json`, with every medium's speed given the
/// gradient `gradient` when there is one.
fn layers10(gradient: Option<[f64; 2]>) -> Result<SceneSpec, Box<dyn std::error::Error>> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/bench/layers10.json");
    let mut spec = SceneSpec::from_json(&std::fs::read_to_string(path)?)?;
    for medium in spec.media.values_mut() {
        medium.gradient = gradient;
    }
    Ok(spec)
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
            .ok_or_else(|| {
                format!(
                    "no case {case}: one_refraction, stack8, dipping8, layers10 or \
                     layers10_speed_gradient"
                )
            })?;
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
    println!(
        "case                     ray ns  +solved_into ns  ratio  solve_with_gradient ns  ratio"
    );
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
            "{name:<23} {ray:>7.1}  {then:>15.1}  {:>5.2}  {with:>22.1}  {:>5.2}",
            then / ray,
            with / ray
        );
    }
    speed_gradient_against_uniform(&mut ws)
}

/// One ray of `layers10_speed_gradient` against one of `layers10` (`Tracer::solve`), the two
/// scenes in alternating rounds: the median nanoseconds per ray of each and their ratio.
fn speed_gradient_against_uniform(ws: &mut Workspace) -> Result<(), Box<dyn std::error::Error>> {
    const ROUNDS: usize = 101;
    let tracers = [
        Tracer::new(Scene::from_spec(&layers10(None)?)?)?,
        Tracer::new(Scene::from_spec(&layers10(Some(SPEED_GRADIENT))?)?)?,
    ];
    let mut g = Gradient::default();
    let mut times: [Vec<f64>; 2] = Default::default();
    for round in 0..ROUNDS {
        for k in 0..2 {
            let i = (round + k) % 2;
            let start = Instant::now();
            let rays = pass(&tracers[i], Way::Ray, ws, &mut g);
            times[i].push(start.elapsed().as_secs_f64() * 1e9 / rays as f64);
        }
    }
    let [uniform, curved] = times.map(|mut t| {
        t.sort_by(f64::total_cmp);
        t[t.len() / 2]
    });
    println!(
        "layers10, one ray (alternating rounds): uniform {uniform:.1} ns, speed gradient \
         {curved:.1} ns, ratio {:.2}",
        curved / uniform
    );
    Ok(())
}
