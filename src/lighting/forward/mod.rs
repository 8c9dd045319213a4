//! Forward direct lighting: Lambert plus energy-normalised Blinn-Phong from point, spot and
//! directional lights, no shadows. One graphics pass writes linear radiance and depth.
//!
//! It supplies the base term (emission and the unshadowed environment irradiance) and the direct
//! term (the lights), together in one pass or either alone: as a direct term it adds into the
//! target over another method's base, testing against that base's depth.
//!
//! It is penumbra's first method and the baseline the others are measured against. Its CPU
//! mirror is [`crate::lighting::brdf`].

use crate::backend::{vk, Bind, PipelineId};
use crate::error::Result;
use crate::gpu_scene::{record_draws, vertex_layout, DrawCall};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{
    begin_term_rendering, term_pass, term_pipeline_desc, CreateContext, FrameContext, LightingMethod, Term, Terms,
};
use crate::scene::{MethodDecl, MethodSchema};

pub const SCHEMA: MethodSchema = MethodSchema {
    name: "forward",
    params: &[],
};

/// Forward has no quality settings: one configuration.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    vec![("forward".to_string(), decl.clone())]
}

/// The pipelines by the terms they draw: base + direct, base alone, direct alone.
pub struct Forward {
    both: PipelineId,
    base: PipelineId,
    direct: PipelineId,
}

impl Forward {
    pub fn new(c: &mut CreateContext<'_>, _decl: &MethodDecl) -> Result<Self> {
        let ds_format = c.gpu.caps().depth_stencil_format;
        let mut pipeline = |terms: Terms| {
            let mut desc = term_pipeline_desc(
                &format!("forward {terms}"),
                "frame/surface.vert",
                "forward/forward.frag",
                terms,
                ds_format,
            );
            desc.vertex_layout = vertex_layout();
            c.gpu.create_graphics_pipeline(&desc, c.shaders)
        };
        Ok(Forward {
            both: pipeline(Terms::BASE_DIRECT)?,
            base: pipeline(Terms::BASE)?,
            direct: pipeline(Terms::DIRECT)?,
        })
    }
}

impl LightingMethod for Forward {
    fn name(&self) -> &'static str {
        "forward"
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        let scene = frame.scene;
        let t = frame.targets;
        let uniforms = frame.uniforms;
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let base = frame.terms.has(Term::Base);
        let pipeline = match (base, frame.terms.has(Term::Direct)) {
            (true, true) => self.both,
            (true, false) => self.base,
            (false, true) => self.direct,
            (false, false) => return Ok(()),
        };
        let pass = term_pass(graph, if base { "forward" } else { "forward direct" }, t, base);
        pass.buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                let _ = begin_term_rendering(ctx.rec, t, base)?;
                ctx.rec.bind_pipeline(pipeline)?;
                let lights = scene.light_bytes();
                let uniform_bytes = bytemuck::bytes_of(&uniforms);
                let calls: Vec<DrawCall> = scene.draws.iter().map(DrawCall::whole).collect();
                record_draws(ctx, scene, &calls, |ctx, material| {
                    let maps = scene.material_maps[material as usize];
                    let [albedo, normal, specular] = maps.binds(scene.sampler);
                    ctx.bind(&[
                        ("frame", Bind::UniformData(uniform_bytes)),
                        ("lights", Bind::StorageData(lights)),
                        albedo,
                        normal,
                        specular,
                    ])
                })?;
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }
}
