//! BDPT's vertices and their densities: what a subpath stores at each vertex ([`Vertex`]),
//! the joint of a strategy ([`Joint`]), the subpaths' reused storage ([`Subpaths`]), and
//! the area densities with which one vertex samples the next (pbrt-v4's `Pdf`,
//! `PdfLight`, `PdfLightOrigin`) that the MIS weights compare.

use super::Bdpt;
use crate::bsdf::{Bsdf, TransportMode};
use crate::math::{Frame, Vec3};
use crate::media::Phase;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kind {
    Camera,
    /// The first vertex of a light subpath, or a light point sampled for s = 1.
    Light(u32),
    /// Where a camera subpath left the scene: the environment in direction `p − previous`.
    Infinite,
    Surface,
    /// A scattering event in a medium.
    Medium,
}

#[derive(Clone)]
pub(super) struct Vertex<C: Color = Vec3> {
    pub(super) kind: Kind,
    pub(super) p: Vec3,
    /// Geometric normal (zero for points and infinity).
    pub(super) ng: Vec3,
    pub(super) si: Option<SurfaceInteraction>,
    pub(super) bsdf: Option<(Bsdf<C>, Frame)>,
    /// The phase function of a medium vertex.
    pub(super) phase: Phase,
    /// Towards the previous vertex of its subpath, in the BSDF's frame (surface vertices with
    /// a BSDF; in world space at a medium vertex): one side of every BSDF or phase query a
    /// connection makes here (sampling the walk on and the s = 1 strategy at a surface start
    /// from the incoming ray's `si.wo` instead).
    pub(super) to_prev: Vec3,
    /// The medium the subpath was in when it reached this vertex (a medium vertex's own; the
    /// camera's and a light's, the medium they sit in).
    pub(super) medium: Option<u32>,
    /// The subpath's density ratios p_c / p_hero over the colour channels up to here (free
    /// flights in media; 1 elsewhere).
    pub(super) ratio: C,
    /// Throughput from the subpath's start to here (its own estimate's factor).
    pub(super) beta: C,
    /// The free-flight factor of the segment from the previous vertex of its subpath to
    /// this one in the MIS densities: e^{−σt·d} in the hero channel over the homogeneous
    /// media it crosses (1 without media, or where `Bdpt::flight_densities` is off). The
    /// segment's both densities carry it (symmetric).
    pub(super) seg: f32,
    /// `seg` in every lane relative to the hero's: e^{−(σt,c − σt,hero)·d} (1 without media).
    pub(super) seg_lanes: C,
    /// σt in the hero channel at a medium vertex whose flight density enters the MIS
    /// densities (1 at every other vertex): with `seg`, a free flight's density σt·e^{−σt·d}
    /// per unit length, a surface reached through a medium e^{−σt·d}.
    pub(super) sigma: f32,
    /// Emission towards the previous vertex of a camera subpath (emitters it reached); at a
    /// medium vertex, the collision estimate of the medium's emission there, the
    /// throughput before the collision included.
    pub(super) le: C,
    /// Spectral mode: the subpath's secondary wavelengths were terminated here or before (a
    /// dispersive smooth interface); a strategy that uses this vertex counts the hero only.
    pub(super) terminated: bool,
    pub(super) delta: bool,
    /// A vertex at infinity (the environment, or a light subpath's origin on an infinite
    /// light): densities towards it stay per unit solid angle.
    pub(super) at_infinity: bool,
    pub(super) pdf_fwd: f32,
    pub(super) pdf_rev: f32,
}

impl<C: Color> Vertex<C> {
    pub(super) fn new(kind: Kind, p: Vec3, beta: C) -> Vertex<C> {
        Vertex {
            kind,
            p,
            ng: Vec3::ZERO,
            si: None,
            bsdf: None,
            phase: Phase::Isotropic,
            to_prev: Vec3::ZERO,
            medium: None,
            ratio: C::ONE,
            beta,
            seg: 1.0,
            seg_lanes: C::ONE,
            sigma: 1.0,
            le: C::ZERO,
            terminated: false,
            delta: false,
            at_infinity: kind == Kind::Infinite,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        }
    }

    pub(super) fn on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// The unit direction to `other` in this vertex's BSDF frame (in world space at a
    /// medium vertex; zero without a BSDF).
    pub(super) fn towards(&self, other: &Vertex<C>) -> Vec3 {
        match (&self.bsdf, self.kind) {
            (_, Kind::Medium) => (other.p - self.p).normalize_or_zero(),
            (Some((_, frame)), _) => local_dir(frame, self.p, other.p),
            (None, _) => Vec3::ZERO,
        }
    }

    /// Whether a connection can end here (no delta lobe only).
    pub(super) fn connectible(&self) -> bool {
        match self.kind {
            Kind::Camera => true,
            Kind::Infinite => true,
            Kind::Light(_) => true,
            Kind::Medium => true,
            Kind::Surface => self.bsdf.as_ref().is_some_and(|(b, _)| b.has_smooth()),
        }
    }
}

/// The two ends of a strategy's connection: the camera subpath's (`pt`; for t = 1 the lens
/// point sampled) and the light subpath's (`qs`: none for s = 0; for s = 1 the light point
/// sampled), with the unit direction from each end to the other in the end's BSDF frame
/// (zero at an end without a BSDF), which f·|cos| and the MIS weight share.
pub struct Joint<'a, C: Color = Vec3> {
    pub(super) pt: &'a Vertex<C>,
    pub(super) qs: Option<&'a Vertex<C>>,
    pub(super) pt_to_qs: Vec3,
    pub(super) qs_to_pt: Vec3,
    /// The connection segment's free-flight factor (as a vertex's `seg`).
    pub(super) seg: f32,
    /// `seg` in every lane relative to the hero's (as a vertex's `seg_lanes`).
    pub(super) seg_lanes: C,
}

impl<'a, C: Color> Joint<'a, C> {
    pub(super) fn new(pt: &'a Vertex<C>, qs: Option<&'a Vertex<C>>) -> Joint<'a, C> {
        let (pt_to_qs, qs_to_pt) = match qs {
            Some(q) => (pt.towards(q), q.towards(pt)),
            None => (Vec3::ZERO, Vec3::ZERO),
        };
        Joint {
            pt,
            qs,
            pt_to_qs,
            qs_to_pt,
            seg: 1.0,
            seg_lanes: C::ONE,
        }
    }
}

/// Where a random walk goes on from a surface vertex (`walk.rs`).
pub(super) struct Scattered<C> {
    /// The sampled direction (world).
    pub(super) wi: Vec3,
    /// The throughput after the vertex (Russian roulette's survival included).
    pub(super) beta: C,
    /// The walk's product of relative indices after the vertex (Russian roulette).
    pub(super) eta: f32,
    /// Solid-angle density of `wi` (1 for a delta lobe: the discrete measure).
    pub(super) pdf_dir: f32,
    /// Solid-angle density of sampling `wo` from `wi`, the reverse way (1 for a delta lobe).
    pub(super) pdf_rev: f32,
    pub(super) delta: bool,
}

/// The vertices of one camera sample's two subpaths, kept from sample to sample so that
/// their storage is allocated once (per row of a pass, per Markov chain).
pub struct Subpaths<C: Color = Vec3> {
    pub(super) camera: Vec<Vertex<C>>,
    pub(super) light: Vec<Vertex<C>>,
}

impl<C: Color> Default for Subpaths<C> {
    fn default() -> Self {
        Subpaths {
            camera: Vec::new(),
            light: Vec::new(),
        }
    }
}

impl<C: Color> Subpaths<C> {
    /// Both subpaths emptied, their storage kept.
    pub(super) fn cleared(&mut self) -> (&mut Vec<Vertex<C>>, &mut Vec<Vertex<C>>) {
        self.camera.clear();
        self.light.clear();
        (&mut self.camera, &mut self.light)
    }
}

/// The light a vertex stands for (its own, an emitter surface's, or the environment).
#[derive(Clone, Copy)]
pub(super) enum LightRef {
    One(u32),
    Environment,
}

/// Area density of `pdf` (per unit solid angle at `from`) at `to`.
pub(super) fn convert_density<C: Color>(pdf: f32, from: &Vertex<C>, to: &Vertex<C>) -> f32 {
    if to.at_infinity {
        return pdf;
    }
    let w = to.p - from.p;
    let d2 = w.length_squared();
    if d2 == 0.0 {
        return 0.0;
    }
    let mut pdf = pdf / d2;
    if to.on_surface() {
        pdf *= to.ng.dot(w / d2.sqrt()).abs();
    }
    pdf
}

/// The unit direction from `from` to `to` in `frame`.
pub(super) fn local_dir(frame: &Frame, from: Vec3, to: Vec3) -> Vec3 {
    frame.to_local((to - from).normalize_or_zero())
}

pub(super) fn remap0(x: f32) -> f32 {
    if x != 0.0 { x } else { 1.0 }
}

impl<M: PathMode> Bdpt<'_, M> {
    pub(super) fn light_of(&self, scene: &Scene, v: &Vertex<M::C>) -> Option<LightRef> {
        match v.kind {
            Kind::Light(l) => Some(if scene.lights[l as usize].is_infinite() {
                LightRef::Environment
            } else {
                LightRef::One(l)
            }),
            Kind::Infinite => Some(LightRef::Environment),
            Kind::Surface => {
                v.si.as_ref()
                    .and_then(|si| scene.shape_light(si))
                    .map(LightRef::One)
            }
            Kind::Camera | Kind::Medium => None,
        }
    }

    /// Density of the light choice and of the origin `v` of a light subpath towards `next`
    /// (pbrt's `PdfLightOrigin`): per unit area, or for the environment per unit solid
    /// angle of the direction (summed over the infinite lights).
    pub(super) fn pdf_light_origin(
        &self,
        scene: &Scene,
        v: &Vertex<M::C>,
        next: &Vertex<M::C>,
    ) -> f32 {
        let w = (next.p - v.p).normalize_or_zero();
        match self.light_of(scene, v) {
            Some(LightRef::One(l)) => {
                let (pos, _) = scene.lights[l as usize].pdf_le(scene, v.p, v.ng, w);
                self.dist.pmf(l as usize) * pos
            }
            Some(LightRef::Environment) => {
                // `w` is the direction light leaves along, away from the environment.
                let d = w;
                scene
                    .infinite_lights
                    .iter()
                    .map(|&i| {
                        let (_, dir) = scene.lights[i as usize].pdf_le(scene, v.p, v.ng, d);
                        self.dist.pmf(i as usize) * dir
                    })
                    .sum()
            }
            None => 0.0,
        }
    }

    /// Area density at `next` of a light subpath leaving the emitter vertex `v` towards it
    /// (pbrt's `PdfLight`).
    pub(super) fn pdf_light(&self, scene: &Scene, v: &Vertex<M::C>, next: &Vertex<M::C>) -> f32 {
        let w = next.p - v.p;
        let d2 = w.length_squared();
        if d2 == 0.0 {
            return 0.0;
        }
        let w = w / d2.sqrt();
        let mut pdf = match self.light_of(scene, v) {
            Some(LightRef::One(l)) => scene.lights[l as usize].pdf_le(scene, v.p, v.ng, w).1 / d2,
            // The density on the disk the environment's rays start from.
            Some(LightRef::Environment) => crate::lights::infinite_disk_pdf(scene),
            None => 0.0,
        };
        if next.on_surface() {
            pdf *= next.ng.dot(w).abs();
        }
        pdf
    }

    /// Area density with which vertex `v` samples `next`: as a light subpath's origin, as the
    /// camera, or by its BSDF having been reached from the previous vertex of its subpath
    /// (`dir` the unit direction to `next` in the BSDF's frame, read only there).
    pub(super) fn pdf(
        &self,
        scene: &Scene,
        v: &Vertex<M::C>,
        next: &Vertex<M::C>,
        dir: Vec3,
    ) -> f32 {
        match v.kind {
            Kind::Light(_) | Kind::Infinite => self.pdf_light(scene, v, next),
            Kind::Camera => {
                let w = (next.p - v.p).normalize_or_zero();
                let (_, dir) = scene.camera.pdf_we(w);
                convert_density(dir, v, next)
            }
            Kind::Surface => match &v.bsdf {
                Some((bsdf, _)) => convert_density(bsdf.pdf(v.to_prev, dir), v, next),
                None => 0.0,
            },
            Kind::Medium => convert_density(v.phase.eval(v.to_prev, dir), v, next),
        }
    }

    /// Area density with which surface or medium vertex `v`, reached instead from the unit
    /// direction `from` (in its BSDF's frame; world space in a medium), samples the previous
    /// vertex of its subpath, `prev`.
    pub(super) fn pdf_back(v: &Vertex<M::C>, from: Vec3, prev: &Vertex<M::C>) -> f32 {
        match (&v.bsdf, v.kind) {
            (_, Kind::Medium) => convert_density(v.phase.eval(from, v.to_prev), v, prev),
            (Some((bsdf, _)), _) => convert_density(bsdf.pdf(from, v.to_prev), v, prev),
            (None, _) => 0.0,
        }
    }

    /// f·|cos| at surface vertex `v` (reached from the previous vertex of its subpath)
    /// towards the unit direction `wi` in its BSDF's frame, in `mode`; at a medium vertex
    /// the phase function towards `wi` in world space.
    pub(super) fn fcos(v: &Vertex<M::C>, wi: Vec3, mode: TransportMode) -> M::C {
        match (&v.bsdf, v.kind) {
            (_, Kind::Medium) => M::C::splat(v.phase.eval(v.to_prev, wi)),
            (Some((bsdf, _)), _) => bsdf.eval(v.to_prev, wi, mode),
            (None, _) => M::C::ZERO,
        }
    }
}

/// One camera sample's colour modes: its wavelengths as drawn (RGB mode: nothing), and with
/// the secondaries terminated.
pub(super) struct Modes<M> {
    pub(super) full: M,
    pub(super) terminated: M,
}

impl<M> Modes<M> {
    /// The mode of a strategy whose vertices were reached after a termination or not.
    #[inline(always)]
    pub(super) fn of(&self, terminated: bool) -> &M {
        if terminated {
            &self.terminated
        } else {
            &self.full
        }
    }
}
