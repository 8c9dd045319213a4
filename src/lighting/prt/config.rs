//! The method's parameters, each checked with one error line naming the scene file, line and field.

use crate::error::{Error, Result};
use crate::lighting::params::Params;
use crate::scene::{MethodDecl, Scene};

/// The document's path (orthographic disk, planar depth, the 8-bit cosine texture and the
/// 2π/1024 scale) or the corrected one (exact per-pixel weights cos·Ω for the mapping in use).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    Faithful,
    Corrected,
}

/// How a hemisphere direction lands in the tile's unit disk (digest §1.4, §3.2 item 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mapping {
    /// Listing 2.4 as written: `(d.x, d.y)`, the Nusselt analogue (the document calls it
    /// stereographic).
    Orthographic = 0,
    /// True stereographic, `(d.x, d.y)/(1 + d.z)`: r = tan(θ/2).
    Stereographic = 1,
    /// Lambert azimuthal equal-area, r = √(1 − cos θ): every pixel the same solid angle.
    EqualArea = 2,
}

/// What near and far clip (digest §1.4 item 3, §3.2 item 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Depth {
    /// The document's: depth along the normal, linear (planes perpendicular to the normal).
    Planar = 0,
    /// Distance from the vertex (spheres): what a ray's t_min/t_max mean.
    Radial = 1,
}

/// Per-pixel quadrature weight of the multiplicative stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Weights {
    /// Listing 2.1's 8-bit cosine texture on its 2/(T−1) grid times hemisphere area / T².
    Legacy,
    /// cos θ · Ω_pixel for the mapping in use, in fp32, zero outside the disk.
    Exact,
}

/// How each tile is summed to one texel of 4 coefficients.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Reduction {
    /// The document's four ping-pong passes (8, 4, 8, 4 taps at 32²) with integer fetches.
    Passes,
    /// One compute workgroup per tile.
    Compute,
}

/// How the raster baker decides which pixels a triangle covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Coverage {
    /// The document's: corners projected, straight edges rasterised (curved edges missed).
    Projected,
    /// A conservative rectangle per triangle and the ray through each pixel centre tested
    /// against it: exact coverage at the pixel centres.
    Exact,
}

/// Where the multiplicative stage gets each pixel's direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Directions {
    /// The mapping's inverse and the basis evaluated exactly.
    Analytic,
    /// The document's: the colour-coded sphere of Listing 2.3 drawn into the tile, its colour
    /// looking the basis up in Listing 2.2's 32 × 64 textures (half-texel misalignments included).
    Sphere,
}

/// Which baker computes the transfer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Baker {
    /// The document's rasterised visibility atlas.
    Raster,
    /// The ray-cast truth on the GPU (compute, BVH).
    Rays,
    /// The ray-cast truth on the CPU.
    RaysCpu,
}

/// How the coefficients are stored (digest §1.9, §3.2 storage).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Storage {
    F32,
    /// Shared exponent per group of coefficients of one band index across vertices (the document's suggestion).
    SharedByBand,
    /// Shared exponent per group of one vertex's coefficients.
    SharedByVertex,
}

impl Storage {
    /// The grouping of a shared-exponent storage (`None`: fp32).
    pub fn grouping(self) -> Option<super::storage::Grouping> {
        match self {
            Storage::F32 => None,
            Storage::SharedByBand => Some(super::storage::Grouping::ByBand),
            Storage::SharedByVertex => Some(super::storage::Grouping::ByVertex),
        }
    }

    /// The format code glsl/prt/shade.vert reads.
    pub fn device_format(self) -> u32 {
        match self {
            Storage::F32 => 0,
            Storage::SharedByBand => 1,
            Storage::SharedByVertex => 2,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    pub mode: Mode,
    pub baker: Baker,
    pub mapping: Mapping,
    pub depth: Depth,
    pub weights: Weights,
    pub reduction: Reduction,
    pub coverage: Coverage,
    pub directions: Directions,
    /// Tile side (pixels per vertex = tile²).
    pub tile: u32,
    /// Vertices rendered per batch (tiles per atlas).
    pub batch: u32,
    /// Coefficients used at run time: 4, 9, 16 (complete bands) or the document's 8 and 12.
    pub coefficients: usize,
    pub near: f64,
    /// `f64::INFINITY`: unbounded.
    pub far: f64,
    /// Occluders write a value growing with distance instead of 0 (§3.1).
    pub gradient: bool,
    /// The occluded/occluding rules as written (see `receivers::OccluderRules::parse`).
    pub occluders: String,
    /// Rays per vertex of the ray-cast bakers.
    pub samples: usize,
    /// The environment turns about world up at this rate (degrees per second): SH rotation.
    pub env_spin: f64,
    /// SH keys per second for scenes with animated objects (§3.3: 5–15).
    pub key_rate: f64,
    /// The loop length of the animation, seconds.
    pub loop_s: f64,
    pub storage: Storage,
    /// Rotation of every vertex camera about its normal, radians (must not matter; tests).
    pub twist: f64,
    /// Exact coverage: the most rectangles (88 bytes each with their indices) one listing pass may hold; the
    /// occluders are listed and drawn in chunks of `rect_budget / batch` triangles. It changes
    /// memory and the number of passes, never the result (tests).
    pub rect_budget: u32,
    /// The longest edge a receiver keeps for the bake, metres: `None` derives it from the scene
    /// (half the smallest object that can shadow it), `Some(0.0)` bakes the meshes as they are.
    pub max_edge: Option<f64>,
    /// The most vertices refinement may add to the scene.
    pub refine_budget: usize,
}

impl Config {
    pub fn defaults(mode: Mode) -> Config {
        let faithful = mode == Mode::Faithful;
        Config {
            mode,
            baker: Baker::Raster,
            // Corrected: the orthographic disk with exact weights is the cosine-weighted estimator (as
            // the ray-cast truth's); equal-area spends fewer pixels near the normal, where the
            // cosine is largest (+2.3 % on the open box's floor at 32², tests/methods/prt_frame.rs).
            mapping: Mapping::Orthographic,
            depth: if faithful { Depth::Planar } else { Depth::Radial },
            weights: if faithful { Weights::Legacy } else { Weights::Exact },
            reduction: if faithful {
                Reduction::Passes
            } else {
                Reduction::Compute
            },
            coverage: if faithful { Coverage::Projected } else { Coverage::Exact },
            directions: if faithful {
                Directions::Sphere
            } else {
                Directions::Analytic
            },
            tile: 32,
            batch: 1024,
            coefficients: 16,
            near: 1e-3,
            far: f64::INFINITY,
            gradient: false,
            occluders: String::new(),
            samples: 1024,
            env_spin: 0.0,
            key_rate: 10.0,
            loop_s: 4.0,
            storage: Storage::F32,
            twist: 0.0,
            rect_budget: 1 << 20,
            // The document bakes the vertices the artist made.
            max_edge: if faithful { Some(0.0) } else { None },
            refine_budget: 16384,
        }
    }

    /// Bands baked: always 4 (16 coefficients); `coefficients` only chooses how many the run
    /// time uses, so every count shares one bake.
    pub fn bands(&self) -> usize {
        4
    }

    /// What the bake depends on (the run-time parameters left out), as a cache key part.
    pub fn bake_key(&self) -> String {
        let far = if self.far.is_finite() {
            format!("{}", self.far)
        } else {
            "inf".into()
        };
        match self.baker {
            Baker::Raster => format!(
                "raster {:?} {:?} {:?} {:?} {:?} {:?} tile={} batch={} bands={} near={} far={far} gradient={} twist={}",
                self.directions,
                self.coverage,
                self.mapping,
                self.depth,
                self.weights,
                self.reduction,
                self.tile,
                self.batch,
                self.bands(),
                self.near,
                self.gradient,
                self.twist
            ),
            _ => format!(
                "rays samples={} bands={} near={} far={far} twist={}",
                self.samples,
                self.bands(),
                self.near,
                self.twist
            ),
        }
    }

    /// The parameters that do nothing with this configuration, and why.
    pub fn inert(&self) -> Vec<(&'static str, &'static str)> {
        match self.baker {
            Baker::Raster => vec![(
                "samples",
                "with the raster baker (it renders each vertex's tile instead)",
            )],
            _ => Vec::new(),
        }
    }

    pub fn from_decl(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let mode = params
            .get_choice("mode", &[("faithful", Mode::Faithful), ("corrected", Mode::Corrected)])?
            .unwrap_or(Mode::Corrected);
        let c = Config::parse_keys(decl, &params, Config::defaults(mode))?;
        c.check_together(decl, scene, &params)?;
        Ok(c)
    }

    /// Each parameter of `decl` over `c` (the mode's defaults), checked on its own.
    // long: one key-by-key parser, a match arm per parameter.
    fn parse_keys(decl: &MethodDecl, params: &Params<'_>, mut c: Config) -> Result<Config> {
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        let float = Params::float;
        for (p, v, _) in &decl.params {
            let p = p.as_str();
            match p {
                "mode" => {}
                "baker" => {
                    c.baker = params.choice(
                        p,
                        v,
                        &[
                            ("raster", Baker::Raster),
                            ("rays", Baker::Rays),
                            ("rays_cpu", Baker::RaysCpu),
                        ],
                    )?
                }
                "mapping" => {
                    c.mapping = params.choice(
                        p,
                        v,
                        &[
                            ("orthographic", Mapping::Orthographic),
                            ("stereographic", Mapping::Stereographic),
                            ("equal_area", Mapping::EqualArea),
                        ],
                    )?
                }
                "depth" => c.depth = params.choice(p, v, &[("planar", Depth::Planar), ("radial", Depth::Radial)])?,
                "weights" => {
                    c.weights = params.choice(p, v, &[("legacy", Weights::Legacy), ("exact", Weights::Exact)])?
                }
                "reduction" => {
                    c.reduction =
                        params.choice(p, v, &[("passes", Reduction::Passes), ("compute", Reduction::Compute)])?
                }
                "directions" => {
                    c.directions = params.choice(
                        p,
                        v,
                        &[("analytic", Directions::Analytic), ("sphere", Directions::Sphere)],
                    )?
                }
                "coverage" => {
                    c.coverage =
                        params.choice(p, v, &[("projected", Coverage::Projected), ("exact", Coverage::Exact)])?
                }
                "storage" => {
                    c.storage = params.choice(
                        p,
                        v,
                        &[
                            ("f32", Storage::F32),
                            ("shared_by_band", Storage::SharedByBand),
                            ("shared_by_vertex", Storage::SharedByVertex),
                        ],
                    )?
                }
                "tile" => {
                    c.tile = v
                        .as_integer()
                        .filter(|t| [8, 16, 32, 64, 128].contains(t))
                        .ok_or_else(|| bad(p, "a tile side of 8, 16, 32, 64 or 128", v))?
                        as u32
                }
                "batch" => {
                    c.batch = v
                        .as_integer()
                        .filter(|b| (1..=4096).contains(b))
                        .ok_or_else(|| bad(p, "a vertex count from 1 to 4096", v))? as u32
                }
                "coefficients" => {
                    c.coefficients = v
                        .as_integer()
                        .filter(|n| [4, 8, 9, 12, 16].contains(n))
                        .ok_or_else(|| bad(p, "4, 9 or 16 (complete bands), or the document's 8 or 12", v))?
                        as usize
                }
                "near" => {
                    c.near = float(v)
                        .filter(|x| x.is_finite() && *x >= 0.0)
                        .ok_or_else(|| bad(p, "a distance >= 0", v))?
                }
                "far" => {
                    c.far = float(v)
                        .filter(|x| x.is_finite() && *x >= 0.0)
                        .map(|x| if x == 0.0 { f64::INFINITY } else { x })
                        .ok_or_else(|| bad(p, "a distance > near, or 0 for none", v))?
                }
                "gradient" => c.gradient = v.as_bool().ok_or_else(|| bad(p, "true or false", v))?,
                "occluders" => {
                    c.occluders = v
                        .as_str()
                        .ok_or_else(|| bad(p, "a string of `receiver: occluders…` rules separated by `;`", v))?
                        .to_string()
                }
                "samples" => {
                    c.samples = v
                        .as_integer()
                        .filter(|n| (16..=1 << 20).contains(n) && n.isqrt() * n.isqrt() == *n)
                        .ok_or_else(|| bad(p, "a square ray count (16, 256, 1024, 4096...) up to 1048576", v))?
                        as usize
                }
                "env_spin" => {
                    c.env_spin = float(v)
                        .filter(|x| x.is_finite() && x.abs() <= 3600.0)
                        .ok_or_else(|| bad(p, "degrees per second, at most 3600", v))?
                }
                "key_rate" => {
                    c.key_rate = float(v)
                        .filter(|x| (1.0..=60.0).contains(x))
                        .ok_or_else(|| bad(p, "keys per second from 1 to 60", v))?
                }
                "max_edge" => {
                    c.max_edge =
                        Some(float(v).filter(|x| x.is_finite() && *x >= 0.0).ok_or_else(|| {
                            bad(p, "an edge length in metres, or 0 to bake the meshes as they are", v)
                        })?)
                }
                "refine_budget" => {
                    c.refine_budget = v
                        .as_integer()
                        .filter(|n| (0..=1 << 22).contains(n))
                        .ok_or_else(|| bad(p, "a vertex count from 0 to 4194304", v))?
                        as usize
                }
                "loop_s" => {
                    c.loop_s = float(v)
                        .filter(|x| *x > 0.0 && *x <= 600.0)
                        .ok_or_else(|| bad(p, "seconds in (0, 600]", v))?
                }
                _ => {}
            }
        }
        Ok(c)
    }

    /// What no single parameter decides: the occluder rules against the scene's objects, near
    /// below far, and the atlas within the largest image.
    fn check_together(&self, decl: &MethodDecl, scene: Option<&Scene>, params: &Params<'_>) -> Result<()> {
        let c = self;
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        if let Some(scene) = scene {
            // The rules name objects: checked here, where an error can point at the line.
            super::receivers::OccluderRules::parse(&c.occluders, scene)
                .map_err(|m| Error::from(scene.method_param_error(decl, "occluders", m)))?;
        }
        if c.far <= c.near {
            return Err(bad(
                "far",
                "a distance greater than near",
                decl.param("far").unwrap_or(&toml::Value::from(0)),
            ));
        }
        let side = c.atlas_side();
        if side > 16384 {
            return Err(bad(
                "batch",
                &format!(
                    "a batch whose atlas fits 16384 pixels (tile {} × ⌈√batch⌉ = {side})",
                    c.tile
                ),
                decl.param("batch").unwrap_or(&toml::Value::from(c.batch as i64)),
            ));
        }
        Ok(())
    }

    /// Tiles per atlas row.
    pub fn tiles_per_row(&self) -> u32 {
        (self.batch as f64).sqrt().ceil() as u32
    }

    /// The atlas's side in pixels.
    pub fn atlas_side(&self) -> u32 {
        self.tiles_per_row() * self.tile
    }

    /// The document's incomplete band sets (8, 12 coefficients) are not rotation invariant.
    pub fn legacy_coefficients(&self) -> bool {
        matches!(self.coefficients, 8 | 12)
    }
}
