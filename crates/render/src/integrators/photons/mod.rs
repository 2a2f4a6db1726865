//! Photon tracing, shared by the light-path integrators (`sppm`, `photon`, `ptracer`): paths
//! start on the lights and in emitting media in proportion to their power
//! (`sources.rs`), are carried by the transport layer's walker (free flights in media, the
//! phase function at collisions, BSDF sampling in importance transport at surfaces) with
//! pbrt-v4's roulette (the photon's power stays about constant), and are reported at every
//! surface hit with a non-delta lobe and every collision in a medium. The camera side of the
//! photon-mapping family, a walk through delta bounces to the first vertex that is not one,
//! is in `camera.rs`.
//!
//! Photon `j` of pass `p` draws from its own sampler stream and photons are traced in fixed
//! chunks whose results come back in chunk order, so whatever is built from them is the same
//! for any thread count.

mod camera;
mod segment;
mod sources;

pub use camera::{CameraWalk, Segment, Vertex, Visit, next_event};
pub use segment::{SegmentMixture, SegmentPoint, segment_point};
pub use sources::{PathStart, PhotonLights, VolumeEmitter, volume_emitters};

use rayon::prelude::*;

use super::transport::{Event, Scatterer, Walker, roulette};
use crate::bsdf::TransportMode;
use crate::math::{UVec2, Vec3};
use crate::sampling::Sampler;
use crate::sampling::sampler::{hash2, u64_to_unit};
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// Photons per chunk: the unit of parallel work.
pub const CHUNK: u64 = 4096;

/// A photon arriving at a surface with a non-delta lobe, or scattering in a medium, in the
/// colour type `C` of its mode.
pub struct PhotonHit<'a, C: Color = Vec3> {
    /// Where and what scatters it: its `depth` the edges from the light (1: direct light),
    /// its `beta` its power, Φ of the emitted sample times the path's throughput (divide by
    /// the number of photons emitted for the flux it stands for; in a medium after the
    /// collision's σs/σt), its `medium` the one it scatters in or, at a surface, arrived
    /// through.
    pub v: Vertex<'a, C>,
    /// Unit direction towards where it came from (world space).
    pub wi: Vec3,
    /// Every bounce before this hit was a delta one and there was at least one (a caustic
    /// photon: light, specular surfaces, here).
    pub caustic: bool,
    /// The photon started in an emitting medium: its direct light is not a light sample's
    /// (next-event estimation reaches lights only).
    pub from_volume: bool,
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
    let Some(start) = lights.start(scene, sampler, m) else {
        return;
    };
    let hero = if scene.media.is_empty() {
        0
    } else {
        m.hero(sampler.next_1d())
    };
    // The path's throughput and channel density ratios (its power is β / mean ratio).
    let mut beta = start.beta;
    let mut ratio = M::C::ONE;
    let power = |beta: M::C, ratio: M::C| beta * m.hero_weight(ratio);
    let mut w = Walker::new(start.ray, f32::INFINITY, start.medium, hero);
    let mut edges = 0u32;
    let mut specular_only = true;
    // Bounded: null crossings do not count as edges.
    for _ in 0..(1 << 16) {
        let b = m.live_max(power(beta, ratio));
        if b <= 0.0 || !b.is_finite() {
            break;
        }
        let (si, pass) = match w.next(scene, sampler, m) {
            Event::Collision {
                p,
                weight,
                ratio: r,
                ..
            } => {
                edges += 1;
                let before = m.live_max(power(beta, ratio));
                beta *= weight;
                ratio *= r;
                let wo = -w.ray.d;
                let phase = &w.medium(scene).expect("collisions happen in media").phase;
                let at = Scatterer::Medium { phase, wo };
                let v = Vertex::collision(at, p, &w, edges, power(beta, ratio));
                let hit = PhotonHit {
                    v,
                    wi: wo,
                    caustic: false,
                    from_volume: start.in_volume,
                };
                deposit(&hit, sampler);
                if !allows(edges + 2) {
                    break;
                }
                specular_only = false;
                let (wi, _) = phase.sample(wo, sampler.next_2d());
                let after = m.live_max(power(beta, ratio));
                if !roulette::by_power(&mut beta, before, after, sampler.next_1d()) {
                    break;
                }
                w.scatter(p, wi);
                continue;
            }
            Event::Escape(_) => break,
            Event::Null(si, pass) => {
                pass.apply(&mut beta, &mut ratio);
                w.cross(scene, &si);
                continue;
            }
            Event::Surface(si, pass) => (si, pass),
        };
        pass.apply(&mut beta, &mut ratio);
        edges += 1;
        // A surface that does not scatter absorbs (an emitter without a BSDF).
        let Some((bsdf, frame)) = scene.bsdf_at_in(&si, m) else {
            break;
        };
        let here = power(beta, ratio);
        let before = m.live_max(here);
        let wo = frame.to_local(si.wo);
        if bsdf.has_smooth() {
            let at = Scatterer::surface(&bsdf, &frame, wo);
            let v = Vertex::surface(at, &si, &w, edges, here);
            let hit = PhotonHit {
                v,
                wi: -w.ray.d,
                caustic: specular_only && edges > 1,
                from_volume: start.in_volume,
            };
            deposit(&hit, sampler);
        }
        if !allows(edges + 2) {
            break;
        }
        let u1 = sampler.next_1d();
        let Some(bs) = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Importance) else {
            break;
        };
        specular_only &= bs.delta;
        beta *= bs.weight;
        let after = m.live_max(power(beta, ratio));
        if !roulette::by_power(&mut beta, before, after, sampler.next_1d()) {
            break;
        }
        w.leave(scene, &si, frame.to_world(bs.wi));
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

/// What a pass of photons is traced with: where they start, the longest path they serve
/// (−1: unbounded) and the seed their streams derive from.
pub struct PhotonJob<'a> {
    pub lights: &'a PhotonLights,
    pub max_depth: i32,
    pub seed: u64,
}

/// Trace photons `0..count` of pass `pass` (`(pass, count)`) in parallel chunks, photon `j`
/// in a fresh colour mode `mode(j)` (its wavelengths may be terminated on the way): `start`
/// makes each chunk's accumulator, `deposit` adds a hit to it (with the photon's mode as it
/// is then and its sampler, whose stream is the photon's own); the accumulators come back in
/// chunk order.
pub fn trace_all<T: Send, M: PathMode>(
    scene: &Scene,
    job: &PhotonJob,
    (pass, count): (u32, u64),
    mode: impl Fn(u64) -> M + Sync,
    start: impl Fn() -> T + Sync,
    deposit: impl Fn(&mut T, &PhotonHit<M::C>, &M, &mut Sampler) + Sync,
) -> Vec<T> {
    let template = Sampler::new(
        base::SamplerKind::Independent,
        1,
        job.seed ^ 0x5048_4F54_4F4E_5321,
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
                    job.lights,
                    job.max_depth,
                    &mut sampler,
                    &m,
                    |hit, sampler| deposit(&mut acc, hit, &m, sampler),
                );
            }
            acc
        })
        .collect()
}
