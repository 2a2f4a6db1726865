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
//! Final gathering reads precomputed estimates where they serve (Christensen 1999, "Faster
//! photon map global illumination"; pbrt-v2's radiance photons): at every
//! `map::RADIANCE_STRIDE`th (16th) photon of the global map (in emission order within a tracing
//! chunk) the irradiance sums of either side of its surface, Σ K·β over the photons found
//! around it; at a diffuse surface, where f is constant over a hemisphere, a gathering ray's
//! estimate is then f times the sum of wo's side at the nearest such photon — one
//! nearest-neighbour query instead of k, no BSDF evaluation per photon — if the photon's
//! region holds the point, their normals agree (cosine ≥ 0.9, either way round) and the
//! vertex's depth budget admits the photons the sums hold (those that fit two edges from
//! the camera); else the exact estimate. Its bias: the estimate at the nearest marked photon
//! instead of at the point, a further blur of at most one lookup radius (tested in
//! `map.rs`: equal in expectation over a plane). Exact estimates at diffuse surfaces also
//! sum K·β on the front side and multiply once.
//!
//! Memory: a stored photon is its position in the tree (12 bytes plus the tree's index,
//! 4 bytes) and [`StoredPhoton`] (48 bytes: two 16-byte aligned vectors, RGB or four
//! spectral lanes, and the edge count and flag): 64 bytes, counted by [`memory_needed`]; a
//! volume map keeps its positions once more (12 bytes), within that bound, and a global map
//! that serves final gathering keeps them while it precomputes and then about 112 bytes per
//! 16 photons (7 a photon), within the bound's slack (4 deposits a path counted, about 3 met).
//!
//! Media (the extended-Nori write-up's volumetric photon mapping): photons also deposit at
//! scattering events in media, in a volume map read with the 4/3·π·r³ kernel where the
//! camera path (or a gathering ray) collides ([`Lookup::Calibrated`] by default), cut to the
//! part of the ball that the collision sees (`map::Enclosure`: 16 rays, so that the
//! estimate does not darken towards the medium's boundary); a
//! collision is a vertex like a surface with a non-delta lobe (next-event estimation through
//! media by the transport layer's shadow query, final gathering by phase sampling). Photons
//! start in emitting media too, whose direct light only the maps carry (`gather.rs`).
//!
//! Spectral mode: [`WAVELENGTH_SETS`] sets of four wavelengths, each with its own maps
//! from an equal share of the photons; a camera sample picks a set and carries its
//! wavelengths. A map estimate is converted to RGB at the camera vertex ([`Estimate`]):
//! with every wavelength when both the camera path and the photon kept theirs, else with
//! the hero's alone.

mod gather;
mod map;

pub use map::{Enclosure, PhotonMap, StoredPhoton};

use self::gather::Gather;
use self::map::MapData;
use super::photons::{self, PhotonHit, PhotonJob, PhotonLights};
use std::time::Instant;

use super::{IntegratorModel, volume_unsupported};
use crate::camera::CameraRay;
use crate::drive::{self, Estimator};
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::session::{Job, RenderOutcome};
use crate::spectral::lanes::{Color, PathMode, RgbMode};
use crate::world::Scene;

/// How photons around a point are found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lookup {
    /// The `k` nearest, within `max_radius` (∞: no cap).
    Nearest { k: u32, max_radius: f32 },
    /// Every photon within the radius.
    Radius(f32),
    /// The `k` nearest within a cap chosen from the map when it is built: the lower
    /// quartile, over a sample of its photons, of the distance to their `k`-th nearest
    /// neighbour. The k nearest alone overestimate dark regions next to bright ones (there
    /// the k-th photon is far, in the bright part);
    /// where fewer than k photons lie within the cap the estimate is a fixed-radius one, a
    /// plain convolution of the photons' density, which keeps the image's mean, and the cap
    /// shrinks as photons are added. The default for volume lookups.
    Calibrated { k: u32 },
}

impl Lookup {
    /// The largest radius it can search.
    pub fn reach(self) -> f32 {
        match self {
            Lookup::Nearest { max_radius, .. } => max_radius,
            Lookup::Radius(r) => r,
            Lookup::Calibrated { .. } => f32::INFINITY,
        }
    }
}

pub use base::PhotonKernel as Kernel;

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
    /// Lookups in the volume map.
    pub volume: Lookup,
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
            volume: Lookup::Calibrated { k: 64 },
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

/// Bytes per stored photon, RGB or spectral (see the module docs).
pub const BYTES_PER_PHOTON: u64 = 64;

/// Wavelength sets of the photon mapper (and of PPM's visible points) in spectral mode: each
/// has its own maps, built from as many photons carrying its four wavelengths, and a camera
/// sample picks one. Few sets tint the image (how many are enough: `bench/README.md`).
pub const WAVELENGTH_SETS: u32 = 32;

/// The photon maps of a scene (of one wavelength set in spectral mode).
pub struct PhotonMaps<C = Vec3> {
    /// Surfaces: every photon (final gathering), or those neither direct nor caustic (read
    /// directly).
    pub global: Option<PhotonMap<C>>,
    pub caustic: Option<PhotonMap<C>>,
    /// Scattering events in media: every photon (final gathering), or those that are not
    /// direct light (read directly).
    pub volume: Option<PhotonMap<C>>,
    /// `cfg.volume` resolved against the volume map ([`PhotonMap::resolve`]).
    pub volume_lookup: Lookup,
    /// Photon paths emitted.
    pub emitted: u64,
}

impl PhotonMaps {
    /// Trace `cfg.photons` photons (RGB) on the current rayon pool and build the maps.
    pub fn build(scene: &Scene, cfg: &PhotonConfig, seed: u64) -> PhotonMaps {
        PhotonMaps::build_in(scene, cfg, seed, 0, cfg.photons, |_| RgbMode)
    }
}

impl<C: Color + Send> PhotonMaps<C> {
    /// Trace `count` photons of pass `pass`, each in a fresh mode from `mode`, and build the
    /// maps.
    pub fn build_in<M: PathMode<C = C>>(
        scene: &Scene,
        cfg: &PhotonConfig,
        seed: u64,
        pass: u32,
        count: u64,
        mode: impl Fn(u64) -> M + Sync,
    ) -> PhotonMaps<C> {
        let lights = PhotonLights::new(scene);
        let gather = cfg.final_gather > 0;
        let chunks = if lights.any() {
            let job = PhotonJob {
                lights: &lights,
                max_depth: cfg.max_depth,
                seed,
            };
            photons::trace_all(
                scene,
                &job,
                (pass, count),
                mode,
                <[MapData<C>; 3]>::default,
                |[global, caustic, volume]: &mut [MapData<C>; 3],
                 hit: &PhotonHit<C>,
                 m: &M,
                 _: &mut Sampler| {
                    // Direct light is next-event estimation's, except from emitting media.
                    let indirect = hit.v.depth > 1 || hit.from_volume;
                    if hit.v.si.is_none() {
                        if gather || indirect {
                            volume.push(hit, m);
                        }
                        return;
                    }
                    if hit.caustic {
                        caustic.push(hit, m);
                    }
                    if gather || (indirect && !hit.caustic) {
                        global.push(hit, m);
                    }
                },
            )
        } else {
            Vec::new()
        };
        let [mut global, mut caustic, mut volume] = <[MapData<C>; 3]>::default();
        for [g, c, v] in chunks {
            global.append(g);
            caustic.append(c);
            volume.append(v);
        }
        let volume = volume.build(true, None);
        // Precomputed estimates for final gathering hold the photons that fit at a gathering
        // ray's vertex two edges from the camera (the common case; see `map::Irradiance`).
        let budget = (cfg.max_depth >= 0).then(|| (cfg.max_depth as u32).saturating_sub(2));
        PhotonMaps {
            global: global.build(false, gather.then_some(((cfg.global, cfg.kernel), budget))),
            caustic: caustic.build(false, None),
            volume_lookup: volume
                .as_ref()
                .map_or(cfg.volume, |m| m.resolve(cfg.volume)),
            volume,
            emitted: count.max(1),
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

/// The photon mapper with its maps: estimates camera samples in the colour mode `M`.
pub struct PhotonMapper<'a, M: PathMode = RgbMode> {
    pub cfg: &'a PhotonConfig,
    /// One wavelength set's uniform number ([`PathMode::from_u`]) and maps per set: one set
    /// in RGB mode, [`WAVELENGTH_SETS`] in spectral mode (photons split evenly).
    pub sets: Vec<(f32, PhotonMaps<M::C>)>,
    /// Where the point and spot lights are (equiangular sampling in media).
    points: Vec<Vec3>,
}

impl IntegratorModel for PhotonConfig {
    fn name(&self) -> &'static str {
        "photon"
    }

    fn unsupported(&self, scene: &Scene) -> Option<String> {
        volume_unsupported(self.name(), scene)
    }

    fn memory(&self, _scene: &Scene) -> Option<(&'static str, u64)> {
        Some(("storing the photons", memory_needed(self)))
    }

    /// The maps first (in spectral mode one set per [`WAVELENGTH_SETS`]), then the camera
    /// pass through the tile loop.
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        let start = Instant::now();
        let sets = if M::SPECTRAL { WAVELENGTH_SETS } else { 1 };
        let scene = job.scene;
        let mapper = PhotonMapper::<M>::build(scene, self, scene.sampler.seed, sets);
        let mut out = drive::render_tiles::<M, _>(job, &mapper);
        out.elapsed = start.elapsed();
        out
    }
}

impl<M: PathMode> Estimator<M> for PhotonMapper<'_, M> {
    /// The radiance along a camera ray (linear sRGB).
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        // One set (RGB) draws nothing, so RGB's sample streams do not depend on the mode.
        let n = self.sets.len();
        let (u, maps) = if n == 1 {
            &self.sets[0]
        } else {
            &self.sets[((sampler.next_1d() * n as f32) as usize).min(n - 1)]
        };
        let m = M::from_u(*u);
        let mut g = Gather {
            cfg: self.cfg,
            points: &self.points,
            scene,
            maps,
            m: &m,
            rgb: Vec3::ZERO,
        };
        // The maps' estimates are converted where they are made (`Gather::rgb`); the rest
        // (emission met, next-event estimates) in the mode's colour, converted at the end.
        let l = g.camera(cray, sampler);
        m.to_rgb(l) + g.rgb
    }
}

impl<'a, M: PathMode> PhotonMapper<'a, M>
where
    M::C: Send,
{
    /// Trace the photons of `sets` wavelength sets (following [`photons::wavelength_set`])
    /// on the current rayon pool and build their maps.
    pub fn build(scene: &Scene, cfg: &'a PhotonConfig, seed: u64, sets: u32) -> Self {
        let sets = sets.max(1);
        let count = cfg.photons.div_ceil(sets as u64);
        let sets = (0..sets)
            .map(|k| {
                let u = photons::wavelength_set(seed, k as u64);
                let maps = PhotonMaps::build_in(scene, cfg, seed, k, count, |_| M::from_u(u));
                (u, maps)
            })
            .collect();
        PhotonMapper {
            cfg,
            sets,
            points: scene.lights.iter().filter_map(|l| l.position()).collect(),
        }
    }
}
