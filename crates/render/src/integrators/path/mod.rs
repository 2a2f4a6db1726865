//! The unidirectional path tracer and its restricted variants (Whitted, Nori's `path_*` and
//! `direct_*`), one loop configured by [`PathConfig`].
//!
//! With the default configuration this is Mitsuba 3's `path` integrator exactly: emitter
//! sampling (one light chosen uniformly) at every vertex with a non-delta BSDF, BSDF sampling
//! to continue, both combined with the power heuristic; Russian roulette from depth `rr_depth`
//! with continuation probability min(max(throughput)·η², 0.95); `max_depth` counts path
//! segments (1: emitters seen directly, 2: direct lighting, −1: unbounded).
//!
//! The course variants change one thing each: no next-event estimation (brute force), uniform
//! hemisphere directions instead of BSDF sampling, several emitter samples per vertex or one
//! per emitter (Whitted, CS184), fixed-probability Russian roulette, splitting at the first
//! vertex. Every combination converges to the same image; only the noise differs.
//!
//! A [`PathRecorder`] sees every vertex, scattering event and contribution of a path (render
//! layers, the path visualiser; `record.rs`); [`NoRecorder`] compiles to nothing.

mod course;
mod record;

use scene::{DirectionSampling, RussianRoulette};

pub(crate) use self::course::nori;
pub use self::record::{
    Contribution, DepthFilter, NoRecorder, PathEnd, PathRecorder, RecordedScatter, RecordedVertex,
    Scatter, Via,
};

use crate::accel::Hit;
use crate::bsdf::{Bsdf, BsdfSample, TransportMode};
use crate::camera::CameraRay;
use crate::geometry::Ray;
use crate::lights::{Light, Receiver};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::{Sampler, warp};
use crate::shapes::SurfaceInteraction;
use crate::textures::TexCoord;
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
        }
    }

    /// The path tracer a scene description asks for.
    pub fn from_desc(d: &scene::PathDesc) -> Self {
        let combine = match (d.nee, d.mis) {
            (false, _) => Combine::BsdfOnly,
            (true, scene::MisHeuristic::Power) => Combine::Power,
            (true, scene::MisHeuristic::Balance) => Combine::Balance,
        };
        PathConfig {
            rr: d.rr,
            directions: d.directions,
            light_samples: d.light_samples.max(1),
            all_lights: d.all_lights,
            splitting: d.splitting.max(1),
            caustics: d.caustics,
            clamp: d.clamp,
            only_depth: d.only_depth,
            ..PathConfig::mitsuba(d.max_depth, 0, d.hide_emitters, combine)
        }
    }
}

#[inline]
fn mis(combine: Combine, a: f32, b: f32) -> f32 {
    let w = match combine {
        Combine::Power => {
            let (a2, b2) = (a * a, b * b);
            a2 / (a2 + b2)
        }
        Combine::Balance => a / (a + b),
        Combine::EmitterOnly | Combine::BsdfOnly => 1.0,
    };
    if w.is_finite() { w } else { 0.0 }
}

/// Where the previous vertex was and how its direction sample was drawn.
#[derive(Clone, Copy)]
struct Previous {
    receiver: Receiver,
    /// Density of the direction sample (including the number of direction samples, which is
    /// always 1 here).
    dir_pdf: f32,
    delta: bool,
}

/// `l` scaled down so that its largest component is at most `max` (pbrt-v4's
/// `maxcomponentvalue`).
#[inline]
pub fn clamp_sample(l: Vec3, max: f32) -> Vec3 {
    let m = l.max_element();
    if m > max { l * (max / m) } else { l }
}

/// The state of a path between two segments.
#[derive(Clone, Copy)]
struct PathState {
    ray: Ray,
    t_max: f32,
    throughput: Vec3,
    eta: f32,
    /// Segments traced so far.
    depth: u32,
    prev: Option<Previous>,
    first: Option<Scatter>,
    /// Splitting still to be done at the next vertex.
    split: bool,
    /// Beer–Lambert absorption coefficient of the dielectric the path is inside, if any.
    absorption: Option<Vec3>,
    /// A non-delta bounce happened: emission found after delta bounces from here is caustic.
    diffuse_seen: bool,
}

impl PathState {
    fn start(cfg: &PathConfig, cray: &CameraRay) -> PathState {
        PathState {
            ray: cray.ray,
            t_max: cray.t_max,
            throughput: Vec3::ONE,
            eta: 1.0,
            depth: 0,
            prev: None,
            first: None,
            split: cfg.splitting > 1,
            absorption: None,
            diffuse_seen: false,
        }
    }

    /// The segment just traced follows a delta bounce that follows a non-delta one.
    #[inline]
    fn caustic(&self) -> bool {
        self.diffuse_seen && self.prev.is_some_and(|p| p.delta)
    }
}

pub fn li(scene: &Scene, cray: &CameraRay, sampler: &mut Sampler, cfg: &PathConfig) -> Vec3 {
    if let Some(depth) = cfg.only_depth {
        let mut rec = DepthFilter {
            depth,
            sum: Vec3::ZERO,
        };
        li_recorded(scene, cray, sampler, cfg, &mut rec);
        return rec.sum;
    }
    li_recorded(scene, cray, sampler, cfg, &mut NoRecorder)
}

/// [`li`], telling `rec` everything that happens along the path.
pub fn li_recorded(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    cfg: &PathConfig,
    rec: &mut impl PathRecorder,
) -> Vec3 {
    let mut result = Vec3::ZERO;
    if cfg.max_depth == 0 {
        return result;
    }
    rec.camera_ray(&cray.ray);
    let state = PathState::start(cfg, cray);
    trace(scene, sampler, cfg, rec, state, &mut result);
    result
}

/// Density with which next-event estimation produces direction `wi` from `r` towards `light`
/// (selection and the number of emitter samples included).
#[inline]
fn nee_pdf(scene: &Scene, cfg: &PathConfig, r: &Receiver, light: u32, pdf_li: f32) -> f32 {
    let selection = if cfg.all_lights {
        1.0
    } else {
        scene.light_pmf(r, light)
    };
    nee_density(cfg, selection, pdf_li)
}

/// [`nee_pdf`] for a light chosen with probability `selection` (known when it was just drawn).
#[inline]
fn nee_density(cfg: &PathConfig, selection: f32, pdf_li: f32) -> f32 {
    selection * pdf_li * cfg.light_samples as f32
}

fn trace(
    scene: &Scene,
    sampler: &mut Sampler,
    cfg: &PathConfig,
    rec: &mut impl PathRecorder,
    mut st: PathState,
    result: &mut Vec3,
) {
    loop {
        let (ray, t_max) = (st.ray, st.t_max);
        let hit = scene.hit(&ray, t_max);
        let go_on = scene.surface(&ray, t_max, hit, |si| {
            vertex(
                scene,
                sampler,
                cfg,
                rec,
                &mut st,
                si,
                result,
                &mut Shadows::Immediate,
            )
        });
        if !go_on {
            return;
        }
    }
}

/// A candidate contribution `l` of next-event estimation and its shadow segment.
struct ShadowQuery {
    ray: Ray,
    t_max: f32,
    l: Vec3,
}

/// Where next-event estimation's candidate contributions go: each counts only if its shadow
/// segment is unblocked.
enum Shadows<'a> {
    /// Test each shadow ray when it is made (the single-path loop).
    Immediate,
    /// Queue it with the slot of its path, to be tested with the rest of the batch after
    /// every path of the batch has been shaded.
    Deferred {
        queue: &'a mut Vec<(ShadowQuery, u32)>,
        slot: u32,
    },
}

impl Shadows<'_> {
    /// Add `q.l` to `result` (and tell `rec`) unless `q.ray` is blocked within `(0, q.t_max)`,
    /// or queue it for the batch to do so.
    #[inline]
    fn add(
        &mut self,
        scene: &Scene,
        q: ShadowQuery,
        result: &mut Vec3,
        rec: &mut impl PathRecorder,
        c: Contribution,
    ) {
        match self {
            // A zero value (an MIS weight of 0) is neither traced nor recorded.
            Shadows::Immediate => {
                if q.l != Vec3::ZERO && !scene.occluded(&q.ray, q.t_max) {
                    *result += q.l;
                    rec.contribution(q.l, c);
                }
            }
            Shadows::Deferred { queue, slot } => queue.push((q, *slot)),
        }
    }
}

/// Paths in flight at once in [`li_batched`].
const BATCH: usize = 32;

/// A path in flight.
struct Slot<T> {
    sampler: Sampler,
    st: PathState,
    result: Vec3,
    tag: T,
}

/// [`li`] for a stream of camera rays, [`BATCH`] paths at a time. `next` sets the sampler up
/// for the next camera sample and returns its tag and ray (`None`: no more); `done` receives
/// each path's estimate with its tag, in the order the paths end.
///
/// Each round runs one stage over all paths in flight before the next stage: closest hits,
/// then shading (emission, emitter sampling, the next direction), then the shadow rays of
/// the whole batch; finished paths are replaced by new ones. One path at a time, every step
/// waits for the one before it (hit → shading → next ray); across a batch the steps are
/// independent, so the processor overlaps them. The estimates are those of [`li`] exactly:
/// each path draws the same random numbers in the same order, and its shadow-ray
/// contributions are added to its sum at the same point (with `splitting`, the split-off
/// paths, traced at once, are added before the vertex's emitter samples instead of after).
pub fn li_batched<T>(
    scene: &Scene,
    cfg: &PathConfig,
    template: &Sampler,
    mut next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
    mut done: impl FnMut(T, Vec3),
) {
    let mut slots: Vec<Slot<T>> = Vec::with_capacity(BATCH);
    let mut hits: Vec<Option<Hit>> = Vec::with_capacity(BATCH);
    let mut queue: Vec<(ShadowQuery, u32)> = Vec::with_capacity(BATCH);
    let mut alive = [false; BATCH];
    let mut sampler = template.clone();
    if cfg.max_depth == 0 {
        while let Some((tag, _)) = next(&mut sampler) {
            done(tag, Vec3::ZERO);
        }
        return;
    }
    let mut more = true;
    while more && slots.len() < BATCH {
        match next(&mut sampler) {
            None => more = false,
            Some((tag, cray)) => slots.push(Slot {
                sampler: sampler.clone(),
                st: PathState::start(cfg, &cray),
                result: Vec3::ZERO,
                tag,
            }),
        }
    }
    while !slots.is_empty() {
        hits.extend(slots.iter().map(|s| scene.hit(&s.st.ray, s.st.t_max)));
        for (k, (s, &hit)) in slots.iter_mut().zip(&hits).enumerate() {
            let mut shadows = Shadows::Deferred {
                queue: &mut queue,
                slot: k as u32,
            };
            let (ray, t_max) = (s.st.ray, s.st.t_max);
            alive[k] = scene.surface(&ray, t_max, hit, |si| {
                vertex(
                    scene,
                    &mut s.sampler,
                    cfg,
                    &mut NoRecorder,
                    &mut s.st,
                    si,
                    &mut s.result,
                    &mut shadows,
                )
            });
        }
        hits.clear();
        for (q, slot) in queue.drain(..) {
            if !scene.occluded(&q.ray, q.t_max) {
                slots[slot as usize].result += q.l;
            }
        }
        // A finished path's slot takes the next camera sample in place (building a new slot
        // and moving it in cost a 224-byte copy per path); without one, the slot goes. From
        // the back, so that `swap_remove` only moves paths already looked at (alive).
        for k in (0..slots.len()).rev() {
            if alive[k] {
                continue;
            }
            let s = &mut slots[k];
            match if more { next(&mut s.sampler) } else { None } {
                Some((tag, cray)) => {
                    s.st = PathState::start(cfg, &cray);
                    let result = std::mem::replace(&mut s.result, Vec3::ZERO);
                    done(std::mem::replace(&mut s.tag, tag), result);
                }
                None => {
                    more = false;
                    let s = slots.swap_remove(k);
                    done(s.tag, s.result);
                }
            }
        }
    }
}

/// One segment of a path: the emission found by `st.ray` (whose closest hit is `si`), emitter
/// sampling at the vertex, and the next direction (`st` advanced in place). `false` when the
/// path ends here.
#[allow(clippy::too_many_arguments)]
fn vertex(
    scene: &Scene,
    sampler: &mut Sampler,
    cfg: &PathConfig,
    rec: &mut impl PathRecorder,
    st: &mut PathState,
    si: Option<&SurfaceInteraction>,
    result: &mut Vec3,
    shadows: &mut Shadows,
) -> bool {
    // Weight of emission reached by the sampled ray from `prev`, given the density with which
    // next-event estimation would have produced the same direction.
    let emission_weight = |prev: &Option<Previous>, nee_pdf: &dyn Fn(&Receiver) -> f32| match prev {
        None => 1.0,
        Some(p) if p.delta => 1.0,
        Some(p) => match cfg.combine {
            Combine::BsdfOnly => 1.0,
            Combine::EmitterOnly => 0.0,
            c => mis(c, p.dir_pdf, nee_pdf(&p.receiver)),
        },
    };
    let first = st.first;
    let contribution = |via, depth| Contribution { depth, first, via };
    let Some(si) = si else {
        if !(st.depth == 0 && cfg.hide_emitters) {
            let mut l = Vec3::ZERO;
            for &i in &scene.infinite_lights {
                let light = &scene.lights[i as usize];
                let le = light.environment(st.ray.d);
                if le == Vec3::ZERO {
                    continue;
                }
                let w = emission_weight(&st.prev, &|r| {
                    nee_pdf(scene, cfg, r, i, light.pdf_li(scene, r, st.ray.d, None))
                });
                l += st.throughput * le * w;
            }
            if st.depth == 0 {
                if let Some(bg) = scene.background {
                    l += bg;
                }
                if let Some(t) = scene.background_texture {
                    let uv = scene.camera.film_uv(st.ray.o, st.ray.d);
                    l += scene.textures[t as usize].eval(TexCoord::uv(uv));
                }
            }
            if l != Vec3::ZERO {
                *result += l;
                rec.contribution(l, contribution(Via::Emission, st.depth + 1));
            }
        }
        rec.end(PathEnd::Escaped);
        return false;
    };
    st.t_max = f32::INFINITY;
    if let Some(sigma) = st.absorption {
        st.throughput *= (-sigma * (si.t * st.ray.d.length())).exp();
    }

    if let Some(li) = scene.shape_light(si)
        && !(st.depth == 0 && cfg.hide_emitters)
        && (cfg.caustics || !st.caustic())
    {
        let light = &scene.lights[li as usize];
        let le = light.le(scene, si);
        if le != Vec3::ZERO {
            let w = emission_weight(&st.prev, &|r| {
                let pdf = light.pdf_li(scene, r, st.ray.d.normalize(), Some(si));
                nee_pdf(scene, cfg, r, li, pdf)
            });
            let l = st.throughput * le * w;
            *result += l;
            rec.contribution(l, contribution(Via::Emission, st.depth + 1));
        }
    }

    // A surface without shading shows its colour to whoever reaches it, and ends the path.
    if scene.has_unlit
        && let Some(c) = scene.unlit_color(si)
    {
        let l = st.throughput * c;
        if l != Vec3::ZERO {
            *result += l;
            rec.contribution(l, contribution(Via::Emission, st.depth + 1));
        }
        rec.end(PathEnd::Absorbed);
        return false;
    }

    let bsdf = scene.bsdf_at(si);
    rec.vertex(&RecordedVertex {
        p: si.p,
        n: si.shading.n,
        depth: st.depth + 1,
        throughput: st.throughput,
    });
    if st.depth.saturating_add(1) >= cfg.max_depth {
        rec.end(PathEnd::MaxDepth);
        return false;
    }
    let Some((bsdf, frame)) = &bsdf else {
        rec.end(PathEnd::Absorbed);
        return false;
    };
    let wo = frame.to_local(si.wo);

    if !cfg.continue_diffuse
        && scene.ambient != Vec3::ZERO
        && let Some(ka) = scene.ambient_reflectance(si)
    {
        let l = st.throughput * ka * scene.ambient;
        if l != Vec3::ZERO {
            *result += l;
            rec.contribution(l, contribution(Via::Ambient, st.depth + 1));
        }
    }

    // Emitter sampling.
    let nee = bsdf.has_smooth() && cfg.combine != Combine::BsdfOnly;
    let mut emitter = Emitter {
        scene,
        cfg,
        si,
        bsdf,
        frame,
        wo,
        receiver: Receiver::from(si),
        throughput: st.throughput,
        result,
        contribution: contribution(Via::EmitterSample, st.depth + 2),
    };
    if cfg.all_lights {
        if nee {
            for i in 0..scene.lights.len() as u32 {
                emitter.sample(i, 1.0, sampler, rec, shadows);
            }
        }
    } else {
        for _ in 0..cfg.light_samples {
            let u = sampler.next_1d();
            let picked = if nee {
                scene.sample_light(u, &emitter.receiver)
            } else {
                None
            };
            match picked {
                Some((i, _, pmf)) => {
                    emitter.sample(i, pmf, sampler, rec, shadows);
                }
                // Keep the sample dimensions aligned whatever the material.
                None => {
                    sampler.next_2d();
                }
            }
        }
    }

    // Splitting: N continuations from this vertex, each carrying 1/N.
    if st.split {
        st.split = false;
        let n = cfg.splitting;
        st.throughput /= n as f32;
        for _ in 1..n {
            let mut next = *st;
            if scatter(scene, sampler, cfg, rec, si, bsdf, frame, wo, &mut next) {
                trace(scene, sampler, cfg, rec, next, result);
            }
        }
    }
    scatter(scene, sampler, cfg, rec, si, bsdf, frame, wo, st)
}

/// A non-delta vertex, as next-event estimation sees it.
struct Emitter<'a> {
    scene: &'a Scene,
    cfg: &'a PathConfig,
    si: &'a SurfaceInteraction,
    bsdf: &'a Bsdf,
    frame: &'a Frame,
    wo: Vec3,
    receiver: Receiver,
    throughput: Vec3,
    result: &'a mut Vec3,
    contribution: Contribution,
}

impl Emitter<'_> {
    /// Next-event estimation towards light `i`: throughput · f·L·w / (p · selection) per
    /// sample, each handed to `shadows` with its shadow ray (`light_samples` are averaged
    /// through the MIS densities). `selection` is the probability with which `i` was chosen
    /// (1 when all lights are sampled): the MIS density needs it, and recomputing it would
    /// walk the light BVH a second time.
    #[inline]
    fn sample(
        &mut self,
        i: u32,
        selection: f32,
        sampler: &mut Sampler,
        rec: &mut impl PathRecorder,
        shadows: &mut Shadows,
    ) {
        let (scene, cfg) = (self.scene, self.cfg);
        let light = &scene.lights[i as usize];
        let n = if cfg.all_lights && light.is_delta() {
            1
        } else if cfg.all_lights {
            cfg.light_samples
        } else {
            1
        };
        let per_light = if cfg.all_lights { n } else { cfg.light_samples } as f32;
        // One sample is the common case (always, unless every light is visited): without the
        // loop, nothing of the loop body is hoisted ahead of it for nothing.
        if n == 1 {
            self.one(light, selection, per_light, sampler, rec, shadows);
        } else {
            for _ in 0..n {
                self.one(light, selection, per_light, sampler, rec, shadows);
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn one(
        &mut self,
        light: &Light,
        selection: f32,
        per_light: f32,
        sampler: &mut Sampler,
        rec: &mut impl PathRecorder,
        shadows: &mut Shadows,
    ) {
        let cfg = self.cfg;
        let u = sampler.next_2d();
        // Borrowed, not moved out of the `Option`: a light sample is 112 bytes.
        let ls = light.sample_li(self.scene, &self.receiver, u);
        let Some(ls) = &ls else {
            return;
        };
        if ls.pdf.is_nan() || ls.pdf <= 0.0 || ls.li == Vec3::ZERO {
            return;
        }
        let wi = self.frame.to_local(ls.wi);
        let mode = TransportMode::Radiance;
        // The BSDF's density only when MIS needs it.
        let weighted = !(ls.delta || cfg.combine == Combine::EmitterOnly);
        let (f, pdf_bsdf) = if !weighted {
            (self.bsdf.eval(self.wo, wi, mode), 0.0)
        } else if cfg.directions == DirectionSampling::Bsdf {
            self.bsdf.eval_pdf(self.wo, wi, mode)
        } else {
            let f = self.bsdf.eval(self.wo, wi, mode);
            (f, direction_pdf(cfg, self.bsdf, self.wo, wi))
        };
        if f == Vec3::ZERO {
            return;
        }
        // Density of this strategy for MIS: all samples of all lights considered.
        let w = if weighted {
            mis(cfg.combine, nee_density(cfg, selection, ls.pdf), pdf_bsdf)
        } else {
            1.0
        };
        let l = self.throughput * (f * ls.li) * (w / (ls.pdf * per_light * selection));
        let (ray, t_max) = ls.target.ray_from(self.si, ls.wi);
        let q = ShadowQuery { ray, t_max, l };
        shadows.add(self.scene, q, self.result, rec, self.contribution);
    }
}

/// Density of the direction strategy at a non-delta vertex.
#[inline]
fn direction_pdf(cfg: &PathConfig, bsdf: &Bsdf, wo: Vec3, wi: Vec3) -> f32 {
    match cfg.directions {
        DirectionSampling::Bsdf => bsdf.pdf(wo, wi),
        DirectionSampling::UniformHemisphere => uniform_direction(bsdf, wo, None).1,
    }
}

/// Uniform directions: over the hemisphere of `wo` for opaque BSDFs, over the sphere for
/// those that transmit. Returns the direction (when `u` is given) and its density.
#[inline]
fn uniform_direction(bsdf: &Bsdf, wo: Vec3, u: Option<Vec2>) -> (Vec3, f32) {
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

/// Draw the next direction at `si`, advance the state `st` to the next segment (throughput,
/// Russian roulette) and tell the recorder; `false` when the path ends here (`st` is then
/// left partly updated and must not be used). In place: the state is large, and returning
/// a new one cost two copies per bounce.
#[allow(clippy::too_many_arguments)]
fn scatter(
    scene: &Scene,
    sampler: &mut Sampler,
    cfg: &PathConfig,
    rec: &mut impl PathRecorder,
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    frame: &Frame,
    wo: Vec3,
    next: &mut PathState,
) -> bool {
    let u1 = sampler.next_1d();
    let u2 = sampler.next_2d();
    let sample = if cfg.directions == DirectionSampling::UniformHemisphere && !bsdf.has_delta() {
        let (wi, pdf) = uniform_direction(bsdf, wo, Some(u2));
        let f = bsdf.eval(wo, wi, TransportMode::Radiance);
        (f != Vec3::ZERO).then(|| BsdfSample {
            wi,
            weight: f / pdf,
            pdf,
            delta: false,
            transmission: wi.z * wo.z < 0.0,
            // Only Russian roulette reads η; 1 keeps it unbiased.
            eta: 1.0,
        })
    } else {
        bsdf.sample(wo, u1, u2, TransportMode::Radiance)
    };
    let Some(bs) = sample else {
        rec.end(PathEnd::Absorbed);
        return false;
    };
    if !bs.delta && !cfg.continue_diffuse {
        rec.end(PathEnd::Absorbed);
        return false;
    }
    next.throughput *= bs.weight;
    next.eta *= bs.eta;
    next.diffuse_seen |= !bs.delta;
    if bs.transmission {
        // Entering through the front (the side the normal points to) or leaving.
        next.absorption = if wo.z > 0.0 {
            scene.interior_absorption(si)
        } else {
            None
        };
    }
    next.ray = si.spawn_ray(frame.to_world(bs.wi));
    next.prev = Some(Previous {
        receiver: Receiver::from(si),
        dir_pdf: bs.pdf,
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
    let t_max_component = next.throughput.max_element();
    if t_max_component.is_nan() || t_max_component <= 0.0 {
        rec.end(PathEnd::Absorbed);
        return false;
    }
    let u_rr = sampler.next_1d();
    let q = match cfg.rr {
        RussianRoulette::Off => 1.0,
        RussianRoulette::Throughput { from_depth } if next.depth >= from_depth => {
            (t_max_component * next.eta * next.eta).min(0.95)
        }
        RussianRoulette::Fixed { after, q } if next.depth >= after => 1.0 - q,
        _ => 1.0,
    };
    if q < 1.0 {
        if u_rr >= q {
            rec.end(PathEnd::Roulette);
            return false;
        }
        next.throughput /= q;
    }
    rec.scatter(&RecordedScatter {
        scatter,
        wi: next.ray.d,
        pdf: bs.pdf,
        throughput: next.throughput,
    });
    true
}
