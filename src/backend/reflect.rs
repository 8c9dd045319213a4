//! Descriptor layouts, push-constant sizes and workgroup sizes read from SPIR-V, so that no
//! pipeline layout is written by hand and every binding can be checked by name.

use std::collections::BTreeMap;

use ash::vk;

use super::error::{BackendError, BackendResult};

/// One descriptor binding as the shader declares it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReflectedBinding {
    pub set: u32,
    pub binding: u32,
    /// The GLSL variable name (block instance name for uniform and storage blocks).
    pub name: String,
    pub ty: vk::DescriptorType,
    pub count: u32,
    pub stages: vk::ShaderStageFlags,
}

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShaderReflection {
    pub bindings: Vec<ReflectedBinding>,
    pub push_constant_size: u32,
    pub push_constant_stages: vk::ShaderStageFlags,
    /// Compute shaders: `local_size_{x,y,z}`.
    pub local_size: Option<[u32; 3]>,
}

impl ShaderReflection {
    pub fn from_spirv(name: &str, stage: vk::ShaderStageFlags, words: &[u32]) -> BackendResult<Self> {
        let err = |m: String| BackendError::Shader {
            name: name.into(),
            message: m,
        };
        let bytes: &[u8] = bytemuck::cast_slice(words);
        let r =
            rspirv_reflect::Reflection::new_from_spirv(bytes).map_err(|e| err(format!("SPIR-V reflection: {e:?}")))?;
        let sets = r
            .get_descriptor_sets()
            .map_err(|e| err(format!("descriptor reflection: {e:?}")))?;
        let mut bindings = Vec::new();
        for (set, map) in sets {
            for (binding, info) in map {
                let count = match info.binding_count {
                    rspirv_reflect::BindingCount::One => 1,
                    rspirv_reflect::BindingCount::StaticSized(n) => n as u32,
                    rspirv_reflect::BindingCount::Unbounded => {
                        return Err(err(format!(
                            "binding `{}`: unbounded arrays are not supported",
                            info.name
                        )))
                    }
                };
                if info.name.is_empty() {
                    return Err(err(format!("set {set} binding {binding} has no name: give every block an instance name, it is how resources are bound")));
                }
                bindings.push(ReflectedBinding {
                    set,
                    binding,
                    name: info.name,
                    ty: vk::DescriptorType::from_raw(info.ty.0 as i32),
                    count,
                    stages: stage,
                });
            }
        }
        let push = r
            .get_push_constant_range()
            .map_err(|e| err(format!("push constants: {e:?}")))?;
        let (push_constant_size, push_constant_stages) = match push {
            Some(p) => (p.offset + p.size, stage),
            None => (0, vk::ShaderStageFlags::empty()),
        };
        let local_size = r.get_compute_group_size().map(|(x, y, z)| [x, y, z]);
        Ok(ShaderReflection {
            bindings,
            push_constant_size,
            push_constant_stages,
            local_size,
        })
    }

    /// Combines the stages of one pipeline; a (set, binding) declared by several stages must agree
    /// in name, type and count.
    pub fn merge(pipeline: &str, stages: &[ShaderReflection]) -> BackendResult<ShaderReflection> {
        let mut by_slot: BTreeMap<(u32, u32), ReflectedBinding> = BTreeMap::new();
        let mut out = ShaderReflection::default();
        for s in stages {
            for b in &s.bindings {
                match by_slot.get_mut(&(b.set, b.binding)) {
                    Some(existing) => {
                        if existing.name != b.name || existing.ty != b.ty || existing.count != b.count {
                            return Err(BackendError::Binding {
                                pipeline: pipeline.into(),
                                binding: b.name.clone(),
                                message: format!(
                                    "set {} binding {} is `{}` {:?}×{} in one stage and `{}` {:?}×{} in another",
                                    b.set, b.binding, existing.name, existing.ty, existing.count, b.name, b.ty, b.count
                                ),
                            });
                        }
                        existing.stages |= b.stages;
                    }
                    None => {
                        by_slot.insert((b.set, b.binding), b.clone());
                    }
                }
            }
            out.push_constant_size = out.push_constant_size.max(s.push_constant_size);
            out.push_constant_stages |= s.push_constant_stages;
            if s.local_size.is_some() {
                out.local_size = s.local_size;
            }
        }
        // Names are how resources are bound, so they must be unique across sets.
        let mut seen = BTreeMap::new();
        for b in by_slot.values() {
            if let Some((s, bi)) = seen.insert(b.name.clone(), (b.set, b.binding)) {
                return Err(BackendError::Binding {
                    pipeline: pipeline.into(),
                    binding: b.name.clone(),
                    message: format!(
                        "name used at set {s} binding {bi} and set {} binding {}",
                        b.set, b.binding
                    ),
                });
            }
        }
        out.bindings = by_slot.into_values().collect();
        Ok(out)
    }

    pub fn binding(&self, name: &str) -> Option<&ReflectedBinding> {
        self.bindings.iter().find(|b| b.name == name)
    }

    pub fn set_count(&self) -> u32 {
        self.bindings.iter().map(|b| b.set + 1).max().unwrap_or(0)
    }
}
