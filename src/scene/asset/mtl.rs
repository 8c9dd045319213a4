//! OBJ + MTL through tobj's material loading: one part per material, the MTL statements mapped
//! onto penumbra's material as `docs/assets.md` writes.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::cutout::Channel;
use super::{checked_image, edited_parts, unit_colour, Asset, CutoutSpec, EmissionMap, PartEdits};
use crate::scene::error::SceneError;
use crate::scene::obj::{models_mesh, read_obj};
use crate::scene::types::Material;

pub(super) fn load(path: &Path) -> Result<Asset, SceneError> {
    let file = path.display().to_string();
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    let mtl_files: RefCell<Vec<PathBuf>> = RefCell::new(Vec::new());
    let loaded = read_obj(path, |name| {
        let p = dir.join(name);
        match std::fs::read(&p) {
            Ok(bytes) => {
                mtl_files.borrow_mut().push(p);
                tobj::load_mtl_buf(&mut bytes.as_slice())
            }
            Err(e) => {
                let msg = format!("cannot read {}: {e}", p.display());
                mtl_error
                    .borrow_mut()
                    .get_or_insert(SceneError::new(&file, None, "mtllib", msg));
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    })?;
    // A missing MTL fails tobj's whole load: report the file it could not read.
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, materials) = loaded.map_err(|e| SceneError::new(&file, None, "obj", format!("tobj: {e}")))?;
    let mtl_name = mtl_files
        .into_inner()
        .last()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| file.clone());
    let materials = materials.map_err(|e| SceneError::new(&mtl_name, None, "mtl", format!("tobj: {e}")))?;
    check_usemtl(path, &file, &materials)?;

    let mut ids: Vec<Option<usize>> = Vec::new();
    for m in &models {
        if !ids.contains(&m.mesh.material_id) {
            ids.push(m.mesh.material_id);
        }
    }
    let mut parts = Vec::new();
    for id in ids {
        let (material, edits) = match id.and_then(|i| materials.get(i).map(|m| (i, m))) {
            Some((i, m)) => material(m, i, dir, &mtl_name)?,
            // Faces before any `usemtl` (or a file with no `mtllib`).
            None => (Material::default_grey("default"), PartEdits::default()),
        };
        let group = models.iter().filter(|m| m.mesh.material_id == id);
        let mesh = models_mesh(group, &file)?;
        parts.extend(edited_parts(mesh, material, edits, &mtl_name)?);
    }
    Ok(Asset {
        parts,
        lights: Vec::new(),
        cameras: Vec::new(),
    })
}

/// A `usemtl` naming no material of the MTL would leave its faces with a default material:
/// an error instead, naming the OBJ line.
fn check_usemtl(path: &Path, file: &str, materials: &[tobj::Material]) -> Result<(), SceneError> {
    let text = std::fs::read(path).map_err(|e| SceneError::new(file, None, "file", format!("cannot read: {e}")))?;
    for (n, line) in String::from_utf8_lossy(&text).lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        let Some(name) = line.strip_prefix("usemtl") else {
            continue;
        };
        let name = name.trim();
        if !name.is_empty() && !materials.iter().any(|m| m.name == name) {
            let known: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
            return Err(SceneError::new(
                file,
                Some(n + 1),
                "usemtl",
                format!("material {name:?} is not in the MTL (it has: {})", known.join(", ")),
            ));
        }
    }
    Ok(())
}

/// Maps one MTL material: Kd/map_Kd, Ks/Ns/map_Ks, bump/map_Bump/norm (tangent-space normal
/// map), d (or Tr = 1 - d), map_d (a cut-out), Ke/map_Ke. Statements penumbra cannot honour are
/// errors.
// long: one MTL statement after another, each mapped or refused.
fn material(m: &tobj::Material, index: usize, dir: &Path, mtl: &str) -> Result<(Material, PartEdits), SceneError> {
    let field = |what: &str| format!("materials[{index}] {:?}.{what}", m.name);
    let colour = |v: Option<[f32; 3]>, what: &str, default: Vec3| match v {
        Some(c) => unit_colour(Vec3::from(c), mtl, &field(what)),
        None => Ok(default),
    };
    let texture = |name: Option<&String>, what: &str| -> Result<Option<PathBuf>, SceneError> {
        let Some(raw) = name else { return Ok(None) };
        let raw = raw.trim();
        if raw.starts_with('-') {
            return Err(SceneError::new(
                mtl,
                None,
                field(what),
                format!("texture options are not supported: `{raw}`"),
            ));
        }
        let rel = raw.replace('\\', "/");
        checked_image(&dir.join(rel), mtl, &field(what)).map(Some)
    };
    for (key, what) in [("refl", "reflection maps"), ("map_Pr", "PBR maps")] {
        if m.unknown_param.contains_key(key) {
            return Err(SceneError::new(
                mtl,
                None,
                field(key),
                format!("{what} are not supported"),
            ));
        }
    }
    // `map_d` is read as a cut-out (texels under one half are cut away), as exporters use it for
    // leaves and grilles: penumbra's opacity is one number per material.
    let cutout = texture(m.dissolve_texture.as_ref(), "map_d")?.map(|map| CutoutSpec {
        map,
        channel: Channel::AlphaOrGrey,
        factor: 1.0,
        cutoff: 0.5,
        field: field("map_d"),
    });
    let opacity = match (m.dissolve, m.unknown_param.get("Tr")) {
        (Some(d), _) => d,
        (None, Some(tr)) => {
            1.0 - tr
                .trim()
                .parse::<f32>()
                .map_err(|_| SceneError::new(mtl, None, field("Tr"), format!("`{tr}` is not a number")))?
        }
        (None, None) => 1.0,
    };
    if !(opacity > 0.0 && opacity <= 1.0) {
        return Err(SceneError::new(
            mtl,
            None,
            field("d"),
            format!("opacity must be in (0, 1], got {opacity}"),
        ));
    }
    let exponent = m.shininess.unwrap_or(32.0);
    if !(exponent.is_finite() && exponent >= 0.0) {
        return Err(SceneError::new(
            mtl,
            None,
            field("Ns"),
            format!("must be a finite number >= 0, got {exponent}"),
        ));
    }
    let emission = match m.emissive {
        Some(e) if !Vec3::from(e).is_finite() || Vec3::from(e).min_element() < 0.0 => {
            return Err(SceneError::new(
                mtl,
                None,
                field("Ke"),
                format!("must be finite and non-negative, got {e:?}"),
            ))
        }
        Some(e) => Vec3::from(e),
        None => Vec3::ZERO,
    };
    // `map_Ke` times `Ke` (the map alone where `Ke` is absent) splits the part into glowing and
    // dark triangles, as a glTF emissive texture does.
    let mut edits = PartEdits { cutout, emission: None };
    let mut emission = emission;
    if let Some(map) = texture(m.unknown_param.get("map_Ke"), "map_Ke")? {
        let factor = m.emissive.map_or(Vec3::ONE, Vec3::from);
        if factor != Vec3::ZERO {
            edits.emission = Some(EmissionMap {
                map,
                factor,
                field: field("map_Ke"),
            });
        }
        emission = Vec3::ZERO;
    }
    let normal = m.unknown_param.get("norm").or(m.normal_texture.as_ref());
    let normal_what = if m.unknown_param.contains_key("norm") {
        "norm"
    } else {
        "bump"
    };
    let material = Material {
        name: m.name.clone(),
        albedo: colour(m.diffuse, "Kd", Vec3::splat(0.8))?,
        specular: colour(m.specular, "Ks", Vec3::ZERO)?,
        exponent,
        albedo_map: texture(m.diffuse_texture.as_ref(), "map_Kd")?,
        normal_map: texture(normal, normal_what)?,
        specular_map: texture(m.specular_texture.as_ref(), "map_Ks")?,
        transmittance: Vec3::ZERO,
        emission,
        opacity,
        sky: false,
    };
    Ok((material, edits))
}
