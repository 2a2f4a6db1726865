//! The step both loops take at each vertex of a path ([`Tracer::vertex`]): emission found
//! by the segment just traced, emitter sampling, splitting, the next direction. The
//! single-path loop ([`Tracer::trace`]) and the batched one (`batched.rs`) build a
//! [`Tracer`] (`state.rs`) per path and step it; the step's parts live by purpose —
//! emission, the unlit and ambient terms and splitting here, next-event estimation in
//! `nee.rs`, the next direction and Russian roulette in `scatter.rs`.

use super::nee::{NeeContext, emission_weight, nee_pdf};
use super::record::{PathEnd, PathRecorder, RecordedVertex, VertexKind, Via};
use super::state::{PathState, Shading, Shadows, Tracer};
use crate::integrators::transport;
use crate::lights::Receiver;
use crate::math::Vec3;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode};
use crate::textures::TexCoord;

impl<R: PathRecorder<M::C>, M: PathMode> Tracer<'_, R, M> {
    /// Trace the path `st` to its end, one segment at a time.
    pub(super) fn trace(&mut self, mut st: PathState<M::C>) {
        let scene = self.scene;
        loop {
            let (ray, t_max) = (st.ray, st.t_max);
            let hit = scene.hit(&ray, t_max);
            let go_on = scene.surface(&ray, t_max, hit, |si| self.vertex(&mut st, si));
            if !go_on {
                return;
            }
        }
    }

    /// One segment of a path: the emission found by `st.ray` (whose closest hit is `si`),
    /// emitter sampling at the vertex, and the next direction (`st` advanced in place).
    /// `false` when the path ends here.
    pub(super) fn vertex(
        &mut self,
        st: &mut PathState<M::C>,
        si: Option<&SurfaceInteraction>,
    ) -> bool {
        let Some(si) = si else {
            self.escaped(st);
            return false;
        };
        st.t_max = f32::INFINITY;
        // Beer–Lambert over the segment (the ray's direction need not be a unit vector).
        if let Some(m) = st.medium
            && let Some(tr) = self.scene.media[m as usize]
                .analytic_transmittance_in(si.t * st.ray.d.length(), self.mode)
        {
            st.throughput *= tr;
        }
        self.emission(st, si);
        if self.unlit(st, si) {
            return false;
        }

        let (scene, cfg) = (self.scene, self.cfg);
        let bsdf = scene.bsdf_at_in(si, self.mode);
        self.rec.vertex(&RecordedVertex {
            p: si.p,
            n: si.shading.n,
            depth: st.depth + 1,
            throughput: st.throughput,
            kind: VertexKind::Surface,
        });
        if st.depth.saturating_add(1) >= cfg.max_depth {
            self.rec.end(PathEnd::MaxDepth);
            return false;
        }
        let Some((bsdf, frame)) = &bsdf else {
            if scene.is_null(si) {
                return self.cross_null(si, st);
            }
            self.rec.end(PathEnd::Absorbed);
            return false;
        };
        let at = Shading {
            si,
            bsdf,
            frame,
            wo: frame.to_local(si.wo),
        };
        self.ambient(st, si);
        NeeContext {
            at,
            receiver: Receiver::from(si),
            throughput: st.throughput,
            contribution: st.contribution(Via::EmitterSample, st.depth + 2),
        }
        .estimate(self);
        if st.split {
            self.split(st, &at);
        }
        self.scatter(&at, st)
    }

    /// `st.ray` left the scene: the environment's emission along it (and the background, for
    /// camera rays).
    #[inline]
    fn escaped(&mut self, st: &PathState<M::C>) {
        let (scene, cfg, m) = (self.scene, self.cfg, self.mode);
        if !(st.depth == 0 && cfg.hide_emitters) {
            let mut l = transport::environment(scene, st.ray.d, m, st.throughput, |i, light| {
                emission_weight(cfg, st.prev.as_ref(), |r| {
                    nee_pdf(scene, cfg, r, i, light.pdf_li(scene, r, st.ray.d, None))
                })
            });
            if st.depth == 0 {
                if let Some(bg) = scene.background {
                    l += m.illuminant(bg);
                }
                if let Some(t) = scene.background_texture {
                    let uv = scene.camera.film_uv(st.ray.o, st.ray.d);
                    l += m.illuminant(scene.textures.get(t).eval(TexCoord::uv(uv)));
                }
            }
            if !l.is_black() {
                self.add(l, st.contribution(Via::Emission, st.depth + 1));
            }
        }
        self.rec.end(PathEnd::Escaped);
    }

    /// Emission of the surface `st.ray` hit at `si`, if it emits (and the configuration
    /// shows it: not to camera rays with `hide_emitters`, not through caustic paths without
    /// `caustics`).
    #[inline]
    fn emission(&mut self, st: &PathState<M::C>, si: &SurfaceInteraction) {
        let (scene, cfg) = (self.scene, self.cfg);
        if !(st.depth == 0 && cfg.hide_emitters)
            && (cfg.caustics || !st.caustic())
            && let Some((li, le)) = transport::emitter_hit(scene, si, self.mode)
        {
            let w = emission_weight(cfg, st.prev.as_ref(), |r| {
                let light = &scene.lights[li as usize];
                let pdf = light.pdf_li(scene, r, st.ray.d.normalize(), Some(si));
                nee_pdf(scene, cfg, r, li, pdf)
            });
            let l = st.throughput * le * w;
            self.add(l, st.contribution(Via::Emission, st.depth + 1));
        }
    }

    /// A surface without shading shows its colour to whoever reaches it, and ends the path
    /// (`true`).
    #[inline]
    fn unlit(&mut self, st: &PathState<M::C>, si: &SurfaceInteraction) -> bool {
        let scene = self.scene;
        if scene.has_unlit
            && let Some(c) = scene.unlit_color(si)
        {
            let l = st.throughput * self.mode.illuminant(c);
            if !l.is_black() {
                self.add(l, st.contribution(Via::Emission, st.depth + 1));
            }
            self.rec.end(PathEnd::Absorbed);
            return true;
        }
        false
    }

    /// The scene's ambient term at a vertex of a Whitted tracer (one that does not continue
    /// after non-delta vertices).
    #[inline]
    fn ambient(&mut self, st: &PathState<M::C>, si: &SurfaceInteraction) {
        let (scene, m) = (self.scene, self.mode);
        if !self.cfg.continue_diffuse
            && scene.ambient != Vec3::ZERO
            && let Some(ka) = scene.ambient_reflectance(si)
        {
            let l = st.throughput * m.albedo(ka) * m.illuminant(scene.ambient);
            if !l.is_black() {
                self.add(l, st.contribution(Via::Ambient, st.depth + 1));
            }
        }
    }

    /// Splitting at `at`: N continuations, each carrying 1/N of the throughput. `st` becomes
    /// the last of them; the other N − 1 are traced to their ends here, with their shadow
    /// rays tested at once (in the batched loop too).
    #[inline]
    fn split(&mut self, st: &mut PathState<M::C>, at: &Shading<M::C>) {
        st.split = false;
        let n = self.cfg.splitting;
        st.throughput /= n as f32;
        for _ in 1..n {
            let mut next = *st;
            if self.scatter(at, &mut next) {
                Tracer {
                    scene: self.scene,
                    cfg: self.cfg,
                    sampler: &mut *self.sampler,
                    rec: &mut *self.rec,
                    mode: self.mode,
                    result: &mut *self.result,
                    shadows: Shadows::Immediate,
                }
                .trace(next);
            }
        }
    }
}
