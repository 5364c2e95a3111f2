//! The dependency direction of `ARCHITECTURE.md`: each module of `src/` uses only the modules
//! listed before it (test code inside a module may use anything), and the kernels in
//! `src/trace/` never reach up to the `Tracer`.

use std::path::Path;

/// The modules in order: each may use only those before it.
const ORDER: &[&str] = &[
    "options",
    "geom",
    "bvh",
    "polyline",
    "leg",
    "scene",
    "demo",
    "regions",
    "amplitude",
    "problem",
    "solver",
    "trace",
    "batch",
    "stationary",
    "search",
    "derivatives",
    "output",
    "response",
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

/// Every top-level module that `text` names after `crate::`: `crate::NAME` and each name of a
/// group, `crate::{NAME::…, NAME}`.
fn uses(text: &str) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.trim_start()
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    for (i, _) in text.match_indices("crate::") {
        let rest = &text[i + 7..];
        let Some(group) = rest.strip_prefix('{') else {
            out.push(ident(rest));
            continue;
        };
        // The names of the group at its own depth: after its `{` and after each `,` there.
        let mut depth = 0;
        let mut start = 0;
        for (j, c) in group.char_indices() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => {
                    out.push(ident(&group[start..j]));
                    break;
                }
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    out.push(ident(&group[start..j]));
                    start = j + 1;
                }
                _ => {}
            }
        }
    }
    out
}

#[test]
fn grouped_imports_count_as_uses() {
    let text = "use crate::{geom::Point, scene::{Scene, Step}, trace};\nuse crate::bvh::Bvh;";
    assert_eq!(uses(text), ["geom", "scene", "trace", "bvh"]);
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
        "flat.rs",
        "one_step.rs",
        "plan.rs",
        "result.rs",
        "stack.rs",
        "start.rs",
        "straight.rs",
    ]
    .map(|name| trace.join(name))
    .into_iter()
    .chain(
        std::fs::read_dir(trace.join("complete"))
            .unwrap()
            .map(|e| e.unwrap().path()),
    ) {
        let name = name.strip_prefix(&trace).unwrap().display().to_string();
        let text = code(&trace.join(&name));
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

/// The names the crate root exports: each name of its `pub use` lines (grouped or not) and
/// each public item it defines itself (its public modules are not names of the vocabulary).
fn root_names(lib: &str) -> Vec<String> {
    let text: String = lib
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let mut names = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < text.len() {
        let rest = &text[i..];
        if depth == 0 && rest.starts_with("pub use ") {
            let end = rest.find(';').expect("a `pub use` ends with `;`");
            let body = &rest[8..end];
            let list = match (body.find('{'), body.rfind('}')) {
                (Some(a), Some(b)) => &body[a + 1..b],
                _ => body.rsplit("::").next().unwrap_or(body),
            };
            names.extend(
                list.split(',')
                    .map(|n| n.split("::").last().unwrap_or("").trim().to_string())
                    .filter(|n| !n.is_empty() && n != "self"),
            );
            i += end + 1;
            continue;
        }
        if depth == 0 {
            for kind in ["fn", "struct", "enum", "const", "static", "type", "trait"] {
                if let Some(after) = rest.strip_prefix("pub ").and_then(|r| r.strip_prefix(kind))
                    && after.starts_with(' ')
                {
                    let name = after
                        .trim_start()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    names.push(name);
                }
            }
        }
        match rest.as_bytes()[0] {
            b'{' => depth += 1,
            b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        i += rest.chars().next().map_or(1, char::len_utf8);
    }
    names
}

/// The most names the crate root may export: what the README's user names.
const MAX_ROOT_NAMES: usize = 30;

#[test]
fn the_crate_root_holds_at_most_thirty_names() {
    let lib =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
    let names = root_names(&lib);
    assert!(names.contains(&"Tracer".to_string()) && names.contains(&"write".to_string()));
    assert!(
        names.len() <= MAX_ROOT_NAMES,
        "the crate root exports {} names (at most {MAX_ROOT_NAMES}): {names:?}",
        names.len()
    );
    // The counter itself: grouped and single `pub use` lines, and items defined at the root.
    let sample = "pub use a::{B, C};\npub use d::E;\npub fn f() {}\npub mod m { pub use x::Y; }";
    assert_eq!(root_names(sample), ["B", "C", "E", "f"]);
}

/// The modules `lib` declares public, each as (name, whether its body is inline `{ … }`).
fn public_modules(lib: &str) -> Vec<(String, bool)> {
    lib.lines()
        .filter_map(|l| l.trim_start().strip_prefix("pub mod "))
        .map(|rest| {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            (name, !rest.trim_end().ends_with(';'))
        })
        .collect()
}

/// Every public module is a file: `eigenray::NAME::Item` is found in `src/NAME.rs` or
/// `src/NAME/mod.rs`, never in a module written inline in `lib.rs` to relabel other modules'
/// items.
#[test]
fn every_public_module_is_a_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(root.join("lib.rs")).unwrap();
    let modules = public_modules(&lib);
    assert!(modules.iter().any(|(m, _)| m == "scene") && modules.len() >= 10);
    for (name, inline) in &modules {
        assert!(!inline, "`pub mod {name}` is written inline in lib.rs");
        assert!(
            root.join(format!("{name}.rs")).is_file() || root.join(name).join("mod.rs").is_file(),
            "`pub mod {name}` has no file"
        );
    }
    // The reader itself.
    let sample = "pub mod a;\n    pub mod b {\n    pub use x::Y;\n}\nmod c;";
    assert_eq!(
        public_modules(sample),
        [("a".to_string(), false), ("b".to_string(), true)]
    );
}

/// One path per type: no module re-exports another module's items (`pub use crate::…`); only
/// the crate root's vocabulary gives a type a second path.
#[test]
fn no_module_re_exports_another_modules_items() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut found = Vec::new();
    for path in all {
        if path == src.join("lib.rs") || path.starts_with(src.join("bin")) {
            continue;
        }
        for (i, line) in code(&path).lines().enumerate() {
            if line.trim_start().starts_with("pub use crate::") {
                found.push(format!("{}:{}", path.display(), i + 1));
            }
        }
    }
    assert!(found.is_empty(), "re-exports: {found:?}");
}

/// The longest a function in `src/` may be, from its `fn` line to its closing brace.
const MAX_FUNCTION_LINES: usize = 150;

/// Each function of `text` longer than [`MAX_FUNCTION_LINES`], as `name (lines)`: a line
/// that declares a `fn` with a body, up to the first later line that closes it at the same
/// indentation.
fn long_functions(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut long = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let Some(at) = trimmed.find("fn ") else {
            continue;
        };
        let head = &trimmed[..at];
        let is_item = head
            .split_whitespace()
            .all(|w| w.starts_with("pub") || ["const", "unsafe", "async", "extern"].contains(&w));
        if !is_item || trimmed.starts_with("//") {
            continue;
        }
        let indent = line.len() - trimmed.len();
        let close = lines[i..]
            .iter()
            .position(|l| l.trim_end().ends_with(['{', ';']))
            .map(|j| i + j);
        let Some(open) = close.filter(|&j| lines[j].trim_end().ends_with('{')) else {
            continue;
        };
        let end = lines[open + 1..].iter().position(|l| {
            let t = l.trim_start();
            l.len() - t.len() == indent && t.starts_with('}')
        });
        if let Some(end) = end {
            let n = open + 1 + end - i + 1;
            if n > MAX_FUNCTION_LINES {
                let name: String = trimmed[at + 3..]
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                long.push(format!("{name} ({n} lines)"));
            }
        }
    }
    long
}

#[test]
fn no_function_in_src_is_over_150_lines() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut long = Vec::new();
    for path in &all {
        for f in long_functions(&code(path)) {
            long.push(format!("{}: {f}", path.display()));
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines: {long:#?}"
    );
    // The scan itself finds a long function and passes a short one.
    let body = "    x += 1;\n".repeat(MAX_FUNCTION_LINES);
    let text = format!("pub(crate) fn long(x: &mut u32) {{\n{body}}}\nfn short() {{}}\n");
    assert_eq!(
        long_functions(&text),
        [format!("long ({} lines)", MAX_FUNCTION_LINES + 2)]
    );
}

/// The sibling files that the code of a file in a folder names: `super::NAME` (grouped or
/// not) and `crate::PREFIX::NAME`, `PREFIX` the folder's module path (`trace::complete`;
/// empty at a crate's root), for each `NAME` in `siblings`. Comment lines (doc links) do not
/// count.
fn sibling_uses(text: &str, prefix: &str, siblings: &[String]) -> Vec<String> {
    let code: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    let mut named = Vec::new();
    let crate_prefix = if prefix.is_empty() {
        "crate::".to_string()
    } else {
        format!("crate::{prefix}::")
    };
    for anchor in ["super::", crate_prefix.as_str()] {
        // `uses` reads the names after `crate::`: the same after the anchor, and nothing
        // after any other `crate::`.
        let shifted = code
            .replace(anchor, "\u{1}")
            .replace("crate::", "\u{2}")
            .replace('\u{1}', "crate::");
        named.extend(uses(&shifted).into_iter().filter(|n| siblings.contains(n)));
    }
    named.sort();
    named.dedup();
    named
}

/// The files of one folder (mod.rs, lib.rs and main.rs, the folder's own module, left out)
/// and the sibling each uses; a cycle among them, if any.
fn folder_cycle(folder: &Path, prefix: &str) -> Option<Vec<String>> {
    let mut names: Vec<String> = std::fs::read_dir(folder)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().to_string())
        .filter(|n| !["mod", "lib", "main"].contains(&n.as_str()))
        .collect();
    names.sort();
    let edges: Vec<Vec<usize>> = names
        .iter()
        .map(|n| {
            let text = code(&folder.join(format!("{n}.rs")));
            sibling_uses(&text, prefix, &names)
                .iter()
                .filter(|m| *m != n)
                .map(|m| names.iter().position(|x| x == m).unwrap())
                .collect()
        })
        .collect();
    // Depth first, colouring: 0 unvisited, 1 on the stack, 2 done.
    fn visit(v: usize, edges: &[Vec<usize>], colour: &mut [u8], stack: &mut Vec<usize>) -> bool {
        colour[v] = 1;
        stack.push(v);
        for &w in &edges[v] {
            if colour[w] == 1 {
                stack.push(w);
                return true;
            }
            if colour[w] == 0 && visit(w, edges, colour, stack) {
                return true;
            }
        }
        stack.pop();
        colour[v] = 2;
        false
    }
    let mut colour = vec![0u8; names.len()];
    for v in 0..names.len() {
        let mut stack = Vec::new();
        if colour[v] == 0 && visit(v, &edges, &mut colour, &mut stack) {
            let last = *stack.last().unwrap();
            let from = stack.iter().position(|&x| x == last).unwrap();
            return Some(stack[from..].iter().map(|&i| names[i].clone()).collect());
        }
    }
    None
}

/// The folders of a crate rooted at `root` (itself included), with their module paths.
fn folders(root: &Path, prefix: &str, out: &mut Vec<(std::path::PathBuf, String)>) {
    out.push((root.to_path_buf(), prefix.to_string()));
    for entry in std::fs::read_dir(root).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            let inner = if prefix.is_empty() {
                name
            } else {
                format!("{prefix}::{name}")
            };
            folders(&path, &inner, out);
        }
    }
}

/// No import circle among the files of any folder, in the library, the command-line tool and
/// the Python package: two files that use each other are one concept or share a third.
#[test]
fn no_import_circles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut all = Vec::new();
    for crate_root in ["src", "src/bin/eigenray", "python/src"] {
        let mut found = Vec::new();
        folders(&root.join(crate_root), "", &mut found);
        // The binary's folder is its own crate, not the library's `bin` module.
        if crate_root == "src" {
            found.retain(|(p, _)| !p.starts_with(root.join("src/bin")));
        }
        all.extend(found);
    }
    assert!(all.len() >= 6, "{} folders", all.len());
    for (folder, prefix) in &all {
        if let Some(cycle) = folder_cycle(folder, prefix) {
            panic!(
                "{}: an import circle: {}",
                folder.display(),
                cycle.join(" → ")
            );
        }
    }
    // The detector finds a circle where there is one.
    let dir = std::env::temp_dir().join(format!("eigenray-circle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("a.rs"), "use super::b::B;\npub struct A;\n").unwrap();
    std::fs::write(dir.join("b.rs"), "use super::{a::A, c};\npub struct B;\n").unwrap();
    std::fs::write(dir.join("c.rs"), "// super::a in a comment\n").unwrap();
    let cycle = folder_cycle(&dir, "x");
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(cycle, Some(vec!["a".into(), "b".into(), "a".into()]));
}
