//! Mitsuba 3's `direct` integrator: emission seen directly, plus `emitter_samples` emitter
//! samples and `bsdf_samples` BSDF samples at the first hit, combined with the power heuristic
//! on the sample-count-weighted densities.

use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::lights::Receiver;
use crate::math::Vec3;
use crate::sampling::Sampler;
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
    let Some(si) = scene.intersect(&cray.ray, cray.t_max) else {
        let mut r = Vec3::ZERO;
        for &i in &scene.infinite_lights {
            r += scene.lights[i as usize].environment(cray.ray.d);
        }
        return r;
    };
    let mut result = Vec3::ZERO;
    if let Some(l) = scene.shape_light(&si) {
        result += scene.lights[l as usize].le(scene, &si);
    }
    let Some((bsdf, frame)) = scene.bsdf_at(&si) else {
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
            let Some(ls) = light.sample_li(scene, &receiver, sampler.next_2d()) else {
                continue;
            };
            if ls.pdf.is_nan() || ls.pdf <= 0.0 || ls.li == Vec3::ZERO {
                continue;
            }
            let wi = frame.to_local(ls.wi);
            let f = bsdf.eval(wo, wi, TransportMode::Radiance);
            if f == Vec3::ZERO {
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
                    let le = light.le(scene, &hit);
                    let pmf = scene.light_pmf(&receiver, l);
                    (le, pmf * light.pdf_li(scene, &receiver, wi, Some(&hit)))
                }
                None => continue,
            },
            None => {
                let mut le = Vec3::ZERO;
                let mut pdf = 0.0;
                for &i in &scene.infinite_lights {
                    let l = &scene.lights[i as usize];
                    le += l.environment(wi);
                    pdf += scene.light_pmf(&receiver, i) * l.pdf_li(scene, &receiver, wi, None);
                }
                (le, pdf)
            }
        };
        if le == Vec3::ZERO {
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
