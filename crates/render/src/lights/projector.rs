//! Mitsuba 3's `projector`: a pinhole at the origin of `to_world` projecting a texture
//! (`irradiance`, any colour texture) through Mitsuba's perspective mapping, normalised as
//! Mitsuba normalises it — the reciprocal of its perspective camera's importance — so that
//! a plane at z = 1 of the frame, facing the light, receives π·scale·E(uv): a receiver at the
//! local point q gets Li = π·scale·E(uv) / (q_z² · (n·ω)) from direction −ω, n the frame's
//! +z (intensity π·scale·E / cos³θ under a rigid frame). A delta light.

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean_radiance, omni};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::geometry::Ray;
use crate::math::{Mat4, PI, Vec2, Vec3};
use crate::sampling::warp;
use crate::spectral::lanes::ColorMode;
use crate::textures::{ColorRef, TexCoord};

#[derive(Clone, Debug)]
pub struct ProjectorLight {
    pub to_world: Mat4,
    pub to_object: Mat4,
    pub irradiance: ColorRef,
    pub scale: f32,
    /// tan of half the horizontal field of view.
    pub tan_half_x: f32,
    /// The texture's width / height (1 for textures without a resolution, as in Mitsuba).
    pub aspect: f32,
    /// cos of the widest lit direction (the image's corners), for emitted rays.
    cos_total: f32,
}

impl ProjectorLight {
    pub fn new(
        to_world: Mat4,
        irradiance: ColorRef,
        scale: f32,
        fov_x_degrees: f32,
        aspect: f32,
    ) -> ProjectorLight {
        let tan_half_x = (0.5 * fov_x_degrees).to_radians().tan();
        let cos_total = Vec3::new(tan_half_x, tan_half_x / aspect, 1.0)
            .normalize()
            .z;
        ProjectorLight {
            to_world,
            to_object: to_world.inverse(),
            irradiance,
            scale,
            tan_half_x,
            aspect,
            cos_total,
        }
    }

    fn position(&self) -> Vec3 {
        Vec3::from_vec4(self.to_world.w_axis)
    }

    /// Mitsuba's perspective mapping of the local point `q` to the image's uv, `None`
    /// behind the light or outside the image.
    fn uv(&self, q: Vec3) -> Option<Vec2> {
        if q.z <= 0.0 {
            return None;
        }
        let s = Vec2::new(q.x, q.y) / (q.z * self.tan_half_x);
        let uv = Vec2::new(0.5 - 0.5 * s.x, 0.5 - 0.5 * self.aspect * s.y);
        ((0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)).then_some(uv)
    }

    /// The radiance factor at the world point `p` seen along the unit `-wi` (wi towards the
    /// light): (uv, π·scale / (q_z²·(n·(−wi)))), `None` where nothing arrives.
    fn arriving(&self, p: Vec3, wi: Vec3) -> Option<(Vec2, f32)> {
        let q = self.to_object.transform_point3a(p);
        let uv = self.uv(q)?;
        let n = Vec3::from_vec4(self.to_world.z_axis);
        let cos = n.dot(-wi);
        if cos.is_nan() || cos <= 0.0 {
            return None;
        }
        Some((uv, PI * self.scale / (q.z * q.z * cos)))
    }
}

impl LightModel for ProjectorLight {
    fn is_delta(&self) -> bool {
        true
    }

    fn position(&self) -> Option<Vec3> {
        Some(ProjectorLight::position(self))
    }

    fn sample_li<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        r: &Receiver,
        _u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
        let o = ProjectorLight::position(self);
        let d = o - r.p;
        let d2 = d.length_squared();
        if d2.is_nan() || d2 <= 0.0 {
            return None;
        }
        let wi = d / d2.sqrt();
        let (uv, k) = self.arriving(r.p, wi)?;
        let li = m.illuminant_at(scene, &self.irradiance, TexCoord::at(uv, r.p)) * k;
        Some(LightSample {
            wi,
            li,
            pdf: 1.0,
            delta: true,
            target: ShadowTarget::Point(o),
        })
    }

    /// A direction uniform in the cone holding the image: weight I(ω)/pdf, I(ω) the
    /// radiance arriving at unit distance along ω.
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        _u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let local = warp::square_to_uniform_cone(u_dir, self.cos_total);
        let pdf_dir = warp::uniform_cone_pdf(self.cos_total);
        let o = ProjectorLight::position(self);
        let w = self.to_world.transform_vector3a(local).normalize_or_zero();
        let at = o + w;
        let (uv, k) = self.arriving(at, -w)?;
        // At unit distance the arriving radiance is the intensity.
        let i = m.illuminant_at(scene, &self.irradiance, TexCoord::at(uv, at)) * k;
        Some(EmissionSample {
            ray: Ray::new(o, w),
            p: o,
            weight: i * (1.0 / pdf_dir),
            pdf_pos: 1.0,
            pdf_dir,
            n: Vec3::ZERO,
        })
    }

    /// (1, the cone's uniform density) inside the cone, (0, 0) outside.
    fn pdf_le(&self, _scene: &impl LightScene, _p: Vec3, _n: Vec3, d: Vec3) -> (f32, f32) {
        let local = self.to_object.transform_vector3a(d).normalize_or_zero();
        if local.z < self.cos_total {
            return (0.0, 0.0);
        }
        (1.0, warp::uniform_cone_pdf(self.cos_total))
    }

    /// ∫ I dω = π·scale·∫ E dA over the image plane at z = 1 (dω = cos³θ dA cancels the
    /// 1/cos³θ): π·scale·mean(E)·(2 tan)·(2 tan / aspect).
    fn power(&self, scene: &impl LightScene) -> f32 {
        let area = 4.0 * self.tan_half_x * self.tan_half_x / self.aspect;
        PI * self.scale * mean_radiance(scene, &self.irradiance) * area
    }

    fn bounds(&self, _scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        let o = ProjectorLight::position(self);
        Some(omni(o, o, phi))
    }
}
