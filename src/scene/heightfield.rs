//! Height fields as a mesh source (`mesh = "heightfield"`): a square grid of heights, loaded
//! from a 16-bit PNG / EXR or generated procedurally (and animated by the height-field methods on
//! the GPU, `glsl/heightfield/generate.glsl`, which mirrors [`HeightfieldSource::height_at`]).
//!
//! Layout: `resolution²` samples over a `size × size` square in the xz-plane centred on the
//! origin; sample (i, j) lies at the centre of its cell, x = −size/2 + (i + ½)·size/res,
//! z = −size/2 + (j + ½)·size/res, height y = h (metres). The mesh joins the samples with two
//! triangles per cell, facing +y, with normals from central differences of the heights (the
//! same normals the height-field methods shade with), uv = ((i + ½)/res, (j + ½)/res).

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::doc::{Field, Table};
use super::error::SceneError;
use super::mesh::Mesh;

/// Largest accepted `resolution` (samples per side).
pub const MAX_HEIGHTFIELD_RESOLUTION: u32 = 1024;
/// Smallest accepted `resolution`.
pub const MIN_HEIGHTFIELD_RESOLUTION: u32 = 8;
/// Largest height image read, on a side: a field samples at most 1024², and an 8192² image took
/// 125 s and 1 GB to decode and resample only to be reduced that far.
pub const MAX_HEIGHT_IMAGE_SIDE: u32 = 4096;

/// A height field: where its heights come from and how they move.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightfieldSource {
    /// Side of the square, metres.
    pub size: f32,
    /// Samples per side (a power of two, 8 to 1024).
    pub resolution: u32,
    pub shape: HeightShape,
    /// Height scale, metres: the amplitude or maximum height of the generators, the height of
    /// full white in a PNG, the factor applied to EXR values.
    pub height: f32,
    /// Fraction of the half-size over which heights fade to 0 toward the border (0 = none).
    pub taper: f32,
    /// The pattern is shifted by this (x, z), metres.
    pub offset: Vec2,
    /// The pattern is rotated about +y by this angle (degrees, counter-clockwise seen from above).
    pub pattern_rotate_deg: f32,
    /// Animation speed: cones turn about the ring centre at `speed` rad/s; every other pattern
    /// moves along its own x axis at `speed` m/s. 0 = static. Time 0 is the traced shape.
    pub speed: f32,
}

/// The generators (`generator = …`) and the image source (`path = …`).
#[derive(Debug, Clone, PartialEq)]
pub enum HeightShape {
    /// h = height everywhere.
    Flat,
    /// A plane rising toward +x: h = tan(slope_deg)·x (`height` is ignored).
    Slope { slope_deg: f32 },
    /// A wall: h = height where x > position, 0 elsewhere.
    Step { position: f32 },
    /// Sine grating along x: h = height·(½ + ½ sin(2πx/wavelength)).
    Sine { wavelength: f32 },
    /// `count` cones on a circle of radius `ring_radius` about the origin; cone k has base radius
    /// radius·s_k and apex height height·s_k with s_k = 1 − size_variation·k/count.
    Cones {
        count: u32,
        radius: f32,
        ring_radius: f32,
        size_variation: f32,
    },
    /// Mountains from fractal value noise n ∈ [0, 1) (`octaves` octaves from `wavelength` down,
    /// each half the size and amplitude of the last): h = height·(max(n − 0.4, 0)/0.6)², plains
    /// where the noise is low and peaks where it is high.
    Fbm { wavelength: f32, octaves: u32, seed: u32 },
    /// Egg tray: h = height·(½ + ½ sin(2πx/λ) sin(2πz/λ)).
    EggTray { wavelength: f32 },
    /// City blocks of pitch `wavelength`: a box building per block (heights 25–100% of `height`,
    /// about one block in seven empty), streets `street`·wavelength wide.
    City { wavelength: f32, seed: u32, street: f32 },
    /// A greyscale image (16-bit PNG: value/65535·height; EXR: first channel·height), stretched
    /// over the square and sampled bilinearly; row 0 is the −z edge, column 0 the −x edge.
    Image { path: PathBuf },
}

/// Codes the GPU generator uses for [`HeightShape`] (see `glsl/heightfield/generate.glsl`).
impl HeightShape {
    pub fn code(&self) -> u32 {
        match self {
            HeightShape::Flat => 0,
            HeightShape::Slope { .. } => 1,
            HeightShape::Step { .. } => 2,
            HeightShape::Sine { .. } => 3,
            HeightShape::Cones { .. } => 4,
            HeightShape::Fbm { .. } => 5,
            HeightShape::EggTray { .. } => 6,
            HeightShape::City { .. } => 7,
            HeightShape::Image { .. } => 8,
        }
    }
}

/// A loaded height image: `width × height` values, row-major, row 0 at −z.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightImage {
    pub width: u32,
    pub height: u32,
    pub values: Vec<f32>,
}

impl HeightImage {
    /// Reads a 16-bit (or 8-bit) greyscale PNG, normalised to [0, 1], or the first channel of an
    /// EXR as stored.
    pub fn load(path: &Path) -> Result<HeightImage, SceneError> {
        let file = path.display().to_string();
        let (_, w, h) = crate::util::image_io::image_header(path)
            .map_err(|e| SceneError::new(&file, None, "file", format!("cannot load the height image: {e}")))?;
        if w > MAX_HEIGHT_IMAGE_SIDE || h > MAX_HEIGHT_IMAGE_SIDE {
            return Err(SceneError::new(
                &file,
                None,
                "file",
                format!("the height image is {w}×{h}; a height field samples at most {MAX_HEIGHTFIELD_RESOLUTION}² so penumbra reads height images of at most {MAX_HEIGHT_IMAGE_SIDE} on a side (downsample it)"),
            ));
        }
        let img = crate::util::image_io::open_image(path)
            .map_err(|e| SceneError::new(&file, None, "file", format!("cannot load the height image: {e}")))?;
        let (width, height) = (img.width(), img.height());
        let values: Vec<f32> = match &img {
            image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_) => {
                img.to_rgba32f().pixels().map(|p| p.0[0]).collect()
            }
            _ => img.to_luma32f().pixels().map(|p| p.0[0]).collect(),
        };
        if width < 2 || height < 2 {
            return Err(SceneError::new(
                &file,
                None,
                "file",
                format!("a height image needs at least 2×2 pixels, got {width}×{height}"),
            ));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(SceneError::new(
                &file,
                None,
                format!("pixel ({}, {})", k as u32 % width, k as u32 / width),
                "is not a finite number",
            ));
        }
        Ok(HeightImage { width, height, values })
    }

    /// Bilinear value at continuous pixel coordinates (pixel centres at integers), clamped to the
    /// edge. Mirrors `hf_image_bilinear` in `glsl/heightfield/generate.glsl`.
    pub fn bilinear(&self, px: f32, py: f32) -> f32 {
        let (w, h) = (self.width as i32, self.height as i32);
        let (fx, fy) = (px.floor(), py.floor());
        let (tx, ty) = (px - fx, py - fy);
        let at = |x: i32, y: i32| self.values[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
        let (x0, y0) = (fx as i32, fy as i32);
        let a = at(x0, y0) + (at(x0 + 1, y0) - at(x0, y0)) * tx;
        let b = at(x0, y0 + 1) + (at(x0 + 1, y0 + 1) - at(x0, y0 + 1)) * tx;
        a + (b - a) * ty
    }
}

/// Integer hash to [0, 1), identical to `hf_hash` in `glsl/heightfield/generate.glsl`.
pub fn hash01(ix: i32, iz: i32, seed: u32) -> f32 {
    let mut h =
        (ix as u32).wrapping_mul(0x8da6_b343) ^ (iz as u32).wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7feb_352d);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846c_a68b);
    h ^= h >> 16;
    (h >> 8) as f32 / 16_777_216.0
}

fn smooth(t: f32) -> f32 {
    t * t * (3.0 - 2.0 * t)
}

/// Value noise in [0, 1) with smoothstep interpolation between lattice values.
fn value_noise(x: f32, z: f32, seed: u32) -> f32 {
    let (fx, fz) = (x.floor(), z.floor());
    let (ix, iz) = (fx as i32, fz as i32);
    let (tx, tz) = (smooth(x - fx), smooth(z - fz));
    let a = hash01(ix, iz, seed);
    let b = hash01(ix + 1, iz, seed);
    let c = hash01(ix, iz + 1, seed);
    let d = hash01(ix + 1, iz + 1, seed);
    let ab = a + (b - a) * tx;
    let cd = c + (d - c) * tx;
    ab + (cd - ab) * tz
}

impl HeightfieldSource {
    /// Metres between neighbouring samples.
    pub fn spacing(&self) -> f32 {
        self.size / self.resolution as f32
    }

    /// Object-space position (x, z) of sample (i, j) of a `res`-sample grid over this square.
    pub fn sample_xz(&self, i: u32, j: u32, res: u32) -> Vec2 {
        let s = self.size / res as f32;
        Vec2::new(
            -0.5 * self.size + (i as f32 + 0.5) * s,
            -0.5 * self.size + (j as f32 + 0.5) * s,
        )
    }

    /// Loads the image of an image source (`None` for generators).
    pub fn load_image(&self) -> Result<Option<HeightImage>, SceneError> {
        match &self.shape {
            HeightShape::Image { path } => HeightImage::load(path).map(Some),
            _ => Ok(None),
        }
    }

    /// The height (metres, object space) at (x, z) at time `t` seconds. `image` must be the
    /// loaded image of an image source. Mirrors `hf_height` in `glsl/heightfield/generate.glsl`.
    pub fn height_at(&self, x: f32, z: f32, t: f32, image: Option<&HeightImage>) -> f32 {
        let (s, c) = self.pattern_rotate_deg.to_radians().sin_cos();
        let (dx, dz) = (x - self.offset.x, z - self.offset.y);
        // Pattern coordinates: the point rotated back by the pattern's rotation.
        let (mut qx, qz) = (c * dx + s * dz, -s * dx + c * dz);
        let cones = matches!(self.shape, HeightShape::Cones { .. });
        if !cones {
            qx -= self.speed * t;
        }
        let a = self.height;
        let tau = std::f32::consts::TAU;
        let h = match &self.shape {
            HeightShape::Flat => a,
            HeightShape::Slope { slope_deg } => slope_deg.to_radians().tan() * qx,
            HeightShape::Step { position } => {
                if qx > *position {
                    a
                } else {
                    0.0
                }
            }
            HeightShape::Sine { wavelength } => a * (0.5 + 0.5 * (tau * qx / wavelength).sin()),
            HeightShape::Cones {
                count,
                radius,
                ring_radius,
                size_variation,
            } => {
                let mut h = 0.0f32;
                for k in 0..*count {
                    let ang = tau * k as f32 / *count as f32 + self.speed * t;
                    let (cx, cz) = (ring_radius * ang.cos(), ring_radius * ang.sin());
                    let sk = 1.0 - size_variation * k as f32 / *count as f32;
                    let r = ((qx - cx) * (qx - cx) + (qz - cz) * (qz - cz)).sqrt();
                    h = h.max(a * sk * (1.0 - r / (radius * sk)).max(0.0));
                }
                h
            }
            HeightShape::Fbm {
                wavelength,
                octaves,
                seed,
            } => {
                let (mut sum, mut norm, mut amp, mut freq) = (0.0f32, 0.0f32, 1.0f32, 1.0 / wavelength);
                for o in 0..*octaves {
                    sum += amp * value_noise(qx * freq, qz * freq, seed.wrapping_add(o));
                    norm += amp;
                    amp *= 0.5;
                    freq *= 2.0;
                }
                let n = sum / norm.max(1e-6);
                let peak = (n - 0.4).max(0.0) / 0.6;
                a * peak * peak
            }
            HeightShape::EggTray { wavelength } => {
                a * (0.5 + 0.5 * (tau * qx / wavelength).sin() * (tau * qz / wavelength).sin())
            }
            HeightShape::City {
                wavelength,
                seed,
                street,
            } => {
                let (u, v) = (qx / wavelength, qz / wavelength);
                let (cu, cv) = (u.floor(), v.floor());
                let (fu, fv) = (u - cu, v - cv);
                let half = 0.5 * (1.0 - street);
                let inside = (fu - 0.5).abs() < half && (fv - 0.5).abs() < half;
                let empty = hash01(cu as i32, cv as i32, seed.wrapping_add(7919)) < 0.15;
                if inside && !empty {
                    a * (0.25 + 0.75 * hash01(cu as i32, cv as i32, *seed))
                } else {
                    0.0
                }
            }
            HeightShape::Image { .. } => match image {
                Some(img) => {
                    let px = (qx / self.size + 0.5) * img.width as f32 - 0.5;
                    let py = (qz / self.size + 0.5) * img.height as f32 - 0.5;
                    a * img.bilinear(px, py)
                }
                None => 0.0,
            },
        };
        h * self.taper_weight(x, z)
    }

    /// The border fade factor at (x, z).
    fn taper_weight(&self, x: f32, z: f32) -> f32 {
        if self.taper <= 0.0 {
            return 1.0;
        }
        let half = 0.5 * self.size;
        let band = self.taper * half;
        let w = |d: f32| smooth(((half - d.abs()) / band).clamp(0.0, 1.0));
        w(x) * w(z)
    }

    /// Heights at the samples of a `res × res` grid over the square at time `t`, row-major
    /// (index j·res + i).
    pub fn grid(&self, res: u32, t: f32, image: Option<&HeightImage>) -> Vec<f32> {
        let mut out = Vec::with_capacity((res * res) as usize);
        for j in 0..res {
            for i in 0..res {
                let p = self.sample_xz(i, j, res);
                out.push(self.height_at(p.x, p.y, t, image));
            }
        }
        out
    }

    /// The mesh at time 0 (object space): one vertex per sample, two triangles per cell.
    pub fn mesh(&self) -> Result<Mesh, SceneError> {
        let image = self.load_image()?;
        let res = self.resolution;
        let h = self.grid(res, 0.0, image.as_ref());
        Ok(grid_mesh(self, res, &h))
    }
}

/// Normal (object space, unit) of a height grid at sample (i, j) from central differences with
/// clamped neighbours: normalize(−∂h/∂x, 1, −∂h/∂z). Mirrors `hf_normal` in the shaders.
pub fn grid_normal(h: &[f32], res: u32, spacing: f32, i: u32, j: u32) -> Vec3 {
    let at = |i: i64, j: i64| h[(j.clamp(0, res as i64 - 1) * res as i64 + i.clamp(0, res as i64 - 1)) as usize];
    let (i, j) = (i as i64, j as i64);
    let dx = (at(i + 1, j) - at(i - 1, j)) / (2.0 * spacing);
    let dz = (at(i, j + 1) - at(i, j - 1)) / (2.0 * spacing);
    Vec3::new(-dx, 1.0, -dz).normalize()
}

/// The triangle mesh of a `res × res` height grid over `src`'s square.
pub fn grid_mesh(src: &HeightfieldSource, res: u32, h: &[f32]) -> Mesh {
    let spacing = src.size / res as f32;
    let mut m = Mesh::default();
    for j in 0..res {
        for i in 0..res {
            let p = src.sample_xz(i, j, res);
            m.positions.push(Vec3::new(p.x, h[(j * res + i) as usize], p.y));
            m.normals.push(grid_normal(h, res, spacing, i, j));
            m.uvs
                .push(Vec2::new((i as f32 + 0.5) / res as f32, (j as f32 + 0.5) / res as f32));
        }
    }
    for j in 0..res - 1 {
        for i in 0..res - 1 {
            let a = j * res + i;
            let (b, c, d) = (a + 1, a + res + 1, a + res);
            // Seen from +y (looking down −y, x right, z down the screen) a → d → c is
            // counter-clockwise.
            m.indices.extend_from_slice(&[a, d, c, a, c, b]);
        }
    }
    m.compute_tangents();
    m
}

/// Keys of `mesh = "heightfield"` besides the placement ones and `material`.
pub(crate) const HEIGHTFIELD_KEYS: &[&str] = &[
    "size",
    "resolution",
    "generator",
    "path",
    "height",
    "wavelength",
    "count",
    "radius",
    "ring_radius",
    "size_variation",
    "octaves",
    "seed",
    "street",
    "slope_deg",
    "position",
    "taper",
    "offset",
    "pattern_rotate_deg",
    "speed",
];

const GENERATORS: [&str; 8] = ["flat", "slope", "step", "sine", "cones", "fbm", "eggtray", "city"];

/// Reads the keys of a `mesh = "heightfield"` object.
// long: one key of the height field after another, each read and checked.
pub(crate) fn read(t: &Table) -> Result<HeightfieldSource, SceneError> {
    let opt_num = |k: &str, what: &str, ok: &dyn Fn(f32) -> bool| -> Result<Option<f32>, SceneError> {
        t.get(k).map(|f| f.number_where(what, ok)).transpose()
    };
    let positive = |k: &str, default: f32| -> Result<f32, SceneError> {
        Ok(opt_num(k, "a positive number", &|x| x > 0.0)?.unwrap_or(default))
    };
    let size = positive("size", 1.0)?;
    let res_f = t.get("resolution");
    let mut resolution = match &res_f {
        Some(f) => Some(power_of_two(f)?),
        None => None,
    };
    let source = match (t.get("generator"), t.get("path")) {
        (Some(_), Some(p)) => return Err(p.err("give either generator or path, not both")),
        (None, None) => {
            return Err(t.missing(
                "generator",
                &format!("one of: {}; or give path = a 16-bit PNG or EXR", GENERATORS.join(", ")),
            ))
        }
        (None, Some(p)) => {
            let path = p.existing_image()?;
            // The image is decoded here, so a corrupt one is an error with the field's line.
            let img = HeightImage::load(&path).map_err(|e| {
                let at = if e.field == "file" {
                    String::new()
                } else {
                    format!("{}: ", e.field)
                };
                p.err(format!("{}: {at}{}", path.display(), e.message))
            })?;
            if resolution.is_none() {
                // An image's own size when it is a power of two, else the next one up.
                resolution = Some(
                    img.width
                        .max(img.height)
                        .next_power_of_two()
                        .clamp(MIN_HEIGHTFIELD_RESOLUTION, MAX_HEIGHTFIELD_RESOLUTION),
                );
            }
            HeightShape::Image { path }
        }
        (Some(g), None) => {
            let kind = g.string()?;
            let wavelength = || positive("wavelength", 1.0);
            let seed = || -> Result<u32, SceneError> {
                Ok(t.get("seed").map(|f| f.int_in(0, u32::MAX)).transpose()?.unwrap_or(1))
            };
            match kind {
                "flat" => HeightShape::Flat,
                "slope" => HeightShape::Slope {
                    slope_deg: opt_num("slope_deg", "an angle in degrees in (-89, 89)", &|x| x.abs() < 89.0)?
                        .unwrap_or(30.0),
                },
                "step" => HeightShape::Step {
                    position: opt_num("position", "a number, metres", &|_| true)?.unwrap_or(0.0),
                },
                "sine" => HeightShape::Sine {
                    wavelength: wavelength()?,
                },
                "cones" => HeightShape::Cones {
                    count: t.get("count").map(|f| f.int_in(1, 64)).transpose()?.unwrap_or(8),
                    radius: positive("radius", 0.25 * size)?,
                    ring_radius: opt_num("ring_radius", "a non-negative number, metres", &|x| x >= 0.0)?
                        .unwrap_or(0.25 * size),
                    size_variation: opt_num("size_variation", "a number in [0, 1)", &|x| (0.0..1.0).contains(&x))?
                        .unwrap_or(0.0),
                },
                "fbm" => HeightShape::Fbm {
                    wavelength: wavelength()?,
                    octaves: t.get("octaves").map(|f| f.int_in(1, 12)).transpose()?.unwrap_or(5),
                    seed: seed()?,
                },
                "eggtray" => HeightShape::EggTray {
                    wavelength: wavelength()?,
                },
                "city" => HeightShape::City {
                    wavelength: wavelength()?,
                    seed: seed()?,
                    street: opt_num("street", "a number in [0, 1)", &|x| (0.0..1.0).contains(&x))?.unwrap_or(0.3),
                },
                other => {
                    return Err(g.err(format!(
                        "unknown generator {other:?}; expected one of: {}",
                        GENERATORS.join(", ")
                    )))
                }
            }
        }
    };
    // Keys that belong to other generators are errors rather than silently ignored.
    let used: &[&str] = match &source {
        HeightShape::Flat => &[],
        HeightShape::Slope { .. } => &["slope_deg"],
        HeightShape::Step { .. } => &["position"],
        HeightShape::Sine { .. } | HeightShape::EggTray { .. } => &["wavelength"],
        HeightShape::Cones { .. } => &["count", "radius", "ring_radius", "size_variation"],
        HeightShape::Fbm { .. } => &["wavelength", "octaves", "seed"],
        HeightShape::City { .. } => &["wavelength", "seed", "street"],
        HeightShape::Image { .. } => &[],
    };
    const SHAPE_KEYS: [&str; 10] = [
        "wavelength",
        "count",
        "radius",
        "ring_radius",
        "size_variation",
        "octaves",
        "seed",
        "street",
        "slope_deg",
        "position",
    ];
    for k in SHAPE_KEYS {
        if let (Some(f), false) = (t.get(k), used.contains(&k)) {
            let what = match &source {
                HeightShape::Image { .. } => "an image height field".to_string(),
                s => format!("generator {:?}", GENERATORS[s.code() as usize]),
            };
            return Err(f.err(format!(
                "not used by {what}; it takes: {}",
                if used.is_empty() {
                    "no shape keys".to_string()
                } else {
                    used.join(", ")
                }
            )));
        }
    }
    let resolution = resolution.unwrap_or(256);
    let offset = match t.get("offset") {
        None => Vec2::ZERO,
        Some(f) => offset2(&f)?,
    };
    Ok(HeightfieldSource {
        size,
        resolution,
        shape: source,
        height: opt_num("height", "a number, metres", &|_| true)?.unwrap_or(1.0),
        taper: opt_num("taper", "a number in [0, 1]", &|x| (0.0..=1.0).contains(&x))?.unwrap_or(0.0),
        offset,
        pattern_rotate_deg: opt_num("pattern_rotate_deg", "an angle in degrees", &|_| true)?.unwrap_or(0.0),
        speed: opt_num("speed", "a number (rad/s for cones, m/s otherwise)", &|_| true)?.unwrap_or(0.0),
    })
}

fn power_of_two(f: &Field) -> Result<u32, SceneError> {
    let r = f.int_in(MIN_HEIGHTFIELD_RESOLUTION, MAX_HEIGHTFIELD_RESOLUTION)?;
    if !r.is_power_of_two() {
        return Err(f.err(format!(
            "expected a power of two from {MIN_HEIGHTFIELD_RESOLUTION} to {MAX_HEIGHTFIELD_RESOLUTION}, got {r}"
        )));
    }
    Ok(r)
}

fn offset2(f: &Field) -> Result<Vec2, SceneError> {
    let items = f.array().map_err(|_| f.err("expected 2 numbers (x, z), metres"))?;
    if items.len() != 2 {
        return Err(f.err(format!("expected 2 numbers (x, z), metres, got {}", items.len())));
    }
    let x = items[0].number_where("a number, metres", |_| true)?;
    let z = items[1].number_where("a number, metres", |_| true)?;
    Ok(Vec2::new(x, z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_height_image_beyond_the_limit_is_refused_before_decoding() {
        let dir = crate::util::test_files::TestDir::new("height-limit");
        let path = dir.join("wide.png");
        image::GrayImage::new(MAX_HEIGHT_IMAGE_SIDE + 1, 2).save(&path).unwrap();
        let Err(e) = HeightImage::load(&path) else {
            panic!("a 4097-wide height image was accepted")
        };
        let e = e.to_string();
        assert!(
            e.contains("wide.png") && e.contains("4097×2") && e.contains("at most 4096 on a side"),
            "{e}"
        );
        let ok = dir.join("ok.png");
        image::GrayImage::new(MAX_HEIGHT_IMAGE_SIDE, 2).save(&ok).unwrap();
        assert!(HeightImage::load(&ok).is_ok());
    }

    fn src(shape: HeightShape) -> HeightfieldSource {
        HeightfieldSource {
            size: 4.0,
            resolution: 16,
            shape,
            height: 1.0,
            taper: 0.0,
            offset: Vec2::ZERO,
            pattern_rotate_deg: 0.0,
            speed: 0.0,
        }
    }

    #[test]
    fn mesh_layout_normals_and_winding() {
        let s = src(HeightShape::Slope { slope_deg: 45.0 });
        let m = s.mesh().unwrap();
        assert_eq!(m.vertex_count(), 256);
        assert_eq!(m.triangle_count(), 2 * 15 * 15);
        // First sample at the centre of the corner cell.
        assert!((m.positions[0] - Vec3::new(-1.875, -1.875, -1.875)).length() < 1e-5);
        // A 45° slope rising toward +x: the normal is (−1, 1, 0)/√2 (interior samples).
        let n = m.normals[5 * 16 + 5];
        assert!((n - Vec3::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-5, "{n}");
        // Every triangle faces up.
        for [a, b, c] in m.triangles() {
            let f = (m.positions[b] - m.positions[a]).cross(m.positions[c] - m.positions[a]);
            assert!(f.y > 0.0);
        }
        m.validate("test").unwrap();
    }

    #[test]
    fn generators_are_bounded_and_animate() {
        let shapes = [
            HeightShape::Sine { wavelength: 1.0 },
            HeightShape::Cones {
                count: 5,
                radius: 0.5,
                ring_radius: 1.0,
                size_variation: 0.5,
            },
            HeightShape::Fbm {
                wavelength: 1.0,
                octaves: 4,
                seed: 3,
            },
            HeightShape::EggTray { wavelength: 1.0 },
            HeightShape::City {
                wavelength: 0.5,
                seed: 2,
                street: 0.3,
            },
        ];
        for shape in shapes {
            let mut s = src(shape.clone());
            s.speed = 0.3;
            let a = s.grid(32, 0.0, None);
            let b = s.grid(32, 1.0, None);
            assert!(a.iter().all(|h| (0.0..=1.0 + 1e-6).contains(h)), "{shape:?}");
            assert!(a.iter().any(|h| *h > 0.2), "{shape:?} is not all flat");
            assert_ne!(a, b, "{shape:?} moves");
        }
    }

    #[test]
    fn hash_is_the_documented_function() {
        // Pinned values: the GLSL twin (hf_hash) must give the same numbers.
        assert_eq!(hash01(0, 0, 0), 0.0);
        let v = hash01(3, -7, 11);
        assert!((0.0..1.0).contains(&v));
        assert_eq!(v, hash01(3, -7, 11));
        assert_ne!(v, hash01(-7, 3, 11));
    }

    fn parse(field: &str) -> Result<crate::scene::Scene, SceneError> {
        let text = format!(
            "[camera]\nposition = [0, 1, 3]\ntarget = [0, 0, 0]\n[[objects]]\nmesh = \"heightfield\"\n{field}\n"
        );
        crate::scene::Scene::from_str(&text, "t.toml", Path::new("."))
    }

    #[test]
    fn scene_keys_and_errors() {
        let s = parse("size = 4\nresolution = 64\ngenerator = \"cones\"\ncount = 3\noffset = [0.5, -1]\nspeed = 0.2")
            .unwrap();
        let crate::scene::MeshSource::Heightfield(h) = &s.objects[0].mesh else {
            panic!()
        };
        assert_eq!(
            (h.size, h.resolution, h.offset, h.speed),
            (4.0, 64, Vec2::new(0.5, -1.0), 0.2)
        );
        assert!(matches!(h.shape, HeightShape::Cones { count: 3, .. }));
        let err = |field: &str| parse(field).unwrap_err().to_string();
        assert_eq!(err("generator = \"dunes\""), "t.toml:6: objects[0].generator: unknown generator \"dunes\"; expected one of: flat, slope, step, sine, cones, fbm, eggtray, city");
        assert_eq!(
            err("generator = \"sine\"\nresolution = 100"),
            "t.toml:7: objects[0].resolution: expected a power of two from 8 to 1024, got 100"
        );
        assert_eq!(
            err("generator = \"sine\"\ncount = 3"),
            "t.toml:7: objects[0].count: not used by generator \"sine\"; it takes: wavelength"
        );
        assert!(
            err("size = 2").starts_with("t.toml:4: objects[0].generator: missing required field"),
            "{}",
            err("size = 2")
        );
        assert!(err("generator = \"flat\"\npath = \"nope.png\"")
            .contains("objects[0].path: give either generator or path, not both"));
        assert!(err("generator = \"flat\"\noffset = [1]").contains("objects[0].offset: expected 2 numbers"));
    }

    #[test]
    fn taper_fades_to_zero_at_the_border() {
        let mut s = src(HeightShape::Flat);
        s.taper = 0.2;
        assert_eq!(s.height_at(0.0, 0.0, 0.0, None), 1.0);
        assert!(s.height_at(1.999, 0.0, 0.0, None) < 1e-3);
    }

    /// Heights load value by value: a 16-bit PNG normalised by 65535, an EXR's first channel as
    /// stored (negative and above-one values kept), row 0 first; non-finite and too-small images
    /// are one error naming the file and the field.
    #[test]
    fn height_images_load_value_by_value() {
        let dir = crate::util::test_files::TestDir::new("height");
        let png = dir.join("h.png");
        let raw: [u16; 6] = [0, 65535, 32768, 1000, 7, 40000];
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(3, 2, raw.to_vec())
            .unwrap()
            .save(&png)
            .unwrap();
        let img = HeightImage::load(&png).unwrap();
        assert_eq!((img.width, img.height), (3, 2));
        for (v, r) in img.values.iter().zip(raw) {
            assert!((v - r as f32 / 65535.0).abs() < 1e-6, "{v} vs {r}");
        }
        let exr = dir.join("h.exr");
        let floats: [f32; 6] = [-1.5, 2.25, 1000.0, 0.0, 0.125, 3.0];
        let rgb: Vec<f32> = floats.iter().flat_map(|&v| [v, 9.0, 9.0]).collect();
        image::Rgb32FImage::from_raw(3, 2, rgb).unwrap().save(&exr).unwrap();
        assert_eq!(HeightImage::load(&exr).unwrap().values, floats.to_vec());
        let nan = dir.join("nan.exr");
        image::Rgb32FImage::from_raw(
            2,
            2,
            vec![0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        )
        .unwrap()
        .save(&nan)
        .unwrap();
        let e = HeightImage::load(&nan).err().unwrap().to_string();
        assert!(
            e.contains("nan.exr") && e.contains("pixel (1, 0)") && e.contains("not a finite number"),
            "{e}"
        );
        let tiny = dir.join("tiny.png");
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(1, 1, vec![5])
            .unwrap()
            .save(&tiny)
            .unwrap();
        let e = HeightImage::load(&tiny).err().unwrap().to_string();
        assert!(e.contains("tiny.png") && e.contains("at least 2×2"), "{e}");
        let e = HeightImage::load(&dir.join("missing.png")).err().unwrap().to_string();
        assert!(e.contains("missing.png") && e.contains("cannot load"), "{e}");
    }
}
