//! The lighting methods penumbra implements, and how a scene's `methods` entries become them.
//!
//! A method adds its passes to the frame graph; everything it needs beyond the shared scene data
//! (pipelines, its own images) it creates in `create`. Only the methods a scene declares are
//! created, so a scene instantiates only the passes it needs.

use crate::backend::{Gpu, ImageId};
use crate::error::{Error, Result};
use crate::forward::Forward;
use crate::graph::{RenderGraph, ResourceStates};
use crate::renderer::{FrameUniforms, SceneGpu};
use crate::scene::{MethodDecl, MethodSchema, Scene};
use crate::shaders::ShaderLibrary;

/// What a method writes into: linear HDR radiance plus a depth/stencil buffer.
#[derive(Clone, Copy, Debug)]
pub struct FrameTargets {
    pub radiance: ImageId,
    pub depth_stencil: ImageId,
    pub width: u32,
    pub height: u32,
}

/// Everything a method reads to build one frame.
pub struct FrameInputs<'a> {
    pub gpu: &'a Gpu,
    pub scene: &'a SceneGpu,
    pub targets: FrameTargets,
    pub uniforms: FrameUniforms,
}

pub trait LightingMethod {
    /// The name scenes and `--method` use.
    fn name(&self) -> &'static str;
    /// Adds the passes that fill `inputs.targets.radiance` for this frame.
    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, inputs: &FrameInputs<'a>) -> Result<()>;
}

/// What the reference must contain for a method's error to mean something.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ReferenceKind {
    /// Emission and light after one surface interaction (shadowed): direct-lighting methods.
    Direct,
    /// Up to this many bounces after the first hit (global illumination methods).
    Bounces(u32),
}

/// How `penumbra chart` treats a method: its schema, its quality sweep, and its reference.
pub struct MethodInfo {
    pub schema: MethodSchema,
    /// The configurations to measure, as (label, declaration with the swept parameters set),
    /// starting from the scene's declaration.
    pub sweep: fn(&MethodDecl) -> Vec<(String, MethodDecl)>,
    pub reference: ReferenceKind,
}

/// Every method penumbra implements.
pub fn registry() -> Vec<MethodInfo> {
    vec![
        MethodInfo { schema: crate::forward::SCHEMA, sweep: crate::forward::sweep, reference: ReferenceKind::Direct },
        MethodInfo { schema: crate::shadow_volumes::SCHEMA, sweep: crate::shadow_volumes::sweep, reference: ReferenceKind::Direct },
        MethodInfo { schema: crate::heightfield::PYRAMID_SCHEMA, sweep: crate::heightfield::pyramid_sweep, reference: ReferenceKind::Direct },
        MethodInfo { schema: crate::heightfield::BRUTE_FORCE_SCHEMA, sweep: crate::heightfield::brute_sweep, reference: ReferenceKind::Direct },
    ]
}

/// Every method scenes may declare, with its parameters.
pub fn schemas() -> Vec<MethodSchema> {
    registry().into_iter().map(|m| m.schema).collect()
}

pub fn info(name: &str) -> Result<MethodInfo> {
    registry().into_iter().find(|m| m.schema.name == name).ok_or_else(|| Error::Usage(format!("method `{name}` is not implemented")))
}

/// Creates the method a scene declared.
pub fn create(decl: &MethodDecl, gpu: &mut Gpu, shaders: &ShaderLibrary, states: &mut ResourceStates, scene: &Scene) -> Result<Box<dyn LightingMethod>> {
    if decl.name != crate::shadow_volumes::NAME {
        scene.refuse_translucency(&format!("the {} method", decl.name)).map_err(Error::Usage)?;
    }
    match decl.name.as_str() {
        "forward" => Ok(Box::new(Forward::new(gpu, shaders, decl)?)),
        crate::shadow_volumes::NAME => Ok(Box::new(crate::shadow_volumes::ShadowVolumes::new(gpu, shaders, states, scene, decl)?)),
        crate::heightfield::PYRAMID | crate::heightfield::BRUTE_FORCE => Ok(Box::new(crate::heightfield::HeightfieldMethod::new(gpu, shaders, states, scene, decl)?)),
        other => Err(Error::Usage(format!("method `{other}` is not implemented"))),
    }
}
