//! Next-event estimation and the multiple-importance-sampling weights that combine it with
//! the sampled directions.
//!
//! At a vertex with a non-delta BSDF, [`NeeContext::estimate`] samples emitters: one chosen
//! by the scene's light selection per sample, `light_samples` samples averaged (Mitsuba and
//! Nori: 1), or every emitter in turn with `light_samples` samples each and one for delta
//! emitters (`all_lights`: Whitted, CS184). Each sample's candidate contribution goes to the
//! path's shadow sink with its shadow ray (`batched.rs`). Emission that a sampled direction
//! finds is weighted by [`emission_weight`]; both sides use the density of the emitter
//! strategy actually in use ([`nee_pdf`]: selection × per-emitter density × sample count),
//! so every strategy has the same mean.

use base::DirectionSampling;

use super::batched::ShadowQuery;
use super::record::{Contribution, PathRecorder};
use super::scatter::direction_pdf;
use super::vertex::{Previous, Shading, Tracer};
use super::{Combine, PathConfig};
use crate::bsdf::TransportMode;
use crate::lights::{Light, Receiver};
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// The MIS weight of a strategy with density `a` against one with density `b`.
#[inline]
fn mis(combine: Combine, a: f32, b: f32) -> f32 {
    let w = match combine {
        Combine::Power => {
            let (a2, b2) = (a * a, b * b);
            a2 / (a2 + b2)
        }
        Combine::Balance => a / (a + b),
        Combine::EmitterOnly | Combine::BsdfOnly => 1.0,
    };
    if w.is_finite() { w } else { 0.0 }
}

/// Weight of emission reached by the ray sampled at `prev` (`None`: a camera ray), given the
/// density with which next-event estimation would have produced the same direction from
/// there (`nee_pdf` of the previous vertex's receiver; only called when MIS needs it).
#[inline]
pub(super) fn emission_weight(
    cfg: &PathConfig,
    prev: Option<&Previous>,
    nee_pdf: impl FnOnce(&Receiver) -> f32,
) -> f32 {
    match prev {
        None => 1.0,
        Some(p) if p.delta => 1.0,
        Some(p) => match cfg.combine {
            Combine::BsdfOnly => 1.0,
            Combine::EmitterOnly => 0.0,
            c => mis(c, p.dir_pdf, nee_pdf(&p.receiver)),
        },
    }
}

/// Density with which next-event estimation produces direction `wi` from `r` towards `light`
/// (selection and the number of emitter samples included).
#[inline]
pub(super) fn nee_pdf(
    scene: &Scene,
    cfg: &PathConfig,
    r: &Receiver,
    light: u32,
    pdf_li: f32,
) -> f32 {
    let selection = if cfg.all_lights {
        1.0
    } else {
        scene.light_pmf(r, light)
    };
    nee_density(cfg, selection, pdf_li)
}

/// [`nee_pdf`] for a light chosen with probability `selection` (known when it was just drawn).
#[inline]
fn nee_density(cfg: &PathConfig, selection: f32, pdf_li: f32) -> f32 {
    selection * pdf_li * cfg.light_samples as f32
}

/// A non-delta vertex, as next-event estimation sees it.
pub(super) struct NeeContext<'a, C: Color> {
    pub(super) at: Shading<'a, C>,
    pub(super) receiver: Receiver,
    /// Throughput of the path up to the vertex.
    pub(super) throughput: C,
    /// What the contributions of this vertex's emitter samples are recorded as.
    pub(super) contribution: Contribution,
}

impl<C: Color> NeeContext<'_, C> {
    /// Emitter sampling at the vertex, by the strategy `t.cfg` asks for (see the module docs).
    /// Without a smooth lobe or with BSDF sampling only, nothing is sampled, but the
    /// one-emitter strategy still draws its sample dimensions, so that the stream stays aligned
    /// whatever the material.
    #[inline]
    pub(super) fn estimate<R: PathRecorder<C>, M: PathMode<C = C>>(
        &self,
        t: &mut Tracer<'_, R, M>,
    ) {
        let (scene, cfg) = (t.scene, t.cfg);
        let nee = self.at.bsdf.has_smooth() && cfg.combine != Combine::BsdfOnly;
        if cfg.all_lights {
            if nee {
                for i in 0..scene.lights.len() as u32 {
                    self.sample(t, i, 1.0);
                }
            }
        } else {
            for _ in 0..cfg.light_samples {
                let u = t.sampler.next_1d();
                let picked = if nee {
                    scene.sample_light(u, &self.receiver)
                } else {
                    None
                };
                match picked {
                    Some((i, _, pmf)) => {
                        self.sample(t, i, pmf);
                    }
                    // Keep the sample dimensions aligned whatever the material.
                    None => {
                        t.sampler.next_2d();
                    }
                }
            }
        }
    }

    /// Next-event estimation towards light `i`: throughput · f·L·w / (p · selection) per
    /// sample, each handed to the shadow sink with its shadow ray (`light_samples` are
    /// averaged through the MIS densities). `selection` is the probability with which `i` was
    /// chosen (1 when all lights are sampled): the MIS density needs it, and recomputing it
    /// would walk the light BVH a second time.
    #[inline]
    fn sample<R: PathRecorder<C>, M: PathMode<C = C>>(
        &self,
        t: &mut Tracer<'_, R, M>,
        i: u32,
        selection: f32,
    ) {
        let (scene, cfg) = (t.scene, t.cfg);
        let light = &scene.lights[i as usize];
        let n = if cfg.all_lights && light.is_delta() {
            1
        } else if cfg.all_lights {
            cfg.light_samples
        } else {
            1
        };
        let per_light = if cfg.all_lights { n } else { cfg.light_samples } as f32;
        // One sample is the common case (always, unless every light is visited): without the
        // loop, nothing of the loop body is hoisted ahead of it for nothing.
        if n == 1 {
            self.one(t, light, selection, per_light);
        } else {
            for _ in 0..n {
                self.one(t, light, selection, per_light);
            }
        }
    }

    /// One emitter sample towards `light`, of `per_light` for this light.
    #[inline(always)]
    fn one<R: PathRecorder<C>, M: PathMode<C = C>>(
        &self,
        t: &mut Tracer<'_, R, M>,
        light: &Light,
        selection: f32,
        per_light: f32,
    ) {
        let (scene, cfg) = (t.scene, t.cfg);
        let Shading {
            si,
            bsdf,
            frame,
            wo,
        } = self.at;
        let u = t.sampler.next_2d();
        // Borrowed, not moved out of the `Option`: a light sample is 112 bytes.
        let ls = light.sample_li(scene, &self.receiver, u, t.mode);
        let Some(ls) = &ls else {
            return;
        };
        if ls.pdf.is_nan() || ls.pdf <= 0.0 || ls.li.is_black() {
            return;
        }
        let wi = frame.to_local(ls.wi);
        let mode = TransportMode::Radiance;
        // The BSDF's density only when MIS needs it.
        let weighted = !(ls.delta || cfg.combine == Combine::EmitterOnly);
        let (f, pdf_bsdf) = if !weighted {
            (bsdf.eval(wo, wi, mode), 0.0)
        } else if cfg.directions == DirectionSampling::Bsdf {
            bsdf.eval_pdf(wo, wi, mode)
        } else {
            let f = bsdf.eval(wo, wi, mode);
            (f, direction_pdf(cfg, bsdf, wo, wi))
        };
        if f.is_black() {
            return;
        }
        // Density of this strategy for MIS: all samples of all lights considered.
        let w = if weighted {
            mis(cfg.combine, nee_density(cfg, selection, ls.pdf), pdf_bsdf)
        } else {
            1.0
        };
        let l = self.throughput * (f * ls.li) * (w / (ls.pdf * per_light * selection));
        let (ray, t_max) = ls.target.ray_from(si, ls.wi);
        t.shadow(ShadowQuery { ray, t_max, l }, self.contribution);
    }
}
