//! `penumbra demo`: the scene in a window with a fly camera and live GPU pass times.

use std::collections::HashSet;
use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{DeviceEvent, DeviceId, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::backend::{vk, Gpu, Swapchain};
use crate::commands::capture::{load_scene, CaptureOptions};
use crate::error::{Error, Result};
use crate::renderer::{FrameOutput, Renderer};
use crate::scene::Camera;

const FRAMES_IN_FLIGHT: usize = 2;

/// A fly camera: position plus yaw/pitch, seeded from the scene's camera.
#[derive(Clone, Debug)]
pub struct FlyCamera {
    pub base: Camera,
    pub yaw: f32,
    pub pitch: f32,
}

impl FlyCamera {
    pub fn new(base: Camera) -> Self {
        let d = (base.target - base.position).normalize_or(Vec3::NEG_Z);
        FlyCamera {
            yaw: d.x.atan2(-d.z),
            pitch: d.y.clamp(-1.0, 1.0).asin(),
            base,
        }
    }
    pub fn forward(&self) -> Vec3 {
        Vec3::new(
            self.yaw.sin() * self.pitch.cos(),
            self.pitch.sin(),
            -self.yaw.cos() * self.pitch.cos(),
        )
    }
    pub fn camera(&self) -> Camera {
        let mut c = self.base.clone();
        c.target = c.position + self.forward();
        c.up = Vec3::Y;
        c
    }
    pub fn look(&mut self, dx: f32, dy: f32) {
        self.yaw += dx * 0.003;
        self.pitch = (self.pitch - dy * 0.003).clamp(-1.5, 1.5);
    }
    pub fn fly(&mut self, keys: &HashSet<KeyCode>, dt: f32) {
        let f = self.forward();
        let right = f.cross(Vec3::Y).normalize_or_zero();
        let mut v = Vec3::ZERO;
        for (k, d) in [
            (KeyCode::KeyW, f),
            (KeyCode::KeyS, -f),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
        ] {
            if keys.contains(&k) {
                v += d;
            }
        }
        let speed = if keys.contains(&KeyCode::ShiftLeft) { 8.0 } else { 2.0 };
        self.base.position += v.normalize_or_zero() * speed * dt;
    }
}

struct Running {
    window: Window,
    renderer: Renderer,
    swapchain: Swapchain,
    camera: FlyCamera,
    keys: HashSet<KeyCode>,
    looking: bool,
    last: Instant,
    title_at: Instant,
    frames: u64,
    screenshots: u32,
    /// Copy the next presented frame back (F12, or the last frame with --screenshot).
    grab_next: bool,
    grabbed: Option<image::RgbaImage>,
    /// The scene's methods and combinations (M cycles through them) and the one shown.
    configurations: Vec<crate::lighting::Configuration>,
    current: usize,
}

impl Running {
    /// Switches to the next of the scene's configurations; a failure is printed and the current
    /// one keeps running.
    fn next_configuration(&mut self) {
        if self.configurations.len() < 2 {
            return;
        }
        let next = (self.current + 1) % self.configurations.len();
        match self.renderer.set_configuration(self.configurations[next].clone()) {
            Ok(()) => {
                self.current = next;
                crate::outln!("configuration: {}", self.configurations[next].name);
            }
            Err(e) => crate::errln!("cannot switch to {}: {e}", self.configurations[next].name),
        }
    }
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
}

struct App {
    opts: CaptureOptions,
    max_frames: Option<u64>,
    screenshot: Option<PathBuf>,
    resize_at: Option<(u64, u32, u32)>,
    cycle_every: Option<u64>,
    state: Option<Running>,
    error: Option<Error>,
}

impl App {
    fn start(&mut self, el: &ActiveEventLoop) -> Result<Running> {
        let scene = load_scene(self.opts.scene.as_deref())?;
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
        let extent = swapchain.extent;
        let configurations = crate::lighting::registry::configurations(&scene)?;
        let renderer = Renderer::new(
            gpu,
            scene,
            self.opts.method.as_deref(),
            (extent.width, extent.height),
            FRAMES_IN_FLIGHT,
        )?;
        let current = configurations
            .iter()
            .position(|c| *c == renderer.configuration)
            .unwrap_or(0);
        let camera = FlyCamera::new(renderer.scene.camera.clone());
        Ok(Running {
            window,
            renderer,
            swapchain,
            camera,
            keys: HashSet::new(),
            looking: false,
            last: Instant::now(),
            title_at: Instant::now(),
            frames: 0,
            screenshots: 0,
            grab_next: false,
            grabbed: None,
            configurations,
            current,
        })
    }

    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        self.error.get_or_insert(e);
        el.exit();
    }
}

impl Running {
    fn recreate(&mut self) -> Result<()> {
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(());
        }
        self.renderer
            .gpu
            .recreate_swapchain(&mut self.swapchain, (size.width, size.height))?;
        let e = self.swapchain.extent;
        self.renderer.resize((e.width, e.height))?;
        Ok(())
    }

    /// Renders and presents one frame; returns false when the window is minimised.
    fn frame(&mut self) -> Result<bool> {
        let size = self.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(false);
        }
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32().min(0.1);
        self.last = now;
        self.camera.fly(&self.keys, dt);

        let slot = self.renderer.current_frame();
        // Waiting for the slot's previous frame also makes its acquire semaphore reusable.
        self.renderer.gpu.wait_frame(slot)?;
        if self.title_at.elapsed().as_secs_f32() > 0.5 {
            if let Some(t) = self.renderer.gpu.frame_timings(slot)? {
                let parts: Vec<String> = t.iter().map(|p| format!("{} {:.2} ms", p.name, p.ms)).collect();
                let methods = self.renderer.method_names().join(" + ");
                self.window.set_title(&format!(
                    "penumbra — {} ({methods}) — {}",
                    self.renderer.configuration.name,
                    parts.join(" | ")
                ));
            }
            self.title_at = Instant::now();
        }
        let Some(acquired) = self.renderer.gpu.acquire(&self.swapchain, self.frames as usize)? else {
            self.recreate()?;
            return Ok(true);
        };
        let wait_stage = vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT;
        self.renderer.states.acquired_image(acquired.image, wait_stage);
        let camera = self.camera.camera();
        let readback = self.grab_next;
        self.renderer.render(
            &camera,
            FrameOutput::Present {
                image: acquired.image,
                exposure: 1.0,
                readback,
            },
        )?;
        let gpu = &self.renderer.gpu;
        gpu.submit_frame(
            self.renderer.last_frame(),
            Some((acquired.acquired, wait_stage)),
            Some(acquired.rendered),
        )?;
        let presented = gpu.present(&self.swapchain, &acquired)?;
        if readback {
            gpu.wait_frame(self.renderer.last_frame())?;
            self.grabbed = Some(self.renderer.presented_pixels(acquired.image)?);
            self.grab_next = false;
        }
        if !presented {
            self.recreate()?;
        }
        self.frames += 1;
        Ok(true)
    }

    /// Saves the last grabbed presented frame.
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
        let Some(s) = self.state.as_mut() else { return };
        let result: Result<()> = (|| {
            match event {
                WindowEvent::CloseRequested => el.exit(),
                WindowEvent::Resized(_) => s.recreate()?,
                WindowEvent::MouseInput {
                    state,
                    button: MouseButton::Left | MouseButton::Right,
                    ..
                } => {
                    s.looking = state == ElementState::Pressed;
                }
                WindowEvent::KeyboardInput { event, .. } => {
                    if let PhysicalKey::Code(code) = event.physical_key {
                        if event.state == ElementState::Pressed {
                            s.keys.insert(code);
                            match code {
                                KeyCode::Escape => el.exit(),
                                // The next presented frame is copied back and saved.
                                KeyCode::F12 if !event.repeat => s.grab_next = true,
                                // The scene's next method or combination.
                                KeyCode::KeyM if !event.repeat => s.next_configuration(),
                                KeyCode::KeyR if !event.repeat => match s.renderer.reload_shaders() {
                                    Ok(n) => crate::outln!("reloaded {n} pipelines from glsl/"),
                                    // A broken shader is reported; the old pipelines keep running.
                                    Err(e) => crate::errln!("shader reload failed, keeping the old pipelines: {e}"),
                                },
                                _ => {}
                            }
                        } else {
                            s.keys.remove(&code);
                        }
                    }
                }
                WindowEvent::RedrawRequested => {
                    // With --frames N --screenshot, the last frame is the one grabbed.
                    if self.screenshot.is_some() && self.max_frames.is_some_and(|n| s.frames + 1 >= n) {
                        s.grab_next = true;
                    }
                    s.frame()?;
                    if s.grabbed.is_some() {
                        let path = match (&self.screenshot, self.max_frames.is_some_and(|n| s.frames >= n)) {
                            (Some(p), true) => p.clone(),
                            _ => {
                                s.screenshots += 1;
                                PathBuf::from(format!("penumbra-screenshot-{}.png", s.screenshots))
                            }
                        };
                        s.save_grab(&path)?;
                        crate::outln!("saved {} after {} frames", path.display(), s.frames);
                    }
                    if let Some((at, w, h)) = self.resize_at {
                        if s.frames == at {
                            // Applied at once (Some) or announced later by a Resized event.
                            if s.window.request_inner_size(PhysicalSize::new(w, h)).is_some() {
                                s.recreate()?;
                            }
                        }
                    }
                    if self.cycle_every.is_some_and(|n| n > 0 && s.frames % n == 0) {
                        s.next_configuration();
                    }
                    if self.max_frames.is_some_and(|n| s.frames >= n) {
                        el.exit();
                    } else {
                        s.window.request_redraw();
                    }
                }
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
            if s.looking {
                s.camera.look(delta.0 as f32, delta.1 as f32);
            }
        }
    }
}

/// Runs the window until Esc, the close button, or `max_frames`.
pub fn run(opts: &CaptureOptions, script: DemoScript) -> Result<()> {
    let DemoScript {
        frames: max_frames,
        screenshot,
        resize_at,
        cycle_every,
    } = script;
    let event_loop = EventLoop::new().map_err(|e| Error::Usage(format!("cannot connect to a display: {e}")))?;
    let mut app = App {
        opts: opts.clone(),
        max_frames,
        screenshot,
        resize_at,
        cycle_every,
        state: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Usage(format!("event loop: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if let Some(s) = app.state.take() {
        s.renderer.gpu.wait_idle()?;
        let n = s.renderer.gpu.validation_log().count();
        let Running {
            renderer, swapchain, ..
        } = s;
        let mut renderer = renderer;
        renderer.gpu.destroy_swapchain(swapchain);
        if n > 0 {
            return Err(Error::Validation(n));
        }
    }
    Ok(())
}
