//! Per-vertex precomputed radiance transfer baked on the GPU (Staniszewski 2005, digest
//! `seed-002-gpu-sh-transfer.md`): for every vertex the SH coefficients of its shadowed
//! clamped-cosine transfer `T_i = ∫ V(ω) max(0, n·ω) y_i(ω) dω`, so that a distant light of any
//! shape shades it for one dot product, `L_o = ρ/π · Σ T_i L_i`.

pub mod config;
pub mod light;
pub mod mapping;
pub mod raster;
pub mod raycast;
pub mod receivers;
pub mod refine;
pub mod sampling;
pub mod storage;

#[cfg(test)]
mod refine_tests;
#[cfg(test)]
mod tests;

use glam::Vec3;

use crate::backend::{
    vk, Bind, BufferId, ColorTarget, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc, SubresourceRange,
};
use crate::bake::BakeKey;
use crate::error::{Error, Result};
use crate::gpu_scene::{record_draws_from, vertex_layout, DrawCall};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{CreateContext, FrameContext, LightingMethod, ReferenceKind, Term, RADIANCE_FORMAT};
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema};
use crate::util::progress::Progress;
use config::{Baker, Config, Mode};
use receivers::{OccluderRules, Placed, Receivers};

pub const NAME: &str = "prt";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "baker",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "mapping",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "depth",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "weights",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "reduction",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "coverage",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "directions",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "storage",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "tile",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "batch",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "coefficients",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "near",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "far",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "gradient",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "occluders",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "samples",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "env_spin",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "key_rate",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "loop_s",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "max_edge",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "refine_budget",
            kind: ParamKind::Int,
        },
    ],
};

/// The raster baker's own parameters: a declaration that sets one asks for that baker.
const RASTER_PARAMS: [&str; 9] = [
    "mapping",
    "depth",
    "weights",
    "directions",
    "coverage",
    "reduction",
    "tile",
    "batch",
    "gradient",
];

/// Unset in corrected mode, `max_edge` from the scene's smallest object, and `baker` from the
/// scene's size; each said in one line.
pub fn plan(
    decl: &MethodDecl,
    facts: &crate::lighting::plan::Facts<'_>,
) -> Result<Vec<crate::lighting::plan::Derived>> {
    let config = Config::from_decl(decl, Some(facts.scene))?;
    // A scene the light-map geometry cannot take is measured when the method is made instead.
    let Ok(triangles) = facts.triangles(NAME) else {
        return Ok(Vec::new());
    };
    let mut derived: Vec<crate::lighting::plan::Derived> =
        baker_note(decl, &config, triangles.len()).into_iter().collect();
    if decl.param("near").is_none() {
        derived.extend(near_note(facts.bounds(NAME)?));
    }
    if config.max_edge.is_some() {
        return Ok(derived);
    }
    let mut objects: Vec<sampling::Object> = (facts.scene.objects.iter())
        .map(|o| sampling::Object {
            name: o.name.clone(),
            triangles: Vec::new(),
        })
        .collect();
    for t in triangles {
        if let Some(o) = objects.get_mut(t.object) {
            o.triangles.push(t.p.map(|p| p.as_vec3()));
        }
    }
    derived.extend(max_edge_note(&objects, &config));
    Ok(derived)
}

/// The compute ray baker in place of the raster one, when the corrected mode's baker is unset
/// (and none of the raster's own parameters is set) and the scene is so large that drawing every
/// occluder triangle for every vertex outgrows walking a tree with each ray: triangles > 2 ×
/// samples × log2(triangles). The raster's work per vertex grows as the triangles, the rays' as
/// samples × log2(triangles); the factor 2 keeps the document's baker wherever the two are
/// within it (the shipped scenes). A 268k-triangle scene's raster bake ran at 13 vertices/s on
/// lavapipe, hours for its 138k vertices.
fn baker_note(decl: &MethodDecl, config: &Config, triangles: usize) -> Option<crate::lighting::plan::Derived> {
    let raster_asked = decl.param("baker").is_some() || RASTER_PARAMS.iter().any(|p| decl.param(p).is_some());
    if config.mode == Mode::Faithful || raster_asked {
        return None;
    }
    let t = triangles as f64;
    let walk = config.samples as f64 * t.max(2.0).log2();
    (t > 2.0 * walk).then(|| {
        crate::lighting::plan::Derived::new(
            "baker",
            "rays",
            format!(
                "the raster baker would draw all {triangles} triangles for each vertex, over twice the {walk:.0} steps ({} rays × log2 of the triangles) a vertex's rays take through the tree",
                config.samples
            ),
        )
    })
}

/// The visibility rays' `near` where the default 1 mm does not suit the scene's size: a
/// thousandth of the scene under 1 m (1 mm is a third of a 3 mm model, whose every occluder
/// it would skip), and a millionth of it past 1 km (where 1 mm is a few steps of a float's
/// resolution, and a ray would meet the surface it leaves). Between the two, 1 mm stays.
fn near_note(bounds: Option<(glam::DVec3, glam::DVec3)>) -> Option<crate::lighting::plan::Derived> {
    let extent = bounds.map(|(lo, hi)| (hi - lo).max_element())?;
    let near = if extent < 1.0 {
        crate::lighting::plan::round2(1e-3 * extent)
    } else if extent > 1e3 {
        crate::lighting::plan::round2(1e-6 * extent)
    } else {
        return None;
    };
    (near > 0.0).then(|| {
        crate::lighting::plan::Derived::new(
            "near",
            near,
            format!(
                "the scene's {extent:.3e} m extent {}",
                if extent < 1.0 {
                    "over 1,000: the default 1 mm would skip the occluders of a model this small"
                } else {
                    "over a million: 1 mm is too few steps of a float's resolution this far out"
                }
            ),
        )
    })
}

/// The derived `max_edge` and why, `None` where nothing can shadow anything else.
fn max_edge_note(objects: &[sampling::Object], config: &Config) -> Option<crate::lighting::plan::Derived> {
    let (edge, smallest) = sampling::max_edge(objects)?;
    let o = &objects[smallest];
    Some(crate::lighting::plan::Derived::new(
        "max_edge",
        edge,
        format!(
            "half the {:.3} m of object {:?}, the smallest that can cast a shadow; receivers' longer edges are split for the bake, at most {} vertices added",
            o.extent(),
            o.name,
            config.refine_budget
        ),
    ))
}

/// Bumped whenever a baker's output for the same inputs changes.
const BAKER_VERSION: u32 = 4;

/// The transfer models shadowed light from distant sources: the direct reference.
pub fn reference(_decl: &MethodDecl) -> ReferenceKind {
    ReferenceKind::Direct
}

/// The chart's sweep: the declared configuration, on the GPU ray baker (declared, or derived on
/// a large scene) with 256 and 4,096 rays as well, the corrected raster baker under each
/// mapping and at 16² tiles, 4 and 9 coefficients (one bake: the run time truncates), the
/// faithful (document) path, and the ray-cast truth on the CPU.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d, None) {
            let mut label = match c.baker {
                Baker::Raster => format!("prt {:?} {:?} {}² n={}", c.mode, c.mapping, c.tile, c.coefficients),
                _ => format!("prt rays {} n={}", c.samples, c.coefficients),
            }
            .to_lowercase();
            // Clip planes other than the defaults tell two declarations apart.
            let defaults = Config::defaults(c.mode);
            if c.near != defaults.near {
                label += &format!(" near={}", c.near);
            }
            if c.far.is_finite() {
                label += &format!(" far={}", c.far);
            }
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    // Where the rays were chosen, the raster points may not finish within a chart's bake limit:
    // the rays' own cost against error is then what the chart can show.
    if Config::from_decl(decl, None).is_ok_and(|c| c.baker == Baker::Rays) {
        for samples in [256i64, 4096] {
            push(decl.with("samples", samples.into()));
        }
    }
    // The raster baker's variants name it: a large scene's declaration may carry the rays.
    let corrected = decl.with("mode", "corrected".into()).with("baker", "raster".into());
    for m in ["orthographic", "stereographic", "equal_area"] {
        push(corrected.with("mapping", m.into()));
    }
    push(corrected.with("tile", 16i64.into()));
    for n in [4i64, 9] {
        push(corrected.with("coefficients", n.into()));
    }
    // The document bakes the meshes as they are with its raster baker: no derived max_edge or
    // baker.
    push(
        decl.with("mode", "faithful".into())
            .without("max_edge")
            .without("baker"),
    );
    push(corrected.with("baker", "rays_cpu".into()));
    out
}

/// One scene draw the method shades: the object it draws (none for an area light's emitter).
struct DrawInfo {
    object: Option<usize>,
}

/// One scene draw as the bakers see it: the object (none for an area light's emitter, which
/// is drawn with its emission and receives nothing), its placement at time 0, its mesh and its
/// first vertex in the scene's vertex buffer.
pub struct SceneMesh<'a> {
    pub object: Option<usize>,
    pub model: glam::Mat4,
    pub mesh: &'a crate::scene::Mesh,
    pub vertex_offset: u32,
}

/// The meshes the transfer is baked on and drawn with, one per scene draw: the scene's own, or,
/// where receivers' long edges were split ([`refine`]), copies in buffers of the method's own.
struct Geometry {
    /// Per scene draw, when refined.
    refined: Option<Vec<crate::scene::Mesh>>,
    /// Per scene draw: its first vertex and its first index in the buffers drawn.
    offsets: Vec<(u32, u32)>,
    /// The refined vertex and index buffers.
    buffers: Option<(BufferId, BufferId)>,
    vertices: u32,
}

impl Geometry {
    /// The scene's draws as the bakers see them.
    fn meshes<'a>(&'a self, cx: &'a CreateContext<'_>) -> Vec<SceneMesh<'a>> {
        let meshes = self.refined.as_deref().unwrap_or(&cx.scene_gpu.meshes);
        (cx.scene_gpu.draws.iter().zip(meshes).zip(&self.offsets))
            .map(|((d, mesh), &(vertex_offset, _))| SceneMesh {
                object: d.object,
                model: d.model,
                mesh,
                vertex_offset,
            })
            .collect()
    }

    /// One draw call per scene draw, over the buffers drawn.
    fn calls(&self, cx: &CreateContext<'_>) -> Vec<DrawCall> {
        let meshes = self.refined.as_deref().unwrap_or(&cx.scene_gpu.meshes);
        (cx.scene_gpu.draws.iter().zip(meshes).zip(&self.offsets))
            .map(|((d, mesh), &(vertex_offset, first_index))| DrawCall {
                material: d.material,
                model: d.model,
                vertex_offset: vertex_offset as i32,
                ranges: vec![(first_index, mesh.indices.len() as u32)],
            })
            .collect()
    }
}

/// The scene's meshes with every receiver's edges split to `max_edge` (derived from the scene
/// when unset, and said in one line), within the vertex budget; the scene's own where nothing
/// needs splitting.
fn refined_geometry(cx: &mut CreateContext<'_>, config: &Config) -> Result<Geometry> {
    let scene_vertices = cx.scene_gpu.meshes.iter().map(|m| m.vertex_count()).sum::<usize>() as u32;
    let own = Geometry {
        refined: None,
        offsets: (cx.scene_gpu.draws.iter())
            .map(|d| (d.vertex_offset as u32, d.first_index))
            .collect(),
        buffers: None,
        vertices: scene_vertices,
    };
    let max_edge = match config.max_edge {
        Some(e) => e,
        None => {
            let Some(note) = max_edge_note(&sampling_objects(cx, None), config) else {
                return Ok(own);
            };
            for line in crate::lighting::plan::notes(NAME, std::slice::from_ref(&note)) {
                crate::errln!("{line}");
            }
            note.value.as_float().unwrap_or(0.0)
        }
    };
    if max_edge <= 0.0 {
        return Ok(own);
    }
    let draws = &cx.scene_gpu.draws;
    let targets: Vec<refine::Target<'_>> = (draws.iter().zip(&cx.scene_gpu.meshes))
        .map(|(d, mesh)| refine::Target {
            mesh,
            model: d.model,
            // Emitters receive nothing: kept as they are.
            max_edge: if d.object.is_some() {
                max_edge as f32
            } else {
                f32::INFINITY
            },
        })
        .collect();
    let refined = refine::refine(&targets, config.refine_budget);
    if refined.added == 0 {
        return Ok(own);
    }
    if refined.budget_spent {
        crate::errln!(
            "warning: {}: {NAME}: splitting edges to {max_edge} m stopped at the budget of {} added vertices (raise refine_budget, or set a longer max_edge)",
            cx.scene.source,
            config.refine_budget
        );
    }
    let (mut vertices, mut indices, mut offsets) = (Vec::new(), Vec::new(), Vec::new());
    for mesh in &refined.meshes {
        offsets.push((vertices.len() as u32, indices.len() as u32));
        vertices.extend(crate::gpu_scene::vertices_of(mesh));
        indices.extend_from_slice(&mesh.indices);
    }
    let vb = cx.gpu.create_buffer_init(
        "prt refined vertices",
        vk::BufferUsageFlags::VERTEX_BUFFER,
        bytemuck::cast_slice(&vertices),
    )?;
    let ib = cx.gpu.create_buffer_init(
        "prt refined indices",
        vk::BufferUsageFlags::INDEX_BUFFER,
        bytemuck::cast_slice(&indices),
    )?;
    cx.states.forget_buffer(vb);
    cx.states.forget_buffer(ib);
    Ok(Geometry {
        refined: Some(refined.meshes),
        offsets,
        buffers: Some((vb, ib)),
        vertices: vertices.len() as u32,
    })
}

/// The receivers of the scene at animation time `t` (every object's vertices, animated objects
/// where they are at `t`), with each receiver's global vertex index.
pub fn receivers_at(
    scene: &crate::scene::Scene,
    meshes: &[SceneMesh<'_>],
    rules: &OccluderRules,
    t: f32,
) -> Result<(Receivers, Vec<u32>)> {
    let mut placed = Vec::new();
    let mut global = Vec::new();
    for m in meshes {
        let Some(o) = m.object else { continue };
        let model = scene.objects[o]
            .animation
            .map_or(m.model, |a| a.transform_at(m.model, t));
        placed.push(Placed {
            object: o,
            model,
            mesh: m.mesh,
        });
        global.extend((0..m.mesh.vertex_count() as u32).map(|v| m.vertex_offset + v));
    }
    let r = receivers::gather(&placed, rules).map_err(|e| Error::Usage(format!("{}: {NAME}: {e}", scene.source)))?;
    Ok((r, global))
}

/// The SH keys' times: one key for a static scene, `loop_s × key_rate` over the loop otherwise.
pub fn key_times(scene: &crate::scene::Scene, config: &Config) -> Vec<f32> {
    if scene.objects.iter().any(|o| o.animation.is_some()) {
        let keys = ((config.loop_s * config.key_rate).round() as u32).max(1);
        (0..keys).map(|k| (k as f64 / config.key_rate) as f32).collect()
    } else {
        vec![0.0]
    }
}

/// Bakes one of `keys` keys with the configured baker.
pub fn bake_transfer(
    gpu: &mut crate::backend::Gpu,
    shaders: &crate::shaders::ShaderLibrary,
    r: &Receivers,
    config: &Config,
    keys: usize,
    progress: &mut Progress,
) -> Result<Vec<f32>> {
    let clip = receivers::Clip {
        near: config.near,
        far: config.far,
    };
    match config.baker {
        Baker::Raster => raster::bake(gpu, shaders, r, config, progress),
        Baker::Rays => raycast::bake_gpu(gpu, shaders, r, config.bands(), config.samples, clip, progress),
        Baker::RaysCpu => raycast::bake_cpu_of_keys(r, config.bands(), config.samples, clip, keys, progress),
    }
}

/// The scene's objects in world space, for [`sampling`]: as uploaded, or as `meshes` (one per
/// scene draw) when given.
fn sampling_objects(cx: &CreateContext<'_>, meshes: Option<&[crate::scene::Mesh]>) -> Vec<sampling::Object> {
    let meshes = meshes.unwrap_or(&cx.scene_gpu.meshes);
    (cx.scene_gpu.draws.iter().zip(meshes))
        .filter_map(|(d, mesh)| {
            let object = cx.scene.objects.get(d.object?)?;
            let p = |k: u32| d.model.transform_point3(mesh.positions[k as usize]);
            let triangles = mesh
                .indices
                .chunks_exact(3)
                .map(|t| [p(t[0]), p(t[1]), p(t[2])])
                .collect();
            Some(sampling::Object {
                name: object.name.clone(),
                triangles,
            })
        })
        .collect()
}

/// Per-vertex PRT: the base term lit by the scene's distant light.
pub struct Prt {
    config: Config,
    pipeline: PipelineId,
    /// keys × scene vertices × 16 coefficients, fp32 or packed (`storage::pack_for_device`).
    transfer: BufferId,
    /// The transfer's format code and words per key.
    storage: (u32, u32),
    light: Vec<Vec3>,
    keys: u32,
    vertices: u32,
    /// The refined vertex and index buffers, when the receivers' edges were split.
    buffers: Option<(BufferId, BufferId)>,
    draws: Vec<DrawInfo>,
    animation: Vec<Option<crate::scene::Animation>>,
    /// This frame's draws and light block.
    calls: Vec<DrawCall>,
    uniform: Vec<f32>,
}

/// The warnings a configuration and scene earn before the bake: inert parameters, a coefficient
/// count that is not whole bands, distant lights only, surfaces behind their normals.
fn warn_about_config(cx: &CreateContext<'_>, decl: &MethodDecl, config: &Config) {
    for w in crate::lighting::params::Params::new(decl, Some(cx.scene)).inert_warnings(&config.inert()) {
        crate::errln!("{w}");
    }
    if config.legacy_coefficients() {
        crate::errln!(
            "warning: {}: {NAME}: {} coefficients is not a whole number of bands: shading changes as the light turns about a normal (digest §3.2 item 7)",
            cx.scene.source,
            config.coefficients
        );
    }
    if let Some(w) = crate::lighting::distant_only_warning(cx.scene, NAME) {
        crate::errln!("{w}");
    }
    // The transfer is baked per vertex on the normal's side (a scene the light-map geometry
    // cannot take, with a sphere light, goes without the check).
    if let Ok(g) = crate::lighting::lightmap::geometry::static_geometry(cx.scene, cx.scene_gpu, NAME) {
        if let Some(w) = crate::lighting::lightmap::geometry::behind_warning(cx.scene, &g.triangles, NAME) {
            crate::errln!("{w}");
        }
    }
}

/// What the baked transfer depends on: the baker and its configuration, the occluder rules,
/// the keys, the meshes, their placements and animation, and the shaders.
fn bake_key(
    cx: &CreateContext<'_>,
    meshes: &[SceneMesh<'_>],
    config: &Config,
    rules: &OccluderRules,
    keys: u32,
) -> BakeKey {
    let key = BakeKey::new("PRT transfer")
        .with("version", BAKER_VERSION)
        .with("config", config.bake_key())
        .with("occluders", rules)
        .with("keys", (keys, config.key_rate));
    let geometry: Vec<f32> = (meshes.iter())
        .flat_map(|m| {
            m.mesh
                .positions
                .iter()
                .chain(&m.mesh.normals)
                .flat_map(|p| p.to_array())
        })
        .chain(meshes.iter().flat_map(|m| m.mesh.indices.iter().map(|&i| i as f32)))
        .collect();
    let placements: Vec<f32> = cx
        .scene_gpu
        .draws
        .iter()
        .flat_map(|d| d.model.to_cols_array())
        .collect();
    key.with_bytes("geometry", bytemuck::cast_slice(&geometry))
        .with_bytes("placements", bytemuck::cast_slice(&placements))
        .with(
            "animation",
            cx.scene.objects.iter().map(|o| o.animation).collect::<Vec<_>>(),
        )
        .with_shaders("prt/")
}

/// The label that names the cache entry: only what the bake depends on (not the run-time
/// coefficient count, which every count's configuration shares).
fn bake_label(config: &Config, receivers: usize, keys: u32) -> String {
    let baker = match config.baker {
        Baker::Raster => format!("raster {:?} {:?} {}²", config.mode, config.mapping, config.tile),
        _ => format!("{:?} {} rays", config.baker, config.samples),
    };
    format!(
        "{NAME} {baker} ({receivers} vertices{})",
        if keys > 1 {
            format!(" × {keys} keys")
        } else {
            String::new()
        }
    )
}

/// The baked transfer (per key, per receiver) placed at each receiver's scene vertex, 16 floats
/// a vertex; an error when the bake does not match the scene (a stale cache entry).
fn transfer_by_vertex(
    cx: &CreateContext<'_>,
    config: &Config,
    baked: &[f32],
    all_keys: &[(Receivers, Vec<u32>)],
    vertices: u32,
) -> Result<Vec<f32>> {
    let dim = config.bands() * config.bands();
    let keys = all_keys.len();
    let per_key = all_keys[0].0.len() * dim;
    if baked.len() != per_key * keys {
        return Err(Error::Internal(format!(
            "{}: {NAME}: the baked transfer does not match the scene (delete the cache entry)",
            cx.scene.source
        )));
    }
    let mut transfer = vec![0.0f32; keys * vertices as usize * 16];
    for (k, (_, global)) in all_keys.iter().enumerate() {
        for (i, &g) in global.iter().enumerate() {
            let src = &baked[k * per_key + i * dim..k * per_key + (i + 1) * dim];
            let dst = (k * vertices as usize + g as usize) * 16;
            transfer[dst..dst + dim].copy_from_slice(src);
        }
    }
    Ok(transfer)
}

impl Prt {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<Prt> {
        let config = Config::from_decl(decl, Some(cx.scene))?;
        warn_about_config(cx, decl, &config);
        let rules = OccluderRules::parse(&config.occluders, cx.scene)
            .map_err(|m| Error::from(cx.scene.method_param_error(decl, "occluders", m)))?;
        let times = key_times(cx.scene, &config);
        let keys = times.len() as u32;
        let geometry = refined_geometry(cx, &config)?;
        for line in sampling::undersampled(&sampling_objects(cx, geometry.refined.as_deref())) {
            crate::errln!("warning: {}: {NAME}: {line}", cx.scene.source);
        }
        let vertices = geometry.vertices;
        let meshes = geometry.meshes(cx);
        let key = bake_key(cx, &meshes, &config, &rules, keys);
        let all_keys: Vec<(Receivers, Vec<u32>)> = times
            .iter()
            .map(|&t| receivers_at(cx.scene, &meshes, &rules, t))
            .collect::<Result<_>>()?;
        let receivers = all_keys[0].0.len();
        if receivers == 0 {
            return Err(Error::Usage(format!(
                "{}: {NAME}: the scene has no object whose vertices could carry a transfer",
                cx.scene.source
            )));
        }
        let label = bake_label(&config, receivers, keys);
        let (gpu, shaders) = (&mut *cx.gpu, cx.shaders);
        let baked: Vec<f32> = cx.bakes.bake(&label, &key, |progress| {
            let mut out = Vec::new();
            for (r, _) in &all_keys {
                out.extend(bake_transfer(gpu, shaders, r, &config, all_keys.len(), progress)?);
            }
            Ok(out)
        })?;
        let transfer = transfer_by_vertex(cx, &config, &baked, &all_keys, vertices)?;
        // Packed over the scene's vertices, so a by-band group is four neighbouring vertices.
        let (words, words_per_key) =
            storage::pack_for_device(&transfer, keys as usize, vertices as usize, config.storage.grouping());
        let transfer = cx.gpu.create_buffer_init(
            "prt transfer",
            vk::BufferUsageFlags::STORAGE_BUFFER,
            bytemuck::cast_slice(&words),
        )?;
        let storage = (config.storage.device_format(), words_per_key as u32);
        cx.states.forget_buffer(transfer);
        let light = light::project(cx.scene, cx.environment, 4)?;

        let mut desc = GraphicsPipelineDesc::new("prt", "prt/shade.vert", Some("prt/shade.frag"));
        desc.vertex_layout = vertex_layout();
        desc.raster.cull = vk::CullModeFlags::NONE;
        desc.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        desc.depth_format = Some(cx.gpu.caps().depth_stencil_format);
        let pipeline = cx.gpu.create_graphics_pipeline(&desc, cx.shaders)?;
        let draws = cx
            .scene_gpu
            .draws
            .iter()
            .map(|d| DrawInfo { object: d.object })
            .collect();
        let animation = cx.scene.objects.iter().map(|o| o.animation).collect();
        let calls = geometry.calls(cx);
        let uniform = light::uniform(&light, config.coefficients, (0, 0, 0.0), vertices, storage);
        Ok(Prt {
            config,
            pipeline,
            transfer,
            storage,
            light,
            keys,
            vertices,
            buffers: geometry.buffers,
            draws,
            animation,
            calls,
            uniform,
        })
    }

    /// The keys bound at time `t` and the blend between them.
    pub fn keys_at(&self, t: f64) -> (u32, u32, f32) {
        key_blend(t, self.keys, self.config.key_rate)
    }
}

/// Two SH keys and the weight of the second at time `t` on a loop of `keys` keys at `rate`.
pub fn key_blend(t: f64, keys: u32, rate: f64) -> (u32, u32, f32) {
    if keys <= 1 {
        return (0, 0, 0.0);
    }
    let x = (t * rate).rem_euclid(keys as f64);
    let a = (x.floor() as u32).min(keys - 1);
    (a, (a + 1) % keys, (x - a as f64) as f32)
}

impl LightingMethod for Prt {
    fn name(&self) -> &'static str {
        NAME
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        let t = frame.clock.time_s;
        let light = if self.config.env_spin != 0.0 {
            light::rotate(&self.light, (self.config.env_spin * t as f64).to_radians())?
        } else {
            self.light.clone()
        };
        self.uniform = light::uniform(
            &light,
            self.config.coefficients,
            self.keys_at(t as f64),
            self.vertices,
            self.storage,
        );
        for (call, (d, item)) in self.calls.iter_mut().zip(self.draws.iter().zip(&frame.scene.draws)) {
            let anim = d.object.and_then(|o| self.animation.get(o).copied().flatten());
            call.model = anim.map_or(item.model, |a| a.transform_at(item.model, t));
        }
        Ok(())
    }

    /// The transfer buffer: 64 bytes a vertex a key in fp32, 20 with a shared exponent.
    fn memory(&self, gpu: &crate::backend::Gpu) -> Result<Vec<crate::lighting::MemoryItem>> {
        let mut items = vec![crate::lighting::MemoryItem {
            method: NAME,
            resource: format!(
                "{NAME} transfer ({} keys x {} vertices, {:?})",
                self.keys, self.vertices, self.config.storage
            ),
            requested: gpu.buffer_desc(self.transfer)?.size,
            allocated: gpu.buffer_memory(self.transfer)?,
        }];
        if let Some((vertices, indices)) = self.buffers {
            for (buffer, what) in [(vertices, "vertices"), (indices, "indices")] {
                items.push(crate::lighting::MemoryItem {
                    method: NAME,
                    resource: format!("{NAME} refined {what} ({} vertices)", self.vertices),
                    requested: gpu.buffer_desc(buffer)?.size,
                    allocated: gpu.buffer_memory(buffer)?,
                });
            }
        }
        Ok(items)
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        if !frame.terms.has(Term::Base) {
            return Ok(());
        }
        let (scene, t, uniforms) = (frame.scene, frame.targets, frame.uniforms);
        let (vert, frag) = (
            vk::PipelineStageFlags2::VERTEX_SHADER,
            vk::PipelineStageFlags2::FRAGMENT_SHADER,
        );
        let buffers = self.buffers.unwrap_or((scene.vertices, scene.indices));
        graph
            .pass("prt")
            .color_attachment(t.radiance, SubresourceRange::mip(0), false)
            .depth_stencil_write(t.depth_stencil, false)
            .buffer(buffers.0, Access::VertexRead, None)
            .buffer(buffers.1, Access::IndexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .buffer(self.transfer, Access::StorageRead { stages: vert }, Some("transfer"))
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc {
                    colors: vec![RenderTarget::load(t.radiance)],
                    depth_stencil: Some(RenderTarget::load(t.depth_stencil)),
                })?;
                ctx.rec.bind_pipeline(self.pipeline)?;
                let uniform_bytes = bytemuck::bytes_of(&uniforms);
                let light: &[u8] = bytemuck::cast_slice(&self.uniform);
                record_draws_from(ctx, buffers, &self.calls, |ctx, material| {
                    let maps = scene.material_maps[material as usize];
                    ctx.bind(&[
                        ("frame", Bind::UniformData(uniform_bytes)),
                        ("light", Bind::StorageData(light)),
                        (
                            "albedo_map",
                            Bind::Sampled {
                                image: maps.albedo,
                                range: SubresourceRange::mip(0),
                                sampler: scene.sampler,
                            },
                        ),
                    ])
                })?;
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }
}
