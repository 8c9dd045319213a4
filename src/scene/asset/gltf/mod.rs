//! glTF 2.0 (`.gltf` with external or data-URI buffers, `.glb`) through the `gltf` crate: the
//! default scene's node hierarchy, every triangle primitive (strips and fans as lists) with its
//! material and vertex colours, KHR_lights_punctual lights and perspective cameras. The material
//! mapping ([`material`]) is written in `docs/assets.md`.

mod material;

use std::path::Path;

use base64::Engine as _;
use glam::{Mat4, Vec2, Vec3};

use super::{edited_parts, Asset, PartEdits};
use crate::scene::error::SceneError;
use crate::scene::mesh::Mesh;
use crate::scene::types::{Camera, Light, Material};
use material::uv_transform;

/// Extensions an asset may require: penumbra reads them.
const SUPPORTED_REQUIRED: [&str; 3] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
];

/// Luminous efficacy used to turn photometric light units into radiometric ones, lm/W: the
/// maximum, that of 555 nm light (so 1 cd = 1/683 W/sr, 1 lx = 1/683 W/m²).
pub const LUMINOUS_EFFICACY: f32 = 683.0;

struct Ctx<'a> {
    file: String,
    dir: &'a Path,
    doc: &'a gltf::Document,
    buffers: Vec<Vec<u8>>,
    /// The document as JSON, for what the `gltf` crate does not expose (texture transforms).
    json: serde_json::Value,
}

impl Ctx<'_> {
    fn err(&self, field: impl Into<String>, msg: impl Into<String>) -> SceneError {
        SceneError::new(&self.file, None, field, msg)
    }
}

pub(super) fn load(path: &Path) -> Result<Asset, SceneError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| SceneError::new(&file, None, "file", format!("cannot read: {e}")))?;
    let gltf = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| SceneError::new(&file, None, "file", format!("not a glTF 2.0 file: {e}")))?;
    for (i, ext) in gltf.document.extensions_required().enumerate() {
        if !SUPPORTED_REQUIRED.contains(&ext) {
            return Err(SceneError::new(
                &file,
                None,
                format!("extensionsRequired[{i}]"),
                format!(
                    "{ext} is not supported (penumbra reads {})",
                    SUPPORTED_REQUIRED.join(", ")
                ),
            ));
        }
    }
    if let Err(e) = gltf.document.clone().into_json().pipe_validate() {
        return Err(SceneError::new(&file, None, e.0, e.1));
    }
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let json =
        raw_json(&bytes).map_err(|e| SceneError::new(&file, None, "file", format!("not a glTF 2.0 file: {e}")))?;
    let mut cx = Ctx {
        file,
        dir,
        doc: &gltf.document,
        buffers: Vec::new(),
        json,
    };
    cx.buffers = load_buffers(&cx, gltf.blob.as_deref())?;
    let mut out = Walk::default();
    let scene = gltf.document.default_scene().or_else(|| gltf.document.scenes().next());
    let Some(scene) = scene else {
        return Err(cx.err("scenes", "the file has no scene"));
    };
    for node in scene.nodes() {
        walk(&cx, &node, Mat4::IDENTITY, &mut out, 0)?;
    }
    let mut parts = Vec::new();
    for (key, mesh, tint) in out.meshes {
        if let Some(prim) = &tint.varies {
            let c = tint.mean();
            crate::errln!(
                "{}: {prim}: COLOR_0 varies over the vertices: its area-weighted mean ({:.3}, {:.3}, {:.3}) multiplies the material's base colour (penumbra's albedo is one value per material)",
                cx.file,
                c.x,
                c.y,
                c.z
            );
        }
        let material = match key {
            Some(i) => material::material(
                &cx,
                &cx.doc
                    .materials()
                    .nth(i)
                    .ok_or_else(|| cx.err("materials", "missing"))?,
                tint.mean(),
            )?,
            None => {
                let mut grey = Material::default_grey("default");
                grey.albedo *= tint.mean();
                Some((grey, PartEdits::default()))
            }
        };
        let Some((material, edits)) = material else { continue };
        let mut mesh = mesh;
        if let Some(i) = key {
            if let Some(t) = uv_transform(&cx, i)? {
                mesh.uvs.iter_mut().for_each(|uv| *uv = t.apply(*uv));
            }
        }
        parts.extend(edited_parts(mesh, material, edits, &cx.file)?);
    }
    Ok(Asset {
        parts,
        lights: out.lights,
        cameras: out.cameras,
    })
}

/// The JSON of a `.gltf` file, or of a `.glb`'s JSON chunk.
fn raw_json(bytes: &[u8]) -> Result<serde_json::Value, String> {
    let text = if bytes.starts_with(b"glTF") {
        gltf::binary::Glb::from_slice(bytes)
            .map_err(|e| e.to_string())?
            .json
            .into_owned()
    } else {
        bytes.to_vec()
    };
    serde_json::from_slice(&text).map_err(|e| e.to_string())
}

/// Runs the `gltf` crate's validation, turning its report into (element, message).
trait PipeValidate {
    fn pipe_validate(self) -> Result<(), (String, String)>;
}

impl PipeValidate for gltf::json::Root {
    fn pipe_validate(self) -> Result<(), (String, String)> {
        match gltf::Document::from_json(self) {
            Ok(_) => Ok(()),
            Err(gltf::Error::Validation(list)) => {
                let (path, e) = list
                    .first()
                    .map(|(p, e)| (p.to_string(), e.to_string()))
                    .unwrap_or_else(|| ("file".into(), "invalid".into()));
                Err((path, format!("invalid glTF: {e}")))
            }
            Err(e) => Err(("file".into(), format!("invalid glTF: {e}"))),
        }
    }
}

fn load_buffers(cx: &Ctx, blob: Option<&[u8]>) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::new();
    for b in cx.doc.buffers() {
        let field = format!("buffers[{}]", b.index());
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .map(<[u8]>::to_vec)
                .ok_or_else(|| cx.err(&field, "refers to the binary chunk, but the file has none"))?,
            gltf::buffer::Source::Uri(uri) => read_uri(cx, uri, &field)?,
        };
        if data.len() < b.length() {
            return Err(cx.err(
                &field,
                format!("byteLength is {} but the data holds {} bytes", b.length(), data.len()),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a `data:` URI, or of a file relative to the asset.
fn read_uri(cx: &Ctx, uri: &str, field: &str) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err(cx.err(field, "a data URI must be base64-encoded"));
        };
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| cx.err(field, format!("bad base64 data: {e}")));
    }
    let path = cx.dir.join(percent_decode(uri));
    std::fs::read(&path).map_err(|e| cx.err(field, format!("cannot read {}: {e}", path.display())))
}

/// Decodes `%XX` escapes of a relative URI.
fn percent_decode(uri: &str) -> String {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = bytes.get(i + 1..i + 3).and_then(|h| std::str::from_utf8(h).ok());
        match (bytes[i], hex.and_then(|h| u8::from_str_radix(h, 16).ok())) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[derive(Default)]
struct Walk {
    /// Triangles per material index (`None`: the default material), in first-use order, with
    /// their vertex colours' tint.
    meshes: Vec<(Option<usize>, Mesh, Tint)>,
    lights: Vec<Light>,
    cameras: Vec<Camera>,
}

/// Deepest node hierarchy followed (a cycle is invalid glTF; this bounds the recursion).
const MAX_DEPTH: usize = 256;

fn walk(cx: &Ctx, node: &gltf::Node, parent: Mat4, out: &mut Walk, depth: usize) -> Result<(), SceneError> {
    let field = format!("nodes[{}]", node.index());
    if depth > MAX_DEPTH {
        return Err(cx.err(field, format!("the node hierarchy is deeper than {MAX_DEPTH}")));
    }
    let local = Mat4::from_cols_array_2d(&node.transform().matrix());
    if !local.is_finite() {
        return Err(cx.err(field, "its transform is not finite"));
    }
    let world = parent * local;
    if let Some(mesh) = node.mesh() {
        for prim in mesh.primitives() {
            let pfield = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let Some((tris, colours)) = primitive(cx, &prim, &pfield)? else {
                continue;
            };
            let tris = tris.transformed(&world);
            let tint = Tint::of(&tris, colours.as_deref(), &pfield);
            let key = prim.material().index();
            match out.meshes.iter_mut().find(|(k, _, _)| *k == key) {
                Some((_, m, t)) => {
                    append(m, &tris);
                    t.add(tint);
                }
                None => out.meshes.push((key, tris, tint)),
            }
        }
    }
    if let Some(camera) = node.camera() {
        if let Some(c) = camera_of(cx, &camera, &world)? {
            out.cameras.push(c);
        }
    }
    if let Some(light) = node.light() {
        out.lights.push(light_of(cx, &light, &world)?);
    }
    for child in node.children() {
        walk(cx, &child, world, out, depth + 1)?;
    }
    Ok(())
}

/// What COLOR_0 does to a part's base colour: penumbra's albedo is one value per material (times
/// its texture), so the vertex colours' area-weighted mean multiplies it. Exact where the colours
/// are one colour; where they vary, a line says the mean stands for them.
#[derive(Debug, Clone)]
struct Tint {
    /// Σ triangle area × its corners' mean colour, and Σ area.
    weighted: Vec3,
    area: f32,
    /// The first primitive whose colours vary (or differ from the primitives' merged before it).
    varies: Option<String>,
    /// The primitive it was made for.
    field: String,
}

impl Tint {
    fn of(mesh: &Mesh, colours: Option<&[Vec3]>, field: &str) -> Tint {
        let mut t = Tint {
            weighted: Vec3::ZERO,
            area: 0.0,
            varies: None,
            field: field.to_string(),
        };
        for [a, b, c] in mesh.triangles() {
            let area = 0.5
                * (mesh.positions[b] - mesh.positions[a])
                    .cross(mesh.positions[c] - mesh.positions[a])
                    .length();
            let colour = colours.map_or(Vec3::ONE, |cs| (cs[a] + cs[b] + cs[c]) / 3.0);
            t.weighted += colour * area;
            t.area += area;
        }
        if let Some(cs) = colours {
            if cs.iter().any(|c| (*c - cs[0]).abs().max_element() > 0.5 / 255.0) {
                t.varies = Some(field.to_string());
            }
        }
        t
    }

    fn add(&mut self, other: Tint) {
        if (self.mean() - other.mean()).abs().max_element() > 0.5 / 255.0 {
            self.varies.get_or_insert_with(|| other.field.clone());
        }
        self.weighted += other.weighted;
        self.area += other.area;
        self.varies = self.varies.take().or(other.varies);
    }

    fn mean(&self) -> Vec3 {
        if self.area > 0.0 {
            self.weighted / self.area
        } else {
            Vec3::ONE
        }
    }
}

fn append(to: &mut Mesh, from: &Mesh) {
    let base = to.positions.len() as u32;
    to.positions.extend_from_slice(&from.positions);
    to.normals.extend_from_slice(&from.normals);
    to.uvs.extend_from_slice(&from.uvs);
    to.tangents.extend_from_slice(&from.tangents);
    to.indices.extend(from.indices.iter().map(|i| base + i));
}

/// A primitive's triangles and its vertex colours, if it has any.
type Triangles = (Mesh, Option<Vec<Vec3>>);

/// One triangle primitive in its mesh's space, checked: finite attributes, indices in range,
/// with its COLOR_0 (linear) if it has one. Strips and fans become lists; points and lines (no
/// area to light) are `None`, with a line saying they were left out.
fn primitive(cx: &Ctx, prim: &gltf::Primitive, field: &str) -> Result<Option<Triangles>, SceneError> {
    use gltf::mesh::Mode;
    if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        crate::errln!(
            "{}: {field}: mode {:?} left out: points and lines have no surface to light",
            cx.file,
            prim.mode()
        );
        return Ok(None);
    }
    for (sem, acc) in prim.attributes() {
        let afield = format!("{field}: {}", semantic_name(&sem));
        check_accessor(cx, &acc, &afield)?;
        let vec3_float =
            acc.data_type() == gltf::accessor::DataType::F32 && acc.dimensions() == gltf::accessor::Dimensions::Vec3;
        if matches!(sem, gltf::Semantic::Positions | gltf::Semantic::Normals) && !vec3_float {
            return Err(cx.err(
                afield,
                "must be a VEC3 of FLOAT (quantized attributes are not supported)",
            ));
        }
    }
    if let Some(acc) = prim.indices() {
        check_accessor(cx, &acc, &format!("{field}: indices"))?;
    }
    let reader = prim.reader(|b| cx.buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(|| cx.err(field, "has no POSITION"))?
        .map(Vec3::from)
        .collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(cx.err(field, format!("POSITION has NaN or infinity (vertex {i})")));
    }
    let n = positions.len();
    let normals: Option<Vec<Vec3>> = reader.read_normals().map(|it| it.map(Vec3::from).collect());
    if let Some(i) = normals.as_ref().and_then(|ns| ns.iter().position(|v| !v.is_finite())) {
        return Err(cx.err(field, format!("NORMAL has NaN or infinity (vertex {i})")));
    }
    let uvs: Option<Vec<Vec2>> = reader
        .read_tex_coords(0)
        .map(|t| t.into_f32().map(Vec2::from).collect());
    if let Some(i) = uvs.as_ref().and_then(|t| t.iter().position(|v| !v.is_finite())) {
        return Err(cx.err(field, format!("TEXCOORD_0 has NaN or infinity (vertex {i})")));
    }
    let colours: Option<Vec<Vec3>> = reader
        .read_colors(0)
        .map(|c| c.into_rgb_f32().map(Vec3::from).collect());
    if let Some(cs) = &colours {
        if cs.len() != n {
            return Err(cx.err(field, format!("COLOR_0 has {} entries for {n} vertices", cs.len())));
        }
        if let Some(i) = cs
            .iter()
            .position(|c| !c.is_finite() || c.min_element() < 0.0 || c.max_element() > 1.0)
        {
            return Err(cx.err(field, format!("COLOR_0 is not a colour in [0, 1] (vertex {i})")));
        }
    }
    let indices: Vec<u32> = match reader.read_indices() {
        Some(ix) => ix.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    let indices = triangle_list(prim.mode(), indices);
    if !indices.len().is_multiple_of(3) {
        return Err(cx.err(field, format!("{} indices do not make whole triangles", indices.len())));
    }
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(cx.err(field, format!("index {bad} is out of range ({n} vertices)")));
    }
    let mut mesh = Mesh {
        positions,
        normals: normals.filter(|v| v.len() == n).unwrap_or_default(),
        // glTF's uv origin is the top-left texel, as penumbra's.
        uvs: uvs.filter(|v| v.len() == n).unwrap_or_else(|| vec![Vec2::ZERO; n]),
        tangents: Vec::new(),
        indices,
    };
    mesh.normalize_normals();
    mesh.compute_tangents();
    mesh.validate(&format!("{}: {field}", cx.file))?;
    Ok(Some((mesh, colours)))
}

/// A strip's or fan's indices as a triangle list, front faces kept (glTF 2.0, 3.7.2.1): strip
/// triangle i is (i, i+1, i+2), its two first corners swapped when i is odd; fan triangle i is
/// (i+1, i+2, 0).
fn triangle_list(mode: gltf::mesh::Mode, ix: Vec<u32>) -> Vec<u32> {
    let n = ix.len().saturating_sub(2);
    match mode {
        gltf::mesh::Mode::TriangleStrip => (0..n)
            .flat_map(|i| match i % 2 {
                0 => [ix[i], ix[i + 1], ix[i + 2]],
                _ => [ix[i + 1], ix[i], ix[i + 2]],
            })
            .collect(),
        gltf::mesh::Mode::TriangleFan => (0..n).flat_map(|i| [ix[i + 1], ix[i + 2], ix[0]]).collect(),
        _ => ix,
    }
}

fn semantic_name(s: &gltf::Semantic) -> String {
    s.to_string()
}

/// An accessor's bytes must lie inside its buffer view, and the view inside its buffer (the
/// reader would otherwise read past the data).
fn check_accessor(cx: &Ctx, acc: &gltf::Accessor, field: &str) -> Result<(), SceneError> {
    if acc.sparse().is_some() {
        return Err(cx.err(field, "sparse accessors are not supported"));
    }
    let Some(view) = acc.view() else {
        return Err(cx.err(field, "an accessor without a bufferView is not supported"));
    };
    let data_len = cx.buffers.get(view.buffer().index()).map_or(0, Vec::len);
    if view.offset() + view.length() > data_len {
        return Err(cx.err(
            field,
            format!(
                "bufferViews[{}] ends at byte {} of a {data_len}-byte buffer",
                view.index(),
                view.offset() + view.length()
            ),
        ));
    }
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    let end = if acc.count() == 0 {
        0
    } else {
        acc.offset() + stride * (acc.count() - 1) + elem
    };
    if end > view.length() {
        return Err(cx.err(
            field,
            format!(
                "accessors[{}] reads past the end of bufferViews[{}]",
                acc.index(),
                view.index()
            ),
        ));
    }
    Ok(())
}

/// A perspective camera; an orthographic one is `None`, with a line saying it was left out.
fn camera_of(cx: &Ctx, camera: &gltf::Camera, world: &Mat4) -> Result<Option<Camera>, SceneError> {
    let field = format!("cameras[{}]", camera.index());
    let gltf::camera::Projection::Perspective(p) = camera.projection() else {
        crate::errln!("{}: {field}: left out: orthographic cameras are not supported", cx.file);
        return Ok(None);
    };
    let fov_y_deg = p.yfov().to_degrees();
    if !(fov_y_deg > 0.0 && fov_y_deg < 180.0 && p.znear() > 0.0 && p.znear().is_finite()) {
        return Err(cx.err(
            field,
            format!("yfov {} rad or znear {} is out of range", p.yfov(), p.znear()),
        ));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).try_normalize();
    let up = world.transform_vector3(Vec3::Y).try_normalize();
    let (Some(forward), Some(up)) = (forward, up) else {
        return Err(cx.err(field, "its node's transform is degenerate"));
    };
    Ok(Some(Camera {
        position,
        target: position + forward,
        up,
        fov_y_deg,
        near: p.znear(),
    }))
}

fn light_of(cx: &Ctx, light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Result<Light, SceneError> {
    let field = format!("KHR_lights_punctual.lights[{}]", light.index());
    let colour = Vec3::from(light.color());
    let intensity = light.intensity();
    if !colour.is_finite() || !intensity.is_finite() || colour.min_element() < 0.0 || intensity < 0.0 {
        return Err(cx.err(field, "color and intensity must be finite and non-negative"));
    }
    let radiometric = colour * intensity / LUMINOUS_EFFICACY;
    let name = light.name().map(str::to_owned).unwrap_or_else(|| field.clone());
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .try_normalize()
        .ok_or_else(|| cx.err(&field, "its node's transform is degenerate"))?;
    let radius = light.range().unwrap_or(0.0).max(0.0);
    Ok(match light.kind() {
        gltf::khr_lights_punctual::Kind::Directional => Light::Directional {
            name,
            direction,
            irradiance: radiometric,
        },
        gltf::khr_lights_punctual::Kind::Point => Light::Point {
            name,
            position,
            intensity: radiometric,
            radius,
        },
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => Light::Spot {
            name,
            position,
            direction,
            intensity: radiometric,
            inner_deg: inner_cone_angle.to_degrees(),
            outer_deg: outer_cone_angle.to_degrees(),
            radius,
        },
    })
}
