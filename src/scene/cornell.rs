//! The Cornell box as a built-in: the classic geometry (Cornell University Program of Computer
//! Graphics measurements), made axis-aligned and scaled so the interior spans x, z ∈ [−1, 1],
//! y ∈ [0, 2] (1 unit = 277.5 mm), open toward +z. Seen from +z: red wall left (x = −1), green
//! wall right (x = +1), short block front right, tall block back left, square light on the ceiling.

use glam::{Mat4, Vec3};

use super::types::{Light, Material, MeshSource};

/// Materials the scene may use without defining them; a `[[materials]]` entry with the same
/// name overrides the built-in.
pub const BUILTIN_MATERIALS: [&str; 4] = ["default", "cornell_white", "cornell_red", "cornell_green"];

/// The built-in material called `name`, if any. Cornell reflectances are the usual RGB
/// approximations of the measured spectra.
pub fn builtin_material(name: &str) -> Option<Material> {
    let albedo = match name {
        "default" => return Some(Material::default_grey(name)),
        "cornell_white" => Vec3::new(0.73, 0.73, 0.73),
        "cornell_red" => Vec3::new(0.63, 0.065, 0.05),
        "cornell_green" => Vec3::new(0.14, 0.45, 0.091),
        _ => return None,
    };
    Some(Material {
        albedo,
        ..Material::default_grey(name)
    })
}

/// Radiance of the ceiling light in W/(m²·sr) (the value common renderers' Cornell scenes use).
pub const LIGHT_RADIANCE: Vec3 = Vec3::new(17.0, 12.0, 4.0);

/// One part of the box: name suffix, mesh, material name, placement within the box.
pub(crate) struct Part {
    pub suffix: &'static str,
    pub mesh: MeshSource,
    pub material: &'static str,
    pub local: Mat4,
}

/// Millimetres of the original data → box units.
const MM: f32 = 2.0 / 555.0;

/// Walls (inward-facing quads, `subdivisions` per side) and the two blocks.
pub(crate) fn parts(subdivisions: u32) -> Vec<Part> {
    let wall = |suffix, material, corner: [f32; 3], u: [f32; 3], v: [f32; 3]| Part {
        suffix,
        mesh: MeshSource::Quad {
            corner: Vec3::from(corner),
            edge_u: Vec3::from(u),
            edge_v: Vec3::from(v),
            subdivisions,
        },
        material,
        local: Mat4::IDENTITY,
    };
    // Blocks: size and centre (mm, original frame mapped to ours) and rotation about y.
    let block = |suffix, height_mm: f32, centre_xz_mm: [f32; 2], rot_deg: f32| {
        let size = Vec3::new(165.0, height_mm, 165.0) * MM;
        Part {
            suffix,
            mesh: MeshSource::Box { size, subdivisions },
            material: "cornell_white",
            local: Mat4::from_translation(Vec3::new(centre_xz_mm[0] * MM, 0.5 * size.y, centre_xz_mm[1] * MM))
                * Mat4::from_rotation_y(rot_deg.to_radians()),
        }
    };
    vec![
        wall(
            "floor",
            "cornell_white",
            [-1.0, 0.0, 1.0],
            [2.0, 0.0, 0.0],
            [0.0, 0.0, -2.0],
        ),
        wall(
            "ceiling",
            "cornell_white",
            [-1.0, 2.0, -1.0],
            [2.0, 0.0, 0.0],
            [0.0, 0.0, 2.0],
        ),
        wall(
            "back",
            "cornell_white",
            [-1.0, 0.0, -1.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
        ),
        wall(
            "left",
            "cornell_red",
            [-1.0, 0.0, 1.0],
            [0.0, 0.0, -2.0],
            [0.0, 2.0, 0.0],
        ),
        wall(
            "right",
            "cornell_green",
            [1.0, 0.0, -1.0],
            [0.0, 0.0, 2.0],
            [0.0, 2.0, 0.0],
        ),
        // Original centres (185.5, 169) and (368.5, 351.25) mm, mapped by x' = 278 − x,
        // z' = 279.5 − z (a 180° turn about y, so the rotation angles carry over).
        block("short_block", 165.0, [92.5, 110.5], -16.6),
        block("tall_block", 330.0, [-90.5, -71.75], 17.2),
    ]
}

/// The ceiling light (130 × 105 mm, 1/555 of the height below the ceiling), facing down, under
/// the box's transform `m`.
pub(crate) fn light(name: String, m: &Mat4) -> Light {
    let (w, d) = (130.0 * MM, 105.0 * MM);
    let corner = Vec3::new(-0.5 * w, 2.0 - MM, -0.5 * d);
    Light::Quad {
        name,
        corner: m.transform_point3(corner),
        edge_u: m.transform_vector3(Vec3::new(w, 0.0, 0.0)),
        edge_v: m.transform_vector3(Vec3::new(0.0, 0.0, d)), // x × z = −y: faces down
        radiance: LIGHT_RADIANCE,
    }
}
