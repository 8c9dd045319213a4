//! The registry: the only place that names techniques. Each entry says what the method accepts
//! (its schema, checked when the scene is loaded), which terms it supplies, how `penumbra chart`
//! sweeps it, what reference it is judged against, whether it draws translucent materials, how
//! it is created, and what it adds to `profile`'s report.
//!
//! Adding a technique: a folder under `src/lighting/` with a type implementing
//! [`LightingMethod`], its shaders in `glsl/<technique>/`, and one entry in [`registry`].

use super::plan::{Derived, Facts};
use super::terms::{self, Supply};
use super::{
    bsp_lights, clustered, forward, heightfield, lpv, prt, radiosity, sh_lightmap, shadow_volumes, vls, Configuration,
    CreateContext, LightingMethod, ReferenceKind, Terms,
};
use crate::error::{Error, Result};
use crate::scene::{MethodDecl, MethodSchema, Scene};
use crate::util::timing::PassStats;

/// Creates a method from its declaration.
pub type CreateFn = fn(&mut CreateContext<'_>, &MethodDecl) -> Result<Box<dyn LightingMethod>>;

/// The parameters a declaration leaves unset, derived from the scene, after refusing what would
/// not fit the memory budget (nothing is allocated yet).
pub type PlanFn = fn(&MethodDecl, &Facts<'_>) -> Result<Vec<Derived>>;

/// Extra lines for `profile`'s report, from the frame's pass timings (`None`: nothing to add).
pub type ReportFn = fn(&[PassStats]) -> Option<String>;

/// What a method keeps of a moving scene's time-0 state, and why.
#[derive(Clone, Copy, Debug)]
pub struct RestPose {
    pub why: &'static str,
    /// It keeps the scene's light direction too, not only the objects' rest pose.
    pub keeps_light_motion: bool,
}

impl RestPose {
    /// The objects and the lights, as the bake took them.
    const fn all(why: &'static str) -> Option<RestPose> {
        Some(RestPose {
            why,
            keeps_light_motion: true,
        })
    }

    /// The objects only: the lights are read every frame.
    const fn objects(why: &'static str) -> Option<RestPose> {
        Some(RestPose {
            why,
            keeps_light_motion: false,
        })
    }
}

/// One technique as the rest of penumbra sees it.
pub struct MethodInfo {
    pub schema: MethodSchema,
    /// The terms it can supply, and whether it can supply a subset of them.
    pub terms: Terms,
    pub separable: bool,
    /// The configurations to measure, as (label, declaration with the swept parameters set),
    /// starting from the scene's declaration.
    pub sweep: fn(&MethodDecl) -> Vec<(String, MethodDecl)>,
    pub reference: fn(&MethodDecl) -> ReferenceKind,
    /// It draws materials with opacity < 1 (others refuse such scenes).
    pub translucency: bool,
    pub create: CreateFn,
    /// Extra lines for `profile`'s report, from the frame's pass timings.
    pub report: Option<ReportFn>,
    /// `None`: it draws the scene's vertex buffer and reads the lights every frame, so it follows
    /// the scene's wind and light motion; otherwise what it keeps of the rest pose, and why (it
    /// says so when created for a scene that moves).
    pub rest_pose: Option<RestPose>,
    /// Derives unset parameters from the scene and checks the memory budget.
    pub plan: Option<PlanFn>,
}

/// Every method penumbra implements.
// long: a table, one entry per method.
pub fn registry() -> Vec<MethodInfo> {
    vec![
        MethodInfo {
            schema: forward::SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: true,
            sweep: forward::sweep,
            reference: |_| ReferenceKind::Direct,
            translucency: true,
            create: |c, d| Ok(Box::new(forward::Forward::new(c, d)?)),
            rest_pose: None,
            report: None,
            plan: None,
        },
        MethodInfo {
            schema: shadow_volumes::SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: true,
            sweep: shadow_volumes::sweep,
            reference: |_| ReferenceKind::Direct,
            translucency: true,
            create: |c, d| Ok(Box::new(shadow_volumes::ShadowVolumes::new(c, d)?)),
            rest_pose: RestPose::objects("its shadow volumes are extruded from the entities' rest-pose positions"),
            report: None,
            plan: None,
        },
        MethodInfo {
            schema: heightfield::PYRAMID_SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: false,
            sweep: heightfield::pyramid_sweep,
            reference: |_| ReferenceKind::Direct,
            translucency: false,
            create: |c, d| Ok(Box::new(heightfield::HeightfieldMethod::new(c, d)?)),
            rest_pose: RestPose::all("it traces its height field's time-0 shape"),
            report: Some(heightfield::measure::table_6_6),
            plan: None,
        },
        MethodInfo {
            schema: heightfield::BRUTE_FORCE_SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: false,
            sweep: heightfield::brute_sweep,
            reference: |_| ReferenceKind::Direct,
            translucency: false,
            create: |c, d| Ok(Box::new(heightfield::HeightfieldMethod::new(c, d)?)),
            rest_pose: RestPose::all("it traces its height field's time-0 shape"),
            report: Some(heightfield::measure::table_6_6),
            plan: None,
        },
        MethodInfo {
            schema: radiosity::SCHEMA,
            terms: Terms::BASE,
            separable: false,
            sweep: radiosity::sweep,
            reference: radiosity::reference,
            translucency: false,
            create: |c, d| Ok(Box::new(radiosity::Radiosity::new(c, d)?)),
            rest_pose: RestPose::all("its light-map is baked from the rest pose and the scene's lights"),
            report: None,
            plan: Some(radiosity::plan),
        },
        MethodInfo {
            schema: sh_lightmap::SCHEMA,
            terms: Terms::BASE,
            separable: false,
            sweep: sh_lightmap::sweep,
            reference: sh_lightmap::reference,
            translucency: false,
            create: |c, d| Ok(Box::new(sh_lightmap::ShLightmap::new(c, d)?)),
            rest_pose: RestPose::all("its light-map is baked from the rest pose"),
            report: None,
            plan: Some(sh_lightmap::plan),
        },
        MethodInfo {
            schema: prt::SCHEMA,
            terms: Terms::BASE,
            separable: false,
            sweep: prt::sweep,
            reference: prt::reference,
            translucency: false,
            create: |c, d| Ok(Box::new(prt::Prt::new(c, d)?)),
            rest_pose: RestPose::all("its transfer is baked from the rest pose"),
            report: None,
            plan: Some(prt::plan),
        },
        MethodInfo {
            schema: lpv::SCHEMA,
            terms: Terms::INDIRECT,
            separable: true,
            sweep: lpv::sweep,
            reference: lpv::reference,
            translucency: false,
            create: |c, d| Ok(Box::new(lpv::Lpv::new(c, d)?)),
            rest_pose: None,
            report: None,
            plan: Some(lpv::plan),
        },
        MethodInfo {
            schema: clustered::SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: true,
            sweep: clustered::sweep,
            // Unshadowed: judged against the shadowed direct reference, its shadows are error.
            reference: |_| ReferenceKind::Direct,
            translucency: false,
            create: |c, d| Ok(Box::new(clustered::Clustered::new(c, d)?)),
            rest_pose: None,
            report: None,
            plan: None,
        },
        MethodInfo {
            schema: vls::SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: true,
            sweep: vls::sweep,
            reference: vls::reference,
            translucency: false,
            create: |c, d| Ok(Box::new(vls::Vls::new(c, d)?)),
            rest_pose: RestPose::all("each segment's lights and shadow feelers are chosen once, from the rest pose"),
            report: None,
            plan: Some(vls::plan),
        },
        MethodInfo {
            schema: bsp_lights::SCHEMA,
            terms: Terms::BASE_DIRECT,
            separable: true,
            sweep: bsp_lights::sweep,
            reference: bsp_lights::reference,
            translucency: false,
            create: |c, d| Ok(Box::new(bsp_lights::BspLights::new(c, d)?)),
            rest_pose: RestPose::all("its per-light vertex colours are baked from the rest pose"),
            report: None,
            plan: Some(bsp_lights::plan),
        },
    ]
}

/// Every method scenes may declare, with its parameters.
pub fn schemas() -> Vec<MethodSchema> {
    registry().into_iter().map(|m| m.schema).collect()
}

pub fn info(name: &str) -> Result<MethodInfo> {
    registry()
        .into_iter()
        .find(|m| m.schema.name == name)
        .ok_or_else(|| Error::Usage(format!("method `{name}` is not implemented")))
}

fn supply() -> Vec<Supply> {
    registry()
        .iter()
        .map(|m| Supply {
            name: m.schema.name,
            terms: m.terms,
            separable: m.separable,
        })
        .collect()
}

/// Every configuration the scene declares: each method alone, then each combination.
pub fn configurations(scene: &Scene) -> Result<Vec<Configuration>> {
    scene.check_methods(&schemas())?;
    Ok(terms::configurations(scene, &supply())?)
}

/// Method `name` at its defaults, where the scene declares no method of its own (an asset alone,
/// or a scene file without `methods`, which draws with `forward`): such a scene takes any method
/// by name, as a viewer would. `None` for a scene that declares its methods, or an unknown name.
pub fn undeclared(scene: &Scene, name: &str) -> Option<Configuration> {
    let declares_none = scene.methods == [MethodDecl::implicit_forward()] && scene.combinations.is_empty();
    (declares_none && schemas().iter().any(|s| s.name == name)).then(|| {
        alone(&MethodDecl {
            name: name.to_owned(),
            line: 0,
            params: Vec::new(),
        })
    })
}

/// What a viewer offers for the scene: its own configurations, then, where it declares no method,
/// every other method at its defaults ([`undeclared`]), in the registry's order.
pub fn offered(scene: &Scene) -> Result<Vec<Configuration>> {
    let mut all = configurations(scene)?;
    for s in schemas() {
        if !all.iter().any(|c| c.name == s.name) {
            all.extend(undeclared(scene, s.name));
        }
    }
    Ok(all)
}

/// The configuration called `name` (a method or a combination), or the scene's first method.
pub fn configuration(scene: &Scene, name: Option<&str>) -> Result<Configuration> {
    let all = configurations(scene)?;
    match name {
        None => all
            .into_iter()
            .next()
            .ok_or_else(|| Error::Usage(format!("{}: the scene enables no method", scene.source))),
        Some(n) => {
            if let Some(c) = all
                .iter()
                .find(|c| c.name == n)
                .cloned()
                .or_else(|| undeclared(scene, n))
            {
                return Ok(c);
            }
            let names: Vec<String> = all.iter().map(|c| c.name.clone()).collect();
            let known: Vec<&str> = schemas().iter().map(|s| s.name).collect();
            if known.contains(&n) {
                return Err(Error::Usage(format!(
                    "{}: method `{n}` is not enabled by the scene (it enables: {})",
                    scene.source,
                    names.join(", ")
                )));
            }
            let combinations = if scene.combinations.is_empty() {
                String::new()
            } else {
                format!(
                    "; the scene's combinations: {}",
                    scene
                        .combinations
                        .iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            };
            Err(Error::Usage(format!(
                "--method {n}: unknown method; known methods: {}{combinations}",
                known.join(", ")
            )))
        }
    }
}

/// The configuration of one method declaration alone (the chart's sweep points).
pub fn alone(decl: &MethodDecl) -> Configuration {
    terms::alone(decl, &supply())
}

/// The reference a configuration is judged against: the most any of its parts models.
pub fn reference_kind(config: &Configuration) -> Result<ReferenceKind> {
    let mut kind: Option<ReferenceKind> = None;
    for p in &config.parts {
        let k = (info(&p.decl.name)?.reference)(&p.decl);
        kind = Some(kind.map_or(k, |a| a.combine(k)));
    }
    Ok(kind.unwrap_or(ReferenceKind::Direct))
}

/// One line per method of `config` that keeps the rest pose in a scene that moves (wind, a
/// turning light): what it leaves out, and why.
pub fn motion_notes(config: &Configuration, scene: &Scene) -> Vec<String> {
    let mut out = Vec::new();
    for p in &config.parts {
        let Some(rest) = info(&p.decl.name).ok().and_then(|i| i.rest_pose) else {
            continue;
        };
        let why = rest.why;
        if let Some(what) = scene.motion_summary_of(rest.keeps_light_motion) {
            let line = format!("{}: note: the {} method keeps the rest pose ({why}): {what} moves in every other method and in the reference, not in it", scene.source, p.decl.name);
            if !out.contains(&line) {
                out.push(line);
            }
        }
    }
    out
}

/// `config` with every part's unset parameters derived from the scene, and the lines saying
/// what was derived and why; refused in one line when a part would not fit the memory budget.
/// Nothing is allocated: `capture` and `chart` call it before the device is created.
pub fn plan(config: &Configuration, scene: &Scene) -> Result<(Configuration, Vec<String>)> {
    let facts = Facts::new(scene);
    let mut out = config.clone();
    let mut notes = Vec::new();
    for p in &mut out.parts {
        if let Some(f) = info(&p.decl.name)?.plan {
            let derived = f(&p.decl, &facts)?;
            for line in super::plan::notes(&p.decl.name, &derived) {
                if !notes.contains(&line) {
                    notes.push(line);
                }
            }
            p.decl = super::plan::apply(&p.decl, &derived);
        }
    }
    Ok((out, notes))
}

/// Creates the methods of a configuration, in frame order, refusing translucent materials for
/// methods that do not draw them. A method that keeps the rest pose of a moving scene says so on
/// standard error ([`motion_notes`]).
pub fn create(config: &Configuration, ctx: &mut CreateContext<'_>) -> Result<Vec<Box<dyn LightingMethod>>> {
    for line in motion_notes(config, ctx.scene) {
        crate::errln!("{line}");
    }
    // A configuration already planned derives nothing more; one that was not is planned here.
    let (config, _) = plan(config, ctx.scene)?;
    let mut out = Vec::new();
    for p in &config.parts {
        let info = info(&p.decl.name)?;
        if !info.translucency {
            ctx.scene
                .refuse_translucency(&format!("the {} method", p.decl.name))
                .map_err(Error::Usage)?;
        }
        ctx.terms = p.terms;
        out.push((info.create)(ctx, &p.decl)?);
    }
    Ok(out)
}

/// What the configuration's methods add to `profile`'s report.
pub fn reports(config: &Configuration, passes: &[PassStats]) -> String {
    let mut out = String::new();
    let mut seen: Vec<usize> = Vec::new();
    for p in &config.parts {
        if let Ok(info) = info(&p.decl.name) {
            if let Some(f) = info.report {
                // Two parts with the same hook report once.
                let id = f as usize;
                if !seen.contains(&id) {
                    seen.push(id);
                    out += &f(passes).unwrap_or_default();
                }
            }
        }
    }
    out
}

/// The points `penumbra chart` measures for a configuration, as (label, configuration): a method
/// alone is its own sweep; a combination is measured as declared, then with each part swept while
/// the others stay as declared.
pub fn sweep(config: &Configuration) -> Result<Vec<(String, Configuration)>> {
    let part_sweep = |i: usize| -> Result<Vec<(String, Configuration)>> {
        let p = &config.parts[i];
        let info = info(&p.decl.name)?;
        Ok((info.sweep)(&p.decl)
            .into_iter()
            .map(|(label, decl)| {
                let mut c = config.clone();
                c.parts[i].decl = decl;
                (label, c)
            })
            .collect())
    };
    if config.parts.len() == 1 {
        return part_sweep(0);
    }
    let mut out = vec![(config.name.clone(), config.clone())];
    for i in 0..config.parts.len() {
        for (label, c) in part_sweep(i)? {
            let label = format!("{}: {label}", config.name);
            if c != *config && !out.iter().any(|(l, _)| *l == label) {
                out.push((label, c));
            }
        }
    }
    Ok(out)
}
