//! The shape of the source tree: top-level modules in layers with every dependency pointing down,
//! `unsafe` code only in the backend, and techniques named only inside the lighting layer (its
//! registry for everything above it), where they share the layer's cores but not each other.
//!
//! Its own test binary: it reads the sources and needs no device, so it builds and runs alone.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Source without comments (doc links may name anything).
fn code(path: &Path) -> String {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Top-level module → the top-level modules its code names (`crate::x`, `use crate::{x, …}`).
fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let top = |p: &Path| {
        p.strip_prefix(&src)
            .unwrap()
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string()
    };
    let modules: BTreeSet<String> = files
        .iter()
        .map(|p| top(p))
        .filter(|m| m != "lib" && m != "main")
        .collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = modules.iter().map(|m| (m.clone(), BTreeSet::new())).collect();
    for f in &files {
        let from = top(f);
        if !modules.contains(&from) {
            continue;
        }
        let text = code(f);
        let mut names: Vec<String> = text
            .split("crate::")
            .skip(1)
            .map(|rest| rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect())
            .collect();
        for group in text.split("use crate::{").skip(1) {
            let inner = group.split('}').next().unwrap_or("");
            names.extend(
                inner
                    .split(',')
                    .map(|n| n.trim().split("::").next().unwrap_or("").to_string()),
            );
        }
        for n in names {
            if n != from && modules.contains(&n) {
                graph.get_mut(&from).unwrap().insert(n);
            }
        }
    }
    graph
}

#[test]
fn no_dependency_cycle_between_top_level_modules() {
    let graph = module_graph();
    assert!(
        graph.contains_key("lighting") && graph.contains_key("renderer"),
        "{graph:?}"
    );
    // Depth-first search for a back edge; the path names the cycle.
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(m.to_string(), 1);
        path.push(m.to_string());
        for n in &g[m] {
            match state.get(n.as_str()).copied().unwrap_or(0) {
                1 => {
                    let start = path.iter().position(|p| p == n).unwrap();
                    return Some(path[start..].iter().cloned().chain([n.clone()]).collect());
                }
                0 => {
                    if let Some(c) = visit(n, g, state, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for m in graph.keys() {
        if state.get(m.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(cycle) = visit(m, &graph, &mut state, &mut Vec::new()) {
                panic!("dependency cycle: {}", cycle.join(" -> "));
            }
        }
    }
}

/// The top-level modules, bottom up; a module may use only modules of lower layers.
const LAYERS: &[&[&str]] = &[
    &["backend", "world"],
    &["shaders", "graph", "util"],
    &["scene", "metrics"],
    &["error"],
    &["sh", "bake", "raytrace"],
    &["environment"],
    &["gpu_scene"],
    &["lighting"],
    &["renderer", "reference"],
    &["commands"],
];

/// Folders of the lighting layer that every technique may share; every other folder there is a
/// technique.
const LIGHTING_CORES: &[&str] = &["lightmap", "many_lights"];

#[test]
fn every_dependency_points_to_a_lower_layer() {
    let graph = module_graph();
    let layer = |m: &str| LAYERS.iter().position(|l| l.contains(&m));
    for (from, uses) in &graph {
        let Some(own) = layer(from) else {
            panic!("top-level module `{from}` is in no layer of LAYERS")
        };
        for to in uses {
            let theirs = layer(to).unwrap_or_else(|| panic!("top-level module `{to}` is in no layer of LAYERS"));
            assert!(
                theirs < own,
                "`{from}` (layer {own}) uses `{to}` (layer {theirs}): dependencies point down"
            );
        }
    }
    for l in LAYERS.iter().flat_map(|l| l.iter()) {
        assert!(
            graph.contains_key(*l),
            "LAYERS names `{l}`, which is not a top-level module"
        );
    }
}

#[test]
fn unsafe_code_lives_in_the_backend_only() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).unwrap();
    assert!(
        lib.contains("#![deny(unsafe_code)]"),
        "src/lib.rs must deny unsafe code"
    );
    let allowed: Vec<&str> = lib.lines().filter(|l| l.contains("allow(unsafe_code)")).collect();
    assert_eq!(allowed.len(), 1, "one allow(unsafe_code), on the backend: {allowed:?}");
    let after_allow = lib.split("#[allow(unsafe_code)]").nth(1).unwrap().trim_start();
    assert!(
        after_allow.starts_with("pub mod backend;"),
        "the allow must be on `backend`"
    );
    let main = std::fs::read_to_string(src.join("main.rs")).unwrap();
    assert!(
        main.contains("#![deny(unsafe_code)]"),
        "src/main.rs must deny unsafe code"
    );
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    for f in files.iter().filter(|f| !f.starts_with(src.join("backend"))) {
        let text = code(f);
        let words = text.split(|c: char| !(c.is_alphanumeric() || c == '_'));
        assert!(
            !words.clone().any(|w| w == "unsafe") || text.contains("deny(unsafe_code)"),
            "{} has `unsafe` outside src/backend",
            f.display()
        );
        assert!(
            !text.contains("allow(unsafe_code)") || f.ends_with("lib.rs"),
            "{} allows unsafe",
            f.display()
        );
    }
}

#[test]
fn only_the_lighting_layer_names_techniques() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let techniques: Vec<String> = std::fs::read_dir(src.join("lighting"))
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().to_string())
        .filter(|name| !LIGHTING_CORES.contains(&name.as_str()))
        .collect();
    assert!(techniques.len() >= 3, "{techniques:?}");
    for f in files.iter().filter(|f| !f.starts_with(src.join("lighting"))) {
        let text = code(f);
        for t in &techniques {
            assert!(
                !text.contains(&format!("lighting::{t}")),
                "{} names the technique `{t}`: go through lighting::registry",
                f.display()
            );
        }
    }
    // Inside the layer, techniques do not use each other: shared code lives in the layer itself
    // (its files and LIGHTING_CORES), and the shared cores use no technique.
    for f in files.iter().filter(|f| f.starts_with(src.join("lighting"))) {
        let own = f
            .strip_prefix(src.join("lighting"))
            .unwrap()
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .to_string();
        if LIGHTING_CORES.contains(&own.as_str()) {
            let text = code(f);
            for t in &techniques {
                assert!(
                    !text.contains(&format!("lighting::{t}")),
                    "{} (a shared core) uses technique `{t}`",
                    f.display()
                );
            }
            continue;
        }
        if !techniques.contains(&own) {
            continue;
        }
        let text = code(f);
        for t in techniques.iter().filter(|t| **t != own) {
            assert!(
                !text.contains(&format!("lighting::{t}")),
                "{} (technique {own}) uses technique `{t}`",
                f.display()
            );
        }
    }
}
