//! From a scene to a baked light-map: the static triangles the baker sees, direct light from the
//! scene's punctual lights as initial energy, the solve, and the atlas (charts shelf-packed with
//! one-texel gaps, border patches filled by the seed's passes 1 and 2, [`super::border`], so
//! bilinear filtering never reads black at a polygon's edge nor steps at a seam).

use glam::{DVec3, Mat4, Vec3};

use super::patches::{Patches, Triangle};
use super::solve::{self, Occluders, Settings};
use crate::backend::{vk, Bind, BufferId, Gpu, GraphicsPipelineDesc, PipelineId, RenderTarget, RenderingDesc, SubresourceRange, VertexAttribute, VertexLayout};
use crate::error::{Error, Result};
use crate::gpu_scene::DrawPush;
use crate::gpu_scene::SceneGpu;
use crate::graph::{Access, PassBuilder};
use crate::lighting::{CreateContext, FrameContext};
use crate::progress::Progress;
use crate::reference::scene_data::srgb_decode;
use crate::scene::{Light, Scene};
use crate::shaders::ShaderLibrary;

/// What the light-map holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Content {
    /// Direct light from the scene's lights and emitters, and every bounce: the whole static frame.
    All,
    /// Only light that bounced at least once (for drawing under a direct method).
    Bounces,
}

/// One scene draw's triangles as the baker sees them, and what the renderer draws them with.
pub struct StaticGeometry {
    pub triangles: Vec<Triangle>,
    /// Per triangle: the scene draw it came from, its corners in object space (the renderer
    /// transforms them exactly as every method does, so depths match) and its mesh uvs.
    pub draw: Vec<usize>,
    pub object_space: Vec<[[f32; 3]; 3]>,
    pub uvs: Vec<[[f32; 2]; 3]>,
    /// Per triangle: its object's material (none for an area light's emitter).
    pub material: Vec<Option<usize>>,
    /// Scene draws of animated objects (the seed's entities): not patched and no occluders in
    /// the bake — dynamic objects neither receive nor cast light-map light (digest §3, item 7) —
    /// but drawn in the base pass, for their depth and emission.
    pub entities: Vec<usize>,
}

/// The scene's draws (objects and area-light emitters) in world space; animated objects are set
/// apart as entities. Sphere lights are refused: sphere emitters are not patched yet.
pub fn static_geometry(scene: &Scene, gpu: &SceneGpu, method: &str) -> Result<StaticGeometry> {
    from_draws(scene, gpu.draws.iter().zip(&gpu.meshes).map(|(item, mesh)| (item.object, item.model, mesh)), method)
}

/// [`static_geometry`] without a GPU: the scene's meshes loaded on the CPU, in the order the
/// scene's upload draws them (objects, then area-light emitters). For tests and tools.
pub fn scene_geometry(scene: &Scene, method: &str) -> Result<StaticGeometry> {
    let mut meshes = Vec::new();
    for o in &scene.objects {
        meshes.push((Some(meshes.len()), o.transform, o.load_mesh(std::path::Path::new(".")).map_err(|e| Error::Usage(e.to_string()))?));
    }
    for (_, mesh, _) in crate::gpu_scene::emitter_meshes(scene) {
        meshes.push((None, Mat4::IDENTITY, mesh));
    }
    from_draws(scene, meshes.iter().map(|(o, m, mesh)| (*o, *m, mesh)), method)
}

fn from_draws<'a>(scene: &Scene, draws: impl Iterator<Item = (Option<usize>, Mat4, &'a crate::scene::Mesh)>, method: &str) -> Result<StaticGeometry> {
    let src = &scene.source;
    let mut emitters = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        match l {
            Light::Quad { radiance, .. } => emitters.push(*radiance),
            Light::Sphere { .. } => return Err(Error::Usage(format!("{src}: lights[{i}] ({:?}): {method} does not patch sphere lights yet (use a quad light)", l.name()))),
            _ => {}
        }
    }
    let mut out = StaticGeometry { triangles: Vec::new(), draw: Vec::new(), object_space: Vec::new(), uvs: Vec::new(), material: Vec::new(), entities: Vec::new() };
    let mut emitter = 0;
    for (d, (object, model, mesh)) in draws.enumerate() {
        let (albedo, emission, sky) = match object {
            Some(o) => {
                let obj = &scene.objects[o];
                if obj.animation.is_some() {
                    out.entities.push(d);
                    continue;
                }
                let m = scene.materials.get(obj.material).ok_or_else(|| Error::Usage(format!("{src}: objects[{o}]: material index out of range")))?;
                // The light-map is multiplied by the albedo map texel by texel when drawn; a
                // bounce reflects the map's mean (what qrad does with a texture's average).
                let map_mean = match &m.albedo_map {
                    Some(path) => mean_albedo(path).map_err(|e| Error::Usage(format!("{src}: material {:?}: albedo_map: cannot load {}: {e}", m.name, path.display())))?,
                    None => Vec3::ONE,
                };
                (m.albedo * map_mean, m.emission, m.sky)
            }
            None => {
                let e = emitters.get(emitter).copied().unwrap_or(Vec3::ZERO);
                emitter += 1;
                (Vec3::ZERO, e, false)
            }
        };
        let m: Mat4 = model;
        for t in mesh.indices.chunks_exact(3) {
            let p = [0, 1, 2].map(|k| m.transform_point3(mesh.positions[t[k] as usize]).as_dvec3());
            let uv = [0, 1, 2].map(|k| mesh.uvs.get(t[k] as usize).map_or([0.0; 2], |v| v.to_array()));
            out.triangles.push(Triangle { p, object: d, albedo: albedo.as_dvec3(), emission: emission.as_dvec3(), sky });
            out.draw.push(d);
            out.object_space.push([0, 1, 2].map(|k| mesh.positions[t[k] as usize].to_array()));
            out.uvs.push(uv);
            out.material.push(object.map(|o| scene.objects[o].material));
        }
    }
    Ok(out)
}

/// The mean of an albedo map's texels, sRGB-decoded as the raster methods decode them.
fn mean_albedo(path: &std::path::Path) -> std::result::Result<Vec3, String> {
    let img = crate::image_io::open_image(path)?.to_rgba8();
    let n = (img.width() as f64 * img.height() as f64).max(1.0);
    let mut sum = glam::DVec3::ZERO;
    for p in img.pixels() {
        sum += glam::DVec3::new(srgb_decode(p.0[0]) as f64, srgb_decode(p.0[1]) as f64, srgb_decode(p.0[2]) as f64);
    }
    Ok((sum / n).as_vec3())
}

/// Adds the reflected direct light of the scene's point, spot and directional lights (shadowed)
/// to every patch's total and unshot radiosity; returns each patch's share. Directional lights
/// are suns ([`super::sun`]) as the corrected mode treats them.
pub fn add_direct_light(p: &mut Patches, occluders: &Occluders, scene: &Scene) -> Result<Vec<DVec3>> {
    add_direct_light_in(p, occluders, scene, solve::Mode::Corrected)
}

/// The scene's BSP world, if it has one, and where it sits (world point `w` is scene point
/// `world_to_scene(w) + translate`).
fn bsp_world(scene: &Scene) -> Result<Option<(std::sync::Arc<crate::world::CompiledWorld>, Vec3)>> {
    for obj in &scene.objects {
        if let crate::scene::MeshSource::World { level, .. } = &obj.mesh {
            let compiled = crate::scene::world_mesh::compiled(level).map_err(|e| Error::Usage(format!("{}: {}: the world does not compile: {e}", scene.source, level.mesh_name())))?;
            return Ok(Some((compiled, obj.transform.w_axis.truncate())));
        }
    }
    Ok(None)
}

/// [`add_direct_light`] with `mode`'s sun (faithful: rays must reach sky, then smoothing) and
/// point lights (faithful, in a BSP world: CaLight lights every patch in the light's PVS, with no
/// ray, so a pillar casts no shadow in the light-map; elsewhere, and corrected, a shadow ray).
pub fn add_direct_light_in(p: &mut Patches, occluders: &Occluders, scene: &Scene, mode: solve::Mode) -> Result<Vec<DVec3>> {
    let mut direct = vec![DVec3::ZERO; p.patches.len()];
    let eps = 1e-4 * p.size;
    let pvs = if mode == solve::Mode::Faithful { bsp_world(scene)? } else { None };
    let leaf = |x: DVec3| pvs.as_ref().map(|(w, translate)| w.leaf_of(crate::scene::world_mesh::scene_to_world(x.as_vec3() - *translate)));
    for (k, q) in p.patches.iter().enumerate() {
        if !q.inside() {
            continue;
        }
        let x = q.centre + q.normal * eps;
        let mut e = DVec3::ZERO;
        for l in &scene.lights {
            let (to_light, irradiance, far) = match l {
                Light::Point { position, intensity, .. } => {
                    let d = position.as_dvec3() - x;
                    (d.normalize_or_zero(), intensity.as_dvec3() / d.length_squared().max(1e-12), position.as_dvec3())
                }
                Light::Spot { position, direction, intensity, inner_deg, outer_deg, .. } => {
                    let d = position.as_dvec3() - x;
                    let l = d.normalize_or_zero();
                    let falloff = crate::lighting::brdf::spot_falloff(outer_deg.to_radians().cos(), inner_deg.to_radians().cos(), (-l).as_vec3().dot(direction.normalize()));
                    (l, intensity.as_dvec3() * falloff as f64 / d.length_squared().max(1e-12), position.as_dvec3())
                }
                _ => continue,
            };
            let cos = q.normal.dot(to_light);
            let seen = match (&pvs, leaf(x), leaf(far)) {
                (Some((w, _)), Some(a), Some(b)) => w.is_visible(a, b),
                _ => occluders.visible(x, far),
            };
            if cos <= 0.0 || !seen {
                continue;
            }
            e += irradiance * cos;
        }
        direct[k] = q.albedo * e;
    }
    for l in &scene.lights {
        if let Light::Directional { direction, irradiance, .. } = l {
            let to_sun = -direction.as_dvec3().normalize_or_zero();
            let lit = super::sun::lit_fraction(p, occluders, to_sun, mode);
            for (k, q) in p.patches.iter().enumerate() {
                direct[k] += q.albedo * irradiance.as_dvec3() * (q.normal.dot(to_sun).max(0.0) * lit[k]);
            }
        }
    }
    for (q, b) in p.patches.iter_mut().zip(&direct) {
        q.total += *b;
        q.unshot += *b;
    }
    Ok(direct)
}

/// Where each chart lies in the atlas: its texel offset, and the atlas size.
#[derive(Clone, Debug)]
pub struct Atlas {
    pub width: u32,
    pub height: u32,
    pub offsets: Vec<(u32, u32)>,
}

/// Shelf packing, tallest first, one empty texel between charts (bilinear filtering must not
/// reach a neighbour: seed 000 §3.3.6).
pub fn pack(p: &Patches) -> Atlas {
    let area: usize = p.charts.iter().map(|c| (c.width + 1) * (c.height + 1)).sum();
    let widest = p.charts.iter().map(|c| c.width + 1).max().unwrap_or(1);
    let width = ((area as f64).sqrt().ceil() as usize).max(widest).next_power_of_two() as u32;
    let mut order: Vec<usize> = (0..p.charts.len()).collect();
    order.sort_by_key(|&c| (std::cmp::Reverse(p.charts[c].height), c));
    let mut offsets = vec![(0, 0); p.charts.len()];
    let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
    for c in order {
        let (w, h) = (p.charts[c].width as u32 + 1, p.charts[c].height as u32 + 1);
        if x + w > width {
            x = 0;
            y += shelf;
            shelf = 0;
        }
        offsets[c] = (x, y);
        x += w;
        shelf = shelf.max(h);
    }
    Atlas { width, height: (y + shelf).max(1), offsets }
}

/// The light-map texels (RGBA32F, row-major): each patch's value (after the border passes,
/// [`super::border`]) at its texel.
pub fn texels(p: &Patches, atlas: &Atlas, value: impl Fn(usize) -> DVec3) -> Vec<[f32; 4]> {
    let mut out = vec![[0.0f32; 4]; (atlas.width * atlas.height) as usize];
    for (ci, c) in p.charts.iter().enumerate() {
        let (ox, oy) = atlas.offsets[ci];
        for j in 0..c.height {
            for i in 0..c.width {
                let v = value(c.first + j * c.width + i);
                out[((oy + j as u32) * atlas.width + ox + i as u32) as usize] = [v.x as f32, v.y as f32, v.z as f32, 1.0];
            }
        }
    }
    out
}

/// Where the shooting runs.
pub enum Shooter<'a> {
    Cpu,
    Gpu(&'a mut Gpu, &'a ShaderLibrary),
}

/// Texels in [0, 1] as R8G8B8A8_UNORM bytes (alpha 255).
pub fn to_rgb8(texels: &[f32]) -> Vec<u8> {
    texels.chunks_exact(4).flat_map(|t| [t[0], t[1], t[2]].map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8).into_iter().chain([255])).collect()
}

/// Each triangle corner's light-map coordinate in the atlas (3 per triangle); a sky chart's
/// triangles all read the centre of its one black texel.
pub fn triangle_uvs(triangles: &[Triangle], p: &Patches, atlas: &Atlas) -> Vec<[f32; 2]> {
    let mut uv = vec![[0.0f32; 2]; 3 * triangles.len()];
    for (ci, c) in p.charts.iter().enumerate() {
        let (ox, oy) = atlas.offsets[ci];
        for &t in &c.triangles {
            for (k, q) in triangles[t].p.iter().enumerate() {
                let (s, r) = if c.sky {
                    (ox as f64 + 0.5, oy as f64 + 0.5)
                } else {
                    let d = *q - c.origin;
                    (d.dot(c.u) / p.size + ox as f64, d.dot(c.v) / p.size + oy as f64)
                };
                uv[3 * t + k] = [(s / atlas.width as f64) as f32, (r / atlas.height as f64) as f32];
            }
        }
    }
    uv
}

/// Bakes the light-map of `geometry`: patches, direct light, the solve, the texels.
pub fn bake(
    geometry: &StaticGeometry,
    scene: &Scene,
    patch_size: f64,
    settings: &Settings,
    content: Content,
    shooter: Shooter<'_>,
    progress: &mut Progress,
) -> Result<(Patches, Atlas, Vec<[f32; 4]>, solve::Report)> {
    let mut p = Patches::build(&geometry.triangles, patch_size);
    let occluders = Occluders::new(&geometry.triangles);
    let direct = add_direct_light_in(&mut p, &occluders, scene, settings.mode)?;
    let mut report = match shooter {
        Shooter::Cpu => solve::solve(&mut p, &occluders, settings, progress),
        Shooter::Gpu(gpu, shaders) => super::gpu::solve(gpu, shaders, &mut p, &geometry.triangles, settings, progress)?,
    };
    let atlas = pack(&p);
    let mut values: Vec<DVec3> = p
        .patches
        .iter()
        .enumerate()
        .map(|(k, q)| {
            let mut reflected = q.total - q.emission;
            if content == Content::Bounces {
                reflected -= direct[k];
            }
            let inv = |a: f64| if a > 0.0 { 1.0 / (a * std::f64::consts::PI) } else { 0.0 };
            (reflected * DVec3::new(inv(q.albedo.x), inv(q.albedo.y), inv(q.albedo.z))).max(DVec3::ZERO)
        })
        .collect();
    if settings.mode == solve::Mode::Faithful {
        // CaLight's light-maps are display values: tone reproduction, 8 bits, read as [0, 1].
        let inside: Vec<usize> = (0..values.len()).filter(|&k| p.patches[k].inside()).collect();
        let mapped = super::tone::reproduce(&inside.iter().map(|&k| values[k]).collect::<Vec<_>>());
        for (&k, c) in inside.iter().zip(mapped) {
            values[k] = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) / 255.0;
        }
    }
    report.border_refused = super::border::apply(&p, &occluders, &mut values);
    if settings.mode == solve::Mode::Faithful {
        // CaLight stores light-maps as RGB8: the border passes averaged display values, which
        // are quantized again here, so the texels are exactly the bytes the texture holds.
        for v in &mut values {
            *v = (*v * 255.0).round().clamp(DVec3::ZERO, DVec3::splat(255.0)) / 255.0;
        }
    }
    let texels = texels(&p, &atlas, |k| values[k]);
    Ok((p, atlas, texels, report))
}

/// `LightmapVertex` of glsl/radiosity/lightmap.vert (object space: the draw's model matrix is
/// pushed, so the depth is the one every other method computes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct LightmapVertex {
    position: [f32; 3],
    normal: [f32; 3],
    lightmap_uv: [f32; 2],
    uv: [f32; 2],
}

/// The static triangles with their light-map coordinates, and the entities without: what a
/// light-mapped base term draws (radiosity's light-maps and SH light-maps alike).
pub struct Mesh {
    vertices: BufferId,
    /// (scene draw, first vertex, vertex count).
    draws: Vec<(usize, u32, u32)>,
    /// Per entry of `draws`: an entity's animation (placed at the frame clock's time, as the
    /// direct methods place it).
    animations: Vec<Option<crate::scene::Animation>>,
}

impl Mesh {
    /// `uvs`: 6 floats per triangle of `geometry` (its corners' light-map coordinates).
    pub fn new(cx: &mut CreateContext<'_>, geometry: &StaticGeometry, uvs: &[f32], method: &str) -> Result<Mesh> {
        // Vertices grouped by scene draw (static_geometry emits them in draw order).
        let mut vertices = Vec::with_capacity(3 * geometry.triangles.len());
        let mut draws: Vec<(usize, u32, u32)> = Vec::new();
        for t in 0..geometry.triangles.len() {
            let d = geometry.draw[t];
            match draws.last_mut() {
                Some(last) if last.0 == d => last.2 += 3,
                _ => draws.push((d, vertices.len() as u32, 3)),
            }
            let o = geometry.object_space[t].map(Vec3::from);
            let n = (o[1] - o[0]).cross(o[2] - o[0]).normalize_or_zero().to_array();
            for k in 0..3 {
                vertices.push(LightmapVertex { position: o[k].to_array(), normal: n, lightmap_uv: [uvs[6 * t + 2 * k], uvs[6 * t + 2 * k + 1]], uv: geometry.uvs[t][k] });
            }
        }
        // Entities: their mesh as it is, outside the light-map (a negative coordinate reads as
        // no light-map light).
        for &d in &geometry.entities {
            let mesh = &cx.scene_gpu.meshes[d];
            let first = vertices.len() as u32;
            for t in mesh.indices.chunks_exact(3) {
                let o = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
                let n = (o[1] - o[0]).cross(o[2] - o[0]).normalize_or_zero().to_array();
                for (k, p) in o.iter().enumerate() {
                    vertices.push(LightmapVertex { position: p.to_array(), normal: n, lightmap_uv: [-1.0, -1.0], uv: mesh.uvs.get(t[k] as usize).map_or([0.0; 2], |v| v.to_array()) });
                }
            }
            draws.push((d, first, vertices.len() as u32 - first));
        }
        let animations = draws.iter().map(|&(d, _, _)| cx.scene_gpu.draws[d].object.and_then(|o| cx.scene.objects[o].animation)).collect();
        let vertices = cx.gpu.create_buffer_init(&format!("{method} vertices"), vk::BufferUsageFlags::VERTEX_BUFFER, bytemuck::cast_slice(&vertices))?;
        cx.states.forget_buffer(vertices);
        Ok(Mesh { vertices, draws, animations })
    }

    /// A pipeline drawing the mesh with `fragment` (and glsl/radiosity/lightmap.vert) into the
    /// radiance target, depth tested and written.
    pub fn pipeline_desc(name: &str, fragment: &str) -> GraphicsPipelineDesc {
        let attr = |location, format, offset| VertexAttribute { location, binding: 0, format, offset };
        let mut desc = GraphicsPipelineDesc::new(name, "radiosity/lightmap.vert", Some(fragment));
        desc.vertex_layout = VertexLayout {
            buffers: vec![(0, std::mem::size_of::<LightmapVertex>() as u32)],
            attributes: vec![attr(0, vk::Format::R32G32B32_SFLOAT, 0), attr(1, vk::Format::R32G32B32_SFLOAT, 12), attr(2, vk::Format::R32G32_SFLOAT, 24), attr(3, vk::Format::R32G32_SFLOAT, 32)],
        };
        desc
    }

    /// Records `pass` (which declares the method's own images) drawing every draw with
    /// `pipeline`; `extra` is bound with each draw's frame, albedo and normal maps.
    pub fn draw<'a>(&'a self, pass: PassBuilder<'_, 'a>, frame: &FrameContext<'a>, pipeline: PipelineId, extra: Vec<(&'static str, Vec<u8>)>) {
        let (scene, t, uniforms, time) = (frame.scene, frame.targets, frame.uniforms, frame.clock.time_s);
        let frag = vk::PipelineStageFlags2::FRAGMENT_SHADER;
        pass.color_attachment(t.radiance, SubresourceRange::mip(0), false)
            .depth_stencil_write(t.depth_stencil, false)
            .buffer(self.vertices, Access::VertexRead, None)
            .buffer(scene.materials, Access::StorageRead { stages: frag }, Some("materials"))
            .record(move |ctx| {
                let _ = ctx.rec.begin_rendering(&RenderingDesc { colors: vec![RenderTarget::load(t.radiance)], depth_stencil: Some(RenderTarget::load(t.depth_stencil)) })?;
                ctx.rec.bind_pipeline(pipeline)?;
                ctx.rec.bind_vertex_buffers(&[(self.vertices, 0)])?;
                for (&(d, first, count), animation) in self.draws.iter().zip(&self.animations) {
                    let item = &scene.draws[d];
                    let model = animation.as_ref().map_or(item.model, |a| a.transform_at(item.model, time));
                    let maps = scene.material_maps[item.material as usize];
                    let mut binds = vec![
                        ("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms))),
                        ("albedo_map", Bind::Sampled { image: maps.albedo, range: SubresourceRange::mip(0), sampler: scene.sampler }),
                        ("normal_map", Bind::Sampled { image: maps.normal, range: SubresourceRange::mip(0), sampler: scene.sampler }),
                    ];
                    binds.extend(extra.iter().map(|(name, bytes)| (*name, Bind::UniformData(bytes))));
                    ctx.bind(&binds)?;
                    ctx.rec.push_constants(DrawPush::new(model, item.material).bytes())?;
                    ctx.rec.draw_from(count, first)?;
                }
                ctx.rec.end_rendering();
                Ok(())
            });
    }
}
