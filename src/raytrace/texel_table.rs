//! Read-only arrays the compute shaders index per invocation (BVH nodes and triangles, the
//! reference's per-triangle shading, materials, texture maps and environment), stored as
//! RGBA32UI images used as tables: [`TABLE_WIDTH`] texels a row, read as read-only storage
//! images with `imageLoad` (`glsl/common/texel_table.glsl`). An integer format, because a float
//! one need not keep every bit pattern: integers stored in floats (indices, counts) are
//! denormals, which a texture unit may flush to zero.
//!
//! Why images and not storage buffers: on lavapipe a storage-buffer load whose address differs
//! between the lanes of a SIMD group compiles to a loop over the lanes with a branch for each,
//! while an image load is a gather without branches. Why storage images and not sampled ones
//! read with `texelFetch`: llvmpipe (Mesa 22.3) compiles a texel fetch to a call that works out
//! each lane's mip level, its size and its offset one lane at a time before the gather (seen in
//! the compiled code with `perf` and `gdb`), where an image load has one level and one row
//! stride; the path tracer ran 1.43-1.50 times faster with image loads. On a GPU all three are
//! plain memory reads. The README has the measured differences (the reference against Mitsuba 3).

use bytemuck::{Pod, Zeroable};

use super::bvh::BvhNode;
use super::TracedTriangle;
use crate::backend::{vk, Gpu, ImageDesc, ImageId, SubresourceRange};
use crate::error::{Error, Result};
use crate::graph::{Access, PassBuilder, ResourceStates};

/// Texels in a row of a table (`TABLE_WIDTH` in glsl/common/texel_table.glsl): Vulkan's
/// smallest allowed maxImageDimension2D, so every device takes it.
pub const TABLE_WIDTH: u32 = 4096;

/// One table: an image bound as a read-only storage image.
#[derive(Clone, Copy, Debug)]
pub struct TexelTable {
    pub image: ImageId,
}

impl TexelTable {
    /// `items` (whose size must be a multiple of 16 bytes) as texels, the last row padded with
    /// zeros; an empty slice gives one zeroed texel. The image is registered in `states` as
    /// sampled.
    pub fn upload<T: Pod>(gpu: &mut Gpu, states: &mut ResourceStates, name: &str, items: &[T]) -> Result<TexelTable> {
        let bytes: &[u8] = bytemuck::cast_slice(items);
        if !std::mem::size_of::<T>().is_multiple_of(16) {
            return Err(Error::Internal(format!(
                "{name}: items of {} bytes are not whole texels",
                std::mem::size_of::<T>()
            )));
        }
        let texels = (bytes.len() as u64 / 16).max(1);
        let rows = texels.div_ceil(TABLE_WIDTH as u64);
        let max = gpu.caps().max_image_dimension_2d as u64;
        if rows > max {
            return Err(Error::Usage(format!("{name}: {texels} texels need {rows} rows of {TABLE_WIDTH}, more than the device's largest image ({max} rows)")));
        }
        // Sampled too: the upload leaves its images in the shader-read layout.
        let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
        let image = gpu.create_image(
            &ImageDesc::new_2d(name, vk::Format::R32G32B32A32_UINT, TABLE_WIDTH, rows as u32).usage(usage),
        )?;
        gpu.upload_image_zero_padded(image, 0, bytes)?;
        // The upload leaves the image as sampled; the first pass that reads it as storage
        // moves it to the general layout.
        states.set_image(
            gpu,
            image,
            Access::SampledRead {
                stages: vk::PipelineStageFlags2::ALL_COMMANDS,
            },
        )?;
        Ok(TexelTable { image })
    }

    /// 4-byte `items` packed four a texel (value i is component i % 4 of texel i / 4).
    pub fn upload_packed<T: Pod + Zeroable>(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        name: &str,
        items: &[T],
    ) -> Result<TexelTable> {
        if std::mem::size_of::<T>() != 4 {
            return Err(Error::Internal(format!(
                "{name}: items of {} bytes do not pack four a texel",
                std::mem::size_of::<T>()
            )));
        }
        let mut texels = vec![[T::zeroed(); 4]; items.len().div_ceil(4)];
        for (i, &item) in items.iter().enumerate() {
            texels[i / 4][i % 4] = item;
        }
        TexelTable::upload(gpu, states, name, &texels)
    }

    /// Declares the pass's read of the table through binding `name` in `stages`.
    pub fn read<'g, 'a>(
        &self,
        pass: PassBuilder<'g, 'a>,
        name: &'static str,
        stages: vk::PipelineStageFlags2,
    ) -> PassBuilder<'g, 'a> {
        pass.storage_read(name, self.image, SubresourceRange::mip(0), stages)
    }
}

/// A BVH as `glsl/common/bvh.glsl` reads it: nodes (two texels each) and triangles (three) in
/// the tables `bvh_nodes` and `bvh_triangles`, and where the shader walks them the skip links
/// of the stackless shadow-ray walk (four a texel) in `bvh_skips`.
#[derive(Clone, Copy, Debug)]
pub struct GpuBvh {
    pub nodes: TexelTable,
    pub triangles: TexelTable,
    pub skips: Option<TexelTable>,
}

impl GpuBvh {
    /// Uploads nodes and triangles (indices as the shader reads them: several trees one after
    /// another if the caller put them so) and the skip links where the shader walks them.
    pub fn upload(
        gpu: &mut Gpu,
        states: &mut ResourceStates,
        label: &str,
        nodes: &[BvhNode],
        triangles: &[TracedTriangle],
        skips: Option<&[u32]>,
    ) -> Result<GpuBvh> {
        let nodes = TexelTable::upload(gpu, states, &format!("{label} bvh nodes"), nodes)?;
        let triangles = TexelTable::upload(gpu, states, &format!("{label} bvh triangles"), triangles)?;
        let skips = match skips {
            Some(s) => Some(TexelTable::upload_packed(
                gpu,
                states,
                &format!("{label} bvh skip links"),
                s,
            )?),
            None => None,
        };
        Ok(GpuBvh {
            nodes,
            triangles,
            skips,
        })
    }

    /// Declares the pass's reads of the tables (and skip links) in `stages`.
    pub fn read<'g, 'a>(&self, pass: PassBuilder<'g, 'a>, stages: vk::PipelineStageFlags2) -> PassBuilder<'g, 'a> {
        let pass = self
            .triangles
            .read(self.nodes.read(pass, "bvh_nodes", stages), "bvh_triangles", stages);
        match self.skips {
            Some(s) => s.read(pass, "bvh_skips", stages),
            None => pass,
        }
    }
}
