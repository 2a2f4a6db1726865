//! The unidirectional path tracer: Mitsuba 3's `path` integrator, and the course tracers
//! (Whitted, Nori's `path_*` and `direct_*`, CS184's, COMP30019's, CENG795's) as
//! configurations of the same loop ([`PathConfig`]).
//!
//! With the default configuration ([`PathConfig::mitsuba`], which the build crate's `path_config`
//! starts from) this is Mitsuba 3's `path` integrator exactly: emitter sampling (one light
//! chosen uniformly, unless the scene asks for another light selection) at every vertex with
//! a non-delta BSDF, BSDF sampling to continue, both combined with the power heuristic;
//! Russian roulette from depth `rr_depth` with continuation probability
//! min(max(throughput)·η², 0.95); `max_depth` counts path segments (1: emitters seen
//! directly, 2: direct lighting, −1: unbounded).
//!
//! The course variants change one thing each: no next-event estimation (brute force), uniform
//! hemisphere directions instead of BSDF sampling, several emitter samples per vertex or one
//! per emitter (Whitted, CS184), fixed-probability Russian roulette, splitting at the first
//! vertex. Every combination converges to the same image; only the noise differs.
//!
//! The module, by purpose:
//!
//! - here: [`PathConfig`] and the entry points [`li`], [`li_recorded`] (one path at a time)
//!   and [`li_batched`] (a stream of camera samples);
//! - `course.rs`: the course configurations ([`PathConfig::whitted`], Nori's) and which
//!   switches each course uses;
//! - `state.rs`: the path state, what a step works with ([`Tracer`](state::Tracer)) and the
//!   shadow sink;
//! - `vertex.rs`: the per-vertex step both loops share;
//! - `nee.rs`: next-event estimation (one emitter, several samples, or every emitter) and the
//!   MIS weights;
//! - `scatter.rs`: the next direction and Russian roulette;
//! - `batched.rs`: the batched loop with its deferred shadow rays — why, and why its
//!   estimates are the single-path loop's bit for bit;
//! - `guided.rs`: path guiding (Müller et al. 2017's SD-tree, trained in phases of the
//!   tile loop; the guided recorder and the mixture of BSDF and learnt directions);
//! - `record.rs`: what a [`PathRecorder`] sees (render layers, the path visualiser);
//!   [`NoRecorder`] compiles to nothing.

mod batched;
mod course;
pub mod guided;
mod nee;
mod record;
mod scatter;
mod state;
mod vertex;

use base::{DirectionSampling, RussianRoulette};

pub use self::batched::li_batched;

pub use self::record::{
    Contribution, DepthFilter, NoRecorder, PathEnd, PathRecorder, RecordedScatter, RecordedVertex,
    Scatter, VertexKind, Via,
};
use self::state::{PathState, Shadows, Tracer};
use super::transport::MisHeuristic;
use crate::camera::CameraRay;
use crate::drive::{self, Estimator};
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::{Color, PathMode, RgbMode};
use crate::world::Scene;

/// How emission found by BSDF-sampled rays is weighted against emitter sampling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combine {
    /// Multiple importance sampling with the power heuristic (β = 2).
    Power,
    /// Multiple importance sampling with the balance heuristic.
    Balance,
    /// Only emitter sampling counts, except after delta bounces and for camera rays.
    EmitterOnly,
    /// Only BSDF sampling counts (no emitter sampling at all).
    BsdfOnly,
}

impl Combine {
    /// The heuristic of the two MIS combinations (`None` for the one-strategy ones).
    #[inline(always)]
    pub fn heuristic(self) -> Option<MisHeuristic> {
        match self {
            Combine::Power => Some(MisHeuristic::Power),
            Combine::Balance => Some(MisHeuristic::Balance),
            Combine::EmitterOnly | Combine::BsdfOnly => None,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathConfig {
    /// Maximum number of path segments; `u32::MAX` for unbounded.
    pub max_depth: u32,
    pub rr: RussianRoulette,
    /// Do not show emitters hit by camera rays.
    pub hide_emitters: bool,
    pub combine: Combine,
    /// Continue paths after non-delta vertices (false: Whitted-style, only delta chains).
    pub continue_diffuse: bool,
    pub directions: DirectionSampling,
    /// Emitter samples per non-delta vertex.
    pub light_samples: u32,
    /// Next-event estimation visits every emitter (`light_samples` each, delta emitters once)
    /// instead of choosing one; Whitted-style tracers.
    pub all_lights: bool,
    /// Continuations traced from the first vertex, each with 1/N of the throughput.
    pub splitting: u32,
    /// Count emission reached through delta bounces after a non-delta one (caustics).
    pub caustics: bool,
    /// Largest component a camera sample may have (scaled down as a whole above it).
    pub clamp: Option<f32>,
    /// Keep only contributions of paths with exactly this many segments.
    pub only_depth: Option<u32>,
    /// Attenuate each segment by the transmittance of the medium it runs through: the path
    /// starts in the camera's medium and, at every transmission, enters the shape's interior
    /// when it crosses from the front (the side the shading normal points to) and its
    /// exterior otherwise. Only purely absorbing homogeneous media can be applied this way
    /// (no scattering, no emission: transmittance is then their whole effect; see
    /// [`Medium::is_purely_absorbing`](crate::media::Medium::is_purely_absorbing)), and only
    /// along the path: shadow rays are not attenuated (in a closed dielectric they are blocked
    /// by its surface anyway). The build step sets it when every medium of the scene comes from
    /// Beer–Lambert absorption in a dielectric (the course formats); off, as Mitsuba's `path`,
    /// media are ignored.
    pub media_absorption: bool,
    /// Path guiding (`guided.rs`): learn the incident light online and sample from it beside
    /// the BSDF. Only with BSDF directions, no splitting and no `only_depth` (`build` checks).
    pub guiding: Option<guided::Guiding>,
}

impl PathConfig {
    pub fn mitsuba(max_depth: i32, rr_depth: u32, hide_emitters: bool, combine: Combine) -> Self {
        PathConfig {
            max_depth: if max_depth < 0 {
                u32::MAX
            } else {
                max_depth as u32
            },
            rr: RussianRoulette::Throughput {
                from_depth: rr_depth,
            },
            hide_emitters,
            combine,
            continue_diffuse: true,
            directions: DirectionSampling::Bsdf,
            light_samples: 1,
            all_lights: false,
            splitting: 1,
            caustics: true,
            clamp: None,
            only_depth: None,
            media_absorption: false,
            guiding: None,
        }
    }
}

/// `l` scaled down so that its largest component is at most `max` (pbrt-v4's
/// `maxcomponentvalue`).
#[inline]
pub fn clamp_sample(l: Vec3, max: f32) -> Vec3 {
    let m = l.max_element();
    if m > max { l * (max / m) } else { l }
}

pub fn li(scene: &Scene, cray: &CameraRay, sampler: &mut Sampler, cfg: &PathConfig) -> Vec3 {
    li_in::<RgbMode>(scene, cray, sampler, cfg)
}

impl<M: PathMode> Estimator<M> for PathConfig {
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        let l = li_in::<M>(scene, cray, sampler, self);
        self.clamp.map_or(l, |max| clamp_sample(l, max))
    }

    /// Several paths in flight per thread ([`li_batched`]), unless `only_depth` asks for a
    /// recorder (one path at a time).
    fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        mut done: impl FnMut(T, Vec3),
    ) {
        if self.only_depth.is_some() {
            return drive::one_at_a_time::<M, Self, T>(self, scene, template, next, done);
        }
        // A separate instantiation for clamping: the default loop is untouched.
        match self.clamp {
            Some(max) => li_batched::<_, M>(scene, self, template, next, |tag, l| {
                done(tag, clamp_sample(l, max))
            }),
            None => li_batched::<_, M>(scene, self, template, next, done),
        }
    }
}

/// [`li`] in the colour mode `M` (set up for this camera sample from `sampler`), as linear
/// sRGB.
pub fn li_in<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &PathConfig,
) -> Vec3 {
    let mode = M::start(sampler);
    if let Some(depth) = cfg.only_depth {
        let mut rec = DepthFilter {
            depth,
            sum: M::C::ZERO,
        };
        li_recorded_in(scene, cray, sampler, cfg, &mode, &mut rec);
        return mode.to_rgb(rec.sum);
    }
    mode.to_rgb(li_recorded_in(
        scene,
        cray,
        sampler,
        cfg,
        &mode,
        &mut NoRecorder,
    ))
}

/// [`li`], telling `rec` everything that happens along the path.
pub fn li_recorded(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &PathConfig,
    rec: &mut impl PathRecorder,
) -> Vec3 {
    li_recorded_in(scene, cray, sampler, cfg, &RgbMode, rec)
}

/// [`li_recorded`] in the colour mode `mode`: the estimate in its colour type.
pub fn li_recorded_in<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &PathConfig,
    mode: &M,
    rec: &mut impl PathRecorder<M::C>,
) -> M::C {
    let mut result = M::C::ZERO;
    if cfg.max_depth == 0 {
        return result;
    }
    rec.camera_ray(&cray.ray);
    let state = PathState::start(scene, cfg, cray);
    Tracer {
        scene,
        cfg,
        sampler,
        rec,
        mode,
        result: &mut result,
        shadows: Shadows::Immediate,
    }
    .trace(state);
    result
}
