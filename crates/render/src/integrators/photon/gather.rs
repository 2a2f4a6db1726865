//! The photon mapper's camera side: camera paths walk through delta bounces (the shared
//! camera-side walk of `photons/camera.rs`, free flights in media) to their first vertex
//! that is not one — a surface with a non-delta lobe or a collision in a medium — and read
//! the maps there.
//!
//! At a surface x: next-event estimates (direct light from the lights, through media), the
//! caustic map's estimate, and either final gathering — BSDF rays from x, each walking to
//! its own first vertex y that is not a delta bounce and reading the map of y's kind there
//! (every photon; the emission of media it collides in too) — or the global map read at x
//! (photons that are neither direct light nor caustic). At a collision in a medium the
//! volume map is read where it is (final gathering from every collision would be far
//! slower, and noisier): every photon when the maps serve final gathering, else the photons
//! that are not direct light plus a next-event estimate. Direct light from emitting media
//! is in the maps alone. A map estimate in a medium is σs times the in-scattered radiance:
//! the camera throughput there, which holds σs, is divided by it. In a homogeneous medium
//! without emission, with point or spot lights about, the in-scattering of a camera segment
//! is estimated at one distance (`photons::segment_point`) instead of a free flight, as at a
//! collision, and the walk crosses the segment with its exact transmittance.

use super::map::{Enclosure, Estimate, PhotonMap};
use super::{Lookup, PhotonConfig, PhotonMaps};
use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::geometry::Ray;
use crate::integrators::photons::{self, CameraWalk, Segment, Vertex, Visit};
use crate::integrators::transport::{Scatterer, Walker};
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// One camera sample's estimates: the maps of its wavelength set and its colour mode.
pub(super) struct Gather<'a, M: PathMode> {
    pub(super) cfg: &'a PhotonConfig,
    /// Where the point and spot lights are (for `photons::segment_point`).
    pub(super) points: &'a [Vec3],
    pub(super) scene: &'a Scene,
    pub(super) maps: &'a PhotonMaps<M::C>,
    pub(super) m: &'a M,
    /// The maps' estimates so far, converted to linear sRGB where they are made (see
    /// `Estimate`).
    pub(super) rgb: Vec3,
}

impl<'a, M: PathMode> Gather<'a, M> {
    /// Photons of at most this many edges fit in a path with `depth` camera edges.
    fn budget(&self, depth: u32) -> Option<u32> {
        let d = self.cfg.max_depth;
        (d >= 0).then(|| (d as u32).saturating_sub(depth))
    }

    /// `beta` / the photons emitted, and in a medium (at `v`) / σs there.
    fn weight(&self, v: &Vertex<M::C>, beta: M::C) -> M::C {
        let w = beta * (1.0 / self.maps.emitted as f32);
        match (v.at, v.medium) {
            (Scatterer::Medium { .. }, Some(i)) => {
                let sigma_s = self.scene.media[i as usize].sigma_s_in(v.p, self.m);
                w * M::C::from_fn(|k| {
                    let s = sigma_s.lane(k);
                    if s > 0.0 { 1.0 / s } else { 0.0 }
                })
            }
            _ => w,
        }
    }

    /// Add `map`'s estimate at `v` (read with `lookup`, the photons that fit after `depth`
    /// edges) times `weight`; in a medium, in the part of the ball that `v` sees
    /// ([`Enclosure`]).
    fn add(
        &mut self,
        (map, lookup): (&Option<PhotonMap<M::C>>, Lookup),
        v: &Vertex<M::C>,
        weight: M::C,
        sampler: &mut Sampler,
    ) {
        let Some(map) = map else { return };
        let budget = self.budget(v.depth);
        let est = match v.at {
            Scatterer::Surface { bsdf, frame, wo } => {
                map.surface_estimate(lookup, self.cfg.kernel, v.p, (bsdf, frame, wo), budget)
            }
            Scatterer::Medium { phase, wo } => {
                let u = [sampler.next_1d(), sampler.next_1d(), sampler.next_1d()];
                let around = Enclosure::probe(self.scene, v.p, lookup.reach(), u);
                map.volume_estimate(lookup, &around, (phase, wo), budget)
            }
        };
        self.rgb += est.to_rgb(weight, self.m);
    }

    /// The global map's precomputed estimate at a surface vertex `v`, where one serves
    /// (`PhotonMap::precomputed`).
    fn precomputed(&self, v: &Vertex<M::C>) -> Option<Estimate<M::C>> {
        let Scatterer::Surface { bsdf, frame, wo } = v.at else {
            return None;
        };
        let map = self.maps.global.as_ref()?;
        map.precomputed(v.p, (bsdf, frame, wo), self.budget(v.depth))
    }

    /// The map of `v`'s kind and its lookup: the global map at a surface, the volume map in
    /// a medium.
    fn map_at(&self, v: &Vertex<M::C>) -> (&'a Option<PhotonMap<M::C>>, Lookup) {
        match v.at {
            Scatterer::Surface { .. } => (&self.maps.global, self.cfg.global),
            Scatterer::Medium { .. } => (&self.maps.volume, self.maps.volume_lookup),
        }
    }

    /// A camera path's walk (`camera`) or a final gathering ray's, which leaves the emitters
    /// it would see to next-event estimation and the caustic map.
    fn walk(&self, depth: u32, camera: bool) -> CameraWalk {
        CameraWalk {
            depth,
            see_emitters: camera,
            see_media: true,
            max_depth: self.cfg.max_depth,
            rr_depth: u32::MAX,
        }
    }

    /// A camera path; returns what is not a map estimate (emission met, next-event
    /// estimates).
    pub(super) fn camera(&mut self, cray: &CameraRay, sampler: &mut Sampler) -> M::C {
        let (scene, m) = (self.scene, self.m);
        let w = CameraWalk::camera_walker(scene, cray, m, sampler);
        self.walk(0, true)
            .run(scene, w, M::C::ONE, m, sampler, &mut Camera(self))
    }

    /// The estimates at a camera path's first non-delta vertex `v`: the maps' added to
    /// `rgb`, the next-event estimates returned.
    fn at_camera_vertex(&mut self, v: &Vertex<M::C>, sampler: &mut Sampler) -> M::C {
        let (cfg, maps) = (self.cfg, self.maps);
        let depth = v.depth;
        let weight = self.weight(v, v.beta);
        if v.si.is_none() {
            return self.in_medium(v, sampler);
        }
        let mut l = M::C::ZERO;
        if cfg.allows(depth + 1) {
            for _ in 0..cfg.direct_samples {
                l += photons::next_event(self.scene, v, sampler, self.m)
                    * (1.0 / cfg.direct_samples as f32);
            }
        }
        self.add((&maps.caustic, cfg.caustic), v, weight, sampler);
        if cfg.final_gather == 0 {
            self.add((&maps.global, cfg.global), v, weight, sampler);
            return l;
        }
        if !cfg.allows(depth + 2) {
            return l;
        }
        let outer = v.beta * (1.0 / cfg.final_gather as f32);
        for _ in 0..cfg.final_gather {
            if let Some((w, beta)) = self.gather_ray(v, sampler) {
                l += self.gather(w, beta, depth, outer, sampler) * (1.0 / cfg.final_gather as f32);
            }
        }
        l
    }

    /// The estimate at a camera vertex `v` in a medium: the volume map read there — every
    /// photon when the maps serve final gathering, else those that are not direct light plus
    /// a next-event estimate (returned, not yet times `v.beta`).
    fn in_medium(&mut self, v: &Vertex<M::C>, sampler: &mut Sampler) -> M::C {
        let (cfg, maps) = (self.cfg, self.maps);
        if !cfg.allows(v.depth + 1) {
            return M::C::ZERO;
        }
        let weight = self.weight(v, v.beta);
        self.add((&maps.volume, maps.volume_lookup), v, weight, sampler);
        if cfg.final_gather > 0 {
            return M::C::ZERO;
        }
        photons::next_event(self.scene, v, sampler, self.m)
    }

    /// A final gathering ray from the surface vertex `v` by its BSDF, and its weight;
    /// `None` when sampling fails or picks a delta lobe (the camera path's to follow).
    fn gather_ray(&self, v: &Vertex<M::C>, sampler: &mut Sampler) -> Option<(Walker, M::C)> {
        let (Scatterer::Surface { bsdf, frame, wo }, Some(si)) = (v.at, v.si) else {
            return None;
        };
        let u1 = sampler.next_1d();
        let bs = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Radiance)?;
        if bs.delta {
            return None;
        }
        let mut w = Walker::new(Ray::new(si.p, bs.wi), f32::INFINITY, v.medium, v.hero);
        w.leave(self.scene, si, frame.to_world(bs.wi));
        Some((w, bs.weight))
    }

    /// A final gathering walk from a vertex `depth` edges from the camera (throughput
    /// `beta`, the camera path's `outer` before it): the map of the kind of the vertex where
    /// it stops being a delta chain, every photon (what it would see of emitters is
    /// next-event estimation's and the caustic map's), added to `rgb`; returns the emission
    /// of media it collides in (times `beta`, not yet times the camera path's throughput).
    fn gather(
        &mut self,
        w: Walker,
        beta: M::C,
        depth: u32,
        outer: M::C,
        sampler: &mut Sampler,
    ) -> M::C {
        let (scene, m) = (self.scene, self.m);
        let walk = self.walk(depth, false);
        walk.run(
            scene,
            w,
            beta,
            m,
            sampler,
            &mut |v: &Vertex<M::C>, sampler: &mut Sampler| {
                let weight = self.weight(v, outer * v.beta);
                match self.precomputed(v) {
                    Some(est) => self.rgb += est.to_rgb(weight, self.m),
                    None => self.add(self.map_at(v), v, weight, sampler),
                }
                M::C::ZERO
            },
        )
    }

    /// The segment estimate (see the module docs): the in-scattered radiance at one
    /// distance (next-event estimation, returned, and the volume map's, added to `rgb`), and
    /// the segment's exact transmittance; `None` where it does not apply.
    fn segment(&mut self, seg: &Segment<M::C>, sampler: &mut Sampler) -> Option<(M::C, M::C)> {
        let room = self.cfg.allows(seg.depth + 1);
        let sp = photons::segment_point(self.points, seg, room, sampler, self.m)?;
        let l = match &sp.x {
            // The point's throughput holds no σs; at a collision it would.
            Some(x) => {
                let beta = x.beta * sp.sigma_s;
                beta * self.in_medium(&Vertex { beta, ..*x }, sampler)
            }
            None => M::C::ZERO,
        };
        Some((sp.tr, l))
    }
}

/// What a camera path reads of the maps.
struct Camera<'g, 'a, M: PathMode>(&'g mut Gather<'a, M>);

impl<M: PathMode> Visit<M> for Camera<'_, '_, M> {
    fn vertex(&mut self, v: &Vertex<M::C>, sampler: &mut Sampler) -> M::C {
        self.0.at_camera_vertex(v, sampler)
    }

    fn segment(&mut self, seg: &Segment<M::C>, sampler: &mut Sampler) -> Option<(M::C, M::C)> {
        self.0.segment(seg, sampler)
    }
}
