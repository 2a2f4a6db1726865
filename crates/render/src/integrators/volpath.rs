//! The volumetric path tracer, with Mitsuba 3's `volpath` semantics.
//!
//! - The path starts in the camera's medium. In a medium, a free flight is sampled up to the
//!   next surface ([`crate::media::Medium::sample`]): a collision scatters by the phase
//!   function, otherwise the path reaches the surface with the flight's pass weight.
//! - `max_depth` counts scattering events, in media and on surfaces; index-matched (`null`)
//!   surfaces are crossed without counting, and change the medium when they bound one.
//!   Russian roulette after `rr_depth` events, with probability min(max(β)·η², 0.95).
//! - Next-event estimation at every medium collision and at every surface with a smooth lobe
//!   (one emitter chosen as the scene's light selection says), its shadow ray attenuated by
//!   the transmittance of every medium it crosses and blocked by any surface that is not
//!   `null`; combined with phase or BSDF sampling by the power heuristic. Emitters reached by
//!   a path use the density of the last real scattering event, as Mitsuba does.
//! - Surfaces whose shape bounds media (`interior`/`exterior`) switch the path's medium to
//!   the side the new direction goes to.
//!
//! Like Mitsuba, a hero channel is drawn per path and free flights are sampled with it;
//! beyond Mitsuba, contributions are weighted by spectral MIS over the choice of hero (the
//! path's channel density ratios, see [`crate::media::Flight`]), and homogeneous media use
//! analytic transmittance on shadow rays: lower variance, the same mean. Grids use delta and
//! ratio tracking, as Mitsuba does.

use base::TransmittanceEstimator;

use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::geometry::Ray;
use crate::integrators::path::{
    Contribution, NoRecorder, PathEnd, PathRecorder, RecordedScatter, RecordedVertex, Scatter,
    VertexKind, Via,
};
use crate::lights::{LightSample, Receiver, ShadowTarget};
use crate::math::Vec3;
use crate::media::Flight;
use crate::sampling::{Equiangular, Sampler, Samples};
use crate::shapes::{SHADOW_EPSILON, SurfaceInteraction, offset_ray_origin};
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

/// The power heuristic (β = 2).
#[inline]
fn mis(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    let w = a2 / (a2 + b2);
    if w.is_finite() { w } else { 0.0 }
}

/// Where a shadow ray starts.
#[derive(Clone, Copy)]
pub(crate) enum From<'a> {
    Surface(&'a SurfaceInteraction),
    Medium(Vec3, f32),
}

/// The radiance arriving along one camera ray.
#[inline]
pub fn li(scene: &Scene, cray: &CameraRay, sampler: &mut Sampler, cfg: &VolPathConfig) -> Vec3 {
    li_in::<RgbMode>(scene, cray, sampler, cfg)
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

/// Adds `l` to the estimate and tells the recorder where it came from.
#[inline(always)]
fn add<C: Color, R: PathRecorder<C>>(result: &mut C, rec: &mut R, l: C, c: Contribution) {
    *result += l;
    rec.contribution(l, c);
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
    let len = cray.ray.d.length();
    let mut ray = Ray::at_time(cray.ray.o, cray.ray.d / len, cray.ray.time);
    let mut t_far = cray.t_max * len;
    let mut medium = scene.camera_medium;
    let mut throughput = M::C::ONE;
    let mut result = M::C::ZERO;
    let mut eta = 1.0f32;
    let mut depth = 0u32;
    // How the path left its first scattering vertex (for the recorder's contributions).
    let mut first: Option<Scatter> = None;
    // Emitters reached through delta events only (or directly) count without MIS.
    let mut specular_chain = !cfg.hide_emitters;
    // The last real scattering event (`None`: the camera) and its direction density.
    let mut last: Option<Receiver> = None;
    let mut last_pdf = 1.0f32;
    // The hero channel and the path's density ratios p_c/p_hero (their mean divides every
    // contribution: spectral MIS over the hero).
    let hero = mode.hero(sampler.next_1d());
    let mut ratio = M::C::ONE;
    let mis_hero = |ratio: M::C| mode.hero_weight(ratio);
    // Emission grids were sampled from the vertex the current segment started at: their
    // emission met by collisions on it is already counted.
    let mut emission_sampled = false;
    // Bounded: null crossings do not count as depth.
    for _ in 0..(1 << 16) {
        if throughput.is_black() {
            rec.end(PathEnd::Absorbed);
            break;
        }
        if depth > cfg.rr_depth {
            // The path's effective weight is throughput / mean ratio.
            let q = (mode.live_max(throughput * mis_hero(ratio)) * eta * eta).min(0.95);
            if sampler.next_1d() >= q {
                rec.end(PathEnd::Roulette);
                break;
            }
            throughput /= q;
        }
        if depth >= cfg.max_depth {
            rec.end(PathEnd::MaxDepth);
            break;
        }
        // Contributions found from here: the emitter is one segment past the last event.
        let found = |via| Contribution {
            depth: depth + 1,
            first,
            via,
        };
        // The surface's interaction waits until no collision comes before it.
        let closest = scene.closest(&ray, t_far);
        if let Some(m) = medium {
            let m = &scene.media[m as usize];
            let d_surface = closest.t(&ray, t_far);
            // Equiangular sampling of this segment towards a point light (strategy B); the
            // collision's own next-event estimation below is strategy A.
            let mut segment = (cfg.equiangular && depth + 1 < cfg.max_depth)
                .then(|| m.grey_homogeneous())
                .flatten()
                .map(|(sigma_t, sigma_s)| Segment {
                    o: ray.o,
                    d: ray.d,
                    end: d_surface,
                    sigma_t,
                    sigma_s,
                    estimator: cfg.transmittance,
                    cached: None,
                });
            if let Some(seg) = &mut segment {
                let l = throughput
                    * seg.equiangular(scene, m, medium, ray.time, sampler, mode)
                    * mis_hero(ratio);
                add(&mut result, rec, l, found(Via::EmitterSample));
            }
            match m.sample_in(&ray, d_surface, hero, sampler, mode) {
                Flight::Scatter {
                    d,
                    weight,
                    ratio: r,
                    emit,
                } => {
                    ratio *= r;
                    // Emission by collision estimation.
                    if let Some(e) = &m.emission
                        && !(depth == 0 && cfg.hide_emitters)
                        && !(emission_sampled && m.emission_sampler.is_some())
                    {
                        let le = e.radiance_in(ray.at(d), mode);
                        let l = throughput * emit * le * mis_hero(ratio);
                        add(&mut result, rec, l, found(Via::Emission));
                    }
                    throughput *= weight;
                    depth += 1;
                    let p = ray.at(d);
                    rec.vertex(&RecordedVertex {
                        p,
                        n: Vec3::ZERO,
                        depth,
                        throughput: throughput * mis_hero(ratio),
                        kind: VertexKind::Medium,
                    });
                    if depth >= cfg.max_depth {
                        rec.end(PathEnd::MaxDepth);
                        break;
                    }
                    let wo = -ray.d;
                    let r = Receiver::at(p);
                    // Contributions from this vertex: one segment past it.
                    let here = |via| Contribution {
                        depth: depth + 1,
                        first: first.or(Some(PHASE)),
                        via,
                    };
                    if let Some((i, ls, pmf)) = sample_light(scene, &r, sampler, mode) {
                        let ph = m.phase.eval(wo, ls.wi);
                        let tr = transmittance(
                            scene,
                            From::Medium(p, ray.time),
                            &ls,
                            medium,
                            cfg.transmittance,
                            sampler,
                            mode,
                        );
                        if !tr.is_black() {
                            let w = match (&mut segment, scene.lights[i as usize].position()) {
                                // A point light also reachable by strategy B.
                                (Some(seg), Some(q)) => {
                                    let p_a = seg.sigma_t * (-seg.sigma_t * d).exp() * pmf;
                                    let p_b = seg.pdf(q, d) * scene.light_pmf(&seg.origin(), i);
                                    mis(p_a, p_b)
                                }
                                _ if ls.delta => 1.0,
                                _ => mis(ls.pdf * pmf, ph),
                            };
                            let l = throughput
                                * tr
                                * ls.li
                                * (ph * w * mis_hero(ratio) / (ls.pdf * pmf));
                            add(&mut result, rec, l, here(Via::EmitterSample));
                        }
                    }
                    if cfg.sample_emission {
                        let l = throughput
                            * sample_emission(
                                scene,
                                From::Medium(p, ray.time),
                                medium,
                                cfg,
                                sampler,
                                mode,
                                |wi| M::C::splat(m.phase.eval(wo, wi)),
                            )
                            * mis_hero(ratio);
                        add(&mut result, rec, l, here(Via::EmitterSample));
                        emission_sampled = true;
                    }
                    let (wi, pdf) = m.phase.sample(wo, sampler.next_2d());
                    rec.scatter(&RecordedScatter {
                        scatter: PHASE,
                        wi,
                        pdf,
                        throughput: throughput * mis_hero(ratio),
                    });
                    first = first.or(Some(PHASE));
                    ray = Ray::at_time(p, wi, ray.time);
                    t_far = f32::INFINITY;
                    last = Some(r);
                    last_pdf = pdf;
                    specular_chain = false;
                    continue;
                }
                Flight::Pass { weight, ratio: r } => {
                    throughput *= weight;
                    ratio *= r;
                }
            }
        }

        let Some(si) = closest.surface(scene, &ray, t_far) else {
            if !(depth == 0 && cfg.hide_emitters) {
                for &i in &scene.infinite_lights {
                    let light = &scene.lights[i as usize];
                    let le = light.environment(ray.d, mode);
                    if le.is_black() {
                        continue;
                    }
                    let w = match &last {
                        Some(r) if !specular_chain => {
                            let pdf = scene.light_pmf(r, i) * light.pdf_li(scene, r, ray.d, None);
                            mis(last_pdf, pdf)
                        }
                        _ => 1.0,
                    };
                    let l = throughput * le * (w * mis_hero(ratio));
                    add(&mut result, rec, l, found(Via::Emission));
                }
                if depth == 0
                    && let Some(bg) = scene.background
                {
                    add(&mut result, rec, mode.illuminant(bg), found(Via::Emission));
                }
            }
            rec.end(PathEnd::Escaped);
            break;
        };

        if let Some(i) = scene.shape_light(&si)
            && !(depth == 0 && cfg.hide_emitters)
        {
            let light = &scene.lights[i as usize];
            let le = light.le(scene, &si, mode);
            if !le.is_black() {
                let w = match &last {
                    Some(r) if !specular_chain => {
                        let pdf = scene.light_pmf(r, i) * light.pdf_li(scene, r, ray.d, Some(&si));
                        mis(last_pdf, pdf)
                    }
                    _ => 1.0,
                };
                let l = throughput * le * (w * mis_hero(ratio));
                add(&mut result, rec, l, found(Via::Emission));
            }
        }

        let null = scene.is_null(&si);
        rec.vertex(&RecordedVertex {
            p: si.p,
            n: si.shading.n,
            depth: depth + 1,
            throughput: throughput * mis_hero(ratio),
            kind: if null {
                VertexKind::Null
            } else {
                VertexKind::Surface
            },
        });
        if null {
            // An index-matched boundary: cross it, in the same direction.
            rec.scatter(&RecordedScatter {
                scatter: Scatter {
                    delta: true,
                    transmission: true,
                },
                wi: ray.d,
                pdf: 1.0,
                throughput: throughput * mis_hero(ratio),
            });
            medium = scene.medium_after(&si, ray.d, medium);
            ray = si.spawn_ray(ray.d);
            t_far = f32::INFINITY;
            continue;
        }
        let Some((bsdf, frame)) = scene.bsdf_at_in(&si, mode) else {
            rec.end(PathEnd::Absorbed);
            break;
        };
        let wo = frame.to_local(si.wo);
        // Contributions from this vertex reach the emitter one segment past it; before the
        // path leaves its first vertex, `first` is still unknown, as in the path tracer.
        let here = |via| Contribution {
            depth: depth + 2,
            first,
            via,
        };
        emission_sampled = false;
        if bsdf.has_smooth() && cfg.sample_emission && depth + 1 < cfg.max_depth {
            let l = throughput
                * sample_emission(
                    scene,
                    From::Surface(&si),
                    medium,
                    cfg,
                    sampler,
                    mode,
                    |wi| bsdf.eval(wo, frame.to_local(wi), TransportMode::Radiance),
                )
                * mis_hero(ratio);
            add(&mut result, rec, l, here(Via::EmitterSample));
            emission_sampled = true;
        }
        if bsdf.has_smooth() && depth + 1 < cfg.max_depth {
            let r = Receiver::from(&si);
            if let Some((_, ls, pmf)) = sample_light(scene, &r, sampler, mode) {
                let (f, pdf) = bsdf.eval_pdf(wo, frame.to_local(ls.wi), TransportMode::Radiance);
                if !f.is_black() {
                    let start = scene.medium_after(&si, ls.wi, medium);
                    let tr = transmittance(
                        scene,
                        From::Surface(&si),
                        &ls,
                        start,
                        cfg.transmittance,
                        sampler,
                        mode,
                    );
                    if !tr.is_black() {
                        let w = if ls.delta {
                            1.0
                        } else {
                            mis(ls.pdf * pmf, pdf)
                        };
                        let l =
                            throughput * tr * f * ls.li * (w * mis_hero(ratio) / (ls.pdf * pmf));
                        add(&mut result, rec, l, here(Via::EmitterSample));
                    }
                }
            }
        }
        let u1 = sampler.next_1d();
        let u2 = sampler.next_2d();
        let Some(bs) = bsdf.sample(wo, u1, u2, TransportMode::Radiance) else {
            rec.end(PathEnd::Absorbed);
            break;
        };
        throughput *= bs.weight;
        eta *= bs.eta;
        if bs.delta {
            // Emission sampling could not follow a delta lobe: collisions count again.
            emission_sampled = false;
        }
        let wi = frame.to_world(bs.wi);
        let scatter = Scatter {
            delta: bs.delta,
            transmission: bs.transmission,
        };
        rec.scatter(&RecordedScatter {
            scatter,
            wi,
            pdf: bs.pdf,
            throughput: throughput * mis_hero(ratio),
        });
        first = first.or(Some(scatter));
        medium = scene.medium_after(&si, wi, medium);
        ray = si.spawn_ray(wi);
        t_far = f32::INFINITY;
        depth += 1;
        last = Some(Receiver::from(&si));
        last_pdf = bs.pdf;
        specular_chain = bs.delta;
    }
    result
}

/// One emitter sample for next-event estimation at `r`: the emitter, the sample and the
/// probability of the emitter's choice. Draws one 1D and one 2D number whatever happens.
#[inline]
fn sample_light<M: PathMode>(
    scene: &Scene,
    r: &Receiver,
    sampler: &mut Sampler,
    mode: &M,
) -> Option<(u32, LightSample<M::C>, f32)> {
    let picked = scene.sample_light(sampler.next_1d(), r);
    let u = sampler.next_2d();
    let (i, light, pmf) = picked?;
    let ls = light.sample_li(scene, r, u, mode)?;
    (ls.pdf > 0.0 && !ls.li.is_black() && pmf > 0.0).then_some((i, ls, pmf))
}

/// A segment `o + t·d`, t ∈ [0, end), through a grey homogeneous medium, for equiangular
/// sampling towards point lights ([`Equiangular`]; a point light in fog otherwise has an
/// estimator of unbounded variance near it).
struct Segment {
    o: Vec3,
    d: Vec3,
    end: f32,
    sigma_t: f32,
    sigma_s: f32,
    estimator: TransmittanceEstimator,
    /// The last light position [`Segment::towards`] was asked for, and its distribution: the
    /// collision's MIS weight asks again for the light strategy B chose (two `atan2` saved).
    cached: Option<(Vec3, Option<Equiangular>)>,
}

impl Segment {
    /// Where strategy B chooses its light (the segment's start).
    fn origin(&self) -> Receiver {
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
    fn pdf(&mut self, q: Vec3, t: f32) -> f32 {
        self.towards(q).map_or(0.0, |e| e.pdf(t))
    }

    /// Strategy B's estimate: a light chosen from the segment's start; if it is a point
    /// light, a distance by equiangular sampling and single scattering there towards the
    /// light, MIS-weighted against the free-flight collision's next-event estimation.
    fn equiangular<M: PathMode>(
        &mut self,
        scene: &Scene,
        m: &crate::media::Medium,
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
        let tr = transmittance(
            scene,
            From::Medium(x, time),
            &ls,
            medium,
            self.estimator,
            sampler,
            mode,
        );
        if tr.is_black() {
            return M::C::ZERO;
        }
        let p_a = self.sigma_t * (-self.sigma_t * t).exp() * scene.light_pmf(&rx, i);
        let ph = m.phase.eval(-self.d, ls.wi);
        let f = (-self.sigma_t * t).exp() * self.sigma_s * ph / ls.pdf;
        tr * ls.li * (f * mis(p_b, p_a) / p_b)
    }
}

/// Next-event estimation towards every emission grid from `from` (in `medium`): a point x
/// chosen by the grid's emission, its σa·Le attenuated by the transmittance to it and
/// divided by its density in solid angle and distance (pdf_V·|x − p|²); `f` is the phase
/// function or BSDF (with its cosine) towards the point.
fn sample_emission<M: PathMode>(
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
        let (p, start) = match &from {
            From::Surface(si) => (si.p, None),
            From::Medium(p, _) => (*p, Some(medium)),
        };
        let to = x - p;
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
        let start = match (start, &from) {
            (Some(m), _) => m,
            (None, From::Surface(si)) => scene.medium_after(si, wi, medium),
            (None, From::Medium(..)) => medium,
        };
        let target = LightSample {
            wi,
            li: M::C::ZERO,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(x),
        };
        let tr = transmittance(
            scene,
            from,
            &target,
            start,
            cfg.transmittance,
            sampler,
            mode,
        );
        sum += fv * tr * source / (pdf_v * d2);
    }
    sum
}

/// The ray from `from` towards the light sample's target and its parameter range.
#[inline]
fn shadow_ray<C>(from: &From<'_>, ls: &LightSample<C>) -> (Ray, f32) {
    match *from {
        From::Surface(si) => ls.target.ray_from(si, ls.wi),
        From::Medium(p, time) => match ls.target {
            ShadowTarget::Infinite => (Ray::at_time(p, ls.wi, time), f32::INFINITY),
            ShadowTarget::Point(q) => (Ray::at_time(p, q - p, time), 1.0 - SHADOW_EPSILON),
            ShadowTarget::Surface { p: q, p_error, n } => {
                let q = offset_ray_origin(q, p_error, n, p - q);
                (Ray::at_time(p, q - p, time), 1.0 - SHADOW_EPSILON)
            }
        },
    }
}

/// Transmittance from `from` to the light sample's target, starting in `medium`: the media
/// crossed attenuate it, `null` surfaces let it through (switching media), any other surface
/// blocks it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn transmittance<M: PathMode>(
    scene: &Scene,
    from: From<'_>,
    ls: &LightSample<M::C>,
    mut medium: Option<u32>,
    estimator: TransmittanceEstimator,
    sampler: &mut impl Samples,
    mode: &M,
) -> M::C {
    let (mut ray, mut t_max) = shadow_ray(&from, ls);
    if !scene.has_nulls {
        // Any surface blocks: one occlusion query, then the medium over the whole segment.
        if scene.occluded(&ray, t_max) {
            return M::C::ZERO;
        }
        return medium.map_or(M::C::ONE, |m| {
            let len = ray.d.length();
            let unit = Ray::at_time(ray.o, ray.d / len, ray.time);
            scene.media[m as usize].transmittance_in(&unit, t_max * len, estimator, sampler, mode)
        });
    }
    let mut tr = M::C::ONE;
    for _ in 0..256 {
        let closest = scene.closest(&ray, t_max);
        // A blocking surface ends the query before any medium is estimated.
        if closest.shape().is_some_and(|s| !scene.shape_is_null(s)) {
            return M::C::ZERO;
        }
        if let Some(m) = medium {
            let len = ray.d.length();
            let unit = Ray::at_time(ray.o, ray.d / len, ray.time);
            let end = closest.t(&ray, t_max);
            tr *= scene.media[m as usize].transmittance_in(
                &unit,
                end * len,
                estimator,
                sampler,
                mode,
            );
            if tr.is_black() {
                return tr;
            }
        }
        let Some(si) = closest.surface(scene, &ray, t_max) else {
            return tr;
        };
        medium = scene.medium_after(&si, ray.d, medium);
        (ray, t_max) = shadow_ray(&From::Surface(&si), ls);
    }
    M::C::ZERO
}
