//! Asset loading on small files written by the tests: what each element becomes, and one error
//! line for each kind of bad input.

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use serde_json::json;

use super::*;
use crate::scene::obj::tests::temp_dir;

/// A 1×1 (or `w`×1) RGBA PNG of the given texels.
pub(crate) fn write_png(path: &Path, texels: &[[u8; 4]]) {
    let img = image::RgbaImage::from_fn(texels.len() as u32, 1, |x, _| image::Rgba(texels[x as usize]));
    img.save(path).unwrap();
}

/// A unit quad in the xy-plane facing +z (two triangles), as a glTF buffer: positions, normals,
/// uvs, u16 indices; returns the bytes and the accessor/bufferView JSON.
pub(crate) fn quad_buffer(positions: [[f32; 3]; 4]) -> (Vec<u8>, serde_json::Value, serde_json::Value) {
    let mut bytes = Vec::new();
    for p in positions {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in 0..4 {
        for c in [0.0f32, 0.0, 1.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for uv in [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        for c in uv {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let views = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": 48},
        {"buffer": 0, "byteOffset": 96, "byteLength": 32},
        {"buffer": 0, "byteOffset": 128, "byteLength": 12}
    ]);
    let (lo, hi) = positions
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(mut lo, mut hi), p| {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
            (lo, hi)
        });
    let accessors = json!([
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": lo, "max": hi},
        {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}
    ]);
    (bytes, views, accessors)
}

const UNIT_QUAD: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];

fn primitive(material: usize) -> serde_json::Value {
    json!({"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": material})
}

/// A glTF document: one quad mesh used by two nodes (the second a child of the first), a camera
/// and a point light, with the buffer as a data URI.
fn document(bytes: &[u8]) -> serde_json::Value {
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let (_, views, accessors) = quad_buffer(UNIT_QUAD);
    let b64 = base64::engine::general_purpose::STANDARD.encode(bytes);
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "scene": 0,
        "scenes": [{"nodes": [0, 3]}],
        "nodes": [
            {"mesh": 0, "translation": [2.0, 0.0, 0.0], "children": [1]},
            {"mesh": 0, "rotation": [0.0, h, 0.0, h], "scale": [2.0, 2.0, 2.0], "translation": [0.0, 1.0, 0.0], "children": [2]},
            {"extensions": {"KHR_lights_punctual": {"light": 0}}, "translation": [0.0, 0.0, 1.0]},
            {"camera": 0, "translation": [0.0, 0.5, 5.0]}
        ],
        "meshes": [{"primitives": [primitive(0)]}],
        "materials": [{
            "name": "gold",
            "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.8, 0.4, 1.0], "metallicFactor": 0.25, "roughnessFactor": 0.5},
            "emissiveFactor": [0.1, 0.0, 0.0]
        }],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.05}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1.0, 0.5, 1.0], "intensity": 683.0, "range": 9.0}]}},
        "bufferViews": views,
        "accessors": accessors,
        "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{b64}")}]
    })
}

use base64::Engine as _;

fn write_json(dir: &Path, name: &str, doc: &serde_json::Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string_pretty(doc).unwrap()).unwrap();
    path
}

#[test]
fn gltf_node_hierarchy_material_light_and_camera() {
    let dir = temp_dir("gltf-basic");
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    let path = write_json(&dir, "quad.gltf", &document(&bytes));
    let asset = load_asset(&path).unwrap();
    // Both nodes use material 0: one part of 4 triangles.
    assert_eq!(asset.parts.len(), 1);
    let mesh = &asset.parts[0].mesh;
    assert_eq!(mesh.triangle_count(), 4);
    // Node 1's world transform: T(2,0,0) · T(0,1,0) · R_y(90°) · S(2).
    let world1 = Mat4::from_translation(Vec3::new(2.0, 1.0, 0.0))
        * Mat4::from_quat(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2))
        * Mat4::from_scale(Vec3::splat(2.0));
    for (k, p) in UNIT_QUAD.iter().enumerate() {
        let p = Vec3::from(*p);
        assert!((mesh.positions[k] - (p + Vec3::X * 2.0)).length() < 1e-5);
        assert!(
            (mesh.positions[4 + k] - world1.transform_point3(p)).length() < 1e-5,
            "{k}"
        );
    }
    // The rotated copy faces +x (R_y(90°) takes +z to +x).
    assert!((mesh.normals[4] - Vec3::X).length() < 1e-5);

    let m = &asset.parts[0].material;
    let base = Vec3::new(1.0, 0.8, 0.4);
    assert!((m.albedo - base * 0.75).length() < 1e-6);
    assert!((m.specular - Vec3::splat(0.04).lerp(base, 0.25)).length() < 1e-6);
    // roughness 0.5: alpha = 0.25, n = 2/0.0625 - 2 = 30.
    assert!((m.exponent - 30.0).abs() < 1e-3, "{}", m.exponent);
    assert_eq!(m.emission, Vec3::new(0.1, 0.0, 0.0));

    // The light hangs under node 1: at world1 · (0, 0, 1); 683 cd = 1 W/sr.
    let Light::Point {
        position,
        intensity,
        radius,
        ..
    } = &asset.lights[0]
    else {
        panic!("{:?}", asset.lights)
    };
    assert!(
        (*position - world1.transform_point3(Vec3::Z)).length() < 1e-5,
        "{position}"
    );
    assert!((*intensity - Vec3::new(1.0, 0.5, 1.0)).length() < 1e-6);
    assert_eq!(*radius, 9.0);

    let c = &asset.cameras[0];
    assert_eq!(c.position, Vec3::new(0.0, 0.5, 5.0));
    assert!((c.target - Vec3::new(0.0, 0.5, 4.0)).length() < 1e-6);
    assert!((c.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-4);
}

#[test]
fn glb_with_embedded_texture_reads_the_same_texels() {
    let dir = temp_dir("glb");
    let png = dir.join("t.png");
    write_png(&png, &[[200, 100, 50, 255]]);
    let png_bytes = std::fs::read(&png).unwrap();
    let (mut bytes, _, _) = quad_buffer(UNIT_QUAD);
    let image_offset = bytes.len();
    bytes.extend_from_slice(&png_bytes);
    while !bytes.len().is_multiple_of(4) {
        bytes.push(0);
    }
    let mut doc = document(&bytes);
    doc["buffers"] = json!([{"byteLength": bytes.len()}]);
    doc["bufferViews"]
        .as_array_mut()
        .unwrap()
        .push(json!({"buffer": 0, "byteOffset": image_offset, "byteLength": png_bytes.len()}));
    doc["images"] = json!([{"bufferView": 4, "mimeType": "image/png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    let mut text = serde_json::to_vec(&doc).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut glb = Vec::new();
    let total = 12 + 8 + text.len() + 8 + bytes.len();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(text.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&text);
    glb.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bytes);
    let path = dir.join("quad.glb");
    std::fs::write(&path, glb).unwrap();
    let asset = load_asset(&path).unwrap();
    let map = asset.parts[0]
        .material
        .albedo_map
        .as_ref()
        .expect("the base colour texture");
    let img = crate::util::image_io::open_image(map).unwrap().to_rgba8();
    assert_eq!(img.get_pixel(0, 0).0, [200, 100, 50, 255]);
    assert_eq!(asset.parts[0].mesh.triangle_count(), 4);
}

/// The error of loading `doc` (after `edit`), displayed.
fn gltf_error(name: &str, edit: impl FnOnce(&mut serde_json::Value, &Path), bytes: Vec<u8>) -> String {
    let dir = temp_dir(name);
    let mut doc = document(&bytes);
    edit(&mut doc, &dir);
    let path = write_json(&dir, "model.gltf", &doc);
    let e = load_asset(&path).unwrap_err().to_string();
    assert!(!e.contains('\n'), "{e}");
    e
}

#[test]
// long: a table of bad inputs, a few lines each.
fn gltf_bad_input_is_one_line_naming_file_and_element() {
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    let mut nan = bytes.clone();
    nan[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = gltf_error("nan", |_, _| {}, nan);
    assert!(
        e.contains("model.gltf: meshes[0].primitives[0]: POSITION has NaN"),
        "{e}"
    );

    let e = gltf_error(
        "ext",
        |d, _| d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]),
        bytes.clone(),
    );
    assert!(
        e.contains("extensionsRequired[0]: KHR_draco_mesh_compression is not supported"),
        "{e}"
    );

    let e = gltf_error(
        "missing-tex",
        |d, _| {
            d["images"] = json!([{"uri": "nowhere.png"}]);
            d["textures"] = json!([{"source": 0}]);
            d["materials"][0]["normalTexture"] = json!({"index": 0});
        },
        bytes.clone(),
    );
    assert!(
        e.contains("materials[0].normalTexture: images[0]: texture not found"),
        "{e}"
    );

    let mut bad_index = bytes.clone();
    let n = bad_index.len();
    bad_index[n - 2..].copy_from_slice(&9u16.to_le_bytes());
    let e = gltf_error("index", |_, _| {}, bad_index);
    assert!(
        e.contains("meshes[0].primitives[0]: index 9 is out of range (4 vertices)"),
        "{e}"
    );

    let e = gltf_error(
        "lines",
        |d, _| d["meshes"][0]["primitives"][0]["mode"] = json!(1),
        bytes.clone(),
    );
    // Lines are left out (with a line saying so): a file of lines alone draws nothing.
    assert!(
        e.contains("model.gltf: file: the asset has no visible triangles"),
        "{e}"
    );

    let e = gltf_error(
        "two-indices",
        |d, _| {
            d["accessors"][3]["count"] = json!(5);
            d["bufferViews"][3]["byteLength"] = json!(10);
        },
        bytes.clone(),
    );
    assert!(
        e.contains("meshes[0].primitives[0]: 5 indices do not make whole triangles"),
        "{e}"
    );

    let dir = temp_dir("garbage");
    for (name, content) in [("g.glb", &b"glTF\x02\0\0\0garbage"[..]), ("g.gltf", &b"{not json"[..])] {
        std::fs::write(dir.join(name), content).unwrap();
        let e = load_asset(&dir.join(name)).unwrap_err().to_string();
        assert!(e.contains(&format!("{name}: file: not a glTF 2.0 file")), "{e}");
    }

    let e = gltf_error(
        "short",
        |d, _| d["buffers"][0]["byteLength"] = json!(4000),
        bytes.clone(),
    );
    assert!(e.contains("buffers[0]: byteLength is 4000"), "{e}");

    // A cut-out mask that cannot be read is one line too.
    let e = gltf_error(
        "cutout",
        |d, dir| {
            std::fs::write(dir.join("leaf.png"), b"not a png").unwrap();
            d["images"] = json!([{"uri": "leaf.png"}]);
            d["textures"] = json!([{"source": 0}]);
            d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
            d["materials"][0]["alphaMode"] = json!("MASK");
        },
        bytes.clone(),
    );
    assert!(e.contains("materials[0].baseColorTexture: images[0]"), "{e}");
}

/// Every triangle faces the way its vertex normals point (its winding is a front face's).
fn assert_front_faces(m: &Mesh) {
    for t in m.triangles() {
        let [a, b, c] = t.map(|i| m.positions[i]);
        let n = m.normals[t[0]] + m.normals[t[1]] + m.normals[t[2]];
        assert!((b - a).cross(c - a).dot(n) > 0.0, "triangle {t:?} is wound backwards");
    }
}

#[test]
fn gltf_strips_and_fans_become_lists_points_lines_and_orthographic_cameras_are_left_out() {
    let dir = temp_dir("modes");
    let (mut bytes, _, _) = quad_buffer(UNIT_QUAD);
    let whole = {
        let doc = document(&bytes);
        load_asset(&write_json(&dir, "list.gltf", &doc)).unwrap().parts[0]
            .mesh
            .area()
    };
    // A strip (0, 1, 3, 2) and a fan (0, 1, 2, 3) over the quad's corners: two triangles each.
    for i in [0u16, 1, 3, 2, 0, 1, 2, 3] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    for (name, mode, offset) in [("strip", 5, 140), ("fan", 6, 148)] {
        let mut doc = document(&bytes);
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": 8}));
        doc["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({"bufferView": 4, "componentType": 5123, "count": 4, "type": "SCALAR"}));
        let mut prim = primitive(0);
        prim["indices"] = json!(4);
        prim["mode"] = json!(mode);
        let mut line = primitive(0);
        line["mode"] = json!(1);
        doc["meshes"][0]["primitives"] = json!([prim, line]);
        doc["cameras"] =
            json!([{"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 9}}]);
        let asset = load_asset(&write_json(&dir, &format!("{name}.gltf"), &doc)).unwrap();
        let mesh = &asset.parts[0].mesh;
        assert_eq!(
            mesh.triangle_count(),
            4,
            "{name}: two quads of two triangles, the line left out"
        );
        assert!(
            (mesh.area() - whole).abs() < 1e-5,
            "{name}: {} against {whole}",
            mesh.area()
        );
        assert_front_faces(mesh);
        assert!(asset.cameras.is_empty(), "{name}: the orthographic camera is left out");
    }
}

/// The quad document of [`document`] and the area its part covers uncut.
fn quad_document(dir: &Path) -> (serde_json::Value, f32) {
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    let doc = document(&bytes);
    let area = load_asset(&write_json(dir, "whole.gltf", &doc)).unwrap().parts[0]
        .mesh
        .area();
    (doc, area)
}

/// Writes `texels` as `name` (a row) and makes it the document's only image and texture 0.
fn one_texture(doc: &mut serde_json::Value, dir: &Path, name: &str, texels: &[[u8; 4]]) {
    write_png(&dir.join(name), texels);
    doc["images"] = json!([{"uri": name}]);
    doc["textures"] = json!([{"source": 0}]);
}

#[test]
fn gltf_texture_transform_moves_the_uvs_and_differing_ones_are_refused() {
    let dir = temp_dir("uvxform");
    let (mut doc, _) = quad_document(&dir);
    one_texture(&mut doc, &dir, "c.png", &[[200, 100, 50, 255]]);
    let xform = json!({"KHR_texture_transform": {"offset": [0.25, -1.0], "rotation": std::f32::consts::FRAC_PI_2, "scale": [2.0, 0.5]}});
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0, "extensions": xform});
    doc["extensionsRequired"] = json!(["KHR_texture_transform"]);
    let before = {
        let mut plain = doc.clone();
        plain["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
        plain["extensionsRequired"] = json!([]);
        load_asset(&write_json(&dir, "plain.gltf", &plain)).unwrap().parts[0]
            .mesh
            .uvs
            .clone()
    };
    let after = load_asset(&write_json(&dir, "moved.gltf", &doc)).unwrap().parts[0]
        .mesh
        .uvs
        .clone();
    // Scale (2, 0.5), then a quarter turn toward -v ((u, v) -> (v, -u)), then the offset.
    for (b, a) in before.iter().zip(&after) {
        let want = glam::Vec2::new(0.5 * b.y + 0.25, -2.0 * b.x - 1.0);
        assert!((*a - want).length() < 1e-5, "{b} -> {a}, want {want}");
    }
    // A normal map without the base colour's transform cannot share its uvs: one line.
    doc["materials"][0]["normalTexture"] = json!({"index": 0});
    let e = load_asset(&write_json(&dir, "mixed.gltf", &doc))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("materials[0].normalTexture.extensions.KHR_texture_transform: differs from pbrMetallicRoughness.baseColorTexture's"),
        "{e}"
    );
    assert!(!e.contains('\n'));
}

#[test]
fn gltf_emissive_texture_splits_the_part_into_glowing_and_dark_triangles() {
    let dir = temp_dir("emissive");
    let (mut doc, whole) = quad_document(&dir);
    // The quad's left half (u < 1/2) glows orange; the right texel is black but for JPEG-like
    // noise under 1% of the orange's luminance, which stays dark.
    one_texture(&mut doc, &dir, "glow.png", &[[255, 128, 0, 255], [3, 3, 3, 255]]);
    doc["materials"][0]["emissiveTexture"] = json!({"index": 0});
    doc["materials"][0]["emissiveFactor"] = json!([2.0, 1.0, 0.5]);
    let asset = load_asset(&write_json(&dir, "glow.gltf", &doc)).unwrap();
    assert_eq!(asset.parts.len(), 2, "a dark part and a glowing part");
    let (dark, lit) = (&asset.parts[0], &asset.parts[1]);
    assert_eq!(dark.material.emission, Vec3::ZERO);
    assert!(lit.material.name.ends_with("(emissive)"), "{}", lit.material.name);
    // sRGB 255 and 128 decode to 1 and 0.2158: times the factor (2, 1, 0.5).
    let want = Vec3::new(2.0, 0.215_861_6, 0.0);
    assert!(
        (lit.material.emission - want).length() < 1e-4,
        "{}",
        lit.material.emission
    );
    assert!((lit.mesh.area() - 0.5 * whole).abs() < 1e-4 && (dark.mesh.area() - 0.5 * whole).abs() < 1e-4);
    assert!(lit.mesh.uvs.iter().all(|uv| uv.x <= 0.5 + 1e-6));
    // A zero factor makes the map dark everywhere: one part, no emission.
    doc["materials"][0]["emissiveFactor"] = json!([0.0, 0.0, 0.0]);
    let asset = load_asset(&write_json(&dir, "off.gltf", &doc)).unwrap();
    assert_eq!(asset.parts.len(), 1);
    assert_eq!(asset.parts[0].material.emission, Vec3::ZERO);
}

#[test]
fn gltf_vertex_colours_multiply_the_base_colour() {
    let dir = temp_dir("colour0");
    let (mut bytes, _, _) = quad_buffer(UNIT_QUAD);
    let mut doc = document(&bytes);
    let plain = load_asset(&write_json(&dir, "plain.gltf", &doc)).unwrap().parts[0]
        .material
        .albedo;
    // COLOR_0 as four VEC3 floats after the quad's data: one colour, then two.
    let add_colours = |doc: &mut serde_json::Value, bytes: &mut Vec<u8>, colours: [[f32; 3]; 4]| {
        let offset = bytes.len();
        bytes.extend(colours.iter().flatten().flat_map(|c| c.to_le_bytes()));
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": 48}));
        doc["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC3"}));
        doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = json!(4);
        let b64 = base64::engine::general_purpose::STANDARD.encode(&*bytes);
        doc["buffers"][0] =
            json!({"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{b64}")});
    };
    add_colours(&mut doc, &mut bytes, [[0.5, 0.25, 1.0]; 4]);
    let one = load_asset(&write_json(&dir, "one.gltf", &doc)).unwrap().parts[0]
        .material
        .albedo;
    assert!(
        (one - plain * Vec3::new(0.5, 0.25, 1.0)).length() < 1e-6,
        "{one} from {plain}"
    );
    // Two colours, each on two corners: each triangle's mean weighs its area (the quad's halves).
    let (mut bytes, _, _) = quad_buffer(UNIT_QUAD);
    let mut doc = document(&bytes);
    add_colours(
        &mut doc,
        &mut bytes,
        [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    );
    let two = load_asset(&write_json(&dir, "two.gltf", &doc)).unwrap().parts[0]
        .material
        .albedo;
    // Triangles (0, 1, 2) and (0, 2, 3): means (2/3, 1/3, 0) and (1/3, 2/3, 0), equal areas.
    assert!(
        (two - plain * Vec3::new(0.5, 0.5, 0.0)).length() < 1e-5,
        "{two} from {plain}"
    );
}

#[test]
fn gltf_mask_texture_cuts_the_triangles_away_where_alpha_is_under_the_cutoff() {
    let dir = temp_dir("cutout");
    let (mut doc, whole) = quad_document(&dir);
    // The quad's uv u runs along x: the texture's right texel (alpha 0) is the quad's right half.
    one_texture(&mut doc, &dir, "leaf.png", &[[0, 255, 0, 255], [0, 255, 0, 0]]);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0});
    doc["materials"][0]["alphaMode"] = json!("MASK");
    let asset = load_asset(&write_json(&dir, "leaf.gltf", &doc)).unwrap();
    let part = &asset.parts[0];
    assert_eq!(part.material.opacity, 1.0);
    assert!(
        (part.mesh.area() - 0.5 * whole).abs() < 1e-4,
        "{} of {whole}",
        part.mesh.area()
    );
    part.mesh.validate("cut").unwrap();
    assert_eq!(part.mesh.tangents.len(), part.mesh.positions.len());
    // Every kept point has u < 1/2: the opaque texel's half.
    assert!(part.mesh.uvs.iter().all(|uv| uv.x <= 0.5 + 1e-6));
    // The base colour factor's alpha scales the texture's: a right texel at alpha 0.6 stays
    // alone (0.6 >= 0.5) and goes under a factor of 0.8 (0.48).
    write_png(&dir.join("leaf.png"), &[[0, 255, 0, 255], [0, 255, 0, 153]]);
    let kept =
        |doc: &serde_json::Value, name: &str| load_asset(&write_json(&dir, name, doc)).unwrap().parts[0].mesh.area();
    assert!((kept(&doc, "faint.gltf") - whole).abs() < 1e-4);
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.0, 1.0, 1.0, 0.8]);
    assert!((kept(&doc, "fainter.gltf") - 0.5 * whole).abs() < 1e-4);
}

#[test]
fn gltf_alpha_modes_and_metallic_roughness_texture() {
    let dir = temp_dir("alpha");
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    let mut doc = document(&bytes);
    doc["materials"][0]["alphaMode"] = json!("BLEND");
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = json!([1.0, 1.0, 1.0, 0.4]);
    // Green (roughness) 255 and 0: mean 0.5; blue (metallic) 255 everywhere.
    write_png(&dir.join("mr.png"), &[[0, 255, 255, 255], [0, 0, 255, 255]]);
    doc["images"] = json!([{"uri": "mr.png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = json!({"index": 0});
    doc["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = json!(1.0);
    doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(1.0);
    let path = write_json(&dir, "blend.gltf", &doc);
    let m = load_asset(&path).unwrap().parts[0].material.clone();
    assert!((m.opacity - 0.4).abs() < 1e-6);
    assert!((m.exponent - 30.0).abs() < 0.5, "{}", m.exponent);
    assert!(
        m.albedo.max_element() < 1e-6,
        "fully metallic: no diffuse, got {}",
        m.albedo
    );

    // MASK with the factor's alpha under the cutoff hides the primitive: no part is left.
    doc["materials"][0]["alphaMode"] = json!("MASK");
    let path = write_json(&dir, "mask.gltf", &doc);
    let e = load_asset(&path).unwrap_err();
    assert!(e.to_string().contains("no visible triangles"), "{e}");
}

const OBJ: &str = "mtllib two.mtl
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1
usemtl brick
f 1/1 2/2 3/3 4/4
usemtl glass
f 2/1 5/2 6/3 3/4
";

fn write_obj(dir: &Path, mtl: &str) -> PathBuf {
    write_png(&dir.join("brick.png"), &[[180, 90, 40, 255]]);
    write_png(&dir.join("brick_n.png"), &[[128, 128, 255, 255]]);
    std::fs::write(dir.join("two.mtl"), mtl).unwrap();
    let path = dir.join("two.obj");
    std::fs::write(&path, OBJ).unwrap();
    path
}

const MTL: &str = "newmtl brick
Kd 0.9 0.8 0.7
Ks 0.1 0.1 0.1
Ns 64
map_Kd brick.png
norm brick_n.png
newmtl glass
Kd 0.2 0.3 0.4
d 0.25
Ke 1 2 3
";

#[test]
fn obj_mtl_one_part_per_material() {
    let dir = temp_dir("objmtl");
    let path = write_obj(&dir, MTL);
    let asset = load_asset(&path).unwrap();
    assert_eq!(asset.parts.len(), 2);
    let (brick, glass) = (&asset.parts[0], &asset.parts[1]);
    assert_eq!(brick.material.name, "brick");
    assert_eq!(brick.material.albedo, Vec3::new(0.9, 0.8, 0.7));
    assert_eq!(brick.material.specular, Vec3::splat(0.1));
    assert_eq!(brick.material.exponent, 64.0);
    assert!(brick.material.albedo_map.as_ref().unwrap().ends_with("brick.png"));
    assert!(brick.material.normal_map.as_ref().unwrap().ends_with("brick_n.png"));
    assert_eq!(brick.mesh.triangle_count(), 2);
    assert!(brick.mesh.positions.iter().all(|p| p.x <= 1.0));
    assert_eq!(glass.material.opacity, 0.25);
    assert_eq!(glass.material.emission, Vec3::new(1.0, 2.0, 3.0));
    assert!(glass.mesh.positions.iter().all(|p| p.x >= 1.0));

    // map_d cuts the faces away where it is under one half: a grey mask (no alpha channel)
    // dark on its right texel keeps the glass quad's left half.
    let dir = temp_dir("objmapd");
    let path = write_obj(&dir, &MTL.replace("d 0.25", "map_d mask.png"));
    write_png(&dir.join("mask.png"), &[[255, 255, 255, 255], [20, 20, 20, 255]]);
    let asset = load_asset(&path).unwrap();
    let glass = &asset.parts[1].mesh;
    assert!((glass.area() - 0.5).abs() < 1e-4, "{}", glass.area());
    assert!(glass.positions.iter().all(|p| p.x <= 1.5 + 1e-6), "the left half stays");

    // map_Ke (with Ke as its factor) glows where its texels do: the glass quad's right half.
    let dir = temp_dir("objmapke");
    let path = write_obj(
        &dir,
        &MTL.replace("Ke 1 2 3", "Ke 1 2 3\nmap_Ke glow.png")
            .replace("d 0.25", "d 1"),
    );
    write_png(&dir.join("glow.png"), &[[0, 0, 0, 255], [255, 255, 255, 255]]);
    let asset = load_asset(&path).unwrap();
    let lit = asset.parts.iter().find(|p| p.material.emission != Vec3::ZERO).unwrap();
    assert_eq!(lit.material.emission, Vec3::new(1.0, 2.0, 3.0));
    assert!((lit.mesh.area() - 0.5).abs() < 1e-4 && lit.mesh.positions.iter().all(|p| p.x >= 1.5 - 1e-6));

    // bump is read as the normal map too.
    let dir = temp_dir("objbump");
    let path = write_obj(&dir, &MTL.replace("norm brick_n.png", "bump brick_n.png"));
    let asset = load_asset(&path).unwrap();
    assert!(asset.parts[0].material.normal_map.is_some());
}

#[test]
fn obj_mtl_bad_input_is_one_line() {
    let cases = [
        (
            MTL.replace("map_Kd brick.png", "map_Kd gone.png"),
            "materials[0] \"brick\".map_Kd: texture not found",
        ),
        (
            MTL.replace("d 0.25", "map_d gone.png"),
            "\"glass\".map_d: texture not found",
        ),
        (
            MTL.replace("Kd 0.2 0.3 0.4", "Kd 0.2 NaN 0.4"),
            "\"glass\".Kd: is not finite",
        ),
        (
            MTL.replace("Kd 0.9 0.8 0.7", "Kd 1.9 0.8 0.7"),
            "\"brick\".Kd: each channel must be in [0, 1]",
        ),
        (
            MTL.replace("newmtl glass", "newmtl glas"),
            "usemtl: material \"glass\" is not in the MTL",
        ),
        (
            MTL.replace("map_Kd brick.png", "map_Kd -bm 2 brick.png"),
            "texture options are not supported",
        ),
    ];
    for (i, (mtl, needle)) in cases.iter().enumerate() {
        let dir = temp_dir(&format!("objbad{i}"));
        let e = load_asset(&write_obj(&dir, mtl)).unwrap_err().to_string();
        assert!(e.contains(needle), "{i}: {e}");
        assert!(!e.contains('\n'));
    }
    let dir = temp_dir("objnomtl");
    let path = write_obj(&dir, MTL);
    std::fs::remove_file(dir.join("two.mtl")).unwrap();
    let e = load_asset(&path).unwrap_err().to_string();
    assert!(e.contains("two.obj: mtllib: cannot read"), "{e}");
}

#[test]
fn scene_places_an_asset_and_takes_its_camera() {
    let dir = temp_dir("scene-asset");
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    write_json(&dir, "quad.gltf", &document(&bytes));
    let toml = r#"
[[objects]]
name = "q"
mesh = "asset"
path = "quad.gltf"
translate = [0, 0, -3]
scale = 0.5
camera = 0
"#;
    let scene = crate::scene::Scene::from_str(toml, "s.toml", &dir).unwrap();
    assert_eq!(scene.objects.len(), 1);
    assert_eq!(scene.materials.last().unwrap().name, "q:gold");
    let m = Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0)) * Mat4::from_scale(Vec3::splat(0.5));
    assert_eq!(scene.objects[0].transform, m);
    assert!((scene.camera.position - m.transform_point3(Vec3::new(0.0, 0.5, 5.0))).length() < 1e-6);
    // The light sits at world1 · (0, 0, 1) = (4, 1, 0) in the asset, then the placement applies.
    let Light::Point { position, .. } = &scene.lights[0] else {
        panic!()
    };
    assert!((*position - Vec3::new(2.0, 0.5, -3.0)).length() < 1e-5, "{position}");

    let bad = toml.replace("camera = 0", "camera = 3");
    let e = crate::scene::Scene::from_str(&bad, "s.toml", &dir)
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.toml:8: objects[0].camera: camera 3 asked for"), "{e}");
}

#[test]
fn an_asset_alone_is_a_scene_framed_and_lit_when_it_has_no_camera_or_light() {
    let dir = temp_dir("alone");
    let path = write_obj(&dir, MTL);
    let scene = crate::scene::Scene::from_file(&path).unwrap();
    assert_eq!(scene.methods[0].name, "forward");
    assert_eq!(scene.objects.len(), 2);
    assert!(matches!(scene.environment, Some(Environment::Constant { .. })));
    assert!(matches!(scene.lights[..], [Light::Directional { .. }]));
    // The bounds (x 0..2, y 0..1, z 0) are in view: their centre is on the view axis.
    let (_, _, fwd) = scene.camera.basis();
    let to_centre = (Vec3::new(1.0, 0.5, 0.0) - scene.camera.position).normalize();
    assert!(fwd.dot(to_centre) > 0.9999);
}

#[test]
fn gltf_spot_and_directional_lights_in_photometric_units() {
    let dir = temp_dir("lights");
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    let mut doc = document(&bytes);
    doc["extensions"]["KHR_lights_punctual"]["lights"] = json!([
        {"type": "spot", "color": [1.0, 1.0, 0.5], "intensity": 1366.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}},
        {"type": "directional", "color": [0.5, 1.0, 1.0], "intensity": 6830.0}
    ]);
    // Node 2 (under node 1, turned 90 degrees about y) holds the spot; a root node turned -90
    // degrees about x (so its -z points down) holds the sun.
    let h = std::f32::consts::FRAC_1_SQRT_2;
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"extensions": {"KHR_lights_punctual": {"light": 1}}, "rotation": [-h, 0.0, 0.0, h]}));
    doc["scenes"][0]["nodes"] = json!([0, 3, 4]);
    let path = write_json(&dir, "lights.gltf", &doc);
    let asset = load_asset(&path).unwrap();
    let Light::Spot {
        direction,
        intensity,
        inner_deg,
        outer_deg,
        ..
    } = &asset.lights[0]
    else {
        panic!("{:?}", asset.lights)
    };
    // Node 1 turns -z to -x: the spot shines along -x.
    assert!((*direction - Vec3::NEG_X).length() < 1e-5, "{direction}");
    assert!((*intensity - Vec3::new(2.0, 2.0, 1.0)).length() < 1e-5);
    assert!((inner_deg - 0.2f32.to_degrees()).abs() < 1e-4 && (outer_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    let Light::Directional {
        direction, irradiance, ..
    } = &asset.lights[1]
    else {
        panic!("{:?}", asset.lights)
    };
    assert!((*direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
    assert!((*irradiance - Vec3::new(5.0, 10.0, 10.0)).length() < 1e-4);
}

#[test]
fn the_command_line_chooses_among_the_cameras_the_assets_carry() {
    let dir = temp_dir("choose-camera");
    let (bytes, _, _) = quad_buffer(UNIT_QUAD);
    let mut doc = document(&bytes);
    // A second camera node, 2 m to the right of the first.
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"camera": 0, "translation": [2.0, 0.5, 5.0]}));
    let second = doc["nodes"].as_array().unwrap().len() - 1;
    doc["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(second));
    let path = write_json(&dir, "two.gltf", &doc);
    let toml = r#"
[camera]
position = [0, 9, 9]
target = [0, 0, 0]

[[objects]]
name = "q"
mesh = "asset"
path = "two.gltf"
translate = [0, 0, -3]
"#;
    let mut scene = crate::scene::Scene::from_str(toml, "s.toml", &dir).unwrap();
    assert_eq!(
        scene.camera.position,
        Vec3::new(0.0, 9.0, 9.0),
        "the scene's own camera by default"
    );
    assert_eq!(scene.cameras.len(), 2);
    let overrides = crate::scene::SceneOverrides {
        camera: Some(1),
        memory_budget_mb: Some(64.0),
    };
    overrides.apply(&mut scene).unwrap();
    // Placed as the object is: the asset's (2, 0.5, 5) moved by (0, 0, -3).
    assert!(
        (scene.camera.position - Vec3::new(2.0, 0.5, 2.0)).length() < 1e-6,
        "{}",
        scene.camera.position
    );
    assert_eq!(scene.memory_budget_mb, Some(64.0));
    let e = scene.choose_camera(2).unwrap_err().to_string();
    assert!(
        e.contains("s.toml: cameras: --camera 2 asked for, the scene's assets carry 2 (--camera 0 to 1)"),
        "{e}"
    );
    assert!(!e.contains('\n'));

    let mut alone = crate::scene::Scene::from_file(&path).unwrap();
    assert!((alone.camera.position - Vec3::new(0.0, 0.5, 5.0)).length() < 1e-6);
    alone.choose_camera(1).unwrap();
    assert!((alone.camera.position - Vec3::new(2.0, 0.5, 5.0)).length() < 1e-6);

    let mut plain = crate::scene::Scene::default_scene();
    let e = plain.choose_camera(0).unwrap_err().to_string();
    assert!(
        e.contains("--camera 0 asked for, no asset of the scene carries a camera"),
        "{e}"
    );
}
