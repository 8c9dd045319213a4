//! Buffers, images, samplers: creation through gpu-allocator, views, upload and readback.

use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::Mutex;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme, Allocator};
use gpu_allocator::MemoryLocation;

use super::device::vulkan_calls;
use super::error::{BackendError, BackendResult, VkContext};
use super::pipeline::PipelineObject;
use super::Gpu;

/// Where a buffer lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryKind {
    /// Device-local; filled by uploads or GPU writes.
    GpuOnly,
    /// Host-visible, written by the CPU every frame (uniforms, dynamic vertex data).
    CpuToGpu,
    /// Host-visible and cached, for readback.
    GpuToCpu,
}

#[derive(Clone, Debug)]
pub struct BufferDesc {
    pub name: String,
    pub size: u64,
    pub usage: vk::BufferUsageFlags,
    pub memory: MemoryKind,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BufferId(pub(crate) u32);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ImageId(pub(crate) u32);

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerId(pub(crate) u32);

/// A mip/layer rectangle of an image. The aspect is the image's business
/// (colour, or depth+stencil together); see [`SubresourceRange::to_vk`].
///
/// `mip_count` / `layer_count` may be `vk::REMAINING_MIP_LEVELS` /
/// `vk::REMAINING_ARRAY_LAYERS`; the graph's `ImageState` resolves them, and the ranges
/// in the barriers it returns are always explicit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SubresourceRange {
    pub base_mip: u32,
    pub mip_count: u32,
    pub base_layer: u32,
    pub layer_count: u32,
}

impl SubresourceRange {
    pub const fn new(base_mip: u32, mip_count: u32, base_layer: u32, layer_count: u32) -> Self {
        Self {
            base_mip,
            mip_count,
            base_layer,
            layer_count,
        }
    }
    /// Every mip and layer of an image with `mips` mips and `layers` layers.
    pub const fn all(mips: u32, layers: u32) -> Self {
        Self::new(0, mips, 0, layers)
    }
    /// Every mip and layer, whatever the image's size.
    pub const fn full() -> Self {
        Self::new(0, vk::REMAINING_MIP_LEVELS, 0, vk::REMAINING_ARRAY_LAYERS)
    }
    /// One mip of layer 0.
    pub const fn mip(mip: u32) -> Self {
        Self::new(mip, 1, 0, 1)
    }
    /// `count` mips from `base`, layer 0.
    pub const fn mips(base: u32, count: u32) -> Self {
        Self::new(base, count, 0, 1)
    }
    /// One mip of one layer.
    pub const fn mip_layer(mip: u32, layer: u32) -> Self {
        Self::new(mip, 1, layer, 1)
    }
    /// One mip, every layer.
    pub const fn mip_all_layers(mip: u32) -> Self {
        Self::new(mip, 1, 0, vk::REMAINING_ARRAY_LAYERS)
    }
    /// Every mip of one layer (e.g. one cube face).
    pub const fn layer_all_mips(layer: u32) -> Self {
        Self::new(0, vk::REMAINING_MIP_LEVELS, layer, 1)
    }
    pub const fn contains(&self, mip: u32, layer: u32) -> bool {
        mip >= self.base_mip
            && mip - self.base_mip < self.mip_count
            && layer >= self.base_layer
            && layer - self.base_layer < self.layer_count
    }
    pub fn to_vk(&self, aspect: vk::ImageAspectFlags) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: aspect,
            base_mip_level: self.base_mip,
            level_count: self.mip_count,
            base_array_layer: self.base_layer,
            layer_count: self.layer_count,
        }
    }
}

/// An image: 2D, 3D, cube or array, with a mip chain.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageDesc {
    pub name: String,
    pub format: vk::Format,
    pub extent: vk::Extent3D,
    pub mip_levels: u32,
    /// Array layers; 6 for a cube map.
    pub layers: u32,
    pub cube: bool,
    pub usage: vk::ImageUsageFlags,
}

impl ImageDesc {
    pub fn new_2d(name: &str, format: vk::Format, width: u32, height: u32) -> Self {
        ImageDesc {
            name: name.into(),
            format,
            extent: vk::Extent3D {
                width,
                height,
                depth: 1,
            },
            mip_levels: 1,
            layers: 1,
            cube: false,
            usage: vk::ImageUsageFlags::empty(),
        }
    }
    pub fn new_3d(name: &str, format: vk::Format, w: u32, h: u32, d: u32) -> Self {
        ImageDesc {
            extent: vk::Extent3D {
                width: w,
                height: h,
                depth: d,
            },
            ..Self::new_2d(name, format, w, h)
        }
    }
    pub fn new_cube(name: &str, format: vk::Format, size: u32) -> Self {
        ImageDesc {
            layers: 6,
            cube: true,
            ..Self::new_2d(name, format, size, size)
        }
    }
    pub fn usage(mut self, usage: vk::ImageUsageFlags) -> Self {
        self.usage |= usage;
        self
    }
    pub fn layers(mut self, layers: u32) -> Self {
        self.layers = layers;
        self
    }
    /// A full mip chain down to 1×1.
    pub fn all_mips(mut self) -> Self {
        let m = self.extent.width.max(self.extent.height).max(self.extent.depth).max(1);
        self.mip_levels = 32 - m.leading_zeros();
        self
    }
    pub fn mips(mut self, n: u32) -> Self {
        self.mip_levels = n;
        self
    }
    pub fn is_3d(&self) -> bool {
        self.extent.depth > 1
    }
    pub fn aspect(&self) -> vk::ImageAspectFlags {
        format_aspect(self.format)
    }
    pub fn mip_extent(&self, mip: u32) -> vk::Extent3D {
        vk::Extent3D {
            width: (self.extent.width >> mip).max(1),
            height: (self.extent.height >> mip).max(1),
            depth: (self.extent.depth >> mip).max(1),
        }
    }
}

pub(crate) fn format_aspect(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
        vk::Format::D16_UNORM_S8_UINT | vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        vk::Format::S8_UINT => vk::ImageAspectFlags::STENCIL,
        _ => vk::ImageAspectFlags::COLOR,
    }
}

/// Bytes per texel of the formats penumbra reads back or uploads.
pub fn format_texel_size(format: vk::Format) -> Option<u64> {
    Some(match format {
        vk::Format::R8_UNORM | vk::Format::S8_UINT | vk::Format::R8_UINT => 1,
        vk::Format::R16_SFLOAT | vk::Format::R16_UNORM => 2,
        vk::Format::R8G8B8A8_UNORM
        | vk::Format::R8G8B8A8_UINT
        | vk::Format::R8G8B8A8_SRGB
        | vk::Format::B8G8R8A8_UNORM
        | vk::Format::B8G8R8A8_SRGB
        | vk::Format::R32_SFLOAT
        | vk::Format::R32_UINT
        | vk::Format::R16G16_SFLOAT
        | vk::Format::D32_SFLOAT => 4,
        vk::Format::R16G16B16A16_SFLOAT | vk::Format::R32G32_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        _ => return None,
    })
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SamplerDesc {
    pub filter: vk::Filter,
    pub mipmap: vk::SamplerMipmapMode,
    pub address: vk::SamplerAddressMode,
}

impl SamplerDesc {
    pub const LINEAR_REPEAT: SamplerDesc = SamplerDesc {
        filter: vk::Filter::LINEAR,
        mipmap: vk::SamplerMipmapMode::LINEAR,
        address: vk::SamplerAddressMode::REPEAT,
    };
    pub const LINEAR_CLAMP: SamplerDesc = SamplerDesc {
        filter: vk::Filter::LINEAR,
        mipmap: vk::SamplerMipmapMode::LINEAR,
        address: vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
    pub const NEAREST_CLAMP: SamplerDesc = SamplerDesc {
        filter: vk::Filter::NEAREST,
        mipmap: vk::SamplerMipmapMode::NEAREST,
        address: vk::SamplerAddressMode::CLAMP_TO_EDGE,
    };
}

pub(crate) struct Buffer {
    pub raw: vk::Buffer,
    pub desc: BufferDesc,
    pub allocation: Option<Allocation>,
}

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct ViewKey {
    pub base_mip: u32,
    pub mip_count: u32,
    pub base_layer: u32,
    pub layer_count: u32,
    pub view_type: vk::ImageViewType,
}

pub(crate) struct Image {
    pub raw: vk::Image,
    pub desc: ImageDesc,
    pub allocation: Option<Allocation>,
    /// Swapchain images are owned by the swapchain, not by us.
    pub owned: bool,
    pub views: RefCell<HashMap<ViewKey, vk::ImageView>>,
}

/// The buffers, images and pipelines created between [`Gpu::begin_resource_scope`] and
/// [`Gpu::end_resource_scope`]: what one owner (a lighting method) holds, freed together by
/// [`Gpu::destroy_scope`] when the owner goes (samplers are shared and cached, never scoped).
#[derive(Debug, Default)]
pub struct ResourceScope {
    pub buffers: Vec<BufferId>,
    pub images: Vec<ImageId>,
    pub pipelines: Vec<super::PipelineId>,
    pub frames: Vec<super::Frame>,
}

/// Storage for every object the Gpu hands out ids for. Slots are never reused, so a stale id
/// fails loudly instead of aliasing a newer object.
#[derive(Default)]
pub(crate) struct Arenas {
    pub buffers: Vec<Option<Buffer>>,
    pub images: Vec<Option<Image>>,
    pub samplers: Vec<Option<vk::Sampler>>,
    pub sampler_cache: HashMap<SamplerDesc, SamplerId>,
    pub pipelines: Vec<Option<PipelineObject>>,
}

impl Arenas {
    pub(crate) unsafe fn destroy_all(&mut self, device: &ash::Device, allocator: &Mutex<Allocator>) {
        for p in self.pipelines.drain(..).flatten() {
            unsafe { p.destroy(device) };
        }
        for s in self.samplers.drain(..).flatten() {
            unsafe { device.destroy_sampler(s, None) };
        }
        for b in self.buffers.drain(..).flatten() {
            unsafe { destroy_buffer(device, allocator, b) };
        }
        for i in self.images.drain(..).flatten() {
            unsafe { destroy_image(device, allocator, i) };
        }
    }
}

pub(crate) unsafe fn destroy_buffer(device: &ash::Device, allocator: &Mutex<Allocator>, mut b: Buffer) {
    unsafe { device.destroy_buffer(b.raw, None) };
    if let (Some(a), Ok(mut alloc)) = (b.allocation.take(), allocator.lock()) {
        let _ = alloc.free(a);
    }
}

unsafe fn destroy_image(device: &ash::Device, allocator: &Mutex<Allocator>, mut i: Image) {
    for (_, v) in i.views.borrow_mut().drain() {
        unsafe { device.destroy_image_view(v, None) };
    }
    if i.owned {
        unsafe { device.destroy_image(i.raw, None) };
    }
    if let (Some(a), Ok(mut alloc)) = (i.allocation.take(), allocator.lock()) {
        let _ = alloc.free(a);
    }
}

impl Gpu {
    /// Memory for a buffer (`linear`) or an optimally tiled image, from gpu-allocator.
    fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
    ) -> BackendResult<Allocation> {
        self.allocator
            .lock()
            .map_err(|_| BackendError::Invalid("allocator lock poisoned".into()))?
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| BackendError::Allocation {
                name: name.into(),
                message: e.to_string(),
            })
    }

    /// A buffer with its memory, owned by the caller rather than the arenas: for objects that
    /// belong to something else the Gpu holds (a frame's upload blocks, created while recording).
    pub(crate) fn create_raw_buffer(&self, desc: &BufferDesc) -> BackendResult<Buffer> {
        let _calls = vulkan_calls();
        if desc.size == 0 {
            return Err(BackendError::Invalid(format!("buffer `{}` has size 0", desc.name)));
        }
        let mut usage = desc.usage;
        if self.caps.uniform_blocks_as_storage && usage.contains(vk::BufferUsageFlags::UNIFORM_BUFFER) {
            // Bound as a storage buffer on this device (backend/uniform_blocks.rs).
            usage |= vk::BufferUsageFlags::STORAGE_BUFFER;
        }
        let info = vk::BufferCreateInfo::default()
            .size(desc.size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { self.device.create_buffer(&info, None) }.vk("vkCreateBuffer")?;
        let requirements = unsafe { self.device.get_buffer_memory_requirements(raw) };
        let location = match desc.memory {
            MemoryKind::GpuOnly => MemoryLocation::GpuOnly,
            MemoryKind::CpuToGpu => MemoryLocation::CpuToGpu,
            MemoryKind::GpuToCpu => MemoryLocation::GpuToCpu,
        };
        let allocation = match self.allocate(&desc.name, requirements, location, true) {
            Ok(a) => a,
            Err(e) => {
                unsafe { self.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        unsafe {
            self.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        }
        .vk("vkBindBufferMemory")?;
        self.set_name(raw, &desc.name);
        Ok(Buffer {
            raw,
            desc: desc.clone(),
            allocation: Some(allocation),
        })
    }

    pub fn create_buffer(&mut self, desc: &BufferDesc) -> BackendResult<BufferId> {
        let buffer = self.create_raw_buffer(desc)?;
        self.arenas.buffers.push(Some(buffer));
        let id = BufferId(self.arenas.buffers.len() as u32 - 1);
        if let Some(scope) = self.scopes.last_mut() {
            scope.buffers.push(id);
        }
        Ok(id)
    }

    /// A device-local buffer filled with `data` (through a staging copy, waited for).
    /// Starts recording what is created (scopes nest; the innermost records).
    pub fn begin_resource_scope(&mut self) {
        self.scopes.push(ResourceScope::default());
    }

    /// Runs `f` inside a resource scope and destroys everything it created, whether it succeeds
    /// or fails: for one-off computations (a bake's compute passes) that must not leave objects
    /// behind on any exit path. `f`'s error comes first.
    pub fn scoped<T, E: From<BackendError>>(&mut self, f: impl FnOnce(&mut Gpu) -> Result<T, E>) -> Result<T, E> {
        self.begin_resource_scope();
        let result = f(self);
        let scope = self.end_resource_scope();
        let freed = self.destroy_scope(&scope);
        let value = result?;
        freed?;
        Ok(value)
    }

    /// Ends the innermost scope and returns what it recorded.
    pub fn end_resource_scope(&mut self) -> ResourceScope {
        self.scopes.pop().unwrap_or_default()
    }

    /// Waits for the device, then destroys everything the scope recorded that still exists.
    pub fn destroy_scope(&mut self, scope: &ResourceScope) -> BackendResult<()> {
        self.wait_idle()?;
        for &f in &scope.frames {
            if self.frames.get(f.0 as usize).is_some_and(|x| x.is_some()) {
                self.destroy_frame(f)?;
            }
        }
        for &p in &scope.pipelines {
            self.destroy_pipeline(p)?;
        }
        for &i in &scope.images {
            self.destroy_image(i);
        }
        for &b in &scope.buffers {
            self.destroy_buffer(b);
        }
        Ok(())
    }

    /// Device memory held through the allocator, in bytes: what live allocations use, and the
    /// memory blocks they are carved from (the figure the driver sees).
    pub fn device_memory(&self) -> (u64, u64) {
        match self.allocator.lock() {
            Ok(a) => {
                let r = a.generate_report();
                (r.total_allocated_bytes, r.total_capacity_bytes)
            }
            Err(_) => (0, 0),
        }
    }

    /// Frames alive now (each with its command buffer, fence, pools and upload buffer).
    pub fn live_frames(&self) -> usize {
        self.frames.iter().filter(|f| f.is_some()).count()
    }

    /// Buffers, images and pipelines alive now.
    pub fn live_objects(&self) -> (usize, usize, usize) {
        let count = |n: usize, alive: &dyn Fn(usize) -> bool| (0..n).filter(|&i| alive(i)).count();
        (
            count(self.arenas.buffers.len(), &|i| self.arenas.buffers[i].is_some()),
            count(self.arenas.images.len(), &|i| self.arenas.images[i].is_some()),
            count(self.arenas.pipelines.len(), &|i| self.arenas.pipelines[i].is_some()),
        )
    }

    pub fn create_buffer_init(
        &mut self,
        name: &str,
        usage: vk::BufferUsageFlags,
        data: &[u8],
    ) -> BackendResult<BufferId> {
        let id = self.create_buffer(&BufferDesc {
            name: name.into(),
            size: data.len().max(4) as u64,
            usage: usage | vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuOnly,
        })?;
        self.upload_buffer(id, 0, data)?;
        Ok(id)
    }

    /// A storage buffer holding `data` (compute passes' inputs).
    pub fn create_storage_buffer(&mut self, name: &str, data: &[u8]) -> BackendResult<BufferId> {
        self.create_buffer_init(name, vk::BufferUsageFlags::STORAGE_BUFFER, data)
    }

    /// A storage buffer of `size` bytes (at least 4) that passes write and the host may clear or
    /// fill (`GpuToCpu` memory to read it back): compute passes' outputs.
    pub fn create_storage_output(&mut self, name: &str, size: u64, memory: MemoryKind) -> BackendResult<BufferId> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        self.create_buffer(&BufferDesc {
            name: name.into(),
            size: size.max(4),
            usage,
            memory,
        })
    }

    pub(crate) fn buffer(&self, id: BufferId) -> BackendResult<&Buffer> {
        self.arenas
            .buffers
            .get(id.0 as usize)
            .and_then(|b| b.as_ref())
            .ok_or_else(|| BackendError::Invalid(format!("buffer {id:?} was destroyed")))
    }

    pub(crate) fn image(&self, id: ImageId) -> BackendResult<&Image> {
        self.arenas
            .images
            .get(id.0 as usize)
            .and_then(|b| b.as_ref())
            .ok_or_else(|| BackendError::Invalid(format!("image {id:?} was destroyed")))
    }

    pub fn buffer_desc(&self, id: BufferId) -> BackendResult<&BufferDesc> {
        Ok(&self.buffer(id)?.desc)
    }

    pub fn image_desc(&self, id: ImageId) -> BackendResult<&ImageDesc> {
        Ok(&self.image(id)?.desc)
    }

    /// The device memory bound to a buffer (its allocation's size: the requested size rounded up
    /// to the driver's requirements).
    pub fn buffer_memory(&self, id: BufferId) -> BackendResult<u64> {
        Ok(self.buffer(id)?.allocation.as_ref().map_or(0, |a| a.size()))
    }

    /// The device memory bound to an image (0 for swapchain images).
    pub fn image_memory(&self, id: ImageId) -> BackendResult<u64> {
        Ok(self.image(id)?.allocation.as_ref().map_or(0, |a| a.size()))
    }

    /// Writes into a host-visible buffer now, or into a device-local one through a staging copy
    /// that is waited for. Not for use while a frame that reads the buffer is in flight.
    pub fn upload_buffer(&mut self, id: BufferId, offset: u64, data: &[u8]) -> BackendResult<()> {
        let _calls = vulkan_calls();
        if data.is_empty() {
            return Ok(());
        }
        let (size, memory, raw, name) = {
            let b = self.buffer(id)?;
            (b.desc.size, b.desc.memory, b.raw, b.desc.name.clone())
        };
        if offset + data.len() as u64 > size {
            return Err(BackendError::Invalid(format!(
                "upload of {} bytes at {offset} overflows buffer `{name}` of {size} bytes",
                data.len()
            )));
        }
        if memory != MemoryKind::GpuOnly {
            let b = self.arenas.buffers[id.0 as usize]
                .as_mut()
                .and_then(|b| b.allocation.as_mut());
            let slice = b
                .and_then(|a| a.mapped_slice_mut())
                .ok_or_else(|| BackendError::Invalid(format!("buffer `{name}` is not host-visible")))?;
            slice[offset as usize..offset as usize + data.len()].copy_from_slice(data);
            return Ok(());
        }
        let staging = self.create_buffer(&BufferDesc {
            name: format!("{name} staging"),
            size: data.len() as u64,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            memory: MemoryKind::CpuToGpu,
        })?;
        self.upload_buffer(staging, 0, data)?;
        let src = self.buffer(staging)?.raw;
        let len = data.len() as u64;
        let result = self.one_shot(|device, cb| unsafe {
            let region = vk::BufferCopy {
                src_offset: 0,
                dst_offset: offset,
                size: len,
            };
            device.cmd_copy_buffer(cb, src, raw, &[region]);
        });
        self.destroy_buffer(staging);
        result
    }

    /// The bytes of a host-visible buffer (call after the frame that wrote it completed).
    pub fn read_buffer(&self, id: BufferId) -> BackendResult<Vec<u8>> {
        self.read_buffer_prefix(id, self.buffer(id)?.desc.size as usize)
    }

    /// The first `len` bytes of a host-visible buffer. Where a pass fills only part of a large
    /// output buffer, this copies only that part: device memory the host reads can be uncached
    /// on a discrete GPU, and copying all of a 64 MiB buffer after every submission cost a PRT
    /// bake more than its rays did.
    pub fn read_buffer_prefix(&self, id: BufferId, len: usize) -> BackendResult<Vec<u8>> {
        let b = self.buffer(id)?;
        if len as u64 > b.desc.size {
            return Err(BackendError::Invalid(format!(
                "read of {len} bytes from buffer `{}` of {} bytes",
                b.desc.name, b.desc.size
            )));
        }
        let slice = b
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| BackendError::Invalid(format!("buffer `{}` is not host-visible", b.desc.name)))?;
        Ok(slice[..len].to_vec())
    }

    pub fn destroy_buffer(&mut self, id: BufferId) {
        let _calls = vulkan_calls();
        if let Some(slot) = self.arenas.buffers.get_mut(id.0 as usize) {
            if let Some(b) = slot.take() {
                unsafe {
                    let _ = self.device.device_wait_idle();
                    destroy_buffer(&self.device, &self.allocator, b);
                }
            }
        }
    }

    pub fn create_image(&mut self, desc: &ImageDesc) -> BackendResult<ImageId> {
        let _calls = vulkan_calls();
        let e = desc.extent;
        let max = if desc.is_3d() {
            self.caps.max_image_dimension_3d
        } else {
            self.caps.max_image_dimension_2d
        };
        if e.width == 0 || e.height == 0 || e.depth == 0 || e.width.max(e.height).max(e.depth) > max {
            return Err(BackendError::Unsupported(format!(
                "image `{}` of {}×{}×{} (device limit {max})",
                desc.name, e.width, e.height, e.depth
            )));
        }
        let fmt_props = unsafe {
            self.instance
                .get_physical_device_format_properties(self.physical, desc.format)
        };
        let needed = usage_format_features(desc.usage);
        if !fmt_props.optimal_tiling_features.contains(needed) {
            return Err(BackendError::Unsupported(format!(
                "format {:?} for {:?} (image `{}`)",
                desc.format, desc.usage, desc.name
            )));
        }
        let mut flags = vk::ImageCreateFlags::empty();
        if desc.cube {
            flags |= vk::ImageCreateFlags::CUBE_COMPATIBLE;
        }
        let info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(if desc.is_3d() {
                vk::ImageType::TYPE_3D
            } else {
                vk::ImageType::TYPE_2D
            })
            .format(desc.format)
            .extent(desc.extent)
            .mip_levels(desc.mip_levels.max(1))
            .array_layers(desc.layers.max(1))
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { self.device.create_image(&info, None) }.vk("vkCreateImage")?;
        let requirements = unsafe { self.device.get_image_memory_requirements(raw) };
        let allocation = match self.allocate(&desc.name, requirements, MemoryLocation::GpuOnly, false) {
            Ok(a) => a,
            Err(e) => {
                unsafe { self.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        unsafe {
            self.device
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        }
        .vk("vkBindImageMemory")?;
        self.set_name(raw, &desc.name);
        let mut desc = desc.clone();
        desc.mip_levels = desc.mip_levels.max(1);
        desc.layers = desc.layers.max(1);
        self.arenas.images.push(Some(Image {
            raw,
            desc,
            allocation: Some(allocation),
            owned: true,
            views: RefCell::new(HashMap::new()),
        }));
        let id = ImageId(self.arenas.images.len() as u32 - 1);
        if let Some(scope) = self.scopes.last_mut() {
            scope.images.push(id);
        }
        Ok(id)
    }

    /// Registers an image owned elsewhere (a swapchain image).
    pub(crate) fn register_external_image(&mut self, raw: vk::Image, desc: ImageDesc) -> ImageId {
        self.arenas.images.push(Some(Image {
            raw,
            desc,
            allocation: None,
            owned: false,
            views: RefCell::new(HashMap::new()),
        }));
        ImageId(self.arenas.images.len() as u32 - 1)
    }

    pub fn destroy_image(&mut self, id: ImageId) {
        let _calls = vulkan_calls();
        if let Some(slot) = self.arenas.images.get_mut(id.0 as usize) {
            if let Some(i) = slot.take() {
                unsafe {
                    let _ = self.device.device_wait_idle();
                    destroy_image(&self.device, &self.allocator, i);
                }
            }
        }
    }

    /// A view of `mip_count` mips from `base_mip` and `layer_count` layers from `base_layer`,
    /// created on first use and cached with the image.
    pub(crate) fn image_view(
        &self,
        id: ImageId,
        base_mip: u32,
        mip_count: u32,
        base_layer: u32,
        layer_count: u32,
        view_type: Option<vk::ImageViewType>,
    ) -> BackendResult<vk::ImageView> {
        let _calls = vulkan_calls();
        let img = self.image(id)?;
        let d = &img.desc;
        let mip_count = if mip_count == vk::REMAINING_MIP_LEVELS {
            d.mip_levels.saturating_sub(base_mip)
        } else {
            mip_count
        };
        let layer_count = if layer_count == vk::REMAINING_ARRAY_LAYERS {
            d.layers.saturating_sub(base_layer)
        } else {
            layer_count
        };
        if mip_count == 0
            || layer_count == 0
            || base_mip.checked_add(mip_count).is_none_or(|m| m > d.mip_levels)
            || base_layer.checked_add(layer_count).is_none_or(|l| l > d.layers)
        {
            return Err(BackendError::Invalid(format!(
                "view of mips {base_mip}+{mip_count}, layers {base_layer}+{layer_count} is outside image `{}` ({} mips, {} layers)",
                d.name, d.mip_levels, d.layers
            )));
        }
        let view_type = view_type.unwrap_or(if d.is_3d() {
            vk::ImageViewType::TYPE_3D
        } else if d.cube && layer_count == 6 {
            vk::ImageViewType::CUBE
        } else if layer_count > 1 {
            vk::ImageViewType::TYPE_2D_ARRAY
        } else {
            vk::ImageViewType::TYPE_2D
        });
        let key = ViewKey {
            base_mip,
            mip_count,
            base_layer,
            layer_count,
            view_type,
        };
        if let Some(&v) = img.views.borrow().get(&key) {
            return Ok(v);
        }
        let info = vk::ImageViewCreateInfo::default()
            .image(img.raw)
            .view_type(view_type)
            .format(d.format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: d.aspect(),
                base_mip_level: base_mip,
                level_count: mip_count,
                base_array_layer: base_layer,
                layer_count,
            });
        let view = unsafe { self.device.create_image_view(&info, None) }.vk("vkCreateImageView")?;
        img.views.borrow_mut().insert(key, view);
        Ok(view)
    }

    /// What the device supports for `format` in optimal tiling (e.g. whether it can be sampled
    /// with linear filtering: `SAMPLED_IMAGE_FILTER_LINEAR`, optional for 32-bit float formats).
    pub fn format_features(&self, format: vk::Format) -> vk::FormatFeatureFlags {
        let _calls = vulkan_calls();
        unsafe {
            self.instance
                .get_physical_device_format_properties(self.physical, format)
        }
        .optimal_tiling_features
    }

    /// A sampler, shared among everyone asking for the same description.
    pub fn sampler(&mut self, desc: SamplerDesc) -> BackendResult<SamplerId> {
        let _calls = vulkan_calls();
        if let Some(&id) = self.arenas.sampler_cache.get(&desc) {
            return Ok(id);
        }
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(desc.filter)
            .min_filter(desc.filter)
            .mipmap_mode(desc.mipmap)
            .address_mode_u(desc.address)
            .address_mode_v(desc.address)
            .address_mode_w(desc.address)
            .max_lod(vk::LOD_CLAMP_NONE);
        let s = unsafe { self.device.create_sampler(&info, None) }.vk("vkCreateSampler")?;
        self.arenas.samplers.push(Some(s));
        let id = SamplerId(self.arenas.samplers.len() as u32 - 1);
        self.arenas.sampler_cache.insert(desc, id);
        Ok(id)
    }

    pub(crate) fn raw_sampler(&self, id: SamplerId) -> BackendResult<vk::Sampler> {
        self.arenas
            .samplers
            .get(id.0 as usize)
            .copied()
            .flatten()
            .ok_or_else(|| BackendError::Invalid(format!("sampler {id:?} was destroyed")))
    }

    /// Fills mip `mip`, all layers, of an image from tightly packed texels and leaves the whole
    /// image in SHADER_READ_ONLY_OPTIMAL with the copy complete (it waits). The frame graph
    /// imports such images as "sampled, nothing pending".
    pub fn upload_image(&mut self, id: ImageId, mip: u32, data: &[u8]) -> BackendResult<()> {
        self.upload_image_padded(id, mip, data, false)
    }

    /// [`Gpu::upload_image`] of `data` and zeros after it up to the mip's size: a table whose
    /// last row is partly used goes to the staging buffer without first being copied whole into
    /// a padded one (the 2 M-triangle BVH of a PRT bake is 210 MB).
    pub fn upload_image_zero_padded(&mut self, id: ImageId, mip: u32, data: &[u8]) -> BackendResult<()> {
        self.upload_image_padded(id, mip, data, true)
    }

    fn upload_image_padded(&mut self, id: ImageId, mip: u32, data: &[u8], pad: bool) -> BackendResult<()> {
        let _calls = vulkan_calls();
        let (raw, desc) = {
            let i = self.image(id)?;
            (i.raw, i.desc.clone())
        };
        let texel = format_texel_size(desc.format)
            .ok_or_else(|| BackendError::Unsupported(format!("upload to format {:?}", desc.format)))?;
        let e = desc.mip_extent(mip);
        let expected = texel * e.width as u64 * e.height as u64 * e.depth as u64 * desc.layers as u64;
        if data.len() as u64 != expected && !(pad && (data.len() as u64) < expected) {
            return Err(BackendError::Invalid(format!(
                "upload to `{}` mip {mip}: {} bytes given, {expected} expected",
                desc.name,
                data.len()
            )));
        }
        let staging = self.create_buffer(&BufferDesc {
            name: format!("{} staging", desc.name),
            size: expected,
            usage: vk::BufferUsageFlags::TRANSFER_SRC,
            memory: MemoryKind::CpuToGpu,
        })?;
        let filled = self.upload_buffer(staging, 0, data).and_then(|()| {
            let rest = expected as usize - data.len();
            if rest == 0 {
                return Ok(());
            }
            self.upload_buffer(staging, data.len() as u64, &vec![0u8; rest])
        });
        if let Err(e) = filled {
            self.destroy_buffer(staging);
            return Err(e);
        }
        let src = self.buffer(staging)?.raw;
        let aspect = desc.aspect();
        let whole = vk::ImageSubresourceRange {
            aspect_mask: aspect,
            base_mip_level: 0,
            level_count: desc.mip_levels,
            base_array_layer: 0,
            layer_count: desc.layers,
        };
        let result = self.one_shot(|device, cb| unsafe {
            let to_dst = [vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::NONE)
                .dst_stage_mask(vk::PipelineStageFlags2::COPY)
                .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .image(raw)
                .subresource_range(whole)];
            device.cmd_pipeline_barrier2(cb, &vk::DependencyInfo::default().image_memory_barriers(&to_dst));
            let region = vk::BufferImageCopy {
                buffer_offset: 0,
                buffer_row_length: 0,
                buffer_image_height: 0,
                image_subresource: vk::ImageSubresourceLayers {
                    aspect_mask: aspect,
                    mip_level: mip,
                    base_array_layer: 0,
                    layer_count: desc.layers,
                },
                image_offset: vk::Offset3D::default(),
                image_extent: e,
            };
            device.cmd_copy_buffer_to_image(cb, src, raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &[region]);
            let to_read = [vk::ImageMemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::COPY)
                .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_access_mask(vk::AccessFlags2::SHADER_SAMPLED_READ)
                .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
                .image(raw)
                .subresource_range(whole)];
            device.cmd_pipeline_barrier2(cb, &vk::DependencyInfo::default().image_memory_barriers(&to_read));
        });
        self.destroy_buffer(staging);
        result
    }

    /// Records `f` into a fresh command buffer, submits it and waits for it.
    pub(crate) fn one_shot(&self, f: impl FnOnce(&ash::Device, vk::CommandBuffer)) -> BackendResult<()> {
        let _calls = vulkan_calls();
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cb = unsafe { self.device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        let result = (|| {
            unsafe {
                self.device
                    .begin_command_buffer(
                        cb,
                        &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .vk("vkBeginCommandBuffer")?;
            }
            f(&self.device, cb);
            unsafe {
                self.device.end_command_buffer(cb).vk("vkEndCommandBuffer")?;
                let fence = self
                    .device
                    .create_fence(&vk::FenceCreateInfo::default(), None)
                    .vk("vkCreateFence")?;
                let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(cb)];
                let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cbs)];
                let r = self
                    .device
                    .queue_submit2(self.queue, &submit, fence)
                    .vk("vkQueueSubmit2")
                    .and_then(|_| {
                        self.device
                            .wait_for_fences(&[fence], true, u64::MAX)
                            .vk("vkWaitForFences")
                    });
                self.device.destroy_fence(fence, None);
                r
            }
        })();
        unsafe { self.device.free_command_buffers(self.command_pool, &[cb]) };
        result
    }
}

fn usage_format_features(usage: vk::ImageUsageFlags) -> vk::FormatFeatureFlags {
    let mut f = vk::FormatFeatureFlags::empty();
    if usage.contains(vk::ImageUsageFlags::SAMPLED) {
        f |= vk::FormatFeatureFlags::SAMPLED_IMAGE;
    }
    if usage.contains(vk::ImageUsageFlags::STORAGE) {
        f |= vk::FormatFeatureFlags::STORAGE_IMAGE;
    }
    if usage.contains(vk::ImageUsageFlags::COLOR_ATTACHMENT) {
        f |= vk::FormatFeatureFlags::COLOR_ATTACHMENT;
    }
    if usage.contains(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT) {
        f |= vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT;
    }
    f
}
