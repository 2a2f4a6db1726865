//! Point lights: intensity / d² towards every direction; a delta light.

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean, omni};
use super::{LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{PI, Vec2, Vec3};
use crate::spectral::lanes::ColorMode;

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Vec3,
}

impl LightModel for PointLight {
    fn is_delta(&self) -> bool {
        true
    }

    fn position(&self) -> Option<Vec3> {
        Some(self.position)
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        r: &Receiver,
        _u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        let d = self.position - r.p;
        let d2 = d.length_squared();
        (d2 > 0.0).then(|| LightSample {
            wi: d / d2.sqrt(),
            li: m.illuminant(self.intensity) / d2,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(self.position),
        })
    }

    /// 4π·I.
    fn power(&self, _scene: &impl LightScene) -> f32 {
        4.0 * PI * mean(self.intensity)
    }

    fn bounds(&self, _scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        Some(omni(self.position, self.position, phi))
    }
}
