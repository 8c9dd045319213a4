//! The static geometry a light-map covers: every object and area-light emitter of the scene in
//! world space as the bakers see it, with what the renderer draws it with; animated objects set
//! apart as the seed's entities.

use glam::{Mat4, Vec3};

use super::patches::Triangle;
use crate::error::{Error, Result};
use crate::gpu_scene::SceneGpu;
use crate::scene::{Light, Scene};
use crate::util::image_io::srgb_decode;

/// One scene draw's triangles as the baker sees them, and what the renderer draws them with.
#[derive(Clone)]
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
    from_draws(
        scene,
        gpu.draws
            .iter()
            .zip(&gpu.meshes)
            .map(|(item, mesh)| (item.object, item.model, mesh)),
        method,
    )
}

/// [`static_geometry`] without a GPU: the scene's meshes loaded on the CPU, in the order the
/// scene's upload draws them (objects, then area-light emitters). For tests and tools.
pub fn scene_geometry(scene: &Scene, method: &str) -> Result<StaticGeometry> {
    let mut meshes = Vec::new();
    for o in &scene.objects {
        meshes.push((
            Some(meshes.len()),
            o.transform,
            o.load_mesh(std::path::Path::new("."))
                .map_err(|e| Error::Usage(e.to_string()))?,
        ));
    }
    for (_, mesh, _) in crate::gpu_scene::emitter_meshes(scene) {
        meshes.push((None, Mat4::IDENTITY, mesh));
    }
    from_draws(scene, meshes.iter().map(|(o, m, mesh)| (*o, *m, mesh)), method)
}

fn from_draws<'a>(
    scene: &Scene,
    draws: impl Iterator<Item = (Option<usize>, Mat4, &'a crate::scene::Mesh)>,
    method: &str,
) -> Result<StaticGeometry> {
    let src = &scene.source;
    let mut emitters = Vec::new();
    for (i, l) in scene.lights.iter().enumerate() {
        match l {
            Light::Quad { radiance, .. } => emitters.push(*radiance),
            Light::Sphere { .. } => {
                return Err(Error::Usage(format!(
                    "{src}: lights[{i}] ({:?}): {method} does not patch sphere lights yet (use a quad light)",
                    l.name()
                )))
            }
            _ => {}
        }
    }
    let mut out = StaticGeometry {
        triangles: Vec::new(),
        draw: Vec::new(),
        object_space: Vec::new(),
        uvs: Vec::new(),
        material: Vec::new(),
        entities: Vec::new(),
    };
    let mut emitter = 0;
    for (d, (object, model, mesh)) in draws.enumerate() {
        let (albedo, emission, sky) = match object {
            Some(o) => {
                let obj = &scene.objects[o];
                if obj.animation.is_some() {
                    out.entities.push(d);
                    continue;
                }
                let m = scene
                    .materials
                    .get(obj.material)
                    .ok_or_else(|| Error::Internal(format!("{src}: objects[{o}]: material index out of range")))?;
                // The light-map is multiplied by the albedo map texel by texel when drawn; a
                // bounce reflects the map's mean (what qrad does with a texture's average).
                let map_mean = match &m.albedo_map {
                    Some(path) => mean_albedo(path).map_err(|e| {
                        Error::Usage(format!(
                            "{src}: material {:?}: albedo_map: cannot load {}: {e}",
                            m.name,
                            path.display()
                        ))
                    })?,
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
            out.triangles.push(Triangle {
                p,
                object: d,
                albedo: albedo.as_dvec3(),
                emission: emission.as_dvec3(),
                sky,
                part: 0,
            });
            out.draw.push(d);
            out.object_space
                .push([0, 1, 2].map(|k| mesh.positions[t[k] as usize].to_array()));
            out.uvs.push(uv);
            out.material.push(object.map(|o| scene.objects[o].material));
        }
    }
    Ok(out)
}

/// The mean of an albedo map's texels, sRGB-decoded as the raster methods decode them.
fn mean_albedo(path: &std::path::Path) -> std::result::Result<Vec3, String> {
    let img = crate::util::image_io::open_image(path)?.to_rgba8();
    let n = (img.width() as f64 * img.height() as f64).max(1.0);
    let mut sum = glam::DVec3::ZERO;
    for p in img.pixels() {
        sum += glam::DVec3::new(
            srgb_decode(p.0[0]) as f64,
            srgb_decode(p.0[1]) as f64,
            srgb_decode(p.0[2]) as f64,
        );
    }
    Ok((sum / n).as_vec3())
}

/// Share of the view seen from behind under which no warning is given (grazing rays at the
/// silhouettes of thin surfaces).
const BEHIND_WARNING_SHARE: f64 = 0.01;

/// The share of `camera`'s view (a 64 × 48 grid of rays) whose first surface among `triangles`
/// (sky and emitters excluded: neither holds baked light) is seen from behind its normal.
pub fn seen_from_behind(triangles: &[Triangle], camera: &crate::scene::Camera) -> f64 {
    let occluders = super::solve::Occluders::new(triangles);
    let (w, h) = (64u32, 48u32);
    let mut behind = 0usize;
    for j in 0..h {
        for i in 0..w {
            let (o, d) = camera.pixel_center_ray(i, j, w, h);
            let (o, d) = (o.as_dvec3(), d.as_dvec3());
            if let Some((_, t)) = occluders.first_hit(o, d) {
                let t = &triangles[t];
                if !t.sky && t.albedo != glam::DVec3::ZERO && t.normal().dot(d) > 0.0 {
                    behind += 1;
                }
            }
        }
    }
    behind as f64 / (w * h) as f64
}

/// One warning line when the scene's camera sees a one-sided bake's surfaces from behind (a
/// closed mesh around the camera, such as a box mesh, whose faces point out): the bake lights
/// each surface on its front only, and the back shows the front's light, where the reference
/// lights each side by what reaches it.
pub fn behind_warning(scene: &Scene, triangles: &[Triangle], method: &str) -> Option<String> {
    let share = seen_from_behind(triangles, &scene.camera);
    (share > BEHIND_WARNING_SHARE).then(|| {
        format!(
            "warning: {}: {method}: {:.0}% of the camera's view sees surfaces from behind, which the bake lights on their front side only (the back shows the front's light); turn them to face the camera",
            scene.source,
            100.0 * share
        )
    })
}
