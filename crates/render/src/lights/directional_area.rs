//! Mitsuba 3's `directionalarea`: an emitting shape whose radiance leaves only along its
//! normal (a delta in direction). As in Mitsuba 3.9.1, nothing reaches it from a receiver
//! or a camera (`sample_li` and `le` give nothing: a direction from elsewhere is never
//! exactly the normal), so only light tracing renders its light: an emitted ray starts
//! uniformly by area and leaves along the normal, carrying `radiance`·A (the power through
//! the surface: `radiance` is a flux density across it).

use super::LightScene;
use super::area::AreaLight;
use super::bvh::LightBounds;
use super::select::mean_radiance;
use super::{EmissionSample, LightModel, LightSample, Receiver};
use crate::geometry::Ray;
use crate::math::{Vec2, Vec3};
use crate::shapes::offset_ray_origin;
use crate::spectral::lanes::ColorMode;
use crate::textures::{TexCoord, TexRef};

/// A `directionalarea` emitter: the shape, radiance and area of an [`AreaLight`]
/// (one-sided, the whole shape).
#[derive(Clone, Debug)]
pub struct DirectionalAreaLight {
    pub area: AreaLight,
}

impl LightModel for DirectionalAreaLight {
    fn is_delta(&self) -> bool {
        true
    }

    fn sample_li<M: ColorMode>(
        &self,
        _scene: &impl LightScene,
        _r: &Receiver,
        _u: Vec2,
        _m: &M,
    ) -> Option<LightSample<M::C>> {
        None
    }

    fn power(&self, scene: &impl LightScene) -> f32 {
        self.area.area * mean_radiance(scene, &self.area.radiance)
    }

    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        _u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let light = &self.area;
        let textured = matches!(light.radiance, TexRef::Texture(_));
        let (p, p_error, n, uv, pdf_pos) = light.sample_position(scene, textured, u_pos)?;
        if !(pdf_pos > 0.0 && pdf_pos.is_finite()) || n == Vec3::ZERO {
            return None;
        }
        let le = m.illuminant_at(scene, &light.radiance, TexCoord::at(uv, p));
        Some(EmissionSample {
            ray: Ray::new(offset_ray_origin(p, p_error, n, n), n),
            p,
            weight: le * (1.0 / pdf_pos),
            pdf_pos,
            pdf_dir: 1.0,
            n,
        })
    }

    /// The area density of the origin and a unit density of the one direction it leaves
    /// along (the normal `n`); (0, 0) for any other direction.
    fn pdf_le(&self, scene: &impl LightScene, p: Vec3, n: Vec3, d: Vec3) -> (f32, f32) {
        let (pdf_pos, _) = self.area.pdf_le(scene, p, n, n);
        if pdf_pos == 0.0 || d.dot(n) < 1.0 - 1e-6 {
            return (0.0, 0.0);
        }
        (pdf_pos, 1.0)
    }

    fn bounds(&self, scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        self.area.bounds(scene, phi)
    }
}
