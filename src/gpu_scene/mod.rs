//! The scene on the GPU: one vertex and one index buffer for every object, materials, lights,
//! material textures and the environment; the vertex layout, the per-draw push constants and one
//! helper that records draws. Every lighting method draws the scene through this module; the GLSL
//! side is `glsl/common/scene.glsl`.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use crate::backend::{
    vk, BackendError, Bind, BufferId, Gpu, ImageDesc, ImageId, SamplerDesc, SamplerId, SubresourceRange,
    VertexAttribute, VertexLayout,
};
use crate::environment::raster::EnvironmentLighting;
use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::graph::{Access, PassContext, ResourceStates};
use crate::scene::{Light, Mesh, Scene};

/// The vertex every raster pass reads: 48 bytes, interleaved.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    pub tangent: [f32; 4],
}

/// The vertex layout of [`Vertex`] (`in_position` … `in_tangent` in glsl/common/scene.glsl).
pub fn vertex_layout() -> VertexLayout {
    let attr = |location, format, offset| VertexAttribute {
        location,
        binding: 0,
        format,
        offset,
    };
    VertexLayout {
        buffers: vec![(0, std::mem::size_of::<Vertex>() as u32)],
        attributes: vec![
            attr(0, vk::Format::R32G32B32_SFLOAT, 0),
            attr(1, vk::Format::R32G32B32_SFLOAT, 12),
            attr(2, vk::Format::R32G32_SFLOAT, 24),
            attr(3, vk::Format::R32G32B32A32_SFLOAT, 32),
        ],
    }
}

/// Push constants of scene draws (`Draw` in glsl/common/scene.glsl): the model matrix and the
/// material index, [`DrawPush::BYTES`] of them pushed.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DrawPush {
    pub model: [f32; 16],
    pub material: u32,
    pub _pad: [u32; 3],
}

impl DrawPush {
    /// The bytes the shaders declare (the padding is not pushed).
    pub const BYTES: usize = 68;

    pub fn new(model: Mat4, material: u32) -> DrawPush {
        DrawPush {
            model: model.to_cols_array(),
            material,
            _pad: [0; 3],
        }
    }

    pub fn bytes(&self) -> &[u8] {
        &bytemuck::bytes_of(self)[..Self::BYTES]
    }
}

/// One draw of a pass: index ranges of one scene draw under one model matrix and material.
#[derive(Clone, Debug)]
pub struct DrawCall {
    pub material: u32,
    pub model: Mat4,
    pub vertex_offset: i32,
    /// (first index, index count) pairs.
    pub ranges: Vec<(u32, u32)>,
}

impl DrawCall {
    /// The whole of scene draw `d` at its placement.
    pub fn whole(d: &DrawItem) -> DrawCall {
        DrawCall {
            material: d.material,
            model: d.model,
            vertex_offset: d.vertex_offset,
            ranges: vec![(d.first_index, d.index_count)],
        }
    }
}

/// Records `calls` from the scene's vertex and index buffers: `bind` runs before the first call
/// and whenever the material changes (to bind the pipeline and the material's resources), then
/// each call pushes its [`DrawPush`] and draws its ranges.
pub fn record_draws(
    ctx: &mut PassContext<'_, '_>,
    scene: &SceneGpu,
    calls: &[DrawCall],
    bind: impl FnMut(&mut PassContext<'_, '_>, u32) -> std::result::Result<(), BackendError>,
) -> std::result::Result<(), BackendError> {
    record_draws_from(ctx, (scene.vertices, scene.indices), calls, bind)
}

/// [`record_draws`] from other vertex and index buffers laid out as the scene's.
pub fn record_draws_from(
    ctx: &mut PassContext<'_, '_>,
    (vertices, indices): (BufferId, BufferId),
    calls: &[DrawCall],
    mut bind: impl FnMut(&mut PassContext<'_, '_>, u32) -> std::result::Result<(), BackendError>,
) -> std::result::Result<(), BackendError> {
    ctx.rec.bind_vertex_buffers(&[(vertices, 0)])?;
    ctx.rec.bind_index_buffer(indices, 0)?;
    let mut bound = None;
    for call in calls {
        if bound != Some(call.material) {
            bind(ctx, call.material)?;
            bound = Some(call.material);
        }
        ctx.rec
            .push_constants(DrawPush::new(call.model, call.material).bytes())?;
        for &(first, count) in &call.ranges {
            ctx.rec.draw_indexed(count, first, call.vertex_offset)?;
        }
    }
    Ok(())
}

/// Matches `Material` in glsl/common/scene.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub albedo: [f32; 4],
    pub specular: [f32; 4],
    pub emission: [f32; 4],
    pub maps: [u32; 4],
}

/// Matches `Light` in glsl/common/lights.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 4],
    pub direction: [f32; 4],
    pub intensity: [f32; 4],
    pub cone: [f32; 4],
}

pub const LIGHT_POINT: f32 = 0.0;
pub const LIGHT_SPOT: f32 = 1.0;
pub const LIGHT_DIRECTIONAL: f32 = 2.0;
/// An emissive quad seen from afar: a point at its centre with intensity L·A·cos θ_e.
pub const LIGHT_QUAD_FAR: f32 = 3.0;

/// One object's slice of the shared buffers.
#[derive(Clone, Debug)]
pub struct DrawItem {
    pub name: String,
    /// The scene object drawn (`scene.objects[i]`), or `None` for an area light's emitter.
    pub object: Option<usize>,
    pub first_index: u32,
    pub index_count: u32,
    pub vertex_offset: i32,
    pub model: Mat4,
    pub material: u32,
}

/// Textures of one material (1×1 defaults where the material has no map).
#[derive(Clone, Copy, Debug)]
pub struct MaterialMaps {
    pub albedo: ImageId,
    pub normal: ImageId,
    pub specular: ImageId,
}

impl MaterialMaps {
    /// The three maps as the surface shaders declare them (`albedo_map`, `normal_map`,
    /// `specular_map`), each whole, through `sampler`.
    pub fn binds(&self, sampler: SamplerId) -> [(&'static str, Bind<'static>); 3] {
        let sampled = |image| Bind::Sampled {
            image,
            range: SubresourceRange::mip(0),
            sampler,
        };
        [
            ("albedo_map", sampled(self.albedo)),
            ("normal_map", sampled(self.normal)),
            ("specular_map", sampled(self.specular)),
        ]
    }
}

pub struct SceneGpu {
    pub vertices: BufferId,
    pub indices: BufferId,
    pub draws: Vec<DrawItem>,
    pub materials: BufferId,
    pub material_maps: Vec<MaterialMaps>,
    pub lights: Vec<GpuLight>,
    pub sampler: SamplerId,
    /// Object-space meshes, kept for CPU-side methods and tests.
    pub meshes: Vec<Mesh>,
    pub environment: EnvironmentLighting,
}

/// Point, spot and directional lights, exactly as given (area lights are left out).
pub fn punctual_lights(scene: &Scene) -> Vec<GpuLight> {
    let mut out = raster_lights(scene);
    out.retain(|l| l.position[3] != LIGHT_QUAD_FAR && !(l.position[3] == LIGHT_POINT && l.cone[3] == AREA_MARK));
    out
}

/// Marks a point light that stands in for a sphere light (`cone.w`), so it can be told apart.
const AREA_MARK: f32 = 1.0;

/// The lights as the raster methods evaluate them: punctual lights exactly; area lights in their
/// far-field form. A sphere of radiance L and radius R is exact as a point of intensity L·πR²
/// wherever it is wholly above the receiver's horizon (and unoccluded); an emissive quad becomes
/// a point of intensity L·A·cos θ_e at its centre, which is accurate only at distances large
/// against its size — the reference renderer integrates both exactly.
pub fn raster_lights(scene: &Scene) -> Vec<GpuLight> {
    let mut out = Vec::new();
    for l in &scene.lights {
        match l {
            Light::Point {
                position, intensity, ..
            } => out.push(GpuLight {
                position: position.extend(LIGHT_POINT).into(),
                direction: [0.0; 4],
                intensity: intensity.extend(0.0).into(),
                cone: [0.0; 4],
            }),
            Light::Spot {
                position,
                direction,
                intensity,
                inner_deg,
                outer_deg,
                ..
            } => out.push(GpuLight {
                position: position.extend(LIGHT_SPOT).into(),
                direction: direction.normalize().extend(0.0).into(),
                intensity: intensity.extend(0.0).into(),
                cone: [inner_deg.to_radians().cos(), outer_deg.to_radians().cos(), 0.0, 0.0],
            }),
            Light::Directional {
                direction, irradiance, ..
            } => out.push(GpuLight {
                position: Vec4::new(0.0, 0.0, 0.0, LIGHT_DIRECTIONAL).into(),
                direction: direction.normalize().extend(0.0).into(),
                intensity: irradiance.extend(0.0).into(),
                cone: [0.0; 4],
            }),
            Light::Sphere {
                center,
                radius,
                radiance,
                ..
            } => out.push(GpuLight {
                position: center.extend(LIGHT_POINT).into(),
                direction: [0.0; 4],
                intensity: (*radiance * std::f32::consts::PI * radius * radius).extend(0.0).into(),
                cone: [0.0, 0.0, 0.0, AREA_MARK],
            }),
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
                ..
            } => {
                let cross = edge_u.cross(*edge_v);
                out.push(GpuLight {
                    position: (*corner + 0.5 * (*edge_u + *edge_v)).extend(LIGHT_QUAD_FAR).into(),
                    direction: cross.normalize_or_zero().extend(0.0).into(),
                    intensity: (*radiance * cross.length()).extend(0.0).into(),
                    cone: [0.0; 4],
                })
            }
        }
    }
    out
}

/// Geometry for the area lights, so every method sees them as emissive surfaces (one-sided for
/// quads, whose back does not emit).
pub(crate) fn emitter_meshes(scene: &Scene) -> Vec<(String, Mesh, Vec3)> {
    use crate::scene::generators;
    let mut out = Vec::new();
    for l in &scene.lights {
        match l {
            Light::Sphere {
                name,
                center,
                radius,
                radiance,
            } => {
                let m = generators::sphere(*radius, 32, 16).transformed(&Mat4::from_translation(*center));
                out.push((name.clone(), m, *radiance));
            }
            Light::Quad {
                name,
                corner,
                edge_u,
                edge_v,
                radiance,
            } => {
                out.push((name.clone(), generators::quad(*corner, *edge_u, *edge_v, 1), *radiance));
            }
            _ => {}
        }
    }
    out
}

fn load_texture(
    gpu: &mut Gpu,
    states: &mut ResourceStates,
    path: Option<&std::path::Path>,
    default: [u8; 4],
    srgb: bool,
    what: &str,
) -> Result<ImageId> {
    let (w, h, data) = match path {
        Some(p) => {
            let img = crate::util::image_io::open_image(p)
                .map_err(|e| Error::Usage(format!("{what}: {}: {e}", p.display())))?
                .to_rgba8();
            (img.width(), img.height(), img.into_raw())
        }
        None => (1, 1, default.to_vec()),
    };
    let format = if srgb {
        vk::Format::R8G8B8A8_SRGB
    } else {
        vk::Format::R8G8B8A8_UNORM
    };
    let name = path
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| format!("default {what}"));
    let id = gpu.create_image(
        &ImageDesc::new_2d(&name, format, w, h).usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST),
    )?;
    gpu.upload_image(id, 0, &data)?;
    states.set_image(
        gpu,
        id,
        Access::SampledRead {
            stages: vk::PipelineStageFlags2::ALL_COMMANDS,
        },
    )?;
    Ok(id)
}

/// `mesh`'s vertices as the vertex buffer holds them (defaults for missing attributes).
pub fn vertices_of(mesh: &Mesh) -> Vec<Vertex> {
    let mut out = Vec::with_capacity(mesh.positions.len());
    push_vertices(&mut out, mesh);
    out
}

fn push_vertices(vertices: &mut Vec<Vertex>, mesh: &Mesh) {
    for i in 0..mesh.positions.len() {
        vertices.push(Vertex {
            position: mesh.positions[i].into(),
            normal: mesh.normals.get(i).copied().unwrap_or(Vec3::Y).into(),
            uv: mesh.uvs.get(i).copied().unwrap_or_default().into(),
            tangent: mesh
                .tangents
                .get(i)
                .copied()
                .unwrap_or(Vec4::new(1.0, 0.0, 0.0, 1.0))
                .into(),
        });
    }
}

impl SceneGpu {
    /// The lights as the shaders' `lights` storage block reads them (zeros for a scene without
    /// lights: a storage binding cannot be empty).
    pub fn light_bytes(&self) -> &[u8] {
        if self.lights.is_empty() {
            &[0u8; 64]
        } else {
            bytemuck::cast_slice(&self.lights)
        }
    }

    /// Uploads the scene; `environment` is its environment as [`EnvironmentMap::of_scene`]
    /// loaded it.
    pub fn upload(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        scene: &Scene,
        environment: &EnvironmentMap,
    ) -> Result<SceneGpu> {
        let mut geometry = Geometry::default();
        for obj in &scene.objects {
            let mesh = obj.load_mesh(std::path::Path::new("."))?;
            let object = Some(geometry.draws.len());
            geometry.push(obj.name.clone(), object, mesh, obj.transform, obj.material as u32);
        }
        let (mut gpu_materials, mut material_maps) = scene_materials(gpu, states, scene)?;
        let emitters = emitter_meshes(scene);
        if !emitters.is_empty() {
            let defaults = MaterialMaps {
                albedo: load_texture(gpu, states, None, [255; 4], true, "albedo_map")?,
                normal: load_texture(gpu, states, None, [128, 128, 255, 255], false, "normal_map")?,
                specular: load_texture(gpu, states, None, [255; 4], false, "specular_map")?,
            };
            for (name, mesh, radiance) in emitters {
                let material = gpu_materials.len() as u32;
                gpu_materials.push(GpuMaterial {
                    albedo: [0.0, 0.0, 0.0, 1.0],
                    specular: [0.0, 0.0, 0.0, 1.0],
                    emission: radiance.extend(0.0).into(),
                    maps: [0, 1, 0, 0],
                });
                material_maps.push(defaults);
                geometry.push(format!("{name} (emitter)"), None, mesh, Mat4::IDENTITY, material);
            }
        }
        let (vb, ib, materials) = upload_buffers(gpu, states, &mut geometry, gpu_materials)?;
        let sampler = gpu.sampler(SamplerDesc::LINEAR_REPEAT)?;
        let environment = EnvironmentLighting::upload(gpu, states, scene, environment)?;
        Ok(SceneGpu {
            vertices: vb,
            indices: ib,
            draws: geometry.draws,
            materials,
            material_maps,
            lights: raster_lights(scene),
            sampler,
            meshes: geometry.meshes,
            environment,
        })
    }
}

/// The scene's meshes in one vertex and one index list, with a draw per mesh.
#[derive(Default)]
struct Geometry {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    draws: Vec<DrawItem>,
    meshes: Vec<Mesh>,
}

impl Geometry {
    fn push(&mut self, name: String, object: Option<usize>, mesh: Mesh, model: Mat4, material: u32) {
        self.draws.push(DrawItem {
            name,
            object,
            first_index: self.indices.len() as u32,
            index_count: mesh.indices.len() as u32,
            vertex_offset: self.vertices.len() as i32,
            model,
            material,
        });
        push_vertices(&mut self.vertices, &mesh);
        self.indices.extend_from_slice(&mesh.indices);
        self.meshes.push(mesh);
    }
}

/// The scene's materials as the shaders read them, and their texture maps (white, flat or
/// full where a map is not given).
fn scene_materials(
    gpu: &mut Gpu,
    states: &mut ResourceStates,
    scene: &Scene,
) -> Result<(Vec<GpuMaterial>, Vec<MaterialMaps>)> {
    let mut gpu_materials = Vec::new();
    let mut material_maps = Vec::new();
    for (i, m) in scene.materials.iter().enumerate() {
        let field = |key: &str| format!("{}: materials[{i}] ({:?}).{key}", scene.source, m.name);
        gpu_materials.push(GpuMaterial {
            albedo: m.albedo.extend(m.opacity).into(),
            specular: m.specular.extend(m.exponent).into(),
            emission: m.emission.extend(0.0).into(),
            maps: [m.normal_map.is_some() as u32, 0, 0, 0],
        });
        material_maps.push(MaterialMaps {
            albedo: load_texture(
                gpu,
                states,
                m.albedo_map.as_deref(),
                [255; 4],
                true,
                &field("albedo_map"),
            )?,
            normal: load_texture(
                gpu,
                states,
                m.normal_map.as_deref(),
                [128, 128, 255, 255],
                false,
                &field("normal_map"),
            )?,
            specular: load_texture(
                gpu,
                states,
                m.specular_map.as_deref(),
                [255; 4],
                false,
                &field("specular_map"),
            )?,
        });
    }
    Ok((gpu_materials, material_maps))
}

/// The vertex, index and material buffers (a degenerate triangle and a zero material stand in
/// for none, as a buffer cannot be empty).
fn upload_buffers(
    gpu: &mut Gpu,
    states: &mut ResourceStates,
    geometry: &mut Geometry,
    mut gpu_materials: Vec<GpuMaterial>,
) -> Result<(BufferId, BufferId, BufferId)> {
    if geometry.vertices.is_empty() {
        geometry.vertices.push(Vertex::zeroed());
        geometry.indices.extend([0, 0, 0]);
    }
    let vb = gpu.create_buffer_init(
        "scene vertices",
        vk::BufferUsageFlags::VERTEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC,
        bytemuck::cast_slice(&geometry.vertices),
    )?;
    let ib = gpu.create_buffer_init(
        "scene indices",
        vk::BufferUsageFlags::INDEX_BUFFER | vk::BufferUsageFlags::STORAGE_BUFFER,
        bytemuck::cast_slice(&geometry.indices),
    )?;
    if gpu_materials.is_empty() {
        gpu_materials.push(GpuMaterial::zeroed());
    }
    let materials = gpu.create_buffer_init(
        "materials",
        vk::BufferUsageFlags::STORAGE_BUFFER,
        bytemuck::cast_slice(&gpu_materials),
    )?;
    for id in [vb, ib, materials] {
        // Uploads were waited for: nothing is pending on these buffers.
        states.forget_buffer(id);
    }
    Ok((vb, ib, materials))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_lights_are_raster_lights_but_not_punctual() {
        let scene = Scene::from_str(
            r#"
[camera]
position = [0, 1, 3]
target = [0, 0, 0]
[[lights]]
type = "point"
position = [0, 2, 0]
intensity = 1
[[lights]]
type = "spot"
position = [0, 2, 0]
target = [0, 0, 0]
intensity = 1
[[lights]]
type = "directional"
direction = [0, -1, 0]
irradiance = 1
[[lights]]
type = "sphere"
center = [0, 3, 0]
radius = 0.5
radiance = 2
[[lights]]
type = "quad"
corner = [0, 2, 0]
edge_u = [2, 0, 0]
edge_v = [0, 0, 1]
radiance = 3
"#,
            "<test>",
            std::path::Path::new("."),
        )
        .unwrap();
        let punctual = punctual_lights(&scene);
        assert_eq!(
            punctual.iter().map(|l| l.position[3]).collect::<Vec<_>>(),
            vec![LIGHT_POINT, LIGHT_SPOT, LIGHT_DIRECTIONAL]
        );
        let raster = raster_lights(&scene);
        assert_eq!(raster.len(), 5);
        // Sphere: I = L·πR²; quad: I = L·A with A = |u × v| = 2, facing (2,0,0)×(0,0,1) = −y.
        assert!((raster[3].intensity[0] - 2.0 * std::f32::consts::PI * 0.25).abs() < 1e-6);
        assert_eq!(raster[4].position, [1.0, 2.0, 0.5, LIGHT_QUAD_FAR]);
        assert_eq!(raster[4].intensity[0], 6.0);
        assert_eq!(raster[4].direction[..3], [0.0, -1.0, 0.0]);
    }
}
