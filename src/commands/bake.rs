//! `penumbra bake SCENE`: runs every bake the scene's methods and combinations need, ahead of
//! time, into the bake cache, and reports each bake's time and size.

use crate::backend::Gpu;
use crate::bake::{BakeReport, Baker};
use crate::commands::capture::{load_scene, CaptureOptions};
use crate::error::Result;
use crate::lighting::registry;
use crate::renderer::Renderer;

/// The bakes of every configuration (or only `opts.method`'s), as (configuration, reports).
pub fn run(opts: &CaptureOptions) -> Result<Vec<(String, Vec<BakeReport>)>> {
    let scene = load_scene(opts.scene.as_deref(), &opts.overrides)?;
    let configurations = match opts.method.as_deref() {
        Some(name) => vec![registry::configuration(&scene, Some(name))?],
        None => registry::configurations(&scene)?,
    };
    let mut out = Vec::new();
    for c in configurations {
        // Creating the methods runs their bakes; the frame targets are a token size.
        let renderer = Renderer::with_configuration(
            Gpu::new(&opts.gpu)?,
            scene.clone(),
            c.clone(),
            (1, 1),
            1,
            Baker::new(Some(Baker::default_dir())),
        )?;
        out.push((c.name, renderer.bakes.clone()));
    }
    Ok(out)
}
