//! Photon tracing, shared by the photon-mapping family (`sppm`, `photon`): lights chosen in
//! proportion to their power, paths started by [`crate::lights::Light::sample_le`], carried
//! by BSDF sampling in importance transport with pbrt-v4's roulette (the photon's power stays
//! about constant), and reported at every surface hit with a non-delta lobe.
//!
//! Photon `j` of pass `p` draws from its own sampler stream and photons are traced in fixed
//! chunks whose results come back in chunk order, so whatever is built from them is the same
//! for any thread count.

use rayon::prelude::*;

use crate::bsdf::{Bsdf, TransportMode};
use crate::geometry::Ray;
use crate::lights::Receiver;
use crate::math::{Frame, UVec2, Vec3};
use crate::media::Flight;
use crate::sampling::sampler::{hash2, u64_to_unit};
use crate::sampling::{Distribution1D, Sampler};
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, ColorMode, PathMode};
use crate::world::Scene;

/// Photons per chunk: the unit of parallel work.
pub const CHUNK: u64 = 4096;

/// How photons choose their light: in proportion to its power.
pub struct PhotonLights {
    dist: Distribution1D,
    any: bool,
}

impl PhotonLights {
    pub fn new(scene: &Scene) -> PhotonLights {
        let powers: Vec<f32> = scene.lights.iter().map(|l| l.power(scene)).collect();
        PhotonLights {
            any: powers.iter().any(|&p| p > 0.0),
            dist: Distribution1D::new(&powers),
        }
    }

    /// Whether any light emits.
    pub fn any(&self) -> bool {
        self.any
    }
}

/// A photon arriving at a surface with a non-delta lobe, or scattering in a medium, in the
/// colour type `C` of its mode.
pub struct PhotonHit<'a, C = Vec3> {
    /// Where: the surface (`None` for a scattering event in a medium).
    pub si: Option<&'a SurfaceInteraction>,
    pub p: Vec3,
    /// The medium of a scattering event; for a surface hit, the medium the photon arrived
    /// through.
    pub medium: Option<u32>,
    /// Its power: Φ of the emitted sample times the path's throughput (divide by the number
    /// of photons emitted for the flux it stands for). In a medium, the power after the
    /// collision's σs/σt (the event is a scattering one).
    pub beta: C,
    /// Unit direction towards where it came from (world space).
    pub wi: Vec3,
    /// Edges from the light to this hit (1: direct light).
    pub edges: u32,
    /// Every bounce before this hit was a delta one and there was at least one (a caustic
    /// photon: light, specular surfaces, here).
    pub caustic: bool,
}

/// Trace one photon path, reporting each surface hit with a non-delta lobe and each
/// scattering event in a medium. `max_depth` (−1: unbounded) is the longest camera-to-light
/// path the photons serve: a photon stops once a camera path of one edge could no longer
/// reach it. In media, free flights are sampled with a hero channel drawn per photon and the
/// photon's power carries the spectral MIS weight over that choice (as `volpath`'s paths).
pub fn trace<M: PathMode>(
    scene: &Scene,
    lights: &PhotonLights,
    max_depth: i32,
    sampler: &mut Sampler,
    m: &M,
    mut deposit: impl FnMut(&PhotonHit<M::C>, &mut Sampler),
) {
    let allows = |edges: u32| max_depth < 0 || edges <= max_depth as u32;
    let (li, pmf, _) = lights.dist.sample_discrete(sampler.next_1d());
    let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
    if pmf.is_nan() || pmf <= 0.0 {
        return;
    }
    let Some(e) = scene.lights[li].sample_le(scene, u_pos, u_dir, m) else {
        return;
    };
    let mut medium = scene.light_media.get(li).copied().flatten();
    let hero = if scene.media.is_empty() {
        0
    } else {
        m.hero(sampler.next_1d())
    };
    // The path's throughput and channel density ratios (its power is β / mean ratio).
    let mut beta = e.weight / pmf;
    let mut ratio = M::C::ONE;
    let power = |beta: M::C, ratio: M::C| beta * m.hero_weight(ratio);
    let mut ray = e.ray;
    let mut edges = 0u32;
    let mut specular_only = true;
    // Bounded: null crossings do not count as edges.
    for _ in 0..(1 << 16) {
        let b = m.live_max(power(beta, ratio));
        if b <= 0.0 || !b.is_finite() {
            break;
        }
        let closest = scene.closest(&ray, f32::INFINITY);
        if let Some(mi) = medium {
            let med = &scene.media[mi as usize];
            let d_surface = closest.t(&ray, f32::INFINITY);
            match med.sample_in(&ray, d_surface, hero, sampler, m) {
                Flight::Scatter {
                    d,
                    weight,
                    ratio: r,
                    ..
                } => {
                    edges += 1;
                    let before = m.live_max(power(beta, ratio));
                    beta *= weight;
                    ratio *= r;
                    let p = ray.at(d);
                    let wo = -ray.d;
                    let hit = PhotonHit {
                        si: None,
                        p,
                        medium,
                        beta: power(beta, ratio),
                        wi: wo,
                        edges,
                        caustic: false,
                    };
                    deposit(&hit, sampler);
                    if !allows(edges + 2) {
                        break;
                    }
                    specular_only = false;
                    let (wi, _) = med.phase.sample(wo, sampler.next_2d());
                    // pbrt-v4's roulette on the change of power at the event.
                    let after = m.live_max(power(beta, ratio));
                    let q = (1.0 - after / before).max(0.0);
                    if sampler.next_1d() < q {
                        break;
                    }
                    beta /= 1.0 - q;
                    ray = Ray::new(p, wi);
                    continue;
                }
                Flight::Pass { weight, ratio: r } => {
                    beta *= weight;
                    ratio *= r;
                }
            }
        }
        let Some(si) = closest.surface(scene, &ray, f32::INFINITY) else {
            break;
        };
        edges += 1;
        let Some((bsdf, frame)) = scene.bsdf_at_in(&si, m) else {
            // A surface that does not scatter absorbs (an emitter without a BSDF) unless it
            // is an index-matched boundary: straight on, into the medium beyond.
            if !scene.is_null(&si) {
                break;
            }
            medium = scene.medium_after(&si, ray.d, medium);
            ray = si.spawn_ray(ray.d);
            edges -= 1;
            continue;
        };
        let here = power(beta, ratio);
        let before = m.live_max(here);
        if bsdf.has_smooth() {
            let hit = PhotonHit {
                si: Some(&si),
                p: si.p,
                medium,
                beta: here,
                wi: -ray.d,
                edges,
                caustic: specular_only && edges > 1,
            };
            deposit(&hit, sampler);
        }
        if !allows(edges + 2) {
            break;
        }
        let wo = frame.to_local(si.wo);
        let u1 = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Importance) else {
            break;
        };
        specular_only &= bs.delta;
        beta *= bs.weight;
        let after = m.live_max(power(beta, ratio));
        let q = (1.0 - after / before).max(0.0);
        if sampler.next_1d() < q {
            break;
        }
        beta /= 1.0 - q;
        let wi = frame.to_world(bs.wi);
        medium = scene.medium_after(&si, wi, medium);
        ray = si.spawn_ray(wi);
    }
}

/// The uniform number ([`PathMode::from_u`]) of wavelength set `k` of the photon-mapping
/// family under `seed`. A set tints everything that sees it alike, so the sets follow a
/// rank-1 lattice (a random start, then steps of the golden ratio's fraction) rather than
/// independent draws: the colour of the mean image over k sets converges as 1/k instead of
/// 1/√k.
pub fn wavelength_set(seed: u64, k: u64) -> f32 {
    let u0 = u64_to_unit(hash2(seed, 0x5350_504D_4C41_4D42));
    (u0 as f64 + k as f64 * 0.618_033_988_749_894_9).fract() as f32
}

/// Trace photons `0..count` of pass `pass` in parallel chunks, photon `j` in a fresh colour
/// mode `mode(j)` (its wavelengths may be terminated on the way): `start` makes each
/// chunk's accumulator, `deposit` adds a hit to it (with the photon's mode as it is then and
/// its sampler, whose stream is the photon's own); the accumulators come back in chunk
/// order.
#[allow(clippy::too_many_arguments)]
pub fn trace_all<T: Send, M: PathMode>(
    scene: &Scene,
    lights: &PhotonLights,
    max_depth: i32,
    seed: u64,
    pass: u32,
    count: u64,
    mode: impl Fn(u64) -> M + Sync,
    start: impl Fn() -> T + Sync,
    deposit: impl Fn(&mut T, &PhotonHit<M::C>, &M, &mut Sampler) + Sync,
) -> Vec<T> {
    let template = Sampler::new(
        base::SamplerKind::Independent,
        1,
        seed ^ 0x5048_4F54_4F4E_5321,
    );
    (0..count.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let mut sampler = template.clone();
            let mut acc = start();
            for j in c * CHUNK..((c + 1) * CHUNK).min(count) {
                sampler.start_pixel_sample(UVec2::new(j as u32, (j >> 32) as u32), pass);
                let m = mode(j);
                trace(
                    scene,
                    lights,
                    max_depth,
                    &mut sampler,
                    &m,
                    |hit, sampler| deposit(&mut acc, hit, &m, sampler),
                );
            }
            acc
        })
        .collect()
}

/// One light sample at a camera vertex with a non-delta lobe (light sampling only, as
/// pbrt-v4's SPPM; the photon maps hold the rest).
pub fn next_event<M: ColorMode>(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &Bsdf<M::C>,
    frame: &Frame,
    wo: Vec3,
    sampler: &mut Sampler,
    m: &M,
) -> M::C {
    let receiver = Receiver::from(si);
    let u = sampler.next_1d();
    let u2 = sampler.next_2d();
    let Some((_, light, pmf)) = scene.sample_light(u, &receiver) else {
        return M::C::ZERO;
    };
    let Some(ls) = light.sample_li(scene, &receiver, u2, m) else {
        return M::C::ZERO;
    };
    if ls.pdf.is_nan() || ls.pdf <= 0.0 || ls.li.is_black() {
        return M::C::ZERO;
    }
    let f = bsdf.eval(wo, frame.to_local(ls.wi), TransportMode::Radiance);
    if f.is_black() {
        return M::C::ZERO;
    }
    let (ray, t_max) = ls.target.ray_from(si, ls.wi);
    if scene.occluded(&ray, t_max) {
        return M::C::ZERO;
    }
    f * ls.li / (ls.pdf * pmf)
}

/// What a camera-side walk hands its caller at a vertex with a non-delta lobe.
pub struct Vertex<'a, C: Color> {
    pub si: &'a SurfaceInteraction,
    pub bsdf: &'a Bsdf<C>,
    pub frame: &'a Frame,
    /// Towards where the walk came from, in the BSDF's frame.
    pub wo: Vec3,
    /// Edges from the walk's start (camera or gathering point) counted from `depth`.
    pub depth: u32,
    /// The walk's throughput up to here.
    pub beta: C,
}

/// Follow `ray` from the camera side through delta bounces, as the photon-mapping family's
/// camera passes and final gathering do: emission met along the way counts when
/// `see_emission`; at every vertex with a non-delta lobe `at_vertex` adds its estimates
/// (times the throughput); the walk goes on only when the BSDF samples a delta lobe there (a
/// non-delta sample is what the vertex's estimates stand for), with Russian roulette from
/// `rr_depth` edges on, and within `max_depth` edges (−1: unbounded). `depth` is the number
/// of edges before `ray`.
#[allow(clippy::too_many_arguments)]
pub fn walk<M: PathMode>(
    scene: &Scene,
    mut ray: Ray,
    mut t_max: f32,
    mut beta: M::C,
    mut depth: u32,
    see_emission: bool,
    max_depth: i32,
    rr_depth: u32,
    m: &M,
    sampler: &mut Sampler,
    mut at_vertex: impl FnMut(&Vertex<M::C>, &mut Sampler) -> M::C,
) -> M::C {
    let allows = |edges: u32| max_depth < 0 || edges <= max_depth as u32;
    let mut l = M::C::ZERO;
    loop {
        depth += 1;
        let Some(si) = scene.intersect(&ray, t_max) else {
            if see_emission {
                for &i in &scene.infinite_lights {
                    l += beta * scene.lights[i as usize].environment(ray.d, m);
                }
            }
            break;
        };
        if see_emission && let Some(li) = scene.shape_light(&si) {
            l += beta * scene.lights[li as usize].le(scene, &si, m);
        }
        let Some((bsdf, frame)) = scene.bsdf_at_in(&si, m) else {
            // Absorbed, unless an index-matched boundary: straight on.
            if !scene.is_null(&si) {
                break;
            }
            ray = si.spawn_ray(ray.d);
            t_max = f32::INFINITY;
            depth -= 1;
            continue;
        };
        let wo = frame.to_local(si.wo);
        if bsdf.has_smooth() {
            let v = Vertex {
                si: &si,
                bsdf: &bsdf,
                frame: &frame,
                wo,
                depth,
                beta,
            };
            l += beta * at_vertex(&v, sampler);
        }
        if !allows(depth + 1) {
            break;
        }
        let u1 = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Radiance) else {
            break;
        };
        if !bs.delta {
            break;
        }
        beta *= bs.weight;
        if depth >= rr_depth {
            let q = m.live_max(beta).min(0.95);
            if sampler.next_1d() >= q || q.is_nan() {
                break;
            }
            beta /= q;
        }
        let b = m.live_max(beta);
        if b <= 0.0 || !b.is_finite() {
            break;
        }
        ray = si.spawn_ray(frame.to_world(bs.wi));
        t_max = f32::INFINITY;
    }
    l
}
