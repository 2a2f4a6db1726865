//! Mitsuba 3's `direct` integrator: emission seen directly, plus `emitter_samples` emitter
//! samples and `bsdf_samples` BSDF samples at the first hit, combined with the power heuristic
//! on the sample-count-weighted densities.

use super::transport::{self, mis};
use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::drive::Estimator;
use crate::lights::Receiver;
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// Mitsuba's `direct` parameters: samples per camera sample of each strategy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DirectConfig {
    pub emitter_samples: u32,
    pub bsdf_samples: u32,
}

impl<M: PathMode> Estimator<M> for DirectConfig {
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        let m = M::start(sampler);
        let l = estimate(scene, cray, sampler, &m, self);
        m.to_rgb(l)
    }
}

/// Emission seen directly, then at the first hit `emitter_samples` emitter samples and
/// `bsdf_samples` BSDF samples, each weighted by the power heuristic over the two
/// strategies' sample-count-weighted densities (Mitsuba ignores media and lets any surface
/// block a shadow ray, as its `path` does).
fn estimate<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    m: &M,
    cfg: &DirectConfig,
) -> M::C {
    let (emitter_samples, bsdf_samples) = (cfg.emitter_samples, cfg.bsdf_samples);
    let Some(si) = scene.intersect(&cray.ray, cray.t_max) else {
        return transport::environment(scene, cray.ray.d, m, M::C::ONE, |_, _| 1.0);
    };
    let mut result = M::C::ZERO;
    if let Some((_, le)) = transport::emitter_hit(scene, &si, m) {
        result += le;
    }
    let Some((bsdf, frame)) = scene.bsdf_at_in(&si, m) else {
        return result;
    };
    let wo = frame.to_local(si.wo);
    let receiver = Receiver::from(&si);
    let total = (emitter_samples + bsdf_samples).max(1) as f32;
    let frac_em = emitter_samples as f32 / total;
    let frac_bsdf = bsdf_samples as f32 / total;

    if bsdf.has_smooth() && !scene.lights.is_empty() {
        for _ in 0..emitter_samples {
            let Some(e) = transport::sample_emitter(scene, &receiver, sampler, m) else {
                continue;
            };
            let ls = &e.ls;
            let wi = frame.to_local(ls.wi);
            let f = bsdf.eval(wo, wi, TransportMode::Radiance);
            if f.is_black() {
                continue;
            }
            let (ray, t_max) = ls.target.ray_from(&si, ls.wi);
            if scene.occluded(&ray, t_max) {
                continue;
            }
            let pdf = ls.pdf * e.pmf;
            let w = if ls.delta {
                1.0
            } else {
                mis::power(pdf * frac_em, bsdf.pdf(wo, wi) * frac_bsdf)
            };
            result += f * ls.li * (w / (pdf * emitter_samples as f32));
        }
    }
    for _ in 0..bsdf_samples {
        let u1 = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Radiance) else {
            continue;
        };
        let wi = frame.to_world(bs.wi);
        let ray = si.spawn_ray(wi);
        // Emission found and the density with which emitter sampling (selection included)
        // would have produced the same direction.
        let (le, light_pdf) = match scene.intersect(&ray, f32::INFINITY) {
            Some(hit) => match transport::emitter_hit(scene, &hit, m) {
                Some((l, le)) => (
                    le,
                    transport::emitter_density(scene, &receiver, l, wi, Some(&hit)),
                ),
                None => continue,
            },
            None => {
                let mut pdf = 0.0;
                let le = transport::environment(scene, wi, m, M::C::ONE, |i, _| {
                    pdf += transport::emitter_density(scene, &receiver, i, wi, None);
                    1.0
                });
                (le, pdf)
            }
        };
        if le.is_black() {
            continue;
        }
        let w = if bs.delta || emitter_samples == 0 {
            1.0
        } else {
            mis::power(bs.pdf * frac_bsdf, light_pdf * frac_em)
        };
        result += bs.weight * le * (w / bsdf_samples as f32);
    }
    result
}
