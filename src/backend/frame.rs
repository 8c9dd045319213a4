//! Per-frame objects: a command buffer, its fence, descriptor pools reset every frame, a
//! timestamp query pool and bump-allocated upload blocks for per-frame constants.
//!
//! A frame's query results and descriptor sets are reused only after its fence has signalled,
//! so `begin_frame` waits for the frame's previous submission before touching any of them.

use std::cell::RefCell;
use std::sync::Mutex;

use ash::vk;
use gpu_allocator::vulkan::Allocator;

use super::device::vulkan_calls;
use super::error::{BackendError, BackendResult, VkContext};
use super::resources::{destroy_buffer, Buffer, BufferDesc, MemoryKind};
use super::timestamps::{elapsed_ns, PassTiming};
use super::Gpu;

/// What a frame holds between frames beyond its command buffer: its descriptor pools and
/// upload blocks, which grow to the most one frame has needed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameFootprint {
    pub descriptor_pools: usize,
    pub upload_blocks: usize,
    pub upload_bytes: u64,
}

/// Handle of a frame in flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame(pub(crate) u32);

pub(crate) const MAX_QUERIES: u32 = 4096;
/// The first upload block of every frame; later blocks double (see [`FrameData::upload_block`]).
pub(crate) const UPLOAD_BYTES: u64 = 4 << 20;
/// What one frame may upload in all: far beyond any per-frame constants, so reaching it means
/// data that should live in a buffer of its own.
pub(crate) const MAX_UPLOAD_BYTES: u64 = 1 << 30;
/// Sets one descriptor pool holds.
pub(crate) const POOL_SETS: u32 = 2048;
/// Descriptors of each type one descriptor pool holds.
pub(crate) const POOL_SIZES: [(vk::DescriptorType, u32); 4] = [
    (vk::DescriptorType::COMBINED_IMAGE_SAMPLER, 4096),
    (vk::DescriptorType::STORAGE_IMAGE, 2048),
    (vk::DescriptorType::UNIFORM_BUFFER, 2048),
    (vk::DescriptorType::STORAGE_BUFFER, 4096),
];
/// Conservative for every device (the spec allows up to 256 for minUniformBufferOffsetAlignment).
pub(crate) const UPLOAD_ALIGN: u64 = 256;

pub(crate) struct FrameData {
    pub cb: vk::CommandBuffer,
    pub fence: vk::Fence,
    pub submitted: bool,
    /// Pools the frame's descriptor sets come from, reset every frame. A frame that binds more
    /// than one pool holds (a pass per light for thousands of lights) adds pools and keeps
    /// them, as it does upload blocks.
    pub descriptor_pools: Vec<vk::DescriptorPool>,
    /// The pool being filled, with the sets and descriptors (per [`POOL_SIZES`] entry) taken
    /// from it: counted here so that no allocation ever asks a pool for more than it holds,
    /// which the spec leaves to the driver to refuse or not.
    pub descriptor_pool_index: usize,
    pub pool_sets: u32,
    pub pool_descriptors: [u32; 4],
    pub queries: Option<vk::QueryPool>,
    pub next_query: u32,
    /// (name, begin query, end query) in the order scopes were opened.
    pub scopes: Vec<(String, u32, Option<u32>)>,
    pub open_scopes: Vec<usize>,
    pub timings: Option<Vec<PassTiming>>,
    /// Host-visible blocks the frame's constants are copied into. A frame that needs more than
    /// the first block's 4 MiB (per-light constants of thousands of lights) adds blocks, each
    /// twice the last, and keeps them: a frame's high-water mark, so a method that uploads
    /// little never holds more than the first block.
    pub uploads: Vec<Buffer>,
    /// The block being filled, and the first free byte in it.
    pub upload_block: usize,
    pub upload_offset: u64,
}

impl FrameData {
    pub(crate) unsafe fn destroy(self, device: &ash::Device, allocator: &Mutex<Allocator>) {
        unsafe {
            for b in self.uploads {
                destroy_buffer(device, allocator, b);
            }
            device.destroy_fence(self.fence, None);
            for pool in self.descriptor_pools {
                device.destroy_descriptor_pool(pool, None);
            }
            if let Some(q) = self.queries {
                device.destroy_query_pool(q, None);
            }
        }
    }
}

impl Gpu {
    /// A new frame slot. Create one for headless work, two or more for frames in flight.
    pub fn create_frame(&mut self) -> BackendResult<Frame> {
        let _calls = vulkan_calls();
        let upload = self.create_upload_block(0, UPLOAD_BYTES)?;
        let cb = unsafe {
            self.device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(self.command_pool)
                    .level(vk::CommandBufferLevel::PRIMARY)
                    .command_buffer_count(1),
            )
        }
        .vk("vkAllocateCommandBuffers")?[0];
        let fence = unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        let descriptor_pool = self.create_descriptor_pool()?;
        let queries = if self.caps.timestamp_valid_bits > 0 {
            Some(
                unsafe {
                    self.device.create_query_pool(
                        &vk::QueryPoolCreateInfo::default()
                            .query_type(vk::QueryType::TIMESTAMP)
                            .query_count(MAX_QUERIES),
                        None,
                    )
                }
                .vk("vkCreateQueryPool")?,
            )
        } else {
            None
        };
        self.frames.push(Some(RefCell::new(FrameData {
            cb,
            fence,
            submitted: false,
            descriptor_pools: vec![descriptor_pool],
            descriptor_pool_index: 0,
            pool_sets: 0,
            pool_descriptors: [0; 4],
            queries,
            next_query: 0,
            scopes: Vec::new(),
            open_scopes: Vec::new(),
            timings: None,
            uploads: vec![upload],
            upload_block: 0,
            upload_offset: 0,
        })));
        let frame = Frame(self.frames.len() as u32 - 1);
        if let Some(scope) = self.scopes.last_mut() {
            scope.frames.push(frame);
        }
        Ok(frame)
    }

    /// Waits for the frame's last submission and frees it (its command buffer, fence, pools and
    /// upload buffer): for work that needs a frame only for a while, such as a bake.
    pub fn destroy_frame(&mut self, f: Frame) -> BackendResult<()> {
        let _calls = vulkan_calls();
        self.wait_frame(f)?;
        let Some(slot) = self.frames.get_mut(f.0 as usize).and_then(|x| x.take()) else {
            return Ok(());
        };
        let fd = slot.into_inner();
        unsafe {
            self.device.free_command_buffers(self.command_pool, &[fd.cb]);
            fd.destroy(&self.device, &self.allocator);
        }
        Ok(())
    }

    /// One of a frame's descriptor pools: [`POOL_SETS`] sets holding at most [`POOL_SIZES`].
    pub(crate) fn create_descriptor_pool(&self) -> BackendResult<vk::DescriptorPool> {
        let _calls = vulkan_calls();
        let sizes = POOL_SIZES.map(|(ty, n)| vk::DescriptorPoolSize {
            ty,
            descriptor_count: n,
        });
        unsafe {
            self.device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(POOL_SETS)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .vk("vkCreateDescriptorPool")
    }

    /// An upload block of `size` bytes: host-visible, bindable as any per-frame data.
    pub(crate) fn create_upload_block(&self, block: usize, size: u64) -> BackendResult<Buffer> {
        self.create_raw_buffer(&BufferDesc {
            name: format!("frame uploads {block}"),
            size,
            usage: vk::BufferUsageFlags::UNIFORM_BUFFER
                | vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::VERTEX_BUFFER
                | vk::BufferUsageFlags::INDEX_BUFFER,
            memory: MemoryKind::CpuToGpu,
        })
    }

    pub fn frame_footprint(&self, f: Frame) -> BackendResult<FrameFootprint> {
        let fd = self
            .frame_data(f)?
            .try_borrow()
            .map_err(|_| BackendError::Invalid("frame is being recorded".into()))?;
        Ok(FrameFootprint {
            descriptor_pools: fd.descriptor_pools.len(),
            upload_blocks: fd.uploads.len(),
            upload_bytes: fd.uploads.iter().map(|b| b.desc.size).sum(),
        })
    }

    pub(crate) fn frame_data(&self, f: Frame) -> BackendResult<&RefCell<FrameData>> {
        self.frames
            .get(f.0 as usize)
            .and_then(|x| x.as_ref())
            .ok_or_else(|| BackendError::Invalid(format!("frame {f:?} does not exist")))
    }

    /// Waits for the frame's last submission (if any) and collects its timestamps.
    pub fn wait_frame(&self, f: Frame) -> BackendResult<()> {
        let _calls = vulkan_calls();
        let mut fd = self
            .frame_data(f)?
            .try_borrow_mut()
            .map_err(|_| BackendError::Invalid("frame is being recorded".into()))?;
        if !fd.submitted {
            return Ok(());
        }
        unsafe { self.device.wait_for_fences(&[fd.fence], true, u64::MAX) }.vk("vkWaitForFences")?;
        unsafe { self.device.reset_fences(&[fd.fence]) }.vk("vkResetFences")?;
        fd.submitted = false;
        fd.timings = self.read_timings(&fd)?;
        Ok(())
    }

    fn read_timings(&self, fd: &FrameData) -> BackendResult<Option<Vec<PassTiming>>> {
        let _calls = vulkan_calls();
        let Some(pool) = fd.queries else { return Ok(None) };
        if fd.next_query == 0 {
            return Ok(Some(Vec::new()));
        }
        let mut raw = vec![0u64; fd.next_query as usize];
        unsafe {
            self.device.get_query_pool_results(
                pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let bits = self.caps.timestamp_valid_bits;
        let period = self.caps.timestamp_period_ns;
        Ok(Some(
            fd.scopes
                .iter()
                .filter_map(|(name, b, e)| {
                    let e = (*e)?;
                    Some(PassTiming {
                        name: name.clone(),
                        ms: elapsed_ns(raw[*b as usize], raw[e as usize], bits, period) / 1e6,
                    })
                })
                .collect(),
        ))
    }

    /// Timings of the frame's last completed submission, in scope order (`None` when the device
    /// has no timestamps on this queue).
    pub fn frame_timings(&self, f: Frame) -> BackendResult<Option<Vec<PassTiming>>> {
        Ok(self.frame_data(f)?.borrow().timings.clone())
    }

    /// Submits the frame's recorded commands. `wait`/`signal` are binary semaphores for
    /// presentation.
    pub fn submit_frame(
        &self,
        f: Frame,
        wait: Option<(vk::Semaphore, vk::PipelineStageFlags2)>,
        signal: Option<vk::Semaphore>,
    ) -> BackendResult<()> {
        let _calls = vulkan_calls();
        let mut fd = self.frame_data(f)?.borrow_mut();
        let cbs = [vk::CommandBufferSubmitInfo::default().command_buffer(fd.cb)];
        let waits: Vec<vk::SemaphoreSubmitInfo> = wait
            .iter()
            .map(|&(s, stage)| vk::SemaphoreSubmitInfo::default().semaphore(s).stage_mask(stage))
            .collect();
        let signals: Vec<vk::SemaphoreSubmitInfo> = signal
            .iter()
            .map(|&s| {
                vk::SemaphoreSubmitInfo::default()
                    .semaphore(s)
                    .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
            })
            .collect();
        let submit = [vk::SubmitInfo2::default()
            .command_buffer_infos(&cbs)
            .wait_semaphore_infos(&waits)
            .signal_semaphore_infos(&signals)];
        if let Some(fault) = super::error::injected_submit_fault() {
            return Err(BackendError::from_vk("vkQueueSubmit2", fault));
        }
        unsafe { self.device.queue_submit2(self.queue, &submit, fd.fence) }.vk("vkQueueSubmit2")?;
        fd.submitted = true;
        Ok(())
    }

    /// Submits and waits: the headless path.
    pub fn submit_and_wait(&self, f: Frame) -> BackendResult<()> {
        self.submit_frame(f, None, None)?;
        self.wait_frame(f)
    }
}
