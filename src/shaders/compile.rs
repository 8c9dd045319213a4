//! GLSL → SPIR-V with shaderc, shared by `build.rs` (embedding at build time) and the runtime
//! (hot reload from `glsl/`), so both compile with exactly the same options.
//!
//! `#include "x.glsl"` resolves against the including file's folder, then against `glsl/`
//! itself, so techniques share `common/…` headers.

use std::path::{Path, PathBuf};

/// The shader stage a file compiles as, from its extension.
pub fn shader_kind(path: &Path) -> Option<shaderc::ShaderKind> {
    Some(match path.extension()?.to_str()? {
        "vert" => shaderc::ShaderKind::Vertex,
        "frag" => shaderc::ShaderKind::Fragment,
        "geom" => shaderc::ShaderKind::Geometry,
        "comp" => shaderc::ShaderKind::Compute,
        _ => return None,
    })
}

/// Compiles `root/rel` with warnings as errors. Returns SPIR-V words, or the compiler's message.
/// The debug info embeds the source text in SPIR-V strings, and rspirv-reflect fails to decode
/// one that a multi-byte character straddles, so shader sources stay ASCII.
fn ascii_only(rel: &str, source: &str) -> Result<(), String> {
    match source.lines().enumerate().find(|(_, l)| !l.is_ascii()) {
        Some((n, _)) => Err(format!("{rel}:{}: non-ASCII character (shader sources must be ASCII: SPIR-V reflection cannot decode the embedded source otherwise)", n + 1)),
        None => Ok(()),
    }
}

pub fn compile_glsl(root: &Path, rel: &str) -> Result<Vec<u32>, String> {
    let path = root.join(rel);
    let kind = shader_kind(&path).ok_or_else(|| format!("{rel}: not a shader stage file"))?;
    let source = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    ascii_only(rel, &source)?;
    let compiler = shaderc::Compiler::new().map_err(|e| format!("shaderc: {e}"))?;
    let mut options = shaderc::CompileOptions::new().map_err(|e| format!("shaderc: {e}"))?;
    // SPIR-V 1.5 (Vulkan 1.2 environment): with 1.6, glslang declares workgroup sizes with
    // LocalSizeId, which rspirv-reflect cannot parse. Nothing penumbra uses needs 1.6.
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
    options.set_target_spirv(shaderc::SpirvVersion::V1_5);
    options.set_source_language(shaderc::SourceLanguage::GLSL);
    options.set_warnings_as_errors();
    options.set_generate_debug_info();
    let root_owned: PathBuf = root.to_path_buf();
    options.set_include_callback(move |name, _ty, from, _depth| {
        let from_dir = root_owned
            .join(from)
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default();
        for dir in [from_dir, root_owned.clone()] {
            let candidate = dir.join(name);
            if let Ok(content) = std::fs::read_to_string(&candidate) {
                ascii_only(name, &content)?;
                let resolved = candidate
                    .strip_prefix(&root_owned)
                    .map(|p| p.to_string_lossy().into_owned())
                    .unwrap_or_else(|_| candidate.to_string_lossy().into_owned());
                return Ok(shaderc::ResolvedInclude {
                    resolved_name: resolved,
                    content,
                });
            }
        }
        Err(format!("cannot find include `{name}` (from {from})"))
    });
    compiler
        .compile_into_spirv(&source, kind, rel, "main", Some(&options))
        .map(|a| a.as_binary().to_vec())
        .map_err(|e| e.to_string())
}

/// The folder under `glsl/` of the check kernels only the tests run (not embedded).
#[cfg_attr(not(test), allow(dead_code))] // the runtime only uses it in tests
pub const TEST_KERNELS: &str = "tests/";

/// Every shader stage file under `root`, as sorted paths relative to it with `/` separators.
#[cfg_attr(not(test), allow(dead_code))] // the runtime only uses it in tests
pub fn list_shaders(root: &Path) -> Vec<String> {
    fn walk(dir: &Path, root: &Path, out: &mut Vec<String>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, root, out);
            } else if shader_kind(&p).is_some() {
                if let Ok(rel) = p.strip_prefix(root) {
                    out.push(rel.to_string_lossy().replace('\\', "/"));
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(root, root, &mut out);
    out.sort();
    out
}
