//! Emission found by a ray: an emitting surface it hits ([`emitter_hit`]) or the environment
//! when it leaves the scene ([`environment`]), each weighted against next-event estimation
//! from the vertex the ray left ([`Previous::weight`], with the emitter-sampling density
//! [`emitter_density`]). Every integrator that follows rays from the camera side reads
//! emission through these.

use super::mis::{self, MisHeuristic};
use crate::lights::{Light, Receiver};
use crate::math::Vec3;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, ColorMode};
use crate::world::Scene;

/// The scattering vertex the current ray left: where emitter sampling would have started
/// from, the solid-angle density of the direction it sampled, and whether a delta lobe made
/// it (then no other strategy could have, and emission found counts in full).
#[derive(Clone, Copy, Debug)]
pub struct Previous {
    pub receiver: Receiver,
    pub pdf: f32,
    pub delta: bool,
}

impl Previous {
    /// The MIS weight of emission found along the ray sampled here, given the density `nee`
    /// with which emitter sampling from the receiver produces the same direction (asked only
    /// when a weight is needed).
    #[inline(always)]
    pub fn weight(&self, h: MisHeuristic, nee: impl FnOnce(&Receiver) -> f32) -> f32 {
        if self.delta {
            1.0
        } else {
            mis::weight(h, self.pdf, nee(&self.receiver))
        }
    }
}

/// The density with which emitter sampling from `r` (the scene's light selection, then the
/// light's own sampling) produces the direction `wi` towards light `i` — through the point
/// `si` on it, for an area light.
#[inline(always)]
pub fn emitter_density(
    scene: &Scene,
    r: &Receiver,
    i: u32,
    wi: Vec3,
    si: Option<&SurfaceInteraction>,
) -> f32 {
    scene.light_pmf(r, i) * scene.lights[i as usize].pdf_li(scene, r, wi, si)
}

/// The emitter whose surface a ray hit at `si` and the radiance it sends back along the ray
/// (`None` where nothing is emitted).
#[inline(always)]
pub fn emitter_hit<M: ColorMode>(
    scene: &Scene,
    si: &SurfaceInteraction,
    mode: &M,
) -> Option<(u32, M::C)> {
    let i = scene.shape_light(si)?;
    let le = scene.lights[i as usize].le(scene, si, mode);
    (!le.is_black()).then_some((i, le))
}

/// The environment's radiance along the escaping direction `d`: Σ β·Le·w over the infinite
/// lights that emit along it, w = `weight(i, light)` their MIS weights.
#[inline(always)]
pub fn environment<M: ColorMode>(
    scene: &Scene,
    d: Vec3,
    mode: &M,
    beta: M::C,
    mut weight: impl FnMut(u32, &Light) -> f32,
) -> M::C {
    let mut l = M::C::ZERO;
    for &i in &scene.infinite_lights {
        let light = &scene.lights[i as usize];
        let le = light.environment(d, mode);
        if le.is_black() {
            continue;
        }
        l += beta * le * weight(i, light);
    }
    l
}
