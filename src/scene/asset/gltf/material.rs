//! glTF materials onto penumbra's Lambert + Blinn-Phong material (the mapping `docs/assets.md`
//! writes): factors and textures, alpha modes, emission, and the uv transform a material's
//! textures share.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::{percent_decode, read_uri, Ctx};
use crate::scene::asset::cutout::Channel;
use crate::scene::asset::{checked_image, unit_colour, CutoutSpec, EmissionMap, PartEdits};
use crate::scene::error::SceneError;
use crate::scene::types::Material;

/// Largest Blinn-Phong exponent a roughness maps to (roughness 0 would give infinity).
pub const MAX_EXPONENT: f32 = 8192.0;

/// The Blinn-Phong exponent of a glTF roughness: α = roughness², n = 2/α² − 2, in [0, MAX_EXPONENT].
pub fn exponent_of_roughness(roughness: f32) -> f32 {
    let alpha = (roughness * roughness).max(1e-4);
    (2.0 / (alpha * alpha) - 2.0).clamp(0.0, MAX_EXPONENT)
}

/// A `KHR_texture_transform`: uv' = T(offset) R(rotation) S(scale) uv. The rotation turns a uv
/// toward −v: (u, v) → (u cos r + v sin r, −u sin r + v cos r), as the implementations and the
/// extension's sample model do ("counter-clockwise" in glTF's v-down uv space); the GLSL listing in
/// the extension's text has the transpose, as the glTF working group's discussion "KHR_texture_transform
/// has the wrong rotation matrix" records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct UvTransform {
    offset: Vec2,
    rotation: f32,
    scale: Vec2,
}

impl UvTransform {
    pub(super) fn apply(&self, uv: Vec2) -> Vec2 {
        let s = uv * self.scale;
        let (sin, cos) = self.rotation.sin_cos();
        Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y) + self.offset
    }
}

/// The uv transform material `index`'s mapped textures share (the base colour's, the normal
/// map's and the emission map's; the metallic-roughness texture is read as its mean, where a transform changes
/// nothing), or `None` when they have none. penumbra has one uv set per part, so textures with
/// different transforms, or a transform's own `texCoord` other than 0, are refused.
pub(super) fn uv_transform(cx: &Ctx, index: usize) -> Result<Option<UvTransform>, SceneError> {
    let m = &cx.json["materials"][index];
    let slots = [
        (
            "pbrMetallicRoughness.baseColorTexture",
            &m["pbrMetallicRoughness"]["baseColorTexture"],
        ),
        ("normalTexture", &m["normalTexture"]),
        ("emissiveTexture", &m["emissiveTexture"]),
    ];
    let mut found: Option<(String, Option<UvTransform>)> = None;
    for (name, info) in slots {
        if info.is_null() {
            continue;
        }
        let field = format!("materials[{index}].{name}.extensions.KHR_texture_transform");
        let t = &info["extensions"]["KHR_texture_transform"];
        let this = if t.is_null() {
            None
        } else {
            let num = |key: &str, default: f32| -> Result<f32, SceneError> {
                match &t[key] {
                    serde_json::Value::Null => Ok(default),
                    v => v
                        .as_f64()
                        .map(|x| x as f32)
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| cx.err(&field, format!("{key} must be a finite number"))),
                }
            };
            let pair = |key: &str, default: f32| -> Result<Vec2, SceneError> {
                match &t[key] {
                    serde_json::Value::Null => Ok(Vec2::splat(default)),
                    serde_json::Value::Array(a) if a.len() == 2 => {
                        let get = |i: usize| a[i].as_f64().map(|x| x as f32).filter(|x| x.is_finite());
                        match (get(0), get(1)) {
                            (Some(x), Some(y)) => Ok(Vec2::new(x, y)),
                            _ => Err(cx.err(&field, format!("{key} must be two finite numbers"))),
                        }
                    }
                    _ => Err(cx.err(&field, format!("{key} must be two finite numbers"))),
                }
            };
            if num("texCoord", 0.0)? != 0.0 {
                return Err(cx.err(&field, "texCoord: only TEXCOORD_0 is supported"));
            }
            Some(UvTransform {
                offset: pair("offset", 0.0)?,
                rotation: num("rotation", 0.0)?,
                scale: pair("scale", 1.0)?,
            })
        };
        match &found {
            Some((first, other)) if *other != this => {
                return Err(cx.err(
                    field,
                    format!("differs from {first}'s: penumbra maps a material's textures with one uv transform"),
                ));
            }
            Some(_) => {}
            None => found = Some((name.to_string(), this)),
        }
    }
    Ok(found.and_then(|(_, t)| t))
}

/// Maps a glTF material (see `docs/assets.md`); `None` for one that hides its primitives
/// (MASK with a base alpha under the cutoff, or BLEND with alpha 0). A MASK material with a
/// base colour texture comes with the cut-out its texture's alpha makes, and an emissive texture
/// with the split of the part into glowing and dark triangles.
pub(super) fn material(cx: &Ctx, m: &gltf::Material, tint: Vec3) -> Result<Option<(Material, PartEdits)>, SceneError> {
    let index = m.index().unwrap_or(0);
    let field = |what: &str| format!("materials[{index}].{what}");
    let pbr = m.pbr_metallic_roughness();
    let base4 = Vec4::from(pbr.base_color_factor());
    let base = unit_colour(base4.truncate(), &cx.file, &field("baseColorFactor"))? * tint;
    let mut metallic = pbr.metallic_factor();
    let mut roughness = pbr.roughness_factor();
    if !(0.0..=1.0).contains(&metallic) || !(0.0..=1.0).contains(&roughness) {
        return Err(cx.err(
            field("pbrMetallicRoughness"),
            "metallicFactor and roughnessFactor must be in [0, 1]",
        ));
    }
    let albedo_map = match pbr.base_color_texture() {
        Some(t) => Some(texture(cx, &t.texture(), t.tex_coord(), &field("baseColorTexture"))?),
        None => None,
    };
    if let Some(t) = pbr.metallic_roughness_texture() {
        let path = texture(cx, &t.texture(), t.tex_coord(), &field("metallicRoughnessTexture"))?;
        let (g, b) = mean_green_blue(&path).map_err(|e| cx.err(field("metallicRoughnessTexture"), e))?;
        roughness *= g;
        metallic *= b;
    }
    let normal_map = match m.normal_texture() {
        Some(t) => Some(texture(cx, &t.texture(), t.tex_coord(), &field("normalTexture"))?),
        None => None,
    };
    let strength = m.emissive_strength().unwrap_or(1.0);
    let mut emission = Vec3::from(m.emissive_factor()) * strength;
    if !emission.is_finite() || emission.min_element() < 0.0 {
        return Err(cx.err(field("emissiveFactor"), "must be finite and non-negative"));
    }
    let mut edits = PartEdits::default();
    if let Some(t) = m.emissive_texture() {
        let map = texture(cx, &t.texture(), t.tex_coord(), &field("emissiveTexture"))?;
        if emission != Vec3::ZERO {
            edits.emission = Some(EmissionMap {
                map,
                factor: emission,
                field: field("emissiveTexture"),
            });
        }
        emission = Vec3::ZERO;
    }
    let alpha = base4.w;
    let opacity = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => 1.0,
        gltf::material::AlphaMode::Mask => {
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            if alpha < cutoff {
                return Ok(None);
            }
            edits.cutout = albedo_map.clone().map(|map| CutoutSpec {
                map,
                channel: Channel::Alpha,
                factor: alpha,
                cutoff,
                field: field("alphaMode"),
            });
            1.0
        }
        gltf::material::AlphaMode::Blend => {
            if alpha <= 0.0 {
                return Ok(None);
            }
            refuse_texture_alpha(cx, albedo_map.as_deref(), |a| a < 1.0, &field("alphaMode"))?;
            alpha.min(1.0)
        }
    };
    let f0 = Vec3::splat(0.04).lerp(base, metallic);
    let material = Material {
        name: m
            .name()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("material{index}")),
        albedo: base * (1.0 - metallic),
        specular: f0,
        exponent: exponent_of_roughness(roughness),
        albedo_map,
        normal_map,
        specular_map: None,
        transmittance: Vec3::ZERO,
        emission,
        opacity,
        sky: false,
    };
    Ok(Some((material, edits)))
}

/// Per-texel alpha cannot be honoured (penumbra's opacity is one number per material): a base
/// colour texture any of whose texels `hides` is refused.
fn refuse_texture_alpha(
    cx: &Ctx,
    map: Option<&Path>,
    hides: impl Fn(f32) -> bool,
    field: &str,
) -> Result<(), SceneError> {
    let Some(path) = map else { return Ok(()) };
    let img = crate::util::image_io::open_image(path)
        .map_err(|e| cx.err(field, format!("{}: {e}", path.display())))?
        .to_rgba8();
    if img.pixels().any(|p| hides(f32::from(p.0[3]) / 255.0)) {
        return Err(cx.err(
            field,
            format!(
                "{}: per-texel alpha (cut-outs, blending) is not supported: penumbra's opacity is one number per material",
                path.display()
            ),
        ));
    }
    Ok(())
}

/// The mean of a texture's green and blue channels (linear, [0, 1]).
fn mean_green_blue(path: &Path) -> Result<(f32, f32), String> {
    let img = crate::util::image_io::open_image(path)?.to_rgba8();
    let n = (img.width() as f64 * img.height() as f64).max(1.0);
    let (g, b) = img.pixels().fold((0.0f64, 0.0f64), |(g, b), p| {
        (g + f64::from(p.0[1]), b + f64::from(p.0[2]))
    });
    Ok(((g / n / 255.0) as f32, (b / n / 255.0) as f32))
}

/// The file of a texture's image: its URI relative to the asset, or (a data URI or an image
/// in a buffer) the bytes written once to a cache folder.
fn texture(cx: &Ctx, tex: &gltf::Texture, tex_coord: u32, field: &str) -> Result<PathBuf, SceneError> {
    if tex_coord != 0 {
        return Err(cx.err(field, format!("texCoord {tex_coord}: only TEXCOORD_0 is supported")));
    }
    let image = tex.source();
    let ifield = format!("{field}: images[{}]", image.index());
    match image.source() {
        gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
            checked_image(&cx.dir.join(percent_decode(uri)), &cx.file, &ifield)
        }
        gltf::image::Source::Uri { uri, .. } => {
            let bytes = read_uri(cx, uri, &ifield)?;
            embedded_image(cx, &bytes, image.index(), &ifield)
        }
        gltf::image::Source::View { view, .. } => {
            let data = cx.buffers.get(view.buffer().index()).map(Vec::as_slice).unwrap_or(&[]);
            let bytes = data
                .get(view.offset()..view.offset() + view.length())
                .ok_or_else(|| cx.err(&ifield, "its bufferView lies outside the buffer"))?;
            embedded_image(cx, bytes, image.index(), &ifield)
        }
    }
}

/// Writes an embedded image into `<temp>/penumbra-assets/<hash of the bytes>.<ext>` (once) so
/// that every method and the reference read it by path as any texture.
fn embedded_image(cx: &Ctx, bytes: &[u8], index: usize, field: &str) -> Result<PathBuf, SceneError> {
    let ext = match image::guess_format(bytes) {
        Ok(image::ImageFormat::Png) => "png",
        Ok(image::ImageFormat::Jpeg) => "jpg",
        _ => return Err(cx.err(field, "an embedded image must be PNG or JPEG")),
    };
    // FNV-1a: a stable name for the same bytes.
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    });
    let dir = std::env::temp_dir().join("penumbra-assets");
    let path = dir.join(format!("{hash:016x}-{}.{ext}", bytes.len()));
    if !path.is_file() {
        let tmp = dir.join(format!("{hash:016x}-{}.{}.tmp", bytes.len(), std::process::id()));
        std::fs::create_dir_all(&dir)
            .and_then(|()| std::fs::write(&tmp, bytes))
            .and_then(|()| std::fs::rename(&tmp, &path))
            .map_err(|e| cx.err(field, format!("cannot write images[{index}] to {}: {e}", dir.display())))?;
    }
    checked_image(&path, &cx.file, field)
}
