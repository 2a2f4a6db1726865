//! The volumetric path tracer, with Mitsuba 3's `volpath` semantics.
//!
//! - The path starts in the camera's medium. In a medium, a free flight is sampled up to the
//!   next surface (the transport layer's [`Walker`]): a collision scatters by the phase
//!   function (`collision.rs`), otherwise the path reaches the surface with the flight's
//!   pass weight.
//! - `max_depth` counts scattering events, in media and on surfaces; index-matched (`null`)
//!   surfaces are crossed without counting, and change the medium when they bound one.
//!   Russian roulette after `rr_depth` events, with probability min(max(β)·η², 0.95).
//! - Next-event estimation at every medium collision and at every surface with a smooth lobe
//!   (one emitter chosen as the scene's light selection says), its shadow ray attenuated by
//!   the transmittance of every medium it crosses and blocked by any surface that is not
//!   `null` (the shadow query); combined with phase or BSDF sampling by the power
//!   heuristic. Emitters reached by a path use the density of the last real scattering event,
//!   as Mitsuba does.
//! - Surfaces whose shape bounds media (`interior`/`exterior`) switch the path's medium to
//!   the side the new direction goes to.
//!
//! Like Mitsuba, a hero channel is drawn per path and free flights are sampled with it;
//! beyond Mitsuba, contributions are weighted by spectral MIS over the choice of hero (the
//! path's channel density ratios, see [`crate::media::Flight`]), and homogeneous media use
//! analytic transmittance on shadow rays: lower variance, the same mean. Grids use delta and
//! ratio tracking, as Mitsuba does. `equiangular.rs` holds the two extra strategies:
//! equiangular sampling towards point lights and next-event estimation of emission grids.

mod collision;
mod equiangular;

use base::TransmittanceEstimator;

use self::equiangular::{Segment, sample_emission};
use super::path::{
    Contribution, NoRecorder, PathEnd, PathRecorder, RecordedScatter, RecordedVertex, Scatter,
    VertexKind, Via,
};
use super::transport::{
    self, Connection, Event, From, MisHeuristic, Previous, Scatterer, Walker, mis, roulette,
};
use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::drive::Estimator;
use crate::lights::{LightSample, Receiver};
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode, RgbMode};
use crate::world::Scene;

/// `volpath`'s parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolPathConfig {
    /// Largest number of scattering events (`u32::MAX`: unbounded).
    pub max_depth: u32,
    /// Russian roulette once more than this many events happened.
    pub rr_depth: u32,
    /// Do not show emitters seen directly from the camera.
    pub hide_emitters: bool,
    /// Also sample points on each medium segment by equiangular sampling towards a point or
    /// spot light, MIS-combined with free-flight sampling (grey homogeneous media).
    pub equiangular: bool,
    /// How shadow rays estimate the transmittance of grids.
    pub transmittance: TransmittanceEstimator,
    /// Sample points of emission grids by their radiance from every scattering vertex (the
    /// collision estimator then leaves those vertices' segments alone); otherwise emission
    /// is only found at collisions.
    pub sample_emission: bool,
}

/// How a path leaves a medium collision, for recorders: a non-delta event (render layers
/// count it as diffuse-like); the vertex's [`VertexKind::Medium`] tells it apart.
const PHASE: Scatter = Scatter {
    delta: false,
    transmission: false,
};

/// The radiance arriving along one camera ray.
#[inline]
pub fn li(scene: &Scene, cray: &CameraRay, sampler: &mut Sampler, cfg: &VolPathConfig) -> Vec3 {
    li_in::<RgbMode>(scene, cray, sampler, cfg)
}

impl<M: PathMode> Estimator<M> for VolPathConfig {
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        li_in::<M>(scene, cray, sampler, self)
    }
}

/// [`li`] in the colour mode `M` (set up for this camera sample from `sampler`), as linear
/// sRGB.
#[inline]
pub fn li_in<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &VolPathConfig,
) -> Vec3 {
    let mode = M::start(sampler);
    let l = li_recorded_in(scene, cray, sampler, cfg, &mode, &mut NoRecorder);
    mode.to_rgb(l)
}

/// [`li`] with a recorder told about the path's vertices (surface, medium and null
/// crossings), its directions and its contributions, as the path tracer's `li_recorded`
/// does. With [`NoRecorder`] it is `li`.
pub fn li_recorded<R: PathRecorder>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &VolPathConfig,
    rec: &mut R,
) -> Vec3 {
    li_recorded_in(scene, cray, sampler, cfg, &RgbMode, rec)
}

/// [`li_recorded`] in the colour mode `mode`: the estimate in its colour type.
pub fn li_recorded_in<M: PathMode, R: PathRecorder<M::C>>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &VolPathConfig,
    mode: &M,
    rec: &mut R,
) -> M::C {
    rec.camera_ray(&cray.ray);
    let hero = mode.hero(sampler.next_1d());
    let mut path = VolPath {
        scene,
        cfg,
        mode,
        rec,
        sampler,
        walker: Walker::camera(scene, cray, hero),
        throughput: M::C::ONE,
        ratio: M::C::ONE,
        result: M::C::ZERO,
        eta: 1.0,
        depth: 0,
        first: None,
        prev: None,
        emission_sampled: false,
    };
    path.trace();
    path.result
}

/// One path of `volpath` and what it works with.
struct VolPath<'a, M: PathMode, R> {
    scene: &'a Scene,
    cfg: &'a VolPathConfig,
    mode: &'a M,
    rec: &'a mut R,
    sampler: &'a mut Sampler,
    walker: Walker,
    throughput: M::C,
    /// The path's density ratios p_c/p_hero over the channels (their mean divides every
    /// contribution: spectral MIS over the hero).
    ratio: M::C,
    result: M::C,
    /// The product of relative indices of refraction crossed (Russian roulette).
    eta: f32,
    /// Scattering events so far.
    depth: u32,
    /// How the path left its first scattering vertex (for the recorder's contributions).
    first: Option<Scatter>,
    /// The last real scattering event (`None`: the camera), whose density weighs emission
    /// found next.
    prev: Option<Previous>,
    /// Emission grids were sampled from the vertex the current segment started at: their
    /// emission met by collisions on it is already counted.
    emission_sampled: bool,
}

/// What a step of the path decided.
enum Step {
    Continue,
    End(PathEnd),
}

impl<M: PathMode, R: PathRecorder<M::C>> VolPath<'_, M, R> {
    /// The spectral-MIS weight of the path so far.
    #[inline(always)]
    fn hero_weight(&self) -> f32 {
        self.mode.hero_weight(self.ratio)
    }

    /// Adds `l` to the estimate and tells the recorder where it came from.
    #[inline(always)]
    fn add(&mut self, l: M::C, via: Via, depth: u32, first: Option<Scatter>) {
        self.result += l;
        self.rec.contribution(l, Contribution { depth, first, via });
    }

    /// What the path carries to the recorder: its throughput with the spectral-MIS weight.
    #[inline(always)]
    fn carried(&self) -> M::C {
        self.throughput * self.hero_weight()
    }

    fn trace(&mut self) {
        // Bounded: null crossings do not count as depth.
        for _ in 0..(1 << 16) {
            if let Step::End(end) = self.step() {
                self.rec.end(end);
                return;
            }
        }
    }

    /// One segment: roulette and the depth limit, then the medium collision or the surface
    /// the segment ends at.
    fn step(&mut self) -> Step {
        if self.throughput.is_black() {
            return Step::End(PathEnd::Absorbed);
        }
        if self.depth > self.cfg.rr_depth {
            // The path's effective weight is throughput / mean ratio.
            let q = roulette::throughput(self.mode.live_max(self.carried()), self.eta);
            if !roulette::survive(&mut self.throughput, q, self.sampler.next_1d()) {
                return Step::End(PathEnd::Roulette);
            }
        }
        if self.depth >= self.cfg.max_depth {
            return Step::End(PathEnd::MaxDepth);
        }
        let scene = self.scene;
        // The surface's interaction waits until no collision comes before it.
        let ahead = self.walker.ahead(scene);
        let mut segment = self.segment(ahead.end);
        if let Some(seg) = &mut segment {
            // Equiangular sampling of this segment towards a point light (strategy B); the
            // collision's own next-event estimation is strategy A.
            let medium = self.walker.medium;
            let m = self.walker.medium(scene).expect("a segment is in a medium");
            let time = self.walker.ray.time;
            let b = seg.equiangular(scene, m, medium, time, self.sampler, self.mode);
            let l = self.throughput * b * self.hero_weight();
            self.add(l, Via::EmitterSample, self.depth + 1, self.first);
        }
        let flight = self.walker.fly(scene, &ahead, self.sampler, self.mode);
        match self.walker.event(scene, ahead, flight) {
            Event::Collision {
                d,
                weight,
                ratio,
                emit,
                ..
            } => self.collision(d, weight, ratio, emit, segment.as_mut()),
            Event::Escape(pass) => {
                pass.apply(&mut self.throughput, &mut self.ratio);
                self.escape();
                Step::End(PathEnd::Escaped)
            }
            Event::Null(si, pass) => {
                pass.apply(&mut self.throughput, &mut self.ratio);
                self.emission(&si);
                self.cross_null(&si);
                Step::Continue
            }
            Event::Surface(si, pass) => {
                pass.apply(&mut self.throughput, &mut self.ratio);
                self.emission(&si);
                self.surface(&si)
            }
        }
    }

    /// The equiangular strategy's segment towards point lights, in a grey homogeneous medium
    /// up to `end` (`None` where it does not apply).
    fn segment(&self, end: f32) -> Option<Segment> {
        let cfg = self.cfg;
        if !(cfg.equiangular && self.depth + 1 < cfg.max_depth) {
            return None;
        }
        let (sigma_t, sigma_s) = self.walker.medium(self.scene)?.grey_homogeneous()?;
        let ray = &self.walker.ray;
        Some(Segment::new(
            ray.o,
            ray.d,
            end,
            sigma_t,
            sigma_s,
            cfg.transmittance,
        ))
    }

    /// Whether emission the path finds now is shown (not to camera rays with
    /// `hide_emitters`).
    #[inline(always)]
    fn sees_emitters(&self) -> bool {
        !(self.depth == 0 && self.cfg.hide_emitters)
    }

    /// The MIS weight of emission from light `i` found along the current ray (through `si`
    /// on it for an area light).
    fn emission_weight(&self, i: u32, si: Option<&SurfaceInteraction>) -> f32 {
        let (scene, d) = (self.scene, self.walker.ray.d);
        self.prev.as_ref().map_or(1.0, |p| {
            p.weight(MisHeuristic::Power, |r| {
                transport::emitter_density(scene, r, i, d, si)
            })
        })
    }

    /// The ray left the scene: the environment's emission along it (and the background, for
    /// camera rays).
    fn escape(&mut self) {
        if !self.sees_emitters() {
            return;
        }
        let (scene, mode) = (self.scene, self.mode);
        let h = self.hero_weight();
        let l = transport::environment(scene, self.walker.ray.d, mode, self.throughput, |i, _| {
            self.emission_weight(i, None) * h
        });
        self.add(l, Via::Emission, self.depth + 1, self.first);
        if self.depth == 0
            && let Some(bg) = scene.background
        {
            self.add(mode.illuminant(bg), Via::Emission, 1, self.first);
        }
    }

    /// Emission of the surface the current ray hit at `si`, if it emits.
    fn emission(&mut self, si: &SurfaceInteraction) {
        if !self.sees_emitters() {
            return;
        }
        if let Some((i, le)) = transport::emitter_hit(self.scene, si, self.mode) {
            let w = self.emission_weight(i, Some(si));
            let l = self.throughput * le * (w * self.hero_weight());
            self.add(l, Via::Emission, self.depth + 1, self.first);
        }
    }

    /// An index-matched boundary: cross it, in the same direction.
    fn cross_null(&mut self, si: &SurfaceInteraction) {
        let carried = self.carried();
        self.rec.vertex(&RecordedVertex {
            p: si.p,
            n: si.shading.n,
            depth: self.depth + 1,
            throughput: carried,
            kind: VertexKind::Null,
        });
        self.rec.scatter(&RecordedScatter {
            scatter: Scatter {
                delta: true,
                transmission: true,
            },
            wi: self.walker.ray.d,
            pdf: 1.0,
            throughput: carried,
        });
        self.walker.cross(self.scene, si);
    }

    /// A surface that scatters or absorbs: emission sampling and next-event estimation from
    /// it, and the next direction.
    fn surface(&mut self, si: &SurfaceInteraction) -> Step {
        let (scene, cfg, mode) = (self.scene, self.cfg, self.mode);
        self.rec.vertex(&RecordedVertex {
            p: si.p,
            n: si.shading.n,
            depth: self.depth + 1,
            throughput: self.carried(),
            kind: VertexKind::Surface,
        });
        let Some((bsdf, frame)) = scene.bsdf_at_in(si, mode) else {
            return Step::End(PathEnd::Absorbed);
        };
        let wo = frame.to_local(si.wo);
        let at = Scatterer::surface(&bsdf, &frame, wo);
        // Contributions from this vertex reach the emitter one segment past it; before the
        // path leaves its first vertex, `first` is still unknown, as in the path tracer.
        let (here, first) = (self.depth + 2, self.first);
        self.emission_sampled = false;
        let smooth = bsdf.has_smooth() && self.depth + 1 < cfg.max_depth;
        if smooth && cfg.sample_emission {
            let f = |wi| at.eval(wi, TransportMode::Radiance);
            self.emission_sample(From::Surface(si), f, (here, first));
        }
        if smooth {
            self.next_event(si, &at, here);
        }
        let u1 = self.sampler.next_1d();
        let u2 = self.sampler.next_2d();
        let Some(bs) = bsdf.sample(wo, u1, u2, TransportMode::Radiance) else {
            return Step::End(PathEnd::Absorbed);
        };
        self.throughput *= bs.weight;
        self.eta *= bs.eta;
        if bs.delta {
            // Emission sampling could not follow a delta lobe: collisions count again.
            self.emission_sampled = false;
        }
        let wi = frame.to_world(bs.wi);
        let scatter = Scatter {
            delta: bs.delta,
            transmission: bs.transmission,
        };
        self.rec.scatter(&RecordedScatter {
            scatter,
            wi,
            pdf: bs.pdf,
            throughput: self.carried(),
        });
        self.first = self.first.or(Some(scatter));
        self.walker.leave(scene, si, wi);
        self.depth += 1;
        self.prev = Some(Previous {
            receiver: Receiver::from(si),
            pdf: bs.pdf,
            delta: bs.delta,
        });
        Step::Continue
    }

    /// Next-event estimation of the emission grids from `from` (scattering by `f`), recorded
    /// at depth `here` after `first`; the collisions of the next segment then leave the grids'
    /// emission alone.
    fn emission_sample(
        &mut self,
        from: From,
        f: impl Fn(Vec3) -> M::C,
        (here, first): (u32, Option<Scatter>),
    ) {
        let (scene, cfg, medium) = (self.scene, self.cfg, self.walker.medium);
        let e = sample_emission(scene, from, medium, cfg, self.sampler, self.mode, f);
        let l = self.throughput * e * self.hero_weight();
        self.add(l, Via::EmitterSample, here, first);
        self.emission_sampled = true;
    }

    /// The transmittance of the connection from `from` (where the path is) to the emitter
    /// sample `ls`; `None` when blocked.
    fn shadow(&mut self, from: From, ls: &LightSample<M::C>) -> Option<M::C> {
        let c = Connection {
            from,
            wi: ls.wi,
            target: ls.target,
            medium: self.walker.medium,
        };
        let (scene, mode) = (self.scene, self.mode);
        let tr = transport::transmittance(scene, &c, self.cfg.transmittance, self.sampler, mode);
        (!tr.is_black()).then_some(tr)
    }

    /// Next-event estimation from the surface at `si` (scattering by `at`), its
    /// contribution recorded at depth `here`.
    fn next_event(&mut self, si: &SurfaceInteraction, at: &Scatterer<M::C>, here: u32) {
        let (scene, mode) = (self.scene, self.mode);
        let r = Receiver::from(si);
        let Some(e) = transport::sample_emitter(scene, &r, self.sampler, mode) else {
            return;
        };
        let (ls, pmf) = (&e.ls, e.pmf);
        let (f, pdf) = at.eval_pdf(ls.wi, TransportMode::Radiance);
        if f.is_black() {
            return;
        }
        let Some(tr) = self.shadow(From::Surface(si), ls) else {
            return;
        };
        let w = if ls.delta {
            1.0
        } else {
            mis::power(ls.pdf * pmf, pdf)
        };
        let l = self.throughput * tr * f * ls.li * (w * self.hero_weight() / (ls.pdf * pmf));
        self.add(l, Via::EmitterSample, here, self.first);
    }
}
