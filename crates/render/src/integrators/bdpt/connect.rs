//! BDPT's strategies: joining a camera subpath and a light subpath — the emitter a camera
//! subpath reached (s = 0), a light point sampled for its end (s = 1), its end connected to
//! the lens (t = 1, splatted) or to the light subpath's end (s, t ≥ 2) — each with the
//! transmittance of its connection (the transport layer's shadow query).

use super::vertex::{Joint, Kind, Modes, Vertex};
use super::{Bdpt, NONE, StrategySink};
use crate::bsdf::TransportMode;
use crate::integrators::transport::{self, Connection, EmitterSample, From};
use crate::lights::{LightSample, Receiver, ShadowTarget};
use crate::math::{Vec2, Vec3};
use crate::sampling::Samples;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;
use base::TransmittanceEstimator;

/// One camera sample's two subpaths as its strategies join them: the vertices, the sample's
/// colour modes and the lane its free flights were sampled in.
pub(super) struct Joins<'a, M: PathMode> {
    pub(super) scene: &'a Scene,
    pub(super) cam: &'a [Vertex<M::C>],
    pub(super) light: &'a [Vertex<M::C>],
    pub(super) hero: usize,
    pub(super) modes: Modes<M>,
}

impl<M: PathMode> Bdpt<'_, M> {
    /// Strategy (s, t ≥ 2) of the subpaths `j`: its MIS-weighted contribution in linear
    /// sRGB and the weight (zero, 0 when it makes none).
    pub(super) fn connect(
        &self,
        j: &Joins<M>,
        (s, t): (usize, usize),
        sampler: &mut impl Samples,
        sink: &mut impl StrategySink<M::C>,
    ) -> (Vec3, f32) {
        let (scene, cam, light, hero, modes) = (j.scene, j.cam, j.light, j.hero, &j.modes);
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
            let joint = Joint::new(pt, None);
            let (f, w) = self.mis(j, &joint, (s, t), pt.ratio, m);
            sink.joint(s, t, &joint, w);
            return (m.to_rgb(pt.beta * pt.le * f), w);
        }
        if !pt.connectible() || !matches!(pt.kind, Kind::Surface | Kind::Medium) {
            return NONE;
        }
        if s == 1 {
            // A light point sampled for pt.
            // The light by power, as light subpaths choose theirs.
            let (li, pmf, _) = self.dist.sample_discrete(sampler.next_1d());
            let u = sampler.next_2d();
            if pmf <= 0.0 || !self.any {
                return NONE;
            }
            let receiver = match &pt.si {
                Some(si) => Receiver::from(si),
                None => Receiver::at(pt.p),
            };
            let Some(EmitterSample { ls, .. }) =
                transport::sample_towards(scene, li as u32, &receiver, u, m)
            else {
                return NONE;
            };
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
            let c = pt.beta * f * tr * ls.li / (ls.pdf * pmf);
            let mut joint = Joint::new(pt, Some(&sampled));
            (joint.seg, joint.seg_lanes) = self.connection_seg(tr, hero);
            let (mis, w) = self.mis(j, &joint, (s, t), pt.ratio, m);
            sink.joint(s, t, &joint, w);
            return (m.to_rgb(c * mis), w);
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
        (joint.seg, joint.seg_lanes) = self.connection_seg(tr, hero);
        let (mis, w) = self.mis(j, &joint, (s, t), pt.ratio * qs.ratio, m);
        sink.joint(s, t, &joint, w);
        (m.to_rgb(c * tr * mis), w)
    }

    /// Strategy t = 1 of the subpaths `j`: light vertex s − 1 seen by the lens; the film
    /// position, the MIS-weighted contribution in linear sRGB and the weight.
    pub(super) fn connect_camera(
        &self,
        j: &Joins<M>,
        s: usize,
        sampler: &mut impl Samples,
        sink: &mut impl StrategySink<M::C>,
    ) -> Option<(Vec2, Vec3, f32)> {
        let (scene, light, hero, modes) = (j.scene, j.light, j.hero, &j.modes);
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
        (joint.seg, joint.seg_lanes) = self.connection_seg(tr, hero);
        let (mis, w) = self.mis(j, &joint, (s, 1), qs.ratio, m);
        sink.joint(s, 1, &joint, w);
        Some((c.p_film, m.to_rgb(qs.beta * f * tr * (c.weight * mis)), w))
    }

    /// The transmittance from surface or medium vertex `v` to the query's target: 0 if a
    /// surface other than a null one lies between; through media an estimate
    /// (the transport layer's shadow query, whose random numbers come from `sampler`). Without media
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
        transport::transmittance(scene, &c, TransmittanceEstimator::default(), sampler, m)
    }

    /// A connection's free-flight factor from its transmittance `tr` (exact where
    /// `flight_densities` holds: homogeneous media only), in the hero lane and in every lane
    /// relative to it.
    fn connection_seg(&self, tr: M::C, hero: usize) -> (f32, M::C) {
        let h = tr.lane(hero);
        if self.flight_densities && h > 0.0 {
            (h, tr / h)
        } else if self.flight_densities {
            (h, M::C::ONE)
        } else {
            (1.0, M::C::ONE)
        }
    }
}
