//! Virtualised light sources (Ridderhof 2002, digest §1.4): the scene's polygons cut into small
//! triangles ("segments"); at set-up each segment keeps the ≤ K lights it will ever shade with —
//! the closest (the thesis) or the most contributing that pass a shadow feeler from the segment's
//! centroid; at run time each segment sums only those lights, at their current intensities.
//!
//! The set-up is a bake (`setup`, cached through the bake stage). The run time is one graphics
//! pass: the segments drawn with unshared vertices carrying the segment's id (so a boundary
//! between different light sets shows, the thesis's Fig. 6-3), the fragment shader looping over
//! the segment's light indices with `glsl/common/many_lights.glsl`. Shadows are the feeler's
//! only: a blocked light is not in the set, an unblocked one lights the whole segment.
//!
//! Modes: `faithful` is the thesis — closest lights, its plane-and-polygon feeler, the OpenGL
//! fixed-function model (`1/(kc + kl·d + kq·d²)`, default `1/(1 + d²)`: the thesis gives no
//! constants); `corrected` ranks by potential contribution, casts feelers over the BVH and
//! shades with the physical model, so its frames are radiance and compare with the reference.
//! Every choice is a parameter of its own as well.

pub(crate) mod setup;

#[cfg(test)]
mod tests;

use glam::DVec3;

use crate::backend::{vk, Bind, BufferId, PipelineId, SpecConstant, VertexAttribute, VertexLayout};
use crate::bake::BakeKey;
use crate::error::{Error, Result};
use crate::graph::{Access, RenderGraph};
use crate::lighting::many_lights::{scene_polygons, LightModel, ManyLight, Occluders, ScenePolygon, Segments};
use crate::lighting::params::Params;
use crate::lighting::{
    begin_term_rendering, term_pass, term_pipeline_desc, CreateContext, FrameContext, LightingMethod, Term, Terms,
};
use crate::scene::{MethodDecl, MethodSchema, ParamKind, ParamSchema, Scene};
use setup::{Feeler, LightSets, Point, Selection, SetupParams};

pub const NAME: &str = "vls";

pub const SCHEMA: MethodSchema = MethodSchema {
    name: NAME,
    params: &[
        ParamSchema {
            name: "mode",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "k",
            kind: ParamKind::Int,
        },
        ParamSchema {
            name: "selection",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "can_illuminate",
            kind: ParamKind::Bool,
        },
        ParamSchema {
            name: "feeler",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "max_segment_area",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "point",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "model",
            kind: ParamKind::String,
        },
        ParamSchema {
            name: "seed_k",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "kc",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "kl",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "kq",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "ambient",
            kind: ParamKind::Float,
        },
        ParamSchema {
            name: "light_ambient",
            kind: ParamKind::Float,
        },
    ],
};

/// The most lights a segment keeps: the shader's loop and the index buffer grow with it.
pub const MAX_K: i64 = 32;

/// Bumped whenever the set-up's output for the same inputs changes.
const SETUP_VERSION: u32 = 4;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Faithful,
    Corrected,
}

/// Bytes the set-up holds per segment: its vertices' positions, normals and polygons, its
/// triangle and polygon, and `k` light indices.
fn bytes_per_segment(k: usize) -> u64 {
    (24 + 24 + 4 + 12 + 4 + 4 * k) as u64
}

/// `max_segment_area` from the scene's area and the segment budget when unset; the set-up
/// refused when its segments would not fit the memory budget.
pub fn plan(
    decl: &MethodDecl,
    facts: &crate::lighting::plan::Facts<'_>,
) -> Result<Vec<crate::lighting::plan::Derived>> {
    use crate::lighting::plan::{round2, segments_for, Derived, SEGMENT_BUDGET};
    let mut config = Config::from_decl_in(decl, Some(facts.scene))?;
    let mut derived = Vec::new();
    let area = facts.area(NAME)?;
    if decl.param("max_segment_area").is_none() && area > 0.0 {
        config.max_segment_area = round2(area / SEGMENT_BUDGET);
        derived.push(Derived::new(
            "max_segment_area",
            config.max_segment_area,
            format!(
                "the scene's {} m² over a budget of {SEGMENT_BUDGET} segments",
                crate::lighting::plan::area_text(area)
            ),
        ));
    }
    if decl.param("k").is_none() && config.mode == Mode::Corrected {
        let lights = ManyLight::from_scene(facts.scene, NAME)?.len();
        config.setup.k = lights.clamp(1, MAX_K as usize);
        derived.push(Derived::new(
            "k",
            config.setup.k as i64,
            format!(
                "every one of the scene's {lights} lights a point can keep, at most {MAX_K}; the sets then \
                 shrink to the most lights any point keeps"
            ),
        ));
    }
    let segments = segments_for(facts.triangles(NAME)?, config.max_segment_area);
    facts.check(
        NAME,
        &format!(
            "{segments} segments at max_segment_area = {} with {} lights each",
            config.max_segment_area, config.setup.k
        ),
        segments * bytes_per_segment(config.setup.k),
        "set a larger max_segment_area",
    )?;
    Ok(derived)
}

/// The method's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    pub mode: Mode,
    pub setup: SetupParams,
    /// World units²: segments are no larger.
    pub max_segment_area: f64,
    /// The fixed-function model's global ambient (`GL_LIGHT_MODEL_AMBIENT`, default 0.2) and
    /// each light's ambient as a fraction of its intensity (`GL_AMBIENT`, default 0), both times
    /// the albedo; the other models have no ambient term.
    pub ambient: f64,
    pub light_ambient: f64,
}

impl Config {
    pub fn from_decl(decl: &MethodDecl) -> Result<Config> {
        Config::from_decl_in(decl, None)
    }

    /// The parameters of `decl`; a bad value is one line naming the scene file and parameter.
    // long: one parameter after another, each read and range-checked.
    pub fn from_decl_in(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let mode = params
            .get_choice("mode", &[("faithful", Mode::Faithful), ("corrected", Mode::Corrected)])?
            .unwrap_or(Mode::Corrected);
        let mut c = match mode {
            Mode::Faithful => Config {
                mode,
                setup: SetupParams {
                    k: 8,
                    selection: Selection::Closest,
                    can_illuminate: false,
                    feeler: Feeler::Thesis,
                    model: LightModel::OpenGl {
                        kc: 1.0,
                        kl: 0.0,
                        kq: 1.0,
                    },
                    point: Point::Centroid,
                },
                max_segment_area: 0.05,
                ambient: 0.2,
                light_ambient: 0.0,
            },
            Mode::Corrected => Config {
                mode,
                setup: SetupParams {
                    // The thesis's 8 is OpenGL's light count; a shader loop stops at the set's
                    // first empty slot, so a set as wide as the lights in reach costs only where
                    // they are.
                    k: MAX_K as usize,
                    selection: Selection::Contribution,
                    can_illuminate: true,
                    feeler: Feeler::Bvh,
                    model: LightModel::Physical,
                    point: Point::Centroid,
                },
                max_segment_area: 0.05,
                ambient: 0.2,
                light_ambient: 0.0,
            },
        };
        if let Some(v) = decl.param("k") {
            c.setup.k = v
                .as_integer()
                .filter(|k| (1..=MAX_K).contains(k))
                .ok_or_else(|| params.error("k", &format!("an integer from 1 to {MAX_K}"), v))?
                as usize;
        }
        if let Some(s) = params.get_choice(
            "selection",
            &[
                ("closest", Selection::Closest),
                ("contribution", Selection::Contribution),
            ],
        )? {
            c.setup.selection = s;
        }
        if let Some(v) = decl.param("can_illuminate") {
            c.setup.can_illuminate = v
                .as_bool()
                .ok_or_else(|| params.error("can_illuminate", "true or false", v))?;
        }
        if let Some(f) = params.get_choice(
            "feeler",
            &[("thesis", Feeler::Thesis), ("bvh", Feeler::Bvh), ("none", Feeler::None)],
        )? {
            c.setup.feeler = f;
        }
        if let Some(p) = params.get_choice("point", &[("centroid", Point::Centroid), ("vertex", Point::Vertex)])? {
            c.setup.point = p;
        }
        if let Some(v) = decl.param("max_segment_area") {
            c.max_segment_area = Params::float(v)
                .filter(|a| a.is_finite() && *a > 0.0)
                .ok_or_else(|| params.error("max_segment_area", "an area in m² above 0", v))?;
        }
        let number = |p: &str, default: f64| -> Result<f64> {
            match decl.param(p) {
                None => Ok(default),
                Some(v) => Params::float(v)
                    .filter(|x| x.is_finite() && *x >= 0.0)
                    .ok_or_else(|| params.error(p, "a number ≥ 0", v)),
            }
        };
        c.ambient = number("ambient", c.ambient)?;
        c.light_ambient = number("light_ambient", c.light_ambient)?;
        if let Some(m) = params.get_choice("model", &[("physical", 0u8), ("seed", 1), ("opengl", 2)])? {
            c.setup.model = match m {
                0 => LightModel::Physical,
                1 => LightModel::Seed { k: 1.0 },
                _ => LightModel::OpenGl {
                    kc: 1.0,
                    kl: 0.0,
                    kq: 1.0,
                },
            };
        }
        c.setup.model = match c.setup.model {
            LightModel::Physical => LightModel::Physical,
            LightModel::Seed { k } => LightModel::Seed {
                k: number("seed_k", k)?,
            },
            LightModel::OpenGl { kc, kl, kq } => {
                let (kc, kl, kq) = (number("kc", kc)?, number("kl", kl)?, number("kq", kq)?);
                if kc + kl + kq <= 0.0 {
                    let v = decl.param("kc").cloned().unwrap_or(toml::Value::Float(kc));
                    return Err(params.error(
                        "kc",
                        "kc, kl and kq not all zero (the attenuation would divide by zero)",
                        &v,
                    ));
                }
                LightModel::OpenGl { kc, kl, kq }
            }
        };
        Ok(c)
    }

    /// The label the chart and the bake report use.
    pub fn label(&self) -> String {
        let s = &self.setup;
        let point = if s.point == Point::Vertex { " per-vertex" } else { "" };
        format!(
            "vls {:?} k={} {:?} feeler={:?} area={}{point}",
            self.mode, s.k, s.selection, s.feeler, self.max_segment_area
        )
        .to_lowercase()
    }
}

/// Judged against direct light: the feeler's shadows are hard shadows of point lights.
pub fn reference(_decl: &MethodDecl) -> crate::lighting::ReferenceKind {
    crate::lighting::ReferenceKind::Direct
}

/// The chart's sweep: as declared, K from 1 to 32, the other selection, and segments 4× larger
/// and smaller.
pub fn sweep(decl: &MethodDecl) -> Vec<(String, MethodDecl)> {
    let mut out: Vec<(String, MethodDecl)> = Vec::new();
    let mut push = |d: MethodDecl| {
        if let Ok(c) = Config::from_decl(&d) {
            let label = c.label();
            if !out.iter().any(|(l, _)| *l == label) {
                out.push((label, d));
            }
        }
    };
    push(decl.clone());
    let declared = Config::from_decl(decl).ok();
    for k in [1i64, 4, 8, 16, 32] {
        push(decl.with("k", k.into()));
    }
    for s in ["closest", "contribution"] {
        push(decl.with("selection", s.into()));
    }
    let area = declared.map_or(0.05, |c| c.max_segment_area);
    for a in [4.0 * area, area / 4.0] {
        push(decl.with("max_segment_area", a.into()));
    }
    // The thesis as written (closest lights, its feeler, the fixed-function model, its 8
    // lights rather than a k derived for the corrected mode), so the chart shows what the
    // corrections buy.
    push(decl.with("mode", "faithful".into()).without("k"));
    out
}

/// The scene as VLS lights it: its polygons, their segments and its lights.
pub struct Layout {
    pub polygons: Vec<ScenePolygon>,
    pub segments: Segments,
    pub lights: Vec<ManyLight>,
}

impl Layout {
    /// `geometry` is the scene's static geometry (`static_geometry` or `scene_geometry`).
    pub fn new(
        scene: &Scene,
        geometry: &crate::lighting::lightmap::geometry::StaticGeometry,
        decl: &MethodDecl,
        config: &Config,
    ) -> Result<Layout> {
        let lights = ManyLight::from_scene(scene, NAME)?;
        let polygons = scene_polygons(&scene.source, geometry, NAME, &crate::world::Tolerance::MESH)?;
        let segments =
            Segments::build(polygons.iter().map(|p| &p.polygon), config.max_segment_area).map_err(|why| {
                let v = decl
                    .param("max_segment_area")
                    .cloned()
                    .unwrap_or(toml::Value::Float(config.max_segment_area));
                Params::new(decl, Some(scene)).error(
                    "max_segment_area",
                    &format!("an area giving fewer segments ({why})"),
                    &v,
                )
            })?;
        Ok(Layout {
            polygons,
            segments,
            lights,
        })
    }

    /// Everything the light sets depend on.
    pub fn key(&self, config: &Config) -> BakeKey {
        let geometry: Vec<f64> = self
            .polygons
            .iter()
            .flat_map(|p| {
                p.polygon
                    .vertices
                    .iter()
                    .flat_map(|v| v.to_array())
                    .chain(p.albedo.to_array())
            })
            .collect();
        BakeKey::new("vls light sets")
            .with("version", SETUP_VERSION)
            .with("setup", config.setup)
            .with("area", config.max_segment_area)
            .with("lights", &self.lights)
            .with_bytes("polygons", bytemuck::cast_slice(&geometry))
    }

    /// The light sets (the bake's work).
    pub fn select(&self, setup: &SetupParams, progress: &mut crate::bake::Progress) -> LightSets {
        let occluders = (setup.feeler == Feeler::Bvh).then(|| Occluders::new(self.polygons.iter().map(|p| &p.polygon)));
        setup::select(
            &self.polygons,
            &self.segments,
            &self.lights,
            setup,
            occluders.as_ref(),
            progress,
        )
    }
}

/// `SegmentVertex` of glsl/vls/vls.vert.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SegmentVertex {
    position: [f32; 3],
    normal: [f32; 3],
    albedo: [f32; 3],
    emission: [f32; 3],
    segment: u32,
    /// The material's specular colour and exponent (the fixed-function model's specular term).
    specular: [f32; 4],
}

/// `VlsParams` of glsl/vls/vls.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ShaderParams {
    info: [u32; 4],
    constants: [f32; 4],
    ambient: [f32; 4],
}

pub struct Vls {
    pipelines: [PipelineId; 3],
    vertices: BufferId,
    vertex_count: u32,
    sets: BufferId,
    params: ShaderParams,
    /// What the light sets dropped, for [`LightingMethod::warnings`] (none: nothing).
    dropped: Option<String>,
}

impl Vls {
    pub fn new(cx: &mut CreateContext<'_>, decl: &MethodDecl) -> Result<Vls> {
        let config = Config::from_decl_in(decl, Some(cx.scene))?;
        let geometry = crate::lighting::lightmap::geometry::static_geometry(cx.scene, cx.scene_gpu, NAME)?;
        let layout = Layout::new(cx.scene, &geometry, decl, &config)?;
        let key = layout.key(&config);
        let sets = cx.bakes.bake(&config.label(), &key, |progress| {
            Ok(layout.select(&config.setup, progress))
        })?;
        let count = setup::points(&layout.segments, config.setup.point).len();
        if sets.k > config.setup.k || sets.segments() != count {
            return Err(Error::Internal(format!(
                "{}: {NAME}: the baked light sets do not match the scene ({} sets of {} for {count} points)",
                cx.scene.source,
                sets.segments(),
                sets.k
            )));
        }
        let vertices = segment_vertices(&layout, config.setup.point, &draw_specular(cx.scene, &geometry));
        let vertex_count = vertices.len() as u32;
        let vertex_bytes: &[u8] = if vertices.is_empty() {
            &[0u8; std::mem::size_of::<SegmentVertex>()]
        } else {
            bytemuck::cast_slice(&vertices)
        };
        let vertices = cx
            .gpu
            .create_buffer_init("vls segments", vk::BufferUsageFlags::VERTEX_BUFFER, vertex_bytes)?;
        cx.states.forget_buffer(vertices);
        let set_bytes: &[u8] = if sets.indices.is_empty() {
            &[0xffu8; 4]
        } else {
            bytemuck::cast_slice(&sets.indices)
        };
        let sets_buffer =
            cx.gpu
                .create_buffer_init("vls light sets", vk::BufferUsageFlags::STORAGE_BUFFER, set_bytes)?;
        cx.states.forget_buffer(sets_buffer);
        let ds_format = cx.gpu.caps().depth_stencil_format;
        let mut pipeline = |terms: Terms| {
            let attr = |location, format, offset| VertexAttribute {
                location,
                binding: 0,
                format,
                offset,
            };
            let mut desc = term_pipeline_desc(
                &format!("vls {terms}"),
                "vls/vls.vert",
                "vls/vls.frag",
                terms,
                ds_format,
            );
            let f3 = vk::Format::R32G32B32_SFLOAT;
            desc.vertex_layout = VertexLayout {
                buffers: vec![(0, std::mem::size_of::<SegmentVertex>() as u32)],
                attributes: vec![
                    attr(0, f3, 0),
                    attr(1, f3, 12),
                    attr(2, f3, 24),
                    attr(3, f3, 36),
                    attr(4, vk::Format::R32_UINT, 48),
                    attr(5, vk::Format::R32G32B32A32_SFLOAT, 52),
                ],
            };
            desc.specialization.push(SpecConstant {
                id: 1,
                bits: u32::from(config.setup.point == Point::Vertex),
            });
            if !terms.has(Term::Base) {
                // Over another method's base, whose triangles are not these segments: a pull
                // towards the eye lets the segments pass the base's equal depth.
                desc.raster.depth_bias = Some((-4.0, -1.0));
            }
            cx.gpu.create_graphics_pipeline(&desc, cx.shaders)
        };
        let pipelines = [
            pipeline(Terms::BASE_DIRECT)?,
            pipeline(Terms::BASE)?,
            pipeline(Terms::DIRECT)?,
        ];
        let params = ShaderParams {
            info: [config.setup.model.code(), sets.k as u32, 0, 0],
            constants: config.setup.model.constants(),
            ambient: [config.ambient as f32, config.light_ambient as f32, 0.0, 0.0],
        };
        let dropped = dropped_light(&sets, count);
        Ok(Vls {
            pipelines,
            vertices,
            vertex_count,
            sets: sets_buffer,
            params,
            dropped,
        })
    }
}

/// What the light sets dropped, as a warning: points a crowd of lights reaches lose the lights
/// past k, and the frame shows no sign of it.
fn dropped_light(sets: &LightSets, points: usize) -> Option<String> {
    (sets.crowded > 0).then(|| {
        format!(
            "{NAME}: at {} of {points} points more than k = {} lights reach; the light past the k \
             strongest is dropped (raise k, up to {MAX_K})",
            sets.crowded, sets.k
        )
    })
}

/// Three vertices per segment, never shared, each with the index of its light set: the
/// segment's, or (per vertex) the segment vertex's.
/// Per scene draw: its material's specular colour and exponent (zero for an emitter's draw).
fn draw_specular(scene: &Scene, geometry: &crate::lighting::lightmap::geometry::StaticGeometry) -> Vec<[f32; 4]> {
    let draws = geometry.draw.iter().max().map_or(0, |&d| d + 1);
    let mut out = vec![[0.0; 4]; draws];
    for (&d, m) in geometry.draw.iter().zip(&geometry.material) {
        if let Some(m) = m.and_then(|m| scene.materials.get(m)) {
            out[d] = [m.specular.x, m.specular.y, m.specular.z, m.exponent];
        }
    }
    out
}

fn segment_vertices(layout: &Layout, point: Point, specular: &[[f32; 4]]) -> Vec<SegmentVertex> {
    let s = &layout.segments;
    let f = |v: DVec3| v.as_vec3().to_array();
    let mut out = Vec::with_capacity(3 * s.triangles.len());
    for (t, tri) in s.triangles.iter().enumerate() {
        let p = &layout.polygons[s.triangle_polygon[t] as usize];
        for &i in tri {
            let set = if point == Point::Vertex { i } else { t as u32 };
            out.push(SegmentVertex {
                position: f(s.positions[i as usize]),
                normal: f(p.polygon.plane.normal),
                albedo: f(p.albedo),
                emission: f(p.emission),
                segment: set,
                specular: specular.get(p.draw).copied().unwrap_or_default(),
            });
        }
    }
    out
}

impl LightingMethod for Vls {
    fn name(&self) -> &'static str {
        NAME
    }

    fn warnings(&self, _gpu: &mut crate::lighting::Gpu) -> Result<Vec<String>> {
        Ok(self.dropped.iter().cloned().collect())
    }

    fn add_passes<'a>(&'a self, graph: &mut RenderGraph<'a>, frame: &FrameContext<'a>) -> Result<()> {
        let (scene, t, uniforms) = (frame.scene, frame.targets, frame.uniforms);
        let stages = vk::PipelineStageFlags2::VERTEX_SHADER | vk::PipelineStageFlags2::FRAGMENT_SHADER;
        let base = frame.terms.has(Term::Base);
        let pipeline = match (base, frame.terms.has(Term::Direct)) {
            (true, true) => self.pipelines[0],
            (true, false) => self.pipelines[1],
            (false, true) => self.pipelines[2],
            (false, false) => return Ok(()),
        };
        let pass = term_pass(graph, if base { "vls" } else { "vls direct" }, t, base);
        let vertex_count = self.vertex_count;
        let params = self.params;
        pass.buffer(self.vertices, Access::VertexRead, None)
            .buffer(self.sets, Access::StorageRead { stages }, Some("sets"))
            .record(move |ctx| {
                let _ = begin_term_rendering(ctx.rec, t, base)?;
                ctx.rec.bind_pipeline(pipeline)?;
                let lights = scene.light_bytes();
                ctx.bind(&[
                    ("frame", Bind::UniformData(bytemuck::bytes_of(&uniforms))),
                    ("lights", Bind::StorageData(lights)),
                    ("params", Bind::UniformData(bytemuck::bytes_of(&params))),
                ])?;
                if vertex_count > 0 {
                    ctx.rec.bind_vertex_buffers(&[(self.vertices, 0)])?;
                    ctx.rec.draw(vertex_count, 1)?;
                }
                ctx.rec.end_rendering();
                Ok(())
            });
        Ok(())
    }
}
