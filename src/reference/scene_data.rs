//! The scene as the path tracer reads it: world-space triangles in BVH leaf order (positions for
//! intersection; shading normals, tangents, uvs and material for the hit), the BVH nodes,
//! materials, their texture maps and every light, laid out as `glsl/reference/pathtrace.comp`
//! declares them.
//!
//! Texture maps follow the raster methods exactly (`src/renderer/scene_gpu.rs` and the
//! `LINEAR_REPEAT` sampler): an albedo map is sRGB-decoded per texel before filtering (an
//! `R8G8B8A8_SRGB` image), normal and specular maps are `UNORM` (byte/255); every map is sampled
//! bilinearly with repeat wrapping at its only mip level. The shader filters by hand from
//! decoded float texels, so the reference does not depend on a device's filtering precision.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4};

use super::features::BvhWalk;
use crate::backend::{vk, BufferId, Gpu};
use crate::environment::EnvironmentMap;
use crate::error::{Error, Result};
use crate::gpu_scene::{punctual_lights, GpuLight};
use crate::graph::{Access, PassBuilder, ResourceStates};
use crate::raytrace::bvh::Bvh;
use crate::raytrace::texel_table::TexelTable;
use crate::raytrace::TracedTriangle;
use crate::scene::{Environment, Light, Scene};
use crate::util::image_io::srgb_decode;

/// Light types beyond the punctual ones of `glsl/common/lights.glsl` (stored in `position.w`).
pub const LIGHT_SPHERE: f32 = 3.0;
pub const LIGHT_QUAD: f32 = 4.0;

/// What the closest hit reads (`Shading` in the shader): world-space vertex normals, tangents
/// (xyz orthogonal to the normal, w the bitangent's sign, as the raster vertex shaders make
/// them), texture coordinates and the material.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TriangleShading {
    pub n0: [f32; 3],
    pub material: u32,
    pub n1: [f32; 3],
    pub _pad0: u32,
    pub n2: [f32; 3],
    pub _pad1: u32,
    pub t0: [f32; 4],
    pub t1: [f32; 4],
    pub t2: [f32; 4],
    pub uv0: [f32; 2],
    pub uv1: [f32; 2],
    pub uv2: [f32; 2],
    pub _pad2: [f32; 2],
}

/// `Material` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TracedMaterial {
    /// rgb: diffuse albedo; w: opacity (stochastic transparency, see pathtrace.comp).
    pub albedo: [f32; 4],
    /// rgb: Blinn-Phong colour; w: exponent.
    pub specular: [f32; 4],
    pub transmittance: [f32; 4],
    pub emission: [f32; 4],
    /// x: albedo map, y: normal map, z: specular map, each an index into
    /// [`TracedScene::textures`] plus one (0: no map).
    pub maps: [u32; 4],
}

/// One texture map, decoded to linear floats (what the raster sampler filters).
#[derive(Clone, Debug, PartialEq)]
pub struct TracedTexture {
    pub width: u32,
    pub height: u32,
    /// Row 0 is the image's top row (v = 0).
    pub texels: Vec<[f32; 4]>,
}

impl TracedTexture {
    /// Bilinear, repeat-wrapped lookup at mip 0, as Vulkan's `LINEAR`/`REPEAT` sampler defines it
    /// (texel centres at half-integers); the CPU twin of `sample_texture` in the shader.
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        let (w, h) = (self.width as i64, self.height as i64);
        // Wrapped first, as the shader does, so large coordinates keep their precision alike.
        let s = (uv - uv.floor()) * Vec2::new(w as f32, h as f32) - 0.5;
        let (i0, j0) = (s.x.floor() as i64, s.y.floor() as i64);
        let (fx, fy) = (s.x - s.x.floor(), s.y - s.y.floor());
        let at = |i: i64, j: i64| Vec4::from(self.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize]);
        let top = at(i0, j0).lerp(at(i0 + 1, j0), fx);
        let bottom = at(i0, j0 + 1).lerp(at(i0 + 1, j0 + 1), fx);
        top.lerp(bottom, fy)
    }
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
    /// How many of `lights` are punctual (they come first).
    pub punctual_lights: u32,
    /// Every distinct (file, encoding) texture map the materials use.
    pub textures: Vec<TracedTexture>,
    /// Constant radiance of rays that escape (when there is no map).
    pub environment: Vec3,
    pub environment_map: Option<EnvironmentMap>,
}

/// A map as the raster methods upload it: 8 bits per channel, sRGB-decoded for albedo.
fn load_texture(path: &std::path::Path, srgb: bool) -> std::result::Result<TracedTexture, String> {
    let img = crate::util::image_io::open_image(path)?.to_rgba8();
    let decode = |b: u8| if srgb { srgb_decode(b) } else { b as f32 / 255.0 };
    let texels = img
        .pixels()
        .map(|p| [decode(p.0[0]), decode(p.0[1]), decode(p.0[2]), p.0[3] as f32 / 255.0])
        .collect();
    Ok(TracedTexture {
        width: img.width(),
        height: img.height(),
        texels,
    })
}

/// The scene's environment: a constant radiance, or a map (then the constant is zero).
fn load_environment(scene: &Scene) -> Result<(Vec3, Option<EnvironmentMap>)> {
    let src = &scene.source;
    Ok(match &scene.environment {
        None => (Vec3::ZERO, None),
        Some(Environment::Constant { radiance }) => (*radiance, None),
        Some(Environment::Image { path, scale }) => (Vec3::ZERO, Some(EnvironmentMap::load(path, *scale, src)?)),
        Some(Environment::Cube { faces, scale }) => (Vec3::ZERO, Some(EnvironmentMap::load_cube(faces, *scale, src)?)),
    })
}

/// Every distinct (file, encoding) map the materials use, loaded once, and per material its
/// albedo, normal and specular maps' slots (index + 1; 0: none).
fn load_material_maps(scene: &Scene) -> Result<(Vec<TracedTexture>, Vec<[u32; 4]>)> {
    let src = &scene.source;
    let mut textures = Vec::new();
    let mut loaded: Vec<(std::path::PathBuf, bool)> = Vec::new();
    let mut material_maps = Vec::with_capacity(scene.materials.len());
    for m in &scene.materials {
        let mut slots = [0u32; 4];
        for (k, (field, map, srgb)) in [
            ("albedo_map", &m.albedo_map, true),
            ("normal_map", &m.normal_map, false),
            ("specular_map", &m.specular_map, false),
        ]
        .into_iter()
        .enumerate()
        {
            let Some(path) = map else { continue };
            let key = (path.clone(), srgb);
            let index = match loaded.iter().position(|l| *l == key) {
                Some(i) => i,
                None => {
                    textures.push(load_texture(path, srgb).map_err(|e| {
                        Error::Usage(format!(
                            "{src}: material \"{}\": {field}: cannot load {}: {e}",
                            m.name,
                            path.display()
                        ))
                    })?);
                    loaded.push(key);
                    textures.len() - 1
                }
            };
            slots[k] = index as u32 + 1;
        }
        material_maps.push(slots);
    }
    Ok((textures, material_maps))
}

/// A sphere or quad light as the tracer reads it; `None` for punctual lights (listed first by
/// `punctual_lights`).
fn area_light(l: &Light) -> Option<GpuLight> {
    match l {
        Light::Sphere {
            center,
            radius,
            radiance,
            ..
        } => Some(GpuLight {
            position: center.extend(LIGHT_SPHERE).into(),
            direction: [*radius, 0.0, 0.0, 0.0],
            intensity: radiance.extend(0.0).into(),
            cone: [0.0; 4],
        }),
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            radiance,
            ..
        } => Some(GpuLight {
            position: corner.extend(LIGHT_QUAD).into(),
            direction: edge_u.extend(0.0).into(),
            intensity: radiance.extend(0.0).into(),
            cone: edge_v.extend(0.0).into(),
        }),
        Light::Point { .. } | Light::Spot { .. } | Light::Directional { .. } => None,
    }
}

/// Every object's triangles with positive area in world space, in scene order, with their
/// vertex normals, tangent frames and uvs, and materials.
struct Gathered {
    corners: Vec<[Vec3; 3]>,
    normals: Vec<[Vec3; 3]>,
    frames: Vec<[(Vec4, Vec2); 3]>,
    material_of: Vec<u32>,
}

impl Gathered {
    fn from_objects(scene: &Scene, time_s: f32) -> Result<Gathered> {
        let mut out = Gathered {
            corners: Vec::new(),
            normals: Vec::new(),
            frames: Vec::new(),
            material_of: Vec::new(),
        };
        for obj in &scene.objects {
            let mut mesh = scene.wind_mesh(obj, obj.load_mesh(std::path::Path::new("."))?, time_s)?;
            // What the raster vertex buffer substitutes for missing attributes (`push_vertices`
            // in src/renderer/scene_gpu.rs), before the placement, as the vertex shaders see it.
            let count = mesh.positions.len();
            if mesh.uvs.len() != count {
                mesh.uvs = vec![Vec2::ZERO; count];
            }
            if mesh.tangents.len() != count {
                mesh.tangents = vec![Vec4::new(1.0, 0.0, 0.0, 1.0); count];
            }
            if mesh.normals.len() != count {
                // Zero normals fall back to the geometric normal in the shader.
                mesh.normals = vec![Vec3::ZERO; count];
            }
            let mesh = mesh.transformed(&obj.transform);
            for [a, b, c] in mesh.triangles() {
                let p = [mesh.positions[a], mesh.positions[b], mesh.positions[c]];
                // Zero-area triangles are never hit; leaving them out keeps the BVH tight.
                let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length_squared();
                if !(area2 > 0.0 && area2.is_finite()) {
                    continue;
                }
                let n = |i: usize| mesh.normals.get(i).copied().unwrap_or(Vec3::ZERO);
                let tangent_uv = |i: usize| {
                    (
                        mesh.tangents.get(i).copied().unwrap_or(Vec4::X),
                        mesh.uvs.get(i).copied().unwrap_or(Vec2::ZERO),
                    )
                };
                out.corners.push(p);
                out.normals.push([n(a), n(b), n(c)]);
                out.frames.push([tangent_uv(a), tangent_uv(b), tangent_uv(c)]);
                out.material_of.push(obj.material as u32);
            }
        }
        Ok(out)
    }

    /// The triangles' GPU records in the BVH's leaf order: positions and edges, and shading.
    fn in_bvh_order(&self, bvh: &Bvh) -> (Vec<TracedTriangle>, Vec<TriangleShading>) {
        let mut triangles = Vec::with_capacity(self.corners.len());
        let mut shading = Vec::with_capacity(self.corners.len());
        for &t in &bvh.order {
            let [p0, p1, p2] = self.corners[t as usize];
            let [n0, n1, n2] = self.normals[t as usize];
            let [(t0, uv0), (t1, uv1), (t2, uv2)] = self.frames[t as usize];
            triangles.push(TracedTriangle {
                p0: p0.extend(0.0).into(),
                e1: (p1 - p0).extend(0.0).into(),
                e2: (p2 - p0).extend(0.0).into(),
            });
            shading.push(TriangleShading {
                n0: n0.into(),
                material: self.material_of[t as usize],
                n1: n1.into(),
                _pad0: 0,
                n2: n2.into(),
                _pad1: 0,
                t0: t0.into(),
                t1: t1.into(),
                t2: t2.into(),
                uv0: uv0.into(),
                uv1: uv1.into(),
                uv2: uv2.into(),
                _pad2: [0.0; 2],
            });
        }
        (triangles, shading)
    }
}

impl TracedScene {
    /// Gathers every object's triangles in world space. Features the tracer does not model are
    /// errors naming the scene and the field, never silently different results.
    pub fn build(scene: &Scene) -> Result<TracedScene> {
        TracedScene::build_at(scene, 0.0)
    }

    /// The scene at `time_s` on the renderer's clock: each object's wind applied to its mesh,
    /// the lights as [`Scene::lights_at`] has them.
    pub fn build_at(scene: &Scene, time_s: f32) -> Result<TracedScene> {
        let moved;
        let scene = if scene.has_motion() || scene.light_board.is_some() {
            moved = Scene {
                lights: scene.lights_at(time_s),
                light_board: None,
                light_motion: None,
                ..scene.clone()
            };
            &moved
        } else {
            scene
        };
        let (environment, environment_map) = load_environment(scene)?;
        let (textures, material_maps) = load_material_maps(scene)?;
        let gathered = Gathered::from_objects(scene, time_s)?;
        let bvh = Bvh::build(&gathered.corners);
        let (triangles, shading) = gathered.in_bvh_order(&bvh);
        let materials = scene
            .materials
            .iter()
            .zip(material_maps)
            .map(|(m, maps)| TracedMaterial {
                albedo: m.albedo.extend(m.opacity).into(),
                specular: m.specular.extend(m.exponent).into(),
                transmittance: m.transmittance.extend(0.0).into(),
                emission: m.emission.extend(0.0).into(),
                maps,
            })
            .collect();
        let mut lights = punctual_lights(scene);
        let punctual_lights = lights.len() as u32;
        lights.extend(scene.lights.iter().filter_map(area_light));
        Ok(TracedScene {
            corners: gathered.corners,
            bvh,
            triangles,
            shading,
            materials,
            lights,
            punctual_lights,
            textures,
            environment,
            environment_map,
        })
    }

    /// Whether a ray leaving a path's last vertex can still find light: some material emits or
    /// the environment is not black. Otherwise the tracer does not trace that ray.
    pub fn light_beyond_last_bounce(&self) -> bool {
        self.materials.iter().any(|m| m.emission[..3].iter().any(|&e| e != 0.0))
            || self.environment != Vec3::ZERO
            || self.environment_map.is_some()
    }

    /// Every texture's texels, one after another, and per texture (first texel, width, height, 0):
    /// the `texture_texels` and `textures` buffers.
    pub fn texture_buffers(&self) -> (Vec<[f32; 4]>, Vec<[u32; 4]>) {
        let mut texels = Vec::new();
        let mut headers = Vec::with_capacity(self.textures.len());
        for t in &self.textures {
            headers.push([texels.len() as u32, t.width, t.height, 0]);
            texels.extend_from_slice(&t.texels);
        }
        (texels, headers)
    }

    /// The buffers and BVH tables, the tables registered in `states`. The octant links only
    /// where `walk` reads them (32 bytes a node); otherwise the binding gets one zeroed texel.
    pub fn upload(&self, gpu: &mut Gpu, states: &mut ResourceStates, walk: BvhWalk) -> Result<SceneBuffers> {
        // Shaders declare runtime arrays; an empty one is bound as one zeroed element.
        fn storage<T: Pod + Zeroable>(gpu: &mut Gpu, name: &str, items: &[T]) -> Result<BufferId> {
            let zero = [T::zeroed()];
            let items = if items.is_empty() { &zero[..] } else { items };
            Ok(gpu.create_buffer_init(name, vk::BufferUsageFlags::STORAGE_BUFFER, bytemuck::cast_slice(items))?)
        }
        let (texels, headers) = self.texture_buffers();
        Ok(SceneBuffers {
            texture_texels: TexelTable::upload(gpu, states, "reference texture texels", &texels)?,
            textures: TexelTable::upload(gpu, states, "reference textures", &headers)?,
            bvh_nodes: TexelTable::upload(gpu, states, "reference bvh nodes", &self.bvh.nodes)?,
            bvh_triangles: TexelTable::upload(gpu, states, "reference bvh triangles", &self.triangles)?,
            bvh_skips: self.octant_links(gpu, states, walk)?,
            shading: TexelTable::upload(gpu, states, "reference triangle shading", &self.shading)?,
            materials: TexelTable::upload(gpu, states, "reference materials", &self.materials)?,
            lights: storage(gpu, "reference lights", &self.lights)?,
            environment_map: TexelTable::upload(
                gpu,
                states,
                "reference environment map",
                self.environment_map.as_ref().map_or(&[][..], |m| &m.texels),
            )?,
            environment_cdf: TexelTable::upload_packed(
                gpu,
                states,
                "reference environment cdf",
                self.environment_map.as_ref().map_or(&[][..], |m| &m.cdf),
            )?,
        })
    }
}

impl TracedScene {
    /// The table `bvh_skips`: the octant links for [`BvhWalk::Ordered`], one zeroed texel for
    /// the stack walk, which does not read it.
    pub fn octant_links(&self, gpu: &mut Gpu, states: &mut ResourceStates, walk: BvhWalk) -> Result<TexelTable> {
        let links = match walk {
            BvhWalk::Ordered => self.bvh.octant_skip_links(),
            BvhWalk::Stack => Vec::new(),
        };
        TexelTable::upload_packed(gpu, states, "reference bvh skip links", &links)
    }
}

/// What the tracer reads of a [`TracedScene`]: the lights in a storage buffer (every invocation
/// reads the same light at a time) and the rest as texel tables, named after the shader
/// bindings.
#[derive(Clone, Copy, Debug)]
pub struct SceneBuffers {
    pub bvh_nodes: TexelTable,
    pub bvh_triangles: TexelTable,
    pub bvh_skips: TexelTable,
    pub shading: TexelTable,
    pub materials: TexelTable,
    pub lights: BufferId,
    pub environment_map: TexelTable,
    pub environment_cdf: TexelTable,
    pub texture_texels: TexelTable,
    pub textures: TexelTable,
}

impl SceneBuffers {
    /// Declares the pass's reads of all of it in `stages`.
    pub fn read<'g, 'a>(&self, pass: PassBuilder<'g, 'a>, stages: vk::PipelineStageFlags2) -> PassBuilder<'g, 'a> {
        let mut pass = pass.buffer(self.lights, Access::StorageRead { stages }, Some("lights"));
        for (name, table) in [
            ("bvh_nodes", self.bvh_nodes),
            ("bvh_triangles", self.bvh_triangles),
            ("bvh_skips", self.bvh_skips),
            ("shading_table", self.shading),
            ("material_table", self.materials),
            ("environment_table", self.environment_map),
            ("environment_cdf_table", self.environment_cdf),
            ("texture_table", self.texture_texels),
            ("texture_headers", self.textures),
        ] {
            pass = table.read(pass, name, stages);
        }
        pass
    }
}
