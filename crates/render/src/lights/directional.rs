//! Directional lights: irradiance arriving along one direction from infinitely far; a delta
//! light.

use super::LightScene;
use super::select::{infinite_emission, infinite_pdf_le, mean, scene_radius};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{PI, Vec2, Vec3};
use crate::spectral::DeclaredSpectrum;
use crate::spectral::lanes::ColorMode;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Direction the light travels in (unit).
    pub direction: Vec3,
    pub irradiance: Vec3,
    /// The spectrum it was declared as (spectral mode only; RGB mode renders the RGB value).
    pub spectrum: Option<Arc<DeclaredSpectrum>>,
}

impl LightModel for DirectionalLight {
    fn is_delta(&self) -> bool {
        true
    }

    fn is_infinite(&self) -> bool {
        true
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _r: &Receiver,
        _u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        Some(LightSample {
            wi: -self.direction,
            li: m.illuminant_declared(self.irradiance, self.spectrum.as_deref()),
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Infinite,
        })
    }

    /// The one direction, from a point uniform on the disk of the scene's bounding sphere
    /// across it: weight E·π r², the power.
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        _u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        if self.direction == Vec3::ZERO {
            return None;
        }
        let irradiance = m.illuminant_declared(self.irradiance, self.spectrum.as_deref());
        infinite_emission(scene, self.direction, irradiance, 1.0, u_pos)
    }

    /// (1/π r², 1) along the light's direction (to a cosine of 1 − 10⁻⁶, about 0.08°: a
    /// direction that went through f32 arithmetic), (0, 0) along any other.
    fn pdf_le(&self, scene: &impl LightScene, _p: Vec3, _n: Vec3, d: Vec3) -> (f32, f32) {
        if self.direction == Vec3::ZERO || d.dot(self.direction) < 1.0 - 1e-6 {
            return (0.0, 0.0);
        }
        infinite_pdf_le(scene, 1.0)
    }

    /// The power through a disk of the scene's bounding radius r: π r²·E.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let r = scene_radius(scene);
        PI * r * r * mean(self.irradiance)
    }
}
