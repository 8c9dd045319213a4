//! Scene-level motion that the renderer applies per frame for every method and the reference
//! path tracer at a frame's time, so a chart compares like with like: **wind** on an object's
//! vertices (Dickson et al. 2011's vertex animation, digest §6.1) and a **light motion** turning a
//! directional light about an axis.
//!
//! Wind, per vertex of object-space position p (in the document's length unit `unit` metres)
//! and weight w (the albedo map's alpha at the vertex's uv, nearest texel, clamped at the edges;
//! 1 without a map), at time t seconds:
//!
//! ```text
//! c  = cos(rate·t + (x + z)/20 − y²/70 + z²/300)            x, y, z = p / unit
//! p' = p + (0, amplitude·unit·w·c, 0)
//! T' = T + (0, 0.1·w·c, 0),  B' = B + (0, 0.1·w·c, 0),  N' = ±normalize(T' × B')
//! ```
//!
//! With `amplitude = 0.3`, `rate = 2` rad/s and `unit = 1` this is the document's
//! `movingPos = position + 0.3·deltaY`, `deltaY.y = cos(time/1000·2 + …)·albedo.a`, its time in
//! milliseconds. The displacement is not zero at t = 0: the reference deforms too.

use std::path::Path;

use glam::{Quat, Vec3, Vec4};

use super::Mesh;

/// The renderer's clock step (a 60 Hz display): frame N is at N × this many seconds, for
/// every method and for the reference's `--frame N` alike.
pub const FRAME_STEP_S: f32 = 1.0 / 60.0;

/// The time of the renderer's frame `frame`, seconds.
pub fn frame_time(frame: u64) -> f32 {
    frame as f32 * FRAME_STEP_S
}

/// An object's wind (`[objects.wind]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wind {
    /// Peak displacement in the document's units (0.3).
    pub amplitude: f32,
    /// Angular rate of the phase, rad/s (the document's 2/1000 per millisecond).
    pub rate: f32,
    /// Metres per the document's length unit: scales both the positions in the phase and the
    /// displacement.
    pub unit: f32,
}

impl Default for Wind {
    fn default() -> Wind {
        Wind {
            amplitude: 0.3,
            rate: 2.0,
            unit: 1.0,
        }
    }
}

impl Wind {
    /// The phase's cosine c at object-space point `p` and time `t`.
    pub fn cosine(&self, p: Vec3, t: f32) -> f32 {
        let q = p / self.unit;
        (self.rate * t + (q.x + q.z) / 20.0 - q.y * q.y / 70.0 + q.z * q.z / 300.0).cos()
    }

    /// The vertical displacement in metres of a vertex at `p` of weight `w`.
    pub fn lift(&self, p: Vec3, w: f32, t: f32) -> f32 {
        self.amplitude * self.unit * w * self.cosine(p, t)
    }

    /// One vertex moved: position, normal and tangent (w, the handedness, kept).
    pub fn vertex(&self, p: Vec3, n: Vec3, tangent: Vec4, w: f32, t: f32) -> (Vec3, Vec3, Vec4) {
        if w == 0.0 {
            return (p, n, tangent);
        }
        let c = self.cosine(p, t);
        let moved = p + Vec3::Y * (self.amplitude * self.unit * w * c);
        let dt = Vec3::Y * (0.1 * w * c);
        let t3 = tangent.truncate();
        let sign = if tangent.w < 0.0 { -1.0 } else { 1.0 };
        let b = n.cross(t3) * sign;
        let (t2, b2) = (t3 + dt, b + dt);
        // T × B = sign·N for an orthonormal frame: the same sign keeps N when c = 0.
        let n2 = (t2.cross(b2) * sign).try_normalize().unwrap_or(n);
        let t2 = t2.try_normalize().unwrap_or(t3);
        (moved, n2, t2.extend(tangent.w))
    }

    /// `mesh` (object space) at time `t`, weights per vertex.
    pub fn deform(&self, mesh: &mut Mesh, weights: &[f32], t: f32) {
        for i in 0..mesh.positions.len() {
            let w = weights.get(i).copied().unwrap_or(0.0);
            let n = mesh.normals.get(i).copied().unwrap_or(Vec3::Y);
            let tan = mesh.tangents.get(i).copied().unwrap_or(Vec4::new(1.0, 0.0, 0.0, 1.0));
            let (p, n, tan) = self.vertex(mesh.positions[i], n, tan, w, t);
            mesh.positions[i] = p;
            if let Some(slot) = mesh.normals.get_mut(i) {
                *slot = n;
            }
            if let Some(slot) = mesh.tangents.get_mut(i) {
                *slot = tan;
            }
        }
    }
}

/// Each vertex's wind weight: the alpha of `albedo_map` at its uv (nearest texel, clamped to the
/// map, so v = 1 is the last row and not the first), or 1 everywhere without a map.
pub fn wind_weights(mesh: &Mesh, albedo_map: Option<&Path>) -> Result<Vec<f32>, String> {
    let Some(path) = albedo_map else {
        return Ok(vec![1.0; mesh.positions.len()]);
    };
    let img = crate::util::image_io::open_image(path)
        .map_err(|e| format!("{}: {e}", path.display()))?
        .to_rgba8();
    let (w, h) = (img.width(), img.height());
    let texel = |x: f32, n: u32| ((x * n as f32).floor().max(0.0) as u32).min(n - 1);
    Ok((0..mesh.positions.len())
        .map(|i| {
            let uv = mesh.uvs.get(i).copied().unwrap_or_default();
            f32::from(img.get_pixel(texel(uv.x, w), texel(uv.y, h)).0[3]) / 255.0
        })
        .collect())
}

/// A directional light turning about an axis (`[light_motion]`): its direction at time t is the
/// scene's turned by `deg_per_s · t` degrees about `axis` (right-handed), exactly the scene's at
/// t = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightMotion {
    /// Index into [`crate::scene::Scene::lights`] (a directional light).
    pub light: usize,
    /// Unit axis.
    pub axis: Vec3,
    pub deg_per_s: f32,
}

impl LightMotion {
    pub fn rotation(&self, t: f32) -> Quat {
        Quat::from_axis_angle(self.axis, (self.deg_per_s * t).to_radians())
    }

    /// `direction` turned to time `t`.
    pub fn direction_at(&self, direction: Vec3, t: f32) -> Vec3 {
        self.rotation(t) * direction
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;

    /// The document's formula written out in f64, independently of [`Wind`].
    fn lift(p: [f64; 3], w: f64, t: f64, amplitude: f64, rate: f64, unit: f64) -> f64 {
        let [x, y, z] = p.map(|c| c / unit);
        amplitude * unit * w * (rate * t + (x + z) / 20.0 - y * y / 70.0 + z * z / 300.0).cos()
    }

    #[test]
    fn wind_lifts_by_the_documents_formula() {
        let d = Wind::default();
        assert_eq!(
            (d.amplitude, d.rate, d.unit),
            (0.3, 2.0, 1.0),
            "the document's constants"
        );
        // The origin at t = 0: cos 0 = 1; at t = π/2 (rate 2): cos π = −1.
        assert!((d.lift(Vec3::ZERO, 1.0, 0.0) - 0.3).abs() < 1e-7);
        assert!((d.lift(Vec3::ZERO, 1.0, std::f32::consts::FRAC_PI_2) + 0.3).abs() < 1e-6);
        // (x + z)/20 = 0.5 and z²/300 = 1/12 at (5, 0, 5); y²/70 = 1 at y = √70.
        for (p, w, t) in [
            ([5.0, 0.0, 5.0], 1.0, 0.0),
            ([0.0, 70f64.sqrt(), 0.0], 0.5, 0.25),
            ([3.0, 2.0, -7.0], 0.8, 1.3),
        ] {
            let got = d.lift(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32), w as f32, t as f32) as f64;
            let want = lift(p, w, t, 0.3, 2.0, 1.0);
            assert!((got - want).abs() < 1e-6, "{p:?}: {got} vs {want}");
        }
        assert!((lift([5.0, 0.0, 5.0], 1.0, 0.0, 0.3, 2.0, 1.0) - 0.3 * (0.5f64 + 1.0 / 12.0).cos()).abs() < 1e-12);
        // `unit` scales the lattice and the displacement: (0.5, 0, 0.5) m in 0.1 m units is the
        // document's (5, 0, 5), lifted a tenth as far.
        let metric = Wind { unit: 0.1, ..d };
        let got = metric.lift(Vec3::new(0.5, 0.0, 0.5), 1.0, 0.0) as f64;
        assert!((got - 0.03 * (0.5f64 + 1.0 / 12.0).cos()).abs() < 1e-7, "{got}");
    }

    #[test]
    fn zero_weight_and_zero_cosine_leave_the_vertex() {
        let d = Wind::default();
        let (p, n, tan) = (
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, 0.6, 0.8),
            Vec4::new(1.0, 0.0, 0.0, -1.0),
        );
        assert_eq!(d.vertex(p, n, tan, 0.0, 0.7), (p, n, tan), "weight 0");
        // Where the phase is π/2 the cosine is 0: nothing moves (to rounding).
        let t = (std::f32::consts::FRAC_PI_2 - d.cosine(Vec3::ZERO, 0.0).acos()) / d.rate;
        let (q, m, _) = d.vertex(Vec3::ZERO, n, tan, 1.0, t);
        assert!(q.distance(Vec3::ZERO) < 1e-6 && m.distance(n) < 1e-6, "{q} {m}");
        // Elsewhere the normal turns but stays unit, and the position moves along y only.
        let (q, m, t2) = d.vertex(p, n, tan, 1.0, 0.2);
        assert!((q - p).x == 0.0 && (q - p).z == 0.0 && (q - p).y != 0.0, "{q} {p}");
        assert!((m.length() - 1.0).abs() < 1e-6 && m.distance(n) > 1e-3 && t2.w == -1.0);
    }

    #[test]
    fn scenes_read_wind_and_light_motion_and_name_bad_fields() {
        let base = "[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[lights]]\ntype = \"directional\"\nname = \"sun\"\ndirection = [0, -1, 0]\nirradiance = 1\n\
                    [[lights]]\ntype = \"point\"\nname = \"bulb\"\nposition = [0, 2, 0]\nintensity = 1\n[[objects]]\nmesh = \"plane\"\n";
        let parse = |extra: &str| Scene::from_str(&format!("{base}{extra}"), "s.toml", std::path::Path::new("."));
        let s = parse("wind = { unit = 0.1 }\n").unwrap();
        assert_eq!(
            s.objects[0].wind,
            Some(Wind {
                unit: 0.1,
                ..Wind::default()
            })
        );
        assert!(s.has_motion());
        let s = parse("[light_motion]\ndeg_per_s = 6\naxis = [0, 2, 0]\n").unwrap();
        assert_eq!(
            s.light_motion,
            Some(LightMotion {
                light: 0,
                axis: Vec3::Y,
                deg_per_s: 6.0
            })
        );
        // 15 s at 6°/s: the sun turned 90° about y; the board-less point light untouched.
        let lights = s.lights_at(15.0);
        let crate::scene::Light::Directional { direction, .. } = lights[0] else {
            panic!()
        };
        assert!(direction.distance(Vec3::new(0.0, -1.0, 0.0)) < 1e-6);
        let s = parse("[light_motion]\ndeg_per_s = 6\naxis = [1, 0, 0]\n").unwrap();
        let crate::scene::Light::Directional { direction, .. } = s.lights_at(15.0)[0] else {
            panic!()
        };
        assert!(direction.distance(Vec3::new(0.0, 0.0, -1.0)) < 1e-6, "{direction}");
        for (extra, field) in [
            ("wind = { unit = 0 }\n", "objects[0].wind.unit"),
            ("wind = { gust = 1 }\n", "objects[0].wind.gust"),
            ("wind = 3\n", "objects[0].wind"),
            (
                "[light_motion]\ndeg_per_s = 6\nlight = \"bulb\"\n",
                "light_motion.light",
            ),
            (
                "[light_motion]\ndeg_per_s = 6\nlight = \"moon\"\n",
                "light_motion.light",
            ),
            ("[light_motion]\ndeg_per_s = 6\naxis = [0, 0, 0]\n", "light_motion.axis"),
            ("[light_motion]\naxis = [0, 1, 0]\n", "light_motion.deg_per_s"),
        ] {
            let e = parse(extra).unwrap_err();
            assert_eq!((e.file.as_str(), e.field.as_str()), ("s.toml", field), "{extra}: {e}");
            assert!(!e.to_string().contains('\n'));
        }
    }
}
