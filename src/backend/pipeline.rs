//! Hand-built graphics and compute pipelines with layouts derived from reflection.

use std::ffi::CString;

use ash::vk;

use super::device::vulkan_calls;
use super::error::{BackendError, BackendResult, VkContext};
use super::reflect::ShaderReflection;
use super::Gpu;

/// Where pipelines get SPIR-V from: the shaders embedded at build time, or recompiled from
/// `glsl/` for hot reload. Implemented outside the backend (`crate::shaders`).
pub trait ShaderSource {
    /// SPIR-V words for a shader path relative to `glsl/`, e.g. `forward/forward.vert`.
    fn spirv(&self, path: &str) -> Result<Vec<u32>, String>;
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecConstant {
    pub id: u32,
    /// The constant's 4 bytes (use `f32::to_bits`, `u32`, or 0/1 for booleans).
    pub bits: u32,
}

#[derive(Clone, Debug, PartialEq)]
pub struct VertexAttribute {
    pub location: u32,
    pub binding: u32,
    pub format: vk::Format,
    pub offset: u32,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexLayout {
    /// (binding, stride) per vertex buffer.
    pub buffers: Vec<(u32, u32)>,
    pub attributes: Vec<VertexAttribute>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RasterState {
    pub cull: vk::CullModeFlags,
    pub front_face: vk::FrontFace,
    pub polygon_mode: vk::PolygonMode,
    /// Clamp depth instead of clipping at the near/far planes (shadow volumes' caps at infinity).
    pub depth_clamp: bool,
    pub depth_bias: Option<(f32, f32)>,
}

impl Default for RasterState {
    fn default() -> Self {
        RasterState {
            cull: vk::CullModeFlags::BACK,
            front_face: vk::FrontFace::COUNTER_CLOCKWISE,
            polygon_mode: vk::PolygonMode::FILL,
            depth_clamp: false,
            depth_bias: None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthState {
    pub test: bool,
    pub write: bool,
    pub compare: vk::CompareOp,
}

impl Default for DepthState {
    fn default() -> Self {
        DepthState {
            test: true,
            write: true,
            compare: vk::CompareOp::LESS,
        }
    }
}

/// Stencil state of one face orientation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StencilFace {
    pub fail: vk::StencilOp,
    pub pass: vk::StencilOp,
    pub depth_fail: vk::StencilOp,
    pub compare: vk::CompareOp,
    pub compare_mask: u32,
    pub write_mask: u32,
    pub reference: u32,
}

impl StencilFace {
    /// Keeps the stencil value and passes where `compare(reference, stencil)` holds.
    pub fn test(compare: vk::CompareOp, reference: u32) -> Self {
        StencilFace {
            fail: vk::StencilOp::KEEP,
            pass: vk::StencilOp::KEEP,
            depth_fail: vk::StencilOp::KEEP,
            compare,
            compare_mask: 0xff,
            write_mask: 0xff,
            reference,
        }
    }
    fn raw(&self) -> vk::StencilOpState {
        vk::StencilOpState {
            fail_op: self.fail,
            pass_op: self.pass,
            depth_fail_op: self.depth_fail,
            compare_op: self.compare,
            compare_mask: self.compare_mask,
            write_mask: self.write_mask,
            reference: self.reference,
        }
    }
}

/// Separate front- and back-face stencil state (two-sided stencil for shadow volumes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StencilFaces {
    pub front: StencilFace,
    pub back: StencilFace,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BlendMode {
    Replace,
    /// dst + src, per channel (light accumulation).
    Additive,
    /// src·α + dst·(1−α).
    Alpha,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColorTarget {
    pub format: vk::Format,
    pub blend: BlendMode,
    pub write_mask: vk::ColorComponentFlags,
}

impl ColorTarget {
    pub fn new(format: vk::Format) -> Self {
        ColorTarget {
            format,
            blend: BlendMode::Replace,
            write_mask: vk::ColorComponentFlags::RGBA,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct GraphicsPipelineDesc {
    pub name: String,
    pub vertex: String,
    pub geometry: Option<String>,
    pub fragment: Option<String>,
    pub vertex_layout: VertexLayout,
    pub topology: vk::PrimitiveTopology,
    pub raster: RasterState,
    pub depth: DepthState,
    pub stencil: Option<StencilFaces>,
    pub color_targets: Vec<ColorTarget>,
    pub depth_format: Option<vk::Format>,
    pub specialization: Vec<SpecConstant>,
}

impl GraphicsPipelineDesc {
    pub fn new(name: &str, vertex: &str, fragment: Option<&str>) -> Self {
        GraphicsPipelineDesc {
            name: name.into(),
            vertex: vertex.into(),
            geometry: None,
            fragment: fragment.map(Into::into),
            vertex_layout: VertexLayout::default(),
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            raster: RasterState::default(),
            depth: DepthState::default(),
            stencil: None,
            color_targets: Vec::new(),
            depth_format: None,
            specialization: Vec::new(),
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct ComputePipelineDesc {
    pub name: String,
    pub shader: String,
    pub specialization: Vec<SpecConstant>,
}

// One per pipeline, kept for hot reload: a few hundred bytes each, so boxing the graphics
// description would save nothing worth an indirection.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PipelineKind {
    Graphics(GraphicsPipelineDesc),
    Compute(ComputePipelineDesc),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PipelineId(pub(crate) u32);

pub(crate) struct PipelineObject {
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layouts: Vec<vk::DescriptorSetLayout>,
    pub reflection: ShaderReflection,
    pub bind_point: vk::PipelineBindPoint,
    pub kind: PipelineKind,
    pub name: String,
}

impl PipelineObject {
    pub(crate) unsafe fn destroy(self, device: &ash::Device) {
        unsafe {
            device.destroy_pipeline(self.raw, None);
            device.destroy_pipeline_layout(self.layout, None);
            for l in self.set_layouts {
                device.destroy_descriptor_set_layout(l, None);
            }
        }
    }
}

fn stage_of(path: &str) -> BackendResult<vk::ShaderStageFlags> {
    let ext = path.rsplit('.').next().unwrap_or("");
    Ok(match ext {
        "vert" => vk::ShaderStageFlags::VERTEX,
        "frag" => vk::ShaderStageFlags::FRAGMENT,
        "geom" => vk::ShaderStageFlags::GEOMETRY,
        "comp" => vk::ShaderStageFlags::COMPUTE,
        _ => {
            return Err(BackendError::Shader {
                name: path.into(),
                message: "unknown shader stage (expected .vert, .frag, .geom or .comp)".into(),
            })
        }
    })
}

struct LoadedStage {
    stage: vk::ShaderStageFlags,
    module: vk::ShaderModule,
}

impl Gpu {
    pub fn create_graphics_pipeline(
        &mut self,
        desc: &GraphicsPipelineDesc,
        shaders: &dyn ShaderSource,
    ) -> BackendResult<PipelineId> {
        let obj = self.build_pipeline(&PipelineKind::Graphics(desc.clone()), shaders)?;
        self.arenas.pipelines.push(Some(obj));
        let id = PipelineId(self.arenas.pipelines.len() as u32 - 1);
        if let Some(scope) = self.scopes.last_mut() {
            scope.pipelines.push(id);
        }
        Ok(id)
    }

    pub fn create_compute_pipeline(
        &mut self,
        desc: &ComputePipelineDesc,
        shaders: &dyn ShaderSource,
    ) -> BackendResult<PipelineId> {
        let obj = self.build_pipeline(&PipelineKind::Compute(desc.clone()), shaders)?;
        self.arenas.pipelines.push(Some(obj));
        let id = PipelineId(self.arenas.pipelines.len() as u32 - 1);
        if let Some(scope) = self.scopes.last_mut() {
            scope.pipelines.push(id);
        }
        Ok(id)
    }

    /// Destroys a pipeline once the device is idle (for pipelines used only for a while, such as
    /// a bake's). Its id stays invalid.
    pub fn destroy_pipeline(&mut self, id: PipelineId) -> BackendResult<()> {
        let _calls = vulkan_calls();
        self.wait_idle()?;
        if let Some(old) = self.arenas.pipelines.get_mut(id.0 as usize).and_then(|p| p.take()) {
            unsafe { old.destroy(&self.device) };
        }
        Ok(())
    }

    /// Rebuilds a pipeline from fresh shaders. On any error the old pipeline stays in place and
    /// the error is returned, so a typo in a shader never takes the running demo down.
    pub fn reload_pipeline(&mut self, id: PipelineId, shaders: &dyn ShaderSource) -> BackendResult<()> {
        let _calls = vulkan_calls();
        let kind = self.pipeline(id)?.kind.clone();
        let new = self.build_pipeline(&kind, shaders)?;
        self.wait_idle()?;
        if let Some(old) = self.arenas.pipelines[id.0 as usize].replace(new) {
            unsafe { old.destroy(&self.device) };
        }
        Ok(())
    }

    /// Every pipeline id currently alive (for reloading them all).
    pub fn pipeline_ids(&self) -> Vec<PipelineId> {
        (0..self.arenas.pipelines.len() as u32)
            .filter(|&i| self.arenas.pipelines[i as usize].is_some())
            .map(PipelineId)
            .collect()
    }

    pub(crate) fn pipeline(&self, id: PipelineId) -> BackendResult<&PipelineObject> {
        self.arenas
            .pipelines
            .get(id.0 as usize)
            .and_then(|p| p.as_ref())
            .ok_or_else(|| BackendError::Invalid(format!("pipeline {id:?} was destroyed")))
    }

    /// What the pipeline's shaders declare.
    pub fn pipeline_reflection(&self, id: PipelineId) -> BackendResult<&ShaderReflection> {
        Ok(&self.pipeline(id)?.reflection)
    }

    fn load_stage(
        &self,
        path: &str,
        shaders: &dyn ShaderSource,
        reflections: &mut Vec<ShaderReflection>,
    ) -> BackendResult<LoadedStage> {
        let _calls = vulkan_calls();
        let stage = stage_of(path)?;
        let words = shaders.spirv(path).map_err(|m| BackendError::Shader {
            name: path.into(),
            message: m,
        })?;
        reflections.push(ShaderReflection::from_spirv(path, stage, &words)?);
        // Reflection keeps the declared types; the driver may see uniform blocks as storage.
        let words = if self.caps.uniform_blocks_as_storage {
            super::uniform_blocks::uniform_blocks_as_storage(&words).map_err(|m| BackendError::Shader {
                name: path.into(),
                message: m,
            })?
        } else {
            words
        };
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        let module = unsafe { self.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
        Ok(LoadedStage { stage, module })
    }

    fn build_pipeline(&self, kind: &PipelineKind, shaders: &dyn ShaderSource) -> BackendResult<PipelineObject> {
        let _calls = vulkan_calls();
        let (name, paths, spec) = match kind {
            PipelineKind::Graphics(d) => {
                let mut p = vec![d.vertex.clone()];
                p.extend(d.geometry.clone());
                p.extend(d.fragment.clone());
                (d.name.clone(), p, d.specialization.clone())
            }
            PipelineKind::Compute(d) => (d.name.clone(), vec![d.shader.clone()], d.specialization.clone()),
        };
        let mut reflections = Vec::new();
        let mut stages: Vec<LoadedStage> = Vec::new();
        let mut result = (|| -> BackendResult<PipelineObject> {
            for p in &paths {
                stages.push(self.load_stage(p, shaders, &mut reflections)?);
            }
            let reflection = ShaderReflection::merge(&name, &reflections)?;
            if reflection.push_constant_size > self.caps.max_push_constants_size {
                return Err(BackendError::Unsupported(format!(
                    "pipeline `{name}` uses {} bytes of push constants; the device allows {}",
                    reflection.push_constant_size, self.caps.max_push_constants_size
                )));
            }
            let set_layouts = self.create_set_layouts(&reflection)?;
            let push_ranges = if reflection.push_constant_size > 0 {
                vec![vk::PushConstantRange {
                    stage_flags: reflection.push_constant_stages,
                    offset: 0,
                    size: reflection.push_constant_size,
                }]
            } else {
                vec![]
            };
            let layout_info = vk::PipelineLayoutCreateInfo::default()
                .set_layouts(&set_layouts)
                .push_constant_ranges(&push_ranges);
            let layout = match unsafe { self.device.create_pipeline_layout(&layout_info, None) } {
                Ok(l) => l,
                Err(e) => {
                    for l in set_layouts {
                        unsafe { self.device.destroy_descriptor_set_layout(l, None) };
                    }
                    return Err(BackendError::Vulkan {
                        call: "vkCreatePipelineLayout",
                        result: e,
                    });
                }
            };
            let raw = match kind {
                PipelineKind::Graphics(d) => self.create_graphics_raw(d, &stages, layout, &spec),
                PipelineKind::Compute(_) => self.create_compute_raw(&stages[0], layout, &spec),
            };
            let raw = match raw {
                Ok(r) => r,
                Err(e) => {
                    unsafe {
                        self.device.destroy_pipeline_layout(layout, None);
                        for l in set_layouts {
                            self.device.destroy_descriptor_set_layout(l, None);
                        }
                    }
                    return Err(e);
                }
            };
            self.set_name(raw, &name);
            let bind_point = match kind {
                PipelineKind::Graphics(_) => vk::PipelineBindPoint::GRAPHICS,
                PipelineKind::Compute(_) => vk::PipelineBindPoint::COMPUTE,
            };
            Ok(PipelineObject {
                raw,
                layout,
                set_layouts,
                reflection,
                bind_point,
                kind: kind.clone(),
                name: name.clone(),
            })
        })();
        for s in stages.drain(..) {
            unsafe { self.device.destroy_shader_module(s.module, None) };
        }
        if let Err(BackendError::Shader { name: n, message }) = &mut result {
            *message = format!("{message} (pipeline `{name}`)");
            let _ = n;
        }
        result
    }

    /// The descriptor type the driver sees for a declared one (uniform blocks may be storage
    /// blocks on this device; see `backend/uniform_blocks.rs`).
    pub(crate) fn driver_descriptor_type(&self, declared: vk::DescriptorType) -> vk::DescriptorType {
        if self.caps.uniform_blocks_as_storage && declared == vk::DescriptorType::UNIFORM_BUFFER {
            vk::DescriptorType::STORAGE_BUFFER
        } else {
            declared
        }
    }

    fn create_set_layouts(&self, r: &ShaderReflection) -> BackendResult<Vec<vk::DescriptorSetLayout>> {
        let _calls = vulkan_calls();
        let mut layouts = Vec::new();
        for set in 0..r.set_count() {
            let bindings: Vec<vk::DescriptorSetLayoutBinding> = r
                .bindings
                .iter()
                .filter(|b| b.set == set)
                .map(|b| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(b.binding)
                        .descriptor_type(self.driver_descriptor_type(b.ty))
                        .descriptor_count(b.count)
                        .stage_flags(b.stages)
                })
                .collect();
            let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings);
            match unsafe { self.device.create_descriptor_set_layout(&info, None) } {
                Ok(l) => layouts.push(l),
                Err(e) => {
                    for l in layouts {
                        unsafe { self.device.destroy_descriptor_set_layout(l, None) };
                    }
                    return Err(BackendError::Vulkan {
                        call: "vkCreateDescriptorSetLayout",
                        result: e,
                    });
                }
            }
        }
        Ok(layouts)
    }

    fn create_compute_raw(
        &self,
        stage: &LoadedStage,
        layout: vk::PipelineLayout,
        spec: &[SpecConstant],
    ) -> BackendResult<vk::Pipeline> {
        let _calls = vulkan_calls();
        let entry = c"main";
        let (entries, data) = spec_data(spec);
        let spec_info = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
        let mut stage_info = vk::PipelineShaderStageCreateInfo::default()
            .stage(stage.stage)
            .module(stage.module)
            .name(entry);
        if !spec.is_empty() {
            stage_info = stage_info.specialization_info(&spec_info);
        }
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage_info)
            .layout(layout)];
        let p = unsafe {
            self.device
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
        }
        .map_err(|(_, e)| BackendError::Vulkan {
            call: "vkCreateComputePipelines",
            result: e,
        })?;
        Ok(p[0])
    }

    // long: one Vulkan graphics pipeline description, state by state.
    fn create_graphics_raw(
        &self,
        d: &GraphicsPipelineDesc,
        stages: &[LoadedStage],
        layout: vk::PipelineLayout,
        spec: &[SpecConstant],
    ) -> BackendResult<vk::Pipeline> {
        let _calls = vulkan_calls();
        if d.raster.depth_clamp && !self.caps.depth_clamp {
            return Err(BackendError::Unsupported(format!(
                "depth clamp (pipeline `{}`)",
                d.name
            )));
        }
        if d.raster.polygon_mode != vk::PolygonMode::FILL && !self.caps.fill_mode_non_solid {
            return Err(BackendError::Unsupported(format!(
                "non-solid fill (pipeline `{}`)",
                d.name
            )));
        }
        if d.geometry.is_some() && !self.caps.geometry_shader {
            return Err(BackendError::Unsupported(format!(
                "geometry shaders (pipeline `{}`)",
                d.name
            )));
        }
        let entry = CString::new("main").map_err(|e| BackendError::Invalid(e.to_string()))?;
        let (entries, data) = spec_data(spec);
        let spec_info = vk::SpecializationInfo::default().map_entries(&entries).data(&data);
        let stage_infos: Vec<vk::PipelineShaderStageCreateInfo> = stages
            .iter()
            .map(|s| {
                let mut i = vk::PipelineShaderStageCreateInfo::default()
                    .stage(s.stage)
                    .module(s.module)
                    .name(&entry);
                if !spec.is_empty() {
                    i = i.specialization_info(&spec_info);
                }
                i
            })
            .collect();
        let vb: Vec<vk::VertexInputBindingDescription> = d
            .vertex_layout
            .buffers
            .iter()
            .map(|&(binding, stride)| vk::VertexInputBindingDescription {
                binding,
                stride,
                input_rate: vk::VertexInputRate::VERTEX,
            })
            .collect();
        let va: Vec<vk::VertexInputAttributeDescription> = d
            .vertex_layout
            .attributes
            .iter()
            .map(|a| vk::VertexInputAttributeDescription {
                location: a.location,
                binding: a.binding,
                format: a.format,
                offset: a.offset,
            })
            .collect();
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vb)
            .vertex_attribute_descriptions(&va);
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(d.topology);
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        let mut raster = vk::PipelineRasterizationStateCreateInfo::default()
            .depth_clamp_enable(d.raster.depth_clamp)
            .polygon_mode(d.raster.polygon_mode)
            .cull_mode(d.raster.cull)
            .front_face(d.raster.front_face)
            .line_width(1.0);
        if let Some((constant, slope)) = d.raster.depth_bias {
            raster = raster
                .depth_bias_enable(true)
                .depth_bias_constant_factor(constant)
                .depth_bias_slope_factor(slope);
        }
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let mut depth_stencil = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(d.depth.test)
            .depth_write_enable(d.depth.write)
            .depth_compare_op(d.depth.compare);
        if let Some(s) = d.stencil {
            depth_stencil = depth_stencil
                .stencil_test_enable(true)
                .front(s.front.raw())
                .back(s.back.raw());
        }
        let attachments: Vec<vk::PipelineColorBlendAttachmentState> = d
            .color_targets
            .iter()
            .map(|t| {
                let a = vk::PipelineColorBlendAttachmentState::default().color_write_mask(t.write_mask);
                match t.blend {
                    BlendMode::Replace => a,
                    BlendMode::Additive => a
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::ONE)
                        .dst_color_blend_factor(vk::BlendFactor::ONE)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ONE)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                        .alpha_blend_op(vk::BlendOp::ADD),
                    BlendMode::Alpha => a
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::SRC_ALPHA)
                        .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ONE)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .alpha_blend_op(vk::BlendOp::ADD),
                }
            })
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let color_formats: Vec<vk::Format> = d.color_targets.iter().map(|t| t.format).collect();
        let (depth_fmt, stencil_fmt) = match d.depth_format {
            Some(f) => {
                let a = super::resources::format_aspect(f);
                (
                    if a.contains(vk::ImageAspectFlags::DEPTH) {
                        f
                    } else {
                        vk::Format::UNDEFINED
                    },
                    if a.contains(vk::ImageAspectFlags::STENCIL) {
                        f
                    } else {
                        vk::Format::UNDEFINED
                    },
                )
            }
            None => (vk::Format::UNDEFINED, vk::Format::UNDEFINED),
        };
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&color_formats)
            .depth_attachment_format(depth_fmt)
            .stencil_attachment_format(stencil_fmt);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stage_infos)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth_stencil)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering)];
        let p = unsafe {
            self.device
                .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
        }
        .map_err(|(_, e)| BackendError::Vulkan {
            call: "vkCreateGraphicsPipelines",
            result: e,
        })?;
        Ok(p[0])
    }
}

fn spec_data(spec: &[SpecConstant]) -> (Vec<vk::SpecializationMapEntry>, Vec<u8>) {
    let entries = spec
        .iter()
        .enumerate()
        .map(|(i, s)| vk::SpecializationMapEntry {
            constant_id: s.id,
            offset: 4 * i as u32,
            size: 4,
        })
        .collect();
    let data = spec.iter().flat_map(|s| s.bits.to_ne_bytes()).collect();
    (entries, data)
}
