//! What a ray's amplitude costs beside the ray: `Tracer::solve` on a scene without
//! `amplitudes`, the same on the scene with them (nothing computed: the solve does not look),
//! and `Tracer::solve` followed by `Tracer::amplitude`, one receiver after the other, on one
//! refraction (`demo::air_water`, Fresnel coefficients) and ten flat layers
//! (`demo::layer_stack(10, …)`, fluid coefficients).
//!
//! - `cargo run --release --example amplitude_cost` times the ways in alternating rounds and
//!   prints the median nanoseconds per ray and the ratios to the ray alone.
//! - `amplitude_cost CASE WAY REPS` runs one way `REPS` times over the case's receivers and
//!   nothing else, for an instruction count: `benches/amplitude_instructions.sh` runs it under
//!   callgrind at 1 and 3 repetitions and prints `(instructions(3) − instructions(1)) / (2 ×
//!   rays)`, the cost of one ray without the set-up.

use std::hint::black_box;
use std::time::Instant;

use eigenray::scene::{AmplitudesSpec, SourceModel};
use eigenray::{Scene, SceneSpec, Tracer, Workspace, demo};

/// The cases: name and scene (without amplitudes).
fn cases() -> Vec<(&'static str, SceneSpec)> {
    vec![
        ("one_refraction", demo::air_water(10_000, 1)),
        ("layers10", demo::layer_stack(10, 2000)),
    ]
}

/// How a ray is asked for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Way {
    /// `Tracer::solve` on the scene without amplitudes.
    Ray,
    /// `Tracer::solve` on the scene with amplitudes (the solve alone).
    RayAsking,
    /// `Tracer::solve`, then `Tracer::amplitude`.
    RayThenAmplitude,
    /// `Tracer::solve_with_amplitude`.
    WithAmplitude,
}

impl Way {
    const ALL: [Way; 4] = [
        Way::Ray,
        Way::RayAsking,
        Way::RayThenAmplitude,
        Way::WithAmplitude,
    ];

    fn name(self) -> &'static str {
        match self {
            Way::Ray => "ray",
            Way::RayAsking => "ray_asking",
            Way::RayThenAmplitude => "ray_then_amplitude",
            Way::WithAmplitude => "solve_with_amplitude",
        }
    }
}

/// The tracers of a case: without amplitudes and with them (a point source).
fn tracers(spec: &SceneSpec) -> Result<[Tracer; 2], Box<dyn std::error::Error>> {
    let mut asking = spec.clone();
    asking.amplitudes = Some(AmplitudesSpec::new(SourceModel::Point));
    Ok([
        Tracer::new(Scene::from_spec(spec)?)?,
        Tracer::new(Scene::from_spec(&asking)?)?,
    ])
}

/// One pass over the scene's receivers from its first source, the way `way`; returns the rays
/// solved.
fn pass(tracers: &[Tracer; 2], way: Way, ws: &mut Workspace) -> usize {
    let tracer = &tracers[usize::from(way != Way::Ray)];
    let scene = tracer.scene();
    let source = scene.sources()[0];
    let mut amplitude = None;
    for &receiver in scene.receivers() {
        let (s, r) = (black_box(source), black_box(receiver));
        if way == Way::WithAmplitude {
            black_box(tracer.solve_with_amplitude(s, r, 0, ws, &mut amplitude));
            black_box(&amplitude);
            continue;
        }
        let record = tracer.solve(s, r, 0, ws);
        if way == Way::RayThenAmplitude {
            black_box(tracer.amplitude(0, &record, ws));
        }
        black_box(record);
    }
    scene.receivers().len()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut ws = Workspace::new();
    if let [case, way, reps] = args.as_slice() {
        let (_, spec) = cases()
            .into_iter()
            .find(|(name, _)| name == case)
            .ok_or_else(|| format!("no case {case}: one_refraction or layers10"))?;
        let way = Way::ALL
            .into_iter()
            .find(|w| w.name() == way)
            .ok_or_else(|| {
                format!("no way {way}: ray, ray_asking, ray_then_amplitude or solve_with_amplitude")
            })?;
        let tracers = tracers(&spec)?;
        let reps: usize = reps.parse()?;
        let mut rays = 0;
        for _ in 0..reps {
            rays += pass(&tracers, way, &mut ws);
        }
        eprintln!("rays per repetition: {}", rays / reps.max(1));
        return Ok(());
    }
    if !args.is_empty() {
        return Err("usage: amplitude_cost [CASE WAY REPS]".into());
    }
    const ROUNDS: usize = 201;
    println!(
        "case            ray ns  asking ns  ratio  +amplitude ns  ratio  with_amplitude ns  ratio"
    );
    for (name, spec) in cases() {
        let tracers = tracers(&spec)?;
        let mut times: [Vec<f64>; 4] = Default::default();
        for round in 0..ROUNDS {
            // A different way first in each round, so that none always runs warm.
            for k in 0..4 {
                let i = (round + k) % 4;
                let start = Instant::now();
                let rays = pass(&tracers, Way::ALL[i], &mut ws);
                times[i].push(start.elapsed().as_secs_f64() * 1e9 / rays as f64);
            }
        }
        let [ray, asking, then, with] = times.map(|mut t| {
            t.sort_by(f64::total_cmp);
            t[t.len() / 2]
        });
        println!(
            "{name:<14} {ray:>7.1}  {asking:>9.1}  {:>5.2}  {then:>13.1}  {:>5.2}  {with:>17.1}  {:>5.2}",
            asking / ray,
            then / ray,
            with / ray
        );
    }
    Ok(())
}
