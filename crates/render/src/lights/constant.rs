//! The constant environment: the same radiance from every direction, sampled uniformly over
//! the sphere.

use super::LightScene;
use super::select::{mean, scene_radius};
use super::{LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{PI, Vec2, Vec3};
use crate::sampling::warp;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::ColorMode;

#[derive(Clone, Debug)]
pub struct ConstantLight {
    pub radiance: Vec3,
}

impl LightModel for ConstantLight {
    fn is_delta(&self) -> bool {
        false
    }

    fn is_infinite(&self) -> bool {
        true
    }

    fn environment<M: ColorMode>(&self, _d: Vec3, m: &M) -> M::C {
        m.illuminant(self.radiance)
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _r: &Receiver,
        u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        Some(LightSample {
            wi: warp::square_to_uniform_sphere(u),
            li: m.illuminant(self.radiance),
            pdf: warp::uniform_sphere_pdf(),
            delta: false,
            target: ShadowTarget::Infinite,
        })
    }

    fn pdf_li(
        &self,
        _: &impl LightScene,
        _: &Receiver,
        _: Vec3,
        _: Option<&SurfaceInteraction>,
    ) -> f32 {
        warp::uniform_sphere_pdf()
    }

    /// The power through a disk of the scene's bounding radius r: 4π·π r²·L.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let r = scene_radius(scene);
        4.0 * PI * PI * r * r * mean(self.radiance)
    }
}
