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

use super::record::{Contribution, PathRecorder};
use super::scatter::direction_pdf;
use super::state::{Shading, ShadowQuery, Tracer};
use super::{Combine, PathConfig};
use crate::bsdf::TransportMode;
use crate::integrators::transport::{self, EmitterSample, Previous, mis};
use crate::lights::Receiver;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

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
        Some(p) => match cfg.combine.heuristic() {
            Some(h) => p.weight(h, nee_pdf),
            None if p.delta || cfg.combine == Combine::BsdfOnly => 1.0,
            None => 0.0,
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
    /// Emitter sampling at the vertex, by the strategy `t.cfg` asks for (see the module docs):
    /// `light_samples` samples of one emitter chosen by the scene's light selection each
    /// (`per_light` = `light_samples`), or of every emitter in turn (`all_lights`: delta
    /// emitters once). Without a smooth lobe or with BSDF sampling only, nothing is sampled,
    /// but the one-emitter strategy still draws its sample dimensions, so that the stream
    /// stays aligned whatever the material.
    #[inline]
    pub(super) fn estimate<R: PathRecorder<C>, M: PathMode<C = C>>(
        &self,
        t: &mut Tracer<'_, R, M>,
    ) {
        let (scene, cfg) = (t.scene, t.cfg);
        let nee = self.at.bsdf.has_smooth() && cfg.combine != Combine::BsdfOnly;
        if cfg.all_lights {
            if !nee {
                return;
            }
            for i in 0..scene.lights.len() as u32 {
                let n = if scene.lights[i as usize].is_delta() {
                    1
                } else {
                    cfg.light_samples
                };
                for _ in 0..n {
                    let u = t.sampler.next_2d();
                    if let Some(e) = transport::sample_towards(scene, i, &self.receiver, u, t.mode)
                    {
                        self.one(t, &e, n as f32);
                    }
                }
            }
        } else {
            for _ in 0..cfg.light_samples {
                if !nee {
                    // Keep the sample dimensions aligned whatever the material.
                    t.sampler.next_1d();
                    t.sampler.next_2d();
                } else if let Some(e) =
                    transport::sample_emitter(scene, &self.receiver, t.sampler, t.mode)
                {
                    self.one(t, &e, cfg.light_samples as f32);
                }
            }
        }
    }

    /// The emitter sample `e` (chosen with probability `e.pmf`: 1 when every light is
    /// sampled), one of `per_light` for its light, as a candidate contribution.
    #[inline(always)]
    fn one<R: PathRecorder<C>, M: PathMode<C = C>>(
        &self,
        t: &mut Tracer<'_, R, M>,
        e: &EmitterSample<C>,
        per_light: f32,
    ) {
        let cfg = t.cfg;
        let Shading {
            si,
            bsdf,
            frame,
            wo,
        } = self.at;
        let (ls, selection) = (&e.ls, e.pmf);
        let wi = frame.to_local(ls.wi);
        let mode = TransportMode::Radiance;
        // The BSDF's density only when MIS needs it.
        let weighted = !(ls.delta || cfg.combine == Combine::EmitterOnly);
        let (f, pdf_bsdf) = if !weighted {
            (bsdf.eval(wo, wi, mode), 0.0)
        } else if cfg.directions == DirectionSampling::Bsdf {
            let (f, pdf) = bsdf.eval_pdf(wo, wi, mode);
            // Guided vertices sample the mixture of the BSDF and the learnt distribution.
            match t.rec.guide().filter(|_| bsdf.guidable()) {
                Some(g) => (f, super::guided::mixture_pdf(pdf, g, ls.wi)),
                None => (f, pdf),
            }
        } else {
            let f = bsdf.eval(wo, wi, mode);
            (f, direction_pdf(cfg, bsdf, wo, wi))
        };
        if f.is_black() {
            return;
        }
        // Density of this strategy for MIS: all samples of all lights considered.
        let w = if weighted {
            cfg.combine.heuristic().map_or(1.0, |h| {
                mis::weight(h, nee_density(cfg, selection, ls.pdf), pdf_bsdf)
            })
        } else {
            1.0
        };
        let l = self.throughput * (f * ls.li) * (w / (ls.pdf * per_light * selection));
        let (ray, t_max) = ls.target.ray_from(si, ls.wi);
        t.shadow(ShadowQuery { ray, t_max, l }, self.contribution);
    }
}
