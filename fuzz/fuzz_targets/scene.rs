//! Fuzz target `scene`: raw bytes as a scene document through the parser, the tracer and the writer.
#![no_main]

use eigenray::Scene;
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    common::within_budget(data.len(), || match Scene::from_json(text) {
        Ok(scene) => common::trace_and_check(scene),
        Err(e) => assert!(
            !e.key.is_empty() && !e.message.is_empty(),
            "error without a key or message: {e:?}"
        ),
    });
});
