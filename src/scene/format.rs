//! The scene file format (documented in `scenes/README.md`): reads the spanned TOML tree into a
//! checked [`Scene`].

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use super::asset;
use super::cornell;
use super::doc::{Ctx, Field, Table};
use super::error::SceneError;
use super::generators;
use super::methods::{self, MethodDecl};
use super::motion::{LightMotion, Wind};
use super::types::{Animation, Camera, CubeFaces, Environment, Light, Material, MeshSource, Object, CUBE_FACE_KEYS};
use super::world_mesh::{self, WorldLevel};
use super::Scene;
use crate::world::level_gen::RoomsParams;

// long: one top-level key after another, in the order their errors are reported.
pub(crate) fn parse(text: &str, source: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    let ctx = Ctx::new(source, text, base_dir);
    let root = ctx.parse()?;
    let top = Table::new(&ctx, String::new(), &root, None)?;
    top.allow(&[
        "camera",
        "materials",
        "objects",
        "lights",
        "environment",
        "methods",
        "combinations",
        "light_arrays",
        "light_board",
        "light_motion",
        "memory_budget_mb",
    ])?;

    // Read first, so its errors come before the materials' and objects'.
    let given_camera = top.get("camera").map(|f| read_camera(&f).map(|c| (c, f))).transpose()?;
    let asset_gives_camera = top.get("objects").and_then(|f| f.array().ok()).is_some_and(|items| {
        items
            .iter()
            .any(|i| i.table().ok().is_some_and(|t| t.get("camera").is_some()))
    });
    if given_camera.is_none() && !asset_gives_camera {
        top.require("camera", "a [camera] table")?;
    }
    let mut materials: Vec<Material> = Vec::new();
    for item in array(top.get("materials"))? {
        materials.push(read_material(&item, &materials)?);
    }
    // Objects may pull in built-in materials, lights (Cornell box, assets) and a camera (assets).
    let mut objects = Vec::new();
    let mut extra_lights = Vec::new();
    let mut asset_camera = None;
    let mut cameras = Vec::new();
    for item in array(top.get("objects"))? {
        let mut out = Expanded {
            materials: &mut materials,
            objects: &mut objects,
            lights: &mut extra_lights,
            camera: &mut asset_camera,
            cameras: &mut cameras,
        };
        read_object(&item, &mut out)?;
    }
    let camera = match (given_camera, asset_camera) {
        (Some((c, _)), None) => c,
        (Some((_, f)), Some(_)) => {
            return Err(f.err("an object's `camera` gives the scene's camera; remove one of the two"))
        }
        (None, Some(c)) => c,
        (None, None) => read_camera(&top.require("camera", "a [camera] table")?)?,
    };
    let mut lights = Vec::new();
    for item in array(top.get("lights"))? {
        lights.push(read_light(&item)?);
    }
    let mut generated = 0u64;
    for item in array(top.get("light_arrays"))? {
        let expanded = read_light_array(&item, generated)?;
        generated += expanded.len() as u64;
        lights.extend(expanded);
    }
    lights.extend(extra_lights);
    let light_board = top.get("light_board").map(|f| read_light_board(&f)).transpose()?;
    let light_motion = top
        .get("light_motion")
        .map(|f| read_light_motion(&f, &lights))
        .transpose()?;
    let environment = top.get("environment").map(|f| read_environment(&f)).transpose()?;
    let memory_budget_mb = opt(top.get("memory_budget_mb"), |f| {
        f.number_where("a memory budget in MB, at least 1", |x| x.is_finite() && x >= 1.0)
    })?
    .map(f64::from);
    let mut methods = match top.get("methods") {
        Some(f) => methods::read(&f)?,
        None => Vec::new(),
    };
    if methods.is_empty() {
        methods.push(MethodDecl::implicit_forward());
    }
    let combinations = match top.get("combinations") {
        Some(f) => methods::read_combinations(&f)?,
        None => Vec::new(),
    };
    Ok(Scene {
        source: source.to_owned(),
        camera,
        cameras,
        materials,
        objects,
        lights,
        environment,
        methods,
        combinations,
        light_board,
        light_motion,
        memory_budget_mb,
    })
}

/// Elements of an optional array field (absent = empty).
fn array<'a>(f: Option<Field<'a>>) -> Result<Vec<Field<'a>>, SceneError> {
    f.map_or(Ok(Vec::new()), |f| f.array())
}

/// Converts an optional field, keeping its error.
fn opt<'a, T>(
    f: Option<Field<'a>>,
    conv: impl FnOnce(&Field<'a>) -> Result<T, SceneError>,
) -> Result<Option<T>, SceneError> {
    f.as_ref().map(conv).transpose()
}

fn positive(f: &Field) -> Result<f32, SceneError> {
    f.number_where("a positive number", |x| x > 0.0)
}

fn non_negative(f: &Field) -> Result<f32, SceneError> {
    f.number_where("a non-negative number", |x| x >= 0.0)
}

fn name(f: &Field) -> Result<String, SceneError> {
    let s = f.string()?;
    if s.trim().is_empty() {
        return Err(f.err("expected a name, got an empty string"));
    }
    Ok(s.to_owned())
}

/// A unit direction from a non-zero vector (normalized in f64: in f32 the squared length of a
/// tiny vector such as [1e-30, 0, 0] underflows to zero).
fn direction(f: &Field) -> Result<Vec3, SceneError> {
    let v = f.vec3()?;
    v.as_dvec3().try_normalize().map(|d| d.as_vec3()).ok_or_else(|| {
        f.err(format!(
            "expected a non-zero direction, got [{}, {}, {}]",
            v.x, v.y, v.z
        ))
    })
}

/// The largest camera coordinate, metres.
const MAX_CAMERA_COORDINATE: f32 = 1e6;

fn read_camera(f: &Field) -> Result<Camera, SceneError> {
    let t = f.table()?;
    t.allow(&["position", "target", "up", "fov_y_deg", "near"])?;
    let position_f = t.require("position", "3 numbers, metres")?;
    let position = position_f.vec3()?;
    let target_f = t.require("target", "3 numbers, metres")?;
    let target = target_f.vec3()?;
    let up_f = t.get("up");
    let up = opt(up_f.clone(), |f| f.vec3())?.unwrap_or(Vec3::Y);
    let fov_y_deg = opt(t.get("fov_y_deg"), |f| {
        f.number_where("a vertical field of view in degrees, in (0, 180)", |x| {
            x > 0.0 && x < 180.0
        })
    })?
    .unwrap_or(60.0);
    let near = opt(t.get("near"), positive)?.unwrap_or(0.05);

    // 32-bit floats keep about a centimetre at a thousand kilometres; farther, the view matrix
    // (and the length of target − position) falls apart.
    for (f, p) in [(&position_f, position), (&target_f, target)] {
        if p.abs().max_element() > MAX_CAMERA_COORDINATE {
            let coords: Vec<String> = p
                .to_array()
                .iter()
                .map(|c| {
                    if c.abs() >= 1e6 {
                        format!("{c:e}")
                    } else {
                        c.to_string()
                    }
                })
                .collect();
            return Err(f.err(format!(
                "[{}] is too far from the origin: coordinates are limited to ±{MAX_CAMERA_COORDINATE:e} m",
                coords.join(", ")
            )));
        }
    }
    let Some(forward) = (target - position).try_normalize() else {
        return Err(target_f.err("must differ from camera.position"));
    };
    if forward.cross(up.normalize_or_zero()).length() < 1e-3 {
        let msg = "must not be zero or parallel to the view direction (target - position)";
        return Err(match &up_f {
            Some(u) => u.err(msg),
            None => t.ctx.err(
                t.line,
                "camera.up",
                format!("the default [0, 1, 0] {msg}; set camera.up"),
            ),
        });
    }
    Ok(Camera {
        position,
        target,
        up,
        fov_y_deg,
        near,
    })
}

fn read_material(f: &Field, earlier: &[Material]) -> Result<Material, SceneError> {
    let t = f.table()?;
    t.allow(&[
        "name",
        "albedo",
        "specular",
        "exponent",
        "albedo_map",
        "normal_map",
        "specular_map",
        "transmittance",
        "emission",
        "opacity",
        "sky",
    ])?;
    let name_f = t.require("name", "a unique material name")?;
    let name = name(&name_f)?;
    if earlier.iter().any(|m| m.name == name) {
        return Err(name_f.err(format!("material {name:?} is defined twice")));
    }
    let albedo = opt(t.get("albedo"), |f| f.unit_colour())?.unwrap_or(Vec3::splat(0.8));
    let transmittance_f = t.get("transmittance");
    let transmittance = opt(transmittance_f.clone(), |f| f.unit_colour())?.unwrap_or(Vec3::ZERO);
    if let Some(tf) = &transmittance_f {
        if (albedo + transmittance).max_element() > 1.0 {
            return Err(tf.err(format!(
                "albedo + transmittance must not exceed 1 in any channel, got {} + {}",
                fmt3(albedo),
                fmt3(transmittance)
            )));
        }
    }
    Ok(Material {
        name,
        albedo,
        specular: opt(t.get("specular"), |f| f.unit_colour())?.unwrap_or(Vec3::ZERO),
        exponent: opt(t.get("exponent"), non_negative)?.unwrap_or(32.0),
        albedo_map: opt(t.get("albedo_map"), |f| f.existing_image())?,
        normal_map: opt(t.get("normal_map"), |f| f.existing_image())?,
        specular_map: opt(t.get("specular_map"), |f| f.existing_image())?,
        transmittance,
        emission: opt(t.get("emission"), |f| f.colour())?.unwrap_or(Vec3::ZERO),
        opacity: opt(t.get("opacity"), |f| {
            f.number_where("a number in (0, 1]", |x| x > 0.0 && x <= 1.0)
        })?
        .unwrap_or(1.0),
        sky: opt(t.get("sky"), |f| f.boolean())?.unwrap_or(false),
    })
}

fn fmt3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// What an object adds to the scene besides itself.
struct Expanded<'a> {
    materials: &'a mut Vec<Material>,
    objects: &'a mut Vec<Object>,
    lights: &'a mut Vec<Light>,
    /// The camera of an asset object that names one (`camera = N`).
    camera: &'a mut Option<Camera>,
    /// Every camera the assets carry, placed: what `--camera N` chooses from.
    cameras: &'a mut Vec<Camera>,
}

// long: one key of an object table after another, each read and checked.
fn read_object(f: &Field, out: &mut Expanded) -> Result<(), SceneError> {
    let (materials, objects, lights) = (&mut *out.materials, &mut *out.objects, &mut *out.lights);
    let t = f.table()?;
    const PLACEMENT: [&str; 5] = ["name", "mesh", "translate", "rotate_deg", "scale"];
    let Some(mesh_f) = t.get("mesh") else {
        // Report a misspelt key before the missing `mesh`.
        t.allow(&all_keys(&[&PLACEMENT[..], &["material"]].concat(), &MESH_KEYS))?;
        return Err(t.missing("mesh", &format!("one of: {}", type_names(&MESH_KEYS))));
    };
    let kind = mesh_f.string()?;
    let Some((_, mesh_extra)) = MESH_KEYS.iter().find(|(n, _)| *n == kind) else {
        let msg = format!(
            "unknown mesh type {kind:?}; expected one of: {}",
            type_names(&MESH_KEYS)
        );
        return Err(mesh_f.err(msg));
    };
    let expands = matches!(kind, "cornell_box" | "bsp_rooms" | "bsp_fig8c");
    let material_key: &[&str] = if expands || kind == "asset" { &[] } else { &["material"] };
    let animation_keys: &[&str] = if expands { &[] } else { &ANIMATION_KEYS };
    let wind_key: &[&str] = if expands || kind == "heightfield" || kind == "asset" {
        &[]
    } else {
        &["wind"]
    };
    t.allow(&[&PLACEMENT[..], material_key, animation_keys, wind_key, mesh_extra].concat())?;

    let obj_name = opt(t.get("name"), name)?.unwrap_or_else(|| f.path.clone());
    let translate = opt(t.get("translate"), |f| f.vec3())?.unwrap_or(Vec3::ZERO);
    let rot = opt(t.get("rotate_deg"), |f| f.vec3())?.unwrap_or(Vec3::ZERO);
    let scale = opt(t.get("scale"), |f| f.positive3())?.unwrap_or(Vec3::ONE);
    // x rotation first, then y, then z.
    let transform = Mat4::from_translation(translate)
        * Mat4::from_rotation_z(rot.z.to_radians())
        * Mat4::from_rotation_y(rot.y.to_radians())
        * Mat4::from_rotation_x(rot.x.to_radians())
        * Mat4::from_scale(scale);
    let subdivisions = opt(t.get("subdivisions"), |f| f.int_in(1, generators::MAX_SUBDIVISIONS))?.unwrap_or(1);

    if kind == "bsp_rooms" || kind == "bsp_fig8c" {
        return read_world(&t, kind, &obj_name, materials, objects);
    }
    let animation = read_animation(&t)?;
    if kind == "asset" {
        return read_asset(&t, &obj_name, transform, animation, out);
    }
    let wind = opt(t.get("wind"), read_wind)?;

    if kind == "cornell_box" {
        for part in cornell::parts(subdivisions) {
            objects.push(Object {
                name: format!("{obj_name}.{}", part.suffix),
                mesh: part.mesh,
                material: material_index(materials, part.material).unwrap_or(0),
                transform: transform * part.local,
                animation,
                wind: None,
            });
        }
        if opt(t.get("light"), |f| f.boolean())?.unwrap_or(true) {
            lights.push(cornell::light(format!("{obj_name}.light"), &transform));
        }
        return Ok(());
    }

    let mesh = match kind {
        "plane" => MeshSource::Plane {
            size: opt(t.get("size"), |f| f.positive2())?.unwrap_or(glam::Vec2::ONE),
            subdivisions,
        },
        "box" => MeshSource::Box {
            size: opt(t.get("size"), |f| f.positive3())?.unwrap_or(Vec3::ONE),
            subdivisions,
        },
        "quad" => {
            let corner = t.require("corner", "3 numbers, metres")?.vec3()?;
            let edge_u = t.require("edge_u", "3 numbers, metres")?.vec3()?;
            let v_f = t.require("edge_v", "3 numbers, metres")?;
            let edge_v = v_f.vec3()?;
            check_quad_edges(&v_f, edge_u, edge_v)?;
            MeshSource::Quad {
                corner,
                edge_u,
                edge_v,
                subdivisions,
            }
        }
        "sphere" => MeshSource::Sphere {
            radius: opt(t.get("radius"), positive)?.unwrap_or(1.0),
            segments: opt(t.get("segments"), |f| f.int_in(3, generators::MAX_SEGMENTS))?.unwrap_or(48),
            rings: opt(t.get("rings"), |f| f.int_in(2, generators::MAX_RINGS))?.unwrap_or(24),
        },
        "bush" => MeshSource::Bush {
            leaves: opt(t.get("leaves"), |f| f.int_in(1, generators::MAX_LEAVES))?.unwrap_or(5500),
            seed: opt(t.get("seed"), |f| f.int_in(0, u32::MAX))?.unwrap_or(1),
            radius: opt(t.get("radius"), positive)?.unwrap_or(1.0),
            height: opt(t.get("height"), positive)?.unwrap_or(1.2),
            leaf_size: opt(t.get("leaf_size"), positive)?.unwrap_or(0.12),
        },
        "heightfield" => MeshSource::Heightfield(super::heightfield::read(&t)?),
        _ => MeshSource::Obj(
            t.require("path", "an OBJ file relative to the scene file")?
                .existing_file()?,
        ),
    };
    let material = match t.get("material") {
        None => material_index(materials, "default").unwrap_or(0),
        Some(mf) => {
            let wanted = mf.string()?;
            material_index(materials, wanted).ok_or_else(|| {
                let mut names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                for b in cornell::BUILTIN_MATERIALS {
                    if !names.contains(&b) {
                        names.push(b);
                    }
                }
                mf.err(format!(
                    "unknown material {wanted:?}; defined materials: {}",
                    names.join(", ")
                ))
            })?
        }
    };
    objects.push(Object {
        name: obj_name,
        mesh,
        material,
        transform,
        animation,
        wind,
    });
    Ok(())
}

/// An asset object: one object per material of the file, its lights, and its camera `camera`
/// when the object names one; all placed by `transform`.
fn read_asset(
    t: &Table,
    name: &str,
    transform: Mat4,
    animation: Option<Animation>,
    out: &mut Expanded,
) -> Result<(), SceneError> {
    let path_f = t.require("path", "an .obj, .gltf or .glb file relative to the scene file")?;
    let path = path_f.existing_file()?;
    if !asset::is_asset_path(&path) {
        return Err(path_f.err("expected an .obj, .gltf or .glb file"));
    }
    let loaded = asset::load_asset(&path)?;
    let first = out.objects.len();
    let lights = loaded.place(&path, name, transform, out.materials, out.objects);
    out.lights.extend(lights);
    for o in &mut out.objects[first..] {
        o.animation = animation;
    }
    out.cameras
        .extend(loaded.cameras.iter().map(|c| asset::transform_camera(c, &transform)));
    if let Some(cf) = t.get("camera") {
        let n = loaded.cameras.len();
        let i = cf.int_in(0, u32::MAX)? as usize;
        let Some(c) = loaded.cameras.get(i) else {
            return Err(cf.err(format!("camera {i} asked for, {} has {n}", path.display())));
        };
        if out.camera.is_some() {
            return Err(cf.err("another object already gives the scene's camera"));
        }
        *out.camera = Some(asset::transform_camera(c, &transform));
    }
    Ok(())
}

/// Keys of an entity's [`Animation`] (any mesh but the expanding ones).
const ANIMATION_KEYS: [&str; 3] = ["spin_deg_per_s", "bob_amplitude", "bob_period_s"];

fn read_animation(t: &Table) -> Result<Option<Animation>, SceneError> {
    let spin = opt(t.get("spin_deg_per_s"), |f| f.vec3())?;
    let amplitude = opt(t.get("bob_amplitude"), |f| f.vec3())?;
    let period = opt(t.get("bob_period_s"), positive)?;
    if spin.is_none() && amplitude.is_none() && period.is_none() {
        return Ok(None);
    }
    Ok(Some(Animation {
        spin_deg_per_s: spin.unwrap_or(Vec3::ZERO),
        bob_amplitude: amplitude.unwrap_or(Vec3::ZERO),
        bob_period_s: period.unwrap_or(4.0),
    }))
}

/// Keys of the world meshes besides the placement: the generator's parameters, then one material
/// per face class (`<class>_material`).
const ROOMS_KEYS: [&str; 10] = [
    "seed",
    "columns",
    "rows",
    "pillars",
    "floor_material",
    "ceiling_material",
    "wall_material",
    "pillar_material",
    "corridor_material",
    "cell_size",
];
const FIG8C_KEYS: [&str; 5] = [
    "floor_material",
    "ceiling_material",
    "wall_material",
    "pillar_material",
    "corridor_material",
];

/// `bsp_rooms` / `bsp_fig8c`: one object per face class, like `cornell_box`. Only a translation
/// is allowed (methods map lights into the world's frame with it).
fn read_world(
    t: &Table,
    kind: &str,
    obj_name: &str,
    materials: &mut Vec<Material>,
    objects: &mut Vec<Object>,
) -> Result<(), SceneError> {
    for key in ["rotate_deg", "scale"] {
        if let Some(f) = t.get(key) {
            return Err(f.err(format!("{kind} allows only `translate` (the world's axes are fixed)")));
        }
    }
    let translate = opt(t.get("translate"), |f| f.vec3())?.unwrap_or(Vec3::ZERO);
    let level = if kind == "bsp_fig8c" {
        WorldLevel::Fig8c
    } else {
        let mut params = RoomsParams::default();
        if let Some(v) = opt(t.get("columns"), |f| f.int_in(1, 8))? {
            params.columns = v as usize;
        }
        if let Some(v) = opt(t.get("rows"), |f| f.int_in(1, 8))? {
            params.rows = v as usize;
        }
        if params.columns * params.rows < 2 {
            let f = t.get("columns").or(t.get("rows"));
            let msg = "columns × rows must be at least 2 (rooms are joined by corridors)";
            return Err(match f {
                Some(f) => f.err(msg),
                None => t.ctx.err(t.line, &t.path, msg),
            });
        }
        if let Some(f) = t.get("pillars") {
            let v = f.int_in(0, 6)? as usize;
            params.pillars = (v, v);
        }
        if let Some(v) = opt(t.get("cell_size"), |f| {
            f.number_where("a cell size in metres, from 12 to 40", |x| (12.0..=40.0).contains(&x))
        })? {
            params.cell_size = f64::from(v);
        }
        let seed = opt(t.get("seed"), |f| f.int_in(0, u32::MAX))?.unwrap_or(1);
        WorldLevel::Rooms {
            seed: u64::from(seed),
            params,
        }
    };
    for (suffix, class) in world_mesh::CLASSES {
        let key = format!("{suffix}_material");
        let material = match t.get(&key) {
            None => material_index(materials, "default").unwrap_or(0),
            Some(mf) => {
                let wanted = mf.string()?;
                material_index(materials, wanted).ok_or_else(|| {
                    let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                    mf.err(format!(
                        "unknown material {wanted:?}; defined materials: {}",
                        names.join(", ")
                    ))
                })?
            }
        };
        objects.push(Object {
            name: format!("{obj_name}.{suffix}"),
            mesh: MeshSource::World {
                level: level.clone(),
                class,
            },
            material,
            transform: Mat4::from_translation(translate),
            animation: None,
            wind: None,
        });
    }
    Ok(())
}

/// Index of material `name`, appending the built-in of that name on first use.
fn material_index(materials: &mut Vec<Material>, name: &str) -> Option<usize> {
    if let Some(i) = materials.iter().position(|m| m.name == name) {
        return Some(i);
    }
    materials.push(cornell::builtin_material(name)?);
    Some(materials.len() - 1)
}

fn check_quad_edges(v_field: &Field, u: Vec3, v: Vec3) -> Result<(), SceneError> {
    let scale = u.length() * v.length();
    if scale.is_nan() || scale <= 0.0 || u.cross(v).length() <= 1e-6 * scale {
        return Err(v_field.err("edge_u and edge_v must be non-zero and not parallel (the quad has no area)"));
    }
    Ok(())
}

/// Each light type and its keys besides `type` and `name`.
const LIGHT_KEYS: [(&str, &[&str]); 5] = [
    ("point", &["position", "intensity", "radius"]),
    (
        "spot",
        &[
            "position",
            "direction",
            "target",
            "intensity",
            "inner_deg",
            "outer_deg",
            "radius",
        ],
    ),
    ("directional", &["direction", "irradiance"]),
    ("sphere", &["center", "radius", "radiance"]),
    ("quad", &["corner", "edge_u", "edge_v", "radiance"]),
];

/// Each mesh type and its keys besides the placement ones and `material`.
const MESH_KEYS: [(&str, &[&str]); 11] = [
    ("asset", &["path", "camera"]),
    ("plane", &["size", "subdivisions"]),
    ("quad", &["corner", "edge_u", "edge_v", "subdivisions"]),
    ("box", &["size", "subdivisions"]),
    ("sphere", &["radius", "segments", "rings"]),
    ("bush", &["leaves", "seed", "radius", "height", "leaf_size"]),
    ("obj", &["path"]),
    ("cornell_box", &["subdivisions", "light"]),
    ("heightfield", super::heightfield::HEIGHTFIELD_KEYS),
    ("bsp_rooms", &ROOMS_KEYS),
    ("bsp_fig8c", &FIG8C_KEYS),
];

/// `common` followed by the keys of every type, without repeats (for tables missing their type).
fn all_keys(common: &[&'static str], by_type: &[(&str, &[&'static str])]) -> Vec<&'static str> {
    let mut keys = common.to_vec();
    for k in by_type.iter().flat_map(|(_, ks)| ks.iter()) {
        if !keys.contains(k) {
            keys.push(k);
        }
    }
    keys
}

fn type_names(by_type: &[(&str, &[&str])]) -> String {
    by_type.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
}

fn read_light(f: &Field) -> Result<Light, SceneError> {
    let t = f.table()?;
    let Some(kind_f) = t.get("type") else {
        // Report a misspelt key before the missing `type`.
        t.allow(&all_keys(&["type", "name"], &LIGHT_KEYS))?;
        return Err(t.missing("type", &format!("one of: {}", type_names(&LIGHT_KEYS))));
    };
    let kind = kind_f.string()?;
    let Some((_, keys)) = LIGHT_KEYS.iter().find(|(n, _)| *n == kind) else {
        let msg = format!(
            "unknown light type {kind:?}; expected one of: {}",
            type_names(&LIGHT_KEYS)
        );
        return Err(kind_f.err(msg));
    };
    t.allow(&[&["type", "name"][..], keys].concat())?;
    let name = opt(t.get("name"), name)?.unwrap_or_else(|| f.path.clone());
    let point = |k: &str| t.require(k, "3 numbers, metres").and_then(|f| f.vec3());
    let colour = |k: &str, what: &str| t.require(k, what).and_then(|f| f.colour());
    Ok(match kind {
        "point" => Light::Point {
            name,
            position: point("position")?,
            intensity: colour("intensity", "W/sr, a number or 3")?,
            radius: opt(t.get("radius"), non_negative)?.unwrap_or(0.0),
        },
        "spot" => {
            let position = point("position")?;
            let direction = match (t.get("direction"), t.get("target")) {
                (Some(d), None) => direction(&d)?,
                (None, Some(tg)) => (tg.vec3()? - position)
                    .try_normalize()
                    .ok_or_else(|| tg.err("must differ from position"))?,
                (Some(_), Some(tg)) => return Err(tg.err("give either direction or target, not both")),
                (None, None) => return Err(t.missing("direction", "3 numbers, or give target instead")),
            };
            let outer_f = t.get("outer_deg");
            let outer_deg = opt(outer_f.clone(), |f| {
                f.number_where("a half-angle in degrees in (0, 90]", |x| x > 0.0 && x <= 90.0)
            })?
            .unwrap_or(30.0);
            let inner_f = t.get("inner_deg");
            let inner_deg = opt(inner_f.clone(), |f| {
                f.number_where("a half-angle in degrees in [0, 90]", |x| (0.0..=90.0).contains(&x))
            })?
            .unwrap_or(0.8 * outer_deg);
            if inner_deg > outer_deg {
                let msg = format!("inner_deg ({inner_deg}) must not exceed outer_deg ({outer_deg})");
                let at = inner_f.or(outer_f);
                return Err(match at {
                    Some(f) => f.err(msg),
                    None => t.ctx.err(t.line, &t.path, msg),
                });
            }
            let intensity = colour("intensity", "W/sr, a number or 3")?;
            let radius = opt(t.get("radius"), non_negative)?.unwrap_or(0.0);
            Light::Spot {
                name,
                position,
                direction,
                intensity,
                inner_deg,
                outer_deg,
                radius,
            }
        }
        "directional" => Light::Directional {
            name,
            direction: direction(&t.require("direction", "the direction the light travels")?)?,
            irradiance: colour("irradiance", "W/m², a number or 3")?,
        },
        "sphere" => Light::Sphere {
            name,
            center: point("center")?,
            radius: positive(&t.require("radius", "metres, > 0")?)?,
            radiance: colour("radiance", "W/(m²·sr), a number or 3")?,
        },
        _ => {
            let corner = point("corner")?;
            let edge_u = point("edge_u")?;
            let v_f = t.require("edge_v", "3 numbers, metres")?;
            let edge_v = v_f.vec3()?;
            check_quad_edges(&v_f, edge_u, edge_v)?;
            Light::Quad {
                name,
                corner,
                edge_u,
                edge_v,
                radiance: colour("radiance", "W/(m²·sr), a number or 3")?,
            }
        }
    })
}

/// Keys of a `[[light_arrays]]` entry.
const LIGHT_ARRAY_KEYS: [&str; 17] = [
    "name",
    "type",
    "count",
    "grid",
    "min",
    "max",
    "center",
    "size",
    "direction",
    "target",
    "jitter_deg",
    "seed",
    "intensity",
    "colours",
    "inner_deg",
    "outer_deg",
    "radius",
];

/// One `[[light_arrays]]` entry expanded into its lights; `earlier` lights were generated by the
/// arrays before it (the limit is on the scene's total).
// long: one key of a light array after another, each read and checked.
fn read_light_array(f: &Field, earlier: u64) -> Result<Vec<Light>, SceneError> {
    use generators::{ArrayAim, ArrayKind, ArrayLayout, LightArray, MAX_ARRAY_LIGHTS};
    let t = f.table()?;
    t.allow(&LIGHT_ARRAY_KEYS)?;
    let kind_f = t.require("type", "\"spot\" or \"point\"")?;
    let kind = match kind_f.string()? {
        "spot" => ArrayKind::Spot,
        "point" => ArrayKind::Point,
        other => return Err(kind_f.err(format!("unknown light array type {other:?}; expected spot or point"))),
    };
    if kind == ArrayKind::Point {
        const AIM_KEYS: [&str; 5] = ["direction", "target", "jitter_deg", "inner_deg", "outer_deg"];
        if let Some(k) = t
            .keys()
            .into_iter()
            .find(|(k, _)| AIM_KEYS.contains(k))
            .and_then(|(k, _)| t.get(k))
        {
            return Err(k.err(format!(
                "only spot arrays aim; a point array takes none of {}",
                AIM_KEYS.join(", ")
            )));
        }
    }
    let name = opt(t.get("name"), name)?.unwrap_or_else(|| f.path.clone());

    let (layout, size_f) = match (t.get("count"), t.get("grid")) {
        (Some(c), None) => (ArrayLayout::Scatter(c.int_in(1, MAX_ARRAY_LIGHTS)?), c),
        (None, Some(g)) => {
            let items = g.array()?;
            if items.len() != 3 {
                return Err(g.err(format!(
                    "expected 3 integers [nx, ny, nz], got {}",
                    super::doc::describe(g.node)
                )));
            }
            let mut n = [0u32; 3];
            for (k, item) in n.iter_mut().zip(&items) {
                *k = item.int_in(1, MAX_ARRAY_LIGHTS).map_err(|_| {
                    g.err(format!(
                        "expected 3 integers from 1 to {MAX_ARRAY_LIGHTS}, got {}",
                        super::doc::describe(g.node)
                    ))
                })?;
            }
            (ArrayLayout::Grid(n), g)
        }
        (Some(_), Some(g)) => return Err(g.err("give either count or grid, not both")),
        (None, None) => return Err(t.missing("grid", "[nx, ny, nz], or give count instead")),
    };
    let count = layout.count();
    if earlier + count > u64::from(MAX_ARRAY_LIGHTS) {
        let before = if earlier > 0 {
            format!(" (after {earlier} from the arrays before it)")
        } else {
            String::new()
        };
        return Err(size_f.err(format!(
            "{count} lights{before}: the light arrays of a scene may make at most {MAX_ARRAY_LIGHTS}"
        )));
    }

    let (min, max) = match (t.get("min"), t.get("max"), t.get("center"), t.get("size")) {
        (Some(lo), Some(hi), None, None) => {
            let (a, b) = (lo.vec3()?, hi.vec3()?);
            if a.cmpgt(b).any() {
                return Err(hi.err(format!(
                    "every coordinate must be at least min's, got min {} and max {}",
                    fmt3(a),
                    fmt3(b)
                )));
            }
            (a, b)
        }
        (None, None, Some(c), Some(s)) => {
            let (c, s) = (c.vec3()?, s.non_negative3()?);
            (c - 0.5 * s, c + 0.5 * s)
        }
        (Some(_), None, None, None) => return Err(t.missing("max", "3 numbers, metres")),
        (None, Some(_), None, None) => return Err(t.missing("min", "3 numbers, metres")),
        (None, None, Some(_), None) => return Err(t.missing("size", "3 non-negative numbers, metres")),
        (None, None, None, Some(_)) => return Err(t.missing("center", "3 numbers, metres")),
        (None, None, None, None) => {
            return Err(t.missing("min", "3 numbers, metres (with max), or give center and size"))
        }
        _ => {
            let at = t.get("center").or(t.get("size")).unwrap_or_else(|| size_f.clone());
            return Err(at.err("give either min and max, or center and size"));
        }
    };
    for (v, key) in [(min, "min"), (max, "max")] {
        if v.abs().max_element() > MAX_CAMERA_COORDINATE {
            let at = t.get(key).or(t.get("center")).unwrap_or_else(|| size_f.clone());
            return Err(at.err(format!(
                "the box reaches {}: coordinates are limited to ±{MAX_CAMERA_COORDINATE:e} m",
                fmt3(v)
            )));
        }
    }

    let aim = match (t.get("direction"), t.get("target")) {
        (Some(d), None) => ArrayAim::Direction(direction(&d)?),
        (None, Some(tg)) => ArrayAim::Target(tg.vec3()?),
        (Some(_), Some(tg)) => return Err(tg.err("give either direction or target, not both")),
        // Arrays are rigs: straight down unless told otherwise.
        (None, None) => ArrayAim::Direction(Vec3::NEG_Y),
    };
    let jitter_deg = opt(t.get("jitter_deg"), |f| {
        f.number_where("a tilt in degrees in [0, 90]", |x| (0.0..=90.0).contains(&x))
    })?
    .unwrap_or(0.0);
    let seed = opt(t.get("seed"), |f| f.int_in(0, u32::MAX))?.unwrap_or(1);
    let intensity = t.require("intensity", "W/sr, a number or 3")?.colour()?;
    let colours = match t.get("colours") {
        None => Vec::new(),
        Some(cf) => {
            let items = cf.array()?;
            if items.is_empty() {
                return Err(cf.err("expected at least one colour"));
            }
            items.iter().map(|c| c.colour()).collect::<Result<Vec<_>, _>>()?
        }
    };
    let outer_f = t.get("outer_deg");
    let outer_deg = opt(outer_f.clone(), |f| {
        f.number_where("a half-angle in degrees in (0, 90]", |x| x > 0.0 && x <= 90.0)
    })?
    .unwrap_or(30.0);
    let inner_f = t.get("inner_deg");
    let inner_deg = opt(inner_f.clone(), |f| {
        f.number_where("a half-angle in degrees in [0, 90]", |x| (0.0..=90.0).contains(&x))
    })?
    .unwrap_or(0.8 * outer_deg);
    if inner_deg > outer_deg {
        let msg = format!("inner_deg ({inner_deg}) must not exceed outer_deg ({outer_deg})");
        return Err(inner_f
            .or(outer_f)
            .map_or_else(|| t.ctx.err(t.line, &t.path, msg.clone()), |f| f.err(msg.clone())));
    }
    let radius = opt(t.get("radius"), non_negative)?.unwrap_or(0.0);
    let array = LightArray {
        name,
        kind,
        layout,
        min,
        max,
        aim,
        jitter_deg,
        seed,
        intensity,
        colours,
        inner_deg,
        outer_deg,
        radius,
    };
    array
        .expand()
        .map_err(|m| t.get("target").map_or_else(|| f.err(m.clone()), |tg| tg.err(m.clone())))
}

fn read_light_board(f: &Field) -> Result<super::types::LightBoard, SceneError> {
    let t = f.table()?;
    t.allow(&["depth", "rate_hz", "seed"])?;
    Ok(super::types::LightBoard {
        depth: opt(t.get("depth"), |f| {
            f.number_where("a dimming depth in [0, 1]", |x| (0.0..=1.0).contains(&x))
        })?
        .unwrap_or(0.5),
        rate_hz: opt(t.get("rate_hz"), |f| {
            f.number_where("a rate in Hz in (0, 1000]", |x| x > 0.0 && x <= 1000.0)
        })?
        .unwrap_or(0.5),
        seed: opt(t.get("seed"), |f| f.int_in(0, u32::MAX))?.unwrap_or(1),
    })
}

/// `[objects.wind]`: Dickson et al. 2011's vertex wind (src/scene/motion.rs), the document's constants by
/// default.
fn read_wind(f: &Field) -> Result<Wind, SceneError> {
    let t = f.table()?;
    t.allow(&["amplitude", "rate", "unit"])?;
    let d = Wind::default();
    Ok(Wind {
        amplitude: opt(t.get("amplitude"), |f| {
            f.number_where("a peak displacement in the document's units, from 0 to 100", |x| {
                (0.0..=100.0).contains(&x)
            })
        })?
        .unwrap_or(d.amplitude),
        rate: opt(t.get("rate"), |f| {
            f.number_where("a phase rate in rad/s, from -1000 to 1000", |x| x.abs() <= 1000.0)
        })?
        .unwrap_or(d.rate),
        unit: opt(t.get("unit"), |f| {
            f.number_where("metres per the document's unit, from 1e-4 to 1e4", |x| {
                (1e-4..=1e4).contains(&x)
            })
        })?
        .unwrap_or(d.unit),
    })
}

/// `[light_motion]`: a directional light (`light`, its name; default the first directional
/// light) turning about `axis` at `deg_per_s`.
fn read_light_motion(f: &Field, lights: &[Light]) -> Result<LightMotion, SceneError> {
    let t = f.table()?;
    t.allow(&["light", "axis", "deg_per_s"])?;
    let light = match t.get("light") {
        Some(lf) => {
            let wanted = lf.string()?;
            let i = lights
                .iter()
                .position(|l| l.name() == wanted)
                .ok_or_else(|| lf.err(format!("no light is named {wanted:?}")))?;
            if !matches!(lights[i], Light::Directional { .. }) {
                return Err(lf.err(format!(
                    "light {wanted:?} is not directional: only a directional light turns"
                )));
            }
            i
        }
        None => lights
            .iter()
            .position(|l| matches!(l, Light::Directional { .. }))
            .ok_or_else(|| f.err("the scene has no directional light to turn"))?,
    };
    let axis = match t.get("axis") {
        Some(af) => {
            let a = af.vec3()?;
            a.try_normalize()
                .filter(|_| a.length() > 1e-6)
                .ok_or_else(|| af.err("expected a non-zero axis"))?
        }
        None => Vec3::Y,
    };
    let deg_per_s = t
        .require("deg_per_s", "degrees per second")?
        .number_where("degrees per second, at most 3600 either way", |x| x.abs() <= 3600.0)?;
    Ok(LightMotion { light, axis, deg_per_s })
}

fn read_environment(f: &Field) -> Result<Environment, SceneError> {
    let t = f.table()?;
    let Some(kind_f) = t.get("type") else {
        t.allow(&["type", "radiance", "path", "scale", "px", "nx", "py", "ny", "pz", "nz"])?;
        return Err(t.missing("type", "constant, image or cube"));
    };
    match kind_f.string()? {
        "constant" => {
            t.allow(&["type", "radiance"])?;
            Ok(Environment::Constant {
                radiance: t.require("radiance", "W/(m²·sr), a number or 3")?.colour()?,
            })
        }
        "image" => {
            t.allow(&["type", "path", "scale"])?;
            Ok(Environment::Image {
                path: t
                    .require("path", "an equirectangular .hdr or .exr file")?
                    .existing_image()?,
                scale: opt(t.get("scale"), non_negative)?.unwrap_or(1.0),
            })
        }
        "cube" => {
            let mut keys = vec!["type", "scale"];
            keys.extend(CUBE_FACE_KEYS);
            t.allow(&keys)?;
            let mut fields = Vec::with_capacity(6);
            for key in CUBE_FACE_KEYS {
                let f = t.require(key, "a square .hdr or .exr cube face")?;
                fields.push((f.existing_image()?, f));
            }
            let faces: [PathBuf; 6] = std::array::from_fn(|k| fields[k].0.clone());
            // Load the faces now, so that a bad one is an error here, with its line, and not a
            // surprise for whichever method reads it first.
            CubeFaces::load(&faces, 1.0).map_err(|(k, msg)| fields[k].1.err(msg))?;
            Ok(Environment::Cube {
                faces,
                scale: opt(t.get("scale"), non_negative)?.unwrap_or(1.0),
            })
        }
        other => Err(kind_f.err(format!(
            "unknown environment type {other:?}; expected constant, image or cube"
        ))),
    }
}
