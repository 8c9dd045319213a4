//! Safe command recording into one frame's command buffer.

use std::cell::RefMut;
use std::ffi::CString;

use ash::vk;

use super::device::{vulkan_calls, DeviceSetLock};
use super::error::{BackendError, BackendResult, VkContext};
use super::frame::{Frame, FrameData, MAX_QUERIES};
use super::pipeline::PipelineId;
use super::resources::{BufferId, ImageId, SubresourceRange};
use super::Gpu;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Clear {
    Color([f32; 4]),
    DepthStencil { depth: f32, stencil: u32 },
}

impl Clear {
    fn raw(self) -> vk::ClearValue {
        match self {
            Clear::Color(c) => vk::ClearValue {
                color: vk::ClearColorValue { float32: c },
            },
            Clear::DepthStencil { depth, stencil } => vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth, stencil },
            },
        }
    }
}

/// One colour or depth/stencil attachment of a rendering scope.
#[derive(Clone, Copy, Debug)]
pub struct RenderTarget {
    pub image: ImageId,
    pub mip: u32,
    pub layer: u32,
    /// `Some` clears to this value; `None` loads the previous contents.
    pub clear: Option<Clear>,
    pub store: bool,
    /// Depth/stencil only: the attachment is tested but not written.
    pub read_only: bool,
}

impl RenderTarget {
    pub fn clear_color(image: ImageId, rgba: [f32; 4]) -> Self {
        RenderTarget {
            image,
            mip: 0,
            layer: 0,
            clear: Some(Clear::Color(rgba)),
            store: true,
            read_only: false,
        }
    }
    pub fn clear_depth(image: ImageId, depth: f32, stencil: u32) -> Self {
        RenderTarget {
            image,
            mip: 0,
            layer: 0,
            clear: Some(Clear::DepthStencil { depth, stencil }),
            store: true,
            read_only: false,
        }
    }
    pub fn load(image: ImageId) -> Self {
        RenderTarget {
            image,
            mip: 0,
            layer: 0,
            clear: None,
            store: true,
            read_only: false,
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct RenderingDesc {
    pub colors: Vec<RenderTarget>,
    pub depth_stencil: Option<RenderTarget>,
}

/// A barrier in backend terms; the frame graph derives these.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageTransition {
    pub image: ImageId,
    pub range: SubresourceRange,
    pub src_stages: vk::PipelineStageFlags2,
    pub src_access: vk::AccessFlags2,
    pub dst_stages: vk::PipelineStageFlags2,
    pub dst_access: vk::AccessFlags2,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BufferTransition {
    pub buffer: BufferId,
    pub src_stages: vk::PipelineStageFlags2,
    pub src_access: vk::AccessFlags2,
    pub dst_stages: vk::PipelineStageFlags2,
    pub dst_access: vk::AccessFlags2,
}

/// Records one frame. Borrowing the [`Gpu`] for its whole life is what keeps every resource it
/// refers to alive until the recording is submitted.
pub struct Recorder<'g> {
    pub(crate) gpu: &'g Gpu,
    pub(crate) frame: RefMut<'g, FrameData>,
    pub(crate) cb: vk::CommandBuffer,
    pipeline: Option<PipelineId>,
    rendering: bool,
    /// Recording calls Vulkan throughout; the hold orders it against devices made or dropped on
    /// other threads (see `vulkan_calls`).
    _calls: DeviceSetLock,
}

impl Gpu {
    /// Waits for the frame's previous submission, resets its pools and begins recording.
    pub fn begin_frame(&self, f: Frame) -> BackendResult<Recorder<'_>> {
        let calls = vulkan_calls();
        self.wait_frame(f)?;
        let mut frame = self
            .frame_data(f)?
            .try_borrow_mut()
            .map_err(|_| BackendError::Invalid("frame is already being recorded".into()))?;
        let cb = frame.cb;
        unsafe {
            for &pool in &frame.descriptor_pools {
                self.device
                    .reset_descriptor_pool(pool, vk::DescriptorPoolResetFlags::empty())
                    .vk("vkResetDescriptorPool")?;
            }
            self.device
                .reset_command_buffer(cb, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            self.device
                .begin_command_buffer(
                    cb,
                    &vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                )
                .vk("vkBeginCommandBuffer")?;
            if let Some(q) = frame.queries {
                self.device.cmd_reset_query_pool(cb, q, 0, MAX_QUERIES);
            }
        }
        frame.next_query = 0;
        frame.scopes.clear();
        frame.open_scopes.clear();
        frame.descriptor_pool_index = 0;
        frame.pool_sets = 0;
        frame.pool_descriptors = [0; 4];
        frame.upload_block = 0;
        frame.upload_offset = 0;
        Ok(Recorder {
            gpu: self,
            frame,
            cb,
            pipeline: None,
            rendering: false,
            _calls: calls,
        })
    }
}

impl<'g> Recorder<'g> {
    pub fn gpu(&self) -> &'g Gpu {
        self.gpu
    }

    /// Ends recording; submit with [`Gpu::submit_frame`] or [`Gpu::submit_and_wait`].
    pub fn finish(mut self) -> BackendResult<()> {
        if self.rendering {
            return Err(BackendError::Invalid("finish() inside a rendering scope".into()));
        }
        while !self.frame.open_scopes.is_empty() {
            self.end_scope();
        }
        unsafe { self.gpu.device.end_command_buffer(self.cb) }.vk("vkEndCommandBuffer")
    }

    /// Opens a debug label and a timestamp scope. Scopes nest; each is closed by [`Self::end_scope`].
    pub fn begin_scope(&mut self, name: &str) {
        if let Some(dd) = &self.gpu.debug_device {
            if let Ok(c) = CString::new(name) {
                let label = vk::DebugUtilsLabelEXT::default().label_name(&c);
                unsafe { dd.cmd_begin_debug_utils_label(self.cb, &label) };
            }
        }
        // Room for this scope's start and end and for the end of every timed scope still open:
        // when a frame has more passes than queries (a stencil volume per light of thousands),
        // the inner scopes go untimed and the outer ones (the whole frame) keep their time.
        let timed_open = self.frame.open_scopes.iter().filter(|&&i| i != usize::MAX).count() as u32;
        let query = if self.frame.next_query + 2 + timed_open <= MAX_QUERIES {
            self.write_timestamp()
        } else {
            None
        };
        let idx = self.frame.scopes.len();
        self.frame.scopes.push((name.to_string(), query.unwrap_or(0), None));
        if query.is_none() {
            // Out of queries or no timestamp support: the scope is labelled but not timed.
            self.frame.scopes.pop();
            self.frame.open_scopes.push(usize::MAX);
        } else {
            self.frame.open_scopes.push(idx);
        }
    }

    pub fn end_scope(&mut self) {
        let Some(idx) = self.frame.open_scopes.pop() else {
            return;
        };
        if idx != usize::MAX {
            let q = self.write_timestamp();
            if let Some(s) = self.frame.scopes.get_mut(idx) {
                s.2 = q;
            }
        }
        if let Some(dd) = &self.gpu.debug_device {
            unsafe { dd.cmd_end_debug_utils_label(self.cb) };
        }
    }

    fn write_timestamp(&mut self) -> Option<u32> {
        let pool = self.frame.queries?;
        if self.frame.next_query >= MAX_QUERIES {
            return None;
        }
        let q = self.frame.next_query;
        self.frame.next_query += 1;
        // ALL_COMMANDS: the timestamp is taken once every earlier command has finished, so a
        // scope measures its own commands (and the barriers recorded inside it).
        unsafe {
            self.gpu
                .device
                .cmd_write_timestamp2(self.cb, vk::PipelineStageFlags2::ALL_COMMANDS, pool, q)
        };
        Some(q)
    }

    pub fn barriers(&mut self, images: &[ImageTransition], buffers: &[BufferTransition]) -> BackendResult<()> {
        if images.is_empty() && buffers.is_empty() {
            return Ok(());
        }
        let mut ib = Vec::with_capacity(images.len());
        for t in images {
            let img = self.gpu.image(t.image)?;
            ib.push(
                vk::ImageMemoryBarrier2::default()
                    .src_stage_mask(t.src_stages)
                    .src_access_mask(t.src_access)
                    .dst_stage_mask(t.dst_stages)
                    .dst_access_mask(t.dst_access)
                    .old_layout(t.old_layout)
                    .new_layout(t.new_layout)
                    .image(img.raw)
                    .subresource_range(vk::ImageSubresourceRange {
                        aspect_mask: img.desc.aspect(),
                        base_mip_level: t.range.base_mip,
                        level_count: t.range.mip_count,
                        base_array_layer: t.range.base_layer,
                        layer_count: t.range.layer_count,
                    }),
            );
        }
        let mut bb = Vec::with_capacity(buffers.len());
        for t in buffers {
            let buf = self.gpu.buffer(t.buffer)?;
            // A uniform block read is a storage read where the driver sees storage blocks.
            let mut dst_access = t.dst_access;
            if self.gpu.caps.uniform_blocks_as_storage && dst_access.contains(vk::AccessFlags2::UNIFORM_READ) {
                dst_access |= vk::AccessFlags2::SHADER_STORAGE_READ;
            }
            bb.push(
                vk::BufferMemoryBarrier2::default()
                    .src_stage_mask(t.src_stages)
                    .src_access_mask(t.src_access)
                    .dst_stage_mask(t.dst_stages)
                    .dst_access_mask(dst_access)
                    .buffer(buf.raw)
                    .offset(0)
                    .size(vk::WHOLE_SIZE),
            );
        }
        let dep = vk::DependencyInfo::default()
            .image_memory_barriers(&ib)
            .buffer_memory_barriers(&bb);
        unsafe { self.gpu.device.cmd_pipeline_barrier2(self.cb, &dep) };
        Ok(())
    }

    /// Begins dynamic rendering over the attachments and sets a full-size viewport and scissor.
    pub fn begin_rendering(&mut self, desc: &RenderingDesc) -> BackendResult<vk::Extent2D> {
        if self.rendering {
            return Err(BackendError::Invalid("nested begin_rendering".into()));
        }
        let first = desc
            .colors
            .first()
            .or(desc.depth_stencil.as_ref())
            .ok_or_else(|| BackendError::Invalid("rendering without attachments".into()))?;
        let e = self.gpu.image(first.image)?.desc.mip_extent(first.mip);
        let extent = vk::Extent2D {
            width: e.width,
            height: e.height,
        };
        let attach =
            |t: &RenderTarget, layout: vk::ImageLayout| -> BackendResult<vk::RenderingAttachmentInfo<'static>> {
                let view = self
                    .gpu
                    .image_view(t.image, t.mip, 1, t.layer, 1, Some(vk::ImageViewType::TYPE_2D))?;
                let mut a = vk::RenderingAttachmentInfo::default()
                    .image_view(view)
                    .image_layout(layout)
                    .load_op(if t.clear.is_some() {
                        vk::AttachmentLoadOp::CLEAR
                    } else {
                        vk::AttachmentLoadOp::LOAD
                    })
                    .store_op(if t.store {
                        vk::AttachmentStoreOp::STORE
                    } else {
                        vk::AttachmentStoreOp::DONT_CARE
                    });
                if let Some(c) = t.clear {
                    a = a.clear_value(c.raw());
                }
                Ok(a)
            };
        let colors = desc
            .colors
            .iter()
            .map(|t| attach(t, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL))
            .collect::<BackendResult<Vec<_>>>()?;
        let mut info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            })
            .layer_count(1)
            .color_attachments(&colors);
        let ds;
        if let Some(t) = &desc.depth_stencil {
            let layout = if t.read_only {
                vk::ImageLayout::DEPTH_STENCIL_READ_ONLY_OPTIMAL
            } else {
                vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
            };
            ds = attach(t, layout)?;
            let aspect = self.gpu.image(t.image)?.desc.aspect();
            if aspect.contains(vk::ImageAspectFlags::DEPTH) {
                info = info.depth_attachment(&ds);
            }
            if aspect.contains(vk::ImageAspectFlags::STENCIL) {
                info = info.stencil_attachment(&ds);
            }
        }
        unsafe {
            self.gpu.device.cmd_begin_rendering(self.cb, &info);
            self.gpu.device.cmd_set_viewport(
                self.cb,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: extent.width as f32,
                    height: extent.height as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            self.gpu.device.cmd_set_scissor(
                self.cb,
                0,
                &[vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent,
                }],
            );
        }
        self.rendering = true;
        Ok(extent)
    }

    /// Clears the stencil aspect of the bound depth/stencil attachment to `value` over `extent`
    /// (what [`Recorder::begin_rendering`] returned), keeping depth: one light's shadow-volume
    /// counts start from zero without touching the depth the ambient pass wrote.
    pub fn clear_stencil(&mut self, extent: vk::Extent2D, value: u32) -> BackendResult<()> {
        if !self.rendering {
            return Err(BackendError::Invalid("clear_stencil outside a rendering scope".into()));
        }
        let attachment = vk::ClearAttachment {
            aspect_mask: vk::ImageAspectFlags::STENCIL,
            color_attachment: 0,
            clear_value: vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: value,
                },
            },
        };
        let rect = vk::ClearRect {
            rect: vk::Rect2D {
                offset: vk::Offset2D::default(),
                extent,
            },
            base_array_layer: 0,
            layer_count: 1,
        };
        unsafe { self.gpu.device.cmd_clear_attachments(self.cb, &[attachment], &[rect]) };
        Ok(())
    }

    /// Commands recorded around the recorder (the overlay's renderer) bound a pipeline of their
    /// own: the next `bind_pipeline` must bind again.
    pub(crate) fn forget_pipeline(&mut self) {
        self.pipeline = None;
    }

    pub fn end_rendering(&mut self) {
        if self.rendering {
            unsafe { self.gpu.device.cmd_end_rendering(self.cb) };
            self.rendering = false;
        }
    }

    pub fn bind_pipeline(&mut self, id: PipelineId) -> BackendResult<()> {
        let p = self.gpu.pipeline(id)?;
        let graphics = p.bind_point == vk::PipelineBindPoint::GRAPHICS;
        if graphics != self.rendering {
            return Err(BackendError::Invalid(format!(
                "pipeline `{}`: {} pipelines bind {} a rendering scope",
                p.name,
                if graphics { "graphics" } else { "compute" },
                if graphics { "inside" } else { "outside" }
            )));
        }
        unsafe { self.gpu.device.cmd_bind_pipeline(self.cb, p.bind_point, p.raw) };
        self.pipeline = Some(id);
        Ok(())
    }

    pub(crate) fn bound_pipeline(&self) -> BackendResult<PipelineId> {
        self.pipeline
            .ok_or_else(|| BackendError::Invalid("no pipeline bound".into()))
    }

    /// Push constants for the bound pipeline; the size must equal the reflected block's size.
    pub fn push_constants(&mut self, bytes: &[u8]) -> BackendResult<()> {
        let p = self.gpu.pipeline(self.bound_pipeline()?)?;
        let size = p.reflection.push_constant_size as usize;
        if bytes.len() != size {
            return Err(BackendError::Binding {
                pipeline: p.name.clone(),
                binding: "push constants".into(),
                message: format!("{} bytes given, the shaders declare {size}", bytes.len()),
            });
        }
        unsafe {
            self.gpu
                .device
                .cmd_push_constants(self.cb, p.layout, p.reflection.push_constant_stages, 0, bytes)
        };
        Ok(())
    }

    pub fn bind_vertex_buffers(&mut self, buffers: &[(BufferId, u64)]) -> BackendResult<()> {
        let raws = buffers
            .iter()
            .map(|(b, _)| self.gpu.buffer(*b).map(|b| b.raw))
            .collect::<BackendResult<Vec<_>>>()?;
        let offsets: Vec<u64> = buffers.iter().map(|(_, o)| *o).collect();
        unsafe { self.gpu.device.cmd_bind_vertex_buffers(self.cb, 0, &raws, &offsets) };
        Ok(())
    }

    pub fn bind_index_buffer(&mut self, buffer: BufferId, offset: u64) -> BackendResult<()> {
        let raw = self.gpu.buffer(buffer)?.raw;
        unsafe {
            self.gpu
                .device
                .cmd_bind_index_buffer(self.cb, raw, offset, vk::IndexType::UINT32)
        };
        Ok(())
    }

    pub fn draw(&mut self, vertices: u32, instances: u32) -> BackendResult<()> {
        self.bound_pipeline()?;
        unsafe { self.gpu.device.cmd_draw(self.cb, vertices, instances, 0, 0) };
        Ok(())
    }

    /// Non-indexed draw starting at vertex `first`.
    pub fn draw_from(&mut self, vertices: u32, first: u32) -> BackendResult<()> {
        self.bound_pipeline()?;
        unsafe { self.gpu.device.cmd_draw(self.cb, vertices, 1, first, 0) };
        Ok(())
    }

    /// Non-indexed instanced draw: `instances` instances from `first_instance` (which
    /// `gl_InstanceIndex` includes), each of `vertices` vertices from `first_vertex`.
    pub fn draw_instanced(
        &mut self,
        vertices: u32,
        first_vertex: u32,
        instances: u32,
        first_instance: u32,
    ) -> BackendResult<()> {
        self.bound_pipeline()?;
        unsafe {
            self.gpu
                .device
                .cmd_draw(self.cb, vertices, instances, first_vertex, first_instance)
        };
        Ok(())
    }

    /// One non-indexed draw whose `VkDrawIndirectCommand` an earlier pass wrote into `buffer` at
    /// `offset` (the buffer needs INDIRECT_BUFFER usage).
    pub fn draw_indirect(&mut self, buffer: BufferId, offset: u64) -> BackendResult<()> {
        self.bound_pipeline()?;
        let raw = self.gpu.buffer(buffer)?.raw;
        unsafe {
            self.gpu.device.cmd_draw_indirect(
                self.cb,
                raw,
                offset,
                1,
                std::mem::size_of::<vk::DrawIndirectCommand>() as u32,
            )
        };
        Ok(())
    }

    /// One indexed draw (the bound index buffer) whose `VkDrawIndexedIndirectCommand` an earlier
    /// pass wrote into `buffer` at `offset` (the buffer needs INDIRECT_BUFFER usage).
    pub fn draw_indexed_indirect(&mut self, buffer: BufferId, offset: u64) -> BackendResult<()> {
        self.bound_pipeline()?;
        let raw = self.gpu.buffer(buffer)?.raw;
        unsafe {
            self.gpu.device.cmd_draw_indexed_indirect(
                self.cb,
                raw,
                offset,
                1,
                std::mem::size_of::<vk::DrawIndexedIndirectCommand>() as u32,
            )
        };
        Ok(())
    }

    pub fn draw_indexed(&mut self, indices: u32, first_index: u32, vertex_offset: i32) -> BackendResult<()> {
        self.bound_pipeline()?;
        unsafe {
            self.gpu
                .device
                .cmd_draw_indexed(self.cb, indices, 1, first_index, vertex_offset, 0)
        };
        Ok(())
    }

    /// Dispatches enough workgroups to cover `threads` invocations in each dimension (the
    /// workgroup size comes from the shader's reflected `local_size`).
    pub fn dispatch(&mut self, threads: [u32; 3]) -> BackendResult<()> {
        let p = self.gpu.pipeline(self.bound_pipeline()?)?;
        let ls = p
            .reflection
            .local_size
            .ok_or_else(|| BackendError::Invalid(format!("pipeline `{}` is not a compute pipeline", p.name)))?;
        let groups = [0, 1, 2].map(|i| threads[i].div_ceil(ls[i].max(1)));
        unsafe { self.gpu.device.cmd_dispatch(self.cb, groups[0], groups[1], groups[2]) };
        Ok(())
    }

    /// Copies one mip/layer of an image (in TRANSFER_SRC_OPTIMAL) into a buffer, tightly packed.
    pub fn copy_image_to_buffer(
        &mut self,
        image: ImageId,
        mip: u32,
        layer: u32,
        buffer: BufferId,
    ) -> BackendResult<()> {
        self.copy_image_to_buffer_at(image, mip, layer, buffer, 0)
    }

    /// [`copy_image_to_buffer`](Self::copy_image_to_buffer) from byte `offset` of the buffer
    /// (several layers into one buffer).
    pub fn copy_image_to_buffer_at(
        &mut self,
        image: ImageId,
        mip: u32,
        layer: u32,
        buffer: BufferId,
        offset: u64,
    ) -> BackendResult<()> {
        let img = self.gpu.image(image)?;
        let buf = self.gpu.buffer(buffer)?;
        let region = vk::BufferImageCopy {
            buffer_offset: offset,
            buffer_row_length: 0,
            buffer_image_height: 0,
            image_subresource: vk::ImageSubresourceLayers {
                aspect_mask: img.desc.aspect(),
                mip_level: mip,
                base_array_layer: layer,
                layer_count: 1,
            },
            image_offset: vk::Offset3D::default(),
            image_extent: img.desc.mip_extent(mip),
        };
        if img.desc.aspect() != vk::ImageAspectFlags::COLOR {
            return Err(BackendError::Unsupported("readback of depth/stencil images".into()));
        }
        unsafe {
            self.gpu.device.cmd_copy_image_to_buffer(
                self.cb,
                img.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buf.raw,
                &[region],
            )
        };
        Ok(())
    }

    pub fn copy_buffer(&mut self, src: BufferId, dst: BufferId, size: u64) -> BackendResult<()> {
        self.copy_buffer_to(src, dst, 0, size)
    }

    /// Copies the first `size` bytes of `src` into `dst` from `dst_offset`.
    pub fn copy_buffer_to(&mut self, src: BufferId, dst: BufferId, dst_offset: u64, size: u64) -> BackendResult<()> {
        let (s, d) = (self.gpu.buffer(src)?.raw, self.gpu.buffer(dst)?.raw);
        unsafe {
            self.gpu.device.cmd_copy_buffer(
                self.cb,
                s,
                d,
                &[vk::BufferCopy {
                    src_offset: 0,
                    dst_offset,
                    size,
                }],
            )
        };
        Ok(())
    }

    pub fn fill_buffer(&mut self, buffer: BufferId, value: u32) -> BackendResult<()> {
        let raw = self.gpu.buffer(buffer)?.raw;
        unsafe { self.gpu.device.cmd_fill_buffer(self.cb, raw, 0, vk::WHOLE_SIZE, value) };
        Ok(())
    }

    /// Writes `words` into `buffer` from its start (a transfer; at most 65,536 bytes).
    pub fn update_buffer(&mut self, buffer: BufferId, words: &[u32]) -> BackendResult<()> {
        let raw = self.gpu.buffer(buffer)?.raw;
        if words.is_empty() || words.len() * 4 > 65_536 {
            return Err(BackendError::Invalid(format!(
                "update_buffer of {} words: 1 to 16,384 allowed",
                words.len()
            )));
        }
        unsafe {
            self.gpu
                .device
                .cmd_update_buffer(self.cb, raw, 0, bytemuck::cast_slice(words))
        };
        Ok(())
    }

    /// Clears a colour image range in TRANSFER_DST_OPTIMAL.
    pub fn clear_color_image(&mut self, image: ImageId, range: SubresourceRange, rgba: [f32; 4]) -> BackendResult<()> {
        let raw = self.gpu.image(image)?.raw;
        let r = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: range.base_mip,
            level_count: range.mip_count,
            base_array_layer: range.base_layer,
            layer_count: range.layer_count,
        };
        unsafe {
            self.gpu.device.cmd_clear_color_image(
                self.cb,
                raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &vk::ClearColorValue { float32: rgba },
                &[r],
            )
        };
        Ok(())
    }

    /// Blits mip 0 of `src` (TRANSFER_SRC_OPTIMAL) onto `dst` (TRANSFER_DST_OPTIMAL), scaling.
    pub fn blit(&mut self, src: ImageId, dst: ImageId) -> BackendResult<()> {
        let (s, d) = (self.gpu.image(src)?, self.gpu.image(dst)?);
        let corner = |e: vk::Extent3D| vk::Offset3D {
            x: e.width as i32,
            y: e.height as i32,
            z: 1,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = vk::ImageBlit2::default()
            .src_subresource(layers)
            .src_offsets([vk::Offset3D::default(), corner(s.desc.extent)])
            .dst_subresource(layers)
            .dst_offsets([vk::Offset3D::default(), corner(d.desc.extent)]);
        let regions = [region];
        let info = vk::BlitImageInfo2::default()
            .src_image(s.raw)
            .src_image_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
            .dst_image(d.raw)
            .dst_image_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .regions(&regions)
            .filter(vk::Filter::LINEAR);
        unsafe { self.gpu.device.cmd_blit_image2(self.cb, &info) };
        Ok(())
    }
}
