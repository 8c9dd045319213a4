//! Clustered shading (Olsson, Billeter & Assarsson 2012) for many unshadowed lights: the view
//! frustum is cut into a grid of clusters (screen tiles × exponential depth slices); a compute
//! pass lists, per cluster, the lights whose bounding sphere touches it; the scene is then
//! drawn like the forward method, each fragment summing only its cluster's lights.
//!
//! Passes per frame: **clustered bounds** (each cluster's view-space box), **clustered assign**
//! (each cluster's lights into fixed slots, with the uncapped count so overflow can be read back)
//! and **clustered** (the shading; **clustered direct** over another method's base).
//!
//! Each light has a range: the scene's `radius`, or where its irradiance falls to `cutoff`
//! ([`assign::range`]). The shading sums a light only within its range, so the image is the
//! forward method's with each light cut off at its range, whatever the grid.

pub mod assign;
pub mod config;

#[cfg(test)]
mod tests;

use glam::Vec3;

use crate::backend::{vk, Bind, BufferDesc, BufferId, ComputePipelineDesc, Gpu, MemoryKind, PipelineId};
use crate::error::{Error, Result};
use crate::gpu_scene::{record_draws, vertex_layout, DrawCall};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{
    begin_term_rendering, term_pass, term_pipeline_desc, CreateContext, FrameContext, LightingMethod, Term, Terms,
};
use crate::scene::{Light, MethodDecl, MethodSchema, ParamKind, ParamSchema};
use assign::{Assignment, ClusterBlock, LightVolume};
use config::Config;

pub const NAME: &str = "clustered";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "tiles",
            kind: ParamKind::FloatArray,
        },
        ParamSchema {
            name: "slices",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "max_per_cluster",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "cutoff",
            kind: ParamKind::Float,
        },
    ],
};

/// The most lights a scene may have: the assignment keeps a tile's lights in shared bit masks
/// (one per band of depth slices) of this many bits, and an invocation may loop over all of them
/// for each of up to 4 slices, under llvmpipe's 65,535 loop iterations per invocation. Matches
/// glsl/clustered/assign.comp.
pub const MAX_LIGHTS: usize = 8192;

/// Depth slices a grid may have; `MAX_SLICES` in glsl/clustered/assign.comp (its loop bounds
/// assume it).
pub const MAX_SLICES: u32 = 256;

/// Invocations in a workgroup of glsl/clustered/assign.comp (its `local_size_x`).
const ASSIGN_LANES: u32 = 64;

/// The chart's sweep: as declared, then a coarse, the default and a fine grid.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d, None) {
            let label = format!(
                "{NAME} {}x{}x{} cap {}",
                c.tiles[0], c.tiles[1], c.slices, c.max_per_cluster
            );
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    let grid = |x: i64, y: i64| toml::Value::Array(vec![x.into(), y.into()]);
    push(decl.with("tiles", grid(16, 9)).with("slices", 16i64.into()));
    push(decl.with("tiles", grid(32, 18)).with("slices", 24i64.into()));
    push(decl.with("tiles", grid(64, 36)).with("slices", 32i64.into()));
    out
}

/// The scene's geometry (emitters included) at its placement: where the slices must reach.
fn scene_box(cx: &CreateContext<'_>) -> Option<(Vec3, Vec3)> {
    let mut min = Vec3::splat(f32::INFINITY);
    let mut max = Vec3::splat(f32::NEG_INFINITY);
    for (d, mesh) in cx.scene_gpu.draws.iter().zip(&cx.scene_gpu.meshes) {
        for p in &mesh.positions {
            let w = d.model.transform_point3(*p);
            min = min.min(w);
            max = max.max(w);
        }
    }
    min.is_finite().then_some((min, max))
}

pub struct Clustered {
    config: Config,
    /// The scene's `radius` of each light as the GPU scene lists them (0: none given).
    radii: Vec<f32>,
    scene_box: Option<(Vec3, Vec3)>,
    /// This frame's grid and light volumes ([`Clustered::plan`]).
    pub block: ClusterBlock,
    pub volumes: Vec<LightVolume>,
    /// Per cluster: its view-space box (two vec4), its light count, its index slots.
    bounds: BufferId,
    pub counts: BufferId,
    pub indices: BufferId,
    /// Per coarse tile, a bit per light that reaches it (glsl/clustered/coarse.comp).
    coarse: BufferId,
    bounds_pipeline: PipelineId,
    coarse_pipeline: PipelineId,
    assign_pipeline: PipelineId,
    both: PipelineId,
    base: PipelineId,
    direct: PipelineId,
}

/// Coarse tiles of `COARSE` × `COARSE` screen tiles (glsl/clustered/clusters.glsl), partial
/// ones at the right and bottom edges included.
fn coarse_tiles(config: &Config) -> u32 {
    config.tiles[0].div_ceil(COARSE) * config.tiles[1].div_ceil(COARSE)
}

/// Columns per side of a coarse tile; `COARSE` in glsl/clustered/clusters.glsl.
pub(crate) const COARSE: u32 = 4;

fn cluster_buffer(gpu: &mut Gpu, name: &str, size: u64) -> Result<BufferId> {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
    Ok(gpu.create_buffer(&BufferDesc {
        name: name.into(),
        size: size.max(16),
        usage,
        memory: MemoryKind::GpuOnly,
    })?)
}

impl Clustered {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<Clustered> {
        let config = Config::from_decl(decl, Some(cx.scene))?;
        if cx.scene_gpu.lights.len() > MAX_LIGHTS {
            return Err(Error::Usage(format!(
                "{}: {NAME}: the scene has {} lights; the cluster assignment handles at most {MAX_LIGHTS}",
                cx.scene.source,
                cx.scene_gpu.lights.len()
            )));
        }
        // The GPU scene lists the scene's lights one for one, in order.
        let radii = cx
            .scene
            .lights
            .iter()
            .map(|l| match l {
                Light::Point { radius, .. } | Light::Spot { radius, .. } => *radius,
                _ => 0.0,
            })
            .collect();
        let clusters = config.clusters() as u64;
        let bounds = cluster_buffer(cx.gpu, "clustered bounds", clusters * 32)?;
        let counts = cluster_buffer(cx.gpu, "clustered counts", clusters * 4)?;
        let indices = cluster_buffer(cx.gpu, "clustered indices", config.index_bytes())?;
        let coarse = cluster_buffer(
            cx.gpu,
            "clustered coarse",
            coarse_tiles(&config) as u64 * (MAX_LIGHTS as u64 / 32) * 4,
        )?;
        let compute = |gpu: &mut Gpu, name: &str, shader: &str| {
            gpu.create_compute_pipeline(
                &ComputePipelineDesc {
                    name: name.into(),
                    shader: shader.into(),
                    specialization: vec![],
                },
                cx.shaders,
            )
        };
        let bounds_pipeline = compute(cx.gpu, "clustered bounds", "clustered/bounds.comp")?;
        let coarse_pipeline = compute(cx.gpu, "clustered coarse", "clustered/coarse.comp")?;
        let assign_pipeline = compute(cx.gpu, "clustered assign", "clustered/assign.comp")?;
        let ds_format = cx.gpu.caps().depth_stencil_format;
        let mut pipeline = |terms: Terms| {
            let mut desc = term_pipeline_desc(
                &format!("{NAME} {terms}"),
                "frame/surface.vert",
                "clustered/clustered.frag",
                terms,
                ds_format,
            );
            desc.vertex_layout = vertex_layout();
            cx.gpu.create_graphics_pipeline(&desc, cx.shaders)
        };
        let (both, base, direct) = (
            pipeline(Terms::BASE_DIRECT)?,
            pipeline(Terms::BASE)?,
            pipeline(Terms::DIRECT)?,
        );
        let mut method = Clustered {
            config,
            radii,
            scene_box: scene_box(cx),
            block: ClusterBlock::default(),
            volumes: Vec::new(),
            bounds,
            counts,
            indices,
            coarse,
            bounds_pipeline,
            coarse_pipeline,
            assign_pipeline,
            both,
            base,
            direct,
        };
        // The scene's camera until the first frame says where the camera is.
        let view_proj = cx.scene.camera.view_projection(16.0 / 9.0).to_cols_array();
        method.plan(&view_proj, &cx.scene_gpu.lights, 1280, 720)?;
        Ok(method)
    }

    pub fn config(&self) -> &Config {
        &self.config
    }

    /// The grid and the light volumes for a frame seen through `view_proj` into a `width ×
    /// height` target, with the lights as they are this frame.
    pub fn plan(
        &mut self,
        view_proj: &[f32; 16],
        lights: &[crate::gpu_scene::GpuLight],
        width: u32,
        height: u32,
    ) -> Result<()> {
        let (view, _, _, near) = assign::decompose(view_proj).ok_or_else(|| {
            Error::Usage(format!(
                "{NAME}: the frame's projection is not a perspective with a near plane"
            ))
        })?;
        let far = self
            .scene_box
            .map_or(2.0 * near, |(min, max)| assign::far_depth(&view, min, max) * 1.01);
        let lights_len = lights.len().min(MAX_LIGHTS);
        self.block = assign::block(&self.config, view_proj, width, height, far, lights_len as u32)
            .ok_or_else(|| Error::Usage(format!("{NAME}: degenerate projection")))?;
        self.volumes = assign::light_volumes(&lights[..lights_len], &self.radii, self.config.cutoff, &view);
        Ok(())
    }

    /// The bounds, coarse and assignment passes: they write [`Clustered::counts`] and
    /// [`Clustered::indices`].
    pub fn add_assignment_passes<'a>(&'a self, graph: &mut RenderGraph<'a>) {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let (read, write) = (
            Access::StorageRead { stages: compute },
            Access::StorageWrite { stages: compute },
        );
        let clusters = self.config.clusters();
        let block = bytemuck::bytes_of(&self.block);
        graph
            .pass("clustered bounds")
            .buffer(self.bounds, write, Some("bounds"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(self.bounds_pipeline)?;
                ctx.bind(&[("clusters", Bind::UniformData(block))])?;
                ctx.rec.dispatch([clusters, 1, 1])
            });
        let volumes = self.volume_bytes();
        let coarse = coarse_tiles(&self.config);
        graph
            .pass("clustered coarse")
            .buffer(self.coarse, write, Some("coarse"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(self.coarse_pipeline)?;
                ctx.bind(&[
                    ("clusters", Bind::UniformData(block)),
                    ("volumes", Bind::StorageData(volumes)),
                ])?;
                // One workgroup per coarse tile.
                ctx.rec.dispatch([coarse * ASSIGN_LANES, 1, 1])
            });
        let tiles = self.config.tiles[0] * self.config.tiles[1];
        graph
            .pass("clustered assign")
            .buffer(self.bounds, read, Some("bounds"))
            .buffer(self.coarse, read, Some("coarse"))
            .buffer(self.counts, write, Some("counts"))
            .buffer(self.indices, write, Some("indices"))
            .record(move |ctx| {
                ctx.rec.bind_pipeline(self.assign_pipeline)?;
                ctx.bind(&[
                    ("clusters", Bind::UniformData(block)),
                    ("volumes", Bind::StorageData(volumes)),
                ])?;
                // One workgroup per tile.
                ctx.rec.dispatch([tiles * ASSIGN_LANES, 1, 1])
            });
    }

    fn volume_bytes(&self) -> &[u8] {
        if self.volumes.is_empty() {
            &[0u8; std::mem::size_of::<LightVolume>()]
        } else {
            bytemuck::cast_slice(&self.volumes)
        }
    }

    /// The last frame's assignment, read back (after it finished).
    pub fn read_assignment(&self, gpu: &mut Gpu) -> Result<Assignment> {
        let clusters = self.config.clusters() as usize;
        let counts = read_words(gpu, self.counts)?;
        let indices = read_words(gpu, self.indices)?;
        Ok(Assignment::from_words(
            &counts[..clusters],
            &indices,
            self.config.max_per_cluster,
        ))
    }

    /// The last frame's uncapped light count per cluster, read back (after it finished).
    pub fn read_counts(&self, gpu: &mut Gpu) -> Result<Vec<u32>> {
        let mut counts = read_words(gpu, self.counts)?;
        counts.truncate(self.config.clusters() as usize);
        Ok(counts)
    }
}

/// The line that says a frame dropped light for want of slots, if it did.
pub fn overflow_warning(counts: &[u32], max_per_cluster: u32) -> Option<String> {
    let cap = max_per_cluster;
    let over = assign::overflowed_clusters(counts, cap);
    if over == 0 {
        return None;
    }
    let dropped = assign::dropped(counts, cap);
    let most = counts.iter().max().copied().unwrap_or(0);
    Some(format!(
        "{NAME}: {over} of {} clusters reached more lights than max_per_cluster = {cap} (the fullest {most}): {dropped} light-cluster pairs were dropped, so what those clusters show lacks their light; raise max_per_cluster, give the lights a radius or raise cutoff",
        counts.len()
    ))
}

fn read_words(gpu: &mut Gpu, buffer: BufferId) -> Result<Vec<u32>> {
    let bytes = crate::graph::read_back_buffer(gpu, buffer, NAME)?;
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

impl LightingMethod for Clustered {
    fn name(&self) -> &'static str {
        NAME
    }

    fn warnings(&self, gpu: &mut Gpu) -> Result<Vec<String>> {
        Ok(overflow_warning(&self.read_counts(gpu)?, self.config.max_per_cluster)
            .into_iter()
            .collect())
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        self.plan(
            &frame.uniforms.view_proj,
            &frame.scene.lights,
            frame.targets.width,
            frame.targets.height,
        )
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        let scene = frame.scene;
        let t = frame.targets;
        let uniforms = frame.uniforms;
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let base = frame.terms.has(Term::Base);
        let direct = frame.terms.has(Term::Direct);
        let pipeline = match (base, direct) {
            (true, true) => self.both,
            (true, false) => self.base,
            (false, true) => self.direct,
            (false, false) => return Ok(()),
        };
        if direct {
            self.add_assignment_passes(graph);
        }
        let mut pass = term_pass(graph, if base { NAME } else { "clustered direct" }, t, base);
        pass = pass
            .buffer(scene.vertices, Access::VertexRead, None)
            .buffer(scene.indices, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"));
        if direct {
            pass = pass
                .buffer(self.counts, Access::StorageRead { stages: frag }, Some("counts"))
                .buffer(self.indices, Access::StorageRead { stages: frag }, Some("indices"));
        }
        let volumes = self.volume_bytes();
        let block = bytemuck::bytes_of(&self.block);
        pass.record(move |ctx| {
            let _ = begin_term_rendering(ctx.rec, t, base)?;
            ctx.rec.bind_pipeline(pipeline)?;
            let lights = scene.light_bytes();
            let uniform_bytes = bytemuck::bytes_of(&uniforms);
            let calls: Vec<DrawCall> = scene.draws.iter().map(DrawCall::whole).collect();
            record_draws(ctx, scene, &calls, |ctx, material| {
                let maps = scene.material_maps[material as usize];
                let [albedo, normal, specular] = maps.binds(scene.sampler);
                let mut binds = vec![
                    ("frame", Bind::UniformData(uniform_bytes)),
                    ("lights", Bind::StorageData(lights)),
                    albedo,
                    normal,
                    specular,
                    ("clusters", Bind::UniformData(block)),
                    ("volumes", Bind::StorageData(volumes)),
                ];
                if !direct {
                    // The base alone reads no cluster (the shader's branch is off).
                    binds.extend([
                        ("counts", Bind::StorageData(&[0u8; 16])),
                        ("indices", Bind::StorageData(&[0u8; 16])),
                    ]);
                }
                ctx.bind(&binds)
            })?;
            ctx.rec.end_rendering();
            Ok(())
        });
        Ok(())
    }
}
