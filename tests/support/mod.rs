//! Shared by the integration tests (each test binary declares `mod support;`): every GPU test
//! runs on lavapipe (or PENUMBRA_TEST_DEVICE) with the Khronos validation layer and
//! synchronization validation, and fails on any message.
#![allow(dead_code)]

use penumbra::backend::{Gpu, GpuDesc};

pub mod crash_report;
pub mod heightfield;
pub mod reference;
pub mod rng;
pub mod shadow_volumes;
#[path = "../../src/util/test_files.rs"]
pub mod test_files;

pub fn test_gpu_desc() -> GpuDesc {
    crash_report::install();
    GpuDesc {
        validation: true,
        device_name: Some(std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into())),
        display: None,
    }
}

pub fn test_gpu() -> Gpu {
    Gpu::new(&test_gpu_desc()).expect("create a validated Vulkan device (is lavapipe installed? run tools/setup.sh)")
}

/// Fails the test if the validation layer reported anything.
pub fn assert_clean(gpu: &Gpu) {
    let messages = gpu.validation_log().take();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages.join("\n")
    );
}

/// A deterministic xorshift64 stream in [0, 1) (53 bits) for test geometry.
pub fn xorshift(seed: u64) -> impl FnMut() -> f64 {
    let mut rng = rng::XorShift(seed);
    move || rng.next_f64()
}

/// `name` in this test process's directory under the system temp dir (the same path for the
/// same name; nothing is made there). The directory goes when the process exits, its tests passed
/// or failed, unless `PENUMBRA_KEEP_TEST_FILES` is set.
pub fn temp_path(name: &str) -> std::path::PathBuf {
    static DIR: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    DIR.get_or_init(|| {
        let dir = process_temp_dir();
        std::fs::create_dir_all(&dir).expect("make the tests' temp dir");
        if std::env::var_os("PENUMBRA_KEEP_TEST_FILES").is_some() {
            eprintln!("test files kept in {}", dir.display());
        } else {
            // The test harness ends through the C library's `exit` (returning from `main`, or
            // `process::exit(101)` after a failure), which runs the `atexit` handlers; Rust runs
            // no destructor for a static.
            // SAFETY: `atexit` only records the pointer to a function that cannot unwind.
            unsafe { libc::atexit(remove_process_temp_dir) };
        }
        dir
    })
    .join(name)
}

/// Bakes the tests make go to this process's temp dir, not `./.penumbra-cache` in the crate's
/// folder (the bake stage's default): a bake left there by an earlier run would stand in for the
/// one a test means to check, and the folder grew by megabytes a run. It runs from the binary's
/// constructors, before `main` starts the test threads, so setting the variable races with no
/// reader; child `penumbra` processes inherit it, and a test that sets its own cache keeps it.
#[used]
#[link_section = ".init_array"]
static ISOLATE_BAKES: extern "C" fn() = isolate_bakes;

extern "C" fn isolate_bakes() {
    if std::env::var_os("PENUMBRA_CACHE").is_none() {
        std::env::set_var("PENUMBRA_CACHE", temp_path("bake-cache"));
    }
}

fn process_temp_dir() -> std::path::PathBuf {
    std::env::temp_dir().join(format!("penumbra-tests-{}", std::process::id()))
}

extern "C" fn remove_process_temp_dir() {
    let _ = std::fs::remove_dir_all(process_temp_dir());
}

/// Records `graph` into `frame` with fresh resource states, submits it and waits.
pub fn run_once(gpu: &Gpu, frame: penumbra::backend::Frame, graph: penumbra::graph::RenderGraph<'_>) {
    let mut states = penumbra::graph::ResourceStates::default();
    let mut rec = gpu.begin_frame(frame).unwrap();
    graph.execute(&mut rec, &mut states).unwrap();
    rec.finish().unwrap();
    gpu.submit_and_wait(frame).unwrap();
}

/// Runs the `penumbra` binary as a user would: validation on, the test device chosen (`compare`
/// takes no device).
pub fn penumbra(args: &[&str]) -> std::process::Output {
    let device = std::env::var("PENUMBRA_TEST_DEVICE").unwrap_or_else(|_| "llvmpipe".into());
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_penumbra"));
    cmd.args(args).env("PENUMBRA_VALIDATION", "1");
    if args.first() != Some(&"compare") {
        cmd.args(["--device", &device]);
    }
    cmd.output().expect("run penumbra")
}

/// The command's standard output, failing the test with its standard error if it failed.
pub fn ok(o: &std::process::Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Scenes the frame tests share (tests/methods/sh_lightmap_frame.rs, tests/methods/prt_frame.rs). `METHOD` is
/// the method declaration; `FLOOR_CELLS` and `WALL_CELLS` the quads' subdivisions (per-vertex
/// methods need vertices where the light-map methods need none). Replace them with
/// [`scene_text`].
pub mod scenes {
    /// An open box, 2 × 1 × 2, under a constant sky of radiance 1, seen from above: its floor's
    /// centre sees the sky through the opening with view factor 0.554126.
    pub const OPEN_BOX: &str = r#"
methods = [METHOD]

[camera]
position = [0.125, 3.0, 0.6]
target = [0.125, 0.0, 0.125]
fov_y_deg = 40

[environment]
type = "constant"
radiance = 1.0

[[materials]]
name = "grey"
albedo = 0.5

[[objects]]
name = "floor"
mesh = "quad"
corner = [-0.875, 0, -0.875]
edge_u = [0, 0, 2]
edge_v = [2, 0, 0]
subdivisions = FLOOR_CELLS
material = "grey"

[[objects]]
name = "wall -x"
mesh = "quad"
corner = [-0.875, 0, -0.875]
edge_u = [0, 1, 0]
edge_v = [0, 0, 2]
subdivisions = WALL_CELLS
material = "grey"

[[objects]]
name = "wall +x"
mesh = "quad"
corner = [1.125, 0, -0.875]
edge_u = [0, 0, 2]
edge_v = [0, 1, 0]
subdivisions = WALL_CELLS
material = "grey"

[[objects]]
name = "wall -z"
mesh = "quad"
corner = [-0.875, 0, -0.875]
edge_u = [2, 0, 0]
edge_v = [0, 1, 0]
subdivisions = WALL_CELLS
material = "grey"

[[objects]]
name = "wall +z"
mesh = "quad"
corner = [-0.875, 0, 1.125]
edge_u = [0, 1, 0]
edge_v = [2, 0, 0]
subdivisions = WALL_CELLS
material = "grey"
"#;

    /// A 2 × 2 wall facing +z, lit by a sun along −z of irradiance 2, ρ = 0.5.
    pub const WALL: &str = r#"
methods = [METHOD]

[camera]
position = [0.0, 1.0, 3.0]
target = [0.0, 1.0, 0.0]
fov_y_deg = 40

[[lights]]
name = "sun"
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = 2.0

[[materials]]
name = "grey"
albedo = 0.5

[[objects]]
name = "wall"
mesh = "quad"
corner = [-1, 0, 0]
edge_u = [2, 0, 0]
edge_v = [0, 2, 0]
subdivisions = WALL_CELLS
material = "grey"
"#;

    /// `template` with the method and the subdivisions filled in.
    pub fn scene_text(template: &str, method: &str, floor_cells: u32, wall_cells: u32) -> String {
        template
            .replace("METHOD", method)
            .replace("FLOOR_CELLS", &floor_cells.to_string())
            .replace("WALL_CELLS", &wall_cells.to_string())
    }
}

/// The device for timings: `PENUMBRA_MEASURE_DEVICE` (else the test device), without the
/// validation layer, whose checks would be timed too.
pub fn measure_gpu() -> Gpu {
    let name = std::env::var("PENUMBRA_MEASURE_DEVICE")
        .or_else(|_| std::env::var("PENUMBRA_TEST_DEVICE"))
        .unwrap_or_else(|_| "llvmpipe".into());
    Gpu::new(&GpuDesc {
        validation: false,
        device_name: Some(name),
        display: None,
    })
    .expect("create the measurement device")
}

/// A comma-separated list of numbers from the environment variable `var`, else `default`.
pub fn env_list<T: std::str::FromStr + Clone>(var: &str, default: &[T]) -> Vec<T> {
    match std::env::var(var) {
        Ok(v) => v
            .split(',')
            .map(|s| {
                s.trim()
                    .parse()
                    .unwrap_or_else(|_| panic!("{var}: {s:?} is not a number"))
            })
            .collect(),
        Err(_) => default.to_vec(),
    }
}

/// What a lighting method needs to be created outside the renderer (on a validated test device):
/// the scene uploaded, its environment and a bake cache that stores nothing. `context` lends
/// them to a method's constructor; the device and resource states stay for the test's passes.
pub struct MethodFixture {
    pub gpu: Gpu,
    pub states: penumbra::graph::ResourceStates,
    pub environment: penumbra::environment::EnvironmentMap,
    pub scene_gpu: penumbra::gpu_scene::SceneGpu,
    pub bakes: penumbra::bake::Baker,
}

static EMBEDDED_SHADERS: penumbra::shaders::ShaderLibrary = penumbra::shaders::ShaderLibrary::Embedded;

impl MethodFixture {
    pub fn new(scene: &penumbra::scene::Scene) -> MethodFixture {
        let mut gpu = test_gpu();
        let mut states = penumbra::graph::ResourceStates::default();
        let environment = penumbra::environment::EnvironmentMap::of_scene(scene).unwrap();
        let scene_gpu = penumbra::gpu_scene::SceneGpu::upload(&mut gpu, &mut states, scene, &environment).unwrap();
        MethodFixture {
            gpu,
            states,
            environment,
            scene_gpu,
            bakes: penumbra::bake::Baker::new(None),
        }
    }

    /// A method's creation context for `scene` drawing `terms`.
    pub fn context<'a>(
        &'a mut self,
        scene: &'a penumbra::scene::Scene,
        terms: penumbra::lighting::Terms,
    ) -> penumbra::lighting::CreateContext<'a> {
        penumbra::lighting::CreateContext {
            gpu: &mut self.gpu,
            shaders: &EMBEDDED_SHADERS,
            states: &mut self.states,
            scene,
            scene_gpu: &self.scene_gpu,
            environment: &self.environment,
            bakes: &mut self.bakes,
            terms,
            frames: 0,
        }
    }
}
