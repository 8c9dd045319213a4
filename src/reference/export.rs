//! `penumbra reference SCENE --export-scene DIR`: the scene exactly as the path tracer sees it,
//! for another renderer (`tools/reference_vs_mitsuba.py` builds a Mitsuba 3 scene from it).
//!
//! `DIR/scene.json` holds the camera, the materials, the lights and the environment;
//! `DIR/material_<k>.ply` the world-space triangles of material `k` (binary little-endian PLY,
//! three vertices of its own per face, each with its position and shading normal; a zero normal
//! where the mesh has none, which the tracer replaces by the face's normal).

use std::path::{Path, PathBuf};

use glam::{Vec3, Vec4};
use serde_json::{json, Value};

use super::TracedScene;
use crate::error::{Error, Result};
use crate::scene::{Environment, Light, Scene};

type Face = ([Vec3; 3], [Vec3; 3]);

fn write(path: &Path, bytes: &[u8]) -> Result<()> {
    std::fs::write(path, bytes).map_err(|e| Error::Usage(format!("{}: cannot write: {e}", path.display())))
}

/// Binary PLY of unshared triangles with per-vertex positions and normals.
pub fn ply(faces: &[Face]) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        faces.len() * 3,
        faces.len()
    );
    let mut out = header.into_bytes();
    for (p, n) in faces {
        for k in 0..3 {
            for v in [p[k].x, p[k].y, p[k].z, n[k].x, n[k].y, n[k].z] {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    for f in 0..faces.len() as u32 {
        out.push(3);
        for k in 0..3 {
            out.extend_from_slice(&(3 * f + k).to_le_bytes());
        }
    }
    out
}

fn v3(v: Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

/// Writes `scene.json` and one PLY per material that has triangles into `dir` (created if
/// missing); returns the files written.
pub fn export(scene: &Scene, traced: &TracedScene, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Usage(format!("{}: cannot create: {e}", dir.display())))?;
    let mut per_material: Vec<Vec<Face>> = vec![Vec::new(); traced.materials.len()];
    for (t, s) in traced.triangles.iter().zip(&traced.shading) {
        let p0 = Vec4::from(t.p0).truncate();
        let p = [p0, p0 + Vec4::from(t.e1).truncate(), p0 + Vec4::from(t.e2).truncate()];
        per_material[s.material as usize].push((p, [s.n0.into(), s.n1.into(), s.n2.into()]));
    }
    let mut written = Vec::new();
    let mut materials = Vec::new();
    for (k, (m, faces)) in scene.materials.iter().zip(&per_material).enumerate() {
        let mesh = if faces.is_empty() {
            Value::Null
        } else {
            let name = format!("material_{k}.ply");
            let path = dir.join(&name);
            write(&path, &ply(faces))?;
            written.push(path);
            json!(name)
        };
        materials.push(json!({
            "name": m.name, "mesh": mesh, "triangles": faces.len(),
            "albedo": v3(m.albedo), "specular": v3(m.specular), "exponent": m.exponent,
            "transmittance": v3(m.transmittance), "emission": v3(m.emission), "opacity": m.opacity,
            "texture_maps": m.albedo_map.is_some() || m.normal_map.is_some() || m.specular_map.is_some(),
        }));
    }
    let lights: Vec<Value> = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Point { position, intensity, .. } => json!({"type": "point", "position": v3(*position), "intensity": v3(*intensity)}),
            Light::Spot { position, direction, intensity, inner_deg, outer_deg, .. } => {
                json!({"type": "spot", "position": v3(*position), "direction": v3(*direction), "intensity": v3(*intensity), "inner_deg": inner_deg, "outer_deg": outer_deg})
            }
            Light::Directional { direction, irradiance, .. } => json!({"type": "directional", "direction": v3(*direction), "irradiance": v3(*irradiance)}),
            Light::Sphere { center, radius, radiance, .. } => json!({"type": "sphere", "center": v3(*center), "radius": radius, "radiance": v3(*radiance)}),
            Light::Quad { corner, edge_u, edge_v, radiance, .. } => {
                json!({"type": "quad", "corner": v3(*corner), "edge_u": v3(*edge_u), "edge_v": v3(*edge_v), "radiance": v3(*radiance)})
            }
        })
        .collect();
    let environment = match &scene.environment {
        None => Value::Null,
        Some(Environment::Constant { radiance }) => json!({"type": "constant", "radiance": v3(*radiance)}),
        Some(Environment::Image { path, scale }) => {
            json!({"type": "image", "path": path.display().to_string(), "scale": scale})
        }
        Some(Environment::Cube { scale, .. }) => json!({"type": "cube", "scale": scale}),
    };
    let cam = &scene.camera;
    let doc = json!({
        "camera": {"position": v3(cam.position), "target": v3(cam.target), "up": v3(cam.up), "fov_y_deg": cam.fov_y_deg},
        "materials": materials,
        "lights": lights,
        "environment": environment,
    });
    let path = dir.join("scene.json");
    write(&path, serde_json::to_string_pretty(&doc).unwrap_or_default().as_bytes())?;
    written.push(path);
    Ok(written)
}

/// [`export`] of a scene file.
pub fn export_file(scene: &Path, dir: &Path) -> Result<Vec<PathBuf>> {
    let scene = Scene::from_file(scene)?;
    let traced = TracedScene::build(&scene)?;
    export(&scene, &traced, dir)
}
