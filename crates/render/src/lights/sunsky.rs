//! Mitsuba 3's `sunsky` environment: the Hošek–Wilkie sky and sun of
//! [`super::sunsky_model`] in the emitter's frame (z up, `to_world` a rotation).
//!
//! Sampling (ours; Mitsuba 3.9.1 samples the sky by a parametric mixture fitted offline):
//! with probability `sun_prob` a direction uniform in the sun's cone, otherwise the sky by a
//! piecewise-constant table over (φ, cos θ) of the upper hemisphere — equal solid angle per
//! cell — whose cells hold the largest sky luminance over their corners and centre, so the
//! table's density is never small where the sky is bright. The density of a direction is
//! the mixture of both, so `pdf_li` agrees with `sample_li` everywhere (χ²-tested in
//! `build/tests/it/chi2_lights.rs`).

use super::LightScene;
use super::select::{infinite_emission, infinite_pdf_le, scene_radius};
use super::sunsky_model::SunSkyModel;
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{Frame, Mat3, PI, Vec2, Vec3, luminance};
use crate::sampling::distrib::Distribution2D;
use crate::sampling::warp;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::ColorMode;

/// Cells of the sky table in φ and in cos θ.
const TABLE_PHI: usize = 256;
const TABLE_COS: usize = 128;

#[derive(Debug)]
pub struct SunSkyLight {
    pub model: SunSkyModel,
    to_world: Mat3,
    to_local: Mat3,
    sun_frame: Frame,
    /// Over (φ/2π, 1 − cos θ) ∈ [0, 1)²: the solid angle per unit of it is 2π.
    sky: Distribution2D,
    /// Probability of sampling the sun's cone (0 without a sun, 1 without a sky).
    sun_prob: f32,
    /// ∫ L dω, the mean of R, G and B (for light selection).
    total: f32,
}

impl SunSkyLight {
    pub fn new(model: SunSkyModel, to_world: Mat3) -> SunSkyLight {
        let dir = |u: f32, v: f32| {
            let cos_t = 1.0 - v;
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let (s, c) = (2.0 * PI * u).sin_cos();
            Vec3::new(sin_t * c, sin_t * s, cos_t)
        };
        let mut sky_only = model.clone();
        sky_only.sun_scale = 0.0;
        let lum = |u: f32, v: f32| {
            let l = luminance(sky_only.eval_rgb(dir(u, v)));
            if l.is_finite() { l.max(0.0) } else { 0.0 }
        };
        // Corner values, shared by neighbouring cells.
        let corners: Vec<f32> = (0..=TABLE_COS)
            .flat_map(|j| (0..=TABLE_PHI).map(move |i| (i, j)))
            .map(|(i, j)| lum(i as f32 / TABLE_PHI as f32, j as f32 / TABLE_COS as f32))
            .collect();
        let corner = |i: usize, j: usize| corners[j * (TABLE_PHI + 1) + i];
        let mut weights = vec![0f32; TABLE_PHI * TABLE_COS];
        let mut sky_sum = 0f64;
        for j in 0..TABLE_COS {
            for i in 0..TABLE_PHI {
                let centre = lum(
                    (i as f32 + 0.5) / TABLE_PHI as f32,
                    (j as f32 + 0.5) / TABLE_COS as f32,
                );
                sky_sum += centre as f64;
                weights[j * TABLE_PHI + i] = centre
                    .max(corner(i, j))
                    .max(corner(i + 1, j))
                    .max(corner(i, j + 1))
                    .max(corner(i + 1, j + 1));
            }
        }
        // ∫ sky luminance dω over the hemisphere (midpoint rule) and the sun's share.
        let sky_power = (sky_sum / (TABLE_PHI * TABLE_COS) as f64) as f32 * 2.0 * PI;
        let sun_solid = 2.0 * PI * (1.0 - model.cos_aperture);
        let sun_centre = {
            let mut sun_only = model.clone();
            sun_only.sky_scale = 0.0;
            sun_only.eval_rgb(model.sun_dir)
        };
        let sun_power = luminance(sun_centre).max(0.0) * sun_solid;
        let sun_prob = if sun_power <= 0.0 {
            0.0
        } else if sky_power <= 0.0 {
            1.0
        } else {
            (sun_power / (sun_power + sky_power)).clamp(0.02, 0.98)
        };
        let total = if model.sun_up() {
            let mean = |c: Vec3| (c.x + c.y + c.z) / 3.0;
            let sky_mean: f64 = (0..TABLE_COS)
                .flat_map(|j| (0..TABLE_PHI).map(move |i| (i, j)))
                .map(|(i, j)| {
                    mean(sky_only.eval_rgb(dir(
                        (i as f32 + 0.5) / TABLE_PHI as f32,
                        (j as f32 + 0.5) / TABLE_COS as f32,
                    ))) as f64
                })
                .sum::<f64>()
                / (TABLE_PHI * TABLE_COS) as f64;
            sky_mean as f32 * 2.0 * PI + mean(sun_centre) * sun_solid
        } else {
            0.0
        };
        SunSkyLight {
            sun_frame: Frame::from_normal(model.sun_dir),
            model,
            to_world,
            to_local: to_world.inverse(),
            sky: Distribution2D::new(&weights, TABLE_PHI, TABLE_COS),
            sun_prob,
            total,
        }
    }

    fn local(&self, d_world: Vec3) -> Vec3 {
        (self.to_local * d_world).normalize_or_zero()
    }

    fn radiance<M: ColorMode>(&self, local: Vec3, m: &M) -> M::C {
        m.spectrum(
            |lambda| self.model.eval_spectral(local, lambda),
            self.model.eval_rgb(local),
        )
    }

    /// The solid-angle density of the local direction `d`.
    fn pdf_local(&self, d: Vec3) -> f32 {
        if !self.model.sun_up() {
            return 0.0;
        }
        let mut pdf = 0.0;
        if self.sun_prob < 1.0 && d.z >= 0.0 {
            let mut u = d.y.atan2(d.x) / (2.0 * PI);
            if u < 0.0 {
                u += 1.0;
            }
            let uv = Vec2::new(u.min(1.0), (1.0 - d.z).clamp(0.0, 1.0));
            pdf += (1.0 - self.sun_prob) * self.sky.pdf(uv) / (2.0 * PI);
        }
        if self.sun_prob > 0.0 && self.model.in_sun(d) {
            pdf += self.sun_prob * warp::uniform_cone_pdf(self.model.cos_aperture);
        }
        pdf
    }

    /// A local direction drawn by the mixture, or `None` when the light emits nothing.
    fn sample_local(&self, u: Vec2) -> Option<Vec3> {
        if !self.model.sun_up() {
            return None;
        }
        if u.x < self.sun_prob {
            let u = Vec2::new((u.x / self.sun_prob).min(1.0 - f32::EPSILON / 2.0), u.y);
            Some(
                self.sun_frame
                    .to_world(warp::square_to_uniform_cone(u, self.model.cos_aperture))
                    .normalize(),
            )
        } else {
            let u = Vec2::new(
                ((u.x - self.sun_prob) / (1.0 - self.sun_prob)).min(1.0 - f32::EPSILON / 2.0),
                u.y,
            );
            let (uv, pdf) = self.sky.sample(u);
            if pdf <= 0.0 {
                return None;
            }
            let cos_t = 1.0 - uv.y;
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let (s, c) = (2.0 * PI * uv.x).sin_cos();
            Some(Vec3::new(sin_t * c, sin_t * s, cos_t))
        }
    }

    /// A world direction towards the sky, its local form and its density.
    fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        let local = self.sample_local(u)?;
        let pdf = self.pdf_local(local);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(((self.to_world * local).normalize(), local, pdf))
    }

    /// The density of sampling the world direction `d_world` (for tests).
    pub fn pdf_world(&self, d_world: Vec3) -> f32 {
        self.pdf_local(self.local(d_world))
    }

    /// A sampled world direction (for tests).
    pub fn sample_world(&self, u: Vec2) -> Option<Vec3> {
        self.sample(u).map(|s| s.0)
    }
}

impl LightModel for SunSkyLight {
    fn is_delta(&self) -> bool {
        false
    }

    fn is_infinite(&self) -> bool {
        true
    }

    fn environment<M: ColorMode>(&self, d: Vec3, m: &M) -> M::C {
        self.radiance(self.local(d), m)
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _r: &Receiver,
        u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        let (wi, local, pdf) = self.sample(u)?;
        Some(LightSample {
            wi,
            li: self.radiance(local, m),
            pdf,
            delta: false,
            target: ShadowTarget::Infinite,
        })
    }

    fn pdf_li(
        &self,
        _: &impl LightScene,
        _: &Receiver,
        wi: Vec3,
        _: Option<&SurfaceInteraction>,
    ) -> f32 {
        self.pdf_world(wi)
    }

    /// As the environment map's: a direction drawn as `sample_li` draws it, from a point
    /// uniform on the disk of the scene's bounding sphere across it.
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let (wi, local, pdf_dir) = self.sample(u_dir)?;
        infinite_emission(scene, -wi, self.radiance(local, m), pdf_dir, u_pos)
    }

    fn pdf_le(&self, scene: &impl LightScene, _p: Vec3, _n: Vec3, d: Vec3) -> (f32, f32) {
        infinite_pdf_le(scene, self.pdf_world(-d))
    }

    /// The power through a disk of the scene's bounding radius r: π r²·∫ L dω.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let r = scene_radius(scene);
        PI * r * r * self.total
    }
}
