//! Fuzz target `structured`: scenes built from structured data (grid-snapped coordinates, so touching, collinear and T-junction cases are common, at scales down to subnormal numbers), validated and traced.
#![no_main]

use eigenray::Scene;
use libfuzzer_sys::fuzz_target;

mod common;
mod spec_gen;
use spec_gen::{Input, all_finite, build};

fuzz_target!(|input: Input| {
    let spec = build(&input);
    let direct = Scene::from_spec(&spec);
    if all_finite(&spec) {
        // The JSON route validates exactly like the spec route.
        let text = serde_json::to_string(&spec).expect("a spec serialises");
        let parsed = Scene::from_json(&text);
        match (&direct, &parsed) {
            (Ok(_), Ok(_)) => {}
            (Err(a), Err(b)) => assert_eq!(a, b, "{text}"),
            _ => panic!(
                "from_spec and from_json disagree: {:?} vs {:?}\n{text}",
                direct.as_ref().err(),
                parsed.as_ref().err()
            ),
        }
    }
    // The budget of the scene as the JSON document it would be.
    let bytes = serde_json::to_string(&spec).map_or(0, |t| t.len());
    common::within_budget(bytes, || match direct {
        Ok(scene) => common::trace_and_check(scene),
        Err(e) => assert!(
            !e.key.is_empty() && !e.message.is_empty(),
            "error without a key or message: {e:?}"
        ),
    });
});
