//! Dynamic per-pixel Phong lighting with robust stenciled shadow volumes over a BSP/PVS world:
//! the Ca3D-Engine thesis §4 and §6.3 (digest §1.3, §1.4, §4.4, §4.5).
//!
//! A frame is
//! 1. **silhouettes** (compute): per light, for each casting entity, the silhouette edges from
//!    edge adjacency, extruded to infinity, with caps (open meshes cast from both sides: every
//!    triangle capped, sides where the turned triangles' windings do not cancel), compacted into
//!    three indirect draws — [`volumes::silhouette_volume`] is its CPU mirror; an entity none of
//!    whose triangles meets the light's near-clip volume (`near_clip.rs`) gets no caps and
//!    counts by z-pass;
//! 2. **ambient**: depth, and the ambient/emissive term of Eq. 5 (`diffuse·lightmap·N_z +
//!    luminance`; the physical mode writes the emission only);
//! 3. per light: **volumes** — stencil cleared, then every caster's volume with two-sided
//!    wrapping stencil ops, colour writes off, depth test on, no depth writes, z-fail (z-pass
//!    for the entities above, or everywhere for comparison), the far caps at infinity (w = 0)
//!    kept by depth clamp where the device has it and by the infinite projection otherwise;
//!    then **lighting** — the light's receivers drawn again, added where the stencil is 0;
//!    lights whose receivers are everything in view instead leave a bit in the frame's light
//!    mask, and one pass over the receivers per group of up to 96 adds each where its bit is set
//!    (`grouped.rs`: on a large mesh a light pass costs its vertices, not its pixels);
//! 4. when translucent entities (material opacity < 1) are in view, the seed's compromise: they
//!    were left out of 2–3 (neither lit nor casting, so light shines through them), and now are
//!    drawn back to front over the image with depth writes (**translucent ambient**), then per
//!    light the opaque casters' volumes again and the light times the opacity, which the depth
//!    test lets reach the nearest translucent layer only.
//!
//! World casters are the back-facing faces (light behind their plane) of the caster strategy
//! ([`config::Casters`]: every face, the light's PVS, or the PVS with the Potential
//! Shadow-Casters Set), each with its own closed volume ([`volumes::polygon_volume_template`],
//! extruded in the vertex shader). Receivers and casters are culled by the light's radius and
//! the camera's PVS (`plan`). Lighting is the seed's Eq. 5 (*faithful*) or radiometric
//! (*physical*), in both of the seed's material paths: special-case pipelines per map
//! combination, or one pipeline with 1×1 default maps. Spot lights (not in the seed) are point
//! lights times the forward method's cone falloff, with a point light's volumes. Directional
//! lights (not in the seed either) extrude entity volumes along their direction, to one point at
//! infinity ([`VolumeLight::homogeneous`]); a BSP world refuses them.

pub(crate) mod config;
pub mod cpu;
mod frame_passes;
mod grouped;
pub mod maps;
pub(crate) mod near_clip;
pub(crate) mod plan;
mod tally;
pub mod volumes;

use std::rc::Rc;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};

use crate::backend::{
    vk, Bind, BlendMode, BufferDesc, BufferId, ColorTarget, ComputePipelineDesc, DepthState, Gpu, GraphicsPipelineDesc,
    ImageDesc, ImageId, MemoryKind, PipelineId, SpecConstant, StencilFace, StencilFaces, VertexAttribute, VertexLayout,
};
use crate::error::{Error, Result};
use crate::gpu_scene::{record_draws, vertex_layout, DrawCall, SceneGpu, LIGHT_DIRECTIONAL, LIGHT_POINT, LIGHT_SPOT};
use crate::graph::{Access, RenderGraph};
use crate::lighting::{CreateContext, FrameContext, LightingMethod, Term, RADIANCE_FORMAT};
use crate::scene::world_mesh::{self, WorldLevel};
use crate::scene::{Light, MeshSource, MethodDecl, Scene};
use crate::shaders::ShaderLibrary;
use crate::world::FaceId;

pub use config::{Casters, Config, MaterialPath, Mode, Stencil, NAME, SCHEMA};
pub use plan::{Entity, FramePlan, LightPlan, LightWorldSets, Spot, VolumeLight, WorldFrame};

/// The chart's sweep (see `config::sweep`).
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    config::sweep(decl)
}

/// Everything the method derives from the scene on the CPU: configuration, the world (if the
/// scene has one), entities, lights and each light's static world sets. Tests build it without
/// a GPU to check what the passes will draw.
pub struct Setup {
    pub config: Config,
    pub world: Option<WorldFrame>,
    /// Scene object indices of the world's class objects.
    pub world_objects: Vec<usize>,
    pub entities: Vec<Entity>,
    pub lights: Vec<VolumeLight>,
    pub sets: Vec<LightWorldSets>,
}

impl Setup {
    /// The setup of a scene on the CPU alone (tests, tools): meshes are loaded from the scene.
    pub fn new(scene: &Scene, decl: &MethodDecl) -> Result<Setup> {
        let meshes = scene
            .objects
            .iter()
            .map(|o| o.load_mesh(std::path::Path::new(".")))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        Setup::with_meshes(scene, &meshes, decl)
    }

    /// `meshes`: each scene object's object-space mesh, as uploaded (`SceneGpu::meshes`).
    pub fn with_meshes(scene: &Scene, meshes: &[crate::scene::Mesh], decl: &MethodDecl) -> Result<Setup> {
        let config = Config::from_decl(decl, scene)?;
        let lights = method_lights(scene)?;
        let mut level: Option<(WorldLevel, Vec3)> = None;
        let mut world_objects = Vec::new();
        let mut entities = Vec::new();
        for (i, obj) in scene.objects.iter().enumerate() {
            let opacity = scene.material_of(obj).map_or(1.0, |m| m.opacity);
            if let MeshSource::World { level: l, .. } = &obj.mesh {
                if opacity < 1.0 {
                    // The BSP, its PVS and the PSCS are compiled from the world's faces as solid
                    // walls, so a translucent world face would still hide what is behind it.
                    return Err(Error::Usage(format!(
                        "{}: objects[{i}] ({}): material {:?}.opacity = {opacity}: the {NAME} method draws translucent entities only; the BSP world is opaque (its PVS treats every face as a wall), so make the glass a separate object",
                        scene.source,
                        obj.name,
                        scene.materials[obj.material].name
                    )));
                }
                let translate = obj.transform.w_axis.truncate();
                match &level {
                    Some((other, t)) if other != l || *t != translate => {
                        return Err(Error::Usage(format!(
                            "{}: objects[{i}] ({}): the {NAME} method supports one BSP world per scene",
                            scene.source, obj.name
                        )));
                    }
                    _ => level = Some((l.clone(), translate)),
                }
                world_objects.push(i);
                continue;
            }
            let mesh = meshes
                .get(i)
                .ok_or_else(|| Error::Internal(format!("{}: objects[{i}]: no uploaded mesh", scene.source)))?;
            let topology = volumes::Topology::new(mesh);
            entities.push(Entity {
                draw: i,
                name: obj.name.clone(),
                bounds: mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO)),
                topology,
                base: obj.transform,
                animation: obj.animation,
                opacity,
            });
        }
        if level.is_some() {
            if let Some((i, l)) = lights.iter().enumerate().find(|(_, l)| l.toward.is_some()) {
                return Err(Error::Usage(format!(
                    "{}: lights[{i}] ({}): the {NAME} method lights a BSP world with point and spot lights only: its caster selection (the light's PVS and PSCS) starts from the light's position, which a directional light does not have",
                    scene.source, l.name
                )));
            }
        }
        let world = match level {
            None => None,
            Some((l, translate)) => {
                let compiled = world_mesh::compiled(&l).map_err(|e| {
                    Error::Usage(format!(
                        "{}: {}: the world does not compile: {e}",
                        scene.source,
                        l.mesh_name()
                    ))
                })?;
                Some(WorldFrame {
                    world: compiled,
                    translate,
                })
            }
        };
        let sets = match &world {
            Some(w) => lights.iter().map(|l| plan::light_world_sets(&config, w, l)).collect(),
            None => vec![LightWorldSets::default(); lights.len()],
        };
        Ok(Setup {
            config,
            world,
            world_objects,
            entities,
            lights,
            sets,
        })
    }

    /// The frame plan for an eye at `camera` (scene space) at animation time `t`.
    pub fn plan(&self, camera: Vec3, t: f32) -> FramePlan {
        plan::plan_frame(
            &self.config,
            self.world.as_ref(),
            &self.sets,
            &self.lights,
            &self.entities,
            camera,
            t,
        )
    }
}

/// The scene's lights as the method takes them, in scene order; any other kind is refused in
/// one line naming the light and why.
fn method_lights(scene: &Scene) -> Result<Vec<VolumeLight>> {
    let mut lights = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        let light = |position, intensity, radius, spot, toward| VolumeLight {
            name: l.name().to_string(),
            position,
            intensity,
            radius,
            spot,
            toward,
        };
        let why = match l {
            Light::Point {
                position,
                intensity,
                radius,
                ..
            } => {
                lights.push(light(*position, *intensity, *radius, None, None));
                continue;
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_deg,
                outer_deg,
                radius,
                ..
            } => {
                // The same cosines as the forward method's lights (renderer::raster_lights).
                let spot = Spot {
                    direction: direction.normalize(),
                    cos_inner: inner_deg.to_radians().cos(),
                    cos_outer: outer_deg.to_radians().cos(),
                };
                lights.push(light(*position, *intensity, *radius, Some(spot), None));
                continue;
            }
            Light::Directional {
                direction, irradiance, ..
            } => {
                lights.push(light(Vec3::ZERO, *irradiance, 0.0, None, Some(-direction.normalize())));
                continue;
            }
            Light::Sphere { .. } => {
                "a sphere light is an area light, whose soft shadows one stencil volume cannot represent"
            }
            Light::Quad { .. } => {
                "a quad light is an area light, whose soft shadows one stencil volume cannot represent"
            }
        };
        return Err(Error::Usage(format!(
            "{}: lights[{i}] ({}): the {NAME} method lights with point, spot and directional lights only: {why}",
            scene.source,
            l.name()
        )));
    }
    Ok(lights)
}

/// `LightBlock` in glsl/shadow_volumes/surface.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct LightBlock {
    /// xyz: the position, w: the radius; a directional light's unit vector toward it, w 0.
    position: [f32; 4],
    colour: [f32; 4],
    /// xyz: a spot light's unit axis; w: the light's kind, numbered as the scene's lights are
    /// (`LIGHT_POINT`, `LIGHT_SPOT`, `LIGHT_DIRECTIONAL`).
    spot_direction: [f32; 4],
    /// x: cos(inner), y: cos(outer).
    cone: [f32; 4],
}

/// `Volume` push constants of glsl/shadow_volumes/volume.vert.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct VolumePush {
    light: [f32; 4],
    nudge_far: u32,
}

/// `Entity` push constants of glsl/shadow_volumes/silhouette.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SilhouettePush {
    model: [f32; 16],
    vertex_offset: u32,
    triangle_offset: u32,
    triangle_count: u32,
    edge_offset: u32,
    edge_count: u32,
    caps_base: u32,
    closed: u32,
    edges_phase: u32,
    near_test: u32,
    index: u32,
}

/// The silhouette pass's command words: three `VkDrawIndirectCommand`.
const SILHOUETTE_COMMAND_WORDS: usize = 12;

/// Where one entity's data lives in the silhouette buffers.
#[derive(Clone, Copy, Debug)]
struct EntitySlots {
    vertex_offset: u32,
    triangle_offset: u32,
    edge_offset: u32,
}

struct SilhouetteBuffers {
    positions: BufferId,
    triangles: BufferId,
    edges: BufferId,
    /// One light's volumes, compacted: the sides from vertex 0, the caps from `caps_base`.
    volumes: BufferId,
    /// The indirect draws whose vertex counts the silhouette pass counts up (sides for z-fail,
    /// caps, sides for z-pass).
    commands: BufferId,
    /// Per entity, whether one of its volumes may reach the near plane (z-fail).
    near: BufferId,
    /// Per round (opaque, translucent) and light, a copy of its `commands` once drawn: what
    /// `frame_notes` reports.
    tally: BufferId,
    /// Each triangle's facing for the light: the triangles' dispatch writes it, the edges' read it.
    facings: BufferId,
    /// Room for every entity's sides at most: where the caps start.
    caps_base: u32,
    slots: Vec<EntitySlots>,
}

/// Where a world face is drawn from: its class object's draw and index range, and its volume
/// template's vertex range.
#[derive(Clone, Copy, Debug, Default)]
struct FaceDraw {
    draw: usize,
    first_index: u32,
    index_count: u32,
    template_first: u32,
    template_count: u32,
}

/// Per material: which special-case pipeline draws it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Features {
    normal_map: bool,
    specular: bool,
}

pub struct ShadowVolumes {
    setup: Setup,
    faces: Vec<FaceDraw>,
    templates: Option<BufferId>,
    silhouettes: Option<SilhouetteBuffers>,
    features: Vec<Features>,
    /// Ambient pipelines by normal map; light pipelines by (normal map, specular).
    ambient: [PipelineId; 2],
    translucent_ambient: [PipelineId; 2],
    light: [[PipelineId; 2]; 2],
    volume: PipelineId,
    /// `stencil = "auto"`: z-pass for a light whose entity volumes miss the near plane.
    volume_zpass: Option<PipelineId>,
    silhouette: PipelineId,
    /// The grouped path's pipelines (`group_lights`, and more than one light).
    group: Option<grouped::GroupPipelines>,
    nudge_far: bool,
    /// The exact flat normal (0.5, 0.5, 1) in RGBA32F for the default-map path (8-bit 128 is
    /// not 0.5).
    default_normal: ImageId,
    /// This frame's plan, made by `prepare`.
    plan: Option<Rc<FramePlan>>,
}

fn spec(id: u32, bits: u32) -> SpecConstant {
    SpecConstant { id, bits }
}
/// The surface pipelines as [`ShadowVolumes`] holds them: ambient (plain, normal-mapped),
/// translucent ambient (the same, blended), and light (by normal map, then specular), the last
/// lighting only where the stencil is clear.
#[allow(clippy::type_complexity)]
fn surface_pipelines(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    c: &Config,
) -> Result<([PipelineId; 2], [PipelineId; 2], [[PipelineId; 2]; 2])> {
    let ds_format = gpu.caps().depth_stencil_format;
    let mode = match c.mode {
        Mode::Faithful => 0,
        Mode::Physical => 1,
    };
    let surface = |name: &str, frag: &str, specs: Vec<SpecConstant>| {
        let mut d = GraphicsPipelineDesc::new(name, "shadow_volumes/surface.vert", Some(frag));
        d.vertex_layout = vertex_layout();
        d.raster.cull = vk::CullModeFlags::NONE;
        d.color_targets = vec![ColorTarget::new(RADIANCE_FORMAT)];
        d.depth_format = Some(ds_format);
        d.specialization = specs;
        d
    };
    let mut ambient = Vec::with_capacity(2);
    for nm in [false, true] {
        let d = surface(
            &format!("{NAME} ambient{}", if nm { " normal-mapped" } else { "" }),
            "shadow_volumes/ambient.frag",
            vec![spec(0, mode), spec(1, nm as u32), spec(3, c.ambient_nz as u32)],
        );
        ambient.push(gpu.create_graphics_pipeline(&d, shaders)?);
    }
    let mut light = Vec::with_capacity(4);
    for nm in [false, true] {
        for sp in [false, true] {
            let mut d = surface(
                &format!(
                    "{NAME} light{}{}",
                    if nm { " normal-mapped" } else { "" },
                    if sp { " specular" } else { "" }
                ),
                "shadow_volumes/light.frag",
                vec![spec(0, mode), spec(1, nm as u32), spec(2, sp as u32), spec(4, c.atten)],
            );
            d.depth = DepthState {
                test: true,
                write: false,
                compare: vk::CompareOp::LESS_OR_EQUAL,
            };
            d.color_targets[0].blend = BlendMode::Additive;
            d.stencil = Some(outside_every_volume());
            light.push(gpu.create_graphics_pipeline(&d, shaders)?);
        }
    }
    // The translucent path's ambient pass: `α·surface + (1 − α)·behind` over the opaque
    // image, with depth writes so the light passes after it find the nearest layer only.
    let mut translucent_ambient = Vec::with_capacity(2);
    for nm in [false, true] {
        let mut d = surface(
            &format!("{NAME} translucent ambient{}", if nm { " normal-mapped" } else { "" }),
            "shadow_volumes/ambient.frag",
            vec![spec(0, mode), spec(1, nm as u32), spec(3, c.ambient_nz as u32)],
        );
        d.color_targets[0].blend = BlendMode::Alpha;
        translucent_ambient.push(gpu.create_graphics_pipeline(&d, shaders)?);
    }
    Ok((
        [ambient[0], ambient[1]],
        [translucent_ambient[0], translucent_ambient[1]],
        [[light[0], light[1]], [light[2], light[3]]],
    ))
}

/// The stencil test of the light passes: a count of 0 is outside every volume of the light.
fn outside_every_volume() -> StencilFaces {
    let outside = StencilFace {
        compare_mask: 0xff,
        write_mask: 0,
        ..StencilFace::test(vk::CompareOp::EQUAL, 0)
    };
    StencilFaces {
        front: outside,
        back: outside,
    }
}

/// The stencil-volume pipelines for the configured counting (z-fail or z-pass, wrapping or
/// clamping; `auto` gets a z-pass one beside the z-fail one), and whether they clamp depth (the
/// device allowing) instead of nudging the far caps.
fn volume_pipelines(
    gpu: &mut Gpu,
    shaders: &ShaderLibrary,
    c: &Config,
) -> Result<(PipelineId, Option<PipelineId>, bool)> {
    let (volume, depth_clamp) = volume_pipeline(gpu, shaders, c, c.stencil == Stencil::ZPass)?;
    let zpass = match c.stencil {
        Stencil::Auto => Some(volume_pipeline(gpu, shaders, c, true)?.0),
        Stencil::ZFail | Stencil::ZPass => None,
    };
    Ok((volume, zpass, depth_clamp))
}

/// One stencil-volume pipeline, counting by z-pass or z-fail.
fn volume_pipeline(gpu: &mut Gpu, shaders: &ShaderLibrary, c: &Config, zpass: bool) -> Result<(PipelineId, bool)> {
    let ds_format = gpu.caps().depth_stencil_format;
    let (inc, dec) = if c.stencil_wrap {
        (vk::StencilOp::INCREMENT_AND_WRAP, vk::StencilOp::DECREMENT_AND_WRAP)
    } else {
        (vk::StencilOp::INCREMENT_AND_CLAMP, vk::StencilOp::DECREMENT_AND_CLAMP)
    };
    let count = |pass: vk::StencilOp, depth_fail: vk::StencilOp| StencilFace {
        pass,
        depth_fail,
        ..StencilFace::test(vk::CompareOp::ALWAYS, 0)
    };
    let keep = vk::StencilOp::KEEP;
    // Outward-facing volumes: z-fail counts +1 for back faces and −1 for front faces behind
    // the surface; z-pass +1 for front faces and −1 for back faces in front of it.
    let faces = if zpass {
        StencilFaces {
            front: count(inc, keep),
            back: count(dec, keep),
        }
    } else {
        StencilFaces {
            front: count(keep, dec),
            back: count(keep, inc),
        }
    };
    let depth_clamp = c.depth_clamp && gpu.caps().depth_clamp;
    let name = format!("{NAME} volumes{}", if zpass { " (z-pass)" } else { "" });
    let mut vd = GraphicsPipelineDesc::new(&name, "shadow_volumes/volume.vert", None);
    vd.vertex_layout = VertexLayout {
        buffers: vec![(0, 16)],
        attributes: vec![VertexAttribute {
            location: 0,
            binding: 0,
            format: vk::Format::R32G32B32A32_SFLOAT,
            offset: 0,
        }],
    };
    vd.raster.cull = vk::CullModeFlags::NONE;
    vd.raster.depth_clamp = depth_clamp;
    vd.depth = DepthState {
        test: true,
        write: false,
        compare: vk::CompareOp::LESS,
    };
    vd.stencil = Some(faces);
    vd.depth_format = Some(ds_format);
    let volume = gpu.create_graphics_pipeline(&vd, shaders)?;
    Ok((volume, depth_clamp))
}

impl ShadowVolumes {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<ShadowVolumes> {
        let (gpu, shaders, scene) = (&mut *cx.gpu, cx.shaders, cx.scene);
        let setup = Setup::with_meshes(scene, &cx.scene_gpu.meshes, decl)?;
        if cx.terms != crate::lighting::Terms::BASE_DIRECT {
            if let Some(e) = setup.entities.iter().find(|e| e.opacity < 1.0) {
                return Err(Error::Usage(format!(
                    "{}: {} ({}): the {NAME} method draws translucent entities only when it supplies both the base and the direct term (it supplies {})",
                    scene.source, e.name, "translucent", cx.terms
                )));
            }
        }
        let c = &setup.config;
        let (ambient, translucent_ambient, light) = surface_pipelines(gpu, shaders, c)?;
        let (volume, volume_zpass, depth_clamp) = volume_pipelines(gpu, shaders, c)?;
        let silhouette = gpu.create_compute_pipeline(
            &ComputePipelineDesc {
                name: format!("{NAME} silhouettes"),
                shader: "shadow_volumes/silhouette.comp".into(),
                specialization: Vec::new(),
            },
            shaders,
        )?;

        let group = match c.group_lights && setup.lights.len() > 1 {
            true => Some(grouped::GroupPipelines::new(gpu, shaders, c)?),
            false => None,
        };
        let features = scene
            .materials
            .iter()
            .map(|m| Features {
                normal_map: m.normal_map.is_some(),
                specular: m.specular.max_element() > 0.0,
            })
            .collect();
        let (faces, templates) = Self::world_geometry(gpu, scene, cx.scene_gpu, &setup)?;
        let silhouettes = Self::silhouette_buffers(gpu, &setup)?;
        let default_normal = gpu.create_image(
            &ImageDesc::new_2d("flat normal (exact)", vk::Format::R32G32B32A32_SFLOAT, 1, 1)
                .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
        )?;
        gpu.upload_image(default_normal, 0, bytemuck::cast_slice(&[0.5f32, 0.5, 1.0, 1.0]))?;
        cx.states.set_image(
            gpu,
            default_normal,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )?;
        Ok(ShadowVolumes {
            setup,
            faces,
            templates,
            silhouettes,
            features,
            ambient,
            translucent_ambient,
            light,
            volume,
            volume_zpass,
            silhouette,
            group,
            nudge_far: !depth_clamp,
            default_normal,
            plan: None,
        })
    }

    pub fn setup(&self) -> &Setup {
        &self.setup
    }

    /// The plan of the last frame prepared.
    pub fn last_plan(&self) -> Option<FramePlan> {
        self.plan.as_deref().cloned()
    }

    /// Per world face: its draw and index range (the class meshes are built as in the scene),
    /// and the volume templates of every face in one vertex buffer.
    fn world_geometry(
        gpu: &mut Gpu,
        scene: &Scene,
        scene_gpu: &SceneGpu,
        setup: &Setup,
    ) -> Result<(Vec<FaceDraw>, Option<BufferId>)> {
        let Some(frame) = &setup.world else {
            return Ok((Vec::new(), None));
        };
        let w = &frame.world;
        let mut faces = vec![FaceDraw::default(); w.faces.len()];
        for (i, obj) in scene.objects.iter().enumerate() {
            let first_index = scene_gpu.draws[i].first_index;
            if let MeshSource::World { class, .. } = &obj.mesh {
                for span in world_mesh::class_mesh(w, *class).1 {
                    let f = &mut faces[span.face as usize];
                    f.draw = i;
                    f.first_index = first_index + span.first_index;
                    f.index_count = span.index_count;
                }
            }
        }
        let mut data: Vec<Vec4> = Vec::new();
        for (id, face) in w.faces.iter().enumerate() {
            let verts: Vec<Vec3> = face.polygon.vertices.iter().map(|&p| frame.to_scene(p)).collect();
            let t = volumes::polygon_volume_template(&verts);
            faces[id].template_first = data.len() as u32;
            faces[id].template_count = t.len() as u32;
            data.extend(t);
        }
        if data.is_empty() {
            return Ok((faces, None));
        }
        let buffer = gpu.create_buffer_init(
            "shadow volume templates",
            vk::BufferUsageFlags::VERTEX_BUFFER,
            bytemuck::cast_slice(&data),
        )?;
        Ok((faces, Some(buffer)))
    }

    fn silhouette_buffers(gpu: &mut Gpu, setup: &Setup) -> Result<Option<SilhouetteBuffers>> {
        if setup.entities.is_empty() || setup.lights.is_empty() {
            return Ok(None);
        }
        let (mut positions, mut triangles, mut edges) =
            (Vec::<Vec4>::new(), Vec::<[u32; 4]>::new(), Vec::<[u32; 4]>::new());
        let mut slots = Vec::new();
        let (mut side_vertices, mut cap_vertices) = (0u32, 0u32);
        for e in &setup.entities {
            let t = &e.topology;
            slots.push(EntitySlots {
                vertex_offset: positions.len() as u32,
                triangle_offset: triangles.len() as u32,
                edge_offset: edges.len() as u32,
            });
            positions.extend(t.positions.iter().map(|p| p.extend(1.0)));
            triangles.extend(t.triangles.iter().map(|t| [t[0], t[1], t[2], 0]));
            edges.extend(t.edges.iter().copied());
            side_vertices += 3 * t.edge_triangles(t.edges.len()) as u32;
            cap_vertices += 6 * t.triangles.len() as u32;
        }
        let out = side_vertices + cap_vertices;
        let storage = |gpu: &mut Gpu, name: &str, bytes: &[u8]| -> Result<BufferId> {
            let zero = [0u8; 16];
            Ok(gpu.create_buffer_init(
                name,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                if bytes.is_empty() { &zero } else { bytes },
            )?)
        };
        let positions = storage(gpu, "entity positions", bytemuck::cast_slice(&positions))?;
        let triangles_total = triangles.len();
        let triangles = storage(gpu, "entity triangles", bytemuck::cast_slice(&triangles))?;
        let edges = storage(gpu, "entity edges", bytemuck::cast_slice(&edges))?;
        let volumes = gpu.create_buffer(&BufferDesc {
            name: "entity shadow volumes".into(),
            size: (u64::from(out) * 16).max(16),
            usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::VERTEX_BUFFER,
            memory: MemoryKind::GpuOnly,
        })?;
        let commands = gpu.create_buffer(&BufferDesc {
            name: "entity shadow volume draws".into(),
            size: 4 * SILHOUETTE_COMMAND_WORDS as u64,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            memory: MemoryKind::GpuOnly,
        })?;
        let facings = gpu.create_buffer(&BufferDesc {
            name: "entity triangle facings".into(),
            size: (4 * triangles_total as u64).max(16),
            usage: vk::BufferUsageFlags::STORAGE_BUFFER,
            memory: MemoryKind::GpuOnly,
        })?;
        let near = gpu.create_buffer(&BufferDesc {
            name: "entity near-plane marks".into(),
            size: (4 * setup.entities.len() as u64).max(16),
            usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuOnly,
        })?;
        let tally = gpu.create_buffer(&BufferDesc {
            name: "entity shadow volume tally".into(),
            size: (2 * setup.lights.len() * SILHOUETTE_COMMAND_WORDS * 4) as u64,
            usage: vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
            memory: MemoryKind::GpuOnly,
        })?;
        Ok(Some(SilhouetteBuffers {
            positions,
            triangles,
            edges,
            volumes,
            commands,
            near,
            tally,
            facings,
            caps_base: side_vertices,
            slots,
        }))
    }

    /// The entities' animation time at renderer time `t`.
    fn time(&self, t: f32) -> f32 {
        self.setup.config.time_s + if self.setup.config.animate { t } else { 0.0 }
    }

    /// Index ranges (per draw, merged) of a set of world faces, in draw order.
    fn face_ranges(&self, faces: &[FaceId]) -> Vec<(usize, Vec<(u32, u32)>)> {
        let mut by_draw: Vec<(usize, Vec<(u32, u32)>)> = Vec::new();
        for &f in faces {
            let fd = self.faces[f as usize];
            match by_draw.iter_mut().find(|(d, _)| *d == fd.draw) {
                Some((_, r)) => r.push((fd.first_index, fd.index_count)),
                None => by_draw.push((fd.draw, vec![(fd.first_index, fd.index_count)])),
            }
        }
        for (_, r) in &mut by_draw {
            r.sort_unstable();
            *r = plan::merge_ranges(r.iter().copied());
        }
        by_draw.sort_by_key(|(d, _)| *d);
        by_draw
    }

    /// The draws of a pass: world ranges and entities, each with its model matrix and
    /// material, sorted by pipeline (features) then material, as the seed pre-sorts meshes.
    fn draw_list(&self, scene: &SceneGpu, plan: &FramePlan, faces: &[FaceId], entities: &[usize]) -> Vec<DrawCall> {
        let mut calls = self.draws_in_order(scene, plan, faces, entities);
        calls.sort_by_key(|c| (self.features_of(c.material), c.material));
        calls
    }

    /// The draws of a pass in the order given (world ranges first): the translucent path keeps
    /// its back-to-front entity order.
    fn draws_in_order(
        &self,
        scene: &SceneGpu,
        plan: &FramePlan,
        faces: &[FaceId],
        entities: &[usize],
    ) -> Vec<DrawCall> {
        let mut calls = Vec::new();
        for (draw, ranges) in self.face_ranges(faces) {
            let d = &scene.draws[draw];
            calls.push(DrawCall {
                material: d.material,
                model: d.model,
                vertex_offset: d.vertex_offset,
                ranges,
            });
        }
        for &e in entities {
            let d = &scene.draws[self.setup.entities[e].draw];
            calls.push(DrawCall {
                material: d.material,
                model: plan.entity_transforms[e],
                vertex_offset: d.vertex_offset,
                ranges: vec![(d.first_index, d.index_count)],
            });
        }
        calls
    }

    fn features_of(&self, material: u32) -> Features {
        match self.setup.config.materials {
            // The default-map path draws everything with the full pipeline.
            MaterialPath::DefaultMaps => Features {
                normal_map: true,
                specular: true,
            },
            MaterialPath::SpecialCase => self.features.get(material as usize).copied().unwrap_or(Features {
                normal_map: false,
                specular: false,
            }),
        }
    }

    /// The maps bound for a material: the scene's, with the exact flat normal standing in for a
    /// missing normal map on the default-map path.
    fn maps(&self, scene: &SceneGpu, material: u32) -> (ImageId, ImageId, ImageId) {
        let m = scene.material_maps[material as usize];
        let has_normal = self.features.get(material as usize).is_some_and(|f| f.normal_map);
        let normal = if has_normal || self.setup.config.materials == MaterialPath::SpecialCase {
            m.normal
        } else {
            self.default_normal
        };
        (m.albedo, normal, m.specular)
    }

    /// Light `light` in homogeneous coordinates this frame ([`VolumeLight::homogeneous`]): a
    /// directional light's direction is the frame's, which the light motion turns.
    fn homogeneous_light(&self, light: usize, scene: &SceneGpu) -> Vec4 {
        let l = &self.setup.lights[light];
        match (l.toward, scene.lights.get(light)) {
            (Some(_), Some(g)) => (-Vec3::from_slice(&g.direction[..3]).normalize()).extend(0.0),
            _ => l.homogeneous(),
        }
    }

    /// `scene`: this frame's lights, whose intensities the light board changes; setup.lights[i]
    /// is scene light i (setup refuses every other kind), so the index is shared.
    fn light_block(&self, light: usize, scene: &SceneGpu) -> LightBlock {
        let l = &self.setup.lights[light];
        let c = &self.setup.config;
        let intensity = scene.lights.get(light).map_or(l.intensity, |g| {
            Vec3::new(g.intensity[0], g.intensity[1], g.intensity[2])
        });
        let colour = match c.mode {
            Mode::Faithful => cpu::faithful_light_colour(intensity, l.radius, c.atten),
            Mode::Physical => intensity,
        };
        if l.toward.is_some() {
            let colour = match c.mode {
                Mode::Faithful => cpu::faithful_sun_colour(intensity),
                Mode::Physical => intensity,
            };
            return LightBlock {
                position: self.homogeneous_light(light, scene).into(),
                colour: colour.extend(0.0).into(),
                spot_direction: [0.0, 0.0, 0.0, LIGHT_DIRECTIONAL],
                cone: [0.0; 4],
            };
        }
        let (spot_direction, cone) = match l.spot {
            Some(s) => (
                s.direction.extend(LIGHT_SPOT).into(),
                [s.cos_inner, s.cos_outer, 0.0, 0.0],
            ),
            None => ([0.0, 0.0, 0.0, LIGHT_POINT], [0.0; 4]),
        };
        LightBlock {
            position: l.position.extend(l.radius).into(),
            colour: colour.extend(0.0).into(),
            spot_direction,
            cone,
        }
    }
}

/// Records the draws of a surface pass, binding the pipeline for each call's features and the
/// material's maps (`extra` names them for the pass's shaders).
#[allow(clippy::too_many_arguments)]
fn record_surface<'b>(
    ctx: &mut crate::graph::PassContext<'_, '_>,
    method: &ShadowVolumes,
    scene: &SceneGpu,
    calls: &[DrawCall],
    pipeline_of: impl Fn(Features) -> PipelineId,
    extra: impl Fn(ImageId, ImageId, ImageId) -> Vec<(&'static str, Bind<'b>)>,
    frame_bytes: &'b [u8],
    light_bytes: &'b [u8],
) -> std::result::Result<(), crate::backend::BackendError> {
    // The pipeline follows the material (its features), so a material change is where both
    // are bound.
    let mut bound_pipeline = None;
    record_draws(ctx, scene, calls, |ctx, material| {
        let pipeline = pipeline_of(method.features_of(material));
        if bound_pipeline != Some(pipeline) {
            ctx.rec.bind_pipeline(pipeline)?;
            bound_pipeline = Some(pipeline);
        }
        let (albedo, normal, specular) = method.maps(scene, material);
        let mut binds: Vec<(&str, Bind<'b>)> = vec![
            ("frame", Bind::UniformData(frame_bytes)),
            ("light", Bind::UniformData(light_bytes)),
        ];
        binds.extend(extra(albedo, normal, specular));
        ctx.bind(&binds)
    })
}

impl LightingMethod for ShadowVolumes {
    fn name(&self) -> &'static str {
        NAME
    }

    fn frame_notes(&self, gpu: &mut Gpu) -> Result<Vec<String>> {
        let Some(s) = &self.silhouettes else {
            return Ok(Vec::new());
        };
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&crate::graph::read_back_buffer(gpu, s.tally, NAME)?);
        let names: Vec<&str> = self.setup.lights.iter().map(|l| l.name.as_str()).collect();
        Ok(tally::notes(&words, &names))
    }

    fn uses_light_mask(&self) -> bool {
        self.group.is_some()
    }

    fn prepare(&mut self, frame: &FrameContext<'_>) -> Result<()> {
        let camera = Vec3::from_slice(&frame.uniforms.camera_pos[..3]);
        self.plan = Some(Rc::new(self.setup.plan(camera, self.time(frame.clock.time_s))));
        Ok(())
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        let (base, direct) = (frame.terms.has(Term::Base), frame.terms.has(Term::Direct));
        let plan = self
            .plan
            .clone()
            .ok_or_else(|| Error::Internal(format!("{NAME}: a frame was recorded before it was prepared")))?;
        let silhouettes = self.silhouettes.as_ref().filter(|_| direct);
        if let Some(s) = silhouettes {
            let tally = s.tally;
            graph
                .pass("volume tally reset")
                .buffer(tally, Access::TransferWrite, None)
                .record(move |ctx| ctx.rec.fill_buffer(tally, 0));
        }

        // The seed's path twice: opaque surfaces (translucent ones omitted from receivers and
        // casters, so light shines through them), then the translucent entities alone, back to
        // front, blended over the opaque image; their depth lets the second round of stencil
        // volumes (opaque casters only) and light passes reach the nearest translucent layer.
        // The opaque ambient pass is the base term, the rest the direct term (the translucent path
        // needs both: `new` refuses translucent entities otherwise).
        for translucent in [false, true] {
            if translucent && (plan.translucent_entities.is_empty() || !direct) {
                break;
            }
            if translucent || base {
                self.add_ambient(graph, frame, &plan, translucent);
            }
            if !direct {
                continue;
            }
            // Lights whose receivers are everything in view are lit together when there are
            // two or more of them (`grouped`); the others, and the translucent round, a pass each.
            let grouping = !translucent && self.group.is_some() && frame.targets.light_mask.is_some();
            let grouped = |lp: &LightPlan| grouping && grouped::groupable(&plan, lp);
            let grouping = grouping && plan.lights.iter().filter(|lp| grouped(lp)).count() > 1;
            let mut group = Vec::new();
            for lp in plan.lights.iter() {
                if translucent && lp.translucent_receivers.is_empty() {
                    continue;
                }
                if let Some(s) = silhouettes.filter(|_| !lp.caster_entities.is_empty()) {
                    self.add_silhouettes(graph, s, &plan, lp, frame, translucent);
                }
                self.add_volumes(graph, frame, lp, translucent);
                if !(grouping && grouped(lp)) {
                    self.add_lighting(graph, frame, &plan, lp, translucent);
                    continue;
                }
                self.add_light_mask(graph, frame, lp, group.len())?;
                group.push(lp.light);
                if group.len() == grouped::LIGHTS_PER_GROUP {
                    self.add_group_lighting(graph, frame, &plan, &group)?;
                    group.clear();
                }
            }
            if !group.is_empty() {
                self.add_group_lighting(graph, frame, &plan, &group)?;
            }
        }
        Ok(())
    }
}
