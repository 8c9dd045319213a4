//! The shape of the source tree: top-level modules in layers with every dependency pointing down,
//! `unsafe` code only in the backend, and techniques named only inside the lighting layer (its
//! registry for everything above it), where they share the layer's cores but not each other.
//!
//! Its own test binary: it reads the sources and needs no device, so it builds and runs alone.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

#[path = "../src/util/test_files.rs"]
mod test_files;

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

/// The longest a function may run, in lines from `fn` to its closing brace, without a reason.
const LONG_FUNCTION_LINES: usize = 100;

/// `text` with comments, string and character literals blanked (newlines kept), so that braces
/// and the word `fn` are counted only in code.
fn blank_literals(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = b.to_vec();
    let blank = |out: &mut Vec<u8>, from: usize, to: usize| {
        for c in &mut out[from..to.min(b.len())] {
            if *c != b'\n' {
                *c = b' ';
            }
        }
    };
    let mut i = 0;
    while i < b.len() {
        let ident_before = i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_');
        let end = if b[i..].starts_with(b"//") {
            b[i..].iter().position(|&c| c == b'\n').map_or(b.len(), |n| i + n)
        } else if b[i..].starts_with(b"/*") {
            text[i + 2..].find("*/").map_or(b.len(), |n| i + 2 + n + 2)
        } else if !ident_before && (b[i..].starts_with(b"r\"") || b[i..].starts_with(b"r#")) {
            let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
            let close = format!("\"{}", "#".repeat(hashes));
            let open = i + 2 + hashes;
            text[open..].find(&close).map_or(b.len(), |n| open + n + close.len())
        } else if b[i] == b'"' {
            let mut j = i + 1;
            while j < b.len() && b[j] != b'"' {
                j += if b[j] == b'\\' { 2 } else { 1 };
            }
            j + 1
        } else if b[i] == b'\'' {
            // A character literal ('x', '\n', '\u{..}'), not a lifetime ('a).
            let rest = &b[i + 1..];
            let len = if rest.first() == Some(&b'\\') {
                rest.iter().position(|&c| c == b'\'').map_or(0, |n| n + 2)
            } else if rest.get(1) == Some(&b'\'') {
                3
            } else {
                0
            };
            i + len.max(1)
        } else {
            i + 1
        };
        if end > i + 1 || b[i] == b'"' {
            blank(&mut out, i, end);
        }
        i = end.max(i + 1);
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Every function with a body in `path`: (name, first line (1-based), length in lines).
fn functions(path: &Path) -> Vec<(String, usize, usize)> {
    let code = blank_literals(&std::fs::read_to_string(path).unwrap());
    let b = code.as_bytes();
    let line_of = |at: usize| code[..at].matches('\n').count() + 1;
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(n) = code[from..].find("fn ") {
        let at = from + n;
        from = at + 3;
        if at > 0 && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_') {
            continue;
        }
        let name: String = code[at + 3..]
            .trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue; // `fn(` types
        }
        // The body opens at the first `{` outside the signature's brackets; a `;` first means
        // a declaration without a body.
        let mut depth = 0i32;
        let mut open = None;
        for (k, &c) in b.iter().enumerate().skip(at) {
            match c {
                b'(' | b'[' | b'<' => depth += 1,
                b')' | b']' => depth -= 1,
                b'>' if b[k - 1] != b'-' && b[k - 1] != b'=' => depth -= 1,
                b';' if depth <= 0 => break,
                b'{' if depth <= 0 => {
                    open = Some(k);
                    break;
                }
                _ => {}
            }
        }
        let Some(open) = open else { continue };
        let mut braces = 0;
        let close = (open..b.len())
            .find(|&k| {
                match b[k] {
                    b'{' => braces += 1,
                    b'}' => braces -= 1,
                    _ => {}
                }
                braces == 0
            })
            .unwrap_or(b.len() - 1);
        out.push((name, line_of(at), line_of(close) - line_of(at) + 1));
    }
    out
}

/// Whether the comments and attributes right above line `line` (1-based) hold a `// long:` reason.
fn has_long_reason(lines: &[&str], line: usize) -> bool {
    lines[..line - 1]
        .iter()
        .rev()
        .map(|l| l.trim())
        .take_while(|l| l.starts_with("//") || l.starts_with("#["))
        .any(|l| {
            l.strip_prefix("// long:")
                .is_some_and(|reason| !reason.trim().is_empty())
        })
}

/// A function longer than a screen does several jobs (then it is split into functions named for
/// them) or is one linear recipe, such as a pipeline description (then a `// long: <why>` line
/// in the comments above it says so).
#[test]
fn long_functions_say_why() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    files.sort();
    let mut unexplained = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
        let text = std::fs::read_to_string(f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (name, line, len) in functions(f) {
            if len <= LONG_FUNCTION_LINES || has_long_reason(&lines, line) {
                continue;
            }
            unexplained.push(format!("{rel}:{line} fn {name}: {len} lines"));
        }
    }
    assert!(
        unexplained.is_empty(),
        "functions over {LONG_FUNCTION_LINES} lines without a `// long: <why>` comment above them; split \
         them by their jobs or say why they are one piece:\n{}",
        unexplained.join("\n")
    );
}

/// The counter itself: a known function's length, and braces in literals and comments ignored.
#[test]
fn long_function_counter_counts_code_lines() {
    let dir = test_files::TestDir::new("long-fn");
    let path = dir.join("sample.rs");
    let body: String = (0..120).map(|i| format!("    let x{i} = '{{'; // }}\n")).collect();
    let text = format!(
        "fn short<'a>(s: &'a str) -> Vec<&'a str> {{\n    vec![s, \"}}\", r#\"{{\"#]\n}}\n\n\
         // long: a test recipe.\nfn long() {{\n{body}}}\n/* fn hidden() {{ */\nfn after() {{}}\n"
    );
    std::fs::write(&path, &text).unwrap();
    let found = functions(&path);
    std::fs::remove_dir_all(&dir).unwrap();
    let names: Vec<(&str, usize, usize)> = found.iter().map(|(n, l, len)| (n.as_str(), *l, *len)).collect();
    assert_eq!(names, [("short", 1, 3), ("long", 6, 122), ("after", 129, 1)]);
    let lines: Vec<&str> = text.lines().collect();
    assert!(has_long_reason(&lines, 6));
    assert!(!has_long_reason(&lines, 1));
}
