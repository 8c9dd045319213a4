//! The scene as the path tracer reads it: world-space triangles in BVH leaf order (positions for
//! intersection, shading normals and material for the hit), the BVH nodes, materials and every
//! light, laid out as `glsl/reference/pathtrace.comp` declares them.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::bvh::{Bvh, BvhNode};
use super::environment::EnvironmentMap;
use crate::backend::{vk, BackendError, BufferId, Gpu};
use crate::error::{Error, Result};
use crate::renderer::{punctual_lights, GpuLight};
use crate::scene::{Environment, Light, Scene};

/// Light types beyond the punctual ones of `glsl/common/lights.glsl` (stored in `position.w`).
pub const LIGHT_SPHERE: f32 = 3.0;
pub const LIGHT_QUAD: f32 = 4.0;

/// What a ray is intersected with: corner and two edges (`Triangle` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TracedTriangle {
    pub p0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}

/// What the closest hit reads (`Shading` in the shader): vertex normals and the material.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TriangleShading {
    pub n0: [f32; 3],
    pub material: u32,
    pub n1: [f32; 3],
    pub _pad0: u32,
    pub n2: [f32; 3],
    pub _pad1: u32,
}

/// `Material` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TracedMaterial {
    pub albedo: [f32; 4],
    /// rgb: Blinn-Phong colour; w: exponent.
    pub specular: [f32; 4],
    pub transmittance: [f32; 4],
    pub emission: [f32; 4],
}

/// The scene flattened for tracing, on the CPU.
pub struct TracedScene {
    /// World-space corners in input order (for CPU checks); the GPU arrays are in BVH order.
    pub corners: Vec<[Vec3; 3]>,
    pub bvh: Bvh,
    pub triangles: Vec<TracedTriangle>,
    pub shading: Vec<TriangleShading>,
    pub materials: Vec<TracedMaterial>,
    /// Punctual lights as [`GpuLight`], then sphere lights (`position` = centre, `direction.x` =
    /// radius, `intensity` = radiance) and quad lights (`position` = corner, `direction` =
    /// edge_u, `cone` = edge_v, `intensity` = radiance).
    pub lights: Vec<GpuLight>,
    /// Constant radiance of rays that escape (when there is no map).
    pub environment: Vec3,
    pub environment_map: Option<EnvironmentMap>,
}

fn unsupported(message: String) -> Error {
    Error::Backend(BackendError::Unsupported(message))
}

impl TracedScene {
    /// Gathers every object's triangles in world space. Features the tracer does not model are
    /// errors naming the scene and the field, never silently different results.
    pub fn build(scene: &Scene) -> Result<TracedScene> {
        let src = &scene.source;
        let (environment, environment_map) = match &scene.environment {
            None => (Vec3::ZERO, None),
            Some(Environment::Constant { radiance }) => (*radiance, None),
            Some(Environment::Image { path, scale }) => (Vec3::ZERO, Some(EnvironmentMap::load(path, *scale, src)?)),
        };
        for m in &scene.materials {
            for (field, map) in [("albedo_map", &m.albedo_map), ("normal_map", &m.normal_map), ("specular_map", &m.specular_map)] {
                if map.is_some() {
                    return Err(unsupported(format!(
                        "{src}: material \"{}\": {field}: the reference renderer does not support texture maps",
                        m.name
                    )));
                }
            }
        }
        let mut corners = Vec::new();
        let mut normals = Vec::new();
        let mut material_of = Vec::new();
        for obj in &scene.objects {
            let mesh = obj.load_mesh(std::path::Path::new("."))?.transformed(&obj.transform);
            for [a, b, c] in mesh.triangles() {
                let p = [mesh.positions[a], mesh.positions[b], mesh.positions[c]];
                // Zero-area triangles are never hit; leaving them out keeps the BVH tight.
                let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length_squared();
                if !(area2 > 0.0 && area2.is_finite()) {
                    continue;
                }
                let n = |i: usize| mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
                corners.push(p);
                normals.push([n(a), n(b), n(c)]);
                material_of.push(obj.material as u32);
            }
        }
        let bvh = Bvh::build(&corners);
        let mut triangles = Vec::with_capacity(corners.len());
        let mut shading = Vec::with_capacity(corners.len());
        for &t in &bvh.order {
            let [p0, p1, p2] = corners[t as usize];
            let [n0, n1, n2] = normals[t as usize];
            triangles.push(TracedTriangle { p0: p0.extend(0.0).into(), e1: (p1 - p0).extend(0.0).into(), e2: (p2 - p0).extend(0.0).into() });
            shading.push(TriangleShading { n0: n0.into(), material: material_of[t as usize], n1: n1.into(), _pad0: 0, n2: n2.into(), _pad1: 0 });
        }
        let materials = scene
            .materials
            .iter()
            .map(|m| TracedMaterial {
                albedo: m.albedo.extend(0.0).into(),
                specular: m.specular.extend(m.exponent).into(),
                transmittance: m.transmittance.extend(0.0).into(),
                emission: m.emission.extend(0.0).into(),
            })
            .collect();
        let mut lights = punctual_lights(scene);
        for l in &scene.lights {
            match l {
                Light::Sphere { center, radius, radiance, .. } => lights.push(GpuLight {
                    position: center.extend(LIGHT_SPHERE).into(),
                    direction: [*radius, 0.0, 0.0, 0.0],
                    intensity: radiance.extend(0.0).into(),
                    cone: [0.0; 4],
                }),
                Light::Quad { corner, edge_u, edge_v, radiance, .. } => lights.push(GpuLight {
                    position: corner.extend(LIGHT_QUAD).into(),
                    direction: edge_u.extend(0.0).into(),
                    intensity: radiance.extend(0.0).into(),
                    cone: edge_v.extend(0.0).into(),
                }),
                Light::Point { .. } | Light::Spot { .. } | Light::Directional { .. } => {}
            }
        }
        Ok(TracedScene { corners, bvh, triangles, shading, materials, lights, environment, environment_map })
    }

    pub fn upload(&self, gpu: &mut Gpu) -> Result<SceneBuffers> {
        // Shaders declare runtime arrays; an empty one is bound as one zeroed element.
        fn storage<T: Pod + Zeroable>(gpu: &mut Gpu, name: &str, items: &[T]) -> Result<BufferId> {
            let zero = [T::zeroed()];
            let items = if items.is_empty() { &zero[..] } else { items };
            Ok(gpu.create_buffer_init(name, vk::BufferUsageFlags::STORAGE_BUFFER, bytemuck::cast_slice(items))?)
        }
        Ok(SceneBuffers {
            nodes: storage::<BvhNode>(gpu, "reference bvh nodes", &self.bvh.nodes)?,
            triangles: storage(gpu, "reference triangles", &self.triangles)?,
            shading: storage(gpu, "reference triangle shading", &self.shading)?,
            materials: storage(gpu, "reference materials", &self.materials)?,
            lights: storage(gpu, "reference lights", &self.lights)?,
            environment_map: storage(gpu, "reference environment map", self.environment_map.as_ref().map_or(&[][..], |m| &m.texels))?,
            environment_cdf: storage(gpu, "reference environment cdf", self.environment_map.as_ref().map_or(&[][..], |m| &m.cdf))?,
        })
    }
}

/// The storage buffers of a [`TracedScene`], named after the shader bindings.
#[derive(Clone, Copy, Debug)]
pub struct SceneBuffers {
    pub nodes: BufferId,
    pub triangles: BufferId,
    pub shading: BufferId,
    pub materials: BufferId,
    pub lights: BufferId,
    pub environment_map: BufferId,
    pub environment_cdf: BufferId,
}

impl SceneBuffers {
    pub fn bindings(&self) -> [(&'static str, BufferId); 7] {
        [
            ("nodes", self.nodes),
            ("triangles", self.triangles),
            ("shading", self.shading),
            ("materials", self.materials),
            ("lights", self.lights),
            ("environment_map", self.environment_map),
            ("environment_cdf", self.environment_cdf),
        ]
    }
}
