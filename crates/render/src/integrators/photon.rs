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
//! 4 bytes) and [`StoredPhoton`] (48 bytes: two 16-byte aligned vectors, RGB or four
//! spectral lanes, and the edge count and flag): 64 bytes, counted by [`memory_needed`].
//!
//! Media (the extended-Nori write-up's volumetric photon mapping): photons also deposit at
//! scattering events in media, in a volume map read with the 4/3·π·r³ kernel at the
//! camera path's collisions ([`Lookup::Calibrated`] by default); every estimate then comes
//! from the maps, direct light included.
//!
//! Spectral mode: [`WAVELENGTH_SETS`] sets of four wavelengths, each with its own maps
//! from an equal share of the photons; a camera sample picks a set and carries its
//! wavelengths. A map estimate is converted to RGB at the camera vertex ([`Estimate`]):
//! with every wavelength when both the camera path and the photon kept theirs, else with
//! the hero's alone.

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
    /// the k-th photon is far, in the bright part: `media-fog` came out 1.4–3 % too bright);
    /// where fewer than k photons lie within the cap the estimate is a fixed-radius one, a
    /// plain convolution of the photons' density, which keeps the image's mean, and the cap
    /// shrinks as photons are added. The default for volume lookups.
    Calibrated { k: u32 },
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

/// What a map keeps of a photon besides its position.
#[derive(Clone, Copy, Debug)]
pub struct StoredPhoton<C = Vec3> {
    /// Towards where it came from.
    pub wi: Vec3,
    pub beta: C,
    /// Edges from the light.
    pub edges: u32,
    /// Its secondary wavelengths were terminated (spectral mode).
    pub terminated: bool,
}

/// Bytes per stored photon, RGB or spectral (see the module docs).
pub const BYTES_PER_PHOTON: u64 = 64;

/// Bytes per stored photon of colour `C`: its position in the tree (12), the tree's index (4)
/// and a [`StoredPhoton`].
#[cfg(test)]
fn bytes_per_photon<C>() -> u64 {
    16 + std::mem::size_of::<StoredPhoton<C>>() as u64
}

/// Wavelength sets of the photon mapper (and of PPM's visible points) in spectral mode: each
/// has its own maps, built from as many photons carrying its four wavelengths, and a camera
/// sample picks one. Few sets tint the image: on Mitsuba's Cornell box (photon mapper, 10⁶
/// photons, final gathering) the red channel's mean is 2.3 % low with 8 sets, within 1 %
/// in every channel with 32.
pub const WAVELENGTH_SETS: u32 = 32;

/// A photon map.
pub struct PhotonMap<C = Vec3> {
    tree: ImmutableKdTree<f32, 3>,
    photons: Vec<StoredPhoton<C>>,
    /// Up to 1024 photon positions spread evenly over the emission order
    /// ([`PhotonMap::resolve`]).
    sample: Vec<[f32; 3]>,
}

impl<C: Color> PhotonMap<C> {
    fn new(points: Vec<[f32; 3]>, photons: Vec<StoredPhoton<C>>) -> Option<PhotonMap<C>> {
        if points.is_empty() {
            return None;
        }
        let tree = ImmutableKdTree::new_from_slice(&points).ok()?;
        let n = points.len();
        let m = n.min(1024);
        let sample = (0..m).map(|i| points[i * n / m]).collect();
        Some(PhotonMap {
            tree,
            photons,
            sample,
        })
    }

    /// Photons stored.
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// `lookup` with a [`Lookup::Calibrated`] cap chosen from this map (from its sample of
    /// photons: deterministic).
    pub fn resolve(&self, lookup: Lookup) -> Lookup {
        let Lookup::Calibrated { k } = lookup else {
            return lookup;
        };
        // The photon itself is its own nearest neighbour: k + 1.
        let kk = NonZero::new(k.max(1) as usize + 1).unwrap_or(NonZero::<usize>::MIN);
        let mut d2: Vec<f32> = (self.sample.iter())
            .filter_map(|q| {
                let found = self
                    .tree
                    .query(q)
                    .nearest_n::<SquaredEuclidean<f32>>(kk)
                    .execute();
                (found.len() == kk.get()).then(|| found[kk.get() - 1].distance)
            })
            .filter(|d| d.is_finite() && *d > 0.0)
            .collect();
        if d2.is_empty() {
            return Lookup::Nearest {
                k,
                max_radius: f32::INFINITY,
            };
        }
        let quarter = d2.len() / 4;
        let (_, quartile, _) = d2.select_nth_unstable_by(quarter, f32::total_cmp);
        Lookup::Nearest {
            k,
            max_radius: quartile.sqrt(),
        }
    }

    /// Σ `term`(photon, d², r²) over the photons `lookup` finds around `p` whose path fits
    /// in `budget` edges, r the radius of the region searched: [photons whose wavelengths
    /// are all live, photons that terminated their secondaries] (spectral mode; see
    /// [`Estimate`]).
    fn sum(
        &self,
        lookup: Lookup,
        p: Vec3,
        budget: Option<u32>,
        term: impl Fn(&StoredPhoton<C>, f32, f32) -> C,
    ) -> Estimate<C> {
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
            Lookup::Nearest { k, .. } | Lookup::Calibrated { k } => {
                // (`Calibrated` is resolved by `PhotonMap::resolve`; unresolved, k nearest.)
                let max_radius = match lookup {
                    Lookup::Nearest { max_radius, .. } => max_radius,
                    _ => f32::INFINITY,
                };
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
        let mut sum = Estimate([C::ZERO; 2]);
        if r2.is_nan() || r2 <= 0.0 {
            return sum;
        }
        for n in &found {
            let ph = &self.photons[n.item as usize];
            if budget.is_some_and(|b| ph.edges > b) {
                continue;
            }
            sum.0[ph.terminated as usize] += term(ph, n.distance, r2);
        }
        sum
    }

    /// Σ K·β and Σ (K·β)² over the photons `lookup` finds around `p`: N times the
    /// irradiance estimate there (of photons of every depth) and what its variance is
    /// estimated from (tests of the density estimation).
    pub fn irradiance_sums(&self, lookup: Lookup, kernel: Kernel, p: Vec3) -> (C, C) {
        let sq = std::cell::Cell::new(C::ZERO);
        let Estimate([live, terminated]) = self.sum(lookup, p, None, |ph, d2, r2| {
            let c = ph.beta * kernel_weight(kernel, d2, r2);
            sq.set(sq.get() + c * c);
            c
        });
        (live + terminated, sq.get())
    }

    /// Σ K·f·β over the photons around a surface point (f without its cosine: the photon's
    /// power holds it), not yet divided by the number of photons emitted.
    #[allow(clippy::too_many_arguments)]
    fn surface(
        &self,
        lookup: Lookup,
        kernel: Kernel,
        p: Vec3,
        bsdf: &Bsdf<C>,
        frame: &Frame,
        wo: Vec3,
        budget: Option<u32>,
    ) -> Estimate<C> {
        self.sum(lookup, p, budget, |ph, d2, r2| {
            let wl = frame.to_local(ph.wi);
            if wl.z == 0.0 {
                return C::ZERO;
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
    ) -> Estimate<C> {
        self.sum(lookup, p, budget, |ph, _, r2| {
            let v = 4.0 / 3.0 * PI * r2 * r2.sqrt();
            ph.beta * (phase.eval(wo, ph.wi) / v)
        })
    }
}

/// A radiance estimate from a map, not yet times the camera path's throughput: the sums
/// over the photons whose wavelengths were all live and over those that had terminated
/// their secondaries (always 0 in RGB mode). A contribution (camera throughput × photon
/// term) counts with every wavelength only when both paths kept theirs, else with the
/// hero's alone, so [`Estimate::to_rgb`] converts at the camera vertex, with the camera
/// path's mode as it is there.
#[derive(Clone, Copy)]
struct Estimate<C>([C; 2]);

impl<C: Color> Estimate<C> {
    /// `beta` (the camera path's throughput) times the estimate, as linear sRGB for the
    /// camera path's mode `m`.
    fn to_rgb<M: PathMode<C = C>>(self, beta: C, m: &M) -> Vec3 {
        let [live, terminated] = self.0;
        if m.terminated() {
            m.to_rgb(beta * (live + terminated))
        } else if terminated.is_black() {
            m.to_rgb(beta * live)
        } else {
            m.to_rgb(beta * live) + m.terminate().to_rgb(beta * terminated)
        }
    }
}

/// Photons gathered for one map, in emission order.
struct MapData<C> {
    points: Vec<[f32; 3]>,
    photons: Vec<StoredPhoton<C>>,
}

impl<C> Default for MapData<C> {
    fn default() -> Self {
        MapData {
            points: Vec::new(),
            photons: Vec::new(),
        }
    }
}

impl<C: Color> MapData<C> {
    /// Store `hit`, carried by a photon now in mode `m`.
    fn push<M: PathMode<C = C>>(&mut self, hit: &PhotonHit<C>, m: &M) {
        self.points.push([hit.p.x, hit.p.y, hit.p.z]);
        self.photons.push(StoredPhoton {
            wi: hit.wi,
            beta: hit.beta,
            edges: hit.edges,
            terminated: m.terminated(),
        });
    }

    fn append(&mut self, mut other: MapData<C>) {
        self.points.append(&mut other.points);
        self.photons.append(&mut other.photons);
    }

    fn build(self) -> Option<PhotonMap<C>> {
        PhotonMap::new(self.points, self.photons)
    }
}

/// The photon maps of a scene (of one wavelength set in spectral mode).
pub struct PhotonMaps<C = Vec3> {
    /// Surfaces: every photon (final gathering, and in scenes with media), or those neither
    /// direct nor caustic (read directly).
    pub global: Option<PhotonMap<C>>,
    pub caustic: Option<PhotonMap<C>>,
    /// Scattering events in media.
    pub volume: Option<PhotonMap<C>>,
    /// `cfg.volume` resolved against the volume map ([`PhotonMap::resolve`]).
    pub volume_lookup: Lookup,
    /// Photon paths emitted.
    pub emitted: u64,
    /// The scene has media: every estimate reads the photons, direct light included (no
    /// next-event estimation, whose shadow rays would need the media's transmittance; the
    /// extended-Nori write-up's volumetric photon mapping).
    pub with_media: bool,
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
        let with_media = !scene.media.is_empty();
        let gather = cfg.final_gather > 0 || with_media;
        let chunks = if lights.any() {
            photons::trace_all(
                scene,
                &lights,
                cfg.max_depth,
                seed,
                pass,
                count,
                mode,
                <[MapData<C>; 3]>::default,
                |[global, caustic, volume]: &mut [MapData<C>; 3],
                 hit: &PhotonHit<C>,
                 m: &M,
                 _: &mut Sampler| {
                    if hit.si.is_none() {
                        volume.push(hit, m);
                        return;
                    }
                    if hit.caustic && !with_media {
                        caustic.push(hit, m);
                    }
                    if gather || (hit.edges > 1 && !hit.caustic) {
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
        let volume = volume.build();
        PhotonMaps {
            global: global.build(),
            caustic: caustic.build(),
            volume_lookup: volume
                .as_ref()
                .map_or(cfg.volume, |m| m.resolve(cfg.volume)),
            volume,
            emitted: count.max(1),
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

/// The photon mapper with its maps: estimates camera samples in the colour mode `M`.
pub struct PhotonMapper<'a, M: PathMode = RgbMode> {
    pub cfg: &'a PhotonConfig,
    /// One wavelength set's uniform number ([`PathMode::from_u`]) and maps per set: one set
    /// in RGB mode, [`WAVELENGTH_SETS`] in spectral mode (photons split evenly).
    pub sets: Vec<(f32, PhotonMaps<M::C>)>,
    /// Where the point and spot lights are (equiangular sampling in media).
    points: Vec<Vec3>,
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

impl<M: PathMode> PhotonMapper<'_, M> {
    /// The radiance along a camera ray (linear sRGB).
    pub fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        // One set (RGB) draws nothing, so RGB's sample streams do not depend on the mode.
        let n = self.sets.len();
        let (u, maps) = if n == 1 {
            &self.sets[0]
        } else {
            &self.sets[((sampler.next_1d() * n as f32) as usize).min(n - 1)]
        };
        let m = M::from_u(*u);
        // The maps' estimates, converted where they are made (`Estimate`); the rest (emission
        // met, next-event estimates) in the mode's colour, converted at the end.
        let mut rgb = Vec3::ZERO;
        let l = if maps.with_media {
            self.trace_with_media(scene, maps, cray, sampler, &m, &mut rgb)
        } else {
            let ray = cray.ray;
            let one = M::C::ONE;
            self.trace(
                scene, maps, ray, cray.t_max, one, 0, true, one, &mut rgb, sampler, &m,
            )
        };
        m.to_rgb(l) + rgb
    }

    /// In a scene with media: the camera path follows delta bounces and free flights (a
    /// hero channel per path with spectral MIS, as `volpath`) to its first scattering
    /// event, and every estimate there comes from the photons: the volume map's at a
    /// collision in a medium (divided by σs, which the collision's weight holds), the
    /// surface map's at a surface with a non-delta lobe (added to `rgb`).
    fn trace_with_media(
        &self,
        scene: &Scene,
        maps: &PhotonMaps<M::C>,
        cray: &CameraRay,
        sampler: &mut Sampler,
        m: &M,
        rgb: &mut Vec3,
    ) -> M::C {
        let cfg = self.cfg;
        let len = cray.ray.d.length();
        let mut ray = Ray::at_time(cray.ray.o, cray.ray.d / len, cray.ray.time);
        let mut t_far = cray.t_max * len;
        let mut medium = scene.camera_medium;
        let hero = m.hero(sampler.next_1d());
        let mut beta = M::C::ONE;
        let mut ratio = M::C::ONE;
        let power = |beta: M::C, ratio: M::C| beta * m.hero_weight(ratio);
        let inv_n = 1.0 / maps.emitted as f32;
        let mut l = M::C::ZERO;
        let mut depth = 0u32;
        // Bounded: null crossings do not count as depth.
        for _ in 0..(1 << 16) {
            let b = power(beta, ratio);
            if b.is_black() || !(b.max_lane().is_finite() && b.mean().is_finite()) {
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
                    let sigma_bar = m.unbounded(h.sigma_t).mean();
                    let (u, v) = (sampler.next_1d(), sampler.next_1d());
                    if sigma_bar > 0.0
                        && cfg.allows(depth + 1)
                        && let Some(map) = &maps.volume
                        && let Some((t, pdf)) =
                            SegmentMixture::new(&self.points, ray.o, ray.d, d_surface, sigma_bar)
                                .sample(u, v)
                    {
                        let p = ray.at(t);
                        let tr = h.transmittance_in(t, m);
                        let est = map.volume(
                            maps.volume_lookup,
                            p,
                            &med.phase,
                            -ray.d,
                            budget(depth + 1),
                        );
                        *rgb += est.to_rgb(power(beta, ratio) * tr * (inv_n / pdf), m);
                    }
                    beta *= h.transmittance_in(d_surface, m);
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
                            if let Some(map) = &maps.volume
                                && cfg.allows(depth + 1)
                            {
                                let sigma_s = med.sigma_s_in(p, m);
                                let inv_s = M::C::from_fn(|i| {
                                    let s = sigma_s.lane(i);
                                    if s > 0.0 { 1.0 / s } else { 0.0 }
                                });
                                let est = map.volume(
                                    maps.volume_lookup,
                                    p,
                                    &med.phase,
                                    -ray.d,
                                    budget(depth),
                                );
                                *rgb += est.to_rgb(power(beta, ratio) * inv_s * inv_n, m);
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
                // Absorbed, unless an index-matched boundary.
                if !scene.is_null(&si) {
                    break;
                }
                medium = scene.medium_after(&si, ray.d, medium);
                ray = si.spawn_ray(ray.d);
                t_far = f32::INFINITY;
                depth -= 1;
                continue;
            };
            let wo = frame.to_local(si.wo);
            if bsdf.has_smooth()
                && let Some(map) = &maps.global
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
                *rgb += est.to_rgb(power(beta, ratio) * inv_n, m);
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
    /// ([`photons::walk`]): the maps' to `rgb`, the rest returned. `depth`: edges before
    /// `ray`; `camera`: a camera path (sees emission, estimates everything) rather than a
    /// final gathering ray (reads the global map only; what it would see of emitters is
    /// next-event estimation's and the caustic map's); `outer`: the camera path's
    /// throughput before `ray`'s walk (its `beta`) started.
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &self,
        scene: &Scene,
        maps: &PhotonMaps<M::C>,
        ray: Ray,
        t_max: f32,
        beta: M::C,
        depth: u32,
        camera: bool,
        outer: M::C,
        rgb: &mut Vec3,
        sampler: &mut Sampler,
        m: &M,
    ) -> M::C {
        photons::walk(
            scene,
            ray,
            t_max,
            beta,
            depth,
            camera,
            self.cfg.max_depth,
            u32::MAX,
            m,
            sampler,
            |v, sampler| self.at_vertex(scene, maps, v, camera, outer, rgb, sampler, m),
        )
    }

    /// The estimates at a non-delta vertex `v` of a walk that started with the camera
    /// throughput `outer`: the maps' added to `rgb`, the next-event estimates returned.
    #[allow(clippy::too_many_arguments)]
    fn at_vertex(
        &self,
        scene: &Scene,
        maps: &PhotonMaps<M::C>,
        v: &photons::Vertex<M::C>,
        camera: bool,
        outer: M::C,
        rgb: &mut Vec3,
        sampler: &mut Sampler,
        m: &M,
    ) -> M::C {
        let cfg = self.cfg;
        let (si, bsdf, frame, wo, depth) = (v.si, v.bsdf, v.frame, v.wo, v.depth);
        // Photons of at most `budget` edges fit in the path.
        let budget = (cfg.max_depth >= 0).then(|| (cfg.max_depth as u32).saturating_sub(depth));
        let beta = outer * v.beta;
        let weight = beta * (1.0 / maps.emitted as f32);
        let estimate = |map: &Option<PhotonMap<M::C>>, lookup| {
            map.as_ref().map_or(Vec3::ZERO, |map| {
                map.surface(lookup, cfg.kernel, si.p, bsdf, frame, wo, budget)
                    .to_rgb(weight, m)
            })
        };
        if !camera {
            *rgb += estimate(&maps.global, cfg.global);
            return M::C::ZERO;
        }
        let mut l = M::C::ZERO;
        if cfg.allows(depth + 1) {
            for _ in 0..cfg.direct_samples {
                l += photons::next_event(scene, si, bsdf, frame, wo, sampler, m)
                    * (1.0 / cfg.direct_samples as f32);
            }
        }
        *rgb += estimate(&maps.caustic, cfg.caustic);
        if cfg.final_gather == 0 {
            *rgb += estimate(&maps.global, cfg.global);
            return l;
        }
        if !cfg.allows(depth + 2) {
            return l;
        }
        let gather_outer = beta * (1.0 / cfg.final_gather as f32);
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
            // A gathering walk sees no emission and returns nothing: its estimates are the
            // global map's, added to `rgb`.
            self.trace(
                scene,
                maps,
                ray,
                f32::INFINITY,
                bs.weight,
                depth,
                false,
                gather_outer,
                rgb,
                sampler,
                m,
            );
        }
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::spectral::SampledSpectrum;
    use crate::stats::{Chi2Config, chi2_test_2d, sidak};

    /// The memory per photon the docs state is what a stored photon takes.
    #[test]
    fn bytes_per_photon_as_documented() {
        assert_eq!(bytes_per_photon::<Vec3>(), BYTES_PER_PHOTON);
        assert_eq!(bytes_per_photon::<SampledSpectrum>(), BYTES_PER_PHOTON);
    }

    /// On a cubic lattice of spacing 1 the 6 nearest neighbours of an inner photon are at
    /// distance 1 and the 7th at √2: the calibrated cap for k = 6 is 1 (most sampled photons
    /// are inner ones), and for k = 7, √2.
    #[test]
    fn calibrated_cap_is_the_lower_quartile_of_kth_distances() {
        let n = 20;
        let mut points = Vec::new();
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    points.push([x as f32, y as f32, z as f32]);
                }
            }
        }
        let photons = vec![
            StoredPhoton {
                wi: Vec3::Z,
                beta: Vec3::ONE,
                edges: 1,
                terminated: false,
            };
            points.len()
        ];
        let map = PhotonMap::new(points, photons).unwrap();
        for (k, want) in [(6, 1.0f32), (7, 2.0f32.sqrt())] {
            match map.resolve(Lookup::Calibrated { k }) {
                Lookup::Nearest {
                    k: got_k,
                    max_radius,
                } => {
                    assert_eq!(got_k, k);
                    assert!((max_radius - want).abs() < 1e-5, "k = {k}: {max_radius}");
                }
                other => panic!("{other:?}"),
            }
        }
        // Other lookups pass through.
        let r = Lookup::Radius(0.5);
        assert_eq!(map.resolve(r), r);
    }

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
