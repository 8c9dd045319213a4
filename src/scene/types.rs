//! The checked, in-memory scene description: camera, materials, objects, lights, environment.
//!
//! Conventions (see `scenes/README.md`): right-handed world, y up, lengths in metres, colours in
//! linear RGB, radiometric quantities in watts (per steradian, per square metre).

use std::path::PathBuf;

use glam::{Mat4, Vec2, Vec3, Vec4};

/// A pinhole camera. Right-handed, y up, looking from `position` toward `target`.
///
/// Image conventions: row 0 is the top of the image and column 0 its left; pixel `(i, j)` covers
/// `[i, i+1) × [j, j+1)` in continuous pixel coordinates, so its centre `(i + 0.5, j + 0.5)`
/// samples NDC `((i + 0.5) / W * 2 - 1, (j + 0.5) / H * 2 - 1)` with NDC y pointing **down**
/// (Vulkan). [`Camera::projection`] and [`Camera::ray`] agree on this.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    /// Approximate up direction; only its component orthogonal to the view direction matters.
    pub up: Vec3,
    /// Full vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f32,
    /// Distance of the near plane in metres (> 0). The far plane is at infinity.
    pub near: f32,
}

impl Camera {
    /// World → view transform (glam `look_at_rh`): the camera looks down −z, y up, x right.
    pub fn view_matrix(&self) -> Mat4 {
        Mat4::look_at_rh(self.position, self.target, self.up)
    }

    /// View → Vulkan clip space for `aspect` = width / height: NDC y points down, depth in [0, 1]
    /// with the standard (not reversed) orientation and an infinite far plane, i.e. depth
    /// `= 1 - near / distance` for a point at `distance` in front of the camera (0 on the near
    /// plane, → 1 at infinity). Use a `LESS` depth test cleared to 1.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let f = 1.0 / (0.5 * self.fov_y_deg.to_radians()).tan();
        Mat4::from_cols(
            Vec4::new(f / aspect, 0.0, 0.0, 0.0),
            Vec4::new(0.0, -f, 0.0, 0.0),
            Vec4::new(0.0, 0.0, -1.0, -1.0),
            Vec4::new(0.0, 0.0, -self.near, 0.0),
        )
    }

    /// `projection(aspect) * view_matrix()`.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view_matrix()
    }

    /// Primary ray through continuous pixel coordinates `(px, py)` of a `width × height` image
    /// (pass `i as f32 + 0.5` for the centre of column `i`; row 0 is the top). Returns the camera
    /// position and a unit direction; consistent with [`Camera::view_projection`].
    pub fn ray(&self, px: f32, py: f32, width: u32, height: u32) -> (Vec3, Vec3) {
        let (w, h) = (width.max(1) as f32, height.max(1) as f32);
        let ndc_x = px / w * 2.0 - 1.0;
        let ndc_y = py / h * 2.0 - 1.0;
        let tan_half = (0.5 * self.fov_y_deg.to_radians()).tan();
        let (right, up, forward) = self.basis();
        let dir = forward + right * (ndc_x * tan_half * (w / h)) - up * (ndc_y * tan_half);
        (self.position, dir.normalize())
    }

    /// Ray through the centre of pixel `(i, j)`.
    pub fn pixel_center_ray(&self, i: u32, j: u32, width: u32, height: u32) -> (Vec3, Vec3) {
        self.ray(i as f32 + 0.5, j as f32 + 0.5, width, height)
    }

    /// Orthonormal (right, up, forward) in world space, as `look_at_rh` builds them.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        (right, up, forward)
    }
}

/// Surface material: Lambertian diffuse plus a Blinn-Phong specular lobe, optional textures,
/// thin-surface diffuse transmittance and emission. Colours are linear RGB.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse albedo ρ, each channel in [0, 1].
    pub albedo: Vec3,
    /// Blinn-Phong specular colour, each channel in [0, 1].
    pub specular: Vec3,
    /// Blinn-Phong exponent (≥ 0).
    pub exponent: f32,
    /// Absolute path of an albedo texture (sRGB-encoded colour; multiplies `albedo`).
    pub albedo_map: Option<PathBuf>,
    /// Absolute path of a tangent-space normal map (OpenGL convention, green = +bitangent).
    pub normal_map: Option<PathBuf>,
    /// Absolute path of a specular texture (multiplies `specular`).
    pub specular_map: Option<PathBuf>,
    /// Diffuse transmittance of a thin surface, each channel in [0, 1], `albedo + transmittance ≤ 1`.
    pub transmittance: Vec3,
    /// Emitted radiance in W/(m²·sr), seen directly only (it lights nothing; use lights for that).
    pub emission: Vec3,
    /// Coverage α in (0, 1]: 1 is opaque; below 1 the surface is translucent, seen as
    /// `α·surface + (1 − α)·behind` (a pane of glass without refraction).
    pub opacity: f32,
    /// A sky surface: `radiosity` neither lights nor patches it, and its sun counts only
    /// where a ray toward the sun reaches one (the Ca3D-Engine thesis §3). Other methods draw it as usual.
    pub sky: bool,
}

impl Material {
    pub fn is_translucent(&self) -> bool {
        self.opacity < 1.0
    }

    /// The material used by objects that name none: grey, matte.
    pub fn default_grey(name: &str) -> Material {
        Material {
            name: name.to_owned(),
            albedo: Vec3::splat(0.8),
            specular: Vec3::ZERO,
            exponent: 32.0,
            albedo_map: None,
            normal_map: None,
            specular_map: None,
            transmittance: Vec3::ZERO,
            emission: Vec3::ZERO,
            opacity: 1.0,
            sky: false,
        }
    }
}

/// Where an object's geometry comes from. Generated meshes are in object space, centred on the
/// origin unless stated otherwise; see `generators.rs` for their exact layout.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshSource {
    /// A Wavefront OBJ file (absolute path once parsed).
    Obj(PathBuf),
    /// Part `part` (the triangles of one material) of an asset file (OBJ + MTL or glTF, see
    /// `crate::scene::asset`), as read when the scene was parsed, in the asset's space.
    Asset {
        path: PathBuf,
        part: usize,
        mesh: std::sync::Arc<super::mesh::Mesh>,
    },
    /// A square grid in the xz-plane at y = 0, facing +y; `size.x` along x, `size.y` along z;
    /// `subdivisions` cells per side.
    Plane { size: Vec2, subdivisions: u32 },
    /// A parallelogram `corner + s·edge_u + t·edge_v`, s, t ∈ [0, 1], facing
    /// `normalize(edge_u × edge_v)` (one-sided, like the quad light); `subdivisions` per side.
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        subdivisions: u32,
    },
    /// An axis-aligned box centred on the origin, each face split into `subdivisions²` cells.
    /// Closed 2-manifold.
    Box { size: Vec3, subdivisions: u32 },
    /// A UV sphere centred on the origin: `segments` around y, `rings` from pole to pole.
    /// Closed 2-manifold.
    Sphere { radius: f32, segments: u32, rings: u32 },
    /// A generated leafy bush standing on the origin (y up): `leaves` bent four-triangle leaves
    /// of length about `leaf_size` scattered over an ellipsoidal crown of horizontal radius
    /// `radius` centred at height `height`, on a trunk and a few branches; deterministic in
    /// `seed`. See [`crate::scene::generators::bush`].
    Bush {
        leaves: u32,
        seed: u32,
        radius: f32,
        height: f32,
        leaf_size: f32,
    },
    /// A height field over a square in the xz-plane (see `crate::scene::heightfield`):
    /// generated or loaded from an image, traced and drawn at its time-0 shape.
    Heightfield(super::heightfield::HeightfieldSource),
    /// The faces of one material class (`class`, a [`crate::world::MaterialId`]) of a compiled
    /// BSP world, in scene axes: see [`crate::scene::world_mesh`].
    World {
        level: super::world_mesh::WorldLevel,
        class: u32,
    },
}

/// Simple rigid motion of an entity over time `t` (seconds): a spin about its own origin (in
/// object space, before the placement) and a sinusoidal bob of its position. At `t = 0` the
/// object is exactly at its placement, which is what methods without animation and the
/// reference render.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Animation {
    /// Angular velocity about the object's x, y, z axes (applied x first), degrees per second.
    pub spin_deg_per_s: Vec3,
    /// Peak offset of the bob, metres: `bob_amplitude · sin(2π t / bob_period_s)`.
    pub bob_amplitude: Vec3,
    pub bob_period_s: f32,
}

impl Animation {
    /// The object → world transform at time `t` for placement `base`.
    pub fn transform_at(&self, base: Mat4, t: f32) -> Mat4 {
        let a = self.spin_deg_per_s * t;
        let spin = Mat4::from_rotation_z(a.z.to_radians())
            * Mat4::from_rotation_y(a.y.to_radians())
            * Mat4::from_rotation_x(a.x.to_radians());
        let phase = std::f32::consts::TAU * t / self.bob_period_s.max(1e-6);
        Mat4::from_translation(self.bob_amplitude * phase.sin()) * base * spin
    }
}

/// One drawable object: a mesh, a material and a placement.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    pub name: String,
    pub mesh: MeshSource,
    /// Index into [`crate::scene::Scene::materials`].
    pub material: usize,
    /// Object → world: `translate · Rz · Ry · Rx · scale` (x rotation applied first).
    pub transform: Mat4,
    /// Motion over time, for methods that animate entities (`transform` is the pose at t = 0).
    pub animation: Option<Animation>,
    /// Vertex wind (Dickson et al. 2011), applied by the renderer every frame for every method.
    pub wind: Option<super::motion::Wind>,
}

/// A light in radiometric units (watts; linear RGB per channel).
#[derive(Debug, Clone, PartialEq)]
pub enum Light {
    /// Isotropic point light. `intensity` in W/sr; `radius` is an influence/culling radius in
    /// metres beyond which the renderer may ignore it (0 = infinite). It does not change the
    /// inverse-square falloff.
    Point {
        name: String,
        position: Vec3,
        intensity: Vec3,
        radius: f32,
    },
    /// Spot light: `intensity` (W/sr) on the axis, full inside `inner_deg`, zero outside
    /// `outer_deg` (half-angles from `direction`, a unit vector). `radius` is an
    /// influence/culling radius as a point light's (0 = infinite).
    Spot {
        name: String,
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        inner_deg: f32,
        outer_deg: f32,
        radius: f32,
    },
    /// Distant light. `direction` is the unit direction the light travels (from the light toward
    /// the scene); `irradiance` in W/m² on a surface facing it.
    Directional {
        name: String,
        direction: Vec3,
        irradiance: Vec3,
    },
    /// Spherical area light emitting uniform `radiance` (W/(m²·sr)) from its surface.
    Sphere {
        name: String,
        center: Vec3,
        radius: f32,
        radiance: Vec3,
    },
    /// One-sided parallelogram area light `corner + s·edge_u + t·edge_v` emitting uniform
    /// `radiance` toward `normalize(edge_u × edge_v)`.
    Quad {
        name: String,
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        radiance: Vec3,
    },
}

impl Light {
    pub fn name(&self) -> &str {
        match self {
            Light::Point { name, .. }
            | Light::Spot { name, .. }
            | Light::Directional { name, .. }
            | Light::Sphere { name, .. }
            | Light::Quad { name, .. } => name,
        }
    }
}

/// The light board (`[light_board]`): every point and spot light's intensity is multiplied by
///
/// ```text
/// f_l(t) = 1 − depth · sin²(π · r_l · t),   r_l = rate_hz · (0.5 + u_l)
/// ```
///
/// where `u_l` ∈ [0, 1) hashes (`seed`, l) for scene light l. So f_l(0) = 1 for every light (frame
/// 0 is the scene's static lights, what the path-traced reference renders), each factor stays in
/// [1 − depth, 1] and returns to 1 every 1/r_l seconds, and the lights drift out of step because
/// their rates differ. Directional and area lights keep factor 1: area lights are also emitting
/// geometry, which no method rescales per frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightBoard {
    /// Deepest dimming, in [0, 1].
    pub depth: f32,
    /// Mean dimming rate; each light's is 0.5–1.5 times it, Hz.
    pub rate_hz: f32,
    pub seed: u32,
}

impl LightBoard {
    /// Light `l`'s rate r_l in Hz.
    pub fn rate_of(&self, l: usize) -> f64 {
        // SplitMix64's finaliser: consecutive indices get unrelated rates.
        let mut z = ((u64::from(self.seed) << 32) ^ l as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        let u = (z >> 11) as f64 / (1u64 << 53) as f64;
        f64::from(self.rate_hz) * (0.5 + u)
    }

    /// f_l(t) for light `l` at `time_s` seconds.
    pub fn factor(&self, l: usize, time_s: f32) -> f32 {
        let s = (std::f64::consts::PI * self.rate_of(l) * f64::from(time_s)).sin();
        (1.0 - f64::from(self.depth) * s * s) as f32
    }
}

/// Radiance arriving from infinitely far away where no geometry is hit.
#[derive(Debug, Clone, PartialEq)]
pub enum Environment {
    /// The same radiance (W/(m²·sr)) from every direction.
    Constant { radiance: Vec3 },
    /// An equirectangular (latitude-longitude) `.hdr`/`.exr` image of radiance, multiplied by
    /// `scale`. See [`Environment::equirect_uv`] for the mapping.
    Image { path: PathBuf, scale: f32 },
    /// A cube map: six square radiance images of one size, in Vulkan's layer order
    /// (+X, −X, +Y, −Y, +Z, −Z; the scene keys [`CUBE_FACE_KEYS`]), multiplied by `scale`. See
    /// [`Environment::cube_dir`] for the orientation of each face.
    Cube { faces: [PathBuf; 6], scale: f32 },
}

/// The scene keys of a cube environment's faces, in Vulkan's layer order.
pub const CUBE_FACE_KEYS: [&str; 6] = ["px", "nx", "py", "ny", "pz", "nz"];

/// A cube environment's faces as loaded: `size`² texels per face, the six faces one after the
/// other in layer order, each row-major from its top row; RGB radiance times `scale`, alpha 0.
#[derive(Debug, Clone, PartialEq)]
pub struct CubeFaces {
    pub size: u32,
    pub texels: Vec<[f32; 4]>,
}

impl CubeFaces {
    /// Loads and checks the six faces: each must open, be square, have face 0's size and hold
    /// finite texels. An error names the face (its index in layer order) and says why in one line.
    pub fn load(faces: &[PathBuf; 6], scale: f32) -> Result<CubeFaces, (usize, String)> {
        let mut size = 0;
        let mut texels = Vec::new();
        for (k, path) in faces.iter().enumerate() {
            let img = image::open(path)
                .map_err(|e| (k, format!("{}: cannot load: {e}", path.display())))?
                .to_rgba32f();
            let (w, h) = img.dimensions();
            if w != h || w == 0 {
                return Err((
                    k,
                    format!(
                        "{}: a cube face must be square and non-empty, this one is {w}x{h}",
                        path.display()
                    ),
                ));
            }
            if k == 0 {
                size = w;
            } else if w != size {
                return Err((
                    k,
                    format!(
                        "{}: is {w}x{w} but {} is {size}x{size}; all six faces must have one size",
                        path.display(),
                        CUBE_FACE_KEYS[0]
                    ),
                ));
            }
            for (i, p) in img.pixels().enumerate() {
                if !p.0[..3].iter().all(|c| c.is_finite()) {
                    let (x, y) = (i as u32 % w, i as u32 / w);
                    return Err((
                        k,
                        format!("{}: texel ({x}, {y}) is not finite: {:?}", path.display(), &p.0[..3]),
                    ));
                }
                texels.push([p.0[0] * scale, p.0[1] * scale, p.0[2] * scale, 0.0]);
            }
        }
        Ok(CubeFaces { size, texels })
    }
}

impl Environment {
    /// Texture coordinates (u right, v down, both in [0, 1]) of world direction `dir` in an
    /// equirectangular map: v = 0 is straight up (+y), v = 1 straight down; u = 0.5 is −z (the
    /// direction a default camera looks), u increases toward +x (u = 0.75 is +x).
    pub fn equirect_uv(dir: Vec3) -> Vec2 {
        let d = dir.normalize_or(Vec3::NEG_Z);
        let u = 0.5 + d.x.atan2(-d.z) / std::f32::consts::TAU;
        let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        Vec2::new(u, v)
    }

    /// Inverse of [`Environment::equirect_uv`]: the unit direction at texture coordinates `uv`.
    pub fn equirect_dir(uv: Vec2) -> Vec3 {
        let phi = (uv.x - 0.5) * std::f32::consts::TAU;
        let theta = uv.y * std::f32::consts::PI;
        Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
    }

    /// The (un-normalised) world direction through face coordinates (s, t) ∈ [−1, 1]² of cube
    /// face `face` (layer order +X, −X, +Y, −Y, +Z, −Z; clamped to 5). s runs with the face
    /// image's columns (u = (s + 1)/2, left to right), t with its rows (v = (t + 1)/2, top to
    /// bottom). This is the Vulkan spec's cube face selection table read backwards, so a
    /// `samplerCube` and [`crate::sh::cube_texel_dir_world`] agree with it.
    pub fn cube_dir(face: usize, s: f32, t: f32) -> Vec3 {
        match face.min(5) {
            0 => Vec3::new(1.0, -t, -s),
            1 => Vec3::new(-1.0, -t, s),
            2 => Vec3::new(s, 1.0, t),
            3 => Vec3::new(s, -1.0, -t),
            4 => Vec3::new(s, -t, 1.0),
            _ => Vec3::new(-s, -t, -1.0),
        }
    }

    /// Inverse of [`Environment::cube_dir`]: the face `dir` selects (the largest |component|;
    /// ties go to x, then y) and its face coordinates (s, t) ∈ [−1, 1]².
    pub fn cube_face(dir: Vec3) -> (usize, f32, f32) {
        let a = dir.abs();
        let (face, ma, sc, tc) = if a.x >= a.y && a.x >= a.z {
            if dir.x >= 0.0 {
                (0, a.x, -dir.z, -dir.y)
            } else {
                (1, a.x, dir.z, -dir.y)
            }
        } else if a.y >= a.z {
            if dir.y >= 0.0 {
                (2, a.y, dir.x, dir.z)
            } else {
                (3, a.y, dir.x, -dir.z)
            }
        } else if dir.z >= 0.0 {
            (4, a.z, dir.x, -dir.y)
        } else {
            (5, a.z, -dir.x, -dir.y)
        };
        if ma <= 0.0 {
            return (5, 0.0, 0.0);
        }
        (face, sc / ma, tc / ma)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            position: Vec3::new(1.0, 2.0, 5.0),
            target: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y_deg: 50.0,
            near: 0.1,
        }
    }

    /// Projects a world point to continuous pixel coordinates and depth.
    fn to_pixel(c: &Camera, p: Vec3, w: u32, h: u32) -> (f32, f32, f32) {
        let clip = c.view_projection(w as f32 / h as f32) * p.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        ((ndc.x + 1.0) * 0.5 * w as f32, (ndc.y + 1.0) * 0.5 * h as f32, ndc.z)
    }

    #[test]
    fn points_on_pixel_rays_project_to_pixel_centres() {
        let c = cam();
        let (w, h) = (64u32, 48u32);
        for &(i, j) in &[(0u32, 0u32), (63, 0), (0, 47), (63, 47), (31, 23), (10, 40)] {
            let (o, d) = c.pixel_center_ray(i, j, w, h);
            assert!((d.length() - 1.0).abs() < 1e-5);
            for t in [0.5f32, 3.0, 40.0] {
                let (x, y, z) = to_pixel(&c, o + d * t, w, h);
                assert!((x - (i as f32 + 0.5)).abs() < 1e-3, "pixel {i},{j}: x {x}");
                assert!((y - (j as f32 + 0.5)).abs() < 1e-3, "pixel {i},{j}: y {y}");
                assert!((0.0..1.0).contains(&z));
            }
        }
    }

    #[test]
    fn row_zero_is_top_and_column_zero_is_left() {
        let c = cam();
        let (right, up, _) = c.basis();
        let (_, d) = c.pixel_center_ray(0, 0, 8, 8);
        assert!(d.dot(up) > 0.0 && d.dot(right) < 0.0);
        // The image centre (4, 4) lies on a pixel corner and looks straight at the target.
        let (_, d) = c.ray(4.0, 4.0, 8, 8);
        assert!((d - (c.target - c.position).normalize()).length() < 1e-5);
    }

    #[test]
    fn depth_is_zero_at_near_and_tends_to_one() {
        let c = cam();
        let (_, _, fwd) = c.basis();
        let near = to_pixel(&c, c.position + fwd * c.near, 4, 4).2;
        let mid = to_pixel(&c, c.position + fwd * (2.0 * c.near), 4, 4).2;
        let far = to_pixel(&c, c.position + fwd * 1e5, 4, 4).2;
        assert!(near.abs() < 1e-5, "{near}");
        assert!((mid - 0.5).abs() < 1e-5, "{mid}");
        assert!(far > 0.999 && far <= 1.0, "{far}");
    }

    #[test]
    fn equirect_round_trip() {
        assert!((Environment::equirect_uv(Vec3::NEG_Z) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        assert!((Environment::equirect_uv(Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
        assert!(Environment::equirect_uv(Vec3::Y).y.abs() < 1e-6);
        for d in [
            Vec3::new(0.3, 0.5, -0.8),
            Vec3::new(-0.9, -0.2, 0.1),
            Vec3::new(0.1, 0.9, 0.4),
        ] {
            let d = d.normalize();
            let back = Environment::equirect_dir(Environment::equirect_uv(d));
            assert!((back - d).length() < 1e-5, "{d} -> {back}");
        }
    }

    #[test]
    fn cube_faces_round_trip() {
        // Every face's centre is its axis, and (face, s, t) -> dir -> (face, s, t) is the identity.
        let axes = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        for (face, axis) in axes.into_iter().enumerate() {
            assert_eq!(Environment::cube_dir(face, 0.0, 0.0), axis);
            for (s, t) in [(-0.9, 0.3), (0.5, -0.7), (0.99, 0.99)] {
                let (f, s2, t2) = Environment::cube_face(Environment::cube_dir(face, s, t).normalize());
                assert_eq!(f, face);
                assert!(
                    (s2 - s).abs() < 1e-5 && (t2 - t).abs() < 1e-5,
                    "{face}: ({s}, {t}) -> ({s2}, {t2})"
                );
            }
        }
        // The +Y face's top row (t = -1) lies toward -z, its left column (s = -1) toward -x.
        assert!(Environment::cube_dir(2, 0.0, -1.0).z < 0.0 && Environment::cube_dir(2, -1.0, 0.0).x < 0.0);
    }
}
