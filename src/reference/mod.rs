//! `penumbra reference`: the ground truth every lighting method is measured against, a Monte
//! Carlo path tracer in a compute shader (`glsl/reference/pathtrace.comp`).
//!
//! What one sample of a pixel estimates:
//! - the camera ray goes through a uniformly random point of the pixel (a box filter);
//! - at each surface: material emission (both sides), next-event estimation of every light
//!   (point, spot and directional exactly as `glsl/common/lights.glsl`; spherical lights by
//!   uniform sampling of the visible cap's cone; quad lights by uniform area sampling, one-sided),
//!   then a direction sampled from the Lambert + Blinn-Phong + diffuse-transmission BSDF. Where
//!   there are many lights ([`LightSelection`]) each colour channel draws one of them per vertex
//!   in proportion to its unshadowed contribution there (an area light's at the point sampled
//!   on it) and counts it weighted by the inverse of that probability, so a vertex costs one to
//!   three shadow rays instead of one per light;
//! - a ray that escapes sees the environment: a constant, found by BSDF sampling alone, or an
//!   equirectangular map ([`crate::environment`]), also sampled at every vertex in proportion to
//!   luminance × sin θ and combined with BSDF sampling by multiple importance sampling (power
//!   heuristic);
//! - a ray that hits an area light after a bounce ends there without adding its radiance
//!   (next-event estimation already counted it), so area lights are seen directly only by
//!   camera rays. Area lights are opaque to all rays;
//! - material emission is added wherever a path hits it (both sides), so an emissive mesh lights
//!   the scene too;
//! - a material's `opacity` α < 1 is stochastic transparency: every ray (camera, bounce and
//!   shadow) stops at such a surface with probability α and otherwise passes through it
//!   unchanged, so a pixel sees `α·surface + (1 − α)·behind` and a pane lets `1 − α` of a
//!   light's power through — the physical counterpart of the `shadow_volumes` method's
//!   compromise (light through glass unattenuated);
//! - albedo, normal and specular maps as the raster methods apply them (see `scene_data`);
//!   the raster methods sample each map at a pixel's centre, the reference averages it over the
//!   pixel, so fine texture detail differs between them by aliasing alone (the maps have one
//!   mip level, so there is no mipmapping to differ);
//! - a path is cut after `bounces` surface interactions past the first hit, so the estimate
//!   counts exactly the light that made at most `bounces + 1` interactions. The bias of that cut
//!   is the energy of longer paths, e.g. ρ^(K+2)/(1 − ρ) of the emission in a closed furnace of
//!   albedo ρ;
//! - Russian roulette ([`Settings::roulette_after`]) ends paths earlier at random without
//!   changing that expected value: where the K-th bounce's ray (and every later one) hits a
//!   surface, the path goes on with probability q = min(max channel of its throughput, 0.95)
//!   and its throughput is divided by q. It costs a little variance and saves much time (README,
//!   "The reference against Mitsuba 3"); the furnace, whose paths all carry the same value,
//!   is the exception: there it adds all of its noise;
//! - past the last interaction the tracer only samples and traces another ray when the scene
//!   has something it could find there (emission or a sky), so a dark scene's paths end a ray
//!   earlier with the same estimate.
//!
//! [`LightPaths::Direct`] is `bounces = 0` (emission seen directly plus light after one surface
//! interaction); [`LightPaths::Indirect`] is the full estimator minus exactly those terms, so
//! direct + indirect = all for the same seed.
//!
//! Each pixel sample draws its random numbers from a PCG stream keyed by (pixel, sample index,
//! seed) and is added to a running mean and sum of squared deviations (Welford), so the result
//! is bit-identical for a seed whatever the batching, and the standard error of the mean is
//! `sqrt(M2 / (n − 1) / n)`. That standard error is itself estimated from the samples: where a
//! pixel's value hinges on rare events (a small bright light found by few paths) it is too
//! small until enough of them have been drawn.
//!
//! With [`Sampler::Sobol`] the 2D draws (the point in the pixel, on an area light, the
//! environment and BSDF directions at each depth) come instead from Owen-scrambled Sobol points
//! in [`SOBOL_REPLICATES`] independently scrambled replicates (sample index modulo their count),
//! a replicate's k-th sample taking the k-th point, still whatever the batching. The mean is as
//! unbiased and its error is smaller (stratification). A replicate's samples are not
//! independent, so their scatter would overstate that error; the replicates are, and the
//! standard error is the scatter of their means (R − 1 degrees of freedom per pixel, so a
//! pixel's standard error is itself rougher than with independent samples; `tests/reference/reference.rs`,
//! README "The Sobol sampler").

pub mod export;

pub mod features;

pub(crate) mod scene_data;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use bytemuck::{Pod, Zeroable};

use crate::backend::{
    vk, Bind, BufferDesc, BufferId, ComputePipelineDesc, Frame, Gpu, GpuDesc, ImageDesc, ImageId, MemoryKind,
    PipelineId, SubresourceRange,
};
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph, ResourceStates};
use crate::scene::Scene;
use crate::shaders::ShaderLibrary;
use crate::util::image_io::HdrImage;
pub use features::Sampler;
use features::{BvhWalk, NeeMode, SceneFeatures};
pub use scene_data::{
    SceneBuffers, TracedMaterial, TracedScene, TracedTexture, TriangleShading, LIGHT_QUAD, LIGHT_SPHERE,
};

/// Which light the estimator counts, by the surface interactions along its path.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightPaths {
    /// Everything up to the bounce limit.
    #[default]
    All,
    /// Emission seen directly and light after exactly one interaction (`bounces` = 0).
    Direct,
    /// [`LightPaths::All`] minus [`LightPaths::Direct`].
    Indirect,
}

/// How many samples each dispatch adds to every pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Batching {
    /// Grow batches toward about a quarter of a second of GPU work each.
    Adaptive,
    /// Exactly this many samples per dispatch (the last one may be smaller).
    Fixed(u32),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// Samples per pixel (≥ 1).
    pub spp: u32,
    /// Surface interactions followed after the first hit (ignored by [`LightPaths::Direct`]).
    pub bounces: u32,
    pub paths: LightPaths,
    pub seed: u32,
    pub batching: Batching,
    /// Russian roulette where the K-th bounce's ray and every later one hits a surface (the
    /// camera ray's hit is never rouletted); `None` switches it off. Unbiased: the expected value
    /// is the same as without, within the `bounces` cap.
    pub roulette_after: Option<u32>,
    pub light_selection: LightSelection,
    /// Where the 2D draws come from; [`Sampler::Sobol`] stratifies a pixel's samples. The
    /// default is independent samples, whose per-pixel standard error has n − 1 degrees of
    /// freedom, as the per-pixel statistics of tests and callers assume; the command line and
    /// the chart choose Sobol.
    pub sampler: Sampler,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            spp: 256,
            bounces: DEFAULT_BOUNCES,
            paths: LightPaths::All,
            seed: 0,
            batching: Batching::Adaptive,
            roulette_after: Some(DEFAULT_ROULETTE_AFTER),
            light_selection: LightSelection::Auto,
            sampler: Sampler::Independent,
        }
    }
}

/// How next-event estimation treats the lights (an area light is sampled at one point either
/// way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSelection {
    /// A shadow ray to every light at every vertex: no noise from punctual lights where nothing
    /// is shadowed, work growing with the light count (and llvmpipe's loop limit reached at about
    /// a thousand punctual lights, or a few hundred area lights, whose shadow rays also test
    /// every area light).
    Every,
    /// Per colour channel one light per vertex, drawn with probability proportional to its
    /// unshadowed contribution c_i to that channel there (an area light's at the point sampled on
    /// it) and counted as Σc times its visibility: unbiased, exact for punctual lights where
    /// nothing is shadowed, never above the unshadowed sum (so no rare large values), and one
    /// shadow ray per vertex where the lights share a colour (three at most).
    One,
    /// [`Every`](Self::Every) up to [`ONE_LIGHT_ABOVE`] lights, [`One`](Self::One) beyond.
    #[default]
    Auto,
}

/// Lights beyond which [`LightSelection::Auto`] draws one per vertex. Measured
/// efficiency (samples/s ÷ variance) of drawing one over visiting every light, lavapipe, full
/// paths: 0.30 with 3 lights, 0.88 with 10, 0.70 with 25, 2.1 with 50 and 2.4 with 100 (ignored
/// test `light_selection_efficiency`).
pub const ONE_LIGHT_ABOVE: u32 = 32;

impl LightSelection {
    fn draws_one(self, lights: u32) -> bool {
        match self {
            LightSelection::Every => false,
            LightSelection::One => true,
            LightSelection::Auto => lights > ONE_LIGHT_ABOVE,
        }
    }
}

/// Russian roulette from the fifth bounce on (as Mitsuba's `rr_depth` 5). Chosen by the speed at
/// which the reference reaches a given relative MSE (samples/s over the relative variance of a
/// sample, [`ReferenceImage::relative_variance_per_sample`]) on 18 shipped scenes
/// (`tools/roulette_efficiency.sh`, README "Russian roulette's first bounce"): against K = 2, the
/// default before, K = 5 is 1.13 times as fast in the geometric mean leaving out the furnace,
/// 5.8 times on the furnace and 2.2 on `two_rooms`, whose light arrives after many bounces and
/// which early roulette cut off most; 0.81 times on `sv_glass` at worst.
pub const DEFAULT_ROULETTE_AFTER: u32 = 5;

/// Enough for 0.6^17 ≈ 2e-4 of the light in a white-walled room to be cut off.
pub const DEFAULT_BOUNCES: u32 = 16;

/// Samples per pixel the shader counts exactly (its counts and means are 32-bit floats).
pub const MAX_SPP: u32 = 1 << 24;

/// The most samples one invocation adds in one dispatch. It bounds the work of an invocation
/// (a 1×1 image would otherwise grow its batches to a quarter of a second of one thread), and
/// a smaller cap is learnt when the device cuts a batch short (see `render`).
pub const MAX_BATCH: u32 = 4096;

impl Settings {
    fn check(&self) -> Result<()> {
        if self.spp == 0 {
            return Err(Error::Usage("--spp must be at least 1".into()));
        }
        if self.paths == LightPaths::Indirect && self.bounces == 0 {
            return Err(Error::Usage(
                "--indirect-only needs --bounces of at least 1: with 0 bounces there is no indirect light".into(),
            ));
        }
        if self.roulette_after == Some(0) {
            return Err(Error::Usage(
                "--roulette-after must be at least 1 (or off): the camera ray's hit is never cut".into(),
            ));
        }
        if let Batching::Fixed(0) = self.batching {
            return Err(Error::Usage("a batch must hold at least one sample".into()));
        }
        // The shader keeps each pixel's sample count and running mean in 32-bit floats.
        if self.spp > MAX_SPP {
            return Err(Error::Usage(format!(
                "--spp {} is more than the tracer counts exactly ({MAX_SPP}, 2^24)",
                self.spp
            )));
        }
        Ok(())
    }

    fn push(&self, offset: u32, count: u32, lights: u32) -> BatchPush {
        let (bounces, mut flags) = match self.paths {
            LightPaths::All => (self.bounces, 0),
            LightPaths::Direct => (0, 0),
            LightPaths::Indirect => (self.bounces, FLAG_INDIRECT_ONLY),
        };
        if self.light_selection.draws_one(lights) {
            flags |= FLAG_ONE_LIGHT;
        }
        BatchPush {
            sample_offset: offset,
            sample_count: count,
            seed: self.seed,
            bounces,
            flags,
            roulette_after: self.roulette_after.unwrap_or(u32::MAX),
            first_row: 0,
        }
    }
}

const FLAG_INDIRECT_ONLY: u32 = 1;
const FLAG_ONE_LIGHT: u32 = 2;

/// The tracer's next-event mode for a batch's flags.
fn nee_mode(flags: u32) -> NeeMode {
    if flags & FLAG_ONE_LIGHT != 0 {
        NeeMode::One
    } else {
        NeeMode::Every
    }
}

/// `Params` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    eye: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    forward: [f32; 4],
    environment: [f32; 4],
    counts: [u32; 4],
    environment_map: [u32; 4],
    /// x: 1 when a ray can still find light after the last interaction (emission or a sky);
    /// y: the punctual lights, which come before the area lights.
    options: [u32; 4],
}

impl Params {
    /// The primary rays' frame: the eye, and the image plane's half extents at distance 1.
    fn set_camera(&mut self, cam: &crate::scene::Camera, width: u32, height: u32) {
        let (right, up, forward) = cam.basis();
        let tan_half = (0.5 * cam.fov_y_deg.to_radians()).tan();
        self.eye = cam.position.extend(1.0).into();
        self.right = (right * tan_half * (width as f32 / height as f32)).extend(0.0).into();
        self.up = (up * tan_half).extend(0.0).into();
        self.forward = forward.extend(0.0).into();
    }
}

/// `Batch` push constants in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct BatchPush {
    sample_offset: u32,
    sample_count: u32,
    seed: u32,
    bounces: u32,
    flags: u32,
    /// First interaction subject to Russian roulette; u32::MAX: none.
    roulette_after: u32,
    /// The dispatch covers the rows from this one on (a band, or the whole image from 0).
    first_row: u32,
}

/// A finished render: per-pixel mean radiance and the standard error of that mean.
#[derive(Clone, Debug)]
pub struct ReferenceImage {
    pub mean: HdrImage,
    /// sqrt(sample variance / n) per RGB channel; infinite with a single sample. Alpha is 1.
    pub standard_error: HdrImage,
    pub spp: u32,
    /// From the first dispatch to the read-back results.
    pub seconds: f64,
}

impl ReferenceImage {
    /// The image's average radiance per RGB channel and the standard error of that average
    /// (pixels are independent estimates: sqrt(Σ s.e.²) / pixels).
    pub fn average(&self) -> ([f64; 3], [f64; 3]) {
        let n = self.mean.pixels.len().max(1) as f64;
        let mut mean = [0.0; 3];
        let mut var = [0.0; 3];
        for (m, e) in self.mean.pixels.iter().zip(&self.standard_error.pixels) {
            for c in 0..3 {
                mean[c] += m[c] as f64 / n;
                var[c] += (e[c] as f64).powi(2) / (n * n);
            }
        }
        (mean, var.map(f64::sqrt))
    }

    /// The variance of one sample, per pixel and channel relative as the chart's relative MSE
    /// weighs errors (over mean² + REL_MSE_EPSILON), averaged: the relative MSE this render
    /// would have against the truth at one sample per pixel. Its noise at n spp is this over n,
    /// so samples/s over this is the speed at which the reference reaches a given relative MSE
    /// (what `--roulette-after` and the other estimator settings trade).
    pub fn relative_variance_per_sample(&self) -> f64 {
        let eps = crate::metrics::stats::REL_MSE_EPSILON;
        let n = 3.0 * self.mean.pixels.len().max(1) as f64;
        let spp = self.spp as f64;
        self.mean
            .pixels
            .iter()
            .zip(&self.standard_error.pixels)
            .map(|(m, e)| {
                (0..3)
                    .map(|c| (e[c] as f64).powi(2) * spp / ((m[c] as f64).powi(2) + eps))
                    .sum::<f64>()
            })
            .sum::<f64>()
            / n
    }

    /// Pixel samples per second.
    pub fn samples_per_second(&self) -> f64 {
        self.mean.width as f64 * self.mean.height as f64 * self.spp as f64 / self.seconds.max(1e-9)
    }
}

/// When [`ReferenceRenderer::render_until`] may stop before its cap.
pub struct Stop<'a> {
    /// No judgement before this many samples: the standard error is itself estimated from the
    /// samples, and too small until the rare events a pixel hinges on have been drawn.
    pub min_spp: u32,
    /// The achieved error over the target for the render so far: at most 1 stops. It must
    /// fall as 1/sqrt(spp), as a standard error does, for the next checkpoint to be predicted.
    pub check: &'a mut dyn FnMut(&ReferenceImage) -> f64,
}

/// Samples a render with a target error takes before it trusts its standard error.
pub const MIN_ADAPTIVE_SPP: u32 = 32;

/// What `--max-stderr` measures (see [`relative_error`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ErrorScope {
    /// The standard error of the image's mean over that mean, the worst RGB channel.
    #[default]
    Image,
    /// The 99th percentile over pixels of each pixel's worst channel's standard error over
    /// sqrt(mean² + 0.01).
    Pixel,
}

/// `--max-stderr E`: render until the relative standard error is at most `max`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorTarget {
    pub max: f64,
    pub scope: ErrorScope,
    pub min_spp: u32,
}

/// The relative standard error of a render, as `--max-stderr` bounds it. With m and s a
/// pixel's mean and standard error in one channel, N pixels:
/// - [`ErrorScope::Image`]: the largest over R, G, B of sqrt(Σ s²) / N (the standard error of
///   the image's mean, pixels being independent) over the image's mean Σ m / N. A channel
///   that is black everywhere (mean and error 0) counts as 0. Black pixels only add to the
///   mean, so they cannot stall it; it bounds the error of image averages, not of pixels.
/// - [`ErrorScope::Pixel`]: the nearest-rank 99th percentile over pixels of the largest over
///   R, G, B of s / sqrt(m² + 0.01). The 0.01 is the relative MSE's (`metrics::stats`): on a
///   black pixel the error is measured against 0.1 W/(m²·sr) instead of against 0, so shadows
///   do not demand endless samples, and E² bounds the reference noise's share of a pixel's
///   relative MSE. The percentile leaves out the worst 1% (light outlines, rare caustics),
///   whose standard errors are the least trustworthy estimates.
///
/// Infinite with one sample per pixel.
pub fn relative_error(image: &ReferenceImage, scope: ErrorScope) -> f64 {
    let (m, s) = (&image.mean.pixels, &image.standard_error.pixels);
    match scope {
        ErrorScope::Image => {
            let (mean, se) = image.average();
            (0..3)
                .map(|c| if se[c] == 0.0 { 0.0 } else { se[c] / mean[c] })
                .fold(0.0, f64::max)
        }
        ErrorScope::Pixel => {
            let mut per_pixel: Vec<f64> = m
                .iter()
                .zip(s)
                .map(|(m, s)| {
                    (0..3)
                        .map(|c| s[c] as f64 / ((m[c] as f64).powi(2) + crate::metrics::stats::REL_MSE_EPSILON).sqrt())
                        .fold(0.0, f64::max)
                })
                .collect();
            crate::metrics::stats::nearest_rank_percentile(&mut per_pixel, 99)
        }
    }
}

/// The tracer for one scene and image size: the scene's buffers, the accumulation images and
/// the pipeline stay on the GPU between renders.
pub struct ReferenceRenderer {
    pub gpu: Gpu,
    pub scene: TracedScene,
    /// The shader's specialization (`features`): what it is compiled for. [`SceneFeatures::of`]
    /// the scene by default; [`SceneFeatures::ALL`] gives the shader as written.
    pub features: SceneFeatures,
    /// How rays walk the BVH: [`BvhWalk::for_device`] by default.
    pub walk: BvhWalk,
    /// The walk whose links `buffers.bvh_skips` holds (the stack walk's are one zeroed texel).
    links_for: BvhWalk,
    /// Pipelines compiled so far, by the features, next-event mode and walk they were made for.
    pipelines: Vec<(SceneFeatures, NeeMode, BvhWalk, Sampler, PipelineId)>,
    buffers: SceneBuffers,
    params: Params,
    mean: ImageId,
    second_moment: ImageId,
    readback: [BufferId; 2],
    /// How many pixels' batches were cut short in the last dispatch (host-visible).
    status: BufferId,
    /// With the Sobol sampler, per pixel the sum of each of its [`SOBOL_REPLICATES`]
    /// replicates' samples (a layer each), and their host-visible copy made at checkpoints; one
    /// unused pixel's worth until a Sobol render.
    replicates: (ImageId, BufferId),
    frame: Frame,
    states: ResourceStates,
    width: u32,
    height: u32,
    /// Batches the device cut short (for some pixels or all) and that were run again with
    /// fewer samples, in the last render.
    pub batches_cut_short: u32,
    /// Per batch run again: how many pixels the device had cut short.
    pub pixels_cut_short: Vec<u32>,
}

const ACCUMULATION_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

impl ReferenceRenderer {
    pub fn new(gpu: Gpu, scene: &Scene, size: (u32, u32)) -> Result<ReferenceRenderer> {
        ReferenceRenderer::at_frame(gpu, scene, size, 0)
    }

    /// The scene as the renderer's frame `frame` has it (its clock's time: wind, light motion
    /// and light board applied), so a method's frame N is compared with the same geometry.
    pub fn at_frame(gpu: Gpu, scene: &Scene, size: (u32, u32), frame: u64) -> Result<ReferenceRenderer> {
        let walk = BvhWalk::for_device(gpu.caps().device_type);
        ReferenceRenderer::at_frame_walking(gpu, scene, size, frame, walk)
    }

    /// [`new`](Self::new) with the BVH walk given rather than chosen for the device (the tables
    /// the other walk needs are uploaded when it is first used).
    pub fn with_walk(gpu: Gpu, scene: &Scene, size: (u32, u32), walk: BvhWalk) -> Result<ReferenceRenderer> {
        ReferenceRenderer::at_frame_walking(gpu, scene, size, 0, walk)
    }

    fn at_frame_walking(
        mut gpu: Gpu,
        scene: &Scene,
        (width, height): (u32, u32),
        frame: u64,
        walk: BvhWalk,
    ) -> Result<ReferenceRenderer> {
        if width == 0 || height == 0 {
            return Err(Error::Usage(format!("image size {width}x{height} is empty")));
        }
        let traced = TracedScene::build_at(scene, crate::scene::motion::frame_time(frame))?;
        let mut states = ResourceStates::default();
        let buffers = traced.upload(&mut gpu, &mut states, walk)?;
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
        let mean =
            gpu.create_image(&ImageDesc::new_2d("reference mean", ACCUMULATION_FORMAT, width, height).usage(usage))?;
        let second_moment = gpu.create_image(
            &ImageDesc::new_2d("reference second moment", ACCUMULATION_FORMAT, width, height).usage(usage),
        )?;
        let bytes = width as u64 * height as u64 * 16;
        let readback = [
            readback_buffer(&mut gpu, "reference mean readback", bytes)?,
            readback_buffer(&mut gpu, "reference second moment readback", bytes)?,
        ];
        let status = gpu.create_buffer(&BufferDesc {
            name: "reference status".into(),
            size: 4,
            usage: vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuToCpu,
        })?;
        let replicates = replicate_sums(&mut gpu, 1, 1)?;
        let frame = gpu.create_frame()?;
        let mut params = Params {
            eye: [0.0; 4],
            right: [0.0; 4],
            up: [0.0; 4],
            forward: [0.0; 4],
            environment: traced.environment.extend(0.0).into(),
            counts: [traced.lights.len() as u32, traced.triangles.len() as u32, width, height],
            environment_map: match &traced.environment_map {
                Some(m) => [m.width, m.height, m.has_power as u32, m.cube as u32],
                None => [0; 4],
            },
            options: [traced.light_beyond_last_bounce() as u32, traced.punctual_lights, 0, 0],
        };
        params.set_camera(&scene.camera, width, height);
        let features = SceneFeatures::of(&traced);
        Ok(ReferenceRenderer {
            gpu,
            scene: traced,
            features,
            walk,
            links_for: walk,
            pipelines: Vec::new(),
            buffers,
            params,
            mean,
            second_moment,
            readback,
            status,
            replicates,
            frame,
            states,
            width,
            height,
            batches_cut_short: 0,
            pixels_cut_short: Vec::new(),
        })
    }

    /// Renders `settings.spp` samples per pixel, calling `progress(done, total)` after each batch.
    ///
    /// A batch adds at most [`MAX_BATCH`] samples per pixel. A device may cut an invocation's
    /// loops short (llvmpipe stops them after 65,535 iterations in all): the shader then stores
    /// nothing for that pixel and counts it, and the batch is run again with half the samples,
    /// which becomes the cap for the rest of the render. A single sample cut short is an error,
    /// and so is any pixel that ends with fewer samples than asked for.
    pub fn render(&mut self, settings: &Settings, progress: &mut dyn FnMut(u32, u32)) -> Result<ReferenceImage> {
        self.render_until(settings, None, progress)
    }

    /// [`render`](Self::render), stopping early once `stop` is met, with `settings.spp` as the
    /// cap. The render is read back at checkpoints (the first at `stop.min_spp`, the next where
    /// the ratio predicts the target, at most 4× the samples so far) and `stop.check` judges it;
    /// samples are keyed by their index, so a render stopped at n samples is bit for bit the one
    /// `--spp n` gives. `progress(done, total)` gets the predicted total.
    pub fn render_until(
        &mut self,
        settings: &Settings,
        mut stop: Option<Stop<'_>>,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<ReferenceImage> {
        settings.check()?;
        // Compiled before the clock starts: the rate counts tracing, not llvmpipe's compile.
        self.pipeline(
            nee_mode(settings.push(0, 1, self.params.counts[0]).flags),
            settings.sampler,
        )?;
        let start = Instant::now();
        let target = Duration::from_millis(250);
        let mut cap = MAX_BATCH;
        self.batches_cut_short = 0;
        self.pixels_cut_short.clear();
        let mut batch = match settings.batching {
            Batching::Adaptive => 1,
            Batching::Fixed(n) => n,
        };
        // Where the next checkpoint falls (the cap when there is no stopping rule).
        let mut next_check = match &stop {
            Some(s) => s.min_spp.max(2).min(settings.spp),
            None => settings.spp,
        };
        // The total `progress` is told: the cap, or where the last checkpoint predicts the end.
        let mut expected = next_check;
        let mut done = 0;
        let mut readback: Option<ReferenceImage> = None;
        while done < settings.spp {
            let count = batch.min(cap).min(next_check - done);
            let checkpoint = done + count == next_check;
            let t0 = Instant::now();
            let short = self.dispatch(
                settings.push(done, count, self.params.counts[0]),
                settings.sampler,
                checkpoint,
                self.height,
            )?;
            if short > 0 {
                if count == 1 {
                    return Err(Error::Usage(format!(
                        "{}: one path-traced sample runs more loop iterations than the device allows one shader invocation ({short} pixel(s) cut short); lower --bounces",
                        self.gpu.caps().name
                    )));
                }
                // The pixels that finished the batch keep it (the shader brings every pixel
                // to the batch's end from what it holds), so running it again with half the
                // samples, then the rest, counts no sample twice.
                cap = count / 2;
                self.batches_cut_short += 1;
                self.pixels_cut_short.push(short);
                continue;
            }
            done += count;
            if settings.batching == Batching::Adaptive {
                let per_sample = t0.elapsed().as_secs_f64() / count as f64;
                let fit = (target.as_secs_f64() / per_sample.max(1e-9)) as u32;
                batch = fit.clamp(1, count.saturating_mul(2));
            }
            if checkpoint {
                let image = self.read_image(done, settings.sampler, start)?;
                if let Some(s) = stop.as_mut() {
                    let ratio = (s.check)(&image);
                    if ratio <= 1.0 || done == settings.spp {
                        progress(done, done);
                        return Ok(image);
                    }
                    // Errors fall as 1/sqrt(spp): aim for where the ratio reaches 1, with 5% to
                    // spare, and look again on the way where that is far.
                    let predicted = (done as f64 * ratio * ratio * 1.05).ceil();
                    next_check = (predicted.min(4.0 * done as f64).min(settings.spp as f64) as u32).max(done + 1);
                    expected = (predicted.min(settings.spp as f64) as u32).max(next_check);
                    progress(done, expected);
                    continue;
                }
                readback = Some(image);
            }
            progress(done, expected);
        }
        readback.ok_or_else(|| Error::Internal("reference: no samples were rendered".into()))
    }

    /// Traces from `camera` from now on (the scene's camera at creation); samples already
    /// accumulated were for the old view, so the next batch should start at sample 0.
    pub fn set_camera(&mut self, camera: &crate::scene::Camera) {
        self.params.set_camera(camera, self.width, self.height);
    }

    /// Progressive rendering a batch at a time (the demo's live reference): adds samples
    /// `done..done + count` to the pixels of `rows` (from sample 0, those pixels start afresh)
    /// and with `read_back` returns the image, whose every pixel must then hold `done + count`
    /// samples (the rows of a sample may come in bands over several calls, the last one reading
    /// back). `Ok(None)` without `read_back`, and also when the device cut the batch short,
    /// which then added nothing: try fewer samples.
    pub fn accumulate(
        &mut self,
        settings: &Settings,
        (done, count): (u32, u32),
        rows: std::ops::Range<u32>,
        read_back: bool,
    ) -> Result<Option<ReferenceImage>> {
        if count == 0 || rows.is_empty() || rows.end > self.height {
            return Err(Error::Usage(format!(
                "reference: a batch of {count} samples over rows {rows:?} of {}",
                self.height
            )));
        }
        let start = Instant::now();
        let mut push = settings.push(done, count, self.params.counts[0]);
        push.first_row = rows.start;
        let short = self.dispatch(push, settings.sampler, read_back, rows.end - rows.start)?;
        if short > 0 {
            if count == 1 {
                return Err(Error::Usage(format!(
                    "{}: one path-traced sample runs more loop iterations than the device allows one shader invocation ({short} pixel(s) cut short)",
                    self.gpu.caps().name
                )));
            }
            return Ok(None);
        }
        if !read_back {
            return Ok(None);
        }
        self.read_image(done + count, settings.sampler, start).map(Some)
    }

    /// The accumulation images as read back by the last checkpoint, holding `spp` samples each.
    fn read_image(&self, spp: u32, sampler: Sampler, start: Instant) -> Result<ReferenceImage> {
        let seconds = start.elapsed().as_secs_f64();
        let read = |b: BufferId| -> Result<HdrImage> {
            let bytes = self.gpu.read_buffer(b)?;
            HdrImage::from_rgba32f_bytes(self.width, self.height, &bytes)
                .ok_or_else(|| Error::Internal("reference readback has the wrong size".into()))
        };
        let mean = read(self.readback[0])?;
        let mut standard_error = read(self.readback[1])?;
        // Every pixel must hold exactly the samples asked for (the shader writes its count).
        let short = standard_error.pixels.iter().filter(|p| p[3] != spp as f32).count();
        if short > 0 {
            return Err(Error::Usage(format!(
                "{short} pixel(s) of the reference hold fewer than {spp} samples: the device cut the tracer short"
            )));
        }
        let n = spp as f64;
        if sampler == Sampler::Sobol {
            let pixels = standard_error.pixels.len();
            let sums = self
                .gpu
                .read_buffer_prefix(self.replicates.1, pixels * SOBOL_REPLICATES as usize * 16)?;
            // Copied into [f32; 4]s: the bytes' Vec<u8> need not be aligned for a cast. One
            // layer after another: replicate r of pixel k is at r * pixels + k.
            let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&sums);
            for (k, p) in standard_error.pixels.iter_mut().enumerate() {
                let replicates: Vec<[f32; 4]> = (0..SOBOL_REPLICATES as usize).map(|r| sums[r * pixels + k]).collect();
                *p = replicate_standard_error(&replicates, spp);
            }
            return Ok(ReferenceImage {
                mean,
                standard_error,
                spp,
                seconds,
            });
        }
        for p in &mut standard_error.pixels {
            for c in &mut p[..3] {
                *c = if spp < 2 {
                    f32::INFINITY
                } else {
                    (*c as f64 / (n - 1.0) / n).max(0.0).sqrt() as f32
                };
            }
            p[3] = 1.0;
        }
        Ok(ReferenceImage {
            mean,
            standard_error,
            spp,
            seconds,
        })
    }

    /// The tracer specialised for `self.features`, `nee`, `self.walk` and `sampler`, compiled on
    /// first use (a scene renders with one mode, so one compile).
    fn pipeline(&mut self, nee: NeeMode, sampler: Sampler) -> Result<PipelineId> {
        let (features, walk) = (self.features, self.walk);
        if walk == BvhWalk::Ordered && self.links_for != walk {
            let stale = self.buffers.bvh_skips.image;
            self.buffers.bvh_skips = self.scene.octant_links(&mut self.gpu, &mut self.states, walk)?;
            self.links_for = walk;
            self.states.forget_image(stale);
            self.gpu.destroy_image(stale);
        }
        // Every feature on is the shader as written, which reads the mode from the batch.
        let nee = if features == SceneFeatures::ALL {
            NeeMode::Either
        } else {
            nee
        };
        if let Some(&(_, _, _, _, id)) = self
            .pipelines
            .iter()
            .find(|(f, n, w, s, _)| *f == features && *n == nee && *w == walk && *s == sampler)
        {
            return Ok(id);
        }
        let desc = ComputePipelineDesc {
            name: "reference path tracer".into(),
            shader: "reference/pathtrace.comp".into(),
            specialization: features.specialization(nee, walk, sampler),
        };
        let id = self.gpu.create_compute_pipeline(&desc, &dev_shaders())?;
        self.pipelines.push((features, nee, walk, sampler, id));
        Ok(id)
    }

    /// One submitted and waited-for batch; the last one also copies the results to the host.
    /// Returns how many pixels' batches were cut short (and so left as they were).
    fn dispatch(&mut self, push: BatchPush, sampler: Sampler, read_back: bool, rows: u32) -> Result<u32> {
        let compute = vk::PipelineStageFlags2::COMPUTE_SHADER;
        let pipeline = self.pipeline(nee_mode(push.flags), sampler)?;
        if sampler == Sampler::Sobol {
            let bytes = self.width as u64 * self.height as u64 * u64::from(SOBOL_REPLICATES) * 16;
            if self.gpu.buffer_desc(self.replicates.1)?.size < bytes {
                let (small, small_host) = self.replicates;
                self.replicates = replicate_sums(&mut self.gpu, self.width, self.height)?;
                self.states.forget_image(small);
                self.gpu.destroy_image(small);
                self.states.forget_buffer(small_host);
                self.gpu.destroy_buffer(small_host);
            }
        }
        let (mean, m2, rb, status) = (self.mean, self.second_moment, self.readback, self.status);
        let (replicates, replicates_host) = self.replicates;
        let layer_bytes = self.gpu.buffer_desc(replicates_host)?.size / u64::from(SOBOL_REPLICATES);
        let all_layers = SubresourceRange::all(1, SOBOL_REPLICATES);
        let width = self.width;
        let params = bytemuck::bytes_of(&self.params);
        let mut graph = RenderGraph::new();
        graph
            .pass("clear status")
            .buffer(status, Access::TransferWrite, None)
            .record(move |ctx| ctx.rec.fill_buffer(status, 0));
        let mut pass = graph
            .pass("path trace")
            .storage_write("mean_radiance", mean, SubresourceRange::mip(0), compute)
            .storage_write("second_moment", m2, SubresourceRange::mip(0), compute)
            .buffer(status, Access::StorageWrite { stages: compute }, Some("status"));
        pass = pass.storage_write("replicate_sums", replicates, all_layers, compute);
        pass = self.buffers.read(pass, compute);
        pass.record(move |ctx| {
            ctx.rec.bind_pipeline(pipeline)?;
            ctx.bind(&[("params", Bind::UniformData(params))])?;
            ctx.rec.push_constants(bytemuck::bytes_of(&push))?;
            ctx.rec.dispatch([width, rows, 1])
        });
        if read_back {
            for (name, image, buffer) in [("read back mean", mean, rb[0]), ("read back second moment", m2, rb[1])] {
                graph
                    .pass(name)
                    .transfer_read(image, SubresourceRange::mip(0))
                    .buffer(buffer, Access::TransferWrite, None)
                    .record(move |ctx| ctx.rec.copy_image_to_buffer(image, 0, 0, buffer));
            }
            graph
                .pass("read back replicate sums")
                .transfer_read(replicates, all_layers)
                .buffer(replicates_host, Access::TransferWrite, None)
                .record(move |ctx| {
                    (0..SOBOL_REPLICATES).try_for_each(|r| {
                        ctx.rec
                            .copy_image_to_buffer_at(replicates, 0, r, replicates_host, u64::from(r) * layer_bytes)
                    })
                });
            graph
                .pass("host visibility")
                .buffer(rb[0], Access::HostRead, None)
                .buffer(rb[1], Access::HostRead, None)
                .buffer(status, Access::HostRead, None)
                .buffer(replicates_host, Access::HostRead, None)
                .record(|_| Ok(()));
        } else {
            graph.output_image(mean);
            graph.output_image(m2);
            graph.output_image(replicates);
            graph
                .pass("host visibility")
                .buffer(status, Access::HostRead, None)
                .record(|_| Ok(()));
        }
        let gpu = &self.gpu;
        graph.run_and_wait(gpu, self.frame, &mut self.states, "reference")?;
        let bytes = gpu.read_buffer(status)?;
        Ok(bytes
            .get(..4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .unwrap_or(u32::MAX))
    }
}

/// Where the tracer's shader comes from: the embedded SPIR-V, or with `PENUMBRA_REF_GLSL=DIR`
/// compiled now from a copy of the `glsl/` folder, so variants of the shader (counters in place
/// of radiance, a term switched off) can be timed without rebuilding (how the README's profile
/// of the reference was made).
fn dev_shaders() -> ShaderLibrary {
    match std::env::var_os("PENUMBRA_REF_GLSL") {
        Some(d) => ShaderLibrary::Directory(d.into()),
        None => ShaderLibrary::Embedded,
    }
}

/// How many independently scrambled replicates the Sobol sampler splits a pixel's samples into
/// (sample index modulo this; the tracer gets it as its specialization constant 12,
/// `SOBOL_REPLICATES` in `glsl/reference/features.glsl`). The scatter of
/// their means is the error of the pixel's mean with R - 1 degrees of freedom; more replicates
/// make that estimate steadier but each replicate's stratification coarser (R replicates of n/R
/// samples), which costs error: on the Cornell box with 32 bounces one scramble per pixel gained
/// 1.74 times over independent samples at 8 spp and 2.29 at 64, and 8 replicates gain 1.68 at
/// 64 spp (README, "The Sobol sampler").
pub const SOBOL_REPLICATES: u32 = 8;

/// A pixel's standard error (RGB, alpha 1) from its replicates' sums under the Sobol sampler:
/// replicate r holds the samples whose index is r modulo R, n_r of the pixel's n. The mean is
/// Σ w_r Y_r with Y_r the replicate's mean and w_r = n_r / n, so its variance is Σ w_r² Var(Y)
/// (the counts differ by at most one), Var(Y) estimated by the scatter of the Y_r. Infinite
/// with fewer than two replicates.
fn replicate_standard_error(sums: &[[f32; 4]], spp: u32) -> [f32; 4] {
    let r = sums.len() as u32;
    let counts: Vec<u32> = (0..r).map(|k| (spp + r - 1 - k) / r).collect();
    let used: Vec<usize> = (0..sums.len()).filter(|&k| counts[k] > 0).collect();
    let mut se = [f32::INFINITY, f32::INFINITY, f32::INFINITY, 1.0];
    if used.len() < 2 {
        return se;
    }
    let weights: f64 = used.iter().map(|&k| (counts[k] as f64 / spp as f64).powi(2)).sum();
    for (c, out) in se.iter_mut().take(3).enumerate() {
        let means: Vec<f64> = used.iter().map(|&k| sums[k][c] as f64 / counts[k] as f64).collect();
        let m = means.iter().sum::<f64>() / means.len() as f64;
        let var = means.iter().map(|y| (y - m).powi(2)).sum::<f64>() / (means.len() - 1) as f64;
        *out = (var * weights).sqrt() as f32;
    }
    se
}

/// The Sobol sampler's per-pixel replicate sums, an image of one layer per replicate in device
/// memory for the tracer (which reads and writes them every batch), and the host-visible buffer
/// the layers are copied to, one after another, at checkpoints.
fn replicate_sums(gpu: &mut Gpu, width: u32, height: u32) -> Result<(ImageId, BufferId)> {
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let desc = ImageDesc::new_2d("reference replicate sums", ACCUMULATION_FORMAT, width, height)
        .layers(SOBOL_REPLICATES)
        .usage(usage);
    let sums = gpu.create_image(&desc)?;
    let bytes = width as u64 * height as u64 * u64::from(SOBOL_REPLICATES) * 16;
    Ok((sums, readback_buffer(gpu, "reference replicate sums readback", bytes)?))
}

fn readback_buffer(gpu: &mut Gpu, name: &str, size: u64) -> Result<BufferId> {
    Ok(gpu.create_buffer(&BufferDesc {
        name: name.into(),
        size,
        usage: vk::BufferUsageFlags::TRANSFER_DST,
        memory: MemoryKind::GpuToCpu,
    })?)
}

/// The standard-error image written next to `output`: `ref.exr` → `ref.stderr.exr`.
pub fn stderr_path(output: &Path) -> PathBuf {
    output.with_extension("stderr.exr")
}

/// What `penumbra reference` was asked for.
#[derive(Clone, Debug)]
pub struct ReferenceOptions {
    pub scene: PathBuf,
    pub output: PathBuf,
    pub size: (u32, u32),
    pub settings: Settings,
    /// The renderer's frame whose scene is traced (0: the scene as written, moved by wind where
    /// it has some).
    pub frame: u64,
    /// `--max-stderr`: stop once this holds (`settings.spp` is then the cap).
    pub target: Option<ErrorTarget>,
    /// Trace through this camera of those the scene's assets carry ([`Scene::choose_camera`]).
    pub camera: Option<usize>,
    pub gpu: GpuDesc,
}

/// What `penumbra reference` did.
pub struct ReferenceReport {
    pub written: Vec<PathBuf>,
    pub image: ReferenceImage,
    /// The relative standard error reached, as the target measures it (with a target).
    pub achieved: Option<f64>,
}

/// Renders the scene and writes the mean and standard-error EXRs, printing progress on stderr.
pub fn run(opts: &ReferenceOptions) -> Result<ReferenceReport> {
    let is_exr = opts
        .output
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        return Err(Error::Usage(format!(
            "{}: the reference is written as OpenEXR; give a file name ending in .exr",
            opts.output.display()
        )));
    }
    opts.settings.check()?;
    let mut scene = Scene::from_file(&opts.scene)?;
    if let Some(i) = opts.camera {
        scene.choose_camera(i)?;
    }
    let gpu = Gpu::new(&opts.gpu)?;
    let mut renderer = ReferenceRenderer::at_frame(gpu, &scene, opts.size, opts.frame)?;
    // Progress (rate, elapsed, remaining) on a terminal only: a log or a pipe gets the summary.
    let mut progress = crate::util::progress::Progress::new("reference (spp)");
    let mut update = |done: u32, total: u32| progress.update(done as u64, total as u64);
    let image = match opts.target {
        Some(t) => {
            if !(t.max.is_finite() && t.max > 0.0) {
                return Err(Error::Usage(format!(
                    "--max-stderr {}: expected a relative standard error above 0, e.g. 0.01",
                    t.max
                )));
            }
            let mut check = |img: &ReferenceImage| relative_error(img, t.scope) / t.max;
            renderer.render_until(
                &opts.settings,
                Some(Stop {
                    min_spp: t.min_spp,
                    check: &mut check,
                }),
                &mut update,
            )?
        }
        None => renderer.render(&opts.settings, &mut update)?,
    };
    progress.finish();
    let achieved = opts.target.map(|t| relative_error(&image, t.scope));
    let n = renderer.gpu.validation_log().count();
    if n > 0 {
        return Err(Error::Validation(n));
    }
    let stderr = stderr_path(&opts.output);
    image.mean.write_exr(&opts.output)?;
    image.standard_error.write_exr(&stderr)?;
    Ok(ReferenceReport {
        written: vec![opts.output.clone(), stderr],
        image,
        achieved,
    })
}

#[cfg(test)]
mod tests {
    use super::{replicate_standard_error, ReferenceImage};
    use crate::util::image_io::HdrImage;

    fn image(width: u32, pixels: Vec<[f32; 4]>) -> HdrImage {
        HdrImage {
            width,
            height: pixels.len() as u32 / width,
            pixels,
        }
    }

    #[test]
    fn relative_variance_per_sample_weighs_pixels_as_the_relative_mse() {
        // Pixel 0: s.e. 0.05 at 4 spp is a variance of 0.01 a sample, over 0.1² + 0.01 = 0.5 in
        // each channel; pixel 1: 0.5² · 4 / (1 + 0.01) in red only. Mean over the six values.
        let img = ReferenceImage {
            mean: image(2, vec![[0.1, 0.1, 0.1, 1.0], [1.0, 1.0, 1.0, 1.0]]),
            standard_error: image(2, vec![[0.05, 0.05, 0.05, 1.0], [0.5, 0.0, 0.0, 1.0]]),
            spp: 4,
            seconds: 1.0,
        };
        let expected = (3.0 * 0.5 + 1.0 / 1.01) / 6.0;
        assert!(
            (img.relative_variance_per_sample() - expected).abs() < 1e-6,
            "{}",
            img.relative_variance_per_sample()
        );
    }

    /// Ten samples in eight replicates: counts 2, 2, 1, 1, 1, 1, 1, 1. The replicate means (red)
    /// 1, 3, 0, 0, 0, 0, 0, 0 have mean 0.5 and sample variance (0.25 + 6.25 + 6 * 0.25) / 7 =
    /// 8 / 7; the weights' squares sum to (4 + 4 + 6) / 100. Green has equal means: no error.
    #[test]
    fn replicate_standard_error_weighs_the_replicates_by_their_counts() {
        let mut sums = [[0.0f32, 2.0, 0.0, 0.0]; 8];
        sums[0][0] = 2.0;
        sums[1][0] = 6.0;
        sums[0][1] = 4.0;
        sums[1][1] = 4.0;
        let se = replicate_standard_error(&sums, 10);
        let want = (8.0f64 / 7.0 * 0.14).sqrt() as f32;
        assert!((se[0] - want).abs() < 1e-6 * want, "{se:?}, want {want}");
        assert_eq!(se[1], 0.0, "{se:?}");
        assert_eq!(se[3], 1.0);
        // One sample fills one replicate: no scatter to measure.
        assert!(replicate_standard_error(&sums, 1)[0].is_infinite());
    }
}
