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
//! reads it as 1, dropping the factor: weights that depend on the scene's scale (and noisier
//! behind glass and mirrors; figures in `bench/README.md`).
//!
//! Participating media: free flights sampled along both subpaths (`Medium::sample_in`, with
//! a hero channel drawn per camera sample and shared by both subpaths) make medium vertices,
//! which scatter by their phase function and connect like surface vertices; every
//! connection carries the transmittance of its segment (through null surfaces and media,
//! the transport layer's shadow query). When every medium is homogeneous the MIS
//! densities carry the free flights' densities (σt·e^{−σt·d} per unit length to a medium
//! vertex, e^{−σt·d} to a surface reached through a medium; Mitsuba 0.6's BDPT does the same)
//! in every colour lane: a connection's segment gets the same factor from its exact
//! transmittance, and the weights are the power heuristic over the (strategy, lane) pairs
//! (`mis.rs`), since a camera sample draws one hero lane and evaluates every strategy. With
//! grids, whose transmittance is only estimated (and whose extinction is grey), they are
//! left out (pbrt-v3's choice) and each strategy's estimate carries the spectral-MIS weight
//! over the hero choice of the vertices it uses (`hero_weight` of the product of both
//! prefixes' density ratios), as `volpath`'s paths do. Either way the weights are one
//! function of the path for every strategy, so they sum to one. An emitting medium's light is
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

//!
//! The module, by purpose: here the configuration, [`Bdpt`] and one camera sample
//! ([`Bdpt::li`], [`Bdpt::strategy`]); `vertex.rs` the vertices, joints and densities;
//! `walk.rs` the subpaths (random walks on the transport layer's walker); `connect.rs` the
//! strategies; `mis.rs` their weights; `render.rs` the render driver and the per-strategy
//! images; `record.rs` what `debug-paths` shows.

mod connect;
mod mis;
mod record;
mod render;
mod vertex;
mod walk;

use std::marker::PhantomData;

pub use self::record::{BdptConnection, BdptSample, BdptVertex, BdptVertexKind};
pub use self::render::memory_needed;
pub use self::vertex::Subpaths;

use self::connect::Joins;
use self::vertex::{Joint, Kind, Modes, Vertex};
use super::{IntegratorModel, camera_unsupported};
use crate::camera::CameraRay;
use crate::math::{Vec2, Vec3};
use crate::media::MediumKind;
use crate::sampling::{Distribution1D, Samples};
use crate::session::{Job, RenderOptions, RenderOutcome};
use crate::spectral::lanes::{Color, PathMode, RgbMode};
use crate::world::Scene;

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
pub trait StrategySink<C: Color> {
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

impl IntegratorModel for BdptConfig {
    fn name(&self) -> &'static str {
        "bdpt"
    }

    fn unsupported(&self, scene: &Scene) -> Option<String> {
        if self.strategy_images.is_some() && self.max_depth < 0 {
            return Some(
                "bdpt: per-strategy images need a finite max depth (e.g. --max-depth 6; \
                 pbrt-v4's default maxdepth 5 is 6 edges)"
                    .to_string(),
            );
        }
        camera_unsupported(self.name(), scene)
    }

    fn memory(&self, scene: &Scene) -> Option<(&'static str, u64)> {
        self.strategy_images
            .map(|_| ("keeping one image per strategy", memory_needed(scene, self)))
    }

    /// Rows of passes (see `render.rs`); not with per-strategy images.
    fn work_items(&self, scene: &Scene, opts: &RenderOptions) -> Result<u64, String> {
        match self.strategy_images {
            None => Ok(render::work_items(scene, opts.spp)),
            Some(_) => Err(
                "bdpt with per-strategy images cannot be split into shards or \
                            resumed from a checkpoint; render it in one process"
                    .into(),
            ),
        }
    }

    /// `opts.spp` passes of one sample per pixel (see `render.rs`).
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        render::render_in::<M>(job, self)
    }
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

    /// σt of medium `medium` in every lane of `m` if the free-flight densities enter the MIS
    /// weights (else, and outside media, `None`).
    pub(super) fn flight_sigma(&self, scene: &Scene, medium: Option<u32>, m: &M) -> Option<M::C> {
        match medium.map(|i| &scene.media[i as usize].kind) {
            Some(MediumKind::Homogeneous(h)) if self.flight_densities => {
                Some(m.unbounded(h.sigma_t))
            }
            _ => None,
        }
    }

    /// Whether paths of `edges` edges are within `min_edges..=max_depth`.
    pub(super) fn allows(&self, edges: usize) -> bool {
        edges >= self.cfg.min_edges as usize
            && (self.cfg.max_depth < 0 || edges <= self.cfg.max_depth as usize)
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

    /// A camera sample's two subpaths, built in `paths`, with its colour modes and hero lane:
    /// the camera's from `cray` (its numbers from the sampler's current stream), the light's
    /// from stream 1 (not drawn at all for a limit of 0), at most `max` = (camera, light)
    /// vertices each; stream 2 is started for the connections. With `exact`, `None` as soon
    /// as a subpath comes out shorter than its limit (a strategy of MLT needs it whole).
    #[inline(always)]
    fn subpaths<'p>(
        &self,
        scene: &'p Scene,
        cray: &CameraRay,
        (max_cam, max_light): (usize, usize),
        exact: bool,
        sampler: &mut impl Samples,
        paths: &'p mut Subpaths<M::C>,
    ) -> Option<Joins<'p, M>> {
        let (cam, light) = paths.cleared();
        let (modes, hero) = Self::start(scene, sampler);
        let m = modes.full.clone();
        self.camera_subpath(scene, cray, (hero, max_cam), sampler, cam, &m);
        if exact && cam.len() != max_cam {
            return None;
        }
        sampler.start_stream(1);
        if max_light > 0 {
            let m = modes.full.clone();
            self.light_subpath(scene, (hero, max_light), sampler, light, &m);
            if exact && light.len() != max_light {
                return None;
            }
        }
        sampler.start_stream(2);
        Some(Joins {
            scene,
            cam,
            light,
            hero,
            modes,
        })
    }

    /// The radiance of one camera sample in linear sRGB (its subpaths built in `paths`);
    /// light-tracing contributions (t = 1) go to `splats` as (film position, value); `sink`
    /// is told of every strategy's. The camera subpath draws from the sampler's current
    /// stream, the light subpath from stream 1, the connections from stream 2
    /// ([`Samples::start_stream`]). In spectral mode both subpaths share the wavelengths and
    /// each terminates its own secondaries; a strategy counts the hero only if a vertex it
    /// uses was reached after a termination. A render tells `()`.
    pub fn li(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        sampler: &mut impl Samples,
        paths: &mut Subpaths<M::C>,
        splats: &mut Vec<(Vec2, Vec3)>,
        sink: &mut impl StrategySink<M::C>,
    ) -> Vec3 {
        let max = match self.cfg.max_depth {
            d if d < 0 => (usize::MAX, usize::MAX),
            d => (d as usize + 1, d as usize),
        };
        let Some(j) = self.subpaths(scene, cray, max, false, sampler, paths) else {
            return Vec3::ZERO;
        };
        let mut l = Vec3::ZERO;
        for t in 1..=j.cam.len() {
            for s in 0..=j.light.len() {
                let depth = s + t;
                if (s == 1 && t == 1) || depth < 2 || !self.allows(depth - 1) {
                    continue;
                }
                if t == 1 {
                    if let Some((p, c, w)) = self.connect_camera(&j, s, sampler, sink) {
                        splats.push((p, c));
                        if w > 0.0 && c != Vec3::ZERO {
                            sink.add(s, 1, Some(p), c, w);
                        }
                    }
                    continue;
                }
                let (c, w) = self.connect(&j, (s, t), sampler, sink);
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
    pub fn strategy(
        &self,
        scene: &Scene,
        (cray, p_film): (&CameraRay, Vec2),
        (s, t): (usize, usize),
        sampler: &mut impl Samples,
        paths: &mut Subpaths<M::C>,
    ) -> Option<(Vec2, Vec3)> {
        let j = self.subpaths(scene, cray, (t, s), true, sampler, paths)?;
        if t == 1 {
            return self
                .connect_camera(&j, s, sampler, &mut ())
                .map(|(p, c, _)| (p, c));
        }
        let (c, _) = self.connect(&j, (s, t), sampler, &mut ());
        Some((p_film, c))
    }
}
