//! `volpath`'s two strategies besides free flights and emitter sampling: equiangular
//! sampling of a segment towards a point light ([`Segment`]), and next-event estimation of
//! emission grids ([`sample_emission`]).

use base::TransmittanceEstimator;

use super::VolPathConfig;
use crate::integrators::transport::{self, Connection, From, mis};
use crate::lights::{Receiver, ShadowTarget};
use crate::math::Vec3;
use crate::media::Medium;
use crate::sampling::{Equiangular, Sampler};
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// A segment `o + t·d`, t ∈ [0, end), through a grey homogeneous medium, for equiangular
/// sampling towards point lights ([`Equiangular`]; a point light in fog otherwise has an
/// estimator of unbounded variance near it).
pub(super) struct Segment {
    o: Vec3,
    d: Vec3,
    end: f32,
    pub(super) sigma_t: f32,
    sigma_s: f32,
    estimator: TransmittanceEstimator,
    /// The last light position [`Segment::towards`] was asked for, and its distribution: the
    /// collision's MIS weight asks again for the light strategy B chose (two `atan2` saved).
    cached: Option<(Vec3, Option<Equiangular>)>,
}

impl Segment {
    pub(super) fn new(
        o: Vec3,
        d: Vec3,
        end: f32,
        sigma_t: f32,
        sigma_s: f32,
        estimator: TransmittanceEstimator,
    ) -> Segment {
        Segment {
            o,
            d,
            end,
            sigma_t,
            sigma_s,
            estimator,
            cached: None,
        }
    }

    /// Where strategy B chooses its light (the segment's start).
    pub(super) fn origin(&self) -> Receiver {
        Receiver::at(self.o)
    }

    /// The equiangular distribution of the segment towards the light at `q`.
    fn towards(&mut self, q: Vec3) -> Option<Equiangular> {
        if let Some((at, e)) = self.cached
            && at == q
        {
            return e;
        }
        let e = Equiangular::new(self.o, self.d, self.end, q);
        self.cached = Some((q, e));
        e
    }

    /// The density of distance `t` under equiangular sampling towards `q`.
    pub(super) fn pdf(&mut self, q: Vec3, t: f32) -> f32 {
        self.towards(q).map_or(0.0, |e| e.pdf(t))
    }

    /// Strategy B's estimate: a light chosen from the segment's start; if it is a point
    /// light, a distance by equiangular sampling and single scattering there towards the
    /// light, MIS-weighted against the free-flight collision's next-event estimation.
    pub(super) fn equiangular<M: PathMode>(
        &mut self,
        scene: &Scene,
        m: &Medium,
        medium: Option<u32>,
        time: f32,
        sampler: &mut Sampler,
        mode: &M,
    ) -> M::C {
        let r0 = self.origin();
        let u_light = sampler.next_1d();
        let u = sampler.next_1d();
        let u2 = sampler.next_2d();
        let Some((i, light, pmf_b)) = scene.sample_light(u_light, &r0) else {
            return M::C::ZERO;
        };
        let Some(q) = light.position() else {
            return M::C::ZERO;
        };
        let Some(e) = self.towards(q) else {
            return M::C::ZERO;
        };
        let t = e.sample(u);
        let p_b = e.pdf(t) * pmf_b;
        if p_b == 0.0 {
            return M::C::ZERO;
        }
        let x = self.o + self.d * t;
        let rx = Receiver::at(x);
        let Some(ls) = light.sample_li(scene, &rx, u2, mode) else {
            return M::C::ZERO;
        };
        if ls.li.is_black() || ls.pdf <= 0.0 {
            return M::C::ZERO;
        }
        let c = Connection {
            from: From::Medium(x, time),
            wi: ls.wi,
            target: ls.target,
            medium,
        };
        let tr = transport::transmittance(scene, &c, self.estimator, sampler, mode);
        if tr.is_black() {
            return M::C::ZERO;
        }
        let p_a = self.sigma_t * (-self.sigma_t * t).exp() * scene.light_pmf(&rx, i);
        let ph = m.phase.eval(-self.d, ls.wi);
        let f = (-self.sigma_t * t).exp() * self.sigma_s * ph / ls.pdf;
        tr * ls.li * (f * mis::power(p_b, p_a) / p_b)
    }
}

/// Next-event estimation towards every emission grid from `from` (the path in `medium`): a
/// point x chosen by the grid's emission, its σa·Le attenuated by the transmittance to it and
/// divided by its density in solid angle and distance (pdf_V·|x − p|²); `f` is the phase
/// function or BSDF (with its cosine) towards the point.
pub(super) fn sample_emission<M: PathMode>(
    scene: &Scene,
    from: From<'_>,
    medium: Option<u32>,
    cfg: &VolPathConfig,
    sampler: &mut Sampler,
    mode: &M,
    f: impl Fn(Vec3) -> M::C,
) -> M::C {
    let mut sum = M::C::ZERO;
    for m in &scene.media {
        let (Some(es), Some(e)) = (&m.emission_sampler, &m.emission) else {
            continue;
        };
        let (u, v, w) = (sampler.next_1d(), sampler.next_2d(), sampler.next_1d());
        let Some((x, pdf_v)) = es.sample(u, v, w) else {
            continue;
        };
        let to = x - from.p();
        let d2 = to.length_squared();
        if d2 <= 0.0 || pdf_v <= 0.0 {
            continue;
        }
        let wi = to / d2.sqrt();
        let source = m.sigma_a_in(x, mode) * e.radiance_in(x, mode);
        let fv = f(wi);
        if source.is_black() || fv.is_black() {
            continue;
        }
        let c = Connection {
            from,
            wi,
            target: ShadowTarget::Point(x),
            medium,
        };
        let tr = transport::transmittance(scene, &c, cfg.transmittance, sampler, mode);
        sum += fv * tr * source / (pdf_v * d2);
    }
    sum
}
