//! The constant environment: the same radiance from every direction, sampled uniformly over
//! the sphere.

use super::LightScene;
use super::select::{infinite_emission, infinite_pdf_le, mean, scene_radius};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{PI, Vec2, Vec3};
use crate::sampling::warp;
use crate::shapes::SurfaceInteraction;
use crate::spectral::DeclaredSpectrum;
use crate::spectral::lanes::ColorMode;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct ConstantLight {
    pub radiance: Vec3,
    /// The spectrum it was declared as (spectral mode only; RGB mode renders the RGB value).
    pub spectrum: Option<Arc<DeclaredSpectrum>>,
}

impl LightModel for ConstantLight {
    fn is_delta(&self) -> bool {
        false
    }

    fn is_infinite(&self) -> bool {
        true
    }

    fn environment<M: ColorMode>(&self, _d: Vec3, m: &M) -> M::C {
        m.illuminant_declared(self.radiance, self.spectrum.as_deref())
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
            li: m.illuminant_declared(self.radiance, self.spectrum.as_deref()),
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

    /// A direction towards the environment uniform on the sphere (the ray travels the other
    /// way), from a point uniform on the disk of the scene's bounding sphere across that
    /// direction: weight L·4π·π r², the power.
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let d = -warp::square_to_uniform_sphere(u_dir);
        let radiance = m.illuminant_declared(self.radiance, self.spectrum.as_deref());
        infinite_emission(scene, d, radiance, warp::uniform_sphere_pdf(), u_pos)
    }

    /// (1/π r², 1/4π) along every direction.
    fn pdf_le(&self, scene: &impl LightScene, _p: Vec3, _n: Vec3, _d: Vec3) -> (f32, f32) {
        infinite_pdf_le(scene, warp::uniform_sphere_pdf())
    }

    /// The power through a disk of the scene's bounding radius r: 4π·π r²·L.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let r = scene_radius(scene);
        4.0 * PI * PI * r * r * mean(self.radiance)
    }
}
