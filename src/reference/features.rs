//! What a traced scene holds, as the tracer's specialization constants
//! (`glsl/reference/features.glsl`).
//!
//! llvmpipe compiles a branch as both of its sides with SIMD lanes masked off: it does not jump
//! over a block even when no lane enters it or the condition is uniform. Code for a kind of light
//! or material a scene does not have therefore costs as much as code it runs. Measured by hand on
//! the Cornell box (release build, lavapipe, 64×64, 32 bounces, 2026-12-04): a block of 40 lines
//! of transcendental arithmetic behind a condition that is never true took the rate from about
//! 155 k to 100 k samples/s, whether the condition varied per lane or came from the uniform
//! buffer. Each constant is true in the shader, which traces any scene; the host makes it false
//! only where the scene has none of the thing, so the compiler drops code no path can reach and
//! the image stays the same bit for bit (`tests/reference/reference.rs`,
//! `specialised_tracer_matches_the_general_one`).

use crate::backend::SpecConstant;

use super::scene_data::{TracedScene, LIGHT_QUAD, LIGHT_SPHERE};

/// How next-event estimation treats the lights: spec constant 9 (`NEE_MODE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum NeeMode {
    /// A shadow ray to every light.
    Every = 0,
    /// One light per colour channel (`FLAG_ONE_LIGHT`).
    One = 1,
    /// Either, as the batch's flag says: the shader's default.
    Either = 2,
}

/// How rays walk the BVH: spec constant 10 (`BVH_WALK_ORDERED`). The same boxes and the same
/// closest hits either way; what differs is the cost on each kind of device (README, "The
/// reference against Mitsuba 3": on lavapipe the ordered walk is 1.02-1.14x the stack walk's
/// rate, on the H200 0.79-0.92x).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BvhWalk {
    /// Nearer child first, the other pushed on a stack (`trace_triangles`): the shader's default.
    Stack,
    /// Without a stack, in an order fixed per ray octant (`trace_triangles_ordered`).
    Ordered,
}

impl BvhWalk {
    /// The faster walk on the device: a CPU implementation (lavapipe) turns each private-array
    /// access indexed per lane into a scalar load or store per lane, which the stack walk pays
    /// on every step; a GPU keeps its stack in fast memory and tests two boxes a step.
    pub fn for_device(device_type: ash::vk::PhysicalDeviceType) -> BvhWalk {
        if device_type == ash::vk::PhysicalDeviceType::CPU {
            BvhWalk::Ordered
        } else {
            BvhWalk::Stack
        }
    }
}

/// Where the tracer's main draws (the point in the pixel, on an area light, the environment and
/// BSDF directions, the BSDF's lobe and Russian roulette) come from: spec constant 11
/// (`SAMPLER_SOBOL`, `glsl/reference/rng.glsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Sampler {
    /// Independent uniform numbers from each sample's PCG stream: the samples of a pixel are
    /// independent, so their scatter is the error of their mean (the standard-error image).
    #[default]
    Independent,
    /// Owen-scrambled Sobol points, shuffled per draw (Burley 2020), in
    /// [`SOBOL_REPLICATES`](super::SOBOL_REPLICATES) independently scrambled replicates per
    /// pixel: each replicate's samples are stratified in each 2D draw, so the pixel's mean has
    /// less error than independent samples' where the integrand is smooth in those dimensions
    /// (README, "The Sobol sampler"), and is still unbiased; the standard error comes from the
    /// scatter of the replicates' means.
    Sobol,
}

impl Sampler {
    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            Sampler::Independent => "independent",
            Sampler::Sobol => "sobol",
        }
    }
}

impl std::str::FromStr for Sampler {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Sampler, String> {
        match s {
            "independent" => Ok(Sampler::Independent),
            "sobol" => Ok(Sampler::Sobol),
            _ => Err(format!("unknown sampler `{s}` (independent or sobol)")),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneFeatures {
    pub maps: bool,
    pub translucency: bool,
    pub specular: bool,
    pub transmission: bool,
    pub punctual_lights: bool,
    pub sphere_lights: bool,
    pub quad_lights: bool,
    pub environment_map: bool,
    pub sampled_environment: bool,
}

impl SceneFeatures {
    /// Every feature on: the shader as written, for any scene.
    pub const ALL: SceneFeatures = SceneFeatures {
        maps: true,
        translucency: true,
        specular: true,
        transmission: true,
        punctual_lights: true,
        sphere_lights: true,
        quad_lights: true,
        environment_map: true,
        sampled_environment: true,
    };

    pub fn of(scene: &TracedScene) -> SceneFeatures {
        let materials = &scene.materials;
        let rgb_nonzero = |c: &[f32; 4]| c[..3].iter().any(|&x| x != 0.0);
        let light_type = |t: f32| scene.lights.iter().any(|l| l.position[3] == t);
        SceneFeatures {
            maps: materials.iter().any(|m| m.maps[..3].iter().any(|&i| i != 0)),
            // The shader tests `opacity >= 1.0`, which a NaN fails too.
            translucency: materials.iter().any(|m| m.albedo[3] < 1.0 || m.albedo[3].is_nan()),
            specular: materials.iter().any(|m| rgb_nonzero(&m.specular)),
            transmission: materials.iter().any(|m| rgb_nonzero(&m.transmittance)),
            punctual_lights: scene.punctual_lights > 0,
            sphere_lights: light_type(LIGHT_SPHERE),
            quad_lights: light_type(LIGHT_QUAD),
            environment_map: scene.environment_map.is_some(),
            sampled_environment: scene.environment_map.as_ref().is_some_and(|m| m.has_power),
        }
    }

    /// The constants in `glsl/reference/features.glsl`'s order.
    pub fn specialization(&self, nee: NeeMode, walk: BvhWalk, sampler: Sampler) -> Vec<SpecConstant> {
        let flags = [
            self.maps,
            self.translucency,
            self.specular,
            self.transmission,
            self.punctual_lights,
            self.sphere_lights,
            self.quad_lights,
            self.environment_map,
            self.sampled_environment,
        ];
        let mut constants: Vec<SpecConstant> = flags
            .iter()
            .enumerate()
            .map(|(id, &on)| SpecConstant {
                id: id as u32,
                bits: u32::from(on),
            })
            .collect();
        constants.push(SpecConstant {
            id: flags.len() as u32,
            bits: nee as u32,
        });
        constants.push(SpecConstant {
            id: flags.len() as u32 + 1,
            bits: u32::from(walk == BvhWalk::Ordered),
        });
        constants.push(SpecConstant {
            id: flags.len() as u32 + 2,
            bits: u32::from(sampler == Sampler::Sobol),
        });
        constants.push(SpecConstant {
            id: flags.len() as u32 + 3,
            bits: super::SOBOL_REPLICATES,
        });
        constants
    }
}
