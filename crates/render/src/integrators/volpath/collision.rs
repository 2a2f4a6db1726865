//! A collision in a medium: the medium's emission there (the collision estimator), next-event
//! estimation towards an emitter (MIS-weighted against phase sampling, or against the
//! equiangular strategy for point lights), emission sampling of grids, and the phase
//! function's new direction.

use super::equiangular::Segment;
use super::{PHASE, Step, VolPath};
use crate::integrators::path::{
    PathEnd, PathRecorder, RecordedScatter, RecordedVertex, VertexKind, Via,
};
use crate::integrators::transport::{self, From, Previous, mis};
use crate::lights::Receiver;
use crate::math::Vec3;
use crate::media::Medium;
use crate::spectral::lanes::{Color, PathMode};

impl<M: PathMode, R: PathRecorder<M::C>> VolPath<'_, M, R> {
    /// The free flight collided at distance `d` (its weight, channel density ratios and
    /// emission weight); `segment` is the equiangular strategy's, if it ran on this segment.
    pub(super) fn collision(
        &mut self,
        d: f32,
        weight: M::C,
        ratio: M::C,
        emit: M::C,
        segment: Option<&mut Segment>,
    ) -> Step {
        let (scene, cfg, mode) = (self.scene, self.cfg, self.mode);
        let m = self
            .walker
            .medium(scene)
            .expect("collisions happen in media");
        self.ratio *= ratio;
        let p = self.walker.ray.at(d);
        // Emission by collision estimation.
        if let Some(e) = &m.emission
            && self.sees_emitters()
            && !(self.emission_sampled && m.emission_sampler.is_some())
        {
            let le = e.radiance_in(p, mode);
            let l = self.throughput * emit * le * self.hero_weight();
            self.add(l, Via::Emission, self.depth + 1, self.first);
        }
        self.throughput *= weight;
        self.depth += 1;
        self.rec.vertex(&RecordedVertex {
            p,
            n: Vec3::ZERO,
            depth: self.depth,
            throughput: self.carried(),
            kind: VertexKind::Medium,
        });
        if self.depth >= cfg.max_depth {
            return Step::End(PathEnd::MaxDepth);
        }
        let wo = -self.walker.ray.d;
        let time = self.walker.ray.time;
        // Contributions from this vertex: one segment past it.
        let (here, first) = (self.depth + 1, self.first.or(Some(PHASE)));
        self.medium_next_event(m, p, d, wo, segment, (here, first));
        if cfg.sample_emission {
            let f = |wi| M::C::splat(m.phase.eval(wo, wi));
            self.emission_sample(From::Medium(p, time), f, (here, first));
        }
        let (wi, pdf) = m.phase.sample(wo, self.sampler.next_2d());
        self.rec.scatter(&RecordedScatter {
            scatter: PHASE,
            wi,
            pdf,
            throughput: self.carried(),
        });
        self.first = first;
        self.walker.scatter(p, wi);
        self.prev = Some(Previous {
            receiver: Receiver::at(p),
            pdf,
            delta: false,
        });
        Step::Continue
    }

    /// Next-event estimation from the collision at `p` (distance `d` along the segment, `wo`
    /// back along it) in medium `m`; for a point light that the segment's equiangular
    /// strategy could also have found, MIS against that strategy.
    fn medium_next_event(
        &mut self,
        m: &Medium,
        p: Vec3,
        d: f32,
        wo: Vec3,
        segment: Option<&mut Segment>,
        (here, first): (u32, Option<crate::integrators::path::Scatter>),
    ) {
        let (scene, mode) = (self.scene, self.mode);
        let r = Receiver::at(p);
        let Some(e) = transport::sample_emitter(scene, &r, self.sampler, mode) else {
            return;
        };
        let (ls, pmf, i) = (&e.ls, e.pmf, e.light);
        let ph = m.phase.eval(wo, ls.wi);
        let Some(tr) = self.shadow(From::Medium(p, self.walker.ray.time), ls) else {
            return;
        };
        let w = match (segment, scene.lights[i as usize].position()) {
            // A point light also reachable by strategy B.
            (Some(seg), Some(q)) => {
                let p_a = seg.sigma_t * (-seg.sigma_t * d).exp() * pmf;
                let p_b = seg.pdf(q, d) * scene.light_pmf(&seg.origin(), i);
                mis::power(p_a, p_b)
            }
            _ if ls.delta => 1.0,
            _ => mis::power(ls.pdf * pmf, ph),
        };
        let l = self.throughput * tr * ls.li * (ph * w * self.hero_weight() / (ls.pdf * pmf));
        self.add(l, Via::EmitterSample, here, first);
    }
}
