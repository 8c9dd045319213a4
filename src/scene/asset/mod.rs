//! Assets made elsewhere: Wavefront OBJ with its MTL materials, and glTF 2.0 (`.gltf`, `.glb`).
//! An asset is read into parts (one mesh per material, in the asset's own space), lights and
//! cameras; a scene places it with a transform ([`super::MeshSource::Asset`]) or renders it alone
//! ([`asset_scene`]). How each format's materials map onto penumbra's Lambert + Blinn-Phong
//! material is written in `docs/assets.md`.
//!
//! Every error is one [`SceneError`] naming the asset file and the element (`meshes[3].primitives[0]`,
//! `materials[2] "stone".map_Kd`), never a panic and never a silent default.

pub mod cutout;
#[cfg(test)]
mod cutout_tests;
mod gltf;
mod mtl;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::error::SceneError;
use super::mesh::Mesh;
use super::types::{Camera, Environment, Light, Material, MeshSource, Object};

/// An asset as read: its parts in the asset's space (node transforms applied), its lights and
/// cameras in the same space.
#[derive(Debug, Clone)]
pub struct Asset {
    pub parts: Vec<AssetPart>,
    pub lights: Vec<Light>,
    pub cameras: Vec<Camera>,
}

/// The triangles of one material.
#[derive(Debug, Clone)]
pub struct AssetPart {
    pub mesh: Arc<Mesh>,
    pub material: Material,
}

/// A material whose texture cuts its triangles out ([`cutout`]): the mask image, its channel,
/// the factor its values are multiplied by, the cutoff, and the element it came from.
struct CutoutSpec {
    map: PathBuf,
    channel: cutout::Channel,
    factor: f32,
    cutoff: f32,
    field: String,
}

/// A texture of emitted light (glTF `emissiveTexture`, sRGB) times `factor`.
struct EmissionMap {
    map: PathBuf,
    factor: Vec3,
    field: String,
}

/// What a material needs done to its part's triangles when the asset is read.
#[derive(Default)]
struct PartEdits {
    cutout: Option<CutoutSpec>,
    emission: Option<EmissionMap>,
}

/// A part after its edits: cut out, then split by its emission map. No part when nothing is
/// left; two when the map glows on some texels and not on others.
fn edited_parts(mesh: Mesh, material: Material, edits: PartEdits, file: &str) -> Result<Vec<AssetPart>, SceneError> {
    let mesh = match &edits.cutout {
        Some(spec) => match cut_part(mesh, spec, file)? {
            Some(m) => m,
            None => return Ok(Vec::new()),
        },
        None => mesh,
    };
    let Some(em) = &edits.emission else {
        return Ok(vec![AssetPart {
            mesh: Arc::new(mesh),
            material,
        }]);
    };
    let err = |m: String| SceneError::new(file, None, em.field.as_str(), format!("{}: {m}", em.map.display()));
    let split = cutout::emission_split(&em.map).map_err(err)?;
    let glow = split.mean * em.factor;
    let mut parts = Vec::new();
    for (mask, emission, suffix) in [(&split.dark, Vec3::ZERO, ""), (&split.lit, glow, " (emissive)")] {
        let piece = if mask.hides_any(0.5) {
            let (mut m, _) = cutout::cut(&mesh, mask, 0.5);
            if m.indices.is_empty() {
                continue;
            }
            m.complete_attributes();
            m.validate(&format!("{file}: {}", em.field))?;
            m
        } else {
            mesh.clone()
        };
        let mut material = material.clone();
        material.emission = emission;
        material.name = format!("{}{suffix}", material.name);
        parts.push((piece, material));
    }
    crate::errln!(
        "{file}: {}: emission read from its texels: {} of {} triangles glow with the lit texels' mean, \
         ({:.3}, {:.3}, {:.3}) W/(m²·sr); texels under 1% of the brightest ({:.1}% of the map's light) are dark",
        em.field,
        parts
            .iter()
            .filter(|(_, m)| m.emission != Vec3::ZERO)
            .map(|(p, _)| p.triangle_count())
            .sum::<usize>(),
        parts.iter().map(|(p, _)| p.triangle_count()).sum::<usize>(),
        glow.x,
        glow.y,
        glow.z,
        100.0 * split.dropped
    );
    Ok(parts
        .into_iter()
        .map(|(mesh, material)| AssetPart {
            mesh: Arc::new(mesh),
            material,
        })
        .collect())
}

/// `mesh` cut by `spec`'s mask, with a line saying what was cut; `None` when nothing is left.
/// A mask that hides no texel leaves the mesh as it is.
fn cut_part(mesh: Mesh, spec: &CutoutSpec, file: &str) -> Result<Option<Mesh>, SceneError> {
    let err = |m: String| SceneError::new(file, None, spec.field.as_str(), format!("{}: {m}", spec.map.display()));
    let mask = cutout::mask_of_image(&spec.map, spec.channel, spec.factor).map_err(err)?;
    if !mask.hides_any(spec.cutoff) {
        return Ok(Some(mesh));
    }
    let (mut cut, report) = cutout::cut(&mesh, &mask, spec.cutoff);
    let whole = match report.whole_by_centre {
        0 => String::new(),
        n => format!(" ({n} kept or dropped whole by the texel under their centre: no extent in texture space, or too much to cut)"),
    };
    crate::errln!(
        "{file}: {}: alpha cut-out: {} triangles cut along the mask's {}-texel cells into {}{whole}",
        spec.field,
        report.triangles_before,
        report.cell_texels,
        report.triangles_after
    );
    if cut.indices.is_empty() {
        return Ok(None);
    }
    cut.complete_attributes();
    cut.validate(&format!("{file}: {}", spec.field))?;
    Ok(Some(cut))
}

/// Whether `path` names a file [`load_asset`] reads (by its extension, any case).
pub fn is_asset_path(path: &Path) -> bool {
    matches!(extension(path).as_str(), "obj" | "gltf" | "glb")
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Reads an OBJ (+ MTL) or glTF 2.0 asset.
pub fn load_asset(path: &Path) -> Result<Asset, SceneError> {
    let file = path.display().to_string();
    let asset = match extension(path).as_str() {
        "obj" => mtl::load(path)?,
        "gltf" | "glb" => gltf::load(path)?,
        other => {
            return Err(SceneError::new(
                &file,
                None,
                "file",
                format!("unknown asset type {other:?}; expected .obj, .gltf or .glb"),
            ))
        }
    };
    if asset.parts.is_empty() {
        return Err(SceneError::new(
            &file,
            None,
            "file",
            "the asset has no visible triangles",
        ));
    }
    Ok(asset)
}

impl Asset {
    /// Bounds of every part, (min, max).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.parts
            .iter()
            .filter_map(|p| p.mesh.bounds())
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// Adds the asset's parts to a scene as objects placed by `transform`, each with its material
    /// named `{name}:{material}` (made unique), and returns the lights it brings, placed alike.
    pub fn place(
        &self,
        path: &Path,
        name: &str,
        transform: Mat4,
        materials: &mut Vec<Material>,
        objects: &mut Vec<Object>,
    ) -> Vec<Light> {
        for (i, part) in self.parts.iter().enumerate() {
            let mut material = part.material.clone();
            let base = format!("{name}:{}", material.name);
            material.name = base.clone();
            let mut k = 1;
            while materials.iter().any(|m| m.name == material.name) {
                k += 1;
                material.name = format!("{base}#{k}");
            }
            materials.push(material);
            objects.push(Object {
                name: format!("{name}.{i}"),
                mesh: MeshSource::Asset {
                    path: path.to_path_buf(),
                    part: i,
                    mesh: part.mesh.clone(),
                },
                material: materials.len() - 1,
                transform,
                animation: None,
                wind: None,
            });
        }
        self.lights.iter().map(|l| transform_light(l, &transform)).collect()
    }
}

/// `light` moved by `m` (positions as points, directions as vectors, renormalised).
pub fn transform_light(light: &Light, m: &Mat4) -> Light {
    let dir = |d: Vec3| m.transform_vector3(d).try_normalize().unwrap_or(d);
    let mut l = light.clone();
    match &mut l {
        Light::Point { position, .. } => *position = m.transform_point3(*position),
        Light::Spot {
            position, direction, ..
        } => {
            *position = m.transform_point3(*position);
            *direction = dir(*direction);
        }
        Light::Directional { direction, .. } => *direction = dir(*direction),
        Light::Sphere { center, .. } => *center = m.transform_point3(*center),
        Light::Quad {
            corner, edge_u, edge_v, ..
        } => {
            *corner = m.transform_point3(*corner);
            *edge_u = m.transform_vector3(*edge_u);
            *edge_v = m.transform_vector3(*edge_v);
        }
    }
    l
}

/// `camera` moved by `m`.
pub fn transform_camera(camera: &Camera, m: &Mat4) -> Camera {
    Camera {
        position: m.transform_point3(camera.position),
        target: m.transform_point3(camera.target),
        up: m.transform_vector3(camera.up),
        ..camera.clone()
    }
}

/// Radiance of the sky an asset without lights is shown under, W/(m²·sr).
pub const VIEWER_SKY_RADIANCE: Vec3 = Vec3::new(0.20, 0.24, 0.30);
/// Irradiance of the sun an asset without lights is shown under, W/m², and where it shines.
pub const VIEWER_SUN_IRRADIANCE: Vec3 = Vec3::new(2.6, 2.5, 2.3);
pub const VIEWER_SUN_DIRECTION: Vec3 = Vec3::new(-0.4, -0.8, -0.45);

/// A camera looking at bounds `(lo, hi)` from the front-right and above, far enough that the
/// bounding sphere fills the vertical field of view.
pub fn framing_camera(lo: Vec3, hi: Vec3) -> Camera {
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-3);
    let fov_y_deg = 45.0f32;
    let distance = radius / (0.5 * fov_y_deg.to_radians()).sin();
    let view = Vec3::new(0.55, 0.4, 1.0).normalize();
    Camera {
        position: centre + view * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_deg,
        near: (0.01 * radius).max(1e-4),
    }
}

/// The scene of an asset alone, as a viewer shows it: the asset's parts, its lights and its
/// camera `camera` (its first when `None`); with no camera, [`framing_camera`]; with no lights, a
/// constant sky and a sun. Renders with the `forward` method.
pub fn asset_scene(path: &Path, camera: Option<usize>) -> Result<super::Scene, SceneError> {
    let file = path.display().to_string();
    let asset = load_asset(path)?;
    let camera = match (camera, asset.cameras.is_empty()) {
        (Some(i), _) => asset.cameras.get(i).cloned().ok_or_else(|| {
            SceneError::new(
                &file,
                None,
                "cameras",
                format!("camera {i} asked for, the asset has {}", asset.cameras.len()),
            )
        })?,
        (None, false) => asset.cameras[0].clone(),
        (None, true) => {
            let (lo, hi) = asset.bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
            framing_camera(lo, hi)
        }
    };
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("asset").to_owned();
    let abs: PathBuf = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut materials = Vec::new();
    let mut objects = Vec::new();
    let mut lights = asset.place(&abs, &name, Mat4::IDENTITY, &mut materials, &mut objects);
    let mut environment = None;
    if lights.is_empty() {
        environment = Some(Environment::Constant {
            radiance: VIEWER_SKY_RADIANCE,
        });
        lights.push(Light::Directional {
            name: "sun".into(),
            direction: VIEWER_SUN_DIRECTION.normalize(),
            irradiance: VIEWER_SUN_IRRADIANCE,
        });
    }
    Ok(super::Scene {
        source: file,
        camera,
        cameras: asset.cameras.clone(),
        materials,
        objects,
        lights,
        environment,
        methods: vec![super::MethodDecl::implicit_forward()],
        combinations: Vec::new(),
        light_board: None,
        light_motion: None,
        memory_budget_mb: None,
    })
}

/// Checks a colour factor: finite, each channel in [0, 1].
fn unit_colour(v: Vec3, file: &str, field: &str) -> Result<Vec3, SceneError> {
    if !v.is_finite() {
        return Err(SceneError::new(file, None, field, format!("is not finite: {v}")));
    }
    if v.min_element() < 0.0 || v.max_element() > 1.0 {
        return Err(SceneError::new(
            file,
            None,
            field,
            format!("each channel must be in [0, 1], got [{}, {}, {}]", v.x, v.y, v.z),
        ));
    }
    Ok(v)
}

/// An image file an asset refers to: it must exist and be an image penumbra reads.
fn checked_image(path: &Path, file: &str, field: &str) -> Result<PathBuf, SceneError> {
    if !path.is_file() {
        return Err(SceneError::new(
            file,
            None,
            field,
            format!("texture not found: {}", path.display()),
        ));
    }
    crate::util::image_io::image_header(path)
        .map_err(|m| SceneError::new(file, None, field, format!("{}: {m}", path.display())))?;
    Ok(std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()))
}
