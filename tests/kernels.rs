//! Every kernel against the general code: the bit-exact kernels and fast paths
//! ([`Kernels::BitExact`]) give the very rays of the general Newton loop alone
//! ([`Kernels::GeneralOnly`]), one by one, warm-started and in batches; the flat-refraction
//! kernel ([`Kernels::All`]) gives the same statuses and times within 1e-12.

use eigenray::{
    BatchOptions, InitialGuess, Ray, Reason, Scene, Status, Tracer, Workspace, demo, trace::Kernels,
};
use serde_json::json;

/// A ray as bits (its residual's NaN compares equal to another NaN).
fn bits(ray: &Ray) -> impl PartialEq + std::fmt::Debug + use<> {
    (
        ray.status,
        ray.time.to_bits(),
        ray.iterations,
        ray.residual.to_bits(),
        ray.reason,
        ray.points
            .iter()
            .map(|p| (p.x.to_bits(), p.y.to_bits()))
            .collect::<Vec<_>>(),
        ray.media.clone(),
    )
}

/// The rays of `scene` through `kernels` and through the general code alone, one by one and
/// from warm starts (each receiver from the previous one's parameters, moved): bit for bit.
/// Returns the statuses of the rays, for the callers to check what the scene exercises.
fn bit_exact(scene: &Scene, kernels: Kernels) -> Vec<Status> {
    let fast = Tracer::new(scene).unwrap().with_kernels(kernels);
    let general = Tracer::new(scene)
        .unwrap()
        .with_kernels(Kernels::GeneralOnly);
    let (a, b) = (fast.trace_all(), general.trace_all());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert_eq!(bits(x), bits(y), "ray {i}: {x:?} vs {y:?}");
    }
    let (mut wa, mut wb) = (Workspace::new(), Workspace::new());
    for (p, path) in scene.paths().iter().enumerate() {
        let mut last = vec![0.5; path.steps.len()];
        for &s in scene.sources() {
            for &r in scene.receivers() {
                let guess: Vec<f64> = last.iter().map(|x| x + 1e-3).collect();
                let x = fast.solve_from(s, r, p, &guess, &mut wa);
                let y = general.solve_from(s, r, p, &guess, &mut wb);
                assert_eq!(
                    (x.status, x.time.to_bits(), x.iterations, x.reason),
                    (y.status, y.time.to_bits(), y.iterations, y.reason)
                );
                assert_eq!(wa.points(), wb.points());
                assert_eq!(wa.parameters(), wb.parameters());
                last.copy_from_slice(wa.parameters());
            }
        }
    }
    for warm_start in [false, true] {
        let opts = BatchOptions {
            warm_start,
            chunk: 16,
        };
        let (ba, bb) = (
            fast.trace_batch(&opts, &eigenray::options::Run::new())
                .unwrap(),
            general
                .trace_batch(&opts, &eigenray::options::Run::new())
                .unwrap(),
        );
        for i in 0..ba.len() {
            assert_eq!(bits(&ba.ray(i)), bits(&bb.ray(i)), "batch ray {i}");
        }
    }
    a.iter().map(|r| r.status).collect()
}

fn count(statuses: &[Status], status: Status) -> usize {
    statuses.iter().filter(|&&s| s == status).count()
}

fn bench(name: &str) -> Scene {
    let path = format!("{}/fixtures/bench/{name}.json", env!("CARGO_MANIFEST_DIR"));
    Scene::from_json(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn bit_exact_kernels_take_the_general_steps() {
    for spec in [
        demo::air_water(200, 3),
        demo::layer_stack(8, 100),
        demo::layer_stack(40, 30),
        demo::dipping_stack(8, 100),
        demo::sea_floor(3000, 100),
    ] {
        bit_exact(&Scene::from_spec(&spec).unwrap(), Kernels::BitExact);
    }
    for name in ["room2d", "seed500", "layers10"] {
        bit_exact(&bench(name), Kernels::BitExact);
    }
    let root = env!("CARGO_MANIFEST_DIR");
    for dir in ["cases", "fuzz"] {
        for entry in std::fs::read_dir(format!("{root}/fixtures/{dir}")).unwrap() {
            let path = entry.unwrap().path();
            let name = path.to_string_lossy();
            if name.ends_with(".json") && !name.ends_with(".expected.json") {
                let scene = Scene::from_json(&std::fs::read_to_string(&path).unwrap()).unwrap();
                bit_exact(&scene, Kernels::BitExact);
            }
        }
    }
}

/// Two parallel refracting segments, a source above and receivers below both, and every
/// order of the two steps: in layer order (the stack kernel's common case), in reverse order
/// (leg 0 runs to the lower interface: the legs at each point lie on one side, no path), and
/// mixed (down, up, down). The kernel's side test decides the reverse order: without it such
/// rays would come out `obstructed`.
#[test]
fn the_stack_kernel_follows_any_step_order() {
    let receivers: Vec<[f64; 2]> = (0..300)
        .map(|i| [-4.0 + 0.027 * i as f64, -1.2 - 0.011 * (i % 40) as f64])
        .collect();
    let orders: [&[&str]; 4] = [
        &["top", "bottom"],
        &["bottom", "top"],
        &["top", "bottom", "top"],
        &["bottom", "top", "bottom", "top"],
    ];
    for order in orders {
        let steps: Vec<_> = order.iter().map(|n| json!({ "refract": n })).collect();
        let media: Vec<_> = (0..=order.len())
            .map(|i| json!(["air", "glass", "water"][i % 3]))
            .collect();
        let doc = json!({
            "media": { "air": { "speed": 1.0 }, "glass": { "speed": 0.6 }, "water": { "speed": 0.8 } },
            "interfaces": {
                "top": { "points": [[-6.0, 0.0], [6.0, 0.0]] },
                "bottom": { "points": [[6.0, -1.0], [-6.0, -1.0]] }
            },
            "sources": [[0.3, 1.0], [-2.0, 0.4]],
            "receivers": receivers,
            "paths": [{ "steps": steps, "media": media }]
        });
        let scene = Scene::from_json(&doc.to_string()).unwrap();
        let statuses = bit_exact(&scene, Kernels::All);
        if order == ["top", "bottom"] {
            assert_eq!(count(&statuses, Status::Converged), statuses.len());
        } else {
            assert!(
                count(&statuses, Status::NoPath) > statuses.len() / 2,
                "{order:?}: {statuses:?}"
            );
        }
    }
    // The reverse order's rays fail the side test at the first step; the complete search
    // then proves that the sequence has no path.
    let doc = json!({
        "media": { "a": { "speed": 1.0 }, "b": { "speed": 0.6 }, "c": { "speed": 0.8 } },
        "interfaces": {
            "top": { "points": [[-6.0, 0.0], [6.0, 0.0]] },
            "bottom": { "points": [[-6.0, -1.0], [6.0, -1.0]] }
        },
        "sources": [[0.3, 1.0]], "receivers": [[1.0, -2.0]],
        "paths": [{ "steps": [{ "refract": "bottom" }, { "refract": "top" }], "media": ["a", "b", "c"] }]
    });
    let scene = Scene::from_json(&doc.to_string()).unwrap();
    let ray = &Tracer::new(&scene).unwrap().trace_all()[0];
    assert_eq!(ray.status, Status::NoPath, "{ray:?}");
    assert_eq!(ray.reason, Some(Reason::NoStationaryPath), "{ray:?}");
}

/// The flat-refraction kernel takes steps of its own: the general code's statuses and
/// reasons, times within 1e-12 and points within 1e-9 of the scene's size.
#[test]
fn the_flat_kernel_agrees_with_the_general_solve() {
    for scene in [
        bench("seed500"),
        Scene::from_spec(&demo::air_water(400, 9)).unwrap(),
    ] {
        let fast = Tracer::new(&scene).unwrap().trace_all();
        let general = Tracer::new(&scene)
            .unwrap()
            .with_kernels(Kernels::GeneralOnly)
            .trace_all();
        for (a, b) in fast.iter().zip(&general) {
            assert_eq!((a.status, a.reason), (b.status, b.reason));
            assert_eq!(a.media, b.media);
            if a.status.has_time() {
                assert!((a.time - b.time).abs() <= 1e-12 * b.time, "{a:?} vs {b:?}");
                for (p, q) in a.points.iter().zip(&b.points) {
                    assert!((*p - *q).length() <= 1e-9 * 10.0);
                }
            }
        }
    }
}

/// The kernels serve the default start only: from the paraxial start every ray goes through
/// the general code, so every kernel choice gives the same rays.
#[test]
fn kernels_do_not_change_the_paraxial_start() {
    let scene = Scene::from_spec(&demo::layer_stack(8, 50)).unwrap();
    let rays = |k: Kernels| {
        Tracer::new(&scene)
            .unwrap()
            .with_initial_guess(InitialGuess::Paraxial)
            .with_kernels(k)
            .trace_all()
    };
    let (a, b) = (rays(Kernels::All), rays(Kernels::GeneralOnly));
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(bits(x), bits(y));
    }
    assert!(a.iter().all(|r| r.iterations > 0));
}
