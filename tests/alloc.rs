//! The per-ray hot path allocates nothing once a workspace has grown (a counting allocator).

use eigenray::{Scene, Tracer, Workspace, demo};

/// Solves every ray of `scene` twice with one workspace (cold start, then warm-started from
/// the previous ray's parameters) and counts the allocations of the second sweep.
fn allocations_per_sweep(scene: &Scene) -> u64 {
    let tracer = Tracer::new(scene).unwrap();
    let mut ws = Workspace::new();
    let mut guess = Vec::new();
    let (ns, nr, np) = (
        scene.sources().len(),
        scene.receivers().len(),
        scene.paths().len(),
    );
    let sweep = |ws: &mut Workspace, guess: &mut Vec<f64>| {
        let mut converged = 0;
        for s in 0..ns {
            for r in 0..nr {
                for p in 0..np {
                    let k = scene.paths()[p].steps.len();
                    let warm = (guess.len() == k).then_some(guess.as_slice());
                    let out = tracer.solve_indexed_from(s, r, p, warm, ws);
                    if out.status == eigenray::Status::Converged {
                        converged += 1;
                    }
                    if guess.len() == k {
                        guess.copy_from_slice(ws.parameters());
                    }
                }
            }
        }
        converged
    };
    // Grow the workspace and the guess buffer to the longest path.
    let longest = scene
        .paths()
        .iter()
        .map(|p| p.steps.len())
        .max()
        .unwrap_or(0);
    guess.resize(longest, 0.0);
    guess.clear();
    let warm_up = sweep(&mut ws, &mut guess);
    assert!(
        warm_up > 0,
        "the scene must have converging rays for the test to mean anything"
    );
    let info = allocation_counter::measure(|| {
        sweep(&mut ws, &mut guess);
    });
    info.count_total
}

fn bench_scene(name: &str) -> Scene {
    let path = format!("{}/fixtures/bench/{name}.json", env!("CARGO_MANIFEST_DIR"));
    Scene::from_json(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn single_refraction_allocates_nothing() {
    let scene = Scene::from_spec(&demo::air_water(200, 3)).unwrap();
    assert_eq!(allocations_per_sweep(&scene), 0);
}

#[test]
fn layer_stack_allocates_nothing() {
    assert_eq!(allocations_per_sweep(&bench_scene("layers10")), 0);
}

#[test]
fn room_reflections_allocate_nothing() {
    // Converged, no_path (open ends, corners) and every branch of the classification.
    assert_eq!(allocations_per_sweep(&bench_scene("room2d")), 0);
}

#[test]
fn region_lookup_allocates_nothing() {
    // Leg media from region lookup (the triangulation), a lens crossed twice, obstruction.
    let scene = Scene::from_json(
        r#"{
        "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.75, "at": [0.5, -0.5] },
                   "glass": { "speed": 0.6, "at": [3.5, 0.6] } },
        "background": "air",
        "domain": [[-2.0, -3.0], [5.0, 3.0]],
        "interfaces": {
            "surface": { "points": [[-2.0, 0.0], [5.0, 0.0]] },
            "lens": { "points": [[3, 0.5], [4, 0.5], [4, 1.5]], "closed": true }
        },
        "sources": [[0.0, 1.0], [3.2, 2.0]],
        "receivers": [[1.0, -1.0], [0.5, -1.0], [3.9, 0.3], [4.5, 2.5]],
        "paths": [
            { "steps": [] },
            { "steps": [{ "refract": "surface" }] },
            { "steps": [{ "reflect": "surface" }] },
            { "steps": [{ "refract": "lens" }, { "refract": "lens" }] }
        ]
    }"#,
    )
    .unwrap();
    assert_eq!(allocations_per_sweep(&scene), 0);
}

/// Allocations of tracing `scene` into a batch that already holds its rays, on `pool` (whose
/// one thread is the test's: the counter counts this thread's allocations).
fn batch_allocations(scene: &Scene, pool: &rayon::ThreadPool) -> u64 {
    let tracer = Tracer::new(scene).unwrap();
    let opts = eigenray::BatchOptions::default();
    let mut batch = eigenray::Batch::default();
    let run = eigenray::options::Run::new();
    pool.install(|| tracer.trace_batch_into(&opts, &run, &mut batch).unwrap());
    let info = allocation_counter::measure(|| {
        pool.install(|| tracer.trace_batch_into(&opts, &run, &mut batch).unwrap());
    });
    info.count_total
}

#[test]
fn batches_allocate_per_call_not_per_ray() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build()
        .unwrap();
    // A batch allocates its offsets and a workspace per rayon job, whatever the rays: ten
    // times the receivers must not cost more. One refraction (solved without a workspace)
    // and a stack of layers (the general path).
    for spec in [|n| demo::air_water(n, 3), |n| demo::layer_stack(3, n)] {
        let few = batch_allocations(&Scene::from_spec(&spec(2_000)).unwrap(), &pool);
        let many = batch_allocations(&Scene::from_spec(&spec(20_000)).unwrap(), &pool);
        assert!(few > 0, "the counter must see the batch's own allocations");
        assert!(
            many <= few + 16,
            "{few} allocations for 2,000 rays, {many} for 20,000"
        );
    }
}

/// Solves every ray of `scene` with one workspace (after a first sweep that grows it) and
/// computes each ray's amplitude; counts the allocations of the amplitudes alone (the solve
/// of a digitised reflector may allocate in its fallback search, which is not theirs).
fn amplitude_allocations(scene: &Scene) -> u64 {
    let tracer = Tracer::new(scene).unwrap();
    let mut ws = Workspace::new();
    let (mut count, mut with) = (0, 0);
    for sweep in 0..2 {
        for s in 0..scene.sources().len() {
            for r in 0..scene.receivers().len() {
                for p in 0..scene.paths().len() {
                    let record = tracer.solve_indexed_from(s, r, p, None, &mut ws);
                    let info = allocation_counter::measure(|| {
                        let a = tracer.amplitude(p, &record, &ws);
                        with += usize::from(a.is_some_and(|a| a.has_value()));
                    });
                    if sweep == 1 {
                        count += info.count_total;
                    }
                }
            }
        }
    }
    assert!(with > 0, "the scene must have amplitudes");
    count
}

#[test]
fn amplitudes_allocate_nothing() {
    let point = eigenray::scene::AmplitudesSpec::new(eigenray::scene::SourceModel::Point);
    for mut spec in [
        demo::air_water(200, 3),
        demo::layer_stack(10, 50),
        demo::sea_floor(300, 50),
    ] {
        spec.amplitudes = Some(point);
        assert_eq!(amplitude_allocations(&Scene::from_spec(&spec).unwrap()), 0);
    }
    // Region lookup and a reflection against the medium across.
    let scene = Scene::from_json(
        r#"{ "media": { "air": { "speed": 1.0 }, "water": { "speed": 0.75, "at": [0.5, -0.5] } },
             "background": "air", "domain": [[-2.0, -3.0], [5.0, 3.0]],
             "interfaces": { "surface": { "points": [[-2.0, 0.0], [5.0, 0.0]], "reflection": "media" } },
             "sources": [[0.0, 1.0]], "receivers": [[1.0, -1.0], [0.5, 1.5], [2.0, 0.5]],
             "paths": [{ "steps": [] }, { "steps": [{ "refract": "surface" }] },
                       { "steps": [{ "reflect": "surface" }] }],
             "amplitudes": { "source": "axisymmetric" } }"#,
    )
    .unwrap();
    assert_eq!(amplitude_allocations(&scene), 0);
}
