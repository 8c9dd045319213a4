//! The tables of numbers in README.md and docs/ are generated from the data files in
//! docs/results/ by tools/results_tables.py; these tests fail when a committed table no longer
//! matches its data, and check that the tool's check notices an edited number.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn run_tool(root: &Path) -> Output {
    match Command::new("python3")
        .arg(root.join("tools/results_tables.py"))
        .arg("--check")
        .output()
    {
        Ok(out) => out,
        Err(e) => panic!(
            "cannot run python3 ({e}): the docs' tables are checked by tools/results_tables.py, \
             which needs python3 (tools/setup.sh installs it)"
        ),
    }
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let dest = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_tree(&path, &dest);
        } else {
            std::fs::copy(&path, &dest).unwrap();
        }
    }
}

#[test]
fn committed_tables_match_their_data() {
    let out = run_tool(&repo());
    assert!(
        out.status.success(),
        "a table in README.md or docs/ differs from its data; run `python3 tools/results_tables.py`:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let said = String::from_utf8_lossy(&out.stderr);
    let count: usize = said
        .split_whitespace()
        .skip_while(|w| *w != "results_tables:")
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(0);
    assert!(
        count >= 20,
        "expected the docs to hold at least 20 generated tables, the tool found {count}"
    );
}

#[test]
fn an_edited_number_fails_the_check() {
    let dir = crate::support::test_files::TestDir::new("docs-tables");
    copy_tree(&repo().join("docs"), &dir.join("docs"));
    std::fs::copy(repo().join("README.md"), dir.join("README.md")).unwrap();
    std::fs::create_dir_all(dir.join("tools")).unwrap();
    std::fs::copy(
        repo().join("tools/results_tables.py"),
        dir.join("tools/results_tables.py"),
    )
    .unwrap();
    assert!(run_tool(&dir).status.success(), "the copy should pass before the edit");

    // One cell of a data file behind a table changes; the committed table still shows the old one.
    let data = dir.join("docs/results/lavapipe/radiosity_chart_cornell.csv");
    let text = std::fs::read_to_string(&data).unwrap();
    assert!(
        text.contains(",0.0092,"),
        "the test's data row moved; pick another cell"
    );
    std::fs::write(&data, text.replacen(",0.0092,", ",0.0093,", 1)).unwrap();
    let out = run_tool(&dir);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(!out.status.success(), "--check passed with a number edited in the data");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("differs from its data"),
        "the failure should name the stale table: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every file under `dir` whose name ends in one of `exts`.
fn files_under(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files_under(&path, exts, out);
        } else if exts.iter().any(|e| path.extension().is_some_and(|x| x == *e)) {
            out.push(path);
        }
    }
}

/// The names of the functions in the Rust sources under `dir`.
fn functions_under(dir: &Path) -> Vec<String> {
    let mut files = Vec::new();
    files_under(dir, &["rs"], &mut files);
    let mut names = Vec::new();
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        for rest in text.split("fn ").skip(1) {
            names.push(rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect());
        }
    }
    names
}

/// The `cargo test` commands the docs give for their measurements run a test binary that exists
/// and name tests in it: test binaries were merged before, and the commands that made the data
/// files named binaries no longer there.
#[test]
fn the_docs_test_commands_name_binaries_and_tests_that_exist() {
    let root = repo();
    let mut files = vec![root.join("README.md"), root.join("scenes/textures/CREDITS.md")];
    files_under(&root.join("docs"), &["md", "csv"], &mut files);
    let mut checked = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (at, _) in text.match_indices("cargo test") {
            // A command ends at its closing backtick or the line's end.
            let command: &str = text[at..].split(['`', '\n']).next().unwrap();
            let words: Vec<&str> = command.split_whitespace().skip(2).collect();
            let mut binary = None;
            let mut filters = Vec::new();
            let mut i = 0;
            while i < words.len() {
                match words[i] {
                    "--test" | "--test-threads" | "--features" | "-p" => {
                        if words[i] == "--test" {
                            binary = words.get(i + 1).copied();
                        }
                        i += 1;
                    }
                    "|" | "&&" | ";" => break,
                    w if !w.starts_with('-') => filters.push(w),
                    _ => {}
                }
                i += 1;
            }
            let sources = match binary {
                Some(name) => {
                    let (file, dir) = (root.join(format!("tests/{name}.rs")), root.join("tests").join(name));
                    assert!(
                        file.exists() || dir.join("main.rs").exists(),
                        "{}: `{command}` runs test binary `{name}`, which does not exist",
                        f.display()
                    );
                    if file.exists() {
                        let mut names = functions_under(&root.join("tests/support"));
                        let text = std::fs::read_to_string(&file).unwrap();
                        for rest in text.split("fn ").skip(1) {
                            names.push(rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect());
                        }
                        names
                    } else {
                        functions_under(&dir)
                    }
                }
                None => functions_under(&root.join("src")),
            };
            for filter in filters {
                let last = filter.rsplit("::").next().unwrap();
                assert!(
                    sources.iter().any(|n| n.contains(last)),
                    "{}: `{command}` names tests matching `{filter}`, and no test function matches",
                    f.display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 15, "only {checked} test filters found in the docs");
}

/// The files git keeps (tracked, or new and not ignored), or `None` outside a git checkout.
fn kept_files(root: &Path) -> Option<Vec<String>> {
    let out = Command::new("git")
        .current_dir(root)
        .args(["ls-files", "--cached", "--others", "--exclude-standard"])
        .output()
        .ok()
        .filter(|o| o.status.success())?;
    Some(
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(str::to_owned)
            .collect(),
    )
}

/// Every relative link and image in README.md and the Markdown under docs/ and scenes/ names a
/// file the repository keeps: the method pages' figures were once written under an ignored
/// pattern, so every clone showed them broken.
#[test]
fn every_file_the_docs_link_is_in_the_repository() {
    let root = repo();
    let mut pages = vec![root.join("README.md")];
    files_under(&root.join("docs"), &["md"], &mut pages);
    files_under(&root.join("scenes"), &["md"], &mut pages);
    let kept = kept_files(&root);
    let (mut checked, mut missing) = (0, Vec::new());
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        for rest in text.split("](").skip(1) {
            let target = rest
                .split(')')
                .next()
                .unwrap_or("")
                .split('#')
                .next()
                .unwrap_or("")
                .trim();
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let mut path = page.parent().unwrap().to_path_buf();
            for part in Path::new(target).components() {
                match part {
                    std::path::Component::ParentDir => {
                        path.pop();
                    }
                    std::path::Component::Normal(p) => path.push(p),
                    _ => {}
                }
            }
            let relative = path.strip_prefix(&root).map(|p| p.to_string_lossy().into_owned());
            let found = match (&kept, &relative) {
                (Some(kept), Ok(rel)) => kept
                    .iter()
                    .any(|f| f == rel || f.starts_with(&format!("{}/", rel.trim_end_matches('/')))),
                _ => path.exists(),
            };
            checked += 1;
            if !found {
                missing.push(format!("{}: {target}", page.strip_prefix(&root).unwrap().display()));
            }
        }
    }
    println!("{checked} links checked");
    assert!(
        checked > 50,
        "only {checked} relative links found: is the parser still reading them?"
    );
    assert!(
        missing.is_empty(),
        "links to files the repository does not keep:\n{}",
        missing.join("\n")
    );
}
