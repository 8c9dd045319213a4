//! The frame graph: a frame is a list of passes that declare which image subresources and
//! buffers they read and write. From those declarations the graph
//! - drops passes whose outputs nothing uses (culling, before anything is recorded),
//! - derives every layout transition and sync2 barrier from per-subresource state
//!   ([`state::ImageState`]), which persists across frames in [`ResourceStates`],
//! - binds the declared resources to the pass's shaders by name (checked against reflection),
//! - wraps each pass in a debug label and a GPU timestamp scope.
//!
//! Passes record through a closure that receives a [`PassContext`].

pub mod state;

use std::collections::{HashMap, HashSet};

use crate::backend::{
    vk, BackendError, Bind, BufferId, BufferTransition, Gpu, ImageId, ImageTransition, Recorder, SamplerId,
    SubresourceRange,
};
pub use state::Access;
use state::{BufferState, ImageState};

/// Where each resource was left by the previous frame; owned by whoever owns the resources.
#[derive(Default)]
pub struct ResourceStates {
    images: HashMap<ImageId, ImageState>,
    buffers: HashMap<BufferId, BufferState>,
}

impl ResourceStates {
    /// Declares an image whose contents are complete and which sits in `access`'s layout
    /// (e.g. a texture uploaded by `Gpu::upload_image`, left SHADER_READ_ONLY_OPTIMAL).
    pub fn set_image(&mut self, gpu: &Gpu, image: ImageId, access: Access) -> Result<(), BackendError> {
        let d = gpu.image_desc(image)?;
        self.images
            .insert(image, ImageState::with_initial(d.mip_levels, d.layers, access));
        Ok(())
    }
    /// A swapchain image just acquired: its previous contents are irrelevant, and the
    /// presentation engine releases it when the acquire semaphore signals, which the frame's
    /// submission waits for at `wait_stage`. Starting the image's state from that stage chains
    /// its first layout transition after the semaphore wait.
    pub fn acquired_image(&mut self, image: ImageId, wait_stage: vk::PipelineStageFlags2) {
        self.images.insert(
            image,
            ImageState::external(1, 1, vk::ImageLayout::UNDEFINED, wait_stage, vk::AccessFlags2::NONE),
        );
    }
    /// Forgets an image (destroyed, or recreated at a new size).
    pub fn forget_image(&mut self, image: ImageId) {
        self.images.remove(&image);
    }
    pub fn forget_buffer(&mut self, buffer: BufferId) {
        self.buffers.remove(&buffer);
    }
    pub fn image_layout(&self, image: ImageId, mip: u32, layer: u32) -> Option<vk::ImageLayout> {
        self.images.get(&image).map(|s| s.layout(mip, layer))
    }
}

#[derive(Clone, Debug)]
struct ImageUse {
    image: ImageId,
    range: SubresourceRange,
    access: Access,
    /// The pass overwrites the whole range: old contents (and layout) need not be kept.
    discard: bool,
    /// Shader binding name, with a sampler for sampled reads.
    binding: Option<(&'static str, Option<SamplerId>)>,
}

#[derive(Clone, Debug)]
struct BufferUse {
    buffer: BufferId,
    access: Access,
    binding: Option<&'static str>,
}

type RecordFn<'a> = Box<dyn FnOnce(&mut PassContext<'_, '_>) -> Result<(), BackendError> + 'a>;

struct PassNode<'a> {
    name: String,
    images: Vec<ImageUse>,
    buffers: Vec<BufferUse>,
    /// Passes whose effect is outside the graph (readback to the host, present).
    side_effect: bool,
    record: Option<RecordFn<'a>>,
}

/// Declares one pass. Finish with [`PassBuilder::record`].
pub struct PassBuilder<'g, 'a> {
    graph: &'g mut RenderGraph<'a>,
    node: PassNode<'a>,
}

impl<'g, 'a> PassBuilder<'g, 'a> {
    /// Samples `range` of `image` in the given stages through the shader binding `name`.
    pub fn sample(
        mut self,
        name: &'static str,
        image: ImageId,
        range: SubresourceRange,
        sampler: SamplerId,
        stages: vk::PipelineStageFlags2,
    ) -> Self {
        self.node.images.push(ImageUse {
            image,
            range,
            access: Access::SampledRead { stages },
            discard: false,
            binding: Some((name, Some(sampler))),
        });
        self
    }
    /// Reads a storage image through binding `name`.
    pub fn storage_read(
        mut self,
        name: &'static str,
        image: ImageId,
        range: SubresourceRange,
        stages: vk::PipelineStageFlags2,
    ) -> Self {
        self.node.images.push(ImageUse {
            image,
            range,
            access: Access::StorageRead { stages },
            discard: false,
            binding: Some((name, None)),
        });
        self
    }
    /// Writes (or reads and writes) a storage image through binding `name`.
    pub fn storage_write(
        mut self,
        name: &'static str,
        image: ImageId,
        range: SubresourceRange,
        stages: vk::PipelineStageFlags2,
    ) -> Self {
        self.node.images.push(ImageUse {
            image,
            range,
            access: Access::StorageWrite { stages },
            discard: false,
            binding: Some((name, None)),
        });
        self
    }
    /// Renders to mip/layer `range` of a colour image. `discard`: the pass clears or fully covers it.
    pub fn color_attachment(mut self, image: ImageId, range: SubresourceRange, discard: bool) -> Self {
        self.node.images.push(ImageUse {
            image,
            range,
            access: Access::ColorAttachmentWrite,
            discard,
            binding: None,
        });
        self
    }
    /// Depth/stencil attachment that is written (test + write, or cleared when `discard`).
    pub fn depth_stencil_write(mut self, image: ImageId, discard: bool) -> Self {
        self.node.images.push(ImageUse {
            image,
            range: SubresourceRange::mip(0),
            access: Access::DepthStencilAttachmentWrite,
            discard,
            binding: None,
        });
        self
    }
    /// Depth/stencil attachment that is only tested.
    pub fn depth_stencil_read(mut self, image: ImageId) -> Self {
        self.node.images.push(ImageUse {
            image,
            range: SubresourceRange::mip(0),
            access: Access::DepthStencilAttachmentRead,
            discard: false,
            binding: None,
        });
        self
    }
    pub fn transfer_read(mut self, image: ImageId, range: SubresourceRange) -> Self {
        self.node.images.push(ImageUse {
            image,
            range,
            access: Access::TransferRead,
            discard: false,
            binding: None,
        });
        self
    }
    pub fn transfer_write(mut self, image: ImageId, range: SubresourceRange, discard: bool) -> Self {
        self.node.images.push(ImageUse {
            image,
            range,
            access: Access::TransferWrite,
            discard,
            binding: None,
        });
        self
    }
    /// Leaves the image ready for presentation (the pass records nothing else with it).
    pub fn present(mut self, image: ImageId) -> Self {
        self.node.images.push(ImageUse {
            image,
            range: SubresourceRange::mip(0),
            access: Access::Present,
            discard: false,
            binding: None,
        });
        self.node.side_effect = true;
        self
    }
    /// A buffer use; `binding` names the shader block it is bound to, if any.
    pub fn buffer(mut self, buffer: BufferId, access: Access, binding: Option<&'static str>) -> Self {
        if matches!(access, Access::HostRead) {
            self.node.side_effect = true;
        }
        self.node.buffers.push(BufferUse {
            buffer,
            access,
            binding,
        });
        self
    }
    /// Marks the pass as having an effect outside the graph, so it is never culled.
    pub fn side_effect(mut self) -> Self {
        self.node.side_effect = true;
        self
    }
    pub fn record(mut self, f: impl FnOnce(&mut PassContext<'_, '_>) -> Result<(), BackendError> + 'a) {
        self.node.record = Some(Box::new(f));
        self.graph.passes.push(self.node);
    }
}

/// What a pass's closure gets: the recorder, and binding of its declared resources.
pub struct PassContext<'r, 'g> {
    pub rec: &'r mut Recorder<'g>,
    images: Vec<ImageUse>,
    buffers: Vec<BufferUse>,
}

impl<'r, 'g> PassContext<'r, 'g> {
    /// Binds every resource the pass declared with a binding name, plus `extra` (per-draw data,
    /// textures that live outside the graph), to the bound pipeline.
    pub fn bind(&mut self, extra: &[(&str, Bind<'_>)]) -> Result<(), BackendError> {
        let mut all: Vec<(&str, Bind<'_>)> = Vec::new();
        for u in &self.images {
            if let Some((name, sampler)) = u.binding {
                let bind = match (u.access, sampler) {
                    (Access::SampledRead { .. }, Some(sampler)) => Bind::Sampled {
                        image: u.image,
                        range: u.range,
                        sampler,
                    },
                    _ => Bind::StorageImage {
                        image: u.image,
                        range: u.range,
                    },
                };
                all.push((name, bind));
            }
        }
        for u in &self.buffers {
            if let Some(name) = u.binding {
                let bind = match u.access {
                    Access::UniformRead { .. } => Bind::UniformBuffer(u.buffer),
                    _ => Bind::StorageBuffer(u.buffer),
                };
                all.push((name, bind));
            }
        }
        all.extend(extra.iter().cloned());
        self.rec.bind(&all)
    }
}

/// One frame's passes, in submission order.
pub struct RenderGraph<'a> {
    passes: Vec<PassNode<'a>>,
    /// Resources whose final contents are wanted after the frame (a capture target, say).
    outputs: HashSet<Resource>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Resource {
    Image(ImageId),
    Buffer(BufferId),
}

/// What executing a graph did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ExecutionReport {
    /// Passes recorded, in order.
    pub recorded: Vec<String>,
    /// Passes dropped because nothing used what they wrote.
    pub culled: Vec<String>,
    pub image_barriers: usize,
    pub buffer_barriers: usize,
}

impl<'a> Default for RenderGraph<'a> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a> RenderGraph<'a> {
    pub fn new() -> Self {
        RenderGraph {
            passes: Vec::new(),
            outputs: HashSet::new(),
        }
    }

    pub fn pass(&mut self, name: &str) -> PassBuilder<'_, 'a> {
        PassBuilder {
            graph: self,
            node: PassNode {
                name: name.into(),
                images: Vec::new(),
                buffers: Vec::new(),
                side_effect: false,
                record: None,
            },
        }
    }

    /// Keeps the passes producing this image (its contents are used after the frame).
    pub fn output_image(&mut self, image: ImageId) {
        self.outputs.insert(Resource::Image(image));
    }

    pub fn output_buffer(&mut self, buffer: BufferId) {
        self.outputs.insert(Resource::Buffer(buffer));
    }

    /// Which passes survive culling: walking backwards, a pass is live if it has a side effect
    /// or writes something a later live pass reads (or that is an output).
    fn live_passes(&self) -> Vec<bool> {
        let mut needed: HashSet<Resource> = self.outputs.clone();
        let mut live = vec![false; self.passes.len()];
        for (i, p) in self.passes.iter().enumerate().rev() {
            let writes = p
                .images
                .iter()
                .filter(|u| u.access.is_write())
                .map(|u| Resource::Image(u.image))
                .chain(
                    p.buffers
                        .iter()
                        .filter(|u| u.access.is_write())
                        .map(|u| Resource::Buffer(u.buffer)),
                );
            let mut is_live = p.side_effect;
            for w in writes {
                if needed.contains(&w) {
                    is_live = true;
                }
            }
            if is_live {
                live[i] = true;
                // Everything the pass touches must be produced before it; attachments that are
                // loaded and images written in part are read-modify-write, so count them too.
                for u in &p.images {
                    if !u.discard {
                        needed.insert(Resource::Image(u.image));
                    }
                }
                for u in &p.buffers {
                    needed.insert(Resource::Buffer(u.buffer));
                }
            }
        }
        live
    }

    /// Records the graph on `frame` inside a timestamp scope named `scope`, submits it and
    /// waits: how one-off work (a bake's compute passes, the reference's batches) runs.
    pub fn run_and_wait(
        self,
        gpu: &Gpu,
        frame: crate::backend::Frame,
        states: &mut ResourceStates,
        scope: &str,
    ) -> Result<(), BackendError> {
        let mut rec = gpu.begin_frame(frame)?;
        rec.begin_scope(scope);
        self.execute(&mut rec, states)?;
        rec.end_scope();
        rec.finish()?;
        gpu.submit_and_wait(frame)
    }

    /// Records every live pass into `rec`, deriving barriers from (and updating) `states`.
    pub fn execute(self, rec: &mut Recorder<'_>, states: &mut ResourceStates) -> Result<ExecutionReport, BackendError> {
        let live = self.live_passes();
        let gpu = rec.gpu();
        let mut report = ExecutionReport::default();
        for (pass, is_live) in self.passes.into_iter().zip(live) {
            if !is_live {
                report.culled.push(pass.name);
                continue;
            }
            rec.begin_scope(&pass.name);
            let mut image_barriers = Vec::new();
            for u in &pass.images {
                let state = match states.images.entry(u.image) {
                    std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
                    std::collections::hash_map::Entry::Vacant(e) => {
                        let d = gpu.image_desc(u.image)?;
                        e.insert(ImageState::new(d.mip_levels, d.layers))
                    }
                };
                let barriers = if u.discard {
                    state.transition_discard(u.range, u.access)
                } else {
                    state.transition(u.range, u.access)
                };
                image_barriers.extend(barriers.into_iter().map(|b| ImageTransition {
                    image: u.image,
                    range: b.range,
                    src_stages: b.src_stages,
                    src_access: b.src_access,
                    dst_stages: b.dst_stages,
                    dst_access: b.dst_access,
                    old_layout: b.old_layout,
                    new_layout: b.new_layout,
                }));
            }
            let mut buffer_barriers = Vec::new();
            for u in &pass.buffers {
                let state = states.buffers.entry(u.buffer).or_default();
                if let Some(b) = state.transition(u.access) {
                    buffer_barriers.push(BufferTransition {
                        buffer: u.buffer,
                        src_stages: b.src_stages,
                        src_access: b.src_access,
                        dst_stages: b.dst_stages,
                        dst_access: b.dst_access,
                    });
                }
            }
            report.image_barriers += image_barriers.len();
            report.buffer_barriers += buffer_barriers.len();
            rec.barriers(&image_barriers, &buffer_barriers)?;
            if let Some(record) = pass.record {
                let mut ctx = PassContext {
                    rec: &mut *rec,
                    images: pass.images,
                    buffers: pass.buffers,
                };
                let result = record(&mut ctx);
                if let Err(e) = result {
                    rec.end_scope();
                    return Err(e);
                }
            }
            rec.end_scope();
            report.recorded.push(pass.name);
        }
        Ok(report)
    }
}

/// The bytes of `buffer`, whole, copied through a host buffer on a frame of its own once the
/// work queued before has finished: a one-off read of GPU data (a light's vertex colours, a
/// volume's cells, the clusters' counts). `name` names the passes and the timestamp scope.
pub fn read_back_buffer(gpu: &mut Gpu, buffer: BufferId, name: &str) -> Result<Vec<u8>, BackendError> {
    let size = gpu.buffer_desc(buffer)?.size;
    let host = gpu.create_buffer(&crate::backend::BufferDesc {
        name: format!("{name} readback"),
        size,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        memory: crate::backend::MemoryKind::GpuToCpu,
    })?;
    let frame = gpu.create_frame()?;
    let mut graph = RenderGraph::new();
    graph
        .pass(&format!("{name} readback"))
        .buffer(buffer, Access::TransferRead, None)
        .buffer(host, Access::TransferWrite, None)
        .record(move |ctx| ctx.rec.copy_buffer(buffer, host, size));
    graph
        .pass(&format!("{name} readback host"))
        .buffer(host, Access::HostRead, None)
        .record(|_| Ok(()));
    let mut states = ResourceStates::default();
    let run = graph.run_and_wait(gpu, frame, &mut states, &format!("{name} readback"));
    let bytes = run.and_then(|()| gpu.read_buffer(host));
    gpu.destroy_buffer(host);
    gpu.destroy_frame(frame)?;
    bytes
}
