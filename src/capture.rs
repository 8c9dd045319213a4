//! `penumbra capture`: render a scene headless and write the PNG and/or EXR.

use std::path::PathBuf;

use crate::backend::{Gpu, GpuDesc};
use crate::error::Result;
use crate::image_io::HdrImage;
use crate::renderer::{FrameOutput, Renderer};
use crate::scene::Scene;

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
}

/// Loads the scene (or the built-in default) as the CLI does.
pub fn load_scene(path: Option<&std::path::Path>) -> Result<Scene> {
    Ok(match path {
        Some(p) => Scene::from_file(p)?,
        None => Scene::default_scene(),
    })
}

/// Renders `frames` frames and returns the last one's radiance.
pub fn render_image(opts: &CaptureOptions) -> Result<(HdrImage, Renderer)> {
    let scene = load_scene(opts.scene.as_deref())?;
    let gpu = Gpu::new(&opts.gpu)?;
    let mut renderer = Renderer::new(gpu, scene, opts.method.as_deref(), opts.size, 1)?;
    let camera = renderer.scene.camera.clone();
    let mut image = None;
    for _ in 0..opts.frames.max(1) {
        image = renderer.render(&camera, FrameOutput::Readback)?.image;
    }
    let image = image.ok_or_else(|| crate::error::Error::Usage("readback returned no image".into()))?;
    Ok((image, renderer))
}

pub fn run(opts: &CaptureOptions) -> Result<Vec<String>> {
    let (image, renderer) = render_image(opts)?;
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
        return Err(crate::error::Error::Usage(format!("{n} validation message(s) (see above)")));
    }
    Ok(written)
}
