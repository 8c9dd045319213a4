//! Binding resources to a pipeline by the names its shaders declare, checked against reflection.

use ash::vk;

use super::error::{BackendError, BackendResult};
use super::frame::UPLOAD_ALIGN;
use super::recorder::Recorder;
use super::reflect::ReflectedBinding;
use super::resources::{BufferId, ImageId, SamplerId, SubresourceRange};

/// A resource for one named shader binding.
#[derive(Clone, Debug)]
pub enum Bind<'a> {
    /// `sampler2D`/`sampler3D`/`samplerCube`…: read in SHADER_READ_ONLY_OPTIMAL.
    Sampled {
        image: ImageId,
        range: SubresourceRange,
        sampler: SamplerId,
    },
    /// `image2D`/`image3D`…: read or written in GENERAL.
    StorageImage {
        image: ImageId,
        range: SubresourceRange,
    },
    UniformBuffer(BufferId),
    StorageBuffer(BufferId),
    /// Bytes copied into this frame's upload buffer and bound as a uniform block.
    UniformData(&'a [u8]),
    /// Bytes copied into this frame's upload buffer and bound as a (read-only) storage block.
    StorageData(&'a [u8]),
}

impl Bind<'_> {
    fn kind(&self) -> &'static str {
        match self {
            Bind::Sampled { .. } => "a sampled image",
            Bind::StorageImage { .. } => "a storage image",
            Bind::UniformBuffer(_) | Bind::UniformData(_) => "a uniform buffer",
            Bind::StorageBuffer(_) | Bind::StorageData(_) => "a storage buffer",
        }
    }
    fn matches(&self, ty: vk::DescriptorType) -> bool {
        matches!(
            (self, ty),
            (Bind::Sampled { .. }, vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                | (Bind::StorageImage { .. }, vk::DescriptorType::STORAGE_IMAGE)
                | (Bind::UniformBuffer(_) | Bind::UniformData(_), vk::DescriptorType::UNIFORM_BUFFER)
                | (Bind::StorageBuffer(_) | Bind::StorageData(_), vk::DescriptorType::STORAGE_BUFFER)
        )
    }
}

enum Info {
    Image(vk::DescriptorImageInfo),
    Buffer(vk::DescriptorBufferInfo),
}

impl Recorder<'_> {
    /// Binds every descriptor of the bound pipeline. Each reflected binding must be given exactly
    /// once, with a resource of the declared type; names the shaders don't declare are errors too,
    /// so a renamed or retyped binding is caught at the first frame instead of reading garbage.
    pub fn bind(&mut self, resources: &[(&str, Bind<'_>)]) -> BackendResult<()> {
        let pipeline_id = self.bound_pipeline()?;
        let gpu = self.gpu;
        let p = gpu.pipeline(pipeline_id)?;
        let err = |binding: &str, message: String| BackendError::Binding { pipeline: p.name.clone(), binding: binding.into(), message };
        for (i, (name, _)) in resources.iter().enumerate() {
            if p.reflection.binding(name).is_none() {
                let declared: Vec<&str> = p.reflection.bindings.iter().map(|b| b.name.as_str()).collect();
                return Err(err(name, format!("not declared by the shaders (they declare: {})", declared.join(", "))));
            }
            if resources[..i].iter().any(|(n, _)| n == name) {
                return Err(err(name, "bound twice".into()));
            }
        }
        let mut infos: Vec<(&ReflectedBinding, Info)> = Vec::new();
        for b in &p.reflection.bindings {
            let Some((_, res)) = resources.iter().find(|(n, _)| *n == b.name) else {
                return Err(err(&b.name, format!("declared as {:?} but not bound", b.ty)));
            };
            if !res.matches(b.ty) {
                return Err(err(&b.name, format!("shader declares {:?}, given {}", b.ty, res.kind())));
            }
            if b.count != 1 {
                return Err(err(&b.name, format!("arrays of {} descriptors are not bindable yet", b.count)));
            }
            let info = match res {
                Bind::Sampled { image, range, sampler } => {
                    let img = gpu.image(*image)?;
                    if !img.desc.usage.contains(vk::ImageUsageFlags::SAMPLED) {
                        return Err(err(&b.name, format!("image `{}` was not created with SAMPLED usage", img.desc.name)));
                    }
                    let view = gpu.image_view(*image, range.base_mip, range.mip_count, range.base_layer, range.layer_count, None)?;
                    Info::Image(vk::DescriptorImageInfo { sampler: gpu.raw_sampler(*sampler)?, image_view: view, image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL })
                }
                Bind::StorageImage { image, range } => {
                    let img = gpu.image(*image)?;
                    if !img.desc.usage.contains(vk::ImageUsageFlags::STORAGE) {
                        return Err(err(&b.name, format!("image `{}` was not created with STORAGE usage", img.desc.name)));
                    }
                    let view = gpu.image_view(*image, range.base_mip, range.mip_count, range.base_layer, range.layer_count, None)?;
                    Info::Image(vk::DescriptorImageInfo { sampler: vk::Sampler::null(), image_view: view, image_layout: vk::ImageLayout::GENERAL })
                }
                Bind::UniformBuffer(id) | Bind::StorageBuffer(id) => {
                    let buf = gpu.buffer(*id)?;
                    let needed = if matches!(res, Bind::UniformBuffer(_)) { vk::BufferUsageFlags::UNIFORM_BUFFER } else { vk::BufferUsageFlags::STORAGE_BUFFER };
                    if !buf.desc.usage.contains(needed) {
                        return Err(err(&b.name, format!("buffer `{}` lacks {needed:?} usage", buf.desc.name)));
                    }
                    Info::Buffer(vk::DescriptorBufferInfo { buffer: buf.raw, offset: 0, range: vk::WHOLE_SIZE })
                }
                Bind::UniformData(bytes) | Bind::StorageData(bytes) => {
                    let (buffer, offset) = self.upload(bytes)?;
                    Info::Buffer(vk::DescriptorBufferInfo { buffer, offset, range: bytes.len().max(4) as u64 })
                }
            };
            infos.push((b, info));
        }
        let sets = if p.set_layouts.is_empty() {
            Vec::new()
        } else {
            let pool = self.frame.descriptor_pool;
            unsafe { gpu.device.allocate_descriptor_sets(&vk::DescriptorSetAllocateInfo::default().descriptor_pool(pool).set_layouts(&p.set_layouts)) }
                .map_err(|e| BackendError::Vulkan { call: "vkAllocateDescriptorSets", result: e })?
        };
        let writes: Vec<vk::WriteDescriptorSet> = infos
            .iter()
            .map(|(b, info)| {
                let w = vk::WriteDescriptorSet::default().dst_set(sets[b.set as usize]).dst_binding(b.binding).descriptor_type(gpu.driver_descriptor_type(b.ty));
                match info {
                    Info::Image(i) => w.image_info(std::slice::from_ref(i)),
                    Info::Buffer(i) => w.buffer_info(std::slice::from_ref(i)),
                }
            })
            .collect();
        unsafe {
            gpu.device.update_descriptor_sets(&writes, &[]);
            if !sets.is_empty() {
                gpu.device.cmd_bind_descriptor_sets(self.cb, p.bind_point, p.layout, 0, &sets, &[]);
            }
        }
        Ok(())
    }

    /// Copies bytes into the frame's upload buffer; returns where they landed.
    pub(crate) fn upload(&mut self, bytes: &[u8]) -> BackendResult<(vk::Buffer, u64)> {
        let offset = self.frame.upload_offset.next_multiple_of(UPLOAD_ALIGN);
        let upload = self.frame.upload;
        let capacity = self.gpu.buffer(upload)?.desc.size;
        if offset + bytes.len() as u64 > capacity {
            return Err(BackendError::Invalid(format!("per-frame upload buffer full ({capacity} bytes); upload large data once instead")));
        }
        // SAFETY-free path: the upload buffer is host-visible and this frame's previous use was
        // waited for in begin_frame, so the CPU may write it.
        let buffer = self.gpu.buffer(upload)?;
        let ptr = buffer.allocation.as_ref().and_then(|a| a.mapped_ptr()).ok_or_else(|| BackendError::Invalid("upload buffer is not mapped".into()))?;
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr(), (ptr.as_ptr() as *mut u8).add(offset as usize), bytes.len());
        }
        self.frame.upload_offset = offset + bytes.len() as u64;
        Ok((buffer.raw, offset))
    }
}
