//! What tests/reference/reference.rs checks rendered images with: the statistical agreement test and
//! closed forms (box-filtered pixels, Lambert's polygon formula, hemispherical quadrature).
#![allow(dead_code)]

use glam::Vec3;
use penumbra::environment::EnvironmentMap;
use penumbra::lighting::brdf::Surface;
use penumbra::reference::ReferenceImage;
use penumbra::scene::Scene;
use penumbra::util::image_io::HdrImage;

/// Agreement of a rendered image with closed-form values, judged by the renderer's own
/// standard errors. Per pixel and channel z = (|got − want| − slack) / s.e.; an unbiased
/// estimator exceeds z = 3 in about 0.3% of checks, so over hundreds of pixels "every one within
/// 3 s.e." would fail by chance. Required instead: at most 2% of the pixels (or 3) beyond 3
/// s.e. in some channel, none beyond 6, and in each channel the mean difference over all pixels
/// within 4 of its own standard error, which catches a bias far smaller than one pixel's noise
/// (4, not 3: with dozens of such sums in tests/reference/reference.rs, 3 would fail by chance once every few
/// shader changes). Channels are judged apart: they share samples, so their errors correlate.
/// Noise-free estimates (s.e. 0) must match to rounding everywhere.
pub struct Agreement {
    pub what: &'static str,
    pub pixels: usize,
    pub beyond_3: usize,
    pub worst: (f32, String),
    pub sum_diff: [f64; 3],
    pub sum_var: [f64; 3],
    pub sum_slack: [f64; 3],
}

impl Agreement {
    pub fn new(what: &'static str) -> Self {
        Agreement {
            what,
            pixels: 0,
            beyond_3: 0,
            worst: (0.0, String::new()),
            sum_diff: [0.0; 3],
            sum_var: [0.0; 3],
            sum_slack: [0.0; 3],
        }
    }

    /// `slack`: known bias or closed-form inaccuracy allowed on top of the noise.
    pub fn check(&mut self, img: &ReferenceImage, i: u32, j: u32, want: Vec3, slack: Vec3) {
        let (got, se) = (img.mean.get(i, j), img.standard_error.get(i, j));
        let mut pixel_z = 0.0f32;
        for c in 0..3 {
            let slack = slack[c] + 1e-5 * want[c].abs() + 1e-6;
            let excess = (got[c] - want[c]).abs() - slack;
            let z = if excess <= 0.0 {
                0.0
            } else if se[c] > 0.0 {
                excess / se[c]
            } else {
                f32::INFINITY
            };
            pixel_z = pixel_z.max(z);
            if z > self.worst.0 {
                self.worst = (
                    z,
                    format!(
                        "pixel ({i},{j}) channel {c}: {} vs {} (s.e. {})",
                        got[c], want[c], se[c]
                    ),
                );
            }
            self.sum_diff[c] += (got[c] - want[c]) as f64;
            self.sum_var[c] += (se[c] as f64).powi(2);
            self.sum_slack[c] += slack as f64;
        }
        self.pixels += 1;
        self.beyond_3 += (pixel_z > 3.0) as usize;
    }

    pub fn assert(&self) {
        let Agreement {
            what, pixels, beyond_3, ..
        } = *self;
        assert!(pixels > 0, "{what}: nothing checked");
        let (z, worst) = &self.worst;
        assert!(
            beyond_3 as f64 <= (0.02 * pixels as f64).max(3.0),
            "{what}: {beyond_3} of {pixels} pixels beyond 3 s.e.; worst z = {z}: {worst}"
        );
        assert!(*z <= 6.0, "{what}: z = {z} at {worst}");
        let n = pixels as f64;
        for c in 0..3 {
            let (diff, tol) = (
                self.sum_diff[c] / n,
                4.0 * self.sum_var[c].sqrt() / n + self.sum_slack[c] / n,
            );
            assert!(
                diff.abs() <= tol,
                "{what}: channel {c}: mean difference {diff} over {pixels} pixels, allowed {tol}"
            );
        }
    }
}

/// The mean of `f` over an n × n grid of points in pixel (i, j): the box-filtered value the
/// jittered camera rays estimate, or None where `f` is undefined somewhere in the pixel.
pub fn pixel_average(i: u32, j: u32, n: u32, mut f: impl FnMut(f32, f32) -> Option<Vec3>) -> Option<Vec3> {
    let mut sum = Vec3::ZERO;
    for a in 0..n {
        for b in 0..n {
            sum += f(
                i as f32 + (a as f32 + 0.5) / n as f32,
                j as f32 + (b as f32 + 0.5) / n as f32,
            )?;
        }
    }
    Some(sum / (n * n) as f32)
}

/// Where the ray through film point (x, y) meets the plane y = 0 within `half` of the origin.
pub fn ground_point(scene: &Scene, x: f32, y: f32, size: (u32, u32), half: f32) -> Option<Vec3> {
    let (o, d) = scene.camera.ray(x, y, size.0, size.1);
    if d.y >= 0.0 {
        return None;
    }
    let p = o + d * (-o.y / d.y);
    (p.x.abs() < half && p.z.abs() < half).then_some(p)
}

/// ∫ f(v, l) cos θ dω over the hemisphere above a surface facing +y: the midpoint rule in
/// cos θ and φ, summed in f64.
pub fn hemispherical_reflectance(v: Vec3, s: &Surface) -> Vec3 {
    let (nc, np) = (96, 192);
    let mut sum = glam::DVec3::ZERO;
    for a in 0..nc {
        let cos_t = (a as f32 + 0.5) / nc as f32;
        let sin_t = (1.0 - cos_t * cos_t).sqrt();
        for b in 0..np {
            let phi = (b as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
            let l = Vec3::new(sin_t * phi.cos(), cos_t, sin_t * phi.sin());
            sum += penumbra::lighting::brdf::brdf_times_cos(Vec3::Y, v, l, s).as_dvec3();
        }
    }
    (sum * (std::f64::consts::TAU / (nc * np) as f64)).as_vec3()
}

/// Irradiance at p (normal n) from a uniform Lambertian polygon of radiance 1 wholly above p's
/// horizon: Lambert's contour formula E = ½ Σ γ_i n·(r_i × r_{i+1})/|r_i × r_{i+1}|.
pub fn polygon_irradiance(p: Vec3, n: Vec3, verts: &[Vec3]) -> f32 {
    let mut sum = 0.0;
    for k in 0..verts.len() {
        let (a, b) = (
            (verts[k] - p).normalize(),
            (verts[(k + 1) % verts.len()] - p).normalize(),
        );
        let c = a.cross(b);
        sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(c.normalize_or_zero());
    }
    0.5 * sum.abs()
}

pub fn rmse(a: &HdrImage, b: &HdrImage, keep: Option<&[bool]>) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for (k, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        if keep.is_none_or(|keep| keep[k]) {
            sum += (0..3).map(|c| (p[c] as f64 - q[c] as f64).powi(2)).sum::<f64>();
            n += 3;
        }
    }
    (sum / n as f64).sqrt()
}

/// Pixels whose footprint does not touch the outline of the scene's (first) quad light, as seen
/// by camera rays: those pixels mix the light's radiance with the room's, a binomial of huge
/// contrast whose few pixels would dominate any RMSE.
pub fn off_light_outline(scene: &Scene, size: (u32, u32)) -> Vec<bool> {
    let Some(penumbra::scene::Light::Quad {
        corner, edge_u, edge_v, ..
    }) = scene.lights.first()
    else {
        panic!("a quad light")
    };
    // Slightly enlarged, so rays that graze the outline count as touching it.
    let (corner, edge_u, edge_v) = (*corner - 0.05 * (*edge_u + *edge_v), 1.1 * *edge_u, 1.1 * *edge_v);
    let hits = |x: f32, y: f32| {
        let (o, d) = scene.camera.ray(x, y, size.0, size.1);
        let pv = d.cross(edge_v);
        let inv = 1.0 / edge_u.dot(pv);
        let tv = o - corner;
        let (u, v) = (tv.dot(pv) * inv, d.dot(tv.cross(edge_u)) * inv);
        (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)
    };
    let mut keep = Vec::new();
    for j in 0..size.1 {
        for i in 0..size.0 {
            let n = 8;
            let covered = (0..=n)
                .flat_map(|a| (0..=n).map(move |b| (a, b)))
                .filter(|&(a, b)| hits(i as f32 + a as f32 / n as f32, j as f32 + b as f32 / n as f32))
                .count();
            keep.push(covered == 0 || covered == (n + 1) * (n + 1));
        }
    }
    keep
}

/// ∫ over the upper hemisphere of f(v, l) cos θ L(l) dω for a surface facing +y, texel by
/// texel with 24 × 24 midpoints each (the map is constant over a texel, the BRDF smooth).
pub fn reflected_environment(map: &EnvironmentMap, v: Vec3, s: &Surface) -> Vec3 {
    let (w, h, n) = (map.width, map.height, 24);
    let mut sum = glam::DVec3::ZERO;
    for j in 0..h / 2 {
        for i in 0..w {
            let t = map.texels[(j * w + i) as usize];
            let mut texel = glam::DVec3::ZERO;
            for a in 0..n {
                for b in 0..n {
                    let uv = glam::Vec2::new(
                        (i as f32 + (b as f32 + 0.5) / n as f32) / w as f32,
                        (j as f32 + (a as f32 + 0.5) / n as f32) / h as f32,
                    );
                    let d_omega = 2.0 * std::f64::consts::PI.powi(2) * (uv.y as f64 * std::f64::consts::PI).sin();
                    let l = penumbra::scene::Environment::equirect_dir(uv);
                    texel += penumbra::lighting::brdf::brdf_times_cos(Vec3::Y, v, l, s).as_dvec3() * d_omega;
                }
            }
            sum += texel * glam::DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64) / (n * n * w * h) as f64;
        }
    }
    sum.as_vec3()
}
