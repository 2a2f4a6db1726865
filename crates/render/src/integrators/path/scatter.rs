//! Leaving a vertex: the next direction (the BSDF's own sampling, or uniform directions for
//! the courses' brute-force tracers), the throughput update, and Russian roulette (Mitsuba's
//! throughput-based one or a fixed probability).

use base::{DirectionSampling, RussianRoulette};

use super::PathConfig;
use super::record::{PathEnd, PathRecorder, RecordedScatter, Scatter};
use super::state::{PathState, Shading, Tracer};
use crate::bsdf::{Bsdf, BsdfSample, TransportMode};
use crate::integrators::transport::{Previous, roulette};
use crate::lights::Receiver;
use crate::math::{Vec2, Vec3};
use crate::sampling::warp;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode};

impl<R: PathRecorder<M::C>, M: PathMode> Tracer<'_, R, M> {
    /// Draw the next direction at `v`, advance the state `next` to the next segment
    /// (throughput, Russian roulette) and tell the recorder; `false` when the path ends here
    /// (`next` is then left partly updated and must not be used). In place: the state is
    /// large, and returning a new one cost two copies per bounce.
    pub(super) fn scatter(&mut self, v: &Shading<M::C>, next: &mut PathState<M::C>) -> bool {
        let cfg = self.cfg;
        let (si, bsdf, wo) = (v.si, v.bsdf, v.wo);
        let u1 = self.sampler.next_1d();
        let u2 = self.sampler.next_2d();
        let sample = if cfg.directions == DirectionSampling::UniformHemisphere && !bsdf.has_delta()
        {
            let (wi, pdf) = uniform_direction(bsdf, wo, Some(u2));
            let f = bsdf.eval(wo, wi, TransportMode::Radiance);
            (!f.is_black()).then(|| BsdfSample {
                wi,
                weight: f / pdf,
                pdf,
                delta: false,
                transmission: wi.z * wo.z < 0.0,
                // Only Russian roulette reads η; 1 keeps it unbiased.
                eta: 1.0,
            })
        } else if let Some(g) = self.rec.guide().filter(|_| bsdf.guidable()) {
            super::guided::sample(bsdf, v.frame, wo, g, u1, u2)
        } else {
            bsdf.sample(wo, u1, u2, TransportMode::Radiance)
        };
        let Some(bs) = sample else {
            self.rec.end(PathEnd::Absorbed);
            return false;
        };
        if !bs.delta && !cfg.continue_diffuse {
            self.rec.end(PathEnd::Absorbed);
            return false;
        }
        self.advance(si, v.frame.to_world(bs.wi), &bs, wo.z > 0.0, next)
    }

    /// Mitsuba's `path` at a `null` surface (an index-matched boundary, which it does not
    /// treat specially): the BSDF samples the straight continuation, a delta transmission of
    /// weight 1 (Mitsuba's `Delta` flags include `Null`), so the crossing counts as a bounce
    /// (depth, Russian roulette), has no emitter sampling (the surface is not smooth), and
    /// an emitter found next counts without MIS.
    #[cold]
    pub(super) fn cross_null(
        &mut self,
        si: &SurfaceInteraction,
        next: &mut PathState<M::C>,
    ) -> bool {
        let bs = BsdfSample {
            wi: -si.wo,
            weight: M::C::ONE,
            pdf: 1.0,
            delta: true,
            transmission: true,
            eta: 1.0,
        };
        let front = si.wo.dot(si.shading.n) > 0.0;
        self.advance(si, -si.wo, &bs, front, next)
    }

    /// Advance `next` along the world direction `wi` of the sample `bs` leaving `si` (whose
    /// incoming direction is on the front side when `front`): throughput, medium, Russian
    /// roulette, and the recorder. `false` when the path ends.
    #[inline(always)]
    fn advance(
        &mut self,
        si: &SurfaceInteraction,
        wi: Vec3,
        bs: &BsdfSample<M::C>,
        front: bool,
        next: &mut PathState<M::C>,
    ) -> bool {
        let (scene, cfg) = (self.scene, self.cfg);
        next.throughput *= bs.weight;
        next.eta *= bs.eta;
        next.diffuse_seen |= !bs.delta;
        if bs.transmission && cfg.media_absorption {
            // Entering through the front (the side the shading normal points to), or leaving.
            next.medium = scene.medium_across(si, front);
        }
        next.ray = si.spawn_ray(wi);
        next.prev = Some(Previous {
            receiver: Receiver::from(si),
            pdf: bs.pdf,
            delta: bs.delta,
        });
        let scatter = Scatter {
            delta: bs.delta,
            transmission: bs.transmission,
        };
        if next.first.is_none() {
            next.first = Some(scatter);
        }
        next.depth += 1;
        let t_max_component = self.mode.live_max(next.throughput);
        if t_max_component.is_nan() || t_max_component <= 0.0 {
            self.rec.end(PathEnd::Absorbed);
            return false;
        }
        let u_rr = self.sampler.next_1d();
        let q = continuation(cfg, next, t_max_component);
        if !roulette::survive(&mut next.throughput, q, u_rr) {
            self.rec.end(PathEnd::Roulette);
            return false;
        }
        self.rec.scatter(&RecordedScatter {
            scatter,
            wi: next.ray.d,
            pdf: bs.pdf,
            throughput: next.throughput,
        });
        true
    }
}

/// Probability that the path `next`, whose largest throughput component is
/// `t_max_component`, continues (1: no roulette at this depth).
#[inline]
fn continuation<C>(cfg: &PathConfig, next: &PathState<C>, t_max_component: f32) -> f32 {
    match cfg.rr {
        RussianRoulette::Off => 1.0,
        RussianRoulette::Throughput { from_depth } if next.depth >= from_depth => {
            roulette::throughput(t_max_component, next.eta)
        }
        RussianRoulette::Fixed { after, q } if next.depth >= after => 1.0 - q,
        _ => 1.0,
    }
}

/// Density of the direction strategy at a non-delta vertex.
#[inline]
pub(super) fn direction_pdf<C: Color>(cfg: &PathConfig, bsdf: &Bsdf<C>, wo: Vec3, wi: Vec3) -> f32 {
    match cfg.directions {
        DirectionSampling::Bsdf => bsdf.pdf(wo, wi),
        DirectionSampling::UniformHemisphere => uniform_direction(bsdf, wo, None).1,
    }
}

/// Uniform directions: over the hemisphere of `wo` for opaque BSDFs, over the sphere for
/// those that transmit. Returns the direction (when `u` is given) and its density.
#[inline]
fn uniform_direction<C: Color>(bsdf: &Bsdf<C>, wo: Vec3, u: Option<Vec2>) -> (Vec3, f32) {
    if bsdf.has_transmission() {
        let w = u.map_or(Vec3::Z, warp::square_to_uniform_sphere);
        (w, warp::uniform_sphere_pdf())
    } else {
        let mut w = u.map_or(Vec3::Z, warp::square_to_uniform_hemisphere);
        if wo.z < 0.0 {
            w.z = -w.z;
        }
        (w, std::f32::consts::FRAC_1_PI * 0.5)
    }
}
