//! The Vulkan backend: the only module of penumbra that calls `ash` in `unsafe` blocks.
//!
//! Everything above it (the frame graph, the lighting methods, the CLI) talks to the GPU through
//! the safe types here: [`Gpu`] owns the instance, device, allocator and every resource, handed
//! out as small typed ids ([`BufferId`], [`ImageId`], [`PipelineId`]); [`Recorder`] records one
//! command buffer. Safety rests on three invariants, kept inside this module:
//! - a resource is destroyed only through [`Gpu`] and only after the GPU is idle or the frame that
//!   used it has been waited for (`Gpu::destroy_*` waits for the device);
//! - every command buffer is recorded by one [`Recorder`] that borrows the [`Gpu`] immutably, so no
//!   resource can be destroyed while a recording refers to it;
//! - descriptor writes are checked against the shader's reflected layout before they are made.

mod descriptors;
mod device;
mod error;
mod frame;
mod overlay;
mod pipeline;
mod recorder;
mod reflect;
mod resources;
mod swapchain;
mod timestamps;
mod uniform_blocks;

pub use descriptors::Bind;
pub use device::{DeviceCaps, Gpu, GpuDesc, ValidationLog};
pub use error::{BackendError, BackendResult};
pub use frame::{Frame, FrameFootprint};
pub use overlay::{Overlay, OverlayFrame};
pub use pipeline::{
    BlendMode, ColorTarget, ComputePipelineDesc, DepthState, GraphicsPipelineDesc, PipelineId, RasterState,
    ShaderSource, SpecConstant, StencilFace, StencilFaces, VertexAttribute, VertexLayout,
};
pub use recorder::{BufferTransition, Clear, ImageTransition, Recorder, RenderTarget, RenderingDesc};
pub use reflect::{ReflectedBinding, ShaderReflection};
pub use resources::{
    format_texel_size, BufferDesc, BufferId, ImageDesc, ImageId, MemoryKind, ResourceScope, SamplerDesc, SamplerId,
    SubresourceRange,
};
pub use swapchain::{AcquiredImage, Swapchain};
pub use timestamps::{PassTiming, TimestampSupport};

/// Re-exported so that callers can name formats, stages and flags without depending on ash
/// directly; these are plain data types.
pub use ash::vk;
