//! Bidirectional path tracing (Veach 1997, with pbrt-v4's structure): per camera sample a
//! camera subpath and a light subpath, and every connection strategy (s light vertices,
//! t camera vertices) weighted by the power heuristic over all strategies that could have
//! made the same path, from the forward and reverse densities of each vertex (area measure).
//!
//! - s = 0: the camera subpath reaches an emitter (or leaves the scene) by itself;
//! - s = 1: a light point sampled for the camera vertex (`Light::sample_li`);
//! - t = 1: a light subpath vertex connected to the camera (`Camera::sample_wi`), splatted
//!   into the film's splat layer (see `film::accum`), merged in tile order;
//! - s, t ≥ 2: the two subpaths' end vertices joined by a shadow ray.
//!
//! (s, t) = (1, 1) is left out, as in pbrt: a light point seen straight by the lens is the
//! s = 0 strategy's. `max_depth` bounds the edges of every path (camera to light), as the
//! path tracer's does. Each subpath goes on by Russian roulette once it has 5 vertices (its
//! survival probability divides its throughput; the MIS densities leave it out).
//!
//! The densities: `pdf_fwd` of a vertex is the density, per unit area (per unit solid angle
//! for a vertex at infinity), with which its own subpath sampled it; `pdf_rev` the density
//! with which the other subpath would have. A vertex's reverse density needs its successor,
//! so it is set one step late; a connection overrides the four around the joint. Light
//! subpaths choose their light by power; the light sampled for s = 1 and the density of an
//! emitter reached by a camera subpath use the same choice. A direction sampled from a
//! delta lobe has density 1 in the discrete measure, both ways (Veach's thesis, ch. 10;
//! Mitsuba 0.6), so the next vertex's area density keeps its cos/d² factor. pbrt stores 0 there and
//! reads it as 1, dropping the factor: weights that depend on the scene's scale. On
//! `cbox-specular` the discrete measure cut BDPT's relMSE at 64 spp 2.5×, on
//! `media-homogeneous` (media in a glass cube) 1.5×, and took away a heavy tail there.
//!
//! Participating media: free flights sampled along both subpaths (`Medium::sample_in`, with
//! a hero channel drawn per camera sample and shared by both subpaths) make medium vertices,
//! which scatter by their phase function and connect like surface vertices; every
//! connection carries the transmittance of its segment (through null surfaces and media,
//! `volpath::transmittance`). Each strategy's estimate carries the spectral-MIS weight over
//! the hero choice of the vertices it uses (`hero_weight` of the product of both prefixes'
//! density ratios), as `volpath`'s paths do. When every medium is homogeneous the MIS
//! densities carry the free flights' densities in the hero channel (σt·e^{−σt·d} per unit
//! length to a medium vertex, e^{−σt·d} to a surface reached through a medium; Mitsuba
//! 0.6's BDPT does the same): a connection's segment gets the same factor from its exact
//! transmittance. With grids, whose transmittance is only estimated, they are left out
//! (pbrt-v3's choice). Either way the weights are one function of the path for every
//! strategy, so they sum to one. (On `media-homogeneous` the densities lowered BDPT's
//! relMSE at 64 spp by 3 %, on `media-fog` by 4.5 %.) An emitting medium's light is
//! found by the camera subpath's collision estimator (`volpath`'s default), the one strategy
//! that samples it: no light subpath starts in a volume, so its MIS weight is 1.
//!
//! `li` tells a `StrategySink` of every strategy it evaluates (its joint, weight and
//! value); plain rendering's, `()`, compiles away. Two sinks use it: the per-strategy
//! images (pbrt-v4's `visualizestrategies` / `visualizeweights`; [`render`] keeps one film
//! per (s, t) when asked), and [`Bdpt::record`] (`bdpt/record.rs`, for `debug-paths`),
//! which also keeps both subpaths.
//!
//! Colour: [`Bdpt`] is generic over the [`PathMode`] (RGB or spectral; `render` picks the
//! scene's). In spectral mode the camera sample draws its wavelengths (after the camera's
//! dimensions) and both subpaths carry them. A smooth dispersive interface terminates the
//! secondary wavelengths of its own subpath only (each subpath walks with its own copy of the
//! mode); a vertex records whether its subpath was terminated by then, and a strategy counts
//! the hero wavelength alone exactly when a vertex it uses was: every strategy that makes a
//! path through such an interface has that interface's vertex on one of its subpaths (a
//! delta vertex is never a connection's end), so all of them count the same wavelengths.
//! (Terminating for the whole camera sample instead, as one shared mode would, makes the
//! choice depend on the other subpath, which in chromatic media depends on the hero
//! wavelength; counting every wavelength after a termination smears a prism's spectrum.)
//! One case is left: a path through both a smooth and a rough dispersive interface, whose
//! rough vertex's density is the mixture over the wavelengths on one subpath and the hero's on
//! the other, so the weights of its strategies need not sum to one. Strategies are converted
//! to linear sRGB one by one (`PathMode::to_rgb`), so the sinks, splats and MLT see RGB.

use std::collections::BTreeMap;
use std::time::Instant;

use rayon::prelude::*;

use crate::bsdf::{Bsdf, TransportMode};
use crate::camera::CameraRay;
use crate::film::Film;
use crate::geometry::Ray;
use crate::lights::{LightSample, Receiver, ShadowTarget};
use crate::math::UVec2;
use crate::math::{Frame, Vec2, Vec3};
use crate::media::{Flight, MediumKind, Phase};
use crate::sampling::{Distribution1D, Sampler, Samples};
use crate::session::{RenderObserver, RenderOptions, RenderOutcome, camera_sample, run_passes};
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode, RgbMode, SpectralMode};
use crate::world::Scene;
use base::{RenderMode, TransmittanceEstimator};
use std::marker::PhantomData;

use super::transport::{Connection, From, transmittance};

mod record;
pub use record::{BdptConnection, BdptSample, BdptVertex, BdptVertexKind};

/// The parameters of [`Bdpt`].
#[derive(Clone, Debug, PartialEq)]
pub struct BdptConfig {
    /// Longest path in edges, camera to light (−1: unbounded).
    pub max_depth: i32,
    /// Shortest path in edges that [`Bdpt::li`] makes strategies for (0: every path): MLT's
    /// Kelemen chains leave paths of one and two edges to a BDPT render of their own
    /// (Mitsuba 0.6's `directSamples`).
    pub min_edges: u32,
    /// Also render one image per strategy (pbrt-v4's `visualizestrategies` /
    /// `visualizeweights`); needs a finite `max_depth`.
    pub strategy_images: Option<StrategyImages>,
}

impl Default for BdptConfig {
    fn default() -> Self {
        BdptConfig {
            max_depth: -1,
            min_edges: 0,
            strategy_images: None,
        }
    }
}

/// What the per-strategy images hold (pbrt-v4's two options).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrategyImages {
    /// Each strategy's own estimate, without its MIS weight (`visualizestrategies`): the
    /// images of one path depth each converge to the whole image of that depth where the
    /// strategy can sample every path, and show where it cannot.
    Unweighted,
    /// The MIS-weighted contributions (`visualizeweights`): they sum to the image.
    Weighted,
}

impl StrategyImages {
    /// The image name of strategy (s, t), pbrt-v4's: `bdpt_dDD_sSS_tTT`, the depth DD
    /// counting bounces (s + t − 2).
    pub fn name(s: usize, t: usize) -> String {
        format!("bdpt_d{:02}_s{s:02}_t{t:02}", s + t - 2)
    }

    /// The strategies of paths of at most `max_depth` edges: (s, t) with t ≥ 1, s + t ≥ 2,
    /// s + t − 1 ≤ max_depth, (1, 1) left out.
    pub fn strategies(max_depth: u32) -> impl Iterator<Item = (usize, usize)> {
        (2..=max_depth as usize + 1).flat_map(|n| {
            (0..n)
                .map(move |s| (s, n - s))
                .filter(|&(s, t)| !(s == 1 && t == 1))
        })
    }
}

/// Told of the strategies [`Bdpt::li`] evaluates (the per-strategy images, `debug-paths`'
/// record); `()` is told nothing, and its calls compile away.
pub(crate) trait StrategySink<C: Color> {
    /// Strategy (s, t) is joined at `joint` (for s = 1 the light point and for t = 1 the
    /// lens point sampled) with MIS weight `w`; its value follows through `add` if nonzero.
    #[inline(always)]
    fn joint(&mut self, _s: usize, _t: usize, _joint: &Joint<C>, _w: f32) {}

    /// Strategy (s, t) made the nonzero MIS-weighted `value` (linear sRGB) with weight
    /// `weight`, splatted at `splat_at` (t = 1; `None`: at the camera sample's film position).
    #[inline(always)]
    fn add(&mut self, _s: usize, _t: usize, _splat_at: Option<Vec2>, _value: Vec3, _weight: f32) {}
}

impl<C: Color> StrategySink<C> for () {}

/// What a strategy that makes nothing returns.
const NONE: (Vec3, f32) = (Vec3::ZERO, 0.0);

/// Subpath vertices that start Russian roulette.
const RR_FROM: usize = 5;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
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
struct Vertex<C: Color = Vec3> {
    kind: Kind,
    p: Vec3,
    /// Geometric normal (zero for points and infinity).
    ng: Vec3,
    si: Option<SurfaceInteraction>,
    bsdf: Option<(Bsdf<C>, Frame)>,
    /// The phase function of a medium vertex.
    phase: Phase,
    /// Towards the previous vertex of its subpath, in the BSDF's frame (surface vertices with
    /// a BSDF; in world space at a medium vertex): one side of every BSDF or phase query a
    /// connection makes here (sampling the walk on and the s = 1 strategy at a surface start
    /// from the incoming ray's `si.wo` instead).
    to_prev: Vec3,
    /// The medium the subpath was in when it reached this vertex (a medium vertex's own; the
    /// camera's and a light's, the medium they sit in).
    medium: Option<u32>,
    /// The subpath's density ratios p_c / p_hero over the colour channels up to here (free
    /// flights in media; 1 elsewhere).
    ratio: C,
    /// Throughput from the subpath's start to here (its own estimate's factor).
    beta: C,
    /// The free-flight factor of the segment from the previous vertex of its subpath to
    /// this one in the MIS densities: e^{−σt·d} in the hero channel over the homogeneous
    /// media it crosses (1 without media, or where `Bdpt::flight_densities` is off). The
    /// segment's both densities carry it (symmetric).
    seg: f32,
    /// σt in the hero channel at a medium vertex whose flight density enters the MIS
    /// densities (1 at every other vertex): with `seg`, a free flight's density σt·e^{−σt·d}
    /// per unit length, a surface reached through a medium e^{−σt·d}.
    sigma: f32,
    /// Emission towards the previous vertex of a camera subpath (emitters it reached); at a
    /// medium vertex, the collision estimate of the medium's emission there, the
    /// throughput before the collision included.
    le: C,
    /// Spectral mode: the subpath's secondary wavelengths were terminated here or before (a
    /// dispersive smooth interface); a strategy that uses this vertex counts the hero only.
    terminated: bool,
    delta: bool,
    /// A vertex at infinity (the environment, or a light subpath's origin on an infinite
    /// light): densities towards it stay per unit solid angle.
    at_infinity: bool,
    pdf_fwd: f32,
    pdf_rev: f32,
}

impl<C: Color> Vertex<C> {
    fn new(kind: Kind, p: Vec3, beta: C) -> Vertex<C> {
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
            sigma: 1.0,
            le: C::ZERO,
            terminated: false,
            delta: false,
            at_infinity: kind == Kind::Infinite,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        }
    }

    fn on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// The unit direction to `other` in this vertex's BSDF frame (in world space at a
    /// medium vertex; zero without a BSDF).
    fn towards(&self, other: &Vertex<C>) -> Vec3 {
        match (&self.bsdf, self.kind) {
            (_, Kind::Medium) => (other.p - self.p).normalize_or_zero(),
            (Some((_, frame)), _) => local_dir(frame, self.p, other.p),
            (None, _) => Vec3::ZERO,
        }
    }

    /// Whether a connection can end here (no delta lobe only).
    fn connectible(&self) -> bool {
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
pub(crate) struct Joint<'a, C: Color = Vec3> {
    pt: &'a Vertex<C>,
    qs: Option<&'a Vertex<C>>,
    pt_to_qs: Vec3,
    qs_to_pt: Vec3,
    /// The connection segment's free-flight factor (as a vertex's `seg`).
    seg: f32,
}

impl<'a, C: Color> Joint<'a, C> {
    fn new(pt: &'a Vertex<C>, qs: Option<&'a Vertex<C>>) -> Joint<'a, C> {
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
        }
    }
}

/// Where a random walk goes on from a surface vertex ([`Bdpt::scatter`]).
struct Scattered<C> {
    /// The sampled direction (world).
    wi: Vec3,
    /// The throughput after the vertex (Russian roulette's survival included).
    beta: C,
    /// The walk's η² factor after the vertex (see [`Bdpt::roulette`]).
    eta2: f32,
    /// Solid-angle density of `wi` (1 for a delta lobe: the discrete measure).
    pdf_dir: f32,
    /// Solid-angle density of sampling `wo` from `wi`, the reverse way (1 for a delta lobe).
    pdf_rev: f32,
    delta: bool,
}

/// The vertices of one camera sample's two subpaths, kept from sample to sample so that
/// their storage is allocated once (per row of a pass, per Markov chain).
pub struct Subpaths<C: Color = Vec3> {
    camera: Vec<Vertex<C>>,
    light: Vec<Vertex<C>>,
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
    fn cleared(&mut self) -> (&mut Vec<Vertex<C>>, &mut Vec<Vertex<C>>) {
        self.camera.clear();
        self.light.clear();
        (&mut self.camera, &mut self.light)
    }
}

/// The light a vertex stands for (its own, an emitter surface's, or the environment).
#[derive(Clone, Copy)]
enum LightRef {
    One(u32),
    Environment,
}

/// Bidirectional path tracer state shared by all samples, for paths in colour mode `M`.
pub struct Bdpt<'a, M: PathMode = RgbMode> {
    cfg: &'a BdptConfig,
    /// Lights chosen by power.
    dist: Distribution1D,
    any: bool,
    /// The free-flight densities enter the MIS weights (`Vertex::seg`, `Vertex::sigma`):
    /// when every medium is homogeneous, whose transmittance is exact, so that a
    /// connection's segment gets the same factor as a sampled one. With grids the weights
    /// leave them out (pbrt-v3's choice): either way one function of the path for every
    /// strategy.
    flight_densities: bool,
    mode: PhantomData<fn() -> M>,
}

/// Area density of `pdf` (per unit solid angle at `from`) at `to`.
fn convert_density<C: Color>(pdf: f32, from: &Vertex<C>, to: &Vertex<C>) -> f32 {
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
fn local_dir(frame: &Frame, from: Vec3, to: Vec3) -> Vec3 {
    frame.to_local((to - from).normalize_or_zero())
}

fn remap0(x: f32) -> f32 {
    if x != 0.0 { x } else { 1.0 }
}

impl<'a, M: PathMode> Bdpt<'a, M> {
    pub fn new(scene: &Scene, cfg: &'a BdptConfig) -> Bdpt<'a, M> {
        let powers: Vec<f32> = scene.lights.iter().map(|l| l.power(scene)).collect();
        Bdpt {
            cfg,
            any: powers.iter().any(|&p| p > 0.0),
            dist: Distribution1D::new(&powers),
            flight_densities: !scene.media.is_empty()
                && scene
                    .media
                    .iter()
                    .all(|m| matches!(m.kind, MediumKind::Homogeneous(_))),
            mode: PhantomData,
        }
    }

    /// σt of medium `medium` in lane `hero` of `m` if the free-flight densities enter the MIS
    /// weights (else, and outside media, `None`).
    fn flight_sigma(&self, scene: &Scene, medium: Option<u32>, hero: usize, m: &M) -> Option<f32> {
        match medium.map(|i| &scene.media[i as usize].kind) {
            Some(MediumKind::Homogeneous(h)) if self.flight_densities => {
                Some(m.unbounded(h.sigma_t).lane(hero))
            }
            _ => None,
        }
    }

    /// Whether paths of `edges` edges are within `min_edges..=max_depth`.
    fn allows(&self, edges: usize) -> bool {
        edges >= self.cfg.min_edges as usize
            && (self.cfg.max_depth < 0 || edges <= self.cfg.max_depth as usize)
    }

    fn light_of(&self, scene: &Scene, v: &Vertex<M::C>) -> Option<LightRef> {
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
    fn pdf_light_origin(&self, scene: &Scene, v: &Vertex<M::C>, next: &Vertex<M::C>) -> f32 {
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
    fn pdf_light(&self, scene: &Scene, v: &Vertex<M::C>, next: &Vertex<M::C>) -> f32 {
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
    fn pdf(&self, scene: &Scene, v: &Vertex<M::C>, next: &Vertex<M::C>, dir: Vec3) -> f32 {
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
    fn pdf_back(v: &Vertex<M::C>, from: Vec3, prev: &Vertex<M::C>) -> f32 {
        match (&v.bsdf, v.kind) {
            (_, Kind::Medium) => convert_density(v.phase.eval(from, v.to_prev), v, prev),
            (Some((bsdf, _)), _) => convert_density(bsdf.pdf(from, v.to_prev), v, prev),
            (None, _) => 0.0,
        }
    }

    /// f·|cos| at surface vertex `v` (reached from the previous vertex of its subpath)
    /// towards the unit direction `wi` in its BSDF's frame, in `mode`; at a medium vertex
    /// the phase function towards `wi` in world space.
    fn fcos(v: &Vertex<M::C>, wi: Vec3, mode: TransportMode) -> M::C {
        match (&v.bsdf, v.kind) {
            (_, Kind::Medium) => M::C::splat(v.phase.eval(v.to_prev, wi)),
            (Some((bsdf, _)), _) => bsdf.eval(v.to_prev, wi, mode),
            (None, _) => M::C::ZERO,
        }
    }

    /// Extend `path` from `ray` (its last vertex the start), `beta` its throughput,
    /// `pdf_dir` the solid-angle density of `ray`'s direction and `medium` the medium it
    /// starts in, up to `max_vertices`; free flights in media sample with lane `hero` of
    /// `m`, the subpath's colour mode.
    #[allow(clippy::too_many_arguments)]
    fn random_walk(
        &self,
        scene: &Scene,
        mut ray: Ray,
        mut t_max: f32,
        mut beta: M::C,
        mut pdf_dir: f32,
        mut medium: Option<u32>,
        hero: usize,
        sampler: &mut impl Samples,
        mode: TransportMode,
        max_vertices: usize,
        path: &mut Vec<Vertex<M::C>>,
        m: &M,
    ) {
        let mut ratio = M::C::ONE;
        // The free-flight factor since the last vertex.
        let mut seg = 1.0f32;
        // Russian roulette's η² factor (`Self::roulette`).
        let mut eta2 = 1.0f32;
        // Bounded: null crossings add no vertex.
        for _ in 0..(1 << 16) {
            if path.len() >= max_vertices {
                return;
            }
            let closest = scene.closest(&ray, t_max);
            if let Some(mi) = medium {
                let med = &scene.media[mi as usize];
                let d_surface = closest.t(&ray, t_max);
                let sigma = self.flight_sigma(scene, medium, hero, m);
                match med.sample_in(&ray, d_surface, hero, sampler, m) {
                    Flight::Scatter {
                        d,
                        weight,
                        ratio: r,
                        emit,
                    } => {
                        // An emitting medium's light, by the collision estimator (as
                        // `volpath`'s), with the throughput before the collision.
                        let emitted = match &med.emission {
                            Some(e) if mode == TransportMode::Radiance => {
                                beta * emit * e.radiance_in(ray.at(d), m)
                            }
                            _ => M::C::ZERO,
                        };
                        beta *= weight;
                        ratio *= r;
                        let prev = path.last().expect("a subpath has a start");
                        let mut v = Vertex::new(Kind::Medium, ray.at(d), beta);
                        v.medium = medium;
                        v.ratio = ratio;
                        v.phase = med.phase;
                        v.le = emitted;
                        v.terminated = m.terminated();
                        v.to_prev = -ray.d;
                        if let Some(s) = sigma {
                            v.seg = seg * (-s * d).exp();
                            v.sigma = s;
                        }
                        v.pdf_fwd = convert_density(pdf_dir, prev, &v) * v.seg * v.sigma;
                        let n = path.len() + 1;
                        let rr = (n, eta2);
                        let Some(sc) = Self::scatter_medium(&v, rr, max_vertices, sampler, m)
                        else {
                            path.push(v);
                            return;
                        };
                        // The phase function is symmetric: the reverse density is the same.
                        path[n - 2].pdf_rev =
                            convert_density(sc.pdf_rev, &v, prev) * v.seg * prev.sigma;
                        seg = 1.0;
                        ray = Ray::at_time(v.p, sc.wi, ray.time);
                        t_max = f32::INFINITY;
                        beta = sc.beta;
                        eta2 = sc.eta2;
                        pdf_dir = sc.pdf_dir;
                        path.push(v);
                        continue;
                    }
                    Flight::Pass { weight, ratio: r } => {
                        beta *= weight;
                        ratio *= r;
                        if let Some(s) = sigma {
                            seg *= (-s * d_surface).exp();
                        }
                    }
                }
            }
            let Some(si) = closest.surface(scene, &ray, t_max) else {
                if mode == TransportMode::Radiance {
                    let prev = path.last().expect("a subpath has a start");
                    let mut v = Vertex::new(Kind::Infinite, prev.p + ray.d, beta);
                    for &i in &scene.infinite_lights {
                        v.le += scene.lights[i as usize].environment(ray.d, m);
                    }
                    v.ratio = ratio;
                    v.terminated = m.terminated();
                    v.seg = seg;
                    v.pdf_fwd = pdf_dir * seg;
                    path.push(v);
                }
                return;
            };
            let bsdf = scene.bsdf_at_in(&si, m);
            if bsdf.is_none() && scene.is_null(&si) {
                medium = scene.medium_after(&si, ray.d, medium);
                ray = si.spawn_ray(ray.d);
                t_max = f32::INFINITY;
                continue;
            }
            let prev = path.last().expect("a subpath has a start");
            let mut v = Vertex::new(Kind::Surface, si.p, beta);
            v.ng = si.ng;
            v.medium = medium;
            v.ratio = ratio;
            v.terminated = m.terminated();
            if mode == TransportMode::Radiance
                && let Some(l) = scene.shape_light(&si)
            {
                v.le = scene.lights[l as usize].le(scene, &si, m);
            }
            v.seg = seg;
            v.pdf_fwd = convert_density(pdf_dir, prev, &v) * seg;
            // The walk goes on from here unless the path is full, the surface has no BSDF,
            // or sampling or Russian roulette ends it; sampled before the vertex is stored.
            let n = path.len() + 1;
            let scattered = bsdf.as_ref().and_then(|(bsdf, frame)| {
                v.to_prev = local_dir(frame, v.p, prev.p);
                if n >= max_vertices {
                    return None;
                }
                let rr = (n, eta2);
                Self::scatter(bsdf, frame, si.wo, beta, ratio, rr, sampler, mode, m)
            });
            let Some(sc) = scattered else {
                v.bsdf = bsdf;
                v.si = Some(si);
                path.push(v);
                return;
            };
            v.delta = sc.delta;
            // The reverse density of the previous vertex: from this one back to it.
            let rev = convert_density(sc.pdf_rev, &v, prev) * seg * prev.sigma;
            path[n - 2].pdf_rev = rev;
            seg = 1.0;
            medium = scene.medium_after(&si, sc.wi, medium);
            ray = si.spawn_ray(sc.wi);
            t_max = f32::INFINITY;
            beta = sc.beta;
            eta2 = sc.eta2;
            pdf_dir = sc.pdf_dir;
            v.bsdf = bsdf;
            v.si = Some(si);
            path.push(v);
        }
    }

    /// The direction a walk leaves a surface vertex in (its `n`th, `eta2` the walk's η²
    /// factor so far: `(n, eta2)`) by sampling its BSDF (`bsdf` in `frame`, `wo` the world
    /// direction back along the incoming ray), with the throughput `beta` and channel density
    /// ratios `ratio` so far; none if sampling fails, Russian roulette ends the path or the
    /// throughput is left zero or not finite.
    #[allow(clippy::too_many_arguments)]
    fn scatter(
        bsdf: &Bsdf<M::C>,
        frame: &Frame,
        wo: Vec3,
        mut beta: M::C,
        ratio: M::C,
        (n, mut eta2): (usize, f32),
        sampler: &mut impl Samples,
        mode: TransportMode,
        m: &M,
    ) -> Option<Scattered<M::C>> {
        let wo = frame.to_local(wo);
        let u1 = sampler.next_1d();
        let bs = bsdf.sample(wo, u1, sampler.next_2d(), mode)?;
        // A delta lobe's direction has probability 1 in the discrete measure both ways
        // (Veach's thesis, ch. 10; Mitsuba 0.6), so that the next vertex's area density
        // keeps its geometric factor (pbrt stores 0 and reads it as 1, which drops it).
        let (pdf_dir, pdf_rev) = if bs.delta {
            (1.0, 1.0)
        } else {
            (bs.pdf, bsdf.pdf(bs.wi, wo))
        };
        beta *= bs.weight;
        if mode == TransportMode::Radiance {
            eta2 *= bs.eta * bs.eta;
        }
        Some(Scattered {
            wi: frame.to_world(bs.wi),
            beta: Self::roulette(beta, ratio, eta2, n, sampler, m)?,
            eta2,
            pdf_dir,
            pdf_rev,
            delta: bs.delta,
        })
    }

    /// The direction a walk leaves medium vertex `v` (its `n`th, the walk's η² factor
    /// `eta2`) in, by sampling its phase function; none once the path is full or Russian
    /// roulette ends it.
    fn scatter_medium(
        v: &Vertex<M::C>,
        (n, eta2): (usize, f32),
        max_vertices: usize,
        sampler: &mut impl Samples,
        m: &M,
    ) -> Option<Scattered<M::C>> {
        if n >= max_vertices {
            return None;
        }
        let (wi, pdf) = v.phase.sample(v.to_prev, sampler.next_2d());
        Some(Scattered {
            wi,
            beta: Self::roulette(v.beta, v.ratio, eta2, n, sampler, m)?,
            eta2,
            pdf_dir: pdf,
            pdf_rev: pdf,
            delta: false,
        })
    }

    /// Russian roulette on the throughput `beta` leaving the `n`th vertex (by its effective
    /// value, β over the mean channel density ratio, in the lanes that still count, times
    /// `eta2`): the survivor's throughput, or none. A camera subpath's `eta2` is the product
    /// of η² over the interfaces it crossed (pbrt-v4's `etaScale`): radiance is scaled by
    /// 1/η² entering glass and back leaving it, so that inside a dense glass β alone would
    /// end most paths that leave it again (in `tinted-glass.xml`, whose SF11 sphere has
    /// η = 1.78, that made light found after several internal reflections a heavy tail).
    /// Light subpaths' importance has no such factor: 1.
    fn roulette(
        mut beta: M::C,
        ratio: M::C,
        eta2: f32,
        n: usize,
        sampler: &mut impl Samples,
        m: &M,
    ) -> Option<M::C> {
        if n >= RR_FROM {
            let q = (m.live_max(beta * m.hero_weight(ratio)) * eta2).min(0.95);
            if sampler.next_1d() >= q || q.is_nan() {
                return None;
            }
            beta /= q;
        }
        (!beta.is_black() && beta.is_finite()).then_some(beta)
    }

    /// The camera subpath of at most `max_vertices` vertices (the camera's included).
    #[allow(clippy::too_many_arguments)]
    fn camera_subpath(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        hero: usize,
        sampler: &mut impl Samples,
        max_vertices: usize,
        path: &mut Vec<Vertex<M::C>>,
        m: &M,
    ) {
        let mut v = Vertex::new(Kind::Camera, cray.lens, M::C::ONE);
        v.medium = scene.camera_medium;
        path.push(v);
        let (_, pdf_dir) = scene.camera.pdf_we(cray.ray.d.normalize());
        let len = cray.ray.d.length();
        let ray = Ray::at_time(cray.ray.o, cray.ray.d / len, cray.ray.time);
        self.random_walk(
            scene,
            ray,
            cray.t_max * len,
            M::C::ONE,
            pdf_dir,
            scene.camera_medium,
            hero,
            sampler,
            TransportMode::Radiance,
            max_vertices,
            path,
            m,
        );
    }

    /// The light subpath of at most `max_vertices` vertices (the light's included).
    fn light_subpath(
        &self,
        scene: &Scene,
        hero: usize,
        sampler: &mut impl Samples,
        max_vertices: usize,
        path: &mut Vec<Vertex<M::C>>,
        m: &M,
    ) {
        let (li, pmf, _) = self.dist.sample_discrete(sampler.next_1d());
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        if !self.any || pmf.is_nan() || pmf <= 0.0 || max_vertices == 0 {
            return;
        }
        let light = &scene.lights[li];
        let Some(e) = light.sample_le(scene, u_pos, u_dir, m) else {
            return;
        };
        if e.pdf_pos <= 0.0 || e.pdf_dir <= 0.0 {
            return;
        }
        let mut v = Vertex::new(Kind::Light(li as u32), e.p, M::C::ZERO);
        v.ng = e.n;
        v.medium = scene.light_media.get(li).copied().flatten();
        let infinite = light.is_infinite();
        v.at_infinity = infinite;
        v.pdf_fwd = if infinite {
            0.0 // set below, once the direction density of every infinite light is known
        } else {
            pmf * e.pdf_pos
        };
        let medium = v.medium;
        path.push(v);
        self.random_walk(
            scene,
            e.ray,
            f32::INFINITY,
            e.weight / pmf,
            e.pdf_dir,
            medium,
            hero,
            sampler,
            TransportMode::Importance,
            max_vertices,
            path,
            m,
        );
        if infinite {
            // pbrt: the first surface's density is the disk's, times its cosine; the
            // light vertex's that of the direction (every infinite light's).
            if path.len() > 1 {
                let next = &path[1];
                let mut pdf = e.pdf_pos;
                if next.on_surface() {
                    pdf *= next.ng.dot(e.ray.d).abs();
                }
                path[1].pdf_fwd = pdf * next.seg * next.sigma;
            }
            let (p, ng) = (path[0].p, path[0].ng);
            path[0].pdf_fwd = scene
                .infinite_lights
                .iter()
                .map(|&i| {
                    let (_, dir) = scene.lights[i as usize].pdf_le(scene, p, ng, e.ray.d);
                    self.dist.pmf(i as usize) * dir
                })
                .sum();
        }
    }

    /// One camera sample's colour mode (in spectral mode its wavelengths, drawn from the
    /// sampler after the camera's dimensions; RGB mode draws nothing) and the lane whose
    /// densities sample free flights in media along both subpaths (scenes without media draw
    /// nothing for it).
    fn start(scene: &Scene, sampler: &mut impl Samples) -> (Modes<M>, usize) {
        let m = M::start(sampler);
        let hero = if scene.media.is_empty() {
            0
        } else {
            m.hero(sampler.next_1d())
        };
        let terminated = m.terminate();
        (
            Modes {
                full: m,
                terminated,
            },
            hero,
        )
    }

    /// The radiance of one camera sample as a render adds it ([`Self::li`] telling no one),
    /// in linear sRGB; light-tracing contributions go to `splats`.
    pub fn estimate(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        sampler: &mut impl Samples,
        paths: &mut Subpaths<M::C>,
        splats: &mut Vec<(Vec2, Vec3)>,
    ) -> Vec3 {
        self.li(scene, cray, sampler, paths, splats, &mut ())
    }

    /// The radiance of one camera sample in linear sRGB (its subpaths built in `paths`);
    /// light-tracing contributions (t = 1) go to `splats` as (film position, value); `sink`
    /// is told of every strategy's. The camera subpath draws from the sampler's current
    /// stream, the light subpath from stream 1, the connections from stream 2
    /// ([`Samples::start_stream`]). In spectral mode both subpaths share the wavelengths and
    /// each terminates its own secondaries; a strategy counts the hero only if a vertex it
    /// uses was reached after a termination.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn li(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        sampler: &mut impl Samples,
        paths: &mut Subpaths<M::C>,
        splats: &mut Vec<(Vec2, Vec3)>,
        sink: &mut impl StrategySink<M::C>,
    ) -> Vec3 {
        let (cam, light) = paths.cleared();
        let (max_cam, max_light) = match self.cfg.max_depth {
            d if d < 0 => (usize::MAX, usize::MAX),
            d => (d as usize + 1, d as usize),
        };
        let (modes, hero) = Self::start(scene, sampler);
        let m = modes.full.clone();
        self.camera_subpath(scene, cray, hero, sampler, max_cam, cam, &m);
        sampler.start_stream(1);
        let m = modes.full.clone();
        self.light_subpath(scene, hero, sampler, max_light, light, &m);
        sampler.start_stream(2);
        let mut l = Vec3::ZERO;
        for t in 1..=cam.len() {
            for s in 0..=light.len() {
                let depth = s + t;
                if (s == 1 && t == 1) || depth < 2 || !self.allows(depth - 1) {
                    continue;
                }
                if t == 1 {
                    if let Some((p, c, w)) =
                        self.connect_camera(scene, cam, light, s, hero, &modes, sampler, sink)
                    {
                        splats.push((p, c));
                        if w > 0.0 && c != Vec3::ZERO {
                            sink.add(s, 1, Some(p), c, w);
                        }
                    }
                    continue;
                }
                let (c, w) = self.connect(scene, cam, light, s, t, hero, &modes, sampler, sink);
                if w > 0.0 && c != Vec3::ZERO {
                    sink.add(s, t, None, c, w);
                }
                l += c;
            }
        }
        l
    }

    /// One strategy's contribution for MLT: a camera subpath of exactly `t` vertices from
    /// `cray` (its randomness from the sampler's current stream), a light subpath of exactly
    /// `s` (from stream 1), joined with randomness from stream 2 (the subpaths built in
    /// `paths`); the film position (the camera ray's, or the light vertex's connection to
    /// the lens for t = 1) and the MIS-weighted value in linear sRGB.
    #[allow(clippy::too_many_arguments)]
    pub fn strategy(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        p_film: Vec2,
        s: usize,
        t: usize,
        sampler: &mut impl Samples,
        paths: &mut Subpaths<M::C>,
    ) -> Option<(Vec2, Vec3)> {
        let (cam, light) = paths.cleared();
        let (modes, hero) = Self::start(scene, sampler);
        let m = modes.full.clone();
        self.camera_subpath(scene, cray, hero, sampler, t, cam, &m);
        if cam.len() != t {
            return None;
        }
        sampler.start_stream(1);
        if s > 0 {
            let m = modes.full.clone();
            self.light_subpath(scene, hero, sampler, s, light, &m);
            if light.len() != s {
                return None;
            }
        }
        sampler.start_stream(2);
        if t == 1 {
            return self
                .connect_camera(scene, cam, light, s, hero, &modes, sampler, &mut ())
                .map(|(p, c, _)| (p, c));
        }
        let (c, _) = self.connect(scene, cam, light, s, t, hero, &modes, sampler, &mut ());
        Some((p_film, c))
    }

    /// Strategy (s, t ≥ 2): its MIS-weighted contribution in linear sRGB and the weight
    /// (zero, 0 when it makes none).
    #[allow(clippy::too_many_arguments)]
    fn connect(
        &self,
        scene: &Scene,
        cam: &[Vertex<M::C>],
        light: &[Vertex<M::C>],
        s: usize,
        t: usize,
        hero: usize,
        modes: &Modes<M>,
        sampler: &mut impl Samples,
        sink: &mut impl StrategySink<M::C>,
    ) -> (Vec3, f32) {
        let pt = &cam[t - 1];
        let m = modes.of(pt.terminated);
        if s == 0 {
            // The camera subpath reached an emitter.
            if pt.le.is_black() {
                return NONE;
            }
            if pt.kind == Kind::Medium {
                // A medium's emission: no light subpath starts in a volume and s = 1 samples
                // no volume point, so this is the one strategy that finds it (weight 1).
                sink.joint(s, t, &Joint::new(pt, None), 1.0);
                return (m.to_rgb(pt.le * m.hero_weight(pt.ratio)), 1.0);
            }
            let c = pt.beta * pt.le * m.hero_weight(pt.ratio);
            let joint = Joint::new(pt, None);
            let w = self.mis_weight(scene, cam, light, &joint, s, t);
            sink.joint(s, t, &joint, w);
            return (m.to_rgb(c * w), w);
        }
        if !pt.connectible() || !matches!(pt.kind, Kind::Surface | Kind::Medium) {
            return NONE;
        }
        if s == 1 {
            // A light point sampled for pt.
            let (li, pmf, _) = self.dist.sample_discrete(sampler.next_1d());
            let u = sampler.next_2d();
            if pmf <= 0.0 || !self.any {
                return NONE;
            }
            let light_ = &scene.lights[li];
            let receiver = match &pt.si {
                Some(si) => Receiver::from(si),
                None => Receiver::at(pt.p),
            };
            let Some(ls) = light_.sample_li(scene, &receiver, u, m) else {
                return NONE;
            };
            if ls.pdf <= 0.0 || ls.li.is_black() {
                return NONE;
            }
            let f = match (&pt.bsdf, &pt.si) {
                (Some((bsdf, frame)), Some(si)) if pt.kind == Kind::Surface => bsdf.eval(
                    frame.to_local(si.wo),
                    frame.to_local(ls.wi),
                    TransportMode::Radiance,
                ),
                _ => Self::fcos(pt, ls.wi, TransportMode::Radiance),
            };
            if f.is_black() {
                return NONE;
            }
            let tr = self.tr(scene, pt, &ls, sampler, m);
            if tr.is_black() {
                return NONE;
            }
            let mut sampled = match ls.target {
                ShadowTarget::Surface { p, n, .. } => {
                    let mut v = Vertex::new(Kind::Light(li as u32), p, M::C::ZERO);
                    v.ng = n;
                    v
                }
                ShadowTarget::Point(p) => Vertex::new(Kind::Light(li as u32), p, M::C::ZERO),
                ShadowTarget::Infinite => {
                    let mut v = Vertex::new(Kind::Light(li as u32), pt.p + ls.wi, M::C::ZERO);
                    v.at_infinity = true;
                    v
                }
            };
            sampled.pdf_fwd = self.pdf_light_origin(scene, &sampled, pt);
            let c = pt.beta * f * tr * ls.li / (ls.pdf * pmf) * m.hero_weight(pt.ratio);
            let mut joint = Joint::new(pt, Some(&sampled));
            joint.seg = self.connection_seg(tr, hero);
            let w = self.mis_weight(scene, cam, light, &joint, s, t);
            sink.joint(s, t, &joint, w);
            return (m.to_rgb(c * w), w);
        }
        let qs = &light[s - 1];
        if !qs.connectible() || !matches!(qs.kind, Kind::Surface | Kind::Medium) {
            return NONE;
        }
        let m = modes.of(pt.terminated || qs.terminated);
        let d = qs.p - pt.p;
        let d2 = d.length_squared();
        if d2 == 0.0 {
            return NONE;
        }
        let mut joint = Joint::new(pt, Some(qs));
        let fq = Self::fcos(qs, joint.qs_to_pt, TransportMode::Importance);
        let fp = Self::fcos(pt, joint.pt_to_qs, TransportMode::Radiance);
        let c = qs.beta * fq * fp * pt.beta / d2;
        if c.is_black() {
            return NONE;
        }
        let query = LightSample {
            wi: d / d2.sqrt(),
            li: M::C::ZERO,
            pdf: 1.0,
            delta: true,
            target: match &qs.si {
                Some(qsi) if qs.kind == Kind::Surface => ShadowTarget::Surface {
                    p: qsi.p,
                    p_error: qsi.p_error,
                    n: qsi.ng,
                },
                _ => ShadowTarget::Point(qs.p),
            },
        };
        let tr = self.tr(scene, pt, &query, sampler, m);
        if tr.is_black() {
            return NONE;
        }
        joint.seg = self.connection_seg(tr, hero);
        let hero = m.hero_weight(pt.ratio * qs.ratio);
        let w = self.mis_weight(scene, cam, light, &joint, s, t);
        sink.joint(s, t, &joint, w);
        (m.to_rgb(c * tr * (hero * w)), w)
    }

    /// Strategy t = 1: light vertex s − 1 seen by the lens; the film position, the
    /// MIS-weighted contribution in linear sRGB and the weight.
    #[allow(clippy::too_many_arguments)]
    fn connect_camera(
        &self,
        scene: &Scene,
        cam: &[Vertex<M::C>],
        light: &[Vertex<M::C>],
        s: usize,
        hero: usize,
        modes: &Modes<M>,
        sampler: &mut impl Samples,
        sink: &mut impl StrategySink<M::C>,
    ) -> Option<(Vec2, Vec3, f32)> {
        let qs = &light[s - 1];
        if !matches!(qs.kind, Kind::Surface | Kind::Medium) || !qs.connectible() {
            return None;
        }
        let m = modes.of(qs.terminated);
        let c = scene.camera.sample_wi(qs.p, sampler.next_2d())?;
        let lens_v = Vertex::new(Kind::Camera, c.p_lens, M::C::ONE);
        let mut joint = Joint::new(&lens_v, Some(qs));
        let f = Self::fcos(qs, joint.qs_to_pt, TransportMode::Importance);
        if f.is_black() {
            return None;
        }
        let query = LightSample {
            wi: c.wi,
            li: M::C::ZERO,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(c.p_lens),
        };
        let tr = self.tr(scene, qs, &query, sampler, m);
        if tr.is_black() {
            return None;
        }
        joint.seg = self.connection_seg(tr, hero);
        let value = qs.beta * f * tr * (c.weight * m.hero_weight(qs.ratio));
        let w = self.mis_weight(scene, cam, light, &joint, s, 1);
        sink.joint(s, 1, &joint, w);
        Some((c.p_film, m.to_rgb(value * w), w))
    }

    /// The transmittance from surface or medium vertex `v` to the query's target: 0 if a
    /// surface other than a null one lies between; through media an estimate
    /// (`volpath::transmittance`, whose random numbers come from `sampler`). Without media
    /// or null surfaces one occlusion query, made here as `transmittance` would make it.
    fn tr(
        &self,
        scene: &Scene,
        v: &Vertex<M::C>,
        query: &LightSample<M::C>,
        sampler: &mut impl Samples,
        m: &M,
    ) -> M::C {
        let from = match (&v.si, v.kind) {
            (Some(si), Kind::Surface) => {
                if !scene.has_nulls && scene.media.is_empty() {
                    let (ray, t_max) = query.target.ray_from(si, query.wi);
                    return if scene.occluded(&ray, t_max) {
                        M::C::ZERO
                    } else {
                        M::C::ONE
                    };
                }
                From::Surface(si)
            }
            _ => From::Medium(v.p, 0.0),
        };
        let c = Connection {
            from,
            wi: query.wi,
            target: query.target,
            medium: v.medium,
        };
        transmittance(scene, &c, TransmittanceEstimator::default(), sampler, m)
    }

    /// A connection's free-flight factor from its transmittance `tr` (exact where
    /// `flight_densities` holds: homogeneous media only).
    fn connection_seg(&self, tr: M::C, hero: usize) -> f32 {
        if self.flight_densities {
            tr.lane(hero)
        } else {
            1.0
        }
    }

    /// The power-heuristic weight of strategy (s, t), joined at `joint` (whose ends replace
    /// the vertices the strategy sampled afresh: the light point for s = 1, the lens point
    /// for t = 1).
    fn mis_weight(
        &self,
        scene: &Scene,
        cam: &[Vertex<M::C>],
        light: &[Vertex<M::C>],
        joint: &Joint<M::C>,
        s: usize,
        t: usize,
    ) -> f32 {
        if s + t == 2 {
            return 1.0;
        }
        let (pt, qs) = (joint.pt, joint.qs);
        let pt_minus = if t >= 2 { Some(&cam[t - 2]) } else { None };
        let qs_minus = if s >= 2 { Some(&light[s - 2]) } else { None };
        // The joint's reverse densities: pt's from qs (or, for s = 0, as a light subpath's
        // origin), and on from pt back along the camera subpath and from qs back along the
        // light subpath.
        // Each carries its segment's free-flight factor and the σt of the vertex it is at
        // (both 1 without media).
        let pt_rev = match qs {
            Some(q) => self.pdf(scene, q, pt, joint.qs_to_pt) * joint.seg * pt.sigma,
            None => self.pdf_light_origin(scene, pt, pt_minus.expect("t ≥ 2 when s = 0")),
        };
        let pt_minus_rev = pt_minus.map(|pm| {
            let pdf = match qs {
                Some(_) => Self::pdf_back(pt, joint.pt_to_qs, pm),
                None => self.pdf_light(scene, pt, pm),
            };
            pdf * pt.seg * pm.sigma
        });
        let qs_rev = qs.map(|q| self.pdf(scene, pt, q, joint.pt_to_qs) * joint.seg * q.sigma);
        let qs_minus_rev = qs
            .zip(qs_minus)
            .map(|(q, qm)| Self::pdf_back(q, joint.qs_to_pt, qm) * q.seg * qm.sigma);
        // (pdf_fwd, pdf_rev, delta) of each vertex with the joint's overrides; the endpoints
        // are connectible, so not delta.
        let cam_at = |i: usize| -> (f32, f32, bool) {
            if i == t - 1 {
                (pt.pdf_fwd, pt_rev, false)
            } else if i + 2 == t {
                let v = &cam[i];
                (v.pdf_fwd, pt_minus_rev.unwrap_or(v.pdf_rev), v.delta)
            } else {
                (cam[i].pdf_fwd, cam[i].pdf_rev, cam[i].delta)
            }
        };
        let light_at = |i: usize| -> (f32, f32, bool) {
            if i + 1 == s {
                let q = qs.expect("s > 0");
                (q.pdf_fwd, qs_rev.unwrap_or(q.pdf_rev), false)
            } else if i + 2 == s {
                let v = &light[i];
                (v.pdf_fwd, qs_minus_rev.unwrap_or(v.pdf_rev), v.delta)
            } else {
                (light[i].pdf_fwd, light[i].pdf_rev, light[i].delta)
            }
        };
        let mut sum = 0.0f32;
        let mut ri = 1.0f32;
        // Strategies (s + t − i, i) with fewer camera vertices ((1, 1) cannot occur: s + t
        // > 2 here).
        for i in (1..t).rev() {
            let (fwd, rev, delta) = cam_at(i);
            let r = remap0(rev) / remap0(fwd);
            ri *= r * r;
            if !delta && !cam_at(i - 1).2 {
                sum += ri;
            }
        }
        ri = 1.0;
        for i in (0..s).rev() {
            let (fwd, rev, delta) = light_at(i);
            let r = remap0(rev) / remap0(fwd);
            ri *= r * r;
            let delta_before = if i > 0 {
                light_at(i - 1).2
            } else {
                // The light of the subpath's origin: a delta light is never hit.
                let origin = qs.filter(|_| s == 1).unwrap_or(&light[0]);
                matches!(origin.kind, Kind::Light(l) if scene.lights[l as usize].is_delta())
            };
            if !delta && !delta_before {
                sum += ri;
            }
        }
        let w = 1.0 / (1.0 + sum);
        if w.is_finite() { w } else { 0.0 }
    }
}

/// One camera sample's colour modes: its wavelengths as drawn (RGB mode: nothing), and with
/// the secondaries terminated.
struct Modes<M> {
    full: M,
    terminated: M,
}

impl<M> Modes<M> {
    /// The mode of a strategy whose vertices were reached after a termination or not.
    #[inline(always)]
    fn of(&self, terminated: bool) -> &M {
        if terminated {
            &self.terminated
        } else {
            &self.full
        }
    }
}

/// The per-strategy images' part of one camera sample: (s, t, film position, value).
struct StrategyRecord<'a> {
    p_film: Vec2,
    weighted: bool,
    out: &'a mut Vec<(u16, u16, Vec2, Vec3)>,
}

impl<C: Color> StrategySink<C> for StrategyRecord<'_> {
    fn add(&mut self, s: usize, t: usize, splat_at: Option<Vec2>, value: Vec3, weight: f32) {
        let v = if self.weighted { value } else { value / weight };
        self.out
            .push((s as u16, t as u16, splat_at.unwrap_or(self.p_film), v));
    }
}

/// Bytes the per-strategy images of `cfg` take (0 without them).
pub fn memory_needed(scene: &Scene, cfg: &BdptConfig) -> u64 {
    match (cfg.strategy_images, u32::try_from(cfg.max_depth)) {
        (Some(_), Ok(d)) => {
            let f = &scene.film;
            let one = crate::film::Film::memory_needed(f.width, f.height, f.crop, &f.filter, 0);
            StrategyImages::strategies(d).count() as u64 * one
        }
        _ => 0,
    }
}

/// Render `scene` with BDPT: `opts.spp` passes of one sample per pixel, rows in parallel,
/// each row's film tile and light-tracing splats merged in row order (the image does not
/// depend on the thread count); a time budget or cancellation stops after a whole pass.
/// With `cfg.strategy_images` the outcome also holds one image per strategy (s, t), named
/// by [`StrategyImages::name`]: every contribution splatted at its film position, so that
/// with the box filter the weighted images sum to the image up to rounding.
pub fn render(
    scene: &Scene,
    cfg: &BdptConfig,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    match scene.mode {
        RenderMode::Rgb => render_in::<RgbMode>(scene, cfg, opts, observer),
        RenderMode::Spectral => render_in::<SpectralMode<'static>>(scene, cfg, opts, observer),
    }
}

fn render_in<M: PathMode>(
    scene: &Scene,
    cfg: &BdptConfig,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    let start = Instant::now();
    let f = &scene.film;
    let mut film = f.film();
    let (pmin, pmax) = film.pixel_bounds();
    let pixel_count = film.pixel_count();
    let bdpt = Bdpt::<M>::new(scene, cfg);
    let template = Sampler::new(scene.sampler.kind, opts.spp.max(1), scene.sampler.seed);
    // The camera's importance is normalised over the full image: light paths per pixel of
    // it, per pass.
    let per_pass = pixel_count.max(1) as f64 / (f.width as f64 * f.height as f64);
    // Every strategy's image, black ones too (the set of files depends on max_depth only).
    let mut strategy_films: BTreeMap<(u16, u16), Film> = match cfg.strategy_images {
        Some(_) => StrategyImages::strategies(cfg.max_depth.max(0) as u32)
            .map(|(s, t)| ((s as u16, t as u16), f.film()))
            .collect(),
        None => BTreeMap::new(),
    };
    let (done, cancelled) = run_passes(opts, observer, start, pixel_count, |pass| {
        let rows: Vec<_> = (pmin.y..pmax.y)
            .into_par_iter()
            .map(|y| {
                let mut tile = film.tile(UVec2::new(pmin.x, y), UVec2::new(pmax.x, y + 1));
                let mut splats = Vec::new();
                let mut records = Vec::new();
                let mut paths = Subpaths::default();
                let mut sampler = template.clone();
                for x in pmin.x..pmax.x {
                    let (p_film, cray) = camera_sample(scene, &mut sampler, UVec2::new(x, y), pass);
                    let (s, p) = (&mut sampler, &mut paths);
                    let l = match cfg.strategy_images {
                        None => bdpt.li(scene, &cray, s, p, &mut splats, &mut ()),
                        Some(kind) => {
                            let mut record = StrategyRecord {
                                p_film,
                                weighted: kind == StrategyImages::Weighted,
                                out: &mut records,
                            };
                            bdpt.li(scene, &cray, s, p, &mut splats, &mut record)
                        }
                    };
                    tile.add_sample(p_film, l);
                }
                (tile, splats, records)
            })
            .collect();
        for (tile, splats, records) in &rows {
            film.merge(tile);
            for &(p, c) in splats {
                film.add_splat(p, c);
            }
            for &(s, t, p, c) in records {
                if let Some(img) = strategy_films.get_mut(&(s, t)) {
                    img.add_splat(p, c);
                }
            }
        }
        film.set_splat_scale(1.0 / (per_pass * (pass + 1) as f64));
        observer.pass_done(&film, pass + 1);
    });
    // Light-tracing images (t = 1) are normalised as the film's splats; the others hold one
    // sample per pixel and pass.
    let extra = strategy_films
        .into_iter()
        .map(|((s, t), mut img)| {
            let paths_per_pixel = if t == 1 { per_pass } else { 1.0 };
            img.set_splat_scale(1.0 / (paths_per_pixel * done.max(1) as f64));
            (StrategyImages::name(s as usize, t as usize), img)
        })
        .collect();
    RenderOutcome {
        film,
        spp: done,
        passes: done,
        elapsed: start.elapsed(),
        cancelled,
        extra,
    }
}
