//! Directional lights: irradiance arriving along one direction from infinitely far; a delta
//! light.

use super::LightScene;
use super::select::{mean, scene_radius};
use super::{LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{PI, Vec2, Vec3};
use crate::spectral::lanes::ColorMode;

#[derive(Clone, Debug)]
pub struct DirectionalLight {
    /// Direction the light travels in (unit).
    pub direction: Vec3,
    pub irradiance: Vec3,
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
            li: m.illuminant(self.irradiance),
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Infinite,
        })
    }

    /// The power through a disk of the scene's bounding radius r: π r²·E.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let r = scene_radius(scene);
        PI * r * r * mean(self.irradiance)
    }
}
