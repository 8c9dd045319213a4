//! Before a method allocates anything: the parameters a scene leaves unset, derived from the
//! scene's size (its extent, area and triangle count) and a memory budget, each with the reason
//! `capture` and `chart` print; and the memory the method would need, refused in one line when
//! it is over the budget.

use std::cell::OnceCell;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::lighting::lightmap::patches::Triangle;
use crate::scene::{MethodDecl, Scene};

/// What a method may allocate when the scene sets no `memory_budget_mb`.
pub const DEFAULT_BUDGET_MB: f64 = 2048.0;

/// One parameter the scene left unset, and why it has the value it was given.
#[derive(Clone, Debug, PartialEq)]
pub struct Derived {
    pub param: &'static str,
    pub value: toml::Value,
    pub why: String,
}

impl Derived {
    pub fn new(param: &'static str, value: impl Into<toml::Value>, why: impl Into<String>) -> Derived {
        Derived {
            param,
            value: value.into(),
            why: why.into(),
        }
    }
}

/// The scene as the derivations read it; its triangles are loaded once, on first use.
pub struct Facts<'a> {
    pub scene: &'a Scene,
    triangles: OnceCell<std::result::Result<Vec<Triangle>, String>>,
}

impl<'a> Facts<'a> {
    pub fn new(scene: &'a Scene) -> Facts<'a> {
        Facts {
            scene,
            triangles: OnceCell::new(),
        }
    }

    /// The scene's objects and area-light emitters in world space, as the light-map bakers patch
    /// them.
    pub fn triangles(&self, method: &str) -> Result<&[Triangle]> {
        self.triangles
            .get_or_init(|| {
                // Measured, not patched: sphere lights (which the light-map bakers refuse when
                // they bake) have no emitter triangles and leave the measure as it is.
                let measured = Scene {
                    lights: (self.scene.lights.iter())
                        .filter(|l| !matches!(l, crate::scene::Light::Sphere { .. }))
                        .cloned()
                        .collect(),
                    ..self.scene.clone()
                };
                crate::lighting::lightmap::geometry::scene_geometry(&measured, method)
                    .map(|g| g.triangles)
                    .map_err(|e| e.to_string())
            })
            .as_deref()
            .map_err(|e| Error::Usage(e.clone()))
    }

    /// Σ triangle area (m²) of the scene's objects and emitters.
    pub fn area(&self, method: &str) -> Result<f64> {
        Ok(self.triangles(method)?.iter().map(Triangle::area).sum())
    }

    /// The bounds of the scene's triangles, `None` when it has none.
    pub fn bounds(&self, method: &str) -> Result<Option<(DVec3, DVec3)>> {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in self.triangles(method)?.iter().flat_map(|t| t.p) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        Ok(lo.is_finite().then_some((lo, hi)))
    }

    /// The memory budget in bytes, and where it comes from.
    pub fn budget(&self) -> (u64, &'static str) {
        match self.scene.memory_budget_mb {
            Some(mb) => ((mb * MB) as u64, "the scene's memory_budget_mb or --memory-budget-mb"),
            None => ((DEFAULT_BUDGET_MB * MB) as u64, "the default memory_budget_mb"),
        }
    }

    /// Refuses `what`, which needs `need` bytes, when that is over the budget: one line naming
    /// the scene, the method, the size, and the two ways out.
    pub fn check(&self, method: &str, what: &str, need: u64, smaller: &str) -> Result<()> {
        let (budget, from) = self.budget();
        if need <= budget {
            return Ok(());
        }
        Err(Error::Usage(format!(
            "{}: {method}: {what} would need {}, over the memory budget of {} ({from}): {smaller}, or raise `memory_budget_mb` at the scene's top level (or --memory-budget-mb)",
            self.scene.source,
            bytes(need),
            bytes(budget)
        )))
    }
}

const MB: f64 = 1024.0 * 1024.0;

/// `n` bytes for a person: MB below a GB, else GB.
pub fn bytes(n: u64) -> String {
    let mb = n as f64 / MB;
    if mb < 1024.0 {
        format!("{mb:.1} MB")
    } else {
        format!("{:.1} GB", mb / 1024.0)
    }
}

/// `x` rounded to two significant digits (derived sizes read as chosen, not computed).
pub fn round2(x: f64) -> f64 {
    if x <= 0.0 || !x.is_finite() {
        return x;
    }
    let e = x.log10().floor() as i32 - 1;
    // Dividing by an exact power of ten keeps 0.012 from reading 0.012000000000000002.
    if e < 0 {
        let s = 10f64.powi(-e);
        (x * s).round() / s
    } else {
        let s = 10f64.powi(e);
        (x / s).round() * s
    }
}

/// An area (m²) for a printed reason: three decimals where that reads, else three significant
/// digits in scientific notation (a 3 cm model's 0.000 m² said nothing).
pub fn area_text(area: f64) -> String {
    if (0.01..1e7).contains(&area) {
        format!("{area:.3}")
    } else {
        format!("{area:.3e}")
    }
}

/// A light-map's patch side (m) for `area` m² over `budget` patches, to two significant digits.
/// No bound in metres: a model in millimetres or a 3 cm figurine takes the same patches per
/// face as a room in metres.
pub fn patch_size_for(area: f64, budget: f64) -> f64 {
    round2((area / budget).sqrt())
}

/// A light-map's default patch side, and why: the scene's area over `budget` patches
/// ([`patch_size_for`]), or where that makes over four times the budget, the smallest size up
/// to four times it (in steps of 1.25) that makes at most that many. Every chart (a group of
/// triangles on a plane, or on a curved surface within a quarter patch of one) takes at least a
/// texel and its border frame, nine patches, at any size, so charts a few patches wide make
/// more patches than their area says until the size grows. Border frames alone make a room of
/// large faces about twice the budget (1.6 to 2.3 times over the generated suite's rooms), which
/// the limit leaves alone. Where no size meets the limit, the area's is kept rather than
/// coarsening the large faces for nothing.
pub fn lightmap_patch_size(triangles: &[Triangle], budget: f64) -> (f64, String) {
    use crate::lighting::lightmap::patches::count;
    let area: f64 = triangles.iter().map(Triangle::area).sum();
    let limit = (4.0 * budget) as u64;
    let from_area = patch_size_for(area, budget);
    let at_area = count(triangles, from_area);
    let mut why = format!("the scene's {} m² over a budget of {budget} patches", area_text(area));
    if at_area <= limit {
        return (from_area, why);
    }
    let mut size = from_area;
    while size < 4.0 * from_area {
        size = round2(size * 1.25);
        // Charts are grouped again at each size: a curved surface's charts grow with it.
        let patches = count(triangles, size);
        if patches <= limit {
            why += &format!(", grown from {from_area} to make at most four times that ({patches})");
            return (size, why);
        }
    }
    why += &format!("; its charts make {at_area} patches, and sizes up to four times larger not four times the budget");
    (from_area, why)
}

/// Segments the many-light methods get when the scene sets no `max_segment_area`: their set-up
/// casts a feeler per segment and light, so the count is what is budgeted (measured on lavapipe,
/// VLS's set-up of the 100-light theatre, 351 m², took 0.5 s at 0.05 m² and 5.0 s at 0.021 m²).
pub const SEGMENT_BUDGET: f64 = 8192.0;

/// Segments (and about as many vertices) `triangles` are cut into at `max_area`: each triangle
/// split in four until no piece is larger, as the segmentation does.
pub fn segments_for(triangles: &[Triangle], max_area: f64) -> u64 {
    triangles
        .iter()
        .map(|t| {
            let (mut a, mut n) = (t.area(), 1u64);
            while a > max_area && n < 1 << 32 {
                a /= 4.0;
                n *= 4;
            }
            n
        })
        .sum()
}

/// The lines `capture` and `chart` print for `derived` of `method`.
pub fn notes(method: &str, derived: &[Derived]) -> Vec<String> {
    derived
        .iter()
        .map(|d| {
            format!(
                "{method}: {} = {} ({}; set {} to override)",
                d.param, d.value, d.why, d.param
            )
        })
        .collect()
}

/// `decl` with `derived` set (as a chart's sweep point sets them: line 0).
pub fn apply(decl: &MethodDecl, derived: &[Derived]) -> MethodDecl {
    derived
        .iter()
        .fold(decl.clone(), |d, x| d.with(x.param, x.value.clone()))
}
