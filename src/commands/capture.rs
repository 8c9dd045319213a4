//! `penumbra capture`: render a scene headless and write the PNG and/or EXR.

use std::path::PathBuf;

use crate::backend::{Gpu, GpuDesc};
use crate::bake::Baker;
use crate::error::Result;
use crate::lighting::{registry, Configuration};
use crate::renderer::{FrameOutput, Renderer};
use crate::scene::{Scene, SceneOverrides};
use crate::util::image_io::HdrImage;

#[derive(Clone, Debug)]
pub struct CaptureOptions {
    pub scene: Option<PathBuf>,
    pub png: Option<PathBuf>,
    pub exr: Option<PathBuf>,
    pub size: (u32, u32),
    pub frames: u32,
    pub method: Option<String>,
    pub exposure: f32,
    pub gpu: GpuDesc,
    /// Render this configuration instead of the scene's own (`--max-error`'s choice).
    pub config: Option<Configuration>,
    /// Render at this many times the size in each axis and box-filter down (1: pixel centres).
    pub supersample: u32,
    /// What the command line sets over the scene file (`--camera`, `--memory-budget-mb`).
    pub overrides: SceneOverrides,
}

/// Loads the scene (or the built-in default) as the CLI does, with the command line's
/// overrides applied.
pub fn load_scene(path: Option<&std::path::Path>, overrides: &SceneOverrides) -> Result<Scene> {
    let mut scene = match path {
        Some(p) => Scene::from_file(p)?,
        None => Scene::default_scene(),
    };
    overrides.apply(&mut scene)?;
    Ok(scene)
}

/// Renders `frames` frames and returns the last one's radiance (at `size × supersample`,
/// box-filtered down to `size`).
pub fn render_image(opts: &CaptureOptions) -> Result<(HdrImage, Renderer)> {
    let render_size = crate::commands::supersample::supersampled_size(opts.size, opts.supersample)?;
    let scene = load_scene(opts.scene.as_deref(), &opts.overrides)?;
    let config = match &opts.config {
        Some(c) => c.clone(),
        None => registry::configuration(&scene, opts.method.as_deref())?,
    };
    // Before the device exists: a method over its memory budget is refused without allocating.
    let (config, notes) = registry::plan(&config, &scene)?;
    for line in notes {
        crate::errln!("{line}");
    }
    let gpu = Gpu::new(&opts.gpu)?;
    // A run estimated past a minute is said before the methods' large allocations.
    let mut renderer = Renderer::for_run(
        gpu,
        scene,
        config,
        render_size,
        Baker::new(Some(Baker::default_dir())),
        opts.frames.max(1) as usize,
    )?;
    let camera = renderer.scene.camera.clone();
    let mut image = None;
    for _ in 0..opts.frames.max(1) {
        image = renderer.render(&camera, FrameOutput::Readback)?.image;
    }
    let image = image.ok_or_else(|| crate::error::Error::Internal("readback returned no image".into()))?;
    let image = if opts.supersample > 1 {
        crate::commands::supersample::box_filter(&image, opts.supersample)?
    } else {
        image
    };
    Ok((image, renderer))
}

pub fn run(opts: &CaptureOptions) -> Result<Vec<String>> {
    let (image, mut renderer) = render_image(opts)?;
    for w in renderer.method_warnings()? {
        eprintln!("warning: {w}");
    }
    let mut written = Vec::new();
    if let Some(p) = &opts.exr {
        image.write_exr(p)?;
        written.push(p.display().to_string());
    }
    let png = match (&opts.png, &opts.exr) {
        (Some(p), _) => Some(p.clone()),
        (None, None) => Some(PathBuf::from("capture.png")),
        (None, Some(_)) => None,
    };
    if let Some(p) = png {
        image.write_png(&p, opts.exposure)?;
        written.push(p.display().to_string());
    }
    let n = renderer.gpu.validation_log().count();
    if n > 0 {
        return Err(crate::error::Error::Validation(n));
    }
    Ok(written)
}

/// `capture --view V`: the method's image composed with its reference (path-traced now at the
/// capture's size, `reference_spp` samples, the kind the configuration is judged against) as
/// the demo composes them; writes the PNG (default `capture-VIEW.png`) and the view's linear
/// values as the EXR (`--exr`, default beside the PNG).
pub fn run_view(
    opts: &CaptureOptions,
    settings: &crate::commands::views::ViewSettings,
    reference_spp: u32,
) -> Result<Vec<String>> {
    let (image, renderer) = render_image(opts)?;
    let kind = registry::reference_kind(&renderer.configuration)?;
    let (mut rs, label) =
        crate::commands::chart::reference_settings(kind, reference_spp, crate::reference::Sampler::Independent);
    rs.spp = reference_spp;
    let mut tracer = crate::reference::ReferenceRenderer::at_frame(
        Gpu::new(&opts.gpu)?,
        &renderer.scene,
        opts.size,
        u64::from(opts.frames.max(1) - 1),
    )?;
    let reference = tracer.render(&rs, &mut |_, _| {})?;
    crate::errln!("reference: {label}, {} spp", reference.spp);
    let composed = crate::commands::views::compose(&image, Some(&reference.mean), settings)?;
    let png = opts
        .png
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("capture-{}.png", settings.view.name())));
    crate::util::image_io::save_image(&png, composed.display.clone().into(), image::ImageFormat::Png)?;
    let exr = opts.exr.clone().unwrap_or_else(|| png.with_extension("exr"));
    composed.values.write_exr(&exr)?;
    let n = renderer.gpu.validation_log().count() + tracer.gpu.validation_log().count();
    if n > 0 {
        return Err(crate::error::Error::Validation(n));
    }
    Ok(vec![png.display().to_string(), exr.display().to_string()])
}

/// `capture --max-error E`: the cheapest configuration within E (relative MSE) from the chart
/// data cached for this scene and size, and a sentence saying why it was chosen.
pub fn choose_configuration(
    opts: &CaptureOptions,
    max_rel_mse: f64,
    cache_dir: &std::path::Path,
) -> Result<(Configuration, String)> {
    use crate::commands::chart::{cached_table, choose, parse_csv, Choice};
    use crate::error::Error;
    let path = opts
        .scene
        .as_deref()
        .ok_or_else(|| Error::Usage("--max-error needs a scene file (the chart is measured per scene)".into()))?;
    let scene = load_scene(Some(path), &opts.overrides)?;
    let table = cached_table(&scene, opts.size, cache_dir);
    // The table is keyed by the scene as seen through the chosen camera: a chart of another
    // camera's view is not this one's.
    let camera = opts
        .overrides
        .camera
        .map_or_else(String::new, |n| format!(" --camera {n}"));
    let text = std::fs::read_to_string(&table).map_err(|_| {
        Error::Usage(format!(
            "{}: no chart data for this scene{} at {}x{} in {}; run `penumbra chart {}{camera} --size {}x{}` first",
            path.display(),
            opts.overrides
                .camera
                .map_or_else(String::new, |n| format!(" through camera {n}")),
            opts.size.0,
            opts.size.1,
            cache_dir.display(),
            path.display(),
            opts.size.0,
            opts.size.1
        ))
    })?;
    let configs = parse_csv(&text)?;
    match choose(&configs, max_rel_mse) {
        Some(Choice::Picked { config, rejected }) => {
            let why = Choice::Picked {
                config: config.clone(),
                rejected,
            }
            .to_string();
            let configuration = registry::offered(&scene)?
                .into_iter()
                .find(|c| c.name == config.method)
                .ok_or_else(|| {
                    Error::Usage(format!(
                        "the chart names method `{}`, which the scene no longer enables; run `penumbra chart` again",
                        config.method
                    ))
                })?;
            let chosen = registry::sweep(&configuration)?
                .into_iter()
                .find(|(label, _)| *label == config.config)
                .map(|(_, d)| d)
                .ok_or_else(|| {
                    Error::Usage(format!(
                        "configuration `{}` is no longer in {}'s sweep; run `penumbra chart` again",
                        config.config, config.method
                    ))
                })?;
            Ok((chosen, why))
        }
        Some(none) => Err(Error::Usage(format!("--max-error {max_rel_mse}: {none}"))),
        None => Err(Error::Usage(format!("{}: the chart table is empty", table.display()))),
    }
}
