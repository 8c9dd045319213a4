//! Scenes: the TOML scene format (documented in `scenes/README.md`), its parser, procedural
//! meshes and OBJ loading. Pure CPU code.
//!
//! ```text
//! let scene = Scene::from_file("scenes/cornell.toml")?;      // or Scene::default_scene()
//! scene.check_methods(&renderer_method_schemas)?;          // names, parameters, types
//! for object in &scene.objects {
//!     let mesh = object.load_mesh(Path::new("."))?;         // object space
//!     let world = mesh.transformed(&object.transform);     // or transform on the GPU
//! }
//! ```
//!
//! Conventions: right-handed world, y up, metres, linear RGB, radiometric units (W/sr, W/m²,
//! W/(m²·sr)). Every error is a [`SceneError`] naming file, line and field on one line.

pub(crate) mod asset;
mod cornell;
mod doc;
mod error;
mod format;
pub mod generate;
pub mod generators;
pub(crate) mod heightfield;
mod mesh;
mod methods;
pub(crate) mod motion;
mod obj;
#[cfg(test)]
mod tests;
mod types;
pub mod world_mesh;

use std::path::Path;

pub use cornell::{builtin_material, BUILTIN_MATERIALS};
pub use error::SceneError;
pub use heightfield::{HeightImage, HeightShape, HeightfieldSource};
pub use mesh::Mesh;
pub use methods::{CombinationDecl, MethodDecl, MethodSchema, ParamKind, ParamSchema};
pub use obj::load_obj;
pub use types::{
    Animation, Camera, CubeFaces, Environment, Light, LightBoard, Material, MeshSource, Object, CUBE_FACE_KEYS,
};

/// The name a scene is known by in error messages: the path it was read from, or
/// [`DEFAULT_SOURCE`].
pub type SourceName = String;

/// Source name of [`Scene::default_scene`].
pub const DEFAULT_SOURCE: &str = "<built-in default>";

/// The built-in default scene's TOML text (also shipped as `scenes/default.toml`).
pub const DEFAULT_SCENE_TOML: &str = include_str!("default.toml");

/// Settings the command line puts over a scene file's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SceneOverrides {
    /// One of the cameras the scene's assets carry ([`Scene::choose_camera`]).
    pub camera: Option<usize>,
    /// The memory budget in MB, over the scene's `memory_budget_mb`.
    pub memory_budget_mb: Option<f64>,
}

impl SceneOverrides {
    /// Puts the overrides over `scene`'s own settings.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), SceneError> {
        if let Some(i) = self.camera {
            scene.choose_camera(i)?;
        }
        if let Some(mb) = self.memory_budget_mb {
            scene.memory_budget_mb = Some(mb);
        }
        Ok(())
    }
}

/// A checked scene. File paths inside it (OBJ meshes, textures, environment maps) are absolute
/// and were verified to exist when it was parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub source: SourceName,
    pub camera: Camera,
    /// The cameras the scene's assets carry, placed as their objects are: what `--camera N`
    /// chooses from ([`Scene::choose_camera`]). Empty when no asset carries one.
    pub cameras: Vec<Camera>,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    pub lights: Vec<Light>,
    pub environment: Option<Environment>,
    /// Requested lighting methods in file order; `[forward]` (line 0) when the file names none.
    pub methods: Vec<MethodDecl>,
    /// Combinations of the methods' terms (`[[combinations]]`), in file order; checked against
    /// what each method supplies by the lighting layer.
    pub combinations: Vec<CombinationDecl>,
    /// Per-frame intensity factors of the point and spot lights (`[light_board]`); none: static.
    pub light_board: Option<LightBoard>,
    /// A directional light turning per frame (`[light_motion]`); none: static.
    pub light_motion: Option<motion::LightMotion>,
    /// What a method may allocate for its bake and volumes (`memory_budget_mb`); none: the
    /// default budget.
    pub memory_budget_mb: Option<f64>,
}

impl Scene {
    /// One line for a bad value of a method's parameter: the scene file, the parameter's line and
    /// `methods[i].name` (what every method's parameter checks report).
    pub fn method_param_error(&self, decl: &MethodDecl, name: &str, message: impl Into<String>) -> SceneError {
        // By the name's line, not by value: a declaration with derived or swept parameters set is
        // still the scene's.
        let index = self
            .methods
            .iter()
            .position(|m| m == decl)
            .or_else(|| {
                self.methods
                    .iter()
                    .position(|m| m.name == decl.name && m.line == decl.line)
            })
            .unwrap_or(0);
        let line = decl
            .params
            .iter()
            .find(|(n, _, _)| n == name)
            .map(|p| p.2)
            .filter(|&l| l > 0)
            // A parameter missing where another needs it: the method's own line.
            .or((decl.line > 0).then_some(decl.line));
        SceneError::new(&self.source, line, format!("methods[{index}].{name}"), message)
    }

    /// Makes the scene's camera its assets' camera `index` (counted over the assets in object
    /// order, each file's cameras in file order): the command line's `--camera N`.
    pub fn choose_camera(&mut self, index: usize) -> Result<(), SceneError> {
        let Some(camera) = self.cameras.get(index) else {
            let has = match self.cameras.len() {
                0 => "no asset of the scene carries a camera".to_owned(),
                1 => "the scene's assets carry 1 (--camera 0)".to_owned(),
                n => format!("the scene's assets carry {n} (--camera 0 to {})", n - 1),
            };
            return Err(SceneError::new(
                &self.source,
                None,
                "cameras",
                format!("--camera {index} asked for, {has}"),
            ));
        };
        self.camera = camera.clone();
        Ok(())
    }

    /// Reads and checks a scene file. Relative paths inside it are relative to its directory.
    /// Errors name the file as `path` was given. An asset file (`.obj`, `.gltf`, `.glb`) is a
    /// scene of its own (`asset::asset_scene`).
    pub fn from_file(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        if asset::is_asset_path(path) {
            return asset::asset_scene(path, None);
        }
        let source = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| SceneError::new(&source, None, "file", format!("cannot read: {e}")))?;
        let base_dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        Scene::from_str(&text, &source, base_dir)
    }

    /// Parses scene text. `source_name` is used in errors; relative paths in the text are
    /// resolved against `base_dir`.
    pub fn from_str(text: &str, source_name: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        format::parse(text, source_name, base_dir)
    }

    /// The built-in default scene: a ground plane, a box and a glossy sphere under a
    /// directional, a point and a spot light.
    pub fn default_scene() -> Scene {
        // The text is ours and a unit test parses it, so failure here is a build defect, not a
        // user error.
        Scene::from_str(DEFAULT_SCENE_TOML, DEFAULT_SOURCE, Path::new("."))
            .unwrap_or_else(|e| panic!("the built-in default scene is invalid: {e}"))
    }

    /// Checks every declared method and parameter against the renderer's `known` methods.
    /// Errors name the line and field (`methods[1]`, `methods[1].resolution`) and list the
    /// known alternatives.
    pub fn check_methods(&self, known: &[MethodSchema]) -> Result<(), SceneError> {
        methods::check(&self.source, &self.methods, known)
    }

    /// The first translucent material (opacity < 1) an object uses, with its index.
    pub fn translucent_material(&self) -> Option<(usize, &Material)> {
        self.objects
            .iter()
            .filter_map(|o| self.materials.get(o.material).map(|m| (o.material, m)))
            .find(|(_, m)| m.is_translucent())
    }

    /// Refuses translucent materials for a consumer (`who`) that draws opaque surfaces only:
    /// one line naming the file, the material and the field, so an image is never silently
    /// drawn as if the glass were opaque.
    pub fn refuse_translucency(&self, who: &str) -> Result<(), String> {
        match self.translucent_material() {
            None => Ok(()),
            Some((i, m)) => Err(format!(
                "{}: materials[{i}] ({}).opacity = {}: {who} draws opaque surfaces only (translucent materials are drawn by the forward and shadow_volumes methods and the reference path tracer)",
                self.source, m.name, m.opacity
            )),
        }
    }

    /// Each light's intensity factor at `time_s` (one per [`Scene::lights`], same order): the
    /// light board's f_l(t) for point and spot lights, 1 for the rest and for every light when
    /// the scene has no board. All 1 at `time_s = 0`.
    pub fn light_factors(&self, time_s: f32) -> Vec<f32> {
        self.lights
            .iter()
            .enumerate()
            .map(|(l, light)| match (&self.light_board, light) {
                (Some(board), Light::Point { .. } | Light::Spot { .. }) => board.factor(l, time_s),
                _ => 1.0,
            })
            .collect()
    }

    /// Whether anything moves per frame besides rigid entity animation: wind on an object, or a
    /// turning light (what methods that bake keep at the rest pose).
    pub fn has_motion(&self) -> bool {
        self.light_motion.is_some() || self.objects.iter().any(|o| o.wind.is_some())
    }

    /// What moves, for a method that keeps the rest pose to say so: "wind (objects\[1\] "bush")".
    pub fn motion_summary(&self) -> Option<String> {
        self.motion_summary_of(true)
    }

    /// [`Scene::motion_summary`], leaving out the light motion unless `light_motion`: for a
    /// method that keeps the rest pose of the objects but follows the turning light.
    pub fn motion_summary_of(&self, light_motion: bool) -> Option<String> {
        let mut parts: Vec<String> = self
            .objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.wind.is_some())
            .map(|(i, o)| format!("wind (objects[{i}] {:?})", o.name))
            .collect();
        if let Some(m) = self.light_motion.as_ref().filter(|_| light_motion) {
            parts.push(format!(
                "light_motion (lights[{}] {:?})",
                m.light,
                self.lights.get(m.light).map(|l| l.name()).unwrap_or("")
            ));
        }
        (!parts.is_empty()).then(|| parts.join(", "))
    }

    /// The scene's lights as the renderer's frame at `time_s` has them: [`Scene::light_motion`]
    /// turning its light, and the light board's factor on each point and spot light's intensity.
    pub fn lights_at(&self, time_s: f32) -> Vec<Light> {
        let mut lights = self.lights.clone();
        for (light, f) in lights.iter_mut().zip(self.light_factors(time_s)) {
            if let Light::Point { intensity, .. } | Light::Spot { intensity, .. } = light {
                *intensity *= f;
            }
        }
        if let Some(m) = &self.light_motion {
            if let Some(Light::Directional { direction, .. }) = lights.get_mut(m.light) {
                *direction = m.direction_at(*direction, time_s);
            }
        }
        lights
    }

    /// `object`'s object-space mesh at `time_s` with its wind applied (`mesh` as loaded).
    pub fn wind_mesh(&self, object: &Object, mut mesh: Mesh, time_s: f32) -> Result<Mesh, SceneError> {
        if let Some(wind) = &object.wind {
            let map = self.material_of(object).and_then(|m| m.albedo_map.as_deref());
            let weights = motion::wind_weights(&mesh, map).map_err(|e| {
                SceneError::new(
                    &self.source,
                    None,
                    format!("object {:?}: wind: albedo_map", object.name),
                    e,
                )
            })?;
            wind.deform(&mut mesh, &weights, time_s);
        }
        Ok(mesh)
    }

    /// The material of `object` (`None` only for a hand-built object with a bad index).
    pub fn material_of(&self, object: &Object) -> Option<&Material> {
        self.materials.get(object.material)
    }
}

impl Object {
    /// The object's mesh in object space (apply [`Object::transform`] to place it), with
    /// normals, uvs and tangents. A relative OBJ path is resolved against `base_dir`; paths in a
    /// parsed [`Scene`] are already absolute, so any `base_dir` works for them.
    pub fn load_mesh(&self, base_dir: &Path) -> Result<Mesh, SceneError> {
        let mesh = match &self.mesh {
            MeshSource::Obj(path) => return load_obj(&base_dir.join(path)),
            MeshSource::Asset { mesh, .. } => return Ok((**mesh).clone()),
            MeshSource::Plane { size, subdivisions } => generators::plane(*size, *subdivisions),
            MeshSource::Quad {
                corner,
                edge_u,
                edge_v,
                subdivisions,
            } => generators::quad(*corner, *edge_u, *edge_v, *subdivisions),
            MeshSource::Box { size, subdivisions } => generators::cuboid(*size, *subdivisions),
            MeshSource::Sphere {
                radius,
                segments,
                rings,
            } => generators::sphere(*radius, *segments, *rings),
            MeshSource::Bush {
                leaves,
                seed,
                radius,
                height,
                leaf_size,
            } => generators::bush(*leaves, *seed, *radius, *height, *leaf_size),
            MeshSource::World { level, class } => {
                let world = world_mesh::compiled(level).map_err(|e| {
                    SceneError::new(
                        format!("object {:?}", self.name),
                        None,
                        level.mesh_name(),
                        format!("the world does not compile: {e}"),
                    )
                })?;
                world_mesh::class_mesh(&world, *class).0
            }
            MeshSource::Heightfield(h) => h.mesh()?,
        };
        // Generators only meet non-finite input from hand-built MeshSources.
        mesh.validate(&format!("object {:?}", self.name))?;
        Ok(mesh)
    }
}
