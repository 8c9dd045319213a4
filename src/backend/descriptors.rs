//! Binding resources to a pipeline by the names its shaders declare, checked against reflection.

use ash::vk;

use super::error::{BackendError, BackendResult};
use super::frame::{MAX_UPLOAD_BYTES, POOL_SETS, POOL_SIZES, UPLOAD_ALIGN};
use super::pipeline::PipelineObject;
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
                | (
                    Bind::UniformBuffer(_) | Bind::UniformData(_),
                    vk::DescriptorType::UNIFORM_BUFFER
                )
                | (
                    Bind::StorageBuffer(_) | Bind::StorageData(_),
                    vk::DescriptorType::STORAGE_BUFFER
                )
        )
    }
}

enum Info {
    Image(vk::DescriptorImageInfo),
    Buffer(vk::DescriptorBufferInfo),
}

/// A binding error of pipeline `pipeline`, naming the binding.
fn binding_error(pipeline: &str, binding: &str, message: String) -> BackendError {
    BackendError::Binding {
        pipeline: pipeline.into(),
        binding: binding.into(),
        message,
    }
}

/// Every name in `resources` must be declared by the pipeline's shaders, and given once.
fn check_names(p: &PipelineObject, resources: &[(&str, Bind<'_>)]) -> BackendResult<()> {
    for (i, (name, _)) in resources.iter().enumerate() {
        if p.reflection.binding(name).is_none() {
            let declared: Vec<&str> = p.reflection.bindings.iter().map(|b| b.name.as_str()).collect();
            return Err(binding_error(
                &p.name,
                name,
                format!("not declared by the shaders (they declare: {})", declared.join(", ")),
            ));
        }
        if resources[..i].iter().any(|(n, _)| n == name) {
            return Err(binding_error(&p.name, name, "bound twice".into()));
        }
    }
    Ok(())
}

/// The resource given for reflected binding `b`, which must be of the declared type and count.
fn resource_for<'r, 'a>(
    p: &PipelineObject,
    b: &ReflectedBinding,
    resources: &'r [(&str, Bind<'a>)],
) -> BackendResult<&'r Bind<'a>> {
    let Some((_, res)) = resources.iter().find(|(n, _)| *n == b.name) else {
        return Err(binding_error(
            &p.name,
            &b.name,
            format!("declared as {:?} but not bound", b.ty),
        ));
    };
    if !res.matches(b.ty) {
        return Err(binding_error(
            &p.name,
            &b.name,
            format!("shader declares {:?}, given {}", b.ty, res.kind()),
        ));
    }
    if b.count != 1 {
        return Err(binding_error(
            &p.name,
            &b.name,
            format!("arrays of {} descriptors are not bindable yet", b.count),
        ));
    }
    Ok(res)
}

impl Recorder<'_> {
    /// Binds every descriptor of the bound pipeline. Each reflected binding must be given exactly
    /// once, with a resource of the declared type; names the shaders don't declare are errors too,
    /// so a renamed or retyped binding is caught at the first frame instead of reading garbage.
    pub fn bind(&mut self, resources: &[(&str, Bind<'_>)]) -> BackendResult<()> {
        let pipeline_id = self.bound_pipeline()?;
        let gpu = self.gpu;
        let p = gpu.pipeline(pipeline_id)?;
        check_names(p, resources)?;
        let mut infos: Vec<(&ReflectedBinding, Info)> = Vec::new();
        for b in &p.reflection.bindings {
            let res = resource_for(p, b, resources)?;
            infos.push((b, self.descriptor_info(&p.name, b, res)?));
        }
        let sets = self.allocate_sets(p, &infos)?;
        self.write_and_bind_sets(p, &sets, &infos);
        Ok(())
    }

    /// What binding `b` of pipeline `pipeline` points at: a view of an image, a whole buffer, or
    /// the bytes of `res` copied into this frame's upload buffer.
    fn descriptor_info(&mut self, pipeline: &str, b: &ReflectedBinding, res: &Bind<'_>) -> BackendResult<Info> {
        let gpu = self.gpu;
        Ok(match res {
            Bind::Sampled { image, range, sampler } => Info::Image(self.image_info(
                pipeline,
                b,
                (*image, range),
                ("SAMPLED", vk::ImageUsageFlags::SAMPLED),
                Some(*sampler),
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            )?),
            Bind::StorageImage { image, range } => Info::Image(self.image_info(
                pipeline,
                b,
                (*image, range),
                ("STORAGE", vk::ImageUsageFlags::STORAGE),
                None,
                vk::ImageLayout::GENERAL,
            )?),
            Bind::UniformBuffer(id) | Bind::StorageBuffer(id) => {
                let buf = gpu.buffer(*id)?;
                let needed = if matches!(res, Bind::UniformBuffer(_)) {
                    vk::BufferUsageFlags::UNIFORM_BUFFER
                } else {
                    vk::BufferUsageFlags::STORAGE_BUFFER
                };
                if !buf.desc.usage.contains(needed) {
                    return Err(binding_error(
                        pipeline,
                        &b.name,
                        format!("buffer `{}` lacks {needed:?} usage", buf.desc.name),
                    ));
                }
                Info::Buffer(vk::DescriptorBufferInfo {
                    buffer: buf.raw,
                    offset: 0,
                    range: vk::WHOLE_SIZE,
                })
            }
            Bind::UniformData(bytes) | Bind::StorageData(bytes) => {
                let (buffer, offset) = self.upload(bytes)?;
                Info::Buffer(vk::DescriptorBufferInfo {
                    buffer,
                    offset,
                    range: bytes.len().max(4) as u64,
                })
            }
        })
    }

    /// An image descriptor for binding `b`: the image must have been created with `usage` (named
    /// for the error), and is seen through a view of `range` in `layout`.
    fn image_info(
        &self,
        pipeline: &str,
        b: &ReflectedBinding,
        (image, range): (ImageId, &SubresourceRange),
        (usage_name, usage): (&str, vk::ImageUsageFlags),
        sampler: Option<SamplerId>,
        layout: vk::ImageLayout,
    ) -> BackendResult<vk::DescriptorImageInfo> {
        let gpu = self.gpu;
        let img = gpu.image(image)?;
        if !img.desc.usage.contains(usage) {
            return Err(binding_error(
                pipeline,
                &b.name,
                format!("image `{}` was not created with {usage_name} usage", img.desc.name),
            ));
        }
        let view = gpu.image_view(
            image,
            range.base_mip,
            range.mip_count,
            range.base_layer,
            range.layer_count,
            None,
        )?;
        let sampler = match sampler {
            Some(id) => gpu.raw_sampler(id)?,
            None => vk::Sampler::null(),
        };
        Ok(vk::DescriptorImageInfo {
            sampler,
            image_view: view,
            image_layout: layout,
        })
    }

    /// The descriptor sets of pipeline `p`, allocated from this frame's pools (none when the
    /// pipeline has no set layouts).
    fn allocate_sets(
        &mut self,
        p: &PipelineObject,
        infos: &[(&ReflectedBinding, Info)],
    ) -> BackendResult<Vec<vk::DescriptorSet>> {
        if p.set_layouts.is_empty() {
            return Ok(Vec::new());
        }
        let gpu = self.gpu;
        let pool = self.descriptor_pool_for(
            p.set_layouts.len() as u32,
            infos.iter().map(|(b, _)| gpu.driver_descriptor_type(b.ty)),
        )?;
        unsafe {
            gpu.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(pool)
                    .set_layouts(&p.set_layouts),
            )
        }
        .map_err(|e| BackendError::Vulkan {
            call: "vkAllocateDescriptorSets",
            result: e,
        })
    }

    /// Writes `infos` into `sets` and binds the sets for pipeline `p`'s following commands.
    fn write_and_bind_sets(&self, p: &PipelineObject, sets: &[vk::DescriptorSet], infos: &[(&ReflectedBinding, Info)]) {
        let gpu = self.gpu;
        let writes: Vec<vk::WriteDescriptorSet> = infos
            .iter()
            .map(|(b, info)| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_set(sets[b.set as usize])
                    .dst_binding(b.binding)
                    .descriptor_type(gpu.driver_descriptor_type(b.ty));
                match info {
                    Info::Image(i) => w.image_info(std::slice::from_ref(i)),
                    Info::Buffer(i) => w.buffer_info(std::slice::from_ref(i)),
                }
            })
            .collect();
        unsafe {
            gpu.device.update_descriptor_sets(&writes, &[]);
            if !sets.is_empty() {
                gpu.device
                    .cmd_bind_descriptor_sets(self.cb, p.bind_point, p.layout, 0, sets, &[]);
            }
        }
    }

    /// The pool to allocate `sets` sets holding `types` from: the one being filled if it has
    /// room for all of them, else the next (created the first time a frame needs it).
    fn descriptor_pool_for(
        &mut self,
        sets: u32,
        types: impl Iterator<Item = vk::DescriptorType>,
    ) -> BackendResult<vk::DescriptorPool> {
        let mut need = [0u32; 4];
        for ty in types {
            let i = POOL_SIZES.iter().position(|(t, _)| *t == ty).ok_or_else(|| {
                BackendError::Invalid(format!("descriptor type {ty:?} has no place in the frame's pools"))
            })?;
            need[i] += 1;
        }
        if sets > POOL_SETS || need.iter().zip(&POOL_SIZES).any(|(n, (_, cap))| n > cap) {
            return Err(BackendError::Invalid(format!(
                "one bind needs {sets} sets and {need:?} descriptors, more than a descriptor pool holds"
            )));
        }
        let f = &mut self.frame;
        let fits = f.pool_sets + sets <= POOL_SETS
            && f.pool_descriptors
                .iter()
                .zip(&need)
                .zip(&POOL_SIZES)
                .all(|((used, n), (_, cap))| used + n <= *cap);
        if !fits {
            if f.descriptor_pool_index + 1 == f.descriptor_pools.len() {
                let pool = self.gpu.create_descriptor_pool()?;
                self.frame.descriptor_pools.push(pool);
            }
            let f = &mut self.frame;
            f.descriptor_pool_index += 1;
            f.pool_sets = 0;
            f.pool_descriptors = [0; 4];
        }
        let f = &mut self.frame;
        f.pool_sets += sets;
        for (used, n) in f.pool_descriptors.iter_mut().zip(need) {
            *used += n;
        }
        Ok(f.descriptor_pools[f.descriptor_pool_index])
    }

    /// Copies bytes into the frame's upload blocks; returns where they landed. When the block
    /// being filled has no room, the next one is used, created (twice the size of the last,
    /// and at least `bytes`) the first time a frame needs it.
    pub(crate) fn upload(&mut self, bytes: &[u8]) -> BackendResult<(vk::Buffer, u64)> {
        let len = bytes.len() as u64;
        loop {
            let block = self.frame.upload_block;
            let offset = self.frame.upload_offset.next_multiple_of(UPLOAD_ALIGN);
            let capacity = self.frame.uploads[block].desc.size;
            if offset + len <= capacity {
                let buffer = &self.frame.uploads[block];
                let ptr = buffer
                    .allocation
                    .as_ref()
                    .and_then(|a| a.mapped_ptr())
                    .ok_or_else(|| BackendError::Invalid("upload buffer is not mapped".into()))?;
                // SAFETY: the block is host-visible and mapped, this frame's previous use of it
                // was waited for in begin_frame, and [offset, offset + len) lies inside it.
                unsafe {
                    std::ptr::copy_nonoverlapping(
                        bytes.as_ptr(),
                        (ptr.as_ptr() as *mut u8).add(offset as usize),
                        bytes.len(),
                    );
                }
                let raw = buffer.raw;
                self.frame.upload_offset = offset + len;
                return Ok((raw, offset));
            }
            if block + 1 == self.frame.uploads.len() {
                let held: u64 = self.frame.uploads.iter().map(|b| b.desc.size).sum();
                let size = (2 * capacity).max(len.next_multiple_of(UPLOAD_ALIGN));
                if held + size > MAX_UPLOAD_BYTES {
                    return Err(BackendError::Invalid(format!(
                        "one frame's uploads would pass {} MiB ({held} bytes held, {len} more asked for); upload large data once into a buffer of its own",
                        MAX_UPLOAD_BYTES >> 20
                    )));
                }
                let next = self.gpu.create_upload_block(block + 1, size)?;
                self.frame.uploads.push(next);
            }
            self.frame.upload_block = block + 1;
            self.frame.upload_offset = 0;
        }
    }
}
