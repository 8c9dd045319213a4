//! Compiles every shader under `glsl/` to SPIR-V (warnings are errors) and embeds them, except the
//! check kernels under `glsl/tests/`, which the tests compile when they run them.

#[path = "src/shaders/compile.rs"]
mod compile;

use std::fmt::Write as _;
use std::path::PathBuf;

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR")).join("glsl");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-changed=src/shaders/compile.rs");
    let mut table = String::from("/// Every shader under glsl/, compiled at build time: (path, SPIR-V bytes).\npub static EMBEDDED: &[(&str, &[u8])] = &[\n");
    let mut failures = Vec::new();
    for rel in compile::list_shaders(&root)
        .into_iter()
        .filter(|p| !p.starts_with(compile::TEST_KERNELS))
    {
        match compile::compile_glsl(&root, &rel) {
            Ok(words) => {
                let file = out.join(format!("{}.spv", rel.replace('/', "__")));
                let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
                std::fs::write(&file, bytes).expect("write SPIR-V into OUT_DIR");
                writeln!(
                    table,
                    "    ({rel:?}, include_bytes!({:?})),",
                    file.display().to_string()
                )
                .ok();
            }
            Err(e) => failures.push(e),
        }
    }
    if !failures.is_empty() {
        for f in &failures {
            for line in f.lines() {
                println!("cargo:warning={line}");
            }
        }
        panic!(
            "{} shader(s) failed to compile:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }
    table.push_str("];\n");
    std::fs::write(out.join("embedded_shaders.rs"), table).expect("write embedded_shaders.rs");
}
