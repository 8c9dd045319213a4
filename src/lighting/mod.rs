//! The lighting layer: what a lighting method is, how methods compose into a frame, and every
//! technique in its own folder.
//!
//! A frame is the sum of three terms written into one radiance target that the renderer clears:
//! the **base** term (depth, emission, ambient or light-map; the sky behind it is drawn by the
//! renderer after the base), the **direct** term (light arriving straight from the light sources)
//! and the **indirect** term (light after further bounces). A method supplies one or more terms
//! ([`registry::MethodInfo::terms`]); a scene's configuration assigns each term to at most one
//! method ([`Configuration`]). Methods after the base add into the target (additive blending) and
//! test against the base's depth, so `shadow_volumes` can draw direct light over a baked
//! light-map, or an LPV its indirect light over any direct method.
//!
//! Only [`registry`] names techniques; the commands above this layer go through it.

pub mod brdf;
pub mod lightmap;
pub mod many_lights;
pub(crate) mod params;
pub mod plan;
pub mod registry;
mod terms;

pub mod bsp_lights;
pub mod clustered;
pub(crate) mod forward;
pub mod heightfield;
pub mod lpv;
pub mod prt;
pub mod radiosity;
pub mod sh_lightmap;
pub mod shadow_volumes;
pub mod vls;

use bytemuck::{Pod, Zeroable};

use crate::backend::{
    vk, BackendResult, BlendMode, ColorTarget, DepthState, Gpu, GraphicsPipelineDesc, ImageId, Recorder, RenderTarget,
    RenderingDesc, SpecConstant, SubresourceRange,
};
use crate::bake::Baker;
use crate::environment::EnvironmentMap;
use crate::error::Result;
use crate::gpu_scene::SceneGpu;
use crate::graph::{PassBuilder, RenderGraph, ResourceStates};
use crate::scene::Scene;
use crate::shaders::ShaderLibrary;

pub use terms::{Configuration, Part, Term, Terms};

/// Linear radiance: 32-bit float so captures read back exactly what the shaders computed.
pub const RADIANCE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Matches `FrameUniforms` in glsl/common/frame.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [f32; 16],
    pub camera_pos: [f32; 4],
    pub ambient: [f32; 4],
    pub counts: [u32; 4],
    /// Environment irradiance, 3-band SH (see `environment::raster`).
    pub env_irradiance: [[f32; 4]; 9],
}

/// What a method writes into: linear HDR radiance plus a depth/stencil buffer.
#[derive(Clone, Copy, Debug)]
pub struct FrameTargets {
    pub radiance: ImageId,
    pub depth_stencil: ImageId,
    /// A target-sized [`LIGHT_MASK_FORMAT`] image a method may use within its passes (which
    /// pixels each of a group of lights reaches), there while a method of the configuration asks
    /// for it ([`LightingMethod::uses_light_mask`]).
    pub light_mask: Option<ImageId>,
    pub width: u32,
    pub height: u32,
}

/// The format of [`FrameTargets::light_mask`].
pub const LIGHT_MASK_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// The renderer's clock, the one every method animates by.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameClock {
    /// Frames rendered before this one (0 for the first).
    pub frame: u64,
    /// Animation time of this frame in seconds: `frame` × [`FrameClock::STEP_S`].
    pub time_s: f32,
}

impl FrameClock {
    /// Animation step per frame (a 60 Hz display).
    pub const STEP_S: f32 = crate::scene::motion::FRAME_STEP_S;

    pub fn at(frame: u64) -> FrameClock {
        FrameClock {
            frame,
            time_s: crate::scene::motion::frame_time(frame),
        }
    }
}

/// Everything a method reads to build one frame.
pub struct FrameContext<'a> {
    pub gpu: &'a Gpu,
    pub scene: &'a SceneGpu,
    pub targets: FrameTargets,
    pub uniforms: FrameUniforms,
    pub clock: FrameClock,
    /// The terms this method draws in this configuration. The target is cleared and, when this
    /// method is not the base, holds the base's depth: a method without [`Term::Base`] must not
    /// write depth and adds into the radiance.
    pub terms: Terms,
}

/// What a method is created from: the device, the uploaded scene (vertex layout, draws with
/// their object ids, materials, lights), the environment as loaded once, and the bake stage.
pub struct CreateContext<'a> {
    pub gpu: &'a mut Gpu,
    pub shaders: &'a ShaderLibrary,
    pub states: &'a mut ResourceStates,
    pub scene: &'a Scene,
    pub scene_gpu: &'a SceneGpu,
    pub environment: &'a EnvironmentMap,
    pub bakes: &'a mut Baker,
    /// The terms this method will draw in the configuration being created.
    pub terms: Terms,
    /// The frames the command will draw with this configuration (0: not said). A method that
    /// estimates its frames says so through [`CreateContext::warn_cost`] before its large
    /// allocations when they pass [`SLOW_RUN_S`].
    pub frames: usize,
}

impl CreateContext<'_> {
    /// Says on stderr, in one line, that [`CreateContext::frames`] frames at `cost` each pass
    /// [`SLOW_RUN_S`]; nothing when they do not or no frame count was given.
    pub fn warn_cost(&self, method: &str, cost: &FrameCost) {
        if self.frames > 0 {
            if let Some(line) = cost_warning(self.scene, method, cost, self.frames) {
                crate::errln!("{line}");
            }
        }
    }
}

/// The line that warns that `frames` frames of `method` at `cost` pass [`SLOW_RUN_S`], naming
/// the scene.
pub fn cost_warning(scene: &Scene, method: &str, cost: &FrameCost, frames: usize) -> Option<String> {
    let w = cost.warning(method, frames)?;
    Some(format!("warning: {}: {w}", scene.source))
}

/// A pass that draws surfaces into the frame's radiance with a [`term_pipeline_desc`] pipeline:
/// drawing the base it writes the depth, otherwise it tests the base's.
pub fn term_pass<'g, 'a>(
    graph: &'g mut RenderGraph<'a>,
    name: &str,
    targets: FrameTargets,
    base: bool,
) -> PassBuilder<'g, 'a> {
    let pass = graph
        .pass(name)
        .color_attachment(targets.radiance, SubresourceRange::mip(0), false);
    if base {
        pass.depth_stencil_write(targets.depth_stencil, false)
    } else {
        pass.depth_stencil_read(targets.depth_stencil)
    }
}

/// Begins a [`term_pass`]'s rendering: onto the radiance as it is, the depth read-only unless
/// the pass draws the base.
pub fn begin_term_rendering(rec: &mut Recorder<'_>, targets: FrameTargets, base: bool) -> BackendResult<vk::Extent2D> {
    let depth = RenderTarget {
        read_only: !base,
        ..RenderTarget::load(targets.depth_stencil)
    };
    rec.begin_rendering(&RenderingDesc {
        colors: vec![RenderTarget::load(targets.radiance)],
        depth_stencil: Some(depth),
    })
}

/// The pipeline of a pass that draws the scene's surfaces and writes `terms` into the frame's
/// radiance: thin surfaces seen from both sides, the terms as specialization constant 0, and —
/// when it is not the base — the base's depth tested but not written and its light added. The
/// caller adds its vertex layout, further constants and any depth bias.
pub fn term_pipeline_desc(
    name: &str,
    vertex: &str,
    fragment: &str,
    terms: Terms,
    depth_format: vk::Format,
) -> GraphicsPipelineDesc {
    let mut desc = GraphicsPipelineDesc::new(name, vertex, Some(fragment));
    desc.raster.cull = vk::CullModeFlags::NONE;
    desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
    desc.depth_format = Some(depth_format);
    desc.specialization = vec![SpecConstant {
        id: 0,
        bits: terms.bits(),
    }];
    if !terms.has(Term::Base) {
        desc.depth = DepthState {
            test: true,
            write: false,
            compare: vk::CompareOp::LESS_OR_EQUAL,
        };
        desc.color_targets[0].blend = BlendMode::Additive;
    }
    desc
}

pub trait LightingMethod {
    /// The name scenes and `--method` use.
    fn name(&self) -> &'static str;
    /// Per-frame planning on the CPU (culling, animation) before any pass is recorded.
    fn prepare(&mut self, _frame: &FrameContext<'_>) -> Result<()> {
        Ok(())
    }
    /// Adds the passes that draw `frame.terms` into `frame.targets`.
    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()>;
    /// The device memory of its resources, per group, for `profile`'s report (none: not
    /// itemised).
    fn memory(&self, _gpu: &Gpu) -> Result<Vec<MemoryItem>> {
        Ok(Vec::new())
    }
    /// What the last (finished) frame had to leave out, read back, each a line for the user:
    /// light the method dropped for want of room, which the image lacks without any other sign.
    /// Read once after a run, not every frame.
    fn warnings(&self, _gpu: &mut Gpu) -> Result<Vec<String>> {
        Ok(Vec::new())
    }
    /// What the last (finished) frame did that its pass timings do not show, read back, each a
    /// line for `profile` (how shadow volumes were counted, say). Read once after a run.
    fn frame_notes(&self, _gpu: &mut Gpu) -> Result<Vec<String>> {
        Ok(Vec::new())
    }
    /// What one frame will take on this device, estimated before the first from its work and a
    /// measured throughput (none: not estimated).
    fn frame_cost(&self) -> Option<FrameCost> {
        None
    }
    /// Whether its passes use [`FrameTargets::light_mask`], which the renderer then keeps.
    fn uses_light_mask(&self) -> bool {
        false
    }
}

/// A run estimated past this many seconds draws a warning before its first frame.
pub const SLOW_RUN_S: f64 = 60.0;

/// A method's estimate of one frame: each stage and its seconds.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameCost {
    /// What each stage is, and its seconds a frame.
    pub parts: Vec<(String, f64)>,
    /// The settings that make it cheaper.
    pub remedy: String,
}

impl FrameCost {
    pub fn seconds(&self) -> f64 {
        self.parts.iter().map(|p| p.1).sum()
    }

    /// One line when `frames` frames are estimated past [`SLOW_RUN_S`]: the total, a frame's
    /// share and the stage that dominates it.
    pub fn warning(&self, method: &str, frames: usize) -> Option<String> {
        let each = self.seconds();
        let total = each * frames.max(1) as f64;
        if total.is_nan() || total <= SLOW_RUN_S {
            return None;
        }
        let (what, part) = self.parts.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
        Some(format!(
            "{method}: {frames} frame(s) estimated at {}, {} a frame (from the work and this device's measured throughput); {what} dominates at {} a frame: {} cut it",
            duration(total),
            duration(each),
            duration(*part),
            self.remedy
        ))
    }
}

/// Seconds for a person.
fn duration(s: f64) -> String {
    if s >= 3600.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s >= 60.0 {
        format!("{:.1} min", s / 60.0)
    } else if s >= 1.0 {
        format!("{s:.1} s")
    } else {
        format!("{:.1} ms", s * 1e3)
    }
}

/// One group of a method's resources and the device memory bound to it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MemoryItem {
    pub method: &'static str,
    /// What it is ("lpv sets (2 wavefronts + accumulation)").
    pub resource: String,
    /// The bytes the resources' sizes ask for, and the bytes allocated for them.
    pub requested: u64,
    pub allocated: u64,
}

/// What the reference must contain for a method's error to mean something.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ReferenceKind {
    /// Emission and light after one surface interaction (shadowed): direct-lighting methods.
    Direct,
    /// Up to this many bounces after the first hit (global illumination methods).
    Bounces(u32),
    /// Light after 2 to this many + 1 interactions: only what bounced (an indirect term alone).
    Indirect(u32),
}

impl ReferenceKind {
    /// What two parts of a configuration model together.
    pub fn combine(self, other: ReferenceKind) -> ReferenceKind {
        use ReferenceKind::*;
        match (self, other) {
            (Direct, Direct) => Direct,
            (Indirect(a), Indirect(b)) => Indirect(a.max(b)),
            (Direct, Indirect(k)) | (Indirect(k), Direct) | (Direct, Bounces(k)) | (Bounces(k), Direct) => Bounces(k),
            (Bounces(a) | Indirect(a), Bounces(b) | Indirect(b)) => Bounces(a.max(b)),
        }
    }
}

/// The one-line warning for a method that lights with distant light only (the environment and
/// directional lights) in a scene with other lights, which it would otherwise drop in silence
/// (a scene lit by a point light alone renders black).
pub fn distant_only_warning(scene: &crate::scene::Scene, method: &str) -> Option<String> {
    let local = local_light_names(scene);
    (!local.is_empty()).then(|| {
        format!(
            "warning: {}: {method} lights with distant light only; it leaves out {}",
            scene.source,
            local.join(", ")
        )
    })
}

/// The names of the scene's lights that are not directional.
fn local_light_names(scene: &crate::scene::Scene) -> Vec<String> {
    scene
        .lights
        .iter()
        .filter(|l| !matches!(l, crate::scene::Light::Directional { .. }))
        .map(|l| l.name().to_string())
        .collect()
}
