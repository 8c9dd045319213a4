//! What every GPU bake that runs in submissions shares (the radiosity shooter, the SH light-map
//! ray caster, the PRT ray caster): work per submission sized by time, the status word a bake
//! shader sets when the device cut an invocation's loops short, and small upload helpers.
//!
//! Why time-sized submissions: a fixed size is either too small on a GPU (each submission's fixed
//! cost dominates) or too large on lavapipe (a progress line that stalls for minutes, and a lot of
//! work thrown away when a loop is cut and the submission runs again with fewer rays per
//! invocation).

use std::time::Duration;

use crate::backend::{vk, BufferId, Gpu, MemoryKind};
use crate::error::{Error, Result};

/// A submission long enough that its fixed cost is small, short enough for a lively progress line.
pub const SUBMISSION_TARGET_SECONDS: f64 = 0.25;

/// The work items of the next submission: starts small (a device that cuts loops short wastes
/// little), then follows the measured rate toward [`SUBMISSION_TARGET_SECONDS`], growing at most
/// `growth` times over the last submission and staying within `min..=max`.
#[derive(Clone, Debug)]
pub struct BatchSizer {
    size: usize,
    min: usize,
    max: usize,
    growth: usize,
}

impl BatchSizer {
    /// `first` is clamped into `min..=max`; `max` below `min` is raised to `min`.
    pub fn new(first: usize, min: usize, max: usize, growth: usize) -> BatchSizer {
        let max = max.max(min);
        BatchSizer {
            size: first.clamp(min, max),
            min,
            max,
            growth: growth.max(1),
        }
    }

    /// Items for the next submission.
    pub fn size(&self) -> usize {
        self.size
    }

    /// After a submission of `done` items that took `elapsed`: the size that would take the target
    /// time at that rate, within the growth limit and the bounds. A last, short submission must
    /// not bring the ceiling under the floor, hence the ceiling is at least `min`.
    pub fn record(&mut self, done: usize, elapsed: Duration) {
        let seconds = elapsed.as_secs_f64().max(1e-9);
        let fit = (SUBMISSION_TARGET_SECONDS * done as f64 / seconds) as usize;
        let ceiling = self.growth.saturating_mul(done).min(self.max).max(self.min);
        self.size = fit.clamp(self.min, ceiling);
    }

    /// After the device cut a submission's loops short: half as many items (not below `min`), to
    /// be traced again with fewer rays per invocation.
    pub fn shrink(&mut self) {
        self.size = self.size.div_ceil(2).max(self.min);
    }
}

/// The count a bake shader left in its 4-byte status buffer: how many invocations the device cut
/// short (llvmpipe ends an invocation's loops after 65,535 iterations). A buffer that reads back
/// short is an internal fault.
pub fn cut_invocations(gpu: &Gpu, status: BufferId, bake: &str) -> Result<u32> {
    let bytes = gpu.read_buffer(status)?;
    bytes
        .get(..4)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .ok_or_else(|| Error::Internal(format!("{bake}: the status word read back short")))
}

/// The error for a bake whose rays still run past the device's loop limit at one ray per
/// invocation: the device cannot run it, the CPU baker can (`remedy` says how to choose it).
pub fn loop_limit_error(gpu: &Gpu, cut: u32, what: &str, remedy: &str) -> Error {
    Error::Usage(format!(
        "{}: {cut} {what}, traced one per shader invocation, ran more loop iterations than the device allows an \
         invocation; {remedy}",
        gpu.caps().name
    ))
}

/// A storage buffer filled with `data` (`usage` added), in device memory.
pub fn storage_buffer(gpu: &mut Gpu, name: &str, usage: vk::BufferUsageFlags, data: &[u8]) -> Result<BufferId> {
    Ok(gpu.create_buffer_init(name, usage | vk::BufferUsageFlags::STORAGE_BUFFER, data)?)
}

/// A 4-byte status word the shader writes and the host reads after every submission.
pub fn status_buffer(gpu: &mut Gpu, bake: &str) -> Result<BufferId> {
    Ok(gpu.create_storage_output(&format!("{bake} status"), 4, MemoryKind::GpuToCpu)?)
}

/// A vector as a std430 `vec4` with `w` in the last lane.
pub fn vec4(v: impl Into<[f32; 3]>, w: f32) -> [f32; 4] {
    let [x, y, z] = v.into();
    [x, y, z, w]
}

/// A double-precision vector as a std430 `vec4` (rounded to f32) with `w` in the last lane.
pub fn dvec4(v: glam::DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batches_follow_the_rate_within_growth_and_bounds() {
        let mut s = BatchSizer::new(64, 16, 1 << 20, 8);
        assert_eq!(s.size(), 64);
        // 64 items in 1 ms: the fit (16,000) is capped at 8 × 64.
        s.record(64, Duration::from_millis(1));
        assert_eq!(s.size(), 512);
        // 512 items in 1 s: a quarter second is 128.
        s.record(512, Duration::from_secs(1));
        assert_eq!(s.size(), 128);
        // Very slow: never below the floor.
        s.record(128, Duration::from_secs(1000));
        assert_eq!(s.size(), 16);
        // A last, short submission (1 item) keeps the ceiling at the floor, not under it.
        s.record(1, Duration::from_nanos(1));
        assert_eq!(s.size(), 16);
        s.shrink();
        assert_eq!(s.size(), 16);
    }

    #[test]
    fn the_ceiling_is_the_maximum() {
        let mut s = BatchSizer::new(4, 1, 512, 2);
        for _ in 0..20 {
            let n = s.size();
            s.record(n, Duration::from_micros(1));
        }
        assert_eq!(s.size(), 512);
        s.shrink();
        assert_eq!(s.size(), 256);
        assert_eq!(
            BatchSizer::new(10_000, 64, 32, 2).size(),
            64,
            "max below min is raised to min"
        );
    }
}
