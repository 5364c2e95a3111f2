//! Fuzz target `scaled`: a scene and a copy scaled by a power of two (exactly: every
//! coordinate times 2^j) give the same statuses, and times scaled by 2^j, or the copy is
//! refused as a whole for leaving the accepted coordinate range. Region lookup, the
//! classification and the solver must not depend on the scene's absolute size.
#![no_main]

use arbitrary::Arbitrary;
use eigenray::scene::{MAX_COORDINATE, MIN_COORDINATE};
use eigenray::{Scene, SceneSpec, SolverOptions, Tracer};
use eigenray::scene::ReceiversSpec;
use libfuzzer_sys::fuzz_target;

mod spec_gen;
use spec_gen::{Input, build};

#[derive(Arbitrary, Debug)]
struct Scaled {
    input: Input,
    /// The power of two.
    exponent: i16,
}

/// Every coordinate of `spec` times `f`.
fn scaled(spec: &SceneSpec, f: f64) -> SceneSpec {
    let mut s = spec.clone();
    let p = |p: &mut [f64; 2]| {
        p[0] *= f;
        p[1] *= f;
    };
    s.media.values_mut().for_each(|m| m.at.iter_mut().for_each(p));
    s.domain.iter_mut().for_each(|[a, b]| {
        p(a);
        p(b);
    });
    s.interfaces
        .values_mut()
        .for_each(|i| i.points.iter_mut().for_each(p));
    s.sources
        .iter_mut()
        .chain(s.receivers.points_mut())
        .for_each(p);
    s
}

/// Whether every nonzero coordinate of `spec` lies in the accepted range.
fn in_range(spec: &SceneSpec) -> bool {
    let ok = |v: f64| v == 0.0 || (MIN_COORDINATE..=MAX_COORDINATE).contains(&v.abs());
    let p = |p: &[f64; 2]| ok(p[0]) && ok(p[1]);
    spec.media.values().all(|m| m.at.as_ref().is_none_or(p))
        && spec.domain.as_ref().is_none_or(|[a, b]| p(a) && p(b))
        && spec.interfaces.values().all(|i| i.points.iter().all(p))
        && spec.sources.iter().all(p)
        && match &spec.receivers {
            ReceiversSpec::Points(list) => list.iter().all(p),
            ReceiversSpec::Grid { grid } => {
                p(&[grid.x[0], grid.y[0]]) && p(&[grid.x[1], grid.y[1]])
            }
        }
}

fuzz_target!(|data: Scaled| {
    let spec = build(&data.input);
    let Ok(mut scene) = Scene::from_spec(&spec) else {
        return;
    };
    let j = i32::from(data.exponent % 700);
    let f = 2f64.powi(j);
    let copy = scaled(&spec, f);
    let mut other = match Scene::from_spec(&copy) {
        Ok(s) => s,
        Err(e) => {
            // Only a copy outside the accepted range may be refused.
            assert!(
                !in_range(&copy) || e.key == "scene",
                "the copy scaled by 2^{j} is refused: {e}"
            );
            return;
        }
    };
    if scene.num_rays() > 16 || scene.paths().iter().any(|p| p.steps.len() > 6) {
        return;
    }
    let capped = SolverOptions {
        max_iterations: scene.solver().max_iterations.min(200),
        ..scene.solver()
    };
    scene.set_solver(capped).expect("valid options");
    other.set_solver(capped).expect("valid options");
    let (a, b) = match (Tracer::new(&scene), Tracer::new(&other)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(a), Err(b)) => {
            assert_eq!(a.key, b.key, "refused differently: {a} / {b}");
            return;
        }
        (a, b) => panic!(
            "one is refused: {:?} / {:?}",
            a.err().map(|e| e.to_string()),
            b.err().map(|e| e.to_string())
        ),
    };
    let (ra, rb) = (a.trace_all(), b.trace_all());
    for (x, y) in ra.iter().zip(&rb) {
        assert_eq!(
            x.status, y.status,
            "ray ({}, {}, {}) at 2^{j}: {x:?} / {y:?}",
            x.source, x.receiver, x.path
        );
        if x.status.has_time() {
            let (t, u) = (x.time, y.time);
            let err = ((u / f - t) / t).abs();
            assert!(err <= 1e-12 || t == 0.0, "time {t} against {u} at 2^{j}");
        }
    }
});
