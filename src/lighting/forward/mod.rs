//! Forward direct lighting: Lambert plus energy-normalised Blinn-Phong from point, spot and
//! directional lights, no shadows. One graphics pass writes linear radiance and depth.
//!
//! It supplies the base term (emission and the unshadowed environment irradiance) and the direct
//! term (the lights), together in one pass or either alone: as a direct term it adds into the
//! target over another method's base, testing against that base's depth.
//!
//! Translucent materials (opacity α < 1) are drawn after the opaque ones, back to front by their
//! draw's centre, each blended over what lies behind it: α times its own light plus 1 − α times
//! the light behind, what the reference's stochastic transparency gives a camera ray. They write
//! no depth. As a direct term alone over another base, forward draws opaque surfaces only.
//!
//! It is penumbra's first method and the baseline the others are measured against. Its CPU
//! mirror is [`crate::lighting::brdf`].

use glam::Vec3;

use crate::backend::{vk, Bind, BlendMode, DepthState, PipelineId};
use crate::error::{Error, Result};
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

/// The pipelines by the terms they draw (base + direct, base alone, direct alone), the blending
/// ones for translucent materials, and which scene draws are translucent.
pub struct Forward {
    both: PipelineId,
    base: PipelineId,
    direct: PipelineId,
    blended_both: PipelineId,
    blended_base: PipelineId,
    /// Per scene draw: its centre in world space when its material is translucent.
    translucent: Vec<Option<Vec3>>,
}

impl Forward {
    pub fn new(c: &mut CreateContext<'_>, _decl: &MethodDecl) -> Result<Self> {
        let translucent: Vec<Option<Vec3>> = c
            .scene_gpu
            .draws
            .iter()
            .zip(&c.scene_gpu.meshes)
            .map(|(d, mesh)| {
                let m = c.scene.materials.get(d.material as usize)?;
                let (lo, hi) = mesh.bounds()?;
                m.is_translucent().then(|| d.model.transform_point3((lo + hi) * 0.5))
            })
            .collect();
        if !c.terms.has(Term::Base) && translucent.iter().any(Option::is_some) {
            c.scene
                .refuse_translucency("the forward method as a direct term over another base")
                .map_err(Error::Usage)?;
        }
        let ds_format = c.gpu.caps().depth_stencil_format;
        let mut pipeline = |terms: Terms, blended: bool| {
            let mut desc = term_pipeline_desc(
                &format!("forward {terms}{}", if blended { " blended" } else { "" }),
                "frame/surface.vert",
                "forward/forward.frag",
                terms,
                ds_format,
            );
            desc.vertex_layout = vertex_layout();
            if blended {
                desc.depth = DepthState {
                    test: true,
                    write: false,
                    compare: vk::CompareOp::LESS_OR_EQUAL,
                };
                desc.color_targets[0].blend = BlendMode::Alpha;
            }
            c.gpu.create_graphics_pipeline(&desc, c.shaders)
        };
        Ok(Forward {
            both: pipeline(Terms::BASE_DIRECT, false)?,
            base: pipeline(Terms::BASE, false)?,
            direct: pipeline(Terms::DIRECT, false)?,
            blended_both: pipeline(Terms::BASE_DIRECT, true)?,
            blended_base: pipeline(Terms::BASE, true)?,
            translucent,
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
        let (pipeline, blended) = match (base, frame.terms.has(Term::Direct)) {
            (true, true) => (self.both, self.blended_both),
            (true, false) => (self.base, self.blended_base),
            (false, true) => (self.direct, self.direct),
            (false, false) => return Ok(()),
        };
        let is_translucent = |i: usize| self.translucent.get(i).is_some_and(Option::is_some);
        let opaque: Vec<DrawCall> = (scene.draws.iter().enumerate())
            .filter(|&(i, _)| !is_translucent(i))
            .map(|(_, d)| DrawCall::whole(d))
            .collect();
        // Back to front from the camera, by each draw's centre.
        let eye = Vec3::from_slice(&uniforms.camera_pos[..3]);
        let mut behind: Vec<(f32, usize)> = (self.translucent.iter().enumerate())
            .filter_map(|(i, c)| c.map(|c| (c.distance_squared(eye), i)))
            .collect();
        behind.sort_by(|a, b| b.0.total_cmp(&a.0));
        let translucent: Vec<DrawCall> = if base {
            behind.iter().map(|&(_, i)| DrawCall::whole(&scene.draws[i])).collect()
        } else {
            Vec::new()
        };
        let pass = term_pass(graph, if base { "forward" } else { "forward direct" }, t, base);
        pass.buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                let _ = begin_term_rendering(ctx.rec, t, base)?;
                let lights = scene.light_bytes();
                let uniform_bytes = bytemuck::bytes_of(&uniforms);
                for (pipeline, calls) in [(pipeline, &opaque), (blended, &translucent)] {
                    if calls.is_empty() {
                        continue;
                    }
                    ctx.rec.bind_pipeline(pipeline)?;
                    record_draws(ctx, scene, calls, |ctx, material| {
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
                }
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }
}
