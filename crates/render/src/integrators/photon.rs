//! Photon mapping (Jensen 2001): photons traced once ([`super::photons`]) and stored in
//! k-d trees (the `kiddo` crate, built from the photons in emission order, so the maps do not
//! depend on the thread count), then a camera pass that follows delta bounces to the first
//! vertex with a non-delta lobe, x, and adds there
//! - one next-event estimate (direct light),
//! - the **caustic map**'s radiance estimate (photons that reached x through delta bounces
//!   only: light → specular → x),
//! - and the rest of the indirect light either by **final gathering** — `final_gather` BSDF
//!   rays from x, each finding its first non-delta vertex y (through delta bounces) and the
//!   **global map**'s estimate of the radiance y reflects towards x (every photon there:
//!   direct, caustic and indirect) — or, with `final_gather = 0`, by the direct
//!   visualisation of the map of photons that are neither direct nor caustic.
//!
//! A radiance estimate at x is Σ K(dₚ)·f(wo, wₚ)·βₚ / N over the photons found around x
//! (wₚ their incoming direction, βₚ their power, N the photons emitted), with K the box
//! 1/(πr²), the cone 3(1 − d/r)/(πr²) or the Epanechnikov 2(1 − d²/r²)/(πr²) kernel, and r
//! the lookup radius: fixed, or the distance to the k-th nearest photon (capped).
//! Like the other integrators a vertex with delta and non-delta lobes (smooth plastic) gets
//! the estimates for its non-delta part and the path goes on when its BSDF samples a delta
//! lobe. `max_depth` bounds camera edges + gather edges + photon edges.
//!
//! Memory: a stored photon is its position in the tree (12 bytes plus the tree's index,
//! 4 bytes) and [`StoredPhoton`] (32 bytes): 48 bytes, counted by [`memory_needed`].
//!
//! Not yet: media (volumetric photon mapping), spectral mode.

use std::num::NonZero;

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use super::photons::{self, PhotonHit, PhotonLights};
use crate::bsdf::{Bsdf, TransportMode};
use crate::camera::CameraRay;
use crate::geometry::Ray;
use crate::math::{Frame, PI, Vec3};
use crate::media::{Flight, MediumKind, Phase};
use crate::sampling::Equiangular;
use crate::sampling::Sampler;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode, RgbMode};
use crate::world::Scene;

/// How photons around a point are found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lookup {
    /// The `k` nearest, within `max_radius` (∞: no cap).
    Nearest { k: u32, max_radius: f32 },
    /// Every photon within the radius.
    Radius(f32),
}

pub use base::PhotonKernel as Kernel;

/// K(d) for squared distance `d2` within radius² `r2`, normalised over the disk.
fn kernel_weight(kernel: Kernel, d2: f32, r2: f32) -> f32 {
    let base = 1.0 / (PI * r2);
    match kernel {
        Kernel::Box => base,
        Kernel::Cone => 3.0 * (1.0 - (d2 / r2).sqrt()).max(0.0) * base,
        Kernel::Epanechnikov => 2.0 * (1.0 - d2 / r2).max(0.0) * base,
    }
}

/// The parameters of the photon mapper.
#[derive(Clone, Debug, PartialEq)]
pub struct PhotonConfig {
    /// Longest path in edges (−1: unbounded).
    pub max_depth: i32,
    /// Photon paths emitted.
    pub photons: u64,
    /// Lookups in the global map (final gathering) or the indirect map.
    pub global: Lookup,
    /// Lookups in the caustic map.
    pub caustic: Lookup,
    pub kernel: Kernel,
    /// Final gathering rays per camera vertex (0: read the indirect map directly).
    pub final_gather: u32,
    /// Next-event estimates per camera vertex.
    pub direct_samples: u32,
}

impl Default for PhotonConfig {
    fn default() -> Self {
        PhotonConfig {
            max_depth: -1,
            photons: 1_000_000,
            global: Lookup::Nearest {
                k: 64,
                max_radius: f32::INFINITY,
            },
            caustic: Lookup::Nearest {
                k: 64,
                max_radius: f32::INFINITY,
            },
            kernel: Kernel::Box,
            final_gather: 16,
            direct_samples: 1,
        }
    }
}

impl PhotonConfig {
    fn allows(&self, edges: u32) -> bool {
        self.max_depth < 0 || edges <= self.max_depth as u32
    }
}

/// What a map keeps of a photon besides its position.
#[derive(Clone, Copy, Debug)]
pub struct StoredPhoton {
    /// Towards where it came from.
    pub wi: Vec3,
    pub beta: Vec3,
    /// Edges from the light.
    pub edges: u32,
}

/// Bytes per stored photon (see the module docs).
pub const BYTES_PER_PHOTON: u64 = 48;

/// A photon map.
pub struct PhotonMap {
    tree: ImmutableKdTree<f32, 3>,
    photons: Vec<StoredPhoton>,
}

impl PhotonMap {
    fn new(points: Vec<[f32; 3]>, photons: Vec<StoredPhoton>) -> Option<PhotonMap> {
        if points.is_empty() {
            return None;
        }
        let tree = ImmutableKdTree::new_from_slice(&points).ok()?;
        Some(PhotonMap { tree, photons })
    }

    /// Photons stored.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Σ `term`(photon, d², r²) over the photons `lookup` finds around `p` whose path fits
    /// in `budget` edges, r the radius of the region searched.
    fn sum(
        &self,
        lookup: Lookup,
        p: Vec3,
        budget: Option<u32>,
        term: impl Fn(&StoredPhoton, f32, f32) -> Vec3,
    ) -> Vec3 {
        let q = [p.x, p.y, p.z];
        let (found, r2) = match lookup {
            Lookup::Radius(r) => {
                let found = self
                    .tree
                    .query(&q)
                    .within::<SquaredEuclidean<f32>>(r * r)
                    .unsorted()
                    .execute();
                (found, r * r)
            }
            Lookup::Nearest { k, max_radius } => {
                let k = NonZero::new(k.max(1) as usize).unwrap_or(NonZero::<usize>::MIN);
                let found = if max_radius.is_finite() {
                    self.tree
                        .query(&q)
                        .nearest_n::<SquaredEuclidean<f32>>(k)
                        .within(max_radius * max_radius)
                        .execute()
                } else {
                    self.tree
                        .query(&q)
                        .nearest_n::<SquaredEuclidean<f32>>(k)
                        .execute()
                };
                // The radius of the region the photons were found in: the k-th distance, or
                // the cap when fewer were found within it.
                let r2 = if found.len() == k.get() || !max_radius.is_finite() {
                    found.last().map_or(0.0, |n| n.distance)
                } else {
                    max_radius * max_radius
                };
                (found, r2)
            }
        };
        if r2.is_nan() || r2 <= 0.0 {
            return Vec3::ZERO;
        }
        let mut sum = Vec3::ZERO;
        for n in &found {
            let ph = &self.photons[n.item as usize];
            if budget.is_some_and(|b| ph.edges > b) {
                continue;
            }
            sum += term(ph, n.distance, r2);
        }
        sum
    }

    /// Σ K·β and Σ (K·β)² over the photons `lookup` finds around `p`: N times the
    /// irradiance estimate there (of photons of every depth) and what its variance is
    /// estimated from (tests of the density estimation).
    pub fn irradiance_sums(&self, lookup: Lookup, kernel: Kernel, p: Vec3) -> (Vec3, Vec3) {
        let sq = std::cell::Cell::new(Vec3::ZERO);
        let sum = self.sum(lookup, p, None, |ph, d2, r2| {
            let c = ph.beta * kernel_weight(kernel, d2, r2);
            sq.set(sq.get() + c * c);
            c
        });
        (sum, sq.get())
    }

    /// Σ K·f·β over the photons around a surface point (f without its cosine: the photon's
    /// power holds it), not yet divided by the number of photons emitted.
    #[allow(clippy::too_many_arguments)]
    fn surface(
        &self,
        lookup: Lookup,
        kernel: Kernel,
        p: Vec3,
        bsdf: &Bsdf,
        frame: &Frame,
        wo: Vec3,
        budget: Option<u32>,
    ) -> Vec3 {
        self.sum(lookup, p, budget, |ph, d2, r2| {
            let wl = frame.to_local(ph.wi);
            if wl.z == 0.0 {
                return Vec3::ZERO;
            }
            let f = bsdf.eval(wo, wl, TransportMode::Radiance) / wl.z.abs();
            f * ph.beta * kernel_weight(kernel, d2, r2)
        })
    }

    /// Σ p(wo, wᵢ)·β / (4/3·π·r³) over the photons scattered around a point in a medium
    /// with phase function `phase`: σs times the in-scattered radiance, not yet divided by
    /// the number of photons emitted.
    fn volume(
        &self,
        lookup: Lookup,
        p: Vec3,
        phase: &Phase,
        wo: Vec3,
        budget: Option<u32>,
    ) -> Vec3 {
        self.sum(lookup, p, budget, |ph, _, r2| {
            let v = 4.0 / 3.0 * PI * r2 * r2.sqrt();
            ph.beta * (phase.eval(wo, ph.wi) / v)
        })
    }
}

/// Photons gathered for one map, in emission order.
#[derive(Default)]
struct MapData {
    points: Vec<[f32; 3]>,
    photons: Vec<StoredPhoton>,
}

impl MapData {
    fn push(&mut self, hit: &PhotonHit) {
        self.points.push([hit.p.x, hit.p.y, hit.p.z]);
        self.photons.push(StoredPhoton {
            wi: hit.wi,
            beta: hit.beta,
            edges: hit.edges,
        });
    }

    fn append(&mut self, mut other: MapData) {
        self.points.append(&mut other.points);
        self.photons.append(&mut other.photons);
    }

    fn build(self) -> Option<PhotonMap> {
        PhotonMap::new(self.points, self.photons)
    }
}

/// The photon maps of a scene.
pub struct PhotonMaps {
    /// Surfaces: every photon (final gathering, and in scenes with media), or those neither
    /// direct nor caustic (read directly).
    pub global: Option<PhotonMap>,
    pub caustic: Option<PhotonMap>,
    /// Scattering events in media.
    pub volume: Option<PhotonMap>,
    /// Photon paths emitted.
    pub emitted: u64,
    /// The scene has media: every estimate reads the photons, direct light included (no
    /// next-event estimation, whose shadow rays would need the media's transmittance; the
    /// extended-Nori write-up's volumetric photon mapping).
    pub with_media: bool,
}

impl PhotonMaps {
    /// Trace `cfg.photons` photons on the current rayon pool and build the maps.
    pub fn build(scene: &Scene, cfg: &PhotonConfig, seed: u64) -> PhotonMaps {
        let lights = PhotonLights::new(scene);
        let with_media = !scene.media.is_empty();
        let gather = cfg.final_gather > 0 || with_media;
        type Acc = [MapData; 3];
        let chunks = if lights.any() {
            photons::trace_all(
                scene,
                &lights,
                cfg.max_depth,
                seed,
                0,
                cfg.photons,
                || RgbMode,
                Acc::default,
                |[global, caustic, volume]: &mut Acc, hit: &PhotonHit, _: &RgbMode| {
                    if hit.si.is_none() {
                        volume.push(hit);
                        return;
                    }
                    if hit.caustic && !with_media {
                        caustic.push(hit);
                    }
                    if gather || (hit.edges > 1 && !hit.caustic) {
                        global.push(hit);
                    }
                },
            )
        } else {
            Vec::new()
        };
        let [mut global, mut caustic, mut volume] = Acc::default();
        for [g, c, v] in chunks {
            global.append(g);
            caustic.append(c);
            volume.append(v);
        }
        PhotonMaps {
            global: global.build(),
            caustic: caustic.build(),
            volume: volume.build(),
            emitted: cfg.photons.max(1),
            with_media,
        }
    }
}

/// Peak bytes of photon storage for `cfg` (every photon stored twice at worst: once in each
/// map; a path deposits at most `max_depth` times, about 3 on average in closed scenes).
pub fn memory_needed(cfg: &PhotonConfig) -> u64 {
    let per_path = if cfg.max_depth > 0 {
        (cfg.max_depth as u64).min(4)
    } else {
        4
    };
    cfg.photons
        .saturating_mul(per_path)
        .saturating_mul(BYTES_PER_PHOTON)
}

/// The photon mapper with its maps: estimates camera samples.
pub struct PhotonMapper<'a> {
    pub cfg: &'a PhotonConfig,
    pub maps: PhotonMaps,
    /// Where the point and spot lights are (equiangular sampling in media).
    points: Vec<Vec3>,
}

impl<'a> PhotonMapper<'a> {
    pub fn new(scene: &Scene, cfg: &'a PhotonConfig, maps: PhotonMaps) -> PhotonMapper<'a> {
        PhotonMapper {
            cfg,
            maps,
            points: scene.lights.iter().filter_map(|l| l.position()).collect(),
        }
    }
}

/// The in-scattered light along a segment of a homogeneous medium without emission, towards
/// point lights: one distance from a mixture of free-flight sampling (σt averaged over the
/// channels, truncated to the segment) and equiangular sampling towards each point light
/// (Kulla & Fajardo 2012), so that collisions land where a point light's singular
/// single scattering is, which free flights alone almost never do (in `media-fog` a
/// quarter of the light sat in the few pixels around the spot light, found by rare
/// collisions).
struct SegmentMixture<'a> {
    points: &'a [Vec3],
    o: Vec3,
    d: Vec3,
    end: f32,
    /// Point lights off the ray's line (those with an equiangular distribution).
    n_eq: usize,
    /// Probability of the free-flight strategy.
    p_ff: f32,
    sigma: f32,
    /// Free-flight mass on the segment, 1 − e^{−σ·end} (1 for an infinite one).
    mass: f32,
}

impl<'a> SegmentMixture<'a> {
    fn new(points: &'a [Vec3], o: Vec3, d: Vec3, end: f32, sigma: f32) -> SegmentMixture<'a> {
        let mut m = SegmentMixture {
            points,
            o,
            d,
            end,
            n_eq: 0,
            p_ff: 1.0,
            sigma,
            mass: if end.is_finite() {
                -(-sigma * end).exp_m1()
            } else {
                1.0
            },
        };
        m.n_eq = m.eqs().count();
        if m.n_eq > 0 {
            m.p_ff = 0.5;
        }
        m
    }

    /// The equiangular distributions (made on the fly: no allocation per ray).
    fn eqs(&self) -> impl Iterator<Item = Equiangular> + '_ {
        self.points
            .iter()
            .filter_map(|&q| Equiangular::new(self.o, self.d, self.end, q))
    }

    /// A distance and its density, from uniform `u` (strategy and free flight) and `v`
    /// (equiangular).
    fn sample(&self, u: f32, v: f32) -> Option<(f32, f32)> {
        let t = if u < self.p_ff {
            // F(t) = (1 − e^{−σt})/mass, inverted.
            -(-(u / self.p_ff * self.mass)).ln_1p() / self.sigma
        } else {
            let k = (((u - self.p_ff) / (1.0 - self.p_ff) * self.n_eq as f32) as usize)
                .min(self.n_eq - 1);
            self.eqs().nth(k)?.sample(v)
        };
        let pdf = self.pdf(t);
        (pdf > 0.0 && pdf.is_finite()).then_some((t, pdf))
    }

    /// The density of distance `t` (0 outside the segment).
    fn pdf(&self, t: f32) -> f32 {
        if !(t >= 0.0 && t < self.end) {
            return 0.0;
        }
        let mut pdf = self.p_ff * self.sigma * (-self.sigma * t).exp() / self.mass;
        if self.n_eq > 0 {
            let eq: f32 = self.eqs().map(|e| e.pdf(t)).sum();
            pdf += (1.0 - self.p_ff) / self.n_eq as f32 * eq;
        }
        pdf
    }
}

impl PhotonMapper<'_> {
    /// The radiance along a camera ray.
    pub fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        if self.maps.with_media {
            return self.trace_with_media(scene, cray, sampler);
        }
        self.trace(scene, cray.ray, cray.t_max, Vec3::ONE, 0, true, sampler)
    }

    /// In a scene with media: the camera path follows delta bounces and free flights (a
    /// hero channel per path with spectral MIS, as `volpath`) to its first scattering
    /// event, and every estimate there comes from the photons: the volume map's at a
    /// collision in a medium (divided by σs, which the collision's weight holds), the
    /// surface map's at a surface with a non-delta lobe.
    fn trace_with_media(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        let cfg = self.cfg;
        let m = &RgbMode;
        let len = cray.ray.d.length();
        let mut ray = Ray::at_time(cray.ray.o, cray.ray.d / len, cray.ray.time);
        let mut t_far = cray.t_max * len;
        let mut medium = scene.camera_medium;
        let hero = m.hero(sampler.next_1d());
        let mut beta = Vec3::ONE;
        let mut ratio = Vec3::ONE;
        let power = |beta: Vec3, ratio: Vec3| beta * m.hero_weight(ratio);
        let inv_n = 1.0 / self.maps.emitted as f32;
        let mut l = Vec3::ZERO;
        let mut depth = 0u32;
        // Bounded: null crossings do not count as depth.
        for _ in 0..(1 << 16) {
            let b = power(beta, ratio);
            if b.is_black() || !b.is_finite() {
                break;
            }
            let budget = |depth: u32| {
                (cfg.max_depth >= 0).then(|| (cfg.max_depth as u32).saturating_sub(depth))
            };
            let closest = scene.closest(&ray, t_far);
            if let Some(mi) = medium {
                let med = &scene.media[mi as usize];
                let d_surface = closest.t(&ray, t_far);
                if let MediumKind::Homogeneous(h) = &med.kind
                    && !self.points.is_empty()
                    && med.emission.is_none()
                {
                    // The segment's in-scattering by one distance (see `SegmentMixture`),
                    // then on to the surface attenuated by the exact transmittance.
                    let sigma_bar = h.sigma_t.element_sum() / 3.0;
                    let (u, v) = (sampler.next_1d(), sampler.next_1d());
                    if sigma_bar > 0.0
                        && cfg.allows(depth + 1)
                        && let Some(map) = &self.maps.volume
                        && let Some((t, pdf)) =
                            SegmentMixture::new(&self.points, ray.o, ray.d, d_surface, sigma_bar)
                                .sample(u, v)
                    {
                        let p = ray.at(t);
                        let tr = (-h.sigma_t * t).exp();
                        let est = map.volume(cfg.global, p, &med.phase, -ray.d, budget(depth + 1));
                        l += power(beta, ratio) * tr * est * (inv_n / pdf);
                    }
                    beta *= (-h.sigma_t * d_surface).exp();
                } else {
                    match med.sample_in(&ray, d_surface, hero, sampler, m) {
                        Flight::Scatter {
                            d,
                            weight,
                            ratio: r,
                            ..
                        } => {
                            depth += 1;
                            beta *= weight;
                            ratio *= r;
                            let p = ray.at(d);
                            if let Some(map) = &self.maps.volume
                                && cfg.allows(depth + 1)
                            {
                                let sigma_s = med.sigma_s(p);
                                let inv_s = Vec3::select(
                                    sigma_s.cmpgt(Vec3::ZERO),
                                    Vec3::ONE / sigma_s,
                                    Vec3::ZERO,
                                );
                                let est =
                                    map.volume(cfg.global, p, &med.phase, -ray.d, budget(depth));
                                l += power(beta, ratio) * inv_s * est * inv_n;
                            }
                            break;
                        }
                        Flight::Pass { weight, ratio: r } => {
                            beta *= weight;
                            ratio *= r;
                        }
                    }
                }
            }
            let Some(si) = closest.surface(scene, &ray, t_far) else {
                for &i in &scene.infinite_lights {
                    l += power(beta, ratio) * scene.lights[i as usize].environment(ray.d, m);
                }
                break;
            };
            depth += 1;
            if let Some(li) = scene.shape_light(&si) {
                l += power(beta, ratio) * scene.lights[li as usize].le(scene, &si, m);
            }
            let Some((bsdf, frame)) = scene.bsdf_at_in(&si, m) else {
                medium = scene.medium_after(&si, ray.d, medium);
                ray = si.spawn_ray(ray.d);
                t_far = f32::INFINITY;
                depth -= 1;
                continue;
            };
            let wo = frame.to_local(si.wo);
            if bsdf.has_smooth()
                && let Some(map) = &self.maps.global
                && cfg.allows(depth + 1)
            {
                let est = map.surface(
                    cfg.global,
                    cfg.kernel,
                    si.p,
                    &bsdf,
                    &frame,
                    wo,
                    budget(depth),
                );
                l += power(beta, ratio) * est * inv_n;
            }
            if !cfg.allows(depth + 1) {
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
            let wi = frame.to_world(bs.wi);
            medium = scene.medium_after(&si, wi, medium);
            ray = si.spawn_ray(wi);
            t_far = f32::INFINITY;
        }
        l
    }

    /// Follow `ray` through delta bounces to non-delta vertices and add their estimates
    /// ([`photons::walk`]). `depth`: edges before `ray`; `camera`: a camera path (sees
    /// emission, estimates everything) rather than a final gathering ray (reads the global
    /// map only; what it would see of emitters is next-event estimation's and the caustic
    /// map's).
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &self,
        scene: &Scene,
        ray: Ray,
        t_max: f32,
        beta: Vec3,
        depth: u32,
        camera: bool,
        sampler: &mut Sampler,
    ) -> Vec3 {
        photons::walk(
            scene,
            ray,
            t_max,
            beta,
            depth,
            camera,
            self.cfg.max_depth,
            u32::MAX,
            &RgbMode,
            sampler,
            |v, sampler| {
                self.at_vertex(scene, v.si, v.bsdf, v.frame, v.wo, v.depth, camera, sampler)
            },
        )
    }

    /// The estimates at a non-delta vertex `depth` edges from the camera.
    #[allow(clippy::too_many_arguments)]
    fn at_vertex(
        &self,
        scene: &Scene,
        si: &SurfaceInteraction,
        bsdf: &Bsdf,
        frame: &Frame,
        wo: Vec3,
        depth: u32,
        camera: bool,
        sampler: &mut Sampler,
    ) -> Vec3 {
        let cfg = self.cfg;
        // Photons of at most `budget` edges fit in the path.
        let budget = (cfg.max_depth >= 0).then(|| (cfg.max_depth as u32).saturating_sub(depth));
        let inv_n = 1.0 / self.maps.emitted as f32;
        let estimate = |map: &Option<PhotonMap>, lookup| {
            map.as_ref().map_or(Vec3::ZERO, |m| {
                m.surface(lookup, cfg.kernel, si.p, bsdf, frame, wo, budget) * inv_n
            })
        };
        if !camera {
            return estimate(&self.maps.global, cfg.global);
        }
        let mut l = Vec3::ZERO;
        if cfg.allows(depth + 1) {
            for _ in 0..cfg.direct_samples {
                l += photons::next_event(scene, si, bsdf, frame, wo, sampler, &RgbMode)
                    / cfg.direct_samples as f32;
            }
        }
        l += estimate(&self.maps.caustic, cfg.caustic);
        if cfg.final_gather == 0 {
            return l + estimate(&self.maps.global, cfg.global);
        }
        if !cfg.allows(depth + 2) {
            return l;
        }
        let mut gathered = Vec3::ZERO;
        for _ in 0..cfg.final_gather {
            let u1 = sampler.next_1d();
            let Some(bs) = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Radiance) else {
                continue;
            };
            // Delta lobes are the camera path's to follow.
            if bs.delta {
                continue;
            }
            let ray = si.spawn_ray(frame.to_world(bs.wi));
            gathered += self.trace(scene, ray, f32::INFINITY, bs.weight, depth, false, sampler);
        }
        l + gathered / cfg.final_gather as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::stats::{Chi2Config, chi2_test_2d, sidak};

    /// `SegmentMixture::sample` draws distances by the density `SegmentMixture::pdf` says: the density
    /// integrates to 1 over a finite segment, and a χ² test (t mapped to s = 1 − e^{−t/2} on
    /// [0, 1), a uniform second coordinate; 32 × 32 cells, 10⁶ samples) does not reject it,
    /// α = 0.01 Šidák-corrected over the 3 cases: two point lights near the ray, one very
    /// near on a short segment, one on an infinite segment.
    #[test]
    fn segment_distances_follow_their_density() {
        let o = Vec3::ZERO;
        let d = Vec3::X;
        let sigma = 0.35;
        let cases: [(Vec<Vec3>, f32); 3] = [
            (
                vec![Vec3::new(2.0, 0.1, 0.0), Vec3::new(4.0, -0.5, 0.3)],
                6.0,
            ),
            (vec![Vec3::new(1.0, 0.05, 0.0)], 3.0),
            (vec![Vec3::new(1.0, 0.2, 0.0)], f32::INFINITY),
        ];
        let level = sidak(0.01, cases.len());
        for (points, end) in cases {
            let mix = SegmentMixture::new(&points, o, d, end, sigma);
            if end.is_finite() {
                let n = 200_000;
                let h = end / n as f32;
                let total: f64 = (0..n)
                    .map(|k| mix.pdf((k as f32 + 0.5) * h) as f64)
                    .sum::<f64>()
                    * h as f64;
                assert!((total - 1.0).abs() < 1e-3, "∫pdf = {total}");
            }
            let scale = 2.0f32;
            let cfg = Chi2Config {
                res: 32,
                sample_count: 1_000_000,
                significance: level,
                seed: 3,
                ..Chi2Config::default()
            };
            let r = chi2_test_2d(
                |u2, u1| {
                    let (t, pdf) = mix.sample(u2.x, u2.y)?;
                    assert!((pdf - mix.pdf(t)).abs() <= 1e-5 * pdf);
                    Some(Vec2::new(-(-t / scale).exp_m1(), u1))
                },
                |p| {
                    let t = -scale * (-p.x).ln_1p();
                    let pdf = mix.pdf(t);
                    if pdf > 0.0 {
                        pdf * scale / (1.0 - p.x)
                    } else {
                        0.0
                    }
                },
                Vec2::ZERO,
                Vec2::ONE,
                &cfg,
            );
            assert!(r.passed, "{points:?}, end {end}: {}", r.message);
        }
    }
}
