//! The unidirectional path tracer and its restricted variants (Whitted, Nori's `path_*` and
//! `direct_*`), one loop configured by [`PathConfig`].
//!
//! With the default configuration this is Mitsuba 3's `path` integrator exactly: emitter
//! sampling (one light chosen uniformly) at every vertex with a non-delta BSDF, BSDF sampling
//! to continue, both combined with the power heuristic; Russian roulette from depth `rr_depth`
//! with continuation probability min(max(throughput)·η², 0.95); `max_depth` counts path
//! segments (1: emitters seen directly, 2: direct lighting, −1: unbounded).

use crate::bsdf::TransportMode;
use crate::build::Scene;
use crate::camera::CameraRay;
use crate::lights::{Receiver, ShadowTarget};
use crate::math::Vec3;
use crate::sampling::Sampler;

/// How emission found by BSDF-sampled rays is weighted against emitter sampling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combine {
    /// Multiple importance sampling with the power heuristic (β = 2).
    Power,
    /// Multiple importance sampling with the balance heuristic.
    Balance,
    /// Only emitter sampling counts, except after delta bounces and for camera rays.
    EmitterOnly,
    /// Only BSDF sampling counts (no emitter sampling at all).
    BsdfOnly,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathConfig {
    /// Maximum number of path segments; `u32::MAX` for unbounded.
    pub max_depth: u32,
    /// Depth from which Russian roulette starts.
    pub rr_depth: u32,
    /// Do not show emitters hit by camera rays.
    pub hide_emitters: bool,
    pub combine: Combine,
    /// Continue paths after non-delta vertices (false: Whitted-style, only delta chains).
    pub continue_diffuse: bool,
}

impl PathConfig {
    pub fn mitsuba(max_depth: i32, rr_depth: u32, hide_emitters: bool, combine: Combine) -> Self {
        PathConfig {
            max_depth: if max_depth < 0 {
                u32::MAX
            } else {
                max_depth as u32
            },
            rr_depth,
            hide_emitters,
            combine,
            continue_diffuse: true,
        }
    }
}

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

/// Where the previous vertex was and how its BSDF sample was drawn.
struct Previous {
    receiver: Receiver,
    bsdf_pdf: f32,
    delta: bool,
}

pub fn li(scene: &Scene, cray: &CameraRay, sampler: &mut Sampler, cfg: &PathConfig) -> Vec3 {
    let mut result = Vec3::ZERO;
    if cfg.max_depth == 0 {
        return result;
    }
    let mut ray = cray.ray;
    let mut t_max = cray.t_max;
    let mut throughput = Vec3::ONE;
    let mut eta = 1.0f32;
    let mut depth = 0u32;
    let mut prev: Option<Previous> = None;

    // Weight of emission reached by the BSDF-sampled ray from `prev`, given the pdf with which
    // emitter sampling would have produced the same direction.
    let emission_weight = |prev: &Option<Previous>, light_pdf: &dyn Fn(&Receiver) -> f32| match prev
    {
        None => 1.0,
        Some(p) if p.delta => 1.0,
        Some(p) => match cfg.combine {
            Combine::BsdfOnly => 1.0,
            Combine::EmitterOnly => 0.0,
            c => mis(c, p.bsdf_pdf, light_pdf(&p.receiver)),
        },
    };

    loop {
        let Some(si) = scene.intersect(&ray, t_max) else {
            if !(depth == 0 && cfg.hide_emitters) {
                for &i in &scene.infinite_lights {
                    let light = &scene.lights[i as usize];
                    let le = light.environment(ray.d);
                    if le == Vec3::ZERO {
                        continue;
                    }
                    let pmf = scene.light_pmf();
                    let w = emission_weight(&prev, &|r| pmf * light.pdf_li(scene, r, ray.d, None));
                    result += throughput * le * w;
                }
                if let Some(bg) = scene.background
                    && depth == 0
                {
                    result += bg;
                }
            }
            break;
        };
        t_max = f32::INFINITY;

        if let Some(li) = scene.shape_light[si.shape as usize]
            && !(depth == 0 && cfg.hide_emitters)
        {
            let light = &scene.lights[li as usize];
            let le = light.le(scene, &si);
            if le != Vec3::ZERO {
                let pmf = scene.light_pmf();
                let w = emission_weight(&prev, &|r| {
                    pmf * light.pdf_li(scene, r, ray.d.normalize(), Some(&si))
                });
                result += throughput * le * w;
            }
        }

        if depth.saturating_add(1) >= cfg.max_depth {
            break;
        }
        let Some((bsdf, frame)) = scene.bsdf_at(&si) else {
            break;
        };
        let wo = frame.to_local(si.wo);
        let receiver = Receiver::from(&si);

        // Emitter sampling.
        if bsdf.has_smooth() && cfg.combine != Combine::BsdfOnly && !scene.lights.is_empty() {
            let (light, pmf) = scene.sample_light(sampler.next_1d());
            let u = sampler.next_2d();
            if let Some(ls) = light.sample_li(scene, &receiver, u)
                && ls.pdf > 0.0
                && ls.li != Vec3::ZERO
            {
                let wi = frame.to_local(ls.wi);
                let f = bsdf.eval(wo, wi, TransportMode::Radiance);
                if f != Vec3::ZERO && !scene.shadowed(&si, &ls.target, ls.wi) {
                    let light_pdf = ls.pdf * pmf;
                    let w = if ls.delta || cfg.combine == Combine::EmitterOnly {
                        1.0
                    } else {
                        mis(cfg.combine, light_pdf, bsdf.pdf(wo, wi))
                    };
                    result += throughput * f * ls.li * (w / light_pdf);
                }
            }
        } else {
            // Keep the sample dimensions aligned whatever the material.
            sampler.next_1d();
            sampler.next_2d();
        }

        // BSDF sampling.
        let u1 = sampler.next_1d();
        let u2 = sampler.next_2d();
        let Some(bs) = bsdf.sample(wo, u1, u2, TransportMode::Radiance) else {
            break;
        };
        if !bs.delta && !cfg.continue_diffuse {
            break;
        }
        throughput *= bs.weight;
        eta *= bs.eta;
        let wi = frame.to_world(bs.wi);
        ray = si.spawn_ray(wi);
        prev = Some(Previous {
            receiver,
            bsdf_pdf: bs.pdf,
            delta: bs.delta,
        });

        depth += 1;
        let t_max_component = throughput.max_element();
        if t_max_component.is_nan() || t_max_component <= 0.0 {
            break;
        }
        let u_rr = sampler.next_1d();
        if depth >= cfg.rr_depth {
            let q = (t_max_component * eta * eta).min(0.95);
            if u_rr >= q {
                break;
            }
            throughput /= q;
        }
    }
    result
}

impl Scene {
    /// Whether the segment from `si` to a light sample is blocked.
    pub fn shadowed(
        &self,
        si: &crate::shapes::SurfaceInteraction,
        target: &ShadowTarget,
        wi: Vec3,
    ) -> bool {
        match *target {
            ShadowTarget::Infinite => self.occluded(&si.spawn_ray(wi), f32::INFINITY),
            ShadowTarget::Point(p) => {
                let (ray, t) = si.spawn_ray_to(p);
                self.occluded(&ray, t)
            }
            ShadowTarget::Surface { p, p_error, n } => {
                let (ray, t) = si.spawn_ray_to_surface(p, p_error, n);
                self.occluded(&ray, t)
            }
        }
    }
}
