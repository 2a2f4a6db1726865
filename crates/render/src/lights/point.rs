//! Point lights: intensity / d² towards every direction; a delta light.

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean, omni};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::geometry::Ray;
use crate::math::{PI, Vec2, Vec3};
use crate::sampling::warp;
use crate::spectral::DeclaredSpectrum;
use crate::spectral::lanes::ColorMode;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Vec3,
    /// The spectrum it was declared as (spectral mode only; RGB mode renders the RGB value).
    pub spectrum: Option<Arc<DeclaredSpectrum>>,
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
            li: m.illuminant_declared(self.intensity, self.spectrum.as_deref()) / d2,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(self.position),
        })
    }

    /// A direction uniform on the sphere: weight I / (1/4π) = 4π·I, the power.
    fn sample_le<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let w = warp::square_to_uniform_sphere(u_dir);
        let pdf_dir = warp::uniform_sphere_pdf();
        Some(EmissionSample {
            ray: Ray::new(self.position, w),
            p: self.position,
            weight: m.illuminant_declared(self.intensity, self.spectrum.as_deref()) / pdf_dir,
            pdf_pos: 1.0,
            pdf_dir,
            n: Vec3::ZERO,
        })
    }

    /// (1, 1/4π) along every direction (`p` is taken to be the position).
    fn pdf_le(&self, _scene: &impl LightScene, _p: Vec3, _n: Vec3, _d: Vec3) -> (f32, f32) {
        (1.0, warp::uniform_sphere_pdf())
    }

    /// 4π·I.
    fn power(&self, _scene: &impl LightScene) -> f32 {
        4.0 * PI * mean(self.intensity)
    }

    fn bounds(&self, _scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        Some(omni(self.position, self.position, phi))
    }
}
