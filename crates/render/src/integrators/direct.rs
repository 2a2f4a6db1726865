//! Mitsuba 3's `direct` integrator: emission seen directly, plus `emitter_samples` emitter
//! samples and `bsdf_samples` BSDF samples at the first hit, combined with the power heuristic
//! on the sample-count-weighted densities.

use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::lights::Receiver;
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::{Color, PathMode, RgbMode};
use crate::world::Scene;

fn power(a: f32, b: f32) -> f32 {
    let w = a * a / (a * a + b * b);
    if w.is_finite() { w } else { 0.0 }
}

pub fn li(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    emitter_samples: u32,
    bsdf_samples: u32,
) -> Vec3 {
    li_in::<RgbMode>(scene, cray, sampler, emitter_samples, bsdf_samples)
}

/// [`li`] in the colour mode `M` (set up for this camera sample from `sampler`), as linear
/// sRGB.
pub fn li_in<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    emitter_samples: u32,
    bsdf_samples: u32,
) -> Vec3 {
    let m = M::start(sampler);
    let l = estimate(scene, cray, sampler, &m, emitter_samples, bsdf_samples);
    m.to_rgb(l)
}

fn estimate<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    m: &M,
    emitter_samples: u32,
    bsdf_samples: u32,
) -> M::C {
    let Some(si) = scene.intersect(&cray.ray, cray.t_max) else {
        let mut r = M::C::ZERO;
        for &i in &scene.infinite_lights {
            r += scene.lights[i as usize].environment(cray.ray.d, m);
        }
        return r;
    };
    let mut result = M::C::ZERO;
    if let Some(l) = scene.shape_light(&si) {
        result += scene.lights[l as usize].le(scene, &si, m);
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
            let u = sampler.next_1d();
            let Some((_, light, pmf)) = scene.sample_light(u, &receiver) else {
                continue;
            };
            let Some(ls) = light.sample_li(scene, &receiver, sampler.next_2d(), m) else {
                continue;
            };
            if ls.pdf.is_nan() || ls.pdf <= 0.0 || ls.li.is_black() {
                continue;
            }
            let wi = frame.to_local(ls.wi);
            let f = bsdf.eval(wo, wi, TransportMode::Radiance);
            if f.is_black() {
                continue;
            }
            let (ray, t_max) = ls.target.ray_from(&si, ls.wi);
            if scene.occluded(&ray, t_max) {
                continue;
            }
            let pdf = ls.pdf * pmf;
            let w = if ls.delta {
                1.0
            } else {
                power(pdf * frac_em, bsdf.pdf(wo, wi) * frac_bsdf)
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
            Some(hit) => match scene.shape_light(&hit) {
                Some(l) => {
                    let light = &scene.lights[l as usize];
                    let le = light.le(scene, &hit, m);
                    let pmf = scene.light_pmf(&receiver, l);
                    (le, pmf * light.pdf_li(scene, &receiver, wi, Some(&hit)))
                }
                None => continue,
            },
            None => {
                let mut le = M::C::ZERO;
                let mut pdf = 0.0;
                for &i in &scene.infinite_lights {
                    let l = &scene.lights[i as usize];
                    le += l.environment(wi, m);
                    pdf += scene.light_pmf(&receiver, i) * l.pdf_li(scene, &receiver, wi, None);
                }
                (le, pdf)
            }
        };
        if le.is_black() {
            continue;
        }
        let w = if bs.delta || emitter_samples == 0 {
            1.0
        } else {
            power(bs.pdf * frac_bsdf, light_pdf * frac_em)
        };
        result += bs.weight * le * (w / bsdf_samples as f32);
    }
    result
}
