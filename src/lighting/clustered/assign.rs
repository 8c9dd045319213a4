//! The cluster grid on the CPU: the uniform block the three passes share, the camera recovered
//! from the frame's view-projection, each light's bounding sphere (and a spot light's cone) in
//! view space, and a CPU twin of the GPU's froxel bounds and sphere and cone tests (for tests
//! and for reading the assignment back).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use super::config::Config;
use crate::gpu_scene::{GpuLight, LIGHT_DIRECTIONAL, LIGHT_SPOT};

/// Matches `ClusterBlock` in glsl/clustered/clusters.glsl (std140).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ClusterBlock {
    /// World → view (the camera looks down −z).
    pub view: [f32; 16],
    /// Columns, rows, slices, index slots per cluster.
    pub grid: [u32; 4],
    /// x: lights.
    pub lights: [u32; 4],
    /// Width and height in pixels; view x and y per unit depth per NDC unit (aspect/f, 1/f).
    pub screen: [f32; 4],
    /// Near, far, ln(far/near), slices / ln(far/near).
    pub depth: [f32; 4],
}

/// Matches `LightVolume` in glsl/clustered/clusters.glsl: where a light can reach.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct LightVolume {
    /// View-space bounding sphere (xyz centre, w radius); radius < 0: the light reaches nowhere,
    /// infinite: everywhere (directional).
    pub sphere: [f32; 4],
    /// x: the range from the light's position (infinite for directional lights).
    pub range: [f32; 4],
    /// A spot light's view-space position; w: the cosine of its outer half-angle.
    pub apex: [f32; 4],
    /// Its view-space unit axis; w: the sine of the outer half-angle, negative for a light
    /// without a cone.
    pub axis: [f32; 4],
}

/// The `apex` and `axis` of a light without a cone.
const NO_CONE: ([f32; 4], [f32; 4]) = ([0.0; 4], [0.0, 0.0, 0.0, -1.0]);

/// The camera as the renderer builds it (`Camera::projection`: an infinite far plane, NDC y
/// down), recovered from the view-projection the frame carries: (world → view, aspect/f, 1/f,
/// near). The first two rows of the projection scale the view's unit x and y rows by f/aspect
/// and −f; its last row is −(view's z row); the third differs from the last by −near in w.
pub fn decompose(view_proj: &[f32; 16]) -> Option<(Mat4, f32, f32, f32)> {
    let vp = Mat4::from_cols_array(view_proj);
    let (r0, r1, r2, r3) = (vp.row(0), vp.row(1), vp.row(2), vp.row(3));
    let (sx, sy) = (r0.truncate().length(), r1.truncate().length());
    let near = r3.w - r2.w;
    // The last row is a unit view axis for this projection and nothing else.
    let unit_axis = (r3.truncate().length() - 1.0).abs() < 1e-3;
    if !(unit_axis && sx > 0.0 && sy > 0.0 && near > 0.0 && sx.is_finite() && sy.is_finite()) {
        return None;
    }
    let view = Mat4::from_cols(r0 / sx, -r1 / sy, -r3, Vec4::W).transpose();
    Some((view, 1.0 / sx, 1.0 / sy, near))
}

/// The block for one frame: the grid of `config` over a `width × height` target, slices from the
/// near plane to `far` (view depth).
pub fn block(
    config: &Config,
    view_proj: &[f32; 16],
    width: u32,
    height: u32,
    far: f32,
    lights: u32,
) -> Option<ClusterBlock> {
    let (view, sx, sy, near) = decompose(view_proj)?;
    let far = far.max(near * 1.01);
    let log_ratio = (far / near).ln();
    Some(ClusterBlock {
        view: view.to_cols_array(),
        grid: [config.tiles[0], config.tiles[1], config.slices, config.max_per_cluster],
        lights: [lights, 0, 0, 0],
        screen: [width as f32, height as f32, sx, sy],
        depth: [near, far, log_ratio, config.slices as f32 / log_ratio],
    })
}

/// The farthest view depth of the box `min`–`max` seen through `view`.
pub fn far_depth(view: &Mat4, min: Vec3, max: Vec3) -> f32 {
    let mut far = 0.0f32;
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        );
        far = far.max(-view.transform_point3(c).z);
    }
    far
}

/// A light's range: the scene's `radius` when it gives one, else where its irradiance at normal
/// incidence, max(I.rgb)/d², falls to `cutoff`. Directional lights reach everywhere.
pub fn range(light: &GpuLight, radius: f32, cutoff: f32) -> f32 {
    if light.position[3] == LIGHT_DIRECTIONAL {
        return f32::INFINITY;
    }
    if radius > 0.0 {
        return radius;
    }
    let peak = light.intensity[0].max(light.intensity[1]).max(light.intensity[2]);
    if peak > 0.0 {
        (peak / cutoff).sqrt()
    } else {
        0.0
    }
}

/// Where each light can reach, in `view` space: a sphere of its range about a point or quad light,
/// the smallest sphere about a spot light's cone cut at its range (a cone's light is zero past
/// its outer angle), everywhere for a directional light. `radii` are the scene's, by light
/// (missing or 0: from `cutoff`).
pub fn light_volumes(lights: &[GpuLight], radii: &[f32], cutoff: f32, view: &Mat4) -> Vec<LightVolume> {
    lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let r = range(l, radii.get(i).copied().unwrap_or(0.0), cutoff);
            let (apex, axis) = NO_CONE;
            if r.is_infinite() {
                return LightVolume {
                    sphere: [0.0, 0.0, 0.0, f32::INFINITY],
                    range: [f32::INFINITY, 0.0, 0.0, 0.0],
                    apex,
                    axis,
                };
            }
            if r <= 0.0 {
                return LightVolume {
                    sphere: [0.0, 0.0, 0.0, -1.0],
                    range: [0.0; 4],
                    apex,
                    axis,
                };
            }
            let p = Vec3::from_slice(&l.position[..3]);
            let direction = Vec3::from_slice(&l.direction[..3]).normalize_or_zero();
            if l.position[3] != LIGHT_SPOT || direction == Vec3::ZERO {
                return LightVolume {
                    sphere: view.transform_point3(p).extend(r).into(),
                    range: [r, 0.0, 0.0, 0.0],
                    apex,
                    axis,
                };
            }
            let cos_outer = l.cone[1].clamp(-1.0, 1.0);
            let (centre, radius) = cone_sphere(p, direction, cos_outer, r);
            let sin_outer = (1.0 - cos_outer * cos_outer).max(0.0).sqrt();
            LightVolume {
                sphere: view.transform_point3(centre).extend(radius).into(),
                range: [r, 0.0, 0.0, 0.0],
                apex: view.transform_point3(p).extend(cos_outer).into(),
                axis: view
                    .transform_vector3(direction)
                    .normalize_or_zero()
                    .extend(sin_outer)
                    .into(),
            }
        })
        .collect()
}

/// The smallest sphere holding the cone from `apex` along unit `axis`, of half-angle
/// acos(`cos_outer`), cut by the sphere of radius `range` about the apex.
pub fn cone_sphere(apex: Vec3, axis: Vec3, cos_outer: f32, range: f32) -> (Vec3, f32) {
    let axis = axis.normalize_or_zero();
    if cos_outer <= 0.0 || axis == Vec3::ZERO {
        // Half-angle of 90° or more: the cut cone is wider than a hemisphere.
        return (apex, range);
    }
    if cos_outer >= std::f32::consts::FRAC_1_SQRT_2 {
        // Narrow (≤ 45°): the sphere through the apex and the cap's rim.
        let r = range / (2.0 * cos_outer);
        (apex + axis * r, r)
    } else {
        // Wide: the sphere about the rim's circle holds the apex and the whole cap.
        let sin = (1.0 - cos_outer * cos_outer).max(0.0).sqrt();
        (apex + axis * (range * cos_outer), range * sin)
    }
}

/// The cluster index of tile (`x`, `y`) in slice `k`.
pub fn cluster_index(block: &ClusterBlock, x: u32, y: u32, k: u32) -> u32 {
    x + block.grid[0] * (y + block.grid[1] * k)
}

/// The view-space box of cluster `c`, as glsl/clustered/bounds.comp computes it (grown by 1e-4 of
/// its far depth, so that a pixel on a face is inside).
pub fn froxel_bounds(block: &ClusterBlock, c: u32) -> (Vec3, Vec3) {
    let [cols, rows, slices, _] = block.grid;
    let (x, y, k) = (c % cols, (c / cols) % rows, c / (cols * rows));
    let [_, _, sx, sy] = block.screen;
    let [near, far, log_ratio, _] = block.depth;
    let ndc_x = |t: u32| t as f32 / cols as f32 * 2.0 - 1.0;
    let ndc_y = |t: u32| t as f32 / rows as f32 * 2.0 - 1.0;
    let depth = |k: u32| {
        if k == 0 {
            near
        } else if k >= slices {
            far
        } else {
            near * (log_ratio * k as f32 / slices as f32).exp()
        }
    };
    let (d0, d1) = (depth(k), depth(k + 1));
    let mut min = Vec3::splat(f32::INFINITY);
    let mut max = Vec3::splat(f32::NEG_INFINITY);
    for d in [d0, d1] {
        for nx in [ndc_x(x), ndc_x(x + 1)] {
            for ny in [ndc_y(y), ndc_y(y + 1)] {
                let p = Vec3::new(nx * d * sx, -ny * d * sy, -d);
                min = min.min(p);
                max = max.max(p);
            }
        }
    }
    let pad = Vec3::splat(1e-4 * d1);
    (min - pad, max + pad)
}

/// Whether `volume` may reach the box `min`–`max`: its sphere touches the box and, for a spot
/// light, its cone reaches the sphere about the box (as glsl/clustered/assign.comp decides).
pub fn touches(volume: &LightVolume, min: Vec3, max: Vec3) -> bool {
    let r = volume.sphere[3];
    if r < 0.0 {
        return false;
    }
    let c = Vec3::from_slice(&volume.sphere[..3]);
    let d = c - c.clamp(min, max);
    d.length_squared() <= r * r && cone_reaches(volume, 0.5 * (min + max), 0.5 * (max - min).length() * (1.0 + 1e-4))
}

/// Whether a spot light's cone, cut at its range, may reach the sphere (`centre`, `radius`);
/// true for a light without a cone. `cone_reaches` in glsl/clustered/clusters.glsl, which says
/// why the test is conservative.
pub fn cone_reaches(volume: &LightVolume, centre: Vec3, radius: f32) -> bool {
    let (cos_outer, sin_outer) = (volume.apex[3], volume.axis[3]);
    if sin_outer < 0.0 {
        return true;
    }
    let to_c = centre - Vec3::from_slice(&volume.apex[..3]);
    let along = to_c.dot(Vec3::from_slice(&volume.axis[..3]));
    let off = (to_c.length_squared() - along * along).max(0.0).sqrt();
    cos_outer * off - sin_outer * along <= radius
        && (along >= -radius || cos_outer < 0.0)
        && along <= radius + volume.range[0]
}

/// Whether `volume` reaches the column of tile (`x`, `y`) between the near and far depths, as
/// `reaches_column` in glsl/clustered/clusters.glsl: not wholly outside one of the column's side
/// planes through the eye, nor before the near or past the far depth.
pub fn reaches_column(block: &ClusterBlock, x: u32, y: u32, volume: &LightVolume) -> bool {
    let s = volume.sphere;
    if s[3] < 0.0 {
        return false;
    }
    let [cols, rows, _, _] = block.grid;
    let [_, _, sx, sy] = block.screen;
    let (x0, x1) = (
        x as f32 / cols as f32 * 2.0 - 1.0,
        (x + 1) as f32 / cols as f32 * 2.0 - 1.0,
    );
    let (y0, y1) = (
        y as f32 / rows as f32 * 2.0 - 1.0,
        (y + 1) as f32 / rows as f32 * 2.0 - 1.0,
    );
    let c = Vec3::from_slice(&s[..3]);
    let r = s[3] + 1e-4 * c.length();
    let planes = [
        Vec3::new(1.0, 0.0, x0 * sx),
        Vec3::new(-1.0, 0.0, -x1 * sx),
        Vec3::new(0.0, 1.0, -y1 * sy),
        Vec3::new(0.0, -1.0, y0 * sy),
    ];
    planes.iter().all(|p| p.normalize().dot(c) >= -r) && -c.z + r >= block.depth[0] && -c.z - r <= block.depth[1]
}

/// The GPU's assignment computed on the CPU: per cluster, the lights that reach its tile's
/// column and touch its box, in light order (uncapped).
pub fn assign_cpu(block: &ClusterBlock, volumes: &[LightVolume]) -> Vec<Vec<u32>> {
    let clusters = block.grid[0] * block.grid[1] * block.grid[2];
    (0..clusters)
        .map(|c| {
            let (x, y) = (c % block.grid[0], (c / block.grid[0]) % block.grid[1]);
            let (min, max) = froxel_bounds(block, c);
            volumes
                .iter()
                .enumerate()
                .filter(|(_, v)| reaches_column(block, x, y, v) && touches(v, min, max))
                .map(|(i, _)| i as u32)
                .collect()
        })
        .collect()
}

/// Clusters whose uncapped light count is over the cap.
pub fn overflowed_clusters(counts: &[u32], max_per_cluster: u32) -> usize {
    counts.iter().filter(|&&n| n > max_per_cluster).count()
}

/// Light-cluster pairs beyond the cap, summed over the clusters.
pub fn dropped(counts: &[u32], max_per_cluster: u32) -> u64 {
    counts.iter().map(|&n| n.saturating_sub(max_per_cluster) as u64).sum()
}

/// The assignment as the GPU wrote it, read back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    /// Per cluster, the lights that touch it: this many, though only `max_per_cluster` are kept.
    pub counts: Vec<u32>,
    /// Per cluster, the kept light indices (at most `max_per_cluster`).
    pub lights: Vec<Vec<u32>>,
    pub max_per_cluster: u32,
}

impl Assignment {
    pub fn from_words(counts: &[u32], indices: &[u32], max_per_cluster: u32) -> Assignment {
        let cap = max_per_cluster as usize;
        let lights = counts
            .iter()
            .enumerate()
            .map(|(c, &n)| indices[c * cap..c * cap + (n as usize).min(cap)].to_vec())
            .collect();
        Assignment {
            counts: counts.to_vec(),
            lights,
            max_per_cluster,
        }
    }

    /// Clusters that had more lights than slots.
    pub fn overflowed_clusters(&self) -> usize {
        overflowed_clusters(&self.counts, self.max_per_cluster)
    }

    /// Light-cluster pairs dropped for want of slots.
    pub fn dropped(&self) -> u64 {
        dropped(&self.counts, self.max_per_cluster)
    }

    /// The clusters holding light `i`.
    pub fn clusters_of(&self, i: u32) -> Vec<usize> {
        self.lights
            .iter()
            .enumerate()
            .filter(|(_, l)| l.contains(&i))
            .map(|(c, _)| c)
            .collect()
    }
}
