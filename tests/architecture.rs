//! The dependency direction of `ARCHITECTURE.md`: each module of `src/` uses only the modules
//! listed before it (test code inside a module may use anything), and the kernels in
//! `src/trace/` never reach up to the `Tracer`.

use std::path::Path;

/// The modules in order: each may use only those before it.
const ORDER: &[&str] = &[
    "geom",
    "bvh",
    "polyline",
    "scene",
    "demo",
    "regions",
    "problem",
    "solver",
    "trace",
    "batch",
    "arrivals",
    "derivatives",
    "output",
    "argmin_bridge",
];

/// The text of a source file up to its test module.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => text[..i].to_string(),
        None => text,
    }
}

/// The top-level module of a file under `src/` (`src/trace/plan.rs` → `trace`).
fn module_of(src: &Path, path: &Path) -> Option<String> {
    let rel = path.strip_prefix(src).ok()?;
    let first = rel
        .components()
        .next()?
        .as_os_str()
        .to_string_lossy()
        .to_string();
    Some(first.trim_end_matches(".rs").to_string())
}

/// Every `crate::NAME` that `text` mentions.
fn uses(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, _) in text.match_indices("crate::") {
        let name: String = text[i + 7..]
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        out.push(name);
    }
    out
}

fn files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn no_module_uses_one_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut checked = 0;
    for path in all {
        let Some(module) = module_of(&src, &path) else {
            continue;
        };
        // The crate root and the binary are the top: they may use everything.
        let Some(rank) = ORDER.iter().position(|m| *m == module) else {
            assert!(
                ["lib", "bin"].contains(&module.as_str()),
                "{}: a module missing from ARCHITECTURE.md's order",
                path.display()
            );
            continue;
        };
        for used in uses(&code(&path)) {
            // The crate root re-exports items of lower modules (`crate::Point`).
            let Some(used_rank) = ORDER.iter().position(|m| *m == used) else {
                continue;
            };
            assert!(
                used_rank <= rank,
                "{} (module `{module}`) uses `crate::{used}`, which ARCHITECTURE.md puts below it",
                path.display()
            );
        }
        checked += 1;
    }
    assert!(checked >= ORDER.len());
}

#[test]
fn kernels_do_not_reach_up_to_the_tracer() {
    let trace = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/trace");
    for name in [
        "classify.rs",
        "complete.rs",
        "flat.rs",
        "one_step.rs",
        "plan.rs",
        "result.rs",
        "stack.rs",
        "start.rs",
        "straight.rs",
    ] {
        let text = code(&trace.join(name));
        let code_lines = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        assert!(
            !code_lines.contains("Tracer"),
            "src/trace/{name} uses the Tracer: kernels take a Context"
        );
    }
}
