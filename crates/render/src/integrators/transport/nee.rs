//! Next-event estimation's parts: an emitter sample for a receiving point
//! ([`sample_emitter`]: the scene's light selection, then a point on the light), and what
//! scatters at the vertex it is made from ([`Scatterer`]: a BSDF in its shading frame or a
//! medium's phase function), whose value and density towards the sample the estimate and
//! its MIS weight need. The shadow query (`shadow.rs`) tests the connection. Each
//! integrator combines the parts into its own estimate (with its sample counts, hero
//! weights and MIS policy).

use crate::bsdf::{Bsdf, TransportMode};
use crate::lights::{LightSample, Receiver};
use crate::math::{Frame, Vec3};
use crate::media::Phase;
use crate::sampling::Samples;
use crate::spectral::lanes::{Color, ColorMode};
use crate::world::Scene;

/// An emitter sample: light `light`, chosen with probability `pmf`, and the sample `ls` on it.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample<C> {
    pub light: u32,
    pub ls: LightSample<C>,
    pub pmf: f32,
}

/// One emitter sample for `r`: a light by the scene's light selection (one 1D number) and a
/// point on it (one 2D number), both drawn whatever happens so that the sample stream stays
/// aligned. `None` when nothing was chosen or the sample carries nothing.
#[inline(always)]
pub fn sample_emitter<M: ColorMode>(
    scene: &Scene,
    r: &Receiver,
    sampler: &mut impl Samples,
    mode: &M,
) -> Option<EmitterSample<M::C>> {
    let picked = scene.sample_light(sampler.next_1d(), r);
    let u = sampler.next_2d();
    let (light, _, pmf) = picked?;
    let s = sample_towards(scene, light, r, u, mode)?;
    (pmf > 0.0).then_some(EmitterSample { pmf, ..s })
}

/// A sample of light `light` for `r` from the uniform pair `u` (its selection probability
/// left at 1): `None` when it carries nothing (zero or undefined density, no radiance).
#[inline(always)]
pub fn sample_towards<M: ColorMode>(
    scene: &Scene,
    light: u32,
    r: &Receiver,
    u: crate::math::Vec2,
    mode: &M,
) -> Option<EmitterSample<M::C>> {
    let ls = scene.lights[light as usize].sample_li(scene, r, u, mode)?;
    (ls.pdf > 0.0 && !ls.li.is_black()).then_some(EmitterSample {
        light,
        ls,
        pmf: 1.0,
    })
}

/// What scatters at a vertex, seen from the direction the path arrived along: a BSDF in its
/// shading frame (`wo` in that frame) or a medium's phase function (`wo` in world space).
#[derive(Clone, Copy)]
pub enum Scatterer<'a, C: Color> {
    Surface {
        bsdf: &'a Bsdf<C>,
        frame: &'a Frame,
        wo: Vec3,
    },
    Medium {
        phase: &'a Phase,
        wo: Vec3,
    },
}

impl<'a, C: Color> Scatterer<'a, C> {
    /// A BSDF in its shading frame, seen from the local direction `wo`.
    #[inline(always)]
    pub fn surface(bsdf: &'a Bsdf<C>, frame: &'a Frame, wo: Vec3) -> Self {
        Scatterer::Surface { bsdf, frame, wo }
    }

    /// f·|cos θ| towards the world direction `wi` (the phase function in a medium) and the
    /// solid-angle density with which the vertex samples `wi`.
    #[inline(always)]
    pub fn eval_pdf(&self, wi: Vec3, mode: TransportMode) -> (C, f32) {
        match *self {
            Scatterer::Surface { bsdf, frame, wo } => bsdf.eval_pdf(wo, frame.to_local(wi), mode),
            Scatterer::Medium { phase, wo } => {
                let p = phase.eval(wo, wi);
                (C::splat(p), p)
            }
        }
    }

    /// f·|cos θ| towards the world direction `wi` (the phase function in a medium).
    #[inline(always)]
    pub fn eval(&self, wi: Vec3, mode: TransportMode) -> C {
        match *self {
            Scatterer::Surface { bsdf, frame, wo } => bsdf.eval(wo, frame.to_local(wi), mode),
            Scatterer::Medium { phase, wo } => C::splat(phase.eval(wo, wi)),
        }
    }
}
