//! Where pipelines get their SPIR-V: embedded at build time, or recompiled from `glsl/` on
//! demand (the demo's hot reload).

mod compile;

use std::path::{Path, PathBuf};

use crate::backend::ShaderSource;

include!(concat!(env!("OUT_DIR"), "/embedded_shaders.rs"));

/// A source of compiled shaders.
#[derive(Clone, Debug)]
pub enum ShaderLibrary {
    /// The SPIR-V compiled into the binary.
    Embedded,
    /// Compile from a `glsl/` folder now (used to reload edited shaders).
    Directory(PathBuf),
}

impl ShaderLibrary {
    /// The folder this crate's shaders live in, when running from a checkout.
    pub fn source_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl")
    }

    /// The check kernels under `glsl/tests/`, which only the tests run and the binary does not
    /// embed: compiled from the checkout when a pipeline asks for them.
    pub fn test_kernels() -> ShaderLibrary {
        ShaderLibrary::Directory(ShaderLibrary::source_dir())
    }

    /// Every embedded shader path, e.g. `frame/surface.vert`.
    pub fn embedded_names() -> impl Iterator<Item = &'static str> {
        EMBEDDED.iter().map(|(n, _)| *n)
    }
}

/// The embedded SPIR-V, in the order of [`ShaderLibrary::embedded_names`] (for cache keys).
pub fn embedded_bytes() -> impl Iterator<Item = &'static [u8]> {
    EMBEDDED.iter().map(|(_, b)| *b)
}

fn words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

impl ShaderSource for ShaderLibrary {
    fn spirv(&self, path: &str) -> Result<Vec<u32>, String> {
        match self {
            ShaderLibrary::Embedded => EMBEDDED
                .iter()
                .find(|(n, _)| *n == path)
                .map(|(_, b)| words(b))
                .ok_or_else(|| format!("no shader `{path}` is embedded (is it under glsl/?)")),
            ShaderLibrary::Directory(root) => compile::compile_glsl(root, path),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shader_is_embedded_and_valid_spirv() {
        let on_disk: Vec<String> = compile::list_shaders(&ShaderLibrary::source_dir())
            .into_iter()
            .filter(|p| !p.starts_with(compile::TEST_KERNELS))
            .collect();
        let embedded: Vec<&str> = ShaderLibrary::embedded_names().collect();
        assert_eq!(on_disk, embedded);
        for name in embedded {
            let w = ShaderLibrary::Embedded.spirv(name).unwrap();
            assert_eq!(w[0], 0x0723_0203, "{name}: SPIR-V magic");
        }
    }

    #[test]
    fn runtime_compile_reports_errors_with_the_file_name() {
        let dir = std::env::temp_dir().join(format!("penumbra-shader-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("bad.comp"),
            "#version 460\nlayout(local_size_x=1) in;\nvoid main() { undefined_thing = 1; }\n",
        )
        .unwrap();
        let err = ShaderLibrary::Directory(dir.clone()).spirv("bad.comp").unwrap_err();
        assert!(err.contains("bad.comp") && err.contains("undefined_thing"), "{err}");
        // Warnings are errors too.
        std::fs::write(
            dir.join("warn.comp"),
            "#version 460\nlayout(local_size_x=1) in;\nvoid main() { int x = 1.5; }\n",
        )
        .unwrap();
        assert!(ShaderLibrary::Directory(dir.clone()).spirv("warn.comp").is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
