//! The clustered method's parameters (scenes/README.md, `clustered`): the cluster grid, the
//! per-cluster light cap and the irradiance that ends a light's range when the scene gives none.

use crate::error::Result;
use crate::lighting::params::Params;
use crate::scene::{MethodDecl, Scene};

/// The grid's memory cap: per cluster a 32-byte box, a count and `max_per_cluster` 32-bit
/// index slots.
pub const MAX_GRID_BYTES: u64 = 256 << 20;

/// Tiles in all: one assignment workgroup each, under the 65,535 workgroups a dispatch may have.
pub const MAX_TILES: u32 = 16384;

/// Clusters in all: one bounds invocation each, in workgroups of 64.
pub const MAX_CLUSTERS: u32 = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Screen tiles across and down. A fixed grid rather than a tile size in pixels: the method's
    /// buffers are made before the frame's size is known and survive a resize.
    pub tiles: [u32; 2],
    /// Depth slices, exponentially spaced from the camera's near plane to the far side of the
    /// scene's geometry.
    pub slices: u32,
    /// Index slots per cluster; lights past it are dropped and counted.
    pub max_per_cluster: u32,
    /// Irradiance (W/m², at normal incidence) at which a light without a `radius` ends: its
    /// range is sqrt(max(intensity.rgb) / cutoff).
    pub cutoff: f32,
}

impl Default for Config {
    fn default() -> Config {
        Config {
            tiles: [32, 18],
            slices: 24,
            max_per_cluster: 128,
            cutoff: 0.01,
        }
    }
}

impl Config {
    pub fn clusters(&self) -> u32 {
        self.tiles[0] * self.tiles[1] * self.slices
    }

    pub fn index_bytes(&self) -> u64 {
        self.clusters() as u64 * self.max_per_cluster as u64 * 4
    }

    /// The boxes, counts and index slots together.
    pub fn grid_bytes(&self) -> u64 {
        self.clusters() as u64 * (32 + 4) + self.index_bytes()
    }

    pub fn from_decl(decl: &MethodDecl, scene: Option<&Scene>) -> Result<Config> {
        let params = Params::new(decl, scene);
        let bad = |p: &str, want: &str, got: &toml::Value| params.error(p, want, got);
        let mut c = Config::default();
        let int = |p: &str, v: &toml::Value, range: std::ops::RangeInclusive<i64>, want: &str| {
            v.as_integer()
                .filter(|n| range.contains(n))
                .map(|n| n as u32)
                .ok_or_else(|| bad(p, want, v))
        };
        for (p, v, _) in &decl.params {
            let p = p.as_str();
            match p {
                "tiles" => {
                    let want = "[columns, rows], two integers from 1 to 256";
                    let grid: Option<Vec<u32>> = v.as_array().filter(|a| a.len() == 2).and_then(|a| {
                        a.iter()
                            .map(|x| x.as_integer().filter(|n| (1..=256).contains(n)).map(|n| n as u32))
                            .collect()
                    });
                    let grid = grid.ok_or_else(|| bad(p, want, v))?;
                    c.tiles = [grid[0], grid[1]];
                }
                "slices" => {
                    c.slices = int(
                        p,
                        v,
                        1..=super::MAX_SLICES as i64,
                        &format!("a depth slice count from 1 to {}", super::MAX_SLICES),
                    )?
                }
                // Up to every light a scene may have: a dense rig can put all of them in one cluster.
                "max_per_cluster" => {
                    c.max_per_cluster = int(
                        p,
                        v,
                        1..=super::MAX_LIGHTS as i64,
                        &format!("index slots per cluster from 1 to {}", super::MAX_LIGHTS),
                    )?
                }
                "cutoff" => {
                    c.cutoff = Params::float(v)
                        .filter(|x| x.is_finite() && *x > 0.0)
                        .map(|x| x as f32)
                        .ok_or_else(|| bad(p, "an irradiance > 0 (W/m²)", v))?
                }
                _ => {}
            }
        }
        // Blame the last of the grid's parameters the scene gives.
        let blame = |order: &[&'static str]| {
            let p = order
                .iter()
                .copied()
                .find(|p| decl.param(p).is_some())
                .unwrap_or(order[0]);
            (p, decl.param(p).cloned().unwrap_or(toml::Value::from("the default")))
        };
        if c.tiles[0] * c.tiles[1] > MAX_TILES {
            let (p, got) = blame(&["tiles"]);
            return Err(bad(
                p,
                &format!("at most {MAX_TILES} tiles in all (one workgroup each)"),
                &got,
            ));
        }
        if c.clusters() > MAX_CLUSTERS {
            let (p, got) = blame(&["slices", "tiles"]);
            return Err(bad(
                p,
                &format!(
                    "at most {MAX_CLUSTERS} clusters (columns × rows × slices is {})",
                    c.clusters()
                ),
                &got,
            ));
        }
        if c.grid_bytes() > MAX_GRID_BYTES {
            let (p, got) = blame(&["max_per_cluster", "slices", "tiles"]);
            let want = format!(
                "a grid that fits in {} MiB (boxes, counts and max_per_cluster index slots per cluster: {} MiB)",
                MAX_GRID_BYTES >> 20,
                c.grid_bytes() >> 20
            );
            return Err(bad(p, &want, &got));
        }
        Ok(c)
    }
}
