//! Raster state the stencil-shadow-volume path depends on: two-sided stencil with separate
//! front/back ops and wrapping, colour writes off, and depth clamp for geometry beyond the far
//! plane. Checked through the colour a stencil-tested pass leaves in each region.

use crate::support as common;

use penumbra::backend::{
    vk, BufferDesc, ColorTarget, DepthState, GraphicsPipelineDesc, ImageDesc, MemoryKind, RenderTarget, RenderingDesc,
    StencilFace, StencilFaces, SubresourceRange, VertexAttribute, VertexLayout,
};
use penumbra::graph::{Access, RenderGraph};
use penumbra::shaders::ShaderLibrary;

const W: u32 = 64;
const H: u32 = 32;

/// Two triangles covering x ∈ [x0, x1] (clip space) at depth z, counter-clockwise on screen
/// when `ccw` (Vulkan's y points down, so the winding is reversed from the usual picture).
fn quad(x0: f32, x1: f32, z: f32, ccw: bool) -> Vec<[f32; 4]> {
    let (a, b, c, d) = (
        [x0, -1.0, z, 1.0],
        [x1, -1.0, z, 1.0],
        [x1, 1.0, z, 1.0],
        [x0, 1.0, z, 1.0],
    );
    // Screen y grows downward: a→d→c is counter-clockwise as seen on screen.
    if ccw {
        vec![a, d, c, a, c, b]
    } else {
        vec![a, b, c, a, c, d]
    }
}

#[test]
fn two_sided_stencil_and_depth_clamp() {
    let mut gpu = common::test_gpu();
    let lib = ShaderLibrary::test_kernels();
    let ds_format = gpu.caps().depth_stencil_format;
    let layout = VertexLayout {
        buffers: vec![(0, 16)],
        attributes: vec![VertexAttribute {
            location: 0,
            binding: 0,
            format: vk::Format::R32G32B32A32_SFLOAT,
            offset: 0,
        }],
    };
    let base = |name: &str| {
        let mut d = GraphicsPipelineDesc::new(name, "tests/solid.vert", Some("tests/solid.frag"));
        d.vertex_layout = layout.clone();
        d.raster.cull = vk::CullModeFlags::NONE;
        d.color_targets = vec![ColorTarget::new(vk::Format::R32G32B32A32_SFLOAT)];
        d.depth_format = Some(ds_format);
        d.depth = DepthState {
            test: true,
            write: false,
            compare: vk::CompareOp::LESS_OR_EQUAL,
        };
        d
    };
    // Front faces increment, back faces decrement, both wrapping; colour writes off.
    let mut count = base("stencil count");
    let op = |pass| StencilFace {
        pass,
        ..StencilFace::test(vk::CompareOp::ALWAYS, 0)
    };
    count.stencil = Some(StencilFaces {
        front: op(vk::StencilOp::INCREMENT_AND_WRAP),
        back: op(vk::StencilOp::DECREMENT_AND_WRAP),
    });
    count.color_targets[0].write_mask = vk::ColorComponentFlags::empty();
    let count = gpu.create_graphics_pipeline(&count, &lib).unwrap();
    let equal = |gpu: &mut penumbra::backend::Gpu, reference: u32| {
        let mut d = base(&format!("stencil == {reference}"));
        let t = StencilFace::test(vk::CompareOp::EQUAL, reference);
        d.stencil = Some(StencilFaces { front: t, back: t });
        gpu.create_graphics_pipeline(&d, &lib).unwrap()
    };
    let (eq2, eq255) = (equal(&mut gpu, 2), equal(&mut gpu, 255));
    let mut clamped = base("depth clamp");
    clamped.raster.depth_clamp = true;
    let clamped = gpu.create_graphics_pipeline(&clamped, &lib).unwrap();
    let unclamped = gpu.create_graphics_pipeline(&base("no depth clamp"), &lib).unwrap();

    // Left third: two front faces (stencil 2). Middle third: one back face (0 − 1 wraps to 255).
    // Right third: geometry at z = 1.5, beyond the far plane, drawn with and without depth clamp.
    let mut verts = Vec::new();
    verts.extend(quad(-1.0, -1.0 / 3.0, 0.5, true));
    verts.extend(quad(-1.0, -1.0 / 3.0, 0.5, true));
    verts.extend(quad(-1.0 / 3.0, 1.0 / 3.0, 0.5, false));
    verts.extend(quad(-1.0, 1.0, 0.0, true)); // full-screen quad for the stencil-tested colour passes
    verts.extend(quad(1.0 / 3.0, 1.0, 1.5, true)); // beyond the far plane
    let vb = gpu
        .create_buffer_init(
            "verts",
            vk::BufferUsageFlags::VERTEX_BUFFER,
            bytemuck::cast_slice(&verts),
        )
        .unwrap();
    let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    let color = gpu
        .create_image(&ImageDesc::new_2d("color", vk::Format::R32G32B32A32_SFLOAT, W, H).usage(usage))
        .unwrap();
    let ds = gpu
        .create_image(
            &ImageDesc::new_2d("depth-stencil", ds_format, W, H).usage(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )
        .unwrap();
    let rb = gpu
        .create_buffer(&BufferDesc {
            name: "rb".into(),
            size: (W * H * 16) as u64,
            usage: vk::BufferUsageFlags::TRANSFER_DST,
            memory: MemoryKind::GpuToCpu,
        })
        .unwrap();

    let mut graph = RenderGraph::new();
    graph
        .pass("stencil test scene")
        .color_attachment(color, SubresourceRange::mip(0), true)
        .depth_stencil_write(ds, true)
        .buffer(vb, Access::VertexRead, None)
        .record(move |ctx| {
            let r = &mut *ctx.rec;
            let _ = r.begin_rendering(&RenderingDesc {
                colors: vec![RenderTarget::clear_color(color, [0.0; 4])],
                depth_stencil: Some(RenderTarget::clear_depth(ds, 1.0, 0)),
            })?;
            r.bind_vertex_buffers(&[(vb, 0)])?;
            let solid = |rgba: [f32; 4]| bytemuck::cast::<[f32; 4], [u8; 16]>(rgba);
            r.bind_pipeline(count)?;
            r.push_constants(&solid([9.0; 4]))?; // must not appear: colour writes are off
            r.draw(18, 1)?;
            for (p, rgba) in [(eq2, [1.0, 0.0, 0.0, 1.0]), (eq255, [0.0, 1.0, 0.0, 1.0])] {
                r.bind_pipeline(p)?;
                r.push_constants(&solid(rgba))?;
                // Vertices 18..24: the full-screen quad.
                r.draw_from(6, 18)?;
            }
            r.bind_pipeline(unclamped)?;
            r.push_constants(&solid([0.0, 0.0, 5.0, 1.0]))?;
            r.draw_from(6, 24)?;
            r.bind_pipeline(clamped)?;
            r.push_constants(&solid([0.0, 0.0, 1.0, 1.0]))?;
            r.draw_from(6, 24)?;
            r.end_rendering();
            Ok(())
        });
    graph
        .pass("read")
        .transfer_read(color, SubresourceRange::mip(0))
        .buffer(rb, Access::TransferWrite, None)
        .record(move |ctx| ctx.rec.copy_image_to_buffer(color, 0, 0, rb));
    graph.pass("host").buffer(rb, Access::HostRead, None).record(|_| Ok(()));
    let frame = gpu.create_frame().unwrap();
    common::run_once(&gpu, frame, graph);
    let px: Vec<[f32; 4]> = bytemuck::cast_slice(&gpu.read_buffer(rb).unwrap()).to_vec();
    let at = |x: u32, y: u32| px[(y * W + x) as usize];
    for y in [1, H / 2, H - 2] {
        assert_eq!(at(5, y), [1.0, 0.0, 0.0, 1.0], "two front faces: stencil 2");
        assert_eq!(
            at(W / 2, y),
            [0.0, 1.0, 0.0, 1.0],
            "one back face: stencil wrapped to 255"
        );
        // Beyond the far plane: clipped without depth clamp, drawn at depth 1 with it.
        assert_eq!(at(W - 5, y), [0.0, 0.0, 1.0, 1.0], "depth-clamped geometry");
    }
    common::assert_clean(&gpu);
}
