//! A workaround for lavapipe: uniform blocks handed to the driver as read-only storage blocks.
//!
//! Lavapipe inlines the values of uniform-buffer (and push-constant) words that steer an `if` or
//! a loop into a fresh copy of the shader, and it does so again every time such a buffer is
//! bound or a push constant changes. Mesa 22.3 (Debian 12) compiles that copy each time and
//! never frees it: a method that binds a uniform block per draw or per frame (the light block of
//! `shadow_volumes`, the generator block of the height fields) leaks a compiled shader per bind,
//! about 11 MB a frame on `scenes/bsp_rooms.toml`. Newer Mesa caches the copies by value, which
//! still grows with every new value. Storage-buffer loads are never inlined, so on lavapipe the
//! backend rewrites each uniform block as a read-only storage block with the same explicit
//! layout (std140 offsets and strides are valid storage-buffer layouts), and binds the data as a
//! storage buffer. Shaders, reflection and [`super::Bind`] keep speaking of uniform buffers.

/// SPIR-V opcodes and enumerants used here.
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_TYPE_FORWARD_POINTER: u32 = 39;
const OP_VARIABLE: u32 = 59;
const DECORATION_BLOCK: u32 = 2;
const DECORATION_BUFFER_BLOCK: u32 = 3;
const DECORATION_NON_WRITABLE: u32 = 24;
const STORAGE_UNIFORM: u32 = 2;
const STORAGE_STORAGE_BUFFER: u32 = 12;

/// One instruction: its word offset and length, opcode and operands.
fn instructions(words: &[u32]) -> Result<Vec<(usize, usize, u32)>, String> {
    if words.len() < 5 || words[0] != 0x0723_0203 {
        return Err("not SPIR-V (bad magic or header)".into());
    }
    let mut out = Vec::new();
    let mut i = 5;
    while i < words.len() {
        let len = (words[i] >> 16) as usize;
        if len == 0 || i + len > words.len() {
            return Err(format!("malformed instruction at word {i}"));
        }
        out.push((i, len, words[i] & 0xffff));
        i += len;
    }
    Ok(out)
}

/// The module with every uniform block turned into a `readonly` storage block: pointers and
/// variables in the `Uniform` storage class move to `StorageBuffer`, and every member of each
/// block struct is decorated `NonWritable` (vertex stages may read storage buffers without
/// `vertexPipelineStoresAndAtomics` only then). Needs SPIR-V 1.3 or later (the `StorageBuffer`
/// class); an older module, or one without uniform blocks, comes back unchanged.
pub(crate) fn uniform_blocks_as_storage(words: &[u32]) -> Result<Vec<u32>, String> {
    let insts = instructions(words)?;
    let (major, minor) = ((words[1] >> 16) & 0xff, (words[1] >> 8) & 0xff);
    if (major, minor) < (1, 3) {
        return Ok(words.to_vec());
    }
    // Structs decorated Block (BufferBlock ones are old-style storage blocks in the Uniform
    // class; they become Block + StorageBuffer like the others).
    let mut blocks: Vec<u32> = Vec::new();
    let mut member_counts: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    let mut uniform_pointees: Vec<u32> = Vec::new();
    let mut any_uniform = false;
    for &(at, len, op) in &insts {
        let w = &words[at..at + len];
        match op {
            OP_DECORATE if len >= 3 && (w[2] == DECORATION_BLOCK || w[2] == DECORATION_BUFFER_BLOCK) => {
                blocks.push(w[1])
            }
            OP_TYPE_STRUCT if len >= 2 => {
                member_counts.insert(w[1], len - 2);
            }
            OP_TYPE_POINTER if len >= 4 && w[2] == STORAGE_UNIFORM => {
                uniform_pointees.push(w[3]);
                any_uniform = true;
            }
            OP_VARIABLE if len >= 4 && w[3] == STORAGE_UNIFORM => any_uniform = true,
            _ => {}
        }
    }
    if !any_uniform {
        return Ok(words.to_vec());
    }
    let uniform_blocks: Vec<u32> = blocks
        .iter()
        .copied()
        .filter(|b| uniform_pointees.contains(b))
        .collect();
    let mut out = Vec::with_capacity(words.len() + 8 * uniform_blocks.len());
    out.extend_from_slice(&words[..5]);
    for &(at, len, op) in &insts {
        let start = out.len();
        out.extend_from_slice(&words[at..at + len]);
        let w = &mut out[start..];
        match op {
            OP_TYPE_POINTER | OP_TYPE_FORWARD_POINTER if len >= 3 && w[2] == STORAGE_UNIFORM => {
                w[2] = STORAGE_STORAGE_BUFFER
            }
            OP_VARIABLE if len >= 4 && w[3] == STORAGE_UNIFORM => w[3] = STORAGE_STORAGE_BUFFER,
            OP_DECORATE if len >= 3 && w[2] == DECORATION_BUFFER_BLOCK && uniform_blocks.contains(&w[1]) => {
                w[2] = DECORATION_BLOCK
            }
            _ => {}
        }
        if op == OP_DECORATE
            && len >= 3
            && uniform_blocks.contains(&words[at + 1])
            && (words[at + 2] == DECORATION_BLOCK || words[at + 2] == DECORATION_BUFFER_BLOCK)
        {
            let id = words[at + 1];
            for m in 0..member_counts.get(&id).copied().unwrap_or(0) as u32 {
                out.extend_from_slice(&[(4 << 16) | OP_MEMBER_DECORATE, id, m, DECORATION_NON_WRITABLE]);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::backend::vk;
    use crate::backend::ShaderReflection;

    fn compile(src: &str, kind: shaderc::ShaderKind) -> Vec<u32> {
        let compiler = shaderc::Compiler::new().unwrap();
        let mut o = shaderc::CompileOptions::new().unwrap();
        o.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_2 as u32);
        o.set_target_spirv(shaderc::SpirvVersion::V1_5);
        compiler
            .compile_into_spirv(src, kind, "t.glsl", "main", Some(&o))
            .unwrap()
            .as_binary()
            .to_vec()
    }

    #[test]
    fn uniform_blocks_become_readonly_storage_blocks_with_the_same_bindings() {
        let src = "#version 460\n\
            layout(set = 0, binding = 0) uniform A { vec4 x; uint n; } a;\n\
            layout(set = 0, binding = 1) readonly buffer B { vec4 y[]; } b;\n\
            layout(set = 1, binding = 2) uniform sampler2D t;\n\
            layout(push_constant) uniform P { uint k; } p;\n\
            layout(location = 0) out vec4 o;\n\
            void main() { o = a.n > p.k ? a.x : b.y[p.k] + texture(t, vec2(0.5)); }\n";
        let words = compile(src, shaderc::ShaderKind::Fragment);
        let out = uniform_blocks_as_storage(&words).unwrap();
        let before = ShaderReflection::from_spirv("t", vk::ShaderStageFlags::FRAGMENT, &words).unwrap();
        let after = ShaderReflection::from_spirv("t", vk::ShaderStageFlags::FRAGMENT, &out).unwrap();
        let ty = |r: &ShaderReflection, n: &str| {
            r.bindings
                .iter()
                .find(|b| b.name == n)
                .map(|b| (b.set, b.binding, b.ty))
                .unwrap()
        };
        assert_eq!(ty(&before, "a"), (0, 0, vk::DescriptorType::UNIFORM_BUFFER));
        assert_eq!(ty(&after, "a"), (0, 0, vk::DescriptorType::STORAGE_BUFFER));
        for n in ["b", "t"] {
            assert_eq!(ty(&before, n), ty(&after, n));
        }
        assert_eq!(before.push_constant_size, after.push_constant_size);
        // No Uniform-class pointer or variable is left; both members of A are NonWritable.
        let insts = instructions(&out).unwrap();
        assert!(!insts.iter().any(
            |&(at, len, op)| (op == OP_TYPE_POINTER && out[at + 2] == STORAGE_UNIFORM)
                || (op == OP_VARIABLE && len >= 4 && out[at + 3] == STORAGE_UNIFORM)
        ));
        let non_writable = insts
            .iter()
            .filter(|&&(at, _, op)| op == OP_MEMBER_DECORATE && out[at + 3] == DECORATION_NON_WRITABLE)
            .count();
        let before_nw = instructions(&words)
            .unwrap()
            .iter()
            .filter(|&&(at, _, op)| op == OP_MEMBER_DECORATE && words[at + 3] == DECORATION_NON_WRITABLE)
            .count();
        assert_eq!(non_writable, before_nw + 2);
        // A module without uniform blocks is returned as it was.
        let plain = compile(
            "#version 460\nlayout(location = 0) out vec4 o;\nvoid main() { o = vec4(1.0); }\n",
            shaderc::ShaderKind::Fragment,
        );
        assert_eq!(uniform_blocks_as_storage(&plain).unwrap(), plain);
        assert!(uniform_blocks_as_storage(&[1, 2, 3]).is_err());
    }
}
