//! `penumbra demo`: the scene in a window with a fly camera, an on-screen panel (egui) of the
//! configuration, the GPU pass times, the camera and the view, and a live reference: the path
//! tracer accumulating the current view while the camera is still, with the method's error
//! against it and the views that show it (method, reference, split, error map, difference).

mod camera;
mod live;
mod panel;
mod rebake;
mod script;

use std::collections::{HashSet, VecDeque};
use std::path::PathBuf;
use std::time::Instant;

use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{DeviceEvent, DeviceId, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::backend::{vk, Gpu, GpuDesc, Overlay, OverlayFrame, PassTiming, Swapchain};
use crate::bake::Baker;
use crate::commands::capture::{load_scene, CaptureOptions};
use crate::commands::views::{Composed, ErrorMap, View, ViewSettings};
use crate::error::{Error, Result};
use crate::lighting::{registry, Configuration};
use crate::renderer::{FrameOutput, Renderer};
use crate::util::image_io::HdrImage;

pub use camera::{bookmarks_path, Bookmarks, FlyCamera};
pub use live::{LiveError, LiveReference};
pub use rebake::BakeStatus;
pub use script::{Event, Script};

const FRAMES_IN_FLIGHT: usize = 2;
/// Frame intervals kept for the panel's graph.
const HISTORY: usize = 240;
/// Error metrics are refreshed at most this often while the reference grows (a switch of
/// method refreshes them at once), and no more often than every four times what they cost, so
/// that the worker computing them leaves most of the CPU to the frames and the tracer.
const METRICS_INTERVAL_S: f64 = 0.25;

/// How this frame's error is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Measurement {
    /// In the frame: a switch of method, whose numbers change at once.
    Now,
    /// On the metrics worker, the frame going on.
    Background,
}

/// One frame as the report (`--report-json`) records it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameRecord {
    pub frame: u64,
    pub configuration: String,
    /// What the panel's method box says is drawn (made by `panel::method_label`).
    pub method_box: String,
    /// The drawn configuration's parameters as declared, `method(name = value, ...)` a part.
    pub parameters: String,
    /// The bake running in the background, as the panel shows it.
    pub baking: Option<BakeStatus>,
    /// How the last background bake that did not switch ended (cancelled), as the panel says.
    pub bake_note: Option<String>,
    /// The failures the panel lists in red (the latest four).
    pub messages: Vec<String>,
    /// The animation frame the next frame is drawn at, and whether the animation is paused.
    pub animation_frame: u64,
    pub paused: bool,
    pub view: View,
    pub spp: u32,
    pub restarts: u32,
    pub error: Option<LiveError>,
    /// Drawn and presented; false while the window is minimised.
    pub presented: bool,
    /// Wall time since the previous frame.
    pub frame_ms: f64,
    /// The live reference's share of it (tracing, read-back, metrics).
    pub reference_ms: f64,
    pub width: u32,
    pub height: u32,
    /// The window's scale factor (physical pixels per point) the panel is laid out at.
    pub scale_factor: f64,
    /// Where the panel last saw the pointer, in points (none before it entered the window).
    pub pointer: Option<[f32; 2]>,
}

struct Running {
    window: Window,
    renderer: Renderer,
    swapchain: Swapchain,
    overlay: Overlay,
    egui: egui::Context,
    egui_input: egui_winit::State,
    /// Physical pixels per point, from the window at start and from the last scale-factor event:
    /// winit's X11 window reports its old factor after a settings change until the window moves.
    scale_factor: f64,
    show_panel: bool,
    camera: FlyCamera,
    keys: HashSet<KeyCode>,
    looking: bool,
    /// The last resize gave the window no area (minimised): frames are skipped until one does.
    minimised: bool,
    dragging_divider: bool,
    cursor_x: f64,
    last: Instant,
    frames: u64,
    screenshots: u32,
    /// Copy the next presented frame back (with --screenshot, the last frame).
    grab_next: bool,
    grabbed: Option<image::RgbaImage>,
    /// Save the view on screen (PNG + EXR) after the next frame.
    save_view: Option<PathBuf>,
    /// The scene's methods and combinations, or every method for a scene that declares none
    /// (M cycles through them), and the one shown.
    configurations: Vec<crate::lighting::Configuration>,
    current: usize,
    /// The configuration the last switch failed to make (the scene refused it): the next M goes
    /// on from it, so that one refusal does not hold the cycle.
    refused: Option<usize>,
    /// Set by a switch: the next frame measures its error whatever the interval.
    switched: bool,
    /// The bakes of a configuration being switched to, running beside the frames.
    rebake: Option<rebake::Rebake>,
    /// A change asked for while they run: made once they have stopped (the latest request wins,
    /// and cancels them).
    queued: Option<(usize, crate::lighting::Configuration)>,
    /// How the last background bake that did not switch ended (cancelled), for the panel.
    bake_note: Option<String>,
    /// The device the bakes run on (without the window's display).
    bake_desc: GpuDesc,
    /// Validation messages of the finished bakes' devices.
    bake_validation: usize,
    params: Vec<panel::ParamEdit>,
    live: LiveReference,
    live_on: bool,
    reference_s: f64,
    metrics_at: Option<Instant>,
    /// What the last refresh of the metrics cost.
    metrics_s: f64,
    view: ViewSettings,
    view_texture: Option<egui::TextureHandle>,
    composed: Option<Composed>,
    method_image: Option<HdrImage>,
    timings: Vec<PassTiming>,
    frame_ms: VecDeque<f32>,
    /// The GPU time of recent frames (ms, the sum of the timestamped passes), oldest first.
    gpu_ms: VecDeque<f32>,
    messages: Vec<String>,
    bookmarks: Bookmarks,
    bookmarks_file: PathBuf,
    /// The bookmark N goes to.
    next_bookmark: usize,
    report: Vec<FrameRecord>,
    scripted: bool,
}

/// Scripted runs (tests, benchmarks): stop after a number of frames, save the last one, resize.
#[derive(Clone, Debug, Default)]
pub struct DemoScript {
    pub frames: Option<u64>,
    pub screenshot: Option<PathBuf>,
    /// After this many frames, ask the window system for this inner size.
    pub resize_at: Option<(u64, u32, u32)>,
    /// Switch to the next configuration every this many frames (as the M key does).
    pub cycle_every: Option<u64>,
    /// Timed input events.
    pub script: Option<Script>,
    /// Write every frame's record (configuration, view, reference spp, error) as JSON here.
    pub report_json: Option<PathBuf>,
    /// Start with the panel hidden (F1 shows it).
    pub hide_panel: bool,
    /// Start with the live reference on, taking this share of the frame time (0: off).
    pub reference_budget: f32,
    pub view: View,
}

struct App {
    opts: CaptureOptions,
    script: DemoScript,
    state: Option<Running>,
    error: Option<Error>,
}

/// A configuration's parameters as declared: `method(name = value, ...)` a part.
fn parameters(config: &crate::lighting::Configuration) -> String {
    let parts: Vec<String> = config
        .parts
        .iter()
        .map(|p| {
            let values: Vec<String> = p.decl.params.iter().map(|(k, v, _)| format!("{k} = {v}")).collect();
            format!("{}({})", p.decl.name, values.join(", "))
        })
        .collect();
    parts.join(" + ")
}

fn param_edits(config: &crate::lighting::Configuration) -> Vec<panel::ParamEdit> {
    let schemas = registry::schemas();
    let mut out = Vec::new();
    for (part, p) in config.parts.iter().enumerate() {
        let Some(schema) = schemas.iter().find(|s| s.name == p.decl.name) else {
            continue;
        };
        for s in schema.params {
            out.push(panel::ParamEdit {
                part,
                name: s.name,
                kind: s.kind,
                text: p.decl.param(s.name).map(|v| v.to_string()).unwrap_or_default(),
            });
        }
    }
    out
}

impl App {
    fn start(&mut self, el: &ActiveEventLoop) -> Result<Running> {
        let scene = load_scene(self.opts.scene.as_deref(), &self.opts.overrides)?;
        let (w, h) = self.opts.size;
        let attrs = Window::default_attributes()
            .with_title("penumbra")
            .with_inner_size(PhysicalSize::new(w, h));
        let window = el
            .create_window(attrs)
            .map_err(|e| Error::Usage(format!("cannot open a window: {e}")))?;
        let desc = self.opts.gpu.clone().with_display(el)?;
        let mut gpu = Gpu::new(&desc)?;
        let size = window.inner_size();
        let swapchain = gpu.create_swapchain(&window, (size.width.max(1), size.height.max(1)), FRAMES_IN_FLIGHT)?;
        let overlay = Overlay::new(&gpu, swapchain.format, FRAMES_IN_FLIGHT)?;
        let extent = swapchain.extent;
        let configurations = registry::offered(&scene)?;
        let chosen = registry::configuration(&scene, self.opts.method.as_deref())?;
        let current = configurations.iter().position(|c| *c == chosen).unwrap_or(0);
        let (renderer, rebake) = first_renderer(
            gpu,
            scene,
            (current, chosen.clone()),
            (extent.width, extent.height),
            &self.opts.gpu,
        )?;
        // Said at start: a minute of frames at one a second, so a method slower than that warns.
        for w in renderer.cost_warnings(60) {
            crate::errln!("{w}");
        }
        let camera = FlyCamera::new(renderer.scene.camera.clone());
        let egui = egui::Context::default();
        let egui_input = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu_max_texture_side()),
        );
        let scale_factor = window.scale_factor();
        let bookmarks_file = bookmarks_path(self.opts.scene.as_deref());
        let bookmarks = Bookmarks::load(&bookmarks_file)?;
        let budget = self.script.reference_budget;
        Ok(Running {
            window,
            params: param_edits(&chosen),
            renderer,
            swapchain,
            overlay,
            egui,
            egui_input,
            scale_factor,
            show_panel: !self.script.hide_panel,
            camera,
            keys: HashSet::new(),
            looking: false,
            minimised: false,
            dragging_divider: false,
            cursor_x: 0.0,
            last: Instant::now(),
            frames: 0,
            screenshots: 0,
            grab_next: false,
            grabbed: None,
            save_view: None,
            configurations,
            current,
            refused: None,
            switched: false,
            rebake,
            queued: None,
            bake_note: None,
            bake_desc: self.opts.gpu.clone(),
            bake_validation: 0,
            live: LiveReference::new(self.opts.gpu.clone(), if budget > 0.0 { budget } else { 0.5 }),
            live_on: budget > 0.0,
            reference_s: 0.0,
            metrics_at: None,
            metrics_s: 0.0,
            view: ViewSettings {
                view: self.script.view,
                exposure: self.opts.exposure,
                ..ViewSettings::default()
            },
            view_texture: None,
            composed: None,
            method_image: None,
            timings: Vec::new(),
            frame_ms: VecDeque::new(),
            gpu_ms: VecDeque::new(),
            messages: Vec::new(),
            bookmarks,
            bookmarks_file,
            next_bookmark: 0,
            report: Vec::new(),
            scripted: self.script.frames.is_some(),
        })
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        el.exit();
    }
}

/// The renderer the window starts with: drawing `chosen` (at its index in the scene's list) where
/// its bakes are cached or it has none; otherwise drawing a stand-in that needs no bake (the scene
/// under `forward`, or its background alone) while `chosen`'s bakes run on a thread of their own,
/// which is returned: the window opens at once and switches when they are done.
fn first_renderer(
    gpu: Gpu,
    scene: crate::scene::Scene,
    (index, chosen): (usize, Configuration),
    size: (u32, u32),
    bake_desc: &GpuDesc,
) -> Result<(Renderer, Option<rebake::Rebake>)> {
    let cache = || Baker::cached_only(Baker::default_dir());
    let background = Configuration {
        name: "background only (stand-in)".into(),
        parts: Vec::new(),
    };
    let mut renderer = Renderer::with_configuration(gpu, scene, background, size, FRAMES_IN_FLIGHT, cache())?;
    let mut baker = cache();
    match renderer.set_configuration_with(chosen.clone(), &mut baker) {
        Ok(()) => return Ok((renderer, None)),
        // Nothing drawn yet to keep: a configuration that cannot be made ends the demo.
        Err(e) if baker.missing().is_none() => return Err(e),
        Err(_) => {}
    }
    if let Some(forward) = forward_stand_in(&renderer.scene) {
        // A scene `forward` refuses keeps the background.
        let _ = renderer.set_configuration_with(forward, &mut cache());
    }
    crate::outln!(
        "baking {} in the background ({} is not in the bake cache); {} draws meanwhile",
        chosen.name,
        baker.missing().unwrap_or_default(),
        renderer.configuration.name
    );
    let rebake = rebake::Rebake::start(bake_desc, renderer.scene.clone(), index, chosen);
    Ok((renderer, Some(rebake)))
}

/// `forward` on the scene, whatever methods it enables: what the window draws while the
/// configuration asked for bakes.
fn forward_stand_in(scene: &crate::scene::Scene) -> Option<Configuration> {
    let mut only_forward = scene.clone();
    only_forward.methods = vec![crate::scene::MethodDecl::implicit_forward()];
    only_forward.combinations.clear();
    let mut config = registry::configuration(&only_forward, Some("forward")).ok()?;
    config.name = "forward (stand-in)".into();
    Some(config)
}

/// Textures egui may make (its font atlas); every Vulkan 1.3 device allows this size.
fn gpu_max_texture_side() -> usize {
    4096
}

impl Running {
    /// A message for the panel (and the terminal): failures that leave the old state running.
    fn report_problem(&mut self, m: String) {
        crate::errln!("{m}");
        self.messages.push(m);
        if self.messages.len() > 4 {
            self.messages.remove(0);
        }
    }

    /// Switches to configuration `next`; a failure is reported and the current one keeps running.
    fn set_configuration(&mut self, next: usize) {
        if let Some(config) = self.configurations.get(next).cloned() {
            self.change_configuration(next, config);
        }
    }

    /// Switches to `config` (the configuration at `index`, or it with edited parameters): at
    /// once when its bakes are in the cache (or it has none); otherwise they run on another
    /// thread while the old configuration keeps drawing, and the switch follows when they end
    /// ([`Running::poll_rebake`]). A change asked for meanwhile cancels them and is made once
    /// they have stopped; the same configuration asked for again lets them run.
    fn change_configuration(&mut self, index: usize, config: crate::lighting::Configuration) {
        if let Some(r) = &mut self.rebake {
            if r.configuration == config && !r.status.cancelling {
                self.queued = None;
                return;
            }
            crate::outln!("{} supersedes the bake of {}", config.name, r.configuration.name);
            r.cancel();
            self.queued = Some((index, config));
            return;
        }
        let started = Instant::now();
        let mut cache = Baker::cached_only(Baker::default_dir());
        match self.renderer.set_configuration_with(config.clone(), &mut cache) {
            Ok(()) => self.switched_to(index, config, started),
            Err(_) if cache.missing().is_some() => {
                crate::outln!(
                    "baking {} in the background ({} is not in the bake cache)",
                    config.name,
                    cache.missing().unwrap_or_default()
                );
                let scene = self.renderer.scene.clone();
                self.bake_note = None;
                self.rebake = Some(rebake::Rebake::start(&self.bake_desc, scene, index, config));
            }
            Err(e) => {
                self.refused = Some(index);
                self.report_problem(format!(
                    "cannot switch to {}, keeping {}: {e}",
                    config.name, self.renderer.configuration.name
                ))
            }
        }
    }

    fn switched_to(&mut self, index: usize, config: crate::lighting::Configuration, started: Instant) {
        self.current = index;
        self.refused = None;
        self.params = param_edits(&config);
        self.switched = true;
        crate::outln!("configuration: {}", config.name);
        if !self.renderer.bakes.is_empty() {
            let bakes: Vec<String> = self
                .renderer
                .bakes
                .iter()
                .map(|b| format!("{} {}", b.name, if b.cached { "from the cache" } else { "built" }))
                .collect();
            crate::outln!(
                "  {} in {:.2} s ({})",
                parameters(&config),
                started.elapsed().as_secs_f64(),
                bakes.join(", ")
            );
        }
        self.configurations[index] = config;
    }

    /// Takes the background bake's progress; when it has ended, switches to its configuration
    /// (its bakes now read from the cache) or reports its failure, then makes a queued change.
    fn poll_rebake(&mut self) {
        let Some(outcome) = self.rebake.as_mut().and_then(|r| r.poll()) else {
            return;
        };
        let r = self.rebake.take().expect("polled above");
        match outcome {
            rebake::Outcome::Baked {
                bakes,
                validation_messages,
            } => {
                self.bake_validation += validation_messages;
                let names: Vec<String> = bakes
                    .iter()
                    .map(|(n, cached)| format!("{n}{}", if *cached { " (cached)" } else { "" }))
                    .collect();
                crate::outln!(
                    "baked {} in {:.2} s: {}",
                    r.configuration.name,
                    r.status.elapsed_s,
                    names.join(", ")
                );
                // A newer request replaces this one, and a cancel that came too late keeps what
                // is drawn (either way its bakes stay in the cache).
                if r.status.cancelling && self.queued.is_none() {
                    self.bake_note = Some(format!(
                        "bake of {} finished as it was cancelled (kept in the cache), keeping {}",
                        r.configuration.name, self.renderer.configuration.name
                    ));
                } else if self.queued.is_none() {
                    let started = Instant::now();
                    // Read from the cache only: the frame never bakes (a bake that could not be
                    // stored failed on its thread).
                    let mut cache = Baker::cached_only(Baker::default_dir());
                    match self
                        .renderer
                        .set_configuration_with(r.configuration.clone(), &mut cache)
                    {
                        Ok(()) => self.switched_to(r.index, r.configuration.clone(), started),
                        Err(e) => self.report_problem(format!("cannot switch to {}: {e}", r.configuration.name)),
                    }
                }
            }
            rebake::Outcome::Cancelled(at) => {
                let note = format!(
                    "bake of {} cancelled after {:.1} s (at {at}), keeping {}",
                    r.configuration.name, r.status.elapsed_s, self.renderer.configuration.name
                );
                crate::outln!("{note}");
                self.bake_note = Some(note);
            }
            rebake::Outcome::Failed(e) => self.report_problem(format!(
                "bake of {} failed, keeping {}: {e}",
                r.configuration.name, self.renderer.configuration.name
            )),
        }
        if let Some((index, config)) = self.queued.take() {
            self.change_configuration(index, config);
        }
    }

    /// Stops the background bake (and forgets a change queued after it); the configuration
    /// drawn now stays.
    fn cancel_bake(&mut self) {
        if let Some(r) = &mut self.rebake {
            crate::outln!("cancelling the bake of {}", r.configuration.name);
            r.cancel();
            self.queued = None;
        }
    }

    /// Switches to the next of the scene's configurations (after the one last refused, if any).
    fn next_configuration(&mut self) {
        if self.configurations.len() < 2 {
            return;
        }
        let from = self.refused.take().unwrap_or(self.current);
        self.set_configuration((from + 1) % self.configurations.len());
    }

    /// The current configuration with the panel's parameters, rebuilt (its bakes through the
    /// bake cache, in the background where they are not cached); an error keeps the old one.
    fn apply_params(&mut self) {
        // The configuration chosen: the one drawn, or the one a stand-in draws for.
        let mut config = self.configurations[self.current].clone();
        for p in &self.params {
            if p.text.trim().is_empty() {
                continue;
            }
            let value = match toml::from_str::<toml::Table>(&format!("v = {}", p.text)) {
                Ok(mut t) => t.remove("v").expect("parsed above"),
                Err(e) => {
                    self.report_problem(format!("{}: `{}` is not a TOML value: {}", p.name, p.text, e.message()));
                    return;
                }
            };
            if let Some(part) = config.parts.get_mut(p.part) {
                part.decl = part.decl.with(p.name, value);
            }
        }
        self.change_configuration(self.current, config);
    }

    /// Sets the parameter `name` (`method.name` where the configuration has several methods)
    /// in the panel and applies the parameters, as typing it and pressing Apply does.
    fn set_param(&mut self, name: &str, value: &str) -> Result<()> {
        let chosen = &self.configurations[self.current];
        let parts: Vec<String> = chosen.parts.iter().map(|p| p.decl.name.clone()).collect();
        let found = self
            .params
            .iter_mut()
            .find(|p| p.name == name || parts.get(p.part).is_some_and(|m| format!("{m}.{}", p.name) == name));
        let Some(p) = found else {
            return Err(Error::Usage(format!(
                "script: `{name}` is not a parameter of {}",
                chosen.name
            )));
        };
        p.text = value.to_string();
        self.apply_params();
        Ok(())
    }

    fn reload_shaders(&mut self) {
        match self.renderer.reload_shaders() {
            Ok(n) => crate::outln!("reloaded {n} pipelines from glsl/"),
            // A broken shader is reported; the old pipelines keep running.
            Err(e) => self.report_problem(format!("shader reload failed, keeping the old pipelines: {e}")),
        }
    }

    fn set_view(&mut self, view: View) {
        self.view.view = view;
        crate::outln!("view: {}", view.name());
    }

    fn next_screenshot_path(&mut self) -> PathBuf {
        self.screenshots += 1;
        PathBuf::from(format!("penumbra-{}-{}.png", self.view.view.name(), self.screenshots))
    }

    /// A key press, from the keyboard or a script.
    fn key(&mut self, el: &ActiveEventLoop, code: KeyCode) {
        match code {
            KeyCode::Escape => el.exit(),
            KeyCode::F1 => self.show_panel = !self.show_panel,
            KeyCode::F12 => self.save_view = Some(self.next_screenshot_path()),
            KeyCode::KeyM => self.next_configuration(),
            KeyCode::KeyC => self.cancel_bake(),
            KeyCode::KeyR => self.reload_shaders(),
            KeyCode::KeyG => self.live_on = !self.live_on,
            KeyCode::KeyP => self.renderer.clock_paused = !self.renderer.clock_paused,
            KeyCode::KeyX => {
                self.view.error_map = match self.view.error_map {
                    ErrorMap::Relative => ErrorMap::Flip,
                    ErrorMap::Flip => ErrorMap::Relative,
                }
            }
            KeyCode::KeyV => {
                let i = View::ALL.iter().position(|v| *v == self.view.view).unwrap_or(0);
                self.set_view(View::ALL[(i + 1) % View::ALL.len()]);
            }
            KeyCode::Digit1 | KeyCode::Digit2 | KeyCode::Digit3 | KeyCode::Digit4 | KeyCode::Digit5 => {
                let i = [
                    KeyCode::Digit1,
                    KeyCode::Digit2,
                    KeyCode::Digit3,
                    KeyCode::Digit4,
                    KeyCode::Digit5,
                ]
                .iter()
                .position(|k| *k == code)
                .unwrap_or(0);
                self.set_view(View::ALL[i]);
            }
            KeyCode::Equal | KeyCode::NumpadAdd => self.view.exposure = (self.view.exposure * 1.25).min(64.0),
            KeyCode::Minus | KeyCode::NumpadSubtract => self.view.exposure = (self.view.exposure / 1.25).max(1e-3),
            KeyCode::BracketLeft => self.view.split = (self.view.split - 0.05).max(0.0),
            KeyCode::BracketRight => self.view.split = (self.view.split + 0.05).min(1.0),
            KeyCode::KeyB => self.add_bookmark(),
            KeyCode::KeyN => {
                let n = self.bookmarks.bookmark.len();
                if n > 0 {
                    self.bookmarks.apply(self.next_bookmark % n, &mut self.camera);
                    self.next_bookmark = (self.next_bookmark + 1) % n;
                }
            }
            _ => {}
        }
    }

    fn add_bookmark(&mut self) {
        self.bookmarks.add(&self.camera);
        match self.bookmarks.save(&self.bookmarks_file) {
            Ok(()) => crate::outln!("bookmark saved in {}", self.bookmarks_file.display()),
            Err(e) => self.report_problem(format!("bookmark not saved: {e}")),
        }
    }

    fn run_action(&mut self, a: panel::Action) {
        match a {
            panel::Action::Configuration(i) => self.set_configuration(i),
            panel::Action::ApplyParams => self.apply_params(),
            panel::Action::CancelBake => self.cancel_bake(),
            panel::Action::ReloadShaders => self.reload_shaders(),
            panel::Action::Screenshot => self.save_view = Some(self.next_screenshot_path()),
            panel::Action::AddBookmark => self.add_bookmark(),
            panel::Action::GoToBookmark(i) => {
                self.bookmarks.apply(i, &mut self.camera);
            }
        }
    }

    fn scripted_event(&mut self, el: &ActiveEventLoop, e: &Event) -> Result<()> {
        match e {
            Event::Key(name) => {
                let code = key_code(name).ok_or_else(|| Error::Usage(format!("script: unknown key `{name}`")))?;
                self.key(el, code);
            }
            Event::Move(d) => self.camera.translate(glam::Vec3::from(*d)),
            Event::Turn([y, p]) => self.camera.turn(*y, *p),
            Event::Budget(b) => {
                self.live_on = *b > 0.0;
                if *b > 0.0 {
                    self.live.budget = b.clamp(0.0, 0.95);
                }
            }
            Event::Split(s) => self.view.split = s.clamp(0.0, 1.0),
            Event::Screenshot(p) => self.save_view = Some(p.clone()),
            Event::Param(name, value) => self.set_param(name, value)?,
            // Sent through the window's event handler by the caller.
            Event::Minimise | Event::Restore => {}
        }
        Ok(())
    }

    fn recreate(&mut self) -> Result<()> {
        let size = self.window.inner_size();
        if self.minimised || size.width == 0 || size.height == 0 {
            return Ok(());
        }
        self.renderer
            .gpu
            .recreate_swapchain(&mut self.swapchain, (size.width, size.height))?;
        let e = self.swapchain.extent;
        self.renderer.resize((e.width, e.height))?;
        self.method_image = None;
        self.composed = None;
        Ok(())
    }

    /// The live reference's work for this frame: follow the view, add what the budget pays for.
    fn reference_step(&mut self) -> Result<bool> {
        if !self.live_on {
            return Ok(false);
        }
        let kind = registry::reference_kind(&self.renderer.configuration)?;
        let t = self.renderer.targets;
        let camera = self.camera.camera();
        let frame = self.renderer.clock_frame();
        self.live
            .follow(&self.renderer.scene, &camera, kind, (t.width, t.height), frame)?;
        self.live.step()
    }

    /// Builds the panel (and the view's image behind it) for this frame.
    fn ui(&mut self) -> Result<OverlayFrame> {
        let mut raw = self.egui_input.take_egui_input(&self.window);
        // The panel is laid out at the factor the last scale-factor event gave, not the window's.
        let points_per_pixel = 1.0 / (self.scale_factor as f32 * self.egui.zoom_factor());
        let size = self.window.inner_size();
        raw.screen_rect = (size.width > 0 && size.height > 0).then(|| {
            egui::Rect::from_min_size(
                egui::Pos2::ZERO,
                egui::vec2(size.width as f32, size.height as f32) * points_per_pixel,
            )
        });
        raw.viewports
            .entry(raw.viewport_id)
            .or_default()
            .native_pixels_per_point = Some(self.scale_factor as f32);
        if let Some(c) = self.composed.as_ref().filter(|_| self.view.view != View::Method) {
            let img = egui::ColorImage::from_rgba_unmultiplied(
                [c.display.width() as usize, c.display.height() as usize],
                c.display.as_raw(),
            );
            match &mut self.view_texture {
                Some(t) => t.set(img, egui::TextureOptions::NEAREST),
                None => {
                    self.view_texture = Some(self.egui.load_texture("view", img, egui::TextureOptions::NEAREST));
                }
            }
        }
        let info = panel::PanelInfo {
            configurations: &self.configurations,
            current: self.current,
            drawn: &self.renderer.configuration.name,
            timings: &self.timings,
            frame_ms: &self.frame_ms,
            gpu_ms: &self.gpu_ms,
            live: &self.live,
            position: self.camera.base.position,
            bookmarks: self.bookmarks.bookmark.len(),
            messages: &self.messages,
            baking: self.rebake.as_ref().map(|r| &r.status),
            queued: self.queued.as_ref().map(|(_, c)| c.name.as_str()),
            bake_note: self.bake_note.as_deref(),
        };
        let mut actions = Vec::new();
        let show_view = self.view.view != View::Method && self.composed.is_some();
        let texture = self.view_texture.as_ref().map(|t| t.id());
        let show_panel = self.show_panel;
        let mut budget = self.live.budget;
        let mut paused = self.renderer.clock_paused;
        let out = self.egui.run_ui(raw, |ui| {
            let ctx = ui.ctx().clone();
            if let (true, Some(id)) = (show_view, texture) {
                let rect = ctx.content_rect();
                let uv = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                ctx.layer_painter(egui::LayerId::background())
                    .image(id, rect, uv, egui::Color32::WHITE);
            }
            if show_panel {
                actions = panel::draw(
                    &ctx,
                    &info,
                    panel::PanelSettings {
                        view: &mut self.view,
                        speed: &mut self.camera.speed,
                        budget: &mut budget,
                        live_on: &mut self.live_on,
                        paused: &mut paused,
                        params: &mut self.params,
                    },
                );
            }
        });
        self.live.budget = budget;
        self.renderer.clock_paused = paused;
        self.egui_input
            .handle_platform_output(&self.window, out.platform_output);
        let primitives = self.egui.tessellate(out.shapes, out.pixels_per_point);
        for a in actions {
            self.run_action(a);
        }
        Ok(OverlayFrame {
            primitives,
            textures: out.textures_delta,
            pixels_per_point: out.pixels_per_point,
        })
    }

    /// Renders and presents one frame; returns false when the window is minimised.
    fn frame(&mut self) -> Result<bool> {
        let size = self.window.inner_size();
        if self.minimised || size.width == 0 || size.height == 0 {
            self.record(self.last.elapsed().as_secs_f64(), 0.0, false);
            self.frames += 1;
            return Ok(false);
        }
        let interval = self.note_interval();
        self.camera.fly(&self.keys, interval.min(0.1) as f32);
        self.poll_rebake();
        self.collect_previous_frame()?;
        let reference_start = Instant::now();
        if let Err(e) = self.reference_step() {
            self.live_on = false;
            self.report_problem(format!("live reference stopped: {e}"));
        }
        let mut reference_s = reference_start.elapsed().as_secs_f64();
        let overlay = self.ui()?;
        // Textures are uploaded now even if this frame is not presented.
        self.overlay.prepare(&self.renderer.gpu, overlay)?;
        let Some(acquired) = self.renderer.gpu.acquire(&self.swapchain, self.frames as usize)? else {
            self.recreate()?;
            return Ok(true);
        };
        let wait_stage = vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT;
        self.renderer.states.acquired_image(acquired.image, wait_stage);
        let camera = self.camera.camera();
        let readback = self.grab_next;
        let measure = self.measurement();
        let radiance =
            measure.is_some() || self.save_view.is_some() || (self.view.view != View::Method && self.live_on);
        self.renderer.render(
            &camera,
            FrameOutput::Present {
                image: acquired.image,
                exposure: self.view.exposure,
                readback,
                radiance,
                overlay: Some(&mut self.overlay),
            },
        )?;
        let gpu = &self.renderer.gpu;
        gpu.submit_frame(
            self.renderer.last_frame(),
            Some((acquired.acquired, wait_stage)),
            Some(acquired.rendered),
        )?;
        let presented = gpu.present(&self.swapchain, &acquired)?;
        if readback || radiance {
            let t0 = Instant::now();
            gpu.wait_frame(self.renderer.last_frame())?;
            // Waiting for the frame is what the radiance read-back costs the window (the next
            // frame's work cannot overlap this one's): the live reference's when it asked.
            if radiance && self.live_on {
                let waited = t0.elapsed().as_secs_f64();
                self.live.spend(waited);
                reference_s += waited;
            }
        }
        if readback {
            self.grabbed = Some(self.renderer.presented_pixels(acquired.image)?);
            self.grab_next = false;
        }
        if radiance {
            let t0 = Instant::now();
            self.after_radiance(measure)?;
            let spent = t0.elapsed().as_secs_f64();
            self.live.spend(spent);
            reference_s += spent;
        }
        self.reference_s = reference_s;
        if !presented {
            self.recreate()?;
        }
        self.record(interval, reference_s, true);
        self.frames += 1;
        Ok(true)
    }

    /// The time since the last frame, kept for the frame-time graph and the reference's share.
    fn note_interval(&mut self) -> f64 {
        let now = Instant::now();
        let interval = (now - self.last).as_secs_f64();
        self.last = now;
        if self.frames > 0 {
            self.frame_ms.push_back((interval * 1000.0) as f32);
            if self.frame_ms.len() > HISTORY {
                self.frame_ms.pop_front();
            }
            self.live.frame_time(interval - self.reference_s);
        }
        interval
    }

    /// Waits for the slot's previous frame (which also makes its acquire semaphore reusable),
    /// takes its GPU timings, and takes the metrics worker's result if it has one.
    fn collect_previous_frame(&mut self) -> Result<()> {
        let slot = self.renderer.current_frame();
        self.renderer.gpu.wait_frame(slot)?;
        if let Some(t) = self.renderer.gpu.frame_timings(slot)? {
            self.gpu_ms.push_back(t.iter().map(|p| p.ms as f32).sum());
            if self.gpu_ms.len() > HISTORY {
                self.gpu_ms.pop_front();
            }
            self.timings = t;
        }
        match self.live.take_measurement() {
            // Off the frame, but the reference's work all the same: charged to its share.
            Ok(Some(cost)) => {
                self.metrics_s = cost;
                self.live.spend(cost);
            }
            Ok(None) => {}
            Err(e) => self.report_problem(format!("error metrics failed: {e}")),
        }
        Ok(())
    }

    /// Whether this frame measures the error: at once after a switch of method; otherwise on
    /// the worker, when the reference has grown since the last measurement, the worker is free
    /// and the interval has passed (in scripted runs, at every growth).
    fn measurement(&self) -> Option<Measurement> {
        let image = self.live.image.as_ref().filter(|_| self.live_on)?;
        if self.switched {
            return Some(Measurement::Now);
        }
        let interval_s = METRICS_INTERVAL_S.max(4.0 * self.metrics_s);
        let due = self.metrics_at.is_none_or(|t| t.elapsed().as_secs_f64() >= interval_s);
        let stale = self.live.error.as_ref().is_none_or(|e| e.spp != image.spp);
        (stale && !self.live.measuring() && (due || self.scripted)).then_some(Measurement::Background)
    }

    /// With this frame's radiance read back: the error, the composed view, a saved view.
    fn after_radiance(&mut self, measure: Option<Measurement>) -> Result<()> {
        let method = self.renderer.radiance_pixels()?;
        match measure {
            Some(Measurement::Now) => {
                let t0 = Instant::now();
                self.live.measure(&method, self.view.exposure)?;
                self.metrics_s = t0.elapsed().as_secs_f64();
                self.metrics_at = Some(Instant::now());
                self.switched = false;
            }
            Some(Measurement::Background) if self.live.measure_in_background(&method, self.view.exposure) => {
                self.metrics_at = Some(Instant::now());
            }
            _ => {}
        }
        let reference = self.live.image.as_ref().map(|i| &i.mean);
        let settings = if reference.is_none() && self.view.view != View::Method {
            // No reference yet: the method is what there is to show.
            ViewSettings {
                view: View::Method,
                ..self.view
            }
        } else {
            self.view
        };
        let composed = crate::commands::views::compose(&method, reference, &settings)?;
        if let Some(p) = self.save_view.take() {
            let exr = crate::commands::views::save(&composed, &p)?;
            crate::outln!(
                "saved {} and {} ({} view)",
                p.display(),
                exr.display(),
                settings.view.name()
            );
        }
        self.composed = Some(composed);
        self.method_image = Some(method);
        Ok(())
    }

    fn record(&mut self, interval: f64, reference_s: f64, presented: bool) {
        let t = self.renderer.targets;
        self.report.push(FrameRecord {
            frame: self.frames,
            configuration: self.renderer.configuration.name.clone(),
            method_box: self.method_label(),
            parameters: parameters(&self.renderer.configuration),
            baking: self.rebake.as_ref().map(|r| r.status.clone()),
            bake_note: self.bake_note.clone(),
            messages: self.messages.clone(),
            animation_frame: self.renderer.clock_frame(),
            paused: self.renderer.clock_paused,
            view: self.view.view,
            spp: self.live.spp(),
            restarts: self.live.restarts,
            error: if self.live_on { self.live.error.clone() } else { None },
            presented,
            frame_ms: interval * 1000.0,
            reference_ms: reference_s * 1000.0,
            width: t.width,
            height: t.height,
            scale_factor: self.scale_factor,
            pointer: self.egui.input(|i| i.pointer.latest_pos()).map(|p| [p.x, p.y]),
        });
    }

    /// Saves the last grabbed presented frame.
    /// What the panel's method box shows.
    fn method_label(&self) -> String {
        panel::method_label(
            self.configurations.get(self.current).map(|c| c.name.as_str()),
            &self.renderer.configuration.name,
            self.rebake.as_ref().map(|r| &r.status),
        )
    }

    fn save_grab(&mut self, path: &std::path::Path) -> Result<()> {
        let image = self
            .grabbed
            .take()
            .ok_or_else(|| Error::Internal("no frame was grabbed".into()))?;
        Ok(crate::util::image_io::save_image(
            path,
            image.into(),
            image::ImageFormat::Png,
        )?)
    }
}

/// The key a script names: a letter, a digit, `F1`…`F12`, or `Escape`, `Plus`, `Minus`, `[`, `]`.
fn key_code(name: &str) -> Option<KeyCode> {
    let letters = [
        KeyCode::KeyA,
        KeyCode::KeyB,
        KeyCode::KeyC,
        KeyCode::KeyD,
        KeyCode::KeyE,
        KeyCode::KeyF,
        KeyCode::KeyG,
        KeyCode::KeyH,
        KeyCode::KeyI,
        KeyCode::KeyJ,
        KeyCode::KeyK,
        KeyCode::KeyL,
        KeyCode::KeyM,
        KeyCode::KeyN,
        KeyCode::KeyO,
        KeyCode::KeyP,
        KeyCode::KeyQ,
        KeyCode::KeyR,
        KeyCode::KeyS,
        KeyCode::KeyT,
        KeyCode::KeyU,
        KeyCode::KeyV,
        KeyCode::KeyW,
        KeyCode::KeyX,
        KeyCode::KeyY,
        KeyCode::KeyZ,
    ];
    let digits = [
        KeyCode::Digit0,
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
        KeyCode::Digit5,
        KeyCode::Digit6,
        KeyCode::Digit7,
        KeyCode::Digit8,
        KeyCode::Digit9,
    ];
    let c: Vec<char> = name.chars().collect();
    match (c.as_slice(), name) {
        ([l], _) if l.is_ascii_alphabetic() => letters.get((l.to_ascii_uppercase() as u8 - b'A') as usize).copied(),
        ([d], _) if d.is_ascii_digit() => digits.get((*d as u8 - b'0') as usize).copied(),
        (_, "F1") => Some(KeyCode::F1),
        (_, "F12") => Some(KeyCode::F12),
        (_, "Escape") => Some(KeyCode::Escape),
        (_, "Plus") => Some(KeyCode::Equal),
        (_, "Minus") => Some(KeyCode::Minus),
        (_, "[") => Some(KeyCode::BracketLeft),
        (_, "]") => Some(KeyCode::BracketRight),
        _ => None,
    }
}

impl App {
    /// Before frame N: the script's events and the old scripted options.
    fn before_frame(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let Some(s) = self.state.as_mut() else { return Ok(()) };
        let window = s.window.id();
        if let Some(script) = &self.script.script {
            let due: Vec<Event> = script.due(s.frames).cloned().collect();
            for e in &due {
                let Some(s) = self.state.as_mut() else { return Ok(()) };
                match e {
                    // What the window system sends when the window is minimised and restored
                    // (Wayland, Windows), through the handler it reaches.
                    Event::Minimise => self.window_event(el, window, WindowEvent::Resized(PhysicalSize::new(0, 0))),
                    Event::Restore => {
                        let size = s.window.inner_size();
                        self.window_event(el, window, WindowEvent::Resized(size));
                    }
                    _ => s.scripted_event(el, e)?,
                }
            }
        }
        let Some(s) = self.state.as_mut() else { return Ok(()) };
        // With --frames N --screenshot, the last frame is the one grabbed.
        if self.script.screenshot.is_some() && self.script.frames.is_some_and(|n| s.frames + 1 >= n) {
            s.grab_next = true;
        }
        Ok(())
    }

    fn after_frame(&mut self, el: &ActiveEventLoop) -> Result<()> {
        let Some(s) = self.state.as_mut() else { return Ok(()) };
        if s.grabbed.is_some() {
            let path = match (
                &self.script.screenshot,
                self.script.frames.is_some_and(|n| s.frames >= n),
            ) {
                (Some(p), true) => p.clone(),
                _ => {
                    s.screenshots += 1;
                    PathBuf::from(format!("penumbra-screenshot-{}.png", s.screenshots))
                }
            };
            s.save_grab(&path)?;
            crate::outln!("saved {} after {} frames", path.display(), s.frames);
        }
        if let Some((at, w, h)) = self.script.resize_at {
            if s.frames == at {
                // Applied at once (Some) or announced later by a Resized event.
                if s.window.request_inner_size(PhysicalSize::new(w, h)).is_some() {
                    s.recreate()?;
                }
            }
        }
        if self.script.cycle_every.is_some_and(|n| n > 0 && s.frames % n == 0) {
            s.next_configuration();
        }
        // A scripted run ends with the configuration it asked for: not while a bake runs.
        let settled = s.rebake.is_none() && s.queued.is_none();
        if settled && self.script.frames.is_some_and(|n| s.frames >= n) {
            el.exit();
        } else if !s.minimised || s.scripted {
            // A minimised window waits for the resize that restores it (scripts go on).
            s.window.request_redraw();
        }
        Ok(())
    }

    fn input(s: &mut Running, el: &ActiveEventLoop, event: &WindowEvent) {
        match event {
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = *state == ElementState::Pressed;
                let split = s.view.view == View::Split;
                match button {
                    MouseButton::Left if split => s.dragging_divider = pressed,
                    MouseButton::Left | MouseButton::Right => s.looking = pressed,
                    _ => {}
                }
                if pressed && s.dragging_divider {
                    s.view.split = (s.cursor_x / s.window.inner_size().width.max(1) as f64) as f32;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                s.cursor_x = position.x;
                if s.dragging_divider {
                    s.view.split = (position.x / s.window.inner_size().width.max(1) as f64).clamp(0.0, 1.0) as f32;
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    if event.state == ElementState::Pressed {
                        s.keys.insert(code);
                        if !event.repeat {
                            s.key(el, code);
                        }
                    } else {
                        s.keys.remove(&code);
                    }
                }
            }
            _ => {}
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.state.is_none() {
            match self.start(el) {
                Ok(s) => {
                    s.window.request_redraw();
                    self.state = Some(s);
                }
                Err(e) => self.fail(el, e),
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let result: Result<()> = (|| {
            let Some(s) = self.state.as_mut() else { return Ok(()) };
            let consumed = match event {
                // egui takes the pointer to points by the window's factor: given it rescaled so
                // that the current factor applies.
                WindowEvent::CursorMoved { device_id, position } => {
                    let stale = s.window.scale_factor() / s.scale_factor;
                    let position = PhysicalPosition::new(position.x * stale, position.y * stale);
                    let moved = WindowEvent::CursorMoved { device_id, position };
                    s.egui_input.on_window_event(&s.window, &moved).consumed
                }
                _ => s.egui_input.on_window_event(&s.window, &event).consumed,
            };
            match event {
                WindowEvent::CloseRequested => el.exit(),
                WindowEvent::ScaleFactorChanged { scale_factor, .. } => s.scale_factor = scale_factor,
                // A DPI change arrives as a resize too: the swapchain follows the window. A
                // minimised window is resized to nothing (on Wayland and Windows).
                WindowEvent::Resized(size) => {
                    s.minimised = size.width == 0 || size.height == 0;
                    s.recreate()?;
                    s.window.request_redraw();
                }
                WindowEvent::RedrawRequested => {
                    self.before_frame(el)?;
                    if let Some(s) = self.state.as_mut() {
                        s.frame()?;
                    }
                    self.after_frame(el)?;
                }
                ref e if !consumed => App::input(s, el, e),
                _ => {}
            }
            Ok(())
        })();
        if let Err(e) = result {
            self.fail(el, e);
        }
    }

    fn device_event(&mut self, _el: &ActiveEventLoop, _id: DeviceId, event: DeviceEvent) {
        if let (Some(s), DeviceEvent::MouseMotion { delta }) = (self.state.as_mut(), event) {
            if s.looking && !s.egui.egui_wants_pointer_input() {
                s.camera.look(delta.0 as f32, delta.1 as f32);
            }
        }
    }
}

/// Runs the window until Esc, the close button, or `max_frames`.
pub fn run(opts: &CaptureOptions, script: DemoScript) -> Result<()> {
    let event_loop = EventLoop::new().map_err(|e| Error::Usage(format!("cannot connect to a display: {e}")))?;
    let report_json = script.report_json.clone();
    let mut app = App {
        opts: opts.clone(),
        script,
        state: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Usage(format!("event loop: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if let Some(mut s) = app.state.take() {
        s.renderer.gpu.wait_idle()?;
        // Quitting stops a bake still running (scripted runs end only once it has).
        if let Some(rebake::Outcome::Baked {
            validation_messages, ..
        }) = s.rebake.take().map(|mut r| {
            r.cancel();
            r.wait()
        }) {
            s.bake_validation += validation_messages;
        }
        let n = s.renderer.gpu.validation_log().count() + s.live.validation_messages() + s.bake_validation;
        if let Some(p) = &report_json {
            let text = serde_json::to_string_pretty(&s.report).map_err(|e| Error::Usage(e.to_string()))?;
            crate::util::image_io::write_file(p, text.as_bytes())
                .map_err(|e| Error::Usage(format!("{}: {e}", p.display())))?;
        }
        let Running {
            renderer,
            swapchain,
            overlay,
            view_texture,
            ..
        } = s;
        // egui's objects go before the device they were made on.
        drop(view_texture);
        drop(overlay);
        let mut renderer = renderer;
        renderer.gpu.destroy_swapchain(swapchain);
        if n > 0 {
            return Err(Error::Validation(n));
        }
    }
    Ok(())
}
